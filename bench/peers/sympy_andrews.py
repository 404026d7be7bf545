"""Andrews' squeezing mechanism modelled with sympy.physics.mechanics (peer benchmark).

Independent peer model for the mbcomp benchmark: the mechanism is built from
sympy.physics.mechanics objects (ReferenceFrame, Point, RigidBody, loads), the
equations of motion are formed with ``KanesMethod`` (1 independent coordinate/speed,
6 dependent coordinates/speeds, 6 configuration and 6 velocity constraints for the
three loops closing at E), lambdified with ``cse=True`` and integrated with
``scipy.integrate.solve_ivp``.  The published M, f, g of the test set are NOT typed in;
they are only used in the self-check (``check_against_published``).

Integrated state (default, ``states="q7u1"``): y = (q[7], u_beta).  At every RHS call
the 6 dependent speeds are solved from the velocity constraints B(q) u = 0, then the
7x7 system ``kane.mass_matrix @ u' = kane.forcing`` (Kane's equation for u_beta stacked
with the differentiated velocity constraints) gives u'; q' = u.  The dependent
coordinates are integrated as plain ODE states, so they drift off g(q) = 0 (no
projection); ``simulate`` reports the constraint residual at t_end.

Alternative ``states="q7u7"``: y = (q[7], u[7]) with ``kane.mass_matrix_full`` /
``kane.forcing_full`` (the textbook sympy route); then velocities drift as well.

API:
    derived = derive()                      # -> Derived (functions + timings)
    res = simulate(derived, rtol, atol, method="Radau", t_end=0.03)
    res["q"] -> dict name->value at t_end, res["cpu_s"], res["nfev"], res["status"], ...
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import json  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import sympy as sm  # noqa: E402
import sympy.physics.mechanics as me  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

REFERENCE_JSON = Path(__file__).resolve().parents[2] / "models" / "data" / "andrews.json"

COORD_NAMES = ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon")
PARAM_NAMES = (
    "m1 m2 m3 m4 m5 m6 m7 xa ya xb yb xc yc c0 i1 i2 i3 i4 i5 i6 i7 d da e ea rr ra "
    "l0 ss sa sb sc sd ta tb u ua ub zf zt fa mom"
).split()


def load_reference(path=REFERENCE_JSON):
    """Return (params dict, q0 array[7], reference q(t=0.03) array[7], raw json)."""
    data = json.loads(Path(path).read_text())
    params = {k: float(v) for k, v in data["parameters"].items()}
    iv = data["initial_values_as_printed"]
    q0 = np.array([float(iv[n]) for n in COORD_NAMES])
    ref = np.array([float(data["reference_t_0.03"][n]) for n in COORD_NAMES])
    return params, q0, ref, data


# --------------------------------------------------------------------------------------
# symbolic model
# --------------------------------------------------------------------------------------
def build_kane():
    """Build the mechanism with sympy.physics.mechanics and form Kane's equations.

    Returns (kane, q, u, p_syms, g, vel_con) where g are the 6 configuration
    constraints and vel_con the 6 velocity constraints (both sympy Matrices)."""
    q = me.dynamicsymbols("beta Theta gamma Phi delta Omega epsilon")
    u = me.dynamicsymbols("u_beta u_Theta u_gamma u_Phi u_delta u_Omega u_epsilon")
    beta, Theta, gamma, Phi, delta, Omega, epsilon = q
    ube, uTh, uga, uPh, ude, uOm, uep = u
    p = sm.symbols(PARAM_NAMES, real=True)
    P = dict(zip(PARAM_NAMES, p))
    (m1, m2, m3, m4, m5, m6, m7) = (P[f"m{i}"] for i in range(1, 8))
    (i1, i2, i3, i4, i5, i6, i7) = (P[f"i{i}"] for i in range(1, 8))
    xa, ya, xb, yb, xc, yc = (P[k] for k in ("xa", "ya", "xb", "yb", "xc", "yc"))
    c0, l0, mom = P["c0"], P["l0"], P["mom"]
    d, da, e, ea, rr, ra = (P[k] for k in ("d", "da", "e", "ea", "rr", "ra"))
    ss, sa, sb, sc, sd = (P[k] for k in ("ss", "sa", "sb", "sc", "sd"))
    ta, tb, uu, ua, ub, zf, zt, fa = (P[k] for k in ("ta", "tb", "u", "ua", "ub", "zf", "zt", "fa"))

    # ground and fixed points ---------------------------------------------------------
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    A = O.locatenew("A", xa * N.x + ya * N.y)
    B = O.locatenew("B", xb * N.x + yb * N.y)
    C = O.locatenew("C", xc * N.x + yc * N.y)
    for P_ in (A, B, C):
        P_.set_vel(N, 0)

    # body frames: every body is oriented directly from N by its absolute angle ---------
    def frame(name, angle, omega):
        fr = me.ReferenceFrame(name)
        fr.orient_axis(N, N.z, angle)
        fr.set_ang_vel(N, omega * N.z)
        return fr

    F1 = frame("F1", beta, ube)                      # crank OF
    F2 = frame("F2", beta + Theta, ube + uTh)        # rod FE (E = F - d*F2.x)
    F3 = frame("F3", gamma, uga)                     # triangle BDE about B
    F4 = frame("F4", Phi + delta, uPh + ude)         # link GE (E = G - e*F4.y)
    F5 = frame("F5", delta, ude)                     # link AG
    F6 = frame("F6", Omega + epsilon, uOm + uep)     # link HE (E = H + zf*F6.x)
    F7 = frame("F7", epsilon, uep)                   # link AH (H = A - u*F7.y)

    def rigid(name, point, parent, fr):
        point.v2pt_theory(parent, N, fr)
        return point

    # loop 1: O - F - E (crank + rod) -------------------------------------------------
    F = rigid("F", O.locatenew("F", rr * F1.x), O, F1)
    G1 = rigid("G1", O.locatenew("G1", ra * F1.x), O, F1)
    G2 = rigid("G2", F.locatenew("G2", -da * F2.x), F, F2)
    E_rod = rigid("E_rod", F.locatenew("E_rod", -d * F2.x), F, F2)
    # triangle (body 3): E = (0, -ss), D = (sd, -sc) in body coordinates; the mass
    # centre is placed at (sa, sb) -- only its distance from the fixed pivot B enters
    # the dynamics (no gravity), M33 = m3 (sa^2+sb^2) + i3.
    E_tri = rigid("E_tri", B.locatenew("E_tri", -ss * F3.y), B, F3)
    D = rigid("D", B.locatenew("D", sd * F3.x - sc * F3.y), B, F3)
    G3 = rigid("G3", B.locatenew("G3", sa * F3.x + sb * F3.y), B, F3)
    # loop A - G - E (bodies 5 and 4) ---------------------------------------------------
    Gp = rigid("Gp", A.locatenew("Gp", zt * F5.x), A, F5)
    G5 = rigid("G5", A.locatenew("G5", ta * F5.x + tb * F5.y), A, F5)
    G4 = rigid("G4", Gp.locatenew("G4", -(e - ea) * F4.y), Gp, F4)
    E_g = rigid("E_g", Gp.locatenew("E_g", -e * F4.y), Gp, F4)
    # loop A - H - E (bodies 7 and 6) ---------------------------------------------------
    H = rigid("H", A.locatenew("H", -uu * F7.y), A, F7)
    G7 = rigid("G7", A.locatenew("G7", ua * F7.x + ub * F7.y), A, F7)
    G6 = rigid("G6", H.locatenew("G6", (zf - fa) * F6.x), H, F6)
    E_h = rigid("E_h", H.locatenew("E_h", zf * F6.x), H, F6)

    # bodies ----------------------------------------------------------------------------
    def body(name, mc, fr, m, izz):
        return me.RigidBody(name, mc, fr, m, (me.inertia(fr, 0, 0, izz), mc))

    bodies = [
        body("crank", G1, F1, m1, i1),
        body("rod", G2, F2, m2, i2),
        body("triangle", G3, F3, m3, i3),
        body("link_GE", G4, F4, m4, i4),
        body("link_AG", G5, F5, m5, i5),
        body("link_HE", G6, F6, m6, i6),
        body("link_AH", G7, F7, m7, i7),
    ]

    # loads: driving torque on the crank, linear spring between D and ground point C --
    r_CD = D.pos_from(C)
    L = sm.sqrt(r_CD.dot(N.x) ** 2 + r_CD.dot(N.y) ** 2)
    spring_force_on_D = -c0 * (L - l0) / L * r_CD
    loads = [(F1, mom * N.z), (D, spring_force_on_D)]

    # constraints: the three loops close at E --------------------------------------------
    pairs = [(E_rod, E_tri), (E_rod, E_g), (E_rod, E_h)]
    g = sm.Matrix([pa.pos_from(O).dot(ax) - pb.pos_from(O).dot(ax)
                   for pa, pb in pairs for ax in (N.x, N.y)])
    vel_con = sm.Matrix([pa.vel(N).dot(ax) - pb.vel(N).dot(ax)
                         for pa, pb in pairs for ax in (N.x, N.y)])

    kd = [qi.diff() - ui for qi, ui in zip(q, u)]
    kane = me.KanesMethod(
        N,
        q_ind=[beta], u_ind=[ube], kd_eqs=kd,
        q_dependent=q[1:], configuration_constraints=g,
        u_dependent=u[1:], velocity_constraints=vel_con,
        bodies=bodies, forcelist=loads,
    )
    kane.kanes_equations(bodies, loads)
    return kane, q, u, p, g, vel_con


# --------------------------------------------------------------------------------------
# derivation + lambdify
# --------------------------------------------------------------------------------------
@dataclass
class Derived:
    params: dict
    p_vals: np.ndarray
    q0: np.ndarray
    ref: np.ndarray
    mass: object          # (q, u, p) -> 7x7  kane.mass_matrix
    forcing: object       # (q, u, p) -> 7x1  kane.forcing
    vel_con_B: object     # (q, p) -> 6x7     velocity constraint matrix B(q) (B u = 0)
    constraints: object   # (q, p) -> 6x1     g(q)
    t_derive: float
    t_lambdify: float
    n_ops: dict = field(default_factory=dict)
    kane: object = None

    def u_full(self, q, u_ind):
        """All 7 speeds from the independent speed via the velocity constraints."""
        Bm = np.asarray(self.vel_con_B(q, self.p_vals), dtype=float)
        u_dep = np.linalg.solve(Bm[:, 1:], -Bm[:, :1] @ np.atleast_1d(u_ind))
        return np.concatenate([np.atleast_1d(u_ind), u_dep])

    def udot(self, q, u):
        """All 7 accelerations at (q, u) from Kane's eq. + differentiated vel. constraints."""
        M = np.asarray(self.mass(q, u, self.p_vals), dtype=float)
        f = np.asarray(self.forcing(q, u, self.p_vals), dtype=float).ravel()
        return np.linalg.solve(M, f)


def derive(verbose=False):
    """Derive the model with KanesMethod and lambdify (cse=True). Returns ``Derived``."""
    params, q0, ref, _ = load_reference()
    t0 = time.perf_counter()
    kane, q, u, p, g, vel_con = build_kane()
    M = kane.mass_matrix
    F = kane.forcing
    Bm, _rest = sm.linear_eq_to_matrix(list(vel_con), list(u))
    t_derive = time.perf_counter() - t0
    if verbose:
        print(f"  KanesMethod derivation: {t_derive:.2f} s")

    t0 = time.perf_counter()
    mass = sm.lambdify((q, u, p), M, modules="numpy", cse=True)
    forcing = sm.lambdify((q, u, p), F, modules="numpy", cse=True)
    vel_B = sm.lambdify((q, p), Bm, modules="numpy", cse=True)
    gfun = sm.lambdify((q, p), g, modules="numpy", cse=True)
    t_lambdify = time.perf_counter() - t0

    n_ops = {"mass_matrix": int(sm.count_ops(M)), "forcing": int(sm.count_ops(F))}
    p_vals = np.array([params[n] for n in PARAM_NAMES])
    return Derived(params, p_vals, q0, ref, mass, forcing, vel_B, gfun,
                   t_derive, t_lambdify, n_ops, kane)


def pydy_full(generator="cython"):
    """Kane's equations of :func:`build_kane` through pydy's code generator (Cython by
    default): ``(rhs(t, y), y0, build_seconds)`` for ``y = (q[7], u[7])`` with
    ``kane.mass_matrix_full`` / ``kane.forcing_full`` (the route of pydy's documentation,
    compiled; the 6 dependent speeds are integrated as states, so they drift like the
    coordinates). ``build_seconds``: derivation + generation + compilation, CPU incl. the
    compiler."""
    from pydy.codegen.ode_function_generators import generate_ode_function

    from .cpu_clock import cpu

    params, q0, _, _ = load_reference()
    pv = np.array([params[n] for n in PARAM_NAMES])
    c0 = cpu()
    kane, q, u, p, _, _ = build_kane()
    f = generate_ode_function(kane.forcing_full, q, u, p, mass_matrix=kane.mass_matrix_full, generator=generator,
                              constants_arg_type="array")
    build = cpu() - c0

    def rhs(t, y):  # a copy: pydy's generated function reuses its output array
        return np.array(f(y, t, pv))

    return rhs, np.concatenate([q0, np.zeros(7)]), build


# --------------------------------------------------------------------------------------
# integration
# --------------------------------------------------------------------------------------
def make_rhs(derived, states="q7u1"):
    """Return (rhs, y0, counter) for solve_ivp. counter[0] counts every RHS call,
    including the finite-difference Jacobian calls of implicit methods."""
    q0 = derived.q0
    counter = [0]
    if states == "q7u1":
        def rhs(t, y):
            counter[0] += 1
            qv = y[:7]
            uv = derived.u_full(qv, y[7:8])
            ud = derived.udot(qv, uv)
            out = np.empty(8)
            out[:7] = uv
            out[7] = ud[0]
            return out
        y0 = np.concatenate([q0, [0.0]])
    elif states == "q7u7":
        def rhs(t, y):
            counter[0] += 1
            qv, uv = y[:7], y[7:]
            return np.concatenate([uv, derived.udot(qv, uv)])
        y0 = np.concatenate([q0, np.zeros(7)])
    else:
        raise ValueError(states)
    return rhs, y0, counter


def simulate(derived, rtol, atol, method="Radau", t_end=0.03, states="q7u1"):
    """Integrate from the published consistent initial state (at rest) to t_end.

    Returns dict: q (name->value at t_end), cpu_s (process_time of solve_ivp only),
    nfev (solver's count), nrhs (all RHS calls incl. FD-Jacobian), njev, nlu, status,
    message, constraint_residual (max |g(q(t_end))|), max_rel_err (vs. reference,
    only if t_end == 0.03)."""
    rhs, y0, counter = make_rhs(derived, states)
    rhs(0.0, y0)  # warm-up (first call of lambdified functions)
    counter[0] = 0
    c0 = time.process_time()
    sol = solve_ivp(rhs, (0.0, t_end), y0, method=method, rtol=rtol, atol=atol,
                    dense_output=False, t_eval=None)
    cpu = time.process_time() - c0
    qend = sol.y[:7, -1]
    res = dict(
        q={n: float(v) for n, v in zip(COORD_NAMES, qend)},
        cpu_s=cpu, nfev=int(sol.nfev), nrhs=int(counter[0]), njev=int(sol.njev),
        nlu=int(sol.nlu), nsteps=int(len(sol.t) - 1), status=int(sol.status),
        message=sol.message,
        constraint_residual=float(np.max(np.abs(
            np.asarray(derived.constraints(qend, derived.p_vals), dtype=float)))),
    )
    if abs(t_end - 0.03) < 1e-15:
        res["max_rel_err"] = float(np.max(np.abs(qend - derived.ref) / np.abs(derived.ref)))
    return res


# --------------------------------------------------------------------------------------
# cross-checks
# --------------------------------------------------------------------------------------
def published_equations(pr):
    """The published M(q), f(q, qd), g(q), G(q) of the test set (for cross-checking only)."""
    P = type("P", (), pr)

    def M_f_g_G(q, qd):
        be, Th, ga, Ph, de, Om, ep = q
        bed, Thd, gad, Phd, ded, Omd, epd = qd
        c = np.cos
        s = np.sin
        M = np.zeros((7, 7), dtype=np.result_type(q, float))
        M[0, 0] = P.m1*P.ra**2 + P.m2*(P.rr**2 - 2*P.da*P.rr*c(Th) + P.da**2) + P.i1 + P.i2
        M[1, 0] = M[0, 1] = P.m2*(P.da**2 - P.da*P.rr*c(Th)) + P.i2
        M[1, 1] = P.m2*P.da**2 + P.i2
        M[2, 2] = P.m3*(P.sa**2 + P.sb**2) + P.i3
        M[3, 3] = P.m4*(P.e-P.ea)**2 + P.i4
        M[4, 3] = M[3, 4] = P.m4*((P.e-P.ea)**2 + P.zt*(P.e-P.ea)*s(Ph)) + P.i4
        M[4, 4] = (P.m4*(P.zt**2 + 2*P.zt*(P.e-P.ea)*s(Ph) + (P.e-P.ea)**2)
                   + P.m5*(P.ta**2 + P.tb**2) + P.i4 + P.i5)
        M[5, 5] = P.m6*(P.zf-P.fa)**2 + P.i6
        M[6, 5] = M[5, 6] = P.m6*((P.zf-P.fa)**2 - P.u*(P.zf-P.fa)*s(Om)) + P.i6
        M[6, 6] = (P.m6*((P.zf-P.fa)**2 - 2*P.u*(P.zf-P.fa)*s(Om) + P.u**2)
                   + P.m7*(P.ua**2 + P.ub**2) + P.i6 + P.i7)
        xd = P.sd*c(ga) + P.sc*s(ga) + P.xb
        yd = P.sd*s(ga) - P.sc*c(ga) + P.yb
        lang = np.sqrt((xd-P.xc)**2 + (yd-P.yc)**2)
        force = -P.c0*(lang - P.l0)/lang
        fx, fy = force*(xd-P.xc), force*(yd-P.yc)
        f = np.array([
            P.mom - P.m2*P.da*P.rr*Thd*(Thd + 2*bed)*s(Th),
            P.m2*P.da*P.rr*bed**2*s(Th),
            fx*(P.sc*c(ga) - P.sd*s(ga)) + fy*(P.sd*c(ga) + P.sc*s(ga)),
            P.m4*P.zt*(P.e-P.ea)*ded**2*c(Ph),
            -P.m4*P.zt*(P.e-P.ea)*Phd*(Phd + 2*ded)*c(Ph),
            -P.m6*P.u*(P.zf-P.fa)*epd**2*c(Om),
            P.m6*P.u*(P.zf-P.fa)*Omd*(Omd + 2*epd)*c(Om),
        ])
        r1 = P.rr*c(be) - P.d*c(be+Th)
        r2 = P.rr*s(be) - P.d*s(be+Th)
        g = np.array([
            r1 - P.ss*s(ga) - P.xb,
            r2 + P.ss*c(ga) - P.yb,
            r1 - P.e*s(Ph+de) - P.zt*c(de) - P.xa,
            r2 + P.e*c(Ph+de) - P.zt*s(de) - P.ya,
            r1 - P.zf*c(Om+ep) - P.u*s(ep) - P.xa,
            r2 - P.zf*s(Om+ep) + P.u*c(ep) - P.ya,
        ])
        G = np.zeros((6, 7), dtype=np.result_type(q, float))
        G11, G12 = -P.rr*s(be) + P.d*s(be+Th), P.d*s(be+Th)
        G21, G22 = P.rr*c(be) - P.d*c(be+Th), -P.d*c(be+Th)
        for k in (0, 2, 4):
            G[k, 0], G[k, 1] = G11, G12
            G[k+1, 0], G[k+1, 1] = G21, G22
        G[0, 2], G[1, 2] = -P.ss*c(ga), -P.ss*s(ga)
        G[2, 3], G[2, 4] = -P.e*c(Ph+de), -P.e*c(Ph+de) + P.zt*s(de)
        G[3, 3], G[3, 4] = -P.e*s(Ph+de), -P.e*s(Ph+de) - P.zt*c(de)
        G[4, 5], G[4, 6] = P.zf*s(Om+ep), P.zf*s(Om+ep) - P.u*c(ep)
        G[5, 5], G[5, 6] = -P.zf*c(Om+ep), -P.zf*c(Om+ep) - P.u*s(ep)
        return M, f, g, G
    return M_f_g_G


def check_initial_accelerations(derived):
    """Accelerations of the sympy model at the published initial state (at rest)."""
    _, _, _, data = load_reference()
    iv = data["initial_values_as_printed"]
    w_pub = np.array([float(iv[f"w_{n} (=d2{n}/dt2)"]) for n in COORD_NAMES])
    w = derived.udot(derived.q0, np.zeros(7))
    return w, w_pub


def check_against_published(derived, n_samples=5, seed=0):
    """Compare the sympy model's accelerations with the published DAE's at random
    consistent states (q on g=0 by Newton from a perturbed q0, qd in ker G).
    Returns max relative difference of the 7 accelerations."""
    pub = published_equations(derived.params)

    def pub_c(qc):
        return pub(qc, np.zeros(7))[3].imag
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(n_samples):
        qv = derived.q0.copy()
        qv[0] += rng.uniform(-3, 3)
        for _it in range(50):  # Newton on the 6 dependent coordinates
            _, _, g, G = pub(qv, np.zeros(7))
            dq = np.linalg.solve(G[:, 1:], -g)
            qv[1:] += dq
            if np.max(np.abs(dq)) < 1e-15:
                break
        uv = derived.u_full(qv, rng.uniform(-1000, 1000))
        w_sym = derived.udot(qv, uv)
        M, f, g, G = pub(qv, uv)
        # published DAE: M w = f - G^T lam,  G w = -(dG/dt) qd  (by finite differences)
        h = 1e-30  # complex-step derivative dG/dt = d/dh G(q + h qd), exact to rounding
        Gd = pub_c(qv + 1j*h*uv) / h
        K = np.block([[M, G.T], [G, np.zeros((6, 6))]])
        rhs = np.concatenate([f, -Gd @ uv])
        w_pub = np.linalg.solve(K, rhs)[:7]
        worst = max(worst, np.max(np.abs(w_sym - w_pub)) / np.max(np.abs(w_pub)))
    return worst


# --------------------------------------------------------------------------------------
def main():
    print("sympy", sm.__version__)
    print("Deriving Andrews' mechanism with sympy.physics.mechanics.KanesMethod ...")
    der = derive(verbose=True)
    print(f"derivation {der.t_derive:.2f} s, lambdify(cse=True) {der.t_lambdify:.2f} s, "
          f"total {der.t_derive + der.t_lambdify:.2f} s; count_ops {der.n_ops}")

    w, w_pub = check_initial_accelerations(der)
    print("initial accelerations (sympy model vs published):")
    for n, a, b in zip(COORD_NAMES, w, w_pub):
        print(f"  w_{n:8s} {a: .15e}  {b: .15e}")
    rel = abs(w[0] - w_pub[0]) / abs(w_pub[0]), abs(w[1] - w_pub[1]) / abs(w_pub[1])
    print(f"  rel. diff w_beta {rel[0]:.2e}, w_Theta {rel[1]:.2e}; "
          f"max |w_others| {np.max(np.abs(w[2:])):.2e}")
    print(f"  g(q0) residual {np.max(np.abs(der.constraints(der.q0, der.p_vals))):.2e}")
    print(f"  random consistent states, max rel. diff of accelerations vs published DAE: "
          f"{check_against_published(der):.2e}")

    print("\nTolerance sweep (atol = rtol), states = (q[7], u_beta), t_end = 0.03 s")
    hdr = (f"{'rtol':>7s} {'method':>7s} {'cpu_s':>8s} {'nfev':>7s} {'nrhs':>7s} "
           f"{'steps':>6s} {'max_rel_err':>11s} {'|g|_end':>9s} status")
    print(hdr)
    for method in ("Radau", "DOP853"):
        for k in range(4, 11):
            tol = 10.0 ** (-k)
            r = simulate(der, rtol=tol, atol=tol, method=method)
            print(f"{tol:7.0e} {method:>7s} {r['cpu_s']:8.3f} {r['nfev']:7d} {r['nrhs']:7d} "
                  f"{r['nsteps']:6d} {r.get('max_rel_err', np.nan):11.3e} "
                  f"{r['constraint_residual']:9.2e} {r['status']}")


if __name__ == "__main__":
    main()
