"""The columns a hybrid run adds after it ends: its event records, the frictions' columns
and dissipation, the impacts' energy, and the accuracy alarm judged again with them.

The run's side of events, modes, impacts, contacts and friction lives in :mod:`mbcomp.hybrid`;
this module is the post-processing above it (it reads :mod:`.accuracy`'s alarms).
"""
from __future__ import annotations

import numpy as np

from ..hybrid.friction import friction_columns
from ..hybrid.slip import slip_dissipation, slipping_joints
from .accuracy import balance_alarm, between_events, energy_alarm

__all__ = ["finish"]


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
