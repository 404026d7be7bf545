"""D'Alembert projection onto independent speeds: a minimal ODE, no multipliers.

The velocity constraints ``A u = r`` (holonomic rows ``C`` and nonholonomic rows ``B``)
are partitioned into dependent and independent speeds by QR with column pivoting on ``A``
(the best-conditioned ``m`` columns become dependent). With the dependent speeds ``u_d``
solved from the independent ones ``v``, admissible accelerations are
``du/dt = N dv/dt + w`` with ``N = [-A_d^-1 A_i; I]`` and ``A_d w_d = -bias``, and the
equations of motion projected onto them (D'Alembert / Kane) are the ODE::

    N^T M N dv/dt = N^T (f - M w)

Examples
--------
>>> from mbcomp.formulations import DAlembert
>>> DAlembert.stabilization, DAlembert.problem
('projection', 'ode')
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..assembly.manifold import SingularPartition, close_positions, pivot_partition, solve_speeds
from ..errors import SimulationError
from .base import Formulation

__all__ = ["DAlembert"]


class DAlembert(Formulation):
    """D'Alembert projection onto independent speeds: the ODE ``N^T M N dv/dt = N^T (f - M w)``.

    The state is ``y = [q, v]`` with ``v`` the independent speeds; open trees have no
    constraints, so ``v = u`` and this is the minimal ODE ``M du/dt = f``. Positions drift
    off the loop-closure manifold only through integration error; :meth:`project` pulls
    them back by Newton on the dependent coordinates. When ``A_d`` becomes ill-conditioned
    (a mechanism approaching a position where the chosen dependent coordinates cannot be
    solved for), :meth:`needs_repartition` says so and :meth:`repartition` chooses again;
    the driver restarts the integrator.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.
    independent : list of str, optional
        Speed names (``system.u_names``) to start with as independent; by default chosen by
        pivoted QR. Either way they are re-chosen when they become ill-conditioned.
    growth_max, cond_max : float
        Re-choose the partition when a dependent speed moves more than ``growth_max`` times
        faster than an independent one (``max |A_d^-1 A_i|``, in the coordinates' units) or
        the condition number of ``A_d`` exceeds ``cond_max``. When pivoting chooses the same
        partition again, the bound becomes twice the growth reached (until a new partition
        is chosen), so a mechanism whose best partition has a larger growth is not asked
        again at every step. Why 4 and not more: near a flat position the growth of a
        partition about to fail climbs from 4 to 100 within a millisecond, and a position
        correction there with the failing speed held (a multistep method's deferred
        projection, ``RESTART_DRIFT``) puts a velocity error of that growth into the motion:
        BDF on the four-bar through its near-flat passage ended 4.6e-4 rad off at rtol 1e-8
        with 100, 1.6e-6 with 4 (DOP853: 1e-7 and 2e-8).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5, w0=0.0)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> r = mbcomp.simulate(m, t_end=1.0, formulation="dalembert")
    >>> r.stats["formulation"], r.stats["independent_speeds"]
    ('dalembert', ['j.w'])
    """

    stabilization = "projection"

    def __init__(self, system, independent=None, growth_max=4.0, cond_max=1e8):
        super().__init__(system)
        self.requested = list(independent) if independent is not None else None
        self.growth_max, self.cond_max = float(growth_max), float(cond_max)
        self.repartitions = 0
        self.dep = np.zeros(0, int)
        self.ind = np.arange(self.nu)
        self._ill = False
        self._limit, self._growth = self.growth_max, 0.0
        self._c = None  # whether the evaluator runs the right-hand side in one C call (asked at the first call)

    # --- partition ---------------------------------------------------------------------------
    def partition(self, A):
        """Dependent and independent speed indices ``(dep, ind)`` chosen by pivoted QR of ``A``."""
        try:
            return pivot_partition(A)
        except SingularPartition:
            raise SimulationError("the constraint Jacobian has lost rank: no set of dependent coordinates exists "
                                  "(a singular position of the mechanism)") from None

    def initial_state(self, t, q, u):
        """``y0 = [q, v]`` from a consistent ``(q, u)``; chooses the first partition."""
        ev = self.system.evaluate(t, q, u)
        self.dep, self.ind = self.partition(ev.A)
        if self.requested is not None:
            self._request(ev.A)
        return np.concatenate((q, u[self.ind]))

    def _request(self, A):
        names = self.system.u_names
        unknown = [n for n in self.requested if n not in names]
        if unknown:
            raise ValueError(f"independent speeds {unknown} are not speeds of the model; choose from {names}")
        ind = np.array(sorted(names.index(n) for n in self.requested), int)
        if ind.size != self.ind.size:
            raise ValueError(f"the mechanism has {self.ind.size} independent speeds (mobility); "
                             f"{len(self.requested)} were requested: {self.requested}")
        dep = np.array([i for i in range(self.nu) if i not in set(ind)], int)
        if dep.size and np.linalg.matrix_rank(A[:, dep]) < dep.size:
            raise ValueError(f"independent speeds {self.requested} do not determine the others at the start "
                             "(the remaining columns of the constraint Jacobian are singular); choose others")
        self.dep, self.ind = dep, ind

    def speeds(self, t, q, v):
        """All speeds ``u`` from the independent ones ``v`` (``[dPhi/dt, Psi] = 0`` exactly), and
        the evaluation used (``None`` for an open tree)."""
        u = np.zeros(self.nu)
        u[self.ind] = v
        if self.dep.size == 0:
            return u, None
        ev = self.system.evaluate(t, q, u)
        return solve_speeds(ev.A, np.concatenate((ev.Phid, ev.Psi)), u, self.dep), ev

    def full(self, t, y):
        """``[q, u]`` for output and post-processing."""
        q, v = y[: self.nq], y[self.nq:]
        u, _ = self.speeds(t, q, v)
        return np.concatenate((q, u))

    def full_many(self, t, Y):
        """:meth:`full` of every row of ``Y`` (the dependent speeds solved per row)."""
        return np.array([self.full(tk, y) for tk, y in zip(t, Y)]).reshape(len(Y), self.nq + self.nu)

    # --- dynamics ----------------------------------------------------------------------------
    def _reduce(self, ev):
        """``(N, w)`` with admissible accelerations ``du/dt = N dv/dt + w``."""
        nu, dep, ind = self.nu, self.dep, self.ind
        N = np.zeros((nu, ind.size))
        N[ind, np.arange(ind.size)] = 1.0
        w = np.zeros(nu)
        A = ev.A
        Ad = A[:, dep]
        lu = sla.lu_factor(Ad, check_finite=False)
        N[dep] = -sla.lu_solve(lu, A[:, ind], check_finite=False)
        growth = np.abs(N[dep]).max() if ind.size else 0.0
        self._judge(growth, np.linalg.cond(Ad) if dep.size > 1 else 1.0)
        w[dep] = sla.lu_solve(lu, -np.concatenate((ev.cb, ev.Bb)), check_finite=False)
        return N, w

    def accelerations(self, ev):
        """``du/dt`` at an evaluation whose speeds satisfy the constraints."""
        self.nlu += 1
        if self.dep.size == 0:  # open tree, no velocity rows: N = I, w = 0 -- the minimal ODE itself
            N, w, Mr, fr = None, None, ev.M, ev.f
        else:
            N, w = self._reduce(ev)
            Mr = N.T @ ev.M @ N
            fr = N.T @ (ev.f - ev.M @ w)
        try:
            c = sla.cho_factor(Mr, check_finite=False)
        except np.linalg.LinAlgError:
            raise SimulationError(self._singular_mass(ev.t)) from None
        vd = sla.cho_solve(c, fr, check_finite=False)
        return vd if N is None else N @ vd + w

    @staticmethod
    def _singular_mass(t):
        return (f"the projected mass matrix is singular at t={t:g}: some independent coordinate carries no "
                "inertia; give the bodies mass or prescribe that motion")

    def solve(self, ev, stabilize=True):
        """Accelerations and multipliers (least squares on ``A^T [lam; mu] = f - M du/dt``), with
        the sign convention of :class:`~mbcomp.formulations.LagrangeIndex1` (``M du/dt + A^T [lam; mu] = f``)."""
        ud = self.accelerations(ev)
        A = ev.A
        if A.shape[0] == 0:
            return ud, np.zeros(0)
        lam = np.linalg.lstsq(A.T, ev.f - ev.M @ ud, rcond=None)[0]
        return ud, lam

    def fun(self, t, y):
        """``dy/dt`` for ``y = [q, v]``.

        On a C program (capability ``"dalembert_fun"``) the whole right-hand side is one C call
        (:meth:`mbcomp.codegen.evaluator.ProgramEvaluator.dalembert_fun`): the same steps as
        below, with the same figures for the partition's conditioning (``max |A_d^-1 A_i|``
        and the 2-norm condition number of ``A_d``, by a Jacobi SVD). A failed guard, a
        non-finite value or an exactly singular dependent block take the Python path."""
        self._check_finite(t, y)
        evaluator = self.system.evaluator
        if self._c is None:  # decided once: asking for it makes no Lagrange program
            offers = getattr(evaluator, "offers", None)
            self._c = offers("dalembert_fun") if offers is not None else "dalembert_fun" in evaluator.capabilities
        if self._c:
            status, dy, growth, cond = evaluator.dalembert_fun(t, y, self.dep, self.ind)
            if status == 0:
                self.nlu += 1
                if self.dep.size:
                    self._judge(growth, cond if self.dep.size > 1 else 1.0)
                return dy
            if status == 3:
                raise SimulationError(self._singular_mass(t))
        q, v = y[: self.nq], y[self.nq:]
        u, ev = self.speeds(t, q, v)
        if ev is None or self.dep.size:
            ev = self.system.evaluate(t, q, u)
        ud = self.accelerations(ev)
        return np.concatenate((self.system.q_rate(q, u), ud[self.ind]))

    #: Jacobians :meth:`jac` made exactly and by differences (class defaults; counted per instance)
    njac_exact = njac_differences = 0

    def jac(self, t, y):
        """``d fun / dy`` at ``y = [q, v]``: exact where the system runs generated programs,
        else (numeric backend, a state where a program does not hold) forward differences
        (:meth:`Formulation.jac`).

        The exact one by the chain rule through the dependent speeds: D'Alembert's
        accelerations are the index-1 multiplier form's without Baumgarte terms (both solve
        ``M du/dt + A^T lam = f``, ``A du/dt = -bias``), so ``d[dq/dt; du/dt]/d[q, u]`` is the
        Lagrange Jacobian program's at zero gains; the speeds ``u(q, v)`` solve
        ``g = [dPhi/dt; Psi](q, u) = 0`` with ``u_ind = v``, so by the implicit function theorem
        ``du/dv = N`` and ``du_dep/dq = -A_d^-1 dg/dq`` (``dg/dq`` from the evaluator's
        ``dae_jacobian("dalembert")`` program)."""
        y = np.asarray(y, float)
        J = self._exact_jac(t, y)
        if J is not None:
            self.njac_exact += 1
            return J
        self.njac_differences += 1
        return super().jac(t, y)

    def _exact_jac(self, t, y):
        evaluator = self.system.evaluator
        lagrange_jac = getattr(evaluator, "lagrange_jac", None)
        rates = getattr(evaluator, "dae_jacobian", None)
        if lagrange_jac is None or rates is None or not np.isfinite(y).all():
            return None
        nq, nu, dep, ind = self.nq, self.nu, self.dep, self.ind
        q, v = y[:nq], y[nq:]
        u, ev = self.speeds(t, q, v)
        JL = lagrange_jac(t, np.concatenate((q, u)), 0.0, 0.0)
        if JL is None:
            return None
        du_dq = np.zeros((nu, nq))
        du_dv = np.zeros((nu, ind.size))
        du_dv[ind, np.arange(ind.size)] = 1.0
        if dep.size:
            prog = rates("dalembert")
            G = prog.dalembert(t, q, u) if prog is not None else None
            if G is None:
                return None
            A = ev.A
            lu = sla.lu_factor(A[:, dep], check_finite=False)
            du_dq[dep] = -sla.lu_solve(lu, G, check_finite=False)
            du_dv[dep] = -sla.lu_solve(lu, A[:, ind], check_finite=False)
        rows = np.concatenate((np.arange(nq), nq + ind))
        Jq, Ju = JL[rows, :nq], JL[rows, nq:]
        return np.hstack((Jq + Ju @ du_dq, Ju @ du_dv))

    # --- manifold ----------------------------------------------------------------------------
    @property
    def projects(self):
        """After every step when there are loops to close or quaternions to normalize."""
        return bool(self.system.topology.cut or self.nq != self.nu)

    def project(self, t, y):
        """Normalize quaternions and solve ``Phi(q) = 0`` for the dependent coordinates
        (Newton, independent coordinates held)."""
        sysm = self.system
        q, v = sysm.normalize(y[: self.nq]), y[self.nq:]
        if sysm.topology.cut:
            u0 = np.zeros(self.nu)

            def residual(qq):
                ev = sysm.evaluate(t, qq, u0)
                return ev.Phi, ev.C, ev

            # holonomic rows against the dependent columns: square for pure loops, least squares
            # (minimum norm) when nonholonomic rows claim dependent speeds too
            c = close_positions(residual, sysm.increment, q, columns=self.dep)
            if not c.acceptable:
                raise SimulationError(f"position correction did not converge at t={t:g} (residual {c.norm:.3g}); "
                                      "the mechanism may be near a singular position")
            q = c.q
        return np.concatenate((q, v))

    def _judge(self, growth, cond):
        """Whether the partition is ill-conditioned at the last evaluation (see ``growth_max``)."""
        self._growth = growth
        self._ill = growth > self._limit or cond > self.cond_max

    def needs_repartition(self, t, y):
        """True when the dependent block of the constraint Jacobian was ill-conditioned at the
        last right-hand-side evaluation."""
        return self.dep.size > 0 and self._ill

    def repartition(self, t, y):
        """Choose the partition again at ``y``; the state in the new partition, or ``None``
        when pivoting chooses the same dependent speeds again (the best available choice is
        ill-conditioned too: the stepper goes on instead of restarting)."""
        q, v = y[: self.nq], y[self.nq:]
        u, _ = self.speeds(t, q, v)
        ev = self.system.evaluate(t, q, u)
        dep, ind = self.partition(ev.A)
        self._ill = False
        if np.array_equal(dep, self.dep):
            self._limit = max(self._limit, 2.0 * self._growth)  # the best there is: ask again when it doubles
            return None
        self.dep, self.ind = dep, ind
        self._limit = self.growth_max
        self.repartitions += 1
        return np.concatenate((q, u[self.ind]))

    def rows_changed(self, t, q, u):
        """After the kept rows changed: the partition chosen again by pivoting over the new
        rows (a requested set of independent speeds is not forced again); the state in it."""
        self.dep, self.ind = self.partition(self.system.evaluate(t, q, u).A)
        self._ill, self._limit = False, self.growth_max
        return np.concatenate((q, u[self.ind]))

    def run_stats(self):
        """``repartitions`` (how often the independent speeds were re-chosen), the
        ``independent_speeds`` at the end (names), and when Jacobians were asked for
        ``jac_exact`` and ``jac_differences`` (see :meth:`jac`)."""
        out = dict(repartitions=self.repartitions, independent_speeds=[self.system.u_names[i] for i in self.ind])
        if self.njac_exact or self.njac_differences:
            out.update(jac_exact=self.njac_exact, jac_differences=self.njac_differences)
        return out
