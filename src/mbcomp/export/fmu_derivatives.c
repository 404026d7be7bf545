/* mbcomp FMU: exact directional (forward) and adjoint (reverse) derivatives, included at the end
 * of the core (fmu_core.c). The including file defines, besides the core's, the generated
 * product programs (mbcomp.export.derivatives): mbd_fun_jvp/_vjp (the Lagrange right-hand side),
 * mbd_out_jvp/_vjp (the output program) and, with D'Alembert's states (SELECT), mbd_res_jvp/_vjp
 * (the velocity residual [dPhi/dt[rows]; Psi] of the constraints), each with its parameter
 * program (_params) and sizes (_NH, _NW), and MBD_DERIVATIVES (without it, exported with
 * derivatives=False, the derivative functions log and fail). A product program differentiates with respect to
 * [q, u, inputs] (NX + NIN numbers):
 *   jvp: d = [alpha, beta, inputs, dq, du, dinputs, eps = 0], out = the program's outputs' change
 *   vjp: d = [alpha, beta, inputs, weights (one per output)], out = the weights' gradient.
 *
 * Knowns are the continuous states (value references VR_X ..) and the inputs (VR_IN ..);
 * unknowns the state derivatives (VR_DX ..) and the outputs (VR_OUT ..). A state of
 * Co-Simulation or of an open tree is an entry of y = [q, u] (with SELECT in Co-Simulation:
 * v[k] = u[ind[k]]); with D'Alembert's states in Model Exchange, x = [q, v] and the dependent
 * speeds follow from the constraints, res(q, u, inputs) = 0: their change solves
 * A_d du_d = -(dres/dq dq + A_i dv + dres/dinputs dd) (forward; the adjoint solves with A_d^T),
 * and dx/dt is the right-hand side without Baumgarte terms (mbrt_dalembert_rhs's accelerations:
 * D'Alembert's projection and the KKT solve give the same accelerations on the constraints).
 * The quaternion outputs are differentiated through mbcomp_quat's own branch (mbd_quat_dual). */

#ifdef MBD_DERIVATIVES
#define MBD_NY (NX + NIN) /* what the product programs differentiate with respect to */
/* a quaternion output whose scalar part is this close to 0 is at its sign flip: no derivative */
#define MBD_QUAT_FLIP 1e-12
#ifndef MBD_NRES
#define MBD_NRES 0
#endif

typedef int (*mbd_prog)(const double *, const double *, double, const double *, const double *, const double *,
                        double *, double *);
typedef int (*mbd_pre)(const double *, double *);

typedef struct {
    mbd_prog f;
    mbd_pre pre;
    int nh, nw, nout;
    const char *what;
} mbd_program;

enum { MBD_FUN, MBD_OUT, MBD_RES };

static const mbd_program MBD_JVP[] = {
    {mbd_fun_jvp, mbd_fun_jvp_params, MBD_FUN_JVP_NH, MBD_FUN_JVP_NW, NX, "right-hand side's tangent program"},
    {mbd_out_jvp, mbd_out_jvp_params, MBD_OUT_JVP_NH, MBD_OUT_JVP_NW, NROW, "outputs' tangent program"},
#if SELECT
    {mbd_res_jvp, mbd_res_jvp_params, MBD_RES_JVP_NH, MBD_RES_JVP_NW, MBD_NRES, "constraints' tangent program"},
#endif
};
static const mbd_program MBD_VJP[] = {
    {mbd_fun_vjp, mbd_fun_vjp_params, MBD_FUN_VJP_NH, MBD_FUN_VJP_NW, MBD_NY, "right-hand side's adjoint program"},
    {mbd_out_vjp, mbd_out_vjp_params, MBD_OUT_VJP_NH, MBD_OUT_VJP_NW, MBD_NY, "outputs' adjoint program"},
#if SELECT
    {mbd_res_vjp, mbd_res_vjp_params, MBD_RES_VJP_NH, MBD_RES_VJP_NW, MBD_NY, "constraints' adjoint program"},
#endif
};

/* runs program g at (t, y = c->y) with the gains g0, g1 and the direction or weights v (nv
   numbers) into out (g.nout); 0, or -1 after logging (a guard, memory, a non-finite value) */
static int mbd_run(Inst *c, const mbd_program *g, double g0, double g1, const double *v, int nv, double *out)
{
    int i, rc, nd = 2 + NIN + nv + 1;
    double *h = (double *)calloc((size_t)(g->nh + g->nw + nd + 3), sizeof(double));
    double *w, *d;
    if (!h) { say(c, 1, "no memory for the %s", g->what); return -1; }
    w = h + g->nh + 1;
    d = w + g->nw + 1;
    d[0] = g0;
    d[1] = g1;
    for (i = 0; i < NIN; i++) d[2 + i] = c->d[2 + i];
    for (i = 0; i < nv; i++) d[2 + NIN + i] = v[i];
    d[2 + NIN + nv] = 0.0; /* eps: the point itself */
    rc = g->pre(c->p, h);
    if (rc) {
        free(h);
        say(c, 1, "the %s's parameter values %s -> export the model again with these values", g->what,
            rc == 1 ? "change a decision taken when the program was generated" : "are not finite");
        return -1;
    }
    rc = g->f(c->y, c->y + NQ, c->t, d, h, c->p, w, out);
    free(h);
    if (rc) {
        say(c, 1, "the %s failed a guard at t=%g (a singular position, or a law's other branch): no exact "
            "derivative here", g->what, c->t);
        return -1;
    }
    for (i = 0; i < g->nout; i++) {
        if (!isfinite(out[i])) {
            say(c, 1, "the %s gave a non-finite value (entry %d) at t=%g: no exact derivative here (a square root "
                "or a distance at zero?)", g->what, i, c->t);
            return -1;
        }
    }
    return 0;
}

/* Q = mbcomp_quat(R) and its change dQ along dR, in mbcomp_quat's branch (the same choice of k
   and sign) */
static void mbd_quat_dual(const double *R, const double *dR, double *Q, double *dQ)
{
    const double tr = R[0] + R[4] + R[8], dtr = dR[0] + dR[4] + dR[8];
    const double cc[4] = {tr, R[0], R[4], R[8]}, dc[4] = {dtr, dR[0], dR[4], dR[8]};
    double q[4], dq[4], s, ds, big, dbig, e, de, n, dn, sg, dsg;
    int k = 0, j;
    for (j = 1; j < 4; ++j)
        if (cc[j] > cc[k]) k = j;
    s = k == 0 ? 1.0 + tr : 1.0 + 2.0 * cc[k] - tr;
    ds = k == 0 ? dtr : 2.0 * dc[k] - dtr;
    big = 0.5 * sqrt(s > 0.0 ? s : 0.0);
    dbig = s > 0.0 ? 0.25 * ds / sqrt(s) : 0.0;
    e = 1.0 / (4.0 * big);
    de = -4.0 * dbig * e * e;
#define MBD_PAIR(a, b, sign, x, dx)                                                                             \
    do {                                                                                                        \
        x = (R[a] sign R[b]) * e;                                                                               \
        dx = (dR[a] sign dR[b]) * e + (R[a] sign R[b]) * de;                                                    \
    } while (0)
    {
        double s21, s02, s10, p01, p02, p12, ds21, ds02, ds10, dp01, dp02, dp12;
        MBD_PAIR(7, 5, -, s21, ds21);
        MBD_PAIR(2, 6, -, s02, ds02);
        MBD_PAIR(3, 1, -, s10, ds10);
        MBD_PAIR(1, 3, +, p01, dp01);
        MBD_PAIR(2, 6, +, p02, dp02);
        MBD_PAIR(5, 7, +, p12, dp12);
        const double v[4][4] = {{big, s21, s02, s10}, {s21, big, p01, p02}, {s02, p01, big, p12}, {s10, p02, p12, big}};
        const double dv[4][4] = {{dbig, ds21, ds02, ds10}, {ds21, dbig, dp01, dp02}, {ds02, dp01, dbig, dp12},
                                 {ds10, dp02, dp12, dbig}};
        for (j = 0; j < 4; ++j) { /* mbcomp_quat's switch on k, row by row */
            q[j] = v[k][j];
            dq[j] = dv[k][j];
        }
    }
#undef MBD_PAIR
    n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    dn = (q[0] * dq[0] + q[1] * dq[1] + q[2] * dq[2] + q[3] * dq[3]) / n;
    sg = q[0] >= 0.0 ? 1.0 / n : -1.0 / n;
    dsg = -sg * dn / n;
    for (j = 0; j < 4; ++j) {
        Q[j] = q[j] * sg;
        dQ[j] = dq[j] * sg + q[j] * dsg;
    }
}

/* the position of a known (state k -> k, input i -> NXS + i) or of an unknown (derivative of state
   k -> k, output slot s -> NXS + s); -1 after logging for a reference that is neither */
static int mbd_known(Inst *c, unsigned vr)
{
    if (vr >= VR_X && vr < VR_DX) return (int)(vr - VR_X);
    if (vr >= VR_IN && vr < VR_IN + NIN) return NXS + (int)(vr - VR_IN);
    say(c, 1, "value reference %u is not a known of a derivative: the knowns are the continuous states (%d..%d) "
        "and the inputs%s", vr, VR_X, VR_DX - 1, vr < VR_X ? " (derivatives with respect to parameters are not "
        "supported)" : "");
    return -1;
}

static int mbd_unknown(Inst *c, unsigned vr)
{
    if (vr >= VR_DX && vr < NVR) return (int)(vr - VR_DX);
    if (vr >= VR_OUT && vr < VR_OUT + NOV) {
        int k;
        for (k = 0; k < MBD_NSKIP; k++) {
            if (MBD_SKIP[k] == (int)(vr - VR_OUT)) {
                say(c, 1, "output %u (a residual's norm, zero on the constraints) has no derivative there", vr);
                return -1;
            }
        }
        return NXS + (int)(vr - VR_OUT);
    }
    say(c, 1, "value reference %u is not an unknown of a derivative: the unknowns are the state derivatives "
        "(%d..%d) and the outputs", vr, VR_DX, NVR - 1);
    return -1;
}

/* the entry of y = [q, u] (and of the right-hand side) of state k */
static int mbd_row(const Inst *c, int k)
{
#if SELECT
    return k < NQ ? k : NQ + c->ind[k - NQ];
#else
    (void)c;
    return k;
#endif
}

/* checks the call, maps the references to positions (pk, pu) and prepares the point (parameters,
   with D'Alembert's states the full speeds and A); *chain: D'Alembert's chain rule applies */
static int mbd_prepare(Inst *c, const unsigned *unk, size_t nunk, const unsigned *kn, size_t nkn, int *pu, int *pk,
                       int *chain, int *need)
{
    size_t i;
    *chain = 0;
    *need = 0;
    for (i = 0; i < nunk; i++) {
        if ((pu[i] = mbd_unknown(c, unk[i])) < 0) return -1;
        *need |= pu[i] < NXS ? 1 : 2;
    }
    for (i = 0; i < nkn; i++)
        if ((pk[i] = mbd_known(c, kn[i])) < 0) return -1;
    if (mb_refresh(c)) return -1;
#if SELECT
    if (!c->cs) {
        if (mb_full_speeds(c)) return -1;
        *chain = 1;
    }
#endif
    if ((*need & 2) && mb_outputs(c)) return -1;
    for (i = 0; i < nunk; i++) { /* a quaternion whose scalar part is ~0: its sign flips there (w >= 0) */
        int slot = pu[i] - NXS;
        if (slot >= NCOL && fabs(c->ov[NCOL + 4 * ((slot - NCOL) / 4)]) <= MBD_QUAT_FLIP) {
            say(c, 1, "output %u is an orientation quaternion whose scalar part is %g at t=%g: its sign flips here "
                "(w >= 0), so it has no derivative", unk[i], c->ov[NCOL + 4 * ((slot - NCOL) / 4)], c->t);
            return -1;
        }
    }
    return 0;
}

/* scratch of one call: the positions and every vector (freed by the caller) */
typedef struct {
    int *pu, *pk;
    double *dy, *f, *o, *r, *g, *gr, *at;
    int *piv;
} mbd_work;

static int mbd_alloc(Inst *c, mbd_work *s, size_t nunk, size_t nkn)
{
    size_t nd = 3 * (size_t)MBD_NY + NX + NROW + MBD_NRES + (size_t)MBD_NRES * MBD_NRES + 8;
    s->pu = (int *)calloc(nunk + nkn + MBD_NRES + 3, sizeof(int));
    s->dy = (double *)calloc(nd, sizeof(double));
    if (!s->pu || !s->dy) {
        free(s->pu);
        free(s->dy);
        say(c, 1, "no memory for a derivative");
        return -1;
    }
    s->pk = s->pu + nunk + 1;
    s->piv = s->pk + nkn + 1;
    s->f = s->dy + MBD_NY + 1;
    s->o = s->f + NX + 1;
    s->r = s->o + NROW + 1;
    s->g = s->r + MBD_NRES + 1;
    s->gr = s->g + MBD_NY + 1;
    s->at = s->gr + MBD_NY + 1;
    return 0;
}

static void mbd_free(mbd_work *s)
{
    free(s->pu);
    free(s->dy);
}

/* dz = J dk: the directional derivative of the unknowns unk along the seed of the knowns kn */
static int mb_directional(Inst *c, const unsigned *unk, size_t nunk, const unsigned *kn, size_t nkn,
                          const double *seed, double *sens)
{
    mbd_work s;
    size_t i;
    int chain, need, rc = -1, j;
    if (mbd_alloc(c, &s, nunk, nkn)) return -1;
    if (mbd_prepare(c, unk, nunk, kn, nkn, s.pu, s.pk, &chain, &need)) goto done;
    for (i = 0; i < nkn; i++) {
        int p = s.pk[i];
        s.dy[p < NXS ? mbd_row(c, p) : NX + p - NXS] += seed[i];
    }
#if SELECT
    if (chain) { /* the dependent speeds' change: A_d du_d = -(the residual's change with du_d = 0) */
        if (mbd_run(c, &MBD_JVP[MBD_RES], c->d[0], c->d[1], s.dy, MBD_NY, s.r)) goto done;
        mbrt_lu_solve(MM, c->ad, c->piv, s.r);
        for (j = 0; j < MM; j++) s.dy[NQ + c->dep[j]] = -s.r[j];
    }
#endif
    if ((need & 1) && mbd_run(c, &MBD_JVP[MBD_FUN], chain ? 0.0 : c->alpha, chain ? 0.0 : c->beta, s.dy, MBD_NY, s.f))
        goto done;
    if ((need & 2) && mbd_run(c, &MBD_JVP[MBD_OUT], c->alpha, c->beta, s.dy, MBD_NY, s.o)) goto done;
    for (i = 0; i < nunk; i++) {
        int p = s.pu[i], slot = p - NXS;
        if (p < NXS) {
            sens[i] = s.f[mbd_row(c, p)];
        } else if (slot < NCOL) {
            sens[i] = s.o[slot];
        } else {
            double Q[4], dQ[4];
            int r = (slot - NCOL) / 4;
            mbd_quat_dual(c->row + NCOL + 9 * r, s.o + NCOL + 9 * r, Q, dQ);
            sens[i] = dQ[(slot - NCOL) % 4];
        }
    }
    rc = 0;
done:
    (void)j;
    mbd_free(&s);
    return rc;
}

/* dk = J^T dz: the adjoint derivative, the seed weighting the unknowns unk, one value per known */
static int mb_adjoint(Inst *c, const unsigned *unk, size_t nunk, const unsigned *kn, size_t nkn, const double *seed,
                      double *sens)
{
    mbd_work s;
    size_t i;
    int chain, need, rc = -1, j, m;
    if (mbd_alloc(c, &s, nunk, nkn)) return -1;
    if (mbd_prepare(c, unk, nunk, kn, nkn, s.pu, s.pk, &chain, &need)) goto done;
    for (i = 0; i < nunk; i++) { /* the weights of the programs' outputs: s.f (fun), s.o (outputs) */
        int p = s.pu[i], slot = p - NXS;
        if (p < NXS) {
            s.f[mbd_row(c, p)] += seed[i];
        } else if (slot < NCOL) {
            s.o[slot] += seed[i];
        } else { /* the quaternion's weight onto its rotation matrix: column m of d Q / d R */
            double Q[4], dQ[4], e[9];
            int r = (slot - NCOL) / 4;
            for (m = 0; m < 9; m++) {
                memset(e, 0, sizeof e);
                e[m] = 1.0;
                mbd_quat_dual(c->row + NCOL + 9 * r, e, Q, dQ);
                s.o[NCOL + 9 * r + m] += dQ[(slot - NCOL) % 4] * seed[i];
            }
        }
    }
    if (need & 1) {
        if (mbd_run(c, &MBD_VJP[MBD_FUN], chain ? 0.0 : c->alpha, chain ? 0.0 : c->beta, s.f, NX, s.gr)) goto done;
        for (j = 0; j < MBD_NY; j++) s.g[j] += s.gr[j];
    }
    if (need & 2) {
        if (mbd_run(c, &MBD_VJP[MBD_OUT], c->alpha, c->beta, s.o, NROW, s.gr)) goto done;
        for (j = 0; j < MBD_NY; j++) s.g[j] += s.gr[j];
    }
#if SELECT
    if (chain) { /* back through the dependent speeds: A_d^T mu = g[dep], g -= (d res/d[q, u, inputs])^T mu */
        for (j = 0; j < MM; j++) {
            s.r[j] = s.g[NQ + c->dep[j]];
            for (m = 0; m < MM; m++) s.at[j * MM + m] = c->a[m * NU + c->dep[j]];
        }
        if (mbrt_lu_factor(MM, s.at, s.piv)) {
            say(c, 1, "the dependent speeds' block is singular at t=%g (a singular position)", c->t);
            goto done;
        }
        mbrt_lu_solve(MM, s.at, s.piv, s.r);
        if (mbd_run(c, &MBD_VJP[MBD_RES], c->d[0], c->d[1], s.r, MBD_NRES, s.gr)) goto done;
        for (j = 0; j < MBD_NY; j++) s.g[j] -= s.gr[j];
    }
#endif
    for (i = 0; i < nkn; i++) {
        int p = s.pk[i];
        sens[i] = s.g[p < NXS ? mbd_row(c, p) : NX + p - NXS];
    }
    rc = 0;
done:
    mbd_free(&s);
    return rc;
}

/* the states that are outputs too (the joint coordinates and speeds: causality "output") are
   unknowns whose derivative is the identity: d(state k)/d(state k) = 1, 0 for every other known.
   They are taken apart here, the other unknowns go to the product programs, and the results are
   put back in the caller's order. */
static int mbd_with_state_outputs(Inst *c, int adjoint, const unsigned *unk, size_t nunk, const unsigned *kn,
                                  size_t nkn, const double *seed, double *sens)
{
    size_t i, j, n = 0;
    int rc = 0;
    for (i = 0; i < nunk; i++) n += unk[i] >= VR_X && unk[i] < VR_DX;
    if (n == 0)
        return adjoint ? mb_adjoint(c, unk, nunk, kn, nkn, seed, sens) : mb_directional(c, unk, nunk, kn, nkn, seed, sens);
    {
        size_t m = nunk - n, k = 0;
        unsigned *rest = (unsigned *)calloc(m + 1, sizeof(unsigned));
        double *part = (double *)calloc((adjoint ? nkn : m) + 1, sizeof(double));
        double *wrest = (double *)calloc(m + 1, sizeof(double));
        if (!rest || !part || !wrest) {
            free(rest); free(part); free(wrest);
            say(c, 1, "no memory for a derivative");
            return -1;
        }
        for (i = 0; i < nunk; i++)
            if (!(unk[i] >= VR_X && unk[i] < VR_DX)) { rest[k] = unk[i]; if (adjoint) wrest[k] = seed[i]; k++; }
        if (m > 0)
            rc = adjoint ? mb_adjoint(c, rest, m, kn, nkn, wrest, part) : mb_directional(c, rest, m, kn, nkn, seed, part);
        if (rc == 0 && adjoint) {
            for (j = 0; j < nkn; j++) sens[j] = m > 0 ? part[j] : 0.0;
            for (i = 0; i < nunk; i++)
                if (unk[i] >= VR_X && unk[i] < VR_DX)
                    for (j = 0; j < nkn; j++)
                        if (kn[j] == unk[i]) sens[j] += seed[i];
        } else if (rc == 0) {
            for (i = 0, k = 0; i < nunk; i++) {
                if (unk[i] >= VR_X && unk[i] < VR_DX) {
                    double d = 0.0;
                    for (j = 0; j < nkn; j++)
                        if (kn[j] == unk[i]) d += seed[j];
                    sens[i] = d;
                } else {
                    sens[i] = part[k++];
                }
            }
        }
        free(rest); free(part); free(wrest);
    }
    return rc;
}

/* the wrappers' entry: checks the arrays and their sizes (forward: nseed = nkn, nsens = nunk;
   adjoint: nseed = nunk, nsens = nkn), then one of the two */
static int mb_derivative(Inst *c, int adjoint, const unsigned *unk, size_t nunk, const unsigned *kn, size_t nkn,
                         const double *seed, size_t nseed, double *sens, size_t nsens)
{
    const char *fn = adjoint ? "the adjoint derivative" : "the directional derivative";
    size_t want_seed = adjoint ? nunk : nkn, want_sens = adjoint ? nkn : nunk;
    if (nseed != want_seed || nsens != want_sens) {
        say(c, 1, "%s: %zu seed and %zu sensitivity values for %zu unknowns and %zu knowns (%s %zu and %zu)", fn,
            nseed, nsens, nunk, nkn, "expected", want_seed, want_sens);
        return -1;
    }
    if ((nunk && !unk) || (nkn && !kn) || (nseed && !seed) || (nsens && !sens)) {
        say(c, 1, "%s: a NULL array", fn);
        return -1;
    }
    if (!nunk || !nkn) {
        size_t i;
        for (i = 0; i < nsens; i++) sens[i] = 0.0;
        return 0;
    }
    return mbd_with_state_outputs(c, adjoint, unk, nunk, kn, nkn, seed, sens);
}
#else /* exported with derivatives=False: no product programs */
static int mb_derivative(Inst *c, int adjoint, const unsigned *unk, size_t nunk, const unsigned *kn, size_t nkn,
                         const double *seed, size_t nseed, double *sens, size_t nsens)
{
    (void)unk; (void)nunk; (void)kn; (void)nkn; (void)seed; (void)nseed; (void)sens; (void)nsens;
#if HYBRID
    say(c, 1, "%s derivatives are not in this FMU: a model with modes (stops, contacts, friction) has none yet",
        adjoint ? "adjoint" : "directional");
#else
    say(c, 1, "%s derivatives are not in this FMU: export it with derivatives=True",
        adjoint ? "adjoint" : "directional");
#endif
    return -1;
}
#endif
