"""Seed Example 6.1: the simple pendulum by Lagrange's equation, eq. (6.20).

The model (``models/textbook/ex6_1_pendulum.py``: revolute, massless rod, point mass) is
checked against

* Lagrange's equation derived here in sympy from the book's energies (6.17), (6.18): it is (6.20);
* (6.20) integrated independently with scipy;
* the exact solution of (6.20) released from rest, ``sin(theta/2) = k sn(K - w0 t | k^2)``
  with ``k = sin(theta0/2)``, ``w0 = sqrt(g/l)`` (Jacobi elliptic function), and the exact
  period ``4 K(k^2) / w0``;
* the energy (6.17) + (6.18), conserved, with the same datum.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex6_1_pendulum.py")
M, L, G, TH0 = 1.0, 0.8, 9.81, 1.2
T_END = 4.0


def test_lagrange_of_6_17_6_18_is_6_20():
    t = sp.Symbol("t")
    m, l, g = sp.symbols("m l g", positive=True)
    th = sp.Function("theta")(t)
    T = m * l ** 2 * th.diff(t) ** 2 / 2  # (6.17)
    V = -m * g * l * sp.cos(th)  # (6.18)
    lag = (T - V).diff(th.diff(t)).diff(t) - (T - V).diff(th)
    assert sp.simplify(lag - (m * l ** 2 * th.diff(t, 2) + m * g * l * sp.sin(th))) == 0  # (6.20)


@pytest.fixture(scope="module")
def result():
    r = mbcomp.simulate(MOD.build(m=M, l=L, g=G, theta0=TH0), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=801)
    assert r.success, r.message
    return r


def test_trajectory_matches_eq_6_20_integrated(result):
    def rhs(t, y):
        return [y[1], -G / L * np.sin(y[0])]  # (6.20) divided by m l^2

    sol = solve_ivp(rhs, (0, T_END), [TH0, 0.0], method="DOP853", rtol=1e-13, atol=1e-14, t_eval=result.time)
    np.testing.assert_allclose(result["theta"], sol.y[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(result["theta_dot"], sol.y[1], rtol=0, atol=1e-9)


def test_trajectory_matches_exact_elliptic_solution(result):
    k2 = np.sin(TH0 / 2) ** 2
    w0 = np.sqrt(G / L)
    sn, cn, dn, _ = ellipj(ellipk(k2) - w0 * result.time, k2)
    theta = 2 * np.arcsin(np.sqrt(k2) * sn)
    np.testing.assert_allclose(result["theta"], theta, rtol=0, atol=1e-9)
    # theta' = -2 k w0 cn (d sn/du = cn dn; cos(theta/2) = dn)
    np.testing.assert_allclose(result["theta_dot"], -2 * np.sqrt(k2) * w0 * cn, rtol=0, atol=1e-8)


def test_energy_6_17_plus_6_18_is_conserved(result):
    th, thd = result["theta"], result["theta_dot"]
    E_book = 0.5 * M * L ** 2 * thd ** 2 - M * G * L * np.cos(th)
    # the world origin is the hinge: mbcomp's potential has the datum of (6.18)
    np.testing.assert_allclose(result["energy.total"], E_book, rtol=0, atol=1e-12)
    assert np.abs(E_book - E_book[0]).max() < 1e-9 * M * G * L


def test_period_matches_exact_elliptic_integral():
    # moved from tests/test_pendulum.py (m = 1.3 kg there; the period does not depend on m)
    l, g, th0 = 0.8, 9.81, 1.2
    r = mbcomp.simulate(MOD.build(m=1.3, l=l, theta0=th0), t_end=4.0, rtol=1e-11, atol=1e-12, n_out=4001)
    th = r["hinge.phi"]
    T_exact = 4 * np.sqrt(l / g) * ellipk(np.sin(th0 / 2) ** 2)
    # first return to theta0 (maximum) after t=0: interpolate the zero crossing of w
    w = r["hinge.w"]
    t = r.time
    # zero crossings of w from + to - mark maxima of theta
    idx = np.where((w[:-1] > 0) & (w[1:] <= 0))[0][0]
    t_max = t[idx] - w[idx] * (t[idx + 1] - t[idx]) / (w[idx + 1] - w[idx])
    assert abs(t_max - T_exact) < 1e-6
    assert th.max() == pytest.approx(th0, abs=1e-9)
