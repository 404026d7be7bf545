/*
 * mbrt_dop853.c -- the Dormand-Prince 8(5,3) pair "DOP853" with its
 * 7th-order continuous extension.
 *
 * Coefficients: P. J. Prince & J. R. Dormand, "High order embedded
 * Runge-Kutta formulae", J. Comput. Appl. Math. 7 (1981) 67-75, in the
 * version of Hairer, Norsett & Wanner, "Solving ODEs I", Sec. II.10 (the
 * published constants, rounded to the nearest double).
 *
 * One step: 12 stages k1..k12 (11 new rhs calls, k1 is the previous step's
 * last derivative), y1 = y + h sum_j b_j k_j (8th order).  Two embedded
 * estimates, of order 5 (weights E5) and 3 (weights E3), are combined as in
 * Hairer's dop853:
 *
 *   err = |h| * e5^2 / sqrt(n * (e5^2 + 0.01 e3^2)),
 *   e5^2 = sum_i (sum_j E5_j k_ji / sc_i)^2,  likewise e3^2,
 *
 * which behaves like O(h^8) for small h and avoids the over-optimistic pure
 * 5th-order estimate for large h.  f(t+h, y1) (k13) is computed only for
 * accepted steps, so a rejected step costs 11 rhs calls.
 *
 * Dense output (Hairer et al., Sec. II.6; Hairer's contd8): three more
 * stages k14..k16 at t + (0.1, 0.2, 7/9) h, then with s = theta, s1 = 1 - s
 *   y(s) = r1 + s (r2 + s1 (r3 + s (r4 + s1 (r5 + s (r6 + s1 (r7 + s r8))))))
 *   r1 = y_n, r2 = y_{n+1} - y_n, r3 = h k1 - r2, r4 = r2 - h k13 - r3,
 *   r_{5+m} = h sum_j D_mj k_j  (m = 0..3, j = 1..16).
 * The extra stages are only computed in steps that contain output times.
 */
#include "mbrt_rk_internal.h"

#define NS 16 /* stages incl. k13 (= f(t+h, y1)) and the 3 dense-output stages */

static const double C[NS] = {
    0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274,
    0.2816496580927726, 0.3333333333333333, 0.25, 0.3076923076923077,
    0.6512820512820513, 0.6, 0.8571428571428571, 1.0,
    1.0, 0.1, 0.2, 0.7777777777777778};

/* A[i][j], j < i.  Row 12 holds the 8th-order weights b (k13 is evaluated at
 * the new solution); rows 13-15 are the dense-output stages. */
static const double A[NS][NS - 1] = {
    {0},
    {0.05260015195876773},
    {0.0197250569845379, 0.0591751709536137},
    {0.02958758547680685, 0.0, 0.08876275643042054},
    {0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792},
    {0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242},
    {0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125},
    {0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328,
     -0.015319437748624402, 0.008273789163814023},
    {0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726,
     27.59209969944671, 20.154067550477894, -43.48988418106996},
    {0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843,
     21.230051448181193, 15.279233632882423, -33.28821096898486, -0.020331201708508627},
    {-0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295,
     -8.149787010746927, -18.52006565999696, 22.739487099350505, 2.4936055526796523,
     -3.0467644718982196},
    {2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625,
     -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063,
     12.360567175794303, 0.6433927460157636},
    {0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
     -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034,
     0.04471061572777259},
    {0.056167502283047954, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25350021021662483,
     -0.2462390374708025, -0.12419142326381637, 0.15329179827876568, 0.00820105229563469,
     0.007567897660545699, -0.008298},
    {0.03183464816350214, 0.0, 0.0, 0.0, 0.0, 0.028300909672366776, 0.053541988307438566,
     -0.05492374857139099, 0.0, 0.0, -0.00010834732869724932, 0.0003825710908356584,
     -0.00034046500868740456, 0.1413124436746325},
    {-0.42889630158379194, 0.0, 0.0, 0.0, 0.0, -4.697621415361164, 7.683421196062599,
     4.06898981839711, 0.3567271874552811, 0.0, 0.0, 0.0, -0.0013990241651590145,
     2.9475147891527724, -9.15095847217987},
};

/* embedded error weights (b - b_hat) over k1..k12 */
static const double E5[12] = {
    0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044, -0.4957589496572502,
    1.6643771824549864, -0.35032884874997366, 0.3341791187130175, 0.08192320648511571,
    -0.022355307863886294};
static const double E3[12] = {
    -0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
    -5.801203960010585, -0.4226823213237919, -0.1521609496625161, 0.20136540080403034,
    0.02265179219836082};

/* dense-output weights over k1..k16 */
static const double D[4][NS] = {
    {-8.428938276109013, 0.0, 0.0, 0.0, 0.0, 0.5667149535193777, -3.0689499459498917,
     2.38466765651207, 2.117034582445028, -0.871391583777973, 2.2404374302607883,
     0.6315787787694688, -0.08899033645133331, 18.148505520854727, -9.194632392478356,
     -4.436036387594894},
    {10.427508642579134, 0.0, 0.0, 0.0, 0.0, 242.28349177525817, 165.20045171727028,
     -374.5467547226902, -22.113666853125306, 7.733432668472264, -30.674084731089398,
     -9.332130526430229, 15.697238121770845, -31.139403219565178, -9.35292435884448,
     35.81684148639408},
    {19.985053242002433, 0.0, 0.0, 0.0, 0.0, -387.0373087493518, -189.17813819516758,
     527.8081592054236, -11.57390253995963, 6.8812326946963, -1.0006050966910838,
     0.7777137798053443, -2.778205752353508, -60.19669523126412, 84.32040550667716,
     11.99229113618279},
    {-25.69393346270375, 0.0, 0.0, 0.0, 0.0, -154.18974869023643, -231.5293791760455,
     357.6391179106141, 93.40532418362432, -37.45832313645163, 104.0996495089623,
     29.8402934266605, -43.53345659001114, 96.32455395918828, -39.17726167561544,
     -149.72683625798564},
};

/* scratch layout (units of n): k2..k12 [0..11), k14..k16 [11..14), stage
 * argument [14], dense coefficients r1..r8 [15..23) */
#define NSCRATCH 23

static void stage_pointers(const mbrt_rk_state *S, const double *K[NS])
{
    size_t n = (size_t)S->n;
    K[0] = S->f0;
    for (int j = 1; j < 12; ++j)
        K[j] = S->s + (size_t)(j - 1) * n;
    K[12] = S->f1;
    for (int j = 13; j < NS; ++j)
        K[j] = S->s + (size_t)(j - 2) * n;
}

/* computes stages first..last (indices into K) */
static int stages(mbrt_rk_state *S, const double *K[NS], int first, int last)
{
    const int n = S->n;
    double *ys = S->s + 14 * (size_t)n;
    for (int i = first; i <= last; ++i) {
        mbrt_rk_combine(n, ys, S->y, S->h, A[i], K, i);
        double ti = (C[i] == 1.0) ? S->t + S->h : S->t + C[i] * S->h;
        S->nfev++;
        int rc = S->f(S->ctx, ti, ys, (double *)K[i]);
        if (rc != 0) {
            S->t_fail = ti;
            return rc;
        }
    }
    return 0;
}

static int trial(mbrt_rk_state *S, double *err)
{
    const int n = S->n;
    const double h = S->h;
    const double *K[NS];
    stage_pointers(S, K);
    int rc = stages(S, K, 1, 11);
    if (rc != 0)
        return rc;
    mbrt_rk_combine(n, S->y1, S->y, h, A[12], K, 12);

    double e5 = 0.0, e3 = 0.0;
    for (int i = 0; i < n; ++i) {
        double s5 = 0.0, s3 = 0.0;
        for (int j = 0; j < 12; ++j) {
            if (E5[j] != 0.0)
                s5 += E5[j] * K[j][i];
            if (E3[j] != 0.0)
                s3 += E3[j] * K[j][i];
        }
        double sc = mbrt_rk_scale(S, i);
        s5 /= sc;
        s3 /= sc;
        e5 += s5 * s5;
        e3 += s3 * s3;
    }
    double den = e5 + 0.01 * e3;
    *err = (den > 0.0) ? fabs(h) * e5 / sqrt(den * n) : 0.0;
    if (!isfinite(den))
        *err = NAN;

    if (*err <= 1.0) { /* accepted: k13 = f(t+h, y1), first stage of the next step */
        S->nfev++;
        rc = S->f(S->ctx, S->t + h, S->y1, S->f1);
        if (rc != 0) {
            S->t_fail = S->t + h;
            return rc;
        }
        /* stage 12 is at t+h too, its argument still in the stage buffer */
        mbrt_rk_stiffness(S, S->s + 14 * (size_t)n, K[11]);
    }
    return 0;
}

static int dense_prepare(mbrt_rk_state *S)
{
    const int n = S->n;
    const double h = S->h;
    const double *K[NS];
    stage_pointers(S, K);
    int rc = stages(S, K, 13, 15);
    if (rc != 0)
        return rc;
    double *r = S->s + 15 * (size_t)n;
    for (int i = 0; i < n; ++i) {
        double dy = S->y1[i] - S->y[i];
        double bspl = h * K[0][i] - dy;
        r[i] = S->y[i];
        r[n + i] = dy;
        r[2 * (size_t)n + i] = bspl;
        r[3 * (size_t)n + i] = dy - h * K[12][i] - bspl;
        for (int m = 0; m < 4; ++m) {
            double d = 0.0;
            for (int j = 0; j < NS; ++j)
                if (D[m][j] != 0.0)
                    d += D[m][j] * K[j][i];
            r[(size_t)(4 + m) * n + i] = h * d;
        }
    }
    return 0;
}

static void dense_eval(const mbrt_rk_state *S, double theta, double *out)
{
    const size_t n = (size_t)S->n;
    const double *r = S->s + 15 * n;
    const double s = theta, s1 = 1.0 - theta;
    for (size_t i = 0; i < n; ++i) {
        double p = r[4 * n + i] + s * (r[5 * n + i] + s1 * (r[6 * n + i] + s * r[7 * n + i]));
        out[i] = r[i] + s * (r[n + i] + s1 * (r[2 * n + i] + s * (r[3 * n + i] + s1 * p)));
    }
}

/* Hairer's dop853 defaults: FAC1 = 0.333, FAC2 = 6, BETA = 0 (no PI part),
 * SAFE = 0.9; step factor err^(1/8). */
static const mbrt_rk_method DOP853 = {
    "DOP853", 8, 8.0, 0.333, 6.0, 0.0, 0.9, NSCRATCH, 6.1, trial, dense_prepare, dense_eval,
};

size_t mbrt_dop853_work_size(int n)
{
    return mbrt_rk_work_size(&DOP853, n);
}

int mbrt_dop853(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n, double t0,
                const double *y0, double t_end, double rtol, const double *atol, double h0,
                double hmax, long max_steps, const double *t_out, int n_out, double *y_out,
                int *n_written, double *work, mbrt_stats *stats)
{
    return mbrt_rk_integrate(&DOP853, f, on_step, ctx, n, t0, y0, t_end, rtol, atol, h0, hmax,
                             max_steps, t_out, n_out, y_out, n_written, work, stats, 0, NULL);
}

int mbrt_dop853_events(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n, double t0,
                      const double *y0, double t_end, double rtol, const double *atol, double h0,
                      double hmax, long max_steps, const double *t_out, int n_out, double *y_out,
                      int *n_written, double *work, mbrt_stats *stats, int stiff_steps, mbrt_events *ev)
{
    return mbrt_rk_integrate(&DOP853, f, on_step, ctx, n, t0, y0, t_end, rtol, atol, h0, hmax,
                             max_steps, t_out, n_out, y_out, n_written, work, stats, stiff_steps, ev);
}
