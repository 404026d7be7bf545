"""The constraint manifold: close positions, solve dependent speeds, choose dependent coordinates.

Every place that puts a state back on the constraints uses these three functions:
consistent initialization, the projection of both formulations after a step, the D'Alembert
dependent speeds, and the linearization's perturbed states. Before, each had its own Newton
loop, its own solve and its own pivoted QR, with five different tolerances.

Tolerances, each with its reason
--------------------------------
``POSITION_TOL = 1e-12``
    Norm of the position-constraint residual ``Phi`` (m for translations, rad for
    rotations) at which a Newton closure stops. It is four orders below the tightest
    integrator ``atol`` the project uses (1e-14 on speeds aside, positions are compared at
    1e-10 and looser), and about 1e4 times rounding of unit-size coordinates, so Newton
    reaches it in one or two steps from an integrator step's drift.
``ACCEPT_FACTOR = 1e3``
    A closure that ends within ``ACCEPT_FACTOR * tol`` after its iterations is accepted:
    quadratic convergence stalls at rounding of the residual's own scale (long links, big
    coordinates), and 1e-9 is still far below what any output reports. Beyond it the
    mechanism is near a singular position and the caller says so.
``EXACT_STEP = 1e-16``
    The linearization needs positions closed to rounding, because its central differences
    divide by ``h ~ 1e-4``: closures with ``exact=True`` go on after ``tol`` until the Newton
    step itself is below this (rounding of unit-size coordinates) or no longer halves the
    residual. The second test ends the closure at the residual's rounding floor: on
    coordinates of 1-3 (a four-bar's angles) rounding-sized steps are a few 1e-16 and often
    stay above ``EXACT_STEP``; without it 7 of the 9 closures of the hanging four-bar's
    linearization ran all their 30 steps.
``PIVOT_TOL = 1e-10``
    Relative size of the last kept diagonal entry of the pivoted QR factor ``R`` below which a
    partition is refused as singular: the dependent block's condition number would exceed
    1e10 and the solved dependent speeds would keep fewer than ~6 correct digits.
``RANK_TOL = 1e-9``
    Relative singular value below which a constraint row counts as redundant at the
    assembled configuration. A four-bar 1e-8 m from flat still has relative singular values
    ~4e-5; rows of a planar loop written with 3-D joints are dependent to rounding (1e-16).

Examples
--------
>>> import numpy as np
>>> from mbcomp.assembly.manifold import close_positions, pivot_partition, solve_speeds
>>> # the unit circle x^2 + y^2 = 1 as a "constraint" on q = (x, y), moving y only
>>> def residual(q):
...     return np.array([q @ q - 1.0]), np.array([2 * q]), None
>>> c = close_positions(residual, lambda q, dq: q + dq, np.array([0.6, 0.9]), columns=np.array([1]))
>>> c.converged, round(float(c.q[1]), 12)
(True, 0.8)
>>> A = np.array([[1.0, 2.0, 0.0]])
>>> pivot_partition(A)          # the best-conditioned column is dependent
(array([1]), array([0, 2]))
>>> u = np.array([1.0, 1.0, 5.0])  # the row u_x + 2 u_y = 0 is violated by 3; u_y is dependent
>>> solve_speeds(A, A @ u, u, np.array([1])).tolist()
[1.0, -0.5, 5.0]
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import scipy.linalg as sla

__all__ = ["Closure", "close_positions", "solve_speeds", "pivot_partition", "rank", "SingularPartition",
           "POSITION_TOL", "ACCEPT_FACTOR", "EXACT_STEP", "PIVOT_TOL", "RANK_TOL"]

POSITION_TOL = 1e-12
ACCEPT_FACTOR = 1e3
EXACT_STEP = 1e-16
PIVOT_TOL = 1e-10
RANK_TOL = 1e-9


class SingularPartition(ValueError):
    """No set of dependent columns exists: the constraint Jacobian has lost rank."""


@dataclass(frozen=True)
class Closure:
    """Where a position closure ended.

    Attributes
    ----------
    q : ndarray
        Coordinates reached.
    r : ndarray
        Residual there (``Phi`` and whatever rows the caller's residual adds).
    J : ndarray
        Its Jacobian with respect to the speeds (rows of ``r`` by ``nu``).
    data : object
        Whatever the caller's residual returned third at ``q`` (usually the evaluation).
    norm : float
        ``||r||``.
    iterations : int
        Newton steps taken.
    tol : float
        The tolerance it was asked for.
    converged : bool
        ``norm <= tol``.
    tol : float
        The tolerance it was asked for (``acceptable`` allows ``ACCEPT_FACTOR`` times it).
    """

    q: np.ndarray
    r: np.ndarray
    J: np.ndarray
    data: Any
    norm: float
    iterations: int
    converged: bool

    @property
    def acceptable(self):
        """Converged, or within ``ACCEPT_FACTOR`` of the tolerance it was asked for."""
        return self.converged or self.norm <= ACCEPT_FACTOR * self.tol

    tol: float = POSITION_TOL


def close_positions(residual: Callable, increment: Callable, q, *, columns=None, tol=POSITION_TOL, max_iter=8,
                    line_search=False, exact=False) -> Closure:
    """Gauss-Newton on ``residual(q) = 0`` with minimum-norm steps in the speed directions ``columns``.

    Parameters
    ----------
    residual : callable
        ``residual(q) -> (r, J, data)``: residual rows, their Jacobian with respect to the
        speeds (rows x nu) and anything to hand back (e.g. the evaluation).
    increment : callable
        ``increment(q, du) -> q``: the system's position update along speed directions
        (quaternions stay unit).
    q : ndarray
        Start coordinates.
    columns : index array or bool mask, optional
        Speed directions allowed to move (dependent or free ones); all by default.
    tol : float
        Stop when ``||r|| <= tol`` (see ``POSITION_TOL``).
    max_iter : int
        Newton steps at most.
    line_search : bool
        Halve a step while it makes the residual larger (down to 1e-4) and stop when no step
        helps: for initialization from user guesses far from the manifold.
    exact : bool
        After reaching ``tol`` go on until the step is below ``EXACT_STEP`` or no longer halves
        the residual (see ``EXACT_STEP``).

    Returns
    -------
    Closure
    """
    q = np.asarray(q)
    r, J, data = residual(q)
    norm = float(np.linalg.norm(r)) if r.size else 0.0
    it = 0
    while r.size and it < max_iter and (norm > tol or exact):
        cols = slice(None) if columns is None else columns
        step_dir = np.zeros(J.shape[1])
        if np.any(np.ones(J.shape[1], bool)[cols]):
            step_dir[cols] = -_least_squares(J[:, cols], r)
        it += 1
        step = 1.0
        while True:
            qn = increment(q, step * step_dir)
            rn, Jn, dn = residual(qn)
            nn = float(np.linalg.norm(rn))
            if not line_search or nn < norm or step < 1e-4:
                break
            step *= 0.5
        if line_search and nn >= norm:
            break  # no step along the Newton direction helps: stalled
        q, r, J, data, norm, before = qn, rn, Jn, dn, nn, norm
        if exact and norm <= tol and (np.abs(step_dir).max(initial=0.0) <= EXACT_STEP or norm > 0.5 * before):
            break  # closed to rounding
    return Closure(q, r, J, data, norm, it, norm <= tol, tol)


#: singular values of a Newton closure's Jacobian below this (m per unit speed coordinate, or
#: 1) are zero whatever the largest: a loop closed across one rigid body has a Jacobian of
#: rounding (1e-17), and a relative cut-off let Newton step 1e16 m along it
JACOBIAN_FLOOR = 1e-12


def _least_squares(J, r):
    """Minimum-norm ``x`` with ``J x ~ r``, singular values below ``eps`` of the largest or
    :data:`JACOBIAN_FLOOR` taken as zero."""
    U, sv, Vt = np.linalg.svd(J, full_matrices=False)
    keep = sv > max(JACOBIAN_FLOOR, np.finfo(float).eps * max(J.shape) * (sv[0] if sv.size else 0.0))
    return Vt[keep].T @ ((U[:, keep].T @ r) / sv[keep])


def solve_speeds(A, res, u, columns=None, *, minimum_norm=False):
    """Speeds ``u`` corrected in ``columns`` so that the velocity rows ``A u - ... = res`` vanish.

    ``res`` is the current velocity-constraint residual (``[dPhi/dt, B u - b]``), linear in
    ``u`` with Jacobian ``A``, so one solve is exact: a square block is solved directly
    (D'Alembert's dependent speeds), any other by minimum-norm least squares (projection,
    free start speeds).

    Parameters
    ----------
    A : ndarray (rows, nu)
        Velocity-constraint Jacobian.
    res : ndarray (rows,)
        Its residual at ``u``.
    u : ndarray (nu,)
        Speeds.
    columns : index array or bool mask, optional
        Speeds that may change (all by default).
    minimum_norm : bool
        Least squares also for a square block. Initialization's free start speeds use it: a
        block square by count is (nearly) singular when fixed start speeds over-specify the
        mechanism; a solve then answers with speeds of ~1e15 that satisfy the contradicting
        rows to rounding, hidden behind the residual test's ``1e-8 |u|`` scale, while the
        minimum-norm answer leaves the contradiction as a residual that the check names.

    Returns
    -------
    ndarray
        The corrected copy of ``u``.
    """
    u = np.array(u, dtype=float)
    if not np.size(res):
        return u
    cols = slice(None) if columns is None else columns
    Ac = A[:, cols]
    if not Ac.size:  # no speed may change (a mechanism without freedom): nothing to correct
        return u
    if Ac.shape[0] == Ac.shape[1] and not minimum_norm:
        try:
            u[cols] -= np.linalg.solve(Ac, res)
            return u
        except np.linalg.LinAlgError:
            pass  # singular block: the minimum-norm correction below
    if Ac.shape[1]:
        u[cols] -= np.linalg.lstsq(Ac, res, rcond=None)[0]
    return u


def pivot_partition(A, m=None, columns=None, tol=PIVOT_TOL):
    """Choose ``m`` best-conditioned columns of ``A`` (pivoted QR) as dependent.

    Parameters
    ----------
    A : ndarray (rows, n)
        Constraint Jacobian (columns = speeds), or its transpose to choose independent rows.
    m : int, optional
        How many to choose (default: the number of rows).
    columns : index array, optional
        Choose among these columns only (default all).
    tol : float
        Refuse when the last chosen diagonal entry of ``R`` is below ``tol`` times the first
        (see ``PIVOT_TOL``); ``tol=0`` never refuses (a rank already known).

    Returns
    -------
    (dep, ind) : index arrays, sorted
        The chosen columns and the rest (both as indices of ``A``).

    Raises
    ------
    SingularPartition
        Fewer than ``m`` columns are available or they are (nearly) dependent.
    """
    n = A.shape[1]
    allowed = np.arange(n) if columns is None else np.asarray(columns, int)
    m = A.shape[0] if m is None else int(m)
    if m == 0:
        return np.zeros(0, int), allowed.copy()
    if allowed.size < m:
        raise SingularPartition(f"{m} rows but only {allowed.size} columns to choose from")
    _, R, piv = sla.qr(A[:, allowed], pivoting=True, mode="economic")
    d = np.abs(np.diag(R))
    if d.size < m or (tol and d[m - 1] <= tol * max(d[0], 1e-300)):
        raise SingularPartition("the constraint Jacobian has lost rank: no set of dependent coordinates exists")
    return np.sort(allowed[piv[:m]]), np.sort(allowed[piv[m:]])


def rank(A, tol=RANK_TOL):
    """Numerical rank: singular values above ``tol`` times ``max(1, largest)`` (see ``RANK_TOL``)."""
    if A.size == 0:
        return 0
    s = np.linalg.svd(A, compute_uv=False)
    return int(np.sum(s > tol * max(1.0, s[0])))
