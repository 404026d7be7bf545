"""Generated straight-line programs: the assembled equations traced once, printed as Python or
C, and run as the system's evaluator.

:func:`compile_system` runs the *same* numeric :meth:`MultibodySystem.evaluate_numeric
<mbcomp.assembly.system.MultibodySystem.evaluate_numeric>` once on numpy object arrays whose
elements are :class:`~mbcomp.codegen.graph.Sym` tracer scalars (:mod:`mbcomp.codegen.tracer`).
Every arithmetic operation becomes a node of a hash-consed expression graph (a
:class:`~mbcomp.codegen.graph.Graph`): equal ``(operation, operands)`` pairs are one node,
which is common-subexpression elimination for free, and ``x*0``, ``x*1``, ``x+0``, ``x-x`` and
operations on constants fold away, so the structural zeros of a planar mechanism or of a
sparse Jacobian cost nothing. The graph is then printed as a straight-line program
(:mod:`mbcomp.codegen.printers`, :mod:`mbcomp.codegen.compiler`):

* ``backend="python"`` (the default, needs no compiler): one Python function per program,
  scalars as local variables and ``math`` functions, compiled with :func:`compile`;
* ``backend="c"``: the same graph printed as C, compiled by the system compiler (``gcc``/``cc``,
  or ``$CC``) into a shared library cached on disk (``$MBCOMP_CACHE``, default
  ``~/.cache/mbcomp``; the key is a hash of the generated source), loaded with :mod:`ctypes`;
* ``backend="auto"``: C when a compiler is found, else Python.

What is a runtime argument and what is baked
--------------------------------------------
* Runtime arguments (``changing them re-derives nothing``): every nonzero number of a numeric
  parameter -- masses, inertia tensors, centres of mass, lengths (``FixedTranslation.r``),
  spring rates, damping coefficients, constant torques, gravity -- and ``q``, ``u``, ``t``.
  Nodes that depend on parameters only (e.g. ``m L^2 / 12`` or a normalized hinge axis) are
  hoisted into a small *parameter program* that runs once per parameter set.
* Drives (:class:`~mbcomp.roles.Drive`) are evaluated numerically at every call and their
  ``(s, v, a)`` enter the program as inputs, so any law works (strings, sympy, numpy or
  ``math`` callables).
* Baked (part of the program's structure): which parameter entries are exactly zero, laws
  given as callables (their expression is traced), and every decision a component took on a
  parameter value (``float(p.n)``, ``if p.d:``, ``abs(n[0]) < 0.9``): such decisions are
  recorded as *guards*. ``compiled.with_params(...)`` reuses the program and only reruns
  the parameter program; if a new value changes the zero pattern, a law or violates a guard,
  the model is traced again (lazily, at the next evaluation) -- never silently wrong.
* Decisions on state values (``if x < 0`` in a force law) are guards checked inside the
  generated program; when one fails, or the program hits a domain error (``sqrt`` of a
  negative number, division by zero), that call falls back to the numeric evaluation, which
  gives exactly the numeric path's result or error (counted in ``stats["fallbacks"]``).

A component whose law cannot be traced (``math.sin`` or ``float()`` of a state value) makes
:func:`compile_system` raise :class:`CodegenError` naming the component and the fix.

Limits
------
* ``x*0 -> 0`` is folded although ``inf*0`` is ``nan``: a program differs from the numeric
  path only where the numeric path itself is already non-finite. Sums are reassociated so
  that parameter terms gather (``(x + p1) + p2 -> x + (p1 + p2)``) and signs move outwards
  (``(-a) b -> -(a b)``); results agree with the numeric path to rounding (1e-15 relative
  in ``M`` and ``f``).
* The program mirrors the numeric evaluation, whose mass matrix is the sum over bodies of
  ``J^T M_b J``: its size grows like ``N^3`` for an N-link chain (planar pendulum: about
  2,000 operations at N = 10, 930,000 at N = 100; 3-D chain: 45,000 at N = 10, 290,000 at
  N = 20). The Python program costs about 20 ns per operation, so it beats the vectorized
  numeric path up to roughly 10^5 operations; the C program (a few ns per operation) beyond.
  gcc -O2 needs ~0.15-0.2 ms per straight-line statement, in parallel units, once: the
  objects and the library are cached (see the compile policy in docs/design/generated-programs.md).
* The result is a :class:`~mbcomp.assembly.system.MultibodySystem` whose evaluator is a
  :class:`ProgramEvaluator` (``system.backend`` is ``"python"`` or ``"c"``); its kinematics,
  reactions and energies are the numeric code, and ``evaluate_numeric`` stays available.
* A compiled system keeps work buffers: do not evaluate one instance from several threads.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen import compile_system
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> fast = compile_system(mbcomp.assemble(m))
>>> ev = fast.evaluate(0.0, np.array([0.5]), np.array([1.0]))
>>> round(float(ev.M[0, 0]), 12), round(float(ev.f[0]), 12)   # m l^2, -m g l sin(phi)
(2.0, -9.406329067414)
>>> heavy = fast.with_params({"bob.m": 3.0})                    # nothing re-derived
>>> round(float(heavy.evaluate(0.0, np.array([0.5]), np.array([1.0])).M[0, 0]), 12), heavy.stats["traces"]
(3.0, 1)
"""
from __future__ import annotations

import os
import time

import numpy as np

from ..assembly.evaluation import Rows
from ..assembly.system import MultibodySystem
from .compiled_evaluation import CompiledEvaluation
from .compiler import Bound, Code
from .dae_jacobian import bound_program
from .graph import CodegenError, Fallback, Retrace
from .jacobian import JacobianCode
from .loaded import bind_cached
from .structure_key import STRUCTURES, compiler
from .toolchain import FLAGS
from .tracer import param_signature, trace
from .verify import verify_evaluation, verify_fun

__all__ = ["compile_system", "ProgramEvaluator", "CompiledEvaluation"]


#: a lazy evaluator (``compile_system(..., lazy=True)``: ``simulate``'s) answers this many evaluations
#: numerically before it makes the evaluation program (at N = 1000 minutes of gcc against 0.2 s a
#: numeric evaluation), unless told otherwise (:meth:`ProgramEvaluator.evaluate_by_program`)
LAZY_EVALUATIONS = 200

#: fewer output points than this are post-processed numerically (compiling the output program
#: costs ~100 numeric points of a small model), counted over a structure's runs in the process
OUTPUT_GRID_MIN = 100


class ProgramEvaluator:
    """The evaluator of a compiled system: ``evaluate`` and ``q_rate`` run the generated program.

    Bound to one :class:`~mbcomp.assembly.system.MultibodySystem` (its parameter values and
    row mask); :func:`compile_system` makes one, ``rebind`` (used by ``with_params``) reuses
    its program for another parameter set. A failed state guard or a domain error falls back
    to the system's numeric evaluation for that call.

    ``stats`` holds the build statistics: ``backend``, ``n_ops`` (operations of the evaluation
    program), ``n_ops_qrate``, ``n_ops_params`` (the hoisted parameter program), ``n_hoisted``,
    ``n_nodes``, ``n_params`` (runtime parameter entries), ``n_guards`` (parameter, state),
    ``state_guards`` (per program: the state decisions it checks); once the Lagrange
    right-hand side program is made (at its first use): ``n_ops_fun``, ``fun_compile_time``,
    ``fun_state_guards``;
    ``baked`` (parameters a component turned into numbers), ``trace_time``, ``compile_time``
    (s), ``cache`` (C: ``"hit"``/``"miss"``), ``traces`` and ``fallbacks``.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import compile_system
    >>> from mbcomp.formulations import LagrangeIndex1
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> s = mbcomp.assemble(m); fast = compile_system(s)
    >>> type(fast.evaluator).__name__, fast.backend, s.backend
    ('ProgramEvaluator', 'python', 'numeric')
    >>> y = np.array([0.5, 0.0])
    >>> bool(np.allclose(LagrangeIndex1(fast).fun(0.0, y), LagrangeIndex1(s).fun(0.0, y), rtol=1e-12))
    True
    >>> res = mbcomp.simulate(fast, t_end=0.5)
    >>> res.status
    'success'
    """

    def __init__(self, system, backend="python", *, cache_dir=None, verify=True, max_nodes=3_000_000, code=None,
                 fun_codes=None, lazy=False, checked=False, reuse=False):
        if backend == "auto":
            backend = "c" if compiler() else "python"
        if backend not in ("python", "c"):
            raise ValueError(f"backend {backend!r} is unknown; use 'python', 'c' or 'auto'")
        self.system, self.backend = system, backend
        self.options = dict(cache_dir=cache_dir, verify=verify, max_nodes=max_nodes, lazy=lazy)
        self.bound = None
        self.numeric_calls = 0  # evaluations answered numerically while the program is not made (lazy)
        self._signature = None
        self.stats = dict(backend=backend, traces=0, fallbacks=0)
        if reuse and fun_codes is None:
            # the programs of a system of the same structure (codegen/structure_key.py): a model
            # rebuilt with other parameter or start values is not traced or printed again
            where = cache_dir or os.environ.get("MBCOMP_CACHE")
            fun_codes, hit = STRUCTURES.entry(system, backend, (max_nodes, where, compiler(), FLAGS), self.signature)
            hit = hit and fun_codes.get("checked", False)
            self.stats["structure_cache"] = "hit" if hit else "miss"
            # a lazy evaluator takes the evaluation program only after LAZY_EVALUATIONS
            # numeric ones (from the cache then, by _bound), as a cold one: the same values
            code, checked = (None if lazy else fun_codes.get("eval"), True) if hit else (None, checked)
        # row mask -> Code of the Lagrange program (or None), and the output programs: one dict
        # shared by every rebound copy (with_params) and every system of this structure, so that
        # runs with other parameter values reuse what any of them traced (a study traced three
        # programs per run before)
        self.funs = fun_codes if fun_codes is not None else {}
        self._fun = None  # (row mask key, Bound or None, the mask object)
        if code is not None:
            self.stats["traces"] = code.traces
            self._bind_eval(code)
            return  # otherwise traced again lazily at the first evaluation
        if lazy:
            # the evaluation program (O(N^2): the dense M) is made only when evaluations are
            # asked for often (LAZY_EVALUATIONS); the right-hand side is traced now, so a law
            # that cannot be traced is reported before the run, as without laziness (not again
            # for a rebound copy or a structure seen before: its structure was checked)
            if checked:
                return
            if system.topology.cut and system.row_mask is None:
                trace(system, max_nodes, program="fun")  # a check: the program needs the row mask
            else:
                self._fun_bound()
            self.funs["checked"] = True
            return
        self._build()
        self.funs["checked"] = True

    @property
    def signature(self):
        """The parameter signature of this evaluator's system (:func:`mbcomp.codegen.tracer.param_signature`),
        computed once."""
        if self._signature is None:
            self._signature = param_signature(self.system)
        return self._signature

    def _bind_eval(self, code):
        """Bind the evaluation program ``code`` to this system when it holds for its parameters."""
        if self.signature == code.signature:
            try:
                self.bound = Bound(code, self.system)
                self._record(code)
            except Retrace:
                self.bound = None

    def rebind(self, system, laws=False):
        """This evaluator's program for ``system`` (other parameter values): reused unless the
        change alters what is baked into it (a zero pattern, a law, a guarded decision); then
        it is traced again at the first evaluation. ``laws``: a law was replaced, so the
        right-hand side is traced now (a law that cannot be traced is reported here, as when
        the program was first made)."""
        code = self.bound.code if self.bound is not None else None
        return ProgramEvaluator(system, self.backend, code=code, fun_codes=self.funs, checked=not laws, **self.options)

    # --- building ----------------------------------------------------------------------------
    def _build(self):
        system, o = self.system, self.options
        t0 = time.perf_counter()
        tr = trace(system, o["max_nodes"])
        trace_time = time.perf_counter() - t0
        code = Code(tr, self.backend, o["cache_dir"])
        code.trace_time = trace_time
        code.traces = self.stats.get("traces", 0) + 1
        self.bound = Bound(code, system, first=True)
        self._record(code)
        if o["verify"]:
            self._verify()
        self.funs["eval"] = code
        return self.bound

    def _record(self, code):
        self.stats.update(n_ops=code.n_ops, n_ops_qrate=code.n_ops_qrate, n_ops_params=code.n_ops_params,
                          n_hoisted=code.n_hoisted, n_nodes=code.n_nodes, n_params=len(code.layout),
                          n_guards=code.n_guards, state_guards=dict(code.state_guards), baked=list(code.baked), trace_time=code.trace_time,
                          compile_time=code.compile_time, cache=code.cache, traces=code.traces)

    def _verify(self):
        """The program against the numeric evaluation at the trace point."""
        verify_evaluation(self.bound, self.system)

    def _verify_fun(self, bound):
        """The Lagrange program against the numeric dense solve at the trace point."""
        verify_fun(bound, self.system)

    @property
    def capabilities(self):
        """What this evaluator offers beyond ``evaluate``/``q_rate``: ``"lagrange_fun"`` when
        the program has the Lagrange index-1 right-hand side (:meth:`lagrange_fun`),
        ``"c_integrate"`` when the C engine can step it (:meth:`integrator`),
        ``"dalembert_fun"`` when the D'Alembert right-hand side runs in one C call
        (:meth:`dalembert_fun`), ``"dae_fun"`` when the DAE forms' residual and Jacobian do
        (:meth:`dae_program`), ``"outputs"``: result columns of whole output grids
        (:meth:`output_grid`). Asking makes the Lagrange program; :meth:`offers` asks for
        one capability and makes only what that one needs."""
        # the D'Alembert and DAE calls need a compiler only: say so without making the
        # evaluation program (O(N^2)), which the Lagrange path never needs
        caps = {"outputs"} | ({"dalembert_fun", "dae_fun"} if self.backend == "c" and compiler() else set())
        bound = self._fun_bound()
        if bound is not None:
            caps.update(("lagrange_fun", "c_integrate") if bound.code.has_engine else ("lagrange_fun",))
        return frozenset(caps)

    def offers(self, name):
        """Whether this evaluator offers the capability ``name`` (see :attr:`capabilities`);
        ``"outputs"``, ``"dalembert_fun"`` and ``"dae_fun"`` are decided without making the
        Lagrange program."""
        if name == "outputs":
            return True
        if name in ("dalembert_fun", "dae_fun"):
            return self._dalembert() is not None
        return name in self.capabilities

    def _dalembert(self):
        """The D'Alembert C call (:class:`mbcomp.codegen.engine.DAlembertProgram`) over the
        evaluation program and the current row mask, or None (Python backend, no compiler)."""
        if self.backend != "c":
            return None
        bound = self.bound or self._bound()
        rm = self.system.row_mask
        cached = getattr(self, "_dal", None)
        if cached is not None and cached[0] is bound and cached[1] is rm:
            return cached[2]
        from .engine import dalembert_program

        prog = dalembert_program(bound, self.system)
        self._dal = (bound, rm, prog)
        return prog

    def dae_program(self, form, gains=None):
        """The residual and Jacobian of a multiplier DAE form in one C call each
        (:class:`mbcomp.codegen.engine.DAEProgram`; ``form`` 1, 2, 3: Index1, GGL, Index3),
        or None (Python backend, no compiler); capability ``"dae_fun"``."""
        if self._dalembert() is None:
            return None
        from .engine import dae_program

        return dae_program(self.bound or self._bound(), self.system, form, gains)

    def dalembert_fun(self, t, y, dep, ind):
        """The D'Alembert right-hand side at ``y = [q, v]`` for the partition ``dep``/``ind``
        in one C call (:meth:`mbcomp.codegen.engine.DAlembertProgram.fun`): ``(status, dy,
        growth, cond)``, status 0 on success (see :data:`mbcomp.codegen.engine.MECH_STATUS`;
        1, a failed guard or a non-finite value, and 2, an exactly singular dependent block,
        are counted as fallbacks: the caller takes its Python path)."""
        r = self._dalembert().fun(t, y, dep, ind)
        if r[0] in (1, 2):
            self.stats["fallbacks"] += 1
        return r

    def _fun_bound(self):
        """The Lagrange program for the system's current row mask: traced at first need (the
        mask is set by consistent initialization), reused by ``with_params``."""
        rm = self.system.row_mask
        if self._fun is not None and self._fun[2] is rm:  # the same mask object: no key to make
            return self._fun[1]
        key = None if rm is None or rm.all() else rm.tobytes()
        if self._fun is not None and self._fun[0] == key:
            self._fun = (key, self._fun[1], rm)
            return self._fun[1]
        system, o = self.system, self.options
        code = self.funs.get(key)
        bound = None
        if code is not None and self.signature == code.signature:
            try:
                bound = Bound(code, system)
            except Retrace:
                code = None
        if bound is None:
            tr = trace(system, o["max_nodes"], program="fun")
            code = Code(tr, self.backend, o["cache_dir"]) if "fun" in tr.groups else None
            self.funs[key] = code
            if code is not None:
                bound = Bound(code, system, first=True)
                self.stats.update(n_ops_fun=code.n_ops_fun, fun_compile_time=code.compile_time,
                                  fun_state_guards=code.state_guards["fun"])
                if o["verify"]:
                    self._verify_fun(bound)
        self._fun = (key, bound, rm)
        return bound

    def integrator(self, alpha, beta, project=None):
        """The compiled engine (:class:`mbcomp.codegen.engine.Integrator`) stepping the Lagrange
        right-hand side with Baumgarte gains ``alpha``, ``beta`` (1/s) in C; None when this
        program has none (Python backend, drives, no Lagrange program). ``project``:
        ``(tol, accept)`` on ``|Phi|`` to project after every accepted step in C with the
        evaluation program; None when :func:`mbcomp.codegen.engine.coordinate_map` does not
        know how the coordinates move."""
        from .engine import Integrator, mech_of

        bound = self._fun_bound()
        if bound is None or not bound.code.has_engine:
            return None
        if project is None:
            return Integrator(bound, alpha, beta)
        evaluation = self.bound or self._bound()
        if evaluation.drive_comps or evaluation.code.inputs:
            # the evaluation program takes the drives' and inputs' values per call, set from
            # Python: inside the C loop the projection would use those of another time (a
            # driven Hooke shaft's outputs sat 0.2 rad off the loop, 1e9 tolerances)
            return None
        mech = mech_of(evaluation, self.system)
        if mech is None or not mech.moves:  # coordinates the C projection cannot move
            return None
        return Integrator(bound, alpha, beta, mech=mech, tol=project[0], accept=project[1])

    def lagrange_fun(self, t, y, alpha, beta):
        """``dy/dt`` of the Lagrange index-1 form (Baumgarte gains ``alpha``, ``beta`` in 1/s,
        zero for none) in one program call, or None when a guard fails (a singular matrix,
        a law's branch): the caller then uses the dense solve."""
        bound = self._fun_bound()
        if bound is None:
            return None
        try:
            return bound.run_fun(t, y, alpha, beta)
        except (Fallback, ArithmeticError, ValueError):
            self.stats["fallbacks"] += 1
            return None

    def structure_memo(self):
        """A dict shared by every system of this structure (the copies of ``with_params``, and
        with ``reuse`` every system the structure cache matched): for what the post-processing
        derives from the structure alone (the columns' units)."""
        return self.funs.setdefault("memo", {})

    def lagrange_bound(self):
        """The bound Lagrange program for the current row mask
        (:class:`mbcomp.codegen.compiler.Bound`), or None when there is none."""
        return self._fun_bound()

    def lagrange_thin(self, alpha, beta):
        """:meth:`lagrange_fun` for the current row mask and gains ``alpha``, ``beta`` (1/s) as
        one C call from Python (:func:`mbcomp.codegen.thin.thin_fun`: ``fun(t, y)`` -> ``dy/dt``,
        or None where it does not hold -- then :meth:`lagrange_fun` says why), or None when
        there is none (a Python program, per-call inputs, no extension on this machine)."""
        bound = self._fun_bound()
        if bound is None:
            return None
        from .thin import thin_fun

        return thin_fun(bound, alpha, beta, self.options["cache_dir"])

    def lagrange_jac(self, t, y, alpha, beta):
        """``d/dy`` of :meth:`lagrange_fun` (``(nq + nu, nq + nu)``) from the exact Jacobian
        program (:class:`mbcomp.codegen.jacobian.JacobianCode`, made at first need per row
        mask and reused by ``with_params``), or None when there is none or it does not hold at
        ``y`` (a failed guard, a non-finite entry): the caller then differences."""
        jac = self.lagrange_jacobian()
        if jac is None:
            return None
        J = jac(t, y, alpha, beta)
        if J is None:
            self.count_jac_fallback()
        return J

    def lagrange_jacobian(self):
        """The bound exact Jacobian program for the current row mask
        (:class:`mbcomp.codegen.jacobian.BoundJacobian`: ``jac(t, y, alpha, beta)`` -> matrix or
        None), or None when there is none; what :meth:`lagrange_jac` calls, for callers that
        keep it per row mask (one Python layer less per call)."""
        if self._fun_bound() is None:
            return None
        rm = self.system.row_mask
        cached = self.__dict__.get("_jac")
        if cached is None or cached[0] is not rm:
            key = ("jac", None if rm is None or rm.all() else rm.tobytes())
            o = self.options
            jac = bind_cached(self.funs, key, lambda: JacobianCode.build(self.system, self.backend, o["cache_dir"],
                                                                         o["max_nodes"]), self.system)
            cached = self._jac = (rm, jac)
        return cached[1]

    def count_jac_fallback(self):
        """Count a state where the exact Jacobian program did not hold (the stats'
        ``jac_fallbacks``)."""
        self.stats["jac_fallbacks"] = self.stats.get("jac_fallbacks", 0) + 1

    def dae_jacobian(self, form):
        """The exact Jacobian program of a multiplier DAE form bound to this system, or None
        (:func:`mbcomp.codegen.dae_jacobian.bound_program`; its code reused by ``with_params``)."""
        o = self.options
        return bound_program(self.system, self.funs, form, self.backend, o["cache_dir"], o["max_nodes"])

    def outputs_key(self, gains):
        """The output program's key among the structure's programs: the row mask now and
        whether there are Baumgarte ``gains``."""
        rm = self.system.row_mask
        return ("outputs", None if rm is None or rm.all() else rm.tobytes(), gains is not None)

    def prepare_outputs(self, n_points, gains):
        """Start making the output program a grid of ``n_points`` (at least
        :data:`OUTPUT_GRID_MIN`) will take, unless made, being made or impossible: traced now,
        compiled on a thread while the run integrates (:meth:`OutputProgram.start`); the one
        :meth:`output_grid` would make. A C backend only."""
        from .outputs import OutputProgram

        key = self.outputs_key(gains)
        if self.backend != "c" or n_points < OUTPUT_GRID_MIN or self.funs.get(key, False) is not False:
            return
        try:
            self.funs[key] = OutputProgram.start(self.system, self.backend, baumgarte=gains is not None,
                                                 cache_dir=self.options["cache_dir"], max_nodes=self.options["max_nodes"])
        except CodegenError:
            self.funs[key] = None

    def output_grid(self, t, Y, gains):
        """The columns at every output time in one call (:meth:`~mbcomp.codegen.outputs.OutputProgram.grid`:
        ``(names, values, quaternions, ok)``), or None without the program: fewer than :data:`OUTPUT_GRID_MIN`
        points (unless the structure's runs made it or paid that many numeric points), a law not traceable, a
        singular trace point. ``gains``: Baumgarte's (1/s) or None. Made per row mask and kind of gains."""
        from .outputs import OutputProgram, settled

        key = self.outputs_key(gains)
        prog = settled(self.funs, key)
        if len(t) < OUTPUT_GRID_MIN and not prog:  # a small grid takes the program only when made already
            seen = self.funs[("numeric outputs",) + key[1:]] = self.funs.get(("numeric outputs",) + key[1:], 0) + len(t)
            if seen <= OUTPUT_GRID_MIN:  # ... or once the structure's runs paid for it numerically
                return None
        if prog is not False and prog is not None and self.signature != prog.signature:
            prog = False
        for _ in range(2):
            if prog is False:
                try:
                    prog = OutputProgram.build(self.system, self.backend, baumgarte=gains is not None,
                                               cache_dir=self.options["cache_dir"], max_nodes=self.options["max_nodes"])
                except CodegenError:
                    prog = None
                self.funs[key] = prog
                if prog is not None:
                    self.stats.update(n_ops_outputs=prog.n_ops, outputs_compile_time=prog.compile_time)
            if prog is None:
                return None
            self.stats["n_ops_outputs"] = prog.n_ops
            try:
                return prog.grid(self.system, t, Y, gains)
            except Retrace:  # these parameter values change a decision baked into the program
                prog = False
        return None

    def _bound(self):
        if self.bound is None:
            code = self.funs.get("eval")  # made by a system of this structure meanwhile
            if code is not None:
                self._bind_eval(code)
            if self.bound is None:
                self._build()
        return self.bound

    # --- the evaluator interface ----------------------------------------------------------------
    def evaluate(self, t, q, u, masked=True):
        """Mass matrix, forces and constraints at ``(t, q, u)`` from the generated program (see
        :class:`CompiledEvaluation`); a failed guard falls back to the numeric evaluation. A
        lazy evaluator answers its first :data:`LAZY_EVALUATIONS` calls numerically."""
        system = self.system
        bound = self.bound
        if bound is None:
            if self.options["lazy"] and self.numeric_calls < LAZY_EVALUATIONS:
                self.numeric_calls += 1
                return system.evaluate_numeric(t, q, u, masked)
            bound = self._bound()
        if type(q) is not np.ndarray or type(u) is not np.ndarray:
            q, u = np.asarray(q), np.asarray(u)
        if q.dtype == object or u.dtype == object:  # traced by someone else (e.g. symbolic): numeric path
            return system.evaluate_numeric(t, q, u, masked)
        try:
            flat = bound.run(t, q, u)
            if not np.isfinite(flat).all():  # a domain error (0/0 in a law): the numeric path raises or agrees
                raise Fallback
        except (Fallback, ArithmeticError, ValueError):
            self.stats["fallbacks"] += 1
            return system.evaluate_numeric(t, q, u, masked)
        rm = system.row_mask
        mask = rm if masked and rm is not None and not rm.all() else None
        return CompiledEvaluation(system, t, q, u, flat, masked, bound.code.layout_out, mask)

    def evaluate_rows(self, t, q, u):
        """The loop-closure rows at ``(t, q, u)``, every row
        (:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_rows`): while a lazy evaluator
        answers numerically, the numeric rows alone (counted as the evaluation they stand
        for); else those of the unmasked :meth:`evaluate`."""
        if self.bound is None and self.options["lazy"] and self.numeric_calls < LAZY_EVALUATIONS:
            self.numeric_calls += 1
            return self.system.evaluate_rows_numeric(t, q, u)
        return Rows.of(self.evaluate(t, q, u, masked=False))

    def complete(self, rows, masked=True):
        """:meth:`evaluate` at the point of the numeric ``rows`` (:meth:`evaluate_rows`'s) from
        their jets: unmasked, their own evaluation completed (not counted again); masked,
        another evaluation (numeric and counted while lazy, else by the program)."""
        if masked and not (self.bound is None and self.options["lazy"] and self.numeric_calls < LAZY_EVALUATIONS):
            return self.evaluate(rows.t, rows.q, rows.u, masked)
        self.numeric_calls += bool(masked)
        return self.system.complete_numeric(rows, masked)

    def q_rate(self, q, u):
        """``dq/dt`` from the speeds (the program; ``u`` for angles; the joints' own while lazy)."""
        bound = self.bound
        if bound is None:
            if self.options["lazy"]:
                return self.system.q_rate_numeric(q, u)
            bound = self._bound()
        if bound.code.qrate_identity:
            return np.array(u, dtype=float)
        try:
            return bound.run_qrate(q, u)
        except (Fallback, ArithmeticError, ValueError):
            self.stats["fallbacks"] += 1
            return self.system.q_rate_numeric(q, u)

    def evaluate_by_program(self):
        """Evaluate by the program from the next call on, not after :data:`LAZY_EVALUATIONS` numeric ones."""
        self.options["lazy"] = False

    @property
    def source(self):
        """The generated source (Python: parameter program and programs; C: the C file)."""
        return self._bound().code.source


def compile_system(system, backend="python", *, cache_dir=None, verify=True, max_nodes=3_000_000, lazy=False,
                   reuse=False):
    """Trace an assembled system once and return it evaluated by the generated program.

    Parameters
    ----------
    system : MultibodySystem
        From :func:`mbcomp.assemble` (initialized or not; the row mask is applied at run time).
        Not changed.
    backend : {"python", "c", "auto"}
        ``"python"`` (default, no compiler), ``"c"`` (system C compiler, cached shared
        library; :class:`CodegenError` without a compiler) or ``"auto"`` (C if available).
    cache_dir : str, optional
        Where compiled libraries are cached (default ``$MBCOMP_CACHE`` or ``~/.cache/mbcomp``).
    verify : bool
        Compare the program with the numeric evaluation at one generic state after building.
    max_nodes : int
        Give up (``CodegenError``) when the expression graph exceeds this many nodes.
    lazy : bool
        Make the Lagrange right-hand side program now and the evaluation program only when
        evaluations are asked for often (:data:`LAZY_EVALUATIONS`; what ``simulate`` does).
    reuse : bool
        Take the programs of a system of the same structure compiled before in this process
        (:mod:`mbcomp.codegen.structure_key`: only parameter or start values differ) instead
        of tracing and printing them again; what ``simulate`` does. ``stats["structure_cache"]``
        says ``"hit"`` or ``"miss"``.

    Returns
    -------
    MultibodySystem
        The same topology, parameter values and row mask, with a :class:`ProgramEvaluator`:
        ``backend`` is ``"python"`` or ``"c"``, ``stats`` the build statistics, ``source`` the
        generated source; ``with_params`` reuses the program.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import compile_system
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=2.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> fast = compile_system(mbcomp.assemble(m))
    >>> fast.stats["n_ops"] > 0, fast.stats["n_params"]   # hinge axis z, rod y, bob mass, gravity y
    (True, 4)
    """
    if not isinstance(system, MultibodySystem):
        raise TypeError(f"compile_system needs an assembled system (mbcomp.assemble(model)), not {type(system).__name__}")
    return system.with_evaluator(lambda s: ProgramEvaluator(s, backend, cache_dir=cache_dir, verify=verify,
                                                            max_nodes=max_nodes, lazy=lazy, reuse=reuse))
