"""The exact Jacobians of the multiplier DAE forms (:mod:`mbcomp.formulations.dae`) and of the
generalized-alpha iteration matrix, as generated programs (Python or C) differentiated from
the traced evaluation by :func:`mbcomp.codegen.tangent.tangent`.

The evaluation (``M, f, Phi, Phid, C, cb, B, b, Bb, Psi`` and the coordinate rates) is traced
once more; in the same graph the accelerations ``a``, the multipliers ``lam`` and GGL's
``eta`` become per-call inputs (slots of ``d`` after the drives' ``(s, v, a)``, the two
Baumgarte gains and the external inputs), the residual of the form is written on them with
the system's row mask, and its derivatives with respect to every entry of the state are
printed as one program that checks the evaluation's guards:

=============  =========================================================================
form           program output
=============  =========================================================================
``"index3"``   ``d/dy [H(q) u, a, f - M a - A^T lam, -Phi, -Psi]`` at ``y = [q, u, a, lam]``
``"ggl"``      ``d/dy [H(q)(u - C^T eta), a, f - M a - A^T lam, -dPhi/dt, -Psi, -Phi]``
``"index1"``   ``d/dy [H(q) u, a, f - M a - A^T lam, -(A a + bias)]`` (bias with the
               Baumgarte terms of gains ``alpha``, ``beta``, inputs; zero for none)
``"mechanical"`` ``K = d(M udot + C^T lam - f)/dq H(q)`` and ``Ct = -df/du`` (``nu x nu``
               each): the tangent stiffness and damping of the generalized-alpha matrix,
               ``H = d(dq/dt)/du`` mapping a speed-space increment to the coordinates
``"dalembert"`` ``G = d[dPhi/dt; Psi]/dq`` (``m x nq``) at ``(q, u)``: with the implicit
               function theorem, how D'Alembert's dependent speeds move with ``q``
=============  =========================================================================

``A = [C; B]`` with the holonomic rows of the row mask. A failed guard or a non-finite entry
means "no exact Jacobian at this state": the callable returns None and the caller differences.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.dae_jacobian import DAEJacobianCode
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = mbcomp.assemble(m)
>>> jac = DAEJacobianCode.build(system, "index3", "python").bind(system)
>>> J = jac(0.0, np.array([0.5, 0.0, -4.7]))      # y = [phi, w, a]; row 3: f - M a, f = -g m l sin(phi)
>>> J.tolist()[:2], bool(abs(J[2, 0] + 9.81 * np.cos(0.5)) < 1e-12), float(J[2, 2])
([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], True, -1.0)
"""
from __future__ import annotations

import ctypes

import numpy as np

from .graph import Fallback, Retrace, no_gc
from .printers import Program
from .loaded import LoadedProgram, bind_cached
from .tangent import tangent
from .tracer import FIELDS, param_layout, param_vector, trace

__all__ = ["DAE_JACOBIAN_FORMS", "MAX_SPEEDS", "DAEJacobianCode", "BoundDAEJacobian", "bound_program",
           "dot", "evaluation_fields"]

#: the forms a program can be made for (see the module docstring)
DAE_JACOBIAN_FORMS = ("index1", "ggl", "index3", "mechanical", "dalembert")

#: above this many speeds :func:`bound_program` makes no program (the forms difference): the
#: derivative of the dense ``M a`` with respect to ``q`` grows as ``nu^3``. A pendulum chain
#: (index 3): nu = 10 10k operations, 2.6 s to trace and compile cold; nu = 20 62k, 11 s;
#: nu = 40 416k, 17 s to trace alone. (``"dalembert"``, ``d[dPhi/dt; Psi]/dq``, has no cap.)
MAX_SPEEDS = 24


def evaluation_fields(tr):
    """``{name: object array}``: the fields of a traced evaluation (:func:`~mbcomp.codegen.tracer.trace`
    with ``program="eval"``, every name of :data:`~mbcomp.codegen.tracer.FIELDS`) as arrays of
    its output nodes (and numbers), in the fields' shapes.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.dae_jacobian import evaluation_fields
    >>> from mbcomp.codegen.tracer import trace
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> F = evaluation_fields(trace(mbcomp.assemble(m), 10**5))
    >>> F["M"].shape, float(F["M"][0, 0].v), F["Phi"].shape      # the mass (kg); no rows
    ((1, 1), 2.0, (0,))
    """
    outs, off, fields = tr.groups["eval"], 0, {}
    for name in FIELDS:
        shape = tr.shapes[name]
        n = int(np.prod(shape, dtype=int))
        arr = np.empty(n, dtype=object)
        arr[:] = outs[off:off + n] if n else []
        fields[name] = arr.reshape(shape)
        off += n
    return fields


def dot(coeffs, xs):
    """``sum_j coeffs[j] xs[j]`` on graph values (Sym or numbers), skipping the coefficients
    that are exactly the number zero (no node for a structural zero).

    Examples
    --------
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.codegen.dae_jacobian import dot
    >>> with Graph() as g:
    ...     x, y = g.input("q", 0, 2.0), g.input("q", 1, 5.0)
    ...     s = dot([3.0, 0.0], [x, y])
    >>> float(s.v), len(g)          # 3 x: one product node, none for 0 y
    (6.0, 4)
    """
    s = 0.0
    for c, x in zip(coeffs, xs):
        if type(c) is float and c == 0.0:
            continue
        s = s + c * x
    return s


def bound_program(system, codes, form, backend, cache_dir=None, max_nodes=3_000_000):
    """The :class:`BoundDAEJacobian` of ``form`` for ``system`` (its row mask and parameter
    values), its code taken from or put into ``codes`` (a dict shared by systems differing
    only in parameter values); None when the evaluation cannot be traced or the system has
    more than :data:`MAX_SPEEDS` speeds (but for ``"dalembert"``).

    Parameters
    ----------
    system : MultibodySystem
    codes : dict
        The cache of programs (an evaluator's ``funs``); key ``("dae_jac", form, row mask)``.
    form : str
        One of :data:`DAE_JACOBIAN_FORMS`.
    backend : {"python", "c"}
    cache_dir : str, optional
    max_nodes : int

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.dae_jacobian import bound_program
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system, codes = mbcomp.assemble(m), {}
    >>> jac = bound_program(system, codes, "index3", "python")
    >>> bound_program(system.with_params({"b.m": 3.0}), codes, "index3", "python").code is jac.code   # reused
    True
    """
    if system.nu > MAX_SPEEDS and form != "dalembert":
        return None
    rm = system.row_mask
    key = ("dae_jac", form, None if rm is None or rm.all() else rm.tobytes())
    return bind_cached(codes, key, lambda: DAEJacobianCode.build(system, form, backend, cache_dir, max_nodes), system)


class DAEJacobianCode:
    """The generated Jacobian program of one DAE form, for one row mask and parameter signature
    (shared by systems differing only in parameter values; :meth:`bind` gives the callable).

    Use :meth:`build`, which returns None when the system has no such program (its
    evaluation cannot be traced).

    Attributes
    ----------
    form : str
        One of :data:`DAE_JACOBIAN_FORMS`.
    n : int
        State size of the form (``nq + nu`` for ``"mechanical"``: the pair ``(K, Ct)``).
    mh, mn : int
        Holonomic rows kept by the row mask, nonholonomic rows.
    n_ops : int
        Operations per call.
    backend : {"python", "c"}

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.dae_jacobian import DAEJacobianCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> code = DAEJacobianCode.build(mbcomp.assemble(m), "ggl", "python")
    >>> code.n, code.mh, code.backend      # [s, v, a]: no rows
    (3, 0, 'python')
    """

    def __init__(self, tr, mask, form, backend, cache_dir=None):
        if form not in DAE_JACOBIAN_FORMS:
            raise ValueError(f"DAE Jacobian form {form!r} is unknown; use one of {DAE_JACOBIAN_FORMS}")
        g = tr.graph
        self.form, self.backend = form, backend
        self.signature, self.layout, self.drives, self.inputs = tr.signature, tr.layout, tr.drives, tr.inputs
        F = evaluation_fields(tr)
        nq, nu = len(tr.groups["qrate"]), F["M"].shape[0] if F["M"].ndim == 2 else 0
        rows = np.flatnonzero(mask) if mask is not None else np.arange(F["Phi"].size)
        self.nq, self.nu = nq, nu
        self.mh, self.mn = len(rows), F["Psi"].size
        mh, m = self.mh, self.mh + self.mn
        qs = [g.memo.get(("in", "q", k)) for k in range(nq)]
        us = [g.memo.get(("in", "u", k)) for k in range(nu)]
        self.base = 3 * len(tr.drives) + 2 + len(tr.inputs)  # first slot of d after the model's own
        with g:
            gains = (g.input("d", 3 * len(tr.drives), 10.0), g.input("d", 3 * len(tr.drives) + 1, 10.0))
            slots = iter(range(self.base, self.base + 2 * nu + 2 * m))

            def new(v):  # an input in the next per-call slot after the model's own (v: trace-time value)
                return g.input("d", next(slots), v)

            C = np.array([F["C"][r] for r in rows], dtype=object).reshape(mh, nu)
            A = np.vstack((C, F["B"].reshape(self.mn, nu))) if self.mn else C
            qrate = list(tr.groups["qrate"])
            if form == "dalembert":
                rates = [F["Phid"][r] for r in rows] + list(F["Psi"])
                flat = [x for row in tangent(g, rates, qs)
                        for x in row]
                self.n = nq
            elif form == "mechanical":
                ud = [new(0.2 + 0.01 * k) for k in range(nu)]
                lam = [new(0.3 - 0.01 * k) for k in range(mh)]
                r = [dot(F["M"][i], ud) + dot(C[:, i], lam) - F["f"][i] for i in range(nu)]
                H = self._rates(g, qrate, us, tr.qrate_identity)
                Rq = tangent(g, r, qs)
                K = [[dot(Rq[i], [H[k][j] for k in range(nq)]) for j in range(nu)] for i in range(nu)]
                Fu = tangent(g, list(F["f"]), us)
                flat = [x for row in K for x in row] + [-x for row in Fu for x in row]
                self.n = nq + nu
            else:
                a = [new(0.2 + 0.01 * k) for k in range(nu)]
                lam = [new(0.3 - 0.01 * k) for k in range(m)]
                eta = [new(0.01 * (k + 1)) for k in range(mh)] if form == "ggl" else []
                dyn = [F["f"][i] - dot(F["M"][i], a) - dot(A[:, i], lam) for i in range(nu)]
                Phi = [F["Phi"][r] for r in rows]
                Phid = [F["Phid"][r] for r in rows]
                Psi = list(F["Psi"])
                if form == "ggl" and mh:
                    H = self._rates(g, qrate, us, tr.qrate_identity)
                    w = [us[j] - dot(C[:, j], eta) for j in range(nu)]
                    qrate = [dot(H[i], w) for i in range(nq)]
                if form == "index3":
                    cons = [-x for x in Phi] + [-x for x in Psi]
                elif form == "ggl":
                    cons = [-x for x in Phid] + [-x for x in Psi] + [-x for x in Phi]
                else:
                    alpha, beta = gains
                    bias = [F["cb"][r] + 2.0 * alpha * F["Phid"][r] + beta * beta * F["Phi"][r] for r in rows]
                    bias += [F["Bb"][k] + alpha * F["Psi"][k] for k in range(self.mn)]
                    cons = [-(dot(A[k], a) + bias[k]) for k in range(m)]
                res = qrate + a + dyn + cons
                ins = qs + us + a + lam + eta
                self.n = len(ins)
                flat = [x for row in tangent(g, res, ins) for x in row]
        self.n_out = len(flat)
        guards = list(tr.guard_groups["eval"]) + list(tr.guard_groups["qrate"])
        prog = Program(g, {"jac": flat}, guard_groups={"jac": guards})
        self.loaded = LoadedProgram(prog, "jac", "mbcomp_dae_jac", backend, cache_dir, "DAE Jacobian program")
        self.pre, self.n_ops, self.n_work = self.loaded.pre, self.loaded.n_ops, self.loaded.n_work

    def _rates(self, g, qrate, us, identity):
        """``H = d(dq/dt)/du`` (nq, nu): the coordinate rates are linear in the speeds."""
        nq, nu = len(qrate), len(us)
        if identity:
            return [[1.0 if i == j else 0.0 for j in range(nu)] for i in range(nq)]
        return tangent(g, qrate, us)  # a missing input (None): derivative zero

    @classmethod
    def build(cls, system, form, backend, cache_dir=None, max_nodes=3_000_000):
        """The Jacobian program of ``form`` for ``system`` (its current row mask).

        Parameters
        ----------
        system : MultibodySystem
            Assembled (and, for loops, initialized: the row mask is the program's).
        form : str
            One of :data:`DAE_JACOBIAN_FORMS`.
        backend : {"python", "c"}
        cache_dir : str, optional
            Where C libraries are cached (default ``$MBCOMP_CACHE`` or ``~/.cache/mbcomp``).
        max_nodes : int
            Abort tracing beyond this many graph nodes.

        Returns
        -------
        DAEJacobianCode
            Raises :class:`~mbcomp.codegen.graph.CodegenError` when the evaluation cannot be
            traced (the caller then differences).

        Examples
        --------
        >>> import mbcomp
        >>> from mbcomp.codegen.dae_jacobian import DAEJacobianCode
        >>> from mbcomp.library import World, Prismatic, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
        >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
        >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
        >>> DAEJacobianCode.build(mbcomp.assemble(m), "mechanical", "python").n_out   # K and Ct, 1 x 1 each
        2
        """
        with no_gc():
            tr = trace(system, max_nodes)
            mask = system.row_mask
            return cls(tr, None if mask is None or mask.all() else mask, form, backend, cache_dir)

    def bind(self, system):
        """The callable :class:`BoundDAEJacobian` for ``system``'s parameter values; None when
        they change a decision baked into the program (then it must be built again).

        Examples
        --------
        >>> import mbcomp
        >>> from mbcomp.codegen.dae_jacobian import DAEJacobianCode
        >>> from mbcomp.library import World, Prismatic, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
        >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
        >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
        >>> system = mbcomp.assemble(m)
        >>> type(DAEJacobianCode.build(system, "index1", "python").bind(system)).__name__
        'BoundDAEJacobian'
        """
        if param_layout(system)[1] != self.signature:
            return None
        pv = param_vector(system, self.layout)
        try:
            h = self.pre.run(pv)
        except Retrace:
            return None
        comps = system.topology.flat.components
        return BoundDAEJacobian(self, [(comps[d], system.P[d]) for d in self.drives], pv, h)


class BoundDAEJacobian:
    """A :class:`DAEJacobianCode` bound to one parameter set.

    ``J = jac(t, y, gains=None)`` for the semi-explicit forms: ``(n, n)`` ``d fun / d y``;
    ``(K, Ct) = jac.mechanical(t, q, u, udot, lam)`` for ``"mechanical"``; ``G =
    jac.dalembert(t, q, u)`` for ``"dalembert"``. Each is None
    where the program does not hold (a failed guard, a non-finite entry). ``gains``: the
    Baumgarte ``(alpha, beta)`` (1/s) of the index-1 form, None for none.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.dae_jacobian import DAEJacobianCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> DAEJacobianCode.build(system, "index3", "python").bind(system)(0.0, np.zeros(3)).tolist()
    [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -2.0]]
    """

    def __init__(self, code, drive_comps, pv, h):
        self.code, self.drive_comps, self.h = code, drive_comps, h
        nd = 3 * len(drive_comps)
        self.nd = nd
        self.d = np.zeros(code.base + 2 * code.nu + 2 * (code.mh + code.mn) + 1)
        if code.backend == "c":
            self.hbuf = np.array(list(h) + [0.0], float)
            self.pbuf = np.array(list(pv) + [0.0], float)
            self.qbuf = np.zeros(code.nq + 1)
            self.ubuf = np.zeros(code.nu + 1)
            self.wbuf = np.zeros(max(code.n_work, 1))
            self.obuf = np.zeros(code.n_out + 1)

    def _per_call(self, t, extra, gains):
        d, code = self.d, self.code
        if self.drive_comps:
            d[: self.nd] = [x for comp, p in self.drive_comps for x in comp.motion(t, p)]
        d[self.nd], d[self.nd + 1] = gains if gains is not None else (0.0, 0.0)
        if code.inputs:
            d[self.nd + 2: code.base] = [inp.value(t) for inp in code.inputs]
        d[code.base: code.base + extra.size] = extra

    def _run(self, t, q, u):
        code = self.code
        if code.backend == "python":
            try:
                out = code.loaded.fun(q.tolist(), u.tolist(), float(t), self.d.tolist(), self.h)
            except (Fallback, ArithmeticError, ValueError):
                return None
            out = np.array(out, float)
        else:
            self.qbuf[: q.size] = q
            self.ubuf[: u.size] = u
            if code.loaded.cfun(self.qbuf.ctypes.data, self.ubuf.ctypes.data, float(t), self.d.ctypes.data,
                                       self.hbuf.ctypes.data, self.pbuf.ctypes.data, self.wbuf.ctypes.data,
                                       self.obuf.ctypes.data):
                return None
            out = self.obuf[: code.n_out].copy()
        return out if np.isfinite(out).all() else None

    def __call__(self, t, y, gains=None):
        code = self.code
        if code.form in ("mechanical", "dalembert"):
            raise ValueError(f"this is the {code.form!r} program: call .{code.form}(...)")
        y = np.asarray(y, float)
        nq, nu = code.nq, code.nu
        self._per_call(t, y[nq + nu:], gains)
        out = self._run(t, y[:nq], y[nq:nq + nu])
        return None if out is None else out.reshape(code.n, code.n)

    def dalembert(self, t, q, u):
        """``G = d[dPhi/dt; Psi]/dq`` (m, nq) at ``(t, q, u)`` (see the module docstring), or None."""
        code = self.code
        if code.form != "dalembert":
            raise ValueError(f"this is the {code.form!r} program: call "
                             + (".mechanical(t, q, u, udot, lam)" if code.form == "mechanical" else "it with (t, y)"))
        self._per_call(t, np.zeros(0), None)
        out = self._run(t, np.asarray(q, float), np.asarray(u, float))
        return None if out is None else out.reshape(code.mh + code.mn, code.nq)

    def mechanical(self, t, q, u, udot, lam):
        """``(K, Ct)``, ``(nu, nu)`` each (see the module docstring), or None."""
        code = self.code
        if code.form != "mechanical":
            raise ValueError(f"this is the {code.form!r} program: call it with (t, y)")
        self._per_call(t, np.concatenate((udot, lam)), None)
        out = self._run(t, np.asarray(q, float), np.asarray(u, float))
        if out is None:
            return None
        nu = code.nu
        return out[: nu * nu].reshape(nu, nu), out[nu * nu:].reshape(nu, nu)
