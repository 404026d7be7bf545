"""scipy's ODE integrators (``RK23, RK45, DOP853, Radau, BDF, LSODA``) as mbcomp steppers.

Each :class:`ScipyStepper` subclass wraps one ``scipy.integrate.OdeSolver`` behind the
:class:`~mbcomp.solvers.base.Stepper` interface, so the driver steps them exactly like
mbcomp's own DAE solvers. They step ODEs ``dy/dt = fun(t, y)`` (``problem = "ode"``):
the index-1 Lagrange form and D'Alembert's form.

Moving the state after a step (the driver's projection, :meth:`ScipyStepper.reset_state`)
depends on the method's memory, which each class declares in ``one_step``:

* one-step methods (``RK23, RK45, DOP853, Radau``) continue from the moved state; their
  stored derivative ``f = fun(t, y)`` (first-same-as-last, Radau's predictor) is refreshed;
* multistep methods (``BDF, LSODA``) keep a history of past steps that cannot be moved: they
  are restarted from the moved state when it differs from theirs by more than the tolerance
  (``stats["restarts"]``), and otherwise keep their own state.

When scipy's step fails (the step size collapsed), :meth:`~mbcomp.solvers.base.Stepper.step`
returns a message naming the method, the time, the likely causes and scipy's last warning;
scipy's warnings are kept (``stats["solver_warnings"]``), not shown. The implicit methods
(``Radau, BDF, LSODA``) get the problem's Jacobian ``jac(t, y)`` when it has one (every
formulation does: :meth:`mbcomp.formulations.Formulation.jac`).

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from mbcomp.solvers.scipy_adapter import SCIPY_STEPPERS
>>> decay = SimpleNamespace(fun=lambda t, y: -2.0 * y)
>>> s = SCIPY_STEPPERS["DOP853"](decay, 0.0, [1.0], 1.0, rtol=1e-10, atol=1e-12)
>>> while s.status == "running":
...     _ = s.step()
>>> round(float(s.y[0]), 10) == round(float(np.exp(-2.0)), 10), s.stats["nsteps"] > 0
(True, True)
"""
from __future__ import annotations

import warnings

import numpy as np

from .base import StepFailure, Stepper

__all__ = ["ScipyStepper", "SCIPY_STEPPERS"]


class _ScipyMethod:
    """Class attribute ``method``: the ``scipy.integrate`` class named by the stepper's ``name``.

    Resolved on each access, so ``scipy.integrate`` (~0.5 s to import) is imported when a
    scipy method is used or looked at, not when :mod:`mbcomp.solvers` is imported.
    """

    def __get__(self, obj, cls):
        if not cls.name:
            return None
        import scipy.integrate

        return getattr(scipy.integrate, cls.name)


class ScipyStepper(Stepper):
    """A ``scipy.integrate.OdeSolver`` stepping ``dy/dt = problem.fun(t, y)``.

    Parameters
    ----------
    problem : object with ``fun(t, y)``
        An ODE (a formulation whose ``problem`` is ``"ode"``).
    t0, y0, t_bound, rtol, atol, first_step, max_step
        As for :class:`~mbcomp.solvers.base.Stepper`; ``first_step`` is scipy's initial
        step size (``None``: scipy chooses).

    Attributes
    ----------
    solver : scipy.integrate.OdeSolver
        The solver currently stepping (a new one after each restart).
    stats : dict
        ``nsteps``, ``nfev``, ``njev``, ``nlu`` (summed over restarts) and ``restarts``;
        scipy does not report rejected steps, so there is no ``nreject``.

    Examples
    --------
    >>> from mbcomp.solvers.scipy_adapter import SCIPY_STEPPERS
    >>> SCIPY_STEPPERS["BDF"].capabilities()
    {'implicit': True, 'adaptive': True, 'one_step': False, 'max_index': 0, 'problem': 'ode'}
    """

    #: the wrapped ``scipy.integrate`` class (from ``name``, imported on first use) and its name
    method = _ScipyMethod()
    name = ""
    adaptive = True
    problem = "ode"

    #: the text of scipy's last warning (None: none so far)
    last_warning = None

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf):
        super().__init__(problem, t0, y0, t_bound, rtol, atol, first_step, max_step)
        del self.stats["nreject"]
        self._done = dict(nfev=0, njev=0, nlu=0)  # work of the solvers replaced by restarts
        self.solver = self._start(self.t, self.y)

    def _start(self, t, y):
        opts = dict(rtol=self.rtol, atol=self.atol, max_step=self.max_step)
        if self.first_step:
            opts["first_step"] = self.first_step
        if self.implicit and hasattr(self.prob, "jac"):
            # the problem's Jacobian: scipy's own finite differences adapt each column's step
            # from the last Jacobian and let it grow without bound for a coordinate nothing
            # depends on (a freely spinning shaft angle) until it overflows
            opts["jac"] = self.prob.jac
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            solver = self.method(self.prob.fun, t, y, self.t_bound, **opts)
        self._note(caught)
        return solver

    def _note(self, caught):
        """Keep scipy's warnings (counted in ``stats["solver_warnings"]``, the last text in
        :attr:`last_warning` for a failure's message) instead of letting them reach the user."""
        for w in caught:
            self.stats["solver_warnings"] = self.stats.get("solver_warnings", 0) + 1
            self.last_warning = f"{w.category.__name__}: {w.message}"

    def _count(self):
        for key, done in self._done.items():
            self.stats[key] = done + int(getattr(self.solver, key, 0))

    def _status_after_step(self):
        """scipy's own status: ``"finished"`` exactly when ``t_bound`` is reached."""
        return self.solver.status

    def _step(self):
        s = self.solver
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            msg = s.step()
        self._note(caught)
        self._count()
        if s.status == "failed":
            cause = f"; scipy warned: {self.last_warning}" if caught else ""
            raise StepFailure(f"the integrator {self.name} failed at t={s.t:g}: {msg}{cause} "
                              "(step size collapsed: stiff or singular dynamics, or tolerances too tight)")
        self.t_old, self.t, self.y = s.t_old, s.t, s.y
        self.stats["nsteps"] += 1

    def dense_output(self):
        return self.solver.dense_output()

    def reset_state(self, y):
        """Continue from the moved state ``y`` (see the module notes)."""
        y = np.array(y, dtype=float)
        if self.one_step:
            self.solver.y = y
            self.solver.f = self.prob.fun(self.t, y)  # the derivative the next step starts from
            self.y = y
        elif self.moved_beyond_tolerance(y):
            for key in self._done:
                self._done[key] = self.stats[key]
            self.solver = self._start(self.t, y)
            self.y = y
            self.stats["restarts"] += 1


def _declare(name, one_step, implicit):
    doc = (f"scipy's ``{name}`` as a stepper ({'one-step' if one_step else 'multistep'}, "
           f"{'implicit' if implicit else 'explicit'}); see :class:`ScipyStepper`.")
    return type(name, (ScipyStepper,), dict(name=name, one_step=one_step, implicit=implicit, __doc__=doc,
                                            __module__=__name__))


#: name -> stepper class, with each method's declared memory and implicitness
SCIPY_STEPPERS = {
    "RK23": _declare("RK23", one_step=True, implicit=False),
    "RK45": _declare("RK45", one_step=True, implicit=False),
    "DOP853": _declare("DOP853", one_step=True, implicit=False),
    "Radau": _declare("Radau", one_step=True, implicit=True),
    "BDF": _declare("BDF", one_step=False, implicit=True),
    "LSODA": _declare("LSODA", one_step=False, implicit=True),
}
