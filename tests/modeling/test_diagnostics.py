"""Diagnoses that name what went wrong (issue 18, item 2): law checks that say what a law
returned and what was expected, laws of the wrong signature refused at validation, every
massless direction listed, extreme mass ratios told apart from massless motion, a
self-connected joint, flanges a joint does not have, model files whose build() returns no
Model, bodies joined to nothing, no World, and open frames of rigid offsets."""
import pathlib
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.conditioning import ILL_CONDITIONED, MASSLESS, directions
from mbcomp.assembly.topology import Topology, no_gravity_note
from mbcomp.initialization import initialize
from mbcomp.library import (FixedTranslation, Force, PointMass, PrescribedMotion, Prismatic, Revolute, RigidBody,
                            RotationalSpring, Spherical, Torque, World, WorldForce, WorldTorque)


def pendulum(bob=None, world=True):
    m = mbcomp.Model()
    base = m.add("world", World()) if world else m.add("world", mbcomp.library.Fixed())
    j = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.3))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    b = m.add("bob", bob or PointMass(m=1.0))
    m.connect(base.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, b.frame_a)
    return m


def motor_on(m, element, joint="hinge"):
    e = m.add("motor", element)
    m.connect(e.flange_b, m[joint].axis)
    return m


def run_error(m):
    with pytest.raises(mbcomp.SimulationError) as ei:
        mbcomp.simulate(m, t_end=0.1)
    return str(ei.value)


# --- law checks at run time: what the law returned and what was expected ---------------------
@pytest.mark.parametrize("law, shown", [(lambda t, phi, w: (1.0, 2.0), "a tuple (1.0, 2.0)"),
                                        (lambda t, phi, w: None, "None"),
                                        (lambda t, phi, w: "1.0", "a str '1.0'"),
                                        (lambda t, phi, w: np.inf, "inf")],
                         ids=["tuple", "None", "str", "inf"])
def test_torque_law_returning_no_number_says_what_it_returned(law, shown):
    msg = run_error(motor_on(pendulum(), Torque(tau=law)))
    assert f"Torque 'motor': the tau law returned {shown} at t=0 (phi=0.3, w=0)" in msg
    assert "it must return one finite number (N m) -> fix the law" in msg
    assert "non-finite" not in msg and "raised SimulationError" not in msg


def test_force_law_names_slider_coordinates_and_newtons():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("slide", Prismatic(n=(1, 0, 0), s0=0.2))
    m.add("block", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, m["block"].frame_a)
    msg = run_error(motor_on(m, Force(f=lambda t, s, v: [s, v]), joint="slide"))
    assert "Force 'motor': the f law returned a list [0.2, 0.0] at t=0 (s=0.2, v=0); it must return one " \
           "finite number (N)" in msg


@pytest.mark.parametrize("law, shown", [(lambda t, frame: None, "None"),
                                        (lambda t, frame: (1.0, 2.0), "a tuple (1.0, 2.0)"),
                                        (lambda t, frame: (1.0, "a", 0.0), "a tuple (1.0, 'a', 0.0)"),
                                        (lambda t, frame: (0.0, np.nan, 0.0), "a tuple (0.0, nan, 0.0)")],
                         ids=["None", "short", "str", "nan"])
def test_world_force_law_returning_no_vector_says_what_it_returned(law, shown):
    m = pendulum()
    push = m.add("push", WorldForce(f=law))
    m.connect(push.frame_b, m["bob"].frame_a)
    msg = run_error(m)
    assert f"WorldForce 'push': the force law returned {shown} at t=0" in msg
    assert "it must return 3 finite numbers (N, world coordinates) -> fix the law" in msg


# --- law signatures at validation ----------------------------------------------------------
def test_torque_law_with_wrong_signature_is_refused_at_validation():
    m = motor_on(pendulum(), Torque(tau=lambda t: 1.0))
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    (pr,) = ei.value.problems
    assert pr.where == "motor.tau"
    assert pr.what == "the tau law takes (t) but is called as tau(t, phi, w)"
    assert pr.fix.startswith("write it as def tau(t, phi, w)")


@pytest.mark.parametrize("cls, name", [(WorldForce, "f"), (WorldTorque, "tau")])
def test_world_load_law_with_wrong_signature_is_refused_at_validation(cls, name):
    m = pendulum()
    load = m.add("load", cls(**{name: lambda t, frame, extra: (0.0, 0.0, 0.0)}))
    m.connect(load.frame_b, m["bob"].frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    (pr,) = ei.value.problems
    assert pr.where == f"load.{name}"
    assert pr.what == f"the {name} law takes (t, frame, extra) but is called as {name}(t, frame)"


def test_laws_taking_extra_defaults_or_star_args_are_accepted():
    m = motor_on(pendulum(), Torque(tau=lambda t, *state, gain=2.0: 0.0))
    m.validate()


def test_prescribed_motion_law_with_wrong_signature_is_refused():
    m = motor_on(pendulum(), PrescribedMotion(s=lambda t, phi: 0.1 * t))
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    (pr,) = ei.value.problems
    assert pr.where == "motor.s" and pr.what == "the s law takes (t, phi) but is called as s(t)"


def test_prescribed_motion_law_returning_none_at_run_time_is_named():
    drive = PrescribedMotion(s=lambda t: 0.3, v=lambda t: None, a=lambda t: 0.0)
    msg = run_error(motor_on(pendulum(), drive))
    assert "PrescribedMotion 'motor': the v law returned None at t=0; it must return one finite number" in msg


# --- massless directions and mass ratios ---------------------------------------------------
def test_every_massless_direction_is_listed():
    """A point mass on a ball joint at its own position: its three rotations carry no inertia."""
    m = mbcomp.Model()
    w = m.add("world", World())
    ball_joint = m.add("ball_joint", Spherical())
    ball = m.add("ball", PointMass(m=1.0))
    m.connect(w.frame_b, ball_joint.frame_a)
    m.connect(ball_joint.frame_b, ball.frame_a)
    with pytest.raises(mbcomp.InitializationError) as ei:
        mbcomp.simulate(m, t_end=0.1)
    assert [p.where for p in ei.value.problems] == ["ball_joint.w.x", "ball_joint.w.y", "ball_joint.w.z"]
    assert str(ei.value).startswith("the mechanism has massless degrees of freedom (3):")
    assert all("PointMass has none of its own: use a RigidBody" in p.fix for p in ei.value.problems)


def test_a_free_point_without_mass_has_three_massless_directions():
    """A free point mass gets a translation-only free joint (it has no rotation to move); with
    no mass its three translations are massless."""
    m = mbcomp.Model()
    m.add("world", World())
    m.add("ball", PointMass(m=0.0), free=True)
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(mbcomp.assemble(m))
    assert sorted(p.where for p in ei.value.problems) == [f"ball.free.v.{a}" for a in "xyz"]
    assert all(p.what.startswith("this motion carries") for p in ei.value.problems)


def double_pendulum(m2):
    m = pendulum(bob=PointMass(m=10.0))
    j2 = m.add("j2", Revolute(n=(0, 0, 1), phi0=0.2))
    r2 = m.add("r2", FixedTranslation(r=(0, -1.0, 0)))
    b2 = m.add("b2", PointMass(m=m2))
    m.connect(m["bob"].frame_a, j2.frame_a)
    m.connect(j2.frame_b, r2.frame_a)
    m.connect(r2.frame_b, b2.frame_a)
    return m


def test_extreme_mass_ratio_is_ill_conditioning_not_massless():
    """A 1e-9 kg bob on a 10 kg one: the run goes on, with a warning naming both and the ratio."""
    with pytest.warns(RuntimeWarning) as rec:
        init = initialize(mbcomp.assemble(double_pendulum(1e-9)))
    (text,) = [str(w.message) for w in rec if "ill-conditioned" in str(w.message)]
    assert "lightest body b2 (1e-09 kg), heaviest bob (10 kg), mass ratio 1e+10" in text
    assert "lose about 10 of 16 digits" in text and "massless" not in text
    assert init.notes == [text.removeprefix("mbcomp: ")]
    # the light bob still swings as a pendulum hung from the heavy one: the run succeeds
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = mbcomp.simulate(double_pendulum(1e-9), t_end=0.2)
    assert res.success, res.message


def test_ordinary_mass_ratio_says_nothing():
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert initialize(mbcomp.assemble(double_pendulum(1e-3))).notes == []


def test_mass_below_roundoff_of_the_largest_is_massless():
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(mbcomp.assemble(double_pendulum(1e-14)))
    assert [p.where for p in ei.value.problems] == ["j2.w"]


def test_thresholds_split_zero_extreme_and_ordinary():
    assert MASSLESS < ILL_CONDITIONED < 1e-7
    Z, ratio = directions(np.diag([1.0, 0.5 * MASSLESS]))
    assert Z.shape[1] == 1 and ratio is None and abs(Z[1, 0]) == 1.0
    Z, ratio = directions(np.diag([1.0, 10 * MASSLESS]))
    assert Z.shape[1] == 0 and ratio == pytest.approx(10 * MASSLESS)
    assert directions(np.diag([1.0, 10 * ILL_CONDITIONED])) [1] is None
    assert directions(np.zeros((2, 2)))[0].shape == (2, 2)


# --- topology: self-joined joints, flanges, floating bodies, gravity, open frames -----------
def test_joint_connected_to_itself_is_named():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute())
    b = m.add("b", RigidBody(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_a, j.frame_b)
    m.connect(j.frame_b, b.frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    (pr,) = ei.value.problems
    assert pr.where == "j"
    assert "both frames of this Revolute, frame_a and frame_b, are the same frame" in pr.what
    assert "b.frame_a, world.frame_b" in pr.what and "two different frames" in pr.fix


def test_joint_with_both_frames_on_one_node_directly():
    m = mbcomp.Model()
    m.add("world", World())
    j = m.add("j", Revolute())
    m.connect(j.frame_a, j.frame_b)
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    assert ei.value.problems[0].where == "j" and "(connected to each other)" in ei.value.problems[0].what


def ball_joint_model():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("ball", Spherical())
    r = m.add("rod", FixedTranslation(r=(1, 0, 0)))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, r.frame_a)
    m.connect(r.frame_b, b.frame_a)
    return m


def test_drive_on_a_spherical_joint_is_refused_when_connected():
    m = ball_joint_model()
    d = m.add("d", PrescribedMotion(s="t"))
    with pytest.raises(mbcomp.ModelError) as ei:
        m.connect(d.flange_b, m["ball"].axis)
    (pr,) = ei.value.problems
    assert pr.where == "drive 'd' on joint 'ball' (Spherical)"
    assert pr.what.startswith("a drive needs a 1-DOF joint's axis flange (Revolute, Prismatic)")
    assert "Revolute" in pr.fix


def test_flange_element_on_a_joint_without_support_is_refused():
    m = ball_joint_model()
    s = m.add("spring", RotationalSpring(c=1.0))
    with pytest.raises(mbcomp.ModelError) as ei:
        m.connect(m["ball"].support, s.flange_a)
    assert ei.value.problems[0].where == "flange element 'spring' on joint 'ball' (Spherical)"
    assert "support flange" in ei.value.problems[0].what


def test_two_drives_on_one_axis_are_refused():
    m = pendulum()
    for name in ("d1", "d2"):
        d = m.add(name, PrescribedMotion(s="t"))
        m.connect(d.flange_b, m["hinge"].axis)
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    (pr,) = ei.value.problems
    assert pr.where == "d2" and "a second drive on joint 'hinge' (already driven by 'd1')" in pr.what


def test_unconnected_body_is_an_error_unless_marked_free():
    m = mbcomp.Model()
    m.add("world", World())
    m.add("ball", RigidBody(m=1.0, I=np.eye(3) * 1e-3))
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    (pr,) = ei.value.problems
    assert pr.where == "ball" and "joined to nothing that reaches the world" in pr.what
    assert pr.what.endswith("so it would fall freely")
    assert "model.add('ball', ..., free=True)" in pr.fix and "FreeMotion" in pr.fix


def floating_pair(free=()):
    m = mbcomp.Model()
    m.add("world", World())
    a = m.add("a", RigidBody(m=1.0, I=np.eye(3)), free="a" in free)
    j = m.add("j", Revolute())
    b = m.add("b", RigidBody(m=1.0, I=np.eye(3)), free="b" in free)
    m.connect(a.frame_a, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def test_floating_assembly_is_an_error_naming_its_bodies():
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(floating_pair())
    (pr,) = ei.value.problems
    assert pr.where == "a, b" and "a floating assembly" in pr.what


def test_floating_assembly_with_one_body_marked_free_floats_from_it():
    system = mbcomp.assemble(floating_pair(free=("b",)))
    assert system.topology.floating == ["b.free"] and system.nu == 7
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(floating_pair(free=("a", "b")))
    assert ei.value.problems[0].where == "b" and "mark only a free" in ei.value.problems[0].fix


def test_body_marked_free_but_joined_to_the_world_is_an_error():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute())
    b = m.add("b", RigidBody(m=1.0, I=np.eye(3)), free=True)
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    assert ei.value.problems[0].where == "b" and "joined to the world" in ei.value.problems[0].what


def test_free_marks_only_bodies():
    with pytest.raises(ValueError, match="free=True marks a body"):
        mbcomp.Model().add("j", Revolute(), free=True)


def test_no_world_gives_a_note_and_a_world_none():
    assert "no World, so there is no gravity" in no_gravity_note(Topology(pendulum(world=False).validate()))
    assert no_gravity_note(Topology(pendulum().validate())) is None


def with_marker(m):
    tip = m.add("tip", FixedTranslation(r=(0, -0.5, 0)))
    m.connect(m["bob"].frame_a, tip.frame_a)
    return m


def test_open_frame_of_a_rigid_offset_is_a_marker_noted_in_info():
    m = with_marker(pendulum())
    system = mbcomp.assemble(m)
    assert system.topology.open_frames == ["tip.frame_b"]
    assert "open frames (rigid offsets ending in nothing, kept as marker frames): tip.frame_b" in system.summary()
    # the marker changes nothing: the pendulum swings as without it
    a = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12)
    b = mbcomp.simulate(pendulum(), t_end=1.0, rtol=1e-10, atol=1e-12)
    assert a.success and abs(a["hinge.phi"][-1] - b["hinge.phi"][-1]) < 1e-12


def test_rigid_offset_with_both_frames_open_is_an_error():
    m = pendulum()
    m.add("lost", FixedTranslation(r=(1, 0, 0)))
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    assert [p.where for p in ei.value.problems] == ["lost.frame_a", "lost.frame_b"]
    assert "the FixedTranslation is joined to nothing" in ei.value.problems[0].what


# --- model files --------------------------------------------------------------------------
@pytest.mark.parametrize("body, shown, fix",
                         [("return None", "build() returned None", "add 'return m'"),
                          ("return 'm'", "build() returned a str ('m')", "return the mbcomp.Model")],
                         ids=["None", "str"])
def test_build_returning_no_model_names_file_and_what_it_returned(tmp_path, body, shown, fix):
    path = tmp_path / "x.py"
    path.write_text(f"def build():\n    {body}\n")
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.load_model(path)
    (pr,) = ei.value.problems
    assert pr.where == str(path) and pr.what == f"{shown}; it must return an mbcomp.Model" and fix in pr.fix


def test_load_model_file_given_a_model_says_it_wants_a_path():
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.load_model_file(pendulum())
    assert "not the path of a model file" in ei.value.problems[0].what
    assert isinstance(pathlib.Path("x"), pathlib.Path)


def test_law_whose_signature_cannot_be_read_is_named_when_it_fails_at_run_time():
    """Some builtins have no readable signature (getattr): validation lets them through, and
    the call tau(t, phi, w) fails in the run, which names the component; a ufunc's signature
    is read and refused at validation."""
    with pytest.raises(mbcomp.ModelError, match="the tau law takes"):
        motor_on(pendulum(), Torque(tau=np.sin)).validate()
    m = motor_on(pendulum(), Torque(tau=getattr))
    m.validate()
    msg = run_error(m)
    assert msg.startswith("Torque 'motor': ") and "TypeError" in msg


def test_torque_on_a_slider_and_force_on_a_hinge_are_refused():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("slide", Prismatic(n=(1, 0, 0)))
    m.add("block", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, m["block"].frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(motor_on(m, Torque(tau=1.0), joint="slide"))
    (pr,) = ei.value.problems
    assert pr.where == "motor" and pr.what == ("this Torque applies a torque (N m), but slide (Prismatic) has a "
                                               "translational axis")
    assert pr.fix.startswith("connect it to a Revolute")
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(motor_on(pendulum(), Force(f=1.0)))
    assert "this Force applies a force (N), but hinge (Revolute) has a rotational axis" in str(ei.value)
