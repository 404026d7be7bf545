"""Explicit Runge-Kutta methods stepped in C: ``dopri5`` (Dormand-Prince 5(4)) and ``dop853``
(Dormand-Prince 8(5,3)), over the compiled engine when the problem has one.

The C runtime (:mod:`mbcomp.codegen.runtime`) integrates a whole stretch of the run -- up to
:attr:`CompiledRK.chunk` output times -- in one call, writing the states at the output times
from its dense output. To the driver each stretch is one "step" of the
:class:`~mbcomp.solvers.base.Stepper` interface: monitors check the stretch's end, the
outputs inside it are the C integrator's own, and a projection (if the formulation projects)
moves the state at the stretch's end. The stepper therefore declares ``needs_outputs``: the
run hands it its output times. A formulation that projects gives an engine that projects
after every accepted step in C (:meth:`mbcomp.formulations.LagrangeIndex1.compiled_integrator`),
continuing from the projected state with its derivative evaluated again, as scipy's one-step
methods do after the driver's projection; the outputs are the unprojected steps' dense
output, which the driver projects when it keeps them, as it does for scipy's methods. A
projection C cannot make (rows losing rank, Newton not converging) ends the stretch at that
step, unprojected: the driver's projection decides there and the rest of the stretch is
stepped in Python.

A problem offers the engine through ``compiled_integrator()`` (the Lagrange formulation on a
C program without drives, see :meth:`mbcomp.codegen.evaluator.ProgramEvaluator.integrator`).
Without one, or from the point where a guard of the program fails (a law's other branch, a
singular matrix) to the end of that stretch, scipy's method of the same order (``RK45``,
``DOP853``) steps the problem's Python ``fun`` one step at a time (a law raising there keeps
every output before it).

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from mbcomp.solvers.compiled_rk import CompiledRK
>>> decay = SimpleNamespace(fun=lambda t, y: -2.0 * y)        # no compiled engine: scipy's DOP853
>>> s = CompiledRK.make("dop853")(decay, 0.0, [1.0], 1.0, rtol=1e-10, atol=1e-12, t_eval=np.linspace(0, 1, 5))
>>> while s.status == "running":
...     _ = s.step()
>>> bool(abs(s.y[0] - np.exp(-2.0)) < 1e-9), s.stats["python_steps"] == s.stats["nsteps"]
(True, True)
"""
from __future__ import annotations

import numpy as np

from .base import StepFailure, Stepper
from .locate import time_tolerance

__all__ = ["CompiledRK", "COMPILED_STEPPERS", "STIFF_METHOD", "STIFF_ONE_STEP", "STIFF_STEPS", "HANDOVER_STATES"]


class CompiledRK(Stepper):
    """An explicit embedded Runge-Kutta method run by the C runtime (see the module notes).

    Parameters
    ----------
    problem : object with ``fun(t, y)`` and optionally ``compiled_integrator()``
    t0, y0, t_bound, rtol, atol, first_step, max_step
        As for :class:`~mbcomp.solvers.base.Stepper`.
    t_eval : ndarray
        The run's output times (s); each stretch ends at one of them.

    Attributes
    ----------
    stats : dict
        ``nsteps`` (accepted steps, in C and in Python), ``nreject`` (in C), ``nfev``,
        ``stretches`` (C calls), ``python_steps`` (steps by scipy's method),
        ``c_projections`` (projections made in C, after accepted steps).
    """

    adaptive = True
    one_step = True
    needs_outputs = True
    #: the order of the method (5: DOPRI5, 8: DOP853) and scipy's class of the same order
    order = 8
    scipy_method = "DOP853"
    #: output times per C call (the stretch the driver sees as one step)
    chunk = 16
    #: accepted steps held by stability after which the run goes on by a stiff method
    #: (:data:`STIFF_METHOD`); 0: never (``dop853``, ``dopri5``; ``auto`` switches)
    stiff_steps = 0
    #: the stepper (a name in :data:`mbcomp.solvers.STEPPERS`) the run hands over to from a step
    #: found stiff when the formulation does not project and the state has at most
    #: :data:`HANDOVER_STATES` entries (``auto``: ``"radau5"``, whose loop runs in C over the same
    #: program, :mod:`mbcomp.solvers.compiled_radau`); else scipy's :data:`STIFF_METHOD` steps on
    #: inside this stepper
    stiff_handover = None

    @classmethod
    def make(cls, name):
        return COMPILED_STEPPERS[name]

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf,
                 t_eval=None):
        super().__init__(problem, t0, y0, t_bound, rtol, atol, first_step, max_step)
        make = getattr(problem, "compiled_integrator", None)
        self.engine = make() if make is not None else None
        t_eval = np.asarray(t_eval if t_eval is not None else [t_bound], float)
        self.t_eval = t_eval[(t_eval > self.t) & (t_eval <= self.t_bound)]
        if not self.t_eval.size or self.t_eval[-1] < self.t_bound:
            self.t_eval = np.append(self.t_eval, self.t_bound)
        self.h = float(first_step or 0.0)
        self.stats.update(stretches=0, python_steps=0, c_projections=0)
        self._solver, self._python_until, self._dense = None, -np.inf, None
        self._python_method = self.scipy_method
        del self.stats["njev"], self.stats["nlu"]
        self._outs = (np.zeros(0), np.zeros((0, self.y.size)))
        self._y_old = self.y
        self._events, self._fresh_event, self._watching = None, -1, False
        #: ``(which, t)`` of the event that ended the last stretch (:meth:`watch`), else None
        self.hit = None
        #: whether the last step was a C stretch watching events (:meth:`watch`)
        self.watched_step = False
        self.stats["event_stretches"] = 0

    def watch(self, index, sign, at, direction, fresh=-1):
        """Watch event functions ``sign_k (y[index_k] - at_k)`` (falling through zero for
        ``direction_k`` -1, rising for +1, either for 0) inside the C loop: a stretch ends at
        the first one located on a step's dense output (``time_tolerance``), its outputs
        before it kept, its state the stepper's, :attr:`hit` = ``(k, t)``. ``fresh``: the
        event acted on at the start (found in the first step only when it returns through
        zero), or -1. Needs the engine (``self.engine`` not None); no events: the plain C
        stretches."""
        if self.engine is None:
            raise ValueError("events can be watched in C only over the compiled engine (compiled_integrator)")
        self._watching = True
        if len(index):
            self._events = self.engine.linear_events(index, sign, at, direction, time_tolerance(self.t_bound, self.rtol))
            self._fresh_event = int(fresh)

    def step_python_once(self):
        """Take the next step on the Python path (scipy's method of the same order): after an
        event located in C that does not act, the step goes on past it."""
        self._python_until = max(self._python_until, np.nextafter(self.t, np.inf))

    def _stretch(self):
        k = int(np.searchsorted(self.t_eval, self.t, side="right"))
        return self.t_eval[k: k + self.chunk]

    def _step(self):
        self.hit, self.watched_step = None, False
        if self.engine is None or self.t < self._python_until:
            return self._python_step()
        self._solver = None
        outs = self._stretch()
        fresh, self._fresh_event = self._fresh_event, -1
        ev = self._events
        r = self.engine.integrate(self.order, self.t, self.y, outs[-1], outs, self.rtol, self.atol, h0=self.h,
                                  hmax=self.max_step if np.isfinite(self.max_step) else 0.0,
                                  stiff_steps=self.stiff_steps, events=ev, fresh=fresh,
                                  event_tol=None if ev is None else time_tolerance(outs[-1], self.rtol))
        self.stats["stretches"] += 1
        self.stats["nfev"] += r.nfev
        if hasattr(self.prob, "nfev"):  # the engine's calls are the formulation's evaluations
            self.prob.nfev += r.nfev
        self.stats["nsteps"] += r.naccept
        self.stats["nreject"] += r.nreject
        self.h = r.h_last or self.h
        self.stats["c_projections"] += r.projections
        declined = r.status == 5 and r.declined != 0
        stiff = r.status == 7
        # the C call's own step cap (status 3, MAX_STEPS) is no failure: the stretch ends at its
        # last accepted step and the next call goes on (a 1e9 s run's 2e6 s output intervals)
        capped = r.status == 3 and r.t_last > self.t
        event = r.status == 8
        if r.status not in (0, 1, 8) and not declined and not capped and not stiff:
            self._reached = max(self._reached, float(r.t_last))
            raise StepFailure(f"the integrator {type(self).__name__} failed at t={r.t_last:g}: {r.message}")
        ts, Ys = list(outs[: len(r.Y)]), list(r.Y)
        if stiff:  # Hairer's test fired: the rest of the run by the stiff method, from this step
            projects = bool(getattr(self.prob, "projects", False))
            self.stats["stiff_from"] = float(r.t_last)
            if not projects and self.stiff_handover is not None and self.y.size <= HANDOVER_STATES:  # radau5 in C
                self.go_on_by = self.stiff_handover
                if r.t_last <= self.t:  # no step made: the next stepper goes on from here
                    return
            else:
                self._python_until, self._python_method = np.inf, STIFF_ONE_STEP if projects else STIFF_METHOD
        if r.status == 1 or declined or stiff:
            # a guard failed (a law's other branch, a singular matrix), or the C projection
            # could not be made (rows losing rank, Newton not converging: the driver's
            # projection decides at y_last, unprojected then): the stretch ends at the last
            # accepted step and the rest of it is stepped on the Python path
            if not stiff:
                self._python_until = outs[-1]
            if r.t_last <= self.t:
                return self._python_step()
            if ts and ts[-1] >= r.t_last:  # that step ended on an output time
                Ys[-1] = r.y_last
            else:
                ts.append(r.t_last)
                Ys.append(r.y_last)
        elif capped:
            ts, Ys = ts + [r.t_last], Ys + [r.y_last]
        elif event:  # the stretch ends at the event: its state is the stepper's
            self.hit = (r.which, float(r.t_event))
            self.stats["event_stretches"] += 1
            if ts and ts[-1] >= r.t_event:
                Ys[-1] = r.y_event
            else:
                ts, Ys = ts + [r.t_event], Ys + [r.y_event]
        self.watched_step = self._watching
        self._y_old, self.t_old = self.y, self.t
        self._outs = (np.array(ts), np.array(Ys))
        self.t, self.y = float(ts[-1]), np.array(Ys[-1])
        self._dense = None

    def _python_step(self):
        """One step of scipy's method of the same order over the problem's Python ``fun``
        (each step is the driver's: a law raising keeps every output before it)."""
        if self._solver is None:
            opts = dict(rtol=self.rtol, atol=self.atol, max_step=self.max_step)
            if self.h:
                opts["first_step"] = min(self.h, self.t_bound - self.t)
            import scipy.integrate as si  # only on the Python path (importing it costs ~0.5 s)

            method = self._python_method
            if method != self.scipy_method and getattr(self.prob, "jac", None) is not None:
                opts["jac"] = self.prob.jac  # the stiff method's Newton matrix: the exact program where one runs
            self._solver = getattr(si, method)(self.prob.fun, self.t, self.y, self.t_bound, **opts)
        sv = self._solver
        nfev = sv.nfev
        msg = sv.step()
        self.stats["nfev"] += sv.nfev - nfev
        self.stats["python_steps"] += 1
        if sv.status == "failed":
            raise StepFailure(f"the integrator {self._python_method} failed at t={sv.t:g}: {msg} "
                              "(step size collapsed: stiff or singular dynamics, or tolerances too tight)")
        self._y_old, self.t_old = self.y, self.t
        self.t, self.y = sv.t, sv.y
        self.h = getattr(sv, "h_abs", self.h)
        self._outs = (np.zeros(0), np.zeros((0, self.y.size)))
        self._dense = sv.dense_output()
        self.stats["nsteps"] += 1

    def reset_state(self, y):
        """Continue from the moved state ``y`` (a projection)."""
        self.y = np.array(y, dtype=float)
        if self._solver is not None:
            self._solver.y = self.y
            self._solver.f = self.prob.fun(self.t, self.y)

    def step_outputs(self):
        """The engine's own states at the output times of the last stretch (None after a
        step on the Python path)."""
        return self._outs if self._dense is None else None

    def dense_output(self):
        """``y(t)`` in the last stretch: the integrator's own output at the output times, a
        cubic Hermite interpolant between the stretch's ends elsewhere (for the monitors)."""
        if self._dense is not None:  # a step on the Python path: scipy's own dense output
            return self._dense
        ts, Ys = self._outs
        t0, t1, y0, y1 = self.t_old, self.t, self._y_old, self.y
        f0, f1 = None, None

        def at(tt):
            nonlocal f0, f1
            k = np.searchsorted(ts, tt)
            for j in (k - 1, k):
                if 0 <= j < len(ts) and abs(ts[j] - tt) <= 1e-12 * max(1.0, abs(tt)):
                    return Ys[j].copy()
            if f0 is None:
                f0, f1 = self.prob.fun(t0, y0), self.prob.fun(t1, y1)
            h = t1 - t0
            s = (tt - t0) / h
            h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
            return h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1

        return at


#: the method the ``auto`` stepper goes on with once the C integrator finds the problem stiff:
#: scipy's LSODA (BDF while stiff, Adams again when the stiffness passes), with the
#: formulation's ``jac`` (the exact Jacobian program where one runs). Measured on a 10-link
#: chain whose bobs slide on damped stiff springs (c = 1e6 N/m, d = 1e5 N s/m, 1 s, rtol 1e-6):
#: dop853 651,427 evaluations, 0.49 s; auto 2,759, 0.086 s; LSODA alone 0.070 s
STIFF_METHOD = "LSODA"
#: ... and where the formulation projects after every step: LSODA's history lives in Fortran,
#: where a projected state would not reach it; scipy's Radau is one-step (2x LSODA's time
#: on the chain above, 40x more accurate)
STIFF_ONE_STEP = "Radau"
#: states at most for which ``auto`` hands a stiff run to radau5 (its loop in C:
#: :attr:`CompiledRK.stiff_handover`) rather than going on by :data:`STIFF_METHOD`: radau5 factors
#: a real and a complex matrix of the state's size, LSODA's BDF a real one, less often. Measured
#: on bench/peers/stiff_chain.py (1 s, rtol 1e-8; 4 states a link): 2 links 6.6 ms against 25
#: ms by LSODA, 5 links 35 against 59 ms, 10 links 78 against 57 ms, 20 links 390 against 113 ms
HANDOVER_STATES = 24
#: Hairer's count (dop853's NSTIFF test: 15 accepted steps with ``|h lambda|`` above the
#: stability limit, fewer than 6 below it in between)
STIFF_STEPS = 15


def _declare(name, order, scipy_method, stiff_steps=0, stiff_handover=None):
    doc = (f"``{name}``: {'DOP853' if order == 8 else 'DOPRI5'} in C over the compiled engine (scipy's "
           f"``{scipy_method}`` without one)"
           + (f"; where the C integrator finds the problem stiff (Hairer's test, {stiff_steps} steps held by "
              f"stability) the run goes on from that step (the stats' ``stiff_from``) by "
              + (f"``{stiff_handover}`` (its loop in C) for a state of at most {HANDOVER_STATES} entries, else "
                 if stiff_handover else "") + f"``{STIFF_METHOD}`` with the exact Jacobian" if stiff_steps else "")
           + "; see :class:`CompiledRK`.")
    return type(name, (CompiledRK,), dict(order=order, scipy_method=scipy_method, stiff_steps=stiff_steps,
                                          stiff_handover=stiff_handover, __doc__=doc, __module__=__name__))


#: name -> stepper class
COMPILED_STEPPERS = {"auto": _declare("auto", 8, "DOP853", STIFF_STEPS, "radau5"), "dop853": _declare("dop853", 8, "DOP853"),
                     "dopri5": _declare("dopri5", 5, "RK45")}
