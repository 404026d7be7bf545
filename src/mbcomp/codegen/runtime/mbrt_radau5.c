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
 * written in mbrt_radau5_internal.h as hexadecimal floats: the same numbers.  The pieces of a
 * step are in mbrt_radau5_step.c, the iteration matrices in mbrt_radau5_linalg.c.  The linear
 * algebra is the runtime's own (the Python stepper's is LAPACK's), so the two agree to
 * round-off in a step, not bit for bit.
 *
 * A call can resume a previous one (resume != 0): the work buffer then still holds the
 * Jacobian, the factors, the predictor and the controller's memory, so that a run integrated
 * in stretches takes the steps of one call.
 */
#include "mbrt_radau5_internal.h"
#include "mbrt_check.h"

#include <stdio.h>
#include <string.h>

size_t mbrt_radau5_work_size(int n)
{
    if (n <= 0)
        return 0;
    size_t m = (size_t)n;
    /* J, E1 (real), E2 (complex, interleaved); 31 vectors of n */
    return HDR + 4 * m * m + 31 * m;
}

size_t mbrt_radau5_iwork_size(int n) { return n <= 0 ? 0 : 2 * (size_t)n; }

static int check_args(mbrt_rhs_fn f, int n, double t0, const double *y0, double t_end, double rtol,
                      const double *atol, double h0, double hmax, long max_steps, const double *t_out,
                      int n_out, const double *y_out, const double *work, const int *iwork,
                      const mbrt_radau5_info *info, mbrt_stats *st)
{
    if (iwork == NULL || info == NULL)
        return mbrt_finish(st, MBRT_BAD_ARGUMENT, t0, "RADAU5: iwork and info must not be NULL.");
    return mbrt_check_integration("RADAU5", f, n, t0, y0, t_end, rtol, atol, h0, hmax, max_steps, t_out, n_out,
                                  y_out, work, st);
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
    return S->hdr[H_JCUR] != 0.0 ? 0 : mbrt_r5_jacobian(S, t);
}

/* The collapsed step's message, naming the last cause. */
static int collapsed(mbrt_stats *st, int kind, double t, double h, const char *reason, int n_fail)
{
    if (kind == 1)
        return mbrt_finish(st, MBRT_STEP_TOO_SMALL, t, "RADAU5: Newton iteration failed to converge at t=%.17g with "
                      "h=%.3g (step size collapsed): %s (%d consecutive failed attempts)", t, h, reason, n_fail);
    if (kind == 2)
        return mbrt_finish(st, MBRT_STEP_TOO_SMALL, t, "RADAU5: step size collapsed at t=%.17g with h=%.3g: the local "
                      "error test keeps failing (last %s; %d consecutive failed attempts)", t, h, reason, n_fail);
    if (kind == 3)
        return mbrt_finish(st, MBRT_RADAU5_SINGULAR, t, "RADAU5: the iteration matrix is singular at t=%.17g with "
                      "h=%.3g (step size collapsed): %s", t, h, reason);
    return mbrt_finish(st, MBRT_STEP_TOO_SMALL, t, "RADAU5: step size collapsed at t=%.17g: h=%.3g is below "
                  "1e-14*|t| without a failed attempt in this step (the solution blows up or is not smooth there)",
                  t, h);
}

/* The Jacobian's failure (jacobian() returned rc != 0) as the integration's status. */
static int jacobian_failed(R5 *S, mbrt_stats *st, int rc, double t)
{
    if (rc > 0)
        return mbrt_finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (difference Jacobian).",
                      S->rhs_rc, S->t_fail);
    return mbrt_finish(st, MBRT_NONFINITE, t, "RADAU5: rhs returned non-finite values at t=%.17g "
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
    if (mbrt_r5_rhs(S, t0, S->y, S->fy) != 0)
        return mbrt_finish(st, MBRT_RHS_FAILED, t0, "RADAU5: rhs returned %d at t=%.17g.", S->rhs_rc, t0);
    if (!mbrt_r5_finite(n, S->fy))
        return mbrt_finish(st, MBRT_NONFINITE, t0, "RADAU5: rhs returned non-finite values at t=%.17g (initial state).",
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
            return mbrt_finish(st, MBRT_MAX_STEPS, t, "RADAU5: max_steps=%ld attempted steps were not enough; stopped "
                          "at t=%.17g.", max_steps, t);
        if (*h <= 1e-14 * fabs(t) || *n_fail >= MAX_FAILURES || !(*h > 0.0))
            return collapsed(st, kind, t, *h, reason, *n_fail);
        *last = t + 1.0001 * *h >= t_end;
        if (*last)
            *h = t_end - t;
        else if (t + 2.0 * *h > t_end) /* no sliver of a last step */
            *h = 0.5 * (t_end - t);
        if (hd[H_HAVE_J] == 0.0 && (rc = mbrt_r5_jacobian(S, t)) != 0)
            return jacobian_failed(S, st, rc, t);
        if (hd[H_LU_H] != *h) {
            int structural;
            if (mbrt_r5_factorize(S, *h, reason, sizeof reason, &structural) != 0) {
                S->info->nsingular++;
                st->nreject++;
                if (structural || ++n_sing >= MAX_SINGULAR)
                    return mbrt_finish(st, MBRT_RADAU5_SINGULAR, t, "RADAU5: the iteration matrix is singular at "
                                  "t=%.17g with h=%.3g: %s", t, *h, reason);
                kind = 3;
                ++*n_fail;
                if ((rc = retry(S, t, h, 0.5)) != 0)
                    return jacobian_failed(S, st, rc, t);
                continue;
            }
        }
        st->nstep++;
        mbrt_r5_predict(S, t, *h);
        int iters;
        double fac;
        rc = mbrt_r5_newton(S, t, *h, theta, &iters, &fac, reason, sizeof reason);
        if (rc < 0)
            return mbrt_finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (a Newton iterate of the "
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
        *err = mbrt_r5_error(S, t, *h, hd[H_FIRST] != 0.0 || *n_fail > 0, S->y);
        if (*err < 0.0)
            return mbrt_finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (the error estimate of the "
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

/* An accepted step from t of size h: Gustafsson's predictive controller, the collocation
 * polynomial (Q = P^T Z: y(t + s h) = y + sum_k Q_k s^(k+1)), and RADAU5's reuse rule (the
 * Jacobian kept below the contraction rate THETA_JAC; with it, h and the factors kept when
 * h_new / h lies in [QUOT_LO, QUOT_HI]).  Returns the next step size. */
static double accept(R5 *S, double t, double h, double err, double theta, double hnew, int n_fail, int last,
                     double hmax)
{
    int n = S->n;
    double *hd = S->hdr;
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
    memcpy(S->yold, S->y, (size_t)n * sizeof(double));
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < n; ++i)
            S->Q[(size_t)k * n + i] = P_[k] * S->Z[i] + P_[3 + k] * S->Z[n + i] + P_[6 + k] * S->Z[2 * (size_t)n + i];
    hd[H_DENSE] = 1.0;
    hd[H_DT0] = t;
    hd[H_DH] = h;
    if (theta > THETA_JAC)
        hd[H_HAVE_J] = 0.0;
    hd[H_JCUR] = 0.0;
    double qt = hnew / h;
    if (theta <= THETA_JAC && qt >= QUOT_LO && qt <= QUOT_HI && !last)
        return h;
    return fmin(hnew, hmax);
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
    mbrt_r5_layout(&S, work, iwork);
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
        mbrt_finish(st, MBRT_OK, t0, "RADAU5: t_end equals t0, nothing to integrate.");
        goto done;
    }
    for (;;) {
        double err = 1.0, theta = 1.0, hnew = h;
        int n_fail = 0, last = 0;
        h = fmin(h, hmax);
        if (attempt(&S, st, t, t_end, &h, max_steps, &err, &theta, &hnew, &n_fail, &last) != 0)
            goto done;
        double h_next = accept(&S, t, h, err, theta, hnew, n_fail, last, hmax);
        double told = t;
        t = last ? t_end : t + h;
        st->naccept++;
        outputs(&S, told, h, t, t_out, n_out, y_out, &iout);
        memcpy(S.y, S.ynew, nb);
        hd[H_T] = t;
        st->t = t;
        h = h_next;
        hd[H_H] = h;
        hd[H_VALID] = 0.0;
        if (mbrt_r5_rhs(&S, t, S.y, S.fy) != 0) {
            mbrt_finish(st, MBRT_RHS_FAILED, t, "RADAU5: rhs returned %d at t=%.17g (the accepted step).", S.rhs_rc, t);
            goto done;
        }
        if (!mbrt_r5_finite(n, S.fy)) {
            mbrt_finish(st, MBRT_NONFINITE, t, "RADAU5: rhs returned non-finite values at t=%.17g (the accepted step).", t);
            goto done;
        }
        hd[H_VALID] = 1.0;
        if (last) {
            mbrt_finish(st, MBRT_OK, t, "RADAU5: reached t_end=%.17g in %ld steps.", t, st->naccept);
            goto done;
        }
        if (t_pause > t0 && t >= t_pause) {
            mbrt_finish(st, MBRT_RADAU5_PAUSED, t, "RADAU5: paused at t=%.17g (t_pause=%.17g).", t, t_pause);
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
