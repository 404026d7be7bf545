"""Generated straight-line programs: the assembled equations traced once, printed as Python or C.

:func:`compile_system` runs the *same* numeric :meth:`MultibodySystem.evaluate
<mbcomp.system.MultibodySystem.evaluate>` once on numpy object arrays whose elements are
:class:`Sym` tracer scalars. Every arithmetic operation becomes a node of a hash-consed
expression graph (a :class:`Graph`): equal ``(operation, operands)`` pairs are one node, which
is common-subexpression elimination for free, and ``x*0``, ``x*1``, ``x+0``, ``x-x`` and
operations on constants fold away, so the structural zeros of a planar mechanism or of a
sparse Jacobian cost nothing. The graph is then printed as a straight-line program:

* ``backend="python"`` (the default, needs no compiler): one Python function per program,
  scalars as local variables and ``math`` functions, compiled with :func:`compile`;
* ``backend="c"``: the same graph printed as C, compiled by the system compiler (``gcc``/``cc``,
  or ``$CC``) into a shared library cached on disk (``$MBCOMP_CACHE``, default
  ``~/.cache/mbcomp``; the key is a hash of the generated source), loaded with :mod:`ctypes`;
* ``backend="auto"``: C when a compiler is found, else Python.

What is a runtime argument and what is baked
--------------------------------------------
* Runtime arguments (``changing them re-derives nothing``): every nonzero number of a numeric
  parameter -- masses, inertia tensors, centres of mass, lengths (``FixedTranslation.r``),
  spring rates, damping coefficients, constant torques, gravity -- and ``q``, ``u``, ``t``.
  Nodes that depend on parameters only (e.g. ``m L^2 / 12`` or a normalized hinge axis) are
  hoisted into a small *parameter program* that runs once per parameter set.
* Drives (:class:`~mbcomp.roles.Drive`) are evaluated numerically at every call and their
  ``(s, v, a)`` enter the program as inputs, so any law works (strings, sympy, numpy or
  ``math`` callables).
* Baked (part of the program's structure): which parameter entries are exactly zero, laws
  given as callables (their expression is traced), and every decision a component took on a
  parameter value (``float(p.n)``, ``if p.d:``, ``abs(n[0]) < 0.9``): such decisions are
  recorded as *guards*. :meth:`CompiledSystem.with_params` reuses the program and only reruns
  the parameter program; if a new value changes the zero pattern, a law or violates a guard,
  the model is traced again (lazily, at the next evaluation) -- never silently wrong.
* Decisions on state values (``if x < 0`` in a force law) are guards checked inside the
  generated program; when one fails, or the program hits a domain error (``sqrt`` of a
  negative number, division by zero), that call falls back to the numeric evaluation, which
  gives exactly the numeric path's result or error (counted in ``stats["fallbacks"]``).

A component whose law cannot be traced (``math.sin`` or ``float()`` of a state value) makes
:func:`compile_system` raise :class:`CodegenError` naming the component and the fix.

Limits
------
* ``x*0 -> 0`` is folded although ``inf*0`` is ``nan``: a program differs from the numeric
  path only where the numeric path itself is already non-finite. Sums are reassociated so
  that parameter terms gather (``(x + p1) + p2 -> x + (p1 + p2)``) and signs move outwards
  (``(-a) b -> -(a b)``); results agree with the numeric path to rounding (1e-15 relative
  in ``M`` and ``f``).
* The program mirrors the numeric evaluation, whose mass matrix is the sum over bodies of
  ``J^T M_b J``: its size grows like ``N^3`` for an N-link chain (planar pendulum: about
  2,000 operations at N = 10, 930,000 at N = 100; 3-D chain: 45,000 at N = 10, 290,000 at
  N = 20). The Python program costs about 20 ns per operation, so it beats the vectorized
  numeric path up to roughly 10^5 operations; the C program (a few ns per operation) beyond.
  gcc needs about 1 s per 15,000 operations at ``-O0`` (used above 4,000 operations; ``-O1``
  below), once: the library is cached.
* A compiled system keeps work buffers: do not evaluate one instance from several threads.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen import compile_system
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> fast = compile_system(mbcomp.assemble(m))
>>> ev = fast.evaluate(0.0, np.array([0.5]), np.array([1.0]))
>>> round(float(ev.M[0, 0]), 12), round(float(ev.f[0]), 12)   # m l^2, -m g l sin(phi)
(2.0, -9.406329067414)
>>> heavy = fast.with_params({"bob.m": 3.0})                    # nothing re-derived
>>> round(float(heavy.evaluate(0.0, np.array([0.5]), np.array([1.0])).M[0, 0]), 12), heavy.stats["traces"]
(3.0, 1)
"""
from __future__ import annotations

import ctypes
import hashlib
import math
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
from types import SimpleNamespace

import numpy as np

from ..assembly.system import MultibodySystem

__all__ = ["compile_system", "CompiledSystem", "CompiledEvaluation", "CodegenError", "Sym", "Graph", "c_compiler"]

FIELDS = ("M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi")
_ROWS = ("Phi", "Phid", "C", "cb")  # holonomic rows: masked by the independent-row mask
_NUM = (int, float, np.number)
_INF = float("inf")


class CodegenError(RuntimeError):
    """A model (or one of its components) cannot be turned into a generated program.

    Examples
    --------
    >>> from mbcomp.codegen import CodegenError
    >>> isinstance(CodegenError("x"), RuntimeError)
    True
    """


class _Fallback(Exception):
    """A guard of the generated program failed: use the numeric evaluation for this call."""


class _Retrace(Exception):
    """A parameter guard failed: the program must be traced again."""


# ----------------------------------------------------------------------------------------------
# the expression graph
# ----------------------------------------------------------------------------------------------
_G = None  # the graph being built; tracing is single-threaded and not re-entrant


class Graph:
    """A hash-consed expression graph; ``with Graph() as g:`` makes it the one :class:`Sym`
    operations record into.

    Node ``i``'s key is ``(op, arg indices...)`` (``("c", value)`` for a constant, ``("in",
    kind, k)`` for an input); operands always have smaller indices, so index order is a
    topological order. :attr:`guards` holds the comparisons taken on traced values.

    Parameters
    ----------
    max_nodes : int
        Abort (``CodegenError``) when the graph grows beyond this many nodes.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen import Graph
    >>> with Graph() as g:
    ...     x = g.input("q", 0, 0.5)
    ...     y = np.cos(x) * x + 0 * x      # the "+ 0 * x" folds away
    ...     z = x * np.cos(x)              # the same node as cos(x) * x
    >>> y is z, len(g), round(y.v, 12)
    (True, 3, 0.438791280945)
    >>> print(g.python_source([y], "f"))
    def f(q, u, t, d, h):
        (q0,) = q[:1]
        x2 = q0 * (_cos(q0))
        return [x2]
    """

    __slots__ = ("keys", "nodes", "memo", "guards", "_guard_keys", "max_nodes", "baked", "_prev")

    def __init__(self, max_nodes=3_000_000):
        self.keys, self.nodes, self.memo = [], [], {}
        self.guards, self._guard_keys = [], set()
        self.baked = []  # param-only nodes converted to numbers (float(), int())
        self.max_nodes = int(max_nodes)

    def __len__(self):
        return len(self.keys)

    def __enter__(self):
        global _G
        self._prev, _G = _G, self
        return self

    def __exit__(self, *exc):
        global _G
        _G = self._prev

    def new(self, key, v, s):
        i = len(self.keys)
        if i >= self.max_nodes:
            raise CodegenError(f"the generated program exceeds max_nodes={self.max_nodes} operations; the "
                               "model is too large for code generation (use the numeric path, or raise max_nodes)")
        n = Sym(i, v, s)
        self.keys.append(key)
        self.nodes.append(n)
        self.memo[key] = n
        return n

    def input(self, kind, k, value, state=True):
        """A new input ``(kind, k)`` with trace-time value ``value``; ``state=False`` marks a
        parameter (nodes depending only on parameters are hoisted)."""
        return self.new(("in", kind, k), float(value), bool(state))

    def const(self, x):
        x = float(x)
        n = self.memo.get(("c", x))
        return n if n is not None else self.new(("c", x), x, False)

    def guard(self, op, a, b, result):
        key = (op, a.i, b.i, result)
        if key not in self._guard_keys:
            self._guard_keys.add(key)
            self.guards.append(key)

    def python_source(self, outputs, name="f"):
        """Python source of one function computing ``outputs`` (nodes or numbers) from the
        inputs ``q, u, t, d`` (lists) and no hoisting (for inspection and tests)."""
        prog = _Program(self, {"out": list(outputs)}, hoist=False)
        return prog.python_main("out", name)


def _mk(key, v, s):
    n = _G.memo.get(key)
    return n if n is not None else _G.new(key, v, s)


def _div(x, y):
    try:
        return x / y
    except ZeroDivisionError:
        return math.copysign(_INF, x) * math.copysign(1.0, y) if x else float("nan")


def _pow(x, y):
    try:
        return math.pow(x, y)
    except (ValueError, OverflowError):
        return float("nan")


def _safe(f, *a):
    try:
        return f(*a)
    except (ValueError, OverflowError):
        return float("nan")


def _split(n):
    """``(state part, parameter part)`` of a sum node (either None): sums that mix state and
    parameter terms are kept as ``state + params`` so parameter terms gather in hoisted nodes."""
    if not n.s:
        return None, n
    k = _G.keys[n.i]
    if k[0] == "+":
        x1, x2 = _G.nodes[k[1]], _G.nodes[k[2]]
        if x1.s != x2.s:
            return (x1, x2) if x1.s else (x2, x1)
    return n, None


def _join(S, P):
    """The node ``S + P`` of a pure state part and a parameter part (numbers allowed)."""
    if type(S) is not Sym:
        return P + S
    if type(P) is not Sym:
        if P == 0:
            return S
        P = _G.const(P)
    lo, hi = (S, P) if S.i < P.i else (P, S)
    return _mk(("+", lo.i, hi.i), S.v + P.v, True)


def _add(a, b):
    keys, nodes = _G.keys, _G.nodes
    ka, kb = keys[a.i][0], keys[b.i][0]
    if ka == "c" and kb == "c":
        return a.v + b.v
    if kb == "neg":  # a + (-c) -> a - c
        return _sub(a, nodes[keys[b.i][1]])
    if ka == "neg":
        return _sub(b, nodes[keys[a.i][1]])
    if a.s or b.s:
        sa, pa = _split(a)
        sb, pb = _split(b)
        if pa is not None or pb is not None:
            S = sb if sa is None else (sa if sb is None else _add(sa, sb))
            P = pb if pa is None else (pa if pb is None else pa + pb)
            return _join(S, P)
    if a.i > b.i:
        a, b = b, a
    return _mk(("+", a.i, b.i), a.v + b.v, a.s or b.s)


def _sub(a, b):
    if a is b:
        return 0.0
    keys, nodes = _G.keys, _G.nodes
    ka, kb = keys[a.i][0], keys[b.i][0]
    if ka == "c" and kb == "c":
        return a.v - b.v
    if kb == "neg":  # a - (-c) -> a + c
        return _add(a, nodes[keys[b.i][1]])
    if ka == "neg":  # (-a) - c -> -(a + c)
        return -(nodes[keys[a.i][1]] + b)
    if a.s or b.s:
        sa, pa = _split(a)
        sb, pb = _split(b)
        if (pa is not None or pb is not None) and sa is not None:
            S = sa if sb is None else _sub(sa, sb)
            P = -pb if pa is None else (pa if pb is None else pa - pb)
            return _join(S, P)
    return _mk(("-", a.i, b.i), a.v - b.v, a.s or b.s)


def _mul(a, b):
    keys = _G.keys
    ka, kb = keys[a.i], keys[b.i]
    if ka[0] == "c" and kb[0] == "c":
        return a.v * b.v
    if ka[0] == "neg":  # signs move outwards, where sums absorb them: (-a) b -> -(a b)
        return _G.nodes[ka[1]] * _G.nodes[kb[1]] if kb[0] == "neg" else -(_G.nodes[ka[1]] * b)
    if kb[0] == "neg":
        return -(a * _G.nodes[kb[1]])
    if a.i > b.i:
        a, b = b, a
    return _mk(("*", a.i, b.i), a.v * b.v, a.s or b.s)


def _neg(a):
    k = _G.keys[a.i]
    if k[0] == "neg":
        return _G.nodes[k[1]]
    if k[0] == "c":
        return -a.v
    if k[0] == "-":  # -(b - c) -> c - b
        return _sub(_G.nodes[k[2]], _G.nodes[k[1]])
    return _mk(("neg", a.i), -a.v, a.s)


def _un(op, f, a):
    return _mk((op, a.i), _safe(f, a.v), a.s)


def _bin(op, f, a, b):
    return _mk((op, a.i, b.i), f(a.v, b.v), a.s or b.s)


def _sym(b):
    """A Sym for the operand ``b`` (a Sym or a number), or None if ``b`` is neither."""
    if type(b) is Sym:
        return b
    if isinstance(b, _NUM) and not isinstance(b, (bool, np.bool_)):
        return _G.const(b)
    return None


class Sym:
    """A traced scalar: one node of the current :class:`Graph` with its trace-time value ``v``.

    Follows mbcomp's tracing protocol (:mod:`mbcomp.jets`, *Tracing*): arithmetic with numbers
    and other ``Sym`` on both sides, ``NotImplemented`` for numpy arrays (numpy then applies
    the operation elementwise), and the methods numpy's object ufuncs call (``cos``, ``sqrt``,
    ``arctan2``, ...). ``s`` is True when the value depends on the state (``q, u, t`` or a
    drive) and False for parameters and expressions of parameters.

    Converting a parameter-only value to a number (``float``, ``int``) or comparing it bakes
    the trace-time result into the program with a guard; doing so with a state value raises
    ``TypeError`` (``float``) or becomes a runtime guard (comparisons, ``bool``).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen import Graph
    >>> with Graph() as g:
    ...     a, b = g.input("q", 0, 3.0), g.input("q", 1, 4.0)
    ...     r = np.sqrt(a * a + b ** 2)
    >>> r.v, r.s
    (5.0, True)
    """

    __slots__ = ("i", "v", "s")
    __mbcomp_traced__ = True

    def __init__(self, i, v, s):
        self.i, self.v, self.s = i, v, s

    def __repr__(self):
        return f"<Sym #{self.i} {_G.keys[self.i][0] if _G is not None and self.i < len(_G.keys) else ''} = {self.v!r}>"

    # --- arithmetic -----------------------------------------------------------------------
    def __add__(a, b):
        if type(b) is Sym:
            return _add(a, b)
        if isinstance(b, _NUM):
            return a if b == 0 else _add(a, _G.const(b))
        return NotImplemented

    __radd__ = __add__

    def __sub__(a, b):
        if type(b) is Sym:
            return _sub(a, b)
        if isinstance(b, _NUM):
            return a if b == 0 else _sub(a, _G.const(b))
        return NotImplemented

    def __rsub__(a, b):
        if isinstance(b, _NUM):
            return _neg(a) if b == 0 else _sub(_G.const(b), a)
        return NotImplemented

    def __mul__(a, b):
        if type(b) is Sym:
            return _mul(a, b)
        if isinstance(b, _NUM):
            if b == 0:
                return 0.0
            if b == 1:
                return a
            if b == -1:
                return _neg(a)
            if b < 0:
                return -_mul(a, _G.const(-b))
            return _mul(a, _G.const(b))
        return NotImplemented

    __rmul__ = __mul__

    def __truediv__(a, b):
        if type(b) is Sym:
            ka, kb = _G.keys[a.i], _G.keys[b.i]
            if ka[0] == "neg" or kb[0] == "neg":  # signs move outwards
                na = _G.nodes[ka[1]] if ka[0] == "neg" else a
                nb = _G.nodes[kb[1]] if kb[0] == "neg" else b
                return na / nb if (ka[0] == "neg") == (kb[0] == "neg") else -(na / nb)
            return _bin("/", _div, a, b)
        if isinstance(b, _NUM):
            if b == 1:
                return a
            if b == -1:
                return _neg(a)
            return _bin("/", _div, a, _G.const(b))
        return NotImplemented

    def __rtruediv__(a, b):
        if isinstance(b, _NUM):
            return 0.0 if b == 0 else _bin("/", _div, _G.const(b), a)
        return NotImplemented

    def __pow__(a, b):
        if type(b) is Sym:
            return _bin("pow", _pow, a, b)
        if isinstance(b, _NUM):
            if b == 0:
                return 1.0
            if b == 1:
                return a
            if b == 2:
                return _mul(a, a)
            if b == 0.5:
                return a.sqrt()
            if b == -1:
                return 1.0 / a
            return _bin("pow", _pow, a, _G.const(b))
        return NotImplemented

    def __rpow__(a, b):
        if isinstance(b, _NUM):
            return 1.0 if b == 1 else _bin("pow", _pow, _G.const(b), a)
        return NotImplemented

    def __neg__(a):
        return _neg(a)

    def __pos__(a):
        return a

    def __abs__(a):
        return _un("abs", abs, a)

    # --- the methods numpy's object-dtype ufuncs call ---------------------------------------
    def cos(a):
        return _un("cos", math.cos, a)

    def sin(a):
        return _un("sin", math.sin, a)

    def tan(a):
        return _un("tan", math.tan, a)

    def arcsin(a):
        return _un("asin", math.asin, a)

    def arccos(a):
        return _un("acos", math.acos, a)

    def arctan(a):
        return _un("atan", math.atan, a)

    def sqrt(a):
        return _un("sqrt", math.sqrt, a)

    def exp(a):
        return _un("exp", math.exp, a)

    def log(a):
        return _un("log", math.log, a)

    def sinh(a):
        return _un("sinh", math.sinh, a)

    def cosh(a):
        return _un("cosh", math.cosh, a)

    def tanh(a):
        return _un("tanh", math.tanh, a)

    def absolute(a):
        return _un("abs", abs, a)

    def conjugate(a):
        return a

    def arctan2(a, b):
        b = _sym(b)
        if b is None:
            return NotImplemented
        return _bin("atan2", math.atan2, a, b)

    def hypot(a, b):
        b = _sym(b)
        if b is None:
            return NotImplemented
        return _bin("hypot", math.hypot, a, b)

    # --- decisions: guards ------------------------------------------------------------------
    def _cmp(a, op, b):
        bs = _sym(b)
        if bs is None:
            return NotImplemented
        res = bool(_CMP[op](a.v, bs.v))
        _G.guard(op, a, bs, res)
        return res

    def __lt__(a, b):
        return a._cmp("<", b)

    def __le__(a, b):
        return a._cmp("<=", b)

    def __gt__(a, b):
        return a._cmp(">", b)

    def __ge__(a, b):
        return a._cmp(">=", b)

    def __eq__(a, b):
        return a._cmp("==", b)

    def __ne__(a, b):
        return a._cmp("!=", b)

    __hash__ = object.__hash__

    def __bool__(a):
        return a._cmp("!=", 0.0)

    def __float__(a):
        if a.s:
            raise TypeError("a traced state-dependent value has no number: float(), math.* functions or float "
                            "arrays cannot be used on it in a generated program")
        _G.guard("==", a, _G.const(a.v), True)
        _G.baked.append(a.i)
        return a.v

    def __int__(a):
        return int(a.__float__())

    def __complex__(a):
        raise TypeError("a traced value cannot be converted to complex")


_CMP = {"<": float.__lt__, "<=": float.__le__, ">": float.__gt__, ">=": float.__ge__,
        "==": float.__eq__, "!=": float.__ne__}


# ----------------------------------------------------------------------------------------------
# programs: the part of the graph that computes a set of outputs, split into the parameter
# program (hoisted, runs once per parameter set) and the state programs
# ----------------------------------------------------------------------------------------------
_PY_UNARY = {"cos": "_cos", "sin": "_sin", "tan": "_tan", "asin": "_asin", "acos": "_acos", "atan": "_atan",
             "sqrt": "_sqrt", "exp": "_exp", "log": "_log", "sinh": "_sinh", "cosh": "_cosh", "tanh": "_tanh",
             "abs": "abs"}
_C_UNARY = {"cos": "cos", "sin": "sin", "tan": "tan", "asin": "asin", "acos": "acos", "atan": "atan",
            "sqrt": "sqrt", "exp": "exp", "log": "log", "sinh": "sinh", "cosh": "cosh", "tanh": "tanh",
            "abs": "fabs"}
_PY_ENV = {"_cos": math.cos, "_sin": math.sin, "_tan": math.tan, "_asin": math.asin, "_acos": math.acos,
           "_atan": math.atan, "_sqrt": math.sqrt, "_exp": math.exp, "_log": math.log, "_sinh": math.sinh,
           "_cosh": math.cosh, "_tanh": math.tanh, "_atan2": math.atan2, "_hypot": math.hypot, "_pow": math.pow,
           "_inf": _INF, "_nan": float("nan")}


def _py_num(x):
    x = float(x)
    if math.isnan(x):
        return "_nan"
    if math.isinf(x):
        return "_inf" if x > 0 else "(-_inf)"
    r = repr(x)
    return f"({r})" if x < 0 else r


def _c_num(x):
    x = float(x)
    if math.isnan(x):
        return "NAN"
    if math.isinf(x):
        return "INFINITY" if x > 0 else "(-INFINITY)"
    r = repr(x)
    return f"({r})" if x < 0 else r


def _expr(key, a, lang):
    """Expression of node ``key`` with operand names ``a``."""
    op = key[0]
    if op in ("+", "-", "*", "/"):
        return f"{a[0]} {op} {a[1]}"
    if op == "neg":
        return f"-{a[0]}"
    if op == "pow":
        return f"_pow({a[0]}, {a[1]})" if lang == "py" else f"pow({a[0]}, {a[1]})"
    if op == "atan2":
        return f"_atan2({a[0]}, {a[1]})" if lang == "py" else f"atan2({a[0]}, {a[1]})"
    if op == "hypot":
        return f"_hypot({a[0]}, {a[1]})" if lang == "py" else f"hypot({a[0]}, {a[1]})"
    table = _PY_UNARY if lang == "py" else _C_UNARY
    return f"{table[op]}({a[0]})"


class _Program:
    """Nodes needed for named output groups, split into hoisted parameter nodes and state nodes."""

    def __init__(self, g, groups, hoist=True, guard_groups=None):
        self.g, self.groups = g, groups
        keys, nodes = g.keys, g.nodes
        n = len(keys)
        need = bytearray(n)
        stack = []
        for outs in groups.values():
            stack.extend(o.i for o in outs if type(o) is Sym)
        for op, ai, bi, _ in g.guards:
            stack += [ai, bi]
        while stack:
            i = stack.pop()
            if need[i]:
                continue
            need[i] = 1
            k = keys[i]
            if k[0] not in ("c", "in"):
                stack.extend(k[1:])
        self.need = need
        # without hoisting every non-constant node belongs to the state programs
        state = [nd.s for nd in nodes] if hoist else [k[0] != "c" for k in keys]
        self.state = state
        # hoisted: parameter-only, non-constant nodes used by state nodes, state guards or outputs
        hoisted = set()
        if hoist:
            for i in range(n):
                if need[i] and state[i] and keys[i][0] != "in":
                    for j in keys[i][1:]:
                        if not state[j] and keys[j][0] != "c":
                            hoisted.add(j)
            for outs in groups.values():
                hoisted.update(o.i for o in outs if type(o) is Sym and not o.s)
            for op, ai, bi, _ in g.guards:
                if state[ai] or state[bi]:
                    hoisted.update(j for j in (ai, bi) if not state[j] and keys[j][0] != "c")
        self.hoisted = sorted(hoisted)
        self.hname = {i: f"h{k}" for k, i in enumerate(self.hoisted)}
        self.hidx = {i: k for k, i in enumerate(self.hoisted)}
        self.param_guards = [gd for gd in g.guards if not (state[gd[1]] or state[gd[2]])]
        self.state_guards = [gd for gd in g.guards if state[gd[1]] or state[gd[2]]]
        # which state guards each program checks (the decisions taken while tracing it)
        gg = guard_groups or {name: g.guards for name in groups}
        self.guards_of = {name: [gd for gd in gg.get(name, ()) if state[gd[1]] or state[gd[2]]] for name in groups}
        # parameter inputs in the order of their input index
        self.params = sorted((keys[i][2], i) for i in range(n) if keys[i][0] == "in" and keys[i][1] == "p")

    # --- per-group state nodes ---------------------------------------------------------------
    def group_nodes(self, name):
        """State nodes (indices, topological order) needed by output group ``name`` and guards."""
        keys, state, hname = self.g.keys, self.state, self.hname
        seen = set()
        stack = [o.i for o in self.groups[name] if type(o) is Sym]
        for op, ai, bi, _ in self.guards_of[name]:
            stack += [ai, bi]
        while stack:
            i = stack.pop()
            if i in seen or not state[i] or i in hname:
                continue
            seen.add(i)
            k = keys[i]
            if k[0] != "in":
                stack.extend(k[1:])
        return sorted(seen)

    def n_ops(self, name):
        keys = self.g.keys
        return sum(1 for i in self.group_nodes(name) if keys[i][0] != "in")

    def pre_nodes(self):
        keys, state = self.g.keys, self.state
        seen = set()
        stack = list(self.hoisted)
        for op, ai, bi, _ in self.param_guards:
            stack += [ai, bi]
        while stack:
            i = stack.pop()
            if i in seen or state[i]:
                continue
            seen.add(i)
            k = keys[i]
            if k[0] not in ("c", "in"):
                stack.extend(k[1:])
        return sorted(i for i in seen if keys[i][0] != "c")

    # --- naming ------------------------------------------------------------------------------
    def _name(self, i, lang, inner):
        """Name of node ``i`` inside a state program (``inner``) or the parameter program."""
        k = self.g.keys[i]
        if inner and i in self.hname:
            return self.hname[i] if lang == "py" else f"h[{self.hidx[i]}]"
        if k[0] == "c":
            return (_py_num if lang == "py" else _c_num)(k[1])
        if k[0] == "in":
            kind, j = k[1], k[2]
            if kind == "t":
                return "t"
            if kind == "p":
                return f"p{j}" if lang == "py" or not inner else f"p[{j}]"
            if lang == "py" or kind not in ("q", "u", "d"):
                return f"{kind}{j}"
            return f"{kind}[{j}]"
        return f"x{i}"

    def _out_name(self, o, lang, inner=True):
        if type(o) is Sym:
            return self._name(o.i, lang, inner)
        return (_py_num if lang == "py" else _c_num)(o)

    # --- Python ------------------------------------------------------------------------------
    def python_main(self, group, fname):
        keys = self.g.keys
        nodes = self.group_nodes(group)
        lines = [f"def {fname}(q, u, t, d, h):"]
        for kind, src in (("q", "q"), ("u", "u"), ("d", "d"), ("p", "h")):
            idx = sorted(keys[i][2] for i in nodes if keys[i][0] == "in" and keys[i][1] == kind)
            if idx:  # parameters appear here only without hoisting: then they come in h
                width = max(idx) + 1
                lines.append(f"    ({', '.join(f'{kind}{j}' for j in range(width))},) = {src}[:{width}]")
        if self.hoisted:
            lines.append(f"    ({', '.join(self.hname[i] for i in self.hoisted)},) = h")
        guards = self._guards_by_node(self.guards_of[group])
        # single-use temporaries are inlined into their one consumer (fewer loads and stores)
        uses = {}
        for i in nodes:
            for j in keys[i][1:] if keys[i][0] != "in" else ():
                uses[j] = uses.get(j, 0) + 1
        for o in self.groups[group]:
            if type(o) is Sym:
                uses[o.i] = uses.get(o.i, 2) + 2
        for gd in self.guards_of[group]:
            for j in gd[1:3]:
                uses[j] = uses.get(j, 0) + 2
        inl, depth = {}, {}
        for i in nodes:
            k = keys[i]
            if k[0] == "in":
                continue
            ops = []
            dep = 0
            for j in k[1:]:
                if j in inl:
                    ops.append(f"({inl.pop(j)})")
                    dep = max(dep, depth[j])
                else:
                    ops.append(self._name(j, "py", True))
            e = _expr(k, ops, "py")
            if uses.get(i, 0) == 1 and dep < 6:
                inl[i], depth[i] = e, dep + 1
            else:
                lines.append(f"    x{i} = {e}")
            for gd in guards.get(i, ()):
                lines.append("    " + self._guard_line(gd, "py", True))
        for gd in guards.get(-1, ()):
            lines.append("    " + self._guard_line(gd, "py", True))
        outs = ", ".join(self._out_name(o, "py") for o in self.groups[group])
        lines.append(f"    return [{outs}]")
        return "\n".join(lines)

    def _guards_by_node(self, guards):
        """Guards keyed by the later of their operands (emitted right after it is computed)."""
        keys, state, hname, out = self.g.keys, self.state, self.hname, {}
        for gd in guards:  # -1: both operands are inputs, constants or hoisted (checked at the end)
            last = max((j for j in gd[1:3] if state[j] and keys[j][0] not in ("c", "in") and j not in hname),
                       default=-1)
            out.setdefault(last, []).append(gd)
        return out

    def _guard_line(self, gd, lang, inner):
        op, ai, bi, res = gd
        a, b = self._name(ai, lang, inner), self._name(bi, lang, inner)
        cond = f"{a} {op} {b}"
        if lang == "py":
            exc = "_Fallback" if inner else "_Retrace"
            return f"if {'not ' if res else ''}({cond}): raise {exc}"
        return f"if ({'!' if res else ''}({cond})) return 1;"

    # --- C -----------------------------------------------------------------------------------
    def c_function(self, group, fname, chunk=2000):
        """C source of ``int fname(q, u, t, d, h, w, out)``: 0 on success, 1 if a guard failed.
        Values crossing chunk boundaries live in the work array ``w``."""
        keys = self.g.keys
        nodes = [i for i in self.group_nodes(group) if keys[i][0] != "in"]
        outs = self.groups[group]
        where_out = {}
        tail = []
        node_set = set(nodes)
        for k, o in enumerate(outs):
            if type(o) is Sym and o.i in node_set:
                where_out.setdefault(o.i, []).append(k)
            else:
                tail.append((k, o))
        chunks = [nodes[s: s + chunk] for s in range(0, len(nodes), chunk)] or [[]]
        chunk_of = {}
        for c, ch in enumerate(chunks):
            for i in ch:
                chunk_of[i] = c
        guards = self._guards_by_node(self.guards_of[group])
        slot = {}
        for c, ch in enumerate(chunks):
            for i in ch:
                for j in keys[i][1:]:
                    if j in chunk_of and chunk_of[j] != c and j not in slot:
                        slot[j] = len(slot)
        sig = ("const double *restrict q, const double *restrict u, double t, const double *restrict d, "
               "const double *restrict h, const double *restrict p, double *restrict w, double *restrict out")
        src = []

        def name(j, c):
            if j in chunk_of:
                return f"x{j}" if chunk_of[j] == c else f"w[{slot[j]}]"
            return self._name(j, "c", True)

        for c, ch in enumerate(chunks):
            body = []
            for i in ch:
                k = keys[i]
                body.append(f"    const double x{i} = {_expr(k, [name(j, c) for j in k[1:]], 'c')};")
                if i in slot:
                    body.append(f"    w[{slot[i]}] = x{i};")
                for ko in where_out.get(i, ()):
                    body.append(f"    out[{ko}] = x{i};")
                for gd in guards.get(i, ()):
                    op, ai, bi, res = gd
                    cond = f"{name(ai, c)} {op} {name(bi, c)}"
                    body.append(f"    if ({'!' if res else ''}({cond})) return 1;")
            src.append(f"static int {fname}_{c}({sig})\n{{\n" + "\n".join(body) + "\n    return 0;\n}\n")
        tail_lines = [f"    out[{k}] = {self._out_name(o, 'c')};" for k, o in tail]
        for gd in guards.get(-1, ()):
            op, ai, bi, res = gd
            cond = f"{self._name(ai, 'c', True)} {op} {self._name(bi, 'c', True)}"
            tail_lines.append(f"    if ({'!' if res else ''}({cond})) return 1;")
        calls = "\n".join(f"    if ({fname}_{c}(q, u, t, d, h, p, w, out)) return 1;" for c in range(len(chunks)))
        src.append(f"int {fname}({sig})\n{{\n{calls}\n" + "\n".join(tail_lines) + "\n    return 0;\n}\n")
        return "\n".join(src), len(slot)


class _ParamProgram:
    """The hoisted parameter program, interpreted with the tracer's own arithmetic: it runs once
    per parameter set (no compilation), and for the traced values it reproduces the trace-time
    values bit for bit. Raises ``_Retrace`` when a parameter guard fails."""

    _BIN = {"+": float.__add__, "-": float.__sub__, "*": float.__mul__, "/": _div, "pow": _pow,
            "atan2": math.atan2, "hypot": math.hypot}
    _UN = {"neg": float.__neg__, "abs": abs, "cos": math.cos, "sin": math.sin, "tan": math.tan, "asin": math.asin,
           "acos": math.acos, "atan": math.atan, "sqrt": math.sqrt, "exp": math.exp, "log": math.log,
           "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh}

    def __init__(self, prog):
        g = prog.g
        keys = g.keys
        self.order = [(i, keys[i]) for i in prog.pre_nodes() if keys[i][0] != "in"]
        self.params = prog.params
        self.guards = prog.param_guards
        self.hoisted = prog.hoisted
        self.shadow = [g.nodes[i].v for i in prog.hoisted]
        used = {j for _, k in self.order for j in k[1:]} | {j for gd in self.guards for j in gd[1:3]}
        self.consts = {j: keys[j][1] for j in used if keys[j][0] == "c"}

    def __len__(self):
        return len(self.order)

    def run(self, pv):
        val = dict(self.consts)
        for j, i in self.params:
            val[i] = pv[j]
        BIN, UN = self._BIN, self._UN
        for i, k in self.order:
            if len(k) == 3:
                val[i] = BIN[k[0]](val[k[1]], val[k[2]])
            else:
                val[i] = _safe(UN[k[0]], val[k[1]])
        for op, ai, bi, res in self.guards:
            if bool(_CMP[op](val[ai], val[bi])) != res:
                raise _Retrace
        return [val[i] for i in self.hoisted]


# ----------------------------------------------------------------------------------------------
# tracing a system
# ----------------------------------------------------------------------------------------------
class _DriveInputs:
    """Stands in for a drive while tracing: its motion is three program inputs."""

    def __init__(self, comp, sva):
        self._comp, self._sva = comp, sva

    def motion(self, t, p):
        return self._sva

    def __getattr__(self, name):
        return getattr(self._comp, name)


def _law_key(v):
    try:
        hash(v)
        return ("v", v)
    except TypeError:
        return ("id", id(v))


def _param_layout(system):
    """Which parameter entries are runtime inputs, and the structural signature of the rest.

    Returns ``(layout, signature)``: ``layout`` lists ``(path, name, index)`` of every nonzero
    numeric parameter entry (``index`` None for scalars); ``signature`` is hashable and
    changes when anything baked into a program changes (zero pattern, shapes, laws)."""
    owners = system.owners()
    drives = {e.drive for e in system.topology.tree if e.drive}  # evaluated numerically at every call
    layout, sig = [], []
    for path in sorted(system.P):
        if path in drives:
            continue
        comp = owners[path]
        decl = comp.params()
        for name, val in sorted(vars(system.P[path]).items()):
            par = decl.get(name)
            kind = par.kind if par is not None else "number"
            if kind == "start":
                continue
            if isinstance(val, (float, np.floating)) and kind in ("number", "law"):
                if val != 0:
                    layout.append((path, name, None))
                sig.append((path, name, "s", val != 0))
            elif isinstance(val, np.ndarray) and val.dtype.kind == "f" and kind in ("number", "law"):
                nz = val != 0
                layout.extend((path, name, idx) for idx in zip(*np.nonzero(nz)))
                sig.append((path, name, "a", val.shape, nz.tobytes()))
            else:
                sig.append((path, name, "o", _law_key(val)))
    return layout, tuple(sig)


def _param_vector(system, layout):
    P = system.P
    return [float(getattr(P[path], name)) if idx is None else float(getattr(P[path], name)[idx])
            for path, name, idx in layout]


def _drive_edges(system):
    return [(e, e.drive) for e in system.topology.tree if e.drive]


def _trace_point(system):
    """A generic state for the trace-time values: the start coordinates, nonzero speeds."""
    q = system.normalize(system.default_q())
    k = np.arange(system.nu)
    u = 0.3 * np.sin(1.7 * k + 0.4) + 0.05
    return 0.1234, q, u


def _component_of(exc):
    """The innermost component whose method raised ``exc`` (from the traceback), or None."""
    from ..modeling.component import Component

    tb, found = exc.__traceback__, None
    while tb is not None:
        obj = tb.tb_frame.f_locals.get("self")
        if isinstance(obj, (Component, _DriveInputs)):
            found = obj
        tb = tb.tb_next
    return found


def _where(exc):
    tb = exc.__traceback__
    last = None
    while tb is not None:
        if tb.tb_frame.f_code.co_filename != __file__:
            last = tb
        tb = tb.tb_next
    if last is None:
        return "?"
    co = last.tb_frame.f_code
    return f"{pathlib.Path(co.co_filename).name}:{last.tb_lineno} in {co.co_name}"


def _trace(system, max_nodes):
    """Trace ``system.evaluate`` and the coordinate rates; returns a namespace with the graph,
    the output groups, shapes, the parameter layout and the drive order."""
    from ..modeling.roles import Joint

    topo = system.topology
    layout, sig = _param_layout(system)
    owners = system.owners()
    t0, q0, u0 = _trace_point(system)
    g = Graph(max_nodes)
    with g:
        P = {}
        pindex = {key: k for k, key in enumerate(layout)}
        for path, ns in system.P.items():
            vals = dict(vars(ns))
            decl = owners[path].params()
            for name, val in vals.items():
                par = decl.get(name)
                kind = par.kind if par is not None else "number"
                if kind not in ("number", "law"):
                    continue
                if isinstance(val, (float, np.floating)) and val != 0:
                    vals[name] = g.input("p", pindex[(path, name, None)], val, state=False)
                elif isinstance(val, np.ndarray) and val.dtype.kind == "f":
                    arr = np.zeros(val.shape, dtype=object)
                    arr[...] = 0.0
                    for idx in zip(*np.nonzero(val)):
                        arr[idx] = g.input("p", pindex[(path, name, idx)], val[idx], state=False)
                    vals[name] = arr
            P[path] = SimpleNamespace(**vals)
        # drives: their (s, v, a) are inputs
        drives = []
        comps = dict(topo.flat.components)
        for e, dname in _drive_edges(system):
            if dname in [d for d, _ in drives]:
                continue
            k = len(drives)
            s, v, a = system.topology.flat.components[dname].motion(t0, system.P[dname])
            sva = (g.input("d", 3 * k, s), g.input("d", 3 * k + 1, v), g.input("d", 3 * k + 2, a))
            comps[dname] = _DriveInputs(comps[dname], sva)
            drives.append((dname, sva))
        flat = SimpleNamespace(**vars(topo.flat))
        flat.components = comps
        topo2 = SimpleNamespace(**vars(topo))
        topo2.flat = flat
        ts = MultibodySystem.__new__(MultibodySystem)
        ts.__dict__.update({k: v for k, v in vars(system).items() if not k.startswith("_cg")})
        ts.topology, ts.P, ts.row_mask = topo2, P, None
        if topo.gravity_source:
            gv = owners[topo.gravity_source].gravity(P[topo.gravity_source])
            ts.g = np.zeros(3) if gv is None else np.asarray(gv)
        q = np.array([g.input("q", k, v) for k, v in enumerate(q0)] + [None], dtype=object)[:-1]
        u = np.array([g.input("u", k, v) for k, v in enumerate(u0)] + [None], dtype=object)[:-1]
        t = g.input("t", 0, t0)
        try:
            ev = ts.evaluate(t, q, u, masked=False)
            n_guards_eval = len(g.guards)
            qd = np.zeros(system.nq, dtype=object)
            for e in topo.tree:
                if e.q.stop > e.q.start:
                    if type(e.comp).q_rate is Joint.q_rate:
                        qd[e.q] = u[e.u]
                    else:
                        qd[e.q] = e.comp.q_rate(q[e.q], u[e.u], P[e.name])
        except CodegenError:
            raise
        except Exception as exc:
            comp = _component_of(exc)
            if isinstance(comp, _DriveInputs):
                comp = comp._comp
            fix = ("write its laws with numpy functions (np.sin, np.sqrt, ...) and plain arithmetic instead of "
                   "math.* or float(), or keep the numeric evaluation for this model (do not compile it)")
            if comp is not None:
                raise CodegenError(f"cannot generate a program for component {comp.path!r} "
                                   f"({type(comp).__name__}): {type(exc).__name__}: {exc} (at {_where(exc)}) "
                                   f"-> fix: {fix}") from exc
            raise CodegenError(f"cannot trace the model's evaluation ({type(exc).__name__}: {exc} at "
                               f"{_where(exc)}) -> fix: {fix}") from exc
    shapes, outs = {}, []
    for name in FIELDS:
        arr = np.asarray(getattr(ev, name))
        shapes[name] = arr.shape
        outs.extend(arr.ravel().tolist())
    qd = qd.tolist()
    baked = _baked_names(g, layout)
    return SimpleNamespace(graph=g, groups={"eval": outs, "qrate": qd}, shapes=shapes, layout=layout,
                           guard_groups={"eval": g.guards[:n_guards_eval], "qrate": g.guards[n_guards_eval:]},
                           signature=sig, drives=[d for d, _ in drives], baked=baked,
                           qrate_identity=_is_identity(g, qd, system))


def _is_identity(g, qd, system):
    if system.nq != system.nu:
        return False
    for k, o in enumerate(qd):
        if type(o) is not Sym or g.keys[o.i] != ("in", "u", k):
            return False
    return True


def _baked_names(g, layout):
    """Names of the runtime parameters whose values a component converted to numbers."""
    keys, names = g.keys, set()
    stack, seen = list(g.baked), set()
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        k = keys[i]
        if k[0] == "in":
            if k[1] == "p":
                path, name, idx = layout[k[2]]
                names.add(f"{path}.{name}")
        elif k[0] != "c":
            stack.extend(k[1:])
    return sorted(names)


# ----------------------------------------------------------------------------------------------
# compilers
# ----------------------------------------------------------------------------------------------
def c_compiler():
    """Path of the C compiler used by ``backend="c"`` (``$CC``, else ``gcc``, else ``cc``), or None.

    Examples
    --------
    >>> from mbcomp.codegen import c_compiler
    >>> c_compiler() is None or isinstance(c_compiler(), str)
    True
    """
    for cand in (os.environ.get("CC"), "gcc", "cc"):
        if cand:
            path = shutil.which(cand)
            if path:
                return path
    return None


def _cache_dir(cache_dir=None):
    d = cache_dir or os.environ.get("MBCOMP_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "mbcomp")
    os.makedirs(d, exist_ok=True)
    return d


class _Code:
    """A traced model turned into callables (shared by systems differing only in parameter values)."""

    def __init__(self, tr, backend, cache_dir=None):
        t0 = time.perf_counter()
        self.layout, self.signature, self.drives = tr.layout, tr.signature, tr.drives
        self.shapes, self.baked, self.qrate_identity = tr.shapes, tr.baked, tr.qrate_identity
        off, self.slices, self.layout_out = 0, {}, []
        for name in FIELDS:
            shape = self.shapes[name]
            n = int(np.prod(shape, dtype=int))
            self.slices[name] = (off, off + n, shape)
            empty = None
            if n == 0:  # one shared read-only empty array instead of a view per call
                empty = np.zeros(shape)
                empty.setflags(write=False)
            self.layout_out.append((name, off, off + n, shape if len(shape) > 1 else None, empty))
            off += n
        self.n_out = off
        prog = _Program(tr.graph, tr.groups, guard_groups=tr.guard_groups)
        self.n_ops = prog.n_ops("eval")
        self.n_ops_qrate = 0 if tr.qrate_identity else prog.n_ops("qrate")
        self.n_hoisted = len(prog.hoisted)
        self.n_guards = (len(prog.param_guards), len(prog.state_guards))
        self.n_nodes = len(tr.graph)
        env = dict(_PY_ENV, _Fallback=_Fallback, _Retrace=_Retrace)
        self.pre = _ParamProgram(prog)
        self.n_ops_params = len(self.pre)
        self.backend = backend
        self.cache = None
        self.nq = len(tr.groups["qrate"])
        if backend == "python":
            src = prog.python_main("eval", "main") + "\n\n" + prog.python_main("qrate", "qrate")
            exec(compile(src, "<mbcomp.codegen program>", "exec"), env)
            self.main, self.qrate = env["main"], env["qrate"]
            self.source = src
        else:
            self._build_c(prog, cache_dir)
            self.source = self.c_source
        self.compile_time = time.perf_counter() - t0

    def _build_c(self, prog, cache_dir):
        cc = c_compiler()
        if cc is None:
            raise CodegenError("backend='c' needs a C compiler (gcc or cc on PATH, or $CC) -> fix: install one, "
                               "or use backend='python' (no compiler needed) or backend='auto'")
        # gcc's optimizer is superlinear in function size: small programs get -O1, large ones
        # -O0 in chunks of 5000 statements (compiles ~5x faster; the program is still a few
        # ns per operation, far below the Python overhead around it)
        small = self.n_ops + self.n_ops_qrate <= 4000
        opt, chunk = ("-O1", 2000) if small else ("-O0", 5000)
        ev_src, n_w1 = prog.c_function("eval", "mbcomp_eval", chunk)
        qr_src, n_w2 = prog.c_function("qrate", "mbcomp_qrate", chunk)
        src = ("/* generated by mbcomp.codegen; do not edit */\n#include <math.h>\n\n" + ev_src + "\n" + qr_src)
        self.c_source = src
        flags = [opt, "-shared", "-fPIC", "-fno-fast-math"]
        key = hashlib.sha256((src + "\0" + " ".join(flags) + "\0" + cc + "\0" + sys.platform).encode()).hexdigest()[:32]
        d = _cache_dir(cache_dir)
        lib = os.path.join(d, f"mbcomp_{key}.so")
        if os.path.exists(lib):
            self.cache = "hit"
        else:
            self.cache = "miss"
            with tempfile.TemporaryDirectory(dir=d) as tmp:
                cpath = os.path.join(tmp, "prog.c")
                with open(cpath, "w") as fh:
                    fh.write(src)
                out = os.path.join(tmp, "prog.so")
                res = subprocess.run([cc, *flags, "-o", out, cpath, "-lm"], capture_output=True, text=True)
                if res.returncode != 0:
                    raise CodegenError(f"the C compiler failed ({cc}): {res.stderr[-2000:]} -> fix: use backend='python'")
                os.replace(out, lib)
        self.lib_path = lib
        self.dll = ctypes.CDLL(lib)
        argt = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p,
                ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
        for fn in (self.dll.mbcomp_eval, self.dll.mbcomp_qrate):
            fn.argtypes = argt
            fn.restype = ctypes.c_int
        self.n_work = max(n_w1, n_w2, 1)


class _Bound:
    """A :class:`_Code` bound to one parameter set (hoisted values, buffers)."""

    def __init__(self, code, system, first=False):
        self.code = code
        pv = _param_vector(system, code.layout)
        self.pv = pv
        # the traced values themselves: the trace-time values; new ones: the parameter program
        # (which raises _Retrace when a parameter guard fails)
        self.h = list(code.pre.shadow) if first else code.pre.run(pv)
        self.drive_comps = [(system.topology.flat.components[d], system.P[d]) for d in code.drives]
        if code.backend == "c":
            self.hbuf = np.array(self.h + [0.0], float)
            self.pbuf = np.array(pv + [0.0], float)
            self.qbuf = np.zeros(max(system.nq, 1))
            self.ubuf = np.zeros(max(system.nu, 1))
            self.dbuf = np.zeros(max(3 * len(code.drives), 1))
            self.wbuf = np.zeros(code.n_work)
            self.obuf = np.zeros(max(code.n_out, 1))
            self.qdbuf = np.zeros(max(system.nq, 1))
            self.ptrs = [a.ctypes.data for a in (self.qbuf, self.ubuf, self.dbuf, self.hbuf, self.pbuf, self.wbuf,
                                                 self.obuf, self.qdbuf)]

    def drive_values(self, t):
        d = []
        for comp, p in self.drive_comps:
            d.extend(comp.motion(t, p))
        return d

    def run(self, t, q, u):
        code = self.code
        if code.backend == "python":
            return np.array(code.main(q.tolist(), u.tolist(), float(t), self.drive_values(t) if self.drive_comps else (),
                                      self.h), float)
        self.qbuf[: q.size] = q
        self.ubuf[: u.size] = u
        if self.drive_comps:
            self.dbuf[: 3 * len(self.drive_comps)] = self.drive_values(t)
        pq, pu, pd, ph, pp, pw, po, _ = self.ptrs
        if code.dll.mbcomp_eval(pq, pu, float(t), pd, ph, pp, pw, po):
            raise _Fallback
        return self.obuf[: code.n_out].copy()

    def run_qrate(self, q, u):
        code = self.code
        if code.backend == "python":
            return np.array(code.qrate(q.tolist(), u.tolist(), 0.0, (), self.h), float)
        self.qbuf[: q.size] = q
        self.ubuf[: u.size] = u
        pq, pu, pd, ph, pp, pw, _, pqd = self.ptrs
        if code.dll.mbcomp_qrate(pq, pu, 0.0, pd, ph, pp, pw, pqd):
            raise _Fallback
        return self.qdbuf[: code.nq].copy()


# ----------------------------------------------------------------------------------------------
# the compiled system
# ----------------------------------------------------------------------------------------------
class CompiledEvaluation:
    """The generated program's result at one ``(t, q, u)``: the attributes of
    :class:`mbcomp.system.Evaluation` that formulations use.

    ``M, f, Phi, Phid, C, cb, B, b, Bb, Psi`` and ``A`` come from the program (holonomic rows
    masked like the numeric evaluation); ``jets``, ``local`` and ``local_nh`` (needed for
    reactions and post-processing only) are computed numerically on first access.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import compile_system
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> ev = compile_system(mbcomp.assemble(m)).evaluate(0.0, np.zeros(1), np.zeros(1))
    >>> ev.M.tolist(), ev.f.tolist(), ev.A.shape
    ([[2.0]], [-19.62], (0, 1))
    """

    __slots__ = ("t", "q", "u", "M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi", "_sys", "_masked", "_num")

    def __init__(self, system, t, q, u, flat, masked, slices, mask):
        self.t, self.q, self.u = t, q, u
        for name, a, b, shape, empty in slices:
            setattr(self, name, empty if empty is not None else flat[a:b] if shape is None else flat[a:b].reshape(shape))
        if masked and mask is not None:
            self.Phi, self.Phid, self.C, self.cb = self.Phi[mask], self.Phid[mask], self.C[mask], self.cb[mask]
        self._sys, self._masked, self._num = system, masked, None

    @property
    def A(self):
        """All constraint rows acting on du/dt: holonomic ``C`` then nonholonomic ``B``."""
        return np.vstack((self.C, self.B)) if self.B.size else self.C

    def numeric(self):
        """The numeric :class:`~mbcomp.system.Evaluation` at the same point (computed once)."""
        if self._num is None:
            self._num = MultibodySystem.evaluate(self._sys, self.t, self.q, self.u, self._masked)
        return self._num

    @property
    def jets(self):
        return self.numeric().jets

    @property
    def local(self):
        return self.numeric().local

    @property
    def local_nh(self):
        return self.numeric().local_nh


class CompiledSystem(MultibodySystem):
    """A :class:`~mbcomp.system.MultibodySystem` whose ``evaluate`` and ``q_rate`` run a
    generated program; everything else (initialization helpers, reactions, energies) is the
    numeric system's. Accepted wherever a system is: ``LagrangeIndex1``, ``DAlembert``,
    :func:`mbcomp.simulate`.

    Build it with :func:`compile_system`. ``stats`` holds the build statistics: ``n_ops``
    (operations of the evaluation program), ``n_ops_qrate``, ``n_ops_params`` (the hoisted
    parameter program), ``n_params`` (runtime parameter entries), ``n_guards``,
    ``baked`` (parameters a component turned into numbers), ``trace_time``, ``compile_time``
    (s), ``cache`` (C: ``"hit"``/``"miss"``), ``traces`` and ``fallbacks``.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import compile_system
    >>> from mbcomp.formulations import LagrangeIndex1
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> s = mbcomp.assemble(m); fast = compile_system(s)
    >>> y = np.array([0.5, 0.0])
    >>> bool(np.allclose(LagrangeIndex1(fast).fun(0.0, y), LagrangeIndex1(s).fun(0.0, y), rtol=1e-12))
    True
    >>> res = mbcomp.simulate(fast, t_end=0.5)
    >>> res.status
    'success'
    """

    def __init__(self, system, backend="python", *, cache_dir=None, verify=True, max_nodes=3_000_000, _code=None):
        if not isinstance(system, MultibodySystem):
            raise TypeError(f"compile_system needs an assembled system (mbcomp.assemble(model)), not {type(system).__name__}")
        self.__dict__.update({k: v for k, v in vars(system).items() if not k.startswith("_cg")})
        if backend == "auto":
            backend = "c" if c_compiler() else "python"
        if backend not in ("python", "c"):
            raise ValueError(f"backend {backend!r} is unknown; use 'python', 'c' or 'auto'")
        self._cg_opts = dict(backend=backend, cache_dir=cache_dir, verify=verify, max_nodes=max_nodes)
        self._cg_bound = None
        self.stats = dict(backend=backend, traces=0, fallbacks=0)
        if _code is not None:
            self.stats["traces"] = _code.traces
            if _param_layout(self)[1] == _code.signature:
                try:
                    self._cg_bound = _Bound(_code, self)
                    self._record(_code)
                except _Retrace:
                    self._cg_bound = None
            return  # otherwise traced again lazily at the first evaluation
        self._build()

    # --- building ----------------------------------------------------------------------------
    def _build(self):
        o = self._cg_opts
        t0 = time.perf_counter()
        tr = _trace(self, o["max_nodes"])
        trace_time = time.perf_counter() - t0
        code = _Code(tr, o["backend"], o["cache_dir"])
        code.trace_time = trace_time
        code.traces = self.stats.get("traces", 0) + 1
        self._cg_bound = _Bound(code, self, first=True)
        self._record(code)
        if o["verify"]:
            self._verify(tr)
        return self._cg_bound

    def _record(self, code):
        self.stats.update(n_ops=code.n_ops, n_ops_qrate=code.n_ops_qrate, n_ops_params=code.n_ops_params,
                          n_hoisted=code.n_hoisted, n_nodes=code.n_nodes, n_params=len(code.layout),
                          n_guards=code.n_guards, baked=list(code.baked), trace_time=code.trace_time,
                          compile_time=code.compile_time, cache=code.cache, traces=code.traces)

    def _verify(self, tr):
        t, q, u = _trace_point(self)
        num = MultibodySystem.evaluate(self, t, q, u, masked=False)
        try:
            flat = self._cg_bound.run(t, q, u)
        except _Fallback:
            return  # a state guard rejects the trace point itself (e.g. a piecewise law at zero)
        code = self._cg_bound.code
        for name in FIELDS:
            a, b, shape = code.slices[name]
            ref = np.asarray(getattr(num, name), float)
            err = np.max(np.abs(flat[a:b].reshape(shape) - ref), initial=0.0)
            if not err <= 1e-9 * (1.0 + np.max(np.abs(ref), initial=0.0)):
                raise CodegenError(f"internal error: the generated program differs from the numeric evaluation in "
                                   f"{name} by {err:.3g}; please report this model (use the numeric path meanwhile)")
        qd = self._cg_bound.run_qrate(q, u)
        if not np.allclose(qd, MultibodySystem.q_rate(self, q, u), rtol=1e-9, atol=1e-12):
            raise CodegenError("internal error: the generated coordinate rates differ from the numeric ones")

    def _bound(self):
        if self._cg_bound is None:
            self._build()
        return self._cg_bound

    # --- the system interface -------------------------------------------------------------------
    def evaluate(self, t, q, u, masked=True):
        """Mass matrix, forces and constraints at ``(t, q, u)`` from the generated program (see
        :class:`CompiledEvaluation`); a failed guard falls back to the numeric evaluation."""
        bound = self._cg_bound or self._bound()
        if type(q) is not np.ndarray or type(u) is not np.ndarray:
            q, u = np.asarray(q), np.asarray(u)
        if q.dtype == object or u.dtype == object:  # traced by someone else (e.g. symbolic): numeric path
            return MultibodySystem.evaluate(self, t, q, u, masked)
        try:
            flat = bound.run(t, q, u)
        except (_Fallback, ArithmeticError, ValueError):
            self.stats["fallbacks"] += 1
            return MultibodySystem.evaluate(self, t, q, u, masked)
        mask = self.row_mask if masked and self.row_mask is not None and not self.row_mask.all() else None
        return CompiledEvaluation(self, t, q, u, flat, masked, bound.code.layout_out, mask)

    def q_rate(self, q, u):
        """``dq/dt`` from the speeds (generated program; a copy of ``u`` for angle coordinates)."""
        bound = self._cg_bound or self._bound()
        if bound.code.qrate_identity:
            return np.array(u, dtype=float)
        try:
            return bound.run_qrate(q, u)
        except (_Fallback, ArithmeticError, ValueError):
            self.stats["fallbacks"] += 1
            return MultibodySystem.q_rate(self, q, u)

    def with_params(self, params):
        """A compiled system with new parameter values: the program is reused (only the hoisted
        parameter program runs again) unless the change alters what is baked into it (a zero
        pattern, a law, a guarded decision); then it is traced again at the first evaluation."""
        base = MultibodySystem.with_params(self, params)
        code = self._cg_bound.code if self._cg_bound is not None else None
        opts = self._cg_opts
        return CompiledSystem(base, opts["backend"], cache_dir=opts["cache_dir"], verify=opts["verify"],
                              max_nodes=opts["max_nodes"], _code=code)

    @property
    def source(self):
        """The generated source (Python: parameter program and programs; C: the C file)."""
        return self._bound().code.source


def compile_system(system, backend="python", *, cache_dir=None, verify=True, max_nodes=3_000_000):
    """Trace an assembled system once and return a :class:`CompiledSystem` running the
    generated program.

    Parameters
    ----------
    system : MultibodySystem
        From :func:`mbcomp.assemble` (initialized or not; the row mask is applied at run time).
    backend : {"python", "c", "auto"}
        ``"python"`` (default, no compiler), ``"c"`` (system C compiler, cached shared
        library; :class:`CodegenError` without a compiler) or ``"auto"`` (C if available).
    cache_dir : str, optional
        Where compiled libraries are cached (default ``$MBCOMP_CACHE`` or ``~/.cache/mbcomp``).
    verify : bool
        Compare the program with the numeric evaluation at one generic state after building.
    max_nodes : int
        Give up (``CodegenError``) when the expression graph exceeds this many nodes.

    Returns
    -------
    CompiledSystem

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import compile_system
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=2.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> fast = compile_system(mbcomp.assemble(m))
    >>> fast.stats["n_ops"] > 0, fast.stats["n_params"]   # hinge axis z, rod y, bob mass, gravity y
    (True, 4)
    """
    return CompiledSystem(system, backend, cache_dir=cache_dir, verify=verify, max_nodes=max_nodes)
