"""Free rigid bodies: implicit and explicit FreeMotion.

* With gravity (and any force applied at any point), the centre of mass follows
  r_cm(t) = r_cm0 + v_cm0 t + (g + F/m) t^2 / 2 exactly, whatever the body's rotation.
* Gravity exerts no torque about the centre of mass: the spin angular momentum R I R^T w and
  the rotational kinetic energy are constant.
* Without gravity a body with three distinct principal moments, spinning about a general
  axis, keeps its world angular momentum and its kinetic energy, while its angular velocity
  wanders (Euler's equations).

Every quantity is computed from the body outputs r, v, w (world) and Q (frame_a -> world).
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.kinematics import quat_to_matrix, rot_axis
from mbcomp.library import FreeMotion, RigidBody, World, WorldForce

G = np.array([0.0, -9.81, 0.0])
M = 2.5
R_CM = np.array([0.12, -0.3, 0.07])
# three distinct principal moments, principal axes tilted with respect to frame_a
_P = rot_axis([1.0, 2.0, -0.5], 0.8)
I_BODY = _P @ np.diag([0.04, 0.09, 0.12]) @ _P.T
R0 = rot_axis([0.3, -1.0, 0.4], 1.1)
P0 = np.array([0.5, 1.0, -0.2])  # frame_a origin, world
V0 = np.array([1.5, 4.0, -0.8])  # frame_a origin velocity, world
W0 = np.array([3.0, -5.0, 7.0])  # angular velocity, frame_a (= frame_b of the joint) axes


def _vec(r, name):
    return np.column_stack([r[f"{name}.{a}"] for a in "xyz"])


def kinematics(r, name, r_cm=R_CM, I=I_BODY, m=M):
    """Centre of mass position/velocity, world angular momentum about the origin, spin part,
    rotational and total kinetic energy, world angular velocity."""
    Q = np.column_stack([r[f"{name}.Q.{a}"] for a in "wxyz"])
    R = np.array([quat_to_matrix(q) for q in Q])
    w = _vec(r, f"{name}.w")
    c = R @ r_cm
    rc = _vec(r, f"{name}.r") + c
    vc = _vec(r, f"{name}.v") + np.cross(w, c)
    Hs = np.einsum("nij,jk,nlk,nl->ni", R, I, R, w)  # spin angular momentum about the CM
    L = m * np.cross(rc, vc) + Hs
    T_rot = 0.5 * np.einsum("ni,ni->n", w, Hs)
    T = 0.5 * m * np.einsum("ni,ni->n", vc, vc) + T_rot
    return dict(rc=rc, vc=vc, Hs=Hs, L=L, T_rot=T_rot, T=T, w=w, R=R)


def explicit_free_body(g):
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=tuple(g)))
    free = mdl.add("free", FreeMotion(r0=P0, R0=R0, v0=V0, w0=W0))
    body = mdl.add("body", RigidBody(m=M, r_cm=R_CM, I=I_BODY))
    mdl.connect(world.frame_b, free.frame_a)
    mdl.connect(free.frame_b, body.frame_a)
    return mdl


def test_body_marked_free_floats_freely():
    """A RigidBody connected to nothing and marked free (``Model.add(..., free=True)``) gets
    the implicit FreeMotion and falls from rest at the origin: r_cm = R_CM + g t^2 / 2."""
    mdl = mbcomp.Model()
    mdl.add("world", World())
    mdl.add("body", RigidBody(m=M, r_cm=R_CM, I=I_BODY), free=True)
    r = mbcomp.simulate(mdl, t_end=1.0, rtol=1e-10, atol=1e-12, n_out=51)
    assert r.success, r.message
    t = r.time[:, None]
    k = kinematics(r, "body")
    np.testing.assert_allclose(k["rc"], R_CM + 0.5 * G * t ** 2, rtol=0, atol=1e-9)
    assert "body.free (FreeMotion)" in r.summary


def test_implicit_free_motion_with_off_centre_force():
    """A body marked free, joined to nothing but a force element, floats (implicit
    FreeMotion, starts at rest at the origin). A constant force at frame_a's origin (off the
    CM) makes it tumble, but its CM still moves with the constant acceleration g + F/m."""
    F = np.array([3.0, 1.0, -2.0])
    mdl = mbcomp.Model()
    mdl.add("world", World())
    body = mdl.add("body", RigidBody(m=M, r_cm=R_CM, I=I_BODY), free=True)
    push = mdl.add("push", WorldForce(f=tuple(F)))
    mdl.connect(push.frame_b, body.frame_a)
    system = mbcomp.assemble(mdl)
    assert "body.free (FreeMotion)" in system.summary() and "body.free" in system.summary()
    assert system.nu == 6 and system.nq == 7
    r = mbcomp.simulate(system, t_end=1.5, rtol=1e-11, atol=1e-12, n_out=151)
    assert r.success, r.message
    t = r.time[:, None]
    k = kinematics(r, "body")
    np.testing.assert_allclose(k["rc"], R_CM + 0.5 * (G + F / M) * t ** 2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(k["vc"], (G + F / M) * t, rtol=0, atol=1e-9)
    # the force's moment about the CM spins the body up: the orientation really changes
    assert np.linalg.norm(k["w"][-1]) > 1.0


@pytest.fixture(scope="module")
def ballistic():
    r = mbcomp.simulate(explicit_free_body(G), t_end=2.0, rtol=1e-11, atol=1e-12, n_out=201)
    assert r.success, r.message
    return r


def test_start_state_is_the_fixed_one(ballistic):
    r = ballistic
    np.testing.assert_allclose(_vec(r, "body.r")[0], P0, atol=1e-14)
    np.testing.assert_allclose(_vec(r, "body.v")[0], V0, atol=1e-14)
    np.testing.assert_allclose(_vec(r, "body.w")[0], R0 @ W0, atol=1e-13)
    Q0 = [r[f"body.Q.{a}"][0] for a in "wxyz"]
    np.testing.assert_allclose(quat_to_matrix(Q0), R0, atol=1e-14)


def test_centre_of_mass_follows_ballistic_parabola(ballistic):
    r = ballistic
    t = r.time[:, None]
    k = kinematics(r, "body")
    rc0 = P0 + R0 @ R_CM
    vc0 = V0 + np.cross(R0 @ W0, R0 @ R_CM)
    np.testing.assert_allclose(k["rc"], rc0 + vc0 * t + 0.5 * G * t ** 2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(k["vc"], vc0 + G * t, rtol=0, atol=1e-9)
    # frame_a's origin is not the CM and does NOT follow a parabola (the test has teeth)
    ra = _vec(r, "body.r")
    assert np.abs(ra - (P0 + V0 * t + 0.5 * G * t ** 2)).max() > 0.05


def test_gravity_exerts_no_torque_about_the_centre_of_mass(ballistic):
    k = kinematics(ballistic, "body")
    H0 = np.linalg.norm(k["Hs"][0])
    assert np.abs(k["Hs"] - k["Hs"][0]).max() < 1e-8 * H0
    assert np.ptp(k["T_rot"]) < 1e-8 * k["T_rot"][0]
    E = ballistic["energy.total"]
    np.testing.assert_allclose(ballistic["energy.kinetic"], k["T"], rtol=1e-12)
    assert np.ptp(E) < 1e-8 * np.abs(ballistic["energy.kinetic"]).max()


def test_torque_free_body_keeps_angular_momentum_and_kinetic_energy():
    r = mbcomp.simulate(explicit_free_body((0.0, 0.0, 0.0)), t_end=4.0, rtol=1e-11, atol=1e-12, n_out=401)
    assert r.success, r.message
    t = r.time[:, None]
    k = kinematics(r, "body")
    L0 = np.linalg.norm(k["L"][0])
    np.testing.assert_allclose(k["L"], np.broadcast_to(k["L"][0], k["L"].shape), rtol=0, atol=1e-8 * L0)
    np.testing.assert_allclose(k["Hs"], np.broadcast_to(k["Hs"][0], k["Hs"].shape), rtol=0,
                               atol=1e-8 * np.linalg.norm(k["Hs"][0]))
    assert np.ptp(k["T"]) < 1e-8 * k["T"][0]
    np.testing.assert_allclose(r["energy.kinetic"], k["T"], rtol=1e-12)
    # CM in uniform straight-line motion
    rc0 = P0 + R0 @ R_CM
    vc0 = V0 + np.cross(R0 @ W0, R0 @ R_CM)
    np.testing.assert_allclose(k["rc"], rc0 + vc0 * t, rtol=0, atol=1e-9)
    # the angular velocity is not constant (general axis, distinct moments): Euler dynamics
    w = k["w"]
    assert np.abs(w - w[0]).max() > 0.2 * np.linalg.norm(w[0])


def test_implicit_free_body_takes_start_values_at_run_time():
    """The implicit FreeMotion of a lone body is named "<body>.free"; its start values are
    runtime parameters. A body thrown upward at v0 is back at its start height at 2 v0 / g."""
    mdl = mbcomp.Model()
    mdl.add("world", World())
    mdl.add("ball", RigidBody(m=1.0, I=np.eye(3) * 1e-3), free=True)
    v0 = 4.0
    t_back = 2 * v0 / 9.81
    res = mbcomp.simulate(mdl, t_end=t_back, rtol=1e-10, atol=1e-12, n_out=5,
                          params={"ball.free.r0": (0.0, 1.0, 0.0), "ball.free.v0": (1.0, v0, 0.0)})
    assert res.success
    assert abs(res["ball.r.y"][-1] - 1.0) < 1e-9
    assert abs(res["ball.r.x"][-1] - t_back) < 1e-9
    assert "ball.free" in res.summary


@pytest.mark.parametrize("backend", ["numeric", "auto"])
def test_a_free_point_mass_is_a_projectile_with_three_coordinates(backend):
    """A point mass added free=True has no rotation to move: it gets a translation-only free
    joint (three coordinates, where a 6-DOF one had three massless rotations) and flies the
    parabola r0 + v0 t + g t^2 / 2."""
    from mbcomp.library import PointMass

    mdl = mbcomp.Model()
    mdl.add("world", World())
    mdl.add("ball", PointMass(m=0.5), free=True)
    r0, v0 = np.array([0.0, 2.0, 0.3]), np.array([1.0, 3.0, -0.5])
    res = mbcomp.simulate(mdl, t_end=1.0, n_out=11, rtol=1e-10, atol=1e-12, backend=backend,
                          params={"ball.free.r0": tuple(r0), "ball.free.v0": tuple(v0)})
    assert res.success and res.stats["coordinates"] == ["ball.free.r.x", "ball.free.r.y", "ball.free.r.z"]
    t = res.time[:, None]
    r = np.stack([res[f"ball.r.{a}"] for a in "xyz"], -1)
    np.testing.assert_allclose(r, r0 + v0 * t + 0.5 * G * t ** 2, atol=1e-10)
    assert "Gruebler M = 6N - C - L = 6*1 - 3 - 0 = 3" in res.summary


def test_a_free_point_mass_on_a_spring_oscillates_at_sqrt_c_over_m():
    """Three-dimensional harmonic motion about the spring's anchor (no gravity, rest length
    0): r(t) = r0 cos(w t) + v0 / w sin(w t), w = sqrt(c / m); energy constant."""
    from mbcomp.library import PointMass, Spring

    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, 0)))
    ball = mdl.add("ball", PointMass(m=2.0), free=True)
    spring = mdl.add("spring", Spring(c=50.0))
    mdl.connect(w.frame_b, spring.frame_a)
    mdl.connect(ball.frame_a, spring.frame_b)
    r0, v0, om = np.array([0.3, -0.1, 0.2]), np.array([0.0, 1.0, 0.5]), 5.0
    res = mbcomp.simulate(mdl, t_end=2.0, n_out=41, rtol=1e-10, atol=1e-12,
                          params={"ball.free.r0": tuple(r0), "ball.free.v0": tuple(v0)})
    assert res.success, res.message
    t = res.time[:, None]
    r = np.stack([res[f"ball.r.{a}"] for a in "xyz"], -1)
    np.testing.assert_allclose(r, r0 * np.cos(om * t) + v0 / om * np.sin(om * t), atol=1e-8)
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-8 * E[0]
