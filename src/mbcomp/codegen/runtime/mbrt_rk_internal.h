/*
 * mbrt_rk_internal.h -- interface between the adaptive Runge-Kutta driver
 * (mbrt_rk.c) and the individual embedded pairs (mbrt_dopri5.c,
 * mbrt_dop853.c).  Not part of the public API; everything public is in
 * mbrt.h.
 *
 * The driver owns step-size selection, output, callbacks, argument checks and
 * bookkeeping; a method only knows its Butcher tableau: how to attempt one
 * step (new solution, error norm, derivative at the new point) and how to
 * evaluate its continuous extension.
 */
#ifndef MBRT_RK_INTERNAL_H
#define MBRT_RK_INTERNAL_H

#include "mbrt.h"

#include <math.h>

/* State shared by the driver and a method during one integration.  All
 * arrays have n entries and live in the caller's work buffer. */
typedef struct {
    mbrt_rhs_fn f;
    void *ctx;
    int n;
    double rtol;
    const double *atol;
    double t, h;      /* current step: from t to t + h                    */
    double *y, *f0;   /* state at t and f(t, y)                            */
    double *y1, *f1;  /* proposed state at t + h and f(t + h, y1)          */
    double *s;        /* method scratch (scratch_per_n * n doubles)        */
    long nfev;        /* rhs evaluations so far                            */
    double hlamb;     /* |h| times the estimated largest |eigenvalue| of df/dy along
                         the accepted step (Hairer's stiffness test; 0: none) */
    double t_fail;    /* time argument of an rhs call that returned nonzero */
} mbrt_rk_state;

typedef struct {
    const char *name;     /* "DOPRI5", "DOP853" (used in messages)        */
    int order;            /* order of the propagated solution (hinit)      */
    double err_order;     /* q in err ~ h^q: step factor (1/err)^(1/q)     */
    double fac_min;       /* smallest h_new / h  (Hairer's FAC1)           */
    double fac_max;       /* largest  h_new / h  (Hairer's FAC2)           */
    double beta;          /* PI ("Lund") stabilisation exponent (BETA)     */
    double safe;          /* safety factor (SAFE)                          */
    int scratch_per_n;    /* method scratch, in units of n doubles         */
    double stiff_limit;   /* hlamb above this is a step held by stability  */

    /* Attempts the step (S->t, S->h) from S->y, S->f0 = f(t, y).  Writes
     * S->y1 and *err (the scaled RMS error estimate; accept iff <= 1).  If
     * *err <= 1 it must also leave S->f1 = f(t + h, y1).  Returns 0, or the
     * nonzero code of a failing rhs call (with S->t_fail set). */
    int (*trial)(mbrt_rk_state *S, double *err);

    /* Builds the continuous extension of the step just accepted (called at
     * most once per step, before y/f0 are overwritten; may call f).  Returns
     * 0 or a failing rhs code. */
    int (*dense_prepare)(mbrt_rk_state *S);

    /* Continuous extension at t + theta*h, theta in [0, 1], into out[n]. */
    void (*dense_eval)(const mbrt_rk_state *S, double theta, double *out);
} mbrt_rk_method;

/* Weight of component i in the error norm (Hairer):
 * sc_i = atol_i + rtol * max(|y_i(t)|, |y_i(t+h)|), kept away from 0 so that
 * atol_i = 0 at y_i = 0 gives a huge, not a NaN, scaled error. */
static inline double mbrt_rk_scale(const mbrt_rk_state *S, int i)
{
    double sc = S->atol[i] + S->rtol * fmax(fabs(S->y[i]), fabs(S->y1[i]));
    return sc > 1e-300 ? sc : 1e-300;
}

/* out = y + h * sum_j a[j] * K[j] over the nonzero a[j] (j < m): the
 * argument of an explicit Runge-Kutta stage. */
static inline void mbrt_rk_combine(int n, double *out, const double *y, double h,
                                   const double *a, const double *const *K, int m)
{
    for (int i = 0; i < n; ++i)
        out[i] = 0.0;
    for (int j = 0; j < m; ++j) {
        if (a[j] == 0.0)
            continue;
        const double *k = K[j];
        double c = a[j];
        for (int i = 0; i < n; ++i)
            out[i] += c * k[i];
    }
    for (int i = 0; i < n; ++i)
        out[i] = y[i] + h * out[i];
}

/* Hairer's stiffness estimate of an accepted step, into S->hlamb: |h| |f(t+h, y1) -
 * f(t+h, Y)| / |y1 - Y| for the method's last stage Y at t+h (argument ys, derivative
 * k_last); f(t+h, y1) is S->f1.  Estimates |h lambda| of the largest eigenvalue met. */
static inline void mbrt_rk_stiffness(mbrt_rk_state *S, const double *ys, const double *k_last)
{
    double num = 0.0, den = 0.0;
    for (int i = 0; i < S->n; ++i) {
        double a = S->f1[i] - k_last[i], b = S->y1[i] - ys[i];
        num += a * a;
        den += b * b;
    }
    S->hlamb = (den > 0.0) ? fabs(S->h) * sqrt(num / den) : 0.0;
}

/* The driver: argument checks, starting step, the step-size loop, dense
 * output at t_out and the callbacks.  The public mbrt_dopri5/mbrt_dop853 are
 * thin wrappers around it. */
int mbrt_rk_integrate(const mbrt_rk_method *M, mbrt_rhs_fn f, mbrt_step_fn on_step,
                      void *ctx, int n, double t0, const double *y0, double t_end,
                      double rtol, const double *atol, double h0, double hmax,
                      long max_steps, const double *t_out, int n_out,
                      double *y_out, int *n_written, double *work, mbrt_stats *stats,
                      int stiff_steps, mbrt_events *ev);

/* The events of an accepted step from S->t to t_new (S->y, S->f0 the step's
 * start, S->y1, S->f1 its end; mbrt.h, mbrt_events): g at the step's end,
 * then the earliest crossing located on the continuous extension (built here
 * if *prepared is 0, which is then set).  *fresh is the event acted on at the
 * run's start (checked in the first step only; set to -1).  Returns 1 with
 * ev->which, t_event, y_event set; 0 (no event: ev's start values become the
 * step's end values); MBRT_EVENTS_G_FAILED (an event function returned nonzero
 * or a value that is not finite) or MBRT_EVENTS_RHS_FAILED (the rhs failed in
 * the continuous extension, S->t_fail its time). */
enum { MBRT_EVENTS_G_FAILED = -1, MBRT_EVENTS_RHS_FAILED = -2 };
int mbrt_events_step(const mbrt_rk_method *M, mbrt_rk_state *S, mbrt_events *ev, double t_new,
                     int *prepared, int *fresh);

/* Evaluates the events at the start (t0, y0) into their start values; 0 or
 * the event function's code. */
int mbrt_events_begin(mbrt_events *ev, double t0, const double *y0);

/* Doubles of work needed by method M for n equations (0 if n <= 0). */
size_t mbrt_rk_work_size(const mbrt_rk_method *M, int n);

#endif /* MBRT_RK_INTERNAL_H */
