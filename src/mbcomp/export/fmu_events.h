/* mbcomp FMU events: the instance's part of a model with modes (fmu_events.c; Python:
 * mbcomp/export/fmu_events.py). Included by fmu_core.c before its instance struct; with
 * HYBRID 0 (no modes) it declares nothing.
 *
 * The generated model file defines, with HYBRID 1: HY_NC contacts and HY_NS stops, their
 * tables (HY_C_*: holonomic (normal) row in the evaluation, first rolling row and their count
 * (HY_C_NH0, HY_C_NHN), restitution, its parameter index or -1, closed at the start, name;
 * HY_NCR: the contacts' rows in all; HY_S_*: q and u index, limits and restitution and their
 * parameter indices; HY_NF frictions, HY_F_*: q and u index, static and kinetic force, start
 * mode), the evaluation program mbhy_eval (HY_NH, HY_NW, HY_NOUT, HY_MH, HY_MN, HY_OFF_*),
 * mbhy_eval_params, with HY_QRATE 1 the coordinate rates mbhy_qrate (dq/dt; else q' = u), the
 * coordinate map HY_NSEG, HY_SEG (mbrt_mech's segments: how q moves along the speeds), HY_REST
 * (m or rad: a rebound rising less rests), HY_CHATTER, the Baumgarte gains HY_ALPHA, HY_BETA
 * and HY_VR, the first event variable's value reference; the rows always in force (loop
 * closures and joints' velocity rows): HY_NPR holonomic rows HY_P_ROWS (indices into Phi, the
 * independent ones) and HY_NPN nonholonomic rows HY_P_NH (indices into B). */
#ifndef HYBRID
#define HYBRID 0
#endif
#if HYBRID
#ifndef HY_NUE /* user events (mbcomp/export/fmu_user_events.py): HY_NUE functions mbue_fun of (t, q, u),
                  HY_UE_DIR their directions, HY_UE_TERM the firings that end the run (0: never) */
#define HY_NUE 0
#endif
#if !HY_NUE
#define HY_UE_NT 0
#define HY_UE_NH 1
#define HY_UE_NW 1
#endif
#define HY_NCOMP (HY_NC + HY_NS + HY_NF) /* components with modes: contacts, stops, frictions */
#define HY_NZC (HY_NC + 2 * HY_NS + 2 * HY_NF) /* the components' indicators: a contact's, a stop's two, a friction's two */
#define HY_NZ (HY_NZC + HY_NUE) /* event indicators: the components', then the user events' */
#define HY_NR (HY_NPR + HY_NPN + HY_NCR + HY_NS + HY_NF + 1) /* rows in force at most: the permanent
                                      rows, every component's rows (a contact's normal and rolling
                                      rows), and one spare */
#define HY_NK (NU + HY_NR)
#define HY_MAX_EVENTS 100000       /* events acted on in one DoStep or event iteration at most */

typedef struct {
    int mode[HY_NCOMP + 1];        /* contacts: 0 open, 1 closed; stops: 0 free, 1 lo, 2 hi;
                                      frictions: 0 stick, 1 slip+, 2 slip- */
    double hits[HY_NCOMP + 1][HY_CHATTER + 2]; /* the last impacts' times (s), oldest first */
    int nhits[HY_NCOMP + 1];
    double last[HY_NCOMP + 1];     /* time (s) of each component's last event, -1 before any */
    double h[HY_NH + 1], w[HY_NW + 1], ev[HY_NOUT + 1]; /* the evaluation program's */
    double K[HY_NK * HY_NK + 1], rhs[HY_NK + 1], G[HY_NR * HY_NR + 1];
    int piv[HY_NK + 1];
    double C[HY_NR * NU + 1], phi[HY_NR + 1], phid[HY_NR + 1], bias[HY_NR + 1];
    int nr, row_of[HY_NCOMP + 1];  /* rows in force; each component's row (-1: none) */
    double ud[NU + 1], lam[HY_NR + 1], z[HY_NZ + 1], ys[NX + 1], ys2[NX + 1], du[NU + 1];
    double evwork[3 * HY_NZ + NX + 1], yev[NX + 1];
    int dir[HY_NZ + 1], fresh;     /* Co-Simulation: the event acted on last, its function at zero */
    long events;                   /* events acted on */
    double ue_h[HY_UE_NH + 1], ue_w[HY_UE_NW + 1]; /* the user events' program's */
    double ue_last[HY_NUE + 1];    /* each time slot's last firing (s), -1 before any (HY_UE_SLOT: a
                                      joint's events share its slot) */
    int ue_n[HY_NUE + 1];          /* its firings */
    int ue_side[HY_NUE + 1];       /* Model Exchange: its side at the last Event Mode: 2 above zero,
                                      1 at zero, 0 below, -1 not yet seen (Co-Simulation: at the
                                      stretch's start) */
    int ended;                     /* a terminal user event fired: the simulation is over */
    int early_ok;                  /* FMI 3.0 Co-Simulation: the importer allows an early return */
} mbev;

struct Inst;
static void mbev_reset(struct Inst *c);
static int mbev_rhs(struct Inst *c, double t, const double *y, double *dy);
static int mbev_step(struct Inst *c, double h);
static int mbev_act(struct Inst *c, int which, int *changed);
static int mbev_get(struct Inst *c, unsigned vr, double *v);
#if HY_NUE /* fmu_user_events.c */
static void hy_user(struct Inst *c, int k, int force);
static int hy_user_sides(struct Inst *c);
static int hy_user_across(struct Inst *c, int k, double tol, double t_end);
#endif
static int mbev_start(struct Inst *c);
#define MB_NZ HY_NZ
#else
#define MB_NZ 0
#endif
/* the event indicators (MB_NZ of them) at the instance's (t, y) into z[nz]: 0, or -1 after logging */
struct Inst;
static int mb_event_indicators(struct Inst *c, double *z, size_t nz);
/* whether a terminal user event ended the simulation (0 without events) */
static int mb_ended(struct Inst *c);
/* -1 after logging that `fn` is refused when the simulation ended, else 0 */
static int mb_after_end(struct Inst *c, const char *fn);
/* FMI 3.0 Co-Simulation: the importer allows an early return (a terminal user event's step
   then returns early at it); mb_early_return: whether the step just made did */
#ifdef MB_EARLY_RETURN
static void mb_allow_early(struct Inst *c, int ok);
static int mb_early_return(struct Inst *c);
#endif
