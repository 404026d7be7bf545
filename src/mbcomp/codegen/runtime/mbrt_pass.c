/*
 * mbrt_pass.c -- singular positions passed inside the C loop (mbrt_pass.h).
 *
 * The range-space solve mirrors mbcomp's assembly/kkt.py solve_kkt with
 * pass_rank: M = L L^T (Cholesky), x0 = M^-1 f, Y = M^-1 A^T, G = A Y, its
 * eigen-decomposition G = V diag(g) V^T (Householder tridiagonalization and the
 * implicit symmetric QR step: G. H. Golub, C. F. Van Loan, "Matrix
 * Computations", 4th ed., 2013, Sec. 8.3; 21 us at m = 20), the multipliers
 * lam = V_k diag(1/g_k) V_k^T (A x0 - rhs) over the kept directions k (g_k >
 * pass_rank max g), du/dt = x0 - Y lam.  The acceleration-level right side is
 * rhs = [-c_b - 2 alpha dPhi/dt - beta^2 Phi; -B_b - alpha Psi] (Baumgarte
 * gains d[0], d[1]).
 *
 * The event function is d/dt log det(C_k C_k^T) by a central difference along
 * the coordinates' rates at the same speeds: exactly zero at a pole of
 * log det (a singular position, whatever its rank drop) by symmetry, and a
 * rise through zero at every other local minimum.  Once a minimum is logged
 * at t_min, the function returns its absolute value for t <= t_min, so the
 * step taken again over it finds no crossing there.
 */
#include "mbrt_pass.h"
#include "mbrt_check.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define PASS_LOGDET_SINGULAR (-1e300)
/* s: the event's d/dt log det r is passed as r / (1 + (r s)^2), linear in t within ~ 2 k s of a pole */
#define PASS_POLE_SPAN 1e-3
/* states sampled on each side of a located minimum inside its step: another sign change of the
 * event function there (two minima in one step, or a maximum located) takes the step again in
 * quarters, and no later step is longer */
#define PASS_SAMPLES 5
/* parts of a step's chord at whose inner points the rate's sign is checked (hides_pair) */
#define PASS_CHORD 4
/* an accepted step with range-space solves below this share of the last step without any:
 * the steps collapse next to a singular position (a step starting ms before one fell to
 * 1e-6 s), and the integration goes back to that step's start (kept across calls), at most
 * twice: a step twice as long as from there to the collapse (the singular position inside
 * it, its stages away from it), then one half as long */
#define PASS_COLLAPSE 0.05

static int finite_all(int n, const double *v)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

static int nvel(const mbrt_mech *P) { return P->nrows + P->mn; }

static const double *arow(const mbrt_mech *P, const double *out, int k)
{
    return k < P->nrows ? out + P->off_C + (size_t)P->rows[k] * (size_t)P->nu
                        : out + P->off_B + (size_t)(k - P->nrows) * (size_t)P->nu;
}

/* Work layout (m = nrows + mn, n = nq + nu): out[n_out], L[nu nu], x0[nu],
 * A[m nu], Yt[m nu], G[m m], V[m m], r[m], lam[m], qd[nq], qs[nq],
 * Gk[nrows nrows], events' work[3 + n], y_event[n], y_start[n], y_back[n], y_after[n],
 * y_before[n], times[cap], rf[5 n] (the refinement's two states, their rates and a state
 * between), smp[PASS_SAMPLES n] (states along the step), ee[m], hh[m] (the eigen-solver's). */
size_t mbrt_pass_work_size(const mbrt_mech *P, int cap)
{
    if (cap < 0 || P == NULL || P->nq <= 0 || P->nu <= 0 || P->n_out <= 0)
        return 0;
    const size_t nq = (size_t)P->nq, nu = (size_t)P->nu, m = (size_t)nvel(P), n = nq + nu;
    return (size_t)P->n_out + nu * nu + nu + 2 * m * nu + 2 * m * m + 2 * m + 2 * nq +
           (size_t)P->nrows * (size_t)P->nrows + 3 + (11 + PASS_SAMPLES) * n + (size_t)cap + 2 * m;
}

typedef struct {
    double *out, *L, *x0, *A, *Yt, *G, *V, *r, *lam, *qd, *qs, *Gk, *evwork, *y_event, *y_start, *y_back, *y_after,
        *y_before, *times, *rf, *smp, *ee, *hh;
} pass_work;

static pass_work layout(const mbrt_pass *S)
{
    const mbrt_mech *P = S->mech;
    const size_t nq = (size_t)P->nq, nu = (size_t)P->nu, m = (size_t)nvel(P), n = nq + nu;
    pass_work W;
    W.out = S->work;
    W.L = W.out + P->n_out;
    W.x0 = W.L + nu * nu;
    W.A = W.x0 + nu;
    W.Yt = W.A + m * nu;
    W.G = W.Yt + m * nu;
    W.V = W.G + m * m;
    W.r = W.V + m * m;
    W.lam = W.r + m;
    W.qd = W.lam + m;
    W.qs = W.qd + nq;
    W.Gk = W.qs + nq;
    W.evwork = W.Gk + (size_t)P->nrows * (size_t)P->nrows;
    W.y_event = W.evwork + 3 + n;
    W.y_start = W.y_event + n;
    W.y_back = W.y_start + n;
    W.y_after = W.y_back + n;
    W.y_before = W.y_after + n;
    W.times = W.y_before + n;
    W.rf = W.times + S->cap;
    W.smp = W.rf + 5 * (size_t)n;
    W.ee = W.smp + PASS_SAMPLES * (size_t)n;
    W.hh = W.ee + m;
    return W;
}

/* Symmetric eigen-decomposition G = V diag(g) V^T of the m x m matrix G (row-major, destroyed;
 * the eigenvalues are left on its diagonal): Householder reduction to tridiagonal form, then
 * the implicit symmetric QR step with Wilkinson's shift, deflating at the bottom (G. H. Golub,
 * C. F. Van Loan, "Matrix Computations", 4th ed., 2013, Secs. 8.3.1-8.3.5).  e and h: m doubles
 * of scratch each.  Returns 0, or 1 when 30 m steps were not enough. */
static int sym_eigen(int m, double *G, double *V, double *e, double *h)
{
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
            V[(size_t)i * m + j] = i == j ? 1.0 : 0.0;
    /* Householder: column k below the subdiagonal annihilated by H_k = I - 2 h h^T on rows k+1.. */
    for (int k = 0; k + 2 < m; ++k) {
        double norm = 0.0;
        for (int i = k + 1; i < m; ++i)
            norm += G[(size_t)i * m + k] * G[(size_t)i * m + k];
        norm = sqrt(norm);
        const double x0 = G[(size_t)(k + 1) * m + k];
        if (norm == 0.0)
            continue;
        const double alpha = x0 > 0.0 ? -norm : norm;
        double hn = 0.0;
        for (int i = 0; i < m; ++i)
            h[i] = i <= k ? 0.0 : G[(size_t)i * m + k];
        h[k + 1] -= alpha;
        for (int i = k + 1; i < m; ++i)
            hn += h[i] * h[i];
        hn = sqrt(hn);
        if (hn == 0.0)
            continue;
        for (int i = k + 1; i < m; ++i)
            h[i] /= hn;
        /* p = A22 h, w = p - (h^T p) h, A22 -= 2 (h w^T + w h^T); e as p/w */
        double hp = 0.0;
        for (int i = k + 1; i < m; ++i) {
            double s = 0.0;
            for (int j = k + 1; j < m; ++j)
                s += G[(size_t)i * m + j] * h[j];
            e[i] = s;
            hp += h[i] * s;
        }
        for (int i = k + 1; i < m; ++i)
            e[i] -= hp * h[i];
        for (int i = k + 1; i < m; ++i)
            for (int j = k + 1; j < m; ++j)
                G[(size_t)i * m + j] -= 2.0 * (h[i] * e[j] + e[i] * h[j]);
        G[(size_t)(k + 1) * m + k] = G[(size_t)k * m + k + 1] = alpha;
        for (int i = k + 2; i < m; ++i)
            G[(size_t)i * m + k] = G[(size_t)k * m + i] = 0.0;
        /* V <- V H_k (V starts as I: V = H_0 H_1 ...): columns k+1.. */
        for (int i = 0; i < m; ++i) {
            double s = 0.0;
            for (int j = k + 1; j < m; ++j)
                s += V[(size_t)i * m + j] * h[j];
            for (int j = k + 1; j < m; ++j)
                V[(size_t)i * m + j] -= 2.0 * s * h[j];
        }
    }
    /* the tridiagonal T: diagonal on G's diagonal (d), subdiagonal e[0..m-2] */
    for (int i = 0; i + 1 < m; ++i)
        e[i] = G[(size_t)(i + 1) * m + i];
    if (m > 0)
        e[m - 1] = 0.0;
    double *d = h; /* h is free now */
    for (int i = 0; i < m; ++i)
        d[i] = G[(size_t)i * m + i];
    int steps = 0;
    for (int hi = m - 1; hi > 0;) {
        if (fabs(e[hi - 1]) <= DBL_EPSILON * (fabs(d[hi - 1]) + fabs(d[hi]))) {
            e[hi - 1] = 0.0;
            --hi;
            continue;
        }
        if (++steps > 30 * m)
            return 1;
        int lo = hi - 1;
        while (lo > 0 && fabs(e[lo - 1]) > DBL_EPSILON * (fabs(d[lo - 1]) + fabs(d[lo])))
            --lo;
        /* Wilkinson's shift: the eigenvalue of the trailing 2 x 2 nearer to its last entry */
        const double a = d[hi - 1], b = e[hi - 1], c = d[hi], delta = 0.5 * (a - c);
        const double mu = c - b * b / (delta + (delta >= 0.0 ? 1.0 : -1.0) * hypot(delta, b));
        double x = d[lo] - mu, z = e[lo];
        for (int k = lo; k < hi; ++k) {
            const double r = hypot(x, z), cs = r > 0.0 ? x / r : 1.0, sn = r > 0.0 ? z / r : 0.0;
            if (k > lo)
                e[k - 1] = r;
            const double dk = d[k], dk1 = d[k + 1], ek = e[k];
            d[k] = cs * cs * dk + 2.0 * cs * sn * ek + sn * sn * dk1;
            d[k + 1] = sn * sn * dk - 2.0 * cs * sn * ek + cs * cs * dk1;
            e[k] = cs * sn * (dk1 - dk) + (cs * cs - sn * sn) * ek;
            if (k + 1 < hi) {
                x = e[k];
                z = sn * e[k + 1];
                e[k + 1] *= cs;
            }
            for (int i = 0; i < m; ++i) {
                const double vk = V[(size_t)i * m + k], vk1 = V[(size_t)i * m + k + 1];
                V[(size_t)i * m + k] = cs * vk + sn * vk1;
                V[(size_t)i * m + k + 1] = -sn * vk + cs * vk1;
            }
        }
    }
    for (int i = 0; i < m; ++i)
        G[(size_t)i * m + i] = d[i];
    return 0;
}

/* dq/dt at (t, q, u) into qd: the program's rate, or u. */
static int coordinate_rate(const mbrt_mech *P, double t, const double *q, const double *u, double *qd)
{
    if (P->qrate == NULL) {
        memcpy(qd, u, sizeof(double) * (size_t)P->nu);
        return 0;
    }
    if (P->qrate(q, u, t, P->d, P->h, P->p, P->w, qd) != 0 || !finite_all(P->nq, qd))
        return 1;
    return 0;
}

int mbrt_pass_rhs(mbrt_pass *S, double t, const double *y, double *dy)
{
    const mbrt_mech *P = S->mech;
    const int nq = P->nq, nu = P->nu, m = nvel(P);
    const double *q = y, *u = y + nq;
    pass_work W = layout(S);
    if (P->eval(q, u, t, P->d, P->h, P->p, P->w, W.out) != 0 || !finite_all(P->n_out, W.out))
        return MBRT_MECH_FALLBACK;
    memcpy(W.L, W.out + P->off_M, sizeof(double) * (size_t)nu * (size_t)nu);
    if (mbrt_chol_factor(nu, W.L) != 0)
        return MBRT_MECH_MASS_SINGULAR;
    double *ud = dy + nq;
    memcpy(W.x0, W.out + P->off_f, sizeof(double) * (size_t)nu);
    mbrt_chol_solve(nu, W.L, W.x0);
    const double alpha = S->d[0], beta = S->d[1];
    for (int k = 0; k < m; ++k) {
        memcpy(W.A + (size_t)k * nu, arow(P, W.out, k), sizeof(double) * (size_t)nu);
        memcpy(W.Yt + (size_t)k * nu, W.A + (size_t)k * nu, sizeof(double) * (size_t)nu);
        mbrt_chol_solve(nu, W.L, W.Yt + (size_t)k * nu);
        double rhs;
        if (k < P->nrows) {
            const int i = P->rows[k];
            rhs = -W.out[P->off_cb + i] - 2.0 * alpha * W.out[P->off_Phid + i] - beta * beta * W.out[P->off_Phi + i];
        } else {
            const int i = k - P->nrows;
            rhs = -W.out[P->off_Bb + i] - alpha * W.out[P->off_Psi + i];
        }
        double ax = 0.0;
        for (int j = 0; j < nu; ++j)
            ax += W.A[(size_t)k * nu + j] * W.x0[j];
        W.r[k] = ax - rhs;
    }
    for (int a = 0; a < m; ++a)
        for (int b = 0; b <= a; ++b) {
            double s1 = 0.0, s2 = 0.0;
            for (int j = 0; j < nu; ++j) {
                s1 += W.A[(size_t)a * nu + j] * W.Yt[(size_t)b * nu + j];
                s2 += W.A[(size_t)b * nu + j] * W.Yt[(size_t)a * nu + j];
            }
            W.G[(size_t)a * m + b] = W.G[(size_t)b * m + a] = 0.5 * (s1 + s2);
        }
    if (sym_eigen(m, W.G, W.V, W.ee, W.hh) != 0)
        return MBRT_MECH_FALLBACK;
    double gmax = 0.0;
    for (int k = 0; k < m; ++k)
        gmax = fmax(gmax, W.G[(size_t)k * m + k]);
    for (int i = 0; i < m; ++i)
        W.lam[i] = 0.0;
    for (int k = 0; k < m; ++k) {
        const double g = W.G[(size_t)k * m + k];
        if (!(g > S->pass_rank * gmax))
            continue;
        double c = 0.0;
        for (int i = 0; i < m; ++i)
            c += W.V[(size_t)i * m + k] * W.r[i];
        c /= g;
        for (int i = 0; i < m; ++i)
            W.lam[i] += c * W.V[(size_t)i * m + k];
    }
    for (int j = 0; j < nu; ++j) {
        double s = W.x0[j];
        for (int k = 0; k < m; ++k)
            s -= W.Yt[(size_t)k * nu + j] * W.lam[k];
        ud[j] = s;
    }
    if (coordinate_rate(P, t, q, u, dy) != 0)
        return MBRT_MECH_FALLBACK;
    return finite_all(nq + nu, dy) ? MBRT_MECH_OK : MBRT_MECH_FALLBACK;
}

static int pass_rhs(void *c, double t, const double *y, double *dy)
{
    mbrt_pass *S = (mbrt_pass *)c;
    const int nq = S->mech->nq, n = nq + S->mech->nu;
    if (S->fun(y, y + nq, t, S->d, S->h, S->p, S->w, dy) == 0 && finite_all(n, dy))
        return 0;
    S->nrange++;
    return mbrt_pass_rhs(S, t, y, dy) == MBRT_MECH_OK ? 0 : 1;
}

/* log det(C_k C_k^T) at (t, q, u); PASS_LOGDET_SINGULAR where its Cholesky
 * fails (the kept rows dependent to rounding); 1 when the evaluation fails. */
static int logdet_rows(const mbrt_pass *S, double t, const double *q, const double *u, double *ld)
{
    const mbrt_mech *P = S->mech;
    const int nu = P->nu, r = P->nrows;
    pass_work W = layout(S);
    if (P->eval(q, u, t, P->d, P->h, P->p, P->w, W.out) != 0 || !finite_all(P->n_out, W.out))
        return 1;
    for (int a = 0; a < r; ++a)
        for (int b = 0; b <= a; ++b) {
            const double *ca = arow(P, W.out, a), *cb = arow(P, W.out, b);
            double s = 0.0;
            for (int j = 0; j < nu; ++j)
                s += ca[j] * cb[j];
            W.Gk[(size_t)a * r + b] = W.Gk[(size_t)b * r + a] = s;
        }
    if (mbrt_chol_factor(r, W.Gk) != 0) {
        *ld = PASS_LOGDET_SINGULAR;
        return 0;
    }
    double s = 0.0;
    for (int a = 0; a < r; ++a)
        s += log(W.Gk[(size_t)a * r + a]);
    *ld = 2.0 * s;
    return 0;
}

/* d/dt log det(C_k C_k^T) at (t, y) by a central difference along dq/dt, into *rate (1/s). */
static int log_rate(mbrt_pass *S, double t, const double *y, double *rate)
{
    const mbrt_mech *P = S->mech;
    const int nq = P->nq;
    const double *q = y, *u = y + nq;
    pass_work W = layout(S);
    S->nevents++;
    if (P->nrows == 0) {
        *rate = 1.0;
        return 0;
    }
    if (coordinate_rate(P, t, q, u, W.qd) != 0)
        return 1;
    double lp, lm;
    for (int i = 0; i < nq; ++i)
        W.qs[i] = q[i] + S->delta * W.qd[i];
    if (logdet_rows(S, t + S->delta, W.qs, u, &lp) != 0)
        return 1;
    for (int i = 0; i < nq; ++i)
        W.qs[i] = q[i] - S->delta * W.qd[i];
    if (logdet_rows(S, t - S->delta, W.qs, u, &lm) != 0)
        return 1;
    *rate = (lp - lm) / (2.0 * S->delta);
    return 0;
}

static int pass_event(void *c, double t, const double *y, double *g)
{
    mbrt_pass *S = (mbrt_pass *)c;
    double rate;
    if (log_rate(S, t, y, &rate) != 0)
        return 1;
    if (t > S->t_seen) { /* a step's end (the location's evaluations lie inside the step) */
        S->t_seen = t;
        S->g_end = rate;
    } else if (t == S->t_from && isnan(S->g_start)) { /* a call's start */
        S->g_start = rate;
    }
    /* made linear through a pole (a singular position: 2 k / (t - t_s) for a rank drop k) as
     * through a plain zero, so Brent's interpolation converges at both */
    const double x = rate * PASS_POLE_SPAN, v = rate / (1.0 + x * x);
    g[0] = t <= S->t_min ? fabs(v) : v;
    return 0;
}

/* Whether the step from (t_from, y_from) to (t, y), whose ends' rates g0, g1 have one sign,
 * hides a minimum and a maximum of log det: the rate of the opposite sign at PASS_CHORD - 1
 * states on the chord between its ends (a step of 0.38 s held a flat position 13 ms after its
 * start and the next maximum before its end: no sign change at the ends; h |rate| was 116
 * there, ~0.1 on the steps away from flat positions, which are not looked at). */
static int hides_pair(mbrt_pass *S, double t, const double *y, double g0, double g1)
{
    const int n = S->mech->nq + S->mech->nu;
    /* only where log det moves by more than 1 over the step: a pole inside it (2 k / (t - t_s),
     * k >= 1) makes h |rate| > 2 at the end next to it */
    if (!(g0 * g1 > 0.0) || S->mech->nrows == 0 || !((t - S->t_from) * fmax(fabs(g0), fabs(g1)) > 1.0))
        return 0;
    pass_work W = layout(S);
    for (int j = 1; j < PASS_CHORD; ++j) {
        const double f = (double)j / PASS_CHORD;
        for (int i = 0; i < n; ++i)
            W.smp[i] = S->y_from[i] + f * (y[i] - S->y_from[i]);
        double rate;
        if (log_rate(S, S->t_from + f * (t - S->t_from), W.smp, &rate) != 0)
            return 0;
        if (rate * g0 < 0.0)
            return 1;
    }
    return 0;
}

static int pass_on_step(void *c, double t, double *y)
{
    mbrt_pass *S = (mbrt_pass *)c;
    const int n = S->mech->nq + S->mech->nu;
    pass_work W = layout(S);
    memcpy(S->y_from, S->y_last, sizeof(double) * (size_t)n); /* this step's start */
    S->t_from = S->t_last;
    S->h_last = t - S->t_last;
    S->t_last = t;
    const long nrange = S->nrange_step;
    S->nrange_step = S->nrange;
    if (S->nrange == nrange) { /* a step without range-space solves: where to go back to */
        memcpy(W.y_back, S->y_from, sizeof(double) * (size_t)n);
        S->t_back = S->t_from;
        S->h_back = S->h_last;
    }
    if (S->h_back > 0.0 && S->h_last < PASS_COLLAPSE * S->h_back && S->nrange > nrange &&
        (S->t_back != S->t_rolled || S->rolled_here < 2)) {
        S->collapse = 1; /* the steps collapse next to a singular position: the step before is taken again */
        return 1;
    }
    const double g0 = S->g_start;
    S->g_start = S->g_end;
    if (!isnan(g0) && (S->t_from != S->t_hidden || S->hidden_here < 6) && hides_pair(S, t, y, g0, S->g_end)) {
        S->hidden = 1; /* the step is taken again in halves */
        return 1;
    }
    if (S->project) {
        double norm = 0.0;
        if (mbrt_project(S->mech, t, y, S->proj_tol, S->proj_iter, S->proj_accept, &norm, S->mech_work) ==
            MBRT_MECH_OK)
            S->nproj++;
        else
            S->nskipped++; /* the rows losing rank at the step's end: the next step projects */
    }
    memcpy(S->y_last, y, sizeof(double) * (size_t)n);
    if (S->redo == 1) { /* the end of the step holding a minimum, taken again (projected) */
        memcpy(W.y_after, y, sizeof(double) * (size_t)n);
        S->t_after = t;
        S->redo = 2;
    }
    return t >= S->t_stop; /* the first step ending at or past the outputs: the call ends there */
}

static int pass_rhs_back(void *c, double s, const double *y, double *dy)
{
    mbrt_pass *S = (mbrt_pass *)c;
    const int rc = pass_rhs(c, -s, y, dy);
    for (int i = 0; i < S->mech->nq + S->mech->nu; ++i)
        dy[i] = -dy[i];
    return rc;
}

/* The outputs t_out[0..m) inside the step (t_before, t_after] that held a minimum at t_min
 * (next to a singular position, or a near miss), written again by integrations from the step's ends towards
 * the minimum (forwards from its start for those before it, backwards in time from its end
 * for those after it), not from the step's continuous extension, whose extra stages may land
 * where the multipliers are rough (an output 1 J off).  0, or the runtime's failing status.
 * At most S->cap outputs (the caller's stretch is shorter). */
static int redo_outputs(mbrt_pass *S, int order, const double *t_out, int m, double *y_out, double rtol,
                        const double *atol, long max_steps, double *work, mbrt_stats *total)
{
    const int n = S->mech->nq + S->mech->nu;
    pass_work W = layout(S);
    mbrt_stats st;
    int split = 0; /* outputs [0, split) before the minimum, [split, m) after it */
    while (split < m && t_out[split] <= S->t_min)
        ++split;
    for (int side = 0; side < 2; ++side) {
        const int lo = side == 0 ? 0 : split, cnt = side == 0 ? split : m - split;
        if (cnt == 0)
            continue;
        double *times = W.times; /* the times of this side, ascending in the integration's time */
        for (int i = 0; i < cnt; ++i)
            times[i] = side == 0 ? t_out[lo + i] : -t_out[m - 1 - i];
        const double ta = side == 0 ? S->t_before : -S->t_after, tb = times[cnt - 1];
        if (!(times[0] > ta))
            return MBRT_BAD_ARGUMENT;
        const mbrt_rhs_fn f = side == 0 ? pass_rhs : pass_rhs_back;
        const double *ya = side == 0 ? W.y_before : W.y_after;
        double *rows = y_out + (size_t)lo * (size_t)n;
        int nw = 0;
        /* first step: the whole way (within the step the main integration took at once) */
        const int rc = order == 8 ? mbrt_dop853(f, NULL, S, n, ta, ya, tb, rtol, atol, tb - ta, 0.0, max_steps, times,
                                                cnt, rows, &nw, work, &st)
                                  : mbrt_dopri5(f, NULL, S, n, ta, ya, tb, rtol, atol, tb - ta, 0.0, max_steps, times,
                                                cnt, rows, &nw, work, &st);
        total->nfev += st.nfev;
        if (rc != MBRT_OK || nw != cnt)
            return rc != MBRT_OK ? rc : MBRT_BAD_ARGUMENT;
        if (side == 1) /* written in descending time: put them back in order */
            for (int i = 0, j = cnt - 1; i < j; ++i, --j)
                for (int c = 0; c < n; ++c) {
                    const double x = rows[(size_t)i * n + c];
                    rows[(size_t)i * n + c] = rows[(size_t)j * n + c];
                    rows[(size_t)j * n + c] = x;
                }
        S->nredone += cnt;
    }
    return 0;
}

/* y at t on the cubic Hermite interpolant of (ta, ya, fa), (tb, yb, fb), into y. */
static void hermite(int n, double ta, double tb, const double *ya, const double *fa, const double *yb,
                    const double *fb, double t, double *y)
{
    const double h = tb - ta, s = (t - ta) / h, s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    for (int i = 0; i < n; ++i)
        y[i] = h00 * ya[i] + h10 * h * fa[i] + h01 * yb[i] + h11 * h * fb[i];
}

/* One side of the step (t_before, t_after] holding the minimum at t_min, integrated from its end
 * (forwards from t_before, backwards in time from t_after) to t (written to y), through
 * PASS_SAMPLES states on the way at which the event function must keep its sign (below zero
 * before the minimum, above after it): else S->split is set.  0, or the runtime's failing status. */
static int sample_side(mbrt_pass *S, int order, int after, double t, double rtol, const double *atol,
                       long max_steps, double *work, mbrt_stats *total, double *y)
{
    const int n = S->mech->nq + S->mech->nu;
    pass_work W = layout(S);
    const double t0 = after ? -S->t_after : S->t_before, t1 = after ? -t : t;
    double times[PASS_SAMPLES];
    for (int j = 0; j < PASS_SAMPLES; ++j)
        times[j] = j + 1 == PASS_SAMPLES ? t1 : t0 + (t1 - t0) * (j + 1) / PASS_SAMPLES;
    const mbrt_rhs_fn f = after ? pass_rhs_back : pass_rhs;
    const double *y0 = after ? W.y_after : W.y_before;
    mbrt_stats st;
    int nw = 0; /* first step: the whole way */
    const int rc = order == 8 ? mbrt_dop853(f, NULL, S, n, t0, y0, t1, rtol, atol, t1 - t0, 0.0, max_steps, times,
                                            PASS_SAMPLES, W.smp, &nw, work, &st)
                              : mbrt_dopri5(f, NULL, S, n, t0, y0, t1, rtol, atol, t1 - t0, 0.0, max_steps, times,
                                            PASS_SAMPLES, W.smp, &nw, work, &st);
    total->nfev += st.nfev;
    if (rc != MBRT_OK)
        return rc;
    for (int j = 0; j + 1 < PASS_SAMPLES; ++j) {
        double g;
        if (pass_event(S, after ? -times[j] : times[j], W.smp + (size_t)j * (size_t)n, &g) != 0)
            return MBRT_RHS_FAILED;
        if (after ? !(g > 0.0) : g > 0.0)
            S->split = 1;
    }
    memcpy(y, W.smp + (size_t)(PASS_SAMPLES - 1) * (size_t)n, sizeof(double) * (size_t)n);
    return 0;
}

/* The minimum just logged at t_min (inside the step (t_before, t_after], located on the step's
 * continuous extension) located again on the motion itself: the states at t_min -+ d from
 * integrations from the step's ends (sample_side: another sign change on the way sets
 * S->split), the root of the event function on the cubic through them and their rates
 * (Illinois false position to tol).  Left as it is where the root is not bracketed there.  0,
 * or the runtime's failing status. */
static int refine_minimum(mbrt_pass *S, int order, double rtol, const double *atol, long max_steps, double *work,
                          double tol, mbrt_stats *total)
{
    const int n = S->mech->nq + S->mech->nu;
    if (S->count == 0 || S->log_t[S->count - 1] != S->t_min)
        return 0;
    pass_work W = layout(S);
    double *ya = W.rf, *yb = ya + n, *fa = yb + n, *fb = fa + n, *ym = fb + n;
    const double te = S->t_min;
    const double d = fmin(0.02 * (S->t_after - S->t_before), 0.5 * fmin(te - S->t_before, S->t_after - te));
    if (!(d > 4.0 * tol))
        return 0;
    const double ta = te - d, tb = te + d;
    const double keep = S->t_min;
    S->t_min = -INFINITY; /* the event function's own values */
    int rc = sample_side(S, order, 0, ta, rtol, atol, max_steps, work, total, ya);
    if (rc == 0)
        rc = sample_side(S, order, 1, tb, rtol, atol, max_steps, work, total, yb);
    if (rc != 0 || S->split) {
        S->t_min = keep;
        return rc;
    }
    if (pass_rhs(S, ta, ya, fa) != 0 || pass_rhs(S, tb, yb, fb) != 0) {
        S->t_min = keep;
        return MBRT_RHS_FAILED;
    }
    double a = ta, b = tb, ga, gb, gm, tm = te;
    int side = 0, ok = pass_event(S, a, ya, &ga) == 0 && pass_event(S, b, yb, &gb) == 0 && ga < 0.0 && gb > 0.0;
    for (int it = 0; ok && it < 100 && b - a > tol; ++it) {
        tm = (a * gb - b * ga) / (gb - ga);
        if (!(tm > a && tm < b))
            tm = 0.5 * (a + b);
        hermite(n, ta, tb, ya, fa, yb, fb, tm, ym);
        if (pass_event(S, tm, ym, &gm) != 0) {
            ok = 0;
            break;
        }
        if (gm == 0.0) {
            a = b = tm;
            break;
        }
        if (gm < 0.0) {
            a = tm;
            ga = gm;
            if (side == -1)
                gb *= 0.5;
            side = -1;
        } else {
            b = tm;
            gb = gm;
            if (side == 1)
                ga *= 0.5;
            side = 1;
        }
    }
    S->t_min = keep;
    if (!ok)
        return 0;
    tm = 0.5 * (a + b);
    hermite(n, ta, tb, ya, fa, yb, fb, tm, ym);
    S->log_t[S->count - 1] = tm;
    memcpy(S->log_y + (size_t)(S->count - 1) * (size_t)n, ym, sizeof(double) * (size_t)n);
    S->nrefined++;
    return 0;
}

static int complete(const mbrt_pass *S, int order)
{
    if (S == NULL || S->fun == NULL || S->d == NULL || S->mech == NULL || S->mech->eval == NULL ||
        S->work == NULL || S->y_last == NULL || S->y_from == NULL || !(S->pass_rank > 0.0) || !(S->delta > 0.0) || S->cap < 0 ||
        (S->cap > 0 && (S->log_t == NULL || S->log_y == NULL)) || (order != 5 && order != 8))
        return 0;
    const mbrt_mech *P = S->mech;
    if (P->nrows < 0 || P->mn < 0 || P->nrows > P->mh || (P->nrows > 0 && P->rows == NULL))
        return 0;
    for (int k = 0; k < P->nrows; ++k)
        if (P->rows[k] < 0 || P->rows[k] >= P->mh)
            return 0;
    return !S->project || (S->mech_work != NULL && S->proj_iter > 0);
}

/* After a runtime call: the outputs of the step holding the minimum just logged (among the nw
 * written from t_out[0]) integrated again and the minimum located again (refine_minimum); a
 * failure leaves the continuous extension's, counted. */
static void redo_step(mbrt_pass *S, int order, const double *t_out, int nw, double *y_out, double rtol,
                      const double *atol, long max_steps, double *work, double tol, mbrt_stats *total)
{
    const int n = S->mech->nq + S->mech->nu;
    int m = 0;
    while (m < nw && t_out[m] <= S->t_before)
        ++m;
    int e = m;
    while (e < nw && t_out[e] < S->t_after) /* one at the step's end is its end */
        ++e;
    const long nrange = S->nrange; /* the steps' range-space solves only (a collapse shows there) */
    int rc = e - m > S->cap ? MBRT_BAD_ARGUMENT
           : redo_outputs(S, order, t_out + m, e - m, y_out + (size_t)m * (size_t)n, rtol, atol, max_steps, work,
                          total);
    if (rc == 0)
        rc = refine_minimum(S, order, rtol, atol, max_steps, work, tol, total);
    S->nrange = nrange;
    if (rc != 0)
        S->nredo_failed++;
}

/* After a collapse: back to the start of the last step without range-space solves (t_back),
 * the minima logged after it dropped, the step to take there in *h (the singular position
 * mid-step, or at the second time the step ending halfway to the collapse).  Returns the index
 * of the first output after t_back. */
static int go_back(mbrt_pass *S, const pass_work *W, const double *t_out, int n_out, double t_min0, double *t,
                   double *h)
{
    int k = 0;
    while (k < n_out && t_out[k] <= S->t_back)
        ++k;
    while (S->count > 0 && S->log_t[S->count - 1] > S->t_back)
        S->count--;
    S->t_min = S->count > 0 ? S->log_t[S->count - 1] : t_min0;
    S->rolled_here = S->t_back == S->t_rolled ? S->rolled_here + 1 : 0;
    *h = (S->rolled_here == 0 ? 2.0 : 0.5) * (S->t_last - S->t_back);
    S->t_rolled = *t = S->t_back;
    memcpy(W->y_start, W->y_back, sizeof(double) * (size_t)(S->mech->nq + S->mech->nu));
    S->nrollbacks++;
    return k;
}

/* After a step found to hold more than one sign change of the event function: back to its
 * start (t_before), the minima logged after it dropped, the step to take there in *h a quarter
 * of it, and no later step longer (S->hcap).  Returns the index of the first output after it. */
static int split_back(mbrt_pass *S, const pass_work *W, const double *t_out, int n_out, double t_min0, double *t,
                      double *h)
{
    int k = 0;
    while (k < n_out && t_out[k] <= S->t_before)
        ++k;
    while (S->count > 0 && S->log_t[S->count - 1] > S->t_before)
        S->count--;
    S->t_min = S->count > 0 ? S->log_t[S->count - 1] : t_min0;
    S->hcap = *h = 0.25 * (S->t_after - S->t_before);
    *t = S->t_before;
    memcpy(W->y_start, W->y_before, sizeof(double) * (size_t)(S->mech->nq + S->mech->nu));
    S->split = 0;
    S->nsplits++;
    return k;
}

/* The runtime's events over the event function, location tolerance tol (s). */
static void arm(mbrt_events *ev, mbrt_pass *S, const pass_work *W, const int *direction, double tol)
{
    memset(ev, 0, sizeof *ev);
    ev->g = pass_event;
    ev->gctx = S;
    ev->n_ev = 1;
    ev->direction = direction;
    ev->tol = tol;
    ev->fresh = -1;
    ev->work = W->evwork;
    ev->y_event = W->y_event;
}

/* Counters and the first stretch's state at a call's start (t0, y0). */
static void begin(mbrt_pass *S, const pass_work *W, double t0, const double *y0, double t_stop)
{
    const int n = S->mech->nq + S->mech->nu;
    S->count = 0;
    S->nrange = S->nproj = S->nskipped = S->nevents = S->nretaken = 0;
    S->nrollbacks = S->nredone = S->nrefined = S->nredo_failed = S->nsplits = S->nhalved = 0;
    S->split = 0;
    S->h_last = 0.0;
    S->t_stop = t_stop;
    memcpy(W->y_start, y0, sizeof(double) * (size_t)n);
    S->redo = S->t_min > t0; /* the step across the last call's end, taken again, holds a minimum */
    S->t_before = t0;
    memcpy(W->y_before, y0, sizeof(double) * (size_t)n);
}

static int finish(mbrt_stats *total, int status, double t, const char *message)
{
    total->status = status;
    total->t = t;
    strcpy(total->message, message);
    return status;
}

int mbrt_pass_integrate(mbrt_pass *S, int order, double t0, const double *y0, double t_stop, double t_end,
                        double rtol, const double *atol, double h0, double hmax, long max_steps,
                        const double *t_out, int n_out, double *y_out, int *n_written, double *work,
                        mbrt_stats *stats)
{
    mbrt_stats local, st;
    mbrt_stats *total = stats ? stats : &local;
    memset(total, 0, sizeof *total);
    total->t = t0;
    if (n_written)
        *n_written = 0;
    if (!complete(S, order) || y0 == NULL || (n_out > 0 && (t_out == NULL || y_out == NULL)) ||
        !(t0 <= t_stop && t_stop <= t_end))
        return finish(total, MBRT_BAD_ARGUMENT, t0, "mbrt_pass_integrate: the description is incomplete (the "
                      "programs, work, pass_rank > 0, delta > 0, the log, order 5 or 8, t0 <= t_stop <= t_end).");
    const int n = S->mech->nq + S->mech->nu, direction = 1;
    pass_work W = layout(S);
    mbrt_events ev;
    /* located to a tenth of the event function's difference step: closer to a singular
     * position its values are rounding (the central difference straddles it) */
    arm(&ev, S, &W, &direction, fmax(fmin(1e-12, rtol / 1000.0) * fmax(1.0, fabs(t_end)), 0.1 * S->delta));
    begin(S, &W, t0, y0, t_stop);
    double t = t0, h = h0;
    const double t_min0 = S->t_min;
    int k = 0;
    for (long round = 0;; ++round) {
        if (round > 4L * S->cap + 100) { /* minima and collapses are bounded: a loop gone wrong */
            finish(total, MBRT_MAX_STEPS, S->t_last, "mbrt_pass_integrate: too many steps taken again.");
            break;
        }
        S->t_last = S->t_seen = S->t_from = t;
        memcpy(S->y_last, W.y_start, sizeof(double) * (size_t)n);
        memcpy(S->y_from, W.y_start, sizeof(double) * (size_t)n);
        S->nrange_step = S->nrange;
        S->collapse = S->hidden = 0;
        S->g_start = NAN;
        int nw = 0;
        memset(&st, 0, sizeof st);
        const double hm = S->hcap > 0.0 ? (hmax > 0.0 ? fmin(hmax, S->hcap) : S->hcap) : hmax;
        const int rc = order == 8
            ? mbrt_dop853_events(pass_rhs, pass_on_step, S, n, t, W.y_start, t_end, rtol, atol, h, hm, max_steps,
                                 t_out + k, n_out - k, y_out + (size_t)k * (size_t)n, &nw, work, &st, 0, &ev)
            : mbrt_dopri5_events(pass_rhs, pass_on_step, S, n, t, W.y_start, t_end, rtol, atol, h, hm, max_steps,
                                 t_out + k, n_out - k, y_out + (size_t)k * (size_t)n, &nw, work, &st, 0, &ev);
        mbrt_add_counts(total, &st);
        if (S->redo == 2)
            redo_step(S, order, t_out + k, nw, y_out + (size_t)k * (size_t)n, rtol, atol, max_steps, work, ev.tol,
                      total);
        S->redo = 0;
        if (S->split) {
            k = split_back(S, &W, t_out, n_out, t_min0, &t, &h);
            continue;
        }
        if (rc == MBRT_STOPPED && S->hidden) { /* the step from t_from again, in halves */
            S->hidden_here = S->t_from == S->t_hidden ? S->hidden_here + 1 : 0;
            S->t_hidden = t = S->t_from;
            h = 0.5 * (S->t_last - S->t_from);
            for (k = 0; k < n_out && t_out[k] <= t; ++k)
                ;
            memcpy(W.y_start, S->y_from, sizeof(double) * (size_t)n);
            S->nhalved++;
            continue;
        }
        if (rc == MBRT_STOPPED && S->collapse) {
            k = go_back(S, &W, t_out, n_out, t_min0, &t, &h);
            continue;
        }
        if (rc == MBRT_STOPPED && S->t_last >= t_stop) { /* past the outputs: the step's start goes on */
            k += nw;
            finish(total, MBRT_OK, S->t_last, "mbrt_pass_integrate: reached the last output.");
            break;
        }
        if (rc != MBRT_EVENT) {
            k += nw;
            break;
        }
        /* a minimum at t_event in the step (t_last, t_seen]: logged, then that step again */
        while (nw > 0 && t_out[k + nw - 1] > S->t_last) /* written again by the step taken again */
            --nw;
        k += nw;
        if (S->count >= S->cap || !(ev.t_event > S->t_min) || !(S->t_seen > S->t_last)) {
            finish(total, MBRT_STOPPED, S->t_last, S->count >= S->cap ? "mbrt_pass_integrate: the log of minima "
                   "is full." : "mbrt_pass_integrate: a minimum was located twice.");
            break;
        }
        S->log_t[S->count] = S->t_min = ev.t_event;
        memcpy(S->log_y + (size_t)S->count * (size_t)n, ev.y_event, sizeof(double) * (size_t)n);
        S->count++;
        h = S->t_seen - S->t_last;
        t = S->t_before = S->t_last;
        memcpy(W.y_start, S->y_last, sizeof(double) * (size_t)n);
        memcpy(W.y_before, S->y_last, sizeof(double) * (size_t)n);
        S->redo = 1;
        S->nretaken++;
    }
    if (n_written)
        *n_written = k;
    return total->status;
}
