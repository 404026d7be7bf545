"""The iteration matrices of RADAU5 (:mod:`mbcomp.solvers.radau`): equilibrated LU factors, solves.

For a Jacobian ``J`` (n, n), a diagonal mass ``E = diag(mass)`` and a step ``h`` the simplified
Newton iteration of Radau IIA solves with ``(gamma/h) E - J`` (real) and ``(mu/h) E - J``
(complex, ``mu = alpha + i beta``). Both are factored by LAPACK ``getrf`` after row and column
equilibration ``diag(r) M diag(s)``, so that a pivot below :data:`PIVOT_TOL` means "rank
deficient" whatever the units of the rows. The two matrices differ only on the diagonal, so
the complex matrix's magnitudes are the real one's with the diagonal replaced: one ``abs``
pass over a real array serves both.

Examples
--------
>>> import numpy as np
>>> from mbcomp.solvers.radau_linalg import IterationMatrices
>>> J = np.array([[-2.0, 1.0], [0.0, -3.0]])
>>> m = IterationMatrices(J, np.ones(2), gamma=2.0, mu=1.0 + 1.0j, h=0.5)
>>> x = m.solve_real(np.array([1.0, 2.0]))
>>> bool(np.allclose((4.0 * np.eye(2) - J) @ x, [1.0, 2.0]))
True
>>> z = m.solve_complex(np.array([1.0, 1.0j]))
>>> bool(np.allclose(((2.0 + 2.0j) * np.eye(2) - J) @ z, [1.0, 1.0j]))
True
"""
from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import get_lapack_funcs

__all__ = ["IterationMatrices", "SingularMatrix", "PIVOT_TOL"]

EPS = np.finfo(float).eps
PIVOT_TOL = 50 * EPS  # |pivot| of the equilibrated matrix below this: singular (rank deficient)
# LAPACK directly: scipy's lu_factor/lu_solve cost ~45 us more a call (argument checks)
_DGETRF, _DGETRS = get_lapack_funcs(("getrf", "getrs"), (np.zeros(1),))
_ZGETRF, _ZGETRS = get_lapack_funcs(("getrf", "getrs"), (np.zeros(1, complex),))


class SingularMatrix(Exception):
    """An iteration matrix is (numerically) singular; the message says where.

    ``structural`` is True for a zero row or column (no step size can cure it).

    Examples
    --------
    >>> from mbcomp.solvers.radau_linalg import SingularMatrix
    >>> SingularMatrix("row 2 is zero", structural=True).structural
    True
    """

    def __init__(self, msg, structural=False):
        super().__init__(msg)
        self.structural = structural


def _equilibration(absM):
    """Row and column scales ``(r, s)`` making the largest entry of each row and column 1.

    ``absM`` (k, n, n): the magnitudes of ``k`` matrices at once (overwritten); ``r``, ``s``
    (k, n). One pass for the real and the complex matrix: the numbers are those of two passes.
    """
    rowmax = absM.max(axis=2)
    if np.count_nonzero(rowmax) < rowmax.size:  # (a quarter of .all()'s cost)
        i = int(np.flatnonzero((rowmax == 0.0).any(axis=0))[0])
        raise SingularMatrix(f"equation {i} involves no variable (row {i} is zero)", structural=True)
    r = 1.0 / rowmax
    absM *= r[:, :, None]
    colmax = absM.max(axis=1)
    if np.count_nonzero(colmax) < colmax.size:
        j = int(np.flatnonzero((colmax == 0.0).any(axis=0))[0])
        raise SingularMatrix(f"variable {j} enters no equation (column {j} is zero)", structural=True)
    return r, 1.0 / colmax


def _lu(getrf, M, r, s):
    """``getrf`` of ``diag(r) M diag(s)`` (overwriting ``M``); the pivots checked. A zero
    pivot (``info > 0``) shows in the pivots; LAPACK's wrappers do not warn."""
    M *= r[:, None]
    M *= s
    lu, piv, _ = getrf(M, overwrite_a=True)
    pivots = np.abs(lu.diagonal())
    smallest = np.minimum.reduce(pivots)
    if not PIVOT_TOL < smallest < np.inf:  # also NaN
        k = int(np.argmin(pivots))
        raise SingularMatrix(f"pivot {k} of the equilibrated matrix is {pivots[k]:.3g} (rank deficient)")
    return lu, piv


class IterationMatrices:
    """Equilibrated LU factors of ``(gamma/h) E - J`` and ``(mu/h) E - J``.

    Parameters
    ----------
    J : ndarray (n, n)
        ``d fun / d y``, finite (the caller checks it).
    mass : ndarray (n,)
        Diagonal of ``E`` (1 differential row, 0 algebraic row).
    gamma : float
        Real eigenvalue of the inverse Butcher matrix.
    mu : complex
        The complex eigenvalue used by the complex system.
    h : float
        Step size (s) the matrices are formed with.
    ode : bool, optional
        Whether ``mass`` is all ones (``E = I``; the caller may know it): then the diagonal is
        formed without the products with ``mass`` (the same numbers). Default: looked up.

    Raises
    ------
    SingularMatrix
        When a row or column is zero, or a pivot of an equilibrated matrix is below
        :data:`PIVOT_TOL` (or not finite).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.solvers.radau_linalg import IterationMatrices, SingularMatrix
    >>> try:
    ...     IterationMatrices(np.zeros((2, 2)), np.array([1.0, 0.0]), 2.0, 1.0 + 1.0j, 0.1)
    ... except SingularMatrix as exc:
    ...     print(exc, exc.structural)
    equation 1 involves no variable (row 1 is zero) True
    """

    def __init__(self, J, mass, gamma, mu, h, ode=None):
        self.h = h
        n = J.shape[0]
        if ode is None:
            ode = bool(np.all(mass == 1.0))
        M = np.empty((n, n))
        np.negative(J, out=M)
        Md = M.reshape(-1)[:: n + 1]  # the diagonal, a view
        if ode:  # E = I: (mu/h) * 1.0 is mu/h, the same numbers without the products
            dc = (mu / h) + Md  # before Md changes: (mu/h) E - J on the diagonal
            Md += gamma / h
        else:
            dc = (mu / h) * mass + Md
            Md += (gamma / h) * mass
        absM = np.empty((2, n, n))  # the real matrix's magnitudes, the complex one's
        np.abs(M, out=absM[0])
        absM[1] = absM[0]
        absM[1].reshape(-1)[:: n + 1] = np.abs(dc)
        Mc = M.astype(complex)
        Mc.reshape(-1)[:: n + 1] = dc
        r, s = _equilibration(absM)
        self._real = _lu(_DGETRF, M, r[0], s[0]) + (r[0], s[0])
        self._complex = _lu(_ZGETRF, Mc, r[1], s[1]) + (r[1], s[1])
        self._rhs = np.empty(n, dtype=complex)  # the complex right-hand side of solve_stages

    def solve_real(self, rhs):
        """``x`` (n,) with ``((gamma/h) E - J) x = rhs``."""
        lu, piv, r, s = self._real
        return s * _DGETRS(lu, piv, r * rhs, overwrite_b=True)[0]

    def solve_complex(self, rhs):
        """``x`` (n,) complex with ``((mu/h) E - J) x = rhs``."""
        lu, piv, r, s = self._complex
        return s * _ZGETRS(lu, piv, r * rhs, overwrite_b=True)[0]

    def solve_stages(self, R, out):
        """Both solves of one Newton iteration in the transformed stage variables.

        Parameters
        ----------
        R : ndarray (3, n)
            Right-hand sides: ``R[0]`` of the real system, ``R[1] + i R[2]`` of the complex one.
        out : ndarray (3, n)
            Written: ``out[0]`` the real solution, ``out[1] + i out[2]`` the complex one (the
            numbers of :meth:`solve_real` and :meth:`solve_complex`, with fewer array calls).
        """
        lu, piv, r, s = self._real
        np.multiply(s, _DGETRS(lu, piv, r * R[0], overwrite_b=True)[0], out[0])
        lu, piv, r, s = self._complex
        b = self._rhs
        b.real = R[1]
        b.imag = R[2]
        b *= r
        x = _ZGETRS(lu, piv, b, overwrite_b=True)[0]
        x *= s
        out[1] = x.real
        out[2] = x.imag
