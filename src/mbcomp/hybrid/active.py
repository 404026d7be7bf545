"""The active set of a hybrid run and the system it makes: the rows in force.

A run with components that have modes (:meth:`mbcomp.modeling.roles.Joint.modes`)
carries its *active set*, a dict ``{joint: mode}`` saying what is closed, open, sticking or
sliding. What holds in it -- its *rows in force* -- is described in one place,
:func:`rows_in_force` (as MuJoCo's ``mj_makeConstraint`` builds its constraint set), and every
consumer reads that description: the system stepped over it (:func:`mode_system`, from
:func:`system_in_force`), the initialization, the impacts and the columns after the run. The
system stepped is the assembled system with

* the rows of open contacts out (:func:`without_rows`: a numeric variant whose topology no
  longer cuts the contact), the rolling rows of sliding contacts out (:func:`without_rolling`);
* the rows the modes hold (:class:`~mbcomp.modeling.events.AxisRow`: ``sign (s - at)`` on a
  tree joint's coordinate: an engaged stop, a stuck friction) appended after its holonomic
  rows by :class:`ModeEvaluator`, which wraps the original evaluator (numeric or a generated
  program, unchanged);
* the constant forces the modes apply on their joints' speeds (a slipping friction's
  ``Modes.force``) added by :class:`ForceEvaluator` (:func:`with_mode_forces`).

A run is a list of segments, each over one active set from its start time on
(:class:`SegmentStart`); :func:`segment_at` answers which segment, so which active set, an
output time belongs to. Everything here reads the system and the active set only; the physics of contacts, friction
and slides (:mod:`.contacts`, :mod:`.friction`, :mod:`.slip`) and the events that change the
active set (:mod:`.events`) sit above.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(limits=(-0.1, 0.1)))
>>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = mbcomp.assemble(m)
>>> held = mode_system(system, {"j": "lo"})
>>> ev = held.evaluate(0.0, np.array([-0.05]), np.array([0.3]))
>>> ev.Phi.tolist(), ev.C.tolist()        # the row phi - lo, 0.05 rad on the allowed side
([0.05], [[1.0]])
>>> rows = rows_in_force(system, {"j": "lo"})
>>> [(n, row.sign) for n, row, _, _ in rows.held], rows.open, rows.sliding
([('j', 1.0)], (), ())
"""
from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError, Problem
from ..modeling.events import ContactRow
from ..modeling.modes import Modes

__all__ = ["RowsInForce", "rows_in_force", "system_in_force", "SegmentStart", "segment_at", "start_modes", "mode_rows", "open_joints", "slipping_joints", "cone_joints", "without_rows",
           "without_rolling", "WrappingEvaluator", "ModeEvaluator", "mode_system", "mode_forces", "ForcesAdded",
           "ForceEvaluator", "with_mode_forces", "evaluation_within"]


def start_modes(system):
    """``{joint: mode}`` of every joint of ``system`` that has modes (``modes(p)`` not None);
    a ``ModelError`` for one whose ``modes(p)`` is no :class:`~mbcomp.modeling.modes.Modes`, or
    that is driven or not a 1-DOF tree joint (no coordinate of its own)."""
    out = {}
    for e in system.topology.edges:
        declared = e.comp.modes(system.P[e.name]) if e.kind == "joint" else None
        if declared is not None and not isinstance(declared, Modes):
            raise ModelError([Problem(e.name, f"modes(p) of {type(e.comp).__name__} gave {declared!r}, not a Modes",
                                      "return a mbcomp.modeling.modes.Modes (its start mode, events, actions and "
                                      "rows), or None for a joint without modes")])
        if declared is not None:
            if e.comp.tree_edge:  # a stop: its events and rows are of its own coordinate
                _axis_index(system, e.name)
            out[e.name] = declared.start
    return out


def _axis_index(system, name):
    """``(q index, u index)`` of tree joint ``name``'s one coordinate; a problem otherwise."""
    e = system.edge(name)
    if e.drive or e.q.stop - e.q.start != 1 or e.u.stop - e.u.start != 1:
        why = "is driven (its motion is prescribed)" if e.drive else "is no 1-DOF joint in the spanning tree"
        raise ModelError([Problem(name, f"a stop needs the joint's own coordinate, but {name} {why}",
                                  "put the stop on a free 1-DOF joint, or cut another joint of the loop")])
    return e.q.start, e.u.start


def mode_rows(system, modes):
    """``[(joint, AxisRow, q index, u index)]`` held by ``modes``."""
    out = []
    for name, mode in sorted(modes.items()):
        e = system.edge(name)
        for row in e.comp.modes(system.P[name]).rows(mode):
            if not isinstance(row, ContactRow):  # a contact's rows are its own: see open_joints
                out.append((name, row, *_axis_index(system, name)))
    return out


def open_joints(system, modes):
    """Names of the joints of ``modes`` (``{joint: mode}``) whose rows are out in their mode."""
    return sorted(n for n, mode in modes.items() if not system.edge(n).comp.modes(system.P[n]).holds_rows(mode))


def slipping_joints(system, modes):
    """Names of the contacts of ``modes`` sliding in their mode (``Modes.slip_friction`` not None)."""
    out = []
    for n, mode in modes.items():
        declared = system.edge(n).comp.modes(system.P[n])
        if declared.slips and declared.slip_friction(mode) is not None:
            out.append(n)
    return sorted(out)


def cone_joints(system, modes):
    """Names of the contacts of ``modes`` holding a row with a friction cone (rolling)."""
    return sorted(n for n, mode in modes.items()
                  for r in system.edge(n).comp.modes(system.P[n]).rows(mode) if isinstance(r, ContactRow)
                  and r.mu_s is not None)


def without_rows(system, names):
    """``system`` without the rows of the cut joints ``names`` (itself when there are none).

    A numeric variant (:meth:`~mbcomp.assembly.system.MultibodySystem.variant`): its topology
    cuts the other joints only, its nonholonomic joints are the others, its row mask is the
    system's restricted to the other rows. A generated program evaluates every row, so an
    open mode is evaluated by the jets."""
    names = set(names)
    if not names:
        return system
    topo = copy.copy(system.topology)
    topo.cut = [c for c in system.topology.cut if c not in names]
    new = system.variant(topology=topo, nonholonomic=[e for e in system.nonholonomic if e.name not in names])
    if system.row_mask is not None:
        keep = [n.rsplit(".", 1)[0] not in names for n in system.constraint_names(all_rows=True)]
        new.row_mask = np.asarray(system.row_mask)[np.array(keep, bool)]
    return new


def without_rolling(system, names):
    """``system`` without the rolling rows (``velocity_constraints``) of the contacts
    ``names``, their holonomic rows kept (itself when there are none): a numeric variant."""
    names = set(names)
    if not names:
        return system
    return system.variant(nonholonomic=[e for e in system.nonholonomic if e.name not in names])


class _RowsAdded:
    """An evaluation with the mode's rows appended to the holonomic ones (everything else
    is the wrapped evaluation's)."""

    def __init__(self, ev, Phi, Phid, C, cb):
        self._ev, self.Phi, self.Phid, self.C, self.cb = ev, Phi, Phid, C, cb

    def __getattr__(self, name):
        return getattr(self._ev, name)

    @property
    def inner(self):
        """The wrapped evaluation (without the mode's rows)."""
        return self._ev

    @property
    def A(self):
        return np.vstack((self.C, self.B)) if self.B.size else self.C


class WrappingEvaluator:
    """An evaluator that changes another's evaluations (a mode's rows, a mode's forces): the
    backend, statistics and coordinate rates are the wrapped one's; it offers no one-call
    programs, so the formulations assemble their equations from ``evaluate``. Subclasses
    implement ``evaluate`` and ``rebind``."""

    capabilities = frozenset()

    def __init__(self, inner):
        self.inner = inner

    @property
    def backend(self):
        return self.inner.backend

    @property
    def stats(self):
        return self.inner.stats

    def q_rate(self, q, u):
        return self.inner.q_rate(q, u)


class ModeEvaluator(WrappingEvaluator):
    """The evaluator of a system in a mode: the original evaluator's evaluation with the
    engaged rows appended (masked evaluations only: an unmasked one lists the assembled
    rows, as ``constraint_names(all_rows=True)`` does)."""

    def __init__(self, inner, rows, nu):
        super().__init__(inner)
        self.rows, self.nu = rows, nu

    def evaluate(self, t, q, u, masked=True):
        ev = self.inner.evaluate(t, q, u, masked)
        if not masked or not self.rows:
            return ev
        k = len(self.rows)
        C = np.zeros((k, self.nu))
        Phi, Phid = np.zeros(k), np.zeros(k)
        for i, (_, row, iq, iu) in enumerate(self.rows):
            Phi[i], Phid[i], C[i, iu] = row.value(q[iq]), row.sign * u[iu], row.sign
        return _RowsAdded(ev, np.concatenate((ev.Phi, Phi)), np.concatenate((ev.Phid, Phid)),
                          np.vstack((ev.C, C)), np.concatenate((ev.cb, np.zeros(k))))

    def rebind(self, system, laws=False):
        return ModeEvaluator(self.inner.rebind(system, laws), self.rows, self.nu)


@dataclass(frozen=True)
class RowsInForce:
    """What holds in an active set (:func:`rows_in_force`).

    Attributes
    ----------
    open : tuple of str
        Joints whose own rows are out (an open contact): :func:`without_rows`.
    sliding : tuple of str
        Contacts sliding: their rolling rows are out (:func:`without_rolling`), their friction
        a force of the state (:mod:`mbcomp.hybrid.slip`).
    held : tuple
        ``(joint, AxisRow, q index, u index)`` of the rows the modes hold on tree joints' own
        coordinates (an engaged stop, a stuck friction), appended after the holonomic rows.
    forces : tuple
        ``(u index, N or N m)``: the constant forces the modes apply on their joints' speeds
        (a slipping friction's ``Modes.force``).
    """

    open: tuple
    sliding: tuple
    held: tuple
    forces: tuple


def rows_in_force(system, active):
    """The :class:`RowsInForce` of the active set ``active`` (``{joint: mode}``) on ``system``:
    the one description of what is closed, open, sticking and sliding that the system stepped,
    the initialization, the impacts and the columns are made from. One pass over the joints,
    each joint's ``modes(p)`` asked once: what :func:`open_joints`, :func:`slipping_joints`,
    :func:`mode_rows` and :func:`mode_forces` give, in their order (by joint name)."""
    opened, sliding, held, forces = [], [], [], []
    for name, mode in sorted(active.items()):
        e = system.edge(name)
        declared = e.comp.modes(system.P[name])
        if not declared.holds_rows(mode):
            opened.append(name)
        if declared.slips and declared.slip_friction(mode) is not None:
            sliding.append(name)
        for row in declared.rows(mode):
            if not isinstance(row, ContactRow):  # a contact's rows are its own: see open_joints
                held.append((name, row, *_axis_index(system, name)))
        value = declared.force(mode) if declared.has_force else 0.0
        if value:
            forces.append((e.u.start, float(value)))
    return RowsInForce(tuple(opened), tuple(sliding), tuple(held), tuple(forces))


def system_in_force(system, rows, held=True):
    """``system`` with the rows in force ``rows`` (:class:`RowsInForce`): open contacts' rows
    and sliding contacts' rolling rows out and, with ``held``, the held rows appended
    (:class:`ModeEvaluator`); the system itself when nothing changes. The modes' forces are
    added by :func:`with_mode_forces`, a slide's friction by
    :func:`~mbcomp.hybrid.slip.with_slip_friction`."""
    base = without_rolling(without_rows(system, rows.open), rows.sliding)
    if not held or not rows.held:
        return base
    return base.with_evaluator(lambda new: ModeEvaluator(base.evaluator, list(rows.held), base.nu))


def mode_system(system, modes):
    """``system`` stepped in the active set ``modes`` (the system itself when nothing changes):
    :func:`system_in_force` of its :func:`rows_in_force` -- the rows of open contacts out, the
    rolling rows of sliding contacts out (their friction is added by
    :func:`~mbcomp.hybrid.slip.with_slip_friction`), engaged stops' rows appended."""
    return system_in_force(system, rows_in_force(system, modes))


@dataclass(frozen=True)
class SegmentStart:
    """The start of one segment of a hybrid run: from ``t`` (s) on, the active set ``modes``
    (``{joint: mode}``) and the sliding contacts' start directions ``dirs`` hold; ``state``
    is ``[q, u]`` there (consistent with the segment's rows), ``before`` the state before the
    event's action (None at the run's start)."""

    t: float
    modes: dict
    dirs: dict
    before: object
    state: np.ndarray


def segment_at(starts, t):
    """The index of the segment each output time of ``t`` (s) belongs to, the segments starting
    at ``starts`` (s, non-decreasing; the first also takes what is before it): an output at an
    event's time belongs to the segment before the event (its state was kept before the action).

    Examples
    --------
    >>> segment_at([0.0, 0.5, 1.0], np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.5])).tolist()
    [0, 0, 0, 1, 1, 2]
    """
    return np.maximum(np.searchsorted(np.asarray(starts, float), t, side="left") - 1, 0)


def mode_forces(system, modes):
    """``[(u index, force)]``: the generalized forces (N or N m) the joints of ``modes`` apply
    on their own speed in their mode (``Modes.force(mode)``, e.g. kinetic friction)."""
    out = []
    for name, mode in sorted(modes.items()):
        e = system.edge(name)
        declared = e.comp.modes(system.P[name])
        value = declared.force(mode) if declared.has_force else 0.0
        if value:
            out.append((e.u.start, float(value)))
    return out


class ForcesAdded:
    """An evaluation whose generalized forces ``f`` carry the modes' forces."""

    def __init__(self, ev, f):
        self._ev, self.f = ev, f

    def __getattr__(self, name):
        return getattr(self._ev, name)

    @property
    def inner(self):
        """The wrapped evaluation (without the modes' forces)."""
        return self._ev


class ForceEvaluator(WrappingEvaluator):
    """An evaluator adding constant generalized forces ``[(u index, N or N m)]`` to the wrapped
    evaluator's ``f`` (its rows and everything else unchanged)."""

    def __init__(self, inner, forces):
        super().__init__(inner)
        self.forces = forces

    def evaluate(self, t, q, u, masked=True):
        ev = self.inner.evaluate(t, q, u, masked)
        f = np.array(ev.f, dtype=float)
        for iu, value in self.forces:
            f[iu] += value
        return ForcesAdded(ev, f)

    def rebind(self, system, laws=False):
        return ForceEvaluator(self.inner.rebind(system, laws), self.forces)


def evaluation_within(sysm, ev, base):
    """The evaluation ``base.evaluate(t, q, u)`` that ``ev``, an evaluation of the mode's
    system ``sysm`` at ``(t, q, u)``, wraps -- when ``sysm``'s evaluator only wraps ``base``'s
    (the modes' rows appended, :class:`ModeEvaluator`; their forces added,
    :class:`ForceEvaluator`) -- else None (``base`` is then evaluated again): the same
    evaluator asked at the same state, so the same numbers, one evaluation instead of two."""
    evaluator = sysm.evaluator
    while evaluator is not base.evaluator:
        if isinstance(evaluator, ModeEvaluator):
            if evaluator.rows:  # without rows it hands the inner evaluation through
                if not isinstance(ev, _RowsAdded):
                    return None
                ev = ev.inner
        elif isinstance(evaluator, ForceEvaluator) and isinstance(ev, ForcesAdded):
            ev = ev.inner
        else:
            return None
        evaluator = evaluator.inner
    return ev


def with_mode_forces(system, modes):
    """``system`` (a mode's system) with the forces its ``modes`` apply (itself when none)."""
    forces = mode_forces(system, modes)
    if not forces:
        return system
    return system.with_evaluator(lambda new: ForceEvaluator(system.evaluator, forces))
