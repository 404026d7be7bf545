/*
 * mbrt_rk.c -- the adaptive driver shared by DOPRI5 and DOP853.
 *
 * Step-size control (Hairer, Norsett & Wanner, "Solving ODEs I", Sec. II.4,
 * and Hairer's codes dopri5.f / dop853.f):
 *
 *   err   = sqrt( (1/n) sum_i (est_i / sc_i)^2 )        (method's estimate)
 *   fac   = err^(1/q - 0.75*beta) / facold^beta / safe   (PI / Lund control)
 *   fac   clipped to [1/fac_max, 1/fac_min],  h_new = h / fac
 *
 * with facold = max(err, 1e-4) of the last accepted step.  A step is
 * accepted iff err <= 1.  After a rejection h shrinks by
 * min(1/fac_min, err^(1/q)/safe) and, right after a rejection, an accepted
 * step may not enlarge h.  The step before t_end is stretched to hit t_end if
 * it would otherwise leave less than 1% of a step.  A trial step whose state
 * or derivative is not finite counts as a rejection with the largest shrink,
 * so overflow from an overly large step is recovered from.
 *
 * The starting step follows Hairer's HINIT (Sec. II.4, "Starting step size"):
 * h such that h^order * max(|f0|, |f'|) ~ 0.01 in the scaled norm, with the
 * second derivative estimated by one explicit Euler step.
 */
#include "mbrt_rk_internal.h"
#include "mbrt_check.h"

#include <float.h>
#include <stdio.h>
#include <string.h>

#define MBRT_DEFAULT_MAX_STEPS 100000L

size_t mbrt_rk_work_size(const mbrt_rk_method *M, int n)
{
    if (n <= 0)
        return 0;
    /* driver: y, f0, y1, f1, ysave */
    return (size_t)(5 + M->scratch_per_n) * (size_t)n;
}

static int all_finite(int n, const double *v)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* Hairer's starting-step guess.  Uses S->y1, S->f1 as scratch and one rhs
 * evaluation.  Returns 0 or the failing rhs code. */
static int initial_step(const mbrt_rk_method *M, mbrt_rk_state *S, double hmax, double *h_out)
{
    int n = S->n;
    double dnf = 0.0, dny = 0.0;
    for (int i = 0; i < n; ++i) {
        double sc = S->atol[i] + S->rtol * fabs(S->y[i]);
        if (sc < 1e-300)
            sc = 1e-300;
        dnf += (S->f0[i] / sc) * (S->f0[i] / sc);
        dny += (S->y[i] / sc) * (S->y[i] / sc);
    }
    /* first guess: 1% of the "time scale" |y| / |y'| */
    double h = (dnf <= 1e-10 || dny <= 1e-10) ? 1e-6 : 0.01 * sqrt(dny / dnf);
    if (!(h > 0.0) || !isfinite(h))
        h = 1e-6;
    h = fmin(h, hmax);
    /* explicit Euler step to estimate the second derivative */
    for (int i = 0; i < n; ++i)
        S->y1[i] = S->y[i] + h * S->f0[i];
    S->nfev++;
    int rc = S->f(S->ctx, S->t + h, S->y1, S->f1);
    if (rc != 0) {
        S->t_fail = S->t + h;
        return rc;
    }
    double der2 = 0.0;
    for (int i = 0; i < n; ++i) {
        double sc = S->atol[i] + S->rtol * fabs(S->y[i]);
        if (sc < 1e-300)
            sc = 1e-300;
        double d = (S->f1[i] - S->f0[i]) / sc;
        der2 += d * d;
    }
    der2 = sqrt(der2) / h;
    /* h^order * max(|f0|, |f''|) = 0.01 */
    double der12 = fmax(fabs(der2), sqrt(dnf));
    double h1;
    if (!isfinite(der12))
        h1 = fmax(1e-6, 1e-3 * h);
    else if (der12 <= 1e-15)
        h1 = fmax(1e-6, 1e-3 * h);
    else
        h1 = pow(0.01 / der12, 1.0 / M->order);
    h = fmin(fmin(100.0 * h, h1), hmax);
    if (!(h > 0.0) || !isfinite(h))
        h = fmin(1e-6, hmax);
    *h_out = h;
    return 0;
}

int mbrt_rk_integrate(const mbrt_rk_method *M, mbrt_rhs_fn f, mbrt_step_fn on_step,
                      void *ctx, int n, double t0, const double *y0, double t_end,
                      double rtol, const double *atol, double h0, double hmax,
                      long max_steps, const double *t_out, int n_out,
                      double *y_out, int *n_written, double *work, mbrt_stats *stats,
                      int stiff_steps, mbrt_events *ev)
{
    mbrt_stats local;
    mbrt_stats *st = stats ? stats : &local;
    memset(st, 0, sizeof *st);
    st->t = t0;
    int iout = 0;
    if (n_written)
        *n_written = 0;

    if (mbrt_check_integration(M->name, f, n, t0, y0, t_end, rtol, atol, h0, hmax, max_steps, t_out, n_out,
                               y_out, work, st))
        return st->status;
    if (ev != NULL && (ev->g == NULL || ev->n_ev < 1 || ev->direction == NULL || ev->work == NULL ||
                       ev->y_event == NULL || !(ev->tol > 0.0) || ev->fresh >= ev->n_ev))
        return mbrt_finish(st, MBRT_BAD_ARGUMENT, t0, "%s: the events are incomplete (a function, n_ev >= 1, "
                      "directions, work, y_event, tol > 0 and fresh < n_ev are needed).", M->name);
    int fresh = ev != NULL ? ev->fresh : -1;

    mbrt_rk_state S;
    S.f = f;
    S.ctx = ctx;
    S.n = n;
    S.rtol = rtol;
    S.atol = atol;
    S.y = work;
    S.f0 = work + (size_t)n;
    S.y1 = work + 2 * (size_t)n;
    S.f1 = work + 3 * (size_t)n;
    double *ysave = work + 4 * (size_t)n;
    S.s = work + 5 * (size_t)n;
    S.nfev = 0;
    S.hlamb = 0.0;
    S.t = t0;
    S.h = 0.0;
    S.t_fail = t0;
    const size_t nb = (size_t)n * sizeof(double);
    memcpy(S.y, y0, nb);

    const double span = t_end - t0;
    if (hmax == 0.0 || hmax > span)
        hmax = span;
    if (max_steps == 0)
        max_steps = MBRT_DEFAULT_MAX_STEPS;

    /* outputs requested at t0 itself (only t_out[0] can be, t_out increasing) */
    if (iout < n_out && t_out[iout] == t0) {
        memcpy(y_out, S.y, nb);
        iout++;
    }
    if (span == 0.0) {
        mbrt_finish(st, MBRT_OK, t0, "%s: t_end equals t0, nothing to integrate.", M->name);
        goto done;
    }

    int rc;
    if (ev != NULL) {
        rc = mbrt_events_begin(ev, t0, S.y);
        if (rc != 0) {
            mbrt_finish(st, MBRT_RHS_FAILED, t0, "%s: the event function returned %d at t=%.17g.", M->name, rc, t0);
            goto done;
        }
    }
    S.nfev++;
    rc = f(ctx, t0, S.y, S.f0);
    if (rc != 0) {
        mbrt_finish(st, MBRT_RHS_FAILED, t0, "%s: rhs returned %d at t=%.17g.", M->name, rc, t0);
        goto done;
    }
    if (!all_finite(n, S.f0)) {
        mbrt_finish(st, MBRT_NONFINITE, t0, "%s: rhs returned a non-finite value at t=%.17g.",
               M->name, t0);
        goto done;
    }

    double h;
    if (h0 > 0.0) {
        h = fmin(h0, hmax);
    } else {
        rc = initial_step(M, &S, hmax, &h);
        if (rc != 0) {
            mbrt_finish(st, MBRT_RHS_FAILED, t0, "%s: rhs returned %d at t=%.17g.",
                   M->name, rc, S.t_fail);
            goto done;
        }
    }

    const double expo = 1.0 / M->err_order - 0.75 * M->beta;
    double facold = 1e-4;
    int reject = 0, last_nonfinite = 0;
    int stiff_run = 0, calm_run = 0; /* Hairer's IASTI, NONSTI */
    double t = t0;
    for (;;) {
        if (st->nstep >= max_steps) {
            mbrt_finish(st, MBRT_MAX_STEPS, t, "%s: max_steps=%ld steps were not enough; stopped at t=%.17g.",
                   M->name, max_steps, t);
            goto done;
        }
        /* round-off limit: h must change t by more than a few ulps of t (of
         * the span when t is near 0); also catches h underflowing */
        if (!(fabs(h) > 10.0 * DBL_EPSILON * fmax(fabs(t), span))) {
            mbrt_finish(st, MBRT_STEP_TOO_SMALL, t, "%s: step size %.3g too small at t=%.17g%s.",
                   M->name, h, t,
                   last_nonfinite ? " (trial steps gave non-finite values)" : "");
            goto done;
        }
        int last = 0;
        if (t + 1.01 * h >= t_end) { /* stretch or shorten to land on t_end */
            h = t_end - t;
            last = 1;
        }
        st->nstep++;
        S.t = t;
        S.h = h;
        double err;
        rc = M->trial(&S, &err);
        if (rc != 0) {
            mbrt_finish(st, MBRT_RHS_FAILED, t, "%s: rhs returned %d at t=%.17g (in a step from t=%.17g).",
                   M->name, rc, S.t_fail, t);
            goto done;
        }
        last_nonfinite = 0;
        if (isnan(err)) {
            err = INFINITY;
            last_nonfinite = 1;
        }
        if (err <= 1.0 && !(all_finite(n, S.y1) && all_finite(n, S.f1))) {
            err = INFINITY;
            last_nonfinite = 1;
        }
        double fac11 = pow(err, expo); /* err^(1/q - 0.75 beta) */
        double fac = fac11 / pow(facold, M->beta) / M->safe;
        fac = fmax(1.0 / M->fac_max, fmin(1.0 / M->fac_min, fac));
        double hnew = h / fac;

        if (!(err <= 1.0)) { /* ---- rejected step ---- */
            st->nreject++;
            hnew = h / fmin(1.0 / M->fac_min, fac11 / M->safe);
            reject = 1;
            h = hnew;
            continue;
        }

        /* ---- accepted step ---- */
        st->naccept++;
        facold = fmax(err, 1e-4);
        double told = t;
        t = last ? t_end : t + h;

        /* the events of this step: the earliest ends the integration there */
        int prepared = 0, hit = 0;
        double t_stop = t;
        if (ev != NULL) {
            S.t = told;
            hit = mbrt_events_step(M, &S, ev, t, &prepared, &fresh);
            if (hit == MBRT_EVENTS_G_FAILED) {
                mbrt_finish(st, MBRT_RHS_FAILED, told, "%s: an event function failed (a nonzero return or a "
                       "non-finite value) in the step from t=%.17g.", M->name, told);
                goto done;
            }
            if (hit == MBRT_EVENTS_RHS_FAILED) {
                mbrt_finish(st, MBRT_RHS_FAILED, told, "%s: rhs failed at t=%.17g (dense output of the step from "
                       "t=%.17g).", M->name, S.t_fail, told);
                goto done;
            }
            if (hit)
                t_stop = ev->t_event;
        }

        /* outputs in (told, t_stop] from the continuous extension of this step */
        while (iout < n_out && t_out[iout] <= t_stop) {
            double *row = y_out + (size_t)iout * (size_t)n;
            if (t_out[iout] == t && !hit) {
                memcpy(row, S.y1, nb);
            } else {
                if (!prepared) {
                    rc = M->dense_prepare(&S);
                    if (rc != 0) {
                        mbrt_finish(st, MBRT_RHS_FAILED, told,
                               "%s: rhs returned %d at t=%.17g (dense output of the step from t=%.17g).",
                               M->name, rc, S.t_fail, told);
                        goto done;
                    }
                    prepared = 1;
                }
                M->dense_eval(&S, (t_out[iout] - told) / h, row);
            }
            iout++;
        }
        if (hit) {
            mbrt_finish(st, MBRT_EVENT, t_stop, "%s: event %d at t=%.17g.", M->name, ev->which, t_stop);
            goto done;
        }

        memcpy(S.y, S.y1, nb);
        memcpy(S.f0, S.f1, nb); /* first same as last */
        S.t = t;
        if (on_step) {
            memcpy(ysave, S.y, nb);
            rc = on_step(ctx, t, S.y);
            if (rc != 0) {
                mbrt_finish(st, MBRT_STOPPED, t, "%s: step callback returned %d at t=%.17g.",
                       M->name, rc, t);
                goto done;
            }
            if (!all_finite(n, S.y)) {
                mbrt_finish(st, MBRT_NONFINITE, t, "%s: step callback made the state non-finite at t=%.17g.",
                       M->name, t);
                goto done;
            }
            if (!last && memcmp(ysave, S.y, nb) != 0) { /* projected: derivative is stale */
                S.nfev++;
                rc = f(ctx, t, S.y, S.f0);
                if (rc != 0) {
                    mbrt_finish(st, MBRT_RHS_FAILED, t, "%s: rhs returned %d at t=%.17g.", M->name, rc, t);
                    goto done;
                }
                if (!all_finite(n, S.f0)) {
                    mbrt_finish(st, MBRT_NONFINITE, t, "%s: rhs returned a non-finite value at t=%.17g.",
                           M->name, t);
                    goto done;
                }
            }
        }
        if (last) {
            mbrt_finish(st, MBRT_OK, t, "%s: reached t_end=%.17g in %ld steps.", M->name, t,
                   st->naccept);
            goto done;
        }
        if (stiff_steps > 0) { /* Hairer's stiffness test on the accepted step */
            if (S.hlamb > M->stiff_limit) {
                calm_run = 0;
                if (++stiff_run >= stiff_steps) {
                    mbrt_finish(st, MBRT_STIFF, t,
                           "%s: the problem became stiff at t=%.17g (|h lambda| = %.3g above %.3g "
                           "for %d steps).", M->name, t, S.hlamb, M->stiff_limit, stiff_run);
                    goto done;
                }
            } else if (++calm_run >= 6) {
                stiff_run = 0;
            }
        }
        if (fabs(hnew) > hmax)
            hnew = hmax;
        if (reject)
            hnew = fmin(hnew, h);
        reject = 0;
        h = hnew;
    }

done:
    st->nfev = S.nfev;
    if (n_written)
        *n_written = iout;
    return st->status;
}
