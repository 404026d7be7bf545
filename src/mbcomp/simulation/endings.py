"""How a run ends early: the messages that say why, and SIGTERM as an interruption.

The driver keeps the results of every accepted step whatever ends a run; these are the
words it uses. A component's law that raises is named from the exception's traceback
(:func:`mbcomp.modeling.blame.blame`: the component, the law and its line) with the time of
the evaluation that raised; an interruption names what interrupted.

Examples
--------
>>> from mbcomp.simulation.endings import law_failure
>>> def tau(t, phi, w):
...     raise ValueError("table ends at 0.3 s")
>>> try:
...     tau(0.31, 0.0, 0.0)
... except ValueError as exc:
...     msg = law_failure(exc, 0.3, 0.3)
>>> msg.split(" (")[0]
'the model: tau raised ValueError at t=0.31: table ends at 0.3 s'
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from numbers import Real

from ..codegen.graph import CodegenError
from ..errors import SimulationError
from ..modeling.blame import blame

__all__ = ["Terminated", "sigterm_interrupts", "law_failure", "start_failure", "raised_in_a_law", "interruption",
           "interrupted_by",
           "time_of"]


class Terminated(BaseException):
    """SIGTERM arrived during the integration (raised by :func:`sigterm_interrupts`' handler).
    A ``BaseException``, like ``KeyboardInterrupt``, so that no ``except Exception`` in a
    model's code swallows it."""


def _raise_terminated(_signum, _frame):
    raise Terminated("SIGTERM")


@contextmanager
def sigterm_interrupts():
    """While the block runs, SIGTERM raises :class:`Terminated`; the previous handler is
    restored after. Only in the main thread (the only one that receives signals), and only
    when the previous handler was set from Python (else it could not be restored)."""
    previous = signal.getsignal(signal.SIGTERM) if threading.current_thread() is threading.main_thread() else None
    if previous is not None:
        signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def time_of(exc):
    """The time (s) of the innermost evaluation in the traceback of ``exc``: the ``t`` of the
    deepest frame holding a real-valued ``t`` (``None`` if no frame does)."""
    tb, t = exc.__traceback__, None
    while tb is not None:
        v = tb.tb_frame.f_locals.get("t")
        if isinstance(v, Real) and not isinstance(v, bool):
            t = float(v)
        tb = tb.tb_next
    return t


def law_failure(exc, t_reached, t_kept):
    """``"<Class> '<path>': <law> raised <Error> at t=<s>: <text> (<file:line in law>); ..."``.

    Parameters
    ----------
    exc : Exception
        Raised while evaluating the model, with its traceback.
    t_reached : float
        End of the last accepted step (s): the raising evaluation was in the step after it.
    t_kept : float
        Last output time kept (s).
    """
    return _raised(exc, t_reached) + f"; the results up to t={t_kept:g} s are kept"


def start_failure(exc, t_start):
    """The message for a law that raises before the first step (consistent start, first
    evaluation): there are no results to keep, so :func:`~mbcomp.simulate` raises it as a
    :class:`~mbcomp.errors.SimulationError` from the law's exception."""
    return _raised(exc, t_start) + " (while finding the consistent start; nothing was integrated)"


def _raised(exc, t_reached):
    b = blame(exc)
    if b.law == "?":  # no component's or user's code in the traceback: not a law to fix
        t = time_of(exc)
        when = f"at t={t:g}" if t is not None else f"in the step from t={t_reached:g}"
        if isinstance(exc, CodegenError):  # its text says what failed and the fix
            return f"the generated program could not be used {when}: {exc}"
        return (f"mbcomp's own code raised {type(exc).__name__} {when}: {exc} (no component's law is in its "
                "traceback) -> this is mbcomp's failure, not the model's: report it with the model")
    who = b.who if b.component is not None else "the model"
    own = f"{b.path}: "  # a component's own diagnosis (a law returned None): its message as it is
    if isinstance(exc, SimulationError) and b.component is not None and str(exc).startswith(own):
        return f"{who}: {str(exc)[len(own):]}"
    t = time_of(exc)
    when = f"at t={t:g}" if t is not None else f"in the step from t={t_reached:g}"
    return (f"{who}: {b.law} raised {type(exc).__name__} {when}: {exc} ({b.where}) -> fix the law or the "
            "model's parameters")


def raised_in_a_law(exc):
    """True when a user's or a component's code is in the traceback of ``exc`` (numpy's
    ``LinAlgError`` from a law is the law's failure, not the formulation's)."""
    return blame(exc).law != "?"


def interruption(how, t_reached, t_kept):
    """``"interrupted <how> at t=<s> s; the results up to t=<s> s are kept"``."""
    return f"interrupted {how} at t={t_reached:g} s; the results up to t={t_kept:g} s are kept"


def interrupted_by(message):
    """The signal an :func:`interruption` message names: ``"SIGTERM"`` for ``"interrupted by
    SIGTERM ..."``, else ``"SIGINT"`` (Ctrl-C)."""
    return "SIGTERM" if message.startswith("interrupted by SIGTERM") else "SIGINT"
