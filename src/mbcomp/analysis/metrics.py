"""Metrics written as text: ``"peak=max(abs(pin.f.y))"`` -> a picklable function of a Result.

The command line's ``mbcomp study --metric NAME=EXPR`` (and anyone who wants a metric that
travels to any executor) parses a small expression language into :class:`Metric`, a
module-level class holding the parsed tree -- it pickles for a process pool and for Dask.
The text is parsed by :mod:`ast` and checked node by node; nothing is ever ``eval``-ed.

The language:

* a column of the :class:`~mbcomp.simulation.result.Result`: any dotted name present in it
  (``pin.f.y``, ``crank_joint.phi``, ``energy.total``, an alias such as ``crank_angle``,
  ``time``), or any name in quotes (``"my-column"``);
* numbers, ``+ - * / **`` and unary minus, element by element;
* element-wise functions ``abs``, ``sqrt``;
* reductions to one number: ``max``, ``min``, ``mean``, ``std``, ``rms``, ``first``,
  ``last`` (the value at ``t_end``), ``range`` (max - min), ``at(column, t)`` (linear
  interpolation at time ``t``, s).

A metric must give one number. A column the result does not have makes the metric fail in
that run's row, with a message naming the column and the similar ones.

Examples
--------
>>> import numpy as np
>>> from mbcomp.simulation.result import Result
>>> from mbcomp.analysis.metrics import Metric, parse_metric
>>> res = Result(np.array([0.0, 1.0, 2.0]), {"pin.f.y": np.array([1.0, -3.0, 2.0])})
>>> name, peak = parse_metric("peak=max(abs(pin.f.y))")
>>> name, peak(res), Metric("last(pin.f.y) - first(pin.f.y)")(res), Metric("at(pin.f.y, 0.5)")(res)
('peak', 3.0, 1.0, -1.0)
>>> Metric("max(pin.f.z)")(res)
Traceback (most recent call last):
...
mbcomp.analysis.metrics.MetricError: max(pin.f.z): the result has no column 'pin.f.z'; similar: pin.f.y -> fix: use one of the result's columns (mbcomp simulate MODEL.py --out x.csv lists them)
"""
from __future__ import annotations

import ast
import difflib
import operator

import numpy as np

__all__ = ["Metric", "MetricError", "parse_metric", "FUNCTIONS"]


class MetricError(ValueError):
    """A metric that cannot be parsed, or cannot be evaluated on a result."""


def _rms(x):
    return np.sqrt(np.mean(np.square(x)))


def _at(x, t, *, time):
    return np.interp(t, time, x)


#: name -> (function, number of arguments, what it does)
FUNCTIONS = {
    "abs": (np.abs, 1, "absolute value, element-wise"),
    "sqrt": (np.sqrt, 1, "square root, element-wise"),
    "max": (np.max, 1, "largest value"),
    "min": (np.min, 1, "smallest value"),
    "mean": (np.mean, 1, "mean over the output points"),
    "std": (np.std, 1, "standard deviation over the output points"),
    "rms": (_rms, 1, "root mean square"),
    "first": (lambda x: np.asarray(x)[0], 1, "value at the start"),
    "last": (lambda x: np.asarray(x)[-1], 1, "value at the end (t_end, or where the run stopped)"),
    "range": (np.ptp, 1, "max - min"),
    "at": (_at, 2, "at(column, t): the value at time t (s), linearly interpolated"),
}

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.Pow: operator.pow}
_ALLOWED = ("numbers, column names (dotted, e.g. pin.f.y, or quoted), + - * / **, and the functions "
            + ", ".join(FUNCTIONS))


def _dotted(node):
    """``pin.f.y`` from its ``Attribute`` chain, or ``None`` if it is not a plain dotted name."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return ".".join([node.id] + parts[::-1])


def _tree(node, text):
    """The checked tree of an ``ast`` node: tuples ``("num", v)``, ``("col", name)``,
    ``("call", fname, args)``, ``("bin", op, a, b)``, ``("neg", a)``."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return ("num", float(node.value))
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return ("col", node.value)
    if isinstance(node, (ast.Name, ast.Attribute)):
        name = _dotted(node)
        if name is not None:
            return ("col", name)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _tree(node.operand, text)
        return ("neg", inner) if isinstance(node.op, ast.USub) else inner
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        return ("bin", type(node.op).__name__, _tree(node.left, text), _tree(node.right, text))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        fname = node.func.id
        if fname not in FUNCTIONS:
            close = difflib.get_close_matches(fname, FUNCTIONS, n=2)
            raise MetricError(f"{text}: no function {fname!r}" + (f" (did you mean {' or '.join(close)}?)" if close
                              else "") + f"; the functions are {', '.join(FUNCTIONS)}")
        nargs = FUNCTIONS[fname][1]
        if len(node.args) != nargs:
            raise MetricError(f"{text}: {fname}() takes {nargs} argument{'s' if nargs > 1 else ''}, "
                              f"got {len(node.args)} ({FUNCTIONS[fname][2]})")
        return ("call", fname, tuple(_tree(a, text) for a in node.args))
    what = ast.get_source_segment(text, node) or type(node).__name__
    raise MetricError(f"{text}: {what!r} is not allowed in a metric -> write it with {_ALLOWED}")


class Metric:
    """A metric parsed from text: ``Metric("max(abs(pin.f.y))")(result) -> float``.

    Parameters
    ----------
    text : str
        The expression (module notes).

    Raises
    ------
    MetricError
        At parsing: text that is not an expression of the language (the message says what
        is allowed); at evaluation: a column the result lacks (naming the similar ones), or
        an expression giving more than one number.

    Examples
    --------
    >>> import pickle, numpy as np
    >>> from mbcomp.simulation.result import Result
    >>> m = pickle.loads(pickle.dumps(Metric("mean(a.w) * 2")))
    >>> m(Result(np.array([0.0, 1.0]), {"a.w": np.array([1.0, 2.0])}))
    3.0
    """

    def __init__(self, text):
        self.text = str(text).strip()
        try:
            node = ast.parse(self.text, mode="eval").body
        except SyntaxError as exc:
            raise MetricError(f"{self.text!r} is not an expression ({exc.msg}) -> write it with {_ALLOWED}, "
                              "e.g. max(abs(pin.f.y))") from None
        self.tree = _tree(node, self.text)

    def __repr__(self):
        return f"Metric({self.text!r})"

    def __call__(self, res):
        value = np.asarray(self._eval(self.tree, res), dtype=float)
        if value.size != 1:
            raise MetricError(f"{self.text}: gives {value.size} values, not one -> reduce it with max, min, mean, "
                              "last, ... e.g. max(abs(...))")
        return float(value.reshape(()))

    def _eval(self, node, res):
        kind = node[0]
        if kind == "num":
            return node[1]
        if kind == "col":
            return self._column(node[1], res)
        if kind == "neg":
            return -self._eval(node[1], res)
        if kind == "bin":
            op = {cls.__name__: fn for cls, fn in _BINARY.items()}[node[1]]
            return op(self._eval(node[2], res), self._eval(node[3], res))
        fn = FUNCTIONS[node[1]][0]
        args = [self._eval(a, res) for a in node[2]]
        if node[1] == "at":
            return fn(*args, time=res.time)
        return fn(*args)

    def _column(self, name, res):
        if name == "time":
            return np.asarray(res.time, float)
        if name in res:
            return np.asarray(res[name], float)
        close = difflib.get_close_matches(name, list(res.names) + ["time"], n=4, cutoff=0.6)
        raise MetricError(f"{self.text}: the result has no column {name!r}"
                          + (f"; similar: {', '.join(close)}" if close else "")
                          + " -> fix: use one of the result's columns (mbcomp simulate MODEL.py --out x.csv lists them)")


def parse_metric(spec):
    """``"NAME=EXPR"`` -> ``(name, Metric(EXPR))`` (a bare ``EXPR`` is named by its text).

    Examples
    --------
    >>> from mbcomp.analysis.metrics import parse_metric
    >>> parse_metric("final=last(crank_joint.phi)")
    ('final', Metric('last(crank_joint.phi)'))
    """
    text = str(spec).strip()
    name, sep, expr = text.partition("=")
    if not sep:
        return text, Metric(text)
    name = name.strip()
    if not name or not expr.strip() or " " in name:
        raise MetricError(f"--metric {text!r}: write NAME=EXPR, e.g. peak=max(abs(pin.f.y))")
    return name, Metric(expr)
