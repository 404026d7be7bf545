"""A ball on a massless rod (SphericalSpherical, UniversalSpherical) swinging under gravity.

The same pendulum two ways: the rod as a tree edge (5 minimal coordinates) and the rod as
a cut joint (one distance row) to a ball on a FreeMotion (6 coordinates). Both must give the
same motion, the rod tension of a point mass on a string, ``T = m |v|^2 / L + m g cos(theta)``
(theta from the downward vertical; ``|v| = L dtheta/dt`` in a vertical plane), the conical
pendulum's steady rate ``Omega^2 = g / (L cos(alpha))``, and conserve energy.

The ball is point-like: its centre of mass on frame_b's origin, a small isotropic inertia (so
it is not massless), which turns freely at a constant rate (the spherical end passes no torque).
As a tree edge the tension is the reaction along the rod: the contract hands a tree joint's
``outputs`` no multiplier, so ``f_rod`` exists only for the cut rod and here the tree's tension
is ``-f . e`` with ``f`` the reaction ``rod.f.*`` on frame_b (turned to world axes by the
ball's quaternion) and ``e`` the rod direction.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.kinematics import quat_to_matrix
from mbcomp.library import FreeMotion, RigidBody, SphericalSpherical, UniversalSpherical, World

M, L, G = 2.0, 1.5, 9.81
RTOL, ATOL = 1e-10, 1e-12
CLASSES = [SphericalSpherical, UniversalSpherical]


def pendulum(cls, cut, phi_a, phi_b, w_a, w_b):
    """The ball on a rod from the world origin (gravity -y); start angles and rates of the
    rod's tree coordinates. ``cut``: the ball on a FreeMotion started in the same state."""
    start = dict(phi_a0=phi_a, phi_b0=phi_b, w_a0=w_a, w_b0=w_b, R0=np.eye(3), w0=np.zeros(3))
    m = mbcomp.Model()
    world = m.add("world", World(g=(0.0, -G, 0.0)))
    ball = m.add("ball", RigidBody(m=M, I=1e-3 * np.eye(3)))
    if cut:
        ref = cls(L=L, **start)
        q, _, u, _ = ref.start(ref.p)
        R, r = ref.relative(q, ref.p)
        Hw, Hv = ref.motion(q, ref.p)
        free = m.add("free", FreeMotion(r0=r, v0=Hv @ u, R0=R, w0=R.T @ (Hw @ u)))
        m.connect(world.frame_b, free.frame_a)
        m.connect(free.frame_b, ball.frame_a)
        rod = m.add("rod", cls(L=L, cut=True))
    else:
        rod = m.add("rod", cls(L=L, **start))
    m.connect(world.frame_b, rod.frame_a)
    m.connect(rod.frame_b, ball.frame_a)
    return m


def run(cls, cut, start, t_end, atol=ATOL):
    system = mbcomp.assemble(pendulum(cls, cut, *start))
    assert system.topology.cut == (["rod"] if cut else [])
    assert system.nu == (6 if cut else 5)
    res = mbcomp.simulate(system, t_end=t_end, rtol=RTOL, atol=atol)
    assert res.status == "success", res.message
    return res


def position(res):
    return np.column_stack([res[f"ball.r.{x}"] for x in "xyz"])


def velocity(res):
    return np.column_stack([res[f"ball.v.{x}"] for x in "xyz"])


def tension(res, cut):
    """The rod's tension: ``f_rod`` of the cut rod, the reaction along the rod of the tree's."""
    if cut:
        return res["rod.f_rod"]
    e = position(res) / L
    f_b = np.column_stack([res[f"rod.f.{x}"] for x in "xyz"])
    Q = np.column_stack([res[f"ball.Q.{x}"] for x in "wxyz"])
    return np.array([-(quat_to_matrix(q) @ f) @ ek for q, f, ek in zip(Q, f_b, e)])


def string_tension(res):
    """``m |v|^2 / L + m g cos(theta)``, theta from the downward vertical (-y)."""
    cos_theta = -res["ball.r.y"] / L
    return M * np.sum(velocity(res) ** 2, axis=1) / L + M * G * cos_theta


SWING = (0.9, 0.0, 0.0, 0.0)                       # from 0.9 rad in the y-z plane, at rest
TUMBLE = (0.8, 0.3, 0.5, 1.0)                      # a general 3-D start
ALPHA = 0.6                                        # the conical pendulum's cone angle (rad)
OMEGA = np.sqrt(G / (L * np.cos(ALPHA)))
# rod at -alpha about x (e = (0, -cos, sin)); moving along +x at Omega L sin(alpha): phi_b' = Omega sin(alpha)
CONE = (-ALPHA, 0.0, 0.0, OMEGA * np.sin(ALPHA))
CONE_TIME = 3 * 2 * np.pi / OMEGA                  # three turns


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_cut_rod_and_tree_rod_give_the_same_motion(cls):
    tree, cut = run(cls, False, TUMBLE, 3.0), run(cls, True, TUMBLE, 3.0)
    assert np.allclose(tree.time, cut.time)
    assert np.abs(position(tree) - position(cut)).max() < 1e-8
    assert np.abs(velocity(tree) - velocity(cut)).max() < 1e-8
    for x in "xyz":   # the ball's spin: the spherical end passes no torque to it
        assert np.abs(tree[f"ball.w.{x}"] - cut[f"ball.w.{x}"]).max() < 1e-8
    assert np.abs(np.linalg.norm(position(tree), axis=1) - L).max() < 1e-12     # the rod's length
    assert np.ptp(np.linalg.norm(position(tree), axis=1)) < 1e-12
    assert np.abs(np.linalg.norm(position(cut), axis=1) - L).max() < 1e-8
    assert np.abs(tension(tree, False) - tension(cut, True)).max() < 1e-6 * M * G


@pytest.mark.parametrize("cut", [False, True], ids=["tree", "cut"])
@pytest.mark.parametrize("start", [SWING, TUMBLE], ids=["planar", "spherical"])
def test_rod_tension_is_the_string_tension(start, cut):
    res = run(SphericalSpherical, cut, start, 3.0)
    T = tension(res, cut)
    assert T.min() > 0.0                           # a hanging pendulum pulls its rod
    np.testing.assert_allclose(T, string_tension(res), rtol=1e-6)
    if start is SWING:                             # stays in the vertical y-z plane: T = m L theta'^2 + m g cos(theta)
        assert np.abs(res["ball.r.x"]).max() < 1e-12
        theta = np.arctan2(res["ball.r.z"], -res["ball.r.y"])
        theta_dot = (res["ball.r.y"] * res["ball.v.z"] - res["ball.r.z"] * res["ball.v.y"]) / -L**2
        np.testing.assert_allclose(T, M * L * theta_dot**2 + M * G * np.cos(theta), rtol=1e-6)
        assert abs(theta[0] + 0.9) < 1e-12 and theta.max() > 0.89 and np.abs(theta).max() < 0.9 + 1e-9   # to +0.9, no higher


@pytest.mark.parametrize("cut", [False, True], ids=["tree", "cut"])
@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_conical_pendulum_turns_steadily(cls, cut):
    res = run(cls, cut, CONE, CONE_TIME)
    cos_cone = -res["ball.r.y"] / L
    assert np.abs(np.arccos(cos_cone) - ALPHA).max() < 1e-8                # the cone angle holds
    turned = np.unwrap(np.arctan2(res["ball.r.x"], res["ball.r.z"]))       # azimuth about +y
    np.testing.assert_allclose(turned - turned[0], OMEGA * res.time, atol=1e-7)   # Omega^2 = g / (L cos(alpha))
    assert turned[-1] - turned[0] > 3 * 2 * np.pi - 1e-6
    np.testing.assert_allclose(tension(res, cut), M * G / np.cos(ALPHA), rtol=1e-6)


@pytest.mark.parametrize("cut", [False, True], ids=["tree", "cut"])
@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_energy_is_conserved(cls, cut):
    res = run(cls, cut, TUMBLE, 5.0, atol=1e-13)      # rtol 1e-10; the drift peaks between steps (dense output)
    E = res["energy.total"]
    assert abs(E[0] - (0.5 * M * np.sum(velocity(res)[0] ** 2) + 0.5 * 1e-3 * sum(res[f"ball.w.{x}"][0] ** 2
                                                                                   for x in "xyz")
                       + M * G * res["ball.r.y"][0])) < 1e-9
    assert np.ptp(E) < 1e-8
