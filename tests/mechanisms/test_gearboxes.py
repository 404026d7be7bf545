"""Gearboxes from ideal gears (library/gears.py): a planetary set's Willis equation and torque
split, and a two-stage gearbox driven by the library's Motor (the seed's torque-speed law with
an armature inertia) into a viscous load, reaching the closed-form balance speed with a closed
energy balance; the same gearbox driven by a Torque law with the armature added to the input
shaft runs the same motion."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import (FixedTranslation, Fixed, IdealGear, Inertia, Motor, PlanetaryGear, PrescribedMotion,
                            Revolute, RotationalDamper, Torque)

TIGHT = dict(rtol=1e-11, atol=1e-12)
ZS, ZR = 18, 72


def planetary(ring_held, T_sun=1.5, d=0.4, T_ring=-0.7):
    """A planetary set: a torque on the sun, a viscous load on the carrier, and the ring either
    held by a drive (s = 0) or free with a torque of its own."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    pg = m.add("pg", PlanetaryGear(z_sun=ZS, z_ring=ZR, J_sun=0.01, J_carrier=0.05, J_ring=0.08))
    m.connect(base.frame_b, pg.frame_a)
    ts = m.add("T_sun", Torque(tau=T_sun))
    load = m.add("load", RotationalDamper(d=d))
    m.connect(ts.flange_b, pg.sun)
    m.connect(load.flange_a, m["pg"]["carrier"].support)
    m.connect(load.flange_b, pg.carrier)
    if ring_held:
        hold = m.add("hold", PrescribedMotion(s=0.0))
        m.connect(hold.flange_b, pg.ring)
    else:
        tr = m.add("T_ring", Torque(tau=T_ring))
        m.connect(tr.flange_b, pg.ring)
    return m


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_a_planetary_set_keeps_willis_equation_along_a_driven_run(backend):
    res = mbcomp.simulate(planetary(ring_held=False), t_end=3.0, backend=backend, **TIGHT)
    ws, wc, wr = res["pg.sun.w"], res["pg.carrier.w"], res["pg.ring.w"]
    assert np.abs(wr - wc).max() > 1.0  # a run that moves the ring against the carrier
    willis = (ws - wc) + (ZR / ZS) * (wr - wc)
    assert np.abs(willis).max() < 1e-9 * np.abs(ws).max()
    moving = np.abs(wr - wc) > 0.1
    np.testing.assert_allclose((ws - wc)[moving] / (wr - wc)[moving], -ZR / ZS, rtol=1e-9)
    # the mesh's torques: ring over sun in the teeth ratio, the carrier takes the rest
    np.testing.assert_allclose(res["pg.mesh.tau_b"], (ZR / ZS) * res["pg.mesh.tau_a"], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["pg.mesh.tau_support"], -(res["pg.mesh.tau_a"] + res["pg.mesh.tau_b"]),
                               atol=1e-10)
    scale = np.abs(res["energy.kinetic"]).max() + np.abs(res["energy.dissipated"]).max()
    assert np.abs(res["energy.balance"]).max() < 1e-8 * scale


def test_a_planetary_set_with_a_held_ring_reaches_the_closed_form_steady_state():
    """Ring held: w_sun = (1 + z_r/z_s) w_carrier; the load d w_c takes (1 + z_r/z_s) T_sun and
    the ring's holding torque is (z_r/z_s) T_sun (the torque split)."""
    T, d = 1.5, 0.4
    res = mbcomp.simulate(planetary(ring_held=True, T_sun=T, d=d), t_end=40.0, **TIGHT)
    i = 1.0 + ZR / ZS
    np.testing.assert_allclose(res["pg.sun.w"], i * res["pg.carrier.w"], rtol=1e-8)
    np.testing.assert_allclose(res["pg.carrier.w"][-1], i * T / d, rtol=1e-8)
    # steady state: the sun's shaft takes T from the motor and -T from the teeth
    np.testing.assert_allclose(res["pg.mesh.tau_a"][-1], -T, rtol=1e-8)
    np.testing.assert_allclose(res["pg.mesh.tau_b"][-1] / res["pg.mesh.tau_a"][-1], ZR / ZS, rtol=1e-10)
    np.testing.assert_allclose(res["hold.tau"][-1], (ZR / ZS) * T, rtol=1e-8)


def _shaft(m, name, base, J, **start):
    j = m.add(name, Revolute(**start))
    hub = m.add(f"{name}_hub", FixedTranslation())
    rotor = m.add(f"{name}_J", Inertia(J=J))
    m.connect(base, j.frame_a)
    m.connect(j.frame_b, hub.frame_a)
    m.connect(rotor.flange, j.axis)
    return j


def two_stage(k1=4.0, k2=-2.5, tau0=3.0, w0=50.0, d=6.0, J=(0.01, 0.03, 0.4), J_a=0.006, stand_in=False):
    """Input shaft 1 driven by a motor ``tau0 (1 - w/w0)`` with armature inertia ``J_a``, geared
    1 -> 2 by k1, 2 -> 3 by k2 (``w_a = k w_b``), a viscous load d on shaft 3. ``stand_in``: the
    motor is a Torque law instead and ``J_a`` is added to shaft 1's rotor."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    J = (J[0] + J_a * stand_in,) + tuple(J[1:])
    s1, s2, s3 = (_shaft(m, f"s{i + 1}", base.frame_b, J[i]) for i in range(3))
    if stand_in:
        motor = m.add("motor", Torque(tau=lambda t, s, v: tau0 * (1.0 - v / w0)))
    else:
        motor = m.add("motor", Motor(tau_stall=tau0, w_no_load=w0, J_armature=J_a))
    load = m.add("load", RotationalDamper(d=d))
    g1, g2 = m.add("g1", IdealGear(ratio=k1)), m.add("g2", IdealGear(ratio=k2))
    m.connect(motor.flange_b, s1.axis)
    m.connect(g1.flange_a, s1.axis); m.connect(g1.flange_b, s2.axis)
    m.connect(g2.flange_a, s2.axis); m.connect(g2.flange_b, s3.axis)
    m.connect(load.flange_a, s3.support); m.connect(load.flange_b, s3.axis)
    return m


@pytest.mark.parametrize("backend", ["numeric", "python", "c"])
def test_a_two_stage_gearbox_reaches_the_speed_where_motor_and_load_balance(backend):
    k1, k2, tau0, w0, d = 4.0, -2.5, 3.0, 50.0, 6.0
    k = k1 * k2
    res = mbcomp.simulate(two_stage(k1, k2, tau0, w0, d), t_end=30.0, backend=backend, **TIGHT)
    # steady state: tau0 (1 - w1/w0) k = d w3 = d w1 / k
    w1 = tau0 * k / (d / k + tau0 * k / w0)
    np.testing.assert_allclose(res["s1.w"][-1], w1, rtol=1e-8)
    np.testing.assert_allclose(res["s3.w"][-1], w1 / k, rtol=1e-8)
    np.testing.assert_allclose(res["s1.w"], k * res["s3.w"], rtol=1e-9)
    # in steady state the output shaft's tooth torque carries the load
    np.testing.assert_allclose(res["g2.tau_b"][-1], d * w1 / k, rtol=1e-8)


def test_the_gearbox_energy_balance_closes():
    """The motor's work = kinetic energy (the armature's too) + the load's dissipation (a grid
    fine enough for the quadrature of the spin-up transient, time constant ~0.13 s)."""
    J_a, J = 0.006, (0.01, 0.03, 0.4)
    res = mbcomp.simulate(two_stage(J=J, J_a=J_a), t_end=1.0, n_out=20001, backend="c", **TIGHT)
    scale = np.abs(res["energy.kinetic"]).max() + np.abs(res["energy.dissipated"]).max()
    assert np.abs(res["energy.balance"]).max() < 1e-8 * scale
    assert res["energy.dissipated"][-1] > 0.2 * scale  # the balance is not trivially small
    shafts = (J[0] + J_a) * res["s1.w"] ** 2 + J[1] * res["s2.w"] ** 2 + J[2] * res["s3.w"] ** 2
    np.testing.assert_allclose(res["energy.kinetic"], 0.5 * shafts, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res["motor.power"], res["motor.tau"] * res["s1.w"], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_the_library_motor_runs_as_a_torque_law_with_the_armature_on_the_shaft(backend):
    a = mbcomp.simulate(two_stage(), t_end=2.0, backend=backend, **TIGHT)
    b = mbcomp.simulate(two_stage(stand_in=True), t_end=2.0, backend=backend, **TIGHT)
    for col in ("s1.w", "s3.phi", "g2.tau_b", "energy.kinetic"):
        np.testing.assert_allclose(a[col], b[col], rtol=1e-9, atol=1e-10, err_msg=col)
    np.testing.assert_allclose(a["motor.tau"], 3.0 * (1 - a["s1.w"] / 50.0), atol=1e-12)


def test_the_gearbox_backends_agree():
    runs = [mbcomp.simulate(two_stage(), t_end=2.0, backend=be, **TIGHT) for be in ("numeric", "python", "c")]
    for col in ("s1.w", "s3.phi", "g1.tau_a", "g2.tau_b", "lambda.g1.mesh", "energy.total"):
        for r in runs[1:]:
            np.testing.assert_allclose(r[col], runs[0][col], atol=1e-9, err_msg=col)


def test_the_gearbox_info_counts_one_dof():
    text = mbcomp.assemble(two_stage()).summary()
    assert "degrees of freedom: 1 " in text and "g1 (1 rows), g2 (1 rows)" in text
