"""The outputs a run keeps up to an event, read from the step's dense output.

An event inside a step cuts the step there: the outputs at output times up to the event
come from that step's dense output (:func:`keep_until`), the ones after it from the next
segment.
"""
from __future__ import annotations

import numpy as np

__all__ = ["keep_until"]


def keep_until(run, t, qu):
    """Keep the outputs at output times up to ``t`` (s) from ``qu(t) -> [q, u]`` (projected
    when the formulation projects). Every state is taken from ``qu`` before any is projected:
    ``qu`` reads the step's dense output in the formulation's coordinates, and a projection's
    ``initial_state`` may choose them again (D'Alembert's independent speeds: the outputs
    after the first were read over the wrong speeds, 6.5 J of a ladder's 28 J missing)."""
    form = run.form
    k0 = len(run.ys)
    times = run.t_out[k0: max(k0, int(np.searchsorted(run.t_out, t, side="right")))]
    for tk, y in [(tk, np.array(qu(tk), dtype=float)) for tk in times]:
        if run.projects:
            y = form.full(tk, form.project(tk, form.initial_state(tk, y[: form.nq], y[form.nq:])))
        run.ys.append(np.array(y, dtype=float))
