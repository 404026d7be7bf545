"""radau5 on the index-1 ODE with its whole stepping loop in C (``mbrt_radau5``, issue 32 item 4).

The runtime's RADAU5 (:mod:`mbcomp.codegen.runtime`, ``mbrt_radau5.c``) runs the algorithm of
:class:`mbcomp.solvers.radau.Radau5` with ``E = I`` -- simplified Newton on the real and
complex systems, equilibrated LU, the filtered error estimate, Gustafsson's controller,
RADAU5's Jacobian and LU reuse, the collocation polynomial at the output times -- over the
model's generated right-hand side program (``mbcomp_fun``) and, where the system has one, its
exact Jacobian program (:mod:`mbcomp.codegen.jacobian`; else forward differences in C). Both
programs are reached through function pointers (``mbrt_prog_ode``), so no Python runs inside
a stretch.

As :class:`~mbcomp.solvers.compiled_rk.CompiledRK` does, a stretch of output times (16, then
twice as many each call, up to 1024) is one
C call and one "step" of the :class:`~mbcomp.solvers.base.Stepper` interface; the stretches
resume each other (``resume``: the Jacobian, the factors, the predictor and the controller's
memory stay in the work buffer), so a run takes the steps of one call whatever its stretches.

Where there is no C engine (the numeric or Python backend, drives, no compiler, a formulation
that projects after every step) the stepper is the Python one: every step in
:meth:`Radau5._step <mbcomp.solvers.radau.Radau5>`. Where the program's guard fails inside a
stretch (a law's other branch), the stretch ends at its last accepted step and the Python
stepper takes the rest of the run from there.

The C and the Python stepper run the same algorithm with the same coefficients; their linear
algebra differs (LAPACK's getrf there, the runtime's own LU here), so they agree to round-off
in each step, and to the tolerance over a run (``tests/solvers/test_compiled_radau.py``).

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from mbcomp.solvers.radau import Radau5
>>> decay = SimpleNamespace(n=1, fun=lambda t, y: -50.0 * y, jac=lambda t, y: np.array([[-50.0]]))
>>> s = Radau5.on_ode()(decay, 0.0, [1.0], 0.1, rtol=1e-8, atol=1e-12, t_eval=np.linspace(0, 0.1, 3))
>>> while s.status == "running":      # no compiled engine: the Python stepper
...     _ = s.step()
>>> bool(abs(s.y[0] - np.exp(-5.0)) < 1e-9), s.stats["stretches"]
(True, 0)
"""
from __future__ import annotations

import ctypes

import numpy as np

from .compiled_rk import CompiledRK

__all__ = ["CompiledRadau5", "RadauEngine", "RadauInfo", "STATUS"]

#: ``mbrt_radau5``'s statuses (``mbrt.h``)
STATUS = {0: "reached t_end", 1: "a guard of the program failed", 2: "step size collapsed", 3: "too many steps",
          4: "non-finite values", 6: "bad argument", 20: "singular iteration matrix"}


class RadauInfo(ctypes.Structure):
    """``mbrt_radau5_info`` (``mbrt.h``): Jacobians (of them differenced), LU factorizations,
    Newton iterations and failures, singular matrices met, the next step (s)."""

    _fields_ = [("njev", ctypes.c_long), ("ndiff", ctypes.c_long), ("nlu", ctypes.c_long),
                ("nnewton", ctypes.c_long), ("nfail_newton", ctypes.c_long), ("nsingular", ctypes.c_long),
                ("h_next", ctypes.c_double)]


_PF = ctypes.c_void_p


class _ProgODE(ctypes.Structure):  # mbrt_prog_ode
    _fields_ = [("fun", _PF), ("d", _PF), ("h", _PF), ("p", _PF), ("w", _PF),
                ("jac", _PF), ("jd", _PF), ("jh", _PF), ("jp", _PF), ("jw", _PF), ("nq", ctypes.c_int)]


def _signature(dll):
    vp, i, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    fn = dll.mbrt_radau5
    if fn.argtypes is None:
        fn.argtypes = [vp, vp, vp, i, d, vp, d, d, d, vp, d, d, ctypes.c_long, vp, i, vp, vp, vp, vp, i, vp, vp, vp]
        fn.restype = i
        dll.mbrt_radau5_dense.argtypes = [vp, i, d, vp]
        dll.mbrt_radau5_dense.restype = None
        for name in ("mbrt_radau5_work_size", "mbrt_radau5_iwork_size"):
            getattr(dll, name).argtypes = [i]
            getattr(dll, name).restype = ctypes.c_size_t
    return fn


class RadauEngine:
    """``mbrt_radau5`` over a model's C right-hand side program and its Jacobian program.

    Parameters
    ----------
    integrator : mbcomp.codegen.engine.Integrator
        The compiled engine of the Lagrange right-hand side (its program ``bound``, gains
        ``d``; ``part_library("radau")``: the runtime's RADAU5, a library of its own).
    jacobian : mbcomp.codegen.jacobian.BoundJacobian or None
        The exact Jacobian program (C backend) of the same system; None: forward differences
        in C.

    Raises
    ------
    mbcomp.codegen.graph.CodegenError
        When RADAU5 cannot be compiled or loaded.
    """

    def __init__(self, integrator, jacobian=None):
        bound = integrator.bound
        dll = integrator.part_library("radau")  # RADAU5 apart, built at its first use; the program by pointers
        self.fn = _signature(dll)
        self.dense_fn = dll.mbrt_radau5_dense
        self.n = n = bound.nq + bound.nu
        self.gains = np.array(integrator.d, float)  # alpha, beta: kept alive here
        jfun = None
        if jacobian is not None and jacobian.code.backend == "c":
            jacobian.dbuf[:2] = self.gains
            jfun = ctypes.cast(jacobian.code.loaded.cfun, ctypes.c_void_p).value
        self.jacobian = jacobian if jfun else None
        a = jacobian.addresses if jfun else (None,) * 7
        self.ctx = _ProgODE(ctypes.cast(bound.code.dll.mbcomp_fun, ctypes.c_void_p).value, self.gains.ctypes.data,
                            bound.hbuf.ctypes.data, bound.pbuf.ctypes.data, bound.wbuf.ctypes.data,
                            jfun, a[2], a[3], a[4], a[5], bound.nq)
        self._keep = bound  # the buffers the context points into
        self.f = ctypes.cast(dll.mbrt_prog_ode_rhs, ctypes.c_void_p).value
        self.j = ctypes.cast(dll.mbrt_prog_ode_jac, ctypes.c_void_p).value
        self.work = np.zeros(int(dll.mbrt_radau5_work_size(n)))
        self.iwork = np.zeros(int(dll.mbrt_radau5_iwork_size(n)), dtype=np.intc)
        self.y_last = np.zeros(n)
        self.stats, self.info = integrator.new_stats(), RadauInfo()

    def integrate(self, t0, y0, t_end, t_out, rtol, atol, h0=0.0, hmax=0.0, max_steps=0, resume=False,
                  t_pause=0.0):
        """One call of ``mbrt_radau5`` from ``(t0, y0)`` to ``t_end``, paused after the first
        step ending at or past ``t_pause`` (status 21) when that lies inside; ``resume``:
        continue the last call (which ended at ``t0``). Returns ``(status, message, Y (rows
        at the t_out reached), t_last, y_last, stats, info)``."""
        y0 = np.ascontiguousarray(y0, float)
        t_out = np.ascontiguousarray(t_out, float)
        atol_v = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, float), (self.n,)))
        Y = np.zeros((len(t_out), self.n))
        nw = ctypes.c_int(0)
        st, info = self.stats, self.info
        status = self.fn(self.f, self.j, ctypes.byref(self.ctx), self.n, float(t0), y0.ctypes.data, float(t_end),
                         float(t_pause), float(rtol), atol_v.ctypes.data, float(h0), float(hmax), int(max_steps), t_out.ctypes.data,
                         len(t_out), Y.ctypes.data, ctypes.byref(nw), self.work.ctypes.data, self.iwork.ctypes.data,
                         int(bool(resume)), self.y_last.ctypes.data, ctypes.byref(st), ctypes.byref(info))
        return (int(status), st.message.decode(errors="replace"), Y[: nw.value], float(st.t), self.y_last.copy(),
                st, info)

    def dense(self, t):
        """The last accepted step's collocation polynomial at ``t`` (s), (n,)."""
        y = np.zeros(self.n)
        self.dense_fn(self.work.ctypes.data, self.n, float(t), y.ctypes.data)
        return y


def engine_of(problem):
    """The :class:`RadauEngine` of an index-1 ODE problem (a Lagrange formulation over a C
    program; the Baumgarte gains as the engine's), or None: no compiled engine, or a
    formulation that projects after every step (the Python stepper then)."""
    make = getattr(problem, "compiled_integrator", None)
    if make is None or getattr(problem, "projects", False):
        return None
    integrator = make()
    if integrator is None or getattr(integrator, "projects", False):
        return None
    system = getattr(problem, "system", None)
    evaluator = getattr(system, "evaluator", None)
    jacobian = evaluator.lagrange_jacobian() if hasattr(evaluator, "lagrange_jacobian") else None
    try:
        return RadauEngine(integrator, jacobian)
    except ValueError:
        return None


class CompiledRadau5(CompiledRK):
    """The C stretches of radau5 over the index-1 ODE (see the module notes): a mixin before
    :class:`~mbcomp.solvers.radau.Radau5` in the ODE variant ``Radau5.on_ode()``, whose steps
    it takes where there is no C engine, with events and when sensitivities are stepped.

    It derives from :class:`~mbcomp.solvers.compiled_rk.CompiledRK` because that is how the
    hybrid layer knows a C stretch integrator (:func:`mbcomp.hybrid.steppers.stepwise`,
    ``watching``): there ``engine`` is set to None or :meth:`watch` is called, and both make
    this stepper step in Python, each step's collocation polynomial there to locate events
    on. Every method of ``CompiledRK`` is overridden here; ``super(CompiledRK, self)``
    reaches the Radau5 methods behind it in the method resolution order.

    Parameters
    ----------
    problem, t0, y0, t_bound, rtol, atol, first_step, max_step
        As for :class:`~mbcomp.solvers.radau.Radau5` (an ODE: every variable differential).
    t_eval : ndarray, optional
        The run's output times (s); each C stretch ends at one of them.

    Attributes
    ----------
    stats : dict
        Radau5's counters (``nsteps``, ``nreject``, ``nfev``, ``njev``, ``nlu``, ``nnewton``,
        ``nfail_newton``, ``nfail_singular``) summed over C and Python, and ``stretches`` (C
        calls), ``python_steps``, ``jac_differenced`` (Jacobians differenced in C),
        ``handovers`` (1 once the C loop handed the run to Python: :attr:`handover` says why).

    Examples
    --------
    >>> from mbcomp.solvers.compiled_radau import CompiledRadau5
    >>> from mbcomp.solvers.radau import Radau5
    >>> ode = Radau5.on_ode()
    >>> issubclass(ode, CompiledRadau5), ode.needs_outputs, ode.problem, ode.implicit
    (True, True, 'ode', True)
    """

    needs_outputs = True
    chunk = 16
    chunk_max = 1024

    adaptive = True
    one_step = True
    stiff_steps = 0

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf,
                 t_eval=None):
        super(CompiledRK, self).__init__(problem, t0, y0, t_bound, rtol=rtol, atol=atol, first_step=first_step,
                             max_step=max_step)
        self.hit, self.watched_step = None, False
        rt = np.unique(self.rtol)
        self.engine = engine_of(problem) if rt.size == 1 and rt[0] > 0 else None
        t_eval = np.asarray(t_eval if t_eval is not None else [t_bound], float)
        self.t_eval = t_eval[(t_eval > self.t) & (t_eval <= self.t_bound)]
        if not self.t_eval.size or self.t_eval[-1] < self.t_bound:
            self.t_eval = np.append(self.t_eval, self.t_bound)
        self.stats.update(stretches=0, python_steps=0, jac_differenced=0, handovers=0)
        #: why the C loop handed the run to the Python stepper (its message), or None
        self.handover = None
        self._resume = False
        self._outs = None
        self._y_old = self.y

    def watch(self, index, sign, at, direction, fresh=-1):
        """Events are located on each Python step's collocation polynomial: no C stretches
        from here on (the arguments, :meth:`CompiledRK.watch`'s, are not needed)."""
        self.engine = None

    def step_python_once(self):
        """Steps are in Python once events are watched (:meth:`watch`): nothing to switch."""

    def _step(self):
        if self.engine is None:
            return self._python_step()
        k = int(np.searchsorted(self.t_eval, self.t, side="right"))
        outs = self.t_eval[k: k + min(self.chunk_max, self.chunk << min(self.stats["stretches"], 30))]
        hmax = self.max_step if np.isfinite(self.max_step) else 0.0
        # to the run's end, paused after the step that passes the stretch's last output: the
        # steps of one call whatever the stretches (the steps do not land on stretch ends)
        status, msg, Y, t_last, y_last, st, info = self.engine.integrate(
            self.t, self.y, self.t_bound, outs, float(self.rtol[0]), self.atol, h0=self.h or 0.0, hmax=hmax,
            resume=self._resume, t_pause=outs[-1] if outs[-1] < self.t_bound else 0.0)
        self._count(st, info)
        if status == 6:
            raise ValueError(f"radau5 (C): {msg}")
        ts, Ys = list(outs[: len(Y)]), list(Y)
        capped = status == 3 and t_last > self.t  # the call's step cap: the next call resumes
        if status not in (0, 21) and not capped:
            # a guard failed (status 1: a law's other branch), or the step failed (collapsed, not
            # finite, singular, capped): the rest of the run by the Python stepper from the last
            # accepted step -- it decides there, and a failure is reported as its own
            self.engine, self.J, self.lu, self._dense, self.f = None, None, None, None, None
            self.stats["handovers"] += 1
            self.handover = msg
            self.h = info.h_next if status == 1 and info.h_next > 0 else None  # a collapsed h: start afresh
            if t_last <= self.t:
                return self._python_step()
        else:
            self.h = info.h_next or self.h
            # outputs past the stretch inside its last step: that step's collocation polynomial
            for tk in self.t_eval[k + len(outs): int(np.searchsorted(self.t_eval, t_last, side="right"))]:
                ts.append(tk)
                Ys.append(self.engine.dense(tk))
        if not ts or ts[-1] < t_last:
            ts.append(t_last)
            Ys.append(y_last)
        self._resume = status in (0, 21) or capped
        self._y_old, self.t_old = self.y, self.t
        self._outs = (np.array(ts), np.array(Ys))
        self.t, self.y = t_last, y_last
        self.first = False

    def _python_step(self):
        self._outs = None
        self.stats["python_steps"] += 1
        return super(CompiledRK, self)._step()

    def _count(self, st, info):
        s = self.stats
        s["stretches"] += 1
        s["nsteps"] += st.naccept
        s["nreject"] += st.nreject
        s["nfev"] += st.nfev
        if hasattr(self.prob, "nfev"):  # the engine's calls are the formulation's evaluations
            self.prob.nfev += st.nfev
        s["njev"] += info.njev
        s["nlu"] += info.nlu
        s["nnewton"] += info.nnewton
        s["nfail_newton"] += info.nfail_newton
        s["nfail_singular"] += info.nsingular
        s["jac_differenced"] += info.ndiff

    def reset_state(self, y):
        """Continue from the moved state ``y``: the next C call takes it as moved (its
        derivative again, the rest kept); on the Python path as :class:`Radau5`."""
        if self.engine is None:
            return super(CompiledRK, self).reset_state(y)
        self.y = np.array(y, dtype=float)

    def step_outputs(self):
        """The C integrator's states at the output times of the last stretch (None after a
        Python step)."""
        return self._outs

    def dense_output(self):
        """``y(t)`` in the last step: the Python stepper's collocation polynomial after a
        Python step; after a C stretch the integrator's own outputs at the output times and a
        cubic Hermite interpolant between the stretch's ends elsewhere (for the monitors)."""
        if self._outs is None:
            return super(CompiledRK, self).dense_output()
        ts, Ys = self._outs
        t0, t1, y0, y1 = self.t_old, self.t, self._y_old, self.y
        fun, cache = self.prob.fun, []

        def at(tt):
            k = np.searchsorted(ts, tt)
            for j in (k - 1, k):
                if 0 <= j < len(ts) and abs(ts[j] - tt) <= 1e-12 * max(1.0, abs(tt)):
                    return Ys[j].copy()
            if not cache:
                cache.extend((fun(t0, y0), fun(t1, y1)))
            h = t1 - t0
            s = (tt - t0) / h
            h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
            return h00 * y0 + h10 * h * cache[0] + h01 * y1 + h11 * h * cache[1]

        return at
