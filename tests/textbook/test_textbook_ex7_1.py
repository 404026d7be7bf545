"""Seed Example 7.1: a bead on a ring spinning at constant omega about a vertical diameter.

The model (``models/textbook/ex7_1_bead_on_ring.py``: a driven vertical revolute for the ring,
a revolute about the ring normal carrying the bead at radius r) is simulated near every
steady state, on both sides of ``omega^2 = g/r``, and checked against

* (7.23) derived here by Lagrange in sympy from the bead's position, and integrated
  independently with scipy;
* the linearization (7.33), derived in sympy: about ``alpha = 0``,
  ``lambda^2 = omega^2 - g/r`` (7.34); about ``cos(alpha_s) = g/(r omega^2)``,
  ``lambda^2 = -omega^2 sin^2(alpha_s)`` (7.35, same value as the book's
  ``(g^2 - omega^4 r^2)/(omega^2 r^2)``); about ``alpha = pi`` (the top, a steady state the
  book's (7.28) omits although ``sin(X1) = 0`` in (7.27) admits it),
  ``lambda^2 = omega^2 + g/r`` (always unstable). The measured small-oscillation frequencies
  and departure rates match these;
* the exact period of a finite oscillation, from the Jacobi integral by quadrature
  (``T = 2 int dalpha / alpha'``), in particular at ``omega^2 = g/r``, where (7.34) gives
  ``lambda = 0`` and the book's "stable" is not decided by the linearization: the bottom is
  stable there through the quartic term of the effective potential;
* the Jacobi integral ``h = (1/2) m r^2 alpha'^2 - (1/2) m omega^2 r^2 sin^2 alpha - m g r cos alpha``
  (conserved; the energy is not, the drive works), and the drive torque
  ``d/dt (m r^2 sin^2(alpha) omega)`` (the ring is massless).

Book notes: (7.21) prints ``V = -m g r cos(theta)``; it is ``cos(alpha)`` (``theta`` is not a
coordinate of this problem; (7.23) uses ``alpha``). (7.28) lists two steady states; there are
three (``alpha = pi``). At ``omega^2 = g/r`` (7.34) gives a double root 0: the linearization is
inconclusive, and the test below shows the nonlinear stability.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import quad, solve_ivp
from scipy.interpolate import CubicHermiteSpline
from scipy.special import ellipk

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex7_1_bead_on_ring.py")
M, R, G = 0.1, 0.5, 9.81
W_LOW, W_HIGH = 3.0, 6.0  # omega^2 = 9 < g/r = 19.62 < 36
TOL = dict(rtol=1e-12, atol=1e-14)


# ------------------------------------------------------------------------- references
def eq_7_23(omega):
    def rhs(t, y):
        a, ad = y
        return [ad, omega ** 2 * np.sin(a) * np.cos(a) - G / R * np.sin(a)]  # (7.23) / (m r^2)

    return rhs


def jacobi(res, omega):
    a, ad = res["alpha"], res["alpha_dot"]
    return 0.5 * M * R ** 2 * ad ** 2 - 0.5 * M * omega ** 2 * R ** 2 * np.sin(a) ** 2 - M * G * R * np.cos(a)


def exact_period(a0, omega):
    """Period of the oscillation released from rest at ``a0``, by quadrature of the Jacobi integral.

    Per unit m r^2 the Jacobi integral is ``alpha'^2/2 + U(alpha)`` with
    ``U = -(g/r) cos(alpha) - (omega^2/2) sin^2(alpha) = (omega^2/2)(cos(alpha) - x_s)^2 + const``,
    ``x_s = g/(r omega^2)``: a square in ``x = cos(alpha)``, so
    ``U(a0) - U(alpha) = (omega^2/2)(x - x0)(2 x_s - x0 - x)``. In the bottom well (``x_s >= 1``)
    the turning points are ``+-a0``; in the off-bottom well they are ``a0`` and ``a1`` with
    ``cos(a1) = 2 x_s - cos(a0)``, and then ``U(a0) - U(alpha) = (omega^2/2)(cos(lo) - x)(x - cos(hi))``.
    ``T = 2 int_lo^hi dalpha / sqrt(2 (U(a0) - U(alpha)))``, every factor written as a product of
    sines of exactly known angle differences (no cancellation near the turning points).
    """
    xs = G / (R * omega ** 2)
    bottom = xs >= 1 - 1e-12  # omega^2 <= g/r (up to rounding at the critical speed)
    if not bottom:  # the swing must stay in the off-bottom well: U(a0) < U(0)
        assert (np.cos(a0) - xs) ** 2 < (1 - xs) ** 2
    a1 = -a0 if bottom else np.arccos(2 * xs - np.cos(a0))
    lo, hi = min(a0, a1), max(a0, a1)
    c, d = (lo + hi) / 2, (hi - lo) / 2

    def f(phi):  # alpha = c + d sin(phi) removes the integrable end singularities
        a = c + d * np.sin(phi)
        up = 2 * d * np.cos(np.pi / 4 - phi / 2) ** 2  # alpha - lo
        dn = 2 * d * np.sin(np.pi / 4 - phi / 2) ** 2  # hi - alpha
        x_minus_xhi = 2 * np.sin((a + hi) / 2) * np.sin(dn / 2)  # cos(alpha) - cos(hi)
        if bottom:  # 2 x_s - x0 - x, with x0 = cos(hi)
            other = 2 * (xs - 1) + 2 * np.sin(hi / 2) ** 2 + 2 * np.sin(a / 2) ** 2
        else:  # cos(lo) - cos(alpha)
            other = 2 * np.sin((lo + a) / 2) * np.sin(up / 2)
        return d * np.cos(phi) / np.sqrt(omega ** 2 * x_minus_xhi * other)

    val, _ = quad(f, -np.pi / 2, np.pi / 2, epsabs=0, epsrel=1e-13, limit=200)
    return 2 * val


def upward_crossings(t, x, xd):
    """Times where x crosses zero upwards (cubic Hermite interpolation with the rate xd)."""
    roots = CubicHermiteSpline(t, x, xd).roots(extrapolate=False)
    return np.array([z for z in roots if np.interp(z, t, xd) > 0])


def simulate(omega, alpha0, t_end, n_out=601):
    r = mbcomp.simulate(MOD.build(m=M, r=R, g=G, omega=omega, alpha0=alpha0, alpha_dot0=0.0),
                        t_end=t_end, n_out=n_out, method="DOP853", **TOL)
    assert r.success, r.message
    return r


def check_against_book(r, omega, atol, rtol=0.0):
    """The simulated trajectory is (7.23) integrated independently; h is conserved; drive torque."""
    sol = solve_ivp(eq_7_23(omega), (0, r.time[-1]), [r["alpha"][0], 0.0], method="DOP853",
                    rtol=1e-13, atol=1e-15, t_eval=r.time)
    np.testing.assert_allclose(r["alpha"], sol.y[0], rtol=rtol, atol=atol)
    np.testing.assert_allclose(r["alpha_dot"], sol.y[1], rtol=rtol, atol=atol * 10)
    np.testing.assert_allclose(r["psi"], omega * r.time, rtol=0, atol=1e-12)
    h = jacobi(r, omega)
    assert np.abs(h - h[0]).max() < 1e-10 * M * G * R
    # mbcomp's energy is T + V of (7.20)-(7.21); h = E - omega * H_y
    E = r["energy.total"]
    np.testing.assert_allclose(E - M * omega ** 2 * R ** 2 * np.sin(r["alpha"]) ** 2, h, rtol=0, atol=1e-13)
    # the drive supplies dH_y/dt, H_y = m r^2 sin^2(alpha) omega (massless ring)
    a, ad = r["alpha"], r["alpha_dot"]
    np.testing.assert_allclose(r["drive.tau"], 2 * M * R ** 2 * omega * np.sin(a) * np.cos(a) * ad,
                               rtol=0, atol=1e-10 * M * G * R)


# ------------------------------------------------------------------------- symbolic
def test_lagrange_gives_7_20_and_7_23_and_linearization_7_33():
    t = sp.Symbol("t")
    m, r, g, w = sp.symbols("m r g omega", positive=True)
    a = sp.Function("alpha")(t)
    # bead in ring axes (r sin a, -r cos a, 0); the ring turns by w t about the vertical y
    p_ring = sp.Matrix([r * sp.sin(a), -r * sp.cos(a), 0])
    Ry = sp.Matrix([[sp.cos(w * t), 0, sp.sin(w * t)], [0, 1, 0], [-sp.sin(w * t), 0, sp.cos(w * t)]])
    p = Ry * p_ring
    v = p.diff(t)
    T = sp.simplify(m * v.dot(v) / 2)
    V = m * g * p[1]
    assert sp.simplify(T - m * (r ** 2 * a.diff(t) ** 2 + w ** 2 * r ** 2 * sp.sin(a) ** 2) / 2) == 0  # (7.20)
    assert sp.simplify(V - (-m * g * r * sp.cos(a))) == 0  # (7.21) with alpha, not theta
    Lag = T - V
    eq = Lag.diff(a.diff(t)).diff(t) - Lag.diff(a)
    book = m * r ** 2 * a.diff(t, 2) - m * w ** 2 * r ** 2 * sp.sin(a) * sp.cos(a) + m * g * r * sp.sin(a)  # (7.23)
    assert sp.simplify(eq - book) == 0
    # linearization: A21 = d f2 / d X1 (7.31)
    X1 = sp.Symbol("X1")
    f2 = w ** 2 * sp.sin(X1) * sp.cos(X1) - g / r * sp.sin(X1)  # (7.24)
    A21 = sp.diff(f2, X1)
    assert sp.simplify(A21 - (w ** 2 * sp.cos(2 * X1) - g / r * sp.cos(X1))) == 0  # (7.31)
    # steady states: the roots of (7.27) include the top, X1 = pi (missing from 7.28)
    for Xs in (0, sp.pi, sp.acos(g / (r * w ** 2))):
        assert sp.simplify(f2.subs(X1, Xs)) == 0
    assert sp.simplify(A21.subs(X1, 0) - (w ** 2 - g / r)) == 0  # (7.34)
    assert sp.simplify(A21.subs(X1, sp.pi) - (w ** 2 + g / r)) == 0  # top: always > 0, unstable
    Xs = sp.acos(g / (r * w ** 2))
    lam2 = sp.simplify(A21.subs(X1, Xs))
    assert sp.simplify(lam2 - (g ** 2 - w ** 4 * r ** 2) / (w ** 2 * r ** 2)) == 0  # (7.35)
    assert sp.simplify(lam2 + w ** 2 * sp.sin(Xs) ** 2) == 0  # = -omega^2 sin^2(alpha_s)
    # the effective potential (per m r^2) is a square in cos(alpha), used by exact_period below
    U = -(g / r) * sp.cos(X1) - w ** 2 / 2 * sp.sin(X1) ** 2
    square = w ** 2 / 2 * (sp.cos(X1) - g / (r * w ** 2)) ** 2 - w ** 2 / 2 - g ** 2 / (2 * r ** 2 * w ** 2)
    assert sp.simplify(U - square) == 0
    assert sp.simplify(sp.diff(U, X1) + f2) == 0


# ------------------------------------------------------------------------- near the steady states
def test_below_critical_bottom_is_stable_at_linear_frequency():
    """omega^2 < g/r: small oscillation about alpha = 0 at sqrt(g/r - omega^2) (7.34, imaginary)."""
    nu = np.sqrt(G / R - W_LOW ** 2)
    eps = 1e-3
    r = simulate(W_LOW, eps, t_end=3.2 * 2 * np.pi / nu)
    check_against_book(r, W_LOW, atol=1e-11)
    assert np.abs(r["alpha"]).max() <= eps * (1 + 1e-9)  # bounded by the start amplitude
    tc = upward_crossings(r.time, r["alpha"], r["alpha_dot"])
    assert len(tc) >= 3
    nu_sim = 2 * np.pi * (len(tc) - 1) / (tc[-1] - tc[0])
    # the nonlinear shift is O(eps^2) ~ 1e-6 relative
    assert nu_sim == pytest.approx(nu, rel=1e-5)
    assert nu_sim == pytest.approx(2 * np.pi / exact_period(eps, W_LOW), rel=1e-9)


def test_below_critical_top_is_unstable():
    """omega^2 < g/r: the top alpha = pi (not in the book's 7.28) departs at sqrt(omega^2 + g/r)."""
    lam = np.sqrt(W_LOW ** 2 + G / R)
    eps = 1e-6
    t_end = np.arccosh(1e-3 / eps) / lam  # until the departure is 1e-3 rad
    r = simulate(W_LOW, np.pi - eps, t_end=t_end, n_out=401)
    # an unstable motion amplifies the local errors by cosh(lambda t_end) = 1e3: 5e-8 of the departure
    check_against_book(r, W_LOW, atol=5e-11)
    dep = np.pi - r["alpha"]
    lin = eps * np.cosh(lam * r.time)
    assert dep[-1] > 0.9e-3
    np.testing.assert_allclose(dep, lin, rtol=1e-5, atol=0)


def test_above_critical_bottom_is_unstable_at_linear_rate():
    """omega^2 > g/r: alpha = 0 departs as eps cosh(lambda t), lambda = sqrt(omega^2 - g/r) (7.34)."""
    lam = np.sqrt(W_HIGH ** 2 - G / R)
    eps = 1e-6
    t_end = np.arccosh(1e-3 / eps) / lam
    r = simulate(W_HIGH, eps, t_end=t_end, n_out=401)
    # an unstable motion amplifies the local errors by cosh(lambda t_end) = 1e3: 5e-8 of the departure
    check_against_book(r, W_HIGH, atol=5e-11)
    lin = eps * np.cosh(lam * r.time)
    assert r["alpha"][-1] > 0.9e-3
    np.testing.assert_allclose(r["alpha"], lin, rtol=1e-5, atol=0)
    # the measured rate: invert the linear solution at the end (nonlinear terms are O(alpha^2) ~ 1e-6)
    rate = np.arccosh(r["alpha"][-1] / eps) / r.time[-1]
    assert rate == pytest.approx(lam, rel=1e-6)


def test_above_critical_off_bottom_state_is_steady_and_stable():
    """omega^2 > g/r: cos(alpha_s) = g/(r omega^2) is a steady state; a perturbation oscillates
    at omega sin(alpha_s) (7.35)."""
    a_s = np.arccos(G / (R * W_HIGH ** 2))
    # exactly at the steady state the bead stays, and the drive does nothing
    r0 = simulate(W_HIGH, a_s, t_end=2.0, n_out=201)
    assert np.abs(r0["alpha"] - a_s).max() < 1e-10
    assert np.abs(r0["drive.tau"]).max() < 1e-10
    nu = W_HIGH * np.sin(a_s)
    eps = 1e-3
    r = simulate(W_HIGH, a_s + eps, t_end=3.2 * 2 * np.pi / nu)
    check_against_book(r, W_HIGH, atol=1e-11)
    dev = r["alpha"] - a_s
    assert np.abs(dev).max() < 1.01 * eps
    tc = upward_crossings(r.time, dev, r["alpha_dot"])
    nu_sim = 2 * np.pi * (len(tc) - 1) / (tc[-1] - tc[0])
    assert nu_sim == pytest.approx(nu, rel=1e-5)
    assert nu_sim == pytest.approx(2 * np.pi / exact_period(a_s + eps, W_HIGH), rel=1e-9)


def test_above_critical_top_is_unstable():
    lam = np.sqrt(W_HIGH ** 2 + G / R)
    eps = 1e-6
    t_end = np.arccosh(1e-3 / eps) / lam
    r = simulate(W_HIGH, np.pi - eps, t_end=t_end, n_out=401)
    np.testing.assert_allclose(np.pi - r["alpha"], eps * np.cosh(lam * r.time), rtol=1e-5, atol=0)


# ------------------------------------------------------------------------- finite oscillations
def test_critical_speed_bottom_is_stable_nonlinearly():
    """omega^2 = g/r: (7.34) gives lambda = 0, the linearization decides nothing. The
    effective potential is quartic, U - U(0) = (g/r) alpha^4 / 8 + ..., so the bottom is stable
    with an amplitude-dependent period (exact, by quadrature), not a linear frequency."""
    w_c = np.sqrt(G / R)
    for amp in (0.05, 0.1):
        T_exact = exact_period(amp, w_c)
        # leading order for alpha'' = -(g/(2r)) alpha^3: T = 4 K(1/2) / (amp sqrt(g/(2r)))
        # (the relative correction is O(amp^2))
        assert T_exact == pytest.approx(4 * ellipk(0.5) / (amp * np.sqrt(G / (2 * R))), rel=2e-3)
    amp = 0.1
    T_exact = exact_period(amp, w_c)
    r = simulate(w_c, amp, t_end=2.2 * T_exact, n_out=801)
    check_against_book(r, w_c, atol=1e-10)
    assert np.abs(r["alpha"]).max() <= amp * (1 + 1e-9)
    tc = upward_crossings(r.time, r["alpha"], r["alpha_dot"])
    assert tc[1] - tc[0] == pytest.approx(T_exact, rel=1e-9)


@pytest.mark.parametrize("omega, alpha0, centre", [(W_LOW, 2.0, 0.0), (W_HIGH, 0.2, None)],
                         ids=["below_large_swing", "above_large_swing_about_off_bottom_state"])
def test_large_oscillation_period_from_jacobi_integral(omega, alpha0, centre):
    if centre is None:
        centre = np.arccos(G / (R * omega ** 2))
    T_exact = exact_period(alpha0, omega)
    r = simulate(omega, alpha0, t_end=2.2 * T_exact, n_out=801)
    check_against_book(r, omega, atol=1e-9)
    dev = r["alpha"] - centre
    tc = upward_crossings(r.time, dev, r["alpha_dot"])
    assert tc[1] - tc[0] == pytest.approx(T_exact, rel=1e-9)
