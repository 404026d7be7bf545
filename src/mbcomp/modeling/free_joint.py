"""The free joint: six degrees of freedom between two frames.

The joints the framework itself needs: the topology (:mod:`mbcomp.assembly.topology`)
inserts a :class:`FreeMotion` from the world for a body marked free (``Model.add(...,
free=True)``) in a group of frames joined to nothing that reaches the world, and a
:class:`FreeTranslation` when that body is a lone point mass (no rotation to move). It lives here, below the assembly, so that the
framework never imports the component library; the library re-exports it
(``mbcomp.library.FreeMotion`` is this class), next to the joints written against the same
role contract (:class:`~mbcomp.modeling.roles.Joint`).

Also here: the two pieces the library's other rotating joints share with it,
:func:`quat_increment` (a finite rotation applied to a quaternion) and
:func:`rotation_matrix_problem` (the parameter check of an orientation matrix).

Examples
--------
>>> import numpy as np
>>> from mbcomp.modeling.free_joint import FreeMotion
>>> j = FreeMotion(r0=(1.0, 0.0, 0.0))
>>> q0, q_fixed, u0, u_fixed = j.start(j.p)
>>> q0.tolist()  # position r, then the quaternion Q (identity: no R0 given)
[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
>>> q_fixed.tolist(), bool(u_fixed.any())  # r0 given: fixed; orientation and speeds are free
([True, True, True, False, False, False], False)
"""
from __future__ import annotations

import numpy as np

from ..geometry.kinematics import matrix_to_quat, quat_multiply, quat_rate, quat_to_matrix
from .component import Param
from .roles import Joint, split_start

__all__ = ["FreeMotion", "FreeTranslation", "quat_increment", "rotation_matrix_problem"]


def rotation_matrix_problem(R):
    """Parameter check of an orientation matrix: a message, or ``None`` when ``R`` is one.

    Parameters
    ----------
    R : array_like (3, 3)
        Candidate rotation matrix (dimensionless).

    Returns
    -------
    str or None
        What is wrong (``R R^T != I`` within 1e-9, or ``det R < 0``), else ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.modeling.free_joint import rotation_matrix_problem
    >>> rotation_matrix_problem(np.eye(3)) is None
    True
    >>> rotation_matrix_problem(np.diag([1.0, 1.0, -1.0]))
    'is not a proper rotation matrix (R R^T = I, det R = +1)'
    """
    R = np.asarray(R, float)
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        return "is not a proper rotation matrix (R R^T = I, det R = +1)"
    return None


def _rotvec_quat(d):
    """Unit quaternion ``(w, x, y, z)`` of the rotation vector ``d`` (rad)."""
    ang = np.linalg.norm(d)
    if ang < 1e-300:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.concatenate(([np.cos(ang / 2)], np.sin(ang / 2) * d / ang))


def quat_increment(Q, d):
    """The unit quaternion ``Q`` turned by the rotation vector ``d`` about its own (body) axes.

    Parameters
    ----------
    Q : ndarray (4,)
        Unit quaternion ``(w, x, y, z)``, body -> reference.
    d : ndarray (3,)
        Rotation vector (rad), body axes: angle ``|d|`` about ``d / |d|``.

    Returns
    -------
    ndarray (4,)
        ``Q * exp(d / 2)``, normalized: the exact flow of ``dQ/dt = quat_rate(Q, w)`` over a
        time ``h`` for a constant body rate ``w = d / h``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.modeling.free_joint import quat_increment
    >>> np.round(quat_increment(np.array([1.0, 0, 0, 0]), np.array([0, 0, np.pi])), 12).tolist()
    [0.0, 0.0, 0.0, 1.0]
    """
    Qn = quat_multiply(Q, _rotvec_quat(d))
    return Qn / np.linalg.norm(Qn)


class FreeMotion(Joint):
    """Six-DOF joint: frame_b moves freely relative to frame_a.

    Coordinates: position ``r`` (m, frame_a coordinates) and quaternion ``Q``; speeds:
    ``v = dr/dt`` (m/s, frame_a coordinates) and angular velocity ``w`` (rad/s, frame_b axes).
    A body connected to nothing gets one automatically from the world frame.

    Examples
    --------
    >>> from mbcomp.library import FreeMotion
    >>> j = FreeMotion(r0=(0, 1, 0), w0=(0, 0.1, 3.0))
    >>> j.nq, j.nu
    (7, 6)
    """

    transmits_load = False
    coordinates = (("r.x", "m"), ("r.y", "m"), ("r.z", "m"),
                   ("Q.w", "1"), ("Q.x", "1"), ("Q.y", "1"), ("Q.z", "1"))
    speeds = (("v.x", "m/s"), ("v.y", "m/s"), ("v.z", "m/s"),
              ("w.x", "rad/s"), ("w.y", "rad/s"), ("w.z", "rad/s"))
    r0 = Param(None, unit="m", shape=(3,), kind="start", doc="start position, frame_a coordinates")
    R0 = Param(None, unit="1", shape=(3, 3), kind="start", check=rotation_matrix_problem,
               doc="start orientation, frame_b -> frame_a")
    v0 = Param(None, unit="m/s", shape=(3,), kind="start", doc="start velocity, frame_a coordinates")
    w0 = Param(None, unit="rad/s", shape=(3,), kind="start", doc="start angular velocity, frame_b axes")

    def start(self, p):
        r, rf = split_start(p.r0, 3)
        R, Rf = split_start(p.R0, 9)
        v, vf = split_start(p.v0, 3)
        w, wf = split_start(p.w0, 3)
        Q = matrix_to_quat(R.reshape(3, 3)) if R.size == 9 else np.array([1.0, 0, 0, 0])
        r = r if r.size == 3 else np.zeros(3)
        v = v if v.size == 3 else np.zeros(3)
        w = w if w.size == 3 else np.zeros(3)
        return (np.concatenate((r, Q)), np.array([rf] * 3 + [Rf] * 3),
                np.concatenate((v, w)), np.array([vf] * 3 + [wf] * 3))

    def relative(self, q, p):
        return quat_to_matrix(q[3:]), q[:3]

    def motion(self, q, p):
        R = quat_to_matrix(q[3:])
        Hw = np.zeros((3, 6), dtype=R.dtype)  # object when traced (mbcomp.codegen.symbolic)
        Hw[:, 3:] = R
        Hv = np.zeros((3, 6))
        Hv[:, :3] = np.eye(3)
        return Hw, Hv

    def q_rate(self, q, u, p):
        return np.concatenate((u[:3], quat_rate(q[3:], u[3:])))

    def increment(self, q, du, p):
        return np.concatenate((q[:3] + du[:3], quat_increment(q[3:], du[3:])))

    def constraints(self, a, b, p):
        return []


class FreeTranslation(Joint):
    """Three-DOF joint: frame_b translates freely relative to frame_a, its orientation that of
    frame_a. The topology inserts it, instead of a :class:`FreeMotion`, for a point mass
    added ``free=True`` with nothing else joined to its frame: a point has no rotational
    inertia, so turning it would be motion nothing determines (three massless rotations).

    Coordinates: position ``r`` (m, frame_a coordinates); speeds ``v = dr/dt`` (m/s).
    Only a tree edge from the world: it closes no loop.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.modeling.free_joint import FreeTranslation
    >>> j = FreeTranslation(r0=(0, 1.0, 0), v0=(2.0, 0, 0))
    >>> q0, q_fixed, u0, u_fixed = j.start(j.p)
    >>> q0.tolist(), u0.tolist(), j.motion(q0, j.p)[1].tolist()
    ([0.0, 1.0, 0.0], [2.0, 0.0, 0.0], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    """

    transmits_load = False
    coordinates = (("r.x", "m"), ("r.y", "m"), ("r.z", "m"))
    speeds = (("v.x", "m/s"), ("v.y", "m/s"), ("v.z", "m/s"))
    r0 = Param(None, unit="m", shape=(3,), kind="start", doc="start position, frame_a coordinates")
    v0 = Param(None, unit="m/s", shape=(3,), kind="start", doc="start velocity, frame_a coordinates")

    def start(self, p):
        r, rf = split_start(p.r0, 3)
        v, vf = split_start(p.v0, 3)
        return (r if r.size == 3 else np.zeros(3), np.array([rf] * 3),
                v if v.size == 3 else np.zeros(3), np.array([vf] * 3))

    def relative(self, q, p):
        return np.eye(3), q[:3]

    def motion(self, q, p):
        return np.zeros((3, 3)), np.eye(3)

    def constraints(self, a, b, p):
        raise NotImplementedError(f"{self.path}: a FreeTranslation is only the implicit free joint of a point mass "
                                  "and closes no loop")
