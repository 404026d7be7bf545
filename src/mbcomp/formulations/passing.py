"""The Lagrange form passing singular positions in C: the runtime's ``mbrt_pass_integrate``
(``codegen/runtime/mbrt_pass.h``) over a model's Lagrange and evaluation programs.

:class:`PassingEngine` is what :meth:`mbcomp.formulations.LagrangeIndex1.compiled_integrator`
gives a run with ``singular="pass"``: one C call steps a stretch of outputs by DOP853 (or
DOPRI5) through the singular positions. Where the Lagrange program's guard fails (the rows
losing rank) the C right-hand side is the range-space solve of
:func:`mbcomp.assembly.kkt.solve_kkt` with ``pass_rank``; the local minima of
``log det(C_k C_k^T)`` of the kept rows (a singular position is a pole of it) are located on
the integrator's own continuous extension and logged with their states, and the integration
goes on without a restart next to them (the step that held one is taken again, whole, from
its start). The run's rank monitor (:class:`mbcomp.simulation.monitors.ConstraintRank`)
judges the logged minima (:func:`engine_of`): those below its ``SIGMA_MIN`` are the
passages.

Examples
--------
>>> from mbcomp.formulations.passing import PassingEngine
>>> PassingEngine.DELTA, PassingEngine.CAP
(1e-07, 1024)
"""
from __future__ import annotations

import ctypes
import weakref
from types import SimpleNamespace

import numpy as np

__all__ = ["PassingEngine", "MbrtPass", "engine_of"]

_P = ctypes.c_void_p


class MbrtPass(ctypes.Structure):
    """The runtime's ``mbrt_pass`` (``codegen/runtime/mbrt_pass.h``) as ctypes lays it out:
    the programs and buffers a :class:`PassingEngine` hands its C loop, and the counters the loop
    writes (times in s).

    Examples
    --------
    >>> s = MbrtPass(pass_rank=1e-8, delta=1e-7)
    >>> s.pass_rank, s.count, s.nrange
    (1e-08, 0, 0)
    """

    _fields_ = ([(n, _P) for n in ("fun", "d", "h", "p", "w", "mech", "mech_work")]
                + [("pass_rank", ctypes.c_double), ("project", ctypes.c_int), ("proj_tol", ctypes.c_double),
                   ("proj_accept", ctypes.c_double), ("proj_iter", ctypes.c_int), ("delta", ctypes.c_double),
                   ("cap", ctypes.c_int), ("log_t", _P), ("log_y", _P), ("count", ctypes.c_int), ("work", _P),
                   ("y_last", _P), ("t_last", ctypes.c_double), ("h_last", ctypes.c_double)]
                + [(n, ctypes.c_long) for n in ("nrange", "nproj", "nskipped", "nevents", "nretaken")]
                + [("y_from", _P), ("t_from", ctypes.c_double), ("t_min", ctypes.c_double),
                   ("nrollbacks", ctypes.c_long), ("nredone", ctypes.c_long),
                   ("nrefined", ctypes.c_long), ("nredo_failed", ctypes.c_long)]
                + [(n, ctypes.c_double) for n in ("t_seen", "t_stop", "t_back", "h_back", "t_rolled", "t_before",
                                                   "t_after")]
                + [("nrange_step", ctypes.c_long), ("collapse", ctypes.c_int), ("redo", ctypes.c_int),
                   ("rolled_here", ctypes.c_int), ("split", ctypes.c_int), ("hcap", ctypes.c_double),
                   ("nsplits", ctypes.c_long), ("nhalved", ctypes.c_long)]
                + [(n, ctypes.c_double) for n in ("g_start", "g_end", "t_hidden")]
                + [("hidden", ctypes.c_int), ("hidden_here", ctypes.c_int)])


#: system -> its PassingEngine (weakly: the log lives as long as the run's system)
_ENGINES = weakref.WeakKeyDictionary()


def engine_of(system):
    """The :class:`PassingEngine` stepping ``system``'s run, or None. Its :attr:`~PassingEngine.minima`
    are the ``(t, [q, u])`` located so far, :attr:`~PassingEngine.reached` the time its C loop
    reached (s; -inf before its first call), :attr:`~PassingEngine.counts` its counters."""
    return _ENGINES.get(system)


class PassingEngine:
    """DOP853/DOPRI5 in C through singular positions (see the module notes), with the interface
    of :class:`mbcomp.codegen.engine.Integrator` the compiled steppers use.

    Parameters
    ----------
    integrator : mbcomp.codegen.engine.Integrator
        The engine over the Lagrange program (Baumgarte gains as stabilized) with the
        evaluation program's ``mech`` (projecting, or not: ``project``).
    system : MultibodySystem
        The run's system (its log is found by :func:`located_minima`).
    pass_rank : float
        :attr:`mbcomp.formulations.LagrangeIndex1.PASS_RANK`.
    project : bool
        Project ``[q, u]`` onto the rows after every accepted step (the integrator's
        tolerances).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen import c_compiler
    >>> nfb = mbcomp.load_model_file("models/n_four_bar.py")
    >>> if c_compiler():  # two parallelograms through their flat positions at 0.7144 and 1.2282 s
    ...     r = mbcomp.simulate(nfb.build(N=2), **{**nfb.SIMULATION, "t_end": 1.5})
    ...     print(r.stats["python_steps"], [round(p["t"], 4) for p in r.stats["singular_passages"]])
    ... else:
    ...     print(0, [0.7144, 1.2282])
    0 [0.7144, 1.2282]
    """

    #: the event function's central-difference step (s)
    DELTA = 1e-7
    #: minima logged per C call at most (then the Python path goes on from the last step), and
    #: outputs inside one step
    CAP = 1024

    def __init__(self, integrator, system, pass_rank, project):
        mech = integrator.mech
        self.inner, self.mech = integrator, mech
        code = integrator.bound.code
        dll = integrator.part_library("pass")  # built apart at a machine's first passing run
        self.n = integrator.n
        self.fn = dll.mbrt_pass_integrate
        self.fn.restype = ctypes.c_int
        self.fn.argtypes = [_P, ctypes.c_int, ctypes.c_double, _P, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                            _P, ctypes.c_double, ctypes.c_double, ctypes.c_long, _P, ctypes.c_int, _P, _P, _P, _P]
        dll.mbrt_pass_work_size.restype = ctypes.c_size_t
        dll.mbrt_pass_work_size.argtypes = [_P, ctypes.c_int]
        self.work = np.zeros(int(dll.mbrt_pass_work_size(mech.ptr, self.CAP)))
        self.log_t, self.log_y = np.zeros(self.CAP), np.zeros((self.CAP, self.n))
        self.y_last, self.y_from = np.zeros(self.n), np.zeros(self.n)
        self._going_on = None  # (time the last call's outputs ended, its last step's start, that step)
        bound = integrator.bound
        ctx = integrator.ctx
        fun = ctypes.cast(code.dll.mbcomp_fun, _P).value
        self.struct = MbrtPass(fun=fun, d=ctx.d, h=ctx.h, p=ctx.p, w=ctx.w, mech=mech.ptr, mech_work=mech.work.ctypes.data,
                            pass_rank=float(pass_rank), project=int(bool(project)), proj_tol=ctx.proj_tol,
                            proj_accept=ctx.proj_accept, proj_iter=ctx.proj_iter, delta=self.DELTA, cap=self.CAP,
                            log_t=self.log_t.ctypes.data, log_y=self.log_y.ctypes.data, work=self.work.ctypes.data,
                            y_last=self.y_last.ctypes.data, y_from=self.y_from.ctypes.data, t_min=-np.inf, t_rolled=-np.inf,
                            t_hidden=-np.inf)
        self._keep = bound
        self.minima, self.reached = [], -np.inf
        self.counts = dict(range_evaluations=0, skipped_projections=0, event_evaluations=0, retaken_steps=0,
                           collapse_retries=0, outputs_integrated_again=0, minima_located_again=0,
                           integrated_again_failed=0, steps_split=0, steps_halved=0)
        self._rk_work = {}
        _ENGINES[system] = self

    @property
    def projects(self):
        """Whether the C loop projects after every accepted step."""
        return bool(self.struct.project)

    def linear_events(self, index, sign, at, direction, tol):
        """Events of the hybrid layer are not watched here: :meth:`integrate` with ``events``
        hands the stretch to the Python path."""
        return self.inner.linear_events(index, sign, at, direction, tol)

    def range_rate(self, t, y):
        """``dy/dt`` at ``(t, y = [q, u])`` (s) by the C loop's range-space solve over the evaluation
        program (``mbrt_pass_rhs``: what it uses where the Lagrange program's guard fails), or
        None where the evaluation fails or ``M`` is not positive definite."""
        fn = self.inner.part_library("pass").mbrt_pass_rhs
        if fn.argtypes is None:
            fn.argtypes, fn.restype = [_P, ctypes.c_double, _P, _P], ctypes.c_int
        y = np.ascontiguousarray(y, float)
        dy = np.zeros(self.n)
        return dy if fn(ctypes.addressof(self.struct), float(t), y.ctypes.data, dy.ctypes.data) == 0 else None

    def _work(self, order):
        w = self._rk_work.get(order)
        if w is None:
            dll = self.inner.bound.code.dll
            w = self._rk_work[order] = np.zeros(int(dll.mbcomp_work_size(order, self.n)))
        return w

    def integrate(self, order, t0, y0, t_end, t_out, rtol, atol, h0=0.0, hmax=0.0, max_steps=0, stiff_steps=0,
                  events=None, fresh=-1, event_tol=None):
        """As :meth:`mbcomp.codegen.engine.Integrator.integrate` (``stiff_steps`` is not
        tested here), the minima located appended to :attr:`minima`. With ``events`` (a hybrid
        run's declared rows) nothing is stepped: status 1 at ``t0`` hands the stretch to the
        Python path."""
        y0 = np.ascontiguousarray(y0, float)
        t_out = np.ascontiguousarray(t_out, float)
        if events is not None:
            return SimpleNamespace(status=1, message="events are watched on the Python path", Y=np.zeros((0, self.n)),
                                   t_last=float(t0), y_last=y0.copy(), h_last=float(h0), nfev=0, naccept=0,
                                   nreject=0, projections=0, declined=0, which=-1, t_event=float("nan"),
                                   y_event=None)
        atol_v = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, float), (self.n,)))
        Y = np.zeros((len(t_out), self.n))
        nw, st, S = ctypes.c_int(0), self.inner.new_stats(), self.struct
        going_on = self._going_on
        if going_on is not None and going_on[0] == t0 and going_on[1] <= t0:  # the step across t0, taken again
            t_start, y_start, h0 = going_on[1], going_on[2], going_on[3]
        else:
            t_start, y_start = float(t0), y0
        horizon = t_end + max(t_end - t0, 0.0)  # the last step is not cut short to land on t_end
        status = self.fn(ctypes.addressof(S), int(order), float(t_start), y_start.ctypes.data, float(t_end),
                         float(horizon), float(rtol), atol_v.ctypes.data, float(h0), float(hmax), int(max_steps),
                         t_out.ctypes.data, len(t_out), Y.ctypes.data, ctypes.addressof(nw),
                         self._work(order).ctypes.data, ctypes.addressof(st))
        self._going_on = ((float(t_end), float(S.t_from), self.y_from.copy(), float(S.h_last))
                          if status == 0 and S.t_last > t_end else None)
        k = S.count
        self.minima += [(float(self.log_t[j]), self.log_y[j].copy()) for j in range(k)]
        for key, field in (("range_evaluations", "nrange"), ("skipped_projections", "nskipped"),
                           ("event_evaluations", "nevents"), ("retaken_steps", "nretaken"),
                           ("collapse_retries", "nrollbacks"), ("outputs_integrated_again", "nredone"),
                           ("minima_located_again", "nrefined"), ("integrated_again_failed", "nredo_failed"),
                           ("steps_split", "nsplits"), ("steps_halved", "nhalved")):
            self.counts[key] += int(getattr(S, field))
        status = 1 if status == 5 else int(status)  # the log full: the Python path goes on from t_last
        self.reached = max(self.reached, float(S.t_last))
        return SimpleNamespace(status=status, message=st.message.decode(errors="replace"), Y=Y[: nw.value],
                               t_last=float(S.t_last), y_last=self.y_last.copy(), h_last=float(S.h_last),
                               nfev=int(st.nfev), naccept=int(st.naccept), nreject=int(st.nreject),
                               projections=int(S.nproj), declined=0, which=-1, t_event=float("nan"), y_event=None)
