"""Printing a traced graph: the hoisted parameter program and the state programs, as Python
or C source.

A :class:`Program` takes the nodes a set of named output groups needs (and the guards taken
while tracing them) and splits them: nodes depending on parameters only are *hoisted* into
the parameter program (:class:`ParamProgram`, interpreted once per parameter set), the rest
are printed as straight-line code, one function per group. The Python printer inlines
single-use temporaries; the C printer splits long functions into chunks (values crossing a
chunk boundary go through a work array). A failed state guard makes the generated function
raise ``_Fallback`` (Python) or return 1 (C).

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

import math

from .graph import _CMP, _INF, Retrace, Sym, _div, _pow, _safe

__all__ = ["PY_ENV", "Program", "ParamProgram"]

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


class Program:
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
                # operands of the node and of the guards checked right after it
                for j in list(keys[i][1:]) + [x for gd in guards.get(i, ()) for x in gd[1:3]]:
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


class ParamProgram:
    """The hoisted parameter program, interpreted with the tracer's own arithmetic: it runs once
    per parameter set (no compilation), and for the traced values it reproduces the trace-time
    values bit for bit. Raises :class:`~mbcomp.codegen.graph.Retrace` when a parameter guard fails."""

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
                raise Retrace
        return [val[i] for i in self.hoisted]
