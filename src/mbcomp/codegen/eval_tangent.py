"""Exact first derivatives of the evaluation with respect to ``q`` and ``u`` as generated
programs (Python or C): what an exact linearization about a state needs
(:mod:`mbcomp.analysis.reduced`).

The evaluation (``program="eval"``: ``M, f, Phi, Phid, C, cb, B, b, Bb, Psi`` with every
holonomic row, unmasked, and the coordinate rates) is traced once more, and in the same
graph three groups of values are formed, with per-call inputs ``a`` (nu accelerations) and
``lam`` (one multiplier per holonomic row, then per nonholonomic row) that the caller fixes:

* ``R1 = f - M a - C^T lam_C - B^T lam_B`` (nu): the dynamic balance at fixed ``a``, ``lam``;
* ``R2 = -[c_b; B_b] - [C; B] a`` (m + k): the acceleration rows at fixed ``a``;
* ``G = [dPhi/dt; Psi]`` (m + k): the velocity rows' residuals.

Their derivative along one direction ``(dq, du)`` is a Jacobian-vector product: the graph is
made again (:func:`mbcomp.codegen.replay.replay`) with every ``q_k`` replaced by ``q_k + eps dq_k`` and every
``u_k`` by ``u_k + eps du_k``, and :func:`~mbcomp.codegen.tangent.tangent` differentiates it
with respect to ``eps`` alone -- one forward sweep, about three times the evaluation's
operations, instead of the whole Jacobian (``nq + nu`` directions at once: at N = 40 links
410,000 operations and 5.5 s for the first linearization, against 16,300 and 0.26 s). Contracting ``M a`` and
``C^T lam`` inside the program keeps it small as well: the derivative of the mass matrix
itself is never formed. With ``a, lam`` the solution of the saddle-point system at the
state, the derivative of that solution follows from one solve with the saddle-point matrix
(the caller's). A second, small program gives ``Q = d(dq/dt)/du``, how the coordinates move
along the speeds.

The programs check the evaluation's guards: where one fails, or a value is not finite, a
call returns None (no exact derivative at that state; the caller differences). Drives'
``(s, v, a)`` and external inputs are evaluated numerically per call, as for the evaluation
program. Programs are cached per topology, parameter signature and backend
(:func:`eval_tangent`), so a sweep over parameter values traces once.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.eval_tangent import eval_tangent
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> dev = eval_tangent(mbcomp.assemble(m))
>>> q, z = np.array([0.5]), np.zeros(1)
>>> dR1, dR2, dG = dev.jvp(0.0, q, z, z, np.zeros(0), np.ones(1), z)   # along dphi = 1, at a = 0
>>> bool(abs(dR1[0] + 2.0 * 9.81 * np.cos(0.5)) < 1e-12)                # d(-m g l sin phi)/dphi
True
"""
from __future__ import annotations

import ctypes
import weakref

import numpy as np

from .dae_jacobian import dot, evaluation_fields
from .graph import Fallback, Retrace, no_gc
from .printers import Program
from .loaded import LoadedProgram
from .replay import replay
from .tangent import tangent
from .tracer import param_layout, param_vector, trace

__all__ = ["EvalTangentCode", "BoundEvalTangent", "eval_tangent"]


class EvalTangentCode:
    """The generated programs of the evaluation's derivatives (see the module docstring) for
    one parameter signature: shared by systems differing only in parameter values;
    :meth:`bind` gives the callable. Use :meth:`build`.

    Attributes
    ----------
    nq, nu : int
    m, k : int
        Holonomic rows (all, unmasked) and nonholonomic rows.
    n_ops : int
        Operations per call of the Jacobian-vector product.
    backend : {"python", "c"}

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.eval_tangent import EvalTangentCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> code = EvalTangentCode.build(mbcomp.assemble(m), "python")
    >>> code.nq, code.nu, code.m, code.k
    (1, 1, 0, 0)
    """

    def __init__(self, tr, nq, nu, backend, cache_dir=None):
        g = tr.graph
        F = evaluation_fields(tr)
        self.nq, self.nu = nq, nu
        self.m, self.k = m, k = F["C"].shape[0], F["B"].shape[0]
        self.signature, self.layout, self.drives, self.inputs = tr.signature, tr.layout, tr.drives, tr.inputs
        # per-call inputs after the drives' (s, v, a), the two gain slots and the external
        # inputs: the balance's a (nu) and lam (m + k), then the direction dq (nq), du (nu), eps
        self.base = base = 3 * len(tr.drives) + 2 + len(tr.inputs)
        with g:
            a = [g.input("d", base + j, 1.0) for j in range(nu)]
            lam = [g.input("d", base + nu + j, 1.0) for j in range(m + k)]
            rows = (np.vstack((F["C"], F["B"])) if k else F["C"]).reshape(m + k, nu)
            M, f = F["M"].reshape(nu, nu), F["f"]
            R1 = [f[i] - dot(M[i], a) - dot(rows[:, i], lam) for i in range(nu)]
            bias = list(F["cb"]) + list(F["Bb"])
            R2 = [-bias[r] - dot(rows[r], a) for r in range(m + k)]
            G = list(F["Phid"]) + list(F["Psi"])
        # Q = d qrate/du: small (per joint), the whole Jacobian in the traced graph
        us = [g.memo.get(("in", "u", j)) for j in range(nu)]  # a missing input (None): derivative zero
        fq = [v for row in tangent(g, list(tr.groups["qrate"]), us) for v in row]
        qprog = Program(g, {"Q": fq}, guard_groups={"Q": list(tr.guard_groups["qrate"])})
        # the balance, the acceleration rows and the velocity rows along one direction
        self.d0 = d0 = base + nu + m + k

        def shift(g2):
            eps = g2.input("d", d0 + nq + nu, 0.0)
            moved = {}
            for kind, n, off in (("q", nq, d0), ("u", nu, d0 + nq)):
                for j in range(n):
                    moved[(kind, j)] = lambda x, c=g2.input("d", off + j, 0.0): x + eps * c
            return moved, eps

        g2, outs, eps = replay(g, R1 + R2 + G, shift)
        J = tangent(g2, outs, [eps])
        prog = Program(g2, {"jvp": [row[0] for row in J]}, guard_groups={"jvp": list(g2.guards)})
        self.n_out = nu + 2 * (m + k)
        self.n_ops = prog.n_ops("jvp")
        self.backend = backend
        jvp, qjac = (LoadedProgram(p, group, fname, backend, cache_dir, "evaluation-derivative program")
                     for p, group, fname in ((prog, "jvp", "mbcomp_jvp"), (qprog, "Q", "mbcomp_qjac")))
        self.pre, self.qpre = jvp.pre, qjac.pre
        self.n_work = max(1, jvp.n_work, qjac.n_work)
        self.fun, self.qfun = (jvp.fun, qjac.fun) if backend == "python" else (jvp.cfun, qjac.cfun)

    @classmethod
    def build(cls, system, backend="python", cache_dir=None, max_nodes=3_000_000):
        """The derivative programs of ``system``'s evaluation. Raises
        :class:`~mbcomp.codegen.graph.CodegenError` (naming the component) when the model
        cannot be traced, as :func:`mbcomp.codegen.compile_system` does."""
        if backend not in ("python", "c"):
            raise ValueError(f"eval_tangent: backend {backend!r} is unknown; use 'python' or 'c'")
        with no_gc():
            tr = trace(system, max_nodes, program="eval")
            return cls(tr, system.nq, system.nu, backend, cache_dir)

    def bind(self, system):
        """The callable :class:`BoundEvalTangent` for ``system``'s parameter values; None when
        they change a decision baked into the program (then it must be built again)."""
        if param_layout(system)[1] != self.signature:
            return None
        pv = param_vector(system, self.layout)
        try:
            h, hq = self.pre.run(pv), self.qpre.run(pv)
        except Retrace:
            return None
        comps = system.topology.flat.components
        drives = [(comps[path], system.P[path]) for path in self.drives]
        return BoundEvalTangent(self, pv, h, hq, drives)


class BoundEvalTangent:
    """An :class:`EvalTangentCode` bound to one parameter set.

    ``jvp(t, q, u, a, lam, dq, du)``: the derivatives along the direction ``(dq, du)``
    (coordinates, speeds) of ``R1 = f - M a - A^T lam`` (nu), ``R2 = -[c_b; B_b] - A a``
    (m + k) and ``G = [dPhi/dt; Psi]`` (m + k), three arrays, the rows every holonomic row
    (unmasked; a row the system's mask leaves out gets ``lam = 0``) then the nonholonomic
    ones; ``Q(q)``: ``d(dq/dt)/du`` (nq, nu). Both return None where the program does not
    hold (a failed guard, a non-finite value).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.eval_tangent import eval_tangent
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=2.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> dev = eval_tangent(mbcomp.assemble(m))
    >>> q, z = np.array([0.5]), np.zeros(1)
    >>> dR1, dR2, dG = dev.jvp(0.0, q, z, z, np.zeros(0), np.ones(1), z)   # along dphi = 1
    >>> bool(abs(dR1[0] + 2.0 * 9.81 * np.cos(0.5)) < 1e-12), dev.Q(q).tolist()  # d(-m g l sin phi)/dphi
    (True, [[1.0]])
    """

    def __init__(self, code, pv, h, hq, drives):
        self.code, self.drive_comps = code, drives
        self.h, self.hq = h, hq
        if code.backend == "c":
            self.h = np.array(list(h) + [0.0], float)
            self.hq = np.array(list(hq) + [0.0], float)
            self.pbuf = np.array(list(pv) + [0.0], float)
            self.qbuf = np.zeros(code.nq + 1)
            self.ubuf = np.zeros(code.nu + 1)
            self.wbuf = np.zeros(max(code.n_work, 1))
            self.obuf = np.zeros(max(code.n_out, code.nq * code.nu) + 1)
        self.at = None  # (t, a, lam) of the per-call inputs last made, and those inputs

    def _inputs(self, t, a, lam):
        code = self.code
        if np.size(a) != code.nu or np.size(lam) != code.m + code.k:
            raise ValueError(f"eval_tangent: a needs {code.nu} entries and lam {code.m + code.k} (every holonomic "
                             f"row, then the nonholonomic ones), not {np.size(a)} and {np.size(lam)}")
        d = []
        for comp, p in self.drive_comps:
            d.extend(float(x) for x in comp.motion(t, p))
        d += [0.0, 0.0] + [float(inp.value(t)) for inp in code.inputs]
        return np.concatenate((d, np.asarray(a, float), np.asarray(lam, float), np.zeros(code.nq + code.nu + 2)))

    def _run(self, fun, h, q, u, t, d, n):
        code = self.code
        if code.backend == "python":
            try:
                out = np.array(fun(list(map(float, q)), list(map(float, u)), float(t), d.tolist(), h), float)
            except (Fallback, ArithmeticError, ValueError):
                return None
        else:
            self.qbuf[: code.nq], self.ubuf[: code.nu] = q, u
            if fun(self.qbuf.ctypes.data, self.ubuf.ctypes.data, float(t), d.ctypes.data, h.ctypes.data,
                   self.pbuf.ctypes.data, self.wbuf.ctypes.data, self.obuf.ctypes.data):
                return None
            out = self.obuf[:n].copy()
        return out if np.isfinite(out).all() else None

    def jvp(self, t, q, u, a, lam, dq, du):
        """``(dR1, dR2, dG)`` along ``(dq, du)`` at ``(t, q, u)`` with the balance taken at
        accelerations ``a`` and multipliers ``lam``; None where the program does not hold."""
        code = self.code
        key = (float(t), np.asarray(a, float).tobytes(), np.asarray(lam, float).tobytes())
        if self.at is None or self.at[0] != key:
            self.at = (key, self._inputs(t, a, lam))
        d, d0 = self.at[1], code.d0
        d[d0: d0 + code.nq] = dq
        d[d0 + code.nq: d0 + code.nq + code.nu] = du
        out = self._run(code.fun, self.h, q, u, t, d, code.n_out)
        if out is None:
            return None
        r = code.m + code.k
        return out[: code.nu], out[code.nu: code.nu + r], out[code.nu + r:]

    def Q(self, q):
        """``d(dq/dt)/du`` (nq, nu) at the coordinates ``q``; None where the program does not hold."""
        code = self.code
        out = self._run(code.qfun, self.hq, q, np.zeros(code.nu), 0.0, np.zeros(code.d0 + code.nq + code.nu + 2),
                        code.nq * code.nu)
        return None if out is None else out.reshape(code.nq, code.nu)


#: topology -> {(signature, backend, velocity rows held): EvalTangentCode}: systems differing
#: only in parameter values (``with_params``) share their topology and so the program
_CODES = weakref.WeakKeyDictionary()


def eval_tangent(system, backend="python", cache_dir=None, max_nodes=3_000_000):
    """The bound derivative program of ``system`` (:class:`BoundEvalTangent`), made at first
    need and reused for every system with the same topology and parameter signature.

    Parameters
    ----------
    system : MultibodySystem
    backend : {"python", "c"}
    cache_dir : str, optional
        Where a C library is cached (see :func:`mbcomp.codegen.compile_system`).
    max_nodes : int
        Give up (:class:`~mbcomp.codegen.graph.CodegenError`) beyond this many graph nodes.

    Returns
    -------
    BoundEvalTangent

    Raises
    ------
    CodegenError
        The model cannot be traced (names the component and the fix), or the program
        would exceed ``max_nodes``.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.eval_tangent import eval_tangent
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> eval_tangent(system).code is eval_tangent(system.with_params({"b.m": 3.0})).code   # traced once
    True
    """
    codes = _CODES.setdefault(system.topology, {})
    # a hybrid run's rows in force share the topology but hold other velocity rows
    key = (param_layout(system)[1], backend, tuple(e.name for e in system.nonholonomic))
    code = codes.get(key)
    if code is not None:
        bound = code.bind(system)
        if bound is not None:
            return bound
    code = codes[key] = EvalTangentCode.build(system, backend, cache_dir, max_nodes)
    bound = code.bind(system)
    if bound is None:  # the trace-time values themselves hold: cannot happen for the traced system
        raise RuntimeError("eval_tangent: internal error: a fresh program does not bind to its own system")
    return bound
