"""Forward-mode derivatives printed as loops over directions: a C Jacobian program whose text
grows like the traced graph, not like the graph times the number of inputs.

:func:`mbcomp.codegen.tangent.tangent` makes one scalar node per (node, direction) pair: on
an N-link chain ``d fun/dy`` is O(N^2) straight-line operations, 19 MB of machine code at
N = 100, a program bound by fetching its own instructions, and minutes of compiler time.
Here the same chain rule is planned on the graph once (:class:`DirectionPlan`) and printed
as one short loop per stored tangent over the directions it can be nonzero in
(:class:`TangentLoops`):

* **Directions in blocks.** The inputs differentiated with respect to are numbered
  ``0 .. n_dir - 1`` and grouped in contiguous *blocks* (``d fun/dy``: the coordinates, then
  the speeds). A node's tangent is nonzero at most on one interval per block, the hull of
  its operands' intervals: a chain's link ``k`` moves with the first ``k`` joints, so the
  loops do about the sparse forward mode's work.
* **Single-use nodes eliminated.** A tangent is linear in its operands' tangents, so a node
  used once (and not an output) is not stored: its user's tangent is written directly as a
  linear combination of stored tangents (its *leaves*) whose coefficients are the products of
  the local partials along the way (:func:`~mbcomp.codegen.tangent.partials`, the same
  partials as the scalar forward and the reverse mode), made as ordinary nodes of the graph
  and computed with the values, once per call. A node whose tangent is a few unit directions
  (``cos q_k``: ``-sin q_k e_k``) is not stored either: its users add those entries.
* **Stored tangents** live in slots of ``n_dir`` doubles of the work array, reused once their
  last user has run; an output's tangent is written straight into its row of ``out``.

The program is the usual generated function ``(q, u, t, d, h, p, w, out)`` in one library:
a value part (a :class:`~mbcomp.codegen.printers.Program` of the coefficients, with the
traced program's guards, hoisting and chunking) writing the coefficients into the work array,
then the loops reading them. The loops are compiled with gcc's vectorizer at its dynamic
cost model (:data:`LOOP_FLAGS`) and, on x86-64 Linux with gcc, cloned for AVX2 (the clone
is chosen when the library loads; SSE2 elsewhere): element by element the same IEEE
operations (no contraction into fused multiply-adds), so the same numbers either way. The
clones run the loops 1.4-1.7 times faster and double their compile time.

Examples
--------
>>> import numpy as np
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.direction_loops import DirectionPlan
>>> with Graph() as g:
...     x, y, z = (g.input("q", k, v) for k, v in enumerate((0.5, 2.0, 1.5)))
...     s = np.sin(x) * y * z                   # used twice, three directions: stored
...     f = [s * x, s * y + z, 3.0]
>>> plan = DirectionPlan(g, f, [x, y, z], [(0, 3)])
>>> [kind for kind, *_ in plan.outputs], len(plan.statements)
(['node', 'node', 'zero'], 3)
>>> exact = [2.0 * np.cos(0.5) * 2.0 * 1.5, 2.0 * np.sin(0.5) * 1.5 + np.sin(0.5) * 2.0 * 1.5,
...          2.0 * np.sin(0.5) * 2.0 + 1.0]      # d(s y + z) = y ds + s dy + dz
>>> bool(np.allclose(plan.dense(1), exact, rtol=1e-15, atol=0))
True
"""
from __future__ import annotations

import ctypes

from .graph import Sym
from .loaded import PROGRAM_ARGTYPES
from .printers import LOCAL_MACRO, SIGNATURE, ParamProgram, Program
from .tangent import OPERATIONS, cone, input_positions, partials
from .toolchain import FLAGS, HEADER, cached_library, chunk, n_units

__all__ = ["DirectionPlan", "TangentLoops", "MAX_TERMS", "UNIT_TERMS", "LOOPS_PER_FUNCTION", "LOOP_FLAGS"]

#: most terms one loop combines; a node whose combination would be longer is stored
MAX_TERMS = 12
#: a node whose tangent is at most this many unit directions (and no stored tangent) is not
#: stored: its users add the entries
UNIT_TERMS = 2
#: loop statements per C function (gcc's time per function grows faster than its length)
LOOPS_PER_FUNCTION = 300
#: flags of the loops' translation units, after the toolchain's: the loops need the
#: vectorizer (at -O2 gcc 12's "very cheap" model leaves every loop whose trip count is not a
#: multiple of the vector width scalar) and nothing else of -O2 (planar 24-link chain, per
#: call and cold build: -O2 with the dynamic model 7.7 us, 6.4 s; -O1 with the vectorizer 7.6
#: us, 4.5 s; no vectorizer 20 us)
LOOP_FLAGS = ("-O1", "-ftree-loop-vectorize", "-fvect-cost-model=dynamic")
_WIDE = ("#ifndef MBCOMP_WIDE\n#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) "
         "&& defined(__linux__)\n#define MBCOMP_WIDE __attribute__((target_clones(\"avx2\", \"default\")))\n"
         "#else\n#define MBCOMP_WIDE\n#endif\n#endif\n")
_LOOP_SIG = "const double *restrict c, double *restrict T, double *restrict out"


class _Lin:
    """A tangent as a linear combination: ``slots`` {stored node: coefficient} and ``units``
    {direction: coefficient}; coefficients are Sym or numbers."""

    __slots__ = ("slots", "units")

    def __init__(self, slots=None, units=None):
        self.slots = slots if slots is not None else {}
        self.units = units if units is not None else {}

    def add_scaled(self, other, c):
        one = type(c) is float and c == 1.0
        for tgt, src in ((self.slots, other.slots), (self.units, other.units)):
            for leaf, v in src.items():
                term = v if one else c * v
                old = tgt.get(leaf)
                tgt[leaf] = term if old is None else old + term

    def coefficients(self):
        return list(self.slots.values()) + list(self.units.values())


class DirectionPlan:
    """The plan of ``d outputs / d inputs`` as loops over directions (see the module notes).

    Parameters
    ----------
    graph : Graph
        The traced graph; the coefficients are built in it (it is made current meanwhile).
    outputs : sequence of Sym or float
    inputs : sequence of Sym or None
        The input nodes; direction ``k`` is position ``k`` (None: a zero column).
    blocks : sequence of (start, stop)
        Contiguous, disjoint blocks covering ``0 .. len(inputs)``.

    Attributes
    ----------
    n_dir : int
        Directions (columns of the Jacobian).
    statements : list of (node, lin, hull)
        The stored tangents in order: ``lin`` the combination (``.slots``: {stored node:
        coefficient}, ``.units``: {direction: coefficient}), ``hull`` per block ``(lo, hi)``
        or None (absolute directions).
    hull : dict
        Node -> its hull, for every stored node.
    outputs : list
        Per output: ``("zero",)``, ``("node", node)`` (a stored tangent) or ``("lin", lin)``
        (unit directions only).
    coefficients : list of Sym
        Every coefficient the loops read, once each (the value program computes them).

    Raises
    ------
    ValueError
        When an input is not an input node of ``graph``, or the graph has an operation the
        forward mode does not know (:data:`~mbcomp.codegen.tangent.OPERATIONS`).
    """

    def __init__(self, graph, outputs, inputs, blocks):
        keys = graph.keys
        seed = input_positions(graph, inputs, "DirectionPlan")
        self.n_dir = len(inputs)
        self.blocks = [tuple(b) for b in blocks]
        outputs = list(outputs)
        out_nodes = {o.i for o in outputs if type(o) is Sym}
        order = cone(keys, sorted(out_nodes))
        uses = {}
        for i in order:
            k = keys[i]
            if k[0] not in ("c", "in"):
                for j in set(k[1:]):
                    uses[j] = uses.get(j, 0) + 1
        lin, self.hull, self.statements = {}, {}, []
        with graph:
            for i in order:
                k = keys[i]
                if k[0] == "in":
                    if i in seed:
                        lin[i] = _Lin(units={seed[i]: 1.0})
                    continue
                if k[0] == "c":
                    continue
                mine = self._combine(graph, i, k, lin)
                if mine is None:
                    continue
                lin[i] = mine
                shared = uses.get(i, 0) > 1 or i in out_nodes
                few_units = not mine.slots and len(mine.units) <= UNIT_TERMS
                if (shared and not few_units) or len(mine.slots) + len(mine.units) > MAX_TERMS:
                    self.hull[i] = self._hull_of(mine)
                    self.statements.append((i, mine, self.hull[i]))
                    lin[i] = _Lin(slots={i: 1.0})  # its users read the stored tangent
        stored = self.hull
        self.outputs = []
        for o in outputs:
            if type(o) is not Sym or o.i not in lin:
                self.outputs.append(("zero",))
            elif o.i in stored:
                self.outputs.append(("node", o.i))
            else:
                self.outputs.append(("lin", lin[o.i]))
        coefs, seen = [], set()
        every = [mine for _, mine, _ in self.statements] + [o[1] for o in self.outputs if o[0] == "lin"]
        for mine in every:
            for c in mine.coefficients():
                if type(c) is Sym and c.i not in seen:
                    seen.add(c.i)
                    coefs.append(c)
        self.coefficients = coefs

    @staticmethod
    def _combine(graph, i, key, lin):
        """Node ``i``'s tangent as a combination of its operands' (None: structurally zero)."""
        op, args = key[0], key[1:]
        if op not in OPERATIONS:
            raise ValueError(f"DirectionPlan: the graph has an operation {op!r} the forward mode cannot differentiate")
        active = [a in lin for a in args]
        if not any(active):
            return None
        parts = partials(graph, i, need_b=len(args) > 1 and active[1])
        if len(args) == 2 and args[0] == args[1]:  # x op x: one operand, its partials summed
            args, active, parts = args[:1], active[:1], (parts[0] + parts[1],)
        mine = _Lin()
        for a, act, p in zip(args, active, parts):
            if act and not (type(p) is float and p == 0.0):
                mine.add_scaled(lin[a], p)
        return mine

    def _hull_of(self, mine):
        out = []
        for b, (lo_b, hi_b) in enumerate(self.blocks):
            lo, hi = hi_b, lo_b
            for leaf in mine.slots:
                h = self.hull[leaf][b]
                if h is not None:
                    lo, hi = min(lo, h[0]), max(hi, h[1])
            for d in mine.units:
                if lo_b <= d < hi_b:
                    lo, hi = min(lo, d), max(hi, d + 1)
            out.append((lo, hi) if lo < hi else None)
        return out

    def n_element_ops(self):
        """Multiply-adds the loops do per call (each loop's width times its terms)."""
        total = 0
        for _, mine, h in self.statements:
            width = sum(b[1] - b[0] for b in h if b is not None)
            total += width * max(1, len(mine.slots)) + len(mine.units)
        return total

    def dense(self, r):
        """Row ``r`` of the Jacobian at the trace point, from the trace-time values (a check of
        the plan in Python; the programs compute the same at any state)."""
        val = {}
        for i, mine, h in self.statements:
            row = [0.0] * self.n_dir
            for leaf, c in mine.slots.items():
                cv = getattr(c, "v", c)
                for d, x in enumerate(val[leaf]):
                    row[d] += cv * x
            for d, c in mine.units.items():
                row[d] += getattr(c, "v", c)
            val[i] = row
        o = self.outputs[r]
        if o[0] == "zero":
            return [0.0] * self.n_dir
        if o[0] == "node":
            return val[o[1]]
        row = [0.0] * self.n_dir
        for d, c in o[1].units.items():
            row[d] += getattr(c, "v", c)
        return row


def _num(x):
    r = repr(float(x))
    return f"({r})" if float(x) < 0 else r


def _places(plan):
    """Where each stored tangent lives: ``({node: C array expression at index k}, n_slots)``.
    Outputs live in their first row of ``out``; the others in slots of ``T``, a slot free
    again after the statement that last reads it."""
    n_dir = plan.n_dir
    first_row = {}
    for r, o in enumerate(plan.outputs):
        if o[0] == "node":
            first_row.setdefault(o[1], r)
    last = {}
    for s, (_, mine, _) in enumerate(plan.statements):
        for leaf in mine.slots:
            last[leaf] = s
    dying = {}
    for leaf, s in last.items():
        dying.setdefault(s, []).append(leaf)
    place, slot_of, free, n_slots = {}, {}, [], 0
    for s, (i, _, _) in enumerate(plan.statements):
        if i in first_row:
            place[i] = f"out[{first_row[i] * n_dir}+k]"
        else:
            slot = free.pop() if free else n_slots
            n_slots = max(n_slots, slot + 1)
            slot_of[i] = slot
            place[i] = f"T[{slot * n_dir}+k]"
        for leaf in dying.get(s, ()):
            if leaf in slot_of and leaf != i:  # freed after the statement's own slot is taken
                free.append(slot_of[leaf])
    return place, first_row, n_slots


def _statement_lines(plan, i, mine, h, place, coef):
    """The C lines computing stored tangent ``i``: per block, one loop per stretch of its hull
    over which the same leaves are nonzero, then the unit entries."""
    dst, lines = place[i], []
    for b in range(len(plan.blocks)):
        if h[b] is None:
            continue
        lo, hi = h[b]
        cuts = {lo, hi}
        for leaf in mine.slots:
            lh = plan.hull[leaf][b]
            if lh is not None:
                cuts.update((max(lo, lh[0]), min(hi, lh[1])))
        cuts = sorted(cuts)
        for a, z in zip(cuts[:-1], cuts[1:]):
            terms = []
            for leaf, cf in mine.slots.items():
                lh = plan.hull[leaf][b]
                if lh is not None and lh[0] <= a and z <= lh[1]:
                    terms.append(place[leaf] if type(cf) is float and cf == 1.0 else f"{coef(cf)}*{place[leaf]}")
            lines.append(f"    for (long k = {a}; k < {z}; ++k) {dst} = {' + '.join(terms) or '0.0'};")
    for d, cf in mine.units.items():
        lines.append(f"    {{ const long k = {d}; {dst} += {coef(cf)}; }}")
    return lines


def _output_lines(plan, first_row, coef):
    """The C lines completing ``out``: zeros outside the stored outputs' hulls, rows of unit
    entries, repeated outputs copied (after every first row is complete)."""
    n_dir, lines, copies = plan.n_dir, [], []
    for r, o in enumerate(plan.outputs):
        row = f"out[{r * n_dir}+k]"
        if o[0] != "node":
            lines.append(f"    for (long k = 0; k < {n_dir}; ++k) {row} = 0.0;")
            if o[0] == "lin":
                lines += [f"    {{ const long k = {d}; {row} += {coef(cf)}; }}" for d, cf in o[1].units.items()]
            continue
        i = o[1]
        if first_row[i] != r:
            copies.append(f"    for (long k = 0; k < {n_dir}; ++k) {row} = out[{first_row[i] * n_dir}+k];")
            continue
        at = 0
        for h in plan.hull[i]:
            if h is not None:
                if at < h[0]:
                    lines.append(f"    for (long k = {at}; k < {h[0]}; ++k) {row} = 0.0;")
                at = h[1]
        if at < n_dir:
            lines.append(f"    for (long k = {at}; k < {n_dir}; ++k) {row} = 0.0;")
    return lines + copies


class TangentLoops:
    """``d outputs / d inputs`` as one compiled C function with the generated programs'
    signature ``int fname(q, u, t, d, h, p, w, out)``: ``out`` the row-major ``(len(outputs),
    n_dir)`` Jacobian; returns 1 when a guard of the traced program fails (the program does
    not hold at that state), else 0. An entry whose partials are not finite is NaN: the
    caller checks.

    Parameters
    ----------
    graph, outputs, inputs, blocks
        As :class:`DirectionPlan`.
    guards : sequence
        The traced program's guards (the decisions taken while tracing ``outputs``).
    fname : str
        The C function's name and its library's cache stem.
    cache_dir : str or None
    what : str
        What the program is, for the error messages.

    Attributes
    ----------
    pre : ParamProgram
        ``pre.run(parameter values)`` gives ``h``.
    cfun : ctypes function
    n_work : int
        Doubles of work array the function needs (values crossing functions, the
        coefficients, the tangent slots).
    n_ops : int
        Scalar operations of the value part plus the loops' multiply-adds, per call.
    backend : str
        ``"c"``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen import c_compiler
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.direction_loops import TangentLoops
    >>> with Graph() as g:
    ...     x, y = g.input("q", 0, 0.5), g.input("u", 0, 2.0)
    ...     f = [np.sin(x) * y, y * y]
    >>> prog = TangentLoops(g, f, [x, y], [(0, 1), (1, 2)], g.guards, "example_loops", None,
    ...                     "an example") if c_compiler() else None
    >>> if prog is not None:
    ...     q, u, w, out = np.array([0.5]), np.array([2.0]), np.zeros(prog.n_work + 1), np.zeros(4)
    ...     h = np.array(prog.pre.run([]) + [0.0])
    ...     assert prog.cfun(q.ctypes.data, u.ctypes.data, 0.0, None, h.ctypes.data, None,
    ...                      w.ctypes.data, out.ctypes.data) == 0
    ...     assert np.allclose(out, [2 * np.cos(0.5), np.sin(0.5), 0.0, 4.0], rtol=1e-15)
    """

    backend = "c"

    def __init__(self, graph, outputs, inputs, blocks, guards, fname, cache_dir, what):
        self.plan = plan = DirectionPlan(graph, outputs, inputs, blocks)
        prog = Program(graph, {"coef": plan.coefficients}, guard_groups={"coef": list(guards)})
        self.pre = ParamProgram(prog)
        value_parts, n_value_work = prog.c_parts("coef", f"{fname}_v", chunk, n_parts=n_units)
        index = {c.i: k for k, c in enumerate(plan.coefficients)}

        def coef(c):
            return f"c[{index[c.i]}]" if type(c) is Sym else _num(c)

        place, first_row, n_slots = _places(plan)
        lines = [ln for i, mine, h in plan.statements for ln in _statement_lines(plan, i, mine, h, place, coef)]
        lines += _output_lines(plan, first_row, coef)
        n_c = len(plan.coefficients)
        entry = (f"int {fname}_v({SIGNATURE});\n"
                 f"int {fname}({SIGNATURE})\n{{\n    double *C = w + {n_value_work};\n"
                 f"    if ({fname}_v(q, u, t, d, h, p, w, C)) return 1;\n"
                 + "".join(f"    {fn}(C, C + {n_c}, out);\n" for fn in _loop_names(fname, len(lines)))
                 + "    return 0;\n}\n")
        units = [(f"{fname}_v{k}", HEADER + src, list(FLAGS)) for k, src in enumerate(value_parts)]
        units += [(f"{fname}_l{k}", HEADER + src, list(FLAGS) + list(LOOP_FLAGS))
                  for k, src in enumerate(_loop_units(fname, lines, entry))]
        self.dll = cached_library(units, fname, cache_dir, what)
        self.cfun = getattr(self.dll, fname)
        self.cfun.argtypes = PROGRAM_ARGTYPES
        self.cfun.restype = ctypes.c_int
        self.n_work = n_value_work + n_c + n_slots * plan.n_dir
        self.n_ops = prog.n_ops("coef") + plan.n_element_ops()


def _loop_names(fname, n_lines):
    return [f"{fname}_L{k}" for k in range(max(1, -(-n_lines // LOOPS_PER_FUNCTION)))]


def _loop_units(fname, lines, entry):
    """The loops as functions of :data:`LOOPS_PER_FUNCTION` lines, in as many translation
    units as the toolchain's policy gives for their size (compiled in parallel); the entry in
    the last."""
    names = _loop_names(fname, len(lines))
    funcs = [f"MBCOMP_LOCAL MBCOMP_WIDE void {fn}({_LOOP_SIG})\n{{\n"
             + "\n".join(lines[k * LOOPS_PER_FUNCTION:(k + 1) * LOOPS_PER_FUNCTION])
             + "\n    (void)c; (void)T; (void)out;\n}\n" for k, fn in enumerate(names)]
    n = max(1, min(len(funcs), n_units(2 * len(lines))))
    per = -(-len(funcs) // n)
    # declared without the clones: a caller in another unit calls the resolved symbol
    decl = "".join(f"MBCOMP_LOCAL void {fn}({_LOOP_SIG});\n" for fn in names)
    units = ["\n".join(funcs[k * per:(k + 1) * per]) for k in range(n)]
    return [LOCAL_MACRO + _WIDE + u for u in units[:-1]] + [LOCAL_MACRO + _WIDE + decl + units[-1] + "\n" + entry]
