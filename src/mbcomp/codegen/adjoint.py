"""Reverse-mode (adjoint) differentiation of a traced :class:`~mbcomp.codegen.graph.Graph`,
and the generated program of the vector-Jacobian products of the Lagrange index-1
right-hand side: ``lam^T d fun / d y`` and ``lam^T d fun / d p``.

:func:`reverse` builds, in the same graph and with the same :class:`~mbcomp.codegen.graph.Sym`
operations, the nodes of ``sum_i w_i d outputs[i] / d inputs[k]`` by reverse accumulation:
the nodes between the inputs and the outputs are visited once in reverse topological
(index) order, each passing its adjoint times its local partials
(:func:`mbcomp.codegen.tangent.partials`, the partials forward mode uses) to its operands.
One sweep gives the derivatives with respect to every input at once, so the cost does not
grow with the number of parameters (forward mode's grows with it). Weights may be input
nodes (the adjoint ``lam`` as per-call inputs) or numbers; a derivative that is
structurally zero stays the number ``0.0``, and comparisons are guards as for
:func:`~mbcomp.codegen.tangent.tangent` (the program is exact within the traced branch).

:class:`AdjointCode` prints the products of the right-hand side ``fun(t, y)`` (traced with
``program="fun"``) with the weights ``lam`` as per-call inputs ``d[2:2+n]`` after the
Baumgarte gains, or the value and gradient of one traced scalar (an objective built on a
trace's outputs), to Python or C; parameter-only subexpressions (the partials of
parameter-only nodes among them) are hoisted and computed once per parameter set.

Examples
--------
>>> import numpy as np
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.adjoint import reverse
>>> with Graph() as g:
...     x, y = g.input("q", 0, 0.5), g.input("u", 0, 2.0)
...     lam0, lam1 = g.input("d", 0, 1.0), g.input("d", 1, 10.0)
...     f = [np.sin(x) * y, y * y]
>>> gx, gy = reverse(g, f, [lam0, lam1], [x, y])   # lam^T J: [lam0 y cos x, lam0 sin x + 2 lam1 y]
>>> round(gx.v, 12), round(gy.v, 12)
(1.755165123781, 40.479425538604)
"""
from __future__ import annotations

import ctypes

import numpy as np

from .graph import Fallback, Retrace, Sym, no_gc
from .printers import Program
from .loaded import LoadedProgram
from .tangent import cone, input_positions, partials
from .toolchain import FLAGS, HEADER, cached_library
from .tracer import param_layout, param_vector, trace

__all__ = ["reverse", "AdjointCode", "BoundAdjoint", "AdjointIntegrator", "chebyshev_nodes", "ADJOINT_GLUE"]


def _is_zero(x):
    return type(x) is not Sym and x == 0.0


def reverse(graph, outputs, weights, inputs):
    """The nodes of ``sum_i weights[i] * d outputs[i] / d inputs[k]`` for every ``k``, built in
    ``graph`` by reverse accumulation.

    Parameters
    ----------
    graph : Graph
        The graph the outputs were traced into (made current while building).
    outputs : sequence of Sym or float
        The values to differentiate (numbers have derivative zero).
    weights : sequence of Sym or float
        One weight per output: nodes of ``graph`` (e.g. inputs: the adjoint variables) or numbers.
    inputs : sequence of Sym or None
        Input nodes (``graph.input``) to differentiate with respect to; None for an input the
        tracer did not make (its derivative is zero).

    Returns
    -------
    list
        Per input: a :class:`~mbcomp.codegen.graph.Sym` of ``graph`` (its trace-time value in
        ``.v``), or the number ``0.0`` when the weighted outputs do not depend on it.

    Raises
    ------
    ValueError
        When an entry of ``inputs`` is not an input node of ``graph``, the weights are not one
        per output, or a node has an operation the partials do not know.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.adjoint import reverse
    >>> with Graph() as g:
    ...     x, k, z = g.input("q", 0, 3.0), g.input("p", 0, 2.0, state=False), g.input("q", 1, 1.0)
    ...     f = k * x ** 3 + np.exp(x / k)
    >>> dx, dk, dz = reverse(g, [f], [1.0], [x, k, z])
    >>> bool(abs(dx.v - (3 * 2.0 * 9.0 + np.exp(1.5) / 2.0)) < 1e-12), dz   # f does not depend on z
    (True, 0.0)
    """
    keys = graph.keys
    outputs, weights = list(outputs), list(weights)
    if len(outputs) != len(weights):
        raise ValueError(f"reverse: {len(outputs)} outputs but {len(weights)} weights (give one weight per output)")
    seeds = set(input_positions(graph, inputs, "reverse"))
    # the nodes on a path from an input to an output, in index (topological) order
    depends = set()
    for i in cone(keys, [o.i for o in outputs if type(o) is Sym]):
        key = keys[i]
        if i in seeds or (key[0] not in ("c", "in") and any(j in depends for j in key[1:])):
            depends.add(i)
    adj = {}
    with graph:
        for o, w in zip(outputs, weights):
            if type(o) is Sym and o.i in depends and not _is_zero(w):
                adj[o.i] = adj[o.i] + w if o.i in adj else w
        for i in sorted(depends, reverse=True):
            key = keys[i]
            if key[0] == "in":
                continue
            a = adj.pop(i, None)
            if a is None or _is_zero(a):
                continue
            ops = key[1:]
            parts = partials(graph, i, len(ops) > 1 and ops[1] in depends)
            for j, p in zip(ops, parts):
                if j not in depends:
                    continue
                c = a * p
                if _is_zero(c):
                    continue
                adj[j] = adj[j] + c if j in adj else c
    out = [0.0 if x is None else adj.get(x.i, 0.0) for x in inputs]
    # a derivative that is a constant node is given as its number: a literal in the program
    # rather than a hoisted value
    return [v.v if type(v) is Sym and keys[v.i][0] == "c" else v for v in out]


class AdjointCode:
    """The generated program of the vector-Jacobian products of a traced right-hand side (or
    the value and gradient of a traced scalar), for one row mask and parameter signature;
    :meth:`bind` gives the callable.

    With ``objective=None`` the program's per-call inputs are ``d = [alpha, beta, lam]``
    (``lam``: ``n = nq + nu`` weights) and its outputs ``[lam^T dfun/dq, lam^T dfun/du,
    lam^T dfun/dp]`` (``n + n_p`` numbers, ``p`` the entries :attr:`wrt`). Given
    ``objective`` (a node or number of ``tr.graph``, e.g. built on ``program="outputs"``),
    ``d = [alpha, beta]`` and the outputs are ``[value, d/dq, d/du, d/dp]`` (``1 + n + n_p``).

    Parameters
    ----------
    tr : namespace
        A trace (:func:`mbcomp.codegen.tracer.trace`) with group ``"fun"`` (or the group
        ``group`` the objective was built on), without drives or inputs taken per call.
    backend : {"python", "c"}
    cache_dir : str, optional
        The compiled programs' cache (C).
    objective : Sym or float, optional
        The scalar to differentiate instead of the right-hand side.
    group : str
        The trace's group whose guards the program checks (``"fun"``; ``"outputs"`` for an
        objective on the result columns).
    keep : sequence of (path, name)
        The parameters the trace kept as inputs where zero (checked again by :meth:`bind`).
    wrt : sequence of (path, name, index), optional
        The runtime parameters to differentiate with respect to (default: all of :attr:`layout`).

    Attributes
    ----------
    n : int
        ``nq + nu``.
    layout : list
        The runtime parameters ``(path, name, index)`` (:func:`~mbcomp.codegen.tracer.param_layout`).
    wrt : list
        Those the program differentiates with respect to, in the order of its outputs.
    n_ops : int
        Operations per call.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.adjoint import AdjointCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> code = AdjointCode.build(system, "python")
    >>> code.n, code.layout        # free fall: fun = [u, g_z], J = [[0, 1], [0, 0]]
    (2, [('b', 'm', None), ('s', 'n', (np.int64(2),)), ('world', 'g', (np.int64(2),))])
    >>> code.bind(system)(0.0, np.zeros(2), [0.0, 0.0, 3.0, 5.0]).tolist()  # [lam^T J, lam^T dfun/dp]
    [0.0, 3.0, 0.0, 0.0, 5.0]

    (``du/dt = g_z``: the mass cancels, the axis is normalized, ``d/dg_z = 1``.)
    """

    def __init__(self, tr, backend, cache_dir=None, objective=None, group="fun", keep=(), wrt=None):
        if backend not in ("python", "c"):  # before the reverse sweep (LoadedProgram checks only after it)
            raise ValueError(f"backend {backend!r} is unknown for the adjoint program; use 'python' or 'c'")
        g = tr.graph
        self.signature, self.layout, self.keep = tr.signature, tr.layout, tuple(keep)
        self.wrt = list(self.layout) if wrt is None else [tuple(w) for w in wrt]
        for w in self.wrt:
            if w not in self.layout:
                raise ValueError(f"adjoint program: {w[0]}.{w[1]}{'' if w[2] is None else list(w[2])} is not a "
                                 "runtime parameter of the program (a zero entry? give it in keep=)")
        nq = len(tr.groups["qrate"])
        nu = sum(1 for k in g.keys if k[0] == "in" and k[1] == "u")
        self.n, self.nq = nq + nu, nq
        ins = ([g.memo.get(("in", "q", k)) for k in range(nq)] + [g.memo.get(("in", "u", k)) for k in range(nu)]
               + [g.memo.get(("in", "p", self.layout.index(w))) for w in self.wrt])
        if objective is None:
            fun = tr.groups["fun"]
            lam = [g.input("d", 2 + k, 0.3 + 0.1 * k) for k in range(self.n)]
            outs, weights, lead = fun, lam, []
        else:
            if type(objective) is Sym and g.keys[objective.i][0] == "c":
                objective = objective.v
            outs, weights, lead = [objective], [1.0], [objective]
        flat = reverse(g, outs, weights, ins)
        self.n_out = len(lead) + len(flat)
        self.scalar = objective is not None
        prog = Program(g, {"vjp": lead + flat}, guard_groups={"vjp": list(tr.guard_groups[group])})
        self.backend = backend
        self.loaded = LoadedProgram(prog, "vjp", "mbcomp_vjp", backend, cache_dir, "adjoint program")
        self.pre, self.n_ops, self.n_work = self.loaded.pre, self.loaded.n_ops, self.loaded.n_work

    @classmethod
    def build(cls, system, backend, keep=(), cache_dir=None, max_nodes=3_000_000, wrt=None):
        """The vector-Jacobian program of ``system``'s Lagrange right-hand side (its current row
        mask), or None when there is none (a singular trace point, drives or inputs the
        program takes per call). ``keep``: parameters ``(path, name)`` made inputs even where
        zero (:func:`~mbcomp.codegen.tracer.param_layout`), so their products are computed;
        ``wrt``: the entries ``(path, name, index)`` of the layout to differentiate with
        respect to, in the order of the outputs (default: every runtime parameter)."""
        with no_gc():
            tr = trace(system, max_nodes, program="fun", keep=keep)
            if "fun" not in tr.groups or tr.drives or tr.inputs:
                return None
            return cls(tr, backend, cache_dir, keep=keep, wrt=wrt)

    def bind(self, system):
        """The callable :class:`BoundAdjoint` for ``system``'s parameter values; None when they
        change a decision baked into the program (then it must be built again)."""
        if param_layout(system, self.keep)[1] != self.signature:
            return None
        pv = param_vector(system, self.layout)
        try:
            h = self.pre.run(pv)
        except Retrace:
            return None
        return BoundAdjoint(self, pv, h)


class BoundAdjoint:
    """An :class:`AdjointCode` bound to one parameter set: ``out = vjp(t, y, d)`` with ``y = [q,
    u]`` and the per-call inputs ``d`` (``[alpha, beta, lam]``, or ``[alpha, beta]`` for an
    objective; the Baumgarte gains in 1/s): a float array (see :class:`AdjointCode`), or None
    where the program does not hold (a failed guard, a non-finite entry).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.adjoint import AdjointCode
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> vjp = AdjointCode.build(system, "python").bind(system)
    >>> out = vjp(0.0, np.array([0.5, 0.0]), [0.0, 0.0, 0.0, 1.0])   # lam = e_u: the row of du/dt
    >>> bool(abs(out[0] + 9.81 * np.cos(0.5)) < 1e-12), float(out[1])   # d/dphi of -g sin(phi) / L
    (True, 0.0)
    """

    def __init__(self, code, pv, h):
        self.code, self.h = code, h
        self.nq = code.nq
        if code.backend == "c":
            self.hbuf = np.array(list(h) + [0.0], float)
            self.pbuf = np.array(list(pv) + [0.0], float)
            self.ybuf = np.zeros(code.n + 1)
            self.dbuf = np.zeros(2 + (0 if code.scalar else code.n) + 1)
            self.wbuf = np.zeros(max(code.n_work, 1))
            self.obuf = np.zeros(code.n_out + 1)

    def __call__(self, t, y, d):
        code, nq = self.code, self.nq
        if code.backend == "python":
            try:
                out = code.loaded.fun(list(map(float, y[:nq])), list(map(float, y[nq:code.n])), float(t),
                               list(map(float, d)), self.h)
            except (Fallback, ArithmeticError, ValueError):
                return None
            out = np.array(out, float)
        else:
            self.ybuf[:code.n] = y
            self.dbuf[:len(d)] = d
            base = self.ybuf.ctypes.data
            if code.loaded.cfun(base, base + 8 * nq, float(t), self.dbuf.ctypes.data, self.hbuf.ctypes.data,
                                   self.pbuf.ctypes.data, self.wbuf.ctypes.data, self.obuf.ctypes.data):
                return None
            out = self.obuf[:code.n_out].copy()
        return out if np.isfinite(out).all() else None


#: the adjoint's right-hand side in C, for the runtime's integrators (``mbrt_dop853``): the
#: state ``y(t)`` interpolated from its values at Chebyshev nodes of each sub-segment of a
#: forward stretch (barycentric formula), then one call of the vector-Jacobian program and
#: one of the objective's integrand program (through function pointers: the glue is the same
#: for every model). Time runs backwards: ``t = t_hi - s``.
ADJOINT_GLUE = r"""
#include <string.h>
typedef int (*mbcomp_prog)(const double *restrict q, const double *restrict u, double t, const double *restrict d,
                           const double *restrict h, const double *restrict p, double *restrict w,
                           double *restrict out);
typedef struct {
    mbcomp_prog vjp; const double *vh, *vp; double *vw;  /* lam^T df/d(y, p) and its hoisted, params, work */
    mbcomp_prog obj; const double *oh, *op; double *ow;  /* the integrand's [g, dg/dy, dg/dp] or NULL  */
    int nq, n, np;                  /* coordinates, state size, parameters                          */
    double t_lo, t_hi;              /* the stretch                                                   */
    int nseg, nnode;                /* equal sub-segments, Chebyshev nodes in each                   */
    const double *Y;                /* nseg * nnode * n: y at the nodes                              */
    const double *x, *bw;           /* the nodes in [0, 1] and their barycentric weights             */
    double *y, *d, *vout, *oout;    /* scratch: n, 2 + n (gains, lam), n + np, 1 + n + np           */
    int failed;                     /* 1: the adjoint program's guard, 2: the integrand's           */
} mbcomp_adj_ctx;

int mbcomp_adj_rhs(void *c, double s, const double *z, double *dz)
{
    mbcomp_adj_ctx *x = (mbcomp_adj_ctx *)c;
    const int n = x->n, m = x->n + x->np;
    const double t = x->t_hi - s, len = (x->t_hi - x->t_lo) / x->nseg;
    double r = (t - x->t_lo) / len;
    int k = (int)floor(r);
    if (k < 0) k = 0;
    if (k >= x->nseg) k = x->nseg - 1;
    const double xi = r - k;
    const double *Yk = x->Y + (size_t)k * x->nnode * n;
    int hit = -1;
    for (int j = 0; j < x->nnode; j++)
        if (xi == x->x[j]) hit = j;
    if (hit >= 0) {
        memcpy(x->y, Yk + (size_t)hit * n, sizeof(double) * (size_t)n);
    } else {
        double sum = 0.0;
        for (int i = 0; i < n; i++) x->y[i] = 0.0;
        for (int j = 0; j < x->nnode; j++) {
            const double cj = x->bw[j] / (xi - x->x[j]);
            const double *Yj = Yk + (size_t)j * n;
            sum += cj;
            for (int i = 0; i < n; i++) x->y[i] += cj * Yj[i];
        }
        for (int i = 0; i < n; i++) x->y[i] /= sum;
    }
    memcpy(x->d + 2, z, sizeof(double) * (size_t)n);
    if (x->vjp(x->y, x->y + x->nq, t, x->d, x->vh, x->vp, x->vw, x->vout)) { x->failed = 1; return 1; }
    for (int i = 0; i < m; i++) dz[i] = x->vout[i];   /* dlam/ds = +(df/dy^T lam + dg/dy^T), s = t_hi - t */
    dz[m] = 0.0;
    if (x->obj != NULL) {
        if (x->obj(x->y, x->y + x->nq, t, x->d, x->oh, x->op, x->ow, x->oout)) { x->failed = 2; return 1; }
        for (int i = 0; i < m; i++) dz[i] += x->oout[1 + i];
        dz[m] = x->oout[0];
    }
    for (int i = 0; i <= m; i++)
        if (!isfinite(dz[i])) { x->failed = 3; return 1; }
    return 0;
}
"""


class _AdjCtx(ctypes.Structure):
    _fields_ = ([("vjp", ctypes.c_void_p), ("vh", ctypes.c_void_p), ("vp", ctypes.c_void_p), ("vw", ctypes.c_void_p),
                 ("obj", ctypes.c_void_p), ("oh", ctypes.c_void_p), ("op", ctypes.c_void_p), ("ow", ctypes.c_void_p),
                 ("nq", ctypes.c_int), ("n", ctypes.c_int), ("np", ctypes.c_int),
                 ("t_lo", ctypes.c_double), ("t_hi", ctypes.c_double), ("nseg", ctypes.c_int), ("nnode", ctypes.c_int)]
                + [(k, ctypes.c_void_p) for k in ("Y", "x", "bw", "y", "d", "vout", "oout")]
                + [("failed", ctypes.c_int)])


def chebyshev_nodes(k):
    """``k`` Chebyshev points of the second kind on ``[0, 1]`` (ends included) and their
    barycentric weights: the polynomial through values there is well conditioned at any degree.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen.adjoint import chebyshev_nodes
    >>> x, w = chebyshev_nodes(5)
    >>> x.round(6).tolist(), w.tolist()
    ([0.0, 0.146447, 0.5, 0.853553, 1.0], [0.5, -1.0, 1.0, -1.0, 0.5])
    """
    j = np.arange(k)
    x = 0.5 - 0.5 * np.cos(np.pi * j / (k - 1))
    w = (-1.0) ** j
    w[0] *= 0.5
    w[-1] *= 0.5
    return x, w


class AdjointIntegrator:
    """The adjoint ``[lam, mu, J]`` integrated backwards over a stretch of a run in C: the
    runtime's DOP853 (:mod:`mbcomp.codegen.runtime`) over :data:`ADJOINT_GLUE`, which calls
    the bound vector-Jacobian program and the objective's integrand program in C.

    Parameters
    ----------
    vjp : BoundAdjoint
        The right-hand side's products (a C program, ``d = [alpha, beta, lam]``).
    integrand : BoundAdjoint or None
        The integrand's value and gradient (a C program on the same parameters ``wrt``).
    gains : (float, float)
        The Baumgarte gains (1/s).
    cache_dir : str, optional

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import c_compiler
    >>> from mbcomp.codegen.adjoint import AdjointCode, AdjointIntegrator, chebyshev_nodes
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> if c_compiler():      # lam(T) = (1, 0) on the position: lam(0) = (1, T), mu_gz = T^2 / 2
    ...     code = AdjointCode.build(system, "c", wrt=[("world", "g", (2,))])
    ...     adj = AdjointIntegrator(code.bind(system), None, (0.0, 0.0))
    ...     x, _ = chebyshev_nodes(8)
    ...     Y = np.zeros((1, 8, 2))             # the state does not matter here (linear)
    ...     z = adj.integrate(0.0, 2.0, Y, np.array([1.0, 0.0, 0.0, 0.0]), 1e-10, 1e-12)
    ...     print(np.round(z, 9).tolist())
    ... else:
    ...     print([1.0, 2.0, 2.0, 0.0])
    [1.0, 2.0, 2.0, 0.0]
    """

    def __init__(self, vjp, integrand, gains, cache_dir=None):
        from .engine import RuntimeStats, runtime_library
        from .toolchain import c_compiler, cache_directory, runtime_directory

        if vjp.code.backend != "c" or (integrand is not None and integrand.code.backend != "c"):
            raise ValueError("AdjointIntegrator needs the C programs (backend='c')")
        self.vjp, self.integrand = vjp, integrand
        self.n, self.nq, self.np = vjp.code.n, vjp.nq, len(vjp.code.wrt)
        d = cache_directory(cache_dir)
        self.rt = runtime_library(c_compiler(), runtime_directory(d))
        self.glue = cached_library([("adjglue", HEADER + ADJOINT_GLUE, list(FLAGS))], "mbcomp_adjglue", cache_dir,
                                   "adjoint integrator")
        self.rhs = ctypes.cast(self.glue.mbcomp_adj_rhs, ctypes.c_void_p).value
        n, m = self.n, self.n + self.np
        self.y, self.d = np.zeros(n + 1), np.zeros(2 + n + 1)
        self.d[:2] = gains
        self.vout, self.oout = np.zeros(m + 1), np.zeros(m + 2)
        self.work = np.zeros(int(self.rt.mbrt_dop853_work_size(m + 1)))
        self.stats = RuntimeStats()
        self.ctx = _AdjCtx(ctypes.cast(vjp.code.loaded.cfun, ctypes.c_void_p).value, vjp.hbuf.ctypes.data,
                           vjp.pbuf.ctypes.data, vjp.wbuf.ctypes.data,
                           None if integrand is None else ctypes.cast(integrand.code.loaded.cfun,
                                                                      ctypes.c_void_p).value,
                           None if integrand is None else integrand.hbuf.ctypes.data,
                           None if integrand is None else integrand.pbuf.ctypes.data,
                           None if integrand is None else integrand.wbuf.ctypes.data,
                           self.nq, n, self.np, 0.0, 0.0, 0, 0, None, None, None, self.y.ctypes.data,
                           self.d.ctypes.data, self.vout.ctypes.data, self.oout.ctypes.data, 0)
        self.nfev = self.naccept = 0

    def integrate(self, t_lo, t_hi, Y, z, rtol, atol):
        """``[lam, mu, J]`` at ``t_lo`` from their values ``z`` at ``t_hi``, with the state
        ``Y[k, j]`` at the Chebyshev nodes ``j`` (:func:`chebyshev_nodes`) of the ``k``-th of
        equal sub-segments of ``[t_lo, t_hi]``. Raises ``ArithmeticError`` naming the program
        that did not hold (a failed guard, a non-finite value) or the integrator's failure."""
        Y = np.ascontiguousarray(Y, float)
        nseg, nnode = Y.shape[0], Y.shape[1]
        x, bw = chebyshev_nodes(nnode)
        c = self.ctx
        c.t_lo, c.t_hi, c.nseg, c.nnode = float(t_lo), float(t_hi), nseg, nnode
        c.Y, c.x, c.bw, c.failed = Y.ctypes.data, x.ctypes.data, bw.ctypes.data, 0
        z0 = np.ascontiguousarray(z, float)
        atol_v = np.full(z0.size, float(atol))
        out = np.zeros(z0.size)
        n_written = ctypes.c_int(0)
        status = self.rt.mbrt_dop853(self.rhs, None, ctypes.byref(c), z0.size, 0.0, z0.ctypes.data,
                                     float(t_hi - t_lo), float(rtol), atol_v.ctypes.data, 0.0, 0.0, 0,
                                     np.array([t_hi - t_lo]).ctypes.data, 1, out.ctypes.data, ctypes.byref(n_written),
                                     self.work.ctypes.data, ctypes.byref(self.stats))
        self.nfev += self.stats.nfev
        self.naccept += self.stats.naccept
        if status != 0 or n_written.value != 1:
            what = {1: "the adjoint program", 2: "the objective's integrand program",
                    3: "the adjoint (a non-finite value)"}.get(c.failed, "the integrator")
            raise ArithmeticError(f"{what} failed at t = {t_hi - self.stats.t:.6g} s: "
                                  f"{self.stats.message.decode(errors='replace')}")
        return out
