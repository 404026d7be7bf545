"""Rigid impacts: the impulse equations with Newton's restitution per contact row.

At an impact the speeds jump from ``u-`` to ``u+`` while the positions stay; the impulses
``Lambda`` (N s for a translation row, N m s for a rotation row) act along the rows involved::

    M (u+ - u-) = C^T Lambda                      (momentum balance over the impact)
    C_i u+ = -e_i C_i u-        i in normal rows   (Newton's law, 0 <= e_i <= 1)
    C_k u+ = 0                  k in kept rows     (loop closures, engaged stops: they hold)

``C_i u`` is a unilateral row's *normal speed*, positive when the contact opens, and a
compressive impulse ``Lambda_i > 0`` pushes the bodies apart (it raises ``C_i u``). Note
that the project's multipliers have the opposite sign (``M du/dt = f - A^T lam``): an
impulse ``Lambda`` is a multiplier of ``-Lambda`` integrated over the impact.

The saddle-point system ``[[M, -C^T], [C, 0]] [u+; Lambda] = [M u-; target]`` is solved by
its range space: ``Y = M^-1 C^T`` (one Cholesky factor of ``M``), ``G = C Y`` (the inverse
mass seen by the rows), ``G Lambda = target - C u-``, ``u+ = u- + Y Lambda``. Redundant rows
(a planar loop written with 3-D joints, a stop row repeating a loop row) are found by the
project's rank test (:func:`mbcomp.assembly.manifold.rank`, ``RANK_TOL``) and left out by
pivoted QR (:func:`mbcomp.assembly.manifold.pivot_partition`), the kept rows first: a
redundant row gets ``Lambda = 0`` and is satisfied when its target is consistent with the
others (always so for rows holding at ``C u- = 0``).

Several impacting rows at once form a linear complementarity problem per row: either
``Lambda_i > 0`` and ``C_i u+ = -e_i C_i u-``, or ``Lambda_i = 0`` and ``C_i u+ >= -e_i C_i u-``
(a pulling impulse is dropped, the row separates faster than its restitution asks). It is
solved by Murty's least-index principal pivoting: start with every impacting row active, flip
the lowest-numbered row that breaks its condition, solve again. ``G`` restricted to
independent rows is positive definite (its Schur complement over the kept rows too), so the
problem has exactly one solution and the pivoting reaches it in finitely many flips.

Limitations (Newton's law per contact, all rows at one instant)
---------------------------------------------------------------
- Simultaneous impacts are not sequential ones: three equal balls of Newton's cradle, the
  first hitting the two others at rest in contact with ``e = 1``, give ``-v/3, 2v/3, 2v/3``
  (energy kept, momentum kept), not the observed ``0, 0, v``; the outcome of a multiple
  impact depends on the wave propagation a rigid model does not have.
- Energy: with one impacting row (any number of kept rows), or several with one common
  ``e``, the kinetic energy falls by ``(1 - e^2)/2 w^T S^-1 w >= 0`` (``w`` the impacting
  rows' normal speeds before, ``S`` their inverse mass with the kept rows holding). With
  *different* coefficients on simultaneous rows it can rise: Newton's law is kinematic and
  does not bound the work of coupled impulses (the random check in
  ``tests/assembly/test_impacts.py``, 2-5 rows on up to 5 speeds, ``e_i`` drawn from [0, 1]
  per row, gains energy in 54 of 1000 cases, never with one common ``e``).
- A redundant impacting row whose target contradicts the independent rows (e.g. two
  identical rows with different ``e``) is left violated; ``full=True`` reports the residual.
- No friction: tangential impulses are zero (a frictionless impact).

Examples
--------
A ball (1 kg point mass, speeds ``(vx, vy)`` in m/s) hits the ground (row ``vy``) with
``e = 0.5``; a second, redundant copy of the row (same ``e``) changes nothing:

>>> import numpy as np
>>> from mbcomp.assembly.impacts import impulse, impact_energy_loss
>>> M = np.eye(2); C = np.array([[0.0, 1.0], [0.0, 1.0]])
>>> u_plus, Lam = impulse(M, C, np.array([1.0, -2.0]), normal_rows=[0, 1], restitution=0.5)
>>> u_plus.tolist(), Lam.round(12).tolist()
([1.0, 1.0], [3.0, 0.0])
>>> float(impact_energy_loss(M, np.array([1.0, -2.0]), u_plus))   # (1 - e^2) m v^2 / 2
1.5
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

from ..errors import SimulationError
from .manifold import pivot_partition, rank

__all__ = ["impulse", "sliding_impulse", "impact_energy_loss", "single_row_loss", "post_impact_state", "Impulse",
           "PostImpact", "IMPACT_TOL"]

#: relative size below which an impulse counts as zero (not pulling) and a normal speed as
#: meeting its target: the range-space solve loses ~cond(G) * eps, and 1e-10 leaves a
#: condition number of 1e5 before rounding could flip a row
IMPACT_TOL = 1e-10


@dataclass(frozen=True)
class Impulse:
    """An impact solved by :func:`impulse` (``full=True``).

    Attributes
    ----------
    u_plus : ndarray (nu,)
        Speeds after the impact.
    Lambda : ndarray (m,)
        Impulse per row of ``C`` (N s or N m s; > 0 compressive), zero for rows not used.
    active : ndarray of int
        Impacting rows that carry an impulse (in contact through the impact).
    dropped : ndarray of int
        Impacting rows left out: their impulse would pull (they separate).
    redundant : ndarray of int
        Rows left out as linearly dependent on the others.
    pivots : int
        Flips of the least-index pivoting (0: every impacting row stayed active).
    residual : float
        Largest ``|C_r u+ - target_r|`` over kept and active rows (m/s or rad/s).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.assembly.impacts import impulse
    >>> r = impulse(np.eye(1), np.array([[1.0]]), np.array([-1.0]), [0], 1.0, full=True)
    >>> r.u_plus.tolist(), r.dropped.tolist(), r.pivots
    ([1.0], [], 0)
    """

    u_plus: np.ndarray
    Lambda: np.ndarray
    active: np.ndarray
    dropped: np.ndarray
    redundant: np.ndarray
    pivots: int
    residual: float


def impulse(M, C, u_minus, normal_rows, restitution, keep_rows=None, *, offset=None, hold_drift=False,
            full=False):
    """Speeds after a rigid impact and the impulses: ``M (u+ - u-) = C^T Lambda``.

    Parameters
    ----------
    M : ndarray (nu, nu)
        Mass matrix (symmetric positive definite; kg, kg m, kg m^2 by speed kind).
    C : ndarray (m, nu)
        Jacobians of the rows involved (normal speed of a contact = ``C_i u + offset_i``, m/s
        or rad/s, positive when it opens).
    u_minus : ndarray (nu,)
        Speeds just before the impact.
    normal_rows : sequence of int
        Indices into ``C`` of the impacting unilateral rows.
    restitution : float or sequence of float
        Newton's coefficient ``e_i`` in [0, 1], one for all or one per impacting row.
    keep_rows : sequence of int, optional
        Indices of bilateral rows that hold through the impact (loop closures, engaged
        stops): ``C_k u+ + offset_k = 0``. Redundant ones are fine.
    offset : ndarray (m,), optional
        Rows' speed at ``u = 0`` (rheonomic rows: ``dPhi/dt = C u + offset``); zero by default.
    hold_drift : bool
        Kept rows keep their speed before (``C_k u+ = C_k u-``) instead of being brought to
        zero: the impulse then does not correct a velocity drift of the loop.
    full : bool
        Return an :class:`Impulse` with the active set, dropped and redundant rows.

    Returns
    -------
    (u_plus, Lambda) : (ndarray (nu,), ndarray (m,))
        Or an :class:`Impulse` when ``full``.

    Raises
    ------
    ValueError
        Shapes, indices or restitution coefficients that do not fit.
    SimulationError
        ``M`` is not positive definite, or the pivoting does not settle.

    Examples
    --------
    A pendulum (rod, m = 2 kg, L = 1.5 m, on a hinge, u = angular speed) hits a stop at its
    tip (tip speed ``L w``) at -3 rad/s, ``e = 0.8``:

    >>> import numpy as np
    >>> from mbcomp.assembly.impacts import impulse
    >>> m, L = 2.0, 1.5
    >>> u_plus, Lam = impulse(np.array([[m * L**2 / 3]]), np.array([[L]]), np.array([-3.0]), [0], 0.8)
    >>> round(float(u_plus[0]), 12), round(float(Lam[0]), 12)   # -e w, (1 + e) I w / L
    (2.4, 5.4)
    """
    M, C, u, normal, keep, e, s = _inputs(M, C, u_minus, normal_rows, restitution, keep_rows, offset)
    before = C @ u + s
    target = np.zeros(C.shape[0])
    target[normal] = -e * before[normal]
    target[keep] = before[keep] if hold_drift else 0.0
    rhs = target - s - C @ u  # the change of C u the impulses must make
    try:
        factor = _cho_factor(M)
    except (np.linalg.LinAlgError, ValueError):
        raise SimulationError("impact: the mass matrix is not positive definite (some speed carries no inertia): "
                              "the impulse equations have no unique answer; give the bodies mass") from None
    Y = _cho_solve(factor, C.T)
    G = C @ Y
    lam, active, redundant, pivots = _complementarity(C, G, rhs, normal, keep)
    u_plus = u + Y @ lam
    if not full:
        return u_plus, lam
    held = _minus(np.concatenate((keep, normal[active])), redundant)
    resid = float(np.abs(C[held] @ u_plus + s[held] - target[held]).max(initial=0.0))
    return Impulse(u_plus, lam, normal[active], normal[~active], redundant, pivots, resid)


def _inputs(M, C, u_minus, normal_rows, restitution, keep_rows, offset):
    """Arrays checked: shapes, row indices in range and disjoint, ``0 <= e <= 1``."""
    M = np.atleast_2d(np.asarray(M, float))
    u = np.asarray(u_minus, float).reshape(-1)
    nu = u.size
    C = np.asarray(C, float).reshape(-1, nu) if np.size(C) else np.zeros((0, nu))
    if M.shape != (nu, nu):
        raise ValueError(f"impact: M has shape {M.shape} but u_minus has {nu} speeds: give M as ({nu}, {nu})")
    m = C.shape[0]
    normal = np.asarray(normal_rows if normal_rows is not None else [], int).reshape(-1)
    keep = np.asarray(keep_rows if keep_rows is not None else [], int).reshape(-1)
    for name, idx in (("normal_rows", normal), ("keep_rows", keep)):
        if idx.size and (idx.min() < 0 or idx.max() >= m or len(set(idx.tolist())) != idx.size):
            raise ValueError(f"impact: {name}={idx.tolist()} must be distinct row indices of C (0..{m - 1})")
    both = sorted(set(normal.tolist()) & set(keep.tolist()))
    if both:
        raise ValueError(f"impact: rows {both} are both impacting and kept: a row is either one or the other")
    e = np.broadcast_to(np.asarray(restitution, float), normal.shape).copy() if np.ndim(restitution) == 0 \
        else np.asarray(restitution, float).reshape(-1)
    if e.shape != normal.shape:
        raise ValueError(f"impact: {e.size} restitution coefficients for {normal.size} impacting rows: "
                         "give one for all or one per row")
    if np.any(~np.isfinite(e)) or np.any(e < 0.0) or np.any(e > 1.0):
        raise ValueError(f"impact: restitution {e.tolist()} must lie in [0, 1] (0 plastic, 1 elastic)")
    s = np.zeros(m) if offset is None else np.asarray(offset, float).reshape(m)
    return M, C, u, normal, keep, e, s


def _cho_factor(A):
    """The upper Cholesky factor of the symmetric positive definite ``A`` by LAPACK's
    ``dpotrf``, the routine and arguments of ``scipy.linalg.cho_factor`` (the same bits)
    without its wrapper's ~15 us a call (an impact makes two to four factorizations and
    solves); ``LinAlgError`` where ``A`` is not positive definite, ``ValueError`` where it is
    not finite."""
    if not np.isfinite(A).all():
        raise ValueError("impact: a matrix with inf or NaN entries")
    if not A.size:
        return np.zeros_like(A)
    c, info = dpotrf(A, lower=0, clean=0)
    if info > 0:
        raise np.linalg.LinAlgError(f"{info}-th leading minor is not positive definite")
    if info < 0:
        raise ValueError(f"dpotrf: illegal value in argument {-info}")
    return c


def _cho_solve(c, b):
    """``A x = b`` from ``A``'s factor ``c`` (:func:`_cho_factor`): LAPACK's ``dpotrs``, as
    ``scipy.linalg.cho_solve``; ``ValueError`` where ``b`` is not finite."""
    b = np.asarray(b, float)
    if not np.isfinite(b).all():
        raise ValueError("impact: a right-hand side with inf or NaN entries")
    if not b.size:
        return np.zeros_like(b)
    x, info = dpotrs(c, b, lower=0)
    if info != 0:
        raise ValueError(f"dpotrs: illegal value in argument {-info}")
    return x


def _independent(C, keep, normal):
    """Rows to solve with: an independent subset of ``keep`` (pivoted QR of its transpose),
    then the impacting rows that add rank beyond them (pivoted QR of their part outside the
    kept rows' span). Returns ``(rows, redundant)``, both sorted index arrays."""
    chosen = keep
    rk = rank(C[keep])
    if rk < keep.size:
        chosen = keep[pivot_partition(C[keep].T, rk, tol=0)[0]]
    extra = normal
    if normal.size:
        ra = rank(C[np.concatenate((chosen, normal))]) - rk
        if ra < normal.size:
            N = C[normal]
            if rk:
                Q = np.linalg.qr(C[chosen].T)[0]
                N = N - (N @ Q) @ Q.T
            extra = normal[pivot_partition(N.T, ra, tol=0)[0]] if ra > 0 else normal[:0]
    rows = np.sort(np.concatenate((chosen, extra)))
    return rows, _minus(np.concatenate((keep, normal)), rows)


def _minus(a, b):
    """The sorted distinct row indices of ``a`` not in ``b`` (``np.setdiff1d`` of a few
    indices, without its ~25 us of set machinery)."""
    return np.array(sorted(set(a.tolist()) - set(b.tolist())), dtype=np.intp)


def _solve(C, G, rhs, rows, m):
    """Impulses on ``rows`` with ``G_rr Lambda_r = rhs_r``; zero elsewhere."""
    lam = np.zeros(m)
    if rows.size:
        Gr = G[np.ix_(rows, rows)]
        try:
            lam[rows] = _cho_solve(_cho_factor(Gr), rhs[rows])
        except np.linalg.LinAlgError:  # independent by the rank test, yet G not numerically SPD
            lam[rows] = np.linalg.lstsq(Gr, rhs[rows], rcond=None)[0]
    return lam


def _complementarity(C, G, rhs, normal, keep):
    """Murty's least-index principal pivoting over the impacting rows: returns ``(Lambda,
    active mask over normal, redundant rows, pivots)``."""
    m = C.shape[0]
    active = np.ones(normal.size, bool)
    scale_v = max(float(np.abs(rhs).max(initial=0.0)), 1e-300)
    limit = 50 * (normal.size + 1)
    for pivots in range(limit + 1):
        rows, redundant = _independent(C, keep, normal[active])
        lam = _solve(C, G, rhs, rows, m)
        change = G @ lam  # C (u+ - u-)
        tol_l = IMPACT_TOL * max(float(np.abs(lam).max(initial=0.0)), 1e-300)
        bad = np.flatnonzero(np.where(active, lam[normal] < -tol_l,
                                      change[normal] < rhs[normal] - IMPACT_TOL * scale_v))
        if not bad.size:
            return lam, active, redundant, pivots
        active[bad[0]] = ~active[bad[0]]
    raise SimulationError(f"impact: the contact rows {normal.tolist()} did not settle on an active set in "
                          f"{limit} pivots (redundant impacting rows?): model the contacts so their rows are "
                          "independent")


def sliding_impulse(M, A, u_minus, offset_keep, c_n, C_t, normal_speed, restitution, mu_k, s):
    """``(u+, [P_n, P_t...])``: an impact through which a contact slides against the unit slip
    direction ``s`` (tangents' coordinates): ``M (u+ - u-) = A^T L + (c_n - mu_k s C_t)^T P_n``
    with the kept rows ``A`` (rates ``A u + offset_keep``) holding and Newton's restitution on
    the contact's normal speed, ``c_n u+ + offset = -e normal_speed`` (``normal_speed``: before,
    with its offset). Exact while the slip keeps its direction through the impact (a ball); the
    tangential impulse is ``-mu_k P_n s``. Kept rows may be redundant: a least-squares solve.
    """
    nu, ma = M.shape[0], A.shape[0]
    D = c_n - mu_k * (s @ C_t)
    K = np.zeros((nu + ma + 1, nu + ma + 1))
    K[:nu, :nu], K[:nu, nu:nu + ma], K[:nu, -1] = M, -A.T, -D
    K[nu:nu + ma, :nu], K[-1, :nu] = A, c_n
    rhs = np.concatenate((np.zeros(nu), -(A @ u_minus + offset_keep), [-(1.0 + restitution) * normal_speed]))
    x = np.linalg.lstsq(K, rhs, rcond=1e-13)[0]
    P_n = x[-1]
    return u_minus + x[:nu], np.concatenate(([P_n], -mu_k * P_n * s))


def impact_energy_loss(M, u_minus, u_plus):
    """Kinetic energy lost in an impact, ``T- - T+`` (J; > 0 lost, < 0 gained).

    For one impacting row ``c`` (and any kept rows holding at ``u-``), with ``w = c u-`` and
    ``S`` the row's inverse mass with the kept rows holding (``S = c M^-1 c^T`` without them),
    ``T+ - T- = -(1 - e^2)/2 w^2 / S``, never positive for ``0 <= e <= 1``. Proof sketch:
    ``u+ - u- = Y Lambda`` with ``Y = M^-1 C^T``, so ``T+ - T- = (C u-)^T Lambda + Lambda^T G
    Lambda / 2`` with ``G = C Y``. The kept rows have ``C_k u- = 0`` and the impacting row needs
    ``c (u+ - u-) = -(1 + e) w``; eliminating the kept rows' impulses gives ``Lambda_c =
    -(1 + e) w / S`` and ``Lambda^T G Lambda = S Lambda_c^2``, so ``T+ - T- = -(1 + e) w^2 / S +
    (1 + e)^2 w^2 / (2 S) = -(1 - e^2) w^2 / (2 S)``. The same algebra with a vector ``w`` and
    one common ``e`` gives ``-(1 - e^2)/2 w^T S^-1 w`` for simultaneous rows.

    Parameters
    ----------
    M : ndarray (nu, nu)
        Mass matrix.
    u_minus, u_plus : ndarray (nu,)
        Speeds before and after.

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.assembly.impacts import impact_energy_loss
    >>> float(impact_energy_loss(2.0 * np.eye(1), np.array([-3.0]), np.array([1.5])))  # 9 - 2.25
    6.75
    """
    M = np.atleast_2d(np.asarray(M, float))
    um, up = np.asarray(u_minus, float), np.asarray(u_plus, float)
    return 0.5 * float(um @ M @ um - up @ M @ up)


def single_row_loss(M, c, u_minus, restitution, C_keep=None):
    """The closed form ``(1 - e^2)/2 w^2 / S`` (J) of one impacting row ``c`` (see
    :func:`impact_energy_loss`), ``S`` its inverse mass with the rows ``C_keep`` holding.

    Parameters
    ----------
    M : ndarray (nu, nu)
        Mass matrix.
    c : ndarray (nu,)
        The impacting row.
    u_minus : ndarray (nu,)
        Speeds before (on the kept rows: ``C_keep u- = 0``).
    restitution : float
        ``e`` in [0, 1].
    C_keep : ndarray (k, nu), optional
        Rows that hold (redundant ones are fine).

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.assembly.impacts import single_row_loss
    >>> float(single_row_loss(np.eye(2), np.array([0.0, 1.0]), np.array([1.0, -2.0]), 0.5))
    1.5
    """
    M = np.atleast_2d(np.asarray(M, float))
    c = np.asarray(c, float).reshape(-1)
    w = float(c @ np.asarray(u_minus, float))
    Y = np.linalg.solve(M, c)
    S = float(c @ Y)
    if C_keep is not None and np.size(C_keep):
        Ck = np.asarray(C_keep, float).reshape(-1, c.size)
        Yk = np.linalg.solve(M, Ck.T)
        S -= float((Ck @ Y) @ np.linalg.lstsq(Ck @ Yk, Ck @ Y, rcond=1e-12)[0])
    return 0.5 * (1.0 - restitution ** 2) * w * w / S


@dataclass(frozen=True)
class PostImpact:
    """The state after an impact of an assembled system (:func:`post_impact_state`).

    Attributes
    ----------
    u : ndarray (nu,)
        Speeds after the impact (positions do not jump).
    impulses : dict
        Row name -> impulse (N s or N m s, > 0 compressive on impacting rows) for every
        impacting and kept row; rows given as an array are named ``"extra[i]"``, kept ones
        ``"keep_extra[i]"``.
    dropped : list of str
        Impacting rows whose impulse would pull: they separate with no impulse.
    loss : float
        Kinetic energy lost, ``T- - T+`` (J).
    pivots : int
        Active-set flips (see :func:`impulse`).
    residual : float
        Largest violation of a kept or active row's target after the impact (m/s, rad/s).
    notes : list of str
        Redundant rows left out (their names).

    Examples
    --------
    See :func:`post_impact_state`.

    >>> from mbcomp.assembly.impacts import PostImpact
    >>> sorted(PostImpact.__dataclass_fields__)[:3]
    ['dropped', 'impulses', 'loss']
    """

    u: np.ndarray
    impulses: dict
    dropped: list
    loss: float
    pivots: int
    residual: float
    notes: list = field(default_factory=list)


def _row_table(system, ev):
    """Every constraint row of the evaluation ``ev`` (unmasked): names, Jacobian (rows, nu) and
    offset (the row speed at ``u = 0``: ``dPhi/dt - C u`` holonomic, ``-b`` nonholonomic)."""
    names = [f"{e.name}.{r}" for e, rows, _ in ev.local for r in rows]
    names += [f"{e.name}.{r}" for e, rows, _ in ev.local_nh for r in rows]
    A = np.vstack((ev.C, ev.B)) if ev.B.size else np.asarray(ev.C)
    offset = np.concatenate((ev.Phid - ev.C @ ev.u, ev.Psi - ev.B @ ev.u)) if ev.B.size else ev.Phid - ev.C @ ev.u
    return names, A.reshape(-1, system.nu), offset


def _pick(names, which, what):
    """Indices of the row names ``which`` in ``names``; unknown ones raise with the list."""
    unknown = [w for w in which if w not in names]
    if unknown:
        raise ValueError(f"impact: {what} {unknown} are not constraint rows of this system; its rows are "
                         f"{names} (system.constraint_names(all_rows=True) and the velocity-constraint rows)")
    return [names.index(w) for w in which]


def post_impact_state(system, t, q, u_minus, rows, restitution, keep="all", *, keep_extra=None,
                      hold_drift=False):
    """Speeds after an impact of an assembled system on some of its rows (or on rows you give).

    Builds ``M`` and the rows' Jacobians from ``system.evaluate_numeric(t, q, u_minus,
    masked=False)`` (all holonomic rows ``C`` with their names
    ``system.constraint_names(all_rows=True)``, then the velocity-constraint rows ``B``) and
    solves the impact with :func:`impulse`.

    Parameters
    ----------
    system : MultibodySystem
        The assembled system.
    t : float
        Time of the impact (s).
    q : ndarray (nq,)
        Positions at the impact (on the constraints).
    u_minus : ndarray (nu,)
        Speeds just before.
    rows : sequence of str or ndarray (k, nu)
        The impacting rows: names of the system's rows, or their Jacobians (a stop's or a
        contact's normal-speed row over ``u``, positive when it opens; scleronomic).
    restitution : float or sequence of float
        Newton's ``e`` in [0, 1], one for all or one per impacting row.
    keep : "all" or sequence of str
        Rows that hold through the impact: ``"all"`` = every row of the system not impacting
        (redundant rows are found and left out), or their names, or ``()`` for none.
    keep_extra : ndarray (j, nu), optional
        More rows that hold (already engaged stops), as Jacobians.
    hold_drift : bool
        See :func:`impulse`: kept rows keep their speed instead of being brought to zero.

    Returns
    -------
    PostImpact

    Examples
    --------
    A pendulum (rod 1 kg, 1 m, on a hinge about z) swinging at -2 rad/s hits a stop at its
    tip; the stop's row is the tip's normal speed ``L w`` (``e = 0.5``):

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, RigidBody
    >>> from mbcomp.assembly.impacts import post_impact_state
    >>> m = mbcomp.Model()
    >>> w = m.add("world", World(g=(0.0, 0.0, 0.0)))
    >>> hinge = m.add("hinge", Revolute(n=(0, 0, 1)))
    >>> rod = m.add("rod", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=np.diag([0.0, 1 / 12, 1 / 12])))
    >>> m.connect(w.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> after = post_impact_state(system, 0.0, system.default_q(), np.array([-2.0]), np.array([[1.0]]), 0.5)
    >>> round(float(after.u[0]), 12), round(after.impulses["extra[0]"], 12), round(after.loss, 12)
    (1.0, 1.0, 0.5)
    """
    ev = system.evaluate_numeric(t, np.asarray(q, float), np.asarray(u_minus, float), masked=False)
    names, A, offset = _row_table(system, ev)
    n_sys = len(names)
    if isinstance(rows, str):
        rows = [rows]
    if isinstance(rows, np.ndarray) and rows.dtype.kind == "f":
        extra = rows.reshape(-1, system.nu)
        normal = list(range(len(names), len(names) + extra.shape[0]))
        names = names + [f"extra[{i}]" for i in range(extra.shape[0])]
        A, offset = np.vstack((A, extra)), np.concatenate((offset, np.zeros(extra.shape[0])))
    else:
        normal = _pick(names, list(rows), "impacting rows")
    if isinstance(keep, str) and keep == "all":
        kept = [i for i in range(n_sys) if i not in normal]
    else:
        kept = _pick(names[:n_sys], [keep] if isinstance(keep, str) else list(keep), "kept rows")
    if keep_extra is not None and np.size(keep_extra):
        ke = np.asarray(keep_extra, float).reshape(-1, system.nu)
        kept += list(range(len(names), len(names) + ke.shape[0]))
        names = names + [f"keep_extra[{i}]" for i in range(ke.shape[0])]
        A, offset = np.vstack((A, ke)), np.concatenate((offset, np.zeros(ke.shape[0])))
    r = impulse(ev.M, A, ev.u, normal, restitution, kept, offset=offset, hold_drift=hold_drift, full=True)
    impulses = {names[i]: float(r.Lambda[i]) for i in list(normal) + kept}
    return PostImpact(r.u_plus, impulses, [names[i] for i in r.dropped], impact_energy_loss(ev.M, ev.u, r.u_plus),
                      r.pivots, r.residual, [f"redundant row left out: {names[i]}" for i in r.redundant])
