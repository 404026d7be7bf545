"""Output expressions of one shape computed by loops: what keeps a program's text linear in
the number of bodies when its outputs grow faster (the mass matrix's N^2 entries).

An *expression* is an output node nothing else in the program uses, with the tree of
single-use operations under it (no guard on any of them): ``M[i, j] = S_i . F_j`` for every
pair of links of a chain is one such tree per entry, all of one *shape* (the operations, and
the kind of each leaf: a shared state value, a hoisted value, an input, a constant's value).
:func:`rolled` finds the expressions of a program and their shapes on arrays (a mass matrix
of 1000 links has 500,000 of them): the trees by pointer jumping, the shapes as exact integer
codes level by level from the bottom, each expression's leaves in the order of their path
from the root. A shape with enough expressions becomes one :class:`Loop`: a table of the
places of every expression's outputs and leaves, which the C printer
(:meth:`mbcomp.codegen.printers.Program.c_parts`) prints as a loop; the shared values the
loops read live in the work array.

Examples
--------
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.printers import Program
>>> with Graph() as g:
...     x = [g.input("q", k, 0.1 * k) for k in range(5)]
...     s = [x[k] * x[k] + x[k] for k in range(5)]      # shared values
...     outs = [s[i] * s[j] + s[i] for i in range(5) for j in range(i + 1, 5)]
>>> prog = Program(g, {"out": outs})
>>> loops, slot, done = rolled(prog, "out", prog.op_nodes("out").tolist(), 8)
>>> len(loops), [op for op, _ in loops[0].ops], loops[0].kinds   # ten outputs, one loop
(1, ['*', '+'], ('w', 'w', 'w'))
>>> loops[0].rows.tolist()[0]     # 4 in a run: places of out, s_i, s_i, s_j, then their steps
[4, 0, 0, 0, 1, 1, 0, 0, 1]
"""
from __future__ import annotations

import numpy as np


__all__ = ["Loop", "rolled", "ROLL_MIN", "ROLL_MAX_OPS"]

#: fewest output expressions of one shape computed by a loop
ROLL_MIN = 16
#: largest output expression (operations) that is rolled into a loop
ROLL_MAX_OPS = 64
#: deepest output expression (levels of operations) that is rolled into a loop
ROLL_MAX_DEPTH = 40
_KINDS = ["", "w", "h", "q", "u", "d", "p", "t"]


def rolled(prog, group, nodes, min_members=ROLL_MIN):
    """The output expressions of ``prog``'s ``group`` computed by loops: ``(loops, slot,
    done)``: the :class:`Loop` of every shape with at least ``min_members`` expressions,
    the work-array slot of each shared value they read (column by column in the expressions'
    order, so that the places along a run of expressions advance by a constant step) and
    a bytearray over the graph marking the nodes the loops compute. ``nodes``: the group's
    operations (:meth:`~mbcomp.codegen.printers.Program.op_nodes`)."""
    ex = _expressions(prog, group, np.array(nodes, dtype=np.int64))
    if ex is None:
        return [], {}, None
    kinds = _leaf_kinds(prog, ex)
    if kinds is None:
        return [], {}, None
    leafkind, leafidx, names = kinds
    sid = _shape_codes(ex, leafkind)
    roots = ex.roots
    rkey = sid[roots] * 1024 + np.minimum(ex.n_outs[roots], 1023)
    _, rinv, rcount = np.unique(rkey, return_inverse=True, return_counts=True)
    rinv = rinv.reshape(-1)
    chosen = rcount >= min_members
    if not chosen.any():
        return [], {}, None
    is_rolled = np.zeros(len(ex.inner), bool)
    is_rolled[roots[chosen[rinv]]] = True
    occ_root, occ_leaf, done = _leaves_in_order(ex, is_rolled)
    out_node, out_pos = ex.outs
    o = np.argsort(out_node, kind="stable")
    out_node, out_pos = out_node[o], out_pos[o]
    loops, slot = [], {}
    for t in np.flatnonzero(chosen).tolist():
        members = roots[rinv == t]
        ops, kk = _render(prog.g.keys, int(members[0]), ex.inner, leafkind, names)
        leaf_nodes = occ_leaf[np.searchsorted(occ_root, members)[:, None] + np.arange(len(kk))]
        k_out = int(ex.n_outs[members[0]])
        outs = out_pos[np.searchsorted(out_node, members)[:, None] + np.arange(k_out)]
        cols = [(c, kd, leaf_nodes[:, c] if kd == "w" else leafidx[leaf_nodes[:, c]])
                for c, kd in enumerate(kk) if type(kd) is str and kd != "t"]
        loops.append(Loop(ops, kk, outs, cols, slot))
    return loops, slot, bytearray(done.tobytes())


class _Expressions:
    """The expressions of a program (see :func:`_expressions`)."""


def _expressions(prog, group, idx):
    """The trees of the expressions of ``group`` (operations ``idx``), or None if it has
    none: ``roots``; ``inner`` (a boolean array: single-use operations that sit inside an
    expression), each one's ``user`` and ``side`` (which operand it is there), ``up`` (its
    expression's root) and ``dist`` (its depth below it); ``tn`` every node of an
    expression with its operands ``ta``, ``tb`` (-1: none), operation code ``tops`` and
    depth ``D``, deepest first; ``n_outs``; ``outs`` (nodes, output places)."""
    n = len(prog.g.keys)
    opc, _, A_all, B_all = prog.arrays()
    A, B = A_all[idx], B_all[idx]
    inprog = np.zeros(n, bool)
    inprog[idx] = True
    hasb = B >= 0
    uses = np.bincount(A, minlength=n) + np.bincount(B[hasb], minlength=n)
    onodes = prog.out_nodes(group)
    out_pos = np.flatnonzero((onodes >= 0) & inprog[np.maximum(onodes, 0)])
    out_node = onodes[out_pos]
    n_outs = np.bincount(out_node, minlength=n)
    guarded = np.zeros(n, bool)
    for gd in prog.guards_of[group]:
        guarded[gd[1]] = guarded[gd[2]] = True
    is_root = inprog & (n_outs > 0) & (uses == 0) & ~guarded
    inner = inprog & (uses == 1) & (n_outs == 0) & ~guarded
    if not is_root.any():
        return None
    user = np.full(n, -1, dtype=np.int64)
    side = np.zeros(n, dtype=np.int64)
    user[A] = idx
    user[B[hasb]] = idx[hasb]
    side[B[hasb]] = 1
    # pointer jumping: up -> the top of each inner node's chain of users, dist -> how far
    up = np.arange(n, dtype=np.int64)
    inn = np.flatnonzero(inner)
    up[inn] = user[inn]
    dist = np.zeros(n, dtype=np.int64)
    dist[inn] = 1
    while True:
        nxt = up[up]
        if np.array_equal(nxt, up):
            break
        dist += dist[up]
        up = nxt
    roots = np.flatnonzero(is_root)
    tin = inn[is_root[up[inn]]]  # the inner nodes of expressions
    size = np.bincount(up[tin], minlength=n)[roots] + 1
    depth = np.zeros(n, dtype=np.int64)
    np.maximum.at(depth, up[tin], dist[tin])
    ok = np.zeros(n, bool)
    ok[roots[(size <= ROLL_MAX_OPS) & (depth[roots] <= ROLL_MAX_DEPTH)]] = True
    roots = roots[ok[roots]]
    if not len(roots):
        return None
    tin = tin[ok[up[tin]]]
    ex = _Expressions()
    tn = np.concatenate((tin, roots))
    D = np.concatenate((dist[tin], np.zeros(len(roots), dtype=np.int64)))
    order = np.argsort(-D, kind="stable")
    ex.tn, ex.D = tn[order], D[order]
    ex.ta, ex.tb, ex.tops = A_all[ex.tn], B_all[ex.tn], opc[ex.tn]
    ex.roots, ex.inner, ex.inprog, ex.user, ex.side, ex.up = roots, inner, inprog, user, side, up
    ex.n_outs, ex.outs = n_outs, (out_node, out_pos)
    return ex


def _leaf_kinds(prog, ex):
    """Each node's kind as a leaf (a code into ``names``: ``"w"`` a shared state value,
    ``"h"`` hoisted, ``"q"``, ``"u"``, ``"d"``, ``"p"``, ``"t"`` inputs, ``("c", value)`` a
    constant) and place (the node for ``"w"``, the hoisted or input index): ``(leafkind,
    leafidx, names)``; None if a leaf is a parameter value that is not hoisted."""
    keys, hidx = prog.g.keys, prog.hidx
    n = len(keys)
    names = list(_KINDS)
    leafkind = np.zeros(n, dtype=np.int64)
    leafkind[ex.inprog] = 1
    leafidx = np.arange(n, dtype=np.int64)
    tbp = ex.tb[ex.tb >= 0]
    outside = np.unique(np.concatenate((ex.ta[~ex.inprog[ex.ta]], tbp[~ex.inprog[tbp]])))
    consts = {}
    for j in outside.tolist():
        k = keys[j]
        if j in hidx:
            leafkind[j], leafidx[j] = 2, hidx[j]
        elif k[0] == "in":
            leafkind[j], leafidx[j] = names.index(k[1]), (0 if k[1] == "t" else k[2])
        elif k[0] == "c":
            code = consts.get(k[1])
            if code is None:
                code = consts[k[1]] = len(names)
                names.append(("c", k[1]))
            leafkind[j], leafidx[j] = code, 0
        else:  # a parameter-only value that is not hoisted (programs printed without hoisting)
            return None
    return leafkind, leafidx, names


def _levels(D):
    """``(lo, hi)`` of the runs of equal depth in ``D`` (sorted deepest first)."""
    cuts = (np.flatnonzero(np.diff(D)) + 1).tolist()
    return list(zip([0] + cuts, cuts + [len(D)]))


def _shape_codes(ex, leafkind):
    """Exact shape codes of the expressions' nodes (equal codes: equal trees of operations
    with equal leaf kinds), from the deepest level up: ``(op, operand codes)`` -> a new
    integer, a leaf's code being minus its kind."""
    sid = np.zeros(len(ex.inner), dtype=np.int64)
    off, base = 1 << 26, 0
    inner = ex.inner
    for lo, hi in _levels(ex.D):
        a, b = ex.ta[lo:hi], ex.tb[lo:hi]
        ca = np.where(inner[a], sid[a], -leafkind[a])
        bb = np.maximum(b, 0)
        cb = np.where(b < 0, -(1 << 25), np.where(inner[bb], sid[bb], -leafkind[bb]))
        key = (ex.tops[lo:hi] << 54) | ((ca + off) << 27) | (cb + off)
        uniq, inv = np.unique(key, return_inverse=True)
        sid[ex.tn[lo:hi]] = base + inv.reshape(-1)
        base += len(uniq)
    return sid


def _leaves_in_order(ex, is_rolled):
    """The leaves of the expressions whose roots are ``is_rolled``: ``(root, leaf)`` of every
    leaf occurrence sorted by root, then by path code (a root 1, an operand twice its user's
    code plus its side), and the bytearray of the nodes those expressions compute."""
    n = len(ex.inner)
    pc = np.zeros(n, dtype=np.int64)
    pc[ex.roots] = 1
    for lo, hi in reversed(_levels(ex.D)):
        if ex.D[lo] > 0:
            x = ex.tn[lo:hi]
            pc[x] = pc[ex.user[x]] * 2 + ex.side[x]
    sel = is_rolled[ex.up[ex.tn]] | is_rolled[ex.tn]
    xs, xa, xb = ex.tn[sel], ex.ta[sel], ex.tb[sel]
    xroot = np.where(is_rolled[xs], xs, ex.up[xs])
    la = ~ex.inner[xa]
    lb = (xb >= 0) & ~ex.inner[np.maximum(xb, 0)]
    occ_root = np.concatenate((xroot[la], xroot[lb]))
    occ_code = np.concatenate((pc[xs[la]] * 2, pc[xs[lb]] * 2 + 1))
    occ_leaf = np.concatenate((xa[la], xb[lb]))
    o = np.lexsort((occ_code, occ_root))
    done = np.zeros(n, np.uint8)
    done[xs] = 1
    return occ_root[o], occ_leaf[o], done


def _render(keys, r, inner, leafkind, names):
    """``(ops, kinds)`` of the expression under output ``r``: its operations in post-order,
    each ``(op, operands)`` with an operand ``a >= 0`` the ``a``-th leaf and ``a < 0`` the
    result of operation ``-1 - a``; the leaves' kinds, in the order of their path code (as
    :func:`_leaves_in_order` orders every expression's leaves)."""
    ops, leaves = [], []

    def walk(x, code):
        args = []
        for s, j in enumerate(keys[x][1:]):
            if inner[j]:
                args.append(walk(j, 2 * code + s))
            else:
                leaves.append((2 * code + s, j))
                args.append(("leaf", 2 * code + s))
        ops.append((keys[x][0], args))
        return -len(ops)

    walk(r, 1)
    leaves.sort()
    col = {code: c for c, (code, _) in enumerate(leaves)}
    out = [(op, tuple(col[a[1]] if type(a) is tuple else a for a in args)) for op, args in ops]
    return out, tuple(names[int(leafkind[j])] for _, j in leaves)


class Loop:
    """One shape of output expressions as a table-driven loop (see :func:`rolled`).

    Each expression is a vector of integers: its output places, then the place of each leaf
    in its array (``w``, ``h``, ``q``, ``u``, ``d``, ``p``; constants and ``t`` are in the
    loop's text). Sorted, the vectors form runs along which every entry advances by a
    constant step (a row of a mass matrix: ``out`` by 1, the row's ``S_i`` by 0, the
    columns' ``F_j`` by their places' stride); :attr:`rows` holds ``count, start..., step...``
    per run, :attr:`weight` is the loop's size for the printer's split into units."""

    def __init__(self, ops, kinds, outs, cols, slot):
        self.ops, self.kinds = ops, kinds
        m, self.n_out = outs.shape
        outs = np.sort(outs, axis=1)
        order = np.lexsort(outs.T[::-1])
        table = [outs[order]]
        # the leaves' places: shared values get work-array slots column by column, in order
        self.cols = [c for c, _, _ in cols]
        for c, kd, col in cols:
            col = col[order]
            if kd == "w":
                uniq, first, inv = np.unique(col, return_index=True, return_inverse=True)
                for k in np.argsort(first, kind="stable").tolist():
                    slot.setdefault(int(uniq[k]), len(slot))
                col = np.array([slot[x] for x in uniq.tolist()], dtype=np.int64)[inv.reshape(-1)]
            table.append(col.reshape(m, 1))
        V = np.hstack(table)
        self.width = W = V.shape[1]
        runs, D = _runs(V)
        rows = np.zeros((len(runs), 1 + 2 * W), dtype=np.int64)
        for r, (cnt, s, d) in enumerate(runs):
            rows[r, 0] = cnt
            rows[r, 1: 1 + W] = V[s]
            if d is not None:
                rows[r, 1 + W:] = D[d]
        self.rows = rows
        self.weight = 20 + len(self.ops) + len(runs) // 8

    def source(self, fname, linkage, sig, expr):
        """C source of ``fname`` (``linkage``, signature ``sig``) computing the expressions;
        ``expr(op, operand names)`` prints one operation."""
        W, n_runs = self.width, len(self.rows)
        rows = ",\n".join("{" + ",".join(map(str, row)) + "}" for row in self.rows.tolist())
        lines = [f"static const int {fname}_tab[{n_runs}][{1 + 2 * W}] = {{\n{rows}}};",
                 f"{linkage} {fname}({sig})\n{{",
                 f"    for (int r = 0; r < {n_runs}; r++) {{",
                 f"        const int *c = {fname}_tab[r];",
                 "        for (int k = 0; k < c[0]; k++) {"]
        # a step that is the same in every run is printed as a number (0: the value is read
        # once per run), so that gcc sees the loop's strides
        multi = self.rows[:, 0] > 1
        step = []
        for v in range(W):
            st = np.unique(self.rows[multi, 1 + W + v]) if multi.any() else np.zeros(1, np.int64)
            step.append(int(st[0]) if len(st) == 1 else None)

        def place(v):
            if step[v] is None:
                return f"c[{1 + v}] + k * c[{1 + W + v}]"
            return f"c[{1 + v}]" if step[v] == 0 else f"c[{1 + v}] + k * {step[v]}"

        leaf, hoisted = [], []
        col_of = {c: self.n_out + n for n, c in enumerate(self.cols)}
        for c, kd in enumerate(self.kinds):
            if type(kd) is tuple:
                leaf.append(expr(("c", kd[1]), ()))
            elif kd == "t":
                leaf.append("t")
            else:
                v = col_of[c]
                line = f"const double a{c} = {kd}[{place(v)}];"
                (hoisted if step[v] == 0 else lines).append(("        " if step[v] == 0 else "            ") + line)
                leaf.append(f"a{c}")
        lines[4:4] = hoisted  # before the inner loop
        for n, (op, args) in enumerate(self.ops):
            names = [leaf[a] if a >= 0 else f"y{-a - 1}" for a in args]
            lines.append(f"            const double y{n} = {expr(op, names)};")
        for o in range(self.n_out):
            lines.append(f"            out[{place(o)}] = y{len(self.ops) - 1};")
        lines += ["        }", "    }", "    return 0;", "}", ""]
        return "\n".join(lines)


def _runs(V):
    """Greedy runs of the rows of ``V``: from each start, as far as the step between
    neighbours stays the first one; ``[(count, start row, step row or None)]`` and the steps."""
    m = len(V)
    D = np.diff(V, axis=0)
    change = np.ones(max(m - 1, 0), dtype=bool)  # change[k]: D[k] differs from D[k - 1]
    if m > 2:
        change[1:] = (D[1:] != D[:-1]).any(axis=1)
    breaks = np.flatnonzero(change).tolist() + [m - 1]
    runs, s, b = [], 0, 0
    while s < m:
        if s == m - 1:
            runs.append((1, s, None))
            break
        while breaks[b] <= s:  # the first change after s ends the run
            b += 1
        e = breaks[b]  # D[s..e-1] are equal: the run is s..e
        runs.append((e - s + 1, s, s))
        s = e + 1
    return runs, D
