"""Rotations, quaternions and small vector helpers (numeric, numpy).

``cross``, ``skew``, ``rot_axis`` (with a numeric axis), ``quat_to_matrix``, ``quat_multiply``
and ``quat_rate`` also accept traced scalars (see :mod:`mbcomp.jets`, *Tracing*).

Conventions used throughout mbcomp
----------------------------------
* A rotation matrix ``R`` maps coordinates resolved in a moving frame to
  coordinates resolved in the reference frame: ``x_ref = R @ x_moving``.
  Its columns are the moving frame's unit vectors resolved in the reference frame.
* Quaternions are ``(w, x, y, z)`` with ``w`` the scalar part; a unit
  quaternion ``Q`` and its rotation matrix ``R(Q)`` follow the same mapping.

Examples
--------
>>> import numpy as np
>>> from mbcomp.kinematics import rot_axis, quat_to_matrix, matrix_to_quat
>>> R = rot_axis([0, 0, 1], np.pi / 2)
>>> np.allclose(R @ [1, 0, 0], [0, 1, 0])
True
>>> np.allclose(quat_to_matrix(matrix_to_quat(R)), R)
True
"""
from __future__ import annotations

import math

import numpy as np

__all__ = [
    "entries",
    "cross_entries",
    "added",
    "cross",
    "skew",
    "unit",
    "rot_axis",
    "by_axis",
    "quat_to_matrix",
    "matrix_to_quat",
    "quat_multiply",
    "quat_rate",
    "perpendicular_pair",
]


def entries(a):
    """The entries of a 3-vector as Python numbers (``tolist``: a float64's value exactly, a
    traced value itself), whose arithmetic is several times cheaper than numpy scalars' and
    than numpy's on arrays of three: the same IEEE operations, so the same bits."""
    return a.tolist() if type(a) is np.ndarray else a


def cross_entries(a, b):
    """``cross(a, b)`` as a list of three Python numbers (:func:`entries` of each)."""
    a0, a1, a2 = a.tolist() if type(a) is np.ndarray else a
    b0, b1, b2 = b.tolist() if type(b) is np.ndarray else b
    return [a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0]


def added(a, *more):
    """``a + b + ...`` of 3-vectors, left to right, as a list of :func:`entries`."""
    a = a.tolist() if type(a) is np.ndarray else a
    for b in more:
        b = b.tolist() if type(b) is np.ndarray else b
        a = [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    return a


def cross(a, b):
    """Cross product of two 3-vectors (much faster than ``numpy.cross`` for single vectors):
    the products and differences of their :func:`entries`, half the time of indexing the arrays."""
    return np.array(cross_entries(a, b))


def skew(a):
    """Skew-symmetric matrix ``S`` with ``S @ b == cross(a, b)``.

    Parameters
    ----------
    a : array_like, shape (3,)
        Vector, any unit, any frame (the result is resolved in the same frame).
    """
    x, y, z = a.tolist() if type(a) is np.ndarray else a
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def unit(a):
    """Unit vector along ``a`` (shape (3,)); raises ``ValueError`` for a zero vector."""
    a = np.asarray(a, dtype=float)
    n = math.sqrt(a.dot(a)) if a.ndim == 1 else np.linalg.norm(a)  # numpy.linalg.norm's sum and root
    if not np.isfinite(n) or n == 0.0:
        raise ValueError("zero or non-finite vector has no direction")
    return a / n


_EYE = np.eye(3)
_EYE.setflags(write=False)
#: what :func:`rot_axis` and :func:`perpendicular_pair` make of an axis, by the axis' bits
#: (a cache hit is the computation's own result); bounded
_BY_AXIS = {}


def by_axis(what, axis, make):
    """``make(a)`` for the axis ``a`` (``axis`` as a float array), made once per ``what`` and
    value of the axis (a tuple of read-only arrays, shared: never written). The conversion to
    floats is made once per call, as an uncached computation does (a traced parameter's
    value is baked there, its guard kept: :mod:`mbcomp.codegen.graph`)."""
    a = np.asarray(axis, dtype=float)
    key = (what, a.tobytes())  # the bits: -0.0 is not 0.0 here
    hit = _BY_AXIS.get(key)
    if hit is None:
        hit = make(a)
        for M in hit:
            M.setflags(write=False)
        if len(_BY_AXIS) >= 4096:
            _BY_AXIS.clear()
        _BY_AXIS[key] = hit
    return hit


def _rodrigues(a):
    N = skew(unit(a))
    return N, N.dot(N)


def rot_axis(axis, angle):
    """Rotation matrix of a rotation by ``angle`` (rad) about ``axis`` (Rodrigues).

    ``N`` (the unit axis' cross matrix) and ``N @ N`` are made once per axis (the joints'
    axes are constants: half of a hinge's kinematics); ``angle`` may be traced.

    Parameters
    ----------
    axis : array_like, shape (3,)
        Rotation axis (normalized here), resolved in the reference frame.
    angle : float
        Rotation angle in rad, right-handed about ``axis``.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(rot_axis([1, 0, 0], np.pi / 2) @ [0, 1, 0], 12) + 0.0
    array([0., 0., 1.])
    """
    N, NN = by_axis("rodrigues", axis, _rodrigues)
    c, s = np.cos(angle), np.sin(angle)
    return _EYE + s * N + (1.0 - c) * NN


def quat_to_matrix(Q):
    """Rotation matrix of quaternion ``Q = (w, x, y, z)`` (normalized here).

    Traced (object) quaternions give an object matrix (see :mod:`mbcomp.jets`, *Tracing*).
    """
    Q = np.asarray(Q)
    if Q.dtype != object:
        Q = Q.astype(float, copy=False)
    w, x, y, z = Q / np.sqrt(Q @ Q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(R):
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of rotation matrix ``R`` (Shepperd);
    for a stack of matrices ``(..., 3, 3)`` the quaternions ``(..., 4)``, one numpy pass.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.kinematics import matrix_to_quat, rot_axis
    >>> matrix_to_quat(rot_axis((0, 0, 1), np.pi / 2)).round(6).tolist()
    [0.707107, 0.0, 0.0, 0.707107]
    >>> matrix_to_quat(np.stack([np.eye(3), rot_axis((1, 0, 0), np.pi)])).round(6).tolist()
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]
    """
    R = np.asarray(R, dtype=float)
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = np.moveaxis(R, (-2, -1), (0, 1)).copy()  # contiguous
    tr = r00 + r11 + r22
    # Shepperd: divide by the largest of 4w^2, 4x^2, 4y^2, 4z^2 (1 + tr, 1 + 2 R_kk - tr)
    k = np.argmax(np.stack([tr, r00, r11, r22]), axis=0)
    big = 0.5 * np.sqrt(np.maximum(np.choose(k, [1.0 + tr, 1.0 + 2 * r00 - tr, 1.0 + 2 * r11 - tr, 1.0 + 2 * r22 - tr]),
                                   0.0))
    with np.errstate(divide="ignore", invalid="ignore"):  # d > 0 on the chosen branch
        d = 1.0 / (4.0 * big)
        s21, s02, s10 = (r21 - r12) * d, (r02 - r20) * d, (r10 - r01) * d
        p01, p02, p12 = (r01 + r10) * d, (r02 + r20) * d, (r12 + r21) * d
    Q = np.stack([np.choose(k, [big, s21, s02, s10]), np.choose(k, [s21, big, p01, p02]),
                  np.choose(k, [s02, p01, big, p12]), np.choose(k, [s10, p02, p12, big])], axis=-1)
    Q = Q / np.linalg.norm(Q, axis=-1, keepdims=True)
    return np.where(Q[..., :1] >= 0, Q, -Q)


def quat_multiply(p, q):
    """Hamilton product ``p * q`` of two quaternions ``(w, x, y, z)``."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return np.array(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ]
    )


def quat_rate(Q, w_body):
    """Time derivative of quaternion ``Q`` for angular velocity ``w_body``.

    Parameters
    ----------
    Q : array_like, shape (4,)
        Orientation of the moving frame.
    w_body : array_like, shape (3,)
        Angular velocity in rad/s, resolved in the *moving* frame.

    Returns
    -------
    ndarray, shape (4,)
        ``0.5 * Q * (0, w_body)``.
    """
    return 0.5 * quat_multiply(Q, np.concatenate(([0.0], w_body)))


def perpendicular_pair(n):
    """Two unit vectors ``t1, t2`` with ``(t1, t2, n)`` right-handed orthonormal (made once
    per axis: read-only arrays)."""
    return by_axis("pair", n, _pair)


def _pair(n):
    n = unit(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = unit(cross(helper, n))
    t2 = cross(n, t1)
    return t1, t2
