/*
 * mbrt_mech.c -- constrained-mechanics kernels over a model's evaluation
 * program: the D'Alembert (coordinate-partitioning) right-hand side and the
 * projection of a state [q, u] onto the constraint manifold.
 *
 * Both work on the flat output of an evaluation program (mbcomp's generated
 * mbcomp_eval, see mbrt_mech in mbrt.h): the mass matrix M, the forces f, the
 * holonomic rows Phi, dPhi/dt, their Jacobian C and bias c_b (all cut-joint
 * rows; the kept ones are listed in P->rows), and the nonholonomic rows B,
 * their bias B_b and residual Psi = B u - b.  The velocity rows are
 * A = [C[rows]; B] with residual [dPhi/dt[rows]; Psi] and acceleration bias
 * [c_b[rows]; B_b].
 *
 * Each routine mirrors a Python routine of mbcomp step by step (the Python
 * one is the reference the tests compare with to 1e-12):
 *
 *   mbrt_dalembert_rhs   formulations/dalembert.py DAlembert.fun: speeds(),
 *                        a second evaluation, _reduce(), N^T M N, Cholesky;
 *   mbrt_project         formulations/lagrange.py LagrangeIndex1.project:
 *                        quaternions normalized, Gauss-Newton with minimum-norm
 *                        steps on Phi(q) = 0 along the speeds (coordinates moved
 *                        additively or, for quaternions, by a finite rotation)
 *                        (assembly/manifold.py close_positions), then the
 *                        minimum-norm speed correction onto A u = 0.
 *
 * Minimum-norm solutions are x = J^T (J J^T)^-1 r by Cholesky; a pivot of
 * J J^T below MBRT_MECH_RANK_TOL times its largest diagonal entry (J's rows
 * dependent to ~7 digits) is reported as MBRT_MECH_SINGULAR instead of being
 * used, so the caller decides with a rank-revealing method.  No allocation,
 * no global state; scratch comes from the caller (mbrt_mech_work_size).
 */
#include "mbrt.h"

#include <math.h>
#include <string.h>

/* relative pivot of J J^T below which the rows of J count as dependent */
#define MBRT_MECH_RANK_TOL 1e-14
/* one-sided Jacobi sweeps at most (it converges quadratically: 5-8 for n <= 30) */
#define MBRT_JACOBI_SWEEPS 60

/* ------------------------------------------------------------------ helpers */

static int nvel(const mbrt_mech *P) { return P->nrows + P->mn; }

/* row k of A = [C[rows]; B] in the flat output */
static const double *arow(const mbrt_mech *P, const double *out, int k)
{
    return k < P->nrows ? out + P->off_C + (size_t)P->rows[k] * (size_t)P->nu
                        : out + P->off_B + (size_t)(k - P->nrows) * (size_t)P->nu;
}

/* velocity residual [dPhi/dt[rows]; Psi] and acceleration bias [c_b[rows]; B_b] of row k */
static double ares(const mbrt_mech *P, const double *out, int k)
{
    return k < P->nrows ? out[P->off_Phid + P->rows[k]] : out[P->off_Psi + (k - P->nrows)];
}

static double abias(const mbrt_mech *P, const double *out, int k)
{
    return k < P->nrows ? out[P->off_cb + P->rows[k]] : out[P->off_Bb + (k - P->nrows)];
}

static int finite_all(int n, const double *v)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* Runs the evaluation program; MBRT_MECH_FALLBACK when a guard failed or a
 * value is not finite (the caller evaluates on its reference path). */
static int evaluate(const mbrt_mech *P, double t, const double *q, const double *u, double *out)
{
    if (P->eval(q, u, t, P->d, P->h, P->p, P->w, out))
        return MBRT_MECH_FALLBACK;
    return finite_all(P->n_out, out) ? MBRT_MECH_OK : MBRT_MECH_FALLBACK;
}

/* x = J^T (J J^T)^-1 r for the m x n rows J (given by a row accessor through
 * the flat output); G is m*m scratch, z m scratch.  Returns MBRT_MECH_OK or
 * MBRT_MECH_SINGULAR (dependent rows, see MBRT_MECH_RANK_TOL). */
static int min_norm(const mbrt_mech *P, const double *out, int m, int n, const double *r, double *x,
                    double *G, double *z, const unsigned char *free)
{
    /* free (NULL: every column): the columns the step may use; the others are 0 in x, and the
       step is the minimum-norm one in the free columns (J_f x_f = r, J_f: J's free columns) */
    double gmax = 0.0;
    for (int i = 0; i < m; ++i) {
        const double *ri = arow(P, out, i);
        for (int j = 0; j <= i; ++j) {
            const double *rj = arow(P, out, j);
            double s = 0.0;
            for (int k = 0; k < n; ++k)
                if (free == NULL || free[k])
                    s += ri[k] * rj[k];
            G[(size_t)i * m + j] = s;
        }
        gmax = fmax(gmax, G[(size_t)i * m + i]);
    }
    if (mbrt_chol_factor(m, G) != 0)
        return MBRT_MECH_SINGULAR;
    for (int i = 0; i < m; ++i) {
        double l = G[(size_t)i * m + i];
        if (!(l * l > MBRT_MECH_RANK_TOL * gmax))
            return MBRT_MECH_SINGULAR;
    }
    memcpy(z, r, sizeof(double) * (size_t)m);
    mbrt_chol_solve(m, G, z);
    for (int k = 0; k < n; ++k)
        x[k] = 0.0;
    for (int i = 0; i < m; ++i) {
        const double *ri = arow(P, out, i);
        for (int k = 0; k < n; ++k)
            if (free == NULL || free[k])
                x[k] += ri[k] * z[i];
    }
    return finite_all(n, x) ? MBRT_MECH_OK : MBRT_MECH_SINGULAR;
}

/* 2-norm condition number of the n x n row-major matrix A (copied to S, n*n
 * scratch) by one-sided Jacobi (Hestenes): rotate pairs of rows until they
 * are orthogonal; the singular values are then the row norms.  INFINITY for
 * a singular matrix, 1 for n <= 1 with a nonzero entry. */
double mbrt_cond2(int n, const double *A, double *S)
{
    if (n <= 0)
        return 1.0;
    memcpy(S, A, sizeof(double) * (size_t)n * (size_t)n);
    for (int sweep = 0; sweep < MBRT_JACOBI_SWEEPS; ++sweep) {
        int rotated = 0;
        for (int p = 0; p < n - 1; ++p) {
            double *sp = S + (size_t)p * n;
            for (int q = p + 1; q < n; ++q) {
                double *sq = S + (size_t)q * n;
                double a = 0.0, b = 0.0, g = 0.0;
                for (int k = 0; k < n; ++k) {
                    a += sp[k] * sp[k];
                    b += sq[k] * sq[k];
                    g += sp[k] * sq[k];
                }
                if (!(fabs(g) > 1e-15 * sqrt(a * b)))
                    continue;  /* orthogonal to working precision (also a or b zero) */
                rotated = 1;
                double zeta = (b - a) / (2.0 * g);
                double tt = (zeta >= 0.0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                double c = 1.0 / sqrt(1.0 + tt * tt), s = c * tt;
                for (int k = 0; k < n; ++k) {
                    double x = sp[k], y = sq[k];
                    sp[k] = c * x - s * y;
                    sq[k] = s * x + c * y;
                }
            }
        }
        if (!rotated)
            break;
    }
    double smax = 0.0, smin = INFINITY;
    for (int i = 0; i < n; ++i) {
        double s = 0.0;
        for (int k = 0; k < n; ++k)
            s += S[(size_t)i * n + k] * S[(size_t)i * n + k];
        s = sqrt(s);
        smax = fmax(smax, s);
        smin = fmin(smin, s);
    }
    if (!(smin > 0.0))
        return INFINITY;
    return smax / smin;
}

/* ------------------------------------------------------------------ sizes */

static int mech_ok(const mbrt_mech *P)
{
    if (P == NULL || P->eval == NULL || P->nq < 0 || P->nu < 0 || P->n_out < 0 || P->mh < 0 || P->mn < 0 ||
        P->nrows < 0 || P->nrows > P->mh || (P->nrows > 0 && P->rows == NULL) || (P->qrate == NULL && P->nq != P->nu))
        return 0;
    for (int k = 0; k < P->nrows; ++k)
        if (P->rows[k] < 0 || P->rows[k] >= P->mh)
            return 0;
    return 1;
}

size_t mbrt_mech_work_size(const mbrt_mech *P)
{
    if (P == NULL || P->nu < 0 || P->nq < 0 || P->n_out < 0)
        return 0;
    size_t nu = (size_t)P->nu, nq = (size_t)P->nq, m = (size_t)(P->nrows + P->mn);
    size_t ni = nu > m ? nu - m : 0;
    /* D'Alembert: out, u, w, tmp (nu each), Ad, S (m*m each), Nd (m*ni), MN (nu*ni), Mr (ni*ni), fr (ni) */
    size_t dal = (size_t)P->n_out + 3 * nu + 2 * m * m + m * ni + nu * ni + ni * ni + ni + m;
    /* projection: out, q, u, step (nu), G (m*m), z, r (m) */
    size_t prj = (size_t)P->n_out + nq + 2 * nu + m * m + 2 * m;
    return (dal > prj ? dal : prj) + 1;
}

/* ------------------------------------------------------------------ D'Alembert */

int mbrt_dalembert_rhs(const mbrt_mech *P, double t, const double *y, const int *dep, const int *ind, int nd,
                       double *dy, double *growth, double *cond, double *work, int *iwork)
{
    if (!mech_ok(P) || y == NULL || dy == NULL || growth == NULL || cond == NULL || work == NULL || nd < 0 ||
        nd > P->nu)
        return MBRT_MECH_BAD_ARGUMENT;
    const int nu = P->nu, nq = P->nq, ni = nu - nd, m = nvel(P);
    if (nd != m || iwork == NULL || (nd > 0 && dep == NULL) || (ni > 0 && ind == NULL))
        return MBRT_MECH_BAD_ARGUMENT;
    {   /* dep and ind must partition 0..nu-1 (iwork[nd..nd+nu) marks them) */
        int *mark = iwork + nd;
        for (int i = 0; i < nu; ++i)
            mark[i] = 0;
        for (int i = 0; i < nd; ++i) {
            if (dep[i] < 0 || dep[i] >= nu || mark[dep[i]])
                return MBRT_MECH_BAD_ARGUMENT;
            mark[dep[i]] = 1;
        }
        for (int i = 0; i < ni; ++i) {
            if (ind[i] < 0 || ind[i] >= nu || mark[ind[i]])
                return MBRT_MECH_BAD_ARGUMENT;
            mark[ind[i]] = 1;
        }
    }
    double *out = work, *u = out + P->n_out, *w = u + nu, *tmp = w + nu;
    double *Ad = tmp + nu, *S = Ad + (size_t)nd * nd, *Nd = S + (size_t)nd * nd;
    double *MN = Nd + (size_t)nd * ni, *Mr = MN + (size_t)nu * ni, *fr = Mr + (size_t)ni * ni;
    double *rhs = fr + ni;
    int *piv = iwork;
    const double *q = y, *v = y + nq;
    int rc;

    *growth = 0.0;
    *cond = 1.0;
    for (int i = 0; i < nu; ++i)
        u[i] = 0.0;
    for (int j = 0; j < ni; ++j)
        u[ind[j]] = v[j];
    if (nd > 0) {
        /* speeds(): the dependent speeds from A u = 0, exactly (square block) */
        if ((rc = evaluate(P, t, q, u, out)) != MBRT_MECH_OK)
            return rc;
        for (int i = 0; i < nd; ++i) {
            const double *ai = arow(P, out, i);
            for (int j = 0; j < nd; ++j)
                Ad[(size_t)i * nd + j] = ai[dep[j]];
            rhs[i] = ares(P, out, i);
        }
        if (mbrt_lu_factor(nd, Ad, piv) != 0)
            return MBRT_MECH_SINGULAR;
        mbrt_lu_solve(nd, Ad, piv, rhs);
        for (int j = 0; j < nd; ++j)
            u[dep[j]] -= rhs[j];
    }
    if ((rc = evaluate(P, t, q, u, out)) != MBRT_MECH_OK)
        return rc;
    const double *M = out + P->off_M, *f = out + P->off_f;
    for (int i = 0; i < nu; ++i)
        w[i] = 0.0;
    if (nd > 0) {
        /* _reduce(): N_d = -A_d^-1 A_i, w_d = -A_d^-1 bias, and the conditioning figures */
        for (int i = 0; i < nd; ++i) {
            const double *ai = arow(P, out, i);
            for (int j = 0; j < nd; ++j)
                Ad[(size_t)i * nd + j] = ai[dep[j]];
        }
        *cond = nd > 1 ? mbrt_cond2(nd, Ad, S) : 1.0;
        if (mbrt_lu_factor(nd, Ad, piv) != 0)
            return MBRT_MECH_SINGULAR;
        double g = 0.0;
        for (int j = 0; j < ni; ++j) {
            for (int i = 0; i < nd; ++i)
                rhs[i] = arow(P, out, i)[ind[j]];
            mbrt_lu_solve(nd, Ad, piv, rhs);
            for (int i = 0; i < nd; ++i) {
                Nd[(size_t)i * ni + j] = -rhs[i];
                g = fmax(g, fabs(rhs[i]));
            }
        }
        *growth = g;
        for (int i = 0; i < nd; ++i)
            rhs[i] = -abias(P, out, i);
        mbrt_lu_solve(nd, Ad, piv, rhs);
        for (int i = 0; i < nd; ++i)
            w[dep[i]] = rhs[i];
    }
    /* Mr = N^T M N and fr = N^T (f - M w), with N[ind] = I and N[dep] = N_d */
    for (int i = 0; i < nu; ++i) {
        const double *Mi = M + (size_t)i * nu;
        double s = f[i];
        for (int k = 0; k < nd; ++k)
            s -= Mi[dep[k]] * w[dep[k]];
        tmp[i] = s;
        for (int j = 0; j < ni; ++j) {
            double mn = Mi[ind[j]];
            for (int k = 0; k < nd; ++k)
                mn += Mi[dep[k]] * Nd[(size_t)k * ni + j];
            MN[(size_t)i * ni + j] = mn;
        }
    }
    for (int a = 0; a < ni; ++a) {
        double s = tmp[ind[a]];
        for (int k = 0; k < nd; ++k)
            s += Nd[(size_t)k * ni + a] * tmp[dep[k]];
        fr[a] = s;
        for (int b = 0; b < ni; ++b) {
            double r = MN[(size_t)ind[a] * ni + b];
            for (int k = 0; k < nd; ++k)
                r += Nd[(size_t)k * ni + a] * MN[(size_t)dep[k] * ni + b];
            Mr[(size_t)a * ni + b] = r;
        }
    }
    /* the upper triangle, as the reference's Cholesky reads it (M is symmetric to rounding) */
    for (int a = 1; a < ni; ++a)
        for (int b = 0; b < a; ++b)
            Mr[(size_t)a * ni + b] = Mr[(size_t)b * ni + a];
    if (mbrt_chol_factor(ni, Mr) != 0)
        return MBRT_MECH_MASS_SINGULAR;
    mbrt_chol_solve(ni, Mr, fr);
    /* dy = [dq/dt(q, u), dv/dt]: the independent rows of N dv/dt + w are dv/dt itself */
    if (P->qrate != NULL) {
        if (P->qrate(q, u, t, P->d, P->h, P->p, P->w, dy))
            return MBRT_MECH_FALLBACK;
    } else {
        memcpy(dy, u, sizeof(double) * (size_t)nu);
    }
    memcpy(dy + nq, fr, sizeof(double) * (size_t)ni);
    return finite_all(nq + ni, dy) ? MBRT_MECH_OK : MBRT_MECH_FALLBACK;
}

/* ------------------------------------------------------------------ projection */

/* Checks the coordinate map: segments inside q and u, every coordinate and speed covered
 * once at most, additive segments of equal width.  Without a map nq == nu is required. */
static int map_ok(const mbrt_mech *P)
{
    if (P->nseg == 0)
        return P->nq == P->nu;
    if (P->nseg < 0 || P->seg == NULL)
        return 0;
    int nq = 0, nu = 0;
    for (int k = 0; k < P->nseg; ++k) {
        const int *s = P->seg + 4 * (size_t)k;
        int kind = s[0], q0 = s[1], u0 = s[2], n = s[3];
        int wq = kind == MBRT_SEG_QUAT ? 4 : n, wu = kind == MBRT_SEG_QUAT ? 3 : n;
        if ((kind != MBRT_SEG_ADD && kind != MBRT_SEG_QUAT) || (kind == MBRT_SEG_QUAT && n != 1) || n < 0 ||
            q0 < 0 || u0 < 0 || q0 > P->nq - wq || u0 > P->nu - wu)
            return 0;
        nq += wq;
        nu += wu;
    }
    return nq == P->nq && nu == P->nu;  /* the segments cover q and u (the caller makes them disjoint) */
}

/* q moved by du along the speeds (MultibodySystem.increment): additive segments add, a
 * quaternion segment is turned by the rotation vector about its own axes and normalized
 * (quat_increment: Q * exp(d/2) / |...|).  du = NULL normalizes the quaternions only. */
static void increment(const mbrt_mech *P, double *q, const double *du, double sign)
{
    if (P->nseg == 0) {
        if (du != NULL)
            for (int i = 0; i < P->nu; ++i)
                q[i] += sign * du[i];
        return;
    }
    for (int k = 0; k < P->nseg; ++k) {
        const int *s = P->seg + 4 * (size_t)k;
        double *qs = q + s[1];
        const double *d = du != NULL ? du + s[2] : NULL;
        if (s[0] == MBRT_SEG_ADD) {
            if (d != NULL)
                for (int i = 0; i < s[3]; ++i)
                    qs[i] += sign * d[i];
            continue;
        }
        double r[4] = {1.0, 0.0, 0.0, 0.0};
        if (d != NULL) {
            double dx = sign * d[0], dy = sign * d[1], dz = sign * d[2];
            double ang = sqrt(dx * dx + dy * dy + dz * dz);
            if (!(ang < 1e-300)) {
                double sa = sin(0.5 * ang) / ang;
                r[0] = cos(0.5 * ang);
                r[1] = sa * dx;
                r[2] = sa * dy;
                r[3] = sa * dz;
            }
        }
        double pw = qs[0], px = qs[1], py = qs[2], pz = qs[3];
        double n0 = pw * r[0] - px * r[1] - py * r[2] - pz * r[3];
        double n1 = pw * r[1] + px * r[0] + py * r[3] - pz * r[2];
        double n2 = pw * r[2] - px * r[3] + py * r[0] + pz * r[1];
        double n3 = pw * r[3] + px * r[2] - py * r[1] + pz * r[0];
        double nn = sqrt(n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3);
        qs[0] = n0 / nn;
        qs[1] = n1 / nn;
        qs[2] = n2 / nn;
        qs[3] = n3 / nn;
    }
}

int mbrt_increment(int nq, int nu, int nseg, const int *seg, double *q, const double *du, double sign)
{
    mbrt_mech P;
    memset(&P, 0, sizeof P);
    P.nq = nq;
    P.nu = nu;
    P.nseg = nseg;
    P.seg = seg;
    if (q == NULL || nq < 0 || nu < 0 || !map_ok(&P))
        return MBRT_MECH_BAD_ARGUMENT;
    increment(&P, q, du, sign);
    return MBRT_MECH_OK;
}

int mbrt_project(const mbrt_mech *P, double t, double *y, double tol, int max_iter, double accept,
                 double *norm, double *work)
{
    return mbrt_project_free(P, t, y, NULL, NULL, tol, max_iter, accept, norm, work);
}

int mbrt_project_free(const mbrt_mech *P, double t, double *y, const unsigned char *pfree,
                      const unsigned char *vfree, double tol, int max_iter, double accept, double *norm,
                      double *work)
{
    if (!mech_ok(P) || y == NULL || work == NULL || !map_ok(P) || max_iter < 0 || !(tol >= 0.0))
        return MBRT_MECH_BAD_ARGUMENT;
    const int nq = P->nq, nu = P->nu, m = nvel(P), mh = P->nrows;
    double *out = work, *q = out + P->n_out, *u = q + nq, *step = u + nu, *G = step + nu, *z = G + (size_t)m * m;
    double *r = z + m;
    int rc;
    memcpy(q, y, sizeof(double) * (size_t)nq);
    memcpy(u, y + nq, sizeof(double) * (size_t)nu);
    increment(P, q, NULL, 1.0);  /* unit quaternions */
    if (!finite_all(nq, q))
        return MBRT_MECH_FALLBACK;
    if ((rc = evaluate(P, t, q, u, out)) != MBRT_MECH_OK)
        return rc;
    double nrm = 0.0;
    for (int k = 0; k < mh; ++k) {
        double phi = out[P->off_Phi + P->rows[k]];
        nrm += phi * phi;
    }
    nrm = sqrt(nrm);
    /* positions: Gauss-Newton with minimum-norm steps (close_positions, all speed directions) */
    for (int it = 0; mh > 0 && it < max_iter && nrm > tol; ++it) {
        for (int k = 0; k < mh; ++k)
            r[k] = out[P->off_Phi + P->rows[k]];
        /* only the holonomic rows: the accessor's first mh rows */
        if ((rc = min_norm(P, out, mh, nu, r, step, G, z, pfree)) != MBRT_MECH_OK)
            return rc;
        increment(P, q, step, -1.0);
        if (!finite_all(nq, q))
            return MBRT_MECH_SINGULAR;
        if ((rc = evaluate(P, t, q, u, out)) != MBRT_MECH_OK)
            return rc;
        nrm = 0.0;
        for (int k = 0; k < mh; ++k) {
            double phi = out[P->off_Phi + P->rows[k]];
            nrm += phi * phi;
        }
        nrm = sqrt(nrm);
    }
    if (norm != NULL)
        *norm = nrm;
    if (!(nrm <= tol) && !(nrm <= accept))
        return MBRT_MECH_NO_CONVERGENCE;
    /* speeds: the minimum-norm correction onto [dPhi/dt, Psi] = 0 (solve_speeds) */
    if (m > 0) {
        for (int k = 0; k < m; ++k)
            r[k] = ares(P, out, k);
        if ((rc = min_norm(P, out, m, nu, r, step, G, z, vfree)) != MBRT_MECH_OK)
            return rc;
        for (int i = 0; i < nu; ++i)
            u[i] -= step[i];
    }
    memcpy(y, q, sizeof(double) * (size_t)nq);
    memcpy(y + nq, u, sizeof(double) * (size_t)nu);
    return MBRT_MECH_OK;
}

/* ------------------------------------------------------------------ DAE forms */

/* Residual F of the semi-explicit multiplier forms (formulations/dae.py) at y = [q, u, a, lam
 * (, eta)]; out is n_out scratch for the evaluation, w nu scratch (GGL). */
static int dae_residual(const mbrt_mech *P, int form, double t, const double *y, const double *gains,
                        double *F, double *out, double *w)
{
    const int nq = P->nq, nu = P->nu, m = nvel(P), mh = P->nrows;
    const double *q = y, *u = y + nq, *a = u + nu, *lam = a + nu, *eta = lam + m;
    int rc;
    if ((rc = evaluate(P, t, q, u, out)) != MBRT_MECH_OK)
        return rc;
    const double *M = out + P->off_M, *f = out + P->off_f;
    const double *vel = u;
    if (form == MBRT_DAE_GGL && mh > 0) {  /* dq/dt = H(q) (u - C^T eta) */
        for (int i = 0; i < nu; ++i)
            w[i] = u[i];
        for (int k = 0; k < mh; ++k) {
            const double *ck = arow(P, out, k);
            for (int i = 0; i < nu; ++i)
                w[i] -= ck[i] * eta[k];
        }
        vel = w;
    }
    if (P->qrate != NULL) {
        if (P->qrate(q, vel, t, P->d, P->h, P->p, P->w, F))
            return MBRT_MECH_FALLBACK;
    } else {
        memcpy(F, vel, sizeof(double) * (size_t)nu);
    }
    double *Fa = F + nq, *Fd = Fa + nu, *Fc = Fd + nu;
    memcpy(Fa, a, sizeof(double) * (size_t)nu);
    for (int i = 0; i < nu; ++i) {  /* f - M a - A^T lam */
        const double *Mi = M + (size_t)i * nu;
        double s = f[i];
        for (int j = 0; j < nu; ++j)
            s -= Mi[j] * a[j];
        Fd[i] = s;
    }
    for (int k = 0; k < m; ++k) {
        const double *ak = arow(P, out, k);
        for (int i = 0; i < nu; ++i)
            Fd[i] -= ak[i] * lam[k];
    }
    if (form == MBRT_DAE_INDEX3) {         /* -Phi, -Psi */
        for (int k = 0; k < m; ++k)
            Fc[k] = k < mh ? -out[P->off_Phi + P->rows[k]] : -out[P->off_Psi + (k - mh)];
    } else if (form == MBRT_DAE_GGL) {     /* -dPhi/dt, -Psi, -Phi */
        for (int k = 0; k < m; ++k)
            Fc[k] = -ares(P, out, k);
        for (int k = 0; k < mh; ++k)
            Fc[m + k] = -out[P->off_Phi + P->rows[k]];
    } else {                               /* -(A a + bias), bias with the Baumgarte terms */
        for (int k = 0; k < m; ++k) {
            const double *ak = arow(P, out, k);
            double b = abias(P, out, k);
            if (gains != NULL)
                b += k < mh ? 2.0 * gains[0] * out[P->off_Phid + P->rows[k]] +
                                  gains[1] * gains[1] * out[P->off_Phi + P->rows[k]]
                            : gains[0] * out[P->off_Psi + (k - mh)];
            double s = 0.0;
            for (int i = 0; i < nu; ++i)
                s += ak[i] * a[i];
            Fc[k] = -(s + b);
        }
    }
    return finite_all(nq + 2 * nu + m + (form == MBRT_DAE_GGL ? mh : 0), F) ? MBRT_MECH_OK : MBRT_MECH_FALLBACK;
}

int mbrt_dae_size(const mbrt_mech *P, int form)
{
    if (P == NULL || (form != MBRT_DAE_INDEX1 && form != MBRT_DAE_GGL && form != MBRT_DAE_INDEX3))
        return -1;
    return P->nq + 2 * P->nu + nvel(P) + (form == MBRT_DAE_GGL ? P->nrows : 0);
}

size_t mbrt_dae_work_size(const mbrt_mech *P, int form)
{
    int n = mbrt_dae_size(P, form);
    if (n < 0 || P->n_out < 0)
        return 0;
    /* out (n_out), w (nu), yy, F1 (n each) */
    return (size_t)P->n_out + (size_t)P->nu + 2 * (size_t)n + 1;
}

int mbrt_dae_fun(const mbrt_mech *P, int form, double t, const double *y, const double *gains, double *F,
                 double *J, int *nfev, double *work)
{
    int n = mbrt_dae_size(P, form);
    if (!mech_ok(P) || n < 0 || y == NULL || F == NULL || work == NULL)
        return MBRT_MECH_BAD_ARGUMENT;
    if (nfev != NULL)
        *nfev = 0;
    const int nq = P->nq, nu = P->nu, m = nvel(P);
    double *out = work, *w = out + P->n_out, *yy = w + nu, *F1 = yy + n;
    int rc = dae_residual(P, form, t, y, gains, F, out, w);
    if (nfev != NULL)
        *nfev += 1;
    if (rc != MBRT_MECH_OK || J == NULL)
        return rc;
    /* forward differences over q, u (and eta), h = 1.5e-8 max(1, |y_i|), as dae.py's jac */
    memcpy(yy, y, sizeof(double) * (size_t)n);
    const int ia = nq + nu, il = nq + 2 * nu;
    for (int i = 0; i < n; ++i) {
        int fd = i < ia || (form == MBRT_DAE_GGL && i >= il + m);
        if (!fd)
            continue;
        double h = 1.5e-8 * fmax(1.0, fabs(y[i]));
        yy[i] = y[i] + h;
        rc = dae_residual(P, form, t, yy, gains, F1, out, w);
        if (nfev != NULL)
            *nfev += 1;
        yy[i] = y[i];
        if (rc != MBRT_MECH_OK)
            return rc;
        for (int r = 0; r < n; ++r)
            J[(size_t)r * n + i] = (F1[r] - F[r]) / h;
    }
    /* the columns of a and lam exactly: the residual is linear in them (M, A at (q, u)) */
    if ((rc = evaluate(P, t, y, y + nq, out)) != MBRT_MECH_OK)
        return rc;
    const double *M = out + P->off_M;
    for (int r = 0; r < n; ++r)
        for (int c = ia; c < il + m; ++c)
            J[(size_t)r * n + c] = 0.0;
    for (int i = 0; i < nu; ++i) {
        J[(size_t)(nq + i) * n + ia + i] = 1.0;
        for (int j = 0; j < nu; ++j)
            J[(size_t)(ia + i) * n + ia + j] = -M[(size_t)i * nu + j];
    }
    for (int k = 0; k < m; ++k) {
        const double *ak = arow(P, out, k);
        for (int i = 0; i < nu; ++i) {
            J[(size_t)(ia + i) * n + il + k] = -ak[i];
            if (form == MBRT_DAE_INDEX1)
                J[(size_t)(il + k) * n + ia + i] = -ak[i];
        }
    }
    return MBRT_MECH_OK;
}
