"""Printing a traced graph: the hoisted parameter program and the state programs, as Python
or C source.

A :class:`Program` takes the nodes a set of named output groups needs (and the guards taken
while tracing them) and splits them: nodes depending on parameters only are *hoisted* into
the parameter program (:class:`ParamProgram`, interpreted once per parameter set), the rest
are printed as straight-line code, one function per group. The Python printer inlines
single-use temporaries; the C printer splits long functions into chunks (values crossing a
chunk boundary go through a work array) and prints repeated blocks of a large program (one
body's statements of a recursion) as loops (:mod:`mbcomp.codegen.block_loops`). A failed
state guard makes the generated function raise ``_Fallback`` (Python) or return 1 (C).

Examples
--------
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.printers import PY_ENV, Program
>>> with Graph() as g:
...     x, k = g.input("q", 0, 0.5), g.input("p", 0, 4.0, state=False)
...     kk = k * k
...     y = kk * x
>>> prog = Program(g, {"out": [y]})
>>> prog.hoisted == [kk.i]               # k*k runs once per parameter set
True
>>> env = dict(PY_ENV); exec(prog.python_main("out", "f"), env)
>>> env["f"]([0.5], [], 0.0, [], [16.0])
[8.0]
"""
from __future__ import annotations

import itertools
import math
import operator
import re

import numpy as np

from .graph import Retrace, Sym
from .ieee import COMPARE, INF, call_or_nan, div, power
from . import block_loops
from .block_loops import block_functions, find_blocks
from .rolling import ROLL_MIN, rolled as _rolled

__all__ = ["PY_ENV", "Program", "ParamProgram", "python_source", "LOCAL_MACRO", "SIGNATURE"]

_PY_UNARY = {"cos": "_cos", "sin": "_sin", "tan": "_tan", "asin": "_asin", "acos": "_acos", "atan": "_atan",
             "sqrt": "_sqrt", "exp": "_exp", "log": "_log", "sinh": "_sinh", "cosh": "_cosh", "tanh": "_tanh",
             "abs": "abs"}
_C_UNARY = {"cos": "cos", "sin": "sin", "tan": "tan", "asin": "asin", "acos": "acos", "atan": "atan",
            "sqrt": "sqrt", "exp": "exp", "log": "log", "sinh": "sinh", "cosh": "cosh", "tanh": "tanh",
            "abs": "fabs"}
#: the names generated Python programs use (``_Fallback`` and ``_Retrace`` are added by the compiler)
PY_ENV = {"_cos": math.cos, "_sin": math.sin, "_tan": math.tan, "_asin": math.asin, "_acos": math.acos,
           "_atan": math.atan, "_sqrt": math.sqrt, "_exp": math.exp, "_log": math.log, "_sinh": math.sinh,
           "_cosh": math.cosh, "_tanh": math.tanh, "_atan2": math.atan2, "_hypot": math.hypot, "_pow": math.pow,
           "_inf": INF, "_nan": float("nan")}


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


def _c_key_expr(key, a):
    """C expression of the node of key ``key`` on operand names ``a``."""
    return _expr(key, a, "c")


def _c_expr(op, a):
    """C expression of operation ``op`` on operand names ``a`` (a constant: ``("c", value)``)."""
    return _c_num(op[1]) if type(op) is tuple else _expr((op,), a, "c")


def python_source(g, outputs, name="f"):
    """Python source of one function ``name(q, u, t, d, h)`` computing ``outputs`` (nodes of
    the graph ``g`` or numbers) from the inputs ``q, u, t, d`` (lists), without hoisting (the
    parameters come in ``h``): a graph printed for reading and for tests.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen import Graph
    >>> from mbcomp.codegen.printers import python_source
    >>> with Graph() as g:
    ...     x = g.input("q", 0, 0.5)
    ...     y = np.cos(x) * x + 0 * x      # the "+ 0 * x" folds away
    >>> print(python_source(g, [y], "f"))
    def f(q, u, t, d, h):
        (q0,) = q[:1]
        x2 = q0 * (_cos(q0))
        return [x2]
    """
    return Program(g, {"out": list(outputs)}, hoist=False).python_main("out", name)


class Program:
    """Nodes needed for named output groups, split into hoisted parameter nodes and state nodes."""

    def __init__(self, g, groups, hoist=True, guard_groups=None):
        self.g, self.groups = g, groups
        keys, nodes = g.keys, g.nodes
        n = len(keys)
        self._arrays = None
        self._outs = {}
        opc, code, A, B = self.arrays()
        is_c, is_in = opc == code.get("c", -1), opc == code.get("in", -1)
        outs = np.concatenate([self.out_nodes(name) for name in groups] + [np.zeros(0, np.int64)])
        outs = outs[outs >= 0]
        starts = np.concatenate((outs, np.array([j for gd in g.guards for j in gd[1:3]], dtype=np.int64)))
        need = _reach(starts, A, B, np.ones(n, bool), ~(is_c | is_in))
        self.need = need
        # without hoisting every non-constant node belongs to the state programs
        state = list(map(_STATE, nodes)) if hoist else [k[0] != "c" for k in keys]
        self.state = state
        S = np.array(state, dtype=bool)
        self._S = S
        # hoisted: parameter-only, non-constant nodes used by state nodes, state guards or outputs
        hoisted = set()
        if hoist:
            users = need & S & ~is_in
            cand = np.concatenate((A[users], B[users]))
            cand = cand[cand >= 0]
            hoisted.update(np.unique(cand[~S[cand] & ~is_c[cand]]).tolist())
            hoisted.update(np.unique(outs[~S[outs]]).tolist())
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
        ins = np.flatnonzero(is_in).tolist()
        self.params = sorted((keys[i][2], i) for i in ins if keys[i][1] == "p")
        self._group_nodes = {}

    def arrays(self):
        """The graph as arrays (computed once): ``(opc, code, A, B)``, each node's operation
        code (``code`` maps the operation names to them; constants ``"c"``, inputs ``"in"``)
        and operand indices (-1: none)."""
        if self._arrays is None:
            keys = self.g.keys
            n = len(keys)
            ops = list(map(_OP, keys))
            code = {o: c for c, o in enumerate(sorted(set(ops)))}
            opc = np.array(list(map(code.__getitem__, ops)), dtype=np.int64)
            del ops
            op_idx = np.flatnonzero((opc != code.get("c", -1)) & (opc != code.get("in", -1)))
            A = np.full(n, -1, dtype=np.int64)
            B = np.full(n, -1, dtype=np.int64)
            if len(op_idx):  # the operations' keys transposed: (names, first operands, second or -1)
                cols = list(itertools.zip_longest(*map(keys.__getitem__, op_idx.tolist()), fillvalue=-1))
                A[op_idx] = np.array(cols[1], dtype=np.int64)
                if len(cols) > 2:
                    B[op_idx] = np.array(cols[2], dtype=np.int64)
                del cols
            self._arrays = (opc, code, A, B)
        return self._arrays

    # --- per-group state nodes ---------------------------------------------------------------
    def group_nodes(self, name):
        """State nodes (indices, topological order) needed by output group ``name`` and guards
        (computed once; do not modify the list)."""
        got = self._group_nodes.get(name)
        if got is None:
            got = self._group_nodes[name] = self._find_group_nodes(name)
        return got

    def _find_group_nodes(self, name):
        opc, code, A, B = self.arrays()
        allowed = self._S.copy()
        allowed[self.hoisted] = False
        outs = self.out_nodes(name)
        starts = np.concatenate((outs[outs >= 0], np.array([j for gd in self.guards_of[name] for j in gd[1:3]],
                                                             dtype=np.int64)))
        return np.flatnonzero(_reach(starts, A, B, allowed, opc != code.get("in", -1))).tolist()

    def out_nodes(self, name):
        """The node of each output of group ``name`` (-1: a number), as an array (computed once)."""
        got = self._outs.get(name)
        if got is None:
            got = self._outs[name] = np.array([o.i if type(o) is Sym else -1 for o in self.groups[name]],
                                              dtype=np.int64)
        return got

    def op_nodes(self, name):
        """The operations among :meth:`group_nodes` (inputs left out), as an array."""
        opc, code, _, _ = self.arrays()
        gn = np.array(self.group_nodes(name), dtype=np.int64)
        return gn[opc[gn] != code.get("in", -1)]

    def n_ops(self, name):
        return len(self.op_nodes(name))

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
    def c_params(self, fname="mbcomp_params"):
        """C source of ``int fname(const double *pv, double *h)``: the hoisted values ``h`` of
        the parameter vector ``pv`` (what :class:`ParamProgram` computes in Python; the same
        IEEE operations, so the same values), 0 on success, 1 when a parameter guard fails
        (the values change a decision taken while tracing: the program does not hold for
        them), 2 when a hoisted value is not finite. What a program needs to run without
        Python (an exported FMU's tunable parameters)."""
        keys = self.g.keys
        pidx = {i: j for j, i in self.params}

        def name(i):
            k = keys[i]
            if k[0] == "c":
                return _c_num(k[1])
            if i in pidx:
                return f"pv[{pidx[i]}]"
            return f"x{i}"

        body = []
        for i in self.pre_nodes():
            k = keys[i]
            if k[0] == "in":
                continue
            body.append(f"    const double x{i} = {_expr(k, [name(j) for j in k[1:]], 'c')};")
        for op, ai, bi, res in self.param_guards:
            body.append(f"    if ({'!' if res else ''}({name(ai)} {op} {name(bi)})) return 1;")
        for k, i in enumerate(self.hoisted):
            body.append(f"    h[{k}] = {name(i)};")
            body.append(f"    if (!isfinite(h[{k}])) return 2;")
        return (f"int {fname}(const double *restrict pv, double *restrict h)\n{{\n" + "\n".join(body)
                + "\n    (void)pv; (void)h;\n    return 0;\n}\n")

    def c_function(self, group, fname, chunk=2000, roll=None, blocks=None):
        """C source of ``int fname(q, u, t, d, h, p, w, out)``: 0 on success, 1 if a guard failed.
        Values crossing chunk boundaries live in the work array ``w``; returns ``(source,
        work size)``. ``roll``, ``blocks``: see :meth:`c_parts` (one translation unit here)."""
        parts, n_work = self.c_parts(group, fname, chunk, 1, roll, blocks)
        return "\n".join(parts), n_work

    def c_parts(self, group, fname, chunk=2000, n_parts=1, roll=None, blocks=None):
        """The C program of ``group`` as ``n_parts`` translation units (without ``#include
        <math.h>``; the last one defines ``int fname(...)``, the others its chunks, with hidden
        visibility) and the size of the work array it needs. ``n_parts`` may be a function of
        the program's size (its straight-line statements and loops) giving the number.

        The straight-line code is split into functions of ``chunk`` statements (gcc's optimizer
        is superlinear in a function's size; ``chunk`` may be a function of the number of
        straight-line statements and of the values the loops read giving it); values crossing
        a function boundary live in the work array ``w``. Output expressions of one shape (a
        tree of single-use operations under an output nothing else uses, e.g. ``M[i, j] = S_i
        . F_j`` for every pair of links) that occur at least ``roll`` times (default
        :data:`~mbcomp.codegen.rolling.ROLL_MIN`; 0: never) are computed by one loop over a
        table of their operands' places instead (:mod:`mbcomp.codegen.rolling`): the program's
        text then grows like its distinct values (O(N) for a chain) instead of its outputs.
        In a program of at least ``blocks`` straight-line statements (default
        :data:`~mbcomp.codegen.block_loops.BLOCK_MIN`; 0: never), runs of repeated blocks (the
        recursions' per-body statements) are computed by loops over the blocks
        (:mod:`mbcomp.codegen.block_loops`; the same operations in the same order): the text
        then grows like one body's statements and tables of places, not like N."""
        keys = self.g.keys
        roll = ROLL_MIN if roll is None else roll
        blocks = block_loops.BLOCK_MIN if blocks is None else blocks
        nodes = self.op_nodes(group).tolist()
        loops, slot, rolled = _rolled(self, group, nodes, roll) if roll and len(nodes) >= roll else ([], {}, None)
        if rolled is not None:
            nodes = [i for i in nodes if not rolled[i]]
        where_out, tail = self._out_places(group, nodes, rolled)
        if callable(chunk):
            chunk = chunk(len(nodes), len(slot))
        guards = self._guards_by_node(self.guards_of[group])
        blocks = find_blocks(self, nodes, guards, where_out) if blocks and len(nodes) >= blocks else []
        if callable(n_parts):  # a repeated block's loop weighs its body
            n_parts = n_parts(len(nodes) - sum(b.L * (b.R - 1) for b in blocks) + sum(lp.weight for lp in loops))
        linkage = "MBCOMP_LOCAL int" if n_parts > 1 else "static int"
        if blocks:
            funcs, n_work = block_functions(self, nodes, blocks, chunk, guards, where_out, slot, fname, linkage,
                                            SIGNATURE, _c_key_expr, self.c_name, self.c_name)
            return self._c_finish(fname, funcs, loops, guards, tail, n_parts, linkage), n_work
        chunks = [nodes[s: s + chunk] for s in range(0, len(nodes), chunk)] or [[]]
        chunk_of = _crossing(keys, chunks, guards, slot)
        funcs = []  # (weight, name, source)

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
            funcs.append((len(ch), f"{fname}_{c}",
                          f"{linkage} {fname}_{c}({SIGNATURE})\n{{\n" + "\n".join(body) + "\n    return 0;\n}\n"))
        return self._c_finish(fname, funcs, loops, guards, tail, n_parts, linkage), len(slot)

    def _c_finish(self, fname, funcs, loops, guards, tail, n_parts, linkage):
        """The translation units of :meth:`c_parts`: the functions ``funcs``, the output
        expressions' ``loops``, and the entry calling them in order, then writing the
        ``tail`` outputs and checking the guards on inputs and hoisted values."""
        for r, lp in enumerate(loops):
            funcs.append((lp.weight, f"{fname}_r{r}", lp.source(f"{fname}_r{r}", linkage, SIGNATURE, _c_expr)))
        tail_lines = _tail_c([(k, self._out_name(o, 'c')) for k, o in tail])
        for gd in guards.get(-1, ()):
            op, ai, bi, res = gd
            cond = f"{self._name(ai, 'c', True)} {op} {self._name(bi, 'c', True)}"
            tail_lines.append(f"    if ({'!' if res else ''}({cond})) return 1;")
        calls = "\n".join(f"    if ({fn}(q, u, t, d, h, p, w, out)) return 1;" for _, fn, _ in funcs)
        entry = f"int {fname}({SIGNATURE})\n{{\n{calls}\n" + "\n".join(tail_lines) + "\n    return 0;\n}\n"
        return _units(funcs, entry, n_parts, linkage)

    def guards_by_node(self, group):
        """The state guards of ``group`` keyed by the node after which they are checked
        (``-1``: at the end)."""
        return self._guards_by_node(self.guards_of[group])

    def output_places(self, group, nodes):
        """``({node: [output places]}, [(place, output)])``: where the straight-line
        ``nodes`` of ``group`` write its outputs, and the outputs written at the end."""
        return self._out_places(group, nodes, None)

    def c_name(self, i):
        """The C text of node ``i`` inside a state program (a local value ``x<i>``, a hoisted
        value, an input or a constant)."""
        return self._name(i, "c", True)

    def _out_places(self, group, nodes, rolled):
        """Where the outputs of ``group`` are written: ``{node: [places]}`` for the
        straight-line ``nodes``, and ``[(place, output)]`` for those written at the end
        (numbers, inputs, hoisted values); those the loops compute (``rolled``) are neither."""
        outs, onodes = self.groups[group], self.out_nodes(group)
        straight = np.zeros(len(self.g.keys), bool)
        straight[nodes] = True
        done = straight.copy()
        if rolled is not None:
            done |= np.frombuffer(rolled, dtype=np.uint8).astype(bool)
        known = onodes >= 0
        where_out = {}
        for k in np.flatnonzero(known & straight[np.maximum(onodes, 0)]).tolist():
            where_out.setdefault(int(onodes[k]), []).append(k)
        tail = [(k, outs[k]) for k in np.flatnonzero(~known | ~done[np.maximum(onodes, 0)]).tolist()]
        return where_out, tail


#: outputs written at the end (numbers, inputs, hoisted values) above which they are copied
#: from static tables by loops: 5,000 straight-line stores in one function cost gcc -O2 ~5 s
#: (the output program of a 300-link chain), the loops nothing
TAIL_TABLE = 64
_REF = re.compile(r"^([quhdpw])\[(\d+)\]$")


def _tail_c(pairs):
    """C statements writing ``out[k] = value`` for ``(k, value text)`` pairs: numbers and
    array elements copied by loops over static tables when there are more than
    :data:`TAIL_TABLE` of them, the rest (``t``, non-finite numbers) one by one."""
    if len(pairs) <= TAIL_TABLE:
        return [f"    out[{k}] = {v};" for k, v in pairs]
    nums, refs, lines = [], {}, []
    for k, v in pairs:
        m = _REF.match(v)
        if m:
            refs.setdefault(m.group(1), []).append((k, int(m.group(2))))
            continue
        try:
            x = float(v.strip("()"))
        except ValueError:
            x = math.nan
        if math.isfinite(x):
            nums.append((k, repr(x)))
        else:
            lines.append(f"    out[{k}] = {v};")
    if nums:
        lines += ["    {",
                  f"        static const long at[{len(nums)}] = {{{', '.join(str(k) for k, _ in nums)}}};",
                  f"        static const double value[{len(nums)}] = {{{', '.join(v for _, v in nums)}}};",
                  f"        for (long i = 0; i < {len(nums)}; ++i) out[at[i]] = value[i];",
                  "    }"]
    for arr, kj in refs.items():
        lines += ["    {",
                  f"        static const long at[{len(kj)}] = {{{', '.join(str(k) for k, _ in kj)}}};",
                  f"        static const long from[{len(kj)}] = {{{', '.join(str(j) for _, j in kj)}}};",
                  f"        for (long i = 0; i < {len(kj)}; ++i) out[at[i]] = {arr}[from[i]];",
                  "    }"]
    return lines


SIGNATURE = ("const double *restrict q, const double *restrict u, double t, const double *restrict d, "
        "const double *restrict h, const double *restrict p, double *restrict w, double *restrict out")


def _crossing(keys, chunks, guards, slot):
    """Each straight-line node's chunk; the values used (by an operation or a guard) in a
    later chunk than theirs get work-array slots (added to ``slot``)."""
    chunk_of = {}
    for c, ch in enumerate(chunks):
        for i in ch:
            chunk_of[i] = c
    for c, ch in enumerate(chunks):
        for i in ch:
            for j in keys[i][1:]:
                if j in chunk_of and chunk_of[j] != c and j not in slot:
                    slot[j] = len(slot)
            for gd in guards.get(i, ()):  # a guard's other operand may be from an earlier chunk
                for j in gd[1:3]:
                    if j in chunk_of and chunk_of[j] != c and j not in slot:
                        slot[j] = len(slot)
    return chunk_of


def _units(funcs, entry, n_parts, linkage):
    """The functions ``(weight, name, source)`` and the entry as ``n_parts`` sources:
    contiguous runs of functions of about equal weight, the entry (with the declarations) in
    the last."""
    if n_parts <= 1:
        return ["\n".join(src for _, _, src in funcs) + "\n" + entry]
    bins = [[] for _ in range(n_parts)]
    total = sum(wt for wt, _, _ in funcs) or 1
    acc = 0
    for wt, fn, src in funcs:
        bins[min(n_parts - 1, acc * n_parts // total)].append(src)
        acc += wt
    decl = "\n".join(f"{linkage} {fn}({SIGNATURE});" for _, fn, _ in funcs)
    parts = [LOCAL_MACRO + "\n".join(b) for b in bins[:-1]]
    parts.append(LOCAL_MACRO + decl + "\n\n" + "\n".join(bins[-1]) + "\n" + entry)
    return parts


_OP = operator.itemgetter(0)
_STATE = operator.attrgetter("s")


def _reach(starts, A, B, allowed, expand):
    """The nodes reachable from ``starts`` through operands (a boolean array): only
    ``allowed`` nodes are reached, and only the operands of ``expand`` nodes are followed
    (breadth first, one array operation per level)."""
    mark = np.zeros(len(A), bool)
    front = np.asarray(starts, dtype=np.int64)
    front = front[allowed[front]]
    while len(front):
        mark[front] = True  # (a node twice in a front is expanded twice: cheaper than sorting)
        e = front[expand[front]]
        nxt = np.concatenate((A[e], B[e]))
        nxt = nxt[nxt >= 0]
        front = nxt[allowed[nxt] & ~mark[nxt]]
    return mark


LOCAL_MACRO = ("#ifndef MBCOMP_LOCAL\n#if defined(__GNUC__)\n#define MBCOMP_LOCAL __attribute__((visibility(\"hidden\")))\n"
          "#else\n#define MBCOMP_LOCAL\n#endif\n#endif\n")


class ParamProgram:
    """The hoisted parameter program, interpreted with the tracer's own arithmetic: it runs once
    per parameter set (no compilation), and for the traced values it reproduces the trace-time
    values bit for bit. Raises :class:`~mbcomp.codegen.graph.Retrace` when a parameter guard fails."""

    _BIN = {"+": float.__add__, "-": float.__sub__, "*": float.__mul__, "/": div, "pow": power,
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
        # an output may itself be a constant node (a derivative's coefficient): hoisted, so read here
        used = ({j for _, k in self.order for j in k[1:]} | {j for gd in self.guards for j in gd[1:3]}
                | set(prog.hoisted))
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
                val[i] = call_or_nan(UN[k[0]], val[k[1]])
        for op, ai, bi, res in self.guards:
            if bool(COMPARE[op](val[ai], val[bi])) != res:
                raise Retrace
        return [val[i] for i in self.hoisted]
