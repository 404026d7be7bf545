"""Lagrange multipliers at index 1: the constraints at acceleration level, solved inside ``fun``.

:class:`LagrangeIndex1` steps ``y = [q, u]`` as an ODE whose accelerations come from the
saddle-point system::

    [ M  C^T  B^T ] [ du/dt ]   [ f                                   ]
    [ C   0    0  ] [  lam  ] = [ -c_b - 2 alpha dPhi/dt - beta^2 Phi ]
    [ B   0    0  ] [  mu   ]   [ -B_b - alpha Psi                     ]

with holonomic rows ``C`` (loop closure, residual ``Phi``) and nonholonomic rows ``B``
(residual ``Psi = B u - b``); ``lam`` are the loop-closure multipliers and ``mu`` the
nonholonomic ones.

Stabilization ``"baumgarte"`` keeps the ``alpha``/``beta`` terms (1/s), ``"projection"``
drops them and instead moves positions and speeds back onto the constraint manifold
after every step (:meth:`LagrangeIndex1.project`), ``"none"`` integrates the plain
index-1 form (drift grows). The constraint force on the tree coordinates is ``-A^T [lam; mu]``.

Examples
--------
>>> from mbcomp.formulations import LagrangeIndex1
>>> LagrangeIndex1.stabilizations
('baumgarte', 'projection', 'none')
"""
from __future__ import annotations

import numpy as np

from ..assembly.kkt import project_state, solve_kkt
from ..assembly.manifold import ACCEPT_FACTOR, POSITION_TOL
from .base import Formulation, projection_needed
from .passing import PassingEngine

__all__ = ["LagrangeIndex1"]


class LagrangeIndex1(Formulation):
    """Index-1 multiplier form of a :class:`~mbcomp.assembly.system.MultibodySystem`: an ODE in ``[q, u]``.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized (``system.row_mask`` set).
    stabilization : {"baumgarte", "projection", "none"}
    alpha, beta : float
        Baumgarte parameters in 1/s (used with ``"baumgarte"``).
    singular : {"stop", "pass"}
        ``"pass"``: near a singular position (the rows' ``A M^-1 A^T`` with eigenvalues below
        :attr:`PASS_RANK` of its largest) the multipliers leave out the directions of those
        eigenvalues, so the accelerations stay bounded while the motion passes through (see
        :meth:`solve`).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.formulations import LagrangeIndex1
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> form = LagrangeIndex1(mbcomp.assemble(m))
    >>> dy = form.fun(0.0, form.initial_state(0.0, np.array([0.5]), np.array([0.0])))
    >>> round(float(dy[1]), 6)          # pendulum of length 1 m: du/dt = -g sin(phi)
    -4.703165
    """

    stabilizations = ("baumgarte", "projection", "none")
    #: with ``singular="pass"``: eigenvalues of ``A M^-1 A^T`` below this times its largest
    #: (a relative singular value of the rows of about 1e-4) are left out of the multipliers
    PASS_RANK = 1e-8

    def __init__(self, system, stabilization="baumgarte", alpha=10.0, beta=10.0, singular="stop"):
        if stabilization not in self.stabilizations:
            raise ValueError(f"stabilization {stabilization!r} is unknown; use one of {self.stabilizations}")
        super().__init__(system)
        self.stabilization = stabilization
        self.alpha, self.beta = float(alpha), float(beta)
        self.singular = singular

    @property
    def projects(self):
        """With ``"projection"``, when there is something to project (loops, quaternions, velocity rows)."""
        return self.stabilization == "projection" and projection_needed(self.system)

    def solve(self, ev, stabilize=True):
        """Accelerations ``du/dt`` and multipliers ``[lam, mu]`` at an evaluation ``ev``.

        ``stabilize=False`` leaves out the Baumgarte terms (the plain index-1 solve used for
        consistent accelerations and reactions). The solve is :func:`mbcomp.assembly.kkt.solve_kkt`
        (with ``singular="pass"`` by the range space, :attr:`PASS_RANK`).
        """
        self.nlu += 1
        rhs = -ev.cb
        rhs_nh = -ev.Bb
        if stabilize and self.stabilization == "baumgarte":
            rhs = rhs - 2.0 * self.alpha * ev.Phid - self.beta ** 2 * ev.Phi
            rhs_nh = rhs_nh - self.alpha * ev.Psi
        return solve_kkt(ev.M, ev.f, ev.A, np.concatenate((rhs, rhs_nh)), ev.t,
                         pass_rank=self.PASS_RANK if self.singular == "pass" else None)

    #: (row mask, the one-C-call right-hand side or None) -- see :meth:`fun`
    _thin_for = (None, None)

    def fun(self, t, y):
        """``dy/dt`` for ``y = [q, u]``.

        A generated C program is called in one C call from here (the evaluator's
        ``lagrange_thin``, kept per row mask: it checks ``y`` and the result for finiteness
        in C); where that does not hold (a guard, a non-finite value) or there is none, the
        full path below decides and says why."""
        thin = self._thin_for
        if thin[0] is self.system.row_mask and thin[1] is not None:
            dy = thin[1](t, y)
            if dy is not None:
                self.nfev += 1
                self.nlu += 1
                return dy
        return self._full_fun(t, y)

    def _full_fun(self, t, y):
        """:meth:`fun` without the thin call: the finiteness check, the evaluator's one-call
        right-hand side (``lagrange_fun``), else the dense solve."""
        self._check_finite(t, y)
        fast = self._one_call()
        if fast is not None:  # the whole right-hand side in one program call
            dy = fast(t, y, *self._gains)
            if dy is not None:
                self.nlu += 1
                return dy
        q, u = y[: self.nq], y[self.nq:]
        ev = self.system.evaluate(t, q, u)
        ud, _ = self.solve(ev)
        return np.concatenate((self.system.q_rate(q, u), ud))

    def jac(self, t, y):
        """``d fun / dy``: exact, from the generated Jacobian program
        (:meth:`mbcomp.codegen.evaluator.ProgramEvaluator.lagrange_jacobian`, kept per row mask) when the system runs a
        generated right-hand side; else (the numeric backend, a state where the program does
        not hold) by forward differences (:meth:`Formulation.jac`)."""
        jac = self._exact_jacobian()
        if jac is not None:
            J = jac(t, np.asarray(y, dtype=float), *self._gains)
            if J is not None:
                return J
            self.system.evaluator.count_jac_fallback()
        return super().jac(t, y)

    def _exact_jacobian(self):
        """The evaluator's bound Jacobian program (``lagrange_jacobian``) or None, looked up
        once per row mask as :meth:`_one_call` (the lookup costs a quarter of the call at N = 5)."""
        mask = self.system.row_mask
        cached = self.__dict__.get("_jacobian_for")
        if cached is None or cached[0] is not mask:
            jac = self.system.evaluator.lagrange_jacobian() if self._one_call() is not None else None
            cached = self._jacobian_for = (mask, jac)
        return cached[1]

    def _one_call(self):
        """The evaluator's one-call right-hand side (``lagrange_fun``) or None, looked up once
        per row mask: asking for the capabilities costs as much as the call itself."""
        mask = self.system.row_mask
        cached = self.__dict__.get("_one_call_for")
        if cached is None or cached[0] is not mask:
            evaluator = self.system.evaluator
            fast = evaluator.lagrange_fun if "lagrange_fun" in evaluator.capabilities else None
            self._gains = (self.alpha, self.beta) if self.stabilization == "baumgarte" else (0.0, 0.0)
            cached = self._one_call_for = (mask, fast)
            thin = getattr(evaluator, "lagrange_thin", None) if fast is not None else None
            self._thin_for = (mask, thin(*self._gains) if thin is not None else None)
        return cached[1]

    def output_gains(self):
        """``(alpha, beta)`` with Baumgarte stabilization, else None."""
        return (self.alpha, self.beta) if self.stabilization == "baumgarte" else None

    def compiled_integrator(self):
        """The C engine over the system's Lagrange program (Baumgarte gains as stabilized), or
        None when the evaluator has none (numeric or Python program, drives).

        With ``"projection"`` the engine projects after every accepted step in C (as
        :meth:`project`, with the same tolerances), so a stretch of outputs is still one C
        call; a joint whose coordinates move in a way the C projection does not know (see
        :func:`mbcomp.codegen.engine.coordinate_map`: additive, ball and free joints it
        knows) leaves no engine: scipy's method steps :meth:`fun` and the driver projects
        after every step.

        With ``singular="pass"`` it is a :class:`~mbcomp.formulations.passing.PassingEngine`:
        the C loop steps through the singular positions (the range-space solve where the
        program's guard fails) and locates the rows' closest approaches on its own
        continuous extension for the rank monitor, without a restart next to them
        (docs/design/generated-programs.md, *Passing singular positions in C*); None where
        the runtime has no ``mbrt_pass_integrate`` or the projection's program is missing."""
        evaluator = self.system.evaluator
        if "c_integrate" not in evaluator.capabilities:
            return None
        if self.singular == "pass":
            return self._passing_engine(evaluator)
        if not self.projects:
            return evaluator.integrator(*((self.alpha, self.beta) if self.stabilization == "baumgarte"
                                          else (0.0, 0.0)))
        return evaluator.integrator(0.0, 0.0, project=(POSITION_TOL, ACCEPT_FACTOR * POSITION_TOL))

    def _passing_engine(self, evaluator):
        """The :class:`~mbcomp.formulations.passing.PassingEngine` of a ``singular="pass"`` run, or None."""
        inner = evaluator.integrator(0.0, 0.0, project=(POSITION_TOL, ACCEPT_FACTOR * POSITION_TOL))
        if inner is None or inner.mech is None:
            return None
        return PassingEngine(inner, self.system, self.PASS_RANK, project=self.projects)

    def project(self, t, y):
        """``y = [q, u]`` moved onto ``Phi = 0`` and ``[dPhi/dt, Psi] = 0`` by minimum-norm
        corrections (Newton on the positions, then least squares on the speeds), quaternions
        normalized."""
        return project_state(self.system, t, y)
