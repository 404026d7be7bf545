"""The scene of a run: default shapes of the library components from what the model knows,
the shapes users declare, and link poses that are the result's own numbers.

Each test states the geometry it expects from the model's parameters (a hinge's axis, a
wheel's radius, a body's inertia) or from the result's columns, so a wrong placement, a wrong
equivalent size or a pose that drifts from the result fails.
"""
import base64
import json

import numpy as np
import pytest

import mbcomp
from mbcomp.geometry.kinematics import quat_to_matrix
from mbcomp.library import (Damper, DiskContact, FixedTranslation, FreeMotion, PointMass, Prismatic, Revolute,
                            RigidBody, Spherical, Spring, World)
from mbcomp.modeling.shapes import STEEL, Box, Cylinder, Grid, Helix, Rod, Sphere
from mbcomp.visual.scene import build_scene
from conftest import load_model


def _decode(text, n):
    return np.frombuffer(base64.b64decode(text), dtype="<f8").reshape(n, -1)


def _pendulum(joint, body, t_end=0.5, **kw):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", joint)
    arm = m.add("arm", FixedTranslation(r=(0.5, 0, 0)))
    b = m.add("b", body)
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, arm.frame_a)
    m.connect(arm.frame_b, b.frame_a)
    return m, mbcomp.simulate(m, t_end=t_end, **kw)


def _of(scene, component):
    return [v for v in scene.visuals if v.component == component]


def _axis_world(scene, v, k=0):
    R, _ = scene.placement(v, k)
    return R[:, 2]


@pytest.fixture(scope="module")
def crank():
    m = load_model("models/slider_crank.py").build()
    return m, mbcomp.simulate(m, t_end=1.0, rtol=1e-8, atol=1e-10, stabilization="projection")


def test_link_poses_are_the_result_columns_exactly(crank):
    _, res = crank
    scene = build_scene(res)
    data = json.loads(json.dumps(scene.to_json()))
    n = data["n"]
    assert np.array_equal(np.frombuffer(base64.b64decode(data["time"]), "<f8"), res.time)
    for body in ("crank", "rod", "slider"):
        link = data["bodies"][body]["link"]
        poses = _decode(data["links"][link]["poses"], n)
        cols = [f"{body}.r.{a}" for a in "xyz"] + [f"{body}.Q.{a}" for a in "wxyz"]
        assert np.array_equal(poses, np.column_stack([res[c] for c in cols]))
        assert data["bodies"][body]["r"] == [0.0, 0.0, 0.0]


def test_a_link_is_drawn_from_joint_to_joint(crank):
    """The crank's rod runs from its hinge to the crank tip 0.2 m out along its x axis; the
    connecting rod's from its hinge to the pin 0.6 m out; at every output time the rod's far
    end is the pin's position on the slider's line (y = 0)."""
    _, res = crank
    scene = build_scene(res)
    (crank_rod,) = _of(scene, "crank")
    assert isinstance(crank_rod.shape, Cylinder) and crank_rod.shape.length == pytest.approx(0.2, abs=1e-12)
    assert np.allclose(crank_rod.r, (0.1, 0, 0), atol=1e-12)
    (rod,) = _of(scene, "rod")
    for k in (0, len(res.time) // 2, -1):
        R, c = scene.placement(rod, k)
        tip = c + R[:, 2] * rod.shape.length / 2
        far = c - R[:, 2] * rod.shape.length / 2
        ends = sorted([tip, far], key=lambda p: np.linalg.norm(p - [res["rod.r.x"][k], res["rod.r.y"][k], 0]))
        assert np.allclose(ends[0], [res["rod.r.x"][k], res["rod.r.y"][k], res["rod.r.z"][k]], atol=1e-12)
        assert np.allclose(ends[1], [res["slider.r.x"][k], res["slider.r.y"][k], res["slider.r.z"][k]], atol=1e-7)


def test_joints_are_drawn_along_their_axes():
    n = np.array([1.0, 2.0, 2.0]) / 3
    _, res = _pendulum(Revolute(n=n, phi0=0.4), PointMass(m=1.0))
    scene = build_scene(res)
    (hinge,) = _of(scene, "j")
    assert isinstance(hinge.shape, Cylinder)
    assert abs(_axis_world(scene, hinge) @ n) == pytest.approx(1.0, abs=1e-12)
    _, res = _pendulum(Prismatic(n=(0, 1, 0), s0=0.1), PointMass(m=1.0))
    scene = build_scene(res)
    (guide,) = _of(scene, "j")
    assert abs(_axis_world(scene, guide)[1]) == pytest.approx(1.0, abs=1e-12)
    s = res["j.s"]  # the rail covers the travel and a tenth of the scale beyond each end
    R, c = scene.placement(guide, 0)
    ends = sorted([(c - R[:, 2] * guide.shape.length / 2)[1], (c + R[:, 2] * guide.shape.length / 2)[1]])
    assert ends == pytest.approx([s.min() - 0.1 * scene.scale, s.max() + 0.1 * scene.scale], abs=1e-12)
    _, res = _pendulum(Spherical(), RigidBody(m=1.0, I=1e-3 * np.eye(3)))
    assert isinstance(_of(build_scene(res), "j")[0].shape, Sphere)


def test_a_point_mass_is_a_steel_sphere_of_its_mass():
    for mass in (5.0, 50.0):
        _, res = _pendulum(Revolute(phi0=0.3), PointMass(m=mass))
        scene = build_scene(res)
        rod, ball = _of(scene, "b")  # the link to the hinge, and the ball
        assert isinstance(rod.shape, Cylinder) and rod.shape.length == pytest.approx(0.5)
        expected = (3 * mass / (4 * np.pi * STEEL)) ** (1 / 3)
        assert scene.scale == pytest.approx(0.5)
        assert ball.shape.radius == pytest.approx(np.clip(expected, 0.04 * 0.5, 0.15 * 0.5))


def test_a_lone_body_is_its_equivalent_box_or_cylinder():
    """A 1 x 2 x 3 m box of 6 kg turned 90 degrees about z, given only by its inertia, is drawn
    as a box of those edges; a disk's inertia gives a cylinder of the disk's radius."""
    m, a, b, c = 6.0, 1.0, 2.0, 3.0
    I0 = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    Rz = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    (box,) = mbcomp.modeling.shapes.body_shapes(m, (0, 0, 0), Rz @ I0 @ Rz.T, [], 1.0)
    assert isinstance(box, Box)
    R = box.rotation
    I_box = m / 12 * np.diag([box.size[1] ** 2 + box.size[2] ** 2, box.size[0] ** 2 + box.size[2] ** 2,
                              box.size[0] ** 2 + box.size[1] ** 2])
    assert np.allclose(R @ I_box @ R.T, Rz @ I0 @ Rz.T, atol=1e-12)
    r, h = 0.3, 0.02
    Ia, Id = m * r * r / 2, m * (3 * r * r + h * h) / 12
    (disk,) = mbcomp.modeling.shapes.body_shapes(m, (0, 0, 0), np.diag([Id, Id, Ia]), [], 1.0)
    assert isinstance(disk, Cylinder) and disk.radius == pytest.approx(r) and disk.length == pytest.approx(h)
    L = 0.8  # a slender rod along y: m L^2 / 12 about x and z, nothing about y -> a thin cylinder of length L
    (rod,) = mbcomp.modeling.shapes.body_shapes(m, (0, 0, 0), np.diag([m * L * L / 12, 0, m * L * L / 12]), [], 1.0)
    assert isinstance(rod, Cylinder) and rod.length == pytest.approx(L) and 0 < rod.radius < 0.05 * L
    assert abs(rod.rotation[:, 2] @ (0, 1, 0)) == pytest.approx(1.0)


def test_a_wheel_is_the_disk_of_its_contact():
    """The bicycle's wheels: each contact draws a disk of its wheel's radius about the spin
    axis, on the wheel's link, and the wheel body draws nothing of its own."""
    mod = load_model("models/bicycle.py")
    res = mbcomp.simulate(mod.build(), t_end=0.2)
    scene = build_scene(res)
    for contact, wheel in (("rear_contact", "rear_wheel"), ("front_contact", "front_wheel")):
        disk, bar = _of(scene, contact)[:2]
        comp = res.system.topology.flat.components[contact]
        assert disk.shape.radius == comp.p.r and disk.link == bar.link == scene.bodies[wheel][0]
        assert bar.shape.size[0] < 2 * comp.p.r  # the bar across the disk stays inside the rim
        assert _of(scene, wheel) == []
        R_link, _ = scene.link_pose(disk.link, 0)
        assert abs(_axis_world(scene, disk) @ (R_link @ comp.p.axis)) == pytest.approx(1.0, abs=1e-12)
    # the ground is the contacts' plane z = 0 exactly (one grid for both), not a floor of the World's
    grids = [v for v in scene.visuals if isinstance(v.shape, Grid)]
    assert [g.component for g in grids] == ["rear_contact"] and _of(scene, "world") == []
    assert grids[0].r[2] == 0.0 and abs(_axis_world(scene, grids[0])[2]) == pytest.approx(1.0)
    lowest = min(res[f"{c}.p.z"].min() for c in ("rear_contact", "front_contact"))
    assert abs(lowest) < 1e-9  # the wheels touch that plane


def test_springs_span_their_attachment_points():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    ball = m.add("ball", RigidBody(m=1.0, I=1e-3 * np.eye(3)), free=True)
    s = m.add("s", Spring(c=100.0, s_unstretched=0.5))
    d = m.add("d", Damper(d=1.0))
    anchor = m.add("anchor", FixedTranslation(r=(0, 0, 1.0)))
    m.connect(w.frame_b, anchor.frame_a)
    for el in (s, d):
        m.connect(anchor.frame_b, el.frame_a)
        m.connect(el.frame_b, ball.frame_a)
    res = mbcomp.simulate(m, t_end=0.5, params={"ball.free.r0": (0.1, 0.0, 0.3)})
    scene = build_scene(res)
    (coil,), (rod,) = _of(scene, "s"), _of(scene, "d")
    assert isinstance(coil.shape, Helix) and isinstance(rod.shape, Rod)
    for k in (0, -1):
        assert np.allclose(scene.point(coil.link, coil.r, k), (0, 0, 1.0), atol=1e-15)
        end = scene.point(coil.to_link, coil.to_r, k)
        assert np.allclose(end, [res[f"ball.r.{a}"][k] for a in "xyz"], atol=1e-12)


def test_a_massless_link_is_posed_by_the_kinematics():
    """Two hinges (z, then x) with no body between them: the cross between them is a link of its
    own, turned by the first hinge's angle about z at every output time."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j1 = m.add("j1", Revolute(n=(0, 0, 1), phi0=0.3, w0=2.0))
    j2 = m.add("j2", Revolute(n=(1, 0, 0), phi0=0.2))
    arm = m.add("arm", FixedTranslation(r=(0, -0.5, 0)))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, j1.frame_a); m.connect(j1.frame_b, j2.frame_a)
    m.connect(j2.frame_b, arm.frame_a); m.connect(arm.frame_b, b.frame_a)
    res = mbcomp.simulate(m, t_end=1.0)
    scene = build_scene(res)
    (hinge2,) = _of(scene, "j2")
    assert scene.links[hinge2.link].name.startswith("j1.frame_b")
    for k in (0, 7, -1):
        R, _ = scene.link_pose(hinge2.link, k)
        phi = res["j1.phi"][k]
        assert np.allclose(R, [[np.cos(phi), -np.sin(phi), 0], [np.sin(phi), np.cos(phi), 0], [0, 0, 1]], atol=1e-12)


def test_the_ground_lies_below_the_motion(crank):
    _, res = crank
    scene = build_scene(res)
    (grid,) = _of(scene, "world")
    assert isinstance(grid.shape, Grid)
    assert np.allclose(_axis_world(scene, grid), (0, 1, 0))
    lowest = min(res["crank.r.y"].min(), res["rod.r.y"].min(), res["slider.r.y"].min(),
                 (res["crank.r.y"] + 0.2 * (2 * (res["crank.Q.w"] * res["crank.Q.z"]))).min())
    assert grid.r[1] < lowest
    assert grid.shape.size >= scene.scale


def test_declared_shapes_colours_and_hiding():
    m, res = _pendulum(Revolute(phi0=0.3, color="red"),
                       RigidBody(m=1.0, shape=[mbcomp.Box((0.1, 0.2, 0.3), r=(0.05, 0, 0)), mbcomp.Sphere(0.02)],
                                 color=(0, 0, 1)))
    scene = build_scene(res)
    assert [v.color for v in _of(scene, "j")] == ["#ff0000"]
    body = _of(scene, "b")
    assert [type(v.shape).__name__ for v in body] == ["Box", "Sphere"] and {v.color for v in body} == {"#0000ff"}
    assert np.allclose(body[0].r, (0.05, 0, 0)) and body[0].link == scene.bodies["b"][0]
    assert _of(build_scene(res, hide=["j", "w*"]), "j") == [] and _of(build_scene(res, hide=["w*"]), "world") == []
    _, res2 = _pendulum(Revolute(phi0=0.3, visible=False), PointMass(m=1.0))
    assert _of(build_scene(res2), "j") == []


def test_bad_looks_are_clear_errors():
    with pytest.raises(TypeError, match="shape=.*not a shape"):
        RigidBody(m=1.0, shape="box")
    with pytest.raises(ValueError, match="no colour"):
        Revolute(color="ultraviolet")
    with pytest.raises(ValueError, match="Cylinder: radius=-1"):
        mbcomp.Cylinder(radius=-1)
    _, res = _pendulum(Revolute(phi0=0.3), RigidBody(m=1.0, shape=mbcomp.Sphere(0.1, frame="frame_b")))
    with pytest.raises(ValueError, match="b: a shape is placed on 'frame_b'.*frame_a"):
        build_scene(res)


def test_trails_and_colouring_by_a_column(crank):
    _, res = crank
    scene = build_scene(res, trails=["rod_tip.frame_b", "crank"], color_by={"rod": "pin.f"})
    tip = scene.trails[0]
    for k in (0, 5, -1):
        assert np.allclose(scene.point(tip["link"], tip["r"], k), [res[f"slider.r.{a}"][k] for a in "xyz"], atol=1e-7)
    (col,) = scene.colors
    assert np.allclose(col["values"], np.sqrt(res["pin.f.x"] ** 2 + res["pin.f.y"] ** 2 + res["pin.f.z"] ** 2))
    assert col["max"] == pytest.approx(col["values"].max())
    with pytest.raises(ValueError, match="trail 'crank.frame_q'.*frame_a"):
        build_scene(res, trails=["crank.frame_q"])
    with pytest.raises(ValueError, match="no column 'pin.force'.*pin.f"):
        build_scene(res, color_by={"rod": "pin.force"})


def test_a_result_from_elsewhere_needs_its_system(crank):
    _, res = crank
    bare = mbcomp.Result(res.time, {n: res[n] for n in res.names})
    with pytest.raises(ValueError, match="system=mbcomp.assemble"):
        build_scene(bare)
    assert build_scene(bare, system=res.system).bodies.keys() == {"crank", "rod", "slider"}


def test_free_bodies_reach_the_scene():
    m = mbcomp.Model()
    m.add("world", World(g=(0, 0, -9.81)))
    m.add("ball", RigidBody(m=1.0, I=1e-3 * np.eye(3)), free=True)
    res = mbcomp.simulate(m, t_end=0.3, params={"ball.free.v0": (1.0, 0, 2.0)})
    scene = build_scene(res)
    k = -1
    assert np.allclose(scene.point(scene.bodies["ball"][0], (0, 0, 0), k), [res[f"ball.r.{a}"][k] for a in "xyz"])
    assert isinstance(FreeMotion(), mbcomp.Joint) and _of(scene, "ball.free") == []
    assert isinstance(_of(scene, "ball")[0].shape, Box)


def test_the_disk_contact_declares_it_draws_the_wheel():
    assert DiskContact.draws_body and not Revolute.draws_body
    q = quat_to_matrix(np.array([1.0, 0, 0, 0]))
    assert np.allclose(q, np.eye(3))
