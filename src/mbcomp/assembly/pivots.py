"""The pivots of the articulated-body factorization (:func:`mbcomp.assembly.recursive.articulated`):
a joint's ``D = S^T I^A S``, factored once and solved against, on numbers or traced values.

Every routine here is plain Python arithmetic on numpy arrays of floats *or* traced
(object) values, so the same code runs numerically and is printed into the generated
programs; a pivot that must be positive is a comparison, which becomes a runtime guard when
traced, and a failed one raises :class:`SingularTree` (the callers fall back to the dense
solve, which gives the diagnosis).

Examples
--------
>>> import numpy as np
>>> from mbcomp.assembly.pivots import cholesky, chol_solve
>>> G = np.array([[4.0, 2.0], [2.0, 3.0]])
>>> x = chol_solve(cholesky(G, "demo"), np.array([2.0, 1.0]))
>>> bool(np.allclose(G @ x, [2.0, 1.0]))
True
"""
from __future__ import annotations

import numpy as np

from ..geometry.kinematics import cross, skew

__all__ = ["SingularTree", "PIVOT_TOL", "Pivot", "chol_inverse", "cholesky", "chol_solve", "mirrored",
           "lower_product", "inverse3", "ball_pivot"]

#: a Cholesky pivot at or below ``PIVOT_TOL`` times the matrix's trace counts as singular
PIVOT_TOL = 1e-13


class SingularTree(ArithmeticError):
    """A matrix of the recursion (a joint's articulated inertia ``S^T I^A S``, or the
    constraint rows' ``A M^-1 A^T``) is singular: the caller falls back to the dense solve,
    which gives the diagnosis (massless motion, redundant rows) or a minimum-norm answer."""


def chol_inverse(D, what):
    """Inverse of a small symmetric positive definite matrix by a guarded Cholesky."""
    k = D.shape[0]
    if k == 1:
        d = D[0, 0]
        if not d > 0:  # a runtime guard when traced
            raise SingularTree(what)
        return np.array([[1.0 / d]], dtype=D.dtype)
    L = cholesky(D, what)
    eye = np.eye(k)
    return np.array([chol_solve(L, eye[:, c]) for c in range(k)], dtype=D.dtype).T


def cholesky(G, what, rel=PIVOT_TOL):
    """Lower Cholesky factor of ``G`` (numeric or traced), raising :class:`SingularTree` at a
    pivot at or below ``rel`` times the trace."""
    n = G.shape[0]
    tol = rel * sum(G[k, k] for k in range(n))
    L = np.zeros((n, n), G.dtype)
    for j in range(n):
        d = G[j, j] - sum(L[j, k] * L[j, k] for k in range(j))
        if not d > tol:
            raise SingularTree(what)
        L[j, j] = np.sqrt(d)
        for i in range(j + 1, n):
            L[i, j] = (G[i, j] - sum(L[i, k] * L[j, k] for k in range(j))) / L[j, j]
    return L


def chol_solve(L, b):
    n = L.shape[0]
    y = [None] * n
    for i in range(n):
        y[i] = (b[i] - sum(L[i, k] * y[k] for k in range(i))) / L[i, i]
    x = [None] * n
    for i in range(n - 1, -1, -1):
        x[i] = (y[i] - sum(L[k, i] * x[k] for k in range(i + 1, n))) / L[i, i]
    return np.array(x, dtype=L.dtype)


class Pivot:
    """One link's pivot ``D = S^T I^A S``, factored for the solves.

    * ``dense``: ``D^-1`` itself (``Dinv``): a root link (no articulated inertia to pass) or a
      one-speed joint;
    * otherwise its Cholesky factor ``L`` (with its pivots' reciprocals ``rinv``) and
      ``W = U L^-T``, so that ``U D^-1 U^T = W W^T`` and ``U D^-1 b = W (L^-1 b)``;
    * a ball joint (``Jinv`` given): the same over the joint's angular velocity in world axes
      ``w = Jw x`` instead of its speeds ``x``: ``D`` is then ``I_aa``, the articulated inertia's
      angular block about the joint's centre, ``U`` is ``I^A X_r [1; 0]`` and ``x = Jinv w``
      (see :func:`articulated`).
    """

    __slots__ = ("Dinv", "L", "rinv", "W", "Jinv")

    def __init__(self, D, U, what, dense, Jinv=None):
        self.Dinv = self.L = self.rinv = self.W = None
        self.Jinv = Jinv
        if dense or D.shape[0] == 1:
            self.Dinv = chol_inverse(D, what)
            return
        L = cholesky(D, what)
        k = L.shape[0]
        self.L, self.rinv = L, [1.0 / L[j, j] for j in range(k)]
        self.W = np.array([self.forward(U[a]) for a in range(U.shape[0])], dtype=U.dtype)

    def forward(self, b):
        """``L^-1 b``."""
        L, r = self.L, self.rinv
        y = []
        for i in range(len(r)):
            acc = b[i]
            for k in range(i):
                acc = acc - L[i, k] * y[k]
            y.append(acc * r[i])
        return y

    def backward(self, y):
        """``L^-T y``."""
        L, r = self.L, self.rinv
        n = len(r)
        x = [None] * n
        for i in range(n - 1, -1, -1):
            acc = y[i]
            for k in range(i + 1, n):
                acc = acc - L[k, i] * x[k]
            x[i] = acc * r[i]
        return np.array(x, dtype=L.dtype)

    def passed(self, U):
        """``U D^-1 U^T`` (6 x 6), its lower triangle computed and mirrored (the same values)."""
        P, Q = (U @ self.Dinv, U) if self.W is None else (self.W, self.W)
        if P.dtype != object:  # numbers: one product, its lower triangle mirrored
            return mirrored(P @ Q.T)
        out = np.empty((6, 6), dtype=object)
        for a in range(6):
            for b in range(a + 1):
                out[a, b] = out[b, a] = P[a] @ Q[b]
        return out


def mirrored(A):
    """``A`` (a new product of numbers) made symmetric: its lower triangle copied upwards."""
    n = A.shape[0]
    if n not in _UPPER:
        _UPPER[n] = np.triu_indices(n, 1)
    i, j = _UPPER[n]
    A[i, j] = A[j, i]
    return A


_UPPER = {}


def lower_product(S, U):
    """``S^T U`` for the symmetric ``D``: its lower triangle computed, mirrored (the Cholesky
    reads only the lower triangle, so its values are those of the full product)."""
    if S.dtype != object and U.dtype != object:
        return mirrored(S.T @ U)
    k = S.shape[1]
    D = np.empty((k, k), dtype=object)
    for a in range(k):
        for b in range(a + 1):
            D[a, b] = D[b, a] = S[:, a] @ U[:, b]
    return D


def inverse3(J, what):
    """Inverse of a 3 x 3 matrix by its cofactors (rows ``b x c / det``, ``c x a / det``,
    ``a x b / det`` for the columns ``a, b, c``); raises :class:`SingularTree` when
    ``det^2 <= PIVOT_TOL |a|^2 |b|^2 |c|^2`` (a scale-free test of the columns' volume)."""
    a, b, c = J[:, 0], J[:, 1], J[:, 2]
    rows = [cross(b, c), cross(c, a), cross(a, b)]
    det = a @ rows[0]
    if not det * det > PIVOT_TOL * ((a @ a) * (b @ b) * (c @ c)):  # a runtime guard when traced
        raise SingularTree(what)
    return np.array(rows, dtype=J.dtype) * (1.0 / det)


def ball_pivot(IA, Jw, r, what):
    """The pivot of a ball joint at ``r`` (three speeds, ``S = [Jw; r x Jw]``): over its
    angular velocity ``w = Jw x`` the motion subspace is ``X_r [1; 0]``, so ``U' = I^A X_r [1; 0]
    = I_1 + I_2 [r]x`` (column blocks of ``I^A``) and ``D' = I_aa = U'_1 - [r]x U'_2``, the
    articulated inertia's angular block about ``r``; ``D = Jw^T D' Jw`` and ``U = U' Jw``, so
    ``U D^-1 U^T = U' D'^-1 U'^T`` (``Jw`` cancels) and ``x = Jw^-1 w``."""
    Rx = skew(r)
    left = IA[:, :3] + IA[:, 3:] @ Rx
    Iaa = np.empty((3, 3), dtype=left.dtype)
    for a in range(3):
        for b in range(a + 1):
            Iaa[a, b] = Iaa[b, a] = left[a, b] - Rx[a] @ left[3:, b]
    return Pivot(Iaa, left, what, False, Jinv=inverse3(Jw, what))
