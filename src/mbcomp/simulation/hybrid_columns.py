"""The columns of a hybrid run: each output over its own segment's system, then what the run
adds after it ends (its event records, the frictions' columns and dissipation, the impacts'
energy, and the accuracy alarm judged again with them).

The post-processing (:func:`~mbcomp.simulation.postprocess.postprocess`) evaluates the
assembled system; an output inside a segment whose rows in force differ
(:func:`~mbcomp.hybrid.active.rows_in_force`: an open contact, an engaged stop, a stuck or
slipping friction, a sliding contact) has its columns computed again over that segment's
system by :func:`segment_columns`, the one place that asks which segment an output time
belongs to (:func:`~mbcomp.hybrid.active.segment_at`). The run's side of events, modes,
impacts, contacts and friction lives in :mod:`mbcomp.hybrid`; this module is the
post-processing above it (it reads :mod:`.accuracy`'s alarms).
"""
from __future__ import annotations

import numpy as np

from ..assembly.column_units import column_units
from ..assembly.outputs import output_values
from ..hybrid.active import rows_in_force, segment_at, system_in_force, without_rows
from ..hybrid.contacts import open_force_columns
from ..hybrid.friction import friction_columns
from ..hybrid.stops import engaged_values, stop_joints, stop_units
from ..hybrid.slip import frictional_contacts, slip_dissipation, slip_state, sliding_values, slipping_joints
from .accuracy import balance_alarm, between_events, energy_alarm

__all__ = ["segment_columns", "finish"]


def segment_columns(series, system, segments, t, Y, system_now):
    """Correct the result's ``series`` (``{column: array}``, over the assembled ``system``) at
    the output times ``t`` (s; ``Y`` their states ``[q, u]``) whose segment's rows in force
    differ, and add the hybrid run's own columns; returns ``{column: unit}`` of the added ones.

    ``segments`` is the run's :class:`~mbcomp.hybrid.active.SegmentStart` list and
    ``system_now(modes, dirs=None)`` a segment's system (:meth:`mbcomp.hybrid.events.Events.system_now`).
    At each output, in its segment (an output at an event's time: the segment before it):

    * open contacts: every column over the system without their rows
      (:func:`~mbcomp.assembly.outputs.output_values`), their force columns (N or N m) 0;
    * rows held or forces acting (an engaged stop, a stuck or slipping friction,
      :func:`~mbcomp.hybrid.stops.changes_dynamics`): every column again from the segment's
      system (:func:`~mbcomp.hybrid.stops.engaged_values`) and ``<joint>.stop`` (N or N m,
      the stop's push, 0 where not engaged) for every joint engaged in some segment;
    * contacts with a friction cone: ``<contact>.sticking`` and ``<contact>.slip``
      (:func:`~mbcomp.hybrid.slip.slip_state`) and, where they slide, every column again
      with the friction as their rolling rows' multipliers
      (:func:`~mbcomp.hybrid.slip.sliding_values`).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> s = m.add("s", Prismatic(n=(0, 1, 0), s0=0.1, limits=(0.0, 1.0))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> r = mbcomp.simulate(m, t_end=0.5, n_out=3)     # lands on the lower stop at 0.14 s
    >>> float(r["s.stop"][0]), round(float(r["s.stop"][-1]), 6), r.units["s.stop"]
    (0.0, 19.62, 'N')
    """
    at = segment_at([seg.t for seg in segments], t)
    stops, cones = stop_joints(system, segments), frictional_contacts(system, segments)
    for n in stops:
        series[f"{n}.stop"] = np.zeros(len(t))
    for n in cones:
        series[f"{n}.sticking"], series[f"{n}.slip"] = np.zeros(len(t)), np.zeros(len(t))
    made = {}
    for i in np.unique(at):  # each segment's rows in force made once, for all its outputs
        _in_segment(series, system, segments[i], t, Y, np.flatnonzero(at == i), cones, made, system_now)
    sticking = {f"{n}.sticking": "1" for n in cones}
    return {**stop_units(system, stops), **sticking, **{f"{n}.slip": "m/s" for n in cones}}


def _in_segment(series, system, seg, t, Y, ks, cones, made, system_now):
    """:func:`segment_columns` at the outputs ``ks`` of the segment ``seg``: what its active set
    changes (read once) written at each (in the order of the outputs, each output's
    corrections in the order of :func:`segment_columns`' list); nothing where it changes
    nothing (the assembled system's columns hold). ``made``: what the run's segments share,
    made when first needed (the columns' units; the systems without open contacts' rows, by
    their names)."""
    nq, modes, dirs = system.nq, seg.modes, seg.dirs
    in_force = rows_in_force(system, modes)
    names = in_force.open
    changes = bool(in_force.held or in_force.forces)  # stops.changes_dynamics
    if not (names or changes or cones):
        return
    if names and names not in made:
        made[names] = without_rows(system, names)
        if "units" not in made:
            made["units"] = column_units(system)
    zeroed = open_force_columns(series, system, names, made.get("units"))
    if changes:
        sysm, base = system_now(modes), system_in_force(system, in_force, held=False)
    sliding = system_now(modes, dirs) if cones and in_force.sliding else None

    def put(k, values):
        for col, val in values.items():
            if col in series:
                series[col][k] = val

    for k in ks:
        tk, q, u = t[k], Y[k, :nq], Y[k, nq:]
        if names:
            put(k, output_values(made[names], tk, q, u)[0])
        if changes:
            values, pushes = engaged_values(system, sysm, modes, tk, q, u, in_force=in_force, base=base)
            put(k, values)
            put(k, {f"{n}.stop": push for n, push in pushes.items()})
        for col in zeroed:  # open contacts' forces (N or N m): 0
            series[col][k] = 0.0
        if cones:
            put(k, slip_state(system, cones, modes, tk, q, u))
            if sliding is not None:
                put(k, sliding_values(system, sliding, modes, dirs, tk, q, u))


def finish(res, events, states=None):
    """``res`` with its ``events`` (a list of :class:`~mbcomp.hybrid.events.EventRecord`, empty without events), the
    stick-slip frictions' columns and dissipation (axes: :func:`~mbcomp.hybrid.friction.friction_columns`; contacts:
    :func:`~mbcomp.hybrid.slip.slip_dissipation`) and, after impacts, the column
    ``energy.impacts`` (J: the kinetic energy the impacts took, and a rebound too slow to
    follow when a stop settles, up to each output time); the accuracy alarm the
    post-processing rang without them is judged again with them all (an impact's loss, a
    friction's work is no drift)."""
    res.events = list(events.records) if events is not None else []
    before = None
    if "energy.balance" in res:
        before = (np.array(res["energy.balance"]), np.array(res["energy.dissipated"]), np.array(res["energy.work"]))
    if events is not None and states is not None:  # stick-slip friction's columns and dissipation
        friction_columns(res, events, states)
        if any(slipping_joints(events.system, seg.modes) for seg in events.segments):
            slip_dissipation(res, events.system, events.segments, events.work_log, states, events.system_now)
    drives = [(r.time, r.detail["drive_work"]) for r in res.events if r.detail.get("drive_work")]
    if drives and "energy.work" in res:  # the drives' impulses at impacts do work (J)
        times, work = np.array(drives).T
        done = np.concatenate(([0.0], np.cumsum(work)))[np.searchsorted(times, res.time, side="right")]
        res.set_column("energy.work", res["energy.work"] + done)
        res.set_column("energy.balance", res["energy.balance"] - done)
    impacts = [(r.time, r.detail["energy_loss"]) for r in res.events if "energy_loss" in r.detail]
    lost = np.zeros(len(res.time))
    if impacts:
        times, losses = np.array(impacts).T
        lost = np.concatenate(([0.0], np.cumsum(losses)))[np.searchsorted(times, res.time, side="right")]
        res.set_column("energy.impacts", lost)
        res.units["energy.impacts"] = "J"
        if "energy.balance" in res:  # E - E0 - W + D, and the impacts' losses now
            res.set_column("energy.balance", res["energy.balance"] + lost)
    if res.status == "inaccurate" and "energy.kinetic" in res and "accuracy alarm" in res.message:
        _alarm_again(res, lost, before)
    return res


def _alarm_again(res, lost, before):
    """Judge the accuracy alarm again with the impacts' losses and the frictions' dissipation
    counted (``before``: the balance and dissipation the post-processing judged, or None for
    a conservative run): the run is ``"success"`` when the alarm no longer rings."""
    T, V, rtol = res["energy.kinetic"], res["energy.potential"], res.stats["rtol"]
    floor = res.stats.get("energy_tolerance", 0.0)  # the energy the tolerances leave open (J)
    if before is not None:
        W, D = res["energy.work"], res["energy.dissipated"]
        was = balance_alarm(before[0], T, V, before[2], before[1], 0.0, rtol, floor)
        # the work's and dissipation's quadrature on the output grid cannot follow a power
        # jumping inside an interval (an impact, a switch): the balance is judged between them
        judged = between_events(res["energy.balance"], res.time, [e.time for e in res.events])
        now = balance_alarm(judged, T, V, W, D + lost, 0.0, rtol, floor)
    else:
        was, now = energy_alarm(T, V, rtol, floor), energy_alarm(T, V + lost, rtol, floor)
    if now[0] is None and was[1]:
        res.status = "success"
        res.message = res.message.replace("; " + was[1], "")
