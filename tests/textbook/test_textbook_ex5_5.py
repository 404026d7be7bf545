"""Seed Example 5.5: two spring-loaded sliders in a rotating slotted disk (D'Alembert).

The model (``models/textbook/ex5_5_slotted_disk.py``) is built from a revolute, two
prismatic joints, two point masses and two translational springs on the slot flanges. It is
checked against

* the book's equations (5.35), (5.37), (5.39), integrated independently with scipy;
* the same equations derived here by Lagrange in sympy (also for a disk with inertia ``J``,
  which the book's massless disk leaves out);
* conservation of the angular momentum (5.40) and of the energy;
* a driven disk at constant rate: then (5.35) and (5.37) are linear oscillators with a closed
  form, and the drive torque is ``dH/dt``.

Book notes: (5.35) and (5.37) print the spring rate as ``K`` (it is ``k``, eqs. 5.32-5.33);
(5.39) lost its brackets in print and reads, from (5.38),
``m1 (rho1 theta'' + 2 rho1' theta') rho1 + m2 (rho2 theta'' + 2 rho2' theta') rho2 = 0``.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex5_5_slotted_disk.py")
M1, M2, K, A = 1.0, 1.5, 40.0, 0.2
Y0 = dict(rho1_0=0.3, rho1_dot0=0.0, rho2_0=0.15, rho2_dot0=0.2, theta0=0.0, theta_dot0=4.0)
T_END = 3.0
TOL = dict(rtol=1e-11, atol=1e-12)


# ---------------------------------------------------------------- independent references
def book_rhs(t, y, m1=M1, m2=M2, k=K, a=A):
    """(5.35), (5.37), (5.39) solved for the accelerations; y = (rho1, rho2, theta, rates)."""
    r1, r2, th, r1d, r2d, thd = y
    r1dd = thd ** 2 * r1 - k / m1 * (r1 - a)  # (5.35)
    r2dd = thd ** 2 * r2 - k / m2 * (r2 - a)  # (5.37)
    thdd = -2 * thd * (m1 * r1 * r1d + m2 * r2 * r2d) / (m1 * r1 ** 2 + m2 * r2 ** 2)  # (5.39)
    return [r1d, r2d, thd, r1dd, r2dd, thdd]


def lagrange_equations():
    """Lagrange's equations for the sliders and a disk of inertia J, derived with sympy.

    Returns the symbols, the list of equations (expressions = 0) in (rho1, rho2, theta) order,
    and the symbols of the coordinates as functions of time.
    """
    t = sp.Symbol("t")
    m1, m2, k, a, J = sp.symbols("m1 m2 k a J", positive=True)
    r1, r2, th = (sp.Function(n)(t) for n in ("rho1", "rho2", "theta"))
    # positions in the plane: r1 = rho1 e_r, r2 = -rho2 e_r with e_r = (cos th, sin th)
    er = sp.Matrix([sp.cos(th), sp.sin(th)])
    v1, v2 = (r1 * er).diff(t), (-r2 * er).diff(t)
    T = (m1 * v1.dot(v1) + m2 * v2.dot(v2) + J * th.diff(t) ** 2) / 2
    V = k * (r1 - a) ** 2 / 2 + k * (r2 - a) ** 2 / 2
    Lag = T - V
    eqs = [sp.simplify(Lag.diff(q.diff(t)).diff(t) - Lag.diff(q)) for q in (r1, r2, th)]
    return (t, m1, m2, k, a, J), eqs, (r1, r2, th)


@pytest.fixture(scope="module")
def lagrange():
    return lagrange_equations()


def test_book_equations_are_lagrange_equations(lagrange):
    (t, m1, m2, k, a, J), eqs, (r1, r2, th) = lagrange
    d, dd = (lambda f: f.diff(t)), (lambda f: f.diff(t, 2))
    book = [
        m1 * (dd(r1) - d(th) ** 2 * r1) + k * (r1 - a),                           # (5.35), K = k
        m2 * (dd(r2) - d(th) ** 2 * r2) + k * (r2 - a),                           # (5.37), K = k
        m1 * (r1 * dd(th) + 2 * d(r1) * d(th)) * r1 + m2 * (r2 * dd(th) + 2 * d(r2) * d(th)) * r2,  # (5.39)
    ]
    for lag, bk in zip(eqs, book):
        assert sp.simplify(lag.subs(J, 0) - bk) == 0
    # (5.40): the theta equation is the rate of the angular momentum about O
    H = (m1 * r1 ** 2 + m2 * r2 ** 2 + J * 1) * d(th)
    assert sp.simplify(eqs[2] - H.diff(t)) == 0


def lagrange_rhs(lagrange, J_value):
    """Accelerations from the sympy Lagrange equations with disk inertia J (numerical function)."""
    (t, m1, m2, k, a, J), eqs, qs = lagrange
    q = sp.symbols("q0:3")
    qd = sp.symbols("qd0:3")
    qdd = sp.symbols("qdd0:3")
    rep = {}
    for i, f in enumerate(qs):
        rep[f.diff(t, 2)] = qdd[i]
    for i, f in enumerate(qs):
        rep[f.diff(t)] = qd[i]
    for i, f in enumerate(qs):
        rep[f] = q[i]
    E = [e.subs(rep).subs({m1: M1, m2: M2, k: K, a: A, J: J_value}) for e in eqs]
    Mm, rhs = sp.linear_eq_to_matrix(E, qdd)
    acc = sp.lambdify((q, qd), Mm.LUsolve(rhs), "numpy")

    def f(tt, y):
        return np.concatenate((y[3:], np.asarray(acc(y[:3], y[3:]), dtype=float).ravel()))

    return f


def momentum(r, J=0.0):
    """Angular momentum about O (5.40), kg m^2/s."""
    return (J + M1 * r["rho1"] ** 2 + M2 * r["rho2"] ** 2) * r["theta_dot"]


def book_energy(r, J=0.0):
    T = 0.5 * (M1 * (r["rho1_dot"] ** 2 + (r["rho1"] * r["theta_dot"]) ** 2)
               + M2 * (r["rho2_dot"] ** 2 + (r["rho2"] * r["theta_dot"]) ** 2) + J * r["theta_dot"] ** 2)
    V = 0.5 * K * ((r["rho1"] - A) ** 2 + (r["rho2"] - A) ** 2)
    return T + V


def reference(rhs, r):
    y0 = [Y0["rho1_0"], Y0["rho2_0"], Y0["theta0"], Y0["rho1_dot0"], Y0["rho2_dot0"], Y0["theta_dot0"]]
    sol = solve_ivp(rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=r.time)
    assert sol.success
    return sol.y


# ---------------------------------------------------------------- the book's free, massless disk
@pytest.fixture(scope="module")
def free():
    r = mbcomp.simulate(MOD.build(**Y0), t_end=T_END, n_out=601, **TOL)
    assert r.success, r.message
    return r


def test_summary_three_dof():
    text = mbcomp.assemble(MOD.build()).summary()
    assert "degrees of freedom: 3 " in text


def test_free_disk_matches_eqs_5_35_5_37_5_39(free):
    r1, r2, th, r1d, r2d, thd = reference(book_rhs, free)
    # the motion is strongly coupled: the disk rate changes by a factor > 1.5 as the sliders move
    assert thd.max() / thd.min() > 1.5 and np.ptp(r1) > 0.1
    for name, ref in (("rho1", r1), ("rho2", r2), ("theta", th),
                      ("rho1_dot", r1d), ("rho2_dot", r2d), ("theta_dot", thd)):
        np.testing.assert_allclose(free[name], ref, rtol=0, atol=1e-9, err_msg=name)


def test_angular_momentum_5_40_is_conserved(free):
    H = momentum(free)
    assert np.abs(H - H[0]).max() < 1e-9 * abs(H[0])


def test_energy_is_conserved_and_equals_book_energy(free):
    E = free["energy.total"]
    # gravity is normal to the disk: mbcomp's potential is only the springs' (sliders at z = 0)
    np.testing.assert_allclose(E, book_energy(free), rtol=0, atol=1e-12)
    assert np.abs(E - E[0]).max() < 1e-9 * E[0]


def test_slot_reaction_is_coriolis_and_angular_acceleration(free):
    """The slot pushes slider 1 along e_theta with m1 (rho1 theta'' + 2 rho1' theta') (5.30)."""
    thdd = free["disk_hinge.w.der"]
    f_theta = M1 * (free["rho1"] * thdd + 2 * free["rho1_dot"] * free["theta_dot"])
    # slot1's frame_b has the disk's axes; e_theta is +y there
    np.testing.assert_allclose(free["slot1.f.y"], f_theta, rtol=0, atol=1e-7)


# ---------------------------------------------------------------- a disk with inertia (extension)
def test_disk_with_inertia_matches_sympy_lagrange(lagrange):
    J = 0.05
    r = mbcomp.simulate(MOD.build(J=J, **Y0), t_end=T_END, n_out=301, **TOL)
    assert r.success, r.message
    r1, r2, th, r1d, r2d, thd = reference(lagrange_rhs(lagrange, J), r)
    np.testing.assert_allclose(r["rho1"], r1, rtol=0, atol=2e-8)
    np.testing.assert_allclose(r["rho2"], r2, rtol=0, atol=2e-8)
    np.testing.assert_allclose(r["theta_dot"], thd, rtol=0, atol=2e-8)
    H = momentum(r, J)
    assert np.abs(H - H[0]).max() < 1e-9 * abs(H[0])
    # without J in H the "momentum" would not be conserved: the disk takes part
    assert np.ptp(momentum(r, 0.0)) > 1e-2 * abs(H[0])


# ---------------------------------------------------------------- driven disk (extension)
def test_driven_disk_closed_form_and_drive_torque():
    omega = 3.0
    r = mbcomp.simulate(MOD.build(omega=omega, **Y0), t_end=T_END, n_out=301, **TOL)
    assert r.success, r.message
    t = r.time
    np.testing.assert_allclose(r["theta"], Y0["theta0"] + omega * t, rtol=0, atol=1e-12)
    # (5.35)/(5.37) with theta' = omega: m rho'' + (k - m omega^2) rho = k a
    for m, name, s0, v0 in ((M1, "rho1", Y0["rho1_0"], Y0["rho1_dot0"]), (M2, "rho2", Y0["rho2_0"], Y0["rho2_dot0"])):
        nu = np.sqrt(K / m - omega ** 2)
        rho_eq = K * A / (K - m * omega ** 2)
        exact = rho_eq + (s0 - rho_eq) * np.cos(nu * t) + v0 / nu * np.sin(nu * t)
        np.testing.assert_allclose(r[name], exact, rtol=0, atol=1e-9, err_msg=name)
    # the drive supplies dH/dt = 2 omega (m1 rho1 rho1' + m2 rho2 rho2')
    tau = 2 * omega * (M1 * r["rho1"] * r["rho1_dot"] + M2 * r["rho2"] * r["rho2_dot"])
    assert np.ptp(tau) > 0.5
    np.testing.assert_allclose(r["drive.tau"], tau, rtol=0, atol=1e-8)
    np.testing.assert_allclose(r["disk_hinge.tau.z"], tau, rtol=0, atol=1e-8)
