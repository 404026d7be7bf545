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

from .errors import SimulationError

__all__ = ["LagrangeIndex1"]


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
            rhs_nh = rhs_nh - self.alpha * ev.g
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
        if d.min() <= 1e-13 * d.max():
            names = self.system.constraint_names() + [f"{e.name}.{r}" for e, rows, _ in ev.local_nh for r in rows]
            raise SimulationError(
                f"the constraint Jacobian lost rank at t={ev.t:g} (a singular position of the mechanism, "
                f"e.g. a loop passing a flat/dead-centre configuration; constraints: {', '.join(names)})")
        x = sla.lu_solve(lu, np.concatenate((f, rhs)), check_finite=False)
        return x[:n], x[n:]

    def rhs(self, t, y):
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
        if ev.Phi.size or ev.g.size:
            u = u - np.linalg.lstsq(ev.A, np.concatenate((ev.Phid, ev.g)), rcond=None)[0]
        return np.concatenate((q, u))
