"""Seed Example 3.2: steady precession of a gyro top, eqs. (3.25)-(3.34).

Model: ``models/textbook/ex3_2_gyro_top.py`` (RigidBody on a Spherical joint at the world
origin, world z up). Start values from the book's steady-precession condition

    (3.33)  m g l = I3 psi' phi' + (I3 - I1) psi'^2 cos theta

must keep the nutation angle constant and the precession rate equal to psi'; a perturbed start
nutates between the turning points of the conserved energy and momenta.

Checked independently here: (3.33) is re-derived from the top's Lagrangian in 3-1-3 Euler
angles (sympy), whose equations are also integrated with scipy for the perturbed start.

Book notes: (3.33) is right, with two readings to get right: ``I1`` is the transverse moment
about the fixed point ``o`` (``I1c + m l^2``, as in Ho = Io w of (3.27)), and ``phi'`` is the
relative spin rate (``omega_3 = phi' + psi' cos theta``). Using the centroidal ``I1c`` in (3.33)
does not give a steady precession (``test_centroidal_inertia_in_3_33_nutates``). The sentence
before (3.33) says "for sin theta = 0"; it must be "sin theta != 0" (one divides (3.32) by
sin theta).
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model
from mbcomp.kinematics import quat_to_matrix

MODEL = load_model("models/textbook/ex3_2_gyro_top.py")

M, LCM, I1C, I3, G = 0.5, 0.04, 5e-4, 1e-3, 9.81
I1 = I1C + M * LCM ** 2  # transverse moment about the fixed point
TOP = dict(m=M, l=LCM, I1c=I1C, I3=I3, g=G)
TH0, SPIN = 1.0, 40.0
OPTS = dict(rtol=1e-11, atol=1e-12, method="DOP853")


def euler_313(res):
    """Precession psi (unwrapped), nutation theta, spin phi (unwrapped), rad, and the body
    rotation matrices, from the body's quaternion output (R = Rz(psi) Rx(theta) Rz(phi))."""
    Q = np.column_stack([res[f"top.Q.{a}"] for a in "wxyz"])
    R = np.array([quat_to_matrix(q) for q in Q])
    theta = np.arccos(np.clip(R[:, 2, 2], -1, 1))
    psi = np.unwrap(np.arctan2(R[:, 0, 2], -R[:, 1, 2]))
    phi = np.unwrap(np.arctan2(R[:, 2, 0], R[:, 2, 1]))
    return psi, theta, phi, R


def invariants(res, R):
    """Energy (J) and vertical angular momentum about the tip (kg m^2/s) from body outputs:
    L = R diag(I1, I1, I3) R^T w (world), E = w.L/2 + m g z_cm."""
    w = np.column_stack([res[f"top.w.{a}"] for a in "xyz"])
    wb = np.einsum("nji,nj->ni", R, w)  # body axes
    Lw = np.einsum("nij,nj->ni", R, np.array([I1, I1, I3]) * wb)
    E = 0.5 * np.einsum("ni,ni->n", w, Lw) + M * G * LCM * R[:, 2, 2]
    return E, Lw[:, 2], wb


def simulate(t_end, n_out, **kw):
    r = mbcomp.simulate(MODEL.build(**TOP, **kw), t_end=t_end, n_out=n_out, **OPTS)
    assert r.success, r.message
    return r


# ------------------------------------------------------------------ independent derivation
t_ = sp.Symbol("t")
_psi, _th, _phi = (sp.Function(n)(t_) for n in ("psi", "theta", "phi"))
_m, _l, _g, _I1, _I3 = sp.symbols("m l g I1 I3", positive=True)
# 3-1-3 Euler angles, body-axis angular velocity; T about the fixed point, V of the centre of mass
_w3 = _phi.diff(t_) + _psi.diff(t_) * sp.cos(_th)
_T = _I1 / 2 * (_th.diff(t_) ** 2 + _psi.diff(t_) ** 2 * sp.sin(_th) ** 2) + _I3 / 2 * _w3 ** 2
_LAG = _T - _m * _g * _l * sp.cos(_th)
_Q = [_psi, _th, _phi]
_EOM = [sp.diff(_LAG.diff(q.diff(t_)), t_) - _LAG.diff(q) for q in _Q]


def test_3_33_from_the_lagrangian():
    """theta equation with theta' = theta'' = 0 and constant psi', phi' is (3.33) times
    -sin theta, i.e. (3.32)."""
    pd, fd, th = sp.symbols("psidot phidot th")
    steady = _EOM[1].subs({_psi.diff(t_, 2): 0, _phi.diff(t_, 2): 0, _th.diff(t_, 2): 0}).subs(
        {_th.diff(t_): 0}).subs({_psi.diff(t_): pd, _phi.diff(t_): fd}).subs(_th, th)
    book = _m * _g * _l - (_I3 * pd * fd + (_I3 - _I1) * pd ** 2 * sp.cos(th))  # (3.33), I1 about o
    assert sp.simplify(steady + sp.sin(th) * book) == 0
    # (3.34) is (3.33) at theta = pi/2
    assert sp.simplify(book.subs(th, sp.pi / 2) - (_m * _g * _l - _I3 * pd * fd)) == 0


def euler_rhs():
    """First-order Euler-angle equations of the top for scipy (independent of mbcomp)."""
    acc = sp.symbols("a0:3")
    qd = sp.symbols("qd0:3")
    qs = sp.symbols("q0:3")
    eqs = [e.subs({q.diff(t_, 2): a for q, a in zip(_Q, acc)}) for e in _EOM]
    sub2 = {q.diff(t_): v for q, v in zip(_Q, qd)}
    eqs = [e.subs(sub2).subs({q: s for q, s in zip(_Q, qs)}) for e in eqs]
    sol = sp.solve(eqs, acc, dict=True)[0]
    vals = {_m: M, _l: LCM, _g: G, _I1: I1, _I3: I3}
    f = sp.lambdify((qs, qd), [sol[a].subs(vals) for a in acc], "numpy")
    return lambda t, y: np.concatenate((y[3:], f(y[:3], y[3:])))


# ------------------------------------------------------------------ steady precession
@pytest.fixture(scope="module")
def steady_slow():
    return simulate(5.0, 1001, theta0=TH0, spin=SPIN, precession="slow")


def test_slow_steady_precession_keeps_nutation_constant(steady_slow):
    r = steady_slow
    slow, _ = MODEL.steady_precession_rates(M, LCM, I1C, I3, G, TH0, SPIN)
    period = 2 * np.pi / slow
    assert r.time[-1] > 3 * period  # several precession periods
    psi, theta, phi, R = euler_313(r)
    assert np.abs(theta - TH0).max() < 1e-9
    np.testing.assert_allclose(psi - psi[0], slow * r.time, rtol=0, atol=1e-8)
    np.testing.assert_allclose(phi - phi[0], SPIN * r.time, rtol=0, atol=1e-8)
    # the precession is real: the axis sweeps around the vertical
    assert psi[-1] - psi[0] > 6 * np.pi


def test_slow_steady_precession_reaction_is_centripetal(steady_slow):
    """The tip force (ball.f, on the top, top axes) turned to world axes is m a_cm + m g k, with
    the centre of mass on a horizontal circle of radius l sin theta at rate psi'."""
    r = steady_slow
    slow, _ = MODEL.steady_precession_rates(M, LCM, I1C, I3, G, TH0, SPIN)
    psi, theta, phi, R = euler_313(r)
    f_world = np.einsum("nij,nj->ni", R, np.column_stack([r[f"ball.f.{a}"] for a in "xyz"]))
    radial = -slow ** 2 * LCM * np.sin(theta)[:, None] * np.column_stack(
        [np.sin(psi), -np.cos(psi), np.zeros_like(psi)])
    expected = M * radial + np.array([0.0, 0.0, M * G])
    np.testing.assert_allclose(f_world, expected, rtol=0, atol=1e-9 * M * G)
    tau = np.column_stack([r[f"ball.tau.{a}"] for a in "xyz"])
    assert np.abs(tau).max() < 1e-12  # a ball joint transmits no torque


def test_energy_and_vertical_momentum_conserved(steady_slow):
    r = steady_slow
    psi, theta, phi, R = euler_313(r)
    E, Lz, wb = invariants(r, R)
    np.testing.assert_allclose(r["energy.total"], E, rtol=1e-12)
    assert np.ptp(E) < 1e-9 * abs(E[0])
    assert np.ptp(Lz) < 1e-9 * abs(Lz[0])
    assert np.ptp(r["omega_3"]) < 1e-9 * SPIN
    np.testing.assert_allclose(r["omega_3"], wb[:, 2], rtol=1e-13)


def test_fast_steady_precession():
    """The other root of (3.33), the fast precession, is steady too."""
    slow, fast = MODEL.steady_precession_rates(M, LCM, I1C, I3, G, TH0, SPIN)
    assert fast > 10 * slow  # genuinely the other branch
    r = simulate(5 * 2 * np.pi / fast, 501, theta0=TH0, spin=SPIN, precession="fast")
    psi, theta, phi, _ = euler_313(r)
    assert np.abs(theta - TH0).max() < 1e-9
    np.testing.assert_allclose(psi - psi[0], fast * r.time, rtol=0, atol=1e-8)


def test_horizontal_top_3_34():
    """theta = pi/2: (3.34) psi' phi' = m g l / I3, the top's axis stays horizontal."""
    spin = 30.0
    psi_dot = M * G * LCM / (I3 * spin)
    r = simulate(3 * 2 * np.pi / psi_dot, 501, theta0=np.pi / 2, spin=spin, precession=psi_dot)
    psi, theta, phi, _ = euler_313(r)
    assert np.abs(theta - np.pi / 2).max() < 1e-9
    np.testing.assert_allclose(psi - psi[0], psi_dot * r.time, rtol=0, atol=1e-8)


def test_centroidal_inertia_in_3_33_nutates():
    """Reading I1 in (3.33) as the centroidal moment gives a wrong psi': the top nutates by
    far more than the steady tolerance."""
    a, b, c = (I3 - I1C) * np.cos(TH0), I3 * SPIN, -M * G * LCM
    wrong = 2 * c / (-b - np.sqrt(b * b - 4 * a * c))
    r = simulate(1.5, 601, theta0=TH0, spin=SPIN, precession=wrong)
    _, theta, _, _ = euler_313(r)
    assert np.ptp(theta) > 1e-3


# ------------------------------------------------------------------ perturbed start
def turning_points(E, Lz, w3):
    """Nutation bounds from E, Lz and omega_3: with u = cos theta and theta' = 0,
    (2E' - 2 m g l u)(1 - u^2) I1 - (Lz - I3 w3 u)^2 = 0, E' = E - I3 w3^2 / 2."""
    Ep = E - 0.5 * I3 * w3 ** 2
    mgl, L3 = M * G * LCM, I3 * w3
    poly = np.polysub(np.polymul([-2 * mgl * I1, 2 * Ep * I1], [-1.0, 0.0, 1.0]),
                      np.polymul([-L3, Lz], [-L3, Lz]))
    u = np.roots(poly)
    u = np.sort(u[(np.abs(u.imag) < 1e-12) & (np.abs(u.real) <= 1)].real)
    assert len(u) == 2
    return np.arccos(u[::-1])  # theta_min, theta_max


def extrema(t, y, kind):
    """Extreme values of a sampled signal, refined by a parabola through the three samples."""
    s = 1 if kind == "max" else -1
    i = np.nonzero((s * y[1:-1] > s * y[:-2]) & (s * y[1:-1] >= s * y[2:]))[0] + 1
    y0, y1, y2 = y[i - 1], y[i], y[i + 1]
    return y1 - (y2 - y0) ** 2 / (8 * (y2 - 2 * y1 + y0))


@pytest.fixture(scope="module")
def perturbed():
    # released with spin only (psi' = 0): the classic nutating top
    return simulate(2.0, 4001, theta0=TH0, spin=SPIN, precession=0.0)


def test_perturbed_top_nutates_between_conserved_bounds(perturbed):
    r = perturbed
    psi, theta, phi, R = euler_313(r)
    E, Lz, wb = invariants(r, R)
    th_min, th_max = turning_points(E[0], Lz[0], wb[0, 2])
    assert th_min == pytest.approx(TH0, abs=1e-12)  # released at the top of the nutation
    assert th_max - th_min > 0.01
    hi, lo = extrema(r.time, theta, "max"), extrema(r.time, theta, "min")
    assert len(hi) >= 5 and len(lo) >= 5  # several nutation cycles
    np.testing.assert_allclose(hi, th_max, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lo, th_min, rtol=0, atol=1e-9)
    assert theta.min() > th_min - 1e-9 and theta.max() < th_max + 1e-9
    assert np.ptp(E) < 1e-9 * abs(E[0]) and np.ptp(Lz) < 1e-9 * abs(Lz[0])


def test_perturbed_top_matches_euler_angle_integration(perturbed):
    r = perturbed
    psi, theta, phi, _ = euler_313(r)
    y0 = [psi[0], TH0, phi[0], 0.0, 0.0, SPIN]
    sol = solve_ivp(euler_rhs(), (0.0, r.time[-1]), y0, method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=r.time)
    assert sol.success
    np.testing.assert_allclose(theta, sol.y[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(psi, sol.y[0], rtol=0, atol=2e-9)
    np.testing.assert_allclose(phi, sol.y[2], rtol=0, atol=2e-9)
