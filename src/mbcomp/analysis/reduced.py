"""The reduced dynamics around a state: independent directions, the manifold, their rates.

About a state ``(q0, u0)`` the speeds are split by their role:

* *moving* directions have nonzero speed (``|u| > rest_tol * max(1, |u0|)``); they must be
  cyclic and are no states;
* among the directions at rest, the holonomic rows ``C`` choose *dependent* position
  directions (pivoted QR, :func:`mbcomp.assembly.manifold.pivot_partition`); the others are
  the independent position increments;
* the velocity rows ``A`` (holonomic and nonholonomic) choose dependent speeds among all;
  the others are the independent speeds.

A perturbed state (independent increments ``dpos``, independent speed changes ``dv``) is put
back on the constraint manifold: positions by Newton along the dependent directions, closed to
rounding (``exact=True``: the linearization's central differences divide by ``h ~ 1e-4``),
dependent speeds by one exact solve of the velocity rows. Its rates come from the full
saddle-point system (index-1 Lagrange), so multiplier terms are kept exactly.
:meth:`Reduced.jacobian` differences that map; :meth:`Reduced.exact` differentiates it
exactly from the evaluation's derivative program (the implicit function theorem on the
rows, the saddle-point system differentiated).

Examples
--------
>>> import mbcomp, numpy as np
>>> from mbcomp.analysis.reduced import Reduced, direction_names
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
>>> rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0))); bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> from mbcomp.assembly.initialization import initialize
>>> s = mbcomp.assemble(m); init = initialize(s)
>>> red = Reduced(s, 0.0, init.q, init.u)
>>> direction_names(s), red.n
(['hinge.phi'], 2)
>>> round(float(red.rate(np.array([0.01, 0.0]))[1]), 6)  # -g/l sin(0.01)
-0.196197
"""
from __future__ import annotations

import numpy as np

from ..assembly.manifold import SingularPartition, close_positions, pivot_partition, solve_speeds
from ..errors import SimulationError
from ..assembly.kkt import accelerations, saddle_matrix

__all__ = ["Reduced", "direction_names", "dependent_directions", "CLOSE_ITER"]

#: Newton steps at most in a closure: with ``exact=True`` (positions closed to rounding, see
#: ``manifold.EXACT_STEP``) a perturbation of 1e-4 takes 2-3 steps and the ignorability
#: test's 0.1 about 6, then rounding-sized steps until one is below ``EXACT_STEP``.
CLOSE_ITER = 30


class _NoExact(Exception):
    """A derivative program does not hold at the state (a failed guard, a non-finite value)."""


def direction_names(system):
    """Names of the ``nu`` position-increment directions (one per speed).

    Joints whose coordinates and speeds pair one to one give the coordinate
    (``hinge.phi``); quaternion joints give rotation-vector components in body axes
    (``free.rot.x``), translations along their speeds (``free.r.x``), anything else ``d<speed>``.
    """
    names = [None] * system.nu
    for e in system.topology.tree:
        if e.u.stop <= e.u.start:
            continue
        c = e.comp
        if c.nq == c.nu:
            for k, (n, _) in enumerate(c.coordinates):
                names[e.u.start + k] = f"{e.name}.{n}"
        else:
            for k, (n, _) in enumerate(c.speeds):
                if n.startswith("w."):
                    n = "rot." + n[2:]
                elif n.startswith("v."):
                    n = "r." + n[2:]
                else:
                    n = f"d{n}"
                names[e.u.start + k] = f"{e.name}.{n}"
    return names


def dependent_directions(A, allowed, what):
    """Columns of ``A`` (restricted to ``allowed``) chosen by pivoted QR as dependent.

    Parameters
    ----------
    A : ndarray (m, nu)
        Constraint rows: ``C`` (``what="position"``) or ``[C; B]`` (``what="speed"``).
    allowed : index array
        Directions that may be dependent.
    what : str
        Names the rows in the error.

    Returns
    -------
    (dep, ind) : sorted index arrays
        The dependent directions and the rest of ``allowed``.

    Raises
    ------
    SimulationError
        Fewer directions than rows, or the rows are singular on ``allowed``.
    """
    m = A.shape[0]
    allowed = np.asarray(allowed, int)
    if allowed.size < m:
        raise SimulationError(f"linearization: {m} {what} constraint rows but only {allowed.size} directions at rest "
                              "to satisfy them")
    try:
        return pivot_partition(A, m, allowed)
    except SingularPartition:
        raise SimulationError(f"linearization: the {what} constraints are singular at this state (or need a "
                              "moving coordinate to be satisfied); choose another steady state") from None


class Reduced:
    """Maps independent position increments and speeds onto the constraint manifold and
    returns their rates.

    Parameters
    ----------
    system : MultibodySystem
        Initialized (``row_mask`` set).
    t : float
        Time, s.
    q0, u0 : ndarray
        The state to perturb about.
    rest_tol : float
        Relative speed below which a direction is at rest.

    Attributes
    ----------
    moving, pind, pdep, vind, vdep : index arrays
        Moving, independent and dependent position directions, independent and dependent speeds.
    n : int
        Number of states: ``pind.size + vind.size``.
    """

    def __init__(self, system, t, q0, u0, rest_tol=1e-10):
        self.s, self.t, self.q0, self.u0 = system, float(t), np.array(q0, float), np.array(u0, float)
        nu = system.nu
        ev = system.evaluate(self.t, self.q0, self.u0)
        scale = max(1.0, float(np.abs(self.u0).max(initial=0.0)))
        moving = np.abs(self.u0) > rest_tol * scale
        self.moving = np.where(moving)[0]
        rest = np.where(~moving)[0]
        if ev.C.shape[0]:  # holonomic rows: dependent position directions among those at rest
            self.pdep, self.pind = dependent_directions(ev.C, rest, "position")
        else:
            self.pdep, self.pind = np.zeros(0, int), rest
        if ev.A.shape[0]:
            self.vdep, self.vind = dependent_directions(ev.A, np.arange(nu), "speed")
        else:
            self.vdep, self.vind = np.zeros(0, int), np.arange(nu)
        self.n = self.pind.size + self.vind.size

    # --- state -> (q, u) ---------------------------------------------------------------------
    def positions(self, dpos, moving=None):
        """Coordinates with the independent increments ``dpos`` (and optional increments of
        the moving directions), projected onto ``Phi = 0`` along the dependent directions."""
        s = self.s
        d = np.zeros(s.nu)
        d[self.pind] = dpos
        if moving is not None:
            d[self.moving] = moving
        q = s.increment(self.q0, d)
        if not self.pdep.size:
            return q
        zero = np.zeros(s.nu)

        def residual(qq):
            ev = s.evaluate(self.t, qq, zero)
            return ev.Phi, ev.C, None

        closure = close_positions(residual, s.increment, q, columns=self.pdep, max_iter=CLOSE_ITER, exact=True)
        if not closure.converged:
            raise SimulationError("linearization: the position constraints could not be closed near the "
                                  "steady state (a singular position?)")
        return closure.q

    def speeds(self, q, dv):
        """Speeds with the independent ones moved by ``dv``, the dependent ones solved from the
        velocity constraints (linear in ``u``: one solve is exact); returns ``(u, evaluation)``."""
        s = self.s
        u = self.u0.copy()
        u[self.vind] += dv
        ev = s.evaluate(self.t, q, u)
        if self.vdep.size:
            u = solve_speeds(ev.A, np.concatenate((ev.Phid, ev.Psi)), u, self.vdep)
            ev = s.evaluate(self.t, q, u)
        return u, ev

    def rate(self, x, moving=None):
        """``d/dt`` of the states ``x`` (independent increments, then independent speeds)."""
        npos = self.pind.size
        q = self.positions(x[:npos], moving)
        u, ev = self.speeds(q, x[npos:])
        ud, _ = accelerations(ev)
        return np.concatenate((u[self.pind], ud[self.vind]))

    # --- exact derivatives ---------------------------------------------------------------------
    def exact(self, derivatives):
        """The exact state matrix ``d rate/dx`` at ``x = 0`` and ``d rate/d moving`` (the
        moving directions' increments), from the evaluation's derivatives; None where they
        do not hold (the caller differences).

        ``derivatives`` is a :class:`mbcomp.codegen.eval_tangent.BoundEvalTangent`:
        ``jvp(t, q, u, a, lam, dq, du)`` gives the derivatives of the balance ``R1 = f - M a -
        A^T lam``, the acceleration rows ``R2 = -[c_b; B_b] - A a`` and the velocity rows ``G =
        [dPhi/dt; Psi]`` along a direction, ``Q(q)`` how the coordinates move along the speeds.
        The map from ``x`` to the state is differentiated by the implicit function theorem,
        the rates by differentiating the saddle-point system (``a``, ``lam``: its solution at
        the state; the values there from the jet recursion, ``evaluate_numeric``)::

            dq_dep = -C_dep^-1 C_D dq_D                   (Phi = 0 along the dependent directions)
            du_dep = -A_dep^-1 dG(dq, du_ind)             (the velocity rows [dPhi/dt; Psi] = 0)
            [M A^T; A 0] [d(du/dt); d lam] = [dR1; dR2](dq, du)

        with ``dq`` in increments along the speeds (coordinates ``Q dq``): two
        Jacobian-vector products per state (one where no speed is dependent). Returns
        ``(A, A_moving)`` (1/s, 1/s^2: rates per state unit).

        Examples
        --------
        >>> import mbcomp, numpy as np
        >>> from mbcomp.analysis.reduced import Reduced
        >>> from mbcomp.assembly.initialization import initialize
        >>> from mbcomp.codegen.eval_tangent import eval_tangent
        >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
        >>> hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
        >>> rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0))); bob = m.add("bob", PointMass(m=1.0))
        >>> m.connect(w.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
        >>> s = mbcomp.assemble(m); init = initialize(s)
        >>> A, _ = Reduced(s, 0.0, init.q, init.u).exact(eval_tangent(s))
        >>> A.tolist()                  # [[0, 1], [-g/l, 0]]
        [[0.0, 1.0], [-19.62, 0.0]]
        """
        s, nu, nq, npos = self.s, self.s.nu, self.s.nq, self.pind.size
        q = self.positions(np.zeros(npos))
        u, _ = self.speeds(q, np.zeros(self.vind.size))
        # the values at the state from the jet recursion, the reference the programs are
        # checked against: one evaluation, and the bicycle's eigenvalues came 20-30x closer to
        # the 40-digit benchmark (5e-15 instead of 1.1e-13 at 5 m/s) than with the generated
        # program's values, whose rounding (1e-14 relative in A) was then all the error left
        ev = s.evaluate_numeric(self.t, q, u)
        try:
            ud, lam = accelerations(ev)
        except SimulationError:
            return None
        mask = s.row_mask
        m_all = ev.C.shape[0] if mask is None else len(mask)
        rows = np.concatenate((np.arange(m_all) if mask is None else np.flatnonzero(mask),
                               m_all + np.arange(ev.B.shape[0]))).astype(int)
        lam_all = np.zeros(m_all + ev.B.shape[0])
        lam_all[rows] = lam
        Q = derivatives.Q(q)
        if Q is None:
            return None
        A, K = ev.A, saddle_matrix(ev.M, ev.A)
        try:
            Cdep = np.linalg.inv(ev.C[:, self.pdep]) if self.pdep.size else None
            Adep = np.linalg.inv(A[:, self.vdep]) if self.vdep.size else None
        except np.linalg.LinAlgError:
            return None

        def column(d, dv):
            """The rates' derivative for the position increment ``d`` (nu) before closure and
            the speed change ``dv`` (nu) before the dependent speeds are solved."""
            if Cdep is not None:
                d = d.copy()
                d[self.pdep] = -Cdep @ (ev.C @ d)
            dq = Q @ d
            out = derivatives.jvp(self.t, q, u, ud, lam_all, dq, dv)
            if out is not None and Adep is not None:
                dv = dv.copy()
                dv[self.vdep] = -Adep @ out[2][rows]
                out = derivatives.jvp(self.t, q, u, ud, lam_all, dq, dv)
            if out is None:
                raise _NoExact
            return dv, np.concatenate((out[0], out[1][rows]))

        E, zero = np.eye(nu), np.zeros(nu)
        try:
            cols = [column(E[j], zero) for j in self.pind] + [column(zero, E[j]) for j in self.vind]
            moving = [column(E[j], zero) for j in self.moving]
            rhs = np.column_stack([c[1] for c in cols + moving]) if cols or moving else np.zeros((K.shape[0], 0))
            dud = np.linalg.solve(K, rhs)[:nu] if rhs.size else rhs[:nu]
        except (_NoExact, np.linalg.LinAlgError):
            return None
        du = np.column_stack([c[0] for c in cols + moving]) if cols or moving else np.zeros((nu, 0))
        out = np.vstack((du[self.pind], dud[self.vind]))
        return out[:, : len(cols)], out[:, len(cols):]

    @staticmethod
    def jacobian(f, n, scale):
        """Central differences with one Richardson step: ``(4 D(h/2) - D(h)) / 3``, ``h = 1e-4 scale``."""
        x0 = np.zeros(n)
        cols = []
        for j in range(n):
            h = 1e-4 * scale[j]

            def D(hh, j=j):
                e = np.zeros(n)
                e[j] = hh
                return (f(x0 + e) - f(x0 - e)) / (2 * hh)

            cols.append((4 * D(h / 2) - D(h)) / 3)
        return np.column_stack(cols) if cols else np.zeros((0, 0))
