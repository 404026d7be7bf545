"""The float arithmetic of traced values: Python's float operations, with the IEEE results
(``inf``, ``nan``) where Python raises.

A generated C program divides by zero into ``inf`` and takes ``sqrt(-1)`` into ``nan``;
Python's ``float`` raises ``ZeroDivisionError`` or ``ValueError`` instead. The trace-time
values (:mod:`mbcomp.codegen.graph`) and the interpreted parameter program
(:class:`mbcomp.codegen.printers.ParamProgram`) compute with the functions here, so that
they give the values the C program gives, bit for bit; the callers then check for
non-finite values where a domain error matters.

Examples
--------
>>> from mbcomp.codegen.ieee import COMPARE, call_or_nan, div, power
>>> import math
>>> div(1.0, 0.0), div(-1.0, 0.0), power(-8.0, 1 / 3), call_or_nan(math.sqrt, -1.0)
(inf, -inf, nan, nan)
>>> COMPARE["<="](1.0, 2.0)
True
"""
from __future__ import annotations

import math

__all__ = ["INF", "COMPARE", "div", "power", "call_or_nan"]

INF = float("inf")
#: the comparisons a traced decision may take, by the operator's text in the program
COMPARE = {"<": float.__lt__, "<=": float.__le__, ">": float.__gt__, ">=": float.__ge__,
           "==": float.__eq__, "!=": float.__ne__}


def div(x, y):
    """``x / y``; division by zero gives ``+-inf`` (sign of ``x`` times sign of ``y``) or
    ``nan`` for ``0 / 0``, as in C."""
    try:
        return x / y
    except ZeroDivisionError:
        return math.copysign(INF, x) * math.copysign(1.0, y) if x else float("nan")


def power(x, y):
    """``math.pow(x, y)``; ``nan`` where it raises (a negative base to a fractional power,
    an overflow)."""
    try:
        return math.pow(x, y)
    except (ValueError, OverflowError):
        return float("nan")


def call_or_nan(f, *a):
    """``f(*a)`` for a ``math`` function ``f``; ``nan`` where it raises (outside its domain,
    an overflow)."""
    try:
        return f(*a)
    except (ValueError, OverflowError):
        return float("nan")
