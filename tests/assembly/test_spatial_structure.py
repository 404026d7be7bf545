"""The structured articulated-body algorithm (assembly/recursive.py: symmetric articulated
inertias computed on one triangle, Cholesky-factored pivots, ball joints multiplied at their
centre) against the dense 6 x 6 form it replaced, on random 3-D trees of every joint kind."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.recursive import articulated, lagrange_accelerations, tree_evaluation, tree_pass
from mbcomp.codegen import compile_system
from mbcomp.library import (FixedTranslation, FreeMotion, Prismatic, Revolute, RigidBody, Spherical, Universal,
                            World)


def random_tree(seed, n_bodies, free_base):
    """A random tree: each body hangs from a random earlier frame (the world or a body's
    offset frame) by a random joint; bodies with random mass, centre and inertia."""
    rng = np.random.default_rng(seed)
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0.0, -9.81, 0.0)))
    frames = [world.frame_b]
    kinds = ["ball", "hinge", "slider", "universal"]
    for k in range(n_bodies):
        m, (a, b, c) = rng.uniform(0.5, 2.0), rng.uniform(0.1, 1.0, 3)  # a box, turned at random
        R = np.linalg.qr(rng.standard_normal((3, 3)))[0]
        I = R @ np.diag(m / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])) @ R.T
        body = mdl.add(f"b{k}", RigidBody(m=m, r_cm=tuple(0.3 * rng.standard_normal(3)), I=(I + I.T) / 2))
        if k == 0 and free_base:
            joint = mdl.add("j0", FreeMotion())
        else:
            kind = kinds[rng.integers(len(kinds))]
            n = rng.standard_normal(3)
            n = tuple(n / np.linalg.norm(n))
            joint = mdl.add(f"j{k}", {"ball": lambda: Spherical(), "hinge": lambda: Revolute(n=n),
                                      "slider": lambda: Prismatic(n=n), "universal": lambda: Universal()}[kind]())
        mdl.connect(frames[rng.integers(len(frames))], joint.frame_a)
        mdl.connect(joint.frame_b, body.frame_a)
        tip = mdl.add(f"t{k}", FixedTranslation(r=tuple(0.5 * rng.standard_normal(3))))
        mdl.connect(joint.frame_b, tip.frame_a)
        frames.append(tip.frame_b)
    s = mbcomp.assemble(mdl)
    q = s.normalize(s.default_q() + 0.3 * rng.standard_normal(s.nq))
    return s, q, rng.standard_normal(s.nu)


def dense_aba(tp, nu):
    """The articulated-body algorithm in dense 6 x 6 products (the form before the structure
    was used): ``U = I^A S``, ``D^-1`` by numpy, ``I^A_p += I^A - U D^-1 U^T``."""
    links, S = tp.links, tp.S
    IA, U, Dinv = list(tp.I), [None] * links.n, [None] * links.n
    for i in range(links.n - 1, -1, -1):
        U[i] = IA[i] @ S[i]
        Dinv[i] = np.linalg.inv(S[i].T @ U[i])
        if links.parent[i] >= 0:
            IA[links.parent[i]] = IA[links.parent[i]] + IA[i] - U[i] @ Dinv[i] @ U[i].T
    pA, tau = [-w for w in tp.W], [None] * links.n
    for i in range(links.n - 1, -1, -1):
        tau[i] = -(S[i].T @ pA[i])
        if links.parent[i] >= 0:
            pA[links.parent[i]] = pA[links.parent[i]] + pA[i] + U[i] @ (Dinv[i] @ tau[i])
    acc, x = [None] * links.n, np.zeros(nu)
    for i in range(links.n):
        p = links.parent[i]
        ap = acc[p] if p >= 0 else np.zeros(6)
        xi = Dinv[i] @ (tau[i] - U[i].T @ ap)
        acc[i] = ap + S[i] @ xi
        x[links.cols[i]] = xi
    return x


CASES = [(seed, n, free) for seed, n, free in ((1, 6, False), (2, 9, True), (3, 12, False), (4, 15, True), (5, 20, True))]


@pytest.mark.parametrize("seed, n, free", CASES)
def test_structured_aba_is_the_dense_aba(seed, n, free):
    """On random 3-D trees (ball, hinge, slider and universal joints, a free base or not) the
    structured ABA gives the dense 6 x 6 ABA's du/dt to 1e-12 (relative), and both solve
    CRBA's ``M du/dt = f``."""
    s, q, u = random_tree(seed, n, free)
    tp = tree_pass(s, 0.2, q, u)
    ref = dense_aba(tp, s.nu)
    ud = lagrange_accelerations(s, 0.2, q, u)
    scale = np.abs(ref).max()
    assert np.abs(ud - ref).max() <= 1e-12 * scale
    ev = tree_evaluation(s, 0.2, q, u)
    assert np.abs(ev.M @ ud - ev.f).max() <= 1e-10 * (np.abs(ev.M).max() * scale + np.abs(ev.f).max())


def test_ball_joints_are_recognized_and_inertias_stay_symmetric():
    """Ball joints (and only joints whose twist at their centre has no linear part) take the
    multiplication at their centre; the articulated inertias handed to parents are exactly
    symmetric (one triangle computed and mirrored)."""
    s, q, u = random_tree(7, 12, True)
    tp = tree_pass(s, 0.0, q, u)
    for i, e in enumerate(tp.links.edges):
        assert (tp.Jw[i] is not None) == isinstance(e.comp, Spherical), e.name
    U, pivots = articulated(tp)
    for i, P in enumerate(pivots):
        if tp.links.parent[i] >= 0:
            X = P.passed(U[i])
            assert np.array_equal(X, X.T)


def test_the_ball_chain_program_takes_fewer_operations():
    """The Lagrange program of the 10-link ball chain: 8,023 operations (11,002 with the dense
    6 x 6 products), verified against the numeric path when it is built."""
    from conftest import load_model

    s = mbcomp.assemble(load_model("models/chain_3d.py").build(N=10))
    c = compile_system(s, "python")
    c.evaluator.capabilities
    assert c.stats["n_ops_fun"] <= 8100, c.stats["n_ops_fun"]


@pytest.mark.parametrize("r_cm", [(0.0, 0.0, 0.0), (0.0, -0.5, 0.0)])
def test_a_ball_joint_moving_no_inertia_about_an_axis_is_singular(r_cm):
    """A ball joint carrying a point mass (at its centre, or on a massless rod: no inertia
    about the rod's line) cannot be solved: the recursion raises SingularTree (the callers'
    dense solve then gives the diagnosis), as the dense pivot ``S^T I^A S`` did."""
    from mbcomp.assembly.recursive import SingularTree

    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0.0, -9.81, 0.0)))
    ball = mdl.add("ball", Spherical())
    bob = mdl.add("bob", RigidBody(m=1.0, r_cm=r_cm, I=np.zeros((3, 3))))
    mdl.connect(world.frame_b, ball.frame_a)
    mdl.connect(ball.frame_b, bob.frame_a)
    s = mbcomp.assemble(mdl)
    q, u = s.default_q(), np.array([0.1, 0.2, 0.3])
    with pytest.raises(SingularTree):
        lagrange_accelerations(s, 0.0, q, u)
    tp = tree_pass(s, 0.0, q, u)
    with pytest.raises(np.linalg.LinAlgError):
        dense_aba(tp, s.nu)
