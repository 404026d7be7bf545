/* MuJoCo's forward dynamics stepped by mbcomp's C DOP853 (mbrt_dop853), no Python per call.
 *
 * The strongest construct a MuJoCo user can build for an accurate trajectory: mj_forward as
 * the right-hand side dy/dt = [qvel, qacc] of y = [qpos, qvel] (nq == nv: hinges and slides
 * only), integrated by the same adaptive DOP853 with dense output mbcomp's engine runs.
 * Built and loaded by bench/peers/mujoco_dop853.py (ctypes). */
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include <mujoco/mujoco.h>
#include "mbrt.h"

typedef struct {
    mjModel *m;
    mjData *d;
    int n;      /* nq == nv */
    long calls;
} mjd_ctx;

static int rhs(void *c, double t, const double *y, double *dy)
{
    mjd_ctx *x = (mjd_ctx *)c;
    int n = x->n;
    x->d->time = t;
    memcpy(x->d->qpos, y, (size_t)n * sizeof(double));
    memcpy(x->d->qvel, y + n, (size_t)n * sizeof(double));
    mj_forward(x->m, x->d);
    memcpy(dy, y + n, (size_t)n * sizeof(double));
    memcpy(dy + n, x->d->qacc, (size_t)n * sizeof(double));
    x->calls++;
    return 0;
}

/* Loads an MJCF file; NULL (and the reason in err) on failure or when nq != nv. */
void *mjd_load(const char *path, char *err, int errlen)
{
    mjModel *m = mj_loadXML(path, NULL, err, errlen);
    if (!m)
        return NULL;
    if (m->nq != m->nv) {
        snprintf(err, (size_t)errlen, "nq = %d != nv = %d: only hinges and slides", (int)m->nq, (int)m->nv);
        mj_deleteModel(m);
        return NULL;
    }
    mjd_ctx *x = (mjd_ctx *)calloc(1, sizeof(mjd_ctx));
    if (!x) {
        mj_deleteModel(m);
        snprintf(err, (size_t)errlen, "out of memory");
        return NULL;
    }
    x->m = m;
    x->d = mj_makeData(m);
    x->n = m->nq;
    if (!x->d) {
        mj_deleteModel(m);
        free(x);
        snprintf(err, (size_t)errlen, "mj_makeData failed");
        return NULL;
    }
    return x;
}

int mjd_size(void *c) { return ((mjd_ctx *)c)->n; }

/* rhs once (for the cross-check) */
int mjd_rhs(void *c, double t, const double *y, double *dy) { return rhs(c, t, y, dy); }

/* Integrates from (t0, y0) to t_end at rtol, atol (scalar): y_out (n_out x 2n) at t_out.
 * Returns the mbrt status; *nfev the rhs calls; msg the integrator's sentence. */
int mjd_integrate(void *c, double t0, const double *y0, double t_end, double rtol, double atol,
                  const double *t_out, int n_out, double *y_out, long *nfev, char *msg, int msglen)
{
    mjd_ctx *x = (mjd_ctx *)c;
    int n2 = 2 * x->n, written = 0;
    double *work = (double *)malloc(mbrt_dop853_work_size(n2) * sizeof(double));
    double *at = (double *)malloc((size_t)n2 * sizeof(double));
    if (!work || !at) {
        free(work);
        free(at);
        snprintf(msg, (size_t)msglen, "out of memory");
        return MBRT_BAD_ARGUMENT;
    }
    for (int i = 0; i < n2; i++)
        at[i] = atol;
    mbrt_stats st;
    int rc = mbrt_dop853(rhs, NULL, c, n2, t0, y0, t_end, rtol, at, 0.0, 0.0, 10000000L, t_out, n_out, y_out,
                         &written, work, &st);
    *nfev = st.nfev;
    snprintf(msg, (size_t)msglen, "%s", st.message);
    if (rc == MBRT_OK && written != n_out) {
        snprintf(msg, (size_t)msglen, "%d of %d outputs written", written, n_out);
        rc = MBRT_BAD_ARGUMENT;
    }
    free(work);
    free(at);
    return rc;
}

void mjd_free(void *c)
{
    mjd_ctx *x = (mjd_ctx *)c;
    if (!x)
        return;
    mj_deleteData(x->d);
    mj_deleteModel(x->m);
    free(x);
}
