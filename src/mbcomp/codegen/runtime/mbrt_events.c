/*
 * mbrt_events.c -- events located on an accepted step's continuous extension
 * (mbrt.h, mbrt_events), for the adaptive Runge-Kutta driver (mbrt_rk.c).
 *
 * A root is bracketed by the event's values at the step's two ends and found
 * by Brent's method (R. P. Brent, "Algorithms for Minimization without
 * Derivatives", 1973, ch. 4: bisection safeguarding secant and inverse
 * quadratic steps) to the caller's time tolerance.  An event acted on at the
 * start of the run starts at zero: when it is back on its far side at the end
 * of the first step, its extreme on the leaving side is found by golden
 * section and the root bracketed between it and the step's end (a rebound
 * shorter than a step is not tunnelled through).
 *
 * Work layout (n_ev events, n equations): g0[n_ev] (values at the step's
 * start), g1[n_ev] (at its end), gs[n_ev] (scratch), ys[n] (scratch state).
 */
#include "mbrt_rk_internal.h"

#include <float.h>
#include <string.h>

size_t mbrt_events_work_size(int n, int n_ev)
{
    if (n <= 0 || n_ev <= 0)
        return 0;
    return 3 * (size_t)n_ev + (size_t)n;
}

int mbrt_linear_event_values(void *ectx, double t, const double *y, double *g)
{
    const mbrt_linear_events *L = (const mbrt_linear_events *)ectx;
    (void)t;
    for (int k = 0; k < L->n_ev; ++k)
        g[k] = L->sign[k] * (y[L->index[k]] - L->at[k]);
    return 0;
}

int mbrt_events_begin(mbrt_events *ev, double t0, const double *y0)
{
    ev->which = -1;
    ev->t_event = t0;
    ev->nevals = 1;
    return ev->g(ev->gctx, t0, y0, ev->work);
}

/* Event k at time tt of the step (S->t, S->h): the continuous extension there,
 * then the event functions.  0, or the event function's nonzero code; a value
 * that is not finite is code -1. */
static int value_at(const mbrt_rk_method *M, const mbrt_rk_state *S, mbrt_events *ev, double tt, int k,
                    double *out)
{
    double *gs = ev->work + 2 * (size_t)ev->n_ev;
    double *ys = ev->work + 3 * (size_t)ev->n_ev;
    M->dense_eval(S, (tt - S->t) / S->h, ys);
    ev->nevals++;
    int rc = ev->g(ev->gctx, tt, ys, gs);
    if (rc != 0)
        return rc;
    if (!isfinite(gs[k]))
        return -1;
    *out = gs[k];
    return 0;
}

/* Brent's root of event k in [a, b] with values fa, fb of opposite signs (or
 * one of them zero), to tol (s). */
static int brent_root(const mbrt_rk_method *M, const mbrt_rk_state *S, mbrt_events *ev, int k, double a,
                      double b, double fa, double fb, double tol, double *root)
{
    if (fa == 0.0) {
        *root = a;
        return 0;
    }
    if (fb == 0.0) {
        *root = b;
        return 0;
    }
    double c = a, fc = fa, d = b - a, e = d;
    for (int it = 0; it < 200; ++it) {
        if ((fb > 0.0) == (fc > 0.0)) { /* keep the root between b and c */
            c = a;
            fc = fa;
            d = e = b - a;
        }
        if (fabs(fc) < fabs(fb)) { /* b: the best estimate so far */
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        const double tol1 = 2.0 * DBL_EPSILON * fabs(b) + 0.5 * tol;
        const double xm = 0.5 * (c - b);
        if (fabs(xm) <= tol1 || fb == 0.0) {
            *root = b;
            return 0;
        }
        if (fabs(e) >= tol1 && fabs(fa) > fabs(fb)) { /* interpolate */
            double p, q, r, s = fb / fa;
            if (a == c) { /* secant */
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else { /* inverse quadratic */
                q = fa / fc;
                r = fb / fc;
                p = s * (2.0 * xm * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if (p > 0.0)
                q = -q;
            else
                p = -p;
            if (2.0 * p < fmin(3.0 * xm * q - fabs(tol1 * q), fabs(e * q))) {
                e = d;
                d = p / q;
            } else { /* bisect */
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += fabs(d) > tol1 ? d : (xm > 0.0 ? tol1 : -tol1);
        int rc = value_at(M, S, ev, b, k, &fb);
        if (rc != 0)
            return rc;
    }
    *root = b; /* 200 iterations bisect any double interval */
    return 0;
}

/* The return through zero of event k (direction dir != 0), zero at t0 and at
 * dir * g1 > 0 at t1: the extreme of -dir * g on [t0, t1] by golden section;
 * the root between it and t1, or t0 when g never left (extreme <= 0). */
static int return_root(const mbrt_rk_method *M, const mbrt_rk_state *S, mbrt_events *ev, int k, int dir,
                       double t0, double t1, double g1, double tol, double *root)
{
    const double r = 0.5 * (sqrt(5.0) - 1.0);
    double a = t0, b = t1, x1 = b - r * (b - a), x2 = a + r * (b - a), v1, v2;
    int rc = value_at(M, S, ev, x1, k, &v1);
    if (rc == 0)
        rc = value_at(M, S, ev, x2, k, &v2);
    if (rc != 0)
        return rc;
    v1 *= -dir;
    v2 *= -dir;
    while (b - a > tol) {
        if (v1 >= v2) { /* the maximum is in [a, x2] */
            b = x2;
            x2 = x1;
            v2 = v1;
            x1 = b - r * (b - a);
            rc = value_at(M, S, ev, x1, k, &v1);
            v1 *= -dir;
        } else {
            a = x1;
            x1 = x2;
            v1 = v2;
            x2 = a + r * (b - a);
            rc = value_at(M, S, ev, x2, k, &v2);
            v2 *= -dir;
        }
        if (rc != 0)
            return rc;
    }
    const double peak = v1 >= v2 ? x1 : x2, vpeak = fmax(v1, v2);
    if (!(vpeak > 0.0)) {
        *root = t0;
        return 0;
    }
    return brent_root(M, S, ev, k, peak, t1, -dir * vpeak, g1, tol, root);
}

static int crossed(double a, double b, int dir)
{
    if (dir <= 0 && a >= 0.0 && 0.0 > b)
        return 1;
    return dir >= 0 && a <= 0.0 && 0.0 < b;
}

int mbrt_events_step(const mbrt_rk_method *M, mbrt_rk_state *S, mbrt_events *ev, double t_new,
                     int *prepared, int *fresh)
{
    const int m = ev->n_ev;
    double *g0 = ev->work, *g1 = ev->work + m;
    ev->nevals++;
    int rc = ev->g(ev->gctx, t_new, S->y1, g1);
    if (rc != 0)
        return MBRT_EVENTS_G_FAILED;
    const int fr = *fresh;
    *fresh = -1;
    int best = -1;
    double t_best = t_new;
    for (int k = 0; k < m; ++k) {
        const int dir = ev->direction[k];
        const double a = g0[k], b = g1[k];
        const int back = (k == fr && dir != 0 && dir * b > 0.0);
        if (!back && !crossed(a, b, dir))
            continue;
        if (!*prepared) {
            rc = M->dense_prepare(S);
            if (rc != 0)
                return MBRT_EVENTS_RHS_FAILED;
            *prepared = 1;
        }
        double tk;
        rc = back ? return_root(M, S, ev, k, dir, S->t, t_new, b, ev->tol, &tk)
                  : brent_root(M, S, ev, k, S->t, t_new, a, b, ev->tol, &tk);
        if (rc != 0)
            return MBRT_EVENTS_G_FAILED;
        if (best < 0 || tk < t_best) {
            best = k;
            t_best = tk;
        }
    }
    if (best < 0) {
        memcpy(g0, g1, sizeof(double) * (size_t)m);
        return 0;
    }
    ev->which = best;
    ev->t_event = t_best;
    M->dense_eval(S, (t_best - S->t) / S->h, ev->y_event);
    return 1;
}
