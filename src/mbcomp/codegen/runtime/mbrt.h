/*
 * mbrt.h -- mbcomp's small C runtime (C99, libc + libm only).
 *
 * This is the numerical kernel that an exported FMU and mbcomp's compiled
 * engine embed.  It must stay free of Python and of any other dependency:
 *
 *   - no global or static mutable state (every routine is reentrant),
 *   - no dynamic allocation: the caller passes all scratch memory; the
 *     integrators tell how much they need with mbrt_*_work_size(),
 *   - row-major double arrays throughout.
 *
 * Contents
 *   1. Dense linear algebra (mbrt_linalg.c): LU with partial pivoting and
 *      Cholesky, both in place.
 *   2. Explicit adaptive Runge-Kutta integrators with dense output
 *      (mbrt_rk.c driver, mbrt_dopri5.c and mbrt_dop853.c tableaux):
 *      DOPRI5 (Dormand-Prince 5(4), 4th-order continuous extension) and
 *      DOP853 (Dormand-Prince 8(5,3), 7th-order continuous extension),
 *      with the step-size control of E. Hairer's codes dopri5.f/dop853.f.
 *   3. Constrained mechanics over a model's evaluation program (mbrt_mech.c):
 *      the D'Alembert right-hand side (coordinate partitioning, N^T M N) and
 *      the projection of [q, u] onto the constraint manifold.
 *
 * References
 *   E. Hairer, S. P. Norsett, G. Wanner, "Solving Ordinary Differential
 *   Equations I: Nonstiff Problems", 2nd ed., Springer 1993, Sec. II.4
 *   (step-size control, starting step), II.5 (DOPRI5), II.6 (dense output),
 *   II.10 (DOP853).  J. R. Dormand, P. J. Prince, "A family of embedded
 *   Runge-Kutta formulae", J. Comput. Appl. Math. 6 (1980) 19-26.
 */
#ifndef MBRT_H
#define MBRT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------ */
/* Dense linear algebra (row-major, in place)                          */
/* ------------------------------------------------------------------ */

/* LU factorisation P A = L U with partial (row) pivoting.  On return A holds
 * U in its upper triangle and the unit-lower L (without its diagonal) below;
 * piv[k] is the row swapped with row k at step k.  Returns 0, or k+1 if the
 * pivot of column k is exactly zero or not finite (the factorisation stops
 * there).  Returns -1 if n < 0 or a pointer is NULL. */
int mbrt_lu_factor(int n, double *A, int *piv);

/* Solves A x = b with the output of mbrt_lu_factor; b is overwritten by x. */
void mbrt_lu_solve(int n, const double *LU, const int *piv, double *b);

/* Cholesky factorisation A = L L^T of a symmetric positive definite matrix.
 * Only the lower triangle of A is read; on return it holds L and the strict
 * upper triangle is set to zero.  Returns 0, or k+1 at the first pivot k
 * that is not positive (or not finite); -1 if n < 0 or A is NULL. */
int mbrt_chol_factor(int n, double *A);

/* Solves L L^T x = b with the output of mbrt_chol_factor; b is overwritten. */
void mbrt_chol_solve(int n, const double *L, double *b);

/* ------------------------------------------------------------------ */
/* Explicit adaptive Runge-Kutta integration with dense output         */
/* ------------------------------------------------------------------ */

/* Right-hand side y' = f(t, y): writes dydt[0..n-1].  Returns 0 if all went
 * well; any nonzero value stops the integration with status 1 and that code
 * quoted in stats->message. */
typedef int (*mbrt_rhs_fn)(void *ctx, double t, const double *y, double *dydt);

/* Called after every accepted step with the new state.  It may modify y in
 * place (e.g. a projection onto a constraint manifold); the integrator then
 * re-evaluates the right-hand side there.  0 = go on, nonzero = stop with
 * status 5. */
typedef int (*mbrt_step_fn)(void *ctx, double t, double *y);

typedef struct {
    long nfev;      /* right-hand side evaluations                        */
    long nstep;     /* attempted steps (naccept + nreject)                */
    long naccept;   /* accepted steps                                     */
    long nreject;   /* rejected steps                                     */
    int status;     /* MBRT_* status below (also the return value)        */
    double t;       /* time of the last accepted state (t_end on success);
                       every t_out <= t has been written                  */
    char message[200]; /* one sentence saying what happened              */
} mbrt_stats;

enum {
    MBRT_OK = 0,              /* reached t_end                              */
    MBRT_RHS_FAILED = 1,      /* rhs returned nonzero (code in message)     */
    MBRT_STEP_TOO_SMALL = 2,  /* step size fell below the round-off limit   */
    MBRT_MAX_STEPS = 3,       /* max_steps attempted steps were not enough  */
    MBRT_NONFINITE = 4,       /* state or derivative became NaN/Inf         */
    MBRT_STOPPED = 5,         /* step callback returned nonzero             */
    MBRT_BAD_ARGUMENT = 6,    /* invalid input                              */
    MBRT_STIFF = 7,           /* the stiffness test fired (the *_events calls) */
    MBRT_EVENT = 8            /* an event was located (the *_events calls)  */
};

/* Number of doubles the work buffer of mbrt_dopri5 must hold (0 if n <= 0). */
size_t mbrt_dopri5_work_size(int n);

/* Integrates y' = f(t, y), y(t0) = y0 from t0 to t_end (t_end >= t0).
 *
 *   rtol       relative tolerance (scalar, >= 100*DBL_EPSILON)
 *   atol       n absolute tolerances (>= 0), same units as y
 *   h0         initial step; 0 = automatic (Hairer's starting-step guess)
 *   hmax       largest step; 0 = |t_end - t0|
 *   max_steps  largest number of attempted steps; 0 = 100000
 *   t_out      n_out strictly increasing times in [t0, t_end] at which y is
 *              wanted (may be NULL if n_out == 0); values come from the
 *              continuous extension of the step containing them, evaluated
 *              before on_step may modify the state
 *   y_out      n_out*n doubles, row-major: y_out[i*n + j] = y_j(t_out[i])
 *   n_written  if not NULL, receives the number of rows of y_out written
 *              (valid even on failure)
 *   work       mbrt_dopri5_work_size(n) doubles of scratch
 *   stats      if not NULL, receives counters, status, final t, message
 *   on_step    may be NULL
 *
 * Returns the status (MBRT_OK ... MBRT_BAD_ARGUMENT).  The tolerance test is
 * Hairer's: sqrt(mean_i (err_i / sc_i)^2) <= 1 with
 * sc_i = atol_i + rtol * max(|y_i(t)|, |y_i(t+h)|). */
int mbrt_dopri5(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n,
                double t0, const double *y0, double t_end,
                double rtol, const double *atol, double h0, double hmax,
                long max_steps, const double *t_out, int n_out,
                double *y_out, int *n_written,
                double *work, mbrt_stats *stats);

/* Number of doubles the work buffer of mbrt_dop853 must hold (0 if n <= 0). */
size_t mbrt_dop853_work_size(int n);

/* As mbrt_dopri5 with the 8th-order DOP853 pair (error estimate combining the
 * 5th- and 3rd-order embedded solutions, 7th-order dense output costing three
 * extra rhs evaluations in each step that contains output times). */
int mbrt_dop853(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n,
                double t0, const double *y0, double t_end,
                double rtol, const double *atol, double h0, double hmax,
                long max_steps, const double *t_out, int n_out,
                double *y_out, int *n_written,
                double *work, mbrt_stats *stats);

/* ------------------------------------------------------------------ */
/* Events located on the dense output (mbrt_events.c)                  */
/* ------------------------------------------------------------------ */

/* Event functions: writes the n_ev values g[0..n_ev-1] at (t, y).  Returns 0,
 * or nonzero to stop the integration (status MBRT_RHS_FAILED). */
typedef int (*mbrt_event_fn)(void *ectx, double t, const double *y, double *g);

/* What the *_events integrators watch.  After every accepted step each event
 * function is evaluated at the step's end; a sign change in its direction
 * (-1: from >= 0 to < 0, +1: from <= 0 to > 0, 0: either) is located on the
 * step's continuous extension by Brent's method to tol (s).  The event `fresh`
 * (acted on at t0: its value starts at zero) is found in the first step only
 * when it is back on the far side of zero at the step's end: the root between
 * its extreme on the leaving side (golden section) and the step's end, or t0
 * when it never left.  The earliest event of the step ends the integration
 * there with status MBRT_EVENT: the outputs at t_out <= t_event are written
 * (from the continuous extension), `which`, `t_event` and `y_event` (n) are
 * set, stats->t = t_event; the step callback is not called for that step. */
typedef struct {
    mbrt_event_fn g;        /* the event values                                   */
    void *gctx;             /* g's context                                         */
    int n_ev;               /* number of event functions (>= 1)                   */
    const int *direction;   /* n_ev directions: -1, 0, +1                          */
    double tol;             /* location tolerance (s), > 0                        */
    int fresh;              /* the event acted on at t0, or -1                     */
    double *work;           /* mbrt_events_work_size(n, n_ev) doubles              */
    double *y_event;        /* n doubles: the state at the event (written)         */
    int which;              /* the event located, -1 if none (written)             */
    double t_event;         /* its time (written)                                  */
    long nevals;            /* event-function evaluations (written)                */
} mbrt_events;

/* Doubles of work an mbrt_events needs for n equations and n_ev events. */
size_t mbrt_events_work_size(int n, int n_ev);

/* Event functions affine in one state entry each: g[k] = sign[k] (y[index[k]]
 * - at[k]) (a joint's own coordinate or speed against a limit).  Its context
 * is an mbrt_linear_events. */
typedef struct {
    int n_ev;
    const int *index;       /* entries of y, 0 <= index[k] < n                     */
    const double *sign, *at;
} mbrt_linear_events;

int mbrt_linear_event_values(void *ectx, double t, const double *y, double *g);

/* As mbrt_dop853 / mbrt_dopri5, with two options.
 *
 * Hairer's stiffness test (stiff_steps > 0): after every accepted step
 * hlamb = |h| |f(t+h, y1) - f(t+h, Y)| / |y1 - Y| (Y the last stage's argument
 * at t+h, so hlamb estimates |h lambda| of the largest eigenvalue of df/dy met)
 * is compared with the method's stability limit (6.1 for DOP853, 3.25 for
 * DOPRI5); when it was above it for stiff_steps accepted steps with fewer than
 * 6 below it in between, the integration stops at that step with status
 * MBRT_STIFF (state and outputs as for MBRT_STOPPED).  stiff_steps <= 0: no test.
 *
 * Events (ev not NULL): watched as described above (MBRT_EVENT). */
int mbrt_dop853_events(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n,
                       double t0, const double *y0, double t_end,
                       double rtol, const double *atol, double h0, double hmax,
                       long max_steps, const double *t_out, int n_out,
                       double *y_out, int *n_written,
                       double *work, mbrt_stats *stats, int stiff_steps, mbrt_events *ev);
int mbrt_dopri5_events(mbrt_rhs_fn f, mbrt_step_fn on_step, void *ctx, int n,
                       double t0, const double *y0, double t_end,
                       double rtol, const double *atol, double h0, double hmax,
                       long max_steps, const double *t_out, int n_out,
                       double *y_out, int *n_written,
                       double *work, mbrt_stats *stats, int stiff_steps, mbrt_events *ev);

/* ------------------------------------------------------------------ */
/* Constrained mechanics over an evaluation program (mbrt_mech.c)      */
/* ------------------------------------------------------------------ */

/* A generated program: reads q, u, t and its inputs d (drive values), h
 * (hoisted parameter values), p (parameters), uses w as work and writes out.
 * Returns 0, or nonzero when a guard of the program failed (a branch other
 * than the traced one, a pivot that must be positive). */
typedef int (*mbrt_prog_fn)(const double *q, const double *u, double t, const double *d,
                            const double *h, const double *p, double *w, double *out);

/* A model's evaluation program and the layout of its flat output: the mass
 * matrix M (nu x nu), forces f (nu), then for the mh holonomic (cut-joint)
 * rows Phi, dPhi/dt (mh each), their Jacobian C (mh x nu) and bias c_b (mh),
 * then for the mn nonholonomic rows B (mn x nu), B_b and Psi = B u - b (mn
 * each), all row-major at the given offsets (in doubles).  Only the holonomic
 * rows rows[0..nrows-1] are used (the independent ones); the velocity rows
 * are A = [C[rows]; B] (m = nrows + mn of them). */
typedef struct {
    mbrt_prog_fn eval;   /* the evaluation (n_out doubles)                       */
    mbrt_prog_fn qrate;  /* dq/dt (nq doubles); NULL: dq/dt = u (then nq == nu)  */
    const double *d, *h, *p; /* the programs' inputs                            */
    double *w;           /* their work array                                     */
    int nq, nu;          /* coordinates, speeds                                  */
    int n_out;           /* doubles of eval's output                             */
    int mh, mn;          /* holonomic rows in the output, nonholonomic rows      */
    int nrows;           /* holonomic rows used (<= mh)                          */
    const int *rows;     /* their indices in 0..mh-1                             */
    int off_M, off_f, off_Phi, off_Phid, off_C, off_cb, off_B, off_Bb, off_Psi;
    /* How coordinates move along the speeds (for mbrt_project): nseg segments of 4
     * ints (kind, q0, u0, n): MBRT_SEG_ADD moves q[q0..q0+n) by du[u0..u0+n),
     * MBRT_SEG_QUAT (n = 1) turns the unit quaternion q[q0..q0+4) (w, x, y, z) by the
     * rotation vector du[u0..u0+3) about its own axes.  nseg = 0: q += du (nq == nu). */
    int nseg;
    const int *seg;
} mbrt_mech;

enum { MBRT_SEG_ADD = 0, MBRT_SEG_QUAT = 1 };

enum {
    MBRT_MECH_OK = 0,
    MBRT_MECH_FALLBACK = 1,        /* a guard failed or a value was not finite:
                                      evaluate on the reference path instead  */
    MBRT_MECH_SINGULAR = 2,        /* a dependent block or the rows lost rank  */
    MBRT_MECH_MASS_SINGULAR = 3,   /* the projected mass matrix is not
                                      positive definite                        */
    MBRT_MECH_NO_CONVERGENCE = 4,  /* the position Newton did not converge     */
    MBRT_MECH_BAD_ARGUMENT = -1
};

/* Doubles of scratch mbrt_dalembert_rhs and mbrt_project need (0 if P is
 * NULL); mbrt_dalembert_rhs also needs nu + nd ints (iwork). */
size_t mbrt_mech_work_size(const mbrt_mech *P);

/* The right-hand side of the D'Alembert form dy/dt for y = [q, v], v the
 * independent speeds u[ind] (ni = nu - nd of them), partition dep/ind (nd and
 * ni indices forming a permutation of 0..nu-1, nd = m):
 *   1. u[ind] = v, u[dep] = 0; evaluate; u[dep] -= A_d^-1 [dPhi/dt; Psi]
 *      (A_d = A[:, dep], LU with partial pivoting): A u = 0 exactly;
 *   2. evaluate at (q, u); N_d = -A_d^-1 A[:, ind], w_d = -A_d^-1 [c_b; B_b];
 *   3. Mr = N^T M N, fr = N^T (f - M w) (N[ind] = I), Cholesky: dv/dt.
 * Writes dy = [dq/dt(q, u), dv/dt] (nq + ni), *growth = max |N_d| (0 when
 * ni = 0) and *cond = the 2-norm condition number of A_d (one-sided Jacobi
 * SVD; 1 when nd <= 1): the figures the caller judges the partition by.
 * Open trees (nd = 0) evaluate once and solve M du/dt = f.  Returns
 * MBRT_MECH_OK, _FALLBACK, _SINGULAR (A_d has an exactly zero pivot),
 * _MASS_SINGULAR or _BAD_ARGUMENT. */
int mbrt_dalembert_rhs(const mbrt_mech *P, double t, const double *y, const int *dep, const int *ind,
                       int nd, double *dy, double *growth, double *cond, double *work, int *iwork);

/* Moves y = [q, u] onto the constraint manifold in place: quaternions
 * normalized, then Gauss-Newton with the speed-space steps
 * du = -C^T (C C^T)^-1 Phi on the rows used (q moved by du through the
 * coordinate map) until |Phi| <= tol or max_iter steps, accepted if
 * |Phi| <= accept at the end (*norm receives |Phi|); then
 * u -= A^T (A A^T)^-1 [dPhi/dt; Psi] at the final q.  y is written only on MBRT_MECH_OK; otherwise
 * _FALLBACK, _SINGULAR (rows dependent: C C^T or A A^T has a relative pivot
 * below 1e-14), _NO_CONVERGENCE or _BAD_ARGUMENT. */
int mbrt_project(const mbrt_mech *P, double t, double *y, double tol, int max_iter, double accept,
                 double *norm, double *work);

/* mbrt_project with the positions' steps in the speed directions k with pfree[k] != 0 only and
 * the speeds' correction in those with vfree[k] != 0 only (minimum norm in those directions; the
 * others keep their values: fixed start values).  NULL: every direction (mbrt_project, the same
 * arithmetic).  Fixed directions that leave the rows no solution give _SINGULAR. */
int mbrt_project_free(const mbrt_mech *P, double t, double *y, const unsigned char *pfree,
                      const unsigned char *vfree, double tol, int max_iter, double accept, double *norm,
                      double *work);

/* q (nq) moved by sign * du (nu) through the coordinate map of nseg segments seg (mbrt_mech's:
 * MBRT_SEG_ADD adds, MBRT_SEG_QUAT turns the quaternion by the rotation vector and normalizes it;
 * nseg = 0: q += sign du, nq == nu), as mbrt_project moves its positions; du = NULL normalizes the
 * quaternions only.  MBRT_MECH_OK, or _BAD_ARGUMENT (no q, a map not covering nq and nu) with q
 * untouched. */
int mbrt_increment(int nq, int nu, int nseg, const int *seg, double *q, const double *du, double sign);

/* ------------------------------------------------------------------ */
/* Impacts acted on inside the C loop (mbrt_events.c; helper-30's block) */
/* ------------------------------------------------------------------ */

/* One stretch of a run by a *_events integrator (the glue's mbcomp_integrate
 * has this signature; ctx carries the rhs, the step callback and the
 * mbrt_events). */
typedef int (*mbrt_stretch_fn)(int order, void *ctx, double t0, const double *y0, double t_end, double rtol,
                               const double *atol, double h0, double hmax, long max_steps, const double *t_out,
                               int n_out, double *y_out, int *n_written, double *work, mbrt_stats *stats);

/* The impacts a stretch loop acts on itself: event k of the watched
 * mbrt_events is an impact closing the row sign[k] u[iu[k]] >= 0 of a system
 * with no constraint rows (P: its evaluation program; only M and f are read),
 * Newton's restitution e[k] in [0, 1]:
 *   du = -(1 + e) (c u) M^-1 c^T / (c M^-1 c^T),  c = sign e_iu.
 * It is acted on only when it is plainly a rebound: approaching (c u < 0),
 * e > 0, the rebound c u+ rising more than twice `rest` (m or rad) against
 * the acceleration c M^-1 f(q, u+) pressing into the row (u+^2 > 4 rest |acc|),
 * the component's impacts not chattering (fewer than `chatter` successive
 * shrinking intervals, none within burst max(1, |t|) s of the one before),
 * room left in the log, an output time left after it; otherwise the loop
 * ends at the event (MBRT_EVENT) and the caller decides.  iu[k] < 0: event k
 * is never acted on here. */
typedef struct {
    int n_ev;               /* the watched events' number                         */
    const int *iu;          /* n_ev speed entries of the rows (0..nu-1), or -1    */
    const double *sign;     /* n_ev signs (+1, -1)                                */
    const double *e;        /* n_ev restitution coefficients in [0, 1]            */
    const int *comp;        /* n_ev components (0..n_comp-1): chattering per component */
    int n_comp;
    double *last;           /* n_comp: time of the last impact (-INFINITY: none); in/out */
    double *gap;            /* n_comp: the interval before it (< 0: none); in/out */
    int *shrinks;           /* n_comp: successive shrinking intervals; in/out     */
    int chatter;            /* shrinking intervals that make chattering (>= 1)    */
    double burst;           /* s per max(1, |t|): closer impacts are the caller's */
    double rest;            /* the resting height (m or rad), >= 0                */
    const mbrt_mech *P;     /* the evaluation program (nrows = mn = 0, nq = nu)   */
    double *work;           /* mbrt_impacts_work_size(P) doubles                   */
    int cap;                /* log entries at most                                 */
    int count;              /* log entries written                                 */
    double *log_t;          /* cap: the impacts' times (s)                         */
    int *log_which;         /* cap: their events                                   */
    double *log_y;          /* cap x 2 n: [q, u-] and [q, u+] of each              */
    double *log_loss;       /* cap: kinetic energy lost (J)                        */
} mbrt_impacts;

/* Doubles of work an mbrt_impacts needs (0 if P is NULL). */
size_t mbrt_impacts_work_size(const mbrt_mech *P);

/* How a run is cut into stretches (one call of the stretch function each), as
 * the stepper calling mbrt_impacts_integrate cuts them. */
typedef struct {
    int chunk, chunk_max;   /* a segment's k-th stretch: min(chunk_max, chunk 2^k) output times */
    int count;              /* the current segment's stretches so far (in and out)            */
    int max_stretches;      /* stretches ending without an event per call at most (>= 1)      */
    double tol_scale;       /* events located to tol_scale max(1, |t_end|) s (> 0)            */
    double h_restart;       /* the first step after an impact (0: guessed, >= 0)              */
    const double *h_last;   /* where the stretch function leaves its last accepted step (a
                               stretch goes on from it); NULL: one stretch without an event   */
    double t_end;           /* the last stretch's end (written)                               */
} mbrt_stretches;

/* A run's stretches with the impacts of I acted on in between: from (t0, y0)
 * (ev->fresh as armed, first step h0) each stretch integrates over the next
 * R's size of output times, its events located to tol_scale max(1, |t_end|)
 * s; the next stretch goes on from its end (first step *h_last); at an impact
 * acted on (I, above) a new segment starts at the event with the speeds after
 * it, event `which` fresh, first step h_restart, its stretch count 0 -- as a
 * new stepper would.  The loop ends after max_stretches stretches ending
 * without an event, at the last output, at an event not acted on
 * (MBRT_EVENT, ev's which/t_event/y_event set) or at another status of the
 * stretch function.  t_out: every output time left (n_out, increasing,
 * > t0); y_out (n_out x n) and *n_written count from t_out[0] over all
 * stretches; stats sums the counters (status, time and message are the last
 * stretch's); y_start: n doubles of scratch.  Returns the status;
 * MBRT_BAD_ARGUMENT for an incomplete description. */
int mbrt_impacts_integrate(mbrt_stretch_fn integrate, int order, void *ctx, mbrt_events *ev, mbrt_impacts *I,
                           mbrt_stretches *R, int n, double t0, const double *y0, const double *t_out, int n_out,
                           double rtol, const double *atol, double h0, double hmax, long max_steps, double *y_out,
                           int *n_written, double *work, mbrt_stats *stats, double *y_start);

/* The multiplier forms as semi-explicit DAEs E dy/dt = F(t, y) (mbcomp's
 * formulations/dae.py), y = [q, u, a, lam] with lam the m = nrows + mn
 * multipliers (GGL: and eta, nrows more):
 *   INDEX3  F = [dq/dt(q, u), a, f - M a - A^T lam, -Phi[rows], -Psi]
 *   GGL     F = [dq/dt(q, u - C^T eta), a, f - M a - A^T lam, -[dPhi/dt; Psi], -Phi]
 *   INDEX1  F = [dq/dt(q, u), a, f - M a - A^T lam, -(A a + bias)],
 *           bias = [c_b; B_b] (+ [2 alpha dPhi/dt + beta^2 Phi; alpha Psi] when
 *           gains = {alpha, beta} is not NULL). */
enum { MBRT_DAE_INDEX1 = 1, MBRT_DAE_GGL = 2, MBRT_DAE_INDEX3 = 3 };

/* The size n of the form's y (-1 for an unknown form). */
int mbrt_dae_size(const mbrt_mech *P, int form);

/* Doubles of scratch mbrt_dae_fun needs. */
size_t mbrt_dae_work_size(const mbrt_mech *P, int form);

/* F(t, y) into F (n), and when J is not NULL also dF/dy (n x n, row-major):
 * forward differences h = 1.5e-8 max(1, |y_i|) over the q and u columns (and
 * eta's), the a and lam columns exactly from M and A at (q, u).  *nfev (may be
 * NULL) receives the residual evaluations made.  Returns MBRT_MECH_OK,
 * _FALLBACK (a guard failed or a value was not finite) or _BAD_ARGUMENT. */
int mbrt_dae_fun(const mbrt_mech *P, int form, double t, const double *y, const double *gains, double *F,
                 double *J, int *nfev, double *work);

/* 2-norm condition number of the n x n row-major A by one-sided Jacobi (S:
 * n*n scratch); INFINITY when A is singular. */
double mbrt_cond2(int n, const double *A, double *S);

/* ------------------------------------------------------------------ */
/* RADAU5 for stiff ODEs, the whole integration in one call            */
/* (mbrt_radau5.c; helper-28's block)                                   */
/* ------------------------------------------------------------------ */

/* d f / d y at (t, y) (fy = f(t, y)) into J (n x n, row-major).  Returns 0,
 * or nonzero when there is no exact Jacobian there: the integrator then
 * differences f (so does a non-finite entry). */
typedef int (*mbrt_jac_fn)(void *ctx, double t, const double *y, const double *fy, double *J);

/* A singular iteration matrix ended the integration; the integration paused
 * at t_pause (mbrt_radau5). */
enum { MBRT_RADAU5_SINGULAR = 20, MBRT_RADAU5_PAUSED = 21 };

/* mbrt_radau5's counters of one call, besides mbrt_stats. */
typedef struct {
    long njev;          /* Jacobians formed (exact or differenced)                 */
    long ndiff;         /* of them by forward differences                          */
    long nlu;           /* LU factorizations (the real and the complex each count) */
    long nnewton;       /* Newton iterations                                       */
    long nfail_newton;  /* attempts failed by Newton                               */
    long nsingular;     /* singular iteration matrices met                         */
    double h_next;      /* the step the next step (or a resumed call) tries        */
} mbrt_radau5_info;

/* Doubles of work / ints of iwork mbrt_radau5 needs (0 if n <= 0). */
size_t mbrt_radau5_work_size(int n);
size_t mbrt_radau5_iwork_size(int n);

/* The method's coefficients, as mbcomp.solvers.radau derives them (45 doubles:
 * c (3), T (9), TI (9), LAM (9), gamma, mu (re, im), d (3), P (9)). */
void mbrt_radau5_coefficients(double *out);

/* Integrates the stiff ODE y' = f(t, y) from t0 to t_end >= t0 by Radau IIA
 * of order 5 (the algorithm of mbcomp.solvers.radau with E = I: simplified
 * Newton on the real and complex systems, equilibrated LU, the filtered error
 * estimate, Gustafsson's controller, RADAU5's Jacobian and LU reuse).
 *
 *   jac        exact Jacobian (NULL: forward differences of f)
 *   t_pause    in (t0, t_end): return after the first accepted step ending at
 *              or past it (MBRT_RADAU5_PAUSED; resumable: the steps of one call
 *              to t_end); otherwise none
 *   rtol       scalar (>= 100 DBL_EPSILON); atol n entries >= 0; the weights
 *              atol_i + rtol max(|y_i(t)|, |y_i(t+h)|)
 *   h0         first step (0: 0.01 |y|/|f|, at least 1e-6); hmax 0: none
 *   max_steps  attempted steps at most (0 = 100000): MBRT_MAX_STEPS, resumable
 *   t_out      n_out increasing times in [t0, t_end]: y_out (n_out x n) from
 *              each step's collocation polynomial; *n_written rows written
 *   work, iwork  mbrt_radau5_work_size(n) doubles, _iwork_size(n) ints
 *   resume     nonzero: continue the integration the work buffer holds when it
 *              ended at t0 (Jacobian, factors, predictor, controller kept: the
 *              steps of one call); a y0 other than its state is taken as moved
 *              there (f again).  Otherwise, or at another t0: a fresh start.
 *   y_last     if not NULL: the state at stats->t (n)
 *   stats      may be NULL; info (the counters of this call) must not be
 *
 * Returns MBRT_OK, MBRT_RHS_FAILED (f returned nonzero: stats->t, y_last the
 * last accepted state), MBRT_STEP_TOO_SMALL (the step size collapsed: the
 * message names the last cause), MBRT_MAX_STEPS, MBRT_NONFINITE (f not finite
 * at an accepted state or in a difference Jacobian), MBRT_RADAU5_SINGULAR,
 * MBRT_RADAU5_PAUSED, MBRT_BAD_ARGUMENT. */
int mbrt_radau5(mbrt_rhs_fn f, mbrt_jac_fn jac, void *ctx, int n, double t0, const double *y0, double t_end,
                double t_pause, double rtol, const double *atol, double h0, double hmax, long max_steps,
                const double *t_out, int n_out, double *y_out, int *n_written, double *work, int *iwork, int resume,
                double *y_last, mbrt_stats *stats, mbrt_radau5_info *info);

/* The collocation polynomial of the last accepted step of the integration
 * in work (mbrt_radau5's) at t, into y (n): exact at the step's ends,
 * extrapolated outside it. */
void mbrt_radau5_dense(const double *work, int n, double t, double *y);

/* A generated program's ODE y = [q, u], y' = fun(q, u, t) and its exact
 * Jacobian program (jac may be NULL), as mbrt_radau5's f and jac: pass
 * mbrt_prog_ode_rhs, mbrt_prog_ode_jac and a mbrt_prog_ode as ctx.  A failed
 * guard of fun stops the integration (MBRT_RHS_FAILED); of jac, differences. */
typedef struct {
    mbrt_prog_fn fun;
    const double *d, *h, *p;
    double *w;
    mbrt_prog_fn jac;
    const double *jd, *jh, *jp;
    double *jw;
    int nq;
} mbrt_prog_ode;

int mbrt_prog_ode_rhs(void *ctx, double t, const double *y, double *dy);
int mbrt_prog_ode_jac(void *ctx, double t, const double *y, const double *fy, double *J);

#ifdef __cplusplus
}
#endif

#endif /* MBRT_H */
