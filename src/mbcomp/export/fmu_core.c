/* mbcomp FMU core: one instance of a generated Lagrange program, shared by the FMI 2.0 and
 * FMI 3.0 wrappers (fmi2.c, fmi3.c), which translate their standard's calls into these.
 *
 * The including file defines, before this one: NQ, NU (coordinates, speeds), NP (tunable
 * parameters), NH (hoisted values), NW (work), GUID (the instantiation token), ALPHA, BETA
 * (Baumgarte gains, 1/s), NCOL, NROT, NH2, NW2 (the output program's columns, rotations,
 * hoisted values and work), NIN (external inputs) and the arrays P0[NP] (parameter values),
 * Y0[NQ+NU] (consistent start state), NOMINAL[NQ+NU], IN0[NIN] (the inputs' start values);
 * and the generated functions
 *   int mbcomp_fun(q, u, t, d, h, p, w, out)      dy/dt of the Lagrange index-1 form, d = gains
 *   int mbcomp_params(pv, h)                      the hoisted values of the parameters pv
 *   int mbcomp_outputs(q, u, t, d, h, p, w, out)  the result columns, then NROT rotation matrices
 *   int mbcomp_outputs_params(pv, h)              its hoisted values
 *   void mbcomp_quat(R, Q)                        a rotation matrix's unit quaternion
 * and, with MECH 1 (a model with constraints to project onto after Co-Simulation steps), the
 * evaluation program mbcomp_eval (and mbcomp_qrate), mbcomp_eval_params and the mbrt_mech
 * layout (NH3, NW3, NOUT3, MH, MN, NROWS, NSEG, QRATE, OFF_*, MECH_ROWS, MECH_SEG, PROJ_*).
 * Value references: 0..NP-1 parameters, NP..NP+NX-1 the states [q, u], NP+NX..NP+2NX-1
 * their derivatives, NP+2NX the time (FMI 3.0's independent variable), then the NCOL columns
 * and the 4 NROT quaternion entries (outputs). Co-Simulation steps with the runtime's DOP853 (mbrt.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mbrt.h"

#define NX (NQ + NU)
#ifndef SELECT
#define SELECT 0
#endif
#if SELECT
/* Model Exchange states x = [q, v]: the coordinates and NI = NU - MM independent speeds
   v = u[ind] of a partition dep/ind chosen again in Event Mode when it degrades */
#define NXS (NQ + NI)
#else
#define NXS NX
#endif
#define VR_X NP
#define VR_DX (NP + NXS)
#define NVR (NP + 2 * NXS)
#define VR_TIME NVR
#define VR_OUT (NVR + 1)
#define NOV (NCOL + 4 * NROT)
#define NROW (NCOL + 9 * NROT)
#define VR_IN (VR_OUT + NOV)
#define VR_START (VR_IN + NIN) /* the start values of [q, u]: parameters */
#define VR_TOL (VR_START + NX)  /* the Co-Simulation integrator's relative tolerance: a parameter */
#ifndef DEFAULT_TOL
#define DEFAULT_TOL 1e-8 /* the export writes the model description's DefaultExperiment tolerance */
#endif

#include "fmu_events.h"

enum { M_INSTANTIATED, M_INIT, M_EVENT, M_CONT, M_STEP, M_TERMINATED, M_ERROR };

typedef struct Inst Inst;
/* how a wrapper hands a message to its importer: error != 0 for an error */
typedef void (*mb_log_fn)(Inst *c, int error, const char *msg);

struct Inst {
    char *name;
    void *env;            /* the importer's environment */
    void (*logger)(void); /* the importer's logging callback, cast back by the wrapper */
    mb_log_fn log;
    int logging, mode, dirty, cs;
    double t, alpha, beta, rtol;
    double p[NP + 1], h[NH + 1], y[NX + 1], dy[NX + 1], w[NW + 1], d[2 + NIN], atol[NX + 1], y_end[NX + 1];
    double h2[NH2 + 1], w2[NW2 + 1], row[NROW + 1], ov[NOV + 1]; /* the output program's */
#if MECH
    double h3[NH3 + 1], w3[NW3 + 1]; /* the evaluation program's (the projection's) */
    mbrt_mech mech;
    double *mwork; /* mbrt_mech_work_size doubles */
    int projections;
#endif
    double y0[NX + 1]; /* the start values (parameters) */
    int starts_changed, tol_set; /* tol_set: the tolerance parameter was set (it wins over the experiment's) */
    /* per speed direction: whether initialization may move its position (pfree) and its speed
       (vfree): the model's guesses; a start value the importer sets is fixed (mbcomp's rule) */
    unsigned char pfree[NU + 1], vfree[NU + 1], set[NX + 1];
    double *work; /* Co-Simulation: mbrt_dop853_work_size(NX) doubles */
#if HYBRID
    mbev hy; /* the active set and what its events need (fmu_events.c) */
#endif
#if SELECT
    double x[NXS + 1], dx[NXS + 1], growth;
    int dep[MM + 1], ind[NI + 1], *iwork, x_dirty, event_due, repartitions;
    double ad[MM * MM + 1], rhs_d[MM + 1], ev[NOUT3 + 1], a[MM * NU + 1]; int piv[MM + 1];
#endif
};

#if SELECT
static int mb_full_speeds(Inst *c);
#endif
static int mb_derivatives(Inst *c);
static int mb_get_dx(Inst *c, double *dx, size_t n);

static void say(Inst *c, int error, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    if (!c || !c->log || (!error && !c->logging)) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c, error, msg);
}

#include "fmu_rules.c"

static void mb_reset(Inst *c)
{
    memcpy(c->p, P0, sizeof(double) * (NP > 0 ? NP : 0));
    memcpy(c->y, Y0, sizeof(double) * NX);
    memcpy(c->y0, Y0, sizeof(double) * NX);
    memcpy(c->pfree, PFREE0, sizeof(unsigned char) * (NU > 0 ? NU : 0));
    memcpy(c->vfree, VFREE0, sizeof(unsigned char) * (NU > 0 ? NU : 0));
    memset(c->set, 0, sizeof c->set);
    c->starts_changed = 0;
    c->tol_set = 0;
    memcpy(c->d + 2, IN0, sizeof(double) * (NIN > 0 ? NIN : 0));
#if SELECT
    {
        int k;
        memcpy(c->dep, DEP0, sizeof(int) * MM);
        memcpy(c->ind, IND0, sizeof(int) * NI);
        memcpy(c->x, Y0, sizeof(double) * NQ);
        for (k = 0; k < NI; k++) c->x[NQ + k] = Y0[NQ + IND0[k]];
        c->x_dirty = 1;
        c->event_due = 0;
    }
#endif
    c->t = 0.0;
    c->alpha = ALPHA;
    c->beta = BETA;
    c->rtol = DEFAULT_TOL;
    c->dirty = 1;
    c->mode = M_INSTANTIATED;
#if HYBRID
    mbev_reset(c);
#endif
}

/* a new instance (NULL when out of memory); the wrapper then sets log, logger, env */
static Inst *mb_new(const char *name, int cs)
{
    Inst *c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    c->name = (char *)malloc(strlen(name) + 1);
    if (!c->name) { free(c); return NULL; }
    strcpy(c->name, name);
    c->cs = cs;
    if (cs) {
        c->work = (double *)calloc(mbrt_dop853_work_size(NX) + 1, sizeof(double));
        if (!c->work) { free(c->name); free(c); return NULL; }
    }
#if MECH
    {
        mbrt_mech m = {mbcomp_eval, QRATE, c->d, c->h3, c->p, c->w3, NQ, NU, NOUT3, MH, MN, NROWS, MECH_ROWS,
                       OFF_M, OFF_F, OFF_PHI, OFF_PHID, OFF_C, OFF_CB, OFF_B, OFF_BB, OFF_PSI, NSEG, MECH_SEG};
        c->mech = m;
    }
    c->mwork = (double *)calloc(mbrt_mech_work_size(&c->mech) + 1, sizeof(double));
    if (!c->mwork) { free(c->work); free(c->name); free(c); return NULL; }
#endif
#if SELECT
    c->iwork = (int *)calloc(NU + MM + 1, sizeof(int));
    if (!c->iwork) { free(c->mwork); free(c->work); free(c->name); free(c); return NULL; }
#endif
    mb_reset(c);
    return c;
}

static void mb_free(Inst *c)
{
    if (!c) return;
    free(c->name);
    free(c->work);
#if MECH
    free(c->mwork);
#endif
#if SELECT
    free(c->iwork);
#endif
    free(c);
}

/* the hoisted values of the current parameters: 0, or -1 when a parameter guard fails (the
   values change a decision taken when the program was generated) or a value is not finite */
static int mb_refresh(Inst *c)
{
    int rc;
    if (!c->dirty) return 0;
    rc = mbcomp_params(c->p, c->h);
    if (!rc) rc = mbcomp_outputs_params(c->p, c->h2);
#if MECH
    if (!rc) rc = mbcomp_eval_params(c->p, c->h3);
#endif
#if HYBRID
    if (!rc) rc = mbhy_eval_params(c->p, c->hy.h);
#endif
    if (rc) {
        char changed[400];
        mb_changed_parameters(c, changed, sizeof changed);
        say(c, 1, "the parameter values %s%s%s -> export the model again with these values",
            rc == 1 ? "change a decision taken when the program was generated (a parameter guard)"
                    : "give a non-finite value", changed[0] ? "; changed from the export: " : "", changed);
        c->mode = M_ERROR;
        return -1;
    }
    c->dirty = 0;
    return 0;
}

/* dy/dt at the instance's (t, y) into c->dy: 0, or -1 after logging why */
static int mb_derivatives(Inst *c)
{
    int i;
    if (mb_refresh(c)) return -1;
    c->d[0] = c->alpha;
    c->d[1] = c->beta;
#if HYBRID
    return mbev_rhs(c, c->t, c->y, c->dy); /* the rows in force of the active set */
#endif
    if (mbcomp_fun(c->y, c->y + NQ, c->t, c->d, c->h, c->p, c->w, c->dy)) {
        say(c, 1, "the right-hand side failed a guard at t=%g (a singular position, or a law's other branch): "
            "mbcomp's numeric path is not in the FMU", c->t);
        return -1;
    }
    for (i = 0; i < NX; i++) {
        if (!isfinite(c->dy[i])) {
            say(c, 1, "the derivative of %s is not finite at t=%g", mb_name((unsigned)(VR_X + i)), c->t);
            return -1;
        }
    }
    return 0;
}

static int mb_rhs(void *ctx, double t, const double *y, double *dydt)
{
    Inst *c = (Inst *)ctx;
#if HYBRID
    return mbev_rhs(c, t, y, dydt);
#endif
    return mbcomp_fun(y, y + NQ, t, c->d, c->h, c->p, c->w, dydt);
}

#if MECH
/* after every accepted Co-Simulation step: y = [q, u] back onto the constraint manifold (the
   runtime's projection: positions by Gauss-Newton, then speeds); nonzero stops the step */
static int mb_project(void *ctx, double t, double *y)
{
    Inst *c = (Inst *)ctx;
    double norm = 0.0;
    int rc = mbrt_project(&c->mech, t, y, PROJ_TOL, PROJ_ITER, PROJ_ACCEPT, &norm, c->mwork);
    if (rc != MBRT_MECH_OK) {
        say(c, 1, "the projection onto the constraints failed at t=%g (status %d, |Phi| = %g): a singular "
            "position, or a step too long for Newton", t, rc, norm);
        return 1;
    }
    c->projections++;
    return 0;
}
#define ON_STEP mb_project
#else
#define ON_STEP NULL
#endif

/* Co-Simulation: integrate from c->t by h with DOP853 at c->rtol; 0, or -1 after logging */
static int mb_step(Inst *c, double h)
{
    mbrt_stats st;
    double t_end;
    int i, rc, written = 0;
#if HYBRID
    return mbev_step(c, h); /* the events located and acted on inside the step */
#endif
    if (!(h >= 0.0) || !isfinite(h)) { say(c, 1, "a communication step of %g s", h); return -1; }
    if (h == 0.0) return 0;
    if (mb_refresh(c)) return -1;
    c->d[0] = c->alpha;
    c->d[1] = c->beta;
    for (i = 0; i < NX; i++) c->atol[i] = c->rtol * 1e-2 * NOMINAL[i];
    memset(&st, 0, sizeof st);
    t_end = c->t + h;
    rc = mbrt_dop853(mb_rhs, ON_STEP, c, NX, c->t, c->y, t_end, c->rtol, c->atol, 0.0, 0.0, 0, &t_end, 1, c->y_end,
                     &written, c->work, &st);
    if (rc != MBRT_OK || written != 1) {
        say(c, 1, "the step from t=%g by %g s failed: %s", c->t, h, st.message);
        c->mode = M_ERROR;
        return -1;
    }
    memcpy(c->y, c->y_end, sizeof(double) * NX);
    c->t = t_end;
    return 0;
}

/* the outputs at the instance's (t, y) into c->ov: 0, or -1 after logging why */
static int mb_outputs(Inst *c)
{
    int i;
    if (mb_refresh(c)) return -1;
#if SELECT
    if (!c->cs && c->x_dirty && mb_full_speeds(c)) return -1;
#endif
    c->d[0] = c->alpha;
    c->d[1] = c->beta;
    if (mbcomp_outputs(c->y, c->y + NQ, c->t, c->d, c->h2, c->p, c->w2, c->row)) {
        say(c, 1, "the outputs failed a guard at t=%g (a singular position, or a law's other branch)", c->t);
        return -1;
    }
    for (i = 0; i < NCOL; i++) c->ov[i] = c->row[i];
    for (i = 0; i < NROT; i++) mbcomp_quat(c->row + NCOL + 9 * i, c->ov + NCOL + 4 * i);
    return 0;
}

/* one variable's value: 0, or -1 after logging (an unknown reference, a failed evaluation);
   have is a per-call cache: bit 1 the derivatives, bit 2 the outputs are computed */
static int mb_get(Inst *c, unsigned vr, double *v, int *have)
{
#if HYBRID
    if (vr >= HY_VR) { int rc = mbev_get(c, vr, v); if (rc <= 0) return rc; }
#endif
    if (vr >= VR_OUT && vr < VR_OUT + NOV) {
        if (!(*have & 2)) {
            if (mb_outputs(c)) return -1;
            *have |= 2;
        }
        *v = c->ov[vr - VR_OUT];
        return 0;
    }
    if (vr < VR_X) { *v = c->p[vr]; return 0; }
#if SELECT
    if (!c->cs) {
        if (vr < VR_DX) { *v = c->x[vr - VR_X]; return 0; }
        if (vr < NVR) {
            if (!(*have & 1)) {
                double tmp[NXS + 1];
                if (mb_get_dx(c, tmp, NXS)) return -1;
                *have |= 1;
            }
            *v = c->dx[vr - VR_DX];
            return 0;
        }
    } else if (vr < NVR) {  /* Co-Simulation integrates [q, u]: the states x read from it */
        int k = (int)(vr < VR_DX ? vr - VR_X : vr - VR_DX);
        if (vr >= VR_DX && !(*have & 1)) {
            if (mb_derivatives(c)) return -1;
            *have |= 1;
        }
        if (k < NQ) { *v = vr < VR_DX ? c->y[k] : c->dy[k]; return 0; }
        *v = vr < VR_DX ? c->y[NQ + c->ind[k - NQ]] : c->dy[NQ + c->ind[k - NQ]];
        return 0;
    }
#else
    if (vr < VR_DX) { *v = c->y[vr - VR_X]; return 0; }
    if (vr < NVR) {
        if (!(*have & 1)) {
            if (mb_derivatives(c)) return -1;
            *have |= 1;
        }
        *v = c->dy[vr - VR_DX];
        return 0;
    }
#endif
    if (vr == VR_TIME) { *v = c->t; return 0; }
    if (vr >= VR_START && vr < VR_START + NX) { *v = c->y0[vr - VR_START]; return 0; }
    if (vr == VR_TOL) { *v = c->rtol; return 0; }
    if (vr >= VR_IN && vr < VR_IN + NIN) { *v = c->d[2 + (vr - VR_IN)]; return 0; }
    say(c, 1, "no variable has the value reference %u", vr);
    return -1;
}

/* a start value of y[i] (0 <= i < NX) set by the importer before the run: kept by the
   initialization (its direction fixed), the model's guesses moved to meet the constraints */
static int mb_set_start(Inst *c, int i, double v)
{
    int k;
    if (!isfinite(v)) { say(c, 1, "the start value of %s set to %g: not finite", YNAME[i], v); return -1; }
    c->y0[i] = v;
    c->y[i] = v;  /* read back as set until the initialization closes the constraints */
#if SELECT
    if (i < NQ) c->x[i] = v;
    for (k = 0; k < NI; k++)
        if (NQ + c->ind[k] == i) c->x[NQ + k] = v;
#endif
    c->set[i] = 1;
    if (i < NQ) {
        for (k = 0; k < QDIRN[i]; k++) c->pfree[QDIR[i] + k] = 0;
    } else {
        c->vfree[i - NQ] = 0;
    }
    c->starts_changed = 1;
    return 0;
}

static int mb_set(Inst *c, unsigned vr, double v)
{
    if (vr < VR_X) {
        if (c->mode != M_INSTANTIATED && c->mode != M_INIT) {
            say(c, 1, "%s is a parameter fixed after initialization", mb_name(vr));
            return -1;
        }
        if (mb_check_value(c, vr, v)) return -1;
        c->p[vr] = v;
        c->dirty = 1;
        return 0;
    }
    if (vr < VR_DX && c->mode != M_INSTANTIATED && c->mode != M_INIT) {
        say(c, 1, "the state %s can be set only before ExitInitializationMode (then by SetContinuousStates)",
            mb_name(vr));
        return -1;
    }
    if (vr < VR_DX) {  /* a state's start value, set before the run: kept by the initialization */
        int k = (int)(vr - VR_X);
#if SELECT
        if (!c->cs && k >= NQ) return mb_set_start(c, NQ + IND0[k - NQ], v);
        if (c->cs && k >= NQ) return mb_set_start(c, NQ + c->ind[k - NQ], v);
#endif
        return mb_set_start(c, k, v);
    }
#if SELECT
    if (vr < VR_DX) {
        int k = (int)(vr - VR_X);
        if (c->cs) {
            if (k < NQ) c->y[k] = v;
            else c->y[NQ + c->ind[k - NQ]] = v;
        } else {
            c->x[k] = v;
            c->x_dirty = 1;
        }
        return 0;
    }
#else
    if (vr < VR_DX) { c->y[vr - VR_X] = v; return 0; }
#endif
    if (vr == VR_TOL) {
        if (c->mode != M_INSTANTIATED && c->mode != M_INIT) {
            say(c, 1, "%s is a parameter fixed after initialization", mb_name(vr));
            return -1;
        }
        if (!(v >= 1e-14 && v < 1.0)) { say(c, 1, "%s = %g is out of range (1e-14 .. 1)", mb_name(vr), v); return -1; }
        c->rtol = v;
        c->tol_set = 1;
        return 0;
    }
    if (vr >= VR_START && vr < VR_START + NX) {
        if (c->mode != M_INSTANTIATED && c->mode != M_INIT) {
            say(c, 1, "%s is a parameter fixed after initialization", mb_name(vr));
            return -1;
        }
        return mb_set_start(c, (int)(vr - VR_START), v);
    }
    if (vr >= VR_IN && vr < VR_IN + NIN) {
        if (!isfinite(v)) { say(c, 1, "the input %s set to a non-finite value", mb_name(vr)); return -1; }
        c->d[2 + (vr - VR_IN)] = v;
        return 0;
    }
    if (vr < (unsigned)NNAMES)
        say(c, 1, "%s cannot be set (a derivative, the time or an output: the FMU computes it)", mb_name(vr));
    else
        say(c, 1, "no variable has the value reference %u", vr);
    return -1;
}

/* --- Model Exchange states ------------------------------------------------------------------
 * Without SELECT the states are y = [q, u]. With SELECT (a model with constraints) they are
 * x = [q, v], v = u[ind] the independent speeds of a partition (D'Alembert's projection of the
 * dynamics, mbrt_dalembert_rhs); the dependent speeds follow from A u = 0; the partition is
 * chosen again, and [q, u] projected onto the constraints, in Event Mode when the dependent
 * block degrades (|A_d^-1 A_i| above GROWTH_MAX) or the positions drift (|Phi| above DRIFT). */
#if SELECT
/* A = [C[rows]; B] and [dPhi/dt[rows]; Psi] at (q, u) = c->y into c->a and c->rhs_d (evaluates) */
static int mb_rows(Inst *c)
{
    int r, j;
    if (mb_refresh(c)) return -1;
    if (mbcomp_eval(c->y, c->y + NQ, c->t, c->d, c->h3, c->p, c->w3, c->ev)) {
        say(c, 1, "the evaluation failed a guard at t=%g (a singular position, or a law's other branch)", c->t);
        return -1;
    }
    for (r = 0; r < NROWS; r++) {
        for (j = 0; j < NU; j++) c->a[r * NU + j] = c->ev[OFF_C + MECH_ROWS[r] * NU + j];
        c->rhs_d[r] = c->ev[OFF_PHID + MECH_ROWS[r]];
    }
    for (r = 0; r < MN; r++) {
        for (j = 0; j < NU; j++) c->a[(NROWS + r) * NU + j] = c->ev[OFF_B + r * NU + j];
        c->rhs_d[NROWS + r] = c->ev[OFF_PSI + r];
    }
    return 0;
}

/* c->y = [q, u] from the states c->x: u[ind] = v, u[dep] solving A u = 0 */
static int mb_full_speeds(Inst *c)
{
    double *u = c->y + NQ;
    int i, j, k, rc;
    memcpy(c->y, c->x, sizeof(double) * NQ);
    for (i = 0; i < NU; i++) u[i] = 0.0;
    for (k = 0; k < NI; k++) u[c->ind[k]] = c->x[NQ + k];
    if (mb_rows(c)) return -1;
    for (i = 0; i < MM; i++)
        for (j = 0; j < MM; j++) c->ad[i * MM + j] = c->a[i * NU + c->dep[j]];
    rc = mbrt_lu_factor(MM, c->ad, c->piv);
    if (rc) {
        say(c, 1, "the dependent speeds' block is singular at t=%g (a singular position)", c->t);
        return -1;
    }
    mbrt_lu_solve(MM, c->ad, c->piv, c->rhs_d);
    for (j = 0; j < MM; j++) u[c->dep[j]] = -c->rhs_d[j];
    c->x_dirty = 0;
    return 0;
}

/* the partition dep/ind at c->y: MM columns of A by Gaussian elimination with complete
   pivoting (the best-conditioned choice it finds), the others independent, in order */
static int mb_choose(Inst *c)
{
    int k, i, j, r, best_i, best_j, used[NU + 1];
    double best, f;
    if (mb_rows(c)) return -1;
    memset(used, 0, sizeof used);
    for (k = 0; k < MM; k++) {
        best = 0.0; best_i = best_j = -1;
        for (i = k; i < MM; i++)
            for (j = 0; j < NU; j++)
                if (!used[j] && fabs(c->a[i * NU + j]) > best) { best = fabs(c->a[i * NU + j]); best_i = i; best_j = j; }
        if (best_i < 0 || !(best > 0.0)) {
            say(c, 1, "the constraint rows have lost rank at t=%g: no set of dependent speeds exists", c->t);
            return -1;
        }
        for (j = 0; j < NU; j++) { f = c->a[k * NU + j]; c->a[k * NU + j] = c->a[best_i * NU + j]; c->a[best_i * NU + j] = f; }
        for (r = k + 1; r < MM; r++) {
            f = c->a[r * NU + best_j] / c->a[k * NU + best_j];
            for (j = 0; j < NU; j++) c->a[r * NU + j] -= f * c->a[k * NU + j];
        }
        used[best_j] = 1;
        c->dep[k] = best_j;
    }
    for (j = 0, k = 0; j < NU; j++)
        if (!used[j]) c->ind[k++] = j;
    return 0;
}

/* c->x from c->y in the current partition */
static void mb_x_of_y(Inst *c)
{
    int k;
    memcpy(c->x, c->y, sizeof(double) * NQ);
    for (k = 0; k < NI; k++) c->x[NQ + k] = c->y[NQ + c->ind[k]];
}
#endif

/* entering the run after initialization: the states in their first partition */
static int mb_start_states(Inst *c)
{
    if (c->starts_changed) {  /* new start values: the state from them, onto the constraints */
        memcpy(c->y, c->y0, sizeof(double) * NX);
#if MECH
        {  /* mbcomp's consistent initialization: the fixed starts kept, the guesses moved */
            double norm = 0.0;
            int rc = mbrt_project_free(&c->mech, c->t, c->y, c->pfree, c->vfree, PROJ_TOL, 60, PROJ_ACCEPT, &norm,
                                       c->mwork);
            if (rc != MBRT_MECH_OK) {
                char names[256];
                size_t used = 0;
                int i;
                names[0] = '\0';
                for (i = 0; i < NX && used + 2 < sizeof names; i++) {
                    if (!c->set[i]) continue;
                    int w = snprintf(names + used, sizeof names - used, "%s%s = %g", used ? ", " : "", YNAME[i],
                                     c->y0[i]);
                    if (w < 0) break;
                    used += (size_t)w < sizeof names - used ? (size_t)w : sizeof names - used - 1;
                }
                say(c, 1, "the start values set (%s) and the model's fixed ones cannot all hold: the constraints "
                    "cannot be met with them (status %d, |Phi| = %g) -> set fewer of them, or values the "
                    "mechanism can reach", used ? names : "none", rc, norm);
                return -1;
            }
        }
#endif
#if HYBRID
        if (mbev_start(c)) return -1; /* onto the rows in force in the start modes (fmu_events.c) */
#endif
        c->starts_changed = 0;
    }
#if SELECT
    if (!c->cs) {
        if (mb_choose(c)) return -1;
        mb_x_of_y(c);
        c->event_due = 0;
    }
#else
    (void)c;
#endif
    return 0;
}

static int mb_set_x(Inst *c, const double *x, size_t n)
{
    if (n != NXS || !x) { say(c, 1, "%zu continuous states given, %d expected", n, NXS); return -1; }
#if SELECT
    memcpy(c->x, x, sizeof(double) * NXS);
    c->x_dirty = 1;
#else
    memcpy(c->y, x, sizeof(double) * NX);
#endif
    return 0;
}

static int mb_get_x(Inst *c, double *x, size_t n)
{
    if (n != NXS || !x) { say(c, 1, "%zu continuous states asked for, %d exist", n, NXS); return -1; }
#if SELECT
    memcpy(x, c->x, sizeof(double) * NXS);
#else
    memcpy(x, c->y, sizeof(double) * NX);
#endif
    return 0;
}

static int mb_get_dx(Inst *c, double *dx, size_t n)
{
    if (n != NXS || !dx) { say(c, 1, "%zu derivatives asked for, %d states exist", n, NXS); return -1; }
#if SELECT
    {
        double cond = 1.0;
        int rc;
        if (mb_refresh(c)) return -1;
        rc = mbrt_dalembert_rhs(&c->mech, c->t, c->x, c->dep, c->ind, MM, c->dx, &c->growth, &cond, c->mwork, c->iwork);
        if (rc != MBRT_MECH_OK) {
            say(c, 1, "the right-hand side failed at t=%g (status %d: a singular position or partition)", c->t, rc);
            return -1;
        }
        memcpy(dx, c->dx, sizeof(double) * NXS);
    }
#else
    if (mb_derivatives(c)) return -1;
    memcpy(dx, c->dy, sizeof(double) * NX);
#endif
    return 0;
}

static int mb_nominals(Inst *c, double *x, size_t n)
{
    if (n != NXS || !x) return -1;
#if SELECT
    {
        int k;
        memcpy(x, NOMINAL, sizeof(double) * NQ);
        for (k = 0; k < NI; k++) x[NQ + k] = NOMINAL[NQ + c->ind[k]];
    }
#else
    (void)c;
    memcpy(x, NOMINAL, sizeof(double) * NX);
#endif
    return 0;
}

/* after an accepted integrator step: whether Event Mode is needed (partition, drift) */
static int mb_completed(Inst *c, int *event)
{
    *event = 0;
#if SELECT
    {
        int r;
        double drift = 0.0;
        if (mb_full_speeds(c)) return -1;
        for (r = 0; r < NROWS; r++) drift = fmax(drift, fabs(c->ev[OFF_PHI + MECH_ROWS[r]]));
        c->event_due = c->growth > GROWTH_MAX || drift > fmax(DRIFT, DRIFT_RTOL * c->rtol);
        *event = c->event_due;
    }
#else
    (void)c;
#endif
    return 0;
}

/* in Event Mode: project and choose the partition again if due; *changed: the states moved */
static int mb_update(Inst *c, int *changed)
{
    *changed = 0;
#if HYBRID
    return mbev_act(c, -1, changed); /* the impacts and mode switches due */
#endif
#if SELECT
    if (c->event_due) {
        double norm = 0.0;
        int old[MM + 1], k, same = 1, rc;
        if (mb_full_speeds(c)) return -1;
        rc = mbrt_project(&c->mech, c->t, c->y, PROJ_TOL, PROJ_ITER, PROJ_ACCEPT, &norm, c->mwork);
        if (rc != MBRT_MECH_OK) {
            say(c, 1, "the projection onto the constraints failed at t=%g (status %d, |Phi| = %g)", c->t, rc, norm);
            return -1;
        }
        memcpy(old, c->dep, sizeof(int) * MM);
        if (mb_choose(c)) return -1;
        for (k = 0; k < MM; k++) same &= old[k] == c->dep[k];
        c->repartitions += !same;
        mb_x_of_y(c);
        c->event_due = 0;
        *changed = 1;
    }
#else
    (void)c;
#endif
    return 0;
}

#include "fmu_events.c"
#include "fmu_state.c"
#include "fmu_derivatives.c" /* exact directional and adjoint derivatives */
