"""A traced graph made again with its inputs moved: ``x -> x + eps c`` (:func:`replay`).

Differentiated with respect to the new ``eps`` inputs alone
(:func:`mbcomp.codegen.tangent.tangent`), the replayed outputs give Jacobian-vector products:
one forward sweep per direction instead of one per input. Used for the evaluation along a
direction (:mod:`mbcomp.codegen.eval_tangent`) and the sensitivities' right-hand side
``f_y S + f_p`` (:mod:`mbcomp.codegen.sensitivity`).

Examples
--------
>>> import numpy as np
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.replay import replay
>>> from mbcomp.codegen.tangent import tangent
>>> with Graph() as g:
...     x = g.input("q", 0, 2.0)
...     f = x * x * x
>>> def shift(g2):                      # q -> q + eps * 5
...     eps = g2.input("d", 0, 0.0)
...     return {("q", 0): lambda node: node + eps * 5.0}, eps
>>> g2, (f2,), eps = replay(g, [f], shift)
>>> (d,), = tangent(g2, [f2], [eps])
>>> float(d.v)                          # 3 x^2 * 5 at x = 2
60.0
"""
from __future__ import annotations

from .graph import Graph, Sym
from .tangent import cone

__all__ = ["replay"]


#: the graph's functions by the :class:`~mbcomp.codegen.graph.Sym` method that makes them
_METHOD = {"cos": "cos", "sin": "sin", "tan": "tan", "asin": "arcsin", "acos": "arccos", "atan": "arctan",
           "sqrt": "sqrt", "exp": "exp", "log": "log", "sinh": "sinh", "cosh": "cosh", "tanh": "tanh",
           "atan2": "arctan2", "hypot": "hypot"}


def _apply(g, op, args):
    """Node ``op(args)`` made again in the current graph ``g`` (operands Sym or numbers)."""
    a = args[0]
    if op == "+":
        return a + args[1]
    if op == "-":
        return a - args[1]
    if op == "*":
        return a * args[1]
    if op == "/":
        return a / args[1]
    if op == "pow":
        return a ** args[1]
    if op == "neg":
        return -a
    if op == "abs":
        return abs(a)
    if op not in _METHOD:
        raise ValueError(f"replay: the graph has an operation {op!r} this module cannot replay")
    a = a if type(a) is Sym else g.const(a)
    return getattr(a, _METHOD[op])(*args[1:])


def replay(g, outputs, shift):
    """``outputs`` of graph ``g`` (and its guards) made again in a new graph whose state inputs
    are moved along a direction: ``shift(g2)`` returns ``(moved, eps)``, ``moved[(kind, k)]``
    the function taking the new input node to its replacement (``q_k + eps dq_k``).
    Differentiated with respect to ``eps`` alone, the outputs give a Jacobian-vector product:
    one forward sweep for one direction instead of one per input. Returns ``(g2, outputs2, eps)``."""
    keys, nodes = g.keys, g.nodes
    seen = cone(keys, [o.i for o in outputs if type(o) is Sym] + [j for gd in g.guards for j in gd[1:3]])
    g2 = Graph(g.max_nodes)
    new = {}
    with g2:
        moved, eps = shift(g2)
        for i in seen:
            key = keys[i]
            if key[0] == "c":
                new[i] = float(key[1])
            elif key[0] == "in":
                x = g2.memo.get(key) or g2.input(key[1], key[2], nodes[i].v, state=nodes[i].s)
                new[i] = moved[key[1:]](x) if key[1:] in moved else x
            else:
                new[i] = _apply(g2, key[0], [new[j] for j in key[1:]])
        for op, ai, bi, res in g.guards:
            a, b = (new[j] if type(new[j]) is Sym else g2.const(new[j]) for j in (ai, bi))
            g2.guard(op, a, b, res)
    return g2, [new[o.i] if type(o) is Sym else o for o in outputs], eps
