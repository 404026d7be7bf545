"""Ideal transmissions on joint axes (library/gears.py over assembly/flange_rows.py): a geared
pair against the reflected inertia, its tooth torque and energy on three backends, the DOF
count, a rack lifted by a pinion, a hoist's drum and rope, a belt, and rotors against rigid bodies."""
import numpy as np
import pytest

import mbcomp
from mbcomp.errors import ModelError
from mbcomp.library import (Belt, Fixed, FixedTranslation, IdealGear, IdealPulley, Inertia, PointMass, Prismatic,
                            RackPinion, Revolute, RigidBody, RotationalSpring, Torque, World)

TIGHT = dict(rtol=1e-12, atol=1e-12)


def _shaft(m, name, base, I_axial, **joint):
    """A shaft on a Revolute about z from ``base``: a body of axial inertia ``I_axial``."""
    j = m.add(name, Revolute(**joint))
    b = m.add(f"{name}_body", RigidBody(m=1.0, I=np.diag([1.0, 1.0, I_axial])))
    m.connect(base, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return j


def geared_pair(k=-3.0, I1=0.2, I2=1.5, tau=2.0, w1=1.0):
    """Shaft 1 (I1) driven by ``tau``, geared to shaft 2 (I2) by ``w1 = k w2``."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    j1 = _shaft(m, "j1", base.frame_b, I1, w0=w1)
    j2 = _shaft(m, "j2", base.frame_b, I2, phi0=0.1)
    g = m.add("gear", IdealGear(ratio=k))
    m.connect(g.flange_a, j1.axis)
    m.connect(g.flange_b, j2.axis)
    if tau:
        tq = m.add("motor", Torque(tau=tau))
        m.connect(tq.flange_b, j1.axis)
    return m


@pytest.fixture(scope="module")
def driven_runs():
    return {be: mbcomp.simulate(geared_pair(), t_end=1.0, backend=be, **TIGHT) for be in ("numeric", "python", "c")}


def test_a_geared_pair_accelerates_with_the_reflected_inertia_on_every_backend(driven_runs):
    k, I1, I2, tau = -3.0, 0.2, 1.5, 2.0
    a1 = tau / (I1 + I2 / k ** 2)  # the input's acceleration: I2 reflected through k^2
    ref = driven_runs["numeric"]
    t = ref["time"]
    for be, res in driven_runs.items():
        np.testing.assert_allclose(res["j1.w"], 1.0 + a1 * t, atol=1e-9, err_msg=be)
        np.testing.assert_allclose(res["j2.w"], (1.0 + a1 * t) / k, atol=1e-9, err_msg=be)
        np.testing.assert_allclose(res["j1.phi"] - k * (res["j2.phi"] - 0.1), 0.0, atol=1e-9)
        # the tooth torque on the input: what the motor gives beyond I1's own acceleration
        np.testing.assert_allclose(res["gear.tau_a"], -(tau - I1 * a1), atol=1e-9, err_msg=be)
        np.testing.assert_allclose(res["gear.tau_b"], -k * res["gear.tau_a"], atol=1e-9, err_msg=be)
        np.testing.assert_allclose(res["lambda.gear.mesh"], -res["gear.tau_a"], atol=1e-12)
        # the bearings take no axial torque: the gear's torques are applied, not reactions
        assert np.abs(res["j1.tau.z"]).max() < 1e-9 and np.abs(res["j2.tau.z"]).max() < 1e-9
        for col in ("j1.w", "j2.phi", "gear.tau_b", "energy.total"):
            np.testing.assert_allclose(res[col], ref[col], atol=1e-9, err_msg=f"{be} {col}")


def test_a_free_running_geared_pair_keeps_its_energy():
    for be in ("numeric", "c"):
        res = mbcomp.simulate(geared_pair(tau=0.0, w1=3.0), t_end=5.0, backend=be, **TIGHT)
        E = res["energy.total"]
        assert abs(E[0] - 0.5 * (0.2 + 1.5 / 9.0) * 9.0) < 1e-12
        assert np.abs(E - E[0]).max() < 1e-10, be


def test_the_gear_removes_one_configuration_dof():
    text = mbcomp.assemble(geared_pair()).summary()
    assert "degrees of freedom: 1 " in text and "= 6*2 - 11 - 0 = 1" in text
    assert "gear (1 rows)" in text


def _hinged_twice(gear_both):
    """A body on two coaxial Revolutes from the base (a loop: one is cut), geared to a third
    shaft from ``ja`` (and, with ``gear_both``, to a fourth from ``jb``)."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    body = m.add("body", RigidBody(m=1.0, I=np.eye(3)))
    ja, jb = m.add("ja", Revolute()), m.add("jb", Revolute())
    for j in (ja, jb):
        m.connect(base.frame_b, j.frame_a); m.connect(j.frame_b, body.frame_a)
    for joint, other in ((ja, "jc"), (jb, "jd"))[: 2 if gear_both else 1]:
        shaft = _shaft(m, other, base.frame_b, 1.0)
        g = m.add(f"gear_{other}", IdealGear(ratio=2.0))
        m.connect(g.flange_a, joint.axis); m.connect(g.flange_b, shaft.axis)
    return m


def test_a_geared_joint_stays_in_the_tree_and_a_geared_joint_that_must_be_cut_is_refused():
    """A geared angle measured on a cut joint would wrap at +-pi: the topology keeps geared
    joints in the tree (here it cuts jb, not ja), and refuses a loop of geared revolutes."""
    system = mbcomp.assemble(_hinged_twice(False))
    assert system.topology.cut == ["jb"]
    res = mbcomp.simulate(_hinged_twice(False), t_end=0.2, params={"jc.w0": 2.0})
    np.testing.assert_allclose(res["ja.w"], 2.0 * res["jc.w"], atol=1e-9)
    with pytest.raises(ModelError, match="closes a kinematic loop"):
        mbcomp.assemble(_hinged_twice(True))


def rack_and_pinion(Ip=0.02, m_rack=3.0, r=0.05):
    m = mbcomp.Model()
    world = m.add("world", World(g=(0, -9.81, 0)))
    pin = m.add("pinion", Revolute(n=(0, 0, 1)))
    m.add("pinion_body", RigidBody(m=1.0, I=np.diag([1.0, 1.0, Ip])))
    rack = m.add("rack", Prismatic(n=(0, 1, 0), s0=0.0, v0=0.0))
    m.add("rack_body", RigidBody(m=m_rack, I=np.eye(3)))
    rp = m.add("mesh", RackPinion(radius=r))
    m.connect(world.frame_b, pin.frame_a); m.connect(pin.frame_b, m["pinion_body"].frame_a)
    m.connect(world.frame_b, rack.frame_a); m.connect(rack.frame_b, m["rack_body"].frame_a)
    m.connect(rp.flange_a, pin.axis); m.connect(rp.flange_b, rack.axis)
    return m


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_a_rack_falls_against_its_pinion_with_the_closed_form_acceleration(backend):
    Ip, mr, r, g = 0.02, 3.0, 0.05, 9.81
    a = -mr * g * r ** 2 / (Ip + mr * r ** 2)  # rack: (Ip / r^2 + m) a = -m g
    res = mbcomp.simulate(rack_and_pinion(Ip, mr, r), t_end=0.5, backend=backend, **TIGHT)
    np.testing.assert_allclose(res["rack.s"], 0.5 * a * res["time"] ** 2, atol=1e-10)
    np.testing.assert_allclose(res["rack.s"], r * res["pinion.phi"], atol=1e-10)
    f_b = mr * (a + g)  # the tooth force holds the rack up by m (g + a)
    np.testing.assert_allclose(res["mesh.f_b"], f_b, atol=1e-8)
    np.testing.assert_allclose(res["mesh.tau_a"], -r * f_b, atol=1e-9)
    assert np.abs(res["energy.total"] - res["energy.total"][0]).max() < 1e-10


def hoist(J=0.04, m_load=2.5, r=0.08, g=9.81):
    """A drum (a rotor of inertia J on a Revolute about z) lowering a point mass on a rope: the
    rope's end on a Prismatic pointing down (away from the drum), gravity -y."""
    m = mbcomp.Model()
    world = m.add("world", World(g=(0, -g, 0)))
    drum = m.add("drum", Revolute(n=(0, 0, 1)))  # its frame_b stays open: the rotor is the drum
    rotor = m.add("drum_J", Inertia(J=J))
    rope_end = m.add("hook", Prismatic(n=(0, -1, 0)))
    m.add("load", PointMass(m=m_load))
    rope = m.add("rope", IdealPulley(radius=r))
    m.connect(world.frame_b, drum.frame_a); m.connect(rotor.flange, drum.axis)
    m.connect(world.frame_b, rope_end.frame_a); m.connect(rope_end.frame_b, m["load"].frame_a)
    m.connect(rope.flange_a, drum.axis); m.connect(rope.flange_b, rope_end.axis)
    return m


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_a_hoist_drum_lowers_its_load_with_the_closed_form_acceleration_and_tension(backend):
    J, ml, r, g = 0.04, 2.5, 0.08, 9.81
    a = ml * g * r ** 2 / (J + ml * r ** 2)  # (J / r^2 + m) a = m g
    res = mbcomp.simulate(hoist(J, ml, r, g), t_end=0.8, backend=backend, **TIGHT)
    t = res["time"]
    np.testing.assert_allclose(res["hook.s"], 0.5 * a * t ** 2, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["hook.v"], a * t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["drum.w"], a * t / r, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["rope.tension"], ml * (g - a), rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["rope.f_b"], -ml * (g - a), rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["rope.tau_a"], r * ml * (g - a), rtol=0, atol=1e-10)  # drives the drum on
    assert np.abs(res["energy.total"] - res["energy.total"][0]).max() < 1e-10
    assert res.units["rope.tension"] == "N" and res.units["rope.tau_a"] == "N m"


def test_a_belt_keeps_its_speed_ratio_and_the_energy():
    ra, rb, Ia, Ib = 0.1, 0.25, 0.3, 0.8
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    ja = _shaft(m, "ja", base.frame_b, Ia, w0=5.0)
    jb = _shaft(m, "jb", base.frame_b, Ib)
    belt = m.add("belt", Belt(r_a=ra, r_b=rb))
    spring = m.add("spring", RotationalSpring(c=4.0))  # a twist spring on b: the belt's tension varies
    m.connect(belt.flange_a, ja.axis); m.connect(belt.flange_b, jb.axis)
    m.connect(spring.flange_a, jb.support); m.connect(spring.flange_b, jb.axis)
    res = mbcomp.simulate(m, t_end=2.0, **TIGHT)
    np.testing.assert_allclose(ra * res["ja.w"], rb * res["jb.w"], atol=1e-10)
    np.testing.assert_allclose(res["belt.tau_a"] / ra + res["belt.tau_b"] / rb, 0.0, atol=1e-10)
    # the spring's torque reaches a through the belt: (Ia + Ib ra^2/rb^2) dwa/dt = -(ra/rb) c phi_b
    np.testing.assert_allclose(res["belt.f"], res["belt.tau_b"] / rb, rtol=1e-12)
    assert np.abs(res["belt.f"]).max() > 1.0
    assert np.abs(res["energy.total"] - res["energy.total"][0]).max() < 1e-10
    assert abs(res["energy.total"][0] - 0.5 * (Ia + Ib * (ra / rb) ** 2) * 25.0) < 1e-12


def _spun_shaft(J=None, body_axial=0.3, spring=True):
    """A shaft on a Revolute about z, spring-loaded: the axial inertia in the body, or a rotor."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    j = m.add("j", Revolute(phi0=0.4, w0=-1.0))
    b = m.add("b", RigidBody(m=2.0, r_cm=(0.0, 0.0, 0.3), I=np.diag([0.5, 0.7, body_axial])))
    m.connect(base.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    if J is not None:
        rotor = m.add("rotor", Inertia(J=J))
        m.connect(rotor.flange, j.axis)
    s = m.add("s", RotationalSpring(c=3.0))
    m.connect(s.flange_a, j.support); m.connect(s.flange_b, j.axis)
    return m


@pytest.mark.parametrize("backend", ["numeric", "python", "c"])
def test_a_rotor_on_a_fixed_axis_is_a_body_of_that_axial_inertia(backend):
    a = mbcomp.simulate(_spun_shaft(J=None, body_axial=0.3 + 0.45), t_end=2.0, backend=backend, **TIGHT)
    b = mbcomp.simulate(_spun_shaft(J=0.45, body_axial=0.3), t_end=2.0, backend=backend, **TIGHT)
    for col in ("j.phi", "j.w", "energy.total", "j.f.x", "j.tau.x", "j.tau.y", "j.tau.z"):
        np.testing.assert_allclose(b[col], a[col], atol=1e-10, err_msg=col)


def _gimbal(rotor_J=None, gyroscopic=True, axial=0.05):
    """A frame turning about x (a carrier), carrying a rotor spinning about the carrier's z."""
    m = mbcomp.Model()
    world = m.add("world", World(g=(0, 0, -9.81)))
    jx = m.add("jx", Revolute(n=(1, 0, 0), w0=0.8))
    carrier = m.add("carrier", RigidBody(m=1.0, r_cm=(0, 0.1, 0), I=np.diag([0.2, 0.3, 0.25])))
    jz = m.add("jz", Revolute(n=(0, 0, 1), w0=30.0))
    spin = m.add("spin", RigidBody(m=0.5, r_cm=(0, 0, 0.2), I=np.diag([0.05, 0.05, axial])))
    m.connect(world.frame_b, jx.frame_a); m.connect(jx.frame_b, carrier.frame_a)
    m.connect(carrier.frame_a, jz.frame_a); m.connect(jz.frame_b, spin.frame_a)
    if rotor_J is not None:
        rotor = m.add("rotor", Inertia(J=rotor_J, gyroscopic=gyroscopic))
        m.connect(rotor.flange, jz.axis)
    return m


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_a_gyroscopic_rotor_on_a_moving_carrier_is_a_body_of_that_axial_inertia(backend):
    full = mbcomp.simulate(_gimbal(axial=0.05 + 0.04), t_end=1.0, backend=backend, **TIGHT)
    rotor = mbcomp.simulate(_gimbal(rotor_J=0.04), t_end=1.0, backend=backend, **TIGHT)
    for col in ("jx.phi", "jx.w", "jz.w", "energy.total", "jx.tau.y", "jz.tau.x"):
        np.testing.assert_allclose(rotor[col], full[col], atol=1e-10, err_msg=col)
    # without it: the moment J (n . w) (w x n) = -J w_z w_x e_y (carrier axes) is about an axis the
    # carrier's bearing holds, so the motion and energy are the same and only that reaction differs
    flat = mbcomp.simulate(_gimbal(rotor_J=0.04, gyroscopic=False), t_end=1.0, backend=backend, **TIGHT)
    np.testing.assert_allclose(flat["jx.phi"], full["jx.phi"], atol=1e-10)
    assert np.abs(flat["energy.total"] - flat["energy.total"][0]).max() < 1e-10
    gyro = 0.04 * full["jz.w"] * full["jx.w"]
    assert np.abs(gyro).max() > 1.0
    np.testing.assert_allclose(np.abs(full["jx.tau.y"] - flat["jx.tau.y"]), np.abs(gyro), atol=1e-8)


def test_a_rotor_needs_a_rotational_axis_and_a_gear_its_kinds():
    m = rack_and_pinion()
    rotor = m.add("rotor", Inertia(J=0.1))
    m.connect(rotor.flange, m["rack"].axis)
    with pytest.raises(ModelError, match="rotor"):
        mbcomp.assemble(m)
    m = rack_and_pinion()
    g = m.add("gear", IdealGear(ratio=2.0))
    m.connect(g.flange_a, m["pinion"].axis); m.connect(g.flange_b, m["rack"].axis)
    with pytest.raises(ModelError, match="gear.flange_b"):
        mbcomp.assemble(m)


def test_a_rotor_alone_carries_the_shaft():
    """No body on the shaft: the rotor's J is all the inertia the Revolute moves."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    j = m.add("j", Revolute())
    hub = m.add("hub", FixedTranslation())
    rotor = m.add("rotor", Inertia(J=0.25))
    tq = m.add("tq", Torque(tau=lambda t, s, v: np.cos(t)))
    m.connect(base.frame_b, j.frame_a); m.connect(j.frame_b, hub.frame_a)
    m.connect(rotor.flange, j.axis); m.connect(tq.flange_b, j.axis)
    res = mbcomp.simulate(m, t_end=2.0, **TIGHT)
    np.testing.assert_allclose(res["j.w"], np.sin(res["time"]) / 0.25, atol=1e-9)


def _bare_shaft(rotor_on="axis", n=(0.0, 0.6, 0.8)):
    """A Revolute about the tilted axis ``n`` with nothing on its frame_b: a rotor (J = 0.4) on
    its ``axis`` (or ``support``, or none) and a torque 1.2 N m."""
    m = mbcomp.Model()
    m.add("world", World(g=(0.0, 0.0, -9.81)))
    j = m.add("j", Revolute(n=n))
    tq = m.add("tq", Torque(tau=1.2))
    m.connect(m["world"].frame_b, j.frame_a); m.connect(tq.flange_b, j.axis)
    if rotor_on:
        rotor = m.add("rotor", Inertia(J=0.4))
        m.connect(rotor.flange, getattr(j, rotor_on))
    return m


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_a_rotor_only_shaft_needs_no_frame_on_its_joint(backend):
    """Revolute + Inertia + Torque, frame_b open: J dw/dt = tau (gravity does no work on a rotor)."""
    res = mbcomp.simulate(_bare_shaft(), t_end=1.5, backend=backend, **TIGHT)
    t = res["time"]
    np.testing.assert_allclose(res["j.w"], 1.2 / 0.4 * t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res["j.phi"], 0.5 * 1.2 / 0.4 * t ** 2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res["energy.kinetic"], 0.5 * 0.4 * res["j.w"] ** 2, rtol=1e-13)


def test_an_open_frame_b_is_still_refused_without_a_rotor_on_the_axis():
    for rotor_on in (None, "support"):  # a rotor on the support turns with frame_a: frame_b moves nothing
        with pytest.raises(ModelError, match=r"j\.frame_b.*must join two frames"):
            mbcomp.assemble(_bare_shaft(rotor_on))


def test_a_motor_s_armature_carries_the_shaft_through_the_motor_s_flange():
    """The rotor reaches the axis through the motor's own flange (flange ports connected in a chain)."""
    from mbcomp.library import Motor

    m = mbcomp.Model()
    base = m.add("base", Fixed())
    j = m.add("j", Revolute())
    motor = m.add("motor", Motor(tau_stall=2.0, w_no_load=40.0, J_armature=0.05))
    m.connect(base.frame_b, j.frame_a); m.connect(motor.flange_b, j.axis)
    res = mbcomp.simulate(m, t_end=1.0, **TIGHT)
    exact = 40.0 * (1 - np.exp(-res["time"] * 2.0 / (0.05 * 40.0)))
    np.testing.assert_allclose(res["j.w"], exact, rtol=0, atol=1e-9)
