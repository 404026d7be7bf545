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
 *
 * mbrt_impacts_integrate (mbrt.h) runs a run's stretches one call of a
 * stretch function each, and between them acts on the impacts that are
 * plainly a stop's rebound: Newton's restitution on one row of the speeds
 * (c = sign e_i), du = -(1 + e)(c u) M^-1 c^T / (c M^-1 c^T) (Newton's law
 * with the impulse along the row; e.g. Pfeiffer & Glocker, "Multibody
 * Dynamics with Unilateral Contacts", 1996, ch. 5), M and f from an
 * evaluation program (mbrt_mech), then a new stretch from the event as a new
 * stepper would start it.  What may rest, chatter or is no such impact is
 * handed back to the caller at the event.
 */
#include "mbrt_rk_internal.h"
#include "mbrt_check.h"

#include <float.h>
#include <stdio.h>
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

/* ------------------------------------------------------------------ */
/* Impacts acted on between two stretches (mbrt.h, mbrt_impacts)       */
/* ------------------------------------------------------------------ */

/* Work layout: out[n_out] (the program's output), L[nu * nu] (Cholesky of M),
 * x[nu] (M^-1 c^T), a[nu] (M^-1 f at the speeds after). */
size_t mbrt_impacts_work_size(const mbrt_mech *P)
{
    if (P == NULL || P->nu <= 0 || P->n_out <= 0)
        return 0;
    return (size_t)P->n_out + (size_t)P->nu * (size_t)P->nu + 2 * (size_t)P->nu;
}

static int impacts_complete(const mbrt_impacts *I, const mbrt_events *ev, int n)
{
    if (I == NULL || ev == NULL || I->n_ev != ev->n_ev || I->iu == NULL || I->sign == NULL || I->e == NULL ||
        I->comp == NULL || I->n_comp < 1 || I->last == NULL || I->gap == NULL || I->shrinks == NULL ||
        I->chatter < 1 || !(I->burst >= 0.0) || !(I->rest >= 0.0) || I->P == NULL || I->work == NULL ||
        I->cap < 0 || I->count < 0 || I->count > I->cap || (I->cap > 0 && (I->log_t == NULL ||
        I->log_which == NULL || I->log_y == NULL || I->log_loss == NULL)))
        return 0;
    const mbrt_mech *P = I->P;
    if (P->eval == NULL || P->nrows != 0 || P->mn != 0 || P->nq != P->nu || P->nq + P->nu != n ||
        P->off_M < 0 || P->off_f < 0 || P->off_M + P->nu * P->nu > P->n_out || P->off_f + P->nu > P->n_out)
        return 0;
    for (int k = 0; k < I->n_ev; ++k) {
        if (I->iu[k] >= P->nu || I->comp[k] < 0 || I->comp[k] >= I->n_comp)
            return 0;
        if (I->iu[k] >= 0 && (!(I->e[k] >= 0.0 && I->e[k] <= 1.0) || fabs(I->sign[k]) != 1.0))
            return 0;
    }
    return 1;
}

/* The program's M (Cholesky-factored into L) and f at (t, q, u); 0, or 1 when a
 * guard failed, a value was not finite or M is not positive definite. */
static int mass_and_force(const mbrt_mech *P, double t, const double *q, const double *u, double *out, double *L)
{
    const int nu = P->nu;
    if (P->eval(q, u, t, P->d, P->h, P->p, P->w, out) != 0)
        return 1;
    for (int i = 0; i < nu * nu; ++i)
        if (!isfinite(out[P->off_M + i]))
            return 1;
    for (int i = 0; i < nu; ++i)
        if (!isfinite(out[P->off_f + i]))
            return 1;
    if (L != NULL) {
        memcpy(L, out + P->off_M, sizeof(double) * (size_t)nu * (size_t)nu);
        if (mbrt_chol_factor(nu, L) != 0)
            return 1;
    }
    return 0;
}

/* u^T M u with M the program's (row-major at out + off_M). */
static double quadratic(const mbrt_mech *P, const double *out, const double *u)
{
    const int nu = P->nu;
    const double *M = out + P->off_M;
    double s = 0.0;
    for (int i = 0; i < nu; ++i) {
        double r = 0.0;
        for (int j = 0; j < nu; ++j)
            r += M[(size_t)i * nu + j] * u[j];
        s += u[i] * r;
    }
    return s;
}

/* Act on the located event ev->which at (ev->t_event, ev->y_event) if it is
 * plainly a rebound (mbrt.h, mbrt_impacts): 1 with y_plus = [q, u+] written and
 * the impact logged, else 0 (the caller decides). */
static int act_on_impact(mbrt_impacts *I, const mbrt_events *ev, int n, double *y_plus)
{
    const int k = ev->which;
    if (k < 0 || k >= I->n_ev || I->iu[k] < 0 || I->count >= I->cap || !(I->e[k] > 0.0))
        return 0;
    const mbrt_mech *P = I->P;
    const int nu = P->nu, iu = I->iu[k], c = I->comp[k];
    const double t = ev->t_event, s = I->sign[k], *q = ev->y_event, *um = ev->y_event + P->nq;
    const double before = s * um[iu];
    if (!(before < 0.0))
        return 0;
    double d = t - I->last[c];
    int shrinks = 0;
    if (isfinite(I->last[c])) {
        if (d <= I->burst * fmax(1.0, fabs(t)))
            return 0;
        shrinks = (I->gap[c] >= 0.0 && d < I->gap[c]) ? I->shrinks[c] + 1 : 0;
        if (shrinks >= I->chatter)
            return 0;
    }
    double *out = I->work, *L = out + P->n_out, *x = L + (size_t)nu * nu, *a = x + nu;
    if (mass_and_force(P, t, q, um, out, L) != 0)
        return 0;
    for (int i = 0; i < nu; ++i)
        x[i] = 0.0;
    x[iu] = s;
    mbrt_chol_solve(nu, L, x); /* M^-1 c^T */
    const double G = s * x[iu];
    if (!(G > 0.0) || !isfinite(G))
        return 0;
    /* the multiplier as assembly/impacts.py's impulse forms it: the change (-e b) - b of the
     * row's rate, then the 1 x 1 Cholesky solve (two divisions by sqrt(G)); M^-1 c^T is this
     * runtime's Cholesky, LAPACK's there: the speeds after agree to rounding, not bit for bit */
    const double change = -I->e[k] * before - before, root = sqrt(G);
    const double lam = change / root / root;
    double *up = y_plus + P->nq;
    memcpy(y_plus, q, sizeof(double) * (size_t)P->nq);
    for (int i = 0; i < nu; ++i)
        up[i] = um[i] + lam * x[i];
    const double t_minus = quadratic(P, out, um), t_plus = quadratic(P, out, up);
    const double after = s * up[iu];
    if (mass_and_force(P, t, q, up, out, NULL) != 0) /* f at the speeds after */
        return 0;
    memcpy(a, out + P->off_f, sizeof(double) * (size_t)nu);
    mbrt_chol_solve(nu, L, a);
    const double acc = s * a[iu];
    if (!isfinite(acc) || !isfinite(after) || !(after * after > 4.0 * I->rest * fabs(acc)))
        return 0; /* a rebound that may rest: the caller's resting test */
    const int j = I->count++;
    I->log_t[j] = t;
    I->log_which[j] = k;
    memcpy(I->log_y + (size_t)j * 2 * n, ev->y_event, sizeof(double) * (size_t)n);
    memcpy(I->log_y + (size_t)j * 2 * n + n, y_plus, sizeof(double) * (size_t)n);
    I->log_loss[j] = 0.5 * (t_minus - t_plus);
    I->gap[c] = isfinite(I->last[c]) ? d : -1.0;
    I->shrinks[c] = shrinks;
    I->last[c] = t;
    return 1;
}

/* Output times of a segment's k-th stretch: min(chunk_max, chunk 2^k). */
static int stretch_size(const mbrt_stretches *R, int k)
{
    double size = (double)R->chunk * pow(2.0, k < 30 ? k : 30);
    return size < R->chunk_max ? (int)size : R->chunk_max;
}

int mbrt_impacts_integrate(mbrt_stretch_fn integrate, int order, void *ctx, mbrt_events *ev, mbrt_impacts *I,
                           mbrt_stretches *R, int n, double t0, const double *y0, const double *t_out, int n_out,
                           double rtol, const double *atol, double h0, double hmax, long max_steps, double *y_out,
                           int *n_written, double *work, mbrt_stats *stats, double *y_start)
{
    mbrt_stats local, st;
    mbrt_stats *total = stats ? stats : &local;
    memset(total, 0, sizeof *total);
    total->t = t0;
    if (n_written)
        *n_written = 0;
    if (integrate == NULL || n <= 0 || y0 == NULL || t_out == NULL || n_out < 1 || R == NULL || R->chunk < 1 ||
        R->chunk_max < R->chunk || R->count < 0 || R->max_stretches < 1 || !(R->tol_scale > 0.0) ||
        !(R->h_restart >= 0.0) || y_out == NULL || y_start == NULL || !impacts_complete(I, ev, n)) {
        total->status = MBRT_BAD_ARGUMENT;
        snprintf(total->message, sizeof total->message, "mbrt_impacts_integrate: the description is incomplete "
                 "(a stretch function, outputs, the stretches' sizes, tol_scale > 0, the events and impacts).");
        return MBRT_BAD_ARGUMENT;
    }
    double t = t0, h = h0;
    int k0 = 0, done = 0;
    memcpy(y_start, y0, sizeof(double) * (size_t)n);
    for (;;) {
        const int size = stretch_size(R, R->count), nout = size < n_out - k0 ? size : n_out - k0;
        const double t_end = t_out[k0 + nout - 1];
        ev->tol = R->tol_scale * fmax(1.0, fabs(t_end));
        ev->which = -1;
        R->t_end = t_end;
        int nw = 0;
        memset(&st, 0, sizeof st);
        const int rc = integrate(order, ctx, t, y_start, t_end, rtol, atol, h, hmax, max_steps, t_out + k0, nout,
                                 y_out + (size_t)k0 * (size_t)n, &nw, work, &st);
        mbrt_add_counts(total, &st);
        k0 += nw;
        R->count++;
        if (n_written)
            *n_written = k0;
        if (rc == MBRT_EVENT) {
            if (k0 >= n_out || !act_on_impact(I, ev, n, y_start))
                return rc;
            t = ev->t_event; /* a new segment: as a new stepper starts it */
            ev->fresh = ev->which;
            h = R->h_restart;
            R->count = 0;
            continue;
        }
        if (rc != MBRT_OK || k0 >= n_out || ++done >= R->max_stretches || R->h_last == NULL || nw < 1)
            return rc;
        t = t_out[k0 - 1]; /* the next stretch of the segment: as the stepper's next call */
        memcpy(y_start, y_out + (size_t)(k0 - 1) * (size_t)n, sizeof(double) * (size_t)n);
        ev->fresh = -1;
        h = *R->h_last != 0.0 ? *R->h_last : h;
    }
}
