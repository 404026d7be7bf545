"""The expression graph of a generated program: :class:`Sym` tracer scalars recording into a
hash-consed :class:`Graph`.

Every arithmetic operation on a :class:`Sym` becomes a node of the current graph: equal
``(operation, operands)`` pairs are one node, which is common-subexpression elimination for
free, and ``x*0``, ``x*1``, ``x+0``, ``x-x`` and operations on constants fold away, so the
structural zeros of a planar mechanism or of a sparse Jacobian cost nothing. Sums are
reassociated so that parameter terms gather (``(x + p1) + p2 -> x + (p1 + p2)``) and signs
move outwards (``(-a) b -> -(a b)``). Decisions taken on traced values (comparisons,
``bool``, ``float`` of a parameter) are recorded as *guards*.

Examples
--------
>>> import numpy as np
>>> from mbcomp.codegen.graph import Graph
>>> with Graph() as g:
...     x = g.input("q", 0, 2.0)
...     y = x * x + 0 * x              # 0 * x and + 0 fold away
...     same = y is x * x              # one node per (operation, operands)
>>> len(g), y.v, same
(2, 4.0, True)
"""
from __future__ import annotations

import contextlib
import gc
import math

import numpy as np

from .ieee import COMPARE, call_or_nan, div, power

__all__ = ["CodegenError", "Fallback", "Retrace", "Graph", "Sym"]

_NUM = (int, float, np.number)


class CodegenError(RuntimeError):
    """A model (or one of its components) cannot be turned into a generated program.

    Examples
    --------
    >>> from mbcomp.codegen import CodegenError
    >>> isinstance(CodegenError("x"), RuntimeError)
    True
    """


class Fallback(Exception):
    """A guard of the generated program failed: use the numeric evaluation for this call."""


class Retrace(Exception):
    """A parameter guard failed: the program must be traced again."""


@contextlib.contextmanager
def no_gc():
    """The cyclic garbage collector paused (restored on exit): building and printing a graph of
    millions of nodes allocates many objects and makes no cycles that matter meanwhile."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _law_site(law_codes, depth=60):
    """``(law, file, line)`` of the innermost frame of the calling stack that runs a law's code
    (``law_codes``: code object -> law name), or None: where a law took a decision."""
    import inspect  # only a model with laws asks (a new guard while tracing): not at every import

    f = inspect.currentframe().f_back.f_back
    for _ in range(depth):
        if f is None:
            return None
        law = law_codes.get(f.f_code)
        if law is not None:
            return law, f.f_code.co_filename, f.f_lineno
        f = f.f_back
    return None


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
    """

    __slots__ = ("keys", "nodes", "memo", "guards", "_guard_keys", "max_nodes", "baked", "_prev", "_gc", "law_codes",
                 "guard_sites")

    def __init__(self, max_nodes=3_000_000):
        self.keys, self.nodes, self.memo = [], [], {}
        self.guards, self._guard_keys = [], set()
        self.baked = []  # param-only nodes converted to numbers (float(), int())
        self.max_nodes = int(max_nodes)
        #: code object of a law (a callable parameter, or code defined inside one) -> its name
        #: (``"component.param"``), set by the tracer: a guard taken inside one is a law's branch
        self.law_codes = {}
        #: guard -> ``(law, file, line)`` for the guards a law's own code took (:meth:`guard`)
        self.guard_sites = {}

    def __len__(self):
        return len(self.keys)

    def __enter__(self):
        global _G
        self._prev, _G = _G, self
        # the collector would walk the growing graph again and again (a quarter of the
        # tracing time); nothing traced makes reference cycles that must go before the end
        self._gc = gc.isenabled()
        gc.disable()
        return self

    def __exit__(self, *exc):
        global _G
        _G = self._prev
        if self._gc:
            gc.enable()

    def new(self, key, v, s):
        i = len(self.keys)
        if i >= self.max_nodes:
            _too_big(self.max_nodes)
        n = _new_sym(Sym)
        n.i, n.v, n.s = i, v, s
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
        """Record the decision ``a op b == result`` taken on traced values (once)."""
        key = (op, a.i, b.i, result)
        if key not in self._guard_keys:
            self._guard_keys.add(key)
            self.guards.append(key)
            if self.law_codes:
                site = _law_site(self.law_codes)
                if site is not None:
                    self.guard_sites[key] = site

    def drop_guards(self, n):
        """Forget the guards recorded after the first ``n`` (those of a branch of the trace
        that was abandoned: its program is not made)."""
        for key in self.guards[n:]:
            self._guard_keys.discard(key)
        del self.guards[n:]


def _too_big(max_nodes):
    raise CodegenError(f"the generated program exceeds max_nodes={max_nodes} operations; the "
                       "model is too large for code generation (use the numeric path, or raise max_nodes)")


def _mk(key, v, s):
    g = _G
    n = g.memo.get(key)
    if n is None:  # Graph.new, inlined: the hot path of tracing
        keys = g.keys
        i = len(keys)
        if i >= g.max_nodes:
            _too_big(g.max_nodes)
        n = _new_sym(Sym)
        n.i, n.v, n.s = i, v, s
        keys.append(key)
        g.nodes.append(n)
        g.memo[key] = n
    return n


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
    return _mk((op, a.i), call_or_nan(f, a.v), a.s)


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
            return _bin("/", div, a, b)
        if isinstance(b, _NUM):
            if b == 1:
                return a
            if b == -1:
                return _neg(a)
            return _bin("/", div, a, _G.const(b))
        return NotImplemented

    def __rtruediv__(a, b):
        if isinstance(b, _NUM):
            return 0.0 if b == 0 else _bin("/", div, _G.const(b), a)
        return NotImplemented

    def __pow__(a, b):
        if type(b) is Sym:
            return _bin("pow", power, a, b)
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
            return _bin("pow", power, a, _G.const(b))
        return NotImplemented

    def __rpow__(a, b):
        if isinstance(b, _NUM):
            return 1.0 if b == 1 else _bin("pow", power, _G.const(b), a)
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
        res = bool(COMPARE[op](a.v, bs.v))
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


_new_sym = object.__new__
