"""Seed Example 6.5: the pendulum's rod tension from the Lagrange multiplier.

(6.79): lambda = m l thetadot^2 + m g cos(theta) along the whole trajectory, and (6.80) is the
pendulum equation (6.20). The model ``models/textbook/ex6_5_pendulum.py`` imposes ``r = l``
three ways (see its docstring): as a loop-closure constraint with a genuine multiplier
(``rod="constraint"``, the book's construction), as a prescribed radial motion
(``"prescribed"``), and as a rigid rod (``"rigid"``, the test formerly in
``tests/test_pendulum.py``, whose assertions are kept). The test also derives (6.76), (6.77),
(6.79), (6.80) from the book's T and V by Lagrange in sympy.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex6_5_pendulum.py")
M, L, G, TH0 = 1.3, 0.8, 9.81, 1.2
T_END = 3.0


def pendulum(m=M, l=L, theta0=TH0, rod="rigid"):
    return MOD.build(m=m, l=l, g=G, theta0=theta0, rod=rod)


def tension(r, m=M, l=L, g=G):
    """(6.79) evaluated on the simulated trajectory."""
    return m * l * r["theta_dot"] ** 2 + m * g * np.cos(r["theta"])


def test_multiplier_equations_from_lagrange():
    """(6.76)/(6.77) from T, V of Fig. 6.7 with the multiplier term, then r = l gives (6.79), (6.80)."""
    t = sp.Symbol("t")
    m, l, g, lam = sp.symbols("m l g lambda")
    r, th = sp.Function("r")(t), sp.Function("theta")(t)
    T = m * (r.diff(t) ** 2 + r ** 2 * th.diff(t) ** 2) / 2
    V = -m * g * r * sp.cos(th)
    Lag = T - V
    # (6.69) with the constraint r - l = 0 (a_r = 1, a_theta = 0): + lambda in the r equation
    eq_r = Lag.diff(r.diff(t)).diff(t) - Lag.diff(r) + lam
    eq_th = Lag.diff(th.diff(t)).diff(t) - Lag.diff(th)
    assert sp.simplify(eq_r - (m * r.diff(t, 2) - m * r * th.diff(t) ** 2 - m * g * sp.cos(th) + lam)) == 0  # (6.76)
    assert sp.simplify(eq_th - ((m * r ** 2 * th.diff(t)).diff(t) + m * g * r * sp.sin(th))) == 0  # (6.77)
    on = {r.diff(t, 2): 0, r.diff(t): 0}
    lam_sol = sp.solve(eq_r.subs(on).subs(r, l), lam)[0]
    assert sp.simplify(lam_sol - (m * l * th.diff(t) ** 2 + m * g * sp.cos(th))) == 0  # (6.79)
    assert sp.simplify(eq_th.subs(on).subs(r, l) - (m * l ** 2 * th.diff(t, 2) + m * g * l * sp.sin(th))) == 0  # (6.80)


def test_constraint_version_cuts_the_pin():
    """r = l is the pin's loop closure: 2 independent rows (the planar loop drops pin.z), 1 DOF."""
    text = mbcomp.assemble(pendulum(rod="constraint")).summary()
    assert "degrees of freedom: 1 " in text
    assert "cut joints (loop closure): pin; 3 constraint rows, rank 2" in text
    assert "redundant constraint rows dropped: pin.z" in text


# ------------------------------------------------------------------ rigid rod (former test_pendulum.py)
def test_rod_tension_equals_eq_6_79():
    m, l, g = 1.3, 0.8, 9.81
    r = mbcomp.simulate(pendulum(m, l), t_end=3.0, rtol=1e-10, atol=1e-12)
    assert r.success
    th, w = r["hinge.phi"], r["hinge.w"]
    tension = m * l * w ** 2 + m * g * np.cos(th)
    # The reaction on frame_b (which rotates with the pendulum) along +y_b points from the
    # bob to the hinge: it is the rod tension.
    np.testing.assert_allclose(r["hinge.f.y"], tension, rtol=1e-8, atol=1e-8)
    # a free hinge transmits no torque about its axis
    assert np.abs(r["hinge.tau.z"]).max() < 1e-9


# ------------------------------------------------------------------ the book's (r, theta) with r = l
@pytest.fixture(scope="module", params=["constraint", "prescribed", "rigid"])
def result(request):
    r = mbcomp.simulate(pendulum(rod=request.param), t_end=T_END, rtol=1e-10, atol=1e-12, n_out=301)
    assert r.success, r.message
    r.rod = request.param
    return r


def test_theta_follows_eq_6_80(result):
    sol = solve_ivp(lambda t, y: [y[1], -G / L * np.sin(y[0])], (0, T_END), [TH0, 0.0], method="DOP853",
                    rtol=1e-13, atol=1e-14, t_eval=result.time)
    np.testing.assert_allclose(result["theta"], sol.y[0], rtol=0, atol=1e-8)
    np.testing.assert_allclose(result["theta_dot"], sol.y[1], rtol=0, atol=1e-8)


def test_multiplier_is_the_tension_6_79(result):
    lam = tension(result)
    assert lam.min() < 0.5 * lam.max()  # the tension varies strongly over a swing of +-1.2 rad
    if result.rod == "constraint":
        # the multiplier of the pin's row along the rod (+y of the rod frame, bob -> hinge):
        # the constraint force on the bob is -C^T lambda = -lambda_y y_rod, so lambda_y = -lambda
        np.testing.assert_allclose(-result["lambda.pin.y"], lam, rtol=1e-8, atol=1e-8)
        # the row across the rod carries nothing: a massless rod on a hinge takes only axial load
        assert np.abs(result["lambda.pin.x"]).max() < 1e-8
        # the constraint r = l holds, and the rod's own hinge follows theta
        assert np.abs(result["r"] - L).max() < 1e-10
        assert np.abs(result["rod_hinge.phi"] - result["theta"]).max() < 1e-10
        # the same force seen as reactions: the pin on the bob, and the rod's hinge
        np.testing.assert_allclose(result["pin.f.y"], lam, rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(result["rod_hinge.f.y"], lam, rtol=1e-8, atol=1e-8)
        # the radial slider is free along its axis: it transmits nothing along r
        assert np.abs(result["radial.f.y"]).max() < 1e-8
    elif result.rod == "prescribed":
        # the drive force along +r (outward) is the eliminated multiplier's generalized force -lambda
        np.testing.assert_allclose(-result["drive.f"], lam, rtol=1e-8, atol=1e-8)
        assert np.abs(result["r"] - L).max() == 0.0
        np.testing.assert_allclose(result["hinge.f.y"], lam, rtol=1e-8, atol=1e-8)
    else:
        np.testing.assert_allclose(result["hinge.f.y"], lam, rtol=1e-8, atol=1e-8)


def test_energy_conserved(result):
    E = result["energy.total"]
    E_book = 0.5 * M * L ** 2 * result["theta_dot"] ** 2 - M * G * L * np.cos(result["theta"])
    np.testing.assert_allclose(E, E_book, rtol=0, atol=1e-9)
    assert np.abs(E - E[0]).max() < 1e-8 * M * G * L
