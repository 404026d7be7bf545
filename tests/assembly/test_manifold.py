"""The constraint manifold (mbcomp.assembly.manifold) on mechanisms with closed-form answers.

* slider-crank (models/slider_crank.py, crank a = 0.2 m, rod b = 0.6 m, slider on the
  crank pivot's x axis): the slider sits at ``s = a cos(phi) +- sqrt(b^2 - a^2 sin^2(phi))``
  (two assembly modes) and moves at ``ds/dt = ds/dphi w``;
* four-bar (models/four_bar.py) at its change point: with ``gap = 0`` all links are
  collinear at ``phi = pi`` and the loop-closure Jacobian loses rank; ``gap > 0`` keeps it.
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.manifold import (ACCEPT_FACTOR, POSITION_TOL, SingularPartition, close_positions, pivot_partition,
                                      rank, solve_speeds)

SLIDER_CRANK = load_model("models/slider_crank.py")
FOUR_BAR = load_model("models/four_bar.py")
A_CRANK, B_ROD = 0.2, 0.6  # slider_crank.build() defaults (m)


def slider_positions(phi):
    """Both assembly modes' slider positions (m) at crank angle ``phi``."""
    root = np.sqrt(B_ROD ** 2 - (A_CRANK * np.sin(phi)) ** 2)
    return A_CRANK * np.cos(phi) + root, A_CRANK * np.cos(phi) - root


def slider_speed(phi, w):
    """ds/dt (m/s) of the slider in the mode ``s > 0`` at crank angle ``phi`` and rate ``w``."""
    root = np.sqrt(B_ROD ** 2 - (A_CRANK * np.sin(phi)) ** 2)
    return (-A_CRANK * np.sin(phi) - A_CRANK ** 2 * np.sin(phi) * np.cos(phi) / root) * w


def positions_residual(system, t=0.0):
    zero = np.zeros(system.nu)

    def residual(q):
        ev = system.evaluate(t, q, zero)
        return ev.Phi, ev.C, ev

    return residual


@pytest.fixture(scope="module")
def slider_crank():
    system = mbcomp.assemble(SLIDER_CRANK.build())
    init = initialize(system)  # sets the independent rows (the loop is planar, the joints 3-D)
    assert system.q_names == ["crank_joint.phi", "slider_joint.s", "pin.phi"]
    return system, init


def test_closed_positions_lie_on_the_loop_and_keep_the_held_crank(slider_crank):
    """From a state perturbed in every coordinate, closure along slider and pin only: the loop
    closes to POSITION_TOL, the crank angle (held) does not move by one bit, and the slider is
    where the closed form puts it."""
    system, init = slider_crank
    q = init.q + np.array([0.4, 0.05, -0.1])
    c = close_positions(positions_residual(system), system.increment, q, columns=np.array([1, 2]))
    assert c.converged and c.norm <= POSITION_TOL
    assert np.linalg.norm(system.evaluate(0.0, c.q, np.zeros(3)).Phi) <= POSITION_TOL
    assert c.q[0] == q[0]
    assert c.q[1] == pytest.approx(slider_positions(q[0])[0], abs=1e-12)
    assert 1 <= c.iterations <= 6  # Newton: quadratic from a 0.1 perturbation


def test_exact_closure_reaches_rounding_and_stops_there():
    """exact=True closes the hanging four-bar's loop to rounding (the linearization divides by
    h ~ 1e-4) and stops at the residual's rounding floor, although on its angles (1-3 rad)
    rounding-sized steps rarely drop below EXACT_STEP: it does not run all max_iter steps.
    The perturbations are the linearization's (coupler angle moved, crank and pin closing)."""
    system = mbcomp.assemble(FOUR_BAR.build(w0=0.0))
    init = initialize(system)
    dep, ind = pivot_partition(system.evaluate(0.0, init.q, init.u).C, columns=[0, 2])
    assert dep.tolist() == [0, 2] and ind.size == 0
    for h in (5e-5, -5e-5, 1e-4, -1e-4, 1e-3):
        q = init.q + np.array([0.0, h, 0.0])
        c = close_positions(positions_residual(system), system.increment, q, columns=dep, max_iter=30, exact=True)
        assert c.converged and c.norm <= 1e-15
        assert c.iterations < 8, (h, c.iterations)
        assert c.q[1] == q[1]


def test_solve_speeds_is_exact_and_leaves_the_independent_speed(slider_crank):
    """The dependent speeds from one solve satisfy the velocity rows to rounding; the crank
    rate (independent) is unchanged; the slider speed equals d/dt of the closed form."""
    system, init = slider_crank
    phi, w = init.q[0], 6.0
    u = np.array([w, 3.0, -7.0])  # dependent speeds wrong on purpose
    ev = system.evaluate(0.0, init.q, u)
    res = np.concatenate((ev.Phid, ev.Psi))
    assert np.abs(res).max() > 1.0
    for minimum_norm in (False, True):  # a nonsingular square block: both answers agree
        un = solve_speeds(ev.A, res, u, np.array([1, 2]), minimum_norm=minimum_norm)
        assert un[0] == w
        assert un[1] == pytest.approx(slider_speed(phi, w), abs=1e-12)
        evn = system.evaluate(0.0, init.q, un)
        assert np.abs(np.concatenate((evn.Phid, evn.Psi))).max() <= 1e-13
    assert init.u[1] == pytest.approx(slider_speed(phi, w), abs=1e-12)  # initialization agrees


def test_minimum_norm_does_not_hide_over_specified_rows():
    """Two velocity rows equal to 1e-15 that disagree (fixed start speeds over-specify): a
    plain solve of the nearly singular block answers with speeds of 1e15 that satisfy both
    rows, so initialization's residual test (scaled by |u|) would pass; the minimum-norm
    answer stays O(1) and leaves the contradiction visible as a residual."""
    A = np.array([[1.0, 1.0], [1.0, 1.0 + 1e-15]])
    res = np.array([2.0, 3.0])
    plain = solve_speeds(A, res, np.zeros(2))
    assert np.abs(plain).max() > 1e14
    un = solve_speeds(A, res, np.zeros(2), minimum_norm=True)
    np.testing.assert_allclose(un, [-1.25, -1.25], rtol=1e-12)  # least squares of the two rows
    assert np.linalg.norm(A @ un + res) == pytest.approx(np.sqrt(0.5), rel=1e-12)
    consistent = solve_speeds(A, np.array([2.0, 2.0]), np.zeros(2), minimum_norm=True)
    np.testing.assert_allclose(consistent, [-1.0, -1.0], rtol=1e-12)  # the shortest exact correction


def test_pivot_partition_near_and_at_the_flat_four_bar():
    """At phi = pi a four-bar 1e-3 m (and 1e-8 m) from flat still has a nonsingular dependent
    block for coupler and pin; the flat change-point linkage has none."""
    for gap in (1e-3, 1e-8):
        system = mbcomp.assemble(FOUR_BAR.build(gap=gap, phi0=np.pi, w0=0.0))
        init = initialize(system)
        C = system.evaluate(0.0, init.q, init.u).C
        assert C.shape == (2, 3) and rank(C) == 2
        dep, _ = pivot_partition(C, columns=[1, 2])
        assert dep.tolist() == [1, 2] and np.linalg.cond(C[:, dep]) < 1e6
    system = mbcomp.assemble(FOUR_BAR.build(gap=0.0, phi0=np.pi, w0=0.0))
    init = initialize(system)
    C = system.evaluate(0.0, init.q, init.u, masked=False).C
    assert rank(C) == 1  # the closure equation along the links has a zero row
    assert init.dropped[0] == "rocker_joint.x"  # so initialization drops it with the 3 out-of-plane rows
    with pytest.raises(SingularPartition, match="lost rank"):
        pivot_partition(C[:2], columns=[1, 2])


def test_rank_counts_the_redundant_out_of_plane_rows():
    """A planar loop closed by a 3-D revolute has 5 rows of rank 2: the three out-of-plane
    rows are redundant, and the pivoted QR of C^T (tol=0, the rank known) keeps in-plane ones."""
    system = mbcomp.assemble(FOUR_BAR.build())
    init = initialize(system)
    C = system.evaluate(0.0, init.q, init.u, masked=False).C
    names = system.constraint_names(all_rows=True)
    assert C.shape == (5, 3) and rank(C) == 2 == init.rank
    keep, drop = pivot_partition(C.T, 2, tol=0)
    assert [names[i] for i in keep] == ["rocker_joint.x", "rocker_joint.y"]
    assert [names[i] for i in drop] == init.dropped


def test_line_search_converges_where_newton_diverges():
    """atan(x) = 0 from x = 2: plain Newton overshoots ever further (|x| grows like x^2) and the
    residual climbs to pi/2; halving the steps converges to the root."""
    def residual(x):
        return np.array([np.arctan(x[0])]), np.array([[1.0 / (1.0 + x[0] ** 2)]]), None

    def increment(x, dx):
        return x + dx

    plain = close_positions(residual, increment, np.array([2.0]), max_iter=6)
    assert not plain.converged and abs(plain.q[0]) > 1e10 and plain.norm > np.arctan(2.0)
    damped = close_positions(residual, increment, np.array([2.0]), max_iter=20, line_search=True)
    assert damped.converged and abs(damped.q[0]) <= POSITION_TOL


@pytest.mark.parametrize("start", [(4.97, -1.2), (3.0, 2.0), (-2.0, 3.0), (10.0, 1.0), (0.0, 0.0)])
def test_line_search_never_increases_the_residual_from_far_guesses(slider_crank, start):
    """Slider and pin guessed metres and radians off: with the line search the residual after
    k steps never exceeds that after k - 1, and the closure ends in one of the two assembly
    modes (crank held)."""
    system, init = slider_crank
    q0 = np.array([init.q[0], *start])
    residual = positions_residual(system)
    norms = [close_positions(residual, system.increment, q0, columns=np.array([1, 2]), max_iter=k,
                             line_search=True).norm for k in range(13)]
    assert all(b <= a for a, b in zip(norms, norms[1:])), norms
    c = close_positions(residual, system.increment, q0, columns=np.array([1, 2]), max_iter=60, line_search=True)
    assert c.converged and c.acceptable and c.norm <= POSITION_TOL < ACCEPT_FACTOR * POSITION_TOL
    assert min(abs(c.q[1] - s) for s in slider_positions(q0[0])) <= 1e-12
