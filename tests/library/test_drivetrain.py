"""Drivetrain flange elements (library/drivetrain.py) against closed-form motions.

* ElastoGear between two shafts on hinges: the two-inertia frequency
  ``sqrt(c (1/I1 + ratio^2/I2))`` (deflection ``e = s_a - ratio s_b``: ``I1 e'' = -tau - ratio^2
  (I1/I2) tau``), with damping the damped frequency; with backlash the whole piecewise
  motion (free flight across the gap in ``backlash / de``, half a spring period on a flank,
  free flight back); the energy balance through contacts and the damping that never pulls;
* BearingFriction on a flywheel: exponential decay (viscous), the tanh-regularized Coulomb
  decay in closed form and its stop time against the exact Coulomb one;
* Motor (seed section 4.7, ``Md = M0 - dM w``) on a flywheel from rest, with and without a
  viscous load, and with its armature inertia (``J + J_a`` in the time constant).
"""
import warnings

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

import mbcomp
from mbcomp.errors import ModelError
from mbcomp.library import BearingFriction, ElastoGear, Motor, MotorTorque, Revolute, RigidBody, World

TIGHT = dict(rtol=1e-11, atol=1e-13)


def shaft(m, name, I, phi0=0.0, w0=0.0):
    """A disk of axial inertia ``I`` (kg m^2) on a hinge about world z: returns the hinge."""
    hinge = m.add(name, Revolute(n=(0, 0, 1), phi0=phi0, w0=w0))
    disk = m.add(f"{name}_disk", RigidBody(m=1.0, I=np.diag([I, I, I])))
    m.connect(m["world"].frame_b, hinge.frame_a)
    m.connect(hinge.frame_b, disk.frame_a)
    return hinge


def geared_shafts(gear, I1, I2, phi1=0.0, w1=0.0, phi2=0.0, w2=0.0):
    m = mbcomp.Model()
    m.add("world", World(g=(0, 0, 0)))
    a, b = shaft(m, "a", I1, phi1, w1), shaft(m, "b", I2, phi2, w2)
    g = m.add("gear", gear)
    m.connect(g.flange_a, a.axis)
    m.connect(g.flange_b, b.axis)
    return m


def flywheel(I, w0, *elements):
    """A flywheel (axial inertia I) spinning at w0 about world z, with flange elements on its
    hinge (two-flange ones between support and axis)."""
    m = mbcomp.Model()
    m.add("world", World(g=(0, 0, 0)))
    hub = shaft(m, "hub", I, 0.0, w0)
    for name, el in elements:
        m.add(name, el)
        if "flange_a" in el.ports():
            m.connect(el.flange_a, hub.support)
        m.connect(el.flange_b, hub.axis)
    return m


def zero_crossings(t, y):
    """Times where ``y`` changes sign, refined on a cubic spline of the samples."""
    spline = CubicSpline(t, y)
    idx = np.nonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)[0]
    return np.array([min((r for r in spline.roots(extrapolate=False) if t[i] <= r <= t[i + 1]),
                         key=lambda r: abs(spline(r))) for i in idx])


def measured_frequency(t, y):
    """Angular frequency (rad/s) from the spacing of the zero crossings (least squares)."""
    tz = zero_crossings(t, y)
    assert len(tz) >= 10
    half_period = np.polyfit(np.arange(len(tz)), tz, 1)[0]
    return np.pi / half_period


# ==========================================================================================
# ElastoGear
# ==========================================================================================
C, I1, I2, RATIO = 40.0, 0.5, 3.0, 2.5
K = 1 / I1 + RATIO ** 2 / I2  # e'' = -K tau


def test_gear_without_backlash_oscillates_at_the_two_inertia_frequency():
    res = mbcomp.simulate(geared_shafts(ElastoGear(c=C, ratio=RATIO), I1, I2, phi1=0.1, w1=0.3, w2=0.2),
                          t_end=5.0, n_out=20001, **TIGHT)
    assert res.stats["backend"] == "c"
    e = res["gear.deflection"]
    np.testing.assert_allclose(e, res["a.phi"] - RATIO * res["b.phi"], atol=1e-15)
    omega = np.sqrt(C * K)
    assert abs(measured_frequency(res.time, e) / omega - 1) < 1e-6
    # closed form e(t) = e0 cos(w t) + de0/w sin(w t); rigid-mesh momentum ratio I1 w_a + I2 w_b
    e0, de0 = 0.1, 0.3 - RATIO * 0.2
    np.testing.assert_allclose(e, e0 * np.cos(omega * res.time) + de0 / omega * np.sin(omega * res.time), atol=1e-9)
    h = RATIO * I1 * res["a.w"] + I2 * res["b.w"]
    np.testing.assert_allclose(h, h[0], atol=1e-10)
    np.testing.assert_allclose(res["gear.tau"], C * e, atol=1e-12)
    assert abs(res["energy.total"] - res["energy.total"][0]).max() < 1e-10


def test_damped_gear_without_backlash_is_a_linear_spring_damper():
    d = 0.4
    res = mbcomp.simulate(geared_shafts(ElastoGear(c=C, d=d, ratio=RATIO), I1, I2, phi1=0.1),
                          t_end=4.0, n_out=20001, **TIGHT)
    e, de = res["gear.deflection"], res["gear.w_rel"]
    sigma = d * K / 2  # e'' + d K e' + c K e = 0
    omega_d = np.sqrt(C * K - sigma ** 2)
    assert abs(measured_frequency(res.time, e) / omega_d - 1) < 1e-6
    np.testing.assert_allclose(res["gear.tau"], C * e + d * de, atol=1e-12)  # pulls too: no flank separates
    assert (res["gear.tau"] < 0).any() and (res["gear.tau"] > 0).any()
    exact = 0.1 * np.exp(-sigma * res.time) * (np.cos(omega_d * res.time)
                                               + sigma / omega_d * np.sin(omega_d * res.time))
    np.testing.assert_allclose(e, exact, atol=1e-9)


def rattle(t, b, v, omega):
    """Deflection of an undamped gear with backlash ``b``, started at ``e = -b/2`` moving
    apart at ``v > 0``: flight across the gap (``b / v``), half a spring period on the positive
    flank, flight back, half a period on the negative flank, and again."""
    h, flight, contact = b / 2, b / v, np.pi / omega
    tau = np.mod(t, 2 * (flight + contact))
    out = np.empty_like(t)
    for k, tk in enumerate(tau):
        if tk < flight:
            out[k] = -h + v * tk
        elif tk < flight + contact:
            out[k] = h + v / omega * np.sin(omega * (tk - flight))
        elif tk < 2 * flight + contact:
            out[k] = h - v * (tk - flight - contact)
        else:
            out[k] = -h - v / omega * np.sin(omega * (tk - 2 * flight - contact))
    return out


def test_backlash_free_flight_then_spring_in_closed_form():
    b, w1 = 0.05, 0.3  # gap crossed at de = w1 (flange_b at rest): in 1/6 s
    gear = ElastoGear(c=C, backlash=b, ratio=RATIO)
    res = mbcomp.simulate(geared_shafts(gear, I1, I2, phi1=-b / 2, w1=w1), t_end=2.0, n_out=8001, **TIGHT)
    assert res.stats["backend"] == "c"
    t, e, tau = res.time, res["gear.deflection"], res["gear.tau"]
    omega = np.sqrt(C * K)
    t_contact = b / w1
    free = t < t_contact
    assert np.abs(tau[free]).max() < 1e-13                       # no torque in the gap (to rounding)
    np.testing.assert_allclose(res["b.w"][free], 0.0, atol=1e-15)
    first = np.argmax(tau > 1e-12)                               # the first sample in contact
    assert t[first - 1] < t_contact <= t[first]
    np.testing.assert_allclose(e, rattle(t, b, w1, omega), atol=1e-8)
    assert e.min() < -b / 2 - 1e-3 and e.max() > b / 2 + 1e-3  # both flanks were hit
    assert abs(res["energy.total"] - res["energy.total"][0]).max() < 1e-10


def test_backlash_damping_never_pulls_and_energy_balances():
    b, d = 0.05, 0.6
    gear = ElastoGear(c=C, d=d, backlash=b, ratio=RATIO)
    res = mbcomp.simulate(geared_shafts(gear, I1, I2, phi1=-0.02, w1=0.5), t_end=2.0, n_out=8001, **TIGHT)
    e, de, tau = res["gear.deflection"], res["gear.w_rel"], res["gear.tau"]
    h = b / 2
    pos, neg, gap = e > h, e < -h, np.abs(e) <= h
    assert pos.any() and neg.any() and gap.any()
    assert np.abs(tau[gap]).max() < 1e-13 and tau[pos].min() > -1e-13 and tau[neg].max() < 1e-13
    spring = C * (e - np.clip(e, -h, h))
    free_damper = spring + d * de                            # the unlimited law
    pulls = (pos & (free_damper < 0)) | (neg & (free_damper > 0))
    assert pulls.any()                                       # the limit was needed ...
    assert np.abs(tau[pulls]).max() < 1e-13                  # ... and the teeth let go
    expect = np.where(pos, np.maximum(0, spring + np.minimum(spring, d * de)),
                      np.where(neg, np.minimum(0, spring + np.maximum(spring, d * de)), 0.0))
    np.testing.assert_allclose(tau, expect, atol=1e-12)
    dissipated = res["energy.dissipated"]
    assert dissipated[-1] > 0.3 * (res["energy.total"][0] - res["energy.total"][-1]) > 0
    assert (-(tau - spring) * de).max() <= 0.0                 # the damping never gives energy back,
    assert res["gear.power_nc"].max() < 1e-5                   # up to the column's difference (c dt de^2)
    lost = res["energy.total"][0] - res["energy.total"][-1]
    assert abs(dissipated[-1] - lost) < 2e-6 * lost
    assert abs(res["energy.balance"]).max() < 2e-6 * res["energy.total"][0]  # 7e-7 on this grid


# ==========================================================================================
# BearingFriction
# ==========================================================================================
IW, W0 = 0.5, 10.0


def test_viscous_bearing_decays_exponentially():
    d = 0.3
    res = mbcomp.simulate(flywheel(IW, W0, ("bearing", BearingFriction(d=d))), t_end=3.0, n_out=301, **TIGHT)
    np.testing.assert_allclose(res["hub.w"], W0 * np.exp(-d / IW * res.time), rtol=1e-9)
    np.testing.assert_allclose(res["bearing.tau"], d * res["hub.w"], rtol=1e-12)
    np.testing.assert_allclose(res["bearing.power"], -d * res["hub.w"] ** 2, rtol=1e-12)


def log_sinh(x):
    return x + np.log1p(-np.exp(-2 * x)) - np.log(2)


def test_coulomb_bearing_stops_in_the_coulomb_time():
    tau_c, ws = 2.0, 1e-3
    a = tau_c / IW
    t_stop = W0 / a  # exact Coulomb: w = W0 - a t, stops at 2.5 s
    res = mbcomp.simulate(flywheel(IW, W0, ("bearing", BearingFriction(tau_c=tau_c, w_smooth=ws))),
                          t_end=1.1 * t_stop, n_out=2201, **TIGHT)
    t, w = res.time, res["hub.w"]
    # the tanh law in closed form: ws ln sinh(w/ws) = ws ln sinh(W0/ws) - a t
    L = log_sinh(W0 / ws) - a * t / ws  # = ln sinh(w / ws)
    exact = ws * np.where(L > 20, L + np.log(2), np.arcsinh(np.exp(np.minimum(L, 20))))  # asinh(e^L)
    np.testing.assert_allclose(w, exact, atol=1e-8)
    sliding = t < t_stop - 0.01
    np.testing.assert_allclose(w[sliding], W0 - a * t[sliding], atol=1e-8)  # tanh = 1 to 1e-8 here
    stop = zero_crossings(t, w - ws)[0]                                      # where w = w_smooth
    assert abs(stop / t_stop - 1) < 1e-3
    assert abs(w[-1]) < ws * 1e-3                                           # and it stays stopped


def test_viscous_and_coulomb_bearing_stop_time():
    d, tau_c, ws = 0.4, 1.0, 1e-4
    t_stop = IW / d * np.log(1 + d * W0 / tau_c)  # I w' = -d w - tau_c
    res = mbcomp.simulate(flywheel(IW, W0, ("bearing", BearingFriction(d=d, tau_c=tau_c, w_smooth=ws))),
                          t_end=1.05 * t_stop, n_out=4001, **TIGHT)
    stop = zero_crossings(res.time, res["hub.w"] - ws)[0]
    assert abs(stop / t_stop - 1) < 1e-3
    assert res["energy.dissipated"][-1] == pytest.approx(0.5 * IW * W0 ** 2, rel=1e-6)


# ==========================================================================================
# Motor (seed section 4.7: Md = M0 - dM w, M0 = tau_stall, dM = tau_stall / w_no_load)
# ==========================================================================================
TS, WNL, J = 0.8, 50.0, 0.02


def test_motor_spins_a_flywheel_up_as_the_linear_law_says():
    res = mbcomp.simulate(flywheel(J, 0.0, ("motor", Motor(tau_stall=TS, w_no_load=WNL))),
                          t_end=5.0, n_out=501, **TIGHT)
    assert res.stats["backend"] == "c"
    # J w' = TS (1 - w / WNL): w = WNL (1 - exp(-t TS / (J WNL)))
    exact = WNL * (1 - np.exp(-res.time * TS / (J * WNL)))
    np.testing.assert_allclose(res["hub.w"] / WNL, exact / WNL, atol=1e-8)
    np.testing.assert_allclose(res["motor.tau"], TS * (1 - res["hub.w"] / WNL), atol=1e-12)
    np.testing.assert_allclose(res["motor.power"], res["motor.tau"] * res["hub.w"], atol=1e-12)


def test_motor_against_viscous_load_settles_where_torques_balance():
    d = 0.01
    w_ss = TS / (d + TS / WNL)  # TS (1 - w/WNL) = d w: 30.8 rad/s
    res = mbcomp.simulate(flywheel(J, 0.0, ("motor", Motor(tau_stall=TS, w_no_load=WNL)),
                                   ("bearing", BearingFriction(d=d))), t_end=20.0, n_out=2001, **TIGHT)
    exact = w_ss * (1 - np.exp(-(d + TS / WNL) * res.time / J))
    np.testing.assert_allclose(res["hub.w"] / WNL, exact / WNL, atol=1e-8)
    assert res["hub.w"][-1] == pytest.approx(w_ss, rel=1e-8)
    assert abs(res["energy.balance"]).max() < 1e-6 * res["energy.total"][-1]


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_motor_armature_inertia_adds_to_the_load(backend):
    Ja = 0.013
    res = mbcomp.simulate(flywheel(J, 0.0, ("motor", Motor(tau_stall=TS, w_no_load=WNL, J_armature=Ja))),
                          t_end=5.0, n_out=501, backend=backend, **TIGHT)
    assert res.stats["backend"] == backend
    # (J + Ja) w' = TS (1 - w / WNL): w = WNL (1 - exp(-t TS / ((J + Ja) WNL)))
    exact = WNL * (1 - np.exp(-res.time * TS / ((J + Ja) * WNL)))
    err = np.abs(res["hub.w"] - exact).max() / WNL
    assert err < 1e-8, err
    np.testing.assert_allclose(res["motor.w"], res["hub.w"], atol=1e-14)
    np.testing.assert_allclose(res["motor.tau"], TS * (1 - res["hub.w"] / WNL), atol=1e-12)
    # the motor's work is the kinetic energy of flywheel and armature
    work = np.concatenate([[0.0], np.cumsum(np.diff(res.time) * 0.5 * (res["motor.power"][1:] + res["motor.power"][:-1]))])
    np.testing.assert_allclose(res["energy.kinetic"], 0.5 * (J + Ja) * res["hub.w"] ** 2, rtol=1e-12, atol=1e-14)
    assert abs(res["energy.balance"]).max() < 1e-6 * res["energy.total"][-1]
    assert abs(work[-1] - res["energy.kinetic"][-1]) < 1e-3 * res["energy.kinetic"][-1]


def test_motor_armature_is_a_rotor_and_parameters_change_at_run_time():
    m = flywheel(J, 0.0, ("motor", Motor(tau_stall=TS, w_no_load=WNL, J_armature=0.01)))
    res = mbcomp.simulate(m, t_end=1.0, params={"motor.armature.J": 0.03, "motor.torque.tau_stall": 2 * TS}, **TIGHT)
    exact = WNL * (1 - np.exp(-res.time * 2 * TS / ((J + 0.03) * WNL)))
    assert np.abs(res["hub.w"] - exact).max() < 1e-8 * WNL


def test_motor_refuses_bad_armature_inertia_and_unknown_laws_by_name():
    for bad in (-1e-3, "heavy", float("nan")):
        with pytest.raises(ValueError, match="J_armature") as err:
            Motor(tau_stall=TS, w_no_load=WNL, J_armature=bad)
        assert "fix" in str(err.value)
    (problem,) = MotorTorque(law="quadratic").problems()
    assert problem.where.endswith(".law") and "'linear'" in problem.fix
    with pytest.raises(ModelError) as err:
        mbcomp.simulate(flywheel(J, 0.0, ("motor", Motor(law="quadratic"))), t_end=0.1)
    assert "motor.torque.law" in str(err.value)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert MotorTorque(tau_stall=TS, w_no_load=WNL).problems() == []
