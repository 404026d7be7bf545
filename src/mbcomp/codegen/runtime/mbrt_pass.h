/*
 * mbrt_pass.h -- singular positions passed inside the C loop (mbrt_pass.c).
 *
 * A Lagrange (index-1) run with singular="pass" stepped by DOP853 or DOPRI5 in
 * one call: the right-hand side is the model's Lagrange program, and where its
 * guard fails (the rows losing rank near a singular position) the range-space
 * solve over the evaluation program, the eigen-directions of G = A M^-1 A^T
 * below pass_rank times its largest left out of the multipliers, so the steps
 * go straight through the singular position.  The positions where the kept
 * holonomic rows C_k come closest to losing rank -- the local minima of
 * log det(C_k C_k^T) along the motion, a singular position being a pole of it
 * -- are located on the integrator's own continuous extension as the roots of
 * the event function d/dt log det(C_k C_k^T) (a central difference along
 * dq/dt, rising through zero), logged with their states, and the integration
 * goes on: the stretch the runtime's events end at the root is taken again
 * from the start of the step that held it with that step's size, so the steps
 * are those of one uninterrupted integration (DOP853 and DOPRI5 are one-step
 * methods with a step-size controller that remembers nothing else here).
 * After every accepted step [q, u] is projected onto the constraint manifold
 * (mbrt_project) when asked; a projection that cannot be made (the rows losing
 * rank at the step's end) is left out for that step and counted.  Two things
 * next to a singular position are not left to chance:
 *   - a step starting milliseconds before one makes the steps collapse (rough
 *     multipliers at the stages, down to 1e-6 s): an accepted step with
 *     range-space solves shorter than PASS_COLLAPSE of the last step without
 *     any sends the integration back to that step's start, to take a step
 *     twice as long as from there to the collapse (then, once more, half as
 *     long) -- a step size the controller could have chosen, not a restart
 *     next to the singular position;
 *   - the outputs inside a step holding a minimum are integrated again from
 *     the step's ends (forwards before the minimum, backwards in time after
 *     it), not read from the continuous extension, whose extra stages may land
 *     where the multipliers are rough (off the rows by 3e-6 rad, 1 J off); the
 *     minimum itself is located again on the cubic through the states at
 *     t_min -+ 2 % of the step those integrations reach; the event function at
 *     four states along each of them must keep its sign, else the step held
 *     two minima (or a maximum was located) and is taken again in quarters, no
 *     later step longer;
 *   - a step whose ends' rates have one sign may still hide a minimum and the
 *     next maximum (a step of 0.38 s over a flat position): where log det moves
 *     by more than 1 over it (h |rate| > 1), the rate at three states on the
 *     chord between its ends with the other sign takes the step again in halves.
 */
#ifndef MBRT_PASS_H
#define MBRT_PASS_H

#include "mbrt.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    mbrt_prog_fn fun;        /* the Lagrange program: out = [dq/dt, du/dt] (nq + nu);
                                nonzero: a guard failed                              */
    const double *d, *h, *p; /* its inputs: d = (alpha, beta) Baumgarte gains (1/s)  */
    double *w;               /* its work array                                       */
    const mbrt_mech *mech;   /* the evaluation program (rows: the kept ones)         */
    double *mech_work;       /* mbrt_mech_work_size(mech) doubles                    */
    double pass_rank;        /* eigenvalues of A M^-1 A^T below this times the largest
                                are left out of the multipliers (> 0)                */
    int project;             /* nonzero: project after every accepted step           */
    double proj_tol, proj_accept; /* |Phi| to reach and to accept (m, rad)          */
    int proj_iter;           /* Newton steps at most                                 */
    double delta;            /* the event's central-difference step (s, > 0)         */
    int cap;                 /* located minima logged at most, and outputs in one step */
    double *log_t;           /* cap: their times (written)                           */
    double *log_y;           /* cap * n: their states [q, u] (written)               */
    int count;               /* minima logged (written)                              */
    double *work;            /* mbrt_pass_work_size(mech) doubles                    */
    double *y_last;          /* n: the last accepted step's state, projected (written) */
    double t_last, h_last;   /* its time and the step that reached it (written)      */
    long nrange;             /* the steps' evaluations by the range-space solve (written) */
    long nproj, nskipped;    /* projections made, left out (written)                 */
    long nevents;            /* event-function evaluations (written)                 */
    long nretaken;           /* steps taken again after a located minimum (written)  */
    double *y_from;          /* n: the last accepted step's start (written)           */
    double t_from;           /* its time (written)                                    */
    double t_min;            /* the last minimum logged (-inf: none; kept across calls) */
    long nrollbacks;         /* steps taken again, longer, where the steps collapsed (written) */
    /* internal: the largest time the event function saw (a step's end), the outputs' end,
     * the step before the last (start, size), the last start taken again after a collapse,
     * the range-space solves at the last step's end, a collapse seen */
    long nredone;            /* outputs next to a singular position integrated again (written) */
    long nrefined;           /* minima located again on the motion itself (written)   */
    long nredo_failed;       /* steps whose outputs or minimum could not be integrated again:
                                the continuous extension's stand (written)             */
    double t_seen, t_stop, t_back, h_back, t_rolled, t_before, t_after;
    long nrange_step;
    int collapse, redo, rolled_here, split;
    double hcap;             /* no step longer than this (0: none; set where a step held
                                two sign changes; kept across calls)                  */
    long nsplits;            /* steps taken again in quarters (written)               */
    long nhalved;            /* steps taken again in halves: a minimum and a maximum
                                hidden between their ends (written)                   */
    double g_start, g_end, t_hidden; /* internal: the rate at the step's ends, the last
                                start taken again in halves                            */
    int hidden, hidden_here;
} mbrt_pass;

/* Doubles of work mbrt_pass needs for the evaluation program P and cap (0 if P is NULL). */
size_t mbrt_pass_work_size(const mbrt_mech *P, int cap);

/* The range-space right-hand side dy = [dq/dt, du/dt] at (t, y) from the
 * evaluation program (what the Lagrange program's guard hands over):
 * MBRT_MECH_OK, _FALLBACK (a guard of the evaluation or a value not finite) or
 * _MASS_SINGULAR. */
int mbrt_pass_rhs(mbrt_pass *S, double t, const double *y, double *dy);

/* Integrates from (t0, y0) towards t_end as mbrt_dop853 (order 8) or
 * mbrt_dopri5 (order 5) with the right-hand side, projection and logged minima
 * described above, the outputs at t_out (<= t_stop <= t_end) written, and ends
 * at the first accepted step reaching t_stop (t_last; no step is cut short to
 * land on t_stop: a next call from t_from, y_from with the step h_last takes
 * that step again and goes on as one integration would); the counters of the
 * runtime's calls are summed in stats.  Returns the status of mbrt.h
 * (MBRT_STOPPED when the log is full or a minimum was located twice: the state
 * at t_last). */
int mbrt_pass_integrate(mbrt_pass *S, int order, double t0, const double *y0, double t_stop, double t_end,
                        double rtol, const double *atol, double h0, double hmax, long max_steps,
                        const double *t_out, int n_out, double *y_out, int *n_written, double *work,
                        mbrt_stats *stats);

#ifdef __cplusplus
}
#endif

#endif /* MBRT_PASS_H */
