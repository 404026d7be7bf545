"""Universal and Planar joints: parameter checks, degree-of-freedom counts, and motions with
closed forms (a body on a Planar joint under gravity; a body on a Universal joint against the
same body on two Revolute joints through a massless cross piece)."""
import numpy as np
import pytest

import mbcomp
from mbcomp import Guess, Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import FixedRotation, Planar, Prismatic, Revolute, RigidBody, Spherical, Universal, World

G = 9.81


def _unit(v):
    return np.asarray(v, float) / np.linalg.norm(v)


@pytest.mark.parametrize("cls, kw, name", [(Universal, dict(n_a=(1, 0, 0), n_b=(1, 1, 0)), "n_b"),
                                           (Planar, dict(n=(0, 0, 1), n_x=(1, 0, 1)), "n_x")])
def test_axes_that_are_not_perpendicular_are_refused(cls, kw, name):
    (problem,) = cls(**kw).problems()
    text = str(problem)
    assert problem.where.endswith(name) and "45 deg" in text and "perpendicular" in text


def _on_world(joint, body=None):
    m = Model()
    world = m.add("world", World(g=(0, 0, -G)))
    j = m.add("j", joint)
    b = m.add("b", body or RigidBody(m=2.0, I=np.diag([0.01, 0.02, 0.03])))
    m.connect(world.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def test_summary_counts_a_body_on_each_joint():
    uni = mbcomp.assemble(_on_world(Universal())).summary()
    assert "degrees of freedom: 2 " in uni and "coordinates (2 q, 2 speeds): j.phi_a, j.phi_b" in uni
    pla = mbcomp.assemble(_on_world(Planar())).summary()
    assert "degrees of freedom: 3 " in pla and "coordinates (3 q, 3 speeds): j.s_x, j.s_y, j.phi" in pla


# --- Planar: free flight in a tilted plane ----------------------------------------------------------
N, NX = _unit((0, 1, 1)), (1, 0, 0)          # plane normal and s_x direction, world = frame_a axes
EY = np.cross(N, NX)
X0, Y0, PHI0, VX0, VY0, W0, M = 0.2, -0.1, 0.3, 0.5, 1.5, 4.0, 2.0


def test_body_on_planar_joint_flies_a_parabola_and_spins_steadily():
    """The centre of mass (at frame_b's origin) accelerates by g's component in the plane,
    ``s_y'' = g . e_y`` (``g . e_x = 0``), it spins at constant rate about n (no torque), and the
    joint takes the normal part of the weight: reaction ``-m (g . n) n`` on frame_b (frame_b
    axes, which keep n)."""
    joint = Planar(n=N, n_x=NX, x0=X0, y0=Y0, phi0=PHI0, vx0=VX0, vy0=VY0, w0=W0)
    res = mbcomp.simulate(_on_world(joint, RigidBody(m=M, I=np.diag([0.01, 0.02, 0.03]))), t_end=1.0,
                          rtol=1e-11, atol=1e-12)
    t, g = res.time, np.array([0, 0, -G])
    np.testing.assert_allclose(res["j.s_x"], X0 + VX0 * t, atol=1e-9)
    np.testing.assert_allclose(res["j.s_y"], Y0 + VY0 * t + 0.5 * (g @ EY) * t ** 2, atol=1e-9)
    np.testing.assert_allclose(res["j.phi"], PHI0 + W0 * t, atol=1e-9)
    np.testing.assert_allclose(res["j.w"], W0, atol=1e-9)
    f = np.stack([res[f"j.f.{a}"] for a in "xyz"], axis=1)
    np.testing.assert_allclose(f, np.tile(-M * (g @ N) * N, (len(t), 1)), atol=1e-8)
    assert np.ptp(res["energy.total"]) < 1e-9


def test_cut_planar_joint_keeps_the_plane():
    """A Planar joint closing a loop: the body hangs on a slide (along x) and a ball joint,
    the Planar joint to the world keeps it in the x-y plane upright -- its two tilt rows act,
    its out-of-plane row is redundant (the slide keeps the ball in the plane). Under gravity
    along x the body slides as a free mass and spins at its start rate."""
    m = Model()
    world = m.add("world", World(g=(-G, 0, 0)))
    slide = m.add("slide", Prismatic(n=(1, 0, 0), s0=0.0, v0=0.5))
    ball = m.add("ball", Spherical(R0=rot_axis((0, 0, 1), 0.2), w0=Guess((0, 0, 3.0))))
    body = m.add("body", RigidBody(m=1.5, I=np.diag([0.02, 0.03, 0.04])))
    plane = m.add("plane", Planar(n=(0, 0, 1)))
    m.connect(world.frame_b, slide.frame_a)
    m.connect(slide.frame_b, ball.frame_a)
    m.connect(ball.frame_b, body.frame_a)
    m.connect(world.frame_b, plane.frame_a)
    m.connect(body.frame_a, plane.frame_b)
    system = mbcomp.assemble(m)
    assert system.topology.cut == ["plane"]
    text = system.summary()
    assert "degrees of freedom: 2 " in text and "plane; 3 constraint rows, rank 2" in text
    res = mbcomp.simulate(system, t_end=1.0, stabilization="projection", rtol=1e-11, atol=1e-12)
    t = res.time
    np.testing.assert_allclose(res["slide.s"], 0.5 * t - 0.5 * G * t ** 2, atol=1e-9)
    np.testing.assert_allclose(res["body.w.z"], 3.0, atol=1e-9)
    assert np.abs(res["body.w.x"]).max() < 1e-9 and np.abs(res["body.w.y"]).max() < 1e-9


# --- Universal on the tree: against two revolutes through a massless cross piece -----------------
NA, NB = _unit((1, 1, 0)), _unit((0, 0, 1))    # perpendicular hinge axes
BODY = dict(m=2.0, r_cm=(0.3, 0.1, -0.2), I=np.diag([0.01, 0.02, 0.03]))


def _hooke(start, uni):
    """A body hanging on a Universal joint, or on Revolute(n_a) then Revolute(n_b)."""
    (pa, pb), (wa, wb) = start
    m = Model()
    world = m.add("world", World(g=(0, 0, -G)))
    body = m.add("b", RigidBody(**BODY))
    if uni:
        j = m.add("j", Universal(n_a=NA, n_b=NB, phi_a0=pa, phi_b0=pb, w_a0=wa, w_b0=wb))
        m.connect(world.frame_b, j.frame_a)
        m.connect(j.frame_b, body.frame_a)
        return m
    ja = m.add("ja", Revolute(n=NA, phi0=pa, w0=wa))
    jb = m.add("jb", Revolute(n=NB, phi0=pb, w0=wb))
    m.connect(world.frame_b, ja.frame_a)
    m.connect(ja.frame_b, jb.frame_a)                 # the cross piece: a frame with no mass
    m.connect(jb.frame_b, body.frame_a)
    return m


def test_universal_on_the_tree_moves_as_two_revolutes():
    """The same mechanism two ways: the Universal's velocity-product term (its motion_bias)
    must reproduce what two revolutes give without one; and energy is conserved."""
    start = ((0.4, -0.3), (2.0, -3.0))
    kw = dict(t_end=2.0, rtol=1e-11, atol=1e-12, n_out=101)
    uni = mbcomp.simulate(_hooke(start, True), **kw)
    two = mbcomp.simulate(_hooke(start, False), **kw)
    assert mbcomp.assemble(_hooke(start, True)).topology.cut == []
    np.testing.assert_allclose(uni["j.phi_a"], two["ja.phi"], atol=1e-8)
    np.testing.assert_allclose(uni["j.phi_b"], two["jb.phi"], atol=1e-8)
    np.testing.assert_allclose(uni["j.w_b"], two["jb.w"], atol=1e-8)
    for a in "xyz":
        np.testing.assert_allclose(uni[f"b.r.{a}"], two[f"b.r.{a}"], atol=1e-8)
        np.testing.assert_allclose(uni[f"j.f.{a}"], two[f"jb.f.{a}"], atol=1e-7)   # the same reaction on the body
    E = uni["energy.total"]
    assert np.ptp(E) < 1e-9 * (1 + np.abs(E).max())
    assert np.ptp(uni["j.w_b"]) > 1.0                 # it swings: the check is not trivial
