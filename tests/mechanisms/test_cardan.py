"""Universal joints in mechanisms: the Hooke drive shaft's speed ratio, the Cardan shaft's
constant velocity, and the spatial slider-crank (models/spatial_slider_crank.py).

Phase convention of the Hooke joint. The input shaft turns about the world x axis by ``phi``
(driven: ``phi = W t``); the output shaft's axis is ``e = (cos(beta), sin(beta), 0)`` (the bend
about z by ``beta``). The Universal's first hinge ``n_a = z`` is fixed in the input shaft, its
second ``n_b = y`` in the output shaft; so at ``phi = 0`` the input yoke is normal to the plane
of the bend (x-y). With the output angle ``psi`` about ``e`` (``psi = 0``: the output yoke in the
plane), the yokes stay perpendicular:
``(0, -sin(phi), cos(phi)) . (-sin(beta) cos(psi), cos(beta) cos(psi), sin(psi)) = 0``, i.e.
``tan(psi) = cos(beta) tan(phi)``, whose derivative is the ratio
``w_out / w_in = cos(beta) / (1 - sin(beta)^2 sin(phi)^2)``.
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp import Guess, Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import (Cylindrical, FixedRotation, FixedTranslation, PrescribedMotion, Revolute, RigidBody,
                            Universal, World)

BETA, W = np.radians(30.0), 2.0
E_OUT = np.array([np.cos(BETA), np.sin(BETA), 0.0])
RUN = dict(t_end=np.pi / W * 2, rtol=1e-10, atol=1e-12, n_out=201, stabilization="projection")
SHAFT_I = np.diag([0.01, 0.02, 0.02])


def hooke_ratio(phi, beta=BETA):
    return np.cos(beta) / (1.0 - np.sin(beta) ** 2 * np.sin(phi) ** 2)


def spin(res, body, axis):
    """The body's angular velocity (rad/s) about the world direction ``axis``."""
    return np.stack([res[f"{body}.w.{a}"] for a in "xyz"], axis=1) @ axis


def _input_shaft(m, world):
    inp = m.add("inp", Revolute(n=(1, 0, 0), phi0=0.0))
    drive = m.add("drive", PrescribedMotion(s=f"{W}*t"))
    s_in = m.add("s_in", RigidBody(m=1.0, r_cm=(-0.2, 0, 0), I=SHAFT_I))
    m.connect(world.frame_b, inp.frame_a)
    m.connect(inp.frame_b, s_in.frame_a)
    m.connect(drive.flange_b, inp.axis)
    return s_in


def drive_shaft(universal_on_tree):
    """Input shaft driven at W about x, output shaft on a bearing bent by BETA about z, joined
    at the origin by a Universal. With a Revolute bearing the Universal closes the loop; with a
    Cylindrical bearing (weight 2 against the Universal's 1.5 with fixed start angles) the
    bearing is cut and the Universal stays on the tree."""
    m = Model()
    world = m.add("world", World(g=(0, 0, 0)))
    s_in = _input_shaft(m, world)
    bend = m.add("bend", FixedRotation(R=rot_axis((0, 0, 1), BETA)))
    if universal_on_tree:
        out = m.add("out", Cylindrical(n=(1, 0, 0)))
        uj = m.add("uj", Universal(n_a=(0, 0, 1), n_b=(0, 1, 0), phi_a0=BETA, phi_b0=0.0))
    else:
        out = m.add("out", Revolute(n=(1, 0, 0), phi0=Guess(0.0)))
        uj = m.add("uj", Universal(n_a=(0, 0, 1), n_b=(0, 1, 0)))
    s_out = m.add("s_out", RigidBody(m=1.0, r_cm=(0.2, 0.05, 0), I=SHAFT_I))
    m.connect(world.frame_b, bend.frame_a)
    m.connect(bend.frame_b, out.frame_a)
    m.connect(out.frame_b, s_out.frame_a)
    m.connect(s_in.frame_a, uj.frame_a)
    m.connect(s_out.frame_a, uj.frame_b)
    return m


@pytest.mark.parametrize("on_tree", [False, True], ids=["cut", "tree"])
def test_hooke_joint_speed_ratio(on_tree):
    system = mbcomp.assemble(drive_shaft(on_tree))
    assert system.topology.cut == (["out"] if on_tree else ["uj"])
    assert "degrees of freedom: 0 " in system.summary()      # the drive takes the one DOF
    res = mbcomp.simulate(system, **RUN)
    assert res.success, res.message
    phi = res["inp.phi"]
    assert np.ptp(phi) > 2 * np.pi - 1e-9                    # a whole revolution
    ratio = spin(res, "s_out", E_OUT) / W
    np.testing.assert_allclose(ratio, hooke_ratio(phi), atol=1e-8)
    assert ratio.min() < np.cos(BETA) + 1e-8 and ratio.max() > 1 / np.cos(BETA) - 1e-8
    if not on_tree:
        # the drive's power feeds the output shaft's kinetic energy (the reaction through the
        # cut Universal): P = d/dt (I w_out^2 / 2), I its inertia about its axis
        # with w_out = W ratio(phi): dw_out/dt = W^2 cos(beta) sin(beta)^2 sin(2 phi) / (1 - sin(beta)^2 sin(phi)^2)^2
        I_out = SHAFT_I[0, 0] + 1.0 * 0.05 ** 2
        s2 = np.sin(BETA) ** 2
        acc = W ** 2 * np.cos(BETA) * s2 * np.sin(2 * phi) / (1 - s2 * np.sin(phi) ** 2) ** 2
        np.testing.assert_allclose(res["drive.power"], I_out * res["out.w"] * acc, atol=1e-8)
        assert np.abs(res["drive.power"]).max() > 0.02                      # 0.03 W at most


def cardan_shaft(bearing):
    """Input shaft (x, driven), intermediate shaft along E_OUT from the origin to L E_OUT, output
    shaft parallel to the input (a Z arrangement) through L E_OUT; the intermediate shaft's two
    yokes are parallel (its y axis: n_b of the first joint, n_a of the second), in phase. With
    ``bearing`` the intermediate shaft turns in a Revolute bearing (both Universals cut), else it
    hangs between the two Universals (one on the tree)."""
    L = 0.5
    m = Model()
    world = m.add("world", World(g=(0, 0, 0)))
    s_in = _input_shaft(m, world)
    mid = m.add("mid", RigidBody(m=1.0, r_cm=(L / 2, 0, 0), I=SHAFT_I))
    mid_end = m.add("mid_end", FixedTranslation(r=(L, 0, 0)))
    u1 = m.add("u1", Universal(n_a=(0, 0, 1), n_b=(0, 1, 0), phi_a0=Guess(BETA), phi_b0=Guess(0.0)))
    u2 = m.add("u2", Universal(n_a=(0, 1, 0), n_b=(0, 0, 1), phi_a0=Guess(0.0), phi_b0=Guess(-BETA)))
    far = m.add("far", FixedTranslation(r=L * E_OUT))
    out = m.add("out", Revolute(n=(1, 0, 0), phi0=Guess(0.0)))
    s_out = m.add("s_out", RigidBody(m=1.0, r_cm=(0.2, 0.05, 0), I=SHAFT_I))
    m.connect(s_in.frame_a, u1.frame_a)
    m.connect(u1.frame_b, mid.frame_a)
    m.connect(mid.frame_a, mid_end.frame_a)
    m.connect(mid_end.frame_b, u2.frame_a)
    m.connect(u2.frame_b, s_out.frame_a)
    m.connect(world.frame_b, far.frame_a)
    m.connect(far.frame_b, out.frame_a)
    m.connect(out.frame_b, s_out.frame_a)
    if bearing:
        bend = m.add("bend", FixedRotation(R=rot_axis((0, 0, 1), BETA)))
        mid_bearing = m.add("mid_bearing", Revolute(n=(1, 0, 0), phi0=Guess(0.0)))
        m.connect(world.frame_b, bend.frame_a)
        m.connect(bend.frame_b, mid_bearing.frame_a)
        m.connect(mid_bearing.frame_b, mid.frame_a)
    return m


@pytest.mark.parametrize("bearing", [True, False], ids=["bearing", "hanging"])
def test_cardan_shaft_is_constant_velocity(bearing):
    system = mbcomp.assemble(cardan_shaft(bearing))
    cut = system.topology.cut
    assert cut == ["u1", "u2"] if bearing else (len(cut) == 1 and cut[0] in ("u1", "u2"))
    assert "degrees of freedom: 0 " in system.summary()
    res = mbcomp.simulate(system, **RUN)
    assert res.success, res.message
    phi = res["inp.phi"]
    w_mid = spin(res, "mid", E_OUT)
    np.testing.assert_allclose(w_mid / W, hooke_ratio(phi), atol=1e-8)       # it fluctuates ...
    assert np.ptp(w_mid) > 0.99 * W * (1 / np.cos(BETA) - np.cos(BETA))   # from cos(beta) W to W / cos(beta)
    np.testing.assert_allclose(res["out.w"], W, atol=1e-8)                   # ... the output does not
    np.testing.assert_allclose(spin(res, "s_out", np.array([1.0, 0, 0])), W, atol=1e-8)


# --- the spatial slider-crank --------------------------------------------------------------------
ssc = load_model("models/spatial_slider_crank.py")


def test_spatial_slider_crank_summary():
    text = mbcomp.assemble(ssc.build()).summary()
    assert "degrees of freedom: 1 " in text
    assert "cut joints (loop closure): ball; 3 constraint rows, rank 3" in text


@pytest.mark.parametrize("kw", [dict(stabilization="projection"), dict(formulation="dalembert")],
                         ids=["projection", "dalembert"])
def test_spatial_slider_crank_kinematics_and_energy(kw):
    res = mbcomp.simulate(ssc.build(), t_end=2.0, rtol=1e-10, atol=1e-12, n_out=41, **kw)
    assert res.success, res.message
    phi = res["crank_angle"]
    assert np.ptp(phi) > 4 * np.pi                                           # it turns round
    np.testing.assert_allclose(res["slider_position"], ssc.slider_position(phi), atol=1e-8)
    # the rod length from the bodies' positions: |P_crank - P_slider| = L
    tip = np.stack([np.full_like(phi, 0.05), 0.1 * np.cos(phi), 0.1 * np.sin(phi)], axis=1)
    slider = np.stack([res[f"slider.r.{a}"] for a in "xyz"], axis=1)
    np.testing.assert_allclose(np.linalg.norm(tip - slider, axis=1), 0.5, atol=1e-8)
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-7
    assert np.ptp(res["energy.kinetic"]) > 0.1                               # energy is exchanged
