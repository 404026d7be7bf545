"""Seed Example 6.2: a cart on a spring carrying a pendulum (two degrees of freedom).

The model is ``models/textbook/ex6_2_cart_pendulum.py`` (moved from the former
``tests/test_example_6_2.py``, whose assertions are all kept here). The book's equations

    (m1 + m2) x'' + m2 L th'' cos th - m2 L th'^2 sin th + k x = 0        (6.36)
    m2 L^2 th'' + m2 L x'' cos th + m2 g L sin th = 0                      (6.37)

are checked to follow from the book's energies (6.24), (6.25) by Lagrange in sympy, are
integrated independently with scipy and compared with the simulation, and the energy
(6.24) + (6.25) is conserved.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex6_2_cart_pendulum.py")
M1, M2, L, K, G = 2.0, 0.7, 0.9, 35.0, 9.81
X0, XD0, TH0, THD0 = 0.15, -0.3, 1.1, 0.8
T_END = 5.0


def cart_pendulum():
    return MOD.build(m1=M1, m2=M2, L=L, k=K, g=G, x0=X0, xd0=XD0, th0=TH0, thd0=THD0)


def book_rhs(t, y, m1=M1, m2=M2, L=L, k=K, g=G):
    """(6.36)-(6.37) solved for x'' and th'' (a 2x2 linear system)."""
    x, th, xd, thd = y
    c, s = np.cos(th), np.sin(th)
    A = np.array([[m1 + m2, m2 * L * c], [m2 * L * c, m2 * L ** 2]])
    b = np.array([m2 * L * thd ** 2 * s - k * x, -m2 * g * L * s])
    xdd, thdd = np.linalg.solve(A, b)
    return [xd, thd, xdd, thdd]


def book_energy(x, th, xd, thd, m1=M1, m2=M2, L=L, k=K, g=G):
    T = 0.5 * (m1 + m2) * xd ** 2 + m2 * L * xd * thd * np.cos(th) + 0.5 * m2 * L ** 2 * thd ** 2  # (6.24)
    V = 0.5 * k * x ** 2 - m2 * g * L * np.cos(th)  # (6.25)
    return T + V


def test_eqs_6_36_6_37_follow_from_energies_by_lagrange():
    """Lagrange in sympy from the bob's position (not from (6.24)) reproduces (6.24), (6.36), (6.37)."""
    t = sp.Symbol("t")
    m1, m2, Ls, k, g = sp.symbols("m1 m2 L k g", positive=True)
    x, th = sp.Function("x")(t), sp.Function("theta")(t)
    r2 = sp.Matrix([x + Ls * sp.sin(th), -Ls * sp.cos(th)])
    v2 = r2.diff(t)
    T = m1 * x.diff(t) ** 2 / 2 + m2 * v2.dot(v2) / 2
    V = k * x ** 2 / 2 + m2 * g * r2[1]
    xd, thd = x.diff(t), th.diff(t)
    T_book = (m1 + m2) * xd ** 2 / 2 + m2 * Ls * xd * thd * sp.cos(th) + m2 * Ls ** 2 * thd ** 2 / 2  # (6.24)
    assert sp.simplify(T - T_book) == 0
    Lag = T - V
    eq_x = Lag.diff(xd).diff(t) - Lag.diff(x)
    eq_th = Lag.diff(thd).diff(t) - Lag.diff(th)
    xdd, thdd = x.diff(t, 2), th.diff(t, 2)
    assert sp.simplify(eq_x - ((m1 + m2) * xdd + m2 * Ls * thdd * sp.cos(th)
                               - m2 * Ls * thd ** 2 * sp.sin(th) + k * x)) == 0  # (6.36)
    assert sp.simplify(eq_th - (m2 * Ls ** 2 * thdd + m2 * Ls * xdd * sp.cos(th)
                                + m2 * g * Ls * sp.sin(th))) == 0  # (6.37)


@pytest.fixture(scope="module")
def result():
    r = mbcomp.simulate(cart_pendulum(), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=501)
    assert r.success, r.message
    return r


@pytest.fixture(scope="module")
def reference(result):
    sol = solve_ivp(book_rhs, (0.0, T_END), [X0, TH0, XD0, THD0], method="DOP853",
                    rtol=1e-13, atol=1e-13, t_eval=result.time)
    assert sol.success
    return sol.y


def test_start_values_are_the_fixed_ones(result):
    assert result["slider.s"][0] == pytest.approx(X0, abs=1e-14)
    assert result["slider.v"][0] == pytest.approx(XD0, abs=1e-14)
    assert result["hinge.phi"][0] == pytest.approx(TH0, abs=1e-14)
    assert result["hinge.w"][0] == pytest.approx(THD0, abs=1e-14)


def test_trajectory_matches_eqs_6_36_6_37(result, reference):
    x, th, xd, thd = reference
    # the motion is genuinely coupled and large: the pendulum swings well past 1 rad
    assert np.ptp(th) > 1.5 and np.ptp(x) > 0.2
    np.testing.assert_allclose(result["slider.s"], x, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["hinge.phi"], th, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["slider.v"], xd, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["hinge.w"], thd, rtol=0, atol=1e-7)
    # the book's names are aliases of the same series
    np.testing.assert_array_equal(result["x"], result["slider.s"])
    np.testing.assert_array_equal(result["theta"], result["hinge.phi"])


def test_bob_position_is_cart_plus_pendulum(result):
    x, th = result["slider.s"], result["hinge.phi"]
    np.testing.assert_allclose(result["bob.r.x"], x + L * np.sin(th), atol=1e-12)
    np.testing.assert_allclose(result["bob.r.y"], -L * np.cos(th), atol=1e-12)
    np.testing.assert_allclose(result["cart.r.x"], x, atol=1e-12)


def test_energy_is_conserved_and_equals_book_energy(result):
    E = result["energy.total"]
    E_book = book_energy(result["slider.s"], result["hinge.phi"], result["slider.v"], result["hinge.w"])
    # mbcomp's potential has the datum at the world origin, like (6.25): same value, not just a constant offset
    np.testing.assert_allclose(E, E_book, rtol=0, atol=1e-9)
    scale = np.abs(result["energy.kinetic"]).max()
    assert np.abs(E - E[0]).max() < 1e-8 * scale


def test_spring_force_balances_horizontal_momentum(result):
    """Newton for the whole system along x: (m1 x'' + m2 x_bob'') = -k x (the slider reaction is normal)."""
    x, th, thd = result["slider.s"], result["hinge.phi"], result["hinge.w"]
    xdd, thdd = result["slider.v.der"], result["hinge.w.der"]
    x_bob_dd = xdd + L * (thdd * np.cos(th) - thd ** 2 * np.sin(th))
    scale = K * np.abs(x).max()
    np.testing.assert_allclose(M1 * xdd + M2 * x_bob_dd, -K * x, rtol=0, atol=1e-9 * scale)
