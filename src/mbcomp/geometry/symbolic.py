"""Numbers or sympy: which arithmetic a function of the geometry toolkit computes with.

:mod:`~mbcomp.geometry.rotations` and :mod:`~mbcomp.geometry.relative_motion` work on floats
and on sympy objects alike: when any argument holds a sympy object (a symbol, an expression,
an exact number such as ``sympy.pi / 3``, a ``sympy.Matrix``) they compute with sympy and
return ``sympy.Matrix`` objects (vectors as 3 x 1 columns), otherwise with floats and numpy
arrays. The choice and the constructors of either kind live here. sympy is imported on the
symbolic path only (:func:`sympy_module`), so the numeric path stays light and fast.

Examples
--------
>>> import sympy as sp
>>> from mbcomp.geometry.symbolic import as_vector, is_symbolic
>>> is_symbolic(1.0, [2.0, 3.0]), is_symbolic(1.0, [sp.Symbol("a"), 3.0])
(False, True)
>>> as_vector([1, 2, 3], False).tolist(), as_vector([1, 2, 3], True).T
([1.0, 2.0, 3.0], Matrix([[1, 2, 3]]))
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["is_symbolic", "sympy_module", "cos_sin", "as_matrix", "elements", "as_vector"]


def is_symbolic(*args) -> bool:
    """True when any argument (or element of a list/tuple/object array) is a sympy object."""
    for a in args:
        if any((cls.__module__ or "").startswith("sympy") for cls in type(a).__mro__):
            return True  # (the MRO also covers sympy's dynamically created function classes)
        if isinstance(a, (list, tuple)) and is_symbolic(*a):
            return True
        if isinstance(a, np.ndarray) and a.dtype == object and is_symbolic(*a.ravel()):
            return True
    return False


def sympy_module():
    """The ``sympy`` module, imported on first use (the symbolic path only)."""
    import sympy
    return sympy


def cos_sin(sym):
    """``(cos, sin)``: sympy's for ``sym``, else ``math``'s."""
    if sym:
        sp = sympy_module()
        return sp.cos, sp.sin
    return math.cos, math.sin


def as_matrix(rows, sym):
    """``rows`` as a ``sympy.Matrix`` (``sym``) or a float array."""
    return sympy_module().Matrix(rows) if sym else np.array(rows, dtype=float)


def elements(v):
    """Elements of a list, tuple, array or sympy Matrix, flattened."""
    return list(np.asarray(v, dtype=object).ravel())


def as_vector(v, sym):
    """3-vector as a sympy column (``sym``) or a float array of shape (3,)."""
    if sym:
        return sympy_module().Matrix(elements(v))
    return np.asarray(v, dtype=float).reshape(3)
