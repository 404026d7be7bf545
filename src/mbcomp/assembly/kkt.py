"""The constrained solve: accelerations and multipliers from an evaluation (index 1, KKT).

At a state ``(t, q, u)`` the speeds' rates ``du/dt`` and the rows' multipliers ``[lam, mu]``
(N, N m: one per row in force) solve the saddle-point (Karush-Kuhn-Tucker) system::

    [ M  A^T ] [ du/dt ]   [ f   ]
    [ A   0  ] [ [lam; mu] ] = [ rhs ]

with ``A = [C; B]`` the holonomic and nonholonomic rows of an
:class:`~mbcomp.assembly.system.Evaluation` and ``rhs`` their acceleration-level right side,
``-[c_b; B_b]`` for the plain index-1 solve (:func:`accelerations`). The constraint force on
the tree coordinates is ``-A^T [lam; mu]``. Everything that needs consistent accelerations or
multipliers -- the Lagrange formulation (with Baumgarte terms in ``rhs``), a hybrid run's
pushes, contact forces and columns -- calls :func:`solve_kkt` here; the impulse solve, its
velocity-level counterpart, is :func:`mbcomp.assembly.impacts.impulse`.
:func:`project_state` moves a state onto the rows (positions, then speeds).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.assembly.kkt import accelerations
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = mbcomp.assemble(m)
>>> ud, lam = accelerations(system.evaluate(0.0, np.array([0.5]), np.array([0.0])))
>>> round(float(ud[0]), 6), lam.size          # du/dt = -g sin(phi) for l = 1 m; no rows
(-4.703165, 0)
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import SimulationError
from .manifold import close_positions, solve_speeds

__all__ = ["solve_kkt", "saddle_matrix", "saddle_point", "accelerations", "project_state"]


def _singular_mass(t):
    return SimulationError(f"the mass matrix is singular at t={t:g}: some coordinate carries no "
                           "inertia; give the bodies mass or prescribe that motion")


def solve_kkt(M, f, A, rhs, t, pass_rank=None):
    """``(du/dt, [lam; mu])`` of the saddle-point system with mass matrix ``M`` (nu, nu),
    forces ``f`` (nu,), rows ``A`` (m, nu) and right side ``rhs`` (m,) at time ``t`` (s; for
    the messages).

    ``pass_rank=None``: the full system by LU; where its pivots lost rank (below 1e-13 of the
    largest: often a trial stage of an explicit method far off the manifold, which error
    control rejects) the minimum-norm answer -- a singular position on the accepted path is
    reported by the run's singularity monitor. ``pass_rank`` (a float): by the range space
    ``G = A M^-1 A^T`` with the eigen-directions of ``G`` below ``pass_rank`` times its
    largest left out (their multipliers zero), so the motion passes a singular position.

    Raises
    ------
    SimulationError
        ``M`` is singular (no rows, or ``pass_rank`` given), or the saddle-point matrix is.
    """
    m = A.shape[0]
    if m == 0 or pass_rank is not None:
        try:
            c = sla.cho_factor(M)
        except np.linalg.LinAlgError:
            raise _singular_mass(t) from None
        x0 = sla.cho_solve(c, f)
        if m == 0:
            return x0, np.zeros(0)
        Y = sla.cho_solve(c, A.T)
        g, V = np.linalg.eigh(A @ Y)
        keep = g > pass_rank * max(g[-1], 0.0)
        r = V[:, keep].T @ (A @ x0 - rhs)
        lam = V[:, keep] @ (r / g[keep])
        return x0 - Y @ lam, lam
    n = M.shape[0]
    K = saddle_matrix(M, A)
    try:
        lu = sla.lu_factor(K, check_finite=False)
    except (ValueError, np.linalg.LinAlgError):
        raise SimulationError(f"the saddle-point matrix is singular at t={t:g}") from None
    d = np.abs(np.diag(lu[0]))
    b = np.concatenate((f, rhs))
    if d.min() <= 1e-13 * d.max():
        x = np.linalg.lstsq(K, b, rcond=1e-13)[0]
    else:
        x = sla.lu_solve(lu, b, check_finite=False)
    return x[:n], x[n:]


def saddle_matrix(M, A):
    """The saddle-point (KKT) matrix ``[[M, A^T], [A, 0]]`` of mass matrix ``M`` (nu, nu) and
    rows ``A`` (m, nu)."""
    n, m = M.shape[0], A.shape[0]
    K = np.zeros((n + m, n + m))
    K[:n, :n] = M
    K[:n, n:] = A.T
    K[n:, :n] = A
    return K


def saddle_point(ev):
    """``(K, b)``: the saddle-point matrix of the evaluation ``ev`` (:func:`saddle_matrix`) and
    its plain index-1 right side ``[f, -c_b, -B_b]``, for a solve with several right sides (a
    sliding contact's friction, linear in its normal force: :mod:`mbcomp.hybrid.slip`)."""
    return saddle_matrix(ev.M, ev.A), np.concatenate((ev.f, -ev.cb, -ev.Bb))


def accelerations(ev):
    """``(du/dt, [lam; mu])`` at the evaluation ``ev``: the plain index-1 solve (no
    stabilization terms), for consistent accelerations, multipliers and reactions."""
    return solve_kkt(ev.M, ev.f, ev.A, np.concatenate((-ev.cb, -ev.Bb)), ev.t)


def project_state(system, t, y):
    """``y = [q, u]`` moved onto ``Phi = 0`` and ``[dPhi/dt, Psi] = 0`` of ``system`` by
    minimum-norm corrections (Newton on the positions, then least squares on the speeds),
    quaternions normalized.

    Raises
    ------
    SimulationError
        The positions' Newton iteration did not converge (near a singular position).
    """
    q, u = system.normalize(y[: system.nq]), y[system.nq:]

    def residual(qq):
        ev = system.evaluate(t, qq, u)
        return ev.Phi, ev.C, ev

    c = close_positions(residual, system.increment, q)
    if not c.acceptable:
        raise SimulationError(f"position projection did not converge at t={t:g} (residual {c.norm:.3g}); "
                              "the mechanism may be near a singular position")
    ev = c.data
    u = solve_speeds(ev.A, np.concatenate((ev.Phid, ev.Psi)), u)
    return np.concatenate((c.q, u))
