"""The sympy-backed traced scalar of :func:`mbcomp.equations`, and exact numbers.

:class:`SymbolicScalar` follows mbcomp's tracing protocol (:mod:`mbcomp.assembly.jets`,
*Tracing*): the numeric code runs on numpy object arrays of them and builds sympy expressions.
A floating-point number meets the symbols as the exact rational of its shortest decimal form
(:func:`exact`: ``0.1`` -> ``1/10``).

Examples
--------
>>> import numpy as np, sympy as sp
>>> from mbcomp.codegen.sympy_scalar import SymbolicScalar, exact
>>> x = SymbolicScalar(sp.Symbol("x"))
>>> exact(np.sin(x) * 0.5 + 9.81)
sin(x)/2 + 981/100
"""
from __future__ import annotations

import contextvars
import math
from functools import lru_cache

import numpy as np
import sympy as sp

__all__ = ["SymbolicScalar", "exact", "traced_value", "traced_law", "UNIT_NORMS"]


@lru_cache(maxsize=4096)
def _exact_float(x: float):
    if not math.isfinite(x):
        raise ValueError(f"non-finite number {x!r} cannot be made exact")
    if x == int(x) and abs(x) < 2 ** 53:
        return sp.Integer(int(x))
    return sp.Rational(repr(x))


def exact(x):
    """``x`` as an exact sympy number or expression.

    Floats become the rational of their shortest decimal form (``0.1`` -> ``1/10``), integers
    sympy integers; sympy objects and :class:`SymbolicScalar` give their expression.

    Examples
    --------
    >>> from mbcomp.symbolic import exact
    >>> exact(0.1), exact(2.0), exact(9.81)
    (1/10, 2, 981/100)
    """
    if isinstance(x, SymbolicScalar):
        return x.expr
    if isinstance(x, sp.Basic):
        return x
    if isinstance(x, (bool, np.bool_)):
        return sp.Integer(int(x))
    if isinstance(x, (int, np.integer)):
        return sp.Integer(int(x))
    if isinstance(x, (float, np.floating)):
        return _exact_float(float(x))
    if isinstance(x, np.ndarray) and x.ndim == 0:
        return exact(x.item())
    raise TypeError(f"{x!r} ({type(x).__name__}) is not a number or a sympy expression")


_NUMBER = (int, float, np.integer, np.floating, sp.Basic)
# squared norms of quaternion coordinates taken as 1 during a trace (unit_quaternions=True)
UNIT_NORMS = contextvars.ContextVar("mbcomp_symbolic_unit_norms", default=frozenset())


def _operand(o):
    """The sympy expression of a binary operand, or ``None`` (-> ``NotImplemented``)."""
    if isinstance(o, SymbolicScalar):
        return o.expr
    if isinstance(o, _NUMBER):
        return exact(o)
    return None


class SymbolicScalar:
    """A traced scalar holding a sympy expression (see :mod:`mbcomp.jets`, *Tracing*).

    Arithmetic with numbers and other traced scalars builds sympy expressions; numbers are
    made exact with :func:`exact`. Operations with ``np.ndarray`` return ``NotImplemented`` so
    numpy applies them elementwise; numpy's object ufuncs call the methods ``cos``, ``sqrt``...

    Examples
    --------
    >>> import numpy as np, sympy as sp
    >>> from mbcomp.symbolic import SymbolicScalar
    >>> x = SymbolicScalar(sp.Symbol("x"))
    >>> v = np.array([x, 0.5]) * 2 + np.cos(x)
    >>> [sp.sympify(e.expr) for e in v]
    [2*x + cos(x), cos(x) + 1]
    """

    __slots__ = ("expr",)
    __mbcomp_traced__ = True

    def __init__(self, expr):
        self.expr = expr

    def __repr__(self):
        return f"SymbolicScalar({self.expr})"

    # -- arithmetic (NotImplemented for arrays: numpy broadcasts elementwise) --
    def __add__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(self.expr + e)

    def __radd__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(e + self.expr)

    def __sub__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(self.expr - e)

    def __rsub__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(e - self.expr)

    def __mul__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(self.expr * e)

    def __rmul__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(e * self.expr)

    def __truediv__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(self.expr / e)

    def __rtruediv__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(e / self.expr)

    def __pow__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(self.expr ** e)

    def __rpow__(self, o):
        e = _operand(o)
        return NotImplemented if e is None else SymbolicScalar(e ** self.expr)

    def __neg__(self):
        return SymbolicScalar(-self.expr)

    def __pos__(self):
        return self

    def __abs__(self):
        return SymbolicScalar(sp.Abs(self.expr))

    # -- what numpy's object-dtype ufuncs call --
    def cos(self):
        return SymbolicScalar(sp.cos(self.expr))

    def sin(self):
        return SymbolicScalar(sp.sin(self.expr))

    def tan(self):
        return SymbolicScalar(sp.tan(self.expr))

    def arccos(self):
        return SymbolicScalar(sp.acos(self.expr))

    def arcsin(self):
        return SymbolicScalar(sp.asin(self.expr))

    def arctan(self):
        return SymbolicScalar(sp.atan(self.expr))

    def arctan2(self, other):
        return SymbolicScalar(sp.atan2(self.expr, exact(other)))

    def sqrt(self):
        if self.expr in UNIT_NORMS.get():  # |Q| of a unit quaternion
            return SymbolicScalar(sp.Integer(1))
        return SymbolicScalar(sp.sqrt(self.expr))

    def exp(self):
        return SymbolicScalar(sp.exp(self.expr))

    def log(self):
        return SymbolicScalar(sp.log(self.expr))

    def sinh(self):
        return SymbolicScalar(sp.sinh(self.expr))

    def cosh(self):
        return SymbolicScalar(sp.cosh(self.expr))

    def tanh(self):
        return SymbolicScalar(sp.tanh(self.expr))

    def conjugate(self):
        return SymbolicScalar(sp.conjugate(self.expr))

    # -- no truth value; no __float__ either (float() and math.* then raise TypeError, and sympy's
    # sympify, which calls __float__ when it exists, does not mistake the scalar for a number) --
    def __bool__(self):
        raise TypeError(f"the traced value {self.expr} has no truth value: a comparison or branch on a "
                        "coordinate, speed or time cannot be traced -> write the law without branching")


def traced_value(value):
    """A parameter value for the traced run: sympy parts wrapped, numbers kept as they are."""
    if isinstance(value, SymbolicScalar):
        return value
    if isinstance(value, sp.MatrixBase):
        value = value.tolist()
    if isinstance(value, sp.Basic):
        return SymbolicScalar(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.array(value, dtype=object)
        if any(isinstance(x, (sp.Basic, SymbolicScalar)) for x in arr.flat):
            out = np.empty(arr.shape, dtype=object)
            for i, x in np.ndenumerate(arr):
                out[i] = traced_value(x)
            return out
        return np.array(value, dtype=float)
    return value


def traced_law(f):
    """A user's law whose results are wrapped (a law may return a plain sympy expression)."""
    def law(*args):
        return traced_value(f(*args))
    return law
