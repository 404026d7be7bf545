"""The exact Jacobian ``d fun / d y`` of the Lagrange index-1 right-hand side, as a generated
program differentiated from the traced right-hand side.

The right-hand side ``fun(t, y) = [dq/dt, du/dt]`` at ``y = [q, u]`` is traced once more
(``program="fun"``, the system's row mask) and its outputs differentiated with respect to the
``q`` and ``u`` inputs: in C as loops over the directions
(:class:`~mbcomp.codegen.direction_loops.TangentLoops`: the coordinates and the speeds are two
blocks), in Python by the scalar forward mode (:func:`mbcomp.codegen.tangent.tangent`). Either
program checks the right-hand side's guards (a failed guard, or a non-finite entry: no exact
Jacobian at that state, the caller differences). Parameter-only subexpressions are hoisted as
in every program and computed once per parameter set (:meth:`JacobianCode.bind`).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.jacobian import JacobianCode
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = mbcomp.assemble(m)
>>> jac = JacobianCode.build(system, "python").bind(system)
>>> J = jac(0.0, np.array([0.5, 0.0]), 0.0, 0.0)      # d/dphi of du/dt = -g sin(phi): -g cos(phi)
>>> J[0].tolist(), bool(abs(J[1, 0] + 9.81 * np.cos(0.5)) < 1e-12), abs(float(J[1, 1]))
([0.0, 1.0], True, 0.0)
"""
from __future__ import annotations

import ctypes
import math

import numpy as np

from .direction_loops import TangentLoops
from .graph import Fallback, Retrace, no_gc
from .printers import Program
from .loaded import LoadedProgram
from .tangent import tangent
from .tracer import param_layout, param_vector, trace

__all__ = ["JacobianCode", "BoundJacobian", "MAX_SPEEDS"]


#: above this many speeds no exact Jacobian program is made while a run asks for one (the
#: callers difference): a cost policy on the cold build, not on the call. The C program
#: (loops over directions, :mod:`mbcomp.codegen.direction_loops`) costs 0.5-0.6x Pinocchio's
#: computeABADerivatives per call on a planar chain at every N measured (5 to 100) and 29x less
#: than forward differences at N = 40, but its first build takes about 5 s at N = 40 and 12-30 s
#: at N = 100 (once per structure; the disk cache keeps it). ``JacobianCode.build(...,
#: max_speeds=None)`` builds it at any size. The DAE forms' bound
#: (:data:`mbcomp.codegen.dae_jacobian.MAX_SPEEDS`) is separate: their programs are scalar.
MAX_SPEEDS = 40


class JacobianCode:
    """The generated program of ``d fun / d y`` for one row mask and parameter signature
    (shared by systems differing only in parameter values; :meth:`bind` gives the callable).

    Use :meth:`build`, which returns None when the system has no such program (a singular
    trace point, drives or external inputs evaluated in Python at every call).

    Attributes
    ----------
    n : int
        ``nq + nu``: the Jacobian is ``(n, n)``.
    n_ops : int
        Operations per call.
    backend : {"python", "c"}

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.jacobian import JacobianCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> code = JacobianCode.build(mbcomp.assemble(m), "python")
    >>> code.n, code.backend      # a free fall: J = [[0, 1], [0, 0]]
    (2, 'python')
    """

    def __init__(self, tr, backend, cache_dir=None):
        g = tr.graph
        fun = tr.groups["fun"]
        self.n = len(fun)
        self.signature, self.layout = tr.signature, tr.layout
        nq = len(tr.groups["qrate"])  # fun = [dq/dt (nq), du/dt (nu)]
        ins = [g.memo.get(("in", "q", k)) for k in range(nq)] + [g.memo.get(("in", "u", k))
                                                                  for k in range(self.n - nq)]
        # the tracer makes every input; one that were missing (None) has derivative zero
        self.backend = backend
        if backend == "c":  # loops over the directions (codegen/direction_loops.py)
            self.loaded = TangentLoops(g, fun, ins, [(0, nq), (nq, self.n)], tr.guard_groups["fun"], "mbcomp_jac",
                                       cache_dir, "Jacobian program")
        else:
            flat = [v for row in tangent(g, fun, ins) for v in row]
            prog = Program(g, {"jac": flat}, guard_groups={"jac": list(tr.guard_groups["fun"])})
            self.loaded = LoadedProgram(prog, "jac", "mbcomp_jac", backend, cache_dir, "Jacobian program")
        self.pre, self.n_ops, self.n_work = self.loaded.pre, self.loaded.n_ops, self.loaded.n_work

    @classmethod
    def build(cls, system, backend, cache_dir=None, max_nodes=3_000_000, max_speeds=MAX_SPEEDS):
        """The Jacobian program of ``system`` (its current row mask), or None when there is
        none: more than ``max_speeds`` speeds (default :data:`MAX_SPEEDS`; None: no bound), a
        singular trace point, or drives and inputs the program takes per call."""
        if max_speeds is not None and system.nu > max_speeds:
            return None
        with no_gc():
            tr = trace(system, max_nodes, program="fun")
            if "fun" not in tr.groups or tr.drives or tr.inputs:
                return None
            return cls(tr, backend, cache_dir)

    def bind(self, system):
        """The callable :class:`BoundJacobian` for ``system``'s parameter values; None when
        they change a decision baked into the program (then it must be built again)."""
        if param_layout(system)[1] != self.signature:
            return None
        pv = param_vector(system, self.layout)
        try:
            h = self.pre.run(pv)
        except Retrace:
            return None
        return BoundJacobian(self, system.nq, pv, h)


class BoundJacobian:
    """A :class:`JacobianCode` bound to one parameter set: ``J = jac(t, y, alpha, beta)``,
    ``(n, n)``, or None where the program does not hold (a failed guard, a non-finite
    entry). ``alpha``, ``beta``: the Baumgarte gains (1/s), zero for none.

    With the C backend, :meth:`run_c` runs the program alone into :attr:`out` (the ``(n, n)``
    view of the output buffer; ``addresses`` are the buffers' addresses, taken once).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.jacobian import JacobianCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> JacobianCode.build(system, "python").bind(system)(0.0, np.zeros(2), 0.0, 0.0).tolist()
    [[0.0, 1.0], [0.0, 0.0]]
    """

    def __init__(self, code, nq, pv, h):
        self.code, self.nq = code, nq
        self.h = h
        if code.backend == "c":
            n = code.n
            self.hbuf = np.array(list(h) + [0.0], float)
            self.pbuf = np.array(list(pv) + [0.0], float)
            self.dbuf = np.zeros(2)
            self.ybuf = np.zeros(n + 1)
            self.wbuf = np.zeros(max(code.n_work, 1))
            self.obuf = np.zeros(n * n + 1)  # the last entry is padding the program never writes
            self.out = self.obuf[: n * n].reshape(n, n)
            # the buffers live as long as this object: their addresses are taken once (reading
            # ``.ctypes.data`` costs about 0.8 us each, six of them more than the whole program
            # of a 5-link chain)
            base = self.ybuf.ctypes.data
            self.addresses = (base, base + 8 * nq, self.dbuf.ctypes.data, self.hbuf.ctypes.data,
                              self.pbuf.ctypes.data, self.wbuf.ctypes.data, self.obuf.ctypes.data)
            self.ones = np.ones(n * n + 1)

    def run_c(self, t, y, alpha, beta):
        """Run the C program at ``(t, y)`` into :attr:`out` (the ``(n, n)`` view of the output
        buffer, overwritten by the next call) without copying or checking the result: 0 when
        the program holds, 1 when a guard failed. ``C`` backend only (the per-call cost of the
        program itself, for benchmarks and callers that check the entries themselves).

        Examples
        --------
        >>> import numpy as np, mbcomp
        >>> from mbcomp.codegen import c_compiler
        >>> from mbcomp.codegen.jacobian import JacobianCode
        >>> from mbcomp.library import World, Prismatic, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
        >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
        >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
        >>> system = mbcomp.assemble(m)
        >>> jac = JacobianCode.build(system, "c").bind(system) if c_compiler() else None
        >>> jac is None or (jac.run_c(0.0, np.zeros(2), 0.0, 0.0), jac.out.tolist()) == (0, [[0.0, 1.0], [0.0, 0.0]])
        True
        """
        self.ybuf[: self.code.n] = y
        d = self.dbuf
        d[0] = alpha
        d[1] = beta
        a = self.addresses
        return self.code.loaded.cfun(a[0], a[1], float(t), a[2], a[3], a[4], a[5], a[6])

    def __call__(self, t, y, alpha, beta):
        code, n, nq = self.code, self.code.n, self.nq
        if code.backend == "python":
            try:
                out = code.loaded.fun(y[:nq].tolist(), y[nq:].tolist(), float(t), [alpha, beta], self.h)
            except (Fallback, ArithmeticError, ValueError):
                return None
            J = np.array(out, float).reshape(n, n)
            return J if np.isfinite(J).all() else None
        # run_c inlined: one Python call less (a tenth of the whole at N = 5)
        self.ybuf[:n] = y
        d = self.dbuf
        d[0] = alpha
        d[1] = beta
        a = self.addresses
        if code.loaded.cfun(a[0], a[1], float(t), a[2], a[3], a[4], a[5], a[6]):
            return None
        # one dot product is finite exactly when every entry is (a NaN or an infinity spreads;
        # an overflow of finite entries is rare and then settled by the full check)
        if not math.isfinite(self.obuf.dot(self.ones)) and not np.isfinite(self.out).all():
            return None
        return self.out.copy()
