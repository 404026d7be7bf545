"""Three-dimensional motion through a Spherical joint: conserved quantities.

(a) Spherical pendulum: a bob on a rigid rod (FixedTranslation) hinged by a ball joint at
    the world origin, gravity along -y. Gravity exerts no torque about the vertical axis
    through the pivot, so the total energy and the vertical (y) component of the angular
    momentum about the pivot are conserved.
(b) Heavy symmetric top: a RigidBody with inertia diag(A, C, A) whose centre of mass lies on
    its symmetry axis (body y), on a ball joint at the origin, spinning fast. Conserved: energy,
    vertical angular momentum L_y, and the spin omega . e_3 about the symmetry axis (Euler's
    third equation with I1 = I2 and no torque about e_3).

The angular momentum is computed from the body outputs only: L = m r_cm x v_cm + R I R^T w,
with r_cm = r + R r_cm_body and v_cm = v + w x (R r_cm_body).
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.kinematics import quat_to_matrix, rot_axis
from mbcomp.library import FixedTranslation, PointMass, RigidBody, Spherical, World

G = 9.81


def _vec(r, name):
    return np.column_stack([r[f"{name}.{a}"] for a in "xyz"])


def body_invariants(r, name, m, r_cm, I):
    """Energy (kinetic + gravity potential, datum y = 0), world angular momentum about the
    origin, and the body-frame rotation matrices, from the body's outputs."""
    Q = np.column_stack([r[f"{name}.Q.{a}"] for a in "wxyz"])
    R = np.array([quat_to_matrix(q) for q in Q])
    w = _vec(r, f"{name}.w")
    c = R @ np.asarray(r_cm, float)
    rc = _vec(r, f"{name}.r") + c
    vc = _vec(r, f"{name}.v") + np.cross(w, c)
    I_world = R @ np.asarray(I, float) @ R.transpose(0, 2, 1)
    Iw = np.einsum("nij,nj->ni", I_world, w)
    L = m * np.cross(rc, vc) + Iw
    E = 0.5 * m * np.einsum("ni,ni->n", vc, vc) + 0.5 * np.einsum("ni,ni->n", w, Iw) + m * G * rc[:, 1]
    return E, L, R, w


# --------------------------------------------------------------------------- (a) pendulum
L_ROD, M_BOB, A_BOB = 1.2, 0.8, 0.05
I_BOB = 0.4 * M_BOB * A_BOB ** 2  # a small solid sphere: isotropic inertia about its centre


def spherical_pendulum(bob):
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0, -G, 0)))
    ball = mdl.add("ball", Spherical(R0=rot_axis([0, 0, 1], 0.7), w0=(2.0, 0.3, 0.5)))
    rod = mdl.add("rod", FixedTranslation(r=(0, -L_ROD, 0)))
    mdl.add("bob", bob)
    mdl.connect(world.frame_b, ball.frame_a)
    mdl.connect(ball.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, bob.frame_a)
    return mdl


@pytest.fixture(scope="module")
def pendulum_result():
    bob = RigidBody(m=M_BOB, I=I_BOB * np.eye(3))
    r = mbcomp.simulate(spherical_pendulum(bob), t_end=4.0, rtol=1e-10, atol=1e-12, n_out=401)
    assert r.success, r.message
    return r


def test_spherical_pendulum_stays_on_sphere(pendulum_result):
    r = pendulum_result
    pos = _vec(r, "bob.r")
    np.testing.assert_allclose(np.linalg.norm(pos, axis=1), L_ROD, rtol=1e-12)
    # it really is a 3-D motion: the bob leaves the x-y plane and swings up and down
    assert np.ptp(pos[:, 2]) > 0.5 and np.ptp(pos[:, 1]) > 0.05


def test_spherical_pendulum_conserves_energy_and_vertical_angular_momentum(pendulum_result):
    r = pendulum_result
    E, Lw, _, _ = body_invariants(r, "bob", M_BOB, (0, 0, 0), I_BOB * np.eye(3))
    np.testing.assert_allclose(r["energy.total"], E, rtol=1e-12, atol=1e-12)
    E_scale = np.abs(r["energy.kinetic"]).max() + M_BOB * G * L_ROD
    assert np.ptp(E) < 1e-7 * E_scale
    # orbital part from the bob's position and velocity alone, plus the sphere's own spin
    pos, vel = _vec(r, "bob.r"), _vec(r, "bob.v")
    Ly = M_BOB * np.cross(pos, vel)[:, 1] + I_BOB * r["bob.w.y"]
    np.testing.assert_allclose(Ly, Lw[:, 1], rtol=1e-12, atol=1e-14)
    L_scale = M_BOB * L_ROD * np.linalg.norm(vel, axis=1).max()
    assert abs(Ly[0]) > 0.1 * L_scale  # a non-trivial conserved value
    assert np.ptp(Ly) < 1e-7 * L_scale
    # the horizontal components are not conserved (gravity torques them): the check has teeth
    assert np.ptp(Lw[:, 0]) > 0.1 * L_scale


def test_point_mass_on_ball_joint_has_undetermined_spin():
    """A bare point mass on the ball joint leaves the spin about the rod massless: mbcomp
    refuses it at initialization (it names the massless speed) instead of integrating a
    singular mass matrix."""
    with pytest.raises(mbcomp.InitializationError, match=r"ball\.w\.y"):
        mbcomp.simulate(spherical_pendulum(PointMass(m=M_BOB)), t_end=0.1)


# --------------------------------------------------------------------------- (b) top
M_TOP, H_TOP, A_TOP, C_TOP = 1.0, 0.1, 0.02, 0.03
SPIN = 40.0


def heavy_top():
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0, -G, 0)))
    ball = mdl.add("ball", Spherical(R0=rot_axis([1, 0, 1], 0.5), w0=(0.5, SPIN, -0.3)))
    top = mdl.add("top", RigidBody(m=M_TOP, r_cm=(0, H_TOP, 0), I=np.diag([A_TOP, C_TOP, A_TOP])))
    mdl.connect(world.frame_b, ball.frame_a)
    mdl.connect(ball.frame_b, top.frame_a)
    return mdl


@pytest.fixture(scope="module")
def top_result():
    r = mbcomp.simulate(heavy_top(), t_end=2.0, rtol=1e-10, atol=1e-12, n_out=401)
    assert r.success, r.message
    return r


def test_heavy_top_invariants(top_result):
    r = top_result
    I = np.diag([A_TOP, C_TOP, A_TOP])
    E, Lw, R, w = body_invariants(r, "top", M_TOP, (0, H_TOP, 0), I)
    # pivot fixed at the origin
    assert np.abs(_vec(r, "top.r")).max() < 1e-14
    # energy: the framework's value equals the independent one, and is constant
    np.testing.assert_allclose(r["energy.total"], E, rtol=1e-12)
    E_scale = 0.5 * C_TOP * SPIN ** 2
    assert np.ptp(E) < 1e-7 * E_scale
    # vertical angular momentum
    L_scale = C_TOP * SPIN
    assert abs(Lw[0, 1]) > 0.5 * L_scale
    assert np.ptp(Lw[:, 1]) < 1e-7 * L_scale
    # spin about the symmetry axis (body y = column 1 of R)
    spin = np.einsum("ni,ni->n", w, R[:, :, 1])
    assert spin[0] == pytest.approx(SPIN, rel=1e-12)
    assert np.ptp(spin) < 1e-7 * SPIN
    # the top precesses: its axis sweeps around the vertical, so L_x, L_z change a lot
    assert np.ptp(Lw[:, 0]) > 0.1 * L_scale and np.ptp(Lw[:, 2]) > 0.1 * L_scale
