"""Components without frames are seen on the joint their flange is on: a rotor ``Inertia`` is a
disk about the joint's axis on the frame its flange turns (the joint's frame_b on ``axis``,
frame_a on ``support``), placed by the scene (``view.axis``).

Checks: the disk's axis in the world is the joint's axis at every output time; its bar turns
by exactly the joint angle; on a support flange it stays put; its radius is the steel disk's
of inertia ``J``.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import Fixed, FixedTranslation, Inertia, Revolute, Torque
from mbcomp.modeling.shapes import STEEL, Box, Cylinder
from mbcomp.visual.scene import build_scene

AXIS = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)


def rotor_model(flange="axis", J=0.05):
    m = mbcomp.Model()
    base = m.add("base", Fixed())
    j = m.add("j", Revolute(n=tuple(AXIS), phi0=0.2))
    hub = m.add("hub", FixedTranslation(r=(0.6, 0.0, 0.0)))
    rotor = m.add("rotor", Inertia(J=J))
    m.connect(base.frame_b, j.frame_a)
    m.connect(j.frame_b, hub.frame_a)
    m.connect(rotor.flange, getattr(j, flange))
    if flange == "support":  # the shaft still needs inertia of its own to turn
        m.add("rotor2", Inertia(J=J))
        m.connect(m["rotor2"].flange, j.axis)
    tq = m.add("tq", Torque(tau=2.0))
    m.connect(tq.flange_b, j.axis)
    return m


def rotor_shapes(scene, name="rotor"):
    disk = next(v for v in scene.visuals if v.component == name and isinstance(v.shape, Cylinder))
    bar = next(v for v in scene.visuals if v.component == name and isinstance(v.shape, Box))
    return disk, bar


def test_a_rotor_is_a_disk_about_its_joint_axis_turning_with_the_joint():
    res = mbcomp.simulate(rotor_model(), t_end=1.0, n_out=20)
    scene = build_scene(res)
    disk, bar = rotor_shapes(scene)
    phi = np.asarray(res["j.phi"])
    assert phi[-1] - phi[0] > 1.0  # it really turns: tau / J t^2 / 2 = 20 rad
    x0 = scene.placement(bar, 0)[0][:, 0]
    for k in range(len(res.time)):
        R, r = scene.placement(disk, k)
        assert abs(abs(R[:, 2] @ AXIS) - 1.0) < 1e-12, "the disk's axis is the joint's"
        assert np.linalg.norm(r) < 1e-12  # on the joint's origin (frame_b's, the hinge's point)
        x = scene.placement(bar, k)[0][:, 0]
        d = phi[k] - phi[0]  # Rodrigues: x0 turned by the joint angle about the axis
        want = x0 * np.cos(d) + np.cross(AXIS, x0) * np.sin(d) + AXIS * (AXIS @ x0) * (1 - np.cos(d))
        np.testing.assert_allclose(x, want, atol=1e-9)


def test_a_rotor_on_a_support_flange_stays_with_frame_a():
    res = mbcomp.simulate(rotor_model("support"), t_end=0.5, n_out=5)
    scene = build_scene(res)
    disk, _ = rotor_shapes(scene)
    assert disk.link == 0  # the joint's frame_a is the world's
    turning, _ = rotor_shapes(scene, "rotor2")
    assert turning.link != 0


@pytest.mark.parametrize("J", [1e-3, 0.05])
def test_the_disk_has_the_inertia_of_a_steel_disk(J):
    res = mbcomp.simulate(rotor_model(J=J), t_end=0.1, n_out=2)
    scene = build_scene(res)
    disk, _ = rotor_shapes(scene)
    r, h = disk.shape.radius, disk.shape.length
    assert h == pytest.approx(r / 4, rel=1e-12)
    assert 0.03 * scene.scale < r < 0.25 * scene.scale  # not clipped to the scene's size (0.6 m)
    assert STEEL * np.pi * r**2 * h * r**2 / 2 == pytest.approx(J, rel=1e-9)
