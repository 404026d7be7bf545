"""Coulomb friction with exact stick/slip switching on a 1-DOF joint's axis: the run's side.

A joint with friction (``Prismatic(friction=SlidingFriction(...))``,
``Revolute(friction=CoulombBearing(...))``, :mod:`mbcomp.library.friction`) has modes
``"stick"``, ``"slip+"`` and ``"slip-"`` (its :class:`~mbcomp.modeling.modes.Modes`):

* in ``"stick"`` it holds a :class:`~mbcomp.modeling.events.StickRow` (the axis' rate held at
  zero); the row's push ``lambda`` (N or N m, the friction force on the axis) is watched by
  :func:`row_events`: ``limit + lambda`` and ``limit - lambda`` falling through zero are the
  joint's events ``"break+"``/``"break-"`` (the load beats the static friction), located by
  Brent like any other event;
* in a slip mode the joint applies its kinetic friction as a generalized force on its own
  speed (``Modes.force(mode)``: ``-F_k`` in ``"slip+"``, ``+F_k`` in ``"slip-"``),
  added to the evaluation's ``f`` by :class:`~mbcomp.hybrid.active.ForceEvaluator`
  (:func:`~mbcomp.hybrid.active.with_mode_forces`);
  its event is the speed crossing zero (``"stick"``), whose action is ``Switch("stick")``;
* entering ``"stick"`` (or starting in it) the run checks at once whether the row can hold
  (:meth:`mbcomp.hybrid.events.Events.start`, and each new segment): a push beyond
  ``limit`` breaks away at once, in the direction of the load.

After the run :func:`friction_columns` adds ``<joint>.friction`` (N or N m, the friction's
force on the axis: the row's push while stuck, the kinetic force while slipping),
``<joint>.sticking`` (1 or 0), ``<joint>.power`` (W) and the dissipated energy, exactly:
``F_k |s(t) - s(t_slip)|`` summed over the slip intervals (the speed keeps its sign in a
slip), added to ``energy.dissipated`` and ``energy.balance``.

Examples
--------
>>> from mbcomp.modeling.events import StickRow
>>> row_events("block", StickRow("stick", 1.0, 0.0, limit=3.0), -1.0)   # held against 1 N
{('joint', 'block', 'break+'): 2.0, ('joint', 'block', 'break-'): 4.0}
"""
from __future__ import annotations

import numpy as np

from .active import segment_at

__all__ = ["row_events", "friction_columns", "count_dissipation"]


def row_events(name, row, push):
    """``{event key: value}`` the run watches for an engaged row of joint ``name`` pushing
    ``push`` (N or N m): ``("release", name, row)`` for a unilateral row, the two break-away
    margins ``limit -+ push`` for a :class:`~mbcomp.modeling.events.StickRow` (a contact's row
    with a friction cone adds the key of its ``"slide"`` event)."""
    from ..modeling.events import ContactRow, StickRow

    if isinstance(row, StickRow):
        return {("joint", name, "break+"): row.limit + push, ("joint", name, "break-"): row.limit - push}
    out = {("release", name, row.name): push}
    if isinstance(row, ContactRow) and row.mu_s is not None:  # the key; its value, the cone's margin: contact_pushes
        out[("joint", name, "slide")] = push
    return out


def _frictional(system, segments):
    """Names of the joints with a mode force (``Modes.has_force``) among the active sets of ``segments``."""
    names = {n for seg in segments for n in seg.modes}
    return sorted(n for n in names if system.edge(n).comp.modes(system.P[n]).has_force)


def friction_columns(res, events, Y):
    """Add the friction columns and the friction's dissipated energy to ``res`` (see the
    module notes); ``Y`` are the output states ``[q, u]``. The energy alarm the missing
    friction work rang is judged again by :func:`mbcomp.simulation.hybrid_columns.finish`,
    once for all its corrections."""
    system, segments = events.system, events.segments
    names = _frictional(system, segments)
    if not names or not len(res.time):
        return res
    t = res.time
    k_mode = segment_at([seg.t for seg in segments], t)  # an output at an event: the mode before
    total = np.zeros(len(t))
    for name in names:
        e, p, comp = system.edge(name), system.P[name], system.edge(name).comp
        iq, iu = e.q.start, e.u.start
        force, stuck, dissipated = np.zeros(len(t)), np.zeros(len(t)), np.zeros(len(t))
        done = 0.0  # the dissipation of the slip intervals already over (J)
        for i, seg in enumerate(segments):
            modes, q_i = seg.modes, seg.state
            sel = np.flatnonzero(k_mode == i)
            mode = modes.get(name)
            F = comp.modes(p).force(mode)
            if mode == "stick":
                stuck[sel] = 1.0
                for k in sel:
                    force[k] = _stick_push(events, modes, name, t[k], Y[k, :system.nq], Y[k, system.nq:])
            else:
                force[sel] = F
            dissipated[sel] = done - F * (Y[sel, iq] - q_i[iq])
            if i + 1 < len(segments):
                done -= F * (segments[i + 1].state[iq] - q_i[iq])
        res.set_column(f"{name}.friction", force)
        res.set_column(f"{name}.sticking", stuck)
        res.set_column(f"{name}.power", force * Y[:, system.nq + iu])
        res.units[f"{name}.friction"] = "N m" if comp.axis_kind == "rotational" else "N"
        res.units[f"{name}.sticking"], res.units[f"{name}.power"] = "1", "W"
        total += dissipated
    if "energy.balance" in res:
        count_dissipation(res, total)
    return res


def _stick_push(events, modes, name, t, q, u):
    """The stick row's push (N or N m) of joint ``name`` at ``(t, q, u)`` in ``modes``."""
    d = events.pushes_in(events.system_now(modes), modes, t, q, u).get(name, {})
    return 0.5 * (d[("joint", name, "break+")] - d[("joint", name, "break-")])


def count_dissipation(res, D):
    """``D`` (J) into ``energy.dissipated`` and ``energy.balance`` of ``res`` (the accuracy alarm
    is judged again once, with every correction, by the post-processing:
    :func:`mbcomp.simulation.hybrid_columns.finish`)."""
    res.set_column("energy.dissipated", res["energy.dissipated"] + D)
    res.set_column("energy.balance", res["energy.balance"] + D)
