/*
 * mbrt_check.c -- the integrators' shared status messages and argument checks (mbrt_check.h).
 */
#include "mbrt_check.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

int mbrt_finish(mbrt_stats *st, int status, double t, const char *fmt, ...)
{
    va_list ap;
    st->status = status;
    st->t = t;
    va_start(ap, fmt);
    vsnprintf(st->message, sizeof st->message, fmt, ap);
    va_end(ap);
    return status;
}

int mbrt_check_integration(const char *who, mbrt_rhs_fn f, int n, double t0, const double *y0, double t_end,
                           double rtol, const double *atol, double h0, double hmax, long max_steps,
                           const double *t_out, int n_out, const double *y_out, const double *work,
                           mbrt_stats *st)
{
    const int B = MBRT_BAD_ARGUMENT;
    if (f == NULL)
        return mbrt_finish(st, B, t0, "%s: the rhs function pointer is NULL.", who);
    if (n <= 0)
        return mbrt_finish(st, B, t0, "%s: the number of equations n=%d must be positive.", who, n);
    if (y0 == NULL || atol == NULL || work == NULL)
        return mbrt_finish(st, B, t0, "%s: y0, atol and work must not be NULL.", who);
    if (!isfinite(t0) || !isfinite(t_end) || !isfinite(t_end - t0))
        return mbrt_finish(st, B, t0, "%s: t0=%g and t_end=%g must be finite.", who, t0, t_end);
    if (t_end < t0)
        return mbrt_finish(st, B, t0, "%s: t_end=%.17g is before t0=%.17g (only forward integration).", who,
                           t_end, t0);
    if (!isfinite(rtol) || !(rtol >= 100.0 * DBL_EPSILON))
        return mbrt_finish(st, B, t0, "%s: rtol=%g must be finite and at least 100*DBL_EPSILON=%.3g.", who, rtol,
                           100.0 * DBL_EPSILON);
    for (int i = 0; i < n; ++i) {
        if (!isfinite(atol[i]) || atol[i] < 0.0)
            return mbrt_finish(st, B, t0, "%s: atol[%d]=%g must be finite and >= 0.", who, i, atol[i]);
        if (!isfinite(y0[i]))
            return mbrt_finish(st, B, t0, "%s: y0[%d]=%g is not finite.", who, i, y0[i]);
    }
    if (!isfinite(h0) || h0 < 0.0)
        return mbrt_finish(st, B, t0, "%s: h0=%g must be finite and >= 0 (0 = automatic).", who, h0);
    if (!isfinite(hmax) || hmax < 0.0)
        return mbrt_finish(st, B, t0, "%s: hmax=%g must be finite and >= 0 (0 = t_end - t0).", who, hmax);
    if (max_steps < 0)
        return mbrt_finish(st, B, t0, "%s: max_steps=%ld must be >= 0 (0 = default).", who, max_steps);
    if (n_out < 0)
        return mbrt_finish(st, B, t0, "%s: n_out=%d must be >= 0.", who, n_out);
    if (n_out > 0 && (t_out == NULL || y_out == NULL))
        return mbrt_finish(st, B, t0, "%s: t_out and y_out must not be NULL when n_out=%d > 0.", who, n_out);
    for (int i = 0; i < n_out; ++i) {
        if (!(t_out[i] >= t0 && t_out[i] <= t_end)) /* also rejects NaN */
            return mbrt_finish(st, B, t0, "%s: t_out[%d]=%.17g is outside [t0, t_end]=[%.17g, %.17g].", who, i,
                               t_out[i], t0, t_end);
        if (i > 0 && !(t_out[i] > t_out[i - 1]))
            return mbrt_finish(st, B, t0, "%s: t_out is not strictly increasing at index %d (%.17g after %.17g).",
                               who, i, t_out[i], t_out[i - 1]);
    }
    return 0;
}

void mbrt_add_counts(mbrt_stats *total, const mbrt_stats *st)
{
    total->nfev += st->nfev;
    total->nstep += st->nstep;
    total->naccept += st->naccept;
    total->nreject += st->nreject;
    total->status = st->status;
    total->t = st->t;
    memcpy(total->message, st->message, sizeof total->message);
}
