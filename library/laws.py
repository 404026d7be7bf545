"""What the library's law parameters are checked against: their signature at validation, and
what they returned at run time.

A law is a user's callable given as a parameter (``Torque(tau=lambda t, phi, w: ...)``,
``WorldForce(f=lambda t, frame: ...)``, ``PrescribedMotion(s=lambda t: ...)``). Two checks
name the component, the law, what went wrong and what was expected:

* :func:`signature_problem` -- when the model is validated: can the law be called with the
  arguments the component will pass (``tau(t, phi, w)``)?
* :func:`describe` -- at run time: a short text of what a law returned (``None``,
  ``a tuple (1.0, 2.0)``, ``nan``), for the message when it is not what was expected.

Examples
--------
>>> from mbcomp.library.laws import describe, signature_problem
>>> signature_problem(lambda t: 1.0, ("t", "phi", "w"))
'takes (t) but is called as (t, phi, w)'
>>> signature_problem(lambda t, phi, w: 1.0, ("t", "phi", "w")) is None
True
>>> describe((1.0, 2.0)), describe(None), describe(float("nan"))
('a tuple (1.0, 2.0)', 'None', 'nan')
"""
from __future__ import annotations

import inspect
from numbers import Real

import numpy as np

from mbcomp.errors import Problem

__all__ = ["signature_problem", "law_problems", "describe", "number", "as_number", "pos", "neg", "smin", "smax"]


def signature_problem(law, names):
    """Why ``law`` cannot be called with ``len(names)`` positional arguments, or ``None``.

    Parameters
    ----------
    law : callable
        The user's law.
    names : tuple of str
        The arguments the component passes, in order (for the message).

    Returns
    -------
    str or None
        ``"takes (t) but is called as (t, phi, w)"``; ``None`` when the call binds, or when
        the signature cannot be read (a builtin or C function: it is checked when it runs).

    Examples
    --------
    >>> from mbcomp.library.laws import signature_problem
    >>> signature_problem(lambda t, frame, extra: 0.0, ("t", "frame"))
    'takes (t, frame, extra) but is called as (t, frame)'
    >>> signature_problem(lambda *args: 0.0, ("t", "frame")) is None
    True
    """
    try:
        sig = inspect.signature(law)
    except (TypeError, ValueError):
        return None
    try:
        sig.bind(*names)
    except TypeError:
        return f"takes {_params(sig)} but is called as ({', '.join(names)})"
    return None


def _params(sig):
    return "(" + ", ".join(str(p) for p in sig.parameters.values()) + ")"


def law_problems(comp, p, laws):
    """:class:`~mbcomp.errors.Problem` for every law parameter of ``comp`` whose signature
    does not fit: for a component's ``check_params``.

    Parameters
    ----------
    comp : Component
        The component (its path names the problem).
    p : namespace
        Its parameter values.
    laws : dict
        ``{parameter name: argument names}``, e.g. ``{"tau": ("t", "phi", "w")}``; a
        parameter holding a number (not a callable) is not checked here.

    Examples
    --------
    >>> from mbcomp.library import Torque
    >>> from mbcomp.library.laws import law_problems
    >>> motor = Torque(tau=lambda t: 1.0)
    >>> law_problems(motor, motor.p, {"tau": ("t", "phi", "w")})[0].what
    'the tau law takes (t) but is called as tau(t, phi, w)'
    """
    out = []
    for name, args in laws.items():
        law = getattr(p, name)
        why = signature_problem(law, args) if callable(law) else None
        if why:
            call = f"{name}({', '.join(args)})"
            said = why.replace("(" + ", ".join(args) + ")", call)
            out.append(Problem(f"{comp.path}.{name}", f"the {name} law {said}",
                               f"write it as def {call}: ... (or lambda {', '.join(args)}: ...)"))
    return out


def describe(value, limit=60):
    """A short text of a value a law returned, for an error message.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.laws import describe
    >>> describe("abc"), describe(np.array([1.0, 2.0])), describe(float("inf"))
    ("a str 'abc'", 'an array [1. 2.] of shape (2,)', 'inf')
    """
    if value is None:
        return "None"
    if isinstance(value, Real) and not isinstance(value, bool):
        return f"{float(value):g}"
    if isinstance(value, np.ndarray):
        text = f"an array {np.array2string(value, threshold=6)} of shape {value.shape}"
    else:
        kind = type(value).__name__
        text = f"{'an' if kind[:1] in 'aeiou' else 'a'} {kind} {value!r}"
    return text if len(text) <= limit else text[:limit - 3] + "..."


def number(x):
    """``x`` for a message: ``f"{x:g}"`` for a number, else its text (a traced symbol while a
    program is generated).

    Examples
    --------
    >>> from mbcomp.library.laws import number
    >>> number(0.30000000000000004), number("phi")
    ('0.3', 'phi')
    """
    try:
        return f"{float(x):g}"
    except (TypeError, ValueError):
        return str(x)


def as_number(val):
    """A law's result as one float, or ``nan`` when it is not one number (``None``, a string,
    a tuple or list, an array of more than one entry).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.laws import as_number
    >>> as_number(2), as_number(np.array([1.5])), as_number((1.0,)), as_number("1.0")
    (2.0, 1.5, nan, nan)
    """
    if val is None or isinstance(val, (str, bytes, tuple, list, dict, set)):
        return float("nan")
    try:
        arr = np.asarray(val, dtype=float)
    except (TypeError, ValueError):
        return float("nan")
    return float(arr.reshape(())) if arr.size == 1 else float("nan")


# Piecewise-linear helpers written with ``abs`` only, so a law using them traces into a
# generated program without a guard (a Python ``if`` on a traced value would not).
def pos(x):
    """``max(x, 0)``: exactly 0 for ``x <= 0``.

    Examples
    --------
    >>> pos(-2.0), pos(3.0), neg(-2.0), smin(1.0, 2.0), smax(1.0, 2.0)
    (0.0, 3.0, -2.0, 1.0, 2.0)
    """
    return 0.5 * (x + abs(x))


def neg(x):
    """``min(x, 0)``: exactly 0 for ``x >= 0``."""
    return 0.5 * (x - abs(x))


def smin(x, y):
    """``min(x, y)`` with ``abs`` only."""
    return 0.5 * (x + y - abs(x - y))


def smax(x, y):
    """``max(x, y)`` with ``abs`` only."""
    return 0.5 * (x + y + abs(x - y))
