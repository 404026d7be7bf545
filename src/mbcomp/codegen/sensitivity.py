"""The programs of forward sensitivities: ``fun``, ``d fun/dy`` and ``d fun/dp`` of the Lagrange
index-1 right-hand side, and the constraint residuals with their derivatives, for chosen
parameters ``p``.

:class:`SensitivityCode` traces a system twice (:func:`mbcomp.codegen.tracer.trace` with the
chosen parameters kept as program inputs even where they are zero, ``keep=``): the right-hand
side ``fun(t, y) = [dq/dt, du/dt]`` (``program="fun"``, the system's row mask), and the
evaluation (``program="eval"``) for the residuals ``Phi`` (positions), ``Phid`` (their time
derivative) and ``Psi`` (velocity rows). Both are differentiated forward
(:func:`mbcomp.codegen.tangent.tangent`) with respect to ``q``, ``u`` and the chosen parameter
entries, and printed as two programs (Python, or C when the system runs a C program). A
failed guard of either (a law's branch the trace did not take) gives None: the derivatives
are not those of the program there.

A parameter is named ``"component.param"`` (a scalar) or ``"component.param[i]"`` /
``"component.param[i, j]"`` (an entry of an array parameter). A parameter a component turns
into a plain number (``float(p.m)``) cannot be differentiated: :meth:`SensitivityCode.build`
says so naming it.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.sensitivity import SensitivityCode
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = mbcomp.assemble(m)
>>> code = SensitivityCode.build(system, ["bob.m", "world.g[1]"], "python")
>>> f, J, Jp = code.bind(system).rhs(0.0, np.array([0.5, 0.0]), 0.0, 0.0)
>>> Jp[1].round(12).tolist()       # du/dt = g_y sin(phi) / l: no mass in it; d/dg_y = sin(0.5)
[0.0, 0.479425538604]
"""
from __future__ import annotations

import ctypes
import re
import weakref
from dataclasses import dataclass
from numbers import Real

import numpy as np

from .dae_jacobian import evaluation_fields
from .graph import CodegenError, Fallback, no_gc
from .printers import Program
from .loaded import LoadedProgram
from .replay import replay
from .tangent import tangent
from .tracer import param_layout, param_vector, trace
from .tracing import parameter_entries

__all__ = ["ParameterRef", "parameter_ref", "SensitivityCode", "BoundSensitivity", "ColumnCode"]

#: the programs of each structure, per topology (:meth:`SensitivityCode.cached`)
_CACHE = weakref.WeakKeyDictionary()

_NAME = re.compile(r"^\s*([A-Za-z_][\w.]*)\.([A-Za-z_]\w*)\s*(?:\[\s*([0-9,\s]+)\])?\s*$")


@dataclass(frozen=True)
class ParameterRef:
    """One parameter entry a sensitivity is taken with respect to.

    Attributes
    ----------
    name : str
        As the user wrote it, e.g. ``"rod.m"`` or ``"rod.I[2, 2]"``.
    path, param : str
        The component's path and the parameter's name.
    index : tuple or None
        The entry of an array parameter (None for a scalar).
    kind : {"param", "start"}
        ``"start"``: a start value (the motion depends on it only through the initial state).
    value : float
        Its value in the system (SI units of the parameter).

    Examples
    --------
    >>> ParameterRef("rod.m", "rod", "m", None, "param", 2.0).key
    ('rod', 'm', None)
    """

    name: str
    path: str
    param: str
    index: tuple | None
    kind: str
    value: float

    @property
    def key(self):
        """``(path, param, index)``: the entry in a program's parameter layout."""
        return (self.path, self.param, self.index)


def parameter_ref(system, name):
    """The :class:`ParameterRef` of ``name`` (``"component.param"`` or ``"component.param[i, j]"``)
    in ``system``; a ``ValueError`` naming what is wrong and the fix otherwise.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.sensitivity import parameter_ref
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(phi0=0.5))
    >>> b = m.add("b", PointMass(m=2.0)); m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> s = mbcomp.assemble(m)
    >>> parameter_ref(s, "b.m").kind, parameter_ref(s, "j.phi0").kind, parameter_ref(s, "j.n[2]").index
    ('param', 'start', (2,))
    """
    match = _NAME.match(str(name))
    if match is None:
        raise ValueError(f"sensitivity parameter {name!r}: write it as 'component.param' or 'component.param[i]' "
                         "(e.g. 'rod.m', 'rod.I[2, 2]')")
    path, param, idx = match.group(1), match.group(2), match.group(3)
    entries = {(p, n): (kind, v) for p, n, kind, v in parameter_entries(system)}
    if path not in system.P:
        raise ValueError(f"sensitivity parameter {name!r}: the model has no component {path!r} "
                         f"-> use one of {', '.join(sorted(system.P))}")
    if (path, param) not in entries:
        have = sorted(n for p, n in entries if p == path)
        raise ValueError(f"sensitivity parameter {name!r}: component {path!r} has no parameter {param!r} "
                         f"(or it is a drive's, whose motion is not differentiated) -> use one of {', '.join(have)}")
    kind, value = entries[(path, param)]
    kind = "start" if kind == "start" else "param"
    arr = np.asarray(getattr(value, "value", value), dtype=object)
    if idx is None:
        if arr.ndim != 0:
            raise ValueError(f"sensitivity parameter {name!r} is an array of shape {arr.shape} -> name one entry, "
                             f"e.g. '{path}.{param}[{', '.join('0' * arr.ndim)}]'")
        v = arr.item()
        index = None
    else:
        index = tuple(int(k) for k in idx.split(",") if k.strip())
        if arr.ndim != len(index) or any(not 0 <= k < n for k, n in zip(index, arr.shape)):
            raise ValueError(f"sensitivity parameter {name!r}: index {index} does not fit {path}.{param} of shape "
                             f"{arr.shape}")
        v = arr[index]
    if not isinstance(v, Real) or isinstance(v, bool):
        raise ValueError(f"sensitivity parameter {name!r} is {type(v).__name__} {v!r}, not a number: only numeric "
                         "parameters (masses, lengths, rates, start values) can be differentiated")
    return ParameterRef(str(name), path, param, index, kind, float(v))


def _jacobian(g, outputs, ins):
    """The flat ``d outputs / d ins`` (row major) built in ``g``; an input that is None (not
    made by the tracer) has derivative zero."""
    return [v for row in tangent(g, outputs, ins) for v in row]


class SensitivityCode:
    """The sensitivity programs of one system structure and set of parameters (see the module
    notes); :meth:`bind` gives the callables for a system's parameter values.

    Use :meth:`build`.

    Attributes
    ----------
    n, nq : int
        States ``nq + nu`` and coordinates.
    params : list of ParameterRef
        The parameters (``"param"`` kind) the programs differentiate with respect to.
    m : int
        Residual rows ``Phi`` (unmasked, all the system's holonomic rows).
    backend : {"python", "c"}

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.sensitivity import SensitivityCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> code = SensitivityCode.build(mbcomp.assemble(m), ["world.g[2]"], "python")
    >>> code.n, [p.name for p in code.params]
    (2, ['world.g[2]'])
    """

    def __init__(self, fun_tr, eval_tr, directions, backend, cache_dir=None):
        self.directions = list(directions)  # every requested parameter: a direction of the jvp program
        self.params = [r for r in directions if r.kind == "param"]
        self.backend, self.cache_dir = backend, cache_dir
        self.signature, self.layout = fun_tr.signature, fun_tr.layout
        self.n = len(fun_tr.groups["fun"])
        self.nq = len(fun_tr.groups["qrate"])
        self.nu = self.n - self.nq
        self._fun_tr, self._eval_tr = fun_tr, eval_tr
        shapes = eval_tr.shapes
        self.m, self.mv = int(np.prod(shapes["Phi"])), int(np.prod(shapes["Psi"]))
        self._printed = {}

    def program(self, key):
        """The printed program ``key``, made at first need: ``"jvp"`` (``fun`` and
        ``f_y S + f_p`` for the ``k`` directions ``S`` given per call), ``"jac"`` (``fun``,
        ``d fun/dy``, ``d fun/dp``: for implicit methods), ``"res"`` (the residuals and their
        derivatives)."""
        if key not in self._printed:
            make = {"jvp": self._jvp_program, "jac": self._jac_program, "res": self._residual_program}[key]
            with no_gc():
                prog, n_out, n_d = make()
            self._printed[key] = _Printed(prog, key, n_out, n_d, self.backend, self.cache_dir)
        return self._printed[key]

    def _inputs(self, g, layout):
        ins = [g.memo.get(("in", "q", k)) for k in range(self.nq)] + [g.memo.get(("in", "u", k))
                                                                      for k in range(self.nu)]
        index = {key: k for k, key in enumerate(layout)}
        ins += [g.memo.get(("in", "p", index[p.key])) for p in self.params]
        return ins

    def _jac_program(self):
        tr = self._fun_tr
        g, fun = tr.graph, list(tr.groups["fun"])
        out = fun + _jacobian(g, fun, self._inputs(g, tr.layout))
        return Program(g, {"jac": out}, guard_groups={"jac": list(tr.guard_groups["fun"])}), len(out), 2

    def _jvp_program(self):
        """``[fun, (f_y S + f_p)]`` with the ``n x k`` directions ``S`` per-call inputs
        (``d[2:2 + n k]``, row major; ``d[2 + n k:]`` the ``k`` step inputs, zero): the traced
        right-hand side replayed with ``y -> y + S eps`` and each parameter ``p_j -> p_j + eps_j``
        (:func:`mbcomp.codegen.replay.replay`), differentiated with respect to ``eps`` alone --
        ``k`` forward sweeps, not ``n + k`` (a 50-link chain's full Jacobian program is 100
        sweeps)."""
        tr = self._fun_tr
        n, nq, k = self.n, self.nq, len(self.directions)
        index = {key: r for r, key in enumerate(tr.layout)}

        def shift(g2):
            eps = [g2.input("d", 2 + n * k + j, 0.0) for j in range(k)]
            S = [[g2.input("d", 2 + i * k + j, 0.0) for j in range(k)] for i in range(n)]
            moved = {}
            for i in range(n):
                kind, pos = ("q", i) if i < nq else ("u", i - nq)
                moved[(kind, pos)] = lambda x, row=S[i]: x + sum(e * c for e, c in zip(eps, row))
            for j, ref in enumerate(self.directions):
                if ref.kind == "param":
                    moved[("p", index[ref.key])] = lambda x, e=eps[j]: x + e
            return moved, eps

        g2, outs, eps = replay(tr.graph, list(tr.groups["fun"]), shift)
        D = tangent(g2, outs, eps)
        out = list(outs) + [v for row in D for v in row]
        prog = Program(g2, {"jvp": out}, guard_groups={"jvp": list(g2.guards)})
        return prog, len(out), 2 + n * k + k

    def _residual_program(self):
        tr = self._eval_tr
        g, fields = tr.graph, evaluation_fields(tr)
        res = list(fields["Phi"]) + list(fields["Phid"]) + list(fields["Psi"])
        out = res + _jacobian(g, res, self._inputs(g, tr.layout))
        return Program(g, {"res": out}, guard_groups={"res": list(tr.guard_groups["eval"])}), len(out), 2

    @classmethod
    def build(cls, system, names, backend, cache_dir=None, max_nodes=3_000_000):
        """The programs of ``system`` (its row mask) for the parameters ``names`` (see
        :func:`parameter_ref`; start values are left out: they enter only the initial state).

        Raises
        ------
        CodegenError
            When the system's laws cannot be traced (naming the component), when drives or
            external inputs are evaluated in Python at every call, when the trace point is
            singular, or when a component turns one of the parameters into a plain number.
        """
        directions = [parameter_ref(system, n) for n in names]
        refs = [r for r in directions if r.kind == "param"]
        keep = {(r.path, r.param) for r in refs}
        with no_gc():
            fun_tr = trace(system, max_nodes, program="fun", keep=keep)
            if "fun" not in fun_tr.groups:
                raise CodegenError("sensitivities: the right-hand side is singular at the trace point (the start "
                                   "position with generic speeds) -> start the mechanism away from a singular position")
            if fun_tr.drives or fun_tr.inputs:
                raise CodegenError("sensitivities: drives whose motion a program cannot hold, or external inputs, "
                                   "are evaluated in Python at every call -> write the drive's motion with numpy "
                                   "functions of t (it is then traced), or run without sensitivities")
            baked = set(fun_tr.baked)
            bad = [r.name for r in refs if f"{r.path}.{r.param}" in baked]
            if bad:
                raise CodegenError(f"sensitivities: {', '.join(bad)} is turned into a plain number by its component "
                                   "(float(), int(), a comparison that picks a branch) -> it cannot be "
                                   "differentiated; write the component's law with the parameter as a value")
            eval_tr = trace(system, max_nodes, program="eval", keep=keep)
            return cls(fun_tr, eval_tr, directions, backend, cache_dir)

    @classmethod
    def cached(cls, system, names, backend):
        """:meth:`build`, once per process for a structure: systems sharing a topology, row
        mask, parameter signature (zero pattern, laws) and requested parameters share their
        programs (a fit's runs at other parameter values trace nothing again)."""
        keep = {(r.path, r.param) for r in (parameter_ref(system, n) for n in names) if r.kind == "param"}
        mask = None if system.row_mask is None else np.asarray(system.row_mask, bool).tobytes()
        key = (param_layout(system, keep)[1], tuple(names), backend, mask)
        per_topology = _CACHE.setdefault(system.topology, {})
        if key not in per_topology:
            per_topology[key] = cls.build(system, names, backend)
        return per_topology[key]

    def bind(self, system):
        """The callables :class:`BoundSensitivity` for ``system``'s parameter values (its
        structure must be this code's; a ``ValueError`` otherwise)."""
        keep = {(r.path, r.param) for r in self.params}
        layout, sig = param_layout(system, keep)
        if sig != self.signature:
            raise ValueError("sensitivities: the system's structure differs from the program's -> build it again")
        pv = param_vector(system, layout)
        return BoundSensitivity(self, pv)


class _Printed(LoadedProgram):
    """One loaded program (``jvp``, ``jac``, ``res`` or ``cols``) taking ``n_d`` per-call
    inputs ``d`` and writing ``n_out`` values."""

    def __init__(self, prog, key, n_out, n_d, backend, cache_dir):
        super().__init__(prog, key, f"mbcomp_sens_{key}", backend, cache_dir, "sensitivity program")
        self.key, self.n_out, self.n_d = key, n_out, n_d


class _Bound:
    """One :class:`_Printed` program bound to a parameter vector ``pv``: :meth:`call`."""

    def __init__(self, printed, n, nq, pv):
        self.printed, self.n, self.nq = printed, n, nq
        self.h = printed.pre.run(pv)
        self.d = np.zeros(printed.n_d + 1)
        if printed.backend == "c":
            self.hbuf = np.array(list(self.h) + [0.0], float)
            self.pbuf = np.array(list(pv) + [0.0], float)
            self.ybuf = np.zeros(n + 1)
            self.wbuf, self.obuf = np.zeros(max(printed.n_work, 1)), np.zeros(printed.n_out + 1)
            base = self.ybuf.ctypes.data  # the buffers live as long as this object: their addresses once
            self.args = (base, base + 8 * nq, self.d.ctypes.data, self.hbuf.ctypes.data, self.pbuf.ctypes.data,
                         self.wbuf.ctypes.data, self.obuf.ctypes.data)

    def call(self, t, y, alpha, beta, extra=None, finite=True):
        """The program's flat output at ``(t, y = [q, u])`` with the per-call inputs ``alpha``,
        ``beta`` and then ``extra``; None where a guard fails or (``finite``) a value is not
        finite."""
        printed, n, nq = self.printed, self.n, self.nq
        self.d[0], self.d[1] = alpha, beta
        if extra is not None:
            self.d[2:2 + len(extra)] = extra
        if printed.backend == "python":
            try:
                out = printed.fun(list(map(float, y[:nq])), list(map(float, y[nq:n])), float(t),
                                  self.d[:printed.n_d].tolist(), self.h)
            except (Fallback, ArithmeticError, ValueError):
                return None
            out = np.array(out, float)
        else:
            self.ybuf[:n] = y
            a = self.args
            if printed.cfun(a[0], a[1], float(t), a[2], a[3], a[4], a[5], a[6]):
                return None
            out = self.obuf[: printed.n_out].copy()
        return out if not finite or np.isfinite(out).all() else None


class BoundSensitivity:
    """A :class:`SensitivityCode` bound to one parameter set.

    :meth:`rhs` gives ``(fun, d fun/dy, d fun/dp)`` and :meth:`residuals` the constraint
    residuals with their derivatives; both None where the program does not hold (a failed
    guard, a non-finite value).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.sensitivity import SensitivityCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> f, J, Jp = SensitivityCode.build(system, ["world.g[2]"], "python").bind(system).rhs(0.0, np.zeros(2), 0.0, 0.0)
    >>> f.tolist(), Jp.ravel().tolist()     # du/dt = g_z
    ([0.0, -9.81], [0.0, 1.0])
    """

    def __init__(self, code, pv):
        self.code, self.pv = code, pv
        self.bound = {}

    def program(self, key):
        """The bound program ``key`` (:meth:`SensitivityCode.program`), made at first need."""
        if key not in self.bound:
            self.bound[key] = _Bound(self.code.program(key), self.code.n, self.code.nq, self.pv)
        return self.bound[key]

    def _call(self, key, t, y, alpha, beta, extra=None):
        return self.program(key).call(t, y, alpha, beta, extra)

    def rhs(self, t, y, alpha, beta):
        """``(fun (n,), d fun/dy (n, n), d fun/dp (n, np))`` at ``(t, y = [q, u])`` with the
        Baumgarte gains ``alpha``, ``beta`` (1/s, zero for none), or None (the ``"jac"``
        program: every direction; for implicit methods)."""
        out = self._call("jac", t, y, alpha, beta)
        if out is None:
            return None
        n, k = self.code.n, len(self.code.params)
        f = out[:n]
        D = out[n:].reshape(n, n + k)
        return f, D[:, :n], D[:, n:]

    def jvp(self, t, y, S, alpha, beta):
        """``(fun (n,), f_y S + f_p (n, k))`` at ``(t, y)`` for the ``k`` requested parameters'
        columns ``S`` (``(n, k)``; a start value's column has no ``f_p``), or None (the ``"jvp"``
        program: ``k`` forward sweeps)."""
        n, k = self.code.n, len(self.code.directions)
        extra = np.concatenate((np.asarray(S, float).ravel(), np.zeros(k)))
        out = self._call("jvp", t, y, alpha, beta, extra)
        if out is None:
            return None
        return out[:n], out[n:].reshape(n, k)

    def residuals(self, t, y):
        """``(r, dr/dq, dr/du, dr/dp)`` of ``r = [Phi (all rows), Phid, Psi]`` at ``(t, y)``, or
        None; ``dr/dq`` is with respect to the coordinates ``q`` (not the speeds' directions)."""
        out = self._call("res", t, y, 0.0, 0.0)
        if out is None:
            return None
        c = self.code
        nr = 2 * c.m + c.mv
        r = out[:nr]
        D = out[nr:].reshape(nr, c.n + len(c.params))
        return r, D[:, :c.nq], D[:, c.nq:c.n], D[:, c.n:]


class ColumnCode:
    """The derivatives of the result columns (:func:`mbcomp.assembly.outputs.output_values`:
    coordinates and rates, reactions, joints' outputs, poses, twists, energies, residuals)
    with respect to ``[q, u]`` and chosen parameters, as one program (the output program
    traced with the parameters kept, :func:`mbcomp.codegen.tracer.trace` ``program="outputs"``,
    differentiated forward).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.sensitivity import ColumnCode
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> code = ColumnCode.build(system, ["b.m"], "python")
    >>> D = code.bind(system)(0.0, np.array([1.0, 2.0]), 0.0, 0.0)
    >>> k = code.names.index("energy.kinetic"); D[k].tolist()      # T = m v^2 / 2: dT/dv = m v, dT/dm = v^2 / 2
    [0.0, 4.0, 2.0]
    """

    def __init__(self, tr, params, backend, n, cache_dir=None):
        self.params, self.backend = list(params), backend
        self.signature = tr.signature
        self.n, self.nq = n, len(tr.groups["qrate"])
        self.names = list(tr.output_names)
        values = tr.groups["outputs"][: len(self.names)]
        g = tr.graph
        ins = [g.memo.get(("in", "q", k)) for k in range(self.nq)] + [g.memo.get(("in", "u", k))
                                                                      for k in range(self.n - self.nq)]
        index = {key: k for k, key in enumerate(tr.layout)}
        ins += [g.memo.get(("in", "p", index[p.key])) for p in self.params]
        flat = _jacobian(g, values, ins)
        prog = Program(g, {"cols": flat}, guard_groups={"cols": list(tr.guard_groups["outputs"])})
        self.printed = _Printed(prog, "cols", len(flat), 2, backend, cache_dir)

    @classmethod
    def build(cls, system, names, backend, cache_dir=None, max_nodes=3_000_000):
        """The column program of ``system`` for the parameters ``names`` (start values left out)."""
        refs = [r for r in (parameter_ref(system, n) for n in names) if r.kind == "param"]
        keep = {(r.path, r.param) for r in refs}
        with no_gc():
            tr = trace(system, max_nodes, program="outputs", baumgarte=True, keep=keep)
            if "outputs" not in tr.groups:
                raise CodegenError("sensitivities of the columns: the output program is singular at the trace point "
                                   "(the start position with generic speeds) -> start the mechanism away from a "
                                   "singular position")
            return cls(tr, refs, backend, system.nq + system.nu, cache_dir)

    def bind(self, system):
        """``D = f(t, y, alpha, beta)``: ``(n_columns, nq + nu + n_params)`` (NaN in the rows of
        columns without a derivative there, e.g. a residual's norm at zero) or None where a
        guard fails."""
        keep = {(r.path, r.param) for r in self.params}
        layout, sig = param_layout(system, keep)
        if sig != self.signature:
            raise ValueError("sensitivities: the system's structure differs from the program's -> build it again")
        bound = _Bound(self.printed, self.n, self.nq, param_vector(system, layout))
        width = self.n + len(self.params)

        def call(t, y, alpha, beta):  # a column may have no derivative (a residual's norm at 0): NaN there
            out = bound.call(t, y, alpha, beta, finite=False)
            return None if out is None else out.reshape(len(self.names), width)
        return call
