"""What every formulation offers the driver and the post-processing.

A formulation reduces the assembled :class:`~mbcomp.assembly.system.MultibodySystem` to a
problem a stepper can step, of one of the kinds of :mod:`mbcomp.solvers.base`
(``problem``): an ODE ``dy/dt = fun(t, y)``, a semi-explicit DAE ``E dy/dt = fun(t, y)``,
or the second-order mechanical form. Whatever its state ``y`` holds (all speeds,
independent speeds, accelerations and multipliers), it maps ``y`` back to the coordinates
and speeds ``[q, u]`` (:meth:`Formulation.full`), says whether the driver should move the
state back onto the constraint manifold after every accepted step
(:attr:`Formulation.projects`, :meth:`Formulation.project`), whether it must re-choose its
coordinates (:meth:`Formulation.needs_repartition`) and gives accelerations and multipliers
at an output point for the reactions (:meth:`Formulation.solve`). The driver asks nothing
else, so it never needs to know which formulation it runs.

Examples
--------
>>> from mbcomp.formulations import Formulation
>>> Formulation.problem, Formulation.stabilization
('ode', 'none')
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError

__all__ = ["Formulation"]

#: relative step of the finite-difference Jacobian (:meth:`Formulation.jac`)
_FD_STEP = float(np.sqrt(np.finfo(float).eps))


class Formulation:
    """Base class: the interface the driver uses, with the defaults of a plain ODE in ``[q, u]``.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized (``system.row_mask`` set).

    Attributes
    ----------
    system : MultibodySystem
    nq, nu : int
        Coordinates and speeds of the system.
    stabilization : {"baumgarte", "projection", "none"}
        How the constraints are kept (reported in the result's stats).
    problem : {"ode", "dae", "mechanical"}
        The stepper kind that can step it (see :mod:`mbcomp.solvers.base`).
    nfev, nlu : int
        Right-hand-side evaluations and linear solves (factorizations) so far.
    singular : {"stop", "pass"}
        What a singular position does to the run (only the Lagrange form passes them).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.formulations import Formulation
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=1.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> form = Formulation(mbcomp.assemble(m))
    >>> y = form.initial_state(0.0, np.array([1.0]), np.array([2.0]))
    >>> form.full(0.0, y).tolist(), form.projects, form.needs_repartition(0.0, y), form.run_stats()
    ([1.0, 2.0], False, False, {})
    """

    stabilization = "none"
    problem = "ode"
    singular = "stop"

    def __init__(self, system):
        self.system = system
        self.nq, self.nu = system.nq, system.nu
        self.nfev = 0
        self.nlu = 0

    def initial_state(self, t, q, u):
        """The stepped state ``y0`` from consistent coordinates ``q`` and speeds ``u``."""
        return np.concatenate((q, u))

    def fun(self, t, y):
        """``dy/dt`` (problem ``"ode"``) or the right side of ``E dy/dt = fun(t, y)`` (``"dae"``)."""
        raise NotImplementedError

    def jac(self, t, y):
        """``d fun / dy`` (``"ode"`` problems) by forward differences, column ``j`` with the step
        ``sqrt(eps) max(|y_j|, 1)``: never a step that grows without bound, whatever the
        dependence on ``y_j`` (scipy's own differences let it grow for a coordinate nothing
        depends on, such as a freely spinning shaft's angle, until it overflows)."""
        y = np.asarray(y, dtype=float)
        return self.difference_columns(t, y, range(y.size))

    def difference_columns(self, t, y, columns, J=None):
        """``J`` (made (n, n) if None) with the ``columns`` of ``d fun / dy`` at ``(t, y)``
        by forward differences (the step of :meth:`jac`); the other columns untouched."""
        f0 = np.asarray(self.fun(t, y))
        J = np.empty((f0.size, y.size)) if J is None else J
        yj = y.copy()
        for j in columns:
            h = _FD_STEP * max(abs(y[j]), 1.0)
            yj[j] = y[j] + h
            h = yj[j] - y[j]  # the step actually taken in floating point
            J[:, j] = (np.asarray(self.fun(t, yj)) - f0) / h
            yj[j] = y[j]
        return J

    def full(self, t, y):
        """``[q, u]`` (coordinates then speeds) of the state ``y``, for output and post-processing."""
        return np.asarray(y[: self.nq + self.nu])

    def full_many(self, t, Y):
        """:meth:`full` of the states ``Y`` (rows) at the times ``t``: ``(n, nq + nu)``."""
        return np.asarray(Y)[:, : self.nq + self.nu]

    def project(self, t, y):
        """``y`` moved back onto the constraint manifold (here: unchanged)."""
        return y

    @property
    def projects(self):
        """Whether the driver should call :meth:`project` after every accepted step."""
        return False

    def needs_repartition(self, t, y):
        """Whether the coordinates the state is written in must be chosen again at ``y``."""
        return False

    def rows_changed(self, t, q, u):
        """The state to go on from at ``(t, q, u)`` (``full`` of the last state) after the kept
        constraint rows (``system.row_mask``) were chosen again: the start state there
        (multipliers and everything else written in the rows made afresh)."""
        return self.initial_state(t, q, u)

    def repartition(self, t, y):
        """The state ``y`` written in newly chosen coordinates, or ``None`` when the choice
        did not change (then the stepper goes on: nothing to restart). Here: ``None``."""
        return None

    def solve(self, ev, stabilize=True):
        """Accelerations ``du/dt`` and multipliers at an evaluation ``ev`` (for reactions)."""
        raise NotImplementedError

    def output_gains(self):
        """The Baumgarte gains ``(alpha, beta)`` (1/s) that :meth:`solve` uses at
        ``stabilize=True`` (the post-processing's multipliers use the same), or None: none."""
        return None

    def compiled_integrator(self):
        """The compiled engine stepping this formulation's ``fun`` in C
        (:class:`mbcomp.codegen.engine.Integrator`), or None (the default: ``fun`` in Python)."""
        return None

    def run_stats(self):
        """Statistics of the run this formulation adds to the result's ``stats``."""
        return {}

    def _check_finite(self, t, y):
        """Count an evaluation; a non-finite state means the integration diverged."""
        self.nfev += 1
        if not np.isfinite(y).all():  # the method, not np.all(): ~1 us of a ~10 us call
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")


def projection_needed(system):
    """Whether a projection can change anything: position rows to close (cut joints, including
    constraint-only joints such as contacts), quaternions to normalize (``nq != nu``) or
    nonholonomic rows to satisfy."""
    return bool(system.topology.cut or system.nq != system.nu or system.nonholonomic)
