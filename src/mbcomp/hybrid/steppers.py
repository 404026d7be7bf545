"""Which stepper a run with events takes (:func:`mbcomp.simulation.driver.integrate`'s segments).

A C integrator (:class:`~mbcomp.solvers.compiled_rk.CompiledRK`: ``auto``, ``dop853``,
``dopri5``) integrates whole stretches of output times in one C call. With events it either
watches them in its own loop -- every event function of the segment a declared
:class:`~mbcomp.modeling.events.EventRow` (:meth:`mbcomp.hybrid.events.Events.c_watch`) --
or steps scipy's method of the same order one step at a time over the compiled right-hand
side, where each step's own dense output is there to locate any event function on
(:func:`stepwise`). Every other method is stepped as it is.

Where the C loop may also act on the segment's impacts (:meth:`Events.c_impacts
<mbcomp.hybrid.c_loop.CLoop.c_impacts>`: stops' rebounds on a system without constraint
rows), one call runs stretch after stretch with the rebounds in between
(:class:`~mbcomp.codegen.c_events.LinearImpacts`), each stretch after an impact cut as a new
stepper's first would be, so the steps are those the Python actions give; the impacts are
entered into the run by :meth:`Events.take_c_impacts <mbcomp.hybrid.c_loop.CLoop.take_c_impacts>`.
:data:`C_IMPACTS` False (tests) leaves every action to Python.
"""
from __future__ import annotations

import numpy as np

from ..codegen.c_events import LinearImpacts
from ..solvers.compiled_rk import CompiledRK
from .events import BURST_SPAN, CHATTER, REST_HEIGHT

__all__ = ["stepwise", "watching", "C_IMPACTS", "IMPACT_LOG", "IMPACT_STRETCHES"]

#: act on stops' plain rebounds inside the C loop (False: every action in Python, as a check)
C_IMPACTS = True
#: impacts one C call acts on at most (the next is acted on in Python, and C goes on after it)
IMPACT_LOG = 64
#: stretches without an event one C call makes at most (the run's hooks -- budget, progress,
#: interrupts -- see the run between calls)
IMPACT_STRETCHES = 8


def stepwise(stepper_class):
    """``stepper_class``, or for a C integrator (:class:`~mbcomp.solvers.compiled_rk.CompiledRK`)
    one that steps scipy's method of the same order over the (compiled) right-hand side one
    step at a time: an event is located on each step's own dense output, which a C stretch
    (outputs only at the output times) does not give."""
    if not issubclass(stepper_class, CompiledRK):
        return stepper_class

    def __init__(self, *args, **kw):
        stepper_class.__init__(self, *args, **kw)
        self.engine = None

    return type(stepper_class.__name__, (stepper_class,), {"__init__": __init__, "__doc__": stepper_class.__doc__})


class _ImpactEngine:
    """The engine a stepper calls, running :class:`LinearImpacts` instead: the stepper hands
    it every output time left; it cuts the stretches itself, as the stepper would (``chunk``,
    ``chunk_max``: :attr:`CompiledRK.chunk`; the segment's count of them, a new segment after
    each impact), up to :data:`IMPACT_STRETCHES` per call, and reports the impacts on the stepper."""

    def __init__(self, stepper, engine, impacts, h_first):
        self.stepper, self.engine, self.impacts, self.h_first = stepper, engine, impacts, h_first
        self.count = 0  # C stretches of the current segment
        self.last = None

    def __getattr__(self, name):
        return getattr(self.engine, name)

    def integrate(self, order, t0, y0, t_end, t_out, rtol, atol, h0=0.0, hmax=0.0, max_steps=0, stiff_steps=0,
                  events=None, fresh=-1, event_tol=None):
        s = self.stepper
        r = self.impacts.integrate(events, order, t0, y0, t_out, rtol, atol, chunk=s.chunk,
                                   chunk_max=getattr(s, "chunk_max", s.chunk), count=self.count,
                                   max_stretches=IMPACT_STRETCHES, tol_scale=min(1e-12, 1e-3 * rtol), h0=h0,
                                   h_restart=self.h_first, hmax=hmax, max_steps=max_steps, stiff_steps=stiff_steps,
                                   fresh=fresh)  # tol_scale: solvers.locate.time_tolerance per max(1, |t|)
        s.impacts_done, self.count, self.last = r.impacts, r.count, (r.status, r.t_end)
        return r


class _Watching:
    """What :func:`watching` adds to a C integrator's class (its class attribute
    ``hybrid_events`` is the run's :class:`~mbcomp.hybrid.events.Events`)."""

    hybrid_events = None
    #: a stiff segment goes on inside this stepper (scipy's stiff method, stepped where the
    #: events are located), not by another stepper the run would make without them
    stiff_handover = None

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.impacts_done, self.acting = [], None
        events = self.hybrid_events
        spec = events.c_watch() if self.engine is not None else None
        if spec is None:
            self.engine = None
            return
        self.watch(*spec)
        if self.engine is None:  # a stepper that watches its events in Python after all (compiled radau5)
            return
        acts = events.c_impacts(REST_HEIGHT, CHATTER, BURST_SPAN) if C_IMPACTS and len(spec[0]) else None
        if acts is not None:
            impacts = LinearImpacts(self.engine, acts["mech"], acts["iu"], acts["sign"], acts["e"], acts["comp"],
                                    acts["chatter"], acts["burst"], acts["rest"], IMPACT_LOG)
            for c, hist in enumerate(acts["history"]):
                impacts.history(c, *hist)
            self.acting = self.engine = _ImpactEngine(self, self.engine, impacts, self.h)

    def _stretch(self):
        if self.acting is None:
            return super()._stretch()
        return self.t_eval[int(np.searchsorted(self.t_eval, self.t, side="right")):]  # the engine cuts them

    def _step(self):
        self.impacts_done = []
        super()._step()
        last = self.acting.last if self.acting is not None else None
        if last is not None and last[0] == 1:  # a guard failed: the Python path to that stretch's end only
            self._python_until = min(self._python_until, last[1])
        if self.acting is not None:
            self.acting.last = None


def watching(stepper_class, events):
    """``stepper_class``, or for a C integrator (:class:`~mbcomp.solvers.compiled_rk.CompiledRK`)
    one whose stretches watch the events in C (:meth:`Events.c_watch`: every event function
    of the segment declared affine, ``Modes.linear_events``) and act on the plain rebounds
    there (:meth:`Events.c_impacts`) -- or, where they cannot be watched (a user's function,
    a push, a slide, no compiled engine), steps scipy's method of the same order one step at
    a time as :func:`stepwise` does. Each stepper is made at the start of a segment, so it
    watches that segment's events."""
    if not issubclass(stepper_class, CompiledRK):
        return stepper_class
    return type(stepper_class.__name__, (_Watching, stepper_class),
                {"hybrid_events": events, "__doc__": stepper_class.__doc__})
