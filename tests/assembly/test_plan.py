"""Topology plans (assembly/plan.py): a model rebuilt with the structure of one assembled
before gets that topology rebound to its own components -- the topology ``Topology(flat)``
builds, attribute by attribute, on every model of models/ and on models with loops, gears,
flange elements, drives, rotors, nested models, free bodies and contacts; a changed
structure, or a parameter value a choice of the topology reads, is built afresh; a bad
model raises what it raised before."""
import dataclasses
import glob
import importlib.util
import os

import numpy as np
import pytest

import mbcomp
from mbcomp import Guess
from mbcomp.assembly.plan import TopologyPlans
from mbcomp.assembly.topology import Edge, Topology, TreeLinks
from mbcomp.errors import ModelError
from mbcomp.library import (Fixed, FixedTranslation, IdealGear, Inertia, PlanetaryGear, PointMass, PrescribedMotion,
                            Prismatic, Revolute, RigidBody, RotationalSpring, Torque, TranslationalSpringDamper, World)
from mbcomp.modeling.component import Component, PortRef
from mbcomp.modeling.model import FlatModel

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MODELS = sorted(glob.glob(os.path.join(ROOT, "models", "*.py")))


def _module(path):
    spec = importlib.util.spec_from_file_location("plan_" + os.path.basename(path)[:-3], path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _plain(v, flat):
    """``v`` with every object the topology holds made comparable: a component of ``flat`` by
    its identity (it must be ``flat``'s), an implicit free joint (made anew by each topology)
    by class, name and parameters, edges and flange rows by their fields, ports by component
    and name."""
    if isinstance(v, Component):
        if flat.components.get(v.path) is v:
            return ("component", id(v))
        return ("implicit", type(v), v.name, repr(sorted(vars(v.p).items())))
    if isinstance(v, PortRef):
        return ("port", _plain(v.component, flat), v.name, v.kind)
    if isinstance(v, Edge) or dataclasses.is_dataclass(v):
        return (type(v), tuple(_plain(getattr(v, f.name), flat) for f in dataclasses.fields(v)))
    if isinstance(v, TreeLinks):
        return _plain(vars(v), flat)
    if isinstance(v, dict):
        return ("dict", tuple((_plain(k, flat), _plain(x, flat)) for k, x in v.items()))
    if isinstance(v, (list, tuple)):
        return (type(v), tuple(_plain(x, flat) for x in v))
    if isinstance(v, (set, frozenset)):
        return ("set", frozenset(_plain(x, flat) for x in v))
    if isinstance(v, FlatModel):
        return ("flat", id(v))
    assert isinstance(v, (str, int, float, bool, slice, type(None), np.floating, np.integer)), type(v)
    return v


def assert_same_topology(fresh, rebound):
    """Every attribute (and the links, the graph and the choices) of ``rebound`` equal to ``fresh``'s,
    the components those of ``fresh``'s own model."""
    flat = fresh.flat
    assert rebound.flat is flat
    assert set(vars(rebound)) - {"links", "_ports_from"} <= set(vars(fresh))  # the ports' maps: when first read
    for name in vars(fresh):
        assert _plain(getattr(rebound, name), flat) == _plain(getattr(fresh, name), flat), name
    assert _plain(rebound.links, flat) == _plain(fresh.links, flat)
    assert rebound.choices() == fresh.choices() and rebound.open_frames == fresh.open_frames
    assert sorted(rebound.graph.edges(keys=True, data="weight")) == sorted(fresh.graph.edges(keys=True, data="weight"))
    for e in rebound.edges:  # the edges are the rebound topology's own, never the template's
        assert not any(e is f for f in fresh.edges)


def check_rebound(build, *variants):
    """The topology of each ``build(**variant)`` after one of ``build()``: rebound, and the
    topology ``Topology`` builds."""
    plans = TopologyPlans()
    first = plans.topology(build().validate())
    for kw in variants or ({},):
        flat = build(**kw).validate()
        got = plans.topology(flat)
        assert_same_topology(Topology(flat), got)
        assert all(e.comp is flat.components[e.name] for e in got.edges if not e.implicit)
    assert plans.hits == len(variants or ({},)) and plans.misses == 1
    return first


@pytest.mark.parametrize("path", MODELS, ids=lambda p: os.path.basename(p)[:-3])
def test_every_model_rebound_is_the_topology_built_afresh(path):
    mod = _module(path)
    check_rebound(mod.build)


def four_bar(fixed=0, tau=None):
    """A four-bar of hinges ``j0..j3``; ``fixed`` the hinge whose start angle is fixed (the
    others' are guesses), which steers the spanning tree; ``tau`` a torque on ``j0``'s axis."""
    m = mbcomp.Model()
    w = m.add("world", World())
    js = [m.add(f"j{i}", Revolute(phi0=0.1 if i == fixed else Guess(0.1))) for i in range(4)]
    for i in range(3):
        link = m.add(f"l{i}", FixedTranslation(r=(1.0, 0.0, 0.0)))
        body = m.add(f"b{i}", RigidBody(m=1.0 + i, I=np.eye(3)))
        m.connect(js[i].frame_b, link.frame_a)
        m.connect(link.frame_a, body.frame_a)
        m.connect(link.frame_b, js[i + 1].frame_a)
    m.connect(w.frame_b, js[0].frame_a)
    m.connect(js[3].frame_b, w.frame_b)
    if tau is not None:
        t = m.add("tq", Torque(tau=tau))
        m.connect(t.flange_b, js[0].axis)
    return m


def drive_s(t):
    return 0.3 * np.sin(t)


def drive_v(t):
    return 0.3 * np.cos(t)


def drive_a(t):
    return -0.3 * np.sin(t)


def drivetrain(J=0.5, k=-3.0, c=10.0, mass=1.0):
    """Gears, a rotor on an open shaft, a rotational spring, a drive, a prismatic spring and a
    nested planetary gear in one model."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    j1, j2, j3 = (m.add(n, Revolute(w0=1.0 if n == "j1" else None)) for n in ("j1", "j2", "j3"))
    b1 = m.add("b1", RigidBody(m=mass, I=np.diag([1.0, 1.0, 0.2])))
    for j in (j1, j2, j3):
        m.connect(base.frame_b, j.frame_a)
    m.connect(j1.frame_b, b1.frame_a)
    rotor = m.add("rotor", Inertia(J=J))  # j2.frame_b stays open: the rotor is its shaft
    m.connect(rotor.flange, j2.axis)
    gear = m.add("gear", IdealGear(ratio=k))
    m.connect(gear.flange_a, j1.axis)
    m.connect(gear.flange_b, j2.axis)
    spring = m.add("spring", RotationalSpring(c=c))
    m.connect(spring.flange_a, j1.axis)
    m.connect(spring.flange_b, j1.support)
    b3 = m.add("b3", RigidBody(m=mass, I=np.eye(3)))
    m.connect(j3.frame_b, b3.frame_a)
    drive = m.add("drive", PrescribedMotion(s=drive_s, v=drive_v, a=drive_a))  # a string law: a new
    # structure per instance (PrescribedMotion keeps the functions it derived from it)
    m.connect(drive.flange_b, j3.axis)
    slide = m.add("slide", Prismatic(n=(1.0, 0.0, 0.0)))
    cart = m.add("cart", PointMass(m=mass))
    m.connect(b3.frame_a, slide.frame_a)
    m.connect(slide.frame_b, cart.frame_a)
    sd = m.add("sd", TranslationalSpringDamper(c=c, d=0.1))
    m.connect(sd.flange_a, slide.axis)
    m.connect(sd.flange_b, slide.support)
    return m


def planetary(J=1e-3, tau=1.0):
    """A nested model (a planetary gear set: shafts, rotors, a gear) driven by a torque on its sun."""
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    pg = m.add("pg", PlanetaryGear(z_sun=20, z_ring=60, J_sun=J, w_carrier0=1.0))
    m.connect(base.frame_b, pg.frame_a)
    t = m.add("tq", Torque(tau=tau))
    m.connect(t.flange_b, pg.sun)
    return m


def floating(m=1.0, r_cm=(0.0, 0.0, 0.0)):
    """A ball marked free (FreeMotion), a lone point mass marked free (FreeTranslation) and a
    rigid body marked free whose mass properties decide (a point mass without inertia or
    offset: FreeTranslation)."""
    mdl = mbcomp.Model()
    mdl.add("world", World())
    mdl.add("ball", RigidBody(m=m, I=1e-3 * np.eye(3)), free=True)
    mdl.add("dot", PointMass(m=m), free=True)
    mdl.add("lump", RigidBody(m=m, r_cm=r_cm, I=np.zeros((3, 3))), free=True)
    return mdl


@pytest.mark.parametrize("build, variants", [
    (lambda tau=0.5: four_bar(tau=tau), [dict(tau=2.0)]),
    (drivetrain, [dict(J=2.0, k=-1.5, c=3.0, mass=4.0)]),
    (planetary, [dict(J=2e-3, tau=-0.5)]),
    (floating, [dict(m=3.0)]),
], ids=["loop", "drivetrain", "nested", "free"])
def test_loops_gears_flanges_drives_rotors_nested_and_free_bodies_rebound_as_built_afresh(build, variants):
    check_rebound(build, *variants)


def test_a_fixed_start_value_that_moves_the_cut_joint_is_built_afresh():
    plans = TopologyPlans()
    first = plans.topology(four_bar(fixed=0).validate())
    flat = four_bar(fixed=3).validate()
    got = plans.topology(flat)
    assert plans.misses == 2 and plans.hits == 0
    assert first.cut == ["j3"] and got.cut != first.cut  # the fixed hinge stays in the tree
    assert_same_topology(Topology(flat), got)
    again = plans.topology(four_bar(fixed=3).validate())  # both kept: each rebound now
    assert plans.hits == 1 and again.cut == got.cut
    assert plans.topology(four_bar(fixed=0).validate()).cut == ["j3"] and plans.hits == 2


def chain(fixed=(0, 1, 2)):
    """Three hinges in a chain (no loop): ``fixed`` the hinges whose start angle is fixed."""
    m = mbcomp.Model()
    frame = m.add("world", World()).frame_b
    for i in range(3):
        j = m.add(f"j{i}", Revolute(phi0=0.1 if i in fixed else Guess(0.1)))
        b = m.add(f"b{i}", RigidBody(m=1.0, r_cm=(0.5, 0.0, 0.0), I=np.eye(3)))
        m.connect(frame, j.frame_a)
        m.connect(j.frame_b, b.frame_a)
        frame = b.frame_a
    return m


def test_fixed_start_values_of_a_chain_without_loops_are_rebound_with_their_weights():
    """A tree without loops takes every joint whatever the weights: rebound, the graph's
    weights those of the new model."""
    plans = TopologyPlans()
    plans.topology(chain().validate())
    flat = chain(fixed=(1,)).validate()
    got = plans.topology(flat)
    assert plans.hits == 1
    assert_same_topology(Topology(flat), got)
    assert sorted(w for _, _, w in got.graph.edges(data="weight")) == [0.0, 0.5, 1.0, 1.0]


def test_mass_properties_that_make_a_free_body_a_point_are_built_afresh():
    plans = TopologyPlans()
    point = plans.topology(floating().validate())
    flat = floating(r_cm=(0.1, 0.0, 0.0)).validate()
    got = plans.topology(flat)
    kinds = {e.name: type(e.comp).__name__ for e in got.edges if e.implicit}
    assert {e.name: type(e.comp).__name__ for e in point.edges if e.implicit}["lump.free"] == "FreeTranslation"
    assert kinds == {"ball.free": "FreeMotion", "dot.free": "FreeTranslation", "lump.free": "FreeMotion"}
    assert plans.misses == 2
    assert_same_topology(Topology(flat), got)


@pytest.mark.parametrize("change", [
    lambda m: m.add("extra", PointMass()) and m.connect(m["b2"].frame_a, m["extra"].frame_a),  # a component more
    lambda m: m.connect(m["b0"].frame_a, m["b1"].frame_a),  # a connection more (j1 joins nothing: refused)
    lambda m: setattr(m["j1"], "tree_edge", False),         # an attribute besides the parameters
])
def test_a_changed_structure_is_not_rebound(change):
    plans = TopologyPlans()
    plans.topology(four_bar().validate())
    changed = four_bar()
    change(changed)
    try:
        fresh = Topology(changed.validate())
    except ModelError as exc:
        with pytest.raises(ModelError) as got:
            plans.topology(changed.validate())
        assert str(got.value) == str(exc)
    else:
        flat = changed.validate()
        assert_same_topology(Topology(flat), plans.topology(flat))
        assert fresh.flat.structure()[0] != four_bar().validate().structure()[0]
    assert plans.hits == 0


def test_a_bad_model_raises_as_before_and_is_never_kept():
    def lost(m=1.0):  # a body joined to nothing that reaches the world
        mdl = mbcomp.Model()
        mdl.add("world", World())
        mdl.add("b", PointMass(m=m))
        j = mdl.add("j", Revolute())
        mdl.connect(mdl["b"].frame_a, j.frame_a)
        mdl.connect(j.frame_b, mdl.add("c", PointMass()).frame_a)
        return mdl

    plans = TopologyPlans()
    with pytest.raises(ModelError) as before:
        Topology(lost().validate())
    for _ in range(2):
        with pytest.raises(ModelError) as got:
            plans.topology(lost(m=2.0).validate())
        assert str(got.value) == str(before.value) and "b" in str(got.value)
    assert len(plans) == 0 and plans.hits == 0
    plans.topology(drivetrain().validate())
    with pytest.raises(ModelError, match="b1.m"):  # a bad value of a kept structure: validation names it
        plans.topology(drivetrain(mass=-1.0).validate())


def test_assemble_through_the_plan_runs_as_built_afresh():
    """A run on a rebound topology is the run on the fresh one, bit for bit."""
    from mbcomp.assembly.plan import topology_of
    from mbcomp.assembly.system import MultibodySystem

    def run(topology):
        return mbcomp.simulate(MultibodySystem(topology), t_end=0.2, n_out=5, backend="numeric")

    fresh = run(Topology(four_bar(tau=0.5).validate()))
    topology_of(four_bar(tau=0.5).validate())
    rebound = run(topology_of(four_bar(tau=0.5).validate()))
    assert fresh.names == rebound.names
    for name in fresh.names:
        assert np.array_equal(np.asarray(fresh[name]), np.asarray(rebound[name]), equal_nan=True), name


def test_a_rebound_topology_pickles_and_copies():
    import copy
    import pickle

    plans = TopologyPlans()
    plans.topology(drivetrain().validate())
    got = plans.topology(drivetrain(J=1.0).validate())
    back = pickle.loads(pickle.dumps(got))
    assert back.q_names == got.q_names and back.cut == got.cut
    assert sorted(x.path for x in back.port_node) == sorted(x.path for x in got.port_node)
    assert {x.path: r.path for x, r in back.flange_of.items()} == {x.path: r.path for x, r in got.flange_of.items()}
    again = plans.topology(drivetrain(J=2.0).validate())
    shallow = copy.copy(again)
    assert _plain(shallow.flange_owner, again.flat) == _plain(again.flange_owner, again.flat)
