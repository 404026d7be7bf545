/*
 * mbrt_dopri5.c -- the Dormand-Prince 5(4) pair "DOPRI5" with its 4th-order
 * continuous extension.
 *
 * Butcher tableau: J. R. Dormand & P. J. Prince, J. Comput. Appl. Math. 6
 * (1980) 19-26, as tabulated in Hairer, Norsett & Wanner, "Solving ODEs I",
 * Table II.5.2.  Seven stages, the 7th at (t+h, y1) so that it is the first
 * stage of the next step ("first same as last"): 6 rhs calls per step.
 * The solution is propagated with the 5th-order weights b = a_7j; the error
 * estimate is  est = h * sum_j e_j k_j  with e = b - b_hat (4th order).
 *
 * Dense output (Hairer et al., Sec. II.6, and Shampine 1986): with
 * theta = (t - t_n)/h,
 *   y(theta) = r1 + theta (r2 + (1-theta) (r3 + theta (r4 + (1-theta) r5)))
 *   r1 = y_n, r2 = y_{n+1} - y_n, r3 = h k1 - r2, r4 = r2 - h k7 - r3,
 *   r5 = h sum_j d_j k_j,
 * a 4th-order interpolant that matches y and y' at both ends of the step.
 */
#include "mbrt_rk_internal.h"

/* nodes c_i */
static const double C[7] = {0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0};

/* a_ij (row i = stage i+1, j < i); row 6 is the 5th-order solution b */
static const double A[7][6] = {
    {0},
    {1.0 / 5.0},
    {3.0 / 40.0, 9.0 / 40.0},
    {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
    {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
    {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0},
};

/* e_j = b_j - b_hat_j (b_hat: the embedded 4th-order weights) */
static const double E[7] = {71.0 / 57600.0,      0.0,           -71.0 / 16695.0, 71.0 / 1920.0,
                            -17253.0 / 339200.0, 22.0 / 525.0,  -1.0 / 40.0};

/* d_j of the dense output (Hairer's dopri5 / Shampine) */
static const double D[7] = {-12715105075.0 / 11282082432.0, 0.0,
                            87487479700.0 / 32700410799.0,  -10690763975.0 / 1880347072.0,
                            701980252875.0 / 199316789632.0, -1453857185.0 / 822651844.0,
                            69997945.0 / 29380423.0};

/* scratch layout (units of n): k2..k6 [0..5), stage argument [5], dense
 * coefficients r1..r5 [6..11) */
#define NSCRATCH 11

static void stage_pointers(const mbrt_rk_state *S, const double *K[7])
{
    size_t n = (size_t)S->n;
    K[0] = S->f0;
    for (int j = 1; j < 6; ++j)
        K[j] = S->s + (size_t)(j - 1) * n;
    K[6] = S->f1;
}

static int trial(mbrt_rk_state *S, double *err)
{
    const int n = S->n;
    const double t = S->t, h = S->h;
    const double *K[7];
    stage_pointers(S, K);
    double *ys = S->s + 5 * (size_t)n;

    /* stages 2..6 */
    for (int i = 1; i < 6; ++i) {
        mbrt_rk_combine(n, ys, S->y, h, A[i], K, i);
        double ti = (i == 5) ? t + h : t + C[i] * h;
        S->nfev++;
        int rc = S->f(S->ctx, ti, ys, (double *)K[i]);
        if (rc != 0) {
            S->t_fail = ti;
            return rc;
        }
    }
    /* 5th-order solution and the FSAL stage k7 = f(t+h, y1) */
    mbrt_rk_combine(n, S->y1, S->y, h, A[6], K, 6);
    S->nfev++;
    int rc = S->f(S->ctx, t + h, S->y1, S->f1);
    if (rc != 0) {
        S->t_fail = t + h;
        return rc;
    }
    /* scaled RMS of the local error estimate */
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        double e = 0.0;
        for (int j = 0; j < 7; ++j)
            if (E[j] != 0.0)
                e += E[j] * K[j][i];
        e = h * e / mbrt_rk_scale(S, i);
        sum += e * e;
    }
    *err = sqrt(sum / n);
    mbrt_rk_stiffness(S, ys, K[5]); /* stage 6 is at t+h too, its argument still in ys */
    return 0;
}

static int dense_prepare(mbrt_rk_state *S)
{
    const int n = S->n;
    const double h = S->h;
    const double *K[7];
    stage_pointers(S, K);
    double *r = S->s + 6 * (size_t)n;
    double *r1 = r, *r2 = r + n, *r3 = r + 2 * (size_t)n, *r4 = r + 3 * (size_t)n,
           *r5 = r + 4 * (size_t)n;
    for (int i = 0; i < n; ++i) {
        double dy = S->y1[i] - S->y[i];
        double bspl = h * K[0][i] - dy;
        double d = 0.0;
        for (int j = 0; j < 7; ++j)
            if (D[j] != 0.0)
                d += D[j] * K[j][i];
        r1[i] = S->y[i];
        r2[i] = dy;
        r3[i] = bspl;
        r4[i] = dy - h * K[6][i] - bspl;
        r5[i] = h * d;
    }
    return 0;
}

static void dense_eval(const mbrt_rk_state *S, double theta, double *out)
{
    const int n = S->n;
    const double *r = S->s + 6 * (size_t)n;
    const double *r1 = r, *r2 = r + n, *r3 = r + 2 * (size_t)n, *r4 = r + 3 * (size_t)n,
                 *r5 = r + 4 * (size_t)n;
    const double th1 = 1.0 - theta;
    for (int i = 0; i < n; ++i)
        out[i] = r1[i] + theta * (r2[i] + th1 * (r3[i] + theta * (r4[i] + th1 * r5[i])));
}

/* Hairer's dopri5 defaults: FAC1 = 0.2, FAC2 = 10, BETA = 0.04, SAFE = 0.9;
 * the error estimate is O(h^5), so the step factor uses 1/q = 1/5. */
static const mbrt_rk_method DOPRI5 = {
    "DOPRI5", 5, 5.0, 0.2, 10.0, 0.04, 0.9, NSCRATCH, 3.25, trial, dense_prepare, dense_eval,
};

size_t mbrt_dopri5_work_size(int n)
{
    return mbrt_rk_work_size(&DOPRI5, n);
}

int mbrt_dopri5(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n, double t0,
                const double *y0, double t_end, double rtol, const double *atol, double h0,
                double hmax, long max_steps, const double *t_out, int n_out, double *y_out,
                int *n_written, double *work, mbrt_stats *stats)
{
    return mbrt_rk_integrate(&DOPRI5, f, on_step, ctx, n, t0, y0, t_end, rtol, atol, h0, hmax,
                             max_steps, t_out, n_out, y_out, n_written, work, stats, 0, NULL);
}

int mbrt_dopri5_events(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n, double t0,
                      const double *y0, double t_end, double rtol, const double *atol, double h0,
                      double hmax, long max_steps, const double *t_out, int n_out, double *y_out,
                      int *n_written, double *work, mbrt_stats *stats, int stiff_steps, mbrt_events *ev)
{
    return mbrt_rk_integrate(&DOPRI5, f, on_step, ctx, n, t0, y0, t_end, rtol, atol, h0, hmax,
                             max_steps, t_out, n_out, y_out, n_written, work, stats, stiff_steps, ev);
}
