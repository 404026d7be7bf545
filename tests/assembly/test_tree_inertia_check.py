"""A system without constraint rows checks its inertia from one recursive pass
(``check_tree_inertia``: the composite-rigid-body mass matrix and the moving scale from the
links' motion subspaces) instead of the dense evaluation: the same matrix to rounding and the
same decisions -- nothing massless, a massless direction named by the same coordinate, an
ill-conditioned ratio -- as ``check_inertia`` on the dense evaluation."""
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.conditioning import check_inertia, check_tree_inertia, moving_scale, tree_moving_scale
from mbcomp.assembly.initialization import TREE_CHECK_SPEEDS, initialize
from mbcomp.assembly.recursive import mass_matrix, tree_pass
from mbcomp.errors import InitializationError
from mbcomp.library import FixedTranslation, PointMass, Revolute, RigidBody, Spherical, World


def chain(n, end=None, seed=0):
    """``n`` links on hinges with tilted axes (a 3-D chain) and, at its end, ``end``: None,
    ``"massless"`` (a point mass on the last hinge's axis: that rotation carries nothing) or
    ``"light"`` (a 1 g body on a ball joint: finite, extreme)."""
    rng = np.random.default_rng(seed)
    m = mbcomp.Model()
    prev = m.add("world", World(g=(0, -9.81, 0))).frame_b
    for k in range(n):
        axis = np.array([0.2 * rng.standard_normal(), 0.2 * rng.standard_normal(), 1.0])
        j = m.add(f"j{k}", Revolute(n=tuple(axis), phi0=0.3 * rng.standard_normal()))
        b = m.add(f"b{k}", RigidBody(m=1.0 + rng.random(), r_cm=(0.25, 0.02, 0.0), I=np.diag([0.01, 0.02, 0.025])))
        rod = m.add(f"rod{k}", FixedTranslation(r=(0.5, 0.0, 0.05)))
        m.connect(prev, j.frame_a)
        m.connect(j.frame_b, b.frame_a)
        m.connect(b.frame_a, rod.frame_a)
        prev = rod.frame_b
    if end == "massless":
        j = m.add("tip_joint", Revolute(n=(1, 0, 0)))
        p = m.add("tip", PointMass(m=0.3))
        m.connect(prev, j.frame_a)
        m.connect(j.frame_b, p.frame_a)
    elif end == "light":
        j = m.add("tip_joint", Spherical())
        b = m.add("tip", RigidBody(m=1e-3, r_cm=(0.01, 0, 0), I=np.diag([1e-7, 1e-7, 1e-7])))
        m.connect(prev, j.frame_a)
        m.connect(j.frame_b, b.frame_a)
    return mbcomp.assemble(m)


def start(s):
    rng = np.random.default_rng(3)
    return s.normalize(s.default_q()), 0.2 * rng.standard_normal(s.nu)


@pytest.mark.parametrize("n", [3, 25])
def test_the_tree_mass_matrix_and_scale_are_the_dense_ones(n):
    s = chain(n)
    q, u = start(s)
    ev = s.evaluate_numeric(0.0, q, u, masked=False)
    tp = tree_pass(s, 0.0, q, u, forces=False)
    M = mass_matrix(tp, s.nu)
    np.testing.assert_allclose(M, ev.M, rtol=0, atol=1e-13 * np.abs(ev.M).max())
    assert tree_moving_scale(s, tp) == pytest.approx(moving_scale(s, ev.jets), rel=1e-12)


def test_a_well_conditioned_chain_passes_both_ways():
    s = chain(TREE_CHECK_SPEEDS + 2)
    q, u = start(s)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_tree_inertia(s, 0.0, q, u) == [] == check_inertia(s, s.evaluate_numeric(0.0, q, u, False))


def test_a_massless_rotation_is_refused_naming_the_same_coordinate_both_ways():
    s = chain(TREE_CHECK_SPEEDS + 2, end="massless")
    q, u = start(s)
    with pytest.raises(InitializationError) as dense:
        check_inertia(s, s.evaluate_numeric(0.0, q, u, False))
    with pytest.raises(InitializationError) as tree:
        check_tree_inertia(s, 0.0, q, u)
    assert "tip_joint" in str(tree.value) and str(tree.value) == str(dense.value)
    with pytest.raises(InitializationError, match="tip_joint"):  # and initialization takes the tree's way
        initialize(s)


def test_an_ill_conditioned_chain_warns_with_the_same_ratio_both_ways():
    s = chain(TREE_CHECK_SPEEDS + 2, end="light")
    q, u = start(s)
    with pytest.warns(RuntimeWarning, match="ill-conditioned") as dense:
        check_inertia(s, s.evaluate_numeric(0.0, q, u, False))
    with pytest.warns(RuntimeWarning, match="ill-conditioned") as tree:
        notes = check_tree_inertia(s, 0.0, q, u)

    def ratio(w):
        return float(str(w[0].message).split("smallest eigenvalue is ")[1].split(" ")[0])

    assert len(notes) == 1 and ratio(tree) == pytest.approx(ratio(dense), rel=1e-2)


def test_a_rowless_start_is_the_dense_start():
    """Initialization of a tree by either way: the same start, no rows, no iterations."""
    s = chain(TREE_CHECK_SPEEDS + 2)
    init = initialize(s)
    assert init.start is None and init.row_mask.shape == (0,) and init.iterations == 0
    small = chain(3)
    ref = initialize(small)
    assert ref.start is not None  # the small system's evaluation is kept for the alarm
    res = mbcomp.simulate(s, t_end=0.2)
    assert res.status == "success"
    np.testing.assert_array_equal(res.stats["init_iterations"], 0)
    q0 = np.array([res[n][0] for n in s.q_names])
    np.testing.assert_array_equal(q0, init.q)


def test_the_tolerance_energy_of_a_large_system_by_the_recursive_pass_is_the_dense_ones(monkeypatch):
    """Without the output program's terms a system of >= RECURSIVE_SPEEDS speeds weighs the
    tolerances with f and M u from the recursive pass: the same energy, to rounding, as from
    the dense evaluation (taken where the start's evaluation is handed in)."""
    from mbcomp.simulation.accuracy import RECURSIVE_SPEEDS, tolerance_energy

    s = chain(RECURSIVE_SPEEDS + 5)
    q, u = start(s)
    Y = np.array([np.concatenate((q, u)), np.concatenate((q + 0.01, 1.3 * u))])
    t = np.array([0.0, 0.1])

    def no_dense(*args, **kw):
        raise AssertionError("the dense evaluation was asked for")

    with monkeypatch.context() as mp:  # (tolerance_energy skips a point it cannot evaluate: 0 then)
        mp.setattr(s, "evaluate", no_dense)
        by_pass = tolerance_energy(s, t, Y, 1e-6, 1e-8)
    dense = max(tolerance_energy(s, t[k:k + 1], Y[k:k + 1], 1e-6, 1e-8, known=s.evaluate_numeric(t[k], Y[k, :s.nq],
                                                                                                 Y[k, s.nq:]))
                for k in range(2))
    assert by_pass > 0.0 and by_pass == pytest.approx(dense, rel=1e-12)
