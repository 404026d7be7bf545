"""Exact first derivatives of the evaluation with respect to ``q`` and ``u``, as a generated
program (Python or C): what an exact linearization about a state needs
(:mod:`mbcomp.analysis.reduced`).

The evaluation (``program="eval"``: ``M, f, Phi, Phid, C, cb, B, b, Bb, Psi`` with every
holonomic row, unmasked, and the coordinate rates) is traced once more, and in the same
graph four groups of values are formed, with per-call inputs ``a`` (nu accelerations) and
``lam`` (one multiplier per holonomic row, then per nonholonomic row) that the caller fixes:

* ``R1 = f - M a - C^T lam_C - B^T lam_B`` (nu): the dynamic balance at fixed ``a``, ``lam``;
* ``R2 = -[c_b; B_b] - [C; B] a`` (m + k): the acceleration rows at fixed ``a``;
* ``G = [dPhi/dt; Psi]`` (m + k): the velocity rows' residuals;
* ``qrate`` (nq): ``dq/dt``, linear in ``u``.

:func:`~mbcomp.codegen.tangent.tangent` differentiates them with respect to the ``q`` and
``u`` inputs; the program returns ``dR1/d[q, u]``, ``dR2/d[q, u]``, ``dG/d[q, u]`` and
``Q = d qrate/du``. Contracting ``M a`` and ``C^T lam`` inside the program keeps it small:
the derivative of the whole mass matrix (``nu^2 (nq + nu)`` entries) is never formed. With
``a, lam`` the solution of the saddle-point system at the state, the derivative of that
solution follows from one solve with the same saddle-point matrix (the caller's).

The program checks the evaluation's guards: where one fails, or an entry is not finite, the
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
>>> system = mbcomp.assemble(m)
>>> d = eval_tangent(system)(0.0, np.array([0.5]), np.array([0.0]), np.array([0.0]), np.zeros(0))
>>> # f = -m g l sin(phi): dR1/dphi = -m g l cos(phi) at a = 0
>>> bool(abs(d.R1[0, 0] + 2.0 * 9.81 * np.cos(0.5)) < 1e-12), d.Q.tolist()
(True, [[1.0]])
"""
from __future__ import annotations

import ctypes
import weakref
from dataclasses import dataclass

import numpy as np

from .graph import Fallback, Retrace, no_gc
from .printers import PY_ENV, ParamProgram, Program
from .tangent import tangent
from .toolchain import FLAGS, HEADER, cached_library, chunk, n_units
from .tracer import FIELDS, param_layout, param_vector, trace

__all__ = ["EvalTangentCode", "BoundEvalTangent", "EvalTangent", "eval_tangent"]


@dataclass(frozen=True)
class EvalTangent:
    """The derivatives at one state (columns: ``nq`` coordinates, then ``nu`` speeds).

    Attributes
    ----------
    R1 : ndarray (nu, nq + nu)
        ``d(f - M a - A^T lam)/d[q, u]`` at fixed ``a`` (1/s^2 etc.: force units per
        coordinate or speed unit).
    R2 : ndarray (m + k, nq + nu)
        ``d(-[c_b; B_b] - A a)/d[q, u]``, every holonomic row (unmasked) then the nonholonomic rows.
    G : ndarray (m + k, nq + nu)
        ``d[dPhi/dt; Psi]/d[q, u]``, the same rows.
    Q : ndarray (nq, nu)
        ``d(dq/dt)/du``: how the coordinates move along the speeds.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.codegen.eval_tangent import EvalTangent
    >>> d = EvalTangent(np.zeros((1, 2)), np.zeros((0, 2)), np.zeros((0, 2)), np.eye(1))
    >>> d.Q.shape
    (1, 1)
    """

    R1: np.ndarray
    R2: np.ndarray
    G: np.ndarray
    Q: np.ndarray


def _fields(tr):
    """``{name: object array}`` of the traced evaluation's fields."""
    out, off = {}, 0
    flat = tr.groups["eval"]
    for name in FIELDS:
        shape = tr.shapes[name]
        n = int(np.prod(shape, dtype=int))
        arr = np.empty(n, dtype=object)
        arr[:] = flat[off: off + n]
        out[name] = arr.reshape(shape)
        off += n
    return out


def _dot(coeffs, xs):
    """``sum_j coeffs[j] xs[j]``, skipping exact zeros (no node for a structural zero)."""
    s = 0.0
    for c, x in zip(coeffs, xs):
        if type(c) is float and c == 0.0:
            continue
        s = s + c * x
    return s


class EvalTangentCode:
    """The generated program of the evaluation's derivatives (see the module docstring) for
    one parameter signature: shared by systems differing only in parameter values;
    :meth:`bind` gives the callable. Use :meth:`build`.

    Attributes
    ----------
    nq, nu : int
    m, k : int
        Holonomic rows (all, unmasked) and nonholonomic rows.
    n_ops : int
        Operations per call.
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
        F = _fields(tr)
        self.nq, self.nu = nq, nu
        self.m, self.k = F["C"].shape[0], F["B"].shape[0]
        self.signature, self.layout, self.drives, self.inputs = tr.signature, tr.layout, tr.drives, tr.inputs
        m, k = self.m, self.k
        # the contraction's inputs after the drives' (s, v, a), the two gain slots and the inputs
        self.base = base = 3 * len(tr.drives) + 2 + len(tr.inputs)
        with g:
            a = [g.input("d", base + j, 1.0) for j in range(nu)]
            lam = [g.input("d", base + nu + j, 1.0) for j in range(m + k)]
            rows = np.vstack((F["C"], F["B"])) if k else F["C"]
            rows = rows.reshape(m + k, nu)
            M, f = F["M"].reshape(nu, nu), F["f"]
            R1 = [f[i] - _dot(M[i], a) - _dot(rows[:, i], lam) for i in range(nu)]
            bias = list(F["cb"]) + list(F["Bb"])
            R2 = [-bias[r] - _dot(rows[r], a) for r in range(m + k)]
            G = list(F["Phid"]) + list(F["Psi"])
        ins = [g.memo.get(("in", "q", j)) for j in range(nq)] + [g.memo.get(("in", "u", j)) for j in range(nu)]
        present = [(j, x) for j, x in enumerate(ins) if x is not None]  # a missing input: derivative zero
        J = tangent(g, R1 + R2 + G, [x for _, x in present])
        n = nq + nu
        flat = [0.0] * (len(J) * n)
        for i, row in enumerate(J):
            for (j, _), v in zip(present, row):
                flat[i * n + j] = v
        upresent = [(j, x) for j, x in present if j >= nq]
        JQ = tangent(g, list(tr.groups["qrate"]), [x for _, x in upresent])
        fq = [0.0] * (nq * nu)
        for i, row in enumerate(JQ):
            for (j, _), v in zip(upresent, row):
                fq[i * nu + j - nq] = v
        self.n_out = len(flat) + len(fq)
        prog = Program(g, {"dev": flat + fq}, guard_groups={"dev": list(g.guards)})
        self.n_ops = prog.n_ops("dev")
        self.pre = ParamProgram(prog)
        self.backend = backend
        if backend == "python":
            env = dict(PY_ENV, _Fallback=Fallback, _Retrace=Retrace)
            exec(compile(prog.python_main("dev", "dev"), "<mbcomp.codegen eval_tangent>", "exec"), env)
            self.fun = env["dev"]
        else:
            self._build_c(prog, cache_dir)

    @classmethod
    def build(cls, system, backend="python", cache_dir=None, max_nodes=3_000_000):
        """The derivative program of ``system``'s evaluation. Raises
        :class:`~mbcomp.codegen.graph.CodegenError` (naming the component) when the model
        cannot be traced, as :func:`mbcomp.codegen.compile_system` does."""
        if backend not in ("python", "c"):
            raise ValueError(f"eval_tangent: backend {backend!r} is unknown; use 'python' or 'c'")
        with no_gc():
            tr = trace(system, max_nodes, program="eval")
            return cls(tr, system.nq, system.nu, backend, cache_dir)

    def _build_c(self, prog, cache_dir):
        parts, self.n_work = prog.c_parts("dev", "mbcomp_dev", chunk, n_parts=n_units)
        units = [(f"dev{j}", HEADER + src, list(FLAGS)) for j, src in enumerate(parts)]
        self.dll = cached_library(units, "mbcomp_dev", cache_dir, "evaluation-derivative program")
        self.dll.mbcomp_dev.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double] + [ctypes.c_void_p] * 5
        self.dll.mbcomp_dev.restype = ctypes.c_int

    def bind(self, system):
        """The callable :class:`BoundEvalTangent` for ``system``'s parameter values; None when
        they change a decision baked into the program (then it must be built again)."""
        if param_layout(system)[1] != self.signature:
            return None
        pv = param_vector(system, self.layout)
        try:
            h = self.pre.run(pv)
        except Retrace:
            return None
        comps = system.topology.flat.components
        drives = [(comps[path], system.P[path]) for path in self.drives]
        return BoundEvalTangent(self, pv, h, drives)


class BoundEvalTangent:
    """An :class:`EvalTangentCode` bound to one parameter set:
    ``d = dev(t, q, u, a, lam)`` is an :class:`EvalTangent`, or None where the program does
    not hold (a failed guard, a non-finite entry). ``a`` (nu,): the accelerations the
    balance is taken at; ``lam`` (m + k,): one multiplier per holonomic row (unmasked; a
    row the system's mask leaves out gets 0) then per nonholonomic row.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.eval_tangent import eval_tangent
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> d = eval_tangent(mbcomp.assemble(m))(0.0, np.zeros(1), np.zeros(1), np.array([1.0]), np.zeros(0))
    >>> d.R1.tolist()        # R1 = m g - m a: no dependence on the state
    [[0.0, 0.0]]
    """

    def __init__(self, code, pv, h, drives):
        self.code, self.h, self.drive_comps = code, h, drives
        if code.backend == "c":
            self.hbuf = np.array(list(h) + [0.0], float)
            self.pbuf = np.array(list(pv) + [0.0], float)
            self.qbuf = np.zeros(code.nq + 1)
            self.ubuf = np.zeros(code.nu + 1)
            self.wbuf = np.zeros(max(code.n_work, 1))
            self.obuf = np.zeros(code.n_out + 1)

    def _per_call(self, t, a, lam):
        d = []
        for comp, p in self.drive_comps:
            d.extend(float(x) for x in comp.motion(t, p))
        d += [0.0, 0.0] + [float(inp.value(t)) for inp in self.code.inputs]
        return np.concatenate((d, np.asarray(a, float), np.asarray(lam, float)))

    def __call__(self, t, q, u, a, lam):
        code = self.code
        nq, nu, r = code.nq, code.nu, code.m + code.k
        if np.size(a) != nu or np.size(lam) != r:
            raise ValueError(f"eval_tangent: a needs {nu} entries and lam {r} (every holonomic row, then the "
                             f"nonholonomic ones), not {np.size(a)} and {np.size(lam)}")
        d = self._per_call(t, a, lam)
        if code.backend == "python":
            try:
                out = np.array(code.fun(list(map(float, q)), list(map(float, u)), float(t), d.tolist(), self.h), float)
            except (Fallback, ArithmeticError, ValueError):
                return None
        else:
            self.qbuf[:nq], self.ubuf[:nu] = q, u
            dbuf = np.concatenate((d, [0.0]))
            if code.dll.mbcomp_dev(self.qbuf.ctypes.data, self.ubuf.ctypes.data, float(t), dbuf.ctypes.data,
                                   self.hbuf.ctypes.data, self.pbuf.ctypes.data, self.wbuf.ctypes.data,
                                   self.obuf.ctypes.data):
                return None
            out = self.obuf[: code.n_out].copy()
        if not np.isfinite(out).all():
            return None
        n = nq + nu
        J = out[: (nu + 2 * r) * n].reshape(nu + 2 * r, n)
        return EvalTangent(J[:nu], J[nu: nu + r], J[nu + r:], out[(nu + 2 * r) * n:].reshape(nq, nu))


#: topology -> {(signature, backend): EvalTangentCode}: systems differing only in parameter
#: values (``with_params``) share their topology and so the program
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
    key = (param_layout(system)[1], backend)
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
