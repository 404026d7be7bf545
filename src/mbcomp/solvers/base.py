"""The stepping interface every mbcomp integrator follows, and the problems it steps.

Modelled on ``scipy.integrate.OdeSolver``: a solver is constructed at ``(t0, y0)`` with a
``t_bound``; the driver calls :meth:`Stepper.step` until ``status`` is ``"finished"`` or
``"failed"``, reads ``t``, ``y`` and interpolates inside the last step with
:meth:`Stepper.dense_output`, and moves the state after a step with
:meth:`Stepper.reset_state` (a projection). Each class *declares* what it can do
(``implicit``, ``adaptive``, ``one_step``, ``max_index``, the ``problem`` kind it accepts) so
the driver never special-cases a solver by name, and counts its work in
:attr:`Stepper.stats` under common names (``nsteps, nreject, nfev, njev, nlu, restarts``).

Problem kinds
-------------
``"ode"``
    ``dy/dt = fun(t, y)``: any object with ``fun(t, y)`` and ``n``.
``"dae"`` (:class:`SemiExplicitDAE`)
    ``E dy/dt = fun(t, y)`` with a constant diagonal ``E = diag(mass)`` (1 for a
    differential row, 0 for an algebraic one) and, per variable, its DAE ``index``
    (1, 2 or 3: how often the constraints must be differentiated to give its derivative);
    index-aware error control scales index-2 variables by ``h`` and index-3 by ``h**2``.
``"mechanical"`` (:class:`MechanicalDAE`)
    ``M(q) du/dt + C(q)^T lam = f(t, q, u)``, ``Phi(t, q) = 0``, ``dq/dt = H(q) u``: the
    second-order structure a generalized-alpha scheme needs; coordinates are moved with
    ``increment(q, dq)`` (``dq`` in speed space), which is a rotation-vector update for
    quaternion coordinates (a Lie-group step).

Examples
--------
>>> import numpy as np
>>> from mbcomp.solvers.base import Stepper
>>> Stepper.capabilities()
{'implicit': False, 'adaptive': False, 'one_step': True, 'max_index': 0, 'problem': 'ode'}
"""
from __future__ import annotations

from typing import Protocol

import numpy as np

__all__ = ["Stepper", "SemiExplicitDAE", "MechanicalDAE", "StepFailure"]


#: A multistep stepper (BDF, LSODA, IDA) keeps integrating its own state after a projection
#: until the projected state is more than this many tolerance units (``atol + rtol |y|``)
#: away; then it restarts from the projected state. Outputs are projected either way. A
#: restart drops the method to order 1 with a tiny step, whose error exceeds the drift it
#: removes: at 1 (the old rule) BDF + D'Alembert on the slider-crank restarted after 23 % of
#: its 11,454 steps, took 43 s for 0.5 s simulated and ended 8e-6 rad off; at 100 it takes
#: 272 steps, 1 restart, 0.95 s, 9e-8 rad. Between 100 and 1000 nothing changes but the
#: bound on the drift, so 100 keeps the integrated state within 100 tolerance units.
RESTART_DRIFT = 100.0


class StepFailure(RuntimeError):
    """A solver could not continue; the message names the cause (Newton failure, step-size
    collapse, singular iteration matrix) and where (``t``)."""


class SemiExplicitDAE(Protocol):
    """``E dy/dt = fun(t, y)`` with ``E = diag(mass)`` constant.

    Attributes
    ----------
    n : int
        Number of variables.
    mass : ndarray (n,)
        1.0 for a differential equation row, 0.0 for an algebraic row.
    index : ndarray (n,) of int
        DAE index of each variable (1 for differential and index-1 algebraic variables).
    """

    n: int
    mass: np.ndarray
    index: np.ndarray

    def fun(self, t: float, y: np.ndarray) -> np.ndarray: ...

    def jac(self, t: float, y: np.ndarray) -> np.ndarray | None:
        """``d fun / d y`` (n, n), or ``None`` to let the solver use finite differences."""


class MechanicalDAE(Protocol):
    """``M(q) a + C(q)^T lam = f(t, q, u)``, ``Phi(t, q) = 0``, ``dq/dt = q_rate(q, u)``.

    Attributes
    ----------
    nq, nu, m : int
        Coordinates, speeds, constraint rows.
    """

    nq: int
    nu: int
    m: int

    def dynamics(self, t: float, q: np.ndarray, u: np.ndarray):
        """``(M (nu, nu), f (nu,), Phi (m,), C (m, nu))`` at ``(t, q, u)``."""

    def increment(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """``q`` moved by ``dq`` given in speed space (nu,)."""

    def q_rate(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``dq/dt`` (nq,)."""


class Stepper:
    """Base class of every mbcomp integrator (one step at a time).

    Parameters
    ----------
    problem : object
        Of the kind named by the class attribute ``problem``.
    t0 : float
        Start time (s).
    y0 : ndarray
        Consistent start state (for ``"mechanical"``: ``[q, u, udot, a, lam]``).
    t_bound : float
        Do not step past this time.
    rtol, atol : float
        Tolerances (adaptive solvers) -- fixed-step solvers use ``first_step`` as ``h``.
    first_step, max_step : float, optional

    Attributes
    ----------
    t, y, t_old : current time, state, time before the last step.
    t_reached : float
        The furthest time an attempt reached (s): ``t``, or beyond it when a failed attempt
        got further before failing (a C stretch that ran out of steps).
    status : {"running", "finished", "failed"}
    stats : dict with ``nsteps, nreject, nfev, njev, nlu, restarts`` (and solver-specific
        counters such as ``nnewton``); a counter a solver cannot know is left out.

    Class attributes (declared, never inferred from a name)
    -------------------------------------------------------
    implicit : bool
        Solves nonlinear equations per step (a Newton iteration with factorizations).
    adaptive : bool
        Chooses its step size from ``rtol``, ``atol``; ``False``: fixed step ``first_step``.
    one_step : bool
        Keeps no history of past steps, so it continues from a state moved by
        :meth:`reset_state`; ``False`` (multistep methods): its history cannot be moved, so
        :meth:`reset_state` restarts it when the move exceeds the tolerance.
    max_index : int
        Highest DAE index it steps (0: ODEs only).
    problem : {"ode", "dae", "mechanical"}
        The problem kind it steps.
    needs_outputs : bool
        Takes the run's output times (``t_eval``) and steps from one to another (the C
        integrators, which write the outputs themselves).
    """

    implicit = False
    needs_outputs = False
    adaptive = False
    one_step = True
    max_index = 0
    problem = "ode"

    @classmethod
    def capabilities(cls):
        """The declared class attributes as a dict."""
        return dict(implicit=cls.implicit, adaptive=cls.adaptive, one_step=cls.one_step, max_index=cls.max_index,
                    problem=cls.problem)

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf):
        self.prob = problem
        self.t = float(t0)
        self.t_old = None
        self.y = np.array(y0, dtype=float)
        self.t_bound = float(t_bound)
        self.rtol, self.atol = rtol, atol
        self.first_step, self.max_step = first_step, max_step
        self.status = "running" if self.t < self.t_bound else "finished"
        self.stats = dict(nsteps=0, nreject=0, nfev=0, njev=0, nlu=0, restarts=0)
        self._reached = self.t

    @property
    def t_reached(self):
        return max(self.t, self._reached)

    def step_outputs(self):
        """The states at output times inside the last step as the integrator computed them,
        ``(ts, Ys)`` (steppers with ``needs_outputs``), or None: the driver interpolates the
        dense output."""
        return None

    #: set by a stepper that asks the run to go on from its state by another stepper (a name
    #: in :data:`mbcomp.solvers.STEPPERS`: ``auto`` hands a stiff problem to ``"radau5"``); the
    #: run makes that one at its next step (:meth:`mbcomp.simulation.stepping.Run.advance`)
    go_on_by = None

    def step(self):
        """Advance one step; returns ``None`` or, on failure, the message (status ``"failed"``)."""
        if self.status != "running":
            raise RuntimeError("step() on a solver that is not running")
        try:
            self._step()
        except StepFailure as exc:
            self.status = "failed"
            return str(exc)
        self.status = self._status_after_step()
        return None

    def _status_after_step(self):
        """``"finished"`` once ``t_bound`` is reached (to rounding), else ``"running"``."""
        return "finished" if self.t >= self.t_bound - 1e-14 * max(1.0, abs(self.t_bound)) else "running"

    def reset_state(self, y):
        """Continue from a modified state ``y`` at the current time (the driver's projection).

        One-step solvers that keep derived data (``fun`` at ``y``) override this to refresh
        it; multistep solvers override it to restart from ``y`` when ``y`` differs from their
        state by more than the tolerance (counted in ``stats["restarts"]``)."""
        self.y = np.array(y, dtype=float)

    def moved_beyond_tolerance(self, y):
        """Whether ``y`` differs from the current state by more than ``RESTART_DRIFT`` times
        ``atol + rtol |y|`` in some component (when a multistep solver must restart after a
        projection; below it, it keeps its own state)."""
        y = np.asarray(y, float)
        scale = self.atol + self.rtol * np.abs(y)
        return bool(np.max(np.abs(y - self.y) / scale, initial=0.0) > RESTART_DRIFT)

    def _step(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def dense_output(self):
        """Callable ``y(t)`` for ``t`` in ``[t_old, t]`` (the last step)."""
        raise NotImplementedError
