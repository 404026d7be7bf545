"""``Model.lock`` and ``mbcomp.reduce``: joints held as rigid connections, what hangs on their
flanges, the errors. Closed forms on small library models; the real robots against
Pinocchio's ``buildReducedModel`` are in ``tests/io/test_lock.py``.

The arm of these tests: a hinge ``a`` about z at the world origin, a point mass ``m1`` at
``L1`` along x, a hinge ``b`` about z there, a point mass ``m2`` at ``L2`` along x beyond it.
Locked at ``b = beta`` the arm is one rigid body about ``a``:
``M = m1 L1^2 + m2 (L1^2 + L2^2 + 2 L1 L2 cos beta)``.
"""
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.errors import ModelError
from mbcomp.library import (FixedTranslation, IdealGear, Inertia, PointMass, PrescribedMotion, Revolute,
                            RotationalDamper, World)

M1, M2, L1, L2 = 1.5, 0.7, 0.8, 0.5


def _arm(b_kw=None, gravity=(0.0, 0.0, 0.0)):
    m = mbcomp.Model()
    w = m.add("world", World(g=gravity))
    a = m.add("a", Revolute(n=(0, 0, 1)))
    r1 = m.add("r1", FixedTranslation(r=(L1, 0, 0)))
    p1 = m.add("p1", PointMass(m=M1))
    b = m.add("b", Revolute(n=(0, 0, 1), **(b_kw or {})))
    r2 = m.add("r2", FixedTranslation(r=(L2, 0, 0)))
    p2 = m.add("p2", PointMass(m=M2))
    m.connect(w.frame_b, a.frame_a)
    m.connect(a.frame_b, r1.frame_a)
    m.connect(r1.frame_b, p1.frame_a)
    m.connect(r1.frame_b, b.frame_a)
    m.connect(b.frame_b, r2.frame_a)
    m.connect(r2.frame_b, p2.frame_a)
    return m


def _composite(beta):
    return M1 * L1 ** 2 + M2 * (L1 ** 2 + L2 ** 2 + 2 * L1 * L2 * np.cos(beta))


@pytest.mark.parametrize("beta", [0.0, 0.9, -2.4])
def test_locked_elbow_is_one_composite_body(beta):
    held = _arm().lock(["b"], at={"b": beta})
    system = mbcomp.assemble(held)
    assert system.q_names == ["a.phi"]
    links = system.topology.links  # what the recursive algorithms (CRBA, RNEA, ABA) walk: one composite body
    assert links.n == 1 and [e.name for e in links.edges] == ["a"] and mbcomp.assemble(_arm()).topology.links.n == 2
    ev = system.evaluate(0.0, np.array([0.4]), np.array([1.3]))
    assert ev.M[0, 0] == pytest.approx(_composite(beta), rel=1e-14)
    assert ev.f[0] == pytest.approx(0.0, abs=1e-13)  # no gravity, one rigid body turning about a fixed axis
    assert held.locked == {"b": {"phi": beta}}


def test_default_is_the_start_value_and_the_original_is_unchanged():
    m = _arm(b_kw={"phi0": 0.6})
    held = m.lock("b")
    assert held.locked == {"b": {"phi": 0.6}}
    assert m.locked == {} and isinstance(m["b"], Revolute) and m["b"].parent is m
    assert mbcomp.assemble(m).q_names == ["a.phi", "b.phi"]  # the original still moves both
    assert held["b"] is not m["b"] and held["a"] is not m["a"]  # a copy: nothing shared to change
    assert mbcomp.assemble(held).evaluate(0.0, np.zeros(1), np.zeros(1)).M[0, 0] == pytest.approx(_composite(0.6))
    assert held.lock_notes == []


def test_reduce_keeps_what_is_asked_and_locking_twice_accumulates():
    m = _arm()
    only_b = mbcomp.reduce(m, keep=["b"], at={"a": 0.3})
    system = mbcomp.assemble(only_b)
    assert system.q_names == ["b.phi"] and only_b.locked == {"a": {"phi": 0.3}}
    ev = system.evaluate(0.0, np.array([0.2]), np.zeros(1))
    assert ev.M[0, 0] == pytest.approx(M2 * L2 ** 2, rel=1e-14)
    both = _arm().lock("a", at={"a": 0.1}).lock("b", at={"b": -0.4})
    assert both.locked == {"a": {"phi": 0.1}, "b": {"phi": -0.4}}
    assert mbcomp.assemble(both).q_names == []


def test_locked_columns_keep_the_joints_names_and_the_reaction_holds_the_elbow():
    """A held elbow under gravity along -y, the shoulder swinging: ``b.phi`` stays its held
    value, ``b.w`` zero, and the lock's reaction torque about z is what holds the outer mass
    (its moment about the elbow: gravity and the centripetal and tangential inertia)."""
    beta = 0.7
    held = _arm(gravity=(0.0, -9.81, 0.0)).lock("b", at={"b": beta})
    res = mbcomp.simulate(held, t_end=0.3, backend="numeric", dt_out=0.1)
    assert res.status == "success"
    np.testing.assert_array_equal(res["b.phi"], beta)
    np.testing.assert_array_equal(res["b.w"], 0.0)
    assert (res.units["b.phi"], res.units["b.w"], res.units["b.tau.z"]) == ("rad", "rad/s", "N m")
    # at t = 0 (rest, phi = 0): the composite's angular acceleration from gravity's moment about a
    alpha = -9.81 * (M1 * L1 + M2 * (L1 + L2 * np.cos(beta))) / _composite(beta)
    e = L2 * np.array([np.cos(beta), np.sin(beta), 0.0])  # elbow -> outer mass
    a_p2 = alpha * np.cross([0, 0, 1.0], e + [L1, 0, 0])
    need = np.cross(e, M2 * a_p2 - M2 * np.array([0.0, -9.81, 0.0]))[2]  # torque the joint puts on link 2
    assert res["b.tau.z"][0] == pytest.approx(need, rel=1e-12)
    assert abs(need) > 1.0  # a load the lock carries


def test_a_damper_on_the_locked_joint_is_dropped_and_said():
    m = _arm()
    d = m.add("damper", RotationalDamper(d=2.0))
    m.connect(m["b"].support, d.flange_a)
    m.connect(m["b"].axis, d.flange_b)
    with pytest.warns(UserWarning, match="damper"):
        held = m.lock("b")
    assert "damper" not in held.components() and "damper" in m.components()
    assert any("RotationalDamper 'damper' on locked b: dropped" in n for n in held.lock_notes)
    assert "dropped with the locks: RotationalDamper 'damper'" in mbcomp.assemble(held).summary()


def test_stops_of_the_locked_joint_are_said():
    with pytest.warns(UserWarning, match="own modes"):
        held = _arm(b_kw={"limits": (-1.0, 1.0)}).lock("b", at={"b": 0.2})
    assert any("StopModes" in n for n in held.lock_notes)


def test_a_drive_on_the_locked_joint_is_an_error_naming_both():
    m = _arm()
    d = m.add("hold", PrescribedMotion(s=0.2))
    m.connect(d.flange_b, m["b"].axis)
    with pytest.raises(ModelError, match=r"hold: the PrescribedMotion drives joint 'b', which is to be locked"):
        m.lock("b")


def _geared():
    m = _arm()
    g = m.add("gear", IdealGear(ratio=2.0))
    m.connect(g.flange_a, m["a"].axis)
    m.connect(g.flange_b, m["b"].axis)
    return m


def test_a_gear_to_a_kept_joint_is_an_error_and_between_locked_joints_is_dropped():
    with pytest.raises(ModelError, match=r"gear: the IdealGear ties locked b to kept a"):
        _geared().lock("b")
    with pytest.warns(UserWarning, match="gear"):
        held = _geared().lock(["a", "b"])
    assert "gear" not in held.components() and mbcomp.assemble(held).q_names == []


def test_a_rotor_on_the_locked_axis_stays_as_inertia_of_the_body():
    """An Inertia J on the elbow's axis turns with link 2 about z: locked, it adds J to the
    composite body's inertia about the shoulder (the shoulder's axis is parallel)."""
    J = 0.25
    m = _arm()
    rot = m.add("rotor", Inertia(J=J))
    m.connect(rot.flange, m["b"].axis)
    full = mbcomp.assemble(m).evaluate(0.0, np.zeros(2), np.zeros(2)).M
    assert full[1, 1] == pytest.approx(M2 * L2 ** 2 + J)  # the rotor counts in the full model too
    with pytest.warns(UserWarning, match="kept as a body"):
        held = m.lock("b", at={"b": 0.5})
    ev = mbcomp.assemble(held).evaluate(0.0, np.zeros(1), np.zeros(1))
    assert ev.M[0, 0] == pytest.approx(_composite(0.5) + J, rel=1e-14)


def test_a_locked_free_joint_fixes_the_base_at_the_pose_given():
    """A pendulum hanging from a floating base (FreeMotion): locked with the base turned by
    90 deg about x, the hinge axis (y in the base) points along z, so gravity (-z) exerts no
    torque about it; unturned, the axis is y and gravity swings it."""
    from mbcomp.library import FreeMotion, RigidBody

    def robot():
        m = mbcomp.Model()
        w = m.add("world", World(g=(0, 0, -9.81)))
        base = m.add("base", FreeMotion())
        body = m.add("body", RigidBody(m=3.0, I=0.1 * np.eye(3)))
        j = m.add("j", Revolute(n=(0, 1, 0)))
        rod = m.add("rod", FixedTranslation(r=(0.4, 0, 0)))
        bob = m.add("bob", PointMass(m=1.0))
        m.connect(w.frame_b, base.frame_a); m.connect(base.frame_b, body.frame_a)
        m.connect(body.frame_a, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
        return m

    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)  # quaternion (w, x, y, z) of 90 deg about x
    turned = mbcomp.assemble(robot().lock("base", at={"base": [0, 0, 1.0, c, s, 0, 0]}))
    upright = mbcomp.assemble(robot().lock("base", at={"base": [0, 0, 1.0, 1, 0, 0, 0]}))
    assert turned.q_names == upright.q_names == ["j.phi"]
    phi = np.array([0.0])
    assert turned.evaluate(0.0, phi, np.zeros(1)).f[0] == pytest.approx(0.0, abs=1e-13)
    assert upright.evaluate(0.0, phi, np.zeros(1)).f[0] == pytest.approx(9.81 * 0.4, rel=1e-13)  # -m g x . about y


def test_errors_name_the_joint_and_the_fix():
    m = _arm()
    with pytest.raises(ModelError, match=r"'bb': names no component of the model .* did you mean 'b'"):
        m.lock("bb")
    with pytest.raises(ModelError, match=r"p1: is a PointMass \(body\), not a joint"):
        m.lock("p1")
    with pytest.raises(ModelError, match=r"r1: is a rigid offset \(FixedTranslation\): it has no coordinates"):
        m.lock("r1")
    with pytest.raises(ModelError, match=r"at\['b'\]: has 2 values, the Revolute has 1 coordinate \(phi\)"):
        m.lock("b", at={"b": [0.1, 0.2]})
    with pytest.raises(ModelError, match=r"at\['a'\]: gives coordinates of a joint not being locked"):
        m.lock("b", at={"a": 0.1})
    with pytest.raises(ModelError, match=r"'c': names no component"):
        mbcomp.reduce(m, keep=["c"])
    assert m.locked == {} and mbcomp.assemble(m).q_names == ["a.phi", "b.phi"]  # refused: nothing changed


def test_a_loop_of_locked_joints_only_is_refused_when_assembled():
    """A four-bar with every hinge locked: one lock must close the loop, and a loop without
    freedom has nothing to close (the error names it and the fix)."""
    m = mbcomp.Model()
    w = m.add("world", World())
    pts = [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)]
    prev = w.frame_b
    for k in range(4):
        j = m.add(f"j{k}", Revolute(n=(0, 0, 1)))
        bar = m.add(f"bar{k}", FixedTranslation(r=np.subtract(pts[(k + 1) % 4], pts[k])))
        mass = m.add(f"m{k}", PointMass(m=1.0))
        m.connect(prev, j.frame_a); m.connect(j.frame_b, bar.frame_a); m.connect(bar.frame_b, mass.frame_a)
        prev = bar.frame_b
    last = m.add("close", Revolute(n=(0, 0, 1)))
    m.connect(prev, last.frame_a); m.connect(last.frame_b, w.frame_b)
    held = m.lock(["j0", "j1", "j2", "j3", "close"])
    with pytest.raises(ModelError, match="closes a loop whose every other joint is rigid, locked or driven"):
        mbcomp.assemble(held).evaluate(0.0, np.zeros(0), np.zeros(0))


def test_lock_adds_nothing_to_a_model_it_cannot_lock():
    m = _arm()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing dropped: no warning
        held = m.lock([])
    assert mbcomp.assemble(held).q_names == ["a.phi", "b.phi"] and held.locked == {}


ARM_FILE = '''
import mbcomp
from mbcomp.library import World, Revolute, FixedTranslation, PointMass, RotationalDamper

def build():
    m = mbcomp.Model(); w = m.add("world", World())
    a = m.add("a", Revolute(n=(0, 0, 1))); r1 = m.add("r1", FixedTranslation(r=(0.8, 0, 0)))
    p1 = m.add("p1", PointMass(m=1.5)); b = m.add("b", Revolute(n=(0, 0, 1)))
    r2 = m.add("r2", FixedTranslation(r=(0.5, 0, 0))); p2 = m.add("p2", PointMass(m=0.7))
    d = m.add("damper", RotationalDamper(d=2.0))
    m.connect(w.frame_b, a.frame_a); m.connect(a.frame_b, r1.frame_a); m.connect(r1.frame_b, p1.frame_a)
    m.connect(r1.frame_b, b.frame_a); m.connect(b.frame_b, r2.frame_a); m.connect(r2.frame_b, p2.frame_a)
    m.connect(b.support, d.flange_a); m.connect(b.axis, d.flange_b)
    return m.lock("b", at={"b": 0.25})
'''


def test_mbcomp_info_says_what_was_locked(tmp_path, capsys):
    from mbcomp.cli.main import main

    path = tmp_path / "held_arm.py"
    path.write_text(ARM_FILE)
    with pytest.warns(UserWarning, match="damper"):
        assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "coordinates (1 q, 1 speeds): a.phi" in out
    assert "locked: 1 joint held as rigid connections (b (Revolute at phi=0.25))" in out
    assert "dropped with the locks: RotationalDamper 'damper' on locked b: dropped" in out
    assert "rigid offsets merged into their bodies (no coordinates): r1, r2\n" in out  # the lock said once, as a lock


def test_a_joint_inside_a_nested_model_is_locked_by_its_path():
    """The arm as a sub-model ``robot`` of a scene: ``scene.lock("robot.b")`` holds the elbow
    (the damper on it, in the sub-model, dropped); locking the sub-model itself gives a model
    standing alone, the scene left as it was."""
    scene = mbcomp.Model()
    robot = scene.add("robot", _arm())
    d = robot.add("damper", RotationalDamper(d=2.0))
    robot.connect(robot["b"].support, d.flange_a)
    robot.connect(robot["b"].axis, d.flange_b)
    with pytest.warns(UserWarning, match="RotationalDamper 'robot.damper' on locked robot.b: dropped"):
        held = scene.lock("robot.b", at={"robot.b": 0.4})
    assert held.locked == {"robot.b": {"phi": 0.4}} and "damper" not in held["robot"].components()
    ev = mbcomp.assemble(held).evaluate(0.0, np.zeros(1), np.zeros(1))
    assert ev.M[0, 0] == pytest.approx(_composite(0.4), rel=1e-14)
    with pytest.warns(UserWarning, match="RotationalDamper 'damper' on locked b"):
        alone = robot.lock(robot["b"], at={robot["b"]: 0.4})
    assert alone.parent is None and alone.locked == {"b": {"phi": 0.4}}
    assert mbcomp.assemble(alone).evaluate(0.0, np.zeros(1), np.zeros(1)).M[0, 0] == pytest.approx(_composite(0.4))
    assert robot.parent is scene and "damper" in robot.components() and scene.locked == {}
