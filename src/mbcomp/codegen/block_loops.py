"""Repeated blocks of a straight-line program computed by loops: what keeps a large program's
machine code small enough for the instruction cache (issue 32 item 3, the 3-D chains).

The recursive algorithms (kinematics, articulated-body factorization, solves) are traced
body by body, so a chain's straight-line program is a few blocks of statements repeated once
per body: the same operations on the same kinds of operands, each block reading its own
earlier statements, the block before it (the recursion) and values of other passes. At
N = 100 the ball chain's ``fun`` is 88,000 statements, ~1 MB of machine code: more than the
L2 cache, so fetching instructions, not arithmetic, set its time.

:func:`find_blocks` finds maximal runs of ``R`` consecutive blocks of ``L`` statements of the
program's order that are the same up to where their operands live: each statement's
operation, its operands' kinds (a computed value, a hoisted value, an input, a constant's
value), its guards and its number of outputs are equal, and an operand computed inside its
own block is the same statement of the block in every repetition. :class:`BlockLoop` prints
such a run as ``for (k = 0; k < R; k++)`` around the block's statements: an operand from
outside the block is read from the work array (or ``q``, ``u``, ``h``, ...) at a place that
advances by a constant step along ``k`` when it does (a table of places per ``k`` when it
does not), and the values read outside their block are stored to the work array, by
constant steps. The loop performs the same operations, in the same order, on the same
operands as the straight-line code it replaces: the values are the same, bit for bit.

Examples
--------
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.printers import Program
>>> with Graph() as g:
...     x = g.input("q", 0, 0.5)
...     ys = []
...     for k in range(12):                      # a recursion: body k reads body k - 1
...         x = x * g.input("u", k, 0.1 * k) + 1.0
...         ys.append(x)
>>> prog = Program(g, {"out": ys})
>>> nodes = prog.op_nodes("out").tolist()
>>> [(b.start, b.L, b.R) for b in find_blocks(prog, nodes, {}, {}, min_cover=8, min_period=2)]
[(2, 2, 11)]
"""
from __future__ import annotations

import numpy as np

__all__ = ["BlockLoop", "find_blocks", "block_functions", "MARK", "BLOCK_MIN", "MIN_REPEATS", "MIN_COVER", "MAX_PERIOD"]

#: straight-line statements from which a program's repeated blocks are computed by loops
#: (the 3-D chains at N = 10, ~8,000 statements: C / C++ medians over 9-13 runs 0.49 against
#: 0.60 straight-line for the ball chain, 0.60 against 0.68 for the floating tree; both vary
#: by up to a quarter with the load on the machine's other hardware thread)
BLOCK_MIN = 2000
#: fewest repetitions of a block computed by a loop
MIN_REPEATS = 5
#: shortest block computed by a loop (statements): a loop reads the values its block's
#: recursion carries from the work array, where straight-line code keeps them in registers;
#: the planar pendulum's blocks (14-42 statements) ran 17 % slower as loops at N = 100 and 300
#: (6 % faster at N = 1000), the ball chain's (63-375) 20-50 % faster at every N from 10
MIN_PERIOD = 48
#: fewest statements a loop replaces
MIN_COVER = 256
#: longest block looked for (statements)
MAX_PERIOD = 6000
#: statements of the window whose repetitions propose a block's length
WINDOW = 16
#: block lengths tried at one position (the nearest repetitions of its window), and of those
#: (the longest runs first) verified: bounds the search where shapes repeat but blocks do not
MAX_CANDIDATES, MAX_VERIFIED = 16, 3
_ARRAYS = ("q", "u", "d", "p")
#: the comment on each printed loop of repeated blocks
MARK = "repeated block"


class _Shapes:
    """The program's statements as integer shape codes and their references (operands, then
    guards' operands), with each computed value's position in the statement order."""

    def __init__(self, prog, nodes, guards, where_out):
        keys, hname = prog.g.keys, prog.hname
        self.nodes = nodes
        self.pos = {i: x for x, i in enumerate(nodes)}

        def cat(j):
            if j in hname:
                return "h"
            k = keys[j]
            if k[0] == "c":
                return ("c", repr(k[1]))
            if k[0] == "in":
                return k[1]
            return "x"

        codes, table, refs = [], {}, []
        for i in nodes:
            k = keys[i]
            gds = guards.get(i, ())
            r = list(k[1:])
            for gd in gds:
                r += [gd[1], gd[2]]
            shape = (k[0], tuple(map(cat, r)), tuple((gd[0], gd[3]) for gd in gds), len(where_out.get(i, ())))
            codes.append(table.setdefault(shape, len(table)))
            refs.append(r)
        self.codes = np.array(codes, dtype=np.int64)
        self.refs = refs
        self.cat = cat


def _window_hash(c, w):
    """A hash of each window of ``w`` codes starting at each position (shorter at the end)."""
    n = len(c)
    h = np.zeros(n, dtype=np.uint64)
    mult = np.uint64(1_000_003)
    with np.errstate(over="ignore"):
        for s in range(w):
            part = np.zeros(n, dtype=np.uint64)
            part[:n - s] = c[s:].astype(np.uint64) + np.uint64(1)
            h = h * mult + part
    return h


def _period_run(c, p, L):
    """Positions ``x >= p`` from ``p`` on with ``c[x] == c[x + L]``, counted until the first
    that is not."""
    n = len(c)
    m, step = 0, max(4 * L, 256)
    while p + m + L < n:
        e = min(n - L, p + m + step)
        neq = np.flatnonzero(c[p + m:e] != c[p + m + L:e + L])
        if len(neq):
            return m + int(neq[0])
        m = e - p
        step *= 2
    return m


def _verified(sh, p, L, R):
    """How many of the ``R`` blocks of ``L`` statements from position ``p`` (equal codes) read
    their own block's statements at the same places as the first block does."""
    pos, refs = sh.pos, sh.refs
    local0 = []
    for off in range(L):
        loc = []
        for j in refs[p + off]:
            x = pos.get(j, -1)
            loc.append(x - p if x >= p else -1)
        local0.append(loc)
    for r in range(1, R):
        base = p + r * L
        for off in range(L):
            for j, want in zip(refs[base + off], local0[off]):
                x = pos.get(j, -1)
                if (x - base if x >= base else -1) != want:
                    return r
    return R


def find_blocks(prog, nodes, guards, where_out, min_repeats=None, min_cover=None, min_period=None, max_period=None):
    """Runs of repeated blocks among the straight-line statements ``nodes`` (in the order
    they are printed) of ``prog``: :class:`BlockLoop` s (positions in ``nodes``, in order,
    not overlapping) of at least ``min_repeats`` blocks of ``min_period`` to ``max_period``
    statements covering at least ``min_cover`` statements (None: the module's constants).
    ``guards``: the guards checked after each node (``{node: [guard]}``), ``where_out``: each
    node's output places. Greedy from the first statement: at each position the block length
    (among the distances to the next windows of equal codes) whose run covers the most
    statements."""
    min_repeats = MIN_REPEATS if min_repeats is None else min_repeats
    min_cover = MIN_COVER if min_cover is None else min_cover
    min_period = MIN_PERIOD if min_period is None else min_period
    max_period = MAX_PERIOD if max_period is None else max_period
    sh = _Shapes(prog, nodes, guards, where_out)
    c, n = sh.codes, len(nodes)
    if n < min_cover:
        return []
    H = _window_hash(c, WINDOW)
    Hl = H.tolist()  # the windows' hashes as Python ints: the cheap first test of each candidate
    out, p = [], 0
    while p + min_cover <= n:
        lim = min(n, p + max_period + 1)
        cands = np.flatnonzero(H[p + min_period:lim] == H[p]) + min_period
        best, h0 = [], Hl[p]
        for L in cands[:MAX_CANDIDATES].tolist():
            if p + min_repeats * L > n:
                continue
            # equal blocks of L >= WINDOW statements start equal windows: where one of the
            # repeats' first windows differs, the blocks do (no array compared)
            if L >= WINDOW and any(Hl[p + k * L] != h0 for k in range(2, min_repeats)):
                continue
            if not np.array_equal(c[p:p + (min_repeats - 1) * L], c[p + L:p + min_repeats * L]):
                continue
            R = (_period_run(c, p, L) + L) // L
            if R * L >= min_cover:
                best.append((-R * L, L, R))
        found = None
        for _, L, R in sorted(best)[:MAX_VERIFIED]:
            R = _verified(sh, p, L, R)
            if R >= min_repeats and R * L >= min_cover:
                found = BlockLoop(sh, p, L, R)
                break
        if found is None:
            p += 1
            continue
        out.append(found)
        p += found.L * found.R
    return out


def _affine(v):
    """``(a, s)`` with ``v[k] == a + s k`` for every k, or None."""
    v = np.asarray(v, dtype=np.int64)
    if len(v) < 2:
        return int(v[0]), 0
    s = int(v[1] - v[0])
    return (int(v[0]), s) if np.array_equal(v, v[0] + s * np.arange(len(v))) else None


class BlockLoop:
    """``R`` repetitions of a block of ``L`` statements from position :attr:`start` of the
    program's straight-line statements (see :func:`find_blocks`), printed as one loop by
    :meth:`source` once the work array's places are known."""

    def __init__(self, sh, start, L, R):
        self.start, self.L, self.R = start, L, R
        self.nodes = sh.nodes[start:start + L * R]
        self._sh = sh

    @property
    def weight(self):
        """Statements of the printed loop's body (the program's split into units)."""
        return self.L + 8

    def iteration_of(self):
        """``{node: iteration}`` of the statements the loop computes."""
        L = self.L
        return {i: x // L for x, i in enumerate(self.nodes)}

    def w_reads(self, keys, hidx):
        """``(off, m, nodes)``: every reference ``m`` of the block's statement ``off`` to a
        computed value outside its own iteration, with the value read in each iteration."""
        L, R, nodes, refs = self.L, self.R, self.nodes, self._sh.refs
        pos0 = {i: x for x, i in enumerate(nodes[:L])}
        for off in range(L):
            for m, j0 in enumerate(refs[self.start + off]):
                if (j0 in pos0 and pos0[j0] <= off) or j0 in hidx or keys[j0][0] in ("c", "in"):
                    continue
                yield off, m, [self._ref(r, off, m) for r in range(R)]

    def source(self, fname, linkage, sig, keys, hidx, slot, where_out, guards, expr, leaf, reads=None):
        """C source of ``fname`` (``linkage``, signature ``sig``) running the loop: 0, or 1
        when a guard fails. ``slot``: the work-array place of every value read outside its
        block (those the loop computes are stored there); ``reads``: ``{(off, m): places}``,
        where reference ``m`` of statement ``off`` reads in each iteration instead (see
        :meth:`w_reads`); ``expr(key, names)`` prints one operation, ``leaf(node)`` a
        constant's or ``t``'s text."""
        L, R, nodes = self.L, self.R, self.nodes
        reads = reads or {}
        pos0 = {i: x for x, i in enumerate(nodes[:L])}
        cols, body = [], []

        def place(arr, v):
            """``arr[...]`` at the places ``v`` (one per iteration)."""
            af = _affine(v)
            if af is not None:
                a, s = af
                return f"{arr}[{a}]" if s == 0 else f"{arr}[{a} + {s} * k]"
            cols.append(v)
            return f"{arr}[t[{len(cols) - 1}]]"

        def ref(off, m, j0):
            """The text of reference ``m`` of the block's statement ``off`` (``j0``: its node
            in the first block)."""
            if j0 in pos0 and pos0[j0] <= off:  # (a guard may read its own statement)
                return f"v{pos0[j0]}"
            col = [self._ref(r, off, m) for r in range(R)]
            if j0 in hidx:
                return place("h", [hidx[j] for j in col])
            k = keys[j0]
            if k[0] == "in" and k[1] in _ARRAYS:
                return place(k[1], [keys[j][2] for j in col])
            if k[0] in ("c", "in"):
                return leaf(j0)
            return place("w", reads.get((off, m)) or [slot[j] for j in col])

        for off, i in enumerate(nodes[:L]):
            k = keys[i]
            names = [ref(off, m, j) for m, j in enumerate(k[1:])]
            body.append(f"        const double v{off} = {expr(k, names)};")
            m = len(k) - 1
            for g, gd in enumerate(guards.get(i, ())):
                a, b = ref(off, m + 2 * g, gd[1]), ref(off, m + 2 * g + 1, gd[2])
                body.append(f"        if ({'!' if gd[3] else ''}({a} {gd[0]} {b})) return 1;")
            for o in range(len(where_out.get(i, ()))):
                its = [where_out[nodes[r * L + off]][o] for r in range(R)]
                body.append(f"        {place('out', its)} = v{off};")
            stored = [nodes[r * L + off] in slot for r in range(R)]
            if any(stored):
                if not all(stored):
                    raise AssertionError("block_functions: a loop's value stored in some iterations only")
                body.append(f"        {place('w', [slot[nodes[r * L + off]] for r in range(R)])} = v{off};")
        lines = [f"{linkage} {fname}({sig})\n{{"]
        if cols:
            T = np.array(cols, dtype=np.int64).T
            rows = ",\n".join("{" + ",".join(map(str, row)) + "}" for row in T.tolist())
            lines.append(f"    static const int tab[{R}][{len(cols)}] = {{\n{rows}}};")
        lines.append(f"    for (int k = 0; k < {R}; k++) {{  /* {MARK}: {R} x {L} statements */")
        if cols:
            lines.append("        const int *t = tab[k];")
        lines += body + ["    }", "    return 0;", "}", ""]
        return "\n".join(lines)

    def _ref(self, r, off, m):
        return self._sh.refs[self.start + r * self.L + off][m]


def block_functions(prog, nodes, blocks, chunk, guards, where_out, slot, fname, linkage, sig, expr, leaf, name):
    """The C functions ``[(weight, name, source)]`` of the straight-line ``nodes`` with the
    repeated ``blocks`` (:func:`find_blocks`) as loops, in program order, and the work
    array's size. Straight statements between loops are split into functions of ``chunk``
    statements. ``slot`` (the places already taken, e.g. by output-expression loops) gets
    the place of every value read outside its function or block; the values of one of a
    loop's statements get places advancing by a constant step along the loop.
    ``name(node)``: the text of a node that is not a computed value (hoisted, input,
    constant)."""
    keys = prog.g.keys
    units = []  # ("s", [nodes]) or ("b", BlockLoop)
    p = 0
    for b in blocks + [None]:
        end = len(nodes) if b is None else b.start
        straight = nodes[p:end]
        units += [("s", straight[s:s + chunk]) for s in range(0, len(straight), chunk)]
        if b is not None:
            units.append(("b", b))
            p = b.start + b.L * b.R
    where = {}  # node -> (unit, iteration)
    for u, (kind, part) in enumerate(units):
        if kind == "s":
            for i in part:
                where[i] = (u, 0)
        else:
            for i, r in part.iteration_of().items():
                where[i] = (u, r)
    need = set()
    for u, (kind, part) in enumerate(units):
        members = part if kind == "s" else part.nodes
        for i in members:
            at = where[i]
            refs = list(keys[i][1:])
            for gd in guards.get(i, ()):
                refs += [gd[1], gd[2]]
            for j in refs:
                if j in where and where[j] != at:
                    need.add(j)
    n_work = max(slot.values(), default=-1) + 1
    halo = set()  # free places just before and after a loop's column
    for kind, part in units:  # a loop's values by constant steps: statement by statement, k fastest
        if kind != "b":
            continue
        L, R = part.L, part.R
        for off in range(L):
            col = [part.nodes[r * L + off] for r in range(R)]
            if any(j in need for j in col) and not any(j in slot for j in col):
                for r, j in enumerate(col):
                    slot[j] = n_work + 1 + r
                halo.update((n_work, n_work + R + 1))
                n_work += R + 2
            elif any(j in need for j in col):  # some taken by an output loop already
                for j in col:
                    if j not in slot:
                        slot[j] = n_work
                        n_work += 1
    reads, extra = _halo_reads(units, keys, prog.hidx, where, slot, halo)
    for kind, part in units:
        if kind == "s":
            for i in part:
                if i in need and i not in slot:
                    slot[i] = n_work
                    n_work += 1
    funcs = []
    for u, (kind, part) in enumerate(units):
        fn = f"{fname}_{u}"
        if kind == "b":
            funcs.append((part.weight, fn, part.source(fn, linkage, sig, keys, prog.hidx, slot, where_out, guards,
                                                       expr, leaf, reads.get(u))))
            continue
        funcs.append((len(part), fn, _straight(fn, linkage, sig, keys, part, u, where, slot, where_out, guards,
                                               expr, name, extra)))
    return funcs, n_work


def _halo_reads(units, keys, hidx, where, slot, halo):
    """Where the loops read values computed by straight-line statements (the recursion's
    first or last body, computed before the loop): at the place a column's constant step
    gives, a free place of ``halo`` (beside another loop's column), so that the loop reads
    by constant steps and not through a table. ``({unit: {(off, m): places}}, {node: [more
    places it is stored to]})``; a straight value without a place yet gets its first one
    here (``slot``)."""
    reads, extra, taken = {}, {}, {}
    for u, (kind, part) in enumerate(units):
        if kind != "b":
            continue
        mine = reads.setdefault(u, {})
        for off, m, col in part.w_reads(keys, hidx):
            fixed = [(r, slot[j]) for r, j in enumerate(col) if units[where[j][0]][0] == "b"]
            if len(fixed) == len(col) or len(fixed) < 2:
                continue
            (r0, p0), (r1, p1) = fixed[0], fixed[1]
            s, rem = divmod(p1 - p0, r1 - r0)
            if rem or any(p != p0 + s * (r - r0) for r, p in fixed):
                continue
            want = {r: p0 + s * (r - r0) for r in range(len(col)) if units[where[col[r]][0]][0] == "s"}
            if not all((P in halo and P not in taken) or taken.get(P) == col[r] for r, P in want.items()):
                continue
            for r, P in want.items():
                j = col[r]
                if taken.get(P) == j:
                    continue
                taken[P] = j
                halo.discard(P)
                if j not in slot:
                    slot[j] = P
                else:
                    extra.setdefault(j, []).append(P)
            mine[(off, m)] = [p0 + s * (r - r0) for r in range(len(col))]
    return reads, extra


def _straight(fn, linkage, sig, keys, part, u, where, slot, where_out, guards, expr, name, extra):
    """C source of one function of straight-line statements (unit ``u``); ``extra``: more
    places a value is stored to."""
    def nm(j):
        if j in where:
            return f"x{j}" if where[j][0] == u else f"w[{slot[j]}]"
        return name(j)

    body = []
    for i in part:
        k = keys[i]
        body.append(f"    const double x{i} = {expr(k, [nm(j) for j in k[1:]])};")
        if i in slot:
            body.append(f"    w[{slot[i]}] = x{i};")
        for P in extra.get(i, ()):
            body.append(f"    w[{P}] = x{i};")
        for ko in where_out.get(i, ()):
            body.append(f"    out[{ko}] = x{i};")
        for op, ai, bi, res in guards.get(i, ()):
            body.append(f"    if ({'!' if res else ''}({nm(ai)} {op} {nm(bi)})) return 1;")
    return f"{linkage} {fn}({sig})\n{{\n" + "\n".join(body) + "\n    return 0;\n}\n"
