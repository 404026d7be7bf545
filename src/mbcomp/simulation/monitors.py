"""Run monitors: what the formulations cannot see, checked at every accepted step.

A formulation integrates whatever its equations say; near a singular position they still
say something, only no longer the truth. The driver (:func:`mbcomp.simulate`) therefore
hands every accepted step to the monitors a model needs (:func:`monitors_for`), each of
which ends the run with a :class:`SingularPosition` naming the cause and the time:

:class:`RedundantRows`
    Rows dropped as redundant at the start (``system.row_mask``) must stay satisfied: a row
    dependent only at the start position (a four-bar started flat, a slider-crank started at
    a dead centre with a loop that closes there by coincidence) is a singular start, and the
    loop would otherwise open silently.
:class:`ConstraintRank`
    The smallest relative singular value ``sigma_min / sigma_max`` of the kept constraint
    Jacobian (``stats["min_constraint_sigma"]``: how close the run came to a singular
    position); below :attr:`ConstraintRank.SIGMA_MIN` the position is singular.
:class:`JointSingularities`
    Joints that know where their own equations break down (``Joint.singularity``: a rolling
    disk lying flat) report their distance from it; below
    :attr:`JointSingularities.JOINT_MIN` the run fails with the joint's reason and fix.

A solver may step *over* a singular position (BDF and fixed-step methods at a flat four-bar
did, then followed another branch). Both the rank and the joint monitors therefore keep the
step-end values of the last three steps in one :class:`StepWindow`; when the middle one is
a local minimum below the monitor's bracket, the window locates the minimum along the dense
output of the two steps around it.

Examples
--------
>>> import numpy as np
>>> from mbcomp.simulation.monitors import StepWindow
>>> w = StepWindow(bracket=1.0)
>>> line = lambda t: np.array([t, 1.0])          # dense output [q, u] of a step: q = t
>>> for t0, t1 in ((-2.0, -1.0), (-1.0, 0.5), (0.5, 2.0)):
...     w.push(t0, t1, {"dist": abs(t1)}, line)
>>> w.dips()
['dist']
>>> t, d = w.locate(lambda t, q, u: abs(q[0] - 0.2), nq=1, nu=1)
>>> round(t, 6), d < 1e-9
(0.2, True)
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..assembly.system import MultibodySystem
from ..errors import SimulationError
from ..formulations.passing import engine_of
from ..solvers.locate import minimum, time_tolerance

__all__ = ["relative_sigma", "evaluate_by_program", "SingularPosition", "StepEnd", "StepWindow", "RedundantRows",
           "ConstraintRank", "JointSingularities", "monitors_for"]


def relative_sigma(C, r=None):
    """``sigma_r / sigma_1`` of ``C`` (``r``: its number of rows by default): 1 for no rows,
    0 when its rank is below ``r``.

    Examples
    --------
    >>> C = np.array([[1.0, 0.0], [1.0, 1e-4], [0.0, 1.0]])   # rank 2; rows 0, 1 nearly dependent
    >>> round(relative_sigma(C[[0, 1]]), 6), round(relative_sigma(C[[0, 2]]), 6), relative_sigma(C, 3)
    (5e-05, 1.0, 0.0)
    """
    r = C.shape[0] if r is None else r
    if not r:
        return 1.0
    sv = np.linalg.svd(C, compute_uv=False)
    if not (sv.size and sv[0] > 0):
        return 0.0
    return float(sv[r - 1] / sv[0]) if sv.size >= r else 0.0


def evaluate_by_program(system):
    """Make ``system``'s lazy evaluator (:func:`mbcomp.codegen.compile_system` with ``lazy``, as
    ``simulate`` compiles) evaluate by its program from its next call on, not after its
    ``LAZY_EVALUATIONS`` (200) numeric evaluations: for a run whose monitors evaluate at every
    step (:class:`ConstraintRank` passing singular positions; the N-four-bar at N = 10 spent
    0.6 s of 1 s in those 200 evaluations). Any other evaluator is left as it is."""
    eager = getattr(system.evaluator, "evaluate_by_program", None)
    if eager is not None:
        eager()


class SingularPosition(SimulationError):
    """A monitor ended the run; results after ``t`` (s) are not valid (the position where the
    motion stopped being defined may lie inside a step whose outputs were already kept)."""

    def __init__(self, msg, t):
        super().__init__(msg)
        self.t = t


class StepEnd:
    """The state ``qu = [q, u]`` at the end of an accepted step, with its constraint rows
    (every row: ``Phi``, ``C``, ... of the unmasked evaluation bit for bit, without the mass
    matrix and forces where the evaluator can) computed once for every monitor that needs them."""

    def __init__(self, system, t, qu):
        self.system, self.t = system, t
        self.q, self.u = qu[: system.nq], qu[system.nq: system.nq + system.nu]

    @cached_property
    def rows(self):
        """:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_rows` at the step's end."""
        return self.system.evaluate_rows(self.t, self.q, self.u)


class StepWindow:
    """Step-end values of the last three accepted steps and the dense output of the last two.

    Parameters
    ----------
    bracket : float
        A local minimum of the step-end values below this is located along the dense output.
    """

    def __init__(self, bracket):
        self.bracket = bracket
        self._steps = []  # (t_start, t_end, {name: value at t_end}, dense [q, u])

    def push(self, t_prev, t, values, dense):
        """Add an accepted step from ``t_prev`` to ``t`` (s) with its step-end ``values``."""
        self._steps = (self._steps + [(t_prev, t, values, dense)])[-3:]

    def dips(self):
        """Names whose middle step-end value is a local minimum below :attr:`bracket`."""
        if len(self._steps) < 3:
            return []
        (_, _, v0, _), (_, _, v1, _), (_, _, v2, _) = self._steps
        return [n for n, v in v1.items() if v < v0.get(n, np.inf) and v < v2.get(n, np.inf) and v < self.bracket]

    def locate(self, value, nq, nu, normalize=None):
        """``(t, value)`` at the minimum of ``value(t, q, u)`` along the last two steps (bounded
        scalar search on the dense output, :func:`mbcomp.solvers.locate.minimum`; ``q``
        normalized by ``normalize`` if given)."""
        (a0, a1, _, da), (_, b1, _, db) = self._steps[-2:]

        def at(tt):
            qu = da(tt) if tt <= a1 else db(tt)
            q = qu[:nq] if normalize is None else normalize(qu[:nq])
            return value(tt, q, qu[nq: nq + nu])

        return minimum(at, a0, b1, tol=time_tolerance(b1))

    def state_at(self, t, nq, nu):
        """``[q, u]`` at ``t`` (s) inside the last two steps, from their dense output."""
        (_, a1, _, da), (_, _, _, db) = self._steps[-2:]
        return np.asarray((da if t <= a1 else db)(t))[: nq + nu]


class RedundantRows:
    """Rows dropped as redundant at the start stay satisfied (else: a singular start).

    Parameters
    ----------
    system : MultibodySystem
        Initialized (``row_mask`` set) with rows dropped.
    atol : float or array
        The run's absolute tolerance; a dropped row may be violated by ``1e-6 + 1e3 atol``.
    """

    def __init__(self, system, atol):
        self.system = system
        self.tol = 1e-6 + 1e3 * float(np.max(atol))

    def check(self, end, t_prev, dense):
        ev = end.rows
        if not ev.Phi.size:
            return
        dropped = ~self.system.row_mask  # the rows dropped now (RowChoice may have changed them)
        bad = np.abs(ev.Phi[dropped])
        # a dependent row is violated about as much as the kept ones (drift of an unstabilized
        # form: IDA at index 1); a row that was dependent only at the start, far more
        drift = float(np.max(np.abs(ev.Phi[~dropped]), initial=0.0))
        if bad.size and bad.max() > max(self.tol, 100.0 * drift):
            names = [n for n, d in zip(self.system.constraint_names(all_rows=True), dropped) if d]
            worst = names[int(np.argmax(bad))]
            raise SingularPosition(
                f"the constraint row {worst} was dropped at the start as redundant (dependent on the "
                f"others there) but is violated by {bad.max():.3g} at t={end.t:g}: the start position is "
                "singular (a flat or dead-centre position where the loop's rank drops) -> start the "
                "mechanism away from it (change the fixed start values)", end.t)

    def stats(self):
        return {}


class ConstraintRank:
    """The kept constraint Jacobian keeps its rank; tracks the closest approach.

    Parameters
    ----------
    system : MultibodySystem
        With loops (cut joints).
    singular : {"stop", "pass"}
    start : Rows, optional
        Every position row and its Jacobian at the start (initialization's,
        ``InitialState.rows``): the first step's start is looked at through them instead of
        evaluating it again (``C`` depends on the time and the coordinates alone).
    """

    BRACKET = 0.2  # a local minimum below this is located (steps of explicit methods cross a flat
    # position with step-end values ~0.1: a smaller bracket let passages go unseen)
    SIGMA_MIN = 1e-6  # a four-bar 1e-8 m from flat: 4e-5; passing exactly through flat: <= 1.6e-7

    #: share of a step over which the slope of ``sigma`` at its ends is taken (dense output)
    SLOPE_SPAN = 1e-3
    #: parts a step is cut into to look for minima of ``sigma`` inside it (a step of an
    #: explicit method at rtol 1e-3 spans 0.4 s, two flat positions of an N = 2 four-bar)
    PARTS = 3

    def __init__(self, system, singular="stop", start=None):
        self.system, self.singular, self._start = system, singular, start
        mask = system.row_mask
        self.rank = int(mask.sum()) if mask is not None else None  # None: every row
        self.sigma_min = 1.0
        self.window = StepWindow(self.BRACKET)
        self.passages = []
        self._end = None  # (t, sigma, slope of sigma) at the last step's end
        self._taken = 0  # minima of the C loop's log judged so far
        if singular == "pass":  # evaluated at every step and along the dense output at every passage
            evaluate_by_program(system)
        elif start is not None and self.sigma(start) < self.BRACKET:
            # the first step is looked into (_inside: its start is near flat by this measure), which
            # switches to the program: switched now, its end's rows come from the program too
            # instead of one more numeric evaluation (Andrews' squeezer: sigma 0.19 all along)
            evaluate_by_program(system)

    def _sigma_at(self, dense, t):
        """``sigma`` of the state the step's ``dense`` output gives at ``t`` (s)."""
        sysm = self.system
        qu = np.asarray(dense(t))
        q, u = sysm.normalize(qu[: sysm.nq]), qu[sysm.nq: sysm.nq + sysm.nu]
        ev = self._start
        if ev is None or not (ev.t == t and np.array_equal(ev.q, q)):
            ev = sysm.evaluate(t, q, u, masked=False)  # (at the start's coordinates: the same C)
        return self.sigma(ev)

    def _inside(self, t_prev, t, rel, dense):
        """``[(t, sigma)]``: the minima of ``sigma`` inside the step ``[t_prev, t]`` (s), located
        along its dense output -- a flat position crossed within one step, which the step-end
        values alone do not show. Only a step with an end below :data:`BRACKET` is looked into
        (a plain run pays nothing for it). ``sigma`` is sampled at :data:`PARTS` - 1 inner points, and
        its slopes at the step's ends (one-sided differences over :data:`SLOPE_SPAN` of the
        step) tell a minimum next to an end."""
        h = t - t_prev
        if not h > 0.0:
            return []
        first = self._end if self._end is not None and self._end[0] == t_prev else None
        s0 = first[1] if first else self._sigma_at(dense, t_prev)
        if min(s0, rel) >= self.BRACKET:  # both ends far from flat (sigma grows ~ linearly off it): nothing to see
            self._end = (t, rel, None)  # its slope is taken if the next step needs it
            return []
        evaluate_by_program(self.system)  # ~20 evaluations per step looked into, from now on: by the program
        dt = self.SLOPE_SPAN * h
        ts = np.linspace(t_prev, t, self.PARTS + 1)
        slope0 = first[2] if first and first[2] is not None else (self._sigma_at(dense, t_prev + dt) - s0) / dt
        v = [s0] + [self._sigma_at(dense, tt) for tt in ts[1:-1]] + [rel]
        slope1 = (rel - self._sigma_at(dense, t - dt)) / dt
        self._end = (t, rel, slope1)
        brackets = []
        for j in range(len(v)):
            before = v[j - 1] if j else v[0] - slope0 * (ts[1] - ts[0])  # the slope as a virtual neighbour
            after = v[j + 1] if j + 1 < len(v) else v[-1] + slope1 * (ts[-1] - ts[-2])
            if v[j] < before and v[j] < after and v[j] < self.BRACKET:
                brackets.append((ts[max(j - 1, 0)], ts[min(j + 1, len(v) - 1)]))
        out = []
        for a, b in brackets:
            tm, sm = minimum(lambda tt: self._sigma_at(dense, tt), a, b, tol=time_tolerance(b))
            if t_prev < tm < t:  # at an end it is the step window's (the three steps' ends)
                out.append((tm, sm))
        return out

    def _passed(self, ts, smin, qu):
        """Record (``"pass"``) or stop at (``"stop"``) a singular position at ``ts`` (s)."""
        sysm = self.system
        ev = sysm.evaluate(ts, sysm.normalize(qu[: sysm.nq]), qu[sysm.nq:], masked=False)
        if self.singular == "stop":
            raise self._singular(ts, smin, ev)
        if self.passages and abs(self.passages[-1]["t"] - ts) <= 1e-6 * max(1.0, abs(ts)):
            return  # the same passage, seen by the step window and inside a step
        drop, joints = self._dependent(ev)
        self.passages.append(dict(t=float(ts), sigma=float(smin), rank_drop=drop, joints=joints))

    def sigma(self, ev):
        """``sigma_r / sigma_1`` of the full ``ev.C``, ``r`` the number of kept rows (0: the
        rank is lost): which rows are kept is :class:`~mbcomp.simulation.rows.RowChoice`'s
        matter, a singular position is where no choice keeps the rank."""
        rank = self.rank
        if rank is not None and ev.C.shape[0] < self.system.row_mask.size:  # an open contact's rows are out
            rank = max(rank - (self.system.row_mask.size - ev.C.shape[0]), 0)
        return relative_sigma(ev.C, rank)

    def _singular(self, t, rel, ev):
        _, joints = self._dependent(ev)
        return SingularPosition(
            f"the mechanism reached a singular position at t={t:g}: the constraint Jacobian lost "
            f"rank (smallest relative singular value {rel:.2g}; rows of {', '.join(joints)} became dependent); "
            "beyond it the motion is not unique (a flat or dead-centre position) -> change the geometry or the "
            "start so it is avoided, or pass it with singular='pass'", t)

    def _dependent(self, ev):
        """``(rank drop, joints)``: how many rows of the full Jacobian ``ev.C`` became
        dependent and the joints of the rows in its left null space."""
        U, sv, _ = np.linalg.svd(ev.C)
        r = self.rank if self.rank is not None else ev.C.shape[0]
        small = sv[:r] < self.SIGMA_MIN * 10 * sv[0] if sv.size else np.zeros(0, bool)
        drop = max(1, int(small.sum()) + max(0, r - sv.size))
        weight = np.abs(U[:, r - drop: r]).max(axis=1) if sv.size else np.zeros(0)
        names = self.system.constraint_names(all_rows=True)
        return drop, list(dict.fromkeys(n.rsplit(".", 1)[0] for n, w in zip(names, weight) if w > 0.1 * weight.max()))

    def _located_in_c(self, t_prev, t):
        """Judge the minima the C loop located in ``(t_prev, t]`` (s) when it stepped there
        (:func:`mbcomp.formulations.passing.engine_of`): True, or False for a step on the
        Python path (the step window's and :meth:`_inside`'s location then)."""
        engine = engine_of(self.system) if self.singular == "pass" else None
        if engine is None or engine.reached < t:
            return False
        minima, sysm = engine.minima, self.system
        while self._taken < len(minima) and minima[self._taken][0] <= t:
            tm, ym = minima[self._taken]
            self._taken += 1
            q, u = sysm.normalize(ym[: sysm.nq]), ym[sysm.nq: sysm.nq + sysm.nu]
            sm = self.sigma(sysm.evaluate(tm, q, u, masked=False))
            self.sigma_min = min(self.sigma_min, sm)
            if sm < self.SIGMA_MIN and tm > t_prev:
                self._passed(tm, sm, ym[: sysm.nq + sysm.nu])
        self._end = None
        return True

    def check(self, end, t_prev, dense):
        rel = self.sigma(end.rows)
        self.sigma_min = min(self.sigma_min, rel)
        if self._located_in_c(t_prev, end.t):
            return
        sysm = self.system
        for ts, smin in self._inside(t_prev, end.t, rel, dense):  # flat positions crossed within this step
            self.sigma_min = min(self.sigma_min, smin)
            if smin < self.SIGMA_MIN:
                self._passed(ts, smin, np.asarray(dense(ts))[: sysm.nq + sysm.nu])
        if rel < self.SIGMA_MIN and self.singular == "stop":
            raise self._singular(end.t, rel, end.rows)
        self.window.push(t_prev, end.t, {"sigma": rel}, dense)
        if self.window.dips():
            ts, smin = self.window.locate(lambda tt, q, u: self.sigma(sysm.evaluate(tt, q, u, masked=False)),
                                          sysm.nq, sysm.nu, sysm.normalize)
            self.sigma_min = min(self.sigma_min, smin)
            if smin < self.SIGMA_MIN:
                self._passed(ts, smin, self.window.state_at(ts, sysm.nq, sysm.nu))

    def stats(self):
        out = {"min_constraint_sigma": self.sigma_min}
        if self.singular == "pass":
            out["singular_passages"] = list(self.passages)
            engine = engine_of(self.system)
            if engine is not None:  # the C loop's: range-space solves, projections left out, minima located
                out.update(engine.counts)
        return out


class JointSingularities:
    """Joints with a :meth:`~mbcomp.modeling.roles.Joint.singularity` stay away from it.

    Parameters
    ----------
    system : MultibodySystem
    edges : list
        The topology edges of those joints.
    """

    JOINT_MIN = 1e-3  # a joint's own distance from where its equations break down (a flat disk)
    JOINT_BRACKET = 0.1

    def __init__(self, system, edges):
        self.system, self.edges = system, edges
        self.window = StepWindow(self.JOINT_BRACKET)

    def distances(self, t, q, u):
        """``{joint: distance}`` at ``(t, q, u)`` for the joints that report one."""
        sysm = self.system
        jets = MultibodySystem.kinematics(sysm, t, q, u)  # the numeric path: a program traced only evaluate
        out = {}
        for e in self.edges:
            d = e.comp.singularity(jets[e.node_a], jets[e.node_b], sysm.P[e.name])
            if d is not None:
                out[e.name] = d
        return out

    def _failure(self, name, t, dist):
        comp = self.system.topology.edge(name).comp
        return SingularPosition(f"{name}: {comp.singularity_reason} at t={t:g} (distance {dist:.2g}); beyond it "
                                f"the motion is not defined -> {comp.singularity_fix}", t)

    def check(self, end, t_prev, dense):
        dist = self.distances(end.t, end.q, end.u)
        cut = set(end.system.topology.cut)  # an open unilateral contact is out of the system: not watched
        dist = {n: d for n, d in dist.items() if self.system.edge(n).comp.tree_edge or n in cut}
        for name, d in dist.items():
            if d < self.JOINT_MIN:
                raise self._failure(name, end.t, d)
        self.window.push(t_prev, end.t, dist, dense)
        sysm = self.system
        for name in self.window.dips():
            t, d = self.window.locate(lambda tt, q, u, name=name: self.distances(tt, q, u).get(name, np.inf),
                                      sysm.nq, sysm.nu, sysm.normalize)
            if d < self.JOINT_MIN:
                raise self._failure(name, t, d)

    def stats(self):
        return {}


def monitors_for(system, atol, singular="stop", start=None):
    """The monitors ``system`` needs, in the order they check a step: joint singularities,
    dropped rows, the constraint Jacobian's rank (the last two only for loops; ``singular``:
    what the rank monitor does at a singular position, ``"stop"`` or ``"pass"``). ``start``:
    initialization's ``InitialState.rows`` (``(system, Rows)``), which the rank monitor reads
    where a step starts at their coordinates."""
    out = []
    joints = [e for e in system.topology.edges if e.kind == "joint" and e.comp.has_singularity]
    if joints:
        out.append(JointSingularities(system, joints))
    if system.topology.cut:
        mask = system.row_mask
        if mask is not None and not mask.all():
            out.append(RedundantRows(system, atol))
        out.append(ConstraintRank(system, singular, start[1] if start is not None and start[0] is system else None))
    return out
