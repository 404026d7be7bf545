/*
 * mbrt_radau5_step.c -- the pieces of one RADAU5 step (see mbrt_radau5.c): the right-hand
 * side counted, the Jacobian (the caller's, else forward differences), the simplified Newton
 * iteration on the transformed stage equations, the predictor, the filtered error estimate;
 * the work buffer's layout, the coefficients, the dense output and the program adapters.
 */
#include "mbrt_radau5_internal.h"

#include <stdio.h>
#include <string.h>

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

int mbrt_r5_finite(int n, const double *v)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

double mbrt_r5_rms(int n, const double *x, const double *sc)
{
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        double v = x[i] / sc[i];
        s += v * v;
    }
    return sqrt(s / n);
}

int mbrt_r5_rhs(R5 *S, double t, const double *y, double *out)
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
int mbrt_r5_jacobian(R5 *S, double t)
{
    int n = S->n;
    double *J = S->J;
    S->info->njev++;
    S->hdr[H_HAVE_J] = 1.0;
    S->hdr[H_JCUR] = 1.0;
    S->hdr[H_LU_H] = 0.0; /* the factors of the old J are void */
    if (S->jac != NULL && S->jac(S->ctx, t, S->y, S->fy, J) == 0 && mbrt_r5_finite(n * n, J))
        return 0;
    S->info->ndiff++;
    double *yp = S->tmp, *fp = S->ev;
    memcpy(yp, S->y, sizeof(double) * (size_t)n);
    for (int j = 0; j < n; ++j) {
        double yj = S->y[j];
        double delta = sqrt(DBL_EPSILON * fmax(1e-5, fabs(yj)));
        yp[j] = yj + delta;
        delta = yp[j] - yj;
        int rc = mbrt_r5_rhs(S, t, yp, fp);
        if (rc != 0)
            return rc;
        if (!mbrt_r5_finite(n, fp))
            return -1;
        for (int i = 0; i < n; ++i)
            J[(size_t)i * n + j] = (fp[i] - S->fy[i]) / delta;
        yp[j] = yj;
    }
    return 0;
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
int mbrt_r5_newton(R5 *S, double t, double h, double *theta_out, int *iters, double *fac, char *msg, size_t len)
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
            if (mbrt_r5_rhs(S, tc[s], ys, F + (size_t)s * n) != 0)
                return -1;
        }
        mat3(n, TI_, F, R);
        mat3(n, LAM_, W, dW);
        for (size_t i = 0; i < n3; ++i)
            R[i] -= dW[i] * mh;
        memcpy(dW, R, n3 * sizeof(double));
        mbrt_r5_solve_real(S, dW);
        mbrt_r5_solve_complex(S, dW + n, dW + 2 * (size_t)n, S->cz);
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
            snprintf(msg, len, "%s", mbrt_r5_finite((int)n3, F) ? "the Newton increment is not finite"
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
void mbrt_r5_predict(R5 *S, double t, double h)
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
        if (mbrt_r5_finite(3 * n, Z))
            return;
    }
    memset(Z, 0, 3 * (size_t)n * sizeof(double));
}

/* The scaled local error (>= 1e-10; INFINITY if not finite); -1 on an rhs failure. */
double mbrt_r5_error(R5 *S, double t, double h, int refilter, const double *absy)
{
    int n = S->n;
    double *ev = S->ev, *mze = S->F, *tmp = S->tmp, *sc = S->R;
    for (int i = 0; i < n; ++i) {
        mze[i] = (D_[0] * S->Z[i] + D_[1] * S->Z[n + i] + D_[2] * S->Z[2 * (size_t)n + i]) / h;
        ev[i] = S->fy[i] + mze[i];
        sc[i] = S->atol[i] + S->rtol * fmax(absy[i], fabs(S->ynew[i]));
    }
    mbrt_r5_solve_real(S, ev);
    double err = mbrt_r5_rms(n, ev, sc);
    if (err >= 1.0 && refilter && isfinite(err)) {
        for (int i = 0; i < n; ++i)
            tmp[i] = S->y[i] + ev[i];
        double *f1 = S->dW;
        if (mbrt_r5_rhs(S, t, tmp, f1) != 0)
            return -1.0;
        if (mbrt_r5_finite(n, f1)) {
            for (int i = 0; i < n; ++i)
                ev[i] = f1[i] + mze[i];
            mbrt_r5_solve_real(S, ev);
            err = mbrt_r5_rms(n, ev, sc);
        }
    }
    if (!isfinite(err))
        err = INFINITY;
    return fmax(err, 1e-10);
}

void mbrt_r5_layout(R5 *S, double *work, int *iwork)
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

void mbrt_radau5_dense(const double *work, int n, double t, double *y)
{
    R5 S;
    S.n = n;
    mbrt_r5_layout(&S, (double *)work, NULL); /* read only here */
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
