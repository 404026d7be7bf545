"""Forward-mode (tangent) differentiation of a traced :class:`~mbcomp.codegen.graph.Graph`.

:func:`tangent` builds, in the same graph and with the same :class:`~mbcomp.codegen.graph.Sym`
operations, the nodes of ``d outputs / d inputs`` by the chain rule over every node between
the inputs and the outputs, so the existing printers (:mod:`mbcomp.codegen.printers`) print
the derivative program to Python and C unchanged, with the graph's common-subexpression
elimination and folding: a derivative that is structurally zero stays the number ``0.0``
(``x*0`` folds), and a derivative shares the nodes of the value it differentiates.

Each operation's local partial derivatives (:data:`OPERATIONS` lists the operations the graph
has) are expressions of its operands and its own node:

========  ====================================  ========  =========================
op        partials                              op        partials
========  ====================================  ========  =========================
``+``     ``1, 1``                              ``sqrt``  ``1 / (2 r)``
``-``     ``1, -1``                             ``exp``   ``r``
``*``     ``b, a``                              ``log``   ``1 / a``
``/``     ``1 / b, -r / b``                     ``sinh``  ``cosh a``
``neg``   ``-1``                                ``cosh``  ``sinh a``
``pow``   ``b a^(b-1), r log a``                ``tanh``  ``1 - r^2``
``abs``   ``a / r``                             ``sin``   ``cos a``
``cos``   ``-sin a``                            ``tan``   ``1 + r^2``
``asin``  ``1 / sqrt(1 - a^2)``                 ``acos``  ``-1 / sqrt(1 - a^2)``
``atan``  ``1 / (1 + a^2)``                     ``atan2`` ``x / (x^2+y^2), -y / (x^2+y^2)``
``hypot`` ``a / r, b / r``
========  ====================================  ========  =========================

(``r`` is the node itself.) The ``log a`` partial of ``pow`` is made only when the exponent
depends on an input. Comparisons are not nodes but *guards* on the trace's branch: within the
branch a program takes, a decision is constant, so it contributes nothing to the derivative
(the derivative program must check the value program's guards: it is exact in that branch).
Where a partial is not finite (``abs`` or ``hypot`` at exactly zero, ``sqrt`` at zero) the
derivative program computes a NaN: its caller must treat a non-finite result as "no exact
derivative here".

Examples
--------
>>> import numpy as np
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.tangent import tangent
>>> with Graph() as g:
...     x, y = g.input("q", 0, 0.5), g.input("u", 0, 2.0)
...     f = [np.sin(x) * y, y * y, 3.0]
>>> J = tangent(g, f, [x, y])
>>> [[round(float(getattr(d, "v", d)), 12) for d in row] for row in J]
[[1.755165123781, 0.479425538604], [0.0, 4.0], [0.0, 0.0]]
>>> J[1][0], J[2][1]          # structural zeros are the number 0.0, no node
(0.0, 0.0)
"""
from __future__ import annotations

import numpy as np

from .graph import Sym

__all__ = ["OPERATIONS", "cone", "input_positions", "partials", "tangent"]

#: every operation a graph node may have (``"c"``: constant, ``"in"``: input)
OPERATIONS = ("c", "in", "+", "-", "*", "/", "neg", "pow", "abs", "cos", "sin", "tan", "asin", "acos", "atan",
              "sqrt", "exp", "log", "sinh", "cosh", "tanh", "atan2", "hypot")


def _partials(op, r, a, b, need_b):
    """The local partial derivatives of node ``r = op(a[, b])`` with respect to its operands
    (Sym or numbers); ``need_b``: whether the second operand's partial is needed."""
    if op == "+":
        return 1.0, 1.0
    if op == "-":
        return 1.0, -1.0
    if op == "*":
        return b, a
    if op == "/":
        return 1.0 / b, -r / b
    if op == "neg":
        return (-1.0,)
    if op == "pow":
        return b * a ** (b - 1.0), (r * np.log(a) if need_b else 0.0)
    if op == "atan2":  # r = atan2(a, b): a is y, b is x
        rr = a * a + b * b
        return b / rr, -a / rr
    if op == "hypot":
        return a / r, b / r
    return (_UNARY[op](r, a),)


def partials(graph, i, need_b=True):
    """The local partial derivatives of node ``i`` of ``graph`` with respect to its operands,
    built with the same operations as the node; call it with ``graph`` current (inside
    ``with graph:``, where the new nodes go).

    The table in the module notes; reverse accumulation (:mod:`mbcomp.codegen.adjoint`)
    uses the same partials as :func:`tangent`, so the two modes differentiate alike.

    Parameters
    ----------
    graph : Graph
    i : int
        A node that is an operation (not a constant or an input).
    need_b : bool
        Whether the second operand's partial is needed (``pow``: ``r log a`` is made only then).

    Returns
    -------
    tuple
        One partial per operand: :class:`~mbcomp.codegen.graph.Sym` of ``graph`` or numbers.

    Raises
    ------
    ValueError
        When node ``i`` is a constant, an input, or has an operation not in :data:`OPERATIONS`.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.tangent import partials
    >>> with Graph() as g:
    ...     x, y = g.input("q", 0, 0.5), g.input("u", 0, 2.0)
    ...     f = np.sin(x) / y
    ...     da, db = partials(g, f.i)      # d(a/b)/da = 1/b, d(a/b)/db = -r/b
    >>> g.keys[f.i][0], [g.keys[j][0] for j in g.keys[f.i][1:]]     # r = a / b: a = sin(x), b = y
    ('/', ['sin', 'in'])
    >>> round(da.v, 12), round(db.v, 12)
    (0.5, -0.119856384651)
    """
    key = graph.keys[i]
    op = key[0]
    if op in ("c", "in") or op not in OPERATIONS:
        raise ValueError(f"partials: node {i} is {op!r}, not an operation this module can differentiate")
    nodes = graph.nodes
    return _partials(op, nodes[i], nodes[key[1]], nodes[key[2]] if len(key) > 2 else None, need_b)


_UNARY = {
    "abs": lambda r, a: a / r,
    "cos": lambda r, a: -np.sin(a),
    "sin": lambda r, a: np.cos(a),
    "tan": lambda r, a: 1.0 + r * r,
    "asin": lambda r, a: 1.0 / np.sqrt(1.0 - a * a),
    "acos": lambda r, a: -1.0 / np.sqrt(1.0 - a * a),
    "atan": lambda r, a: 1.0 / (1.0 + a * a),
    "sqrt": lambda r, a: 0.5 / r,
    "exp": lambda r, a: r,
    "log": lambda r, a: 1.0 / a,
    "sinh": lambda r, a: np.cosh(a),
    "cosh": lambda r, a: np.sinh(a),
    "tanh": lambda r, a: 1.0 - r * r,
}


def cone(keys, roots):
    """Indices of the nodes the nodes ``roots`` (indices) depend on, themselves included, in
    topological (index) order; ``keys`` is the graph's ``keys``.

    Examples
    --------
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.tangent import cone
    >>> with Graph() as g:
    ...     x, y = g.input("q", 0, 1.0), g.input("q", 1, 2.0)
    ...     f, other = x * x, y + 1.0
    >>> cone(g.keys, [f.i]) == sorted({x.i, f.i})
    True
    """
    seen, stack = set(), list(roots)
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        k = keys[i]
        if k[0] not in ("c", "in"):
            stack.extend(k[1:])
    return sorted(seen)


def input_positions(graph, inputs, who):
    """``{node index: position in inputs}`` of the input nodes ``inputs`` of ``graph`` (None
    entries, inputs the tracer did not make, are left out); the check both differentiation
    modes make of what they differentiate with respect to.

    Raises
    ------
    ValueError
        Naming ``who`` and the entry that is not an input node of ``graph``.

    Examples
    --------
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.tangent import input_positions
    >>> with Graph() as g:
    ...     x, y = g.input("q", 0, 1.0), g.input("u", 0, 2.0)
    >>> input_positions(g, [y, None, x], "example") == {y.i: 0, x.i: 2}
    True
    """
    keys, nodes, out = graph.keys, graph.nodes, {}
    for k, x in enumerate(inputs):
        if x is None:
            continue
        if type(x) is not Sym or x.i >= len(keys) or keys[x.i][0] != "in" or nodes[x.i] is not x:
            raise ValueError(f"{who}: inputs[{k}] is not an input node of this graph (make it with Graph.input)")
        out[x.i] = k
    return out


def tangent(graph, outputs, inputs):
    """The nodes of ``d outputs / d inputs``, built in ``graph`` by forward-mode differentiation.

    Parameters
    ----------
    graph : Graph
        The graph the outputs were traced into (made current while building).
    outputs : sequence of Sym or float
        The values to differentiate (numbers have derivative zero).
    inputs : sequence of Sym or None
        Input nodes (``graph.input``) to differentiate with respect to; None for an input the
        tracer did not make (``graph.memo.get(...)``): its column is zero.

    Returns
    -------
    list of list
        ``J[i][k]``: ``d outputs[i] / d inputs[k]`` as a :class:`~mbcomp.codegen.graph.Sym`
        of ``graph`` (its trace-time value in ``.v``), or the number ``0.0`` when it is
        structurally zero.

    Raises
    ------
    ValueError
        When an entry of ``inputs`` is not an input node of ``graph``, or a node has an
        operation this module does not know (not in :data:`OPERATIONS`).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.tangent import tangent
    >>> with Graph() as g:
    ...     x, k = g.input("q", 0, 3.0), g.input("p", 0, 2.0, state=False)
    ...     f = k * x ** 3 + np.exp(x / k)
    >>> (d,), = tangent(g, [f], [x])
    >>> bool(abs(d.v - (3 * 2.0 * 9.0 + np.exp(1.5) / 2.0)) < 1e-12)
    True
    >>> tangent(g, [f], [g.memo.get(("in", "u", 0)), x])[0][0]    # no input u: its column is zero
    0.0
    """
    keys, nodes = graph.keys, graph.nodes
    seed = input_positions(graph, inputs, "tangent")
    outputs = list(outputs)
    with graph:
        deriv = _forward(keys, nodes, cone(keys, [o.i for o in outputs if type(o) is Sym]), seed, len(inputs),
                         {o.i for o in outputs if type(o) is Sym})
        J = []
        for o in outputs:
            row = [0.0] * len(inputs)
            if type(o) is Sym:
                for k, v in deriv.get(o.i, {}).items():
                    row[k] = v
            J.append(row)
    return J


def _forward(keys, nodes, order, seed, n_inputs, wanted):
    """``{node: {input position: derivative}}`` (nonzero entries only) of the nodes ``wanted``
    over ``order``.

    The derivative nodes are made one input (direction) at a time, each direction a sweep
    through the nodes that depend on that input, after every node's local partials: the
    program then computes the partials with the values and each direction's derivatives
    together, where they are used (made node by node instead, the derivatives of one node
    for every direction sit together and each is used far from where it was computed: the
    C program of a 40-link chain's Jacobian ran 1.7 times slower, its values living in the
    work array rather than in registers and the first-level cache). The nodes made, and so
    the operations, are the same in either order."""
    dep, parts_of = {}, {}  # node -> bit mask of the inputs it depends on; -> its local partials
    for i in order:
        key = keys[i]
        op = key[0]
        if op == "in":
            if i in seed:
                dep[i] = 1 << seed[i]
            continue
        if op == "c":
            continue
        if op not in OPERATIONS:
            raise ValueError(f"tangent: the graph has an operation {op!r} this module cannot differentiate")
        masks = [dep.get(j, 0) for j in key[1:]]
        m = masks[0] | masks[-1]
        if not m:
            continue
        dep[i] = m
        parts_of[i] = _partials(op, nodes[i], nodes[key[1]], nodes[key[2]] if len(key) > 2 else None,
                                len(masks) > 1 and bool(masks[1]))
    active = [(i, dep[i], keys[i][1:], parts_of.get(i)) for i in order if i in dep]
    deriv = {}
    for k in range(n_inputs):
        bit = 1 << k
        cur = {}
        for i, m, args, parts in active:
            if not m & bit:
                continue
            if parts is None:  # the input itself
                cur[i] = 1.0
                continue
            v = 0.0
            for p, j in zip(parts, args):
                d = cur.get(j)
                if d is not None:
                    v = v + p * d
            if type(v) is Sym or v != 0.0:
                cur[i] = v
        for i in wanted.intersection(cur):
            deriv.setdefault(i, {})[k] = cur[i]
    return deriv
