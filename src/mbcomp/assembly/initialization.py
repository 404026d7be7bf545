"""Consistent initialization: positions, then velocities, on the constraint manifold.

Start values the user gave as plain numbers are *fixed*; values wrapped in
:class:`~mbcomp.Guess` (and unset values, guess 0) are free. Positions are corrected by
Gauss-Newton steps of minimum norm in the free directions, with a line search (the guesses
may be far off), until the loop-closure constraints hold
(:func:`~mbcomp.assembly.manifold.close_positions`); then the free speeds are corrected so
that the velocity constraints hold (:func:`~mbcomp.assembly.manifold.solve_speeds`). At the
assembled configuration a rank test finds redundant constraint rows (a planar loop written
with 3-D joints), which are dropped and reported.

The Newton's iterates read the constraint rows alone
(:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_rows`: no mass matrix, forces or
velocity rows); the full evaluation is made once, at the closed configuration, from the last
rows' jets (:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_from`), masked when rows
were dropped: bit for bit what a full evaluation at every iterate gave
(``tests/assembly/test_initialization_rows.py``), with one to two full evaluations instead of
one per iterate plus one or two (CPU: Andrews' squeezer 1.7 -> 1.0 ms, a slider-crank start
from guesses in ``mbcomp.batch`` 2.3 -> 1.8 ms).

Tolerances, each with its reason
--------------------------------
``tol = 1e-12`` (:data:`~mbcomp.assembly.manifold.POSITION_TOL`)
    The positions' Newton stops at ``||Phi|| <= tol``.
``NOT_CLOSED = 1e-8``
    A closure residual above it after the Newton steps means the loop cannot be assembled
    (and a constraint row's residual above it names that row's joint). It is looser than the
    manifold's acceptance ``ACCEPT_FACTOR * tol`` (1e-9) and kept so: no model of the project
    ends between the two (all close below 1e-12, four-bars started 1 rad off at their flat
    position too, converging linearly), but a user's start whose line search stalls there has
    always been accepted, and 1e-9 would make it an error.
``VELOCITY_TOL = 1e-12``
    Velocity-constraint residual below which the start speeds are taken as they are (no
    solve, so fixed and guessed speeds keep their exact values).

Examples
--------
A slider-crank: the crank angle is fixed, the rod angle and slider position are guesses;
initialization closes the loop and solves the free speeds.

>>> import mbcomp, numpy as np
>>> from mbcomp.assembly.initialization import initialize
>>> from mbcomp.library import World, Revolute, Prismatic, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> crank = m.add("crank", Revolute(n=(0, 0, 1), phi0=0.5, w0=2.0))
>>> a = m.add("a", FixedTranslation(r=(0.2, 0, 0))); pa = m.add("pa", PointMass(m=1.0))
>>> rod = m.add("rod", Revolute(n=(0, 0, 1), phi0=mbcomp.Guess(-0.3)))
>>> b = m.add("b", FixedTranslation(r=(0.6, 0, 0))); pb = m.add("pb", PointMass(m=1.0))
>>> slide = m.add("slide", Prismatic(n=(1, 0, 0), s0=mbcomp.Guess(0.7)))
>>> pin = m.add("pin", Revolute(n=(0, 0, 1)))
>>> m.connect(w.frame_b, crank.frame_a); m.connect(crank.frame_b, a.frame_a); m.connect(a.frame_b, pa.frame_a)
>>> m.connect(a.frame_b, rod.frame_a); m.connect(rod.frame_b, b.frame_a); m.connect(b.frame_b, pb.frame_a)
>>> m.connect(w.frame_b, slide.frame_a); m.connect(slide.frame_b, pin.frame_a); m.connect(pin.frame_b, b.frame_b)
>>> s = mbcomp.assemble(m); init = initialize(s)
>>> sin_rod = -0.2 * np.sin(0.5) / 0.6          # the rod end stays on the slider's line y = 0
>>> bool(abs(np.sin(0.5 + init.q[1]) - sin_rod) < 1e-12), float(init.q[0]), float(init.u[0])
(True, 0.5, 2.0)
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InitializationError, Problem
from .conditioning import check_inertia, check_tree_inertia
from .manifold import POSITION_TOL, close_positions, pivot_partition, rank, solve_speeds

__all__ = ["initialize", "InitialState", "NOT_CLOSED", "VELOCITY_TOL", "fixed_starts"]

NOT_CLOSED = 1e-8
VELOCITY_TOL = 1e-12
#: a system without constraint rows of at least this many speeds checks its inertia from one
#: pass of the recursive algorithms (:func:`~mbcomp.assembly.conditioning.check_tree_inertia`,
#: no dense evaluation: 0.6 -> 0.25 s at 1000 links, 9.5 -> 7.6 ms at 100); a smaller one
#: evaluates as a system with rows does (as fast there, and the evaluation is kept for the
#: accuracy alarm: :attr:`InitialState.start`)
TREE_CHECK_SPEEDS = 20


@dataclass
class InitialState:
    """Consistent start: coordinates ``q``, speeds ``u``, and what initialization decided."""

    q: np.ndarray
    u: np.ndarray
    row_mask: np.ndarray
    dropped: list = field(default_factory=list)  # names of redundant constraint rows
    iterations: int = 0
    rank: int = 0  # rank of the holonomic constraint Jacobian
    nonholonomic: int = 0  # number of velocity-level constraint rows
    notes: list = field(default_factory=list)  # warnings for the run (an ill-conditioned mass matrix)
    #: ``(system, Evaluation)``: the evaluation at the start ``(t0, q, u)`` and the system it is
    #: of, for later users at the same state (the accuracy alarm's tolerance energy)
    start: tuple = field(default=None, repr=False, compare=False)
    #: ``(system, Rows)``: every position row and its Jacobian at ``(t0, q)``, the closure's last
    #: (``Phi`` and ``C`` depend on the time and the coordinates alone), for the rank monitor
    rows: tuple = field(default=None, repr=False, compare=False)


def _starts(system):
    q = np.zeros(system.nq)
    u = np.zeros(system.nu)
    qfix = np.zeros(system.nu, bool)
    ufix = np.zeros(system.nu, bool)
    cut_fixed = []  # (edge, value q, fixed, value u, fixed) on 1-DOF cut joints
    for e in system.topology.edges:
        if e.kind != "joint" or e.dof == 0 or e.drive:
            continue
        q0, qf, u0, uf = e.comp.start(system.P[e.name])
        if e.q.stop > e.q.start:
            q[e.q], u[e.u], qfix[e.u], ufix[e.u] = q0, u0, qf, uf
        elif e.name in system.topology.cut and (np.any(qf) or np.any(uf)):
            cut_fixed.append((e, q0, qf, u0, uf))
    return q, u, qfix, ufix, cut_fixed


def fixed_starts(system):
    """Which start values ``system``'s initialization keeps: ``(qfix, ufix, cut)``, per speed
    direction whether its position (``qfix``) and its speed (``ufix``) are fixed start values
    (a value given, not a :class:`~mbcomp.Guess`), and the cut joints with fixed ones (they have
    no coordinates of their own: initialization measures them on their rows).

    Examples
    --------
    >>> import pathlib, mbcomp
    >>> root = pathlib.Path(mbcomp.__file__).resolve().parents[2]
    >>> crank = mbcomp.load_model_file(root / "models" / "slider_crank.py")
    >>> qfix, ufix, cut = fixed_starts(mbcomp.assemble(crank.build()))
    >>> qfix.tolist(), ufix.tolist(), cut
    ([True, False, False], [True, False, False], [])
    """
    _, _, qfix, ufix, cut_fixed = _starts(system)
    return qfix, ufix, [e.name for e, *_ in cut_fixed]


def _position_names(system):
    """For each speed index, the name of the position coordinate it moves.

    Joints whose coordinates and speeds pair one to one (hinges, sliders) give the
    coordinate name (``crank_joint.phi``); joints with a quaternion (spherical, free
    motion) give ``"<joint> (start position/orientation)"``.
    """
    names = [""] * system.nu
    for e in system.topology.tree:
        if e.kind != "joint" or e.drive or e.dof == 0:
            continue
        c = e.comp
        qn = [f"{e.name}.{n}" for n, _ in c.coordinates]
        un = range(e.u.start, e.u.stop)
        if c.nq == c.nu:
            for i, n in zip(un, qn):
                names[i] = n
        else:
            for i in un:
                names[i] = f"{e.name} (start position/orientation)"
    return names


def _measure_rows(system, t, q, u, cut_fixed, which):
    """Residuals and Jacobian rows (finite differences on the speeds) for start values fixed
    on cut joints (1-DOF joints only)."""
    res, rows, names = [], [], []
    for e, q0, qf, u0, uf in cut_fixed:
        if e.dof != 1:
            raise InitializationError([Problem(e.name, "start values are fixed on a multi-DOF joint that closes a loop",
                                               "fix start values on tree joints instead, or mark these as Guess(...)")])
        flags, target = (qf, q0) if which == "q" else (uf, u0)
        if not np.any(flags):
            continue

        def meas(qq, uu):
            jets = system.kinematics(t, qq, uu)
            return np.array(e.comp.measure(jets[e.node_a], jets[e.node_b], system.P[e.name]))

        m0 = meas(q, u)
        k = 0 if which == "q" else 1
        res.append(m0[k] - target[0])
        row = np.zeros(system.nu)
        h = 1e-7
        for i in range(system.nu):
            du = np.zeros(system.nu)
            du[i] = h
            if which == "q":
                row[i] = (meas(system.increment(q, du), u)[0] - meas(system.increment(q, -du), u)[0]) / (2 * h)
            else:
                row[i] = (meas(q, u + du)[1] - meas(q, u - du)[1]) / (2 * h)
        rows.append(row)
        names.append(f"{e.name}.{e.comp.coordinates[0][0] if which == 'q' else e.comp.speeds[0][0]}")
    return np.array(res), np.array(rows).reshape(len(rows), system.nu), names


def initialize(system, t0=0.0, tol=POSITION_TOL, max_iter=60):
    """Consistent ``(q, u)`` honouring fixed start values; sets ``system.row_mask``.

    Parameters
    ----------
    system : MultibodySystem
    t0 : float
        Start time, s (prescribed motions).
    tol : float
        Position-constraint residual at which the Newton closure stops (m, rad).
    max_iter : int
        Newton steps at most.

    Returns
    -------
    InitialState

    Raises
    ------
    InitializationError
        When fixed start values over-specify the mechanism (naming the coordinates and cut
        joints involved) or when a loop cannot be closed (naming the cut joints).
    """
    system.row_mask = None
    q, u, qfix, ufix, cut_fixed = _starts(system)
    q = system.normalize(q)
    if system.nu >= TREE_CHECK_SPEEDS and _rowless(system):  # nothing to close, the inertia from one pass
        system.row_mask = np.ones(0, bool)
        return InitialState(q, u, system.row_mask, notes=check_tree_inertia(system, t0, q, u))
    closure = _close_positions(system, t0, q, u, cut_fixed, ~qfix, tol, max_iter)
    mask, dropped = _independent_rows(system, closure.data.C)
    if closure.r.size and closure.norm > NOT_CLOSED:
        def closes_when_free():
            return _close_positions(system, t0, q, u, cut_fixed, None, tol, max_iter).norm <= NOT_CLOSED

        raise _not_closed(system, closure, qfix, cut_fixed, closes_when_free)
    system.row_mask = mask
    # every row kept and the system's own evaluator (numeric or program, wrapping nothing): the
    # unmasked evaluation at the closure's end (closure.q, u) is the masked one (a hybrid mode's
    # wrapper adds held rows or friction to masked evaluations only); either is made from the
    # closure's last rows (Rows: the jets and rows, or the evaluation they came from)
    own = getattr(system.evaluator, "system", None) is system and getattr(system.evaluator, "inner", None) is None
    same = bool(mask.all()) and own
    u, ev = _close_speeds(system, t0, closure.q, u, ufix, cut_fixed, system.evaluate_from(closure.data, not same))
    notes = check_inertia(system, ev)
    return InitialState(closure.q, u, mask, dropped, closure.iterations, rank(ev.C), ev.B.shape[0], notes,
                        start=(system, ev), rows=(system, closure.data))


def _rowless(system):
    """Whether ``system`` holds no constraint rows at all: no cut joints or flange
    constraints, no nonholonomic rows, evaluated by its own evaluator (a hybrid mode's
    wrapper may add held rows)."""
    topo, ev = system.topology, system.evaluator
    return (not topo.cut and not topo.flange_rows and not system.nonholonomic
            and getattr(ev, "system", None) is system and getattr(ev, "inner", None) is None)


def _close_positions(system, t0, q, u, cut_fixed, free, tol, max_iter):
    """Gauss-Newton with line search on ``[Phi; fixed cut-joint coordinates] = 0``, moving the
    ``free`` directions (all if ``None``); the closure's ``data`` is the unmasked rows
    (:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_rows`: no mass matrix and forces
    at the Newton's iterates; ``system.evaluate_from`` makes the evaluation at its end)."""

    def residual(qq):
        rows = system.evaluate_rows(t0, qq, u)
        r2, C2, _ = _measure_rows(system, t0, qq, u, cut_fixed, "q")
        return np.concatenate((rows.Phi, r2)), np.vstack((rows.C, C2)), rows

    return close_positions(residual, system.increment, q, columns=free, tol=tol, max_iter=max_iter,
                           line_search=True)


def _independent_rows(system, C):
    """Mask of independent rows of the position constraints ``C`` at the assembled
    configuration (pivoted QR of ``C^T`` keeps the best-conditioned ``rank(C)`` rows) and the
    names of the dropped ones."""
    n_phi = C.shape[0]
    mask = np.ones(n_phi, bool)
    rank_all = rank(C)
    if not n_phi or rank_all == n_phi:
        return mask, []
    keep, _ = pivot_partition(C.T, rank_all, tol=0)
    mask[:] = False
    mask[keep] = True
    row_names = system.constraint_names(all_rows=True)
    return mask, [row_names[i] for i in range(n_phi) if not mask[i]]


def _not_closed(system, closure, qfix, cut_fixed, closes_when_free):
    """The error for a loop that did not close: over-specified by fixed start values (if
    ``closes_when_free()``: it closes with all of them free), else not assemblable."""
    r, C, norm = closure.r, closure.J, closure.norm
    row_names = system.constraint_names(all_rows=True)
    n_phi = closure.data.Phi.size
    bad_rows = sorted({row_names[i].rsplit(".", 1)[0] for i in range(n_phi) if abs(r[i]) > NOT_CLOSED})
    pos_names = _position_names(system)
    fixed = list(dict.fromkeys(pos_names[i] for i in range(system.nu)
                               if qfix[i] and np.any(np.abs(C[:, i]) > 1e-12)))
    fixed += [f"{c[0].name}.{c[0].comp.coordinates[0][0]}" for c in cut_fixed if np.any(c[2])]
    if fixed and closes_when_free():
        return InitializationError([Problem(
            ", ".join(fixed),
            f"fixed start values over-specify the mechanism: with them the loop through "
            f"{', '.join(bad_rows) or 'the cut joints'} cannot close (residual {norm:.3g}), without them it can",
            "fix fewer start values: wrap the others in Guess(...), e.g. phi0=Guess(0.3)")])
    return InitializationError([Problem(
        ", ".join(bad_rows),
        f"the kinematic loop cannot be assembled (closure residual {norm:.3g} after {closure.iterations} Newton steps)",
        "check lengths and joint axes of the loop (can it close at all?) or give better Guess(...) start values")])


def _close_speeds(system, t0, q, u, ufix, cut_fixed, ev):
    """Free speeds corrected (minimum norm) so that ``[dPhi/dt; Psi; fixed cut-joint speeds]``
    vanish; returns ``(u, evaluation)``, or raises when fixed start speeds over-specify.
    ``ev``: the (masked) evaluation at ``(t0, q, u)``."""
    r2, C2, _ = _measure_rows(system, t0, q, u, cut_fixed, "u")
    Cv = np.vstack((ev.A, C2))
    rv = np.concatenate((ev.Phid, ev.Psi, r2))
    if not rv.size or np.linalg.norm(rv) <= VELOCITY_TOL:
        return u, ev
    if (~ufix).any():
        u = solve_speeds(Cv, rv, u, ~ufix, minimum_norm=True)
    ev = system.evaluate(t0, q, u)
    rv2 = np.concatenate((ev.Phid, ev.Psi, _measure_rows(system, t0, q, u, cut_fixed, "u")[0]))
    if np.linalg.norm(rv2) > 1e-8 * max(1.0, np.linalg.norm(u)):
        fixed = [system.u_names[i] for i in range(system.nu) if ufix[i] and np.any(np.abs(Cv[:, i]) > 1e-12)]
        raise InitializationError([Problem(
            ", ".join(fixed) or "start speeds",
            f"fixed start speeds over-specify the mechanism (velocity constraint residual {np.linalg.norm(rv2):.3g})",
            "fix fewer start speeds: wrap the others in Guess(...), e.g. w0=Guess(0.0)")])
    return u, ev
