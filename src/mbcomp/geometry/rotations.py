"""Elementary rotations, Euler angles (3-1-3 and 3-2-1) and Euler-angle rates.

Numeric and symbolic in one API
-------------------------------
Every function here works on floats *and* on sympy objects: when any argument holds a
sympy object (a symbol, an expression, an exact number such as ``sympy.pi / 3``, or a
``sympy.Matrix``) the function computes with sympy and returns ``sympy.Matrix`` objects
(vectors as 3 x 1 columns); otherwise it computes with floats and returns numpy arrays.
sympy is only imported on the symbolic path, so the numeric path stays light and fast.

Conventions
-----------
* As everywhere in mbcomp (:mod:`mbcomp.kinematics`), a rotation matrix maps components
  resolved in the rotated (moving) frame to components resolved in the reference frame,
  ``x_ref = R @ x_moving``; its columns are the moving unit vectors in reference components.
* :func:`C1`, :func:`C2`, :func:`C3` are the right-handed rotations by an angle about the
  reference x, y and z axes in this convention, e.g.
  ``C3(a) = [[cos a, -sin a, 0], [sin a, cos a, 0], [0, 0, 1]]``.  Many spacecraft-attitude
  texts (e.g. Hughes) call ``C_i(a)`` the *transpose* of these (the component transformation from the
  reference to the rotated frame); so do the planar transformations in the seed book's
  Examples 1.2 and 1.3.
* Euler angles are given in the order the rotations are applied, each about an axis of the
  frame produced by the previous rotation (intrinsic), and the matrix is the product of the
  elementary rotations in that order:

  - ``"313"`` precession-nutation-spin ``(phi, theta, psi)``:
    ``R = C3(phi) @ C1(theta) @ C3(psi)``;
  - ``"321"`` yaw-pitch-roll ``(psi, theta, phi)``:
    ``R = C3(psi) @ C2(theta) @ C1(phi)``.

* Quaternions are ``(w, x, y, z)``, scalar first, as in :mod:`mbcomp.kinematics`.

Relation to the seed book (ch. 1)
---------------------------------
The book's direction-cosine matrix ``C`` (eqs. 1.25-1.26) maps rotating-frame components to
inertial ones, the same convention as here.  Its ``C1, C2, C3`` of eqs. 1.29-1.32 are the
*first, second and third rotation* of the 3-1-3 sequence, not rotations about axes 1, 2, 3:
book ``C1 = C3(phi)`` (about Z), book ``C2 = C1(theta)`` (about the line of nodes x'),
book ``C3 = C3(psi)`` (about z''), so book ``C1 C2 C3 = euler_to_matrix("313", (phi, theta,
psi))``.  The yaw-pitch-roll matrices ``[R_psi][R_theta][R_phi]`` of eqs. 1.33-1.36 are
``C3(psi) C2(theta) C1(phi) = euler_to_matrix("321", (psi, theta, phi))``, and the finite
rotations ``T1, T2, T3`` of eqs. 1.55-1.57 (about Z, Y, X) are ``C3, C2, C1``.  The book
orders the yaw-pitch-roll rates as ``(phi', theta', psi')`` in eq. 1.40; here rates follow the
angle order ``(psi', theta', phi')``.

Examples
--------
>>> import numpy as np
>>> from mbcomp.rotations import euler_to_matrix, matrix_to_euler
>>> R = euler_to_matrix("321", (0.3, -0.2, 1.1))
>>> np.allclose(matrix_to_euler("321", R), (0.3, -0.2, 1.1))
True
>>> import sympy as sp
>>> t = sp.symbols("theta")
>>> euler_to_matrix("313", (0, t, 0))
Matrix([
[1,          0,           0],
[0, cos(theta), -sin(theta)],
[0, sin(theta),  cos(theta)]])
"""
from __future__ import annotations

import math

import numpy as np

from ..geometry.kinematics import quat_multiply, quat_to_matrix, skew
from .symbolic import as_matrix, as_vector, cos_sin, elements, is_symbolic, sympy_module

__all__ = [
    "C1", "C2", "C3",
    "tilde", "vee",
    "euler_to_matrix", "matrix_to_euler",
    "euler_to_quat", "quat_to_euler",
    "euler_rate_matrix", "euler_rates",
]

SEQUENCES = {"313": (2, 0, 2), "321": (2, 1, 0)}
_NAMES = {"313": ("phi (precession)", "theta (nutation)", "psi (spin)"),
          "321": ("psi (yaw)", "theta (pitch)", "phi (roll)")}
_TINY = 8 * np.finfo(float).eps


# ------------------------------------------------------------------------------ helpers
def _check_seq(seq):
    if seq not in SEQUENCES:
        raise ValueError(f"unknown Euler sequence {seq!r}: use '313' (precession-nutation-spin) "
                         f"or '321' (yaw-pitch-roll)")
    return SEQUENCES[seq]


def _angles(angles, sym):
    a = elements(angles)
    if len(a) != 3:
        raise ValueError(f"expected three Euler angles, got {len(a)}")
    return a if sym else [float(x) for x in a]


def _elementary(axis, angle, sym):
    c, s = cos_sin(sym)
    ca, sa = c(angle), s(angle)
    if axis == 0:
        rows = [[1, 0, 0], [0, ca, -sa], [0, sa, ca]]
    elif axis == 1:
        rows = [[ca, 0, sa], [0, 1, 0], [-sa, 0, ca]]
    else:
        rows = [[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]]
    return as_matrix(rows, sym)


# ------------------------------------------------------------------------------ rotations
def C1(angle):
    """Rotation by ``angle`` about the x axis (moving-to-reference components).

    Parameters
    ----------
    angle : float or sympy expression
        Rotation angle in rad, right-handed about x.

    Returns
    -------
    ndarray or sympy.Matrix, shape (3, 3)
        ``[[1, 0, 0], [0, cos a, -sin a], [0, sin a, cos a]]``; maps components in the rotated
        frame to components in the reference frame (``x_ref = C1(a) @ x_rot``).

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(C1(np.pi / 2) @ [0, 1, 0], [0, 0, 1])
    True
    """
    return _elementary(0, angle, is_symbolic(angle))


def C2(angle):
    """Rotation by ``angle`` about the y axis (moving-to-reference components).

    Parameters
    ----------
    angle : float or sympy expression
        Rotation angle in rad, right-handed about y.

    Returns
    -------
    ndarray or sympy.Matrix, shape (3, 3)
        ``[[cos a, 0, sin a], [0, 1, 0], [-sin a, 0, cos a]]`` (``x_ref = C2(a) @ x_rot``).

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(C2(np.pi / 2) @ [0, 0, 1], [1, 0, 0])
    True
    """
    return _elementary(1, angle, is_symbolic(angle))


def C3(angle):
    """Rotation by ``angle`` about the z axis (moving-to-reference components).

    Parameters
    ----------
    angle : float or sympy expression
        Rotation angle in rad, right-handed about z.

    Returns
    -------
    ndarray or sympy.Matrix, shape (3, 3)
        ``[[cos a, -sin a, 0], [sin a, cos a, 0], [0, 0, 1]]`` (``x_ref = C3(a) @ x_rot``).

    Examples
    --------
    >>> import sympy as sp
    >>> C3(sp.pi / 2) * sp.Matrix([1, 0, 0])
    Matrix([
    [0],
    [1],
    [0]])
    """
    return _elementary(2, angle, is_symbolic(angle))


def tilde(a):
    """Skew-symmetric (cross-product) matrix ``a~`` of a 3-vector, the book's eq. 1.7.

    Parameters
    ----------
    a : array_like or sympy.Matrix, shape (3,)
        Vector (any unit), resolved in some frame; ``tilde(a) @ b == a x b`` for ``b``
        resolved in the same frame.

    Returns
    -------
    ndarray or sympy.Matrix, shape (3, 3)
        ``[[0, -a3, a2], [a3, 0, -a1], [-a2, a1, 0]]``; the numeric path is
        :func:`mbcomp.kinematics.skew`.

    Examples
    --------
    >>> import sympy as sp
    >>> w1, w2, w3 = sp.symbols("omega1:4")
    >>> tilde([w1, w2, w3])
    Matrix([
    [      0, -omega3,  omega2],
    [ omega3,       0, -omega1],
    [-omega2,  omega1,       0]])
    """
    if not is_symbolic(a):
        return skew(np.asarray(a, dtype=float).reshape(3))
    x, y, z = as_vector(a, True)
    return sympy_module().Matrix([[0, -z, y], [z, 0, -x], [-y, x, 0]])


def vee(S):
    """Axial vector ``a`` of a skew-symmetric matrix ``S = tilde(a)`` (inverse of :func:`tilde`).

    Parameters
    ----------
    S : array_like or sympy.Matrix, shape (3, 3)
        Skew-symmetric matrix; only its skew part is used, ``a = vee((S - S^T) / 2)``.

    Returns
    -------
    ndarray, shape (3,), or sympy.Matrix, shape (3, 1)
        ``(S[2, 1], S[0, 2], S[1, 0])`` of the skew part.

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(vee(tilde([1.0, 2.0, 3.0])), [1, 2, 3])
    True
    """
    sym = is_symbolic(S)
    if sym:
        S = sympy_module().Matrix(S)
        return sympy_module().Matrix([(S[2, 1] - S[1, 2]) / 2, (S[0, 2] - S[2, 0]) / 2, (S[1, 0] - S[0, 1]) / 2])
    S = np.asarray(S, dtype=float)
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


# ------------------------------------------------------------------------------ Euler angles
def euler_to_matrix(seq, angles):
    """Rotation matrix of an Euler-angle triple.

    Parameters
    ----------
    seq : {"313", "321"}
        ``"313"``: precession-nutation-spin ``(phi, theta, psi)``,
        ``R = C3(phi) @ C1(theta) @ C3(psi)`` (the book's ``C1 C2 C3``, eq. 1.32);
        ``"321"``: yaw-pitch-roll ``(psi, theta, phi)``, ``R = C3(psi) @ C2(theta) @ C1(phi)``
        (the book's ``[R_psi][R_theta][R_phi]``, eq. 1.36).
    angles : sequence of 3 floats or sympy expressions
        Angles in rad, in the order the rotations are applied.

    Returns
    -------
    ndarray or sympy.Matrix, shape (3, 3)
        Maps body (moving-frame) components to reference components.

    Examples
    --------
    >>> import numpy as np
    >>> R = euler_to_matrix("313", (0.4, 0.5, 0.6))
    >>> np.allclose(R, C3(0.4) @ C1(0.5) @ C3(0.6))
    True
    """
    axes = _check_seq(seq)
    sym = is_symbolic(angles)
    a = _angles(angles, sym)
    R = _elementary(axes[0], a[0], sym)
    for ax, ang in zip(axes[1:], a[1:]):
        R = R * _elementary(ax, ang, True) if sym else R @ _elementary(ax, ang, False)
    return R


def matrix_to_euler(seq, R):
    """Euler angles of a rotation matrix.

    Parameters
    ----------
    seq : {"313", "321"}
        Euler sequence (see :func:`euler_to_matrix`).
    R : array_like or sympy.Matrix, shape (3, 3)
        Rotation matrix, body-to-reference components.

    Returns
    -------
    ndarray, shape (3,), or sympy.Matrix, shape (3, 1)
        Angles in rad in rotation order. ``"313"``: ``phi, psi`` in (-pi, pi],
        ``theta`` in [0, pi]. ``"321"``: ``psi, phi`` in (-pi, pi], ``theta`` in [-pi/2, pi/2].

    Notes
    -----
    Gimbal lock (``"313"``: ``sin(theta) = 0``; ``"321"``: ``cos(theta) = 0``): only the sum or
    difference of the first and third angle is defined there. The numeric path computes
    that combination from matrix entries that stay well conditioned, takes the third angle
    from its own entries (set to 0 when they vanish to round-off) and the first angle as the
    remainder, so the returned triple always reproduces ``R`` to round-off. The symbolic path
    returns the plain ``atan2``/``acos``/``asin`` formulas, valid away from gimbal lock.

    Examples
    --------
    >>> import numpy as np
    >>> matrix_to_euler("313", C3(0.7)).round(12) + 0.0    # gimbal lock: all in phi
    array([0.7, 0. , 0. ])
    >>> np.allclose(matrix_to_euler("313", euler_to_matrix("313", (1.0, 2.0, -3.0))), (1, 2, -3))
    True
    """
    _check_seq(seq)
    if is_symbolic(R):
        sp = sympy_module()
        R = sp.Matrix(R)
        if seq == "313":
            return sp.Matrix([sp.atan2(R[0, 2], -R[1, 2]), sp.acos(R[2, 2]), sp.atan2(R[2, 0], R[2, 1])])
        return sp.Matrix([sp.atan2(R[1, 0], R[0, 0]), sp.asin(-R[2, 0]), sp.atan2(R[2, 1], R[2, 2])])
    R = np.asarray(R, dtype=float)
    if seq == "313":
        s = math.hypot(R[2, 0], R[2, 1])  # sin(theta) >= 0
        theta = math.atan2(s, R[2, 2])
        psi = math.atan2(R[2, 0], R[2, 1]) if s > _TINY else 0.0
        if R[2, 2] >= 0.0:  # R11 + R22 = (1 + cos th) cos(phi + psi), R21 - R12 = (1 + cos th) sin(..)
            first = math.atan2(R[1, 0] - R[0, 1], R[0, 0] + R[1, 1]) - psi
        else:  # R11 - R22 = (1 - cos th) cos(phi - psi), R21 + R12 = (1 - cos th) sin(..)
            first = math.atan2(R[1, 0] + R[0, 1], R[0, 0] - R[1, 1]) + psi
        return np.array([_wrap(first), theta, psi])
    c = math.hypot(R[2, 1], R[2, 2])  # cos(theta) >= 0
    theta = math.atan2(-R[2, 0], c)
    phi = math.atan2(R[2, 1], R[2, 2]) if c > _TINY else 0.0
    if R[2, 0] <= 0.0:  # sin th >= 0: R22 + R13 = (1 + sin th) cos(psi - phi), R23 - R12 = (..) sin
        first = math.atan2(R[1, 2] - R[0, 1], R[1, 1] + R[0, 2]) + phi
    else:  # R22 - R13 = (1 - sin th) cos(psi + phi), R23 + R12 = -(1 - sin th) sin(psi + phi)
        first = math.atan2(-(R[1, 2] + R[0, 1]), R[1, 1] - R[0, 2]) - phi
    return np.array([_wrap(first), theta, phi])


def _wrap(a):
    """Angle mapped into (-pi, pi]."""
    a = math.remainder(a, 2 * math.pi)
    return math.pi if a == -math.pi else a


def _axis_quat(axis, angle, sym):
    c, s = cos_sin(sym)
    q = [c(angle / 2), 0, 0, 0]
    q[1 + axis] = s(angle / 2)
    return q


def euler_to_quat(seq, angles):
    """Unit quaternion of an Euler-angle triple.

    Parameters
    ----------
    seq : {"313", "321"}
        Euler sequence (see :func:`euler_to_matrix`).
    angles : sequence of 3 floats or sympy expressions
        Angles in rad, in rotation order.

    Returns
    -------
    ndarray, shape (4,), or sympy.Matrix, shape (4, 1)
        ``(w, x, y, z)``, the product of the three elementary quaternions
        (:func:`mbcomp.kinematics.quat_multiply`); numeric results have ``w >= 0`` like
        :func:`mbcomp.kinematics.matrix_to_quat`, symbolic ones are the plain product.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.kinematics import quat_to_matrix
    >>> Q = euler_to_quat("321", (0.3, 0.2, 0.1))
    >>> np.allclose(quat_to_matrix(Q), euler_to_matrix("321", (0.3, 0.2, 0.1)))
    True
    """
    axes = _check_seq(seq)
    sym = is_symbolic(angles)
    a = _angles(angles, sym)
    Q = _axis_quat(axes[0], a[0], sym)
    for ax, ang in zip(axes[1:], a[1:]):
        Q = quat_multiply(Q, _axis_quat(ax, ang, sym))
    if sym:
        return sympy_module().Matrix(list(Q))
    Q = np.asarray(Q, dtype=float)
    return Q if Q[0] >= 0 else -Q


def quat_to_euler(seq, Q):
    """Euler angles of a quaternion.

    Parameters
    ----------
    seq : {"313", "321"}
        Euler sequence (see :func:`euler_to_matrix`).
    Q : array_like or sympy.Matrix, shape (4,)
        Quaternion ``(w, x, y, z)``; numeric input is normalized, symbolic input is assumed
        to be a unit quaternion.

    Returns
    -------
    ndarray, shape (3,), or sympy.Matrix, shape (3, 1)
        Angles in rad, as :func:`matrix_to_euler` (including its gimbal-lock handling).

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(quat_to_euler("313", euler_to_quat("313", (0.1, 0.2, 0.3))), (0.1, 0.2, 0.3))
    True
    """
    if not is_symbolic(Q):
        return matrix_to_euler(seq, quat_to_matrix(Q))
    sp = sympy_module()
    Q = list(sp.Matrix(Q))
    conj = [Q[0], -Q[1], -Q[2], -Q[3]]
    cols = []
    for k in range(3):  # R e_k = vector part of Q (0, e_k) Q*
        e = [0, 0, 0, 0]
        e[1 + k] = 1
        cols.append([sp.expand(x) for x in quat_multiply(quat_multiply(Q, e), conj)[1:]])
    return matrix_to_euler(seq, sp.Matrix(cols).T)


# ------------------------------------------------------------------------------ rates
def euler_rate_matrix(seq, angles, frame="body"):
    """Matrix ``E`` giving the angular velocity from Euler-angle rates, ``omega = E @ rates``.

    Parameters
    ----------
    seq : {"313", "321"}
        Euler sequence (see :func:`euler_to_matrix`).
    angles : sequence of 3 floats or sympy expressions
        Angles in rad, in rotation order.
    frame : {"body", "space"}
        ``"body"``: ``omega`` resolved in the rotated (body) frame, ``tilde(omega) = R^T dR/dt``;
        ``"space"``: resolved in the reference frame, ``tilde(omega) = dR/dt R^T``.

    Returns
    -------
    ndarray or sympy.Matrix, shape (3, 3)
        ``E`` such that ``omega = E @ (rate1, rate2, rate3)`` (rad/s), rates in rotation order.
        Body frame, ``"313"`` ``(phi, theta, psi)``::

            [[sin th sin psi,  cos psi, 0],
             [sin th cos psi, -sin psi, 0],
             [cos th,          0,       1]]

        (the book's eq. 1.38, whose (2, 2) entry is misprinted ``-sin phi``); body frame,
        ``"321"`` ``(psi, theta, phi)``::

            [[-sin th,         0,      1],
             [ cos th sin phi,  cos phi, 0],
             [ cos th cos phi, -sin phi, 0]]

        (the book's eq. 1.40 with its columns in the order roll, pitch, yaw).
        Space frame: ``R @ E_body``.

    Examples
    --------
    >>> import numpy as np
    >>> E = euler_rate_matrix("313", (0.0, 0.5, 0.0))
    >>> np.allclose(E @ [0.0, 0.0, 2.0], [0, 0, 2])     # pure spin about body z
    True
    """
    _check_seq(seq)
    if frame not in ("body", "space"):
        raise ValueError(f"frame must be 'body' or 'space', got {frame!r}")
    sym = is_symbolic(angles)
    a1, th, a3 = _angles(angles, sym)
    c, s = cos_sin(sym)
    if seq == "313":
        phi, psi = a1, a3
        if frame == "body":
            rows = [[s(th) * s(psi), c(psi), 0], [s(th) * c(psi), -s(psi), 0], [c(th), 0, 1]]
        else:
            rows = [[0, c(phi), s(phi) * s(th)], [0, s(phi), -c(phi) * s(th)], [1, 0, c(th)]]
    else:
        psi, phi = a1, a3
        if frame == "body":
            rows = [[-s(th), 0, 1], [c(th) * s(phi), c(phi), 0], [c(th) * c(phi), -s(phi), 0]]
        else:
            rows = [[0, -s(psi), c(psi) * c(th)], [0, c(psi), s(psi) * c(th)], [1, 0, -s(th)]]
    return as_matrix(rows, sym)


def euler_rates(seq, angles, omega, frame="body", tol=1e-12):
    """Euler-angle rates from an angular velocity (the inverse of :func:`euler_rate_matrix`).

    Parameters
    ----------
    seq : {"313", "321"}
        Euler sequence (see :func:`euler_to_matrix`).
    angles : sequence of 3 floats or sympy expressions
        Angles in rad, in rotation order.
    omega : array_like or sympy.Matrix, shape (3,)
        Angular velocity in rad/s, resolved as ``frame`` says.
    frame : {"body", "space"}
        Frame ``omega`` is resolved in (see :func:`euler_rate_matrix`).
    tol : float
        Numeric gimbal-lock threshold on ``|sin theta|`` (``"313"``) or ``|cos theta|``
        (``"321"``), dimensionless.

    Returns
    -------
    ndarray, shape (3,), or sympy.Matrix, shape (3, 1)
        Rates in rad/s, in rotation order.

    Raises
    ------
    ValueError
        At gimbal lock, where ``E`` is singular: ``"313"`` at ``sin(theta) = 0``
        (nutation 0 or pi: precession and spin axes coincide), ``"321"`` at ``cos(theta) = 0``
        (pitch +-pi/2: yaw and roll axes coincide). Symbolic input raises only when the
        determining factor is exactly zero; otherwise the result contains it as a divisor.

    Examples
    --------
    >>> import numpy as np
    >>> ang = (0.2, 0.3, 0.4)
    >>> w = euler_rate_matrix("321", ang, "space") @ [1.0, 2.0, 3.0]
    >>> np.allclose(euler_rates("321", ang, w, "space"), [1, 2, 3])
    True
    """
    _check_seq(seq)
    if frame not in ("body", "space"):
        raise ValueError(f"frame must be 'body' or 'space', got {frame!r}")
    sym = is_symbolic(angles, omega)
    a1, th, a3 = _angles(angles, sym)
    wx, wy, wz = as_vector(omega, sym)
    c, s = cos_sin(sym)
    d = s(th) if seq == "313" else c(th)
    if (sym and d == 0) or (not sym and abs(d) <= tol):
        name = _NAMES[seq][1]
        cond = "sin(theta) = 0: precession and spin axes coincide" if seq == "313" else \
            "cos(theta) = 0: yaw and roll axes coincide"
        raise ValueError(f"gimbal lock of the {seq} Euler angles at {name} = {th}: {cond}, "
                         f"the Euler-angle rates are not determined by the angular velocity")
    if seq == "313":
        phi, psi = a1, a3
        if frame == "body":
            r1 = (s(psi) * wx + c(psi) * wy) / d
            r2 = c(psi) * wx - s(psi) * wy
            r3 = wz - c(th) * r1
        else:
            r3 = (s(phi) * wx - c(phi) * wy) / d
            r2 = c(phi) * wx + s(phi) * wy
            r1 = wz - c(th) * r3
    else:
        psi, phi = a1, a3
        if frame == "body":
            r1 = (s(phi) * wy + c(phi) * wz) / d
            r2 = c(phi) * wy - s(phi) * wz
            r3 = wx + s(th) * r1
        else:
            r3 = (c(psi) * wx + s(psi) * wy) / d
            r2 = -s(psi) * wx + c(psi) * wy
            r1 = wz + s(th) * r3
    if sym:
        return sympy_module().Matrix([r1, r2, r3])
    return np.array([r1, r2, r3])
