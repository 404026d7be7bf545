"""Reductions of the assembled system to something an integrator can step.

:class:`LagrangeIndex1` - Lagrange multipliers with acceleration-level constraints::

    [ M  C^T  B^T ] [ du/dt ]   [ f                                   ]
    [ C   0    0  ] [  lam  ] = [ -c_b - 2 alpha dPhi/dt - beta^2 Phi ]
    [ B   0    0  ] [  mu   ]   [ -B_b - alpha (B u - b)               ]

with holonomic rows ``C`` (loop closure) and nonholonomic rows ``B u = b``.

Stabilization ``"baumgarte"`` keeps the ``alpha``/``beta`` terms (1/s), ``"projection"``
drops them and instead moves positions and velocities back onto the constraint manifold
after every step (see :meth:`LagrangeIndex1.project`), ``"none"`` integrates the plain
index-1 form (drift grows). The constraint force on the tree coordinates is ``-C^T lam``.

Examples
--------
>>> from mbcomp.formulations import LagrangeIndex1
>>> LagrangeIndex1.stabilizations
('baumgarte', 'projection', 'none')
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import SimulationError

__all__ = ["LagrangeIndex1", "DAlembert"]


class LagrangeIndex1:
    """Index-1 multiplier form of a :class:`~mbcomp.system.MultibodySystem`.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized (``system.row_mask`` set).
    stabilization : {"baumgarte", "projection", "none"}
    alpha, beta : float
        Baumgarte parameters in 1/s (used with ``"baumgarte"``).
    """

    stabilizations = ("baumgarte", "projection", "none")

    def __init__(self, system, stabilization="baumgarte", alpha=10.0, beta=10.0):
        if stabilization not in self.stabilizations:
            raise ValueError(f"stabilization {stabilization!r} is unknown; use one of {self.stabilizations}")
        self.system, self.stabilization = system, stabilization
        self.alpha, self.beta = float(alpha), float(beta)
        self.nq, self.nu = system.nq, system.nu
        self.nfev = 0
        self.nlu = 0
        self.rank_deficient = 0  # saddle-point solves at states where the constraints lost rank

    def split(self, y):
        return y[: self.nq], y[self.nq:]

    def solve(self, ev, stabilize=True):
        """Accelerations ``du/dt`` and multipliers ``lam`` at an evaluation."""
        M, f, C = ev.M, ev.f, ev.A
        m = C.shape[0]
        self.nlu += 1
        if m == 0:
            try:
                c = sla.cho_factor(M)
            except np.linalg.LinAlgError:
                raise SimulationError(f"the mass matrix is singular at t={ev.t:g}: some coordinate carries no "
                                      "inertia; give the bodies mass or prescribe that motion") from None
            return sla.cho_solve(c, f), np.zeros(0)
        rhs = -ev.cb
        rhs_nh = -ev.Bb
        if stabilize and self.stabilization == "baumgarte":
            rhs = rhs - 2.0 * self.alpha * ev.Phid - self.beta ** 2 * ev.Phi
            rhs_nh = rhs_nh - self.alpha * ev.Psi
        rhs = np.concatenate((rhs, rhs_nh))
        n = self.nu
        K = np.zeros((n + m, n + m))
        K[:n, :n] = M
        K[:n, n:] = C.T
        K[n:, :n] = C
        try:
            lu = sla.lu_factor(K, check_finite=False)
        except (ValueError, np.linalg.LinAlgError):
            raise SimulationError(f"the saddle-point matrix is singular at t={ev.t:g}") from None
        d = np.abs(np.diag(lu[0]))
        b = np.concatenate((f, rhs))
        if d.min() <= 1e-13 * d.max():
            # rank lost at this state: often a trial stage of an explicit method far off the
            # manifold (stiff Baumgarte terms), which error control rejects. Minimum-norm answer
            # here; a singular position on the accepted path is reported by the driver's
            # singularity monitor (mbcomp.simulation), which sees accepted steps only.
            self.rank_deficient += 1
            x = np.linalg.lstsq(K, b, rcond=1e-13)[0]
        else:
            x = sla.lu_solve(lu, b, check_finite=False)
        return x[:n], x[n:]

    def fun(self, t, y):
        """``dy/dt`` for ``y = [q, u]``."""
        self.nfev += 1
        q, u = self.split(y)
        if not (np.all(np.isfinite(y))):
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")
        ev = self.system.evaluate(t, q, u)
        ud, _ = self.solve(ev)
        return np.concatenate((self.system.q_rate(q, u), ud))

    def project(self, t, y, tol=1e-12, max_iter=8):
        """Move ``y`` onto ``Phi = 0`` and ``dPhi/dt = 0`` (minimum-norm corrections) and
        normalize quaternions; returns the projected state."""
        sysm = self.system
        q, u = self.split(y)
        q = sysm.normalize(q)
        for _ in range(max_iter):
            ev = sysm.evaluate(t, q, u)
            if ev.Phi.size == 0 or np.linalg.norm(ev.Phi) <= tol:
                break
            dq = -np.linalg.lstsq(ev.C, ev.Phi, rcond=None)[0]
            q = sysm.increment(q, dq)
        else:
            ev = sysm.evaluate(t, q, u)
            if np.linalg.norm(ev.Phi) > 1e3 * tol:
                raise SimulationError(f"position projection did not converge at t={t:g} "
                                      f"(residual {np.linalg.norm(ev.Phi):.3g}); the mechanism may be near a singular position")
        if ev.Phi.size or ev.Psi.size:
            u = u - np.linalg.lstsq(ev.A, np.concatenate((ev.Phid, ev.Psi)), rcond=None)[0]
        return np.concatenate((q, u))


class DAlembert:
    """D'Alembert projection onto independent speeds: a minimal ODE, no multipliers.

    The velocity constraints ``A u = r`` (holonomic rows ``C`` and nonholonomic rows ``B``)
    are partitioned into dependent and independent speeds by QR with column pivoting on
    ``A`` (the best-conditioned ``m`` columns become dependent). With ``u_d`` solved from the
    independent speeds ``v``, admissible accelerations are ``du/dt = N dv/dt + w`` with
    ``N = [-A_d^-1 A_i; I]`` and ``A_d w_d = -bias``, and the equations of motion projected
    onto them (D'Alembert / Kane) are the ODE::

        N^T M N dv/dt = N^T (f - M w)

    The state is ``y = [q, v]``; open trees have no constraints, so ``v = u`` and this is
    the minimal ODE ``M du/dt = f``. Positions drift off the loop-closure manifold only
    through integration error; :meth:`project` pulls them back by Newton on the dependent
    coordinates. When ``A_d`` becomes ill-conditioned (a mechanism approaching a position
    where the chosen dependent coordinates cannot be solved for), :meth:`needs_repartition`
    says so and :meth:`repartition` chooses again; the driver restarts the integrator.

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
        the condition number of ``A_d`` exceeds ``cond_max``.

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

    def __init__(self, system, independent=None, growth_max=100.0, cond_max=1e8):
        self.system = system
        self.requested = list(independent) if independent is not None else None
        self.nq, self.nu = system.nq, system.nu
        self.growth_max, self.cond_max = float(growth_max), float(cond_max)
        self.nfev = 0
        self.nlu = 0
        self.repartitions = 0
        self.dep = np.zeros(0, int)
        self.ind = np.arange(self.nu)
        self._ill = False

    # --- partition ---------------------------------------------------------------------------
    def partition(self, A):
        """Choose dependent speed indices (pivoted QR of ``A``); returns ``(dep, ind)``."""
        m = A.shape[0]
        if m == 0:
            return np.zeros(0, int), np.arange(self.nu)
        _, R, piv = sla.qr(A, pivoting=True, mode="economic")
        d = np.abs(np.diag(R))
        if d.size < m or d[m - 1] <= 1e-12 * max(d[0], 1e-300):
            raise SimulationError("the constraint Jacobian has lost rank: no set of dependent coordinates exists "
                                  "(a singular position of the mechanism)")
        return np.sort(piv[:m]), np.sort(piv[m:])

    @property
    def nv(self):
        return self.ind.size

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

    def split(self, y):
        return y[: self.nq], y[self.nq:]

    def speeds(self, t, q, v, u_guess=None):
        """All speeds ``u`` from the independent ones (satisfying ``A u = r`` exactly)."""
        u = np.zeros(self.nu) if u_guess is None else np.array(u_guess, float)
        u[self.ind] = v
        if self.dep.size == 0:
            return u, None
        ev = self.system.evaluate(t, q, u)
        res = np.concatenate((ev.Phid, ev.Psi))
        Ad = ev.A[:, self.dep]
        u[self.dep] -= np.linalg.solve(Ad, res)
        return u, ev

    def full(self, t, y):
        """``[q, u]`` for output and post-processing."""
        q, v = self.split(y)
        u, _ = self.speeds(t, q, v)
        return np.concatenate((q, u))

    # --- dynamics ----------------------------------------------------------------------------
    def _reduce(self, ev):
        """``(N, w)`` with admissible accelerations ``du/dt = N dv/dt + w``."""
        nu, dep, ind = self.nu, self.dep, self.ind
        N = np.zeros((nu, ind.size))
        N[ind, np.arange(ind.size)] = 1.0
        w = np.zeros(nu)
        if dep.size:
            A = ev.A
            Ad = A[:, dep]
            lu = sla.lu_factor(Ad, check_finite=False)
            N[dep] = -sla.lu_solve(lu, A[:, ind], check_finite=False)
            growth = np.abs(N[dep]).max() if ind.size else 0.0
            self._ill = growth > self.growth_max or (dep.size > 1 and np.linalg.cond(Ad) > self.cond_max)
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
            raise SimulationError(f"the projected mass matrix is singular at t={ev.t:g}: some independent "
                                  "coordinate carries no inertia; give the bodies mass or prescribe that motion") from None
        vd = sla.cho_solve(c, fr, check_finite=False)
        return vd if N is None else N @ vd + w

    def solve(self, ev, stabilize=True):
        """Accelerations and multipliers (least squares on ``A^T lam = f - M du/dt``), with the
        sign convention of :class:`LagrangeIndex1` (``M du/dt + A^T lam = f``)."""
        ud = self.accelerations(ev)
        A = ev.A
        if A.shape[0] == 0:
            return ud, np.zeros(0)
        lam = np.linalg.lstsq(A.T, ev.f - ev.M @ ud, rcond=None)[0]
        return ud, lam

    def fun(self, t, y):
        """``dy/dt`` for ``y = [q, v]``."""
        self.nfev += 1
        if not np.all(np.isfinite(y)):
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")
        q, v = self.split(y)
        u, ev = self.speeds(t, q, v)
        if ev is None or self.dep.size:
            ev = self.system.evaluate(t, q, u)
        ud = self.accelerations(ev)
        return np.concatenate((self.system.q_rate(q, u), ud[self.ind]))

    # --- manifold ----------------------------------------------------------------------------
    def project(self, t, y, tol=1e-12, max_iter=8):
        """Normalize quaternions and solve ``Phi(q) = 0`` for the dependent coordinates
        (Newton, independent coordinates held)."""
        sysm = self.system
        q, v = self.split(y)
        q = sysm.normalize(q)
        if self.system.topology.cut:
            u0 = np.zeros(self.nu)
            for _ in range(max_iter):
                ev = sysm.evaluate(t, q, u0)
                if ev.Phi.size == 0 or np.linalg.norm(ev.Phi) <= tol:
                    break
                # holonomic rows against the dependent columns: square for pure loops, least
                # squares (minimum norm) when nonholonomic rows claim dependent speeds too
                dq = np.zeros(self.nu)
                dq[self.dep] = -np.linalg.lstsq(ev.C[:, self.dep], ev.Phi, rcond=None)[0]
                q = sysm.increment(q, dq)
            else:
                ev = sysm.evaluate(t, q, u0)
                if np.linalg.norm(ev.Phi) > 1e3 * tol:
                    raise SimulationError(f"position correction did not converge at t={t:g} (residual "
                                          f"{np.linalg.norm(ev.Phi):.3g}); the mechanism may be near a singular position")
        return np.concatenate((q, v))

    def needs_repartition(self, t, y):
        """True when the dependent block of the constraint Jacobian was ill-conditioned at the
        last right-hand-side evaluation."""
        return self.dep.size > 0 and self._ill

    def repartition(self, t, y):
        """Choose the partition again at ``y``; returns the state in the new partition."""
        q, v = self.split(y)
        u, _ = self.speeds(t, q, v)
        ev = self.system.evaluate(t, q, u)
        self.dep, self.ind = self.partition(ev.A)
        self._ill = False
        self.repartitions += 1
        return np.concatenate((q, u[self.ind]))
