/*
 * mbrt_check.h -- what every integrator of the runtime (mbrt_rk.c: DOPRI5, DOP853;
 * mbrt_radau5.c: RADAU5) reports and checks the same way: its status with a message, and the
 * arguments of an integration.  Not part of the public API; everything public is in mbrt.h.
 */
#ifndef MBRT_CHECK_H
#define MBRT_CHECK_H

#include "mbrt.h"

/* Records status, time and a printf-style message in st; returns the status. */
int mbrt_finish(mbrt_stats *st, int status, double t, const char *fmt, ...);

/* Checks the arguments of an integration from t0 to t_end with outputs at t_out; returns 0,
 * or MBRT_BAD_ARGUMENT with a message naming the argument, prefixed by "<who>: ". */
int mbrt_check_integration(const char *who, mbrt_rhs_fn f, int n, double t0, const double *y0, double t_end,
                           double rtol, const double *atol, double h0, double hmax, long max_steps,
                           const double *t_out, int n_out, const double *y_out, const double *work,
                           mbrt_stats *st);

/* Adds st's evaluations, steps, acceptances and rejections to total and takes its status,
 * time and message: the counts of a loop of integrations (events, passages) as one. */
void mbrt_add_counts(mbrt_stats *total, const mbrt_stats *st);

#endif
