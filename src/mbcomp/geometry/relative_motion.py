"""Finite motions (4 x 4 homogeneous transforms) and motion of a point in a moving frame.

Like :mod:`mbcomp.rotations`, every function works on floats and on sympy objects: any
sympy input (symbol, expression, exact number, ``sympy.Matrix``) switches to sympy and
returns ``sympy.Matrix`` results (vectors as 3 x 1 columns); otherwise numpy arrays are
returned.  :func:`screw_motion` is numeric only.

Homogeneous transforms
----------------------
A frame B placed in a reference frame A by the rotation ``R`` (B components to A
components, ``x_A = R @ x_B``) and the position ``r`` of B's origin (resolved in A) is the
4 x 4 matrix ``T = [[R, r], [0, 0, 0, 1]]``: a point with coordinates ``p_B`` in B has
coordinates ``p_A = R @ p_B + r`` in A, i.e. ``[p_A, 1] = T @ [p_B, 1]`` (the seed book's
eqs. 1.63-1.65, a finite translation ``u`` after a finite rotation ``A``: ``T = T1 T2``).
Chains compose left to right: ``T_AC = T_AB @ T_BC``.

Point moving in a moving frame
------------------------------
A frame with origin O moves with velocity ``v_O``, acceleration ``a_O``, angular velocity
``omega`` and angular acceleration ``alpha = d(omega)/dt``; a point P at ``r`` from O moves
relative to the frame with ``v_rel``, ``a_rel`` (rates of its frame coordinates). Then
(book eqs. 1.14 and 1.19)::

    v_P = v_O + omega x r + v_rel
    a_P = a_O + alpha x r + omega x (omega x r) + 2 omega x v_rel + a_rel
          \\_____ transport (frame point) _____/   \\_ Coriolis _/   relative

All vectors must be resolved in one common frame (any frame, e.g. the moving one). Note
that ``alpha`` is the *inertial* derivative of ``omega``; only in the components of the
frame whose angular velocity is ``omega`` does it equal the derivative of ``omega``'s
components (``omega x omega = 0``).

Examples
--------
>>> import sympy as sp
>>> from mbcomp.relative_motion import point_acceleration
>>> W, R, v = sp.symbols("Omega R v")
>>> acc = point_acceleration(a_O=[0, 0, 0], omega=[0, 0, W], alpha=[0, 0, 0],
...                          r=[R, 0, 0], v_rel=[0, v, 0])
>>> acc.centripetal.T, acc.coriolis.T
(Matrix([[-Omega**2*R, 0, 0]]), Matrix([[-2*Omega*v, 0, 0]]))
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from ..geometry.kinematics import cross, unit
from .symbolic import as_vector, is_symbolic, sympy_module

__all__ = [
    "homogeneous", "homogeneous_inverse", "compose", "transform_points", "screw_motion",
    "ScrewMotion", "VelocityTerms", "AccelerationTerms", "point_velocity", "point_acceleration",
]


# ------------------------------------------------------------------------------ transforms
def homogeneous(R=None, r=None):
    """4 x 4 homogeneous transform ``[[R, r], [0, 0, 0, 1]]`` of a finite motion.

    Parameters
    ----------
    R : array_like or sympy.Matrix, shape (3, 3), optional
        Rotation, moving (B) to reference (A) components; identity if omitted.
    r : array_like or sympy.Matrix, shape (3,), optional
        Position of B's origin resolved in A (length unit of the model); zero if omitted.

    Returns
    -------
    ndarray or sympy.Matrix, shape (4, 4)
        ``T`` with ``[p_A, 1] = T @ [p_B, 1]``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.rotations import C3
    >>> T = homogeneous(C3(np.pi / 2), [1.0, 0, 0])
    >>> np.allclose(T @ [1, 0, 0, 1], [1, 1, 0, 1])
    True
    """
    sym = is_symbolic(R, r)
    if sym:
        sp = sympy_module()
        T = sp.eye(4)
        if R is not None:
            T[:3, :3] = sp.Matrix(R)
        if r is not None:
            T[:3, 3] = as_vector(r, True)
        return T
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = np.asarray(R, dtype=float)
    if r is not None:
        T[:3, 3] = np.asarray(r, dtype=float).reshape(3)
    return T


def homogeneous_inverse(T):
    """Inverse of a homogeneous transform, ``[[R^T, -R^T r], [0, 0, 0, 1]]``.

    Parameters
    ----------
    T : array_like or sympy.Matrix, shape (4, 4)
        Transform B -> A (see :func:`homogeneous`).

    Returns
    -------
    ndarray or sympy.Matrix, shape (4, 4)
        Transform A -> B (uses ``R^-1 = R^T``; no matrix inversion).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.rotations import C1
    >>> T = homogeneous(C1(0.3), [1.0, 2.0, 3.0])
    >>> np.allclose(homogeneous_inverse(T) @ T, np.eye(4))
    True
    """
    if is_symbolic(T):
        T = sympy_module().Matrix(T)
        Rt = T[:3, :3].T
        return homogeneous(Rt, -Rt * T[:3, 3])
    T = np.asarray(T, dtype=float)
    Rt = T[:3, :3].T
    return homogeneous(Rt, -Rt @ T[:3, 3])


def compose(*transforms):
    """Product of a chain of homogeneous transforms, ``T_AB @ T_BC @ ...``.

    Parameters
    ----------
    *transforms : array_like or sympy.Matrix, shape (4, 4)
        ``T_AB, T_BC, ...``: each places the next frame in the previous one.

    Returns
    -------
    ndarray or sympy.Matrix, shape (4, 4)
        ``T_AZ``, the last frame placed in the first; identity for no arguments.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.rotations import C3
    >>> T = compose(homogeneous(r=[1.0, 0, 0]), homogeneous(C3(0.5)))   # book: T = T1 T2
    >>> np.allclose(T, homogeneous(C3(0.5), [1, 0, 0]))
    True
    """
    sym = is_symbolic(*transforms)
    out = sympy_module().eye(4) if sym else np.eye(4)
    for T in transforms:
        out = out * sympy_module().Matrix(T) if sym else out @ np.asarray(T, dtype=float)
    return out


def transform_points(T, points):
    """Coordinates in frame A of points given in frame B, ``p_A = R @ p_B + r``.

    Parameters
    ----------
    T : array_like or sympy.Matrix, shape (4, 4)
        Transform B -> A.
    points : array_like, shape (3,) or (n, 3), or sympy.Matrix, shape (3, 1)
        Point coordinates in B (length unit of the model).

    Returns
    -------
    ndarray, shape (3,) or (n, 3), or sympy.Matrix, shape (3, 1)
        Coordinates in A. A symbolic call takes one point.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.rotations import C3
    >>> T = homogeneous(C3(np.pi), [0, 0, 1.0])
    >>> transform_points(T, [[1.0, 0, 0], [0, 2.0, 0]]).round(12) + 0.0
    array([[-1.,  0.,  1.],
           [ 0., -2.,  1.]])
    """
    if is_symbolic(T, points):
        T = sympy_module().Matrix(T)
        return T[:3, :3] * as_vector(points, True) + T[:3, 3]
    T = np.asarray(T, dtype=float)
    p = np.asarray(points, dtype=float)
    return p @ T[:3, :3].T + T[:3, 3]


class ScrewMotion(NamedTuple):
    """Chasles' screw of a finite motion: rotation ``angle`` about the line through ``point``
    along ``axis`` combined with the translation ``translation`` along ``axis``.

    Attributes
    ----------
    axis : ndarray, shape (3,)
        Unit vector of the screw axis, reference components.
    angle : float
        Rotation angle in [0, pi] in rad, right-handed about ``axis``.
    translation : float
        Slide along ``axis`` (length unit of the model).
    point : ndarray, shape (3,)
        Point of the axis closest to the reference origin (length unit).

    Examples
    --------
    >>> import numpy as np
    >>> s = ScrewMotion(np.array([0, 0, 1.0]), np.pi, 0.5, np.zeros(3))
    >>> s.translation
    0.5
    """

    axis: Any
    angle: float
    translation: float
    point: Any


def screw_motion(T, tol=1e-12):
    """Screw (Chasles) parameters of a finite rigid motion given as a homogeneous transform.

    Every displacement ``x -> R x + r`` is a rotation by ``angle`` about a line along ``axis``
    through ``point`` plus a slide ``translation`` along that line:
    ``R x + r = R (x - point) + point + translation * axis``.

    Parameters
    ----------
    T : array_like, shape (4, 4)
        Numeric homogeneous transform (see :func:`homogeneous`).
    tol : float
        Rotation angle (rad) below which the motion is treated as a pure translation.

    Returns
    -------
    ScrewMotion
        For a pure translation: ``angle = 0``, ``axis`` along ``r``, ``point = 0`` (any
        parallel line would do); ``axis = (0, 0, 1)`` when ``r = 0`` too.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.rotations import C3
    >>> s = screw_motion(homogeneous(C3(np.pi / 2), [1.0, 1.0, 0.5]))
    >>> np.allclose(s.axis, [0, 0, 1]), abs(s.angle - np.pi / 2) < 1e-12, s.translation
    (True, True, 0.5)
    >>> np.allclose(s.point, [0, 1, 0])
    True
    """
    T = np.asarray(T, dtype=float)
    R, r = T[:3, :3], T[:3, 3]
    c = max(-1.0, min(1.0, 0.5 * (np.trace(R) - 1.0)))
    v = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])  # sin(angle) * axis
    angle = math.atan2(np.linalg.norm(v), c)
    if angle < tol:
        n = r / np.linalg.norm(r) if np.linalg.norm(r) > 0 else np.array([0.0, 0.0, 1.0])
        return ScrewMotion(n, 0.0, float(n @ r), np.zeros(3))
    if c > -0.5:  # well-conditioned skew part
        n = unit(v)
    else:  # near a half turn: axis from the symmetric part, R + R^T - 2c I = 2 (1 - c) n n^T
        S = R + R.T - 2.0 * c * np.eye(3)
        k = int(np.argmax(np.diag(S)))
        n = unit(S[:, k])
        if n @ v < 0:
            n = -n
    d = float(n @ r)
    r_perp = r - d * n
    point = 0.5 * (r_perp + cross(n, r_perp) / math.tan(0.5 * angle))  # (I - R) point = r_perp
    return ScrewMotion(n, angle, d, point)


# ------------------------------------------------------------------------------ moving frame
class VelocityTerms(NamedTuple):
    """Velocity of a point described in a moving frame, term by term (book eq. 1.14).

    Attributes
    ----------
    origin : vector
        ``v_O``, velocity of the frame's origin.
    rotation : vector
        ``omega x r``, due to the frame's rotation.
    relative : vector
        ``v_rel``, velocity seen by an observer moving with the frame.

    Examples
    --------
    >>> t = point_velocity([1.0, 0, 0], [0, 0, 1.0], [1.0, 0, 0])
    >>> t.transport.tolist(), t.total.tolist()
    ([1.0, 1.0, 0.0], [1.0, 1.0, 0.0])
    """

    origin: Any
    rotation: Any
    relative: Any

    @property
    def transport(self):
        """``v_O + omega x r``: velocity of the frame-fixed point coinciding with P."""
        return self.origin + self.rotation

    @property
    def total(self):
        """Absolute velocity ``v_P``."""
        return self.origin + self.rotation + self.relative


class AccelerationTerms(NamedTuple):
    """Acceleration of a point described in a moving frame, term by term (book eq. 1.19).

    Attributes
    ----------
    origin : vector
        ``a_O``, acceleration of the frame's origin.
    euler : vector
        ``alpha x r``, the angular-acceleration (Euler) term.
    centripetal : vector
        ``omega x (omega x r)``.
    coriolis : vector
        ``2 omega x v_rel``.
    relative : vector
        ``a_rel``, acceleration seen by an observer moving with the frame.

    Examples
    --------
    >>> t = point_acceleration([0, 0, 0], [0, 0, 2.0], [0, 0, 0], [1.0, 0, 0])
    >>> t.centripetal.tolist(), t.total.tolist()
    ([-4.0, 0.0, 0.0], [-4.0, 0.0, 0.0])
    """

    origin: Any
    euler: Any
    centripetal: Any
    coriolis: Any
    relative: Any

    @property
    def transport(self):
        """``a_O + alpha x r + omega x (omega x r)``: acceleration of the frame-fixed point
        coinciding with P."""
        return self.origin + self.euler + self.centripetal

    @property
    def total(self):
        """Absolute acceleration ``a_P``."""
        return self.origin + self.euler + self.centripetal + self.coriolis + self.relative


def _vecs(sym, *vs):
    out = []
    for v in vs:
        if v is None:
            v = [0, 0, 0]
        out.append(as_vector(v, sym))
    return out


def _cross(a, b, sym):
    return a.cross(b) if sym else cross(a, b)


def point_velocity(v_O, omega, r, v_rel=None):
    """Velocity of a point P described in a moving frame, ``v_O + omega x r + v_rel``.

    All vectors are resolved in one common frame.

    Parameters
    ----------
    v_O : array_like or sympy.Matrix, shape (3,)
        Velocity of the frame's origin O (m/s).
    omega : array_like or sympy.Matrix, shape (3,)
        Angular velocity of the frame (rad/s).
    r : array_like or sympy.Matrix, shape (3,)
        Position of P relative to O (m).
    v_rel : array_like or sympy.Matrix, shape (3,), optional
        Velocity of P relative to the frame (rates of its frame coordinates) (m/s); zero for
        a frame-fixed point.

    Returns
    -------
    VelocityTerms
        ``origin``, ``rotation``, ``relative`` and the sums ``transport`` and ``total``.

    Examples
    --------
    >>> import sympy as sp
    >>> a, b, p, y = sp.symbols("a b phidot psidot")
    >>> point_velocity([0, 0, 0], [0, p, y], [b, a, 0]).total.T     # the book's Example 1.1
    Matrix([[-a*psidot, b*psidot, -b*phidot]])
    """
    sym = is_symbolic(v_O, omega, r, v_rel)
    v_O, omega, r, v_rel = _vecs(sym, v_O, omega, r, v_rel)
    return VelocityTerms(v_O, _cross(omega, r, sym), v_rel)


def point_acceleration(a_O, omega, alpha, r, v_rel=None, a_rel=None):
    """Acceleration of a point P described in a moving frame, term by term.

    ``a_P = a_O + alpha x r + omega x (omega x r) + 2 omega x v_rel + a_rel``, all vectors
    resolved in one common frame.

    Parameters
    ----------
    a_O : array_like or sympy.Matrix, shape (3,)
        Acceleration of the frame's origin O (m/s^2).
    omega : array_like or sympy.Matrix, shape (3,)
        Angular velocity of the frame (rad/s).
    alpha : array_like or sympy.Matrix, shape (3,)
        Angular acceleration of the frame, the inertial time derivative of ``omega``
        (rad/s^2).
    r : array_like or sympy.Matrix, shape (3,)
        Position of P relative to O (m).
    v_rel, a_rel : array_like or sympy.Matrix, shape (3,), optional
        Velocity (m/s) and acceleration (m/s^2) of P relative to the frame; zero if omitted.

    Returns
    -------
    AccelerationTerms
        ``origin``, ``euler``, ``centripetal``, ``coriolis``, ``relative`` and the sums
        ``transport`` and ``total``.

    Examples
    --------
    >>> import numpy as np
    >>> acc = point_acceleration([0, 0, 0], [0, 0, 1.0], [0, 0, 0], [1.0, 0, 0], v_rel=[1.0, 0, 0])
    >>> acc.coriolis.tolist()
    [0.0, 2.0, 0.0]
    """
    sym = is_symbolic(a_O, omega, alpha, r, v_rel, a_rel)
    a_O, omega, alpha, r, v_rel, a_rel = _vecs(sym, a_O, omega, alpha, r, v_rel, a_rel)
    return AccelerationTerms(a_O, _cross(alpha, r, sym), _cross(omega, _cross(omega, r, sym), sym),
                             2 * _cross(omega, v_rel, sym), a_rel)
