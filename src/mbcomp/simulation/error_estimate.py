"""The global error a run made, estimated by a companion run at a tighter tolerance.

An integrator controls the error it makes in one step; what a user reads is the global
error at the outputs, which the local errors add up to. For a conservative mechanism the
energy alarm (:mod:`mbcomp.simulation.accuracy`) sees the part of it that changes the
energy, but not the *phase error*: a pendulum whose energy is exact to 1e-9 can still lag
its true motion by a visible angle after many periods (the larger its swing, the faster
its phase error grows: its period depends on its amplitude). ``simulate(...,
error_estimate=True)`` measures it the only general way: the same request is run again at
:data:`TIGHTER` times the tolerances on the same output grid, and the difference is the
estimate (the companion's own error is smaller by the method's order: ~60x for dop853 at a
100x tighter tolerance).

The estimate goes into the result's ``stats``:

* ``"error_estimate"``: ``{column: max over the common outputs of |main - companion|}``, in
  the column's unit, for every column of both runs;
* ``"global_error"``: the largest of those over the state (the coordinates and speeds),
  with ``"global_error_column"`` naming the column it was found in;
* ``"error_estimate_rtol"``, ``"error_estimate_atol"``: the companion's tolerances;
  ``"error_estimate_note"`` when the companion could not be tighter (rtol at its floor) or
  did not reach the main run's end (the estimate covers the common outputs only).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(phi0=1.0))
>>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> r = mbcomp.simulate(m, t_end=20.0, rtol=1e-5, atol=1e-7, error_estimate=True)
>>> r.stats["global_error_column"], bool(1e-7 < r.stats["global_error"] < 1e-2)
('j.w', True)
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationInterrupted
from .endings import interrupted_by

__all__ = ["TIGHTER", "RTOL_FLOOR", "companion_tolerances", "estimate", "with_estimate"]

#: the companion run's tolerances are this times the main run's
TIGHTER = 1e-2
#: the companion's relative tolerance is never below this (round-off: a tighter request
#: makes steps that add more rounding error than they remove)
RTOL_FLOOR = 1e-13


def companion_tolerances(rtol, atol):
    """``(rtol, atol, note)`` of the companion run: :data:`TIGHTER` times the main run's,
    the relative one floored at :data:`RTOL_FLOOR` (``note`` says so, else ``""``)."""
    rtol_c = max(rtol * TIGHTER, RTOL_FLOOR)
    note = ""
    if rtol_c > rtol * TIGHTER:
        note = (f"rtol={rtol:g} is near the floor of what a tighter companion run can check (its rtol "
                f"{rtol_c:g}, not {rtol * TIGHTER:g}): the estimate mixes the companion's own error in")
    return rtol_c, atol * TIGHTER, note


def estimate(res, companion, state_names, rtol_c, atol_c, note=""):
    """Put the error estimate of ``res`` measured against ``companion`` (the same request at
    ``rtol_c``, ``atol_c`` on the same output grid) into ``res.stats`` (see the module notes);
    ``state_names``: the columns of the state (coordinates and speeds). Returns ``res``."""
    n = min(len(res.time), len(companion.time))
    notes = [note] if note else []
    if n < len(res.time):
        notes.append(f"the companion run ended at t={companion.time[n - 1]:g} s ({companion.status}: "
                     f"{companion.message}); the estimate covers the outputs up to there")
    apart = np.flatnonzero(np.abs(res.time[:n] - companion.time[:n]) > 1e-12 * max(1.0, abs(res.time[n - 1]))) \
        if n else []
    if len(apart):  # a terminal event ends the two runs at slightly different times: its output is not compared
        n = int(apart[0])
        notes.append(f"the runs' last outputs fall at different times (a terminal event); compared up to "
                     f"t={res.time[n - 1]:g} s" if n else "the runs share no output time")
    per_column = {}
    for name in res.names:
        if name not in companion:
            continue
        a, b = np.asarray(res[name])[:n], np.asarray(companion[name])[:n]
        if a.dtype.kind not in "fiu" or b.dtype.kind not in "fiu" or a.shape != b.shape:
            continue
        with np.errstate(invalid="ignore"):
            d = np.abs(a.astype(float) - b.astype(float))
        per_column[name] = float(np.nanmax(d)) if d.size and not np.all(np.isnan(d)) else 0.0
    states = {k: v for k, v in per_column.items() if k in set(state_names)}
    worst = max(states, key=states.get) if states else None
    res.stats.update(error_estimate=per_column, error_estimate_rtol=rtol_c, error_estimate_atol=atol_c,
                     global_error=states[worst] if worst else 0.0, global_error_column=worst)
    if notes:
        res.stats["error_estimate_note"] = "; ".join(notes)
    return res


def with_estimate(res, run, rtol, atol):
    """``res`` with its error estimate (:func:`estimate`) from ``run(rtol_c, atol_c)``, the
    same request at the companion's tolerances (:func:`companion_tolerances`). An interrupt
    during the companion raises :class:`~mbcomp.errors.SimulationInterrupted` carrying
    ``res``, which is whole."""
    rtol_c, atol_c, note = companion_tolerances(rtol, atol)
    why = "interrupted during the error estimate's companion run; the main run is complete in .result"
    try:
        companion = run(rtol_c, atol_c)
    except KeyboardInterrupt:  # Ctrl-C outside the integration (assembly, compilation)
        res.stats["error_estimate_note"] = "the companion run was interrupted: no estimate"
        raise SimulationInterrupted(res, "SIGINT", why) from None
    if companion.status == "interrupted":
        res.stats["error_estimate_note"] = "the companion run was interrupted: no estimate"
        raise SimulationInterrupted(res, interrupted_by(companion.message), why)
    system = res.system
    states = [] if system is None else list(system.q_names) + list(system.u_names)
    return estimate(res, companion, states, rtol_c, atol_c, note)
