"""External inputs: a signal from outside the model standing where a law is given.

``Input("motor_torque", unit="N m")`` can be given wherever a component takes a law of time and
state (``Torque(tau=Input(...))``), or be called inside a law of one's own
(``lambda t, phi, w: -k * phi + u(t)`` with ``u = Input(...)``). Its value:

* in ``mbcomp.simulate(..., inputs={"motor_torque": f})``: ``f(t)``, a function of time, a
  constant, or a table ``(times, values)`` interpolated linearly;
* in an exported FMU: what the importer sets (an FMU input variable of that name), so a
  controller outside the FMU drives the model;
* otherwise: its ``start`` value.

A generated program reads inputs like the drives' values: per-call inputs after the drives'
``(s, v, a)`` and the two Baumgarte gains (:mod:`mbcomp.codegen.tracer`); the input is keyed by
its name, so two ``Input`` objects of one name are one signal.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass, Torque
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))         # no gravity
>>> j = m.add("j", Revolute(phi0=0.0, w0=0.0)); bob = m.add("bob", PointMass(m=2.0))
>>> rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
>>> motor = m.add("motor", Torque(tau=mbcomp.Input("motor_torque", unit="N m")))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> m.connect(j.axis, motor.flange_b)
>>> r = mbcomp.simulate(m, t_end=1.0, inputs={"motor_torque": 4.0})   # 4 N m on 2 kg m^2
>>> round(float(r["j.w"][-1]), 9)
2.0
"""
from __future__ import annotations

import contextvars
import math
import re
import weakref

import numpy as np

__all__ = ["Input", "input_signals", "signal_of", "check_names"]

#: while a program is traced: a function Input -> its traced value (set by the tracer)
_TRACE = contextvars.ContextVar("mbcomp_input_trace", default=None)
#: while a run evaluates: {name: f(t)} (set by ``simulate`` through :func:`input_signals`)
_SIGNALS = contextvars.ContextVar("mbcomp_input_signals", default=None)
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.]*$")
#: every Input alive (a name given to ``simulate`` that none has is a typo)
_LIVE = weakref.WeakSet()


class Input:
    """A signal from outside the model, used as a law (see the module notes).

    Parameters
    ----------
    name : str
        The signal's name (``simulate``'s ``inputs`` key, the FMU variable's name): letters,
        digits, ``_`` and ``.``, not starting with a digit.
    unit : str
        Its unit as mbcomp writes units (``"N m"``, ``"N"``); ``"1"`` for none.
    start : float
        Its value when nothing gives one.
    description : str
        What it is (the FMU variable's description).

    Examples
    --------
    >>> u = Input("force", unit="N", start=1.5)
    >>> u(0.0), u.name
    (1.5, 'force')
    """

    def __init__(self, name, unit="1", start=0.0, description=""):
        if not isinstance(name, str) or not _NAME.match(name):
            raise ValueError(f"Input name {name!r}: use letters, digits, '_' and '.', not starting with a digit, "
                             "e.g. Input('motor_torque')")
        start = float(start)
        if not math.isfinite(start):
            raise ValueError(f"Input {name!r}: start={start!r} must be finite")
        self.name, self.unit, self.start, self.description = name, str(unit), start, str(description)
        _LIVE.add(self)

    def __call__(self, t, *state):
        """The value at time ``t`` (s); ``state`` (what a law receives) is ignored."""
        traced = _TRACE.get()
        if traced is not None:
            return traced(self)
        return self.value(t)

    def value(self, t):
        """The numeric value at ``t`` (s): the run's signal, else ``start``."""
        signals = _SIGNALS.get()
        f = signals.get(self.name) if signals else None
        if f is None:
            return self.start
        v = float(f(float(t)))
        if not math.isfinite(v):
            raise ValueError(f"input {self.name!r} is {v!r} at t={float(t):g}: its signal must give finite values")
        return v

    def __repr__(self):
        return f"Input({self.name!r}, unit={self.unit!r}, start={self.start!r})"


def check_names(names):
    """``ValueError`` for a name no :class:`Input` has (a typo in ``simulate``'s ``inputs``)."""
    known = {i.name for i in _LIVE}
    unknown = sorted(set(names) - known)
    if unknown:
        raise ValueError(f"inputs {unknown}: no Input of the model has that name -> the model's inputs are "
                         f"{sorted(known) or 'none'} (an Input is made with mbcomp.Input('name', ...))")


def signal_of(name, given):
    """A function of time from what ``simulate``'s ``inputs`` gives for ``name``: a callable
    ``f(t)``, a number, or a table ``(times, values)`` (interpolated linearly, held constant
    outside); ``ValueError`` naming the input otherwise."""
    if callable(given):
        return given
    if isinstance(given, (int, float, np.floating)):
        c = float(given)
        return lambda t: c
    try:
        times, values = (np.asarray(x, float) for x in given)
    except (TypeError, ValueError):
        raise ValueError(f"input {name!r}: give a function of time f(t), a number, or a table (times, values); "
                         f"got {type(given).__name__}") from None
    if times.ndim != 1 or times.shape != values.shape or times.size < 1 or np.any(np.diff(times) <= 0):
        raise ValueError(f"input {name!r}: the table (times, values) needs two 1-D arrays of one length with "
                         "strictly increasing times")
    return lambda t: float(np.interp(t, times, values))


class input_signals:
    """Context: the inputs' signals ``{name: f(t)}`` while a run evaluates (``simulate``)."""

    def __init__(self, signals):
        self.signals = dict(signals)

    def __enter__(self):
        self.token = _SIGNALS.set(self.signals)
        return self

    def __exit__(self, *exc):
        _SIGNALS.reset(self.token)
        return False


class traced_inputs:
    """Context for the tracer: each Input called is made a per-call input by ``node_of(inp)``
    (the tracer's allocator); ``order`` lists the inputs by their slot."""

    def __init__(self, node_of):
        self.node_of = node_of

    def __enter__(self):
        self.token = _TRACE.set(self.node_of)
        return self

    def __exit__(self, *exc):
        _TRACE.reset(self.token)
        return False
