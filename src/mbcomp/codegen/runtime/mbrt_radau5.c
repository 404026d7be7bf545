/*
 * mbrt_radau5.c -- Radau IIA of order 5 (RADAU5) for stiff ODEs y' = f(t, y), the whole
 * integration in one call.
 *
 * The algorithm is the one of mbcomp's Python stepper (src/mbcomp/solvers/radau.py, after
 * Hairer & Wanner, "Solving ODEs II", Sec. IV.8) restricted to E = I (every variable
 * differential, index 1), step for step:
 *
 *   stages      Z = Y - y0 from (A^-1 (x) I) Z = h F(Z) by simplified Newton iterations,
 *               decoupled by T^-1 A^-1 T = diag(gamma, [[alpha, -beta], [beta, alpha]]) into
 *               the real system (gamma/h) I - J and the complex one (mu/h) I - J, each
 *               factored once (LU with partial pivoting after row and column equilibration;
 *               a pivot below 50 eps of the equilibrated matrix: singular).  At most 7
 *               iterations; the contraction rate theta decides slow convergence and
 *               divergence (the predicted error after the remaining iterations).
 *   error       err = ((gamma/h) I - J)^-1 (f(t0, y0) + sum_i d_i Z_i / h), the scaled RMS
 *               norm with sc_i = atol_i + rtol max(|y0_i|, |y1_i|); after a rejection or at
 *               the first step refiltered once with f(t0, y0 + err).
 *   step size   h_new = h / clip(err^(1/4) / fac, 1/8, 5), fac = 0.9 (2 NIT + 1) / (NIT +
 *               2 NIT); Gustafsson's predictive controller after accepted steps; no
 *               increase right after a failed attempt; 0.1 h after a failed first step.
 *   reuse       the Jacobian is kept when Newton contracted faster than 0.03; with it kept
 *               and h_new / h in [1, 1.2] h is kept too, and so are the factors.  A failed
 *               attempt with a stale Jacobian forms a new one first.
 *   predictor   the last step's collocation polynomial extrapolated to the new nodes.
 *   output      the collocation polynomial (degree 3) at the caller's t_out.
 *
 * The coefficients are the Python stepper's (derived there from the collocation definition),
 * written here as hexadecimal floats: the same numbers.  The linear algebra is this file's
 * own (the Python stepper's is LAPACK's), so the two agree to round-off, not bit for bit.
 *
 * A call can resume a previous one (resume != 0): the work buffer then still holds the
 * Jacobian, the factors, the predictor and the controller's memory, so that a run integrated
 * in stretches takes the steps of one call.
 */
#include "mbrt.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define NIT 7              /* Newton iterations at most (RADAU5's NIT)               */
#define THETA_JAC 0.03     /* keep the Jacobian below this contraction rate          */
#define SAFETY 0.9
#define FAC_MAX 8.0        /* largest step increase                                  */
#define FAC_MIN 0.2        /* largest decrease after an error-test rejection         */
#define QUOT_LO 1.0        /* keep h (and the factors) when h_new / h is in here     */
#define QUOT_HI 1.2
#define MAX_SINGULAR 5     /* consecutive singular matrices before giving up         */
#define MAX_FAILURES 60    /* consecutive failed attempts in one step                */
#define H_START 1e-6       /* shortest automatic first step                          */
#define PIVOT_TOL (50.0 * DBL_EPSILON)
#define DEFAULT_MAX_STEPS 100000L
#define HDR 16             /* doubles of the resumable header                        */

/* the Python stepper's coefficients (mbcomp.solvers.radau: C, T, TI, LAM, GAMMA, MU, D_ERR, P_DENSE) */
static const double C_[3] = {0x1.3d8b64657caeap-3, 0x1.4a36c0803a6dfp-1, 1.0};
static const double T_[9] = {0x1.82d23845d6779p-4, 0x1.0715053fb4eadp-3, 0x1.bf6cccc37fe73p-6,
                             0x1.0037de70aa1fap-2, -0x1.7c2eb3951e591p-3, -0x1.649b5c5d01267p-2,
                             1.0, -0x1.d19d567e523e0p-1, -0.0};
static const double TI_[9] = {0x1.0b70201a79c3fp+2, 0x1.4f8c15da84ea0p-2, 0x1.0bf7ff59d56f0p-1,
                              0x1.2614a65cf8d5dp+2, 0x1.70f99ce1aad9fp-2, -0x1.0c57949a59de5p-1,
                              0x1.1b1ed9d7c3a5ep-1, -0x1.6a00b9a724fa4p+1, 0x1.4f92ea3ad9822p-1};
static const double LAM_[9] = {0x1.d1a48d83e7320p+1, 0.0, 0.0, 0.0, 0x1.572db93e0c667p+1, -0x1.86747f2c3fcbdp+1,
                               0.0, 0x1.86747f2c3fcb3p+1, 0x1.572db93e0c675p+1};
static const double GAMMA_ = 0x1.d1a48d83e731bp+1;
static const double MU_RE = 0x1.572db93e0c667p+1, MU_IM = 0x1.86747f2c3fcbdp+1;
static const double D_[3] = {-0x1.418fd8baffe06p+3, 0x1.61d41b2d54583p+0, -0x1.5555555555533p-2};
static const double P_[9] = {0x1.418fd8baffe07p+3, -0x1.9a12ce7b30917p+4, 0x1.f295c43b61426p+3,
                             -0x1.61d41b2d54586p+0, 0x1.497af24bb6781p+3, -0x1.1d406ee60bed0p+3,
                             0x1.5555555555555p-2, -0x1.5555555555554p+1, 0x1.aaaaaaaaaaaaap+1};

void mbrt_radau5_coefficients(double *out)
{
    /* c (3), T (9), TI (9), LAM (9), gamma, mu (re, im), d (3), P (9): 45 doubles */
    memcpy(out, C_, sizeof C_);
    memcpy(out + 3, T_, sizeof T_);
    memcpy(out + 12, TI_, sizeof TI_);
    memcpy(out + 21, LAM_, sizeof LAM_);
    out[30] = GAMMA_;
    out[31] = MU_RE;
    out[32] = MU_IM;
    memcpy(out + 33, D_, sizeof D_);
    memcpy(out + 36, P_, sizeof P_);
}

/* The resumable header: what a call leaves for the next (resume != 0). */
enum { H_VALID, H_T, H_H, H_HACC, H_ERRACC, H_FACCON, H_FIRST, H_HAVE_J, H_JCUR, H_LU_H, H_DENSE,
       H_DT0, H_DH, H_N };

typedef struct {
    mbrt_rhs_fn f;
    mbrt_jac_fn jac;
    void *ctx;
    int n;
    double rtol, newton_tol;
    const double *atol;
    double *hdr;
    double *y, *fy, *ynew, *J, *E1, *E2, *r1, *s1, *r2, *s2;
    double *Z, *W, *F, *R, *dW, *yold, *Q, *scale, *ev, *tmp, *cz;
    int *p1, *p2;
    long nfev;
    mbrt_radau5_info *info;
    double t_fail;      /* time of an rhs call that returned nonzero */
    int rhs_rc;         /* its code                                   */
} R5;

size_t mbrt_radau5_work_size(int n)
{
    if (n <= 0)
        return 0;
    size_t m = (size_t)n;
    /* J, E1 (real), E2 (complex, interleaved); 31 vectors of n */
    return HDR + 4 * m * m + 31 * m;
}

size_t mbrt_radau5_iwork_size(int n) { return n <= 0 ? 0 : 2 * (size_t)n; }

static int finish(mbrt_stats *st, int status, double t, const char *fmt, ...)
{
    va_list ap;
    st->status = status;
    st->t = t;
    va_start(ap, fmt);
    vsnprintf(st->message, sizeof st->message, fmt, ap);
    va_end(ap);
    return status;
}

static int finite_all(int n, const double *v)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

static double rms(int n, const double *x, const double *sc)
{
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        double v = x[i] / sc[i];
        s += v * v;
    }
    return sqrt(s / n);
}

static int rhs(R5 *S, double t, const double *y, double *out)
{
    S->nfev++;
    int rc = S->f(S->ctx, t, y, out);
    if (rc != 0) {
        S->t_fail = t;
        S->rhs_rc = rc;
        return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------ Jacobian */
/* d f / d y at (t, y) into S->J: the caller's jac, else (NULL, nonzero, or a non-finite
 * entry) forward differences with delta_j = sqrt(eps max(1e-5, |y_j|)) rounded to what
 * y_j + delta_j represents.  Returns 0, 1 (the rhs failed) or -1 (a non-finite difference). */
static int jacobian(R5 *S, double t)
{
    int n = S->n;
    double *J = S->J;
    S->info->njev++;
    S->hdr[H_HAVE_J] = 1.0;
    S->hdr[H_JCUR] = 1.0;
    S->hdr[H_LU_H] = 0.0; /* the factors of the old J are void */
    if (S->jac != NULL && S->jac(S->ctx, t, S->y, S->fy, J) == 0 && finite_all(n * n, J))
        return 0;
    S->info->ndiff++;
    double *yp = S->tmp, *fp = S->ev;
    memcpy(yp, S->y, sizeof(double) * (size_t)n);
    for (int j = 0; j < n; ++j) {
        double yj = S->y[j];
        double delta = sqrt(DBL_EPSILON * fmax(1e-5, fabs(yj)));
        yp[j] = yj + delta;
        delta = yp[j] - yj;
        int rc = rhs(S, t, yp, fp);
        if (rc != 0)
            return rc;
        if (!finite_all(n, fp))
            return -1;
        for (int i = 0; i < n; ++i)
            J[(size_t)i * n + j] = (fp[i] - S->fy[i]) / delta;
        yp[j] = yj;
    }
    return 0;
}

/* ------------------------------------------------------------------ factors */
/* LU with partial pivoting of the n x n row-major real A in place; |pivot| below tol or
 * not finite: returns 1 + its index. */
static int lu_real(int n, double *A, int *piv, double *pmin)
{
    double smallest = INFINITY;
    for (int k = 0; k < n; ++k) {
        int p = k;
        double big = fabs(A[(size_t)k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            double v = fabs(A[(size_t)i * n + k]);
            if (v > big) {
                big = v;
                p = i;
            }
        }
        piv[k] = p;
        if (p != k)
            for (int j = 0; j < n; ++j) {
                double tmp = A[(size_t)k * n + j];
                A[(size_t)k * n + j] = A[(size_t)p * n + j];
                A[(size_t)p * n + j] = tmp;
            }
        double d = A[(size_t)k * n + k];
        smallest = fmin(smallest, fabs(d));
        if (!(fabs(d) > PIVOT_TOL) || !isfinite(d)) {
            *pmin = fabs(d);
            return k + 1;
        }
        for (int i = k + 1; i < n; ++i) {
            double l = A[(size_t)i * n + k] / d;
            A[(size_t)i * n + k] = l;
            if (l != 0.0)
                for (int j = k + 1; j < n; ++j)
                    A[(size_t)i * n + j] -= l * A[(size_t)k * n + j];
        }
    }
    *pmin = smallest;
    return 0;
}

/* The same for the complex A (interleaved re, im); pivots by |re| + |im| as LAPACK. */
static int lu_complex(int n, double *A, int *piv, double *pmin)
{
    double smallest = INFINITY;
    for (int k = 0; k < n; ++k) {
        int p = k;
        double big = -1.0;
        for (int i = k; i < n; ++i) {
            const double *a = A + 2 * ((size_t)i * n + k);
            double v = fabs(a[0]) + fabs(a[1]);
            if (v > big) {
                big = v;
                p = i;
            }
        }
        piv[k] = p;
        if (p != k)
            for (int j = 0; j < 2 * n; ++j) {
                double tmp = A[2 * (size_t)k * n + j];
                A[2 * (size_t)k * n + j] = A[2 * (size_t)p * n + j];
                A[2 * (size_t)p * n + j] = tmp;
            }
        double dre = A[2 * ((size_t)k * n + k)], dim = A[2 * ((size_t)k * n + k) + 1];
        double mod = hypot(dre, dim);
        smallest = fmin(smallest, mod);
        if (!(mod > PIVOT_TOL) || !isfinite(mod)) {
            *pmin = mod;
            return k + 1;
        }
        double den = dre * dre + dim * dim, ire = dre / den, iim = -dim / den; /* 1 / pivot */
        for (int i = k + 1; i < n; ++i) {
            double *a = A + 2 * ((size_t)i * n + k);
            double lre = a[0] * ire - a[1] * iim, lim = a[0] * iim + a[1] * ire;
            a[0] = lre;
            a[1] = lim;
            if (lre == 0.0 && lim == 0.0)
                continue;
            const double *u = A + 2 * (size_t)k * n;
            double *row = A + 2 * (size_t)i * n;
            for (int j = k + 1; j < n; ++j) {
                double ure = u[2 * j], uim = u[2 * j + 1];
                row[2 * j] -= lre * ure - lim * uim;
                row[2 * j + 1] -= lre * uim + lim * ure;
            }
        }
    }
    *pmin = smallest;
    return 0;
}

/* Factors (gamma/h) I - J and (mu/h) I - J after equilibration.  Returns 0, or 1 with the
 * reason in msg (structural: *structural = 1). */
static int factorize(R5 *S, double h, char *msg, size_t len, int *structural)
{
    int n = S->n;
    const double *J = S->J;
    double g = GAMMA_ / h, cre = MU_RE / h, cim = MU_IM / h;
    double *E1 = S->E1, *E2 = S->E2, *r1 = S->r1, *s1 = S->s1, *r2 = S->r2, *s2 = S->s2;
    *structural = 0;
    /* the matrices, and the row maxima of their magnitudes */
    for (int i = 0; i < n; ++i) {
        double m1 = 0.0, m2 = 0.0;
        for (int j = 0; j < n; ++j) {
            size_t ij = (size_t)i * n + j;
            double a = -J[ij];
            if (i == j) {
                double dre = cre + a, dim = cim;
                E1[ij] = a + g;
                E2[2 * ij] = dre;
                E2[2 * ij + 1] = dim;
                m1 = fmax(m1, fabs(E1[ij]));
                m2 = fmax(m2, hypot(dre, dim));
            } else {
                E1[ij] = a;
                E2[2 * ij] = a;
                E2[2 * ij + 1] = 0.0;
                m1 = fmax(m1, fabs(a));
                m2 = fmax(m2, fabs(a));
            }
        }
        if (!(m1 > 0.0) || !(m2 > 0.0)) {
            snprintf(msg, len, "equation %d involves no variable (row %d is zero)", i, i);
            *structural = 1;
            return 1;
        }
        r1[i] = 1.0 / m1;
        r2[i] = 1.0 / m2;
    }
    for (int j = 0; j < n; ++j) {
        double m1 = 0.0, m2 = 0.0;
        for (int i = 0; i < n; ++i) {
            size_t ij = (size_t)i * n + j;
            m1 = fmax(m1, fabs(E1[ij]) * r1[i]);
            m2 = fmax(m2, hypot(E2[2 * ij], E2[2 * ij + 1]) * r2[i]);
        }
        if (!(m1 > 0.0) || !(m2 > 0.0)) {
            snprintf(msg, len, "variable %d enters no equation (column %d is zero)", j, j);
            *structural = 1;
            return 1;
        }
        s1[j] = 1.0 / m1;
        s2[j] = 1.0 / m2;
    }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            size_t ij = (size_t)i * n + j;
            E1[ij] = E1[ij] * r1[i] * s1[j];
            E2[2 * ij] = E2[2 * ij] * r2[i] * s2[j];
            E2[2 * ij + 1] = E2[2 * ij + 1] * r2[i] * s2[j];
        }
    S->info->nlu += 2;
    double pmin;
    int k = lu_real(n, E1, S->p1, &pmin);
    if (k == 0)
        k = lu_complex(n, E2, S->p2, &pmin);
    if (k != 0) {
        snprintf(msg, len, "pivot %d of the equilibrated matrix is %.3g (rank deficient)", k - 1, pmin);
        return 1;
    }
    S->hdr[H_LU_H] = h;
    return 0;
}

/* x = ((gamma/h) I - J)^-1 b (b overwritten by x). */
static void solve_real(const R5 *S, double *b)
{
    int n = S->n;
    const double *A = S->E1;
    for (int i = 0; i < n; ++i)
        b[i] *= S->r1[i];
    for (int k = 0; k < n; ++k) { /* the rows' interchanges first (L's rows were swapped too) */
        int p = S->p1[k];
        double t = b[k];
        b[k] = b[p];
        b[p] = t;
    }
    for (int k = 0; k < n; ++k)
        for (int i = k + 1; i < n; ++i)
            b[i] -= A[(size_t)i * n + k] * b[k];
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int j = i + 1; j < n; ++j)
            s -= A[(size_t)i * n + j] * b[j];
        b[i] = s / A[(size_t)i * n + i];
    }
    for (int i = 0; i < n; ++i)
        b[i] *= S->s1[i];
}

/* x + i y = ((mu/h) I - J)^-1 (x + i y), in place; cz: 2n scratch. */
static void solve_complex(const R5 *S, double *x, double *y, double *cz)
{
    int n = S->n;
    const double *A = S->E2;
    for (int i = 0; i < n; ++i) {
        cz[2 * i] = x[i] * S->r2[i];
        cz[2 * i + 1] = y[i] * S->r2[i];
    }
    for (int k = 0; k < n; ++k) { /* the rows' interchanges first */
        int p = S->p2[k];
        double a = cz[2 * k], b = cz[2 * k + 1];
        cz[2 * k] = cz[2 * p];
        cz[2 * k + 1] = cz[2 * p + 1];
        cz[2 * p] = a;
        cz[2 * p + 1] = b;
    }
    for (int k = 0; k < n; ++k) {
        double bre = cz[2 * k], bim = cz[2 * k + 1];
        for (int i = k + 1; i < n; ++i) {
            const double *l = A + 2 * ((size_t)i * n + k);
            cz[2 * i] -= l[0] * bre - l[1] * bim;
            cz[2 * i + 1] -= l[0] * bim + l[1] * bre;
        }
    }
    for (int i = n - 1; i >= 0; --i) {
        double sre = cz[2 * i], sim = cz[2 * i + 1];
        const double *row = A + 2 * (size_t)i * n;
        for (int j = i + 1; j < n; ++j) {
            sre -= row[2 * j] * cz[2 * j] - row[2 * j + 1] * cz[2 * j + 1];
            sim -= row[2 * j] * cz[2 * j + 1] + row[2 * j + 1] * cz[2 * j];
        }
        double dre = row[2 * i], dim = row[2 * i + 1], den = dre * dre + dim * dim;
        cz[2 * i] = (sre * dre + sim * dim) / den;
        cz[2 * i + 1] = (sim * dre - sre * dim) / den;
    }
    for (int i = 0; i < n; ++i) {
        x[i] = cz[2 * i] * S->s2[i];
        y[i] = cz[2 * i + 1] * S->s2[i];
    }
}

/* out (3 x n) = M (3 x 3) . X (3 x n) */
static void mat3(int n, const double *M, const double *X, double *out)
{
    for (int r = 0; r < 3; ++r) {
        double a = M[3 * r], b = M[3 * r + 1], c = M[3 * r + 2];
        double *o = out + (size_t)r * n;
        const double *x0 = X, *x1 = X + n, *x2 = X + 2 * (size_t)n;
        for (int i = 0; i < n; ++i)
            o[i] = a * x0[i] + b * x1[i] + c * x2[i];
    }
}

/* ------------------------------------------------------------------ Newton */
/* The simplified Newton iteration from the predicted S->Z.  Returns 1 (converged: *theta,
 * *iters), 0 (failed: *fac the step factor, msg the reason), or -1 (an rhs failure). */
static int newton(R5 *S, double t, double h, double *theta_out, int *iters, double *fac, char *msg, size_t len)
{
    int n = S->n;
    size_t n3 = 3 * (size_t)n;
    double *Z = S->Z, *W = S->W, *F = S->F, *R = S->R, *dW = S->dW;
    mat3(n, TI_, Z, W);
    double mh = 1.0 / h;
    double faccon = pow(fmax(S->hdr[H_FACCON], DBL_EPSILON), 0.8);
    double theta = THETA_JAC, dnorm_old = 0.0, thq_old = 0.0;
    double tc[3] = {t + C_[0] * h, t + C_[1] * h, t + C_[2] * h};
    for (int k = 0; k < NIT; ++k) {
        S->info->nnewton++;
        for (int s = 0; s < 3; ++s) {
            double *ys = S->tmp;
            for (int i = 0; i < n; ++i)
                ys[i] = S->y[i] + Z[(size_t)s * n + i];
            if (rhs(S, tc[s], ys, F + (size_t)s * n) != 0)
                return -1;
        }
        mat3(n, TI_, F, R);
        mat3(n, LAM_, W, dW);
        for (size_t i = 0; i < n3; ++i)
            R[i] -= dW[i] * mh;
        memcpy(dW, R, n3 * sizeof(double));
        solve_real(S, dW);
        solve_complex(S, dW + n, dW + 2 * (size_t)n, S->cz);
        double ss = 0.0;
        for (int s = 0; s < 3; ++s)
            for (int i = 0; i < n; ++i) {
                double v = dW[(size_t)s * n + i] / S->scale[i];
                ss += v * v;
            }
        double dnorm = sqrt(ss / (double)n3);
        if (!isfinite(dnorm)) {
            *iters = k + 1;
            *fac = 0.5;
            snprintf(msg, len, "%s", finite_all((int)n3, F) ? "the Newton increment is not finite"
                                                           : "the right-hand side is not finite at a Newton iterate");
            return 0;
        }
        if (k >= 1) {
            double thq = dnorm_old > 0.0 ? dnorm / dnorm_old : 0.0;
            theta = (k == 1) ? thq : sqrt(thq * thq_old);
            thq_old = thq;
            if (theta < 0.99) {
                faccon = theta / (1.0 - theta);
                double dyth = faccon * dnorm * pow(theta, NIT - 1 - k) / S->newton_tol;
                if (dyth >= 1.0) {
                    double qnewt = fmax(1e-4, fmin(20.0, dyth));
                    *fac = 0.8 * pow(qnewt, -1.0 / (4 + NIT - 1 - k));
                    *iters = k + 1;
                    snprintf(msg, len, "Newton converges too slowly (rate %.3g)", theta);
                    return 0;
                }
            } else {
                *fac = 0.5;
                *iters = k + 1;
                snprintf(msg, len, "Newton diverges (rate %.3g)", theta);
                return 0;
            }
        }
        dnorm_old = dnorm;
        for (size_t i = 0; i < n3; ++i)
            W[i] += dW[i];
        mat3(n, T_, W, Z);
        if (faccon * dnorm <= S->newton_tol) {
            S->hdr[H_FACCON] = faccon;
            *theta_out = theta;
            *iters = k + 1;
            return 1;
        }
    }
    *fac = 0.5;
    *iters = NIT;
    snprintf(msg, len, "no convergence in %d Newton iterations", NIT);
    return 0;
}

/* The stage increments' prediction: the last step's collocation polynomial at the new nodes
 * (zero at the first step or when not finite). */
static void predict(R5 *S, double t, double h)
{
    int n = S->n;
    double *Z = S->Z;
    if (S->hdr[H_DENSE] != 0.0) {
        double t0 = S->hdr[H_DT0], h0 = S->hdr[H_DH];
        for (int s = 0; s < 3; ++s) {
            double x = ((t + C_[s] * h) - t0) / h0, x2 = x * x, x3 = x2 * x;
            for (int i = 0; i < n; ++i)
                Z[(size_t)s * n + i] = (S->yold[i] + (x * S->Q[i] + x2 * S->Q[n + i] + x3 * S->Q[2 * (size_t)n + i]))
                                       - S->y[i];
        }
        if (finite_all(3 * n, Z))
            return;
    }
    memset(Z, 0, 3 * (size_t)n * sizeof(double));
}

/* The scaled local error (>= 1e-10; INFINITY if not finite); -1 on an rhs failure. */
static double error_estimate(R5 *S, double t, double h, int refilter, const double *absy)
{
    int n = S->n;
    double *ev = S->ev, *mze = S->F, *tmp = S->tmp, *sc = S->R;
    for (int i = 0; i < n; ++i) {
        mze[i] = (D_[0] * S->Z[i] + D_[1] * S->Z[n + i] + D_[2] * S->Z[2 * (size_t)n + i]) / h;
        ev[i] = S->fy[i] + mze[i];
        sc[i] = S->atol[i] + S->rtol * fmax(absy[i], fabs(S->ynew[i]));
    }
    solve_real(S, ev);
    double err = rms(n, ev, sc);
    if (err >= 1.0 && refilter && isfinite(err)) {
        for (int i = 0; i < n; ++i)
            tmp[i] = S->y[i] + ev[i];
        double *f1 = S->dW;
        if (rhs(S, t, tmp, f1) != 0)
            return -1.0;
        if (finite_all(n, f1)) {
            for (int i = 0; i < n; ++i)
                ev[i] = f1[i] + mze[i];
            solve_real(S, ev);
            err = rms(n, ev, sc);
        }
    }
    if (!isfinite(err))
        err = INFINITY;
    return fmax(err, 1e-10);
}

static int check_args(mbrt_rhs_fn f, int n, double t0, const double *y0, double t_end, double rtol,
                      const double *atol, double h0, double hmax, long max_steps, const double *t_out,
                      int n_out, const double *y_out, const double *work, const int *iwork,
                      const mbrt_radau5_info *info, mbrt_stats *st)
{
    const int B = MBRT_BAD_ARGUMENT;
    if (f == NULL || y0 == NULL || atol == NULL || work == NULL || iwork == NULL || info == NULL)
        return finish(st, B, t0, "RADAU5: f, y0, atol, work, iwork and info must not be NULL.");
    if (n <= 0)
        return finish(st, B, t0, "RADAU5: the number of equations n=%d must be positive.", n);
    if (!isfinite(t0) || !isfinite(t_end) || !(t_end >= t0) || !isfinite(t_end - t0))
        return finish(st, B, t0, "RADAU5: t0=%.17g and t_end=%.17g must be finite, t_end >= t0.", t0, t_end);
    if (!isfinite(rtol) || !(rtol >= 100.0 * DBL_EPSILON))
        return finish(st, B, t0, "RADAU5: rtol=%g must be finite and at least 100*DBL_EPSILON.", rtol);
    for (int i = 0; i < n; ++i) {
        if (!isfinite(atol[i]) || atol[i] < 0.0)
            return finish(st, B, t0, "RADAU5: atol[%d]=%g must be finite and >= 0.", i, atol[i]);
        if (!isfinite(y0[i]))
            return finish(st, B, t0, "RADAU5: y0[%d]=%g is not finite.", i, y0[i]);
    }
    if (!isfinite(h0) || h0 < 0.0 || !isfinite(hmax) || hmax < 0.0 || max_steps < 0 || n_out < 0)
        return finish(st, B, t0, "RADAU5: h0=%g, hmax=%g, max_steps=%ld and n_out=%d must be finite and >= 0.",
                      h0, hmax, max_steps, n_out);
    if (n_out > 0 && (t_out == NULL || y_out == NULL))
        return finish(st, B, t0, "RADAU5: t_out and y_out must not be NULL when n_out=%d > 0.", n_out);
    for (int i = 0; i < n_out; ++i) {
        if (!(t_out[i] >= t0 && t_out[i] <= t_end))
            return finish(st, B, t0, "RADAU5: t_out[%d]=%.17g is outside [t0, t_end]=[%.17g, %.17g].", i, t_out[i],
                          t0, t_end);
        if (i > 0 && !(t_out[i] > t_out[i - 1]))
            return finish(st, B, t0, "RADAU5: t_out is not strictly increasing at index %d.", i);
    }
    return 0;
}

static void layout(R5 *S, double *work, int *iwork)
{
    size_t m = (size_t)S->n, mm = m * m;
    double *p = work;
    S->hdr = p;
    p += HDR;
    S->J = p;
    p += mm;
    S->E1 = p;
    p += mm;
    S->E2 = p;
    p += 2 * mm;
    double **v[] = {&S->y, &S->fy, &S->ynew, &S->r1, &S->s1, &S->r2, &S->s2, &S->yold, &S->scale, &S->ev, &S->tmp};
    for (size_t k = 0; k < sizeof v / sizeof v[0]; ++k) {
        *v[k] = p;
        p += m;
    }
    double **w[] = {&S->Z, &S->W, &S->F, &S->R, &S->dW, &S->Q};
    for (size_t k = 0; k < sizeof w / sizeof w[0]; ++k) { /* 3 n each */
        *w[k] = p;
        p += 3 * m;
    }
    S->cz = p; /* 2 n: 11 + 18 + 2 = 31 vectors of n in all */
    S->p1 = iwork;
    S->p2 = iwork != NULL ? iwork + m : NULL;
}

/* The first step: 0.01 ||y|| / ||y'|| (scaled), at least H_START, at most span and hmax. */
static double initial_step(const R5 *S, double span, double hmax)
{
    int n = S->n;
    double d0 = 0.0, d1 = 0.0;
    for (int i = 0; i < n; ++i) {
        double sc = S->atol[i] + S->rtol * fabs(S->y[i]);
        d0 += (S->y[i] / sc) * (S->y[i] / sc);
        d1 += (S->fy[i] / sc) * (S->fy[i] / sc);
    }
    d0 = sqrt(d0 / n);
    d1 = sqrt(d1 / n);
    double h = H_START;
    if (d0 > 1e-5 && d1 > 1e-5)
        h = fmax(H_START, 0.01 * d0 / d1);
    return fmin(fmin(h, span), hmax);
}

/* A failed attempt's next step size: a stale Jacobian (formed at an earlier point) is formed
 * again first, a current one kept (RADAU5's CALJAC).  0 or jacobian()'s code. */
static int retry(R5 *S, double t, double *h, double fac)
{
    *h *= fac;
    return S->hdr[H_JCUR] != 0.0 ? 0 : jacobian(S, t);
}

/* The collapsed step's message, naming the last cause. */
static int collapsed(mbrt_stats *st, int kind, double t, double h, const char *reason, int n_fail)
{
    if (kind == 1)
        return finish(st, MBRT_STEP_TOO_SMALL, t, "RADAU5: Newton iteration failed to converge at t=%.17g with "
                      "h=%.3g (step size collapsed): %s (%d consecutive failed attempts)", t, h, reason, n_fail);
    if (kind == 2)
        return finish(st, MBRT_STEP_TOO_SMALL, t, "RADAU5: step size collapsed at t=%.17g with h=%.3g: the local "
                      "error test keeps failing (last %s; %d consecutive failed attempts)", t, h, reason, n_fail);
    if (kind == 3)
        return finish(st, MBRT_RADAU5_SINGULAR, t, "RADAU5: the iteration matrix is singular at t=%.17g with "
                      "h=%.3g (step size collapsed): %s", t, h, reason);
    return finish(st, MBRT_STEP_TOO_SMALL, t, "RADAU5: step size collapsed at t=%.17g: h=%.3g is below "
                  "1e-14*|t| without a failed attempt in this step (the solution blows up or is not smooth there)",
                  t, h);
}

/* The Jacobian's failure (jacobian() returned rc != 0) as the integration's status. */
static int jacobian_failed(R5 *S, mbrt_stats *st, int rc, double t)
{
    if (rc > 0)
        return finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (difference Jacobian).",
                      S->rhs_rc, S->t_fail);
    return finish(st, MBRT_NONFINITE, t, "RADAU5: rhs returned non-finite values at t=%.17g "
                  "(difference Jacobian).", t);
}

/* Starts a fresh integration in the header, or resumes the previous one. */
static int begin(R5 *S, mbrt_stats *st, double t0, const double *y0, double h0, double hmax, double span,
                 int resume, double *h)
{
    int n = S->n;
    double *hd = S->hdr;
    size_t nb = (size_t)n * sizeof(double);
    if (resume && hd[H_VALID] == 1.0 && hd[H_N] == (double)n && hd[H_T] == t0) {
        *h = hd[H_H];
        if (memcmp(S->y, y0, nb) == 0)
            return 0;
        memcpy(S->y, y0, nb); /* a moved state (a projection): f again, the rest kept */
    } else {
        memset(hd, 0, HDR * sizeof(double));
        hd[H_N] = n;
        hd[H_FIRST] = 1.0;
        hd[H_FACCON] = 1.0;
        memcpy(S->y, y0, nb);
        *h = 0.0;
    }
    hd[H_VALID] = 0.0; /* valid again once the derivative is */
    hd[H_T] = t0;
    if (rhs(S, t0, S->y, S->fy) != 0)
        return finish(st, MBRT_RHS_FAILED, t0, "RADAU5: rhs returned %d at t=%.17g.", S->rhs_rc, t0);
    if (!finite_all(n, S->fy))
        return finish(st, MBRT_NONFINITE, t0, "RADAU5: rhs returned non-finite values at t=%.17g (initial state).",
                      t0);
    hd[H_VALID] = 1.0;
    if (*h == 0.0)
        *h = h0 > 0.0 ? fmin(h0, hmax) : initial_step(S, span, hmax);
    return 0;
}

/* One step's attempts until one is accepted: 0 (accepted: S->ynew, *err, *theta, *hnew,
 * *n_fail, *last set) or the failure's status. */
static int attempt(R5 *S, mbrt_stats *st, double t, double t_end, double *h, long max_steps, double *err,
                   double *theta, double *hnew, int *n_fail, int *last)
{
    int n = S->n, kind = 0, n_sing = 0, rc;
    double *hd = S->hdr;
    char reason[120] = "";
    for (int i = 0; i < n; ++i)
        S->scale[i] = S->atol[i] + S->rtol * fabs(S->y[i]);
    *n_fail = 0;
    for (;;) {
        if (st->nstep >= max_steps)
            return finish(st, MBRT_MAX_STEPS, t, "RADAU5: max_steps=%ld attempted steps were not enough; stopped "
                          "at t=%.17g.", max_steps, t);
        if (*h <= 1e-14 * fabs(t) || *n_fail >= MAX_FAILURES || !(*h > 0.0))
            return collapsed(st, kind, t, *h, reason, *n_fail);
        *last = t + 1.0001 * *h >= t_end;
        if (*last)
            *h = t_end - t;
        else if (t + 2.0 * *h > t_end) /* no sliver of a last step */
            *h = 0.5 * (t_end - t);
        if (hd[H_HAVE_J] == 0.0 && (rc = jacobian(S, t)) != 0)
            return jacobian_failed(S, st, rc, t);
        if (hd[H_LU_H] != *h) {
            int structural;
            if (factorize(S, *h, reason, sizeof reason, &structural) != 0) {
                S->info->nsingular++;
                st->nreject++;
                if (structural || ++n_sing >= MAX_SINGULAR)
                    return finish(st, MBRT_RADAU5_SINGULAR, t, "RADAU5: the iteration matrix is singular at "
                                  "t=%.17g with h=%.3g: %s", t, *h, reason);
                kind = 3;
                ++*n_fail;
                if ((rc = retry(S, t, h, 0.5)) != 0)
                    return jacobian_failed(S, st, rc, t);
                continue;
            }
        }
        st->nstep++;
        predict(S, t, *h);
        int iters;
        double fac;
        rc = newton(S, t, *h, theta, &iters, &fac, reason, sizeof reason);
        if (rc < 0)
            return finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (a Newton iterate of the "
                          "step from t=%.17g).", S->rhs_rc, S->t_fail, t);
        if (rc == 0) {
            S->info->nfail_newton++;
            st->nreject++;
            kind = 1;
            ++*n_fail;
            if ((rc = retry(S, t, h, fac)) != 0)
                return jacobian_failed(S, st, rc, t);
            continue;
        }
        for (int i = 0; i < n; ++i)
            S->ynew[i] = S->y[i] + S->Z[2 * (size_t)n + i];
        *err = error_estimate(S, t, *h, hd[H_FIRST] != 0.0 || *n_fail > 0, S->y);
        if (*err < 0.0)
            return finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (the error estimate of the "
                          "step from t=%.17g).", S->rhs_rc, S->t_fail, t);
        double fs = fmin(SAFETY, SAFETY * (2 * NIT + 1) / (iters + 2 * NIT));
        double quot = fmax(1.0 / FAC_MAX, fmin(1.0 / FAC_MIN, pow(*err, 0.25) / fs));
        *hnew = *h / quot;
        if (*err >= 1.0) {
            st->nreject++;
            kind = 2;
            snprintf(reason, sizeof reason, "scaled error %.3g", *err);
            ++*n_fail;
            if ((rc = retry(S, t, h, hd[H_FIRST] != 0.0 ? 0.1 : *hnew / *h)) != 0)
                return jacobian_failed(S, st, rc, t);
            continue;
        }
        return 0;
    }
}

/* The collocation polynomial of the accepted step at t_out in (told, t_new]. */
static void outputs(const R5 *S, double told, double h, double t_new, const double *t_out, int n_out,
                    double *y_out, int *iout)
{
    int n = S->n;
    while (*iout < n_out && t_out[*iout] <= t_new) {
        double *row = y_out + (size_t)*iout * (size_t)n;
        if (t_out[*iout] == t_new) {
            memcpy(row, S->ynew, (size_t)n * sizeof(double));
        } else {
            double x = (t_out[*iout] - told) / h, x2 = x * x, x3 = x2 * x;
            for (int i = 0; i < n; ++i)
                row[i] = S->yold[i] + (S->Q[i] * x + S->Q[n + i] * x2 + S->Q[2 * (size_t)n + i] * x3);
        }
        ++*iout;
    }
}

int mbrt_radau5(mbrt_rhs_fn f, mbrt_jac_fn jac, void *ctx, int n, double t0, const double *y0, double t_end,
                double t_pause, double rtol, const double *atol, double h0, double hmax, long max_steps,
                const double *t_out, int n_out, double *y_out, int *n_written, double *work, int *iwork, int resume,
                double *y_last, mbrt_stats *stats, mbrt_radau5_info *info)
{
    mbrt_stats local;
    mbrt_stats *st = stats ? stats : &local;
    memset(st, 0, sizeof *st);
    st->t = t0;
    int iout = 0;
    if (n_written)
        *n_written = 0;
    if (info != NULL)
        memset(info, 0, sizeof *info);
    if (check_args(f, n, t0, y0, t_end, rtol, atol, h0, hmax, max_steps, t_out, n_out, y_out, work, iwork, info, st))
        return st->status;
    R5 S;
    memset(&S, 0, sizeof S);
    S.f = f;
    S.jac = jac;
    S.ctx = ctx;
    S.n = n;
    S.rtol = rtol;
    S.atol = atol;
    S.info = info;
    S.newton_tol = fmax(10.0 * DBL_EPSILON / rtol, fmin(0.03, sqrt(rtol)));
    layout(&S, work, iwork);
    double *hd = S.hdr;
    const double span = t_end - t0;
    if (hmax == 0.0)
        hmax = INFINITY;
    if (max_steps == 0)
        max_steps = DEFAULT_MAX_STEPS;
    size_t nb = (size_t)n * sizeof(double);
    double h, t = t0;
    if (begin(&S, st, t0, y0, h0, hmax, span, resume, &h) != 0)
        goto done;
    if (iout < n_out && t_out[0] == t0)
        memcpy(y_out, S.y, nb), iout++;
    if (span == 0.0) {
        finish(st, MBRT_OK, t0, "RADAU5: t_end equals t0, nothing to integrate.");
        goto done;
    }
    for (;;) {
        double err = 1.0, theta = 1.0, hnew = h;
        int n_fail = 0, last = 0;
        h = fmin(h, hmax);
        if (attempt(&S, st, t, t_end, &h, max_steps, &err, &theta, &hnew, &n_fail, &last) != 0)
            goto done;
        /* ---- accepted: Gustafsson's predictive controller ---- */
        double quot = h / hnew;
        if (hd[H_FIRST] == 0.0 && hd[H_HACC] > 0.0) {
            double facgus = (hd[H_HACC] / h) * pow(err * err / hd[H_ERRACC], 0.25) / SAFETY;
            facgus = fmax(1.0 / FAC_MAX, fmin(1.0 / FAC_MIN, facgus));
            quot = fmax(quot, facgus);
            hnew = h / quot;
        }
        hd[H_HACC] = h;
        hd[H_ERRACC] = fmax(1e-2, err);
        if (n_fail > 0)
            hnew = fmin(hnew, h);
        hd[H_FIRST] = 0.0;
        /* the collocation polynomial: Q = P^T Z, y(t + s h) = y + sum_k Q_k s^(k+1) */
        memcpy(S.yold, S.y, nb);
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < n; ++i)
                S.Q[(size_t)k * n + i] = P_[k] * S.Z[i] + P_[3 + k] * S.Z[n + i] + P_[6 + k] * S.Z[2 * (size_t)n + i];
        hd[H_DENSE] = 1.0;
        hd[H_DT0] = t;
        hd[H_DH] = h;
        double told = t;
        t = last ? t_end : t + h;
        st->naccept++;
        outputs(&S, told, h, t, t_out, n_out, y_out, &iout);
        memcpy(S.y, S.ynew, nb);
        hd[H_T] = t;
        st->t = t;
        /* Jacobian and factors for the next step */
        if (theta > THETA_JAC)
            hd[H_HAVE_J] = 0.0;
        hd[H_JCUR] = 0.0;
        double qt = hnew / h;
        if (!(theta <= THETA_JAC && qt >= QUOT_LO && qt <= QUOT_HI && !last))
            h = fmin(hnew, hmax);
        hd[H_H] = h;
        hd[H_VALID] = 0.0;
        if (rhs(&S, t, S.y, S.fy) != 0) {
            finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (the accepted step).", S.rhs_rc, t);
            goto done;
        }
        if (!finite_all(n, S.fy)) {
            finish(st, MBRT_NONFINITE, t, "RADAU5: rhs returned non-finite values at t=%.17g (the accepted step).", t);
            goto done;
        }
        hd[H_VALID] = 1.0;
        if (last) {
            finish(st, MBRT_OK, t, "RADAU5: reached t_end=%.17g in %ld steps.", t, st->naccept);
            goto done;
        }
        if (t_pause > t0 && t >= t_pause) {
            finish(st, MBRT_RADAU5_PAUSED, t, "RADAU5: paused at t=%.17g (t_pause=%.17g).", t, t_pause);
            goto done;
        }
    }
done:
    if (st->status != MBRT_BAD_ARGUMENT) {
        hd[H_H] = h;
        st->nfev = S.nfev;
        if (y_last != NULL)
            memcpy(y_last, S.y, nb);
        info->h_next = h;
    }
    if (n_written)
        *n_written = iout;
    return st->status;
}

void mbrt_radau5_dense(const double *work, int n, double t, double *y)
{
    R5 S;
    S.n = n;
    layout(&S, (double *)work, NULL); /* read only here */
    const double *hd = S.hdr, *Q = S.Q;
    double x = (t - hd[H_DT0]) / hd[H_DH], x2 = x * x, x3 = x2 * x;
    for (int i = 0; i < n; ++i)
        y[i] = S.yold[i] + (Q[i] * x + Q[n + i] * x2 + Q[2 * (size_t)n + i] * x3);
}

/* ------------------------------------------------------------------ programs */
int mbrt_prog_ode_rhs(void *ctx, double t, const double *y, double *dy)
{
    const mbrt_prog_ode *P = (const mbrt_prog_ode *)ctx;
    return P->fun(y, y + P->nq, t, P->d, P->h, P->p, P->w, dy) != 0;
}

int mbrt_prog_ode_jac(void *ctx, double t, const double *y, const double *fy, double *J)
{
    const mbrt_prog_ode *P = (const mbrt_prog_ode *)ctx;
    (void)fy;
    if (P->jac == NULL)
        return 1;
    return P->jac(y, y + P->nq, t, P->jd, P->jh, P->jp, P->jw, J) != 0;
}
