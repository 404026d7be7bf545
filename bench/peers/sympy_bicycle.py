"""sympy.physics.mechanics peer for the Whipple bicycle: KanesMethod + linearize + lambdify.

The model is the benchmark bicycle of J.P. Meijaard, J.M. Papadopoulos, A. Ruina, A.L. Schwab,
*Linearized dynamics equations for the balance and steer of a bicycle: a benchmark and review*,
Proc. R. Soc. A 463 (2007) 1955-1982 (the model of ``models/bicycle.py``), written the way a
sympy/PyDy user writes it. Parameters: Table 1 of the paper, read from
``models/data/bicycle_parameters.json`` (parsed here; nothing is imported from mbcomp).

Modelled: four rigid bodies in the paper's axes (x forward, y right, z down, gravity +g along
z): rear frame B with the rider, rear wheel R, front assembly H (fork + handlebar), front
wheel F; knife-edge wheels rolling without slip on flat level ground; frictionless hinges, no
rider input. Inertias are about each body's centre of mass in the axes of the upright
reference configuration.

How:

* coordinates: yaw ``q1`` (about z), roll ``q2`` (about the yawed x), pitch ``q3`` of the rear
  frame (about its y, measured from the upright reference, so ``q3 = 0`` upright; it is the
  dependent coordinate), rear-wheel angle ``q4``, steer ``q5`` (about the steer axis, tilted
  back by lambda and fixed in the rear frame; positive turns right), front-wheel angle ``q6``;
  generalized speeds ``u_i = q_i'``. The position of the rear contact point is ignorable and
  left out: the rear hub's velocity is set from rolling without slip of the rear wheel
  (``v_hub = rR Bf.z x w_R`` with ``Bf.z`` the roll frame's z, which lies in the wheel plane);
* the front contact point is found from the front hub as ``rF`` times the unit vector in the
  wheel plane pointing down (``Fy x (z x Fy)`` normalised); its height above the ground is the
  configuration constraint (solved for the pitch ``q3``), and the velocity of the front wheel's
  material point there (three components) gives the velocity constraints, solved for the
  yaw, pitch and front-wheel rates (``u1, u3, u6``); independent speeds roll, rear wheel and
  steer rate (``u2, u4, u5``);
* ``KanesMethod`` with ``q_dependent``/``configuration_constraints``/``u_dependent``/
  ``velocity_constraints`` and ``kanes_equations``; then ``KanesMethod.linearize(op_point=...,
  A_and_B=True)`` about upright straight running at forward speed ``v`` (all angles and the
  yaw, roll, pitch and steer rates zero, wheel rates ``-v/rR`` and ``-v/rF``, all accelerations
  zero) with ``v`` a symbol, then the rows and columns of roll, steer, roll rate and steer
  rate are taken from the 8x8 state matrix (yaw and the wheel angles are ignorable and the
  rear-wheel rate decouples at first order), and ``lambdify(cse=True)`` gives ``A(v)``.

Choices: the numeric parameter values are substituted when the model is built (sympy
``Float`` constants; only ``v`` stays symbolic, entering through the op point). Even so the
linearization is the slow step: ``Linearizer`` differentiates the unsimplified equations at
a general configuration, solves the constraint Jacobians symbolically (``C_0, C_1, C_2``) and
multiplies the blocks before it substitutes the op point. Measured on the benchmark machine
(2 cores, one process): derive ~8 s, linearize ~11 min (661 s), lambdify 0.02 s, one ``A(v)``
~2.5 us. Keeping the 25 parameters symbolic as well was not tried; it can only be slower.
``simplify`` is left off everywhere (sympy's default) and the default ``linear_solver='LU'``
is kept. One pitfall: that LU does not pivot on symbolic entries, so the velocity constraints
are ordered (lateral, vertical, forward) to give nonzero pivots for (yaw, pitch, front-wheel
rate) at the upright op point; the natural order (forward, lateral, vertical) gives a
Jacobian whose first pivot vanishes there, and the linearized matrix comes out all ``nan``
(after the full 13 minutes).

Check (``__main__``): ``A(v)`` agrees with the state matrix built from the paper's printed
``M, C1, K0, K2`` to 5e-13 at 5 m/s (3e-12 at 10 m/s); the weave and capsize speeds agree with
the printed matrices' own roots to 1e-13 m/s (weave 4.2923825363, 9e-8 above the published
4.292382445956, as the printed matrices are; capsize 6.0242620154, 4e-10 below 6.024262015827).

API: ``derive(path) -> Derived`` with ``states`` (``["roll", "steer", "roll_rate",
"steer_rate"]``), ``A`` (callable ``A(v) -> (4, 4)`` float array), and the wall-clock times
``t_derive`` (model + ``kanes_equations``), ``t_linearize`` (``linearize`` incl. the op-point
substitution and reduction to 4x4) and ``t_lambdify`` in s; ``speeds(derived, lo, hi) ->
(weave, capsize)`` in m/s by Brent's method on the largest real part of the eigenvalues.

Run ``python bench/peers/sympy_bicycle.py`` to derive, time and check against the paper.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import json  # noqa: E402
import pathlib  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parents[2] / "models" / "data" / "bicycle_parameters.json"
WEAVE_PUBLISHED, CAPSIZE_PUBLISHED = 4.292382445956, 6.024262015827  # m/s, the paper's Table 2


@dataclass
class Derived:
    states: list
    A: object
    t_derive: float
    t_linearize: float
    t_lambdify: float


def _value(text):
    """A Table 1 entry as a sympy number: a decimal or ``pi/k``."""
    import sympy as sp

    text = str(text).strip()
    if text.startswith("pi/"):
        return (sp.pi / int(text[3:])).evalf()
    return sp.Float(text)


def parameters(path=DATA):
    """Table 1 as a flat dict of sympy Floats: ``w, c, lam, g, rR, mR, IRxx, IRyy, xB, zB, mB,
    IBxx, IByy, IBzz, IBxz, xH, zH, mH, IHxx, IHyy, IHzz, IHxz, rF, mF, IFxx, IFyy``."""
    raw = json.loads(pathlib.Path(path).read_text())["parameters"]
    p = {"w": raw["w_m"], "c": raw["c_m"], "lam": raw["lambda_rad"], "g": raw["g_N_per_kg"]}
    for group in ("rear_wheel_R", "rear_body_B", "front_assembly_H", "front_wheel_F"):
        for key, val in raw[group].items():
            p[key.split("_")[0]] = val
    return {k: _value(v) for k, v in p.items()}


def _build(p):
    """The bicycle as a KanesMethod with ``kanes_equations`` done, and its op point at speed v."""
    import sympy as sp
    import sympy.physics.mechanics as me

    q1, q2, q3, q4, q5, q6 = q = me.dynamicsymbols("q1:7")
    u1, u2, u3, u4, u5, u6 = u = me.dynamicsymbols("u1:7")
    sin_lam, cos_lam = sp.sin(p["lam"]), sp.cos(p["lam"])

    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])  # yaw
    Bf = A.orientnew("Bf", "Axis", [q2, A.x])  # roll
    C = Bf.orientnew("C", "Axis", [q3, Bf.y])  # pitch: the rear frame B
    D = C.orientnew("D", "Axis", [q4, C.y])  # rear wheel R
    steer_axis = sin_lam * C.x + cos_lam * C.z  # downward along the steer axis, fixed in C
    E = C.orientnew("E", "Axis", [q5, steer_axis])  # front assembly H
    F = E.orientnew("F", "Axis", [q6, E.y])  # front wheel
    A.set_ang_vel(N, u1 * N.z)
    Bf.set_ang_vel(A, u2 * A.x)
    C.set_ang_vel(Bf, u3 * Bf.y)
    D.set_ang_vel(C, u4 * C.y)
    E.set_ang_vel(C, u5 * steer_axis)
    F.set_ang_vel(E, u6 * E.y)

    # Points; positions in the reference configuration (rear contact at the origin) are turned
    # into vectors fixed in the rear frame C (or in E for the front assembly).
    rR, rF, w, c = p["rR"], p["rF"], p["w"], p["c"]
    Do = me.Point("Do")  # rear hub, reference position (0, 0, -rR)
    Do.set_vel(N, rR * Bf.z.cross(D.ang_vel_in(N)))  # rear wheel rolls without slip
    Bo = Do.locatenew("Bo", p["xB"] * C.x + (p["zB"] + rR) * C.z)
    Bo.v2pt_theory(Do, N, C)
    s_x, s_z = w + c, 0  # where the steer axis meets the ground in the reference configuration
    S = Do.locatenew("S", s_x * C.x + (s_z + rR) * C.z)  # on the steer axis, fixed in C and E
    S.v2pt_theory(Do, N, C)
    Ho = S.locatenew("Ho", (p["xH"] - s_x) * E.x + (p["zH"] - s_z) * E.z)
    Ho.v2pt_theory(S, N, E)
    Fo = S.locatenew("Fo", (w - s_x) * E.x + (-rF - s_z) * E.z)  # front hub
    Fo.v2pt_theory(S, N, E)
    down = E.y.cross(N.z.cross(E.y))  # in the front wheel's plane, towards the ground
    Fn = Fo.locatenew("Fn", rF * down / sp.sqrt(down.dot(down)))  # front contact point
    Fn.v2pt_theory(Fo, N, F)  # the front wheel's material point there

    # Configuration constraint: the front contact is on the ground (height relative to the rear
    # contact, which is at Do + rR Bf.z). Velocity constraints: no slip at the front contact.
    holonomic = (Fn.pos_from(Do) - rR * Bf.z).dot(N.z)
    v_contact = Fn.vel(N)
    # Row order matters: sympy solves these for (u1, u3, u6) by LU without pivoting on the
    # general symbolic Jacobian; at the upright op point the forward row does not involve the
    # yaw rate, so putting it first gives 0/0 (nan) after substitution. Lateral row first.
    nonholonomic = [v_contact.dot(A.y), v_contact.dot(A.z), v_contact.dot(A.x)]

    bodies = [
        me.RigidBody("B", Bo, C, p["mB"],
                     (me.inertia(C, p["IBxx"], p["IByy"], p["IBzz"], 0, 0, p["IBxz"]), Bo)),
        me.RigidBody("R", Do, D, p["mR"], (me.inertia(D, p["IRxx"], p["IRyy"], p["IRxx"]), Do)),
        me.RigidBody("H", Ho, E, p["mH"],
                     (me.inertia(E, p["IHxx"], p["IHyy"], p["IHzz"], 0, 0, p["IHxz"]), Ho)),
        me.RigidBody("F", Fo, F, p["mF"], (me.inertia(F, p["IFxx"], p["IFyy"], p["IFxx"]), Fo)),
    ]
    loads = [(b.masscenter, b.mass * p["g"] * N.z) for b in bodies]

    km = me.KanesMethod(N, q_ind=[q1, q2, q4, q5, q6], u_ind=[u2, u4, u5],
                        kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)],
                        q_dependent=[q3], configuration_constraints=[holonomic],
                        u_dependent=[u1, u3, u6], velocity_constraints=nonholonomic)
    km.kanes_equations(bodies, loads)

    v = sp.Symbol("v")
    t = me.dynamicsymbols._t
    rates = {u4: -v / rR, u6: -v / rF}
    op_point = [{qi: 0 for qi in q},
                {ui: rates.get(ui, 0) for ui in u},
                {qi.diff(t): rates.get(ui, 0) for qi, ui in zip(q, u)},
                {ui.diff(t): 0 for ui in u}]
    return km, v, op_point, [q1, q2, q4, q5, q6, u2, u4, u5]


def derive(path=DATA):
    import sympy as sp

    p = parameters(path)
    t0 = time.perf_counter()
    km, v, op_point, x = _build(p)
    t_derive = time.perf_counter() - t0

    t0 = time.perf_counter()
    A_full, _, _ = km.linearize(op_point=op_point, A_and_B=True)  # x' = A x, x = [q_ind, u_ind]
    keep = [x.index(s) for s in (x[1], x[3], x[5], x[7])]  # roll q2, steer q5, u2, u5
    A4 = A_full.extract(keep, keep)
    t_linearize = time.perf_counter() - t0

    t0 = time.perf_counter()
    f = sp.lambdify([v], A4, modules="numpy", cse=True)
    t_lambdify = time.perf_counter() - t0

    def A(speed):
        return np.asarray(f(float(speed)), dtype=float)

    return Derived(["roll", "steer", "roll_rate", "steer_rate"], A, t_derive, t_linearize, t_lambdify)


def _max_real(A, v):
    return float(np.linalg.eigvals(A(v)).real.max())


def _roots(A, lo, hi, n=41):
    """Sign changes of the largest real part on an n-point grid, refined by Brent's method."""
    grid = np.linspace(lo, hi, n)
    vals = [_max_real(A, s) for s in grid]
    roots = []
    for a, b, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
        if fa == 0.0:
            roots.append(float(a))
        elif fa * fb < 0:
            roots.append(brentq(lambda s: _max_real(A, s), a, b, xtol=1e-14, rtol=1e-15))
    return roots


def speeds(derived, lo=0.0, hi=10.0):
    """(weave, capsize) speeds in m/s: where the largest real part of the eigenvalues of A(v)
    falls through 0 (weave) and rises through 0 again (capsize)."""
    A = derived.A if hasattr(derived, "A") else derived
    lo = max(lo, 1e-3)  # v = 0 is a double root of the capsize/castering modes; step off it
    roots = _roots(A, lo, hi)
    falls = [r for r in roots if _max_real(A, r + 1e-6) < 0]
    rises = [r for r in roots if _max_real(A, r + 1e-6) > 0]
    if not falls or not rises:
        raise ValueError(f"no stable speed range found in [{lo}, {hi}] (roots {roots})")
    weave = falls[0]
    capsize = min(r for r in rises if r > weave)
    return weave, capsize


def _printed_A(v, g=9.81):
    M = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
    C1 = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
    K0 = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
    K2 = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ (g * K0 + v * v * K2), -v * Minv @ C1]])


if __name__ == "__main__":
    d = derive()
    print(f"derive     {d.t_derive:8.2f} s  (model + kanes_equations)")
    print(f"linearize  {d.t_linearize:8.2f} s  (KanesMethod.linearize, op point, 4x4)")
    print(f"lambdify   {d.t_lambdify:8.2f} s")
    d.A(5.0)
    n = 1000
    t0 = time.perf_counter()
    for _ in range(n):
        d.A(5.0)
    print(f"A(v)       {(time.perf_counter() - t0) / n * 1e6:8.1f} us per evaluation")
    np.set_printoptions(precision=12, linewidth=120)
    A5 = d.A(5.0)
    print("A(5) =\n", A5)
    print(f"max |A(5) - A_printed(5)| = {np.abs(A5 - _printed_A(5.0)).max():.3e}")
    for s in (0.0, 2.0, 4.0, 6.0, 8.0, 10.0):
        print(f"  v = {s:4.1f}: max |A - A_printed| = {np.abs(d.A(s) - _printed_A(s)).max():.3e}")
    ev = np.linalg.eigvals(A5)
    print("eigenvalues at 5 m/s:", np.sort_complex(ev))
    weave, capsize = speeds(d)
    pw, pc = speeds(_printed_A)
    print(f"weave   {weave:.12f} m/s  (published {WEAVE_PUBLISHED}: {weave - WEAVE_PUBLISHED:+.2e};"
          f" printed-matrix root {pw:.12f}: {weave - pw:+.2e})")
    print(f"capsize {capsize:.12f} m/s  (published {CAPSIZE_PUBLISHED}: {capsize - CAPSIZE_PUBLISHED:+.2e};"
          f" printed-matrix root {pc:.12f}: {capsize - pc:+.2e})")
