"""Clear errors: every mistake a modeller can make is reported with the right error type, the
component/port/parameter it concerns, and a hint how to fix it."""
import re

import numpy as np
import pytest

import mbcomp
from mbcomp import Guess
from mbcomp.initialization import initialize
from mbcomp.library import (Fixed, FixedTranslation, PointMass, PrescribedMotion, Prismatic, Revolute,
                            RigidBody, World)

from conftest import load_model

SC = load_model("models/slider_crank.py")
CRANK, ROD = 0.2, 0.6


def problem_at(err, where):
    """The problem whose ``where`` names ``where``; asserts the message carries it and a fix."""
    hits = [p for p in err.problems if where in p.where]
    assert hits, f"no problem names {where!r}: {err.problems}"
    pr = hits[0]
    assert isinstance(pr.what, str) and pr.what.strip()
    assert isinstance(pr.fix, str) and pr.fix.strip(), f"{where}: no fix hint"
    msg = str(err)
    assert where in msg and "fix:" in msg and pr.fix in msg
    return pr


def pendulum(hinge=None, bob=None, connect_tip=True):
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("hinge", hinge or Revolute(n=(0, 0, 1), phi0=0.4, w0=0.0))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    b = m.add("bob", bob or PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    if connect_tip:
        m.connect(rod.frame_b, b.frame_a)
    return m


def slider_crank(phi0=0.3, w0=6.0, s0=Guess(CRANK + ROD), v0=None, rod_length=ROD, slider_y=0.0):
    """The slider-crank of models/slider_crank.py with the slider line at height
    ``slider_y`` and optionally fixed slider start values."""
    m = mbcomp.Model()
    world = m.add("world", World(g=(0.0, -9.81, 0.0)))
    crank_joint = m.add("crank_joint", Revolute(n=(0, 0, 1), phi0=phi0, w0=w0))
    crank = m.add("crank", RigidBody(m=1.0, r_cm=(CRANK / 2, 0, 0), I=SC.rod_inertia(1.0, CRANK)))
    crank_tip = m.add("crank_tip", FixedTranslation(r=(CRANK, 0, 0)))
    rod_joint = m.add("rod_joint", Revolute(n=(0, 0, 1), phi0=Guess(-0.1)))
    rod = m.add("rod", RigidBody(m=2.0, r_cm=(rod_length / 2, 0, 0), I=SC.rod_inertia(2.0, rod_length)))
    rod_tip = m.add("rod_tip", FixedTranslation(r=(rod_length, 0, 0)))
    base = m.add("slider_base", Fixed(r=(0.0, slider_y, 0.0)))
    slider_joint = m.add("slider_joint", Prismatic(n=(1, 0, 0), s0=s0, v0=v0))
    slider = m.add("slider", RigidBody(m=0.5))
    pin = m.add("pin", Revolute(n=(0, 0, 1)))
    m.connect(world.frame_b, crank_joint.frame_a)
    m.connect(crank_joint.frame_b, crank.frame_a)
    m.connect(crank_joint.frame_b, crank_tip.frame_a)
    m.connect(crank_tip.frame_b, rod_joint.frame_a)
    m.connect(rod_joint.frame_b, rod.frame_a)
    m.connect(rod_joint.frame_b, rod_tip.frame_a)
    m.connect(base.frame_b, slider_joint.frame_a)
    m.connect(slider_joint.frame_b, slider.frame_a)
    m.connect(rod_tip.frame_b, pin.frame_a)
    m.connect(slider_joint.frame_b, pin.frame_b)
    return m


def consistent_slider_position(phi):
    return CRANK * np.cos(phi) + np.sqrt(ROD ** 2 - (CRANK * np.sin(phi)) ** 2)


# ------------------------------------------------------------------------------------------
def test_joint_with_unconnected_frame():
    # rod.frame_b left open is a marker frame (a rigid offset may end in nothing), but the bob
    # is then joined to nothing that reaches the world: an error unless marked free
    m = pendulum(connect_tip=False)
    m.validate()
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    assert len(ei.value.problems) == 1
    pr = problem_at(ei.value, "bob")
    assert pr.where == "bob" and "joined to nothing that reaches the world" in pr.what
    assert "model.add('bob', ..., free=True)" in pr.fix
    # a joint: frame_b of a Revolute open
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("hinge", Revolute())
    m.connect(w.frame_b, j.frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    pr = problem_at(ei.value, "hinge.frame_b")
    assert pr.where == "hinge.frame_b" and "Revolute" in pr.what and "connect" in pr.fix
    assert "a joint with 1 degree of freedom must join two frames" in pr.what


def test_negative_mass():
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.simulate(pendulum(bob=PointMass(m=-1.0)), t_end=0.1)
    pr = problem_at(ei.value, "bob.m")
    assert pr.where == "bob.m"
    assert ">= 0" in pr.what and "kg" in pr.what
    assert re.search(r"\bm\b", pr.fix) and "kg" in pr.fix
    with pytest.raises(mbcomp.ModelError) as ei:
        pendulum(bob=RigidBody(m=-2.0)).validate()
    problem_at(ei.value, "bob.m")


def test_negative_mass_in_a_submodel_is_named_by_its_full_path():
    sub = mbcomp.Model()
    b = sub.add("bob", PointMass(m=-1.0))
    sub.expose("frame_a", b.frame_a)
    m = mbcomp.Model()
    w = m.add("world", World())
    m.add("arm", sub)
    m.connect(w.frame_b, sub.frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    assert problem_at(ei.value, "arm.bob.m").where == "arm.bob.m"


def test_inertia_violating_triangle_inequality():
    body = RigidBody(m=1.0, I=np.diag([0.1, 0.1, 0.5]))
    with pytest.raises(mbcomp.ModelError) as ei:
        pendulum(bob=body).validate()
    pr = problem_at(ei.value, "bob.I")
    assert "triangle inequality" in pr.what and "0.5" in pr.what
    assert "I" in pr.fix and "kg m^2" in pr.fix
    # a negative principal moment is reported too (and not as a triangle-inequality problem)
    with pytest.raises(mbcomp.ModelError) as ei:
        pendulum(bob=RigidBody(m=1.0, I=np.diag([0.1, 0.1, -0.05]))).validate()
    assert "negative principal moment" in problem_at(ei.value, "bob.I").what


@pytest.mark.parametrize("cls", [Revolute, Prismatic])
def test_zero_joint_axis(cls):
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(pendulum(hinge=cls(n=(0, 0, 0))))
    pr = problem_at(ei.value, "hinge.n")
    assert "must not be zero" in pr.what
    assert pr.fix.startswith("give n") and "axis" in pr.fix


def test_over_specified_initial_conditions():
    """Crank angle and slider position both fixed, to values that do not fit together."""
    s_ok = consistent_slider_position(0.3)
    m = slider_crank(phi0=0.3, s0=s_ok - 0.2)
    system = mbcomp.assemble(m)
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(system)
    err = ei.value
    assert isinstance(err, mbcomp.ModelError) and len(err.problems) == 1
    pr = err.problems[0]
    assert "crank_joint" in pr.where and "slider_joint" in pr.where
    assert "over-specify" in pr.what
    assert "Guess(" in pr.fix
    assert "fix:" in str(err) and "crank_joint" in str(err)
    with pytest.raises(mbcomp.InitializationError):
        mbcomp.simulate(m, t_end=0.1)
    # control: the same values that fit together, or the slider position as a guess, initialize
    ok = mbcomp.assemble(slider_crank(phi0=0.3, s0=s_ok))
    st = initialize(ok)
    assert st.q[ok.q_names.index("slider_joint.s")] == pytest.approx(s_ok, abs=1e-9)
    initialize(mbcomp.assemble(slider_crank(phi0=0.3, s0=Guess(s_ok - 0.2))))


def test_over_specified_positions_name_the_fixed_coordinates():
    """The user fixed crank_joint.phi (phi0) and slider_joint.s (s0); the message must name
    those coordinates, not the speeds crank_joint.w / slider_joint.v (whose start values are
    a different matter, and w0 is fixed too here)."""
    m = slider_crank(phi0=0.3, s0=consistent_slider_position(0.3) - 0.2)
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(mbcomp.assemble(m))
    where = ei.value.problems[0].where
    assert "crank_joint.phi" in where and "slider_joint.s" in where, where


def test_over_specified_start_speeds():
    m = slider_crank(phi0=0.3, w0=6.0, s0=Guess(consistent_slider_position(0.3)), v0=5.0)
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(mbcomp.assemble(m))
    pr = ei.value.problems[0]
    assert "crank_joint.w" in pr.where and "slider_joint.v" in pr.where
    assert "start speeds over-specify" in pr.what and "Guess(" in pr.fix


def test_loop_that_cannot_be_assembled():
    """Rod too short: crank (0.2) + rod (0.3) cannot reach a slider line 1 m below the crank."""
    m = slider_crank(rod_length=0.3, slider_y=-1.0)
    system = mbcomp.assemble(m)
    cut = system.topology.cut
    assert len(cut) == 1
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(system)
    pr = problem_at(ei.value, cut[0])
    assert "cannot be assembled" in pr.what and "over-specify" not in pr.what
    assert "lengths" in pr.fix and "Guess(" in pr.fix


def test_unknown_parameter_name_in_constructor():
    with pytest.raises(TypeError) as ei:
        Revolute(axs=(0, 0, 1))
    msg = str(ei.value)
    assert "Revolute" in msg and "'axs'" in msg
    assert "its parameters are: n, phi0, w0" in msg
    with pytest.raises(TypeError, match=r"PointMass has no parameter 'mass'.*parameters are: m"):
        PointMass(mass=1.0)


def test_unknown_parameter_name_at_runtime():
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(pendulum(), params={"hinge.nn": (1, 0, 0)})
    pr = problem_at(ei.value, "hinge.nn")
    assert "no such parameter" in pr.what and "n, phi0, w0" in pr.fix
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(pendulum(), params={"hinj.n": (1, 0, 0)})
    pr = problem_at(ei.value, "hinj.n")
    assert "hinj" in pr.what and "hinge" in pr.fix


def test_wrongly_shaped_parameter():
    with pytest.raises(mbcomp.ModelError) as ei:
        pendulum(hinge=Revolute(n=(0, 1))).validate()
    pr = problem_at(ei.value, "hinge.n")
    assert "shape (2,)" in pr.what and "(3,)" in pr.what
    assert pr.fix.startswith("give n")
    with pytest.raises(mbcomp.ModelError) as ei:
        pendulum(bob=RigidBody(I=[1.0, 1.0, 1.0])).validate()
    assert "expected (3, 3)" in problem_at(ei.value, "bob.I").what
    with pytest.raises(mbcomp.ModelError) as ei:
        pendulum(bob=PointMass(m="heavy")).validate()
    assert "not a number" in problem_at(ei.value, "bob.m").what


def test_validate_collects_every_problem_and_raises_once():
    m = mbcomp.Model()
    w = m.add("world", World())
    hinge = m.add("hinge", Revolute(n=(0, 0, 0)))  # 1: zero axis
    body = m.add("body", RigidBody(m=-1.0, I=np.diag([0.1, 0.1, 0.5])))  # 2: mass, 3: inertia
    slide = m.add("slide", Prismatic(n=(1, 0)))  # 4: shape
    m.add("loose", FixedTranslation(r=(1, 0, 0)))  # 5, 6: both frames unconnected
    pm = m.add("pm", PointMass(m=float("nan")))  # 7: not finite
    m.connect(w.frame_b, hinge.frame_a)
    m.connect(hinge.frame_b, body.frame_a)
    m.connect(body.frame_a, slide.frame_a)
    m.connect(slide.frame_b, pm.frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    err = ei.value
    assert len(err.problems) == 7
    assert str(err).startswith("model has problems (7):")
    for where in ("hinge.n", "body.m", "body.I", "slide.n", "loose.frame_a", "loose.frame_b", "pm.m"):
        problem_at(err, where)
    assert str(err).count("fix:") == 7


def test_massless_degree_of_freedom():
    """A point mass on the hinge axis: rotating about the axis moves no mass."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("hinge", Revolute(n=(0, 0, 1)))
    b = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    with pytest.raises(mbcomp.InitializationError) as ei:
        mbcomp.simulate(m, t_end=0.1)
    assert "massless degrees of freedom" in str(ei.value)
    pr = problem_at(ei.value, "hinge.w")
    assert "no mass" in pr.what and "drive" in pr.fix


def test_idle_revolute_carrying_nothing_is_named():
    """A pendulum with an extra hinge at the bob whose frame_b carries a massless body: the
    error names the idle hinge, not the pendulum's."""
    m = pendulum()
    idle = m.add("idle", Revolute(n=(1, 0, 0)))
    nothing = m.add("nothing", RigidBody(m=0.0))
    m.connect(m["bob"].frame_a, idle.frame_a)
    m.connect(idle.frame_b, nothing.frame_a)
    with pytest.raises(mbcomp.InitializationError) as ei:
        initialize(mbcomp.assemble(m))
    pr = problem_at(ei.value, "idle.w")
    assert pr.where == "idle.w"
    assert "mass" in pr.fix


def driven_hinge(drive):
    m = pendulum(hinge=Revolute(n=(0, 0, 1)))
    d = m.add("drive", drive)
    m.connect(d.flange_b, m["hinge"].axis)
    return m


@pytest.mark.parametrize("extra", [{}, {"v": np.cos}], ids=["no_v_a", "v_only"])
def test_prescribed_motion_with_numpy_law_needs_v_and_a(extra):
    m = driven_hinge(PrescribedMotion(s=lambda t: np.sin(t), **extra))
    with pytest.raises(mbcomp.ModelError) as ei:
        mbcomp.assemble(m)
    pr = problem_at(ei.value, "drive.s")
    assert "could not be differentiated" in pr.what
    assert "v=" in pr.fix and "a=" in pr.fix and "sympy" in pr.fix
    # with v and a given it is accepted
    ok = driven_hinge(PrescribedMotion(s=np.sin, v=np.cos, a=lambda t: -np.sin(t)))
    mbcomp.assemble(ok)


def test_prescribed_motion_with_unknown_symbol():
    with pytest.raises(mbcomp.ModelError) as ei:
        driven_hinge(PrescribedMotion(s="omega*t")).validate()
    pr = problem_at(ei.value, "drive.s")
    assert "omega" in pr.what


def test_prescribed_motion_runtime_numpy_law_is_rejected():
    """A law given at runtime (params=) is checked like one given to the constructor."""
    system = mbcomp.assemble(driven_hinge(PrescribedMotion(s="0.1*t")))
    with pytest.raises(mbcomp.ModelError) as ei:
        system.with_params({"drive.s": lambda t: np.sin(t)})
    problem_at(ei.value, "drive.s")


def test_connecting_a_frame_to_a_flange_raises():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("hinge", Revolute())
    with pytest.raises(ValueError) as ei:
        m.connect(w.frame_b, j.axis)
    msg = str(ei.value)
    assert "world.frame_b" in msg and "hinge.axis" in msg
    assert "(frame)" in msg and "(flange)" in msg
    assert "connect frames to frames and flanges to flanges" in msg
    assert m.flatten().connections == ()  # nothing half-connected
