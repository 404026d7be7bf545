"""Seed Example 3.1: pendulum on a massless cart with prescribed motion u(t) (eqs. 3.12-3.20).

Model: ``models/textbook/ex3_1_pendulum_cart.py`` (Prismatic cart driven by PrescribedMotion,
u = A sin(Omega t); rod on a Revolute about z; gravity -y). The hinge angle phi is the
book's theta in the convention of its unit vectors (3.16): e_r = sin th e_x - cos th e_y
points from the hinge to the rod's centre of mass, so theta > 0 swings the rod towards +x.

Book errors found (settled by the Newton-Euler derivation with the book's own unit vectors in
``test_book_equations_from_newton_euler_in_3_16_convention``, by an independent Lagrange
derivation, and by the simulation):

- (3.18) is printed with ``+ m L/2 u'' cos th`` on the right; with the unit vectors of (3.16)
  it must be ``- m L/2 u'' cos th``: a cart accelerating towards +x pushes the hinge forward
  and the rod is left behind (theta'' < 0). The printed (3.18) is the equation of motion for
  the mirrored angle -theta; the model matches it in that form (``test_printed_3_18_...``).
  In one and the same convention, printed (3.18) and (3.19) cannot both hold: (3.19) holds
  for theta of (3.16) and fails for -theta (its u'' sin th term changes sign).
- (3.15) ``L/2 F_th = Ic th''`` has the wrong sign: the hinge force F_th e_th acts at
  -L/2 e_r from the centre of mass, its moment is -L/2 F_th e_z. (3.20)
  ``F_th = -2 Ic th''/L`` is the correct one (it contradicts the printed 3.15).
- (3.14) writes the hinge force as ``Fr e_r + F_th e_th`` but (3.17)/(3.19) treat ``Fr`` as
  the tension, i.e. the force on the rod along ``-e_r`` (Fr = m g at rest). With that reading
  (3.19) is right.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import cumulative_simpson, solve_ivp

import mbcomp
from conftest import load_model

MODEL = load_model("models/textbook/ex3_1_pendulum_cart.py")

M, L, G = 1.4, 0.8, 9.81
IC = M * L ** 2 / 12.0
A, OMEGA = 0.2, 6.0
TH0, THD0 = 0.3, -0.5
T_END = 5.0
PARAMS = dict(m=M, L=L, g=G, A=A, Omega=OMEGA, theta0=TH0, theta_dot0=THD0)


def u(t):
    return A * np.sin(OMEGA * t)


def ud(t):
    return A * OMEGA * np.cos(OMEGA * t)


def udd(t):
    return -A * OMEGA ** 2 * np.sin(OMEGA * t)


def printed_3_18(t, y):
    """(Ic + m L^2/4) th'' + m g L/2 sin th = + m L/2 u'' cos th, exactly as printed."""
    th, thd = y
    return [thd, (M * L / 2 * udd(t) * np.cos(th) - M * G * L / 2 * np.sin(th)) / (IC + M * L ** 2 / 4)]


def corrected_3_18(t, y):
    """(3.18) in the convention of (3.16): right-hand side -m L/2 u'' cos th."""
    th, thd = y
    return [thd, -(M * L / 2 * udd(t) * np.cos(th) + M * G * L / 2 * np.sin(th)) / (IC + M * L ** 2 / 4)]


def integrate(rhs, y0, t_eval):
    sol = solve_ivp(rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=t_eval)
    assert sol.success
    return sol.y


@pytest.fixture(scope="module", params=[False, True], ids=["no_cart_body", "massless_cart_body"])
def result(request):
    r = mbcomp.simulate(MODEL.build(cart_body=request.param, **PARAMS), t_end=T_END, rtol=1e-11, atol=1e-12,
                        method="DOP853", n_out=501)
    assert r.success, r.message
    return r


def test_summary_reports_prescribed_joint_eliminated():
    system = mbcomp.assemble(MODEL.build(**PARAMS))
    text = system.summary()
    # Gruebler: cart frame + rod, 5 + 5 joint constraints, one prescribed motion: 12 - 10 - 1 = 1
    assert "degrees of freedom: 1   (Gruebler M = 6N - C - L = 6*2 - 10 - 1 = 1)" in text
    assert "prescribed (eliminated, rheonomic): cart by drive" in text
    assert "tree joints (minimal coordinates): hinge" in text
    assert system.nu == 1 and list(system.q_names) == ["hinge.phi"]


def test_cart_follows_prescribed_motion(result):
    t = result.time
    np.testing.assert_allclose(result["u"], u(t), rtol=0, atol=1e-14)
    np.testing.assert_allclose(result["cart.v"], ud(t), rtol=0, atol=1e-13)


def test_book_equations_from_newton_euler_in_3_16_convention():
    """Redo the book's derivation symbolically with its own unit vectors (3.16) and the
    hinge force written as in (3.14), P e_r + Q e_th: Newton for the centre of mass, Euler
    about it. Result: (3.18) needs -m L/2 u'' cos th, (3.19) is -P (the tension), (3.20) is Q,
    and (3.15) as printed is off by a sign."""
    t = sp.Symbol("t")
    m, Lr, g, Ic = sp.symbols("m L g I_c", positive=True)
    th = sp.Function("theta")(t)
    uu = sp.Function("u")(t)
    P, Q, thdd = sp.symbols("P Q thdd")
    ex, ey, ez = sp.Matrix([1, 0, 0]), sp.Matrix([0, 1, 0]), sp.Matrix([0, 0, 1])
    # invert (3.16): e_x = sin th e_r + cos th e_th, e_y = -cos th e_r + sin th e_th
    er = sp.sin(th) * ex - sp.cos(th) * ey
    eth = sp.cos(th) * ex + sp.sin(th) * ey
    assert sp.simplify(sp.sin(th) * er + sp.cos(th) * eth - ex) == sp.zeros(3, 1)
    assert sp.simplify(-sp.cos(th) * er + sp.sin(th) * eth - ey) == sp.zeros(3, 1)
    assert sp.simplify(er.cross(eth) - ez) == sp.zeros(3, 1)  # theta is counter-clockwise about e_z
    rc = uu * ex + Lr / 2 * er
    ac = rc.diff(t, 2).subs(th.diff(t, 2), thdd)
    F = P * er + Q * eth
    newton = F - m * g * ey - m * ac
    euler = (-Lr / 2 * er).cross(F)[2] - Ic * thdd
    sol = sp.solve([newton.dot(er), newton.dot(eth), euler], [P, Q, thdd], dict=True)[0]
    thd, ud2 = th.diff(t), uu.diff(t, 2)
    corrected = -(m * Lr / 2 * ud2 * sp.cos(th) + m * g * Lr / 2 * sp.sin(th)) / (Ic + m * Lr ** 2 / 4)
    printed = (m * Lr / 2 * ud2 * sp.cos(th) - m * g * Lr / 2 * sp.sin(th)) / (Ic + m * Lr ** 2 / 4)
    assert sp.simplify(sol[thdd] - corrected) == 0
    assert sp.simplify(sol[thdd] - printed) != 0
    # (3.19): Fr = m L/2 th'^2 + m g cos th - m u'' sin th is the tension -P
    assert sp.simplify(-sol[P] - (m * Lr / 2 * thd ** 2 + m * g * sp.cos(th) - m * ud2 * sp.sin(th))) == 0
    # (3.20): F_th = -2 Ic th''/L is right; printed (3.15) L/2 F_th = Ic th'' is not
    assert sp.simplify(sol[Q] - (-2 * Ic * sol[thdd] / Lr)) == 0
    assert sp.simplify(Lr / 2 * sol[Q] + Ic * sol[thdd]) == 0


def test_lagrange_equation_in_phi():
    """Independent Lagrange derivation in the model's own coordinate phi (no book input):
    it is the corrected (3.18)."""
    t = sp.Symbol("t")
    m, Lr, g, Ic = sp.symbols("m L g I_c", positive=True)
    phi = sp.Function("phi")(t)
    uu = sp.Function("u")(t)
    x = uu + Lr / 2 * sp.sin(phi)
    y = -Lr / 2 * sp.cos(phi)
    T = m / 2 * (x.diff(t) ** 2 + y.diff(t) ** 2) + Ic / 2 * phi.diff(t) ** 2
    Lag = T - m * g * y
    eom = sp.diff(Lag.diff(phi.diff(t)), t) - Lag.diff(phi)
    a = sp.solve(eom, phi.diff(t, 2))[0]
    corrected = -(m * Lr / 2 * uu.diff(t, 2) * sp.cos(phi) + m * g * Lr / 2 * sp.sin(phi)) / (Ic + m * Lr ** 2 / 4)
    assert sp.simplify(a - corrected) == 0


def test_theta_matches_corrected_3_18(result):
    th, thd = integrate(corrected_3_18, [TH0, THD0], result.time)
    assert np.ptp(th) > 0.5  # a large, driven swing
    np.testing.assert_allclose(result["theta"], th, rtol=0, atol=1e-9)
    np.testing.assert_allclose(result["hinge.w"], thd, rtol=0, atol=1e-9)
    # and the accelerations satisfy it at every output point
    t = result.time
    rhs = corrected_3_18(t, [result["theta"], result["hinge.w"]])[1]
    np.testing.assert_allclose(result["hinge.w.der"], rhs, rtol=0, atol=1e-8)


def test_printed_3_18_holds_for_the_mirrored_angle_only(result):
    """The printed (3.18) describes -theta: it matches the model with theta -> -phi, and
    departs from it by far in the convention of (3.16)."""
    th_m, thd_m = integrate(printed_3_18, [-TH0, -THD0], result.time)
    np.testing.assert_allclose(-result["theta"], th_m, rtol=0, atol=1e-9)
    np.testing.assert_allclose(-result["hinge.w"], thd_m, rtol=0, atol=1e-9)
    th_p, _ = integrate(printed_3_18, [TH0, THD0], result.time)
    assert np.abs(th_p - result["theta"]).max() > 0.3


def test_reactions_match_3_19_and_3_20(result):
    """hinge.f is the force on the rod at the hinge, resolved in the rod frame: its x axis is
    e_th = (cos th, sin th), its y axis is -e_r = (-sin th, cos th). So hinge.f.y is the
    book's tension Fr (3.19) and hinge.f.x is F_th (3.20). The torque at the hinge is zero."""
    t, th, w, a = result.time, result["theta"], result["hinge.w"], result["hinge.w.der"]
    Fr = M * L / 2 * w ** 2 + M * G * np.cos(th) - M * udd(t) * np.sin(th)  # (3.19)
    Fth = -2 * IC * a / L  # (3.20)
    scale = np.abs(Fr).max()
    assert scale > M * G and np.abs(Fth).max() > 0.1 * scale  # both non-trivial
    np.testing.assert_allclose(result["F_r"], Fr, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(result["F_theta"], Fth, rtol=0, atol=1e-9 * scale)
    for k in ("hinge.f.z", "hinge.tau.x", "hinge.tau.y", "hinge.tau.z"):
        assert np.abs(result[k]).max() < 1e-9 * scale
    # the massless cart passes the hinge force to the floor (y) and the drive (x); the cart's
    # frame_b does not rotate, so its reaction resolved in frame_b is in world axes
    Fx = Fth * np.cos(th) - Fr * np.sin(th)
    Fy = Fth * np.sin(th) + Fr * np.cos(th)
    np.testing.assert_allclose(result["F_drive"], Fx, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(result["cart.f.x"], Fx, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(result["cart.f.y"], Fy, rtol=0, atol=1e-9 * scale)


def test_drive_force_is_newton_for_the_rod(result):
    """Independently of the book: f = m x_cm'' with x_cm = u + L/2 sin th."""
    t, th, w, a = result.time, result["theta"], result["hinge.w"], result["hinge.w.der"]
    xcm_dd = udd(t) + L / 2 * (a * np.cos(th) - w ** 2 * np.sin(th))
    ycm_dd = L / 2 * (a * np.sin(th) + w ** 2 * np.cos(th))
    scale = np.abs(M * xcm_dd).max()
    assert scale > 1.0
    np.testing.assert_allclose(result["drive.f"], M * xcm_dd, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(result["cart.f.y"], M * (ycm_dd + G), rtol=0, atol=1e-9 * scale)


def test_energy_balance_with_drive_power(result):
    """The energy of the rod on the moving cart changes by the drive's work:
    E(t) - E(0) = int f u' dt (Simpson's rule on the output grid)."""
    t, th, w, v = result.time, result["theta"], result["hinge.w"], result["cart.v"]
    T = 0.5 * M * (v ** 2 + L * v * w * np.cos(th) + L ** 2 / 4 * w ** 2) + 0.5 * IC * w ** 2
    V = -M * G * L / 2 * np.cos(th)
    E = result["energy.total"]
    np.testing.assert_allclose(E, T + V, rtol=0, atol=1e-10)
    work = cumulative_simpson(result["drive.f"] * v, x=t, initial=0.0)
    assert np.ptp(E) > 1.0  # the drive pumps energy in and out
    np.testing.assert_allclose(E - E[0], work, rtol=0, atol=2e-4)
