"""Seed Example 3.3 (section 3.3): stability of a spinning plate, eqs. (3.37)-(3.45).

The model (a free plate, no gravity) contains no equations of motion; its body-axis angular
velocity is compared with

* the linearized solution of (3.39)-(3.40), ``eta(t) = expm(-K t) eta(0)``, whose exponent is
  (3.44) ``lambda^2 = (I1 - I3)(I2 - I1) w0^2 / (I2 I3)`` (checked: the book's (3.37)-(3.45)
  are right; with the spin axis labelled 1 in a right-handed cyclic order; in terms of the
  intermediate axis ``2`` spun between ``1`` and ``3`` it is the familiar
  ``lambda = w0 sqrt((I2 - I1)(I3 - I2) / (I1 I3))``),
* the full Euler equations (3.37) with M = 0 integrated by scipy at tight tolerance,
* the invariants of a torque-free body: kinetic energy and the world angular momentum.

The book states stability only qualitatively ("marginally stable", "increase exponentially");
the tests make it quantitative: amplitude and frequency of the bounded oscillation, and the
growth rate of the unstable one.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

import mbcomp
from conftest import load_model
from mbcomp.kinematics import quat_to_matrix

ex = load_model("models/textbook/ex3_3_spinning_plate.py")

W0 = 10.0
I_PLATE = np.diag(ex.plate_part().I)  # Ix < Iy < Iz
TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-15)
RUN = dict(method="DOP853", rtol=1e-11, atol=1e-13)


def body_rates(res):
    return np.column_stack([res[f"omega_{c}"] for c in "xyz"])


def linear_K(axis):
    """K of (3.40) for spin about ``axis`` and the book's (I1, I2, I3)."""
    i1, i2, i3 = ex.spin_axes(axis)
    I1, I2, I3 = I_PLATE[[i1, i2, i3]]
    return np.array([[0.0, (I1 - I3) * W0 / I2], [(I2 - I1) * W0 / I3, 0.0]]), (I1, I2, I3)


def lambda_sq(I1, I2, I3):
    """(3.44)."""
    return (I1 - I3) * (I2 - I1) * W0 ** 2 / (I2 * I3)


def euler_rhs(t, w):
    """(3.37) with M = 0, plate axes x, y, z."""
    A, B, C = I_PLATE
    x, y, z = w
    return [(B - C) * y * z / A, (C - A) * z * x / B, (A - B) * x * y / C]


def test_plate_moments_are_distinct_and_ordered():
    A, B, C = I_PLATE
    assert A < B < C and B - A > 0.3 * B and C - B > 0.3 * B
    for axis, k in (("smallest", 0), ("intermediate", 1), ("largest", 2)):
        assert ex.spin_axes(axis)[0] == k
    with pytest.raises(ValueError, match="fix"):
        ex.spin_axes("diagonal")


@pytest.mark.parametrize("axis", ["largest", "smallest"])
def test_spin_about_extreme_axis_stays_bounded(axis):
    eps = 1e-3
    K, (I1, I2, I3) = linear_K(axis)
    lam2 = lambda_sq(I1, I2, I3)
    assert lam2 < 0  # (3.44): Case I
    Omega = np.sqrt(-lam2)
    period = 2 * np.pi / Omega
    r = mbcomp.simulate(ex.build(axis=axis, omega0=W0, eps=eps), t_end=2.2 * period, n_out=801, **RUN)
    assert r.success, r.message
    i1, i2, i3 = ex.spin_axes(axis)
    w = body_rates(r)
    eta0 = np.array([eps * W0, eps * W0])
    lin = np.array([expm(-K * t) @ eta0 for t in r.time])
    # the linearized solution of (3.40) is right to O(eps^2) relative (measured: 1e-5 eps w0
    # about the smallest axis, 2e-7 eps w0 about the largest)
    np.testing.assert_allclose(w[:, [i2, i3]], lin, rtol=0, atol=30 * eps * (eps * W0))
    # (3.39) first row: eta1 constant; the neglected eta2 eta3 term moves it by O(eps^2 w0) only
    np.testing.assert_allclose(w[:, i1], W0, rtol=0, atol=3 * eps ** 2 * W0)
    # amplitudes predicted by (3.40): eta(t) = eta(0) cos(Omega t) - K eta(0) sin(Omega t) / Omega,
    # so each component swings with amplitude sqrt(eta_i(0)^2 + ((K eta(0))_i / Omega)^2)
    amp = np.sqrt(eta0 ** 2 + ((K @ eta0) / Omega) ** 2)
    np.testing.assert_allclose(np.abs(w[:, [i2, i3]]).max(axis=0), amp, rtol=1e-4)
    assert np.abs(w[:, [i2, i3]]).max() < 3 * eps * W0  # stays small: bounded
    # after one period 2 pi / sqrt(-lambda^2) the perturbation is back at its start value,
    # after half a period it is not
    back = np.array([np.interp(period, r.time, w[:, i]) for i in (i2, i3)])
    half = np.array([np.interp(period / 2, r.time, w[:, i]) for i in (i2, i3)])
    np.testing.assert_allclose(back, eta0, rtol=0, atol=1e-3 * amp.max())
    assert np.abs(half - eta0).max() > 0.5 * amp.max()


def test_spin_about_intermediate_axis_grows_at_the_rate_of_3_45():
    eps = 1e-6
    K, (I1, I2, I3) = linear_K("intermediate")
    lam2 = lambda_sq(I1, I2, I3)
    assert lam2 > 0  # (3.44): Case II
    lam = np.sqrt(lam2)
    A, B, C = I_PLATE
    assert lam == pytest.approx(W0 * np.sqrt((B - A) * (C - B) / (A * C)), rel=1e-14)
    t_end = np.log(1e-3 / eps) / lam  # until eta ~ 1e-3 w0: linear theory still holds
    r = mbcomp.simulate(ex.build(axis="intermediate", omega0=W0, eps=eps), t_end=t_end, n_out=401, **RUN)
    assert r.success, r.message
    i1, i2, i3 = ex.spin_axes("intermediate")
    w = body_rates(r)
    eta = w[:, [i2, i3]]
    eta0 = np.array([eps * W0, eps * W0])
    lin = np.array([expm(-K * t) @ eta0 for t in r.time])
    np.testing.assert_allclose(eta, lin, rtol=1e-5, atol=1e-6 * eps * W0)
    # growth rate measured from the simulation alone, late in the linear phase (the decaying
    # mode has died out): slope of log|eta| against t
    late = r.time > 0.5 * t_end
    slope = np.polyfit(r.time[late], np.log(np.linalg.norm(eta[late], axis=1)), 1)[0]
    assert slope == pytest.approx(lam, rel=1e-3)
    assert np.linalg.norm(eta[-1]) > 100 * np.linalg.norm(eta0)


def test_intermediate_spin_flips_and_extreme_spins_do_not():
    """Beyond the linear phase the intermediate-axis spin reverses (the plate turns over)
    while the same perturbation about the other axes stays within a few eps w0."""
    eps, t_end = 1e-3, 3.0
    r = mbcomp.simulate(ex.build(axis="intermediate", omega0=W0, eps=eps), t_end=t_end, n_out=601, **RUN)
    assert r.success, r.message
    w = body_rates(r)
    assert w[:, 1].min() < -0.9 * W0  # omega_y has reversed
    assert np.abs(w[:, [0, 2]]).max() > 0.5 * W0
    # the full Euler equations (3.37) give the same nonlinear flip
    ref = solve_ivp(euler_rhs, (0, t_end), ex.start_rate("intermediate", W0, eps), t_eval=r.time, **TIGHT)
    np.testing.assert_allclose(w, ref.y.T, rtol=0, atol=1e-8 * W0)


@pytest.mark.parametrize("axis", ["largest", "intermediate"])
def test_torque_free_invariants(axis):
    r = mbcomp.simulate(ex.build(axis=axis, omega0=W0, eps=1e-2), t_end=3.0, n_out=301, **RUN)
    assert r.success, r.message
    w = body_rates(r)
    I = np.diag(I_PLATE)
    T = 0.5 * np.einsum("ni,ij,nj->n", w, I, w)
    R = np.array([quat_to_matrix([r[f"plate.Q.{c}"][k] for c in "wxyz"]) for k in range(len(r.time))])
    L = np.einsum("nij,jk,nk->ni", R, I, w)  # world angular momentum about the centre of mass
    np.testing.assert_allclose(r["energy.kinetic"], T, rtol=1e-12)
    assert np.ptp(T) < 1e-9 * T[0]
    np.testing.assert_allclose(L, np.broadcast_to(L[0], L.shape), rtol=0, atol=1e-9 * np.linalg.norm(L[0]))
    # the body-axis rates from plate.w (world) agree with the joint's body-axis speeds
    w_world = np.column_stack([r[f"plate.w.{c}"] for c in "xyz"])
    np.testing.assert_allclose(np.einsum("nij,nj->ni", R, w), w_world, atol=1e-12 * W0)
    # the centre of mass does not move (no force, no start velocity)
    assert max(np.abs(r[f"plate.r.{c}"]).max() for c in "xyz") < 1e-12
