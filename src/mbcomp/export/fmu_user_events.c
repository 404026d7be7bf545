/* mbcomp FMU user events: the C of export_fmu(..., events=[f]) and of the joints whose every
 * event ends the run (Python: mbcomp/export/fmu_user_events.py). Included at the end of
 * fmu_events.c; declarations in fmu_events.h. With HY_NUE user events (the generated model file:
 * mbue_fun, their values at (t, q, u) after the components' indicators; HY_UE_DIR, HY_UE_TERM,
 * HY_UE_SLOT, HY_UE_NAME) a firing is recorded in its time slot and the terminal one (its count
 * reached) ends the simulation (c->hy.ended: the wrappers' terminateSimulation, fmi2Discard). */
#if HYBRID && HY_NUE
/* the side of a value: 0 below zero, 1 at zero, 2 above */
static int hy_side(double z) { return z > 0.0 ? 2 : z == 0.0 ? 1 : 0; }

/* user event k at (c->t, c->y) (its value in c->hy.z): force, Co-Simulation located it crossing
   in its direction; else (Model Exchange) it fires when it crossed since the last Event Mode in
   its direction, as mbcomp.hybrid.events._crossed: falling from above zero to at or below it,
   rising from below zero to at or above it -- an importer's root finding may land exactly on a
   function linear in time at its root (t - 0.3 rising: FMPy's CVODE stopped at z = 0, and the
   event never fired), and leaving zero afterwards is no second crossing. A firing is recorded;
   the terminal one (its count reached) ends the simulation. */
static void hy_user(Inst *c, int k, int force)
{
    int side = hy_side(c->hy.z[HY_NZC + k]), was = c->hy.ue_side[k], fire = force, dir = HY_UE_DIR[k];
    if (!force && !c->cs) {
        c->hy.ue_side[k] = side;
        fire = (dir <= 0 && was == 2 && side <= 1) || (dir >= 0 && was == 0 && side >= 1);
    }
    if (!fire) return;
    c->hy.ue_last[HY_UE_SLOT[k]] = c->t;
    c->hy.ue_n[k]++;
    c->hy.events++;
    if (HY_UE_TERM[k] > 0 && c->hy.ue_n[k] >= HY_UE_TERM[k]) {
        c->hy.ended = 1;
        say(c, 0, "event %s at t=%.12g s: the simulation ends (terminal)", HY_UE_NAME[k], c->t);
    }
}

/* Co-Simulation: each user event's side (hy_side) at the start of a stretch, into
   c->hy.ue_side (Model Exchange's record; Co-Simulation locates crossings instead) */
static int hy_user_sides(Inst *c)
{
    int k;
    if (mbev_indicators(c, c->t, c->y, c->hy.z)) return -1;
    for (k = 0; k < HY_NUE; k++) c->hy.ue_side[k] = hy_side(c->hy.z[HY_NZC + k]);
    return 0;
}

/* Co-Simulation: user event k, located on the near side of its root (still on its stretch's
   start side, or at zero), stepped across by the location tolerance (Euler steps of
   tolerance's length, as hy_across): the next stretch starts past it and does not find it
   again (the runtime's `fresh` is the components' return through zero, not a user's) */
static int hy_user_across(Inst *c, int k, double tol, double t_end)
{
    int i, n;
    double z, t1;
    for (n = 0; n < 8; n++) {
        if (mbev_indicators(c, c->t, c->y, c->hy.z)) return -1;
        z = c->hy.z[HY_NZC + k];
        t1 = fmin(c->t + tol, t_end);
        if ((z != 0.0 && hy_side(z) != c->hy.ue_side[k]) || !(t1 > c->t)) return 0;
        if (mbev_rhs(c, c->t, c->y, c->dy)) return -1;
        for (i = 0; i < NX; i++) c->y[i] += (t1 - c->t) * c->dy[i];
        c->t = t1;
    }
    return 0;
}
#endif

static int mb_ended(Inst *c)
{
#if HYBRID
    return c->hy.ended;
#else
    (void)c;
    return 0;
#endif
}

static int mb_after_end(Inst *c, const char *fn)
{
    if (!mb_ended(c)) return 0;
    say(c, 1, "%s: the simulation ended there, at t=%.12g s (a terminal event) -> terminate the FMU (or reset it to "
        "run again)", fn, c->t);
    return -1;
}

#ifdef MB_EARLY_RETURN
static void mb_allow_early(Inst *c, int ok)
{
#if HYBRID
    c->hy.early_ok = ok != 0;
#else
    (void)c;
    (void)ok;
#endif
}

static int mb_early_return(Inst *c)
{
#if HYBRID
    return c->hy.ended && c->hy.early_ok;
#else
    (void)c;
    return 0;
#endif
}
#endif

static int mb_event_indicators(Inst *c, double *z, size_t nz)
{
    if (nz != (size_t)MB_NZ || (nz && !z)) {
        say(c, 1, "%zu event indicators asked for, %d exist", nz, MB_NZ);
        return -1;
    }
#if HYBRID
    if (nz && (mb_refresh(c) || mbev_indicators(c, c->t, c->y, z))) return -1;
#endif
    return 0;
}
