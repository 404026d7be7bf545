"""What the C integrators' loop watches and acts on in a segment: the part of
:class:`~mbcomp.hybrid.events.Events` that speaks to the compiled engine (a mixin).

* :meth:`CLoop.c_watch`: the segment's event functions as the C loop watches them, when every
  one is a declared :class:`~mbcomp.modeling.events.EventRow` (``Modes.linear_events``).
* :meth:`CLoop.c_impacts`: which of them the C loop may act on itself -- an
  :class:`~mbcomp.modeling.events.Impact` closing one :class:`~mbcomp.modeling.events.AxisRow`
  of the joint's own speed, on a system without constraint rows, drives or quaternions, whose
  evaluation program gives ``M`` and ``f`` (:class:`mbcomp.codegen.c_events.LinearImpacts`).
  The runtime acts only on a plain rebound (approaching, ``e > 0``, rising more than twice the
  resting height, not chattering); any other event ends the stretch there and is decided
  here as before.
* :meth:`CLoop.take_c_impacts`: the impacts acted on in C entered into the run's records, the
  segment log and the components' hits, as :meth:`Events.act` enters its own.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1), s0=1.0, limits=(0.0, 2.0), restitution=0.5))
>>> b = m.add("b", PointMass(m=1.0)); m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> r = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12)     # two bounces, acted on in C
>>> t1 = float(np.sqrt(2 / 9.81))
>>> [round(x.time / t1, 9) for x in r.events]                       # the fall, then 2 e sqrt(2 g) / g
[1.0, 2.0]
>>> round(r.events[1].detail["speed_after"] / r.events[0].detail["speed_after"], 12)
0.5
"""
from __future__ import annotations

import numpy as np

from ..errors import ModelError, Problem
from ..modeling.events import AxisRow, Impact, StickRow
from .active import SegmentStart, mode_rows

__all__ = ["CLoop", "IMPACT_SPEEDS"]

#: systems of at most this many speeds act on impacts in C (their evaluation program is made
#: for the actions anyway: ``simulation.driver.EVENT_PROGRAM_SPEEDS``)
IMPACT_SPEEDS = 24


def _check_row(name, row, edge):
    """A ``ModelError`` naming joint, row and fix for an EventRow past the joint's own entries."""
    n = (edge.q if row.of == "q" else edge.u).stop - (edge.q if row.of == "q" else edge.u).start
    if not 0 <= row.index < n:
        kind = "coordinates" if row.of == "q" else "speeds"
        raise ModelError([Problem(name, f"its modes' EventRow {row.name!r} reads {row.of}[{row.index}], but the joint "
                                  f"has {n} {kind}", f"give an index from 0 to {n - 1} in event_rows")],
                         header="event rows out of range")


class CLoop:
    """The C loop's part of :class:`~mbcomp.hybrid.events.Events` (see the module notes); it
    uses the run's ``system``, ``modes``, ``user_left``, records and segments."""

    def _declared(self, name, mode):
        """Joint ``name``'s ``Modes``, its event rows in ``mode`` checked once (:func:`_check_row`)."""
        e = self.system.edge(name)
        declared = e.comp.modes(self.system.P[name])
        if declared.linear_events and (name, mode) not in self._checked:
            for row in declared.event_rows(mode):
                _check_row(name, row, e)
            self._checked.add((name, mode))
        return declared

    def c_watch(self):
        """The current segment's event functions as the C loop watches them --
        ``(index, sign, at, direction, fresh)`` for
        :meth:`~mbcomp.solvers.compiled_rk.CompiledRK.watch`, ``y = [q, u]`` -- or None when
        one of them is not an :class:`~mbcomp.modeling.events.EventRow` (a user's function,
        a mode that does not declare ``linear_events``, an engaged row's push, a slide)."""
        if any(left != 0 for left in self.user_left):
            return None
        sysm, nq = self.system, self.system.nq
        keys, index, sign, at, direction = [], [], [], [], []
        for name, mode in self.modes.items():
            declared, e = self._declared(name, mode), sysm.edge(name)
            if not declared.linear_events or declared.rows(mode) or declared.slips:
                return None
            for row in declared.event_rows(mode):
                keys.append(("joint", name, row.name))
                index.append(e.q.start + row.index if row.of == "q" else nq + e.u.start + row.index)
                sign.append(row.sign)
                at.append(row.at)
                direction.append(row.direction)
        self._c_keys = keys
        fresh = keys.index(self._fresh) if self._fresh in keys else -1
        return index, sign, at, direction, fresh

    def _c_mech(self):
        """The evaluation program of the run's system as the runtime reads it
        (:class:`mbcomp.codegen.c_events.MassProgram`), or None where the C loop cannot act: not a C
        program, drives or inputs (their values are set from Python per call), rows."""
        if not hasattr(self, "_mech"):
            s, self._mech = self.system, None
            if (s.backend == "c" and s.nq == s.nu and s.nu <= IMPACT_SPEEDS and not s.topology.cut
                    and not s.topology.drives
                    and not any(e.kind == "joint" and e.comp.has_singularity for e in s.topology.edges)):
                self._mech = _evaluation_mech(s, self.segments[-1].state)
        return self._mech

    def c_impacts(self, rest_height, chatter, burst_span):
        """What the C loop may act on in the current segment (after :meth:`c_watch`), or None:
        ``mech`` (the evaluation program), per watched event ``iu`` (its row's speed entry, -1
        when not an impact the loop acts on), ``sign``, ``e``, ``comp`` (its component's index
        into ``history``: ``(last impact s, interval before it s, successive shrinking
        intervals)``), and the thresholds ``rest`` (``rest_height atol``, m or rad),
        ``chatter`` and ``burst`` (s per ``max(1, |t|)``)."""
        sysm = self.system
        if self.system_now() is not sysm or self._c_mech() is None:
            return None
        iu, sign, e, comp, names = [], [], [], [], []
        for _, who, name in self._c_keys:
            action = self._declared(who, self.modes[who]).action(name, self.modes[who])
            rows = mode_rows(sysm, {who: action.engage}) if isinstance(action, Impact) else []
            plain = (len(rows) == 1 and isinstance(rows[0][1], AxisRow) and not isinstance(rows[0][1], StickRow)
                     and abs(rows[0][1].sign) == 1.0 and 0.0 <= action.restitution <= 1.0)
            iu.append(int(rows[0][3]) if plain else -1)
            sign.append(float(rows[0][1].sign) if plain else 1.0)
            e.append(float(action.restitution) if plain else 0.0)
            names += [] if who in names else [who]
            comp.append(names.index(who))
        if max(iu, default=-1) < 0:
            return None
        self._c_rows = list(zip(sign, iu, e))
        return dict(mech=self._c_mech(), iu=iu, sign=sign, e=e, comp=comp,
                    history=[_history(self._hits.get(who, [])) for who in names],
                    rest=rest_height * self.atol, chatter=chatter, burst=burst_span)

    def take_c_impacts(self, done):
        """Enter the impacts the C loop acted on (``[(t, event, [q, u-], [q, u+], loss J)]``,
        :meth:`mbcomp.codegen.c_events.LinearImpacts.integrate`) as :meth:`act` enters its own:
        the record, the component's hits, the next segment's start, the event just acted on."""
        nq = self.system.nq
        for t, k, before, after, loss in done:
            key = self._c_keys[k]
            sign, iu, e = self._c_rows[k]
            self._before = before
            self._record(t, key[1], key[2], "impact", {"speed_before": float(sign * before[nq + iu]),
                                                       "speed_after": float(sign * after[nq + iu]),
                                                       "energy_loss": float(loss), "restitution": e,
                                                       "drive_work": 0.0})
            self._hits.setdefault(key[1], []).append(t)
            self.segments.append(SegmentStart(float(t), dict(self.modes), dict(self.slip_dirs), before, after))
            self._worked_to = t
            self._fresh = self._last = key
            self.stats["event_evaluations"] += 1


def _evaluation_mech(system, state):
    """The :class:`~mbcomp.codegen.c_events.MassProgram` of ``system``'s C evaluation program
    when it has no rows, drives or inputs, else None; ``state`` a ``[q, u]`` where an
    evaluation makes the program if it is not made yet (a run with events evaluates by it)."""
    from ..codegen.c_events import MassProgram

    if getattr(system.evaluator, "bound", None) is None:
        system.evaluate(0.0, state[: system.nq], state[system.nq:])
    bound = getattr(system.evaluator, "bound", None)
    if bound is None or bound.drive_comps or bound.code.inputs:
        return None
    mech = MassProgram(bound)
    return mech if mech.rows == 0 else None


def _history(hits):
    """``(last, gap, shrinks)`` of a component's impact times ``hits`` (s): the last (-inf:
    none), the interval before it (-1: none) and how many successive intervals shrank (as
    ``events._chattering`` compares them)."""
    if not hits:
        return -np.inf, -1.0, 0
    d = np.diff(hits)
    shrinks = 0
    for i in range(len(d) - 1, 0, -1):
        if not d[i] < d[i - 1]:
            break
        shrinks += 1
    return float(hits[-1]), float(d[-1]) if d.size else -1.0, shrinks
