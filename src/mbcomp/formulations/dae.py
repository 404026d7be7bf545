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

``A = [C; B]`` stacks the holonomic (loop-closure) and nonholonomic rows; ``lam`` stacks their
multipliers (the loop-closure ones, then the nonholonomic ``mu``) with the sign convention of
:class:`~mbcomp.formulations.LagrangeIndex1` (``M du/dt + A^T lam = f``), so reactions are
the same in every form. :class:`Mechanical` offers the same system in second-order form for
the generalized-alpha scheme (holonomic constraints only).

Every form is a :class:`~mbcomp.formulations.Formulation`: ``initial_state(t, q, u)``
(consistent ``y0`` from consistent positions and speeds), ``full(t, y) -> [q, u]`` for
output, and ``solve(ev)`` (accelerations and multipliers at an output point, for
reactions). Their ``fun`` counts evaluations in ``nfev``.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.formulations.dae import Index3
>>> from mbcomp.assembly.initialization import initialize
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

from ..assembly.kkt import accelerations, project_state
from ..errors import SimulationError
from .base import Formulation, projection_needed
from .lagrange import LagrangeIndex1

__all__ = ["Index1", "GGL", "Index3", "Mechanical", "DAE_FORMS"]


class _Multipliers(Formulation):
    """Common parts: row counts and the index-1 solve for consistent accelerations and multipliers."""

    def __init__(self, system):
        super().__init__(system)
        ev = system.evaluate(0.0, system.default_q(), np.zeros(system.nu))  # row counts only
        self.mh, self.mn = ev.Phi.size, ev.Psi.size  # holonomic and nonholonomic rows (independent ones)
        self.m = self.mh + self.mn
        self.njac_exact = self.njac_differences = 0  # Jacobians from the exact program, by differences

    def run_stats(self):
        """``jac_exact`` and ``jac_differences``: the Jacobians (iteration matrices for
        :class:`Mechanical`) made by the exact program and by differences (none asked: {})."""
        if not (self.njac_exact or self.njac_differences):
            return {}
        return {"jac_exact": self.njac_exact, "jac_differences": self.njac_differences}

    def _exact_program(self, name):
        """The bound exact Jacobian program ``name`` of the system (looked up once per row
        mask), or None: a numeric evaluator, or an evaluation that cannot be differentiated."""
        mask = self.system.row_mask
        cached = self.__dict__.get("_exact_prog")
        if cached is None or cached[0] is not mask:
            make = getattr(self.system.evaluator, "dae_jacobian", None)
            cached = self._exact_prog = (mask, make(name) if make is not None else None)
        return cached[1]

    def solve(self, ev, stabilize=True):
        """Accelerations ``du/dt`` and multipliers at an evaluation (index-1 solve)."""
        self.nlu += 1
        return accelerations(ev)

    def consistent(self, t, q, u):
        """``(a, lam)`` at consistent ``(q, u)``: accelerations (m/s^2, rad/s^2) and multipliers."""
        return accelerations(self.system.evaluate(t, q, u))


class _SemiExplicit(_Multipliers):
    """``E dy/dt = fun(t, y)`` with ``y = [q, u, a, lam, ...]``: ``E``, the dynamic rows, the Jacobian."""

    problem = "dae"

    @property
    def mass(self):
        """Diagonal of ``E``: 1 for the differential rows (``q``, ``u``), 0 for the algebraic ones."""
        E = np.zeros(self.n)
        E[: self.nq + self.nu] = 1.0
        return E

    def _split(self, y):
        """``(q, u, a, lam)``, and GGL's ``eta`` in ``lam``'s tail when present."""
        nq, nu = self.nq, self.nu
        return y[:nq], y[nq:nq + nu], y[nq + nu:nq + 2 * nu], y[nq + 2 * nu:]

    def initial_state(self, t, q, u):
        """``[q, u, a, lam]`` with the accelerations and multipliers of the index-1 solve."""
        a, lam = self.consistent(t, q, u)
        return np.concatenate((q, u, a, lam))

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

    # --- the residual and Jacobian in one C call (capability "dae_fun") -----------------------
    #: the form's number in the C runtime (``MBRT_DAE_*``: 1 Index1, 2 GGL, 3 Index3)
    _c_form = None

    def _c_gains(self):
        """The Baumgarte gains the C residual adds (Index1 with ``"baumgarte"``), else None."""
        return None

    def _c_call(self, t, y, jac=False):
        """``(F, J)`` from one C call (:class:`mbcomp.codegen.engine.DAEProgram`: the same
        residual, the same finite-difference columns and exact linear blocks), or None: no
        such program (numeric or Python backend), or a failed guard / non-finite value at
        this ``y`` (then the Python path answers)."""
        mask = self.system.row_mask
        cached = self.__dict__.get("_c_prog")
        if cached is None or cached[0] is not mask:
            ev = self.system.evaluator
            offers = getattr(ev, "offers", None)
            ok = offers("dae_fun") if offers is not None else "dae_fun" in ev.capabilities
            cached = self._c_prog = (mask, ev.dae_program(self._c_form, self._c_gains()) if ok else None)
        prog = cached[1]
        if prog is None:
            return None
        status, F, J, nfev = prog(t, y, jac)
        if status:
            self.system.evaluator.stats["fallbacks"] += 1
            return None
        self.nfev += nfev - 1  # the caller counted one
        return F, J

    #: the form's name for the exact Jacobian program (:mod:`mbcomp.codegen.dae_jacobian`)
    _exact_form = None

    @property
    def exact_jac(self):
        """Whether :meth:`jac` has an exact Jacobian program (the system runs a generated
        evaluation that could be differentiated); at a state where it does not hold (a
        failed guard, a non-finite entry) :meth:`jac` still differences."""
        return self._exact_program(self._exact_form) is not None

    def jac(self, t, y):
        """``d fun / d y`` (n, n): exact, from the generated Jacobian program
        (:meth:`mbcomp.codegen.evaluator.ProgramEvaluator.dae_jacobian`) when the system runs
        a generated evaluation; else (the numeric backend, a state where the program does not
        hold) forward differences over ``q``, ``u`` (and GGL's ``eta``) with the linear ``a``
        and ``lam`` columns exactly from ``M`` and ``A``. :meth:`run_stats` counts which."""
        y = np.asarray(y, float)
        if not np.isfinite(y).all():
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")
        prog = self._exact_program(self._exact_form)
        if prog is not None:
            J = prog(t, y, self._c_gains())
            if J is not None:
                self.njac_exact += 1
                return J
        self.njac_differences += 1
        self._check_finite(t, y)
        r = self._c_call(t, y, jac=True)
        if r is not None:
            return r[1]
        self.nfev -= 1  # counted again by fun in difference_columns
        J = self.difference_columns(t, y, self._fd_columns(), np.empty((self.n, self.n)))
        q, u = y[: self.nq], y[self.nq: self.nq + self.nu]
        self._linear_blocks(J, self.system.evaluate(t, q, u))
        return J

    def _fd_columns(self):
        return range(self.nq + self.nu)


class Index3(_SemiExplicit):
    """Index-3 form: position constraints ``Phi(t, q) = 0`` with ``[q, u, a, lam]`` as state.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.formulations.dae import Index3
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> form = Index3(mbcomp.assemble(m))
    >>> y0 = form.initial_state(0.0, np.zeros(1), np.zeros(1))     # [s, v, a]: free fall, no constraint rows
    >>> form.n, form.problem, form.index.tolist(), y0.round(12).tolist()
    (3, 'dae', [1, 2, 3], [0.0, 0.0, -9.81])
    >>> r = form.fun(0.0, y0)                        # [ds/dt, dv/dt, f - M a]: the dynamic row holds
    >>> r[:2].round(12).tolist(), bool(abs(r[2]) < 1e-12)
    ([0.0, -9.81], True)
    """

    def __init__(self, system):
        super().__init__(system)
        self.n = self.nq + 2 * self.nu + self.m
        self.index = np.concatenate((np.ones(self.nq, int), np.full(self.nu, 2), np.full(self.nu, 3),
                                     np.full(self.mh, 3), np.full(self.mn, 2)))

    _c_form = 3
    _exact_form = "index3"

    def fun(self, t, y):
        """``[dq/dt, du/dt, f - M a - A^T lam, -Phi, -Psi]``; ``E`` keeps the first two."""
        self._check_finite(t, y)
        r = self._c_call(t, y)
        if r is not None:
            return r[0]
        q, u, a, lam = self._split(y)
        ev, dyn = self._dyn(t, q, u, a, lam)
        return np.concatenate((self.system.q_rate(q, u), a, dyn, -ev.Phi, -ev.Psi))


class GGL(_SemiExplicit):
    """Index-2 form of Gear, Gupta and Leimkuhler: velocity constraints enforced by ``lam``,
    position constraints by the extra multiplier ``eta`` that moves ``q`` along ``C^T``.

    On the exact solution ``eta = 0``; numerically it absorbs the drift so both
    ``Phi = 0`` and ``dPhi/dt = 0`` hold at every step.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.formulations.dae import GGL
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> form = GGL(mbcomp.assemble(m))
    >>> form.n, form.mh, form.index.tolist()      # an open tree: no rows, so no lam and no eta
    (3, 0, [1, 1, 2])
    """

    def __init__(self, system):
        super().__init__(system)
        self.n = self.nq + 2 * self.nu + self.m + self.mh
        self.index = np.concatenate((np.ones(self.nq + self.nu, int), np.full(self.nu + self.m + self.mh, 2)))

    def initial_state(self, t, q, u):
        """``[q, u, a, lam, eta]`` with ``eta = 0``."""
        return np.concatenate((super().initial_state(t, q, u), np.zeros(self.mh)))

    def _fd_columns(self):
        return list(range(self.nq + self.nu)) + list(range(self.n - self.mh, self.n))

    _c_form = 2
    _exact_form = "ggl"

    def fun(self, t, y):
        """``[H(q)(u - C^T eta), du/dt, f - M a - A^T lam, -dPhi/dt, -Psi, -Phi]``."""
        self._check_finite(t, y)
        r = self._c_call(t, y)
        if r is not None:
            return r[0]
        q, u, a, rest = self._split(y)
        lam, eta = rest[: self.m], rest[self.m:]
        ev, dyn = self._dyn(t, q, u, a, lam)
        w = u - ev.C.T @ eta if self.mh else u
        return np.concatenate((self.system.q_rate(q, w), a, dyn, -ev.Phid, -ev.Psi, -ev.Phi))


class Index1(_SemiExplicit):
    """Index-1 form: constraints at acceleration level, ``a`` and ``lam`` algebraic.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized.
    stabilization : {"baumgarte", "projection", "none"}
        As for :class:`~mbcomp.formulations.LagrangeIndex1`; with ``"projection"`` the driver
        calls :meth:`project` after each step.
    alpha, beta : float
        Baumgarte parameters (1/s).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.formulations.dae import Index1
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> form = Index1(mbcomp.assemble(m), "projection")
    >>> form.index.tolist(), form.mass.tolist(), form.projects    # nothing to project on an open chain
    ([1, 1, 1], [1.0, 1.0, 0.0], False)
    """

    def __init__(self, system, stabilization="baumgarte", alpha=10.0, beta=10.0):
        super().__init__(system)
        if stabilization not in LagrangeIndex1.stabilizations:
            raise ValueError(f"stabilization {stabilization!r} is unknown; use one of {LagrangeIndex1.stabilizations}")
        self.stabilization = stabilization
        self.alpha, self.beta = float(alpha), float(beta)
        self.n = self.nq + 2 * self.nu + self.m
        self.index = np.ones(self.n, int)

    @property
    def projects(self):
        """As for :class:`~mbcomp.formulations.LagrangeIndex1`."""
        return self.stabilization == "projection" and projection_needed(self.system)

    def _linear_blocks(self, J, ev):
        ia, il = super()._linear_blocks(J, ev)
        J[il, ia] = -ev.A  # the acceleration-level rows  -(A a + bias)
        return ia, il

    _c_form = 1
    _exact_form = "index1"

    def _c_gains(self):
        return (self.alpha, self.beta) if self.stabilization == "baumgarte" else None

    def fun(self, t, y):
        """``[dq/dt, du/dt, f - M a - A^T lam, -(A a + bias)]`` (bias with the Baumgarte terms)."""
        self._check_finite(t, y)
        r = self._c_call(t, y)
        if r is not None:
            return r[0]
        q, u, a, lam = self._split(y)
        ev, dyn = self._dyn(t, q, u, a, lam)
        bias = np.concatenate((ev.cb, ev.Bb))
        if self.stabilization == "baumgarte":
            bias = bias + np.concatenate((2.0 * self.alpha * ev.Phid + self.beta ** 2 * ev.Phi, self.alpha * ev.Psi))
        return np.concatenate((self.system.q_rate(q, u), a, dyn, -(ev.A @ a + bias)))

    def project(self, t, y):
        """Positions and speeds onto the constraint manifold, then consistent ``a``, ``lam``."""
        qu = project_state(self.system, t, np.asarray(y[: self.nq + self.nu]))
        return self.initial_state(t, qu[: self.nq], qu[self.nq:])


class Mechanical(_Multipliers):
    """Second-order form for :class:`~mbcomp.solvers.genalpha.GeneralizedAlpha`:
    ``M(q) du/dt + C^T lam = f``, ``Phi(t, q) = 0``; state ``[q, u, udot, a, lam]``.

    Parameters
    ----------
    system : MultibodySystem
        Assembled and consistently initialized; velocity (nonholonomic) constraints are not
        supported by this form.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.formulations.dae import Mechanical
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> form = Mechanical(mbcomp.assemble(m))
    >>> form.problem, form.initial_state(0.0, np.array([1.0]), np.array([0.5])).round(12).tolist()  # [q, u, udot, a]
    ('mechanical', [1.0, 0.5, -9.81, -9.81])
    """

    problem = "mechanical"

    def __init__(self, system):
        super().__init__(system)
        if self.mn:
            raise ValueError("the generalized-alpha form handles holonomic constraints only; this model has "
                             f"{self.mn} velocity (nonholonomic) constraint rows -> use method='radau5' or 'ida'")
        self.n = self.nq + 3 * self.nu + self.mh

    def initial_state(self, t, q, u):
        """``[q, u, udot, a, lam]`` with ``udot = a`` from the index-1 solve."""
        a, lam = self.consistent(t, q, u)
        return np.concatenate((q, u, a, a, lam))

    def dynamics(self, t, q, u):
        """``(M, f, Phi, C)`` at ``(t, q, u)``."""
        self.nfev += 1
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(u))):
            raise SimulationError(f"the state became non-finite at t={t:g} (the integration diverged)")
        ev = self.system.evaluate(t, q, u)
        return ev.M, ev.f, ev.Phi, ev.C

    def tangents(self, t, q, u, udot, lam):
        """``(K, Ct)``, ``(nu, nu)`` each, exact from the generated program: ``K = d(M udot +
        C^T lam - f)/dq`` through :meth:`increment` (N per unit speed-space increment) and
        ``Ct = -df/du`` (N s), for the generalized-alpha iteration matrix; None where there is
        no program (numeric backend) or it does not hold at ``(q, u)`` (then the stepper
        differences :meth:`dynamics`). Counted in :meth:`run_stats`."""
        prog = self._exact_program("mechanical")
        KC = prog.mechanical(t, q, u, udot, lam) if prog is not None else None
        if KC is None:
            self.njac_differences += 1
        else:
            self.njac_exact += 1
        return KC

    def increment(self, q, dq):
        """``q`` moved by ``dq`` given in speed space (quaternions stay unit)."""
        return self.system.increment(q, dq)

    def q_rate(self, q, u):
        """``dq/dt`` from the speeds."""
        return self.system.q_rate(q, u)


DAE_FORMS = {1: Index1, 2: GGL, 3: Index3}
