/* mbcomp FMU events: the active set of a model with modes, the system of its rows in force,
 * its event indicators and the actions at its events (included at the end of fmu_core.c;
 * declarations in fmu_events.h; Python: mbcomp/export/fmu_events.py).
 *
 * The rows in force are the permanent rows (a loop's closure: its independent holonomic rows,
 * and the velocity rows of joints that are no contacts with modes; hy_add_permanent), then the
 * closed contacts' rows (from the evaluation program: the normal
 * row, then the contact's rolling rows B u = b, velocity rows with Phi 0 and rate Psi) and the
 * engaged stops' rows sign (q[iq] - at); the accelerations are the Lagrange index-1 solve
 * [M C^T; C 0] [du/dt; lam] = [f; -c_b - 2 alpha dPhi/dt - beta^2 Phi], a row's push -lam;
 * dq/dt = qrate(q, u) (quaternions) or u.
 * An impact closing a row solves [M C^T; C 0] [u+; -P] = [M u-; r], the impact row (a
 * contact's normal row) with Newton's restitution (C u+ + o = -e (C u- + o)), the rows in force
 * and the contact's rolling rows held (C u+ + o = 0: perfectly rough), as
 * mbcomp.assembly.impacts.impulse; o = dPhi/dt - C u. After every event the active set settles
 * as mbcomp's Events._segment: closed contacts that would pull open, the most pulling first; an
 * engaged row that would pull at once stays free; a contact let go that would accelerate into
 * its surface (rolling rows: Painleve-like) is an error naming it. Indicators (each event is its
 * indicator falling through zero): an open contact's gap (m), a closed one's push (N); a free
 * stop's distances to its limits (rad or m), an engaged limit's push; a stuck friction's
 * margins F_s + push and F_s - push (N or N m), a slipping one's speed along its slip (the
 * other indicator F_s). A stuck friction holds its rate (a row of value 0); a slipping one adds
 * -+F_k to its joint's force. */
#define HY_F0 (HY_NC + HY_NS) /* the first friction among the components */
#if HYBRID

static double hy_par(const Inst *c, int idx, double v) { return idx >= 0 ? c->p[idx] : v; }
static double hy_e(const Inst *c, int k)
{
    return k < HY_NC ? hy_par(c, HY_C_EP[k], HY_C_E[k]) : hy_par(c, HY_S_EP[k - HY_NC], HY_S_E[k - HY_NC]);
}
static double hy_at(const Inst *c, int s, int lim)
{
    return lim == 1 ? hy_par(c, HY_S_LOP[s], HY_S_LO[s]) : hy_par(c, HY_S_HIP[s], HY_S_HI[s]);
}

static void mbev_reset(Inst *c)
{
    int k, early = c->hy.early_ok; /* the importer's choice at instantiation outlives a reset */
    memset(&c->hy, 0, sizeof c->hy);
    c->hy.early_ok = early;
    for (k = 0; k < HY_NCOMP; k++) {
        c->hy.mode[k] = k < HY_NC ? HY_C_CLOSED0[k] : k >= HY_F0 ? HY_F_MODE0[k - HY_F0] : 0;
        c->hy.last[k] = -1.0;
    }
    for (k = 0; k < HY_NZC; k++) c->hy.dir[k] = -1;
    c->hy.fresh = -1;
#if HY_NUE
    for (k = 0; k < HY_NUE; k++) {
        c->hy.dir[HY_NZC + k] = HY_UE_DIR[k];
        c->hy.ue_last[k] = -1.0;
        c->hy.ue_side[k] = -1;
    }
    (void)mbue_params(c->p, c->hy.ue_h); /* the user events depend on no parameter: constants only */
#endif
}

/* the evaluation program at (t, y) into c->hy.ev: 0, or -1 after logging */
static int hy_eval(Inst *c, double t, const double *y)
{
    int i;
    if (mbhy_eval(y, y + NQ, t, c->d, c->hy.h, c->p, c->hy.w, c->hy.ev)) {
        say(c, 1, "the evaluation failed a guard at t=%g (a singular position, or a law's other branch)", t);
        return -1;
    }
    for (i = 0; i < HY_NOUT; i++)
        if (!isfinite(c->hy.ev[i])) {
            say(c, 1, "the evaluation gave a non-finite value (entry %d) at t=%g", i, t);
            return -1;
        }
    return 0;
}

/* a contact's rolling rows (velocity rows B u = b: Phi 0, the rate Psi, the bias B_b),
   appended after its normal row */
static void hy_add_rolling(Inst *c, int k)
{
#if HY_MN
    int i, j, r;
    for (i = HY_C_NH0[k]; i < HY_C_NH0[k] + HY_C_NHN[k]; i++) {
        r = c->hy.nr++;
        for (j = 0; j < NU; j++) c->hy.C[r * NU + j] = c->hy.ev[HY_OFF_B + i * NU + j];
        c->hy.phi[r] = 0.0;
        c->hy.phid[r] = c->hy.ev[HY_OFF_PSI + i];
        c->hy.bias[r] = c->hy.ev[HY_OFF_BB + i];
    }
#else
    (void)c;
    (void)k;
#endif
}

/* the rows (C, Phi, dPhi/dt, c_b) of component k in its engaged mode `m`, appended: a contact's
   normal row, then its rolling rows unless hol (positions: the holonomic rows only) */
static void hy_add_row(Inst *c, const double *y, int k, int m, int hol)
{
    int j, r = c->hy.nr;
    double *C = c->hy.C + r * NU;
    if (k < HY_NC) {
        int row = HY_C_ROW[k];
        for (j = 0; j < NU; j++) C[j] = c->hy.ev[HY_OFF_C + row * NU + j];
        c->hy.phi[r] = c->hy.ev[HY_OFF_PHI + row];
        c->hy.phid[r] = c->hy.ev[HY_OFF_PHID + row];
        c->hy.bias[r] = c->hy.ev[HY_OFF_CB + row];
        c->hy.row_of[k] = r;
        c->hy.nr = r + 1;
        if (!hol) hy_add_rolling(c, k);
        return;
    } else if (k >= HY_F0) { /* a stuck friction: its rate held */
        int f = k - HY_F0;
        for (j = 0; j < NU; j++) C[j] = 0.0;
        C[HY_F_IU[f]] = 1.0;
        c->hy.phi[r] = 0.0;
        c->hy.phid[r] = y[NQ + HY_F_IU[f]];
        c->hy.bias[r] = 0.0;
    } else {
        int s = k - HY_NC;
        double sign = m == 1 ? 1.0 : -1.0;
        for (j = 0; j < NU; j++) C[j] = 0.0;
        C[HY_S_IU[s]] = sign;
        c->hy.phi[r] = sign * (y[HY_S_IQ[s]] - hy_at(c, s, m));
        c->hy.phid[r] = sign * y[NQ + HY_S_IU[s]];
        c->hy.bias[r] = 0.0;
    }
    c->hy.row_of[k] = r;
    c->hy.nr = r + 1;
}

/* the rows always in force, appended (first): the loop closures' independent holonomic rows
   (HY_P_ROWS: C, Phi, dPhi/dt, c_b from the evaluation), then unless hol the velocity rows of
   the joints that are no contacts with modes (HY_P_NH: B u = b, Phi 0, the rate Psi, the bias B_b) */
static void hy_add_permanent(Inst *c, int hol)
{
    int i, j, r, row;
    for (i = 0; i < HY_NPR; i++) {
        r = c->hy.nr++;
        row = HY_P_ROWS[i];
        for (j = 0; j < NU; j++) c->hy.C[r * NU + j] = c->hy.ev[HY_OFF_C + row * NU + j];
        c->hy.phi[r] = c->hy.ev[HY_OFF_PHI + row];
        c->hy.phid[r] = c->hy.ev[HY_OFF_PHID + row];
        c->hy.bias[r] = c->hy.ev[HY_OFF_CB + row];
    }
#if HY_MN
    for (i = 0; i < HY_NPN && !hol; i++) {
        r = c->hy.nr++;
        row = HY_P_NH[i];
        for (j = 0; j < NU; j++) c->hy.C[r * NU + j] = c->hy.ev[HY_OFF_B + row * NU + j];
        c->hy.phi[r] = 0.0;
        c->hy.phid[r] = c->hy.ev[HY_OFF_PSI + row];
        c->hy.bias[r] = c->hy.ev[HY_OFF_BB + row];
    }
#else
    (void)hol;
#endif
}

/* the rows in force at y (after hy_eval; hol: the holonomic rows only); extra >= 0: component
   extra's rows in mode m_extra last; the permanent rows first. At most HY_NPR + HY_NPN + HY_NCR +
   HY_NS + HY_NF rows (extra is not counted twice): within HY_NR. */
static void hy_rows(Inst *c, const double *y, int extra, int m_extra, int hol)
{
    int k;
    c->hy.nr = 0;
    hy_add_permanent(c, hol);
    for (k = 0; k < HY_NCOMP; k++) {
        c->hy.row_of[k] = -1;
        if (k != extra && (k >= HY_F0 ? c->hy.mode[k] == 0 : c->hy.mode[k] != 0))
            hy_add_row(c, y, k, c->hy.mode[k], hol);
    }
    if (extra >= 0) hy_add_row(c, y, extra, m_extra, hol);
}

/* K = [M C^T; C 0] of the rows in force, factored: 0, or -1 after logging */
static int hy_saddle(Inst *c, double t)
{
    int i, j, n = NU + c->hy.nr;
    double *K = c->hy.K;
    for (i = 0; i < n * n; i++) K[i] = 0.0;
    for (i = 0; i < NU; i++)
        for (j = 0; j < NU; j++) K[i * n + j] = c->hy.ev[HY_OFF_M + i * NU + j];
    for (i = 0; i < c->hy.nr; i++)
        for (j = 0; j < NU; j++) K[(NU + i) * n + j] = K[j * n + NU + i] = c->hy.C[i * NU + j];
    if (mbrt_lu_factor(n, K, c->hy.piv) != 0) {
        say(c, 1, "the rows in force are dependent or the mass matrix is singular at t=%g", t);
        return -1;
    }
    return 0;
}

/* du/dt and the multipliers at (t, y) in the current modes: 0, or -1 after logging */
static int hy_accel(Inst *c, double t, const double *y)
{
    int i, n;
    if (hy_eval(c, t, y)) return -1;
    hy_rows(c, y, -1, 0, 0);
    if (hy_saddle(c, t)) return -1;
    n = NU + c->hy.nr;
    for (i = 0; i < NU; i++) c->hy.rhs[i] = c->hy.ev[HY_OFF_F + i];
    for (i = 0; i < HY_NF; i++) /* a slipping friction's force on its speed */
        if (c->hy.mode[HY_F0 + i]) c->hy.rhs[HY_F_IU[i]] += c->hy.mode[HY_F0 + i] == 1 ? -HY_F_KINETIC[i] : HY_F_KINETIC[i];
    for (i = 0; i < c->hy.nr; i++)
        c->hy.rhs[NU + i] = -c->hy.bias[i] - 2.0 * HY_ALPHA * c->hy.phid[i] - HY_BETA * HY_BETA * c->hy.phi[i];
    mbrt_lu_solve(n, c->hy.K, c->hy.piv, c->hy.rhs);
    for (i = 0; i < n; i++)
        if (!isfinite(c->hy.rhs[i])) { say(c, 1, "the accelerations are not finite at t=%g", t); return -1; }
    memcpy(c->hy.ud, c->hy.rhs, sizeof(double) * NU);
    for (i = 0; i < c->hy.nr; i++) c->hy.lam[i] = c->hy.rhs[NU + i];
    return 0;
}

static int mbev_rhs(Inst *c, double t, const double *y, double *dy)
{
    if (hy_accel(c, t, y)) return -1;
#if HY_QRATE
    {
        int i;
        if (mbhy_qrate(y, y + NQ, t, c->d, c->hy.h, c->p, c->hy.w, dy)) {
            say(c, 1, "the coordinate rates failed a guard at t=%g", t);
            return -1;
        }
        for (i = 0; i < NQ; i++)
            if (!isfinite(dy[i])) { say(c, 1, "the coordinate rates are not finite at t=%g", t); return -1; }
    }
#else
    memcpy(dy, y + NQ, sizeof(double) * NU); /* dq/dt = u */
#endif
    memcpy(dy + NQ, c->hy.ud, sizeof(double) * NU);
    return 0;
}

/* the event indicators at (t, y) into z (HY_NZ) */
static int mbev_indicators(Inst *c, double t, const double *y, double *z)
{
    int k;
    if (hy_accel(c, t, y)) return -1;
    for (k = 0; k < HY_NC; k++)
        z[k] = c->hy.mode[k] ? -c->hy.lam[c->hy.row_of[k]] : c->hy.ev[HY_OFF_PHI + HY_C_ROW[k]];
    for (k = 0; k < HY_NS; k++) {
        int m = c->hy.mode[HY_NC + k], r = c->hy.row_of[HY_NC + k];
        double q = y[HY_S_IQ[k]];
        z[HY_NC + 2 * k] = m == 1 ? -c->hy.lam[r] : q - hy_at(c, k, 1);
        z[HY_NC + 2 * k + 1] = m == 2 ? -c->hy.lam[r] : hy_at(c, k, 2) - q;
    }
    for (k = 0; k < HY_NF; k++) {
        int m = c->hy.mode[HY_F0 + k], i = HY_NC + 2 * HY_NS + 2 * k;
        double u = y[NQ + HY_F_IU[k]], push = m == 0 ? -c->hy.lam[c->hy.row_of[HY_F0 + k]] : 0.0;
        z[i] = m == 0 ? HY_F_STATIC[k] + push : m == 1 ? u : HY_F_STATIC[k];
        z[i + 1] = m == 0 ? HY_F_STATIC[k] - push : m == 2 ? -u : HY_F_STATIC[k];
    }
#if HY_NUE
    if (mbue_fun(y, y + NQ, t, c->d, c->hy.ue_h, c->p, c->hy.ue_w, z + HY_NZC)) {
        say(c, 1, "a user event's function failed a guard at t=%g", t);
        return -1;
    }
    for (k = 0; k < HY_NUE; k++)
        if (!isfinite(z[HY_NZC + k])) {
            say(c, 1, "the user event %s is not finite at t=%g", HY_UE_NAME[k], t);
            return -1;
        }
#endif
    return 0;
}

static int hy_event_fn(void *ctx, double t, const double *y, double *g)
{
    return mbev_indicators((Inst *)ctx, t, y, g) ? 1 : 0;
}

/* x = (C C^T)^-1 b for the rows of the last hy_rows (b: nr values, x may be b): 0, or -1 */
static int hy_gram_solve(Inst *c, double t, const double *b, double *x)
{
    int i, j, l, nr = c->hy.nr;
    double *G = c->hy.G;
    if (nr <= 0 || nr > HY_NR) return -1;
    for (i = 0; i < nr; i++)
        for (j = 0; j < nr; j++)
            for (G[i * nr + j] = 0.0, l = 0; l < NU; l++) G[i * nr + j] += c->hy.C[i * NU + l] * c->hy.C[j * NU + l];
    if (mbrt_lu_factor(nr, G, c->hy.piv)) { say(c, 1, "the rows in force are dependent at t=%g", t); return -1; }
    memmove(x, b, sizeof(double) * nr);
    mbrt_lu_solve(nr, G, c->hy.piv, x);
    return 0;
}

/* y moved onto the rows in force and, extra >= 0, component extra's rows in mode m (the
   quaternions normalized, the positions by Gauss-Newton on the holonomic rows, q moved through
   the coordinate map; with speeds, the speeds by least squares on every row, rolling rows too,
   as mbcomp.assembly.kkt.project_state): 0, or -1 after logging */
static int hy_project(Inst *c, double t, double *y, int extra, int m, int speeds)
{
    int it, i, l, nr = 0;
    double norm = 0.0, *x = c->hy.rhs;
    if (mbrt_increment(NQ, NU, HY_NSEG, HY_SEG, y, NULL, 1.0) != MBRT_MECH_OK) {
        say(c, 1, "the coordinate map does not fit the coordinates (%d) and speeds (%d)", NQ, NU);
        return -1;
    }
    for (it = 0; it <= 30; it++) {
        if (hy_eval(c, t, y)) return -1;
        hy_rows(c, y, extra, m, 1);
        nr = c->hy.nr;
        for (norm = 0.0, i = 0; i < nr; i++) norm = fmax(norm, fabs(c->hy.phi[i]));
        if (!nr || norm <= 1e-15 || it == 30) break;
        if (hy_gram_solve(c, t, c->hy.phi, x)) return -1;
        for (l = 0; l < NU; l++)
            for (c->hy.du[l] = 0.0, i = 0; i < nr; i++) c->hy.du[l] += c->hy.C[i * NU + l] * x[i];
        if (mbrt_increment(NQ, NU, HY_NSEG, HY_SEG, y, c->hy.du, -1.0) != MBRT_MECH_OK) return -1;
    }
    if (norm > 1e-10) {
        say(c, 1, "the state cannot be moved onto the rows in force at t=%g (|Phi| = %g)", t, norm);
        return -1;
    }
    if (speeds) {
        hy_rows(c, y, extra, m, 0); /* every row in force, at the last evaluation (y's positions) */
        if (c->hy.nr && hy_gram_solve(c, t, c->hy.phid, x)) return -1;
        for (l = 0; l < NU; l++)
            for (i = 0; i < c->hy.nr; i++) y[NQ + l] -= c->hy.C[i * NU + l] * x[i];
    }
    for (l = 0; l < NX; l++)
        if (!isfinite(y[l])) {
            say(c, 1, "moving the state onto the rows in force at t=%g gave a non-finite value", t);
            return -1;
        }
    return 0;
}

static int hy_consistent(Inst *c, double t, double *y) { return hy_project(c, t, y, -1, 0, 1); }

/* the columns of the rows of the last hy_rows that `free` (NU flags) does not let move, zeroed */
static void hy_free_columns(Inst *c, const unsigned char *free)
{
    int i, j;
    for (i = 0; i < c->hy.nr; i++)
        for (j = 0; j < NU; j++)
            if (!free[j]) c->hy.C[i * NU + j] = 0.0;
}

/* the start values the importer set and the model's fixed ones could not all hold: logged, -1 */
static int hy_start_fails(Inst *c, double norm)
{
    char names[256];
    size_t used = 0;
    int i, w;
    names[0] = '\0';
    for (i = 0; i < NX && used + 2 < sizeof names; i++) {
        if (!c->set[i]) continue;
        w = snprintf(names + used, sizeof names - used, "%s%s = %g", used ? ", " : "", YNAME[i], c->y0[i]);
        if (w < 0) break;
        used += (size_t)w < sizeof names - used ? (size_t)w : sizeof names - used - 1;
    }
    say(c, 1, "the start values set (%s) and the model's fixed ones cannot all hold: the rows in force at the "
        "start (the loops' closures, the closed contacts) cannot be met with them (|Phi| = %g) -> set fewer of "
        "them, or values the mechanism can reach", used ? names : "none", norm);
    return -1;
}

/* the importer's start values (c->y from c->y0) moved onto the rows in force in the start
   modes -- the loops' closures, the closed contacts' rows -- the starts it set and the model's
   fixed ones kept (the directions c->pfree, c->vfree do not move: mbcomp's consistent
   initialization, as mbrt_project_free for a model without modes): the positions by Gauss-Newton
   with minimum-norm steps in the free directions (through the coordinate map), then the speeds
   by the least correction of the free ones: 0, or -1 after logging the starts set */
static int mbev_start(Inst *c)
{
    int it, i, l;
    double norm = 0.0, speed = 0.0, t = c->t, *y = c->y, *x = c->hy.rhs;
    if (mbrt_increment(NQ, NU, HY_NSEG, HY_SEG, y, NULL, 1.0) != MBRT_MECH_OK) return hy_start_fails(c, NAN);
    for (it = 0; it <= 60; it++) { /* to mbcomp's initialization's tolerance: starts that meet it stay */
        if (hy_eval(c, t, y)) return -1;
        hy_rows(c, y, -1, 0, 1);
        for (norm = 0.0, i = 0; i < c->hy.nr; i++) norm = fmax(norm, fabs(c->hy.phi[i]));
        if (!c->hy.nr || norm <= 1e-12 || it == 60) break;
        hy_free_columns(c, c->pfree);
        if (hy_gram_solve(c, t, c->hy.phi, x)) return hy_start_fails(c, norm);
        for (l = 0; l < NU; l++)
            for (c->hy.du[l] = 0.0, i = 0; i < c->hy.nr; i++) c->hy.du[l] += c->hy.C[i * NU + l] * x[i];
        if (mbrt_increment(NQ, NU, HY_NSEG, HY_SEG, y, c->hy.du, -1.0) != MBRT_MECH_OK) return hy_start_fails(c, norm);
    }
    if (!(norm <= 1e-10)) return hy_start_fails(c, norm);
    hy_rows(c, y, -1, 0, 0); /* every row in force, at the last evaluation (y's positions) */
    for (i = 0; i < c->hy.nr; i++) speed = fmax(speed, fabs(c->hy.phid[i]));
    if (!(speed > 1e-10)) c->hy.nr = 0; /* the speeds meet the rows already (1e-10): they stay */
    hy_free_columns(c, c->vfree);
    if (c->hy.nr && hy_gram_solve(c, t, c->hy.phid, x)) return hy_start_fails(c, norm);
    for (l = 0; l < NU; l++)
        for (i = 0; i < c->hy.nr; i++) y[NQ + l] -= c->hy.C[i * NU + l] * x[i];
    for (l = 0; l < NX; l++)
        if (!isfinite(y[l])) return hy_start_fails(c, norm);
    return 0;
}

/* the impact of component k closing its row (stops: limit lim) at (t, y): y's speeds become
   u+; *before, *after: the row's speed before and after (m/s or rad/s). A contact's impact row
   is its normal row, its rolling rows held through it (perfectly rough), as the other rows in
   force (mbcomp.hybrid.contacts.contact_impact). */
static int hy_impact(Inst *c, double t, double *y, int k, int lim, double *before, double *after)
{
    int i, j, n, last;
    double e = hy_e(c, k), o;
    if (hy_eval(c, t, y)) return -1;
    hy_rows(c, y, k, lim, 0);
    if (hy_saddle(c, t)) return -1;
    n = NU + c->hy.nr;
    last = c->hy.row_of[k];
    for (i = 0; i < NU; i++)
        for (c->hy.rhs[i] = 0.0, j = 0; j < NU; j++) c->hy.rhs[i] += c->hy.ev[HY_OFF_M + i * NU + j] * y[NQ + j];
    for (i = 0; i < c->hy.nr; i++) {
        for (o = c->hy.phid[i], j = 0; j < NU; j++) o -= c->hy.C[i * NU + j] * y[NQ + j];
        c->hy.rhs[NU + i] = i == last ? -e * c->hy.phid[i] - o : -o;
        if (i == last) *before = c->hy.phid[i], *after = o;
    }
    mbrt_lu_solve(n, c->hy.K, c->hy.piv, c->hy.rhs);
    for (i = 0; i < NU; i++) {
        if (!isfinite(c->hy.rhs[i])) { say(c, 1, "the impact at t=%g gave non-finite speeds", t); return -1; }
        y[NQ + i] = c->hy.rhs[i];
        *after += c->hy.C[last * NU + i] * y[NQ + i];
    }
    return 0;
}

/* whether the rebound (the row's speed `after`) rises less than HY_REST against the row's
   acceleration in the current modes (mbcomp.hybrid.events: _rests, _contact_rests) */
static int hy_rests(Inst *c, double t, const double *y, int k, int lim, double after, int *rests)
{
    int j, r;
    double acc;
    if (hy_accel(c, t, y)) return -1;
    hy_rows(c, y, k, lim, 0); /* the row's values (the solve above is kept) */
    r = c->hy.row_of[k];
    for (acc = c->hy.bias[r], j = 0; j < NU; j++) acc += c->hy.C[r * NU + j] * c->hy.ud[j];
    *rests = acc < 0.0 && after * after <= -2.0 * acc * HY_REST;
    return 0;
}

/* mbcomp.hybrid.events._chattering: the last HY_CHATTER intervals between k's impacts each shrank */
static int hy_chattering(Inst *c, int k)
{
    int i;
    const double *h = c->hy.hits[k];
    if (c->hy.nhits[k] < HY_CHATTER + 2) return 0;
    for (i = 2; i < HY_CHATTER + 2; i++)
        if (!(h[i] - h[i - 1] < h[i - 1] - h[i - 2])) return 0;
    return 1;
}

static void hy_hit(Inst *c, int k, double t)
{
    int n = c->hy.nhits[k];
    if (n == HY_CHATTER + 2) {
        memmove(c->hy.hits[k], c->hy.hits[k] + 1, sizeof(double) * (HY_CHATTER + 1));
        n--;
    }
    c->hy.hits[k][n] = t;
    c->hy.nhits[k] = n + 1;
}

/* whether some engaged row would pull at (t, y) (mbcomp: an engaged row that would pull: stay) */
static int hy_pulls(Inst *c, double t, const double *y, int *pulls)
{
    int k;
    if (mbev_indicators(c, t, y, c->hy.z)) return -1;
    *pulls = 0;
    for (k = 0; k < HY_F0; k++) /* a stuck friction's row is bilateral up to its limit */
        if (c->hy.mode[k] && -c->hy.lam[c->hy.row_of[k]] < 0.0) *pulls = 1;
    return 0;
}

static int hy_engaged(int k, int m) { return k >= HY_F0 ? m == 0 : m != 0; }

/* the contacts closed in `before` and closed still that would pull at (t, y), the state made
   consistent with the current modes (on a copy), opened one at a time, the most pulling first:
   a contact closing may unload another (the bicycle's front wheel landing lifts the rear one;
   mbcomp.hybrid.events._open_pulling, each a release): 0, or -1 after logging */
static int hy_open_pulling(Inst *c, double t, const int *before)
{
    int k, n, worst;
    double p, least;
    for (n = 0; n < HY_NC; n++) {
        memcpy(c->hy.ys2, c->y, sizeof(double) * NX);
        if (hy_consistent(c, t, c->hy.ys2) || mbev_indicators(c, t, c->hy.ys2, c->hy.z)) return -1;
        for (worst = -1, least = 0.0, k = 0; k < HY_NC; k++)
            if (before[k] && c->hy.mode[k] && (p = -c->hy.lam[c->hy.row_of[k]]) < least) least = p, worst = k;
        if (worst < 0) return 0;
        c->hy.mode[worst] = 0;
        c->hy.last[worst] = t;
        c->hy.events++;
    }
    return 0;
}

/* every contact let go at (c->t, c->y) (closed in `before`, open now) must leave: its gap's
   acceleration a = C_n du/dt + c_b,n in the new modes not into the surface. Closed it would pull
   (or its push vanished), open it would penetrate: a Painleve-like inconsistency of perfectly
   rough rolling rows (the frictionless bicycle tumbling at v = 2 m/s: its wheel, its normal force gone with a
   lateral force left), an error naming the contact: 0, or -1 after logging */
static int hy_lets_go(Inst *c, const int *before)
{
    int k, j, row, done = 0;
    double a, cn, un, cj, t = c->t;
    for (k = 0; k < HY_NC; k++) {
        if (!before[k] || c->hy.mode[k]) continue;
        if (!done && hy_accel(c, t, c->y)) return -1;
        done = 1;
        row = HY_C_ROW[k];
        for (a = c->hy.ev[HY_OFF_CB + row], cn = un = 0.0, j = 0; j < NU; j++) {
            cj = c->hy.ev[HY_OFF_C + row * NU + j];
            a += cj * c->hy.ud[j];
            cn += cj * cj;
            un += c->hy.ud[j] * c->hy.ud[j];
        }
        if (a < -1e-6 * (sqrt(cn) * sqrt(un) + fabs(c->hy.ev[HY_OFF_CB + row]))) {
            /* the words of mbcomp.hybrid.events.Events._let_go_outward */
            say(c, 1, "%s: let go at t=%.12g s, but open it accelerates into what it touches (%.4g m/s^2) while "
                "closed it would pull: its normal force fell to zero with its rolling rows still holding a "
                "tangential load (rows that never slip need an unbounded friction coefficient there), so no mode "
                "is consistent (a Painleve-like contradiction) -> give the contact Coulomb friction "
                "(friction=ContactFriction(mu_s, mu_k)) so it slides before it lifts off", HY_C_NAME[k], t, a);
            c->mode = M_ERROR;
            return -1;
        }
    }
    return 0;
}

/* the active set after an event at (c->t, c->y) from the modes `before` (mbcomp's
   Events._segment): contacts closed before that now pull opened (hy_open_pulling); where the
   event engaged a row and a held row still pulls, the modes `before` come back with the state
   `back` (engaged it would pull: it stays free); the state made consistent, the contacts let go
   checked (hy_lets_go): 0, or -1 after logging */
static int hy_settle(Inst *c, const int *before, const double *back)
{
    int k, closing = 0, pulls = 0;
    double t = c->t;
    if (hy_open_pulling(c, t, before)) return -1;
    for (k = 0; k < HY_NCOMP; k++) closing |= hy_engaged(k, c->hy.mode[k]) && !hy_engaged(k, before[k]);
    if (hy_consistent(c, t, c->y)) return -1;
    if (closing && hy_pulls(c, t, c->y, &pulls)) return -1;
    if (pulls) {
        memcpy(c->hy.mode, before, sizeof(int) * HY_NCOMP);
        memcpy(c->y, back, sizeof(double) * NX);
        if (hy_consistent(c, t, c->y)) return -1;
    }
    return hy_lets_go(c, before);
}

/* component k's impact (stops: at limit lim) at (c->t, c->y) if approaching: Newton's
   restitution, then at rest (too small a rebound, e = 0, or a Zeno accumulation) engaged */
static int hy_do_impact(Inst *c, int k, int lim, int *acted)
{
    double before = 0.0, after = 0.0, t = c->t;
    int rests = 0, m = k < HY_NC ? 1 : lim, modes[HY_NCOMP + 1];
    if (c->hy.last[k] == t) return 0; /* it acted at this instant (released with its push through zero: it
                                         leaves, its speed onto the row zero to rounding -- the projection
                                         onto a loop's rows leaves 1e-16 -- as a fresh event function in mbcomp) */
    memcpy(modes, c->hy.mode, sizeof(int) * HY_NCOMP);
    memcpy(c->hy.ys, c->y, sizeof(double) * NX);
    if (hy_impact(c, t, c->hy.ys, k, m, &before, &after)) return -1;
    if (!(before < 0.0)) { /* not approaching: no impact (mbcomp's _decide); at rest on it (a start
                              touching, mbcomp's Events.start) it engages */
        if (hy_rests(c, t, c->y, k, m, before, &rests)) return -1;
        if (!rests) return 0;
        *acted = 1;
        c->hy.events++;
        c->hy.last[k] = t;
        c->hy.mode[k] = m;
        memcpy(c->hy.ys, c->y, sizeof(double) * NX);
        return hy_settle(c, modes, c->hy.ys);
    }
    memcpy(c->y, c->hy.ys, sizeof(double) * NX);
    *acted = 1;
    c->hy.events++;
    c->hy.last[k] = t;
    hy_hit(c, k, t);
    /* where the importer stepped past the touch (a fixed step: the body inside), the positions
       back onto the row; a located event's 1e-15 m is moved as much (the speeds are the impact's) */
    if (hy_project(c, t, c->y, k, m, 0)) return -1;
    if (hy_e(c, k) > 0.0 && hy_rests(c, t, c->y, k, m, after, &rests)) return -1;
    if (hy_e(c, k) == 0.0 || rests || hy_chattering(c, k)) c->hy.mode[k] = m;
    memcpy(c->hy.ys, c->y, sizeof(double) * NX);
    return hy_settle(c, modes, c->hy.ys);
}

/* component k switched to mode `to` at (c->t, c->y): a release, a break-away, a stick */
static int hy_switch(Inst *c, int k, int to, int *acted)
{
    int modes[HY_NCOMP + 1];
    memcpy(modes, c->hy.mode, sizeof(int) * HY_NCOMP);
    c->hy.mode[k] = to;
    c->hy.last[k] = c->t;
    c->hy.events++;
    *acted = 1;
    memcpy(c->hy.ys, c->y, sizeof(double) * NX);
    return hy_settle(c, modes, c->hy.ys);
}


/* acts on indicator i at (c->t, c->y); force: it was located falling through zero */
static int hy_act_on(Inst *c, int i, int force, int *acted)
{
    int k = i < HY_NC ? i : HY_NC + (i - HY_NC) / 2, lim = i < HY_NC ? 1 : 1 + (i - HY_NC) % 2;
    int m = c->hy.mode[k];
    if (!force && !(c->hy.z[i] <= 0.0)) return 0;
    if (k >= HY_F0) { /* stuck: break away the way the load drives (lim 1: forward); slipping: stick */
        if (!force && !(c->hy.z[i] < 0.0)) return 0; /* a slip starts at zero speed, a margin at its limit */
        if (m == 0) return hy_switch(c, k, lim, acted);
        return m == lim ? hy_switch(c, k, 0, acted) : 0;
    }
    if (m == 0) return hy_do_impact(c, k, lim, acted);
    /* a held row's push: release when below zero, or at zero exactly (FMI's domain z <= 0: an
       importer's root finding may land on a push linear in time at its root) unless the row
       engaged at this instant */
    if (m == lim && (force || c->hy.z[i] < 0.0 || (c->hy.z[i] == 0.0 && c->hy.last[k] != c->t)))
        return hy_switch(c, k, 0, acted);
    return 0;
}

/* acts on indicator i: a component's (hy_act_on) or a user event's, which changes no state
   (not an action the active set settles on) */
static int hy_act(Inst *c, int i, int force, int *acted)
{
#if HY_NUE
    if (i >= HY_NZC) {
        hy_user(c, i - HY_NZC, force);
        return 0;
    }
#endif
    return hy_act_on(c, i, force, acted);
}

/* Event Mode: every event at (c->t, c->y) acted on (which >= 0: the indicator the
   Co-Simulation step located; -1: every indicator at or below zero); *changed: the state or
   the active set changed (the importer restarts its integrator) */
static int mbev_act(Inst *c, int which, int *changed)
{
    int i, n, acted;
    *changed = 0;
    if (mb_refresh(c)) return -1;
    if (which >= 0) { /* the located event, then what it brings about at once (a break-away) */
        acted = 0;
        if (mbev_indicators(c, c->t, c->y, c->hy.z) || hy_act(c, which, 1, &acted)) return -1;
        *changed = acted;
    }
    for (n = 0; n < HY_MAX_EVENTS; n++) {
        acted = 0;
        if (mbev_indicators(c, c->t, c->y, c->hy.z)) return -1;
        for (i = 0; i < HY_NZ && !acted && !c->hy.ended; i++)
            if (hy_act(c, i, 0, &acted)) return -1;
        if (!acted || c->hy.ended) return 0;
        *changed = 1;
    }
    say(c, 1, "chattering: %d events at t=%g without settling", HY_MAX_EVENTS, c->t);
    return -1;
}

/* Co-Simulation: an event located on the near side of its root (the indicator still above
   zero: a push released, a margin broken a little early) is stepped across by the location
   tolerance in its mode, so the next mode starts past the root (a released load that would
   press again at once chattered at one instant): 0, or -1 after logging */
static int hy_across(Inst *c, int which, double tol, double t_end)
{
    double t1 = fmin(c->t + tol, t_end);
    int i;
    if (mbev_indicators(c, c->t, c->y, c->hy.z)) return -1;
    if (!(c->hy.z[which] > 0.0) || !(t1 > c->t)) return 0; /* crossed (or at zero): act here */
    /* one Euler step of a tolerance's length (its error, (t1 - t)^2 |d2y/dt2| / 2, ~1e-24) */
    if (mbev_rhs(c, c->t, c->y, c->dy)) return -1;
    for (i = 0; i < NX; i++) c->y[i] += (t1 - c->t) * c->dy[i];
    c->t = t1;
    return 0;
}


/* Co-Simulation: from c->t by h with DOP853 at c->rtol, the events located on its dense
   output (mbrt_dop853_events) and acted on: 0, or -1 after logging */
static int mbev_step(Inst *c, double h)
{
    mbrt_stats st;
    mbrt_events ev;
    double t_end;
    int i, rc, n, changed, written = 0;
    if (!(h >= 0.0) || !isfinite(h)) { say(c, 1, "a communication step of %g s", h); return -1; }
    if (mb_after_end(c, "a step")) return -1;
    if (h == 0.0) return 0;
    if (mb_refresh(c)) return -1;
    c->d[0] = c->alpha;
    c->d[1] = c->beta;
    for (i = 0; i < NX; i++) c->atol[i] = c->rtol * 1e-2 * NOMINAL[i];
    t_end = c->t + h;
    /* what is due at the step's start (the run's start: touching, beyond a friction's limit; an
       input changed since the last step: a push turned) -- the runtime sees only crossings */
    if (mbev_act(c, -1, &changed)) { c->mode = M_ERROR; return -1; }
    for (n = 0; n < HY_MAX_EVENTS; n++) {
        if (!(t_end > c->t)) return 0;
#if HY_NUE
        if (hy_user_sides(c)) { c->mode = M_ERROR; return -1; }
#endif
        memset(&st, 0, sizeof st);
        memset(&ev, 0, sizeof ev);
        ev.g = hy_event_fn;
        ev.gctx = c;
        ev.n_ev = HY_NZ;
        ev.direction = c->hy.dir;
        ev.tol = fmin(1e-12, c->rtol / 1000.0) * fmax(1.0, fabs(t_end));
        ev.fresh = c->hy.fresh;
        ev.work = c->hy.evwork;
        ev.y_event = c->hy.yev;
        ev.which = -1;
        written = 0;
        rc = mbrt_dop853_events(mb_rhs, NULL, c, NX, c->t, c->y, t_end, c->rtol, c->atol, 0.0, 0.0, 0, &t_end, 1,
                                c->y_end, &written, c->work, &st, 0, &ev);
        if (rc == MBRT_OK && written == 1) {
            memcpy(c->y, c->y_end, sizeof(double) * NX);
            c->t = t_end;
            c->hy.fresh = -1;
            return 0;
        }
        if (rc != MBRT_EVENT || ev.which < 0 || ev.which >= HY_NZ) {
            say(c, 1, "the step from t=%g by %g s failed: %s", c->t, h, st.message);
            c->mode = M_ERROR;
            return -1;
        }
        memcpy(c->y, c->hy.yev, sizeof(double) * NX);
        c->t = ev.t_event;
        if ((ev.which < HY_NZC && hy_across(c, ev.which, ev.tol, t_end)) || mbev_act(c, ev.which, &changed)) {
            c->mode = M_ERROR;
            return -1;
        }
        c->hy.fresh = ev.which;
        if (c->hy.ended) return 0; /* a terminal user event: the step stops at it */
#if HY_NUE
        if (ev.which >= HY_NZC) { /* a user event: across it, found again only crossing back */
            c->hy.fresh = -1;
            if (hy_user_across(c, ev.which - HY_NZC, ev.tol, t_end)) { c->mode = M_ERROR; return -1; }
        }
#endif
    }
    say(c, 1, "chattering: %d events within the step from t=%g", HY_MAX_EVENTS, c->t);
    c->mode = M_ERROR;
    return -1;
}

/* the event variables: indicators (HY_VR ..) and each component's last event time (s) */
static int mbev_get(Inst *c, unsigned vr, double *v)
{
    if (vr >= HY_VR && vr < HY_VR + HY_NZ) {
        if (mb_refresh(c) || mbev_indicators(c, c->t, c->y, c->hy.z)) return -1;
        *v = c->hy.z[vr - HY_VR];
        return 0;
    }
    if (vr >= HY_VR + HY_NZ && vr < HY_VR + HY_NZ + HY_NCOMP) { *v = c->hy.last[vr - HY_VR - HY_NZ]; return 0; }
    if (vr >= HY_VR + HY_NZ + HY_NCOMP && vr < HY_VR + HY_NZ + HY_NCOMP + HY_UE_NT) {
        *v = c->hy.ue_last[vr - HY_VR - HY_NZ - HY_NCOMP];
        return 0;
    }
    return 1;
}
#endif

#include "fmu_user_events.c" /* the user events: firing, Co-Simulation's crossing, the run's end */
