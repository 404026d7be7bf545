"""The massless rods (library/rods.py): conventions, the distance row and its tension's sign,
start values, degree-of-freedom counts, and the universal pair's singularity.

The generic joint contract (jets against finite differences, the tree motion against
``relative``/``q_rate`` with the rods' ``motion_bias``) is in ``test_contracts.py``; whole
pendulums in ``tests/mechanisms/test_rod_pendulum.py``.
"""
from types import SimpleNamespace

import numpy as np
import pytest

import mbcomp
from mbcomp import Guess
from mbcomp.errors import InitializationError
from mbcomp.jets import FrameJet
from mbcomp.kinematics import rot_axis
from mbcomp.library import RigidBody, SphericalSpherical, UniversalSpherical, World

CLASSES = [SphericalSpherical, UniversalSpherical]
ids = [c.__name__ for c in CLASSES]
M, L, G = 2.0, 1.5, 9.81


@pytest.mark.parametrize("cls", CLASSES, ids=ids)
def test_tree_coordinates_follow_the_documented_convention(cls):
    n_a, e_rod = np.array([0.0, 0.0, 2.0]), np.array([1.0, 0.0, 0.7])   # e_rod's part normal to n_a: +x
    rod = cls(L=L, n_a=n_a, e_rod=e_rod)
    Q1 = np.array([1.0, 0.0, 0.0, 0.0])
    R, r = rod.relative(np.concatenate(([0.0, 0.0], Q1)), rod.p)
    np.testing.assert_allclose(R, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(r, [L, 0.0, 0.0], atol=1e-15)
    pa, pb = 0.7, -0.4
    R, r = rod.relative(np.concatenate(([pa, pb], Q1)), rod.p)
    # phi_a turns the rod about n_a, phi_b tilts it towards +n_a: e = rot(z, pa) (cos pb x + sin pb z)
    e = rot_axis([0, 0, 1], pa) @ np.array([np.cos(pb), 0.0, np.sin(pb)])
    np.testing.assert_allclose(r, L * e, atol=1e-14)
    # the rod frame carries frame_b: frame_a's x axis is turned onto the rod
    np.testing.assert_allclose(R @ [1.0, 0.0, 0.0], e, atol=1e-14)
    # Q is frame_b in the rod frame: a quarter turn about the rod's own x axis leaves r alone
    Qx = np.array([np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0])
    R2, r2 = rod.relative(np.concatenate(([pa, pb], Qx)), rod.p)
    np.testing.assert_allclose(r2, r, atol=1e-15)
    np.testing.assert_allclose(R2, R @ rot_axis([1, 0, 0], np.pi / 2), atol=1e-14)


def _jets(ra, rb, va, vb):
    z = np.zeros((3, 0))
    return (FrameJet(np.eye(3), np.asarray(ra, float), np.zeros(3), np.asarray(va, float), z, z, np.zeros(3),
                     np.zeros(3)),
            FrameJet(np.eye(3), np.asarray(rb, float), np.zeros(3), np.asarray(vb, float), z, z, np.zeros(3),
                     np.zeros(3)))


@pytest.mark.parametrize("cls", CLASSES, ids=ids)
def test_distance_row_is_the_squared_form(cls):
    rod = cls(L=2.0)
    a, b = _jets([0.1, 0.2, 0.3], [1.1, -2.0, 0.3], [0.0, 1.0, 0.0], [0.5, 0.0, -1.0])
    ((name, c),) = rod.constraints(a, b, rod.p)
    d = b.r - a.r
    assert name == "length"
    assert np.isclose(c.val, (d @ d - 4.0) / 4.0)                  # (|d|^2 - L^2) / (2 L)
    np.testing.assert_allclose(c.jac[6:9], d / 2.0)                # on the rod: the unit direction
    np.testing.assert_allclose(c.jac[0:3], -d / 2.0)
    np.testing.assert_allclose(c.jac[[3, 4, 5, 9, 10, 11]], 0.0)   # the ends turn freely
    assert np.isclose(c.dot, d @ (b.v - a.v) / 2.0)
    assert np.isclose(c.bias, (b.v - a.v) @ (b.v - a.v) / 2.0)
    # the tension from the multiplier: lam |d| / L; no multiplier (a tree edge), no column
    assert rod.outputs(a, b, rod.p, {"length": 3.0}) == {"f_rod": pytest.approx(3.0 * np.linalg.norm(d) / 2.0)}
    assert rod.outputs(a, b, rod.p, {}) == {}


def _hanging(cls, up):
    """A ball at rest on a cut rod straight below (``up``: above) the world origin."""
    m = mbcomp.Model()
    world = m.add("world", World(g=(0.0, -G, 0.0)))
    ball = m.add("ball", RigidBody(m=M, I=1e-3 * np.eye(3)), free=True)
    rod = m.add("rod", cls(L=L, cut=True))
    m.connect(world.frame_b, rod.frame_a)
    m.connect(rod.frame_b, ball.frame_a)
    return m, {"ball.free.r0": (0.0, L if up else -L, 0.0), "ball.free.v0": (0.0, 0.0, 0.0)}


@pytest.mark.parametrize("cls", CLASSES, ids=ids)
def test_tension_sign_pulled_hanging_pushed_standing(cls):
    m, params = _hanging(cls, up=False)
    res = mbcomp.simulate(m, t_end=0.2, params=params)
    np.testing.assert_allclose(res["rod.f_rod"], M * G, rtol=1e-9)            # holds the weight: tension
    m, params = _hanging(cls, up=True)
    res = mbcomp.simulate(m, t_end=0.2, params=params)
    np.testing.assert_allclose(res["rod.f_rod"][0], -M * G, rtol=1e-9)        # props it up: compression


@pytest.mark.parametrize("cls", CLASSES, ids=ids)
def test_dof_counts_tree_edge_and_cut(cls):
    m = mbcomp.Model()
    world = m.add("world", World())
    ball = m.add("ball", RigidBody(m=M, I=1e-3 * np.eye(3)))
    rod = m.add("rod", cls(L=L, phi_a0=0.5))
    m.connect(world.frame_b, rod.frame_a)
    m.connect(rod.frame_b, ball.frame_a)
    tree = mbcomp.assemble(m).summary()
    assert "degrees of freedom: 5   (Gruebler M = 6N - C - L = 6*1 - 1 - 0 = 5)" in tree
    assert "coordinates (6 q, 5 speeds): rod.phi_a, rod.phi_b, rod.Q.w" in tree
    m, params = _hanging(cls, up=False)
    cut = mbcomp.assemble(m, params).summary()
    assert "degrees of freedom: 5   (Gruebler M = 6N - C - L = 6*1 - 1 - 0 = 5)" in cut
    assert "coordinates (7 q, 6 speeds)" in cut and "cut joints (loop closure): rod; 1 constraint rows, rank 1" in cut


def test_start_values_fixed_or_guess():
    rod = SphericalSpherical(phi_a0=0.3, phi_b0=Guess(0.1), w0=(0.0, 0.0, 2.0), R0=Guess(np.eye(3)))
    q, q_fixed, u, u_fixed = rod.start(rod.p)
    np.testing.assert_allclose(q, [0.3, 0.1, 1.0, 0.0, 0.0, 0.0])
    assert q_fixed.tolist() == [True, False, False, False, False]
    np.testing.assert_allclose(u, [0.0, 0.0, 0.0, 0.0, 2.0])
    assert u_fixed.tolist() == [False, False, True, True, True]
    assert SphericalSpherical(cut=True).nq == 0 and SphericalSpherical(cut=True).nu == 0
    assert SphericalSpherical.tree_edge and not SphericalSpherical(cut=True).tree_edge


def test_initialization_solves_the_distance_row():
    m, _ = _hanging(SphericalSpherical, up=False)
    res = mbcomp.simulate(m, t_end=0.1, params={"ball.free.r0": Guess((0.3, -1.0, 0.2))})
    r0 = np.array([res[f"ball.r.{x}"][0] for x in "xyz"])
    assert abs(np.linalg.norm(r0) - L) < 1e-10
    np.testing.assert_allclose(r0 / L, np.array([0.3, -1.0, 0.2]) / np.linalg.norm([0.3, -1.0, 0.2]), atol=1e-9)
    with pytest.raises(InitializationError, match="rod"):                       # fixed off the rod's sphere
        mbcomp.simulate(m, t_end=0.1, params={"ball.free.r0": (0.3, -1.0, 0.2)})


def test_zero_direction_parallel_to_the_axis_is_reported():
    (problem,) = UniversalSpherical(n_a=(0, 2, 0), e_rod=(0, -1, 0)).problems()
    assert "parallel" in str(problem) and "e_rod" in str(problem)


@pytest.mark.parametrize("cls", CLASSES, ids=ids)
def test_tree_coordinates_stop_at_the_axis_the_constraint_passes(cls):
    """Started at rest 30 deg above +x (n_a = x), the ball swings down through the direction of
    n_a: the tree coordinates' singularity stops the run there, naming it; the pure constraint
    (cut=True) swings through with the string tension."""
    m = mbcomp.Model()
    world = m.add("world", World(g=(0.0, -G, 0.0)))
    ball = m.add("ball", RigidBody(m=M, I=1e-3 * np.eye(3)))
    rod = m.add("rod", cls(L=L, phi_a0=0.0, phi_b0=2 * np.pi / 3, w_a0=0.0, w_b0=0.0))  # e = (sin, -cos, 0)
    m.connect(world.frame_b, rod.frame_a)
    m.connect(rod.frame_b, ball.frame_a)
    res = mbcomp.simulate(m, t_end=1.0)
    assert res.status == "failed" and "rod" in res.message and "n_a" in res.message
    hit = res.time[-1]
    assert 0.2 < hit < 0.6                                                      # about a quarter swing
    m, _ = _hanging(cls, up=False)
    params = {"ball.free.r0": (L * np.cos(np.pi / 6), L * np.sin(np.pi / 6), 0.0)}
    res = mbcomp.simulate(m, t_end=1.0, params=params, rtol=1e-10, atol=1e-12)
    assert res.status == "success" and res["ball.r.y"].min() < -1.0             # swung through and down
    speed2 = sum(res[f"ball.v.{x}"] ** 2 for x in "xyz")
    np.testing.assert_allclose(res["rod.f_rod"], M * speed2 / L - M * G * res["ball.r.y"] / L, rtol=1e-6)


@pytest.mark.parametrize("cls", CLASSES, ids=ids)
def test_visuals_span_the_rod_with_balls_at_both_ends(cls):
    from mbcomp.visual.scene import build_scene

    m = mbcomp.Model()
    world = m.add("world", World(g=(0.0, -G, 0.0)))
    ball = m.add("ball", RigidBody(m=M, I=1e-3 * np.eye(3)))
    rod = m.add("rod", cls(L=L, phi_a0=0.7, phi_b0=0.2))
    m.connect(world.frame_b, rod.frame_a)
    m.connect(rod.frame_b, ball.frame_a)
    res = mbcomp.simulate(m, t_end=0.3)
    scene = build_scene(res)
    mine = [v for v in scene.visuals if v.component == "rod"]
    assert sorted(type(v.shape).__name__ for v in mine) == ["Rod", "Sphere", "Sphere"]
    k = len(res.time) - 1
    ball_r = np.array([res[f"ball.r.{x}"][k] for x in "xyz"])
    centres = sorted((scene.placement(v, k)[1] for v in mine if type(v.shape).__name__ == "Sphere"),
                     key=np.linalg.norm)
    np.testing.assert_allclose(centres[0], 0.0, atol=1e-12)                   # at frame_a (the world origin)
    np.testing.assert_allclose(centres[1], ball_r, atol=1e-12)                # at frame_b (the ball)
    (span,) = [v for v in mine if type(v.shape).__name__ == "Rod"]
    np.testing.assert_allclose(scene.placement(span, k)[1], 0.0, atol=1e-12)
    np.testing.assert_allclose(scene.point(span.to_link, span.to_r, k), ball_r, atol=1e-12)
