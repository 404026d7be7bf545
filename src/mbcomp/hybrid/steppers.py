"""Which stepper a run with events takes (:func:`mbcomp.simulation.driver.integrate`'s segments).

A C integrator (:class:`~mbcomp.solvers.compiled_rk.CompiledRK`: ``auto``, ``dop853``,
``dopri5``) integrates whole stretches of output times in one C call. With events it either
watches them in its own loop -- every event function of the segment a declared
:class:`~mbcomp.modeling.events.EventRow` (:meth:`mbcomp.hybrid.events.Events.c_watch`) --
or steps scipy's method of the same order one step at a time over the compiled right-hand
side, where each step's own dense output is there to locate any event function on
(:func:`stepwise`). Every other method is stepped as it is.
"""
from __future__ import annotations

from ..solvers.compiled_rk import CompiledRK

__all__ = ["stepwise", "watching"]


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


def watching(stepper_class, events):
    """``stepper_class``, or for a C integrator (:class:`~mbcomp.solvers.compiled_rk.CompiledRK`)
    one whose stretches watch the events in C (:meth:`Events.c_watch`: every event function
    of the segment declared affine, ``Modes.linear_events``) -- or, where they cannot be
    (a user's function, a push, a slide, no compiled engine), steps scipy's method of the
    same order one step at a time as :func:`stepwise` does. Each stepper is made at the start
    of a segment, so it watches that segment's events."""
    if not issubclass(stepper_class, CompiledRK):
        return stepper_class

    def __init__(self, *args, **kw):
        stepper_class.__init__(self, *args, **kw)
        spec = events.c_watch() if self.engine is not None else None
        if spec is None:
            self.engine = None
        else:
            self.watch(*spec)

    return type(stepper_class.__name__, (stepper_class,), {"__init__": __init__, "__doc__": stepper_class.__doc__})
