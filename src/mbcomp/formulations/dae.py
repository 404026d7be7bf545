"""The multiplier form as differential-algebraic equations of index 1, 2 (GGL) and 3.

:mod:`mbcomp.formulations` reduces the assembled system to ODEs (index-1 multipliers solved
inside the right-hand side, or D'Alembert projection). The classes here keep the
multipliers as unknowns, for DAE solvers (:mod:`mbcomp.solvers`), in the semi-explicit
form ``E dy/dt = fun(t, y)`` with ``E`` constant and diagonal:

=========================  ==========================================  ===========================
form                        state ``y`` and equations                   variable index
=========================  ==========================================  ===========================
:class:`Index3`             ``[q, u, a, lam]``:                          q 1, u 2, a 3, lam 3
                            ``q' = H(q) u``, ``u' = a``,                 (nonholonomic rows: 2)
                            ``0 = f - M a - A^T lam``, ``0 = Phi(t, q)``
                            (and ``0 = B u - b`` for velocity rows)
:class:`GGL`                ``[q, u, a, lam, eta]``:                     q 1, u 1, a 2, lam 2, eta 2
                            ``q' = H(q)(u - C^T eta)``, ``u' = a``,
                            ``0 = f - M a - A^T lam``,
                            ``0 = dPhi/dt``, ``0 = B u - b``,
                            ``0 = Phi(t, q)``  (Gear-Gupta-Leimkuhler)
:class:`Index1`             ``[q, u, a, lam]``:                          all 1
                            ``0 = f - M a - A^T lam``,
                            ``0 = A a + bias`` (+ Baumgarte terms)
=========================  ==========================================  ===========================

``A = [C; B]`` stacks the holonomic (loop-closure) and nonholonomic rows; ``lam`` has one
entry per row with the sign convention of :class:`~mbcomp.formulations.LagrangeIndex1`
(``M du/dt + A^T lam = f``), so reactions are the same in every form.
:class:`Mechanical` offers the same system in second-order form for the generalized-alpha
scheme (holonomic constraints only).

Every form has ``initial_state(t, q, u)`` (consistent ``y0`` from consistent positions and
speeds), ``full(t, y) -> [q, u]`` for output, and ``solve(ev)`` (accelerations and
multipliers at an output point, for reactions). Their ``fun`` counts evaluations in
``nfev``.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.daeforms import Index3
>>> from mbcomp.initialization import initialize
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> s = mbcomp.assemble(m); init = initialize(s)
>>> form = Index3(s); y0 = form.initial_state(0.0, init.q, init.u)
>>> form.n, form.index.tolist(), round(float(y0[2]), 6)     # [phi, w, a]: a = -g sin(phi)
(3, [1, 2, 3], -4.703165)
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError
from ..formulations.lagrange import LagrangeIndex1

__all__ = ["Index1", "GGL", "Index3", "Mechanical", "DAE_FORMS"]


class _MultiplierDAE:
    """Common parts: sizes, the index-1 solve for consistent accelerations, output mapping."""

    stabilization = "none"
    index_of_form = 0

    def __init__(self, system):
        self.system = system
        self.nq, self.nu = system.nq, system.nu
        ev = system.evaluate(0.0, system.default_q(), np.zeros(system.nu))  # row counts only
        self.mh, self.mn = ev.Phi.size, ev.Psi.size  # holonomic and nonholonomic rows (independent ones)
        self.m = self.mh + self.mn
        self.nfev = 0
        self.nlu = 0
        self._ode = LagrangeIndex1(system, "none")

    def solve(self, ev, stabilize=True):
        """Accelerations ``du/dt`` and multipliers at an evaluation (index-1 solve)."""
        self.nlu += 1
        return self._ode.solve(ev, stabilize=False)

    def _check(self, t, y):
        self.nfev += 1
        if not np.all(np.isfinite(y)):
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")

    def full(self, t, y):
        return np.asarray(y[: self.nq + self.nu])

    def project(self, t, y):
        return y

    def consistent(self, t, q, u):
        """``(a, lam)`` at consistent ``(q, u)``."""
        ev = self.system.evaluate(t, q, u)
        a, lam = self._ode.solve(ev, stabilize=False)
        return a, lam

    @property
    def mass(self):
        E = np.zeros(self.n)
        E[: self.nq + self.nu] = 1.0
        return E

    def _dyn(self, t, q, u, a, lam):
        ev = self.system.evaluate(t, q, u)
        return ev, ev.f - ev.M @ a - ev.A.T @ lam

    # --- Jacobian: finite differences only where fun is nonlinear -----------------------------
    def _linear_blocks(self, J, ev):
        """Fill the columns of ``a`` and ``lam`` (fun is linear in them) from ``M`` and ``A``."""
        nq, nu = self.nq, self.nu
        ia = slice(nq + nu, nq + 2 * nu)
        il = slice(nq + 2 * nu, nq + 2 * nu + self.m)
        J[:, ia] = 0.0
        J[:, il] = 0.0
        J[nq:nq + nu, ia] = np.eye(nu)
        J[ia, ia] = -ev.M
        J[ia, il] = -ev.A.T
        return ia, il

    def jac(self, t, y):
        """``d fun / d y`` (n, n): forward differences over ``q``, ``u`` (and GGL's ``eta``), the
        linear ``a`` and ``lam`` columns exactly from ``M`` and ``A``."""
        y = np.asarray(y, float)
        f0 = self.fun(t, y)
        J = np.empty((self.n, self.n))
        for i in self._fd_columns():
            h = 1.5e-8 * max(1.0, abs(y[i]))
            yy = y.copy()
            yy[i] += h
            J[:, i] = (self.fun(t, yy) - f0) / h
        q, u = y[: self.nq], y[self.nq: self.nq + self.nu]
        self._linear_blocks(J, self.system.evaluate(t, q, u))
        return J

    def _fd_columns(self):
        return range(self.nq + self.nu)


class Index3(_MultiplierDAE):
    """Index-3 form: position constraints ``Phi(t, q) = 0`` with ``[q, u, a, lam]`` as state.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.
    """

    index_of_form = 3

    def __init__(self, system):
        super().__init__(system)
        self.n = self.nq + 2 * self.nu + self.m
        self.index = np.concatenate((np.ones(self.nq, int), np.full(self.nu, 2), np.full(self.nu, 3),
                                     np.full(self.mh, 3), np.full(self.mn, 2)))

    def split(self, y):
        nq, nu = self.nq, self.nu
        return y[:nq], y[nq:nq + nu], y[nq + nu:nq + 2 * nu], y[nq + 2 * nu:]

    def initial_state(self, t, q, u):
        a, lam = self.consistent(t, q, u)
        return np.concatenate((q, u, a, lam))

    def fun(self, t, y):
        self._check(t, y)
        q, u, a, lam = self.split(y)
        ev, dyn = self._dyn(t, q, u, a, lam)
        return np.concatenate((self.system.q_rate(q, u), a, dyn, -ev.Phi, -ev.Psi))


class GGL(_MultiplierDAE):
    """Index-2 form of Gear, Gupta and Leimkuhler: velocity constraints enforced by ``lam``,
    position constraints by the extra multiplier ``eta`` that moves ``q`` along ``C^T``.

    On the exact solution ``eta = 0``; numerically it absorbs the drift so both
    ``Phi = 0`` and ``dPhi/dt = 0`` hold at every step.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.
    """

    index_of_form = 2

    def __init__(self, system):
        super().__init__(system)
        self.n = self.nq + 2 * self.nu + self.m + self.mh
        self.index = np.concatenate((np.ones(self.nq + self.nu, int), np.full(self.nu + self.m + self.mh, 2)))

    def split(self, y):
        nq, nu, m = self.nq, self.nu, self.m
        return y[:nq], y[nq:nq + nu], y[nq + nu:nq + 2 * nu], y[nq + 2 * nu:nq + 2 * nu + m], y[nq + 2 * nu + m:]

    def initial_state(self, t, q, u):
        a, lam = self.consistent(t, q, u)
        return np.concatenate((q, u, a, lam, np.zeros(self.mh)))

    def _fd_columns(self):
        return list(range(self.nq + self.nu)) + list(range(self.n - self.mh, self.n))

    def fun(self, t, y):
        self._check(t, y)
        q, u, a, lam, eta = self.split(y)
        ev, dyn = self._dyn(t, q, u, a, lam)
        w = u - ev.C.T @ eta if self.mh else u
        return np.concatenate((self.system.q_rate(q, w), a, dyn, -ev.Phid, -ev.Psi, -ev.Phi))


class Index1(_MultiplierDAE):
    """Index-1 form: constraints at acceleration level, ``a`` and ``lam`` algebraic.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.
    stabilization : {"baumgarte", "projection", "none"}
        As for :class:`~mbcomp.formulations.LagrangeIndex1`; ``"projection"`` is applied by
        the driver after each step (one-step solvers only).
    alpha, beta : float
        Baumgarte parameters (1/s).
    """

    index_of_form = 1

    def __init__(self, system, stabilization="baumgarte", alpha=10.0, beta=10.0):
        super().__init__(system)
        self.stabilization = stabilization
        self._stab = LagrangeIndex1(system, stabilization, alpha, beta)
        self.alpha, self.beta = float(alpha), float(beta)
        self.n = self.nq + 2 * self.nu + self.m
        self.index = np.ones(self.n, int)

    split = Index3.split
    initial_state = Index3.initial_state

    def _linear_blocks(self, J, ev):
        ia, il = super()._linear_blocks(J, ev)
        J[il, ia] = -ev.A  # the acceleration-level rows  -(A a + bias)
        return ia, il

    def fun(self, t, y):
        self._check(t, y)
        q, u, a, lam = self.split(y)
        ev, dyn = self._dyn(t, q, u, a, lam)
        bias = np.concatenate((ev.cb, ev.Bb))
        if self.stabilization == "baumgarte":
            bias = bias + np.concatenate((2.0 * self.alpha * ev.Phid + self.beta ** 2 * ev.Phi, self.alpha * ev.Psi))
        return np.concatenate((self.system.q_rate(q, u), a, dyn, -(ev.A @ a + bias)))

    def project(self, t, y):
        """Positions and speeds onto the constraint manifold, then consistent ``a``, ``lam``."""
        qu = self._stab.project(t, np.asarray(y[: self.nq + self.nu]))
        q, u = qu[: self.nq], qu[self.nq:]
        a, lam = self.consistent(t, q, u)
        return np.concatenate((q, u, a, lam))


class Mechanical(_MultiplierDAE):
    """Second-order form for :class:`~mbcomp.solvers.genalpha.GeneralizedAlpha`:
    ``M(q) du/dt + C^T lam = f``, ``Phi(t, q) = 0``; state ``[q, u, udot, a, lam]``.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized; velocity (nonholonomic) constraints are not
        supported by this form.
    """

    index_of_form = 3

    def __init__(self, system):
        super().__init__(system)
        if self.mn:
            raise ValueError("the generalized-alpha form handles holonomic constraints only; this model has "
                             f"{self.mn} velocity (nonholonomic) constraint rows -> use method='radau5' or 'ida'")
        self.n = self.nq + 3 * self.nu + self.mh

    def initial_state(self, t, q, u):
        a, lam = self.consistent(t, q, u)
        return np.concatenate((q, u, a, a, lam))

    def dynamics(self, t, q, u):
        """``(M, f, Phi, C)`` at ``(t, q, u)``."""
        self.nfev += 1
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(u))):
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")
        ev = self.system.evaluate(t, q, u)
        return ev.M, ev.f, ev.Phi, ev.C

    def increment(self, q, dq):
        return self.system.increment(q, dq)

    def q_rate(self, q, u):
        return self.system.q_rate(q, u)


DAE_FORMS = {1: Index1, 2: GGL, 3: Index3}
