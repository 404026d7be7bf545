"""Second-order kinematic jets: a quantity with its velocity Jacobian and bias acceleration.

Every frame in an assembled model is described by a :class:`FrameJet`: its pose, its
velocity split into ``J @ u`` plus any prescribed (rheonomic) part, and its *bias*
acceleration (the acceleration when ``du/dt = 0``). Chaining joints along the spanning
tree with :meth:`FrameJet.through` gives every frame's jet in one pass, so the mass
matrix, forces, constraint Jacobians and the acceleration right-hand side follow without
symbolic differentiation.

Cut-joint constraints are written with :class:`VecJet`/:class:`ScalarJet`, whose Jacobians
are taken with respect to the 12 local twist components ``(v_a, w_a, v_b, w_b)`` of the
joint's two frames (world coordinates). The product rule is applied to value, velocity and
bias together, so a joint only writes its position-level constraint.

Examples
--------
>>> import numpy as np
>>> from mbcomp.jets import FrameJet
>>> g = FrameJet.ground(nu=1)
>>> arm = g.through(np.eye(3), np.zeros(3), Hw=np.array([[0.], [0.], [1.]]),
...                 Hv=np.zeros((3, 1)), cols=slice(0, 1), w_rel=np.array([0, 0, 2.0]))
>>> tip = arm.offset(np.eye(3), np.array([1.0, 0, 0]))
>>> tip.v, tip.a  # velocity and centripetal (bias) acceleration of the tip
(array([0., 2., 0.]), array([-4.,  0.,  0.]))

Tracing (object scalars)
------------------------
The jet recursion, :meth:`mbcomp.system.MultibodySystem.evaluate` and the standard library
are plain numpy arithmetic, so they also run on numpy *object* arrays whose elements are
*traced scalars*: a sympy-backed scalar gives the symbolic equations of motion
(:mod:`mbcomp.symbolic`), a graph-building scalar gives a straight-line program. The
protocol a traced scalar class must follow:

* class attribute ``__mbcomp_traced__ = True`` (what :func:`is_traced` tests; library code
  skips numeric-only checks such as ``isfinite`` or ``L < 1e-12`` for such values);
* arithmetic ``+ - * / **`` with plain numbers (Python or numpy ints and floats) and with other
  traced scalars, on both sides (``__radd__``, ``__rsub__``, ``__rmul__``, ``__rtruediv__``,
  ``__rpow__``), and unary ``-``, ``+``, ``abs()``;
* every binary operator returns ``NotImplemented`` when the other operand is an
  ``np.ndarray``, so that numpy broadcasts the operation over the array elementwise;
* no ``__array_priority__``/``__array_ufunc__``;
* methods called by numpy's object-dtype ufuncs: ``cos``, ``sin``, ``tan``, ``arcsin``,
  ``arccos``, ``arctan``, ``arctan2(other)``, ``sqrt``, ``exp``, ``log``, ``sinh``, ``cosh``,
  ``tanh`` (``np.cos(x)`` calls ``x.cos()``, ``np.linalg.norm`` uses ``*``, ``+`` and ``sqrt``);
* no truth value and no number: ``__bool__`` should raise ``TypeError`` with a clear message
  (``if x < 0`` in a law cannot be traced), and ``__float__``/``__int__`` should not be defined
  (``float(x)``, ``math.sin(x)`` then raise ``TypeError``; sympy's ``sympify`` calls ``__float__``
  on any object that has it).

A traced evaluation passes ``q`` and ``u`` as object arrays (``t`` may be a traced scalar);
arrays created inside an evaluation then take dtype ``object``, numeric ones stay ``float``
(the dtype is chosen once per call, so the numeric path is unchanged). Parameters, joint
axes and start values may stay numbers: they meet traced values in ordinary arithmetic.
"""
from __future__ import annotations

import numpy as np

from ..geometry.kinematics import cross as _cross, cross_entries as _cx, entries as _e, skew

__all__ = ["FrameJet", "VecJet", "ScalarJet", "local_point", "local_vector", "rigid_constraints",
           "position_constraints", "velocity_along", "slip_velocity", "is_traced", "as_array"]


def is_traced(x):
    """True if ``x`` is a traced scalar (see *Tracing* above) or an object array.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.jets import is_traced
    >>> is_traced(1.5), is_traced(np.zeros(2)), is_traced(np.zeros(2, dtype=object))
    (False, False, True)
    """
    if isinstance(x, np.ndarray):
        return x.dtype == object
    return getattr(type(x), "__mbcomp_traced__", False)


def as_array(x):
    """``x`` as a float array, or as an object array if it holds traced scalars.

    Examples
    --------
    >>> from mbcomp.jets import as_array
    >>> as_array([1, 2]).dtype
    dtype('float64')
    """
    a = np.asarray(x)
    return a if a.dtype == object else a.astype(float, copy=False)


#: the zero motion of a pose-only jet (read-only: shared by every such jet)
_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)


def _obj(J):
    return J if J.dtype == object else J.astype(object)


# The jets' 3-vector arithmetic is done on their entries (kinematics.entries: Python numbers, or
# the traced values themselves) and each result made an array once: numpy's elementwise
# operations one by one, in the same order, on operands of three cost more in calls than in
# arithmetic. Matrix products stay numpy's (``.dot``: the same BLAS call as ``@``, a quarter of
# its overhead; on object arrays the same sums in the same order).
def _add(a, b):
    return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]


def _sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def _scaled(c, a):
    return [c * a[0], c * a[1], c * a[2]]


class _Memo:
    """What is made once per jet: :func:`local_vector`'s results by vector (``vectors``, numbers
    only; None until asked) -- kept apart from the jet's own fields (``FrameJet.__slots__``)."""

    __slots__ = ("vectors",)


class FrameJet(_Memo):
    """Pose, velocity and bias acceleration of a frame, with Jacobians w.r.t. speeds ``u``.

    Attributes
    ----------
    R : ndarray (3, 3)
        Orientation: frame coordinates -> world coordinates.
    r : ndarray (3,)
        Origin position in m, world coordinates.
    w, v : ndarray (3,)
        Angular velocity (rad/s) and origin velocity (m/s), world coordinates, total.
    Jw, Jv : ndarray (3, nu)
        Their Jacobians with respect to the speeds ``u``.
    alpha, a : ndarray (3,)
        Bias angular and linear accelerations (those at ``du/dt = 0``), world coordinates.
    """

    __slots__ = ("R", "r", "w", "v", "Jw", "Jv", "alpha", "a")

    def __init__(self, R, r, w, v, Jw, Jv, alpha, a):
        self.R, self.r, self.w, self.v = R, r, w, v
        self.Jw, self.Jv, self.alpha, self.a = Jw, Jv, alpha, a
        self.vectors = None  # local_vector's results on this jet, by vector (numbers only)

    @classmethod
    def ground(cls, nu, R=None, r=None):
        z = np.zeros(3)
        return cls(_EYE.copy() if R is None else as_array(R), z.copy() if r is None else as_array(r),
                   z.copy(), z.copy(), np.zeros((3, nu)), np.zeros((3, nu)), z.copy(), z.copy())

    def offset(self, R0, p0):
        """Jet of a frame rigidly attached at ``p0`` (m, this frame's coordinates), rotated by ``R0``."""
        R = self.R
        rho = R.dot(p0)
        r0, r1, r2 = rh = rho.tolist()
        w0, w1, w2 = self.w.tolist()
        l0, l1, l2 = self.alpha.tolist()
        a0, a1, a2 = self.a.tolist()
        v0, v1, v2 = self.v.tolist()
        x0, x1, x2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0  # w x rho
        a = [(a0 + (l1 * r2 - l2 * r1)) + (w1 * x2 - w2 * x1), (a1 + (l2 * r0 - l0 * r2)) + (w2 * x0 - w0 * x2),
             (a2 + (l0 * r1 - l1 * r0)) + (w0 * x1 - w1 * x0)]
        return FrameJet(R.dot(R0), self.r + rho, self.w, np.array([v0 + x0, v1 + x1, v2 + x2]), self.Jw,
                        self.Jv - skew(rh).dot(self.Jw), self.alpha, np.array(a))

    def offset_pose(self, R0, p0):
        """:meth:`offset`'s pose and Jacobians alone (the same operations, so the same bits):
        ``w``, ``v``, ``alpha``, ``a`` are left zero, for a pass that needs the inertias only."""
        rho = self.R.dot(p0)
        Jw = self.Jw
        Jv = self.Jv - skew(rho).dot(Jw) if Jw.shape[1] else self.Jv  # no columns: nothing to move
        return FrameJet(self.R.dot(R0), self.r + rho, _ZERO3, _ZERO3, Jw, Jv, _ZERO3, _ZERO3)

    def pose_through(self, R_rel, r_rel, Hw, Hv, forward=True):
        """:meth:`through` (``forward``) or :meth:`back_through` without the motion, from a
        jet without Jacobian columns (a link's parent, :mod:`~mbcomp.assembly.recursive`): the
        pose and the joint's own ``k`` columns -- what those give a parent whose ``k`` columns
        are zero, bit for bit (``0 + Ra Hw``; ``0 - [rho]x 0`` is ``+0`` for a finite ``rho``);
        ``w``, ``v``, ``alpha``, ``a`` zero -- for a pass that needs the inertias only (float jets)."""
        if forward:
            Ra = self.R
            rho = Ra.dot(r_rel)
            return FrameJet(Ra.dot(R_rel), self.r + rho, _ZERO3, _ZERO3, 0.0 + Ra.dot(Hw), 0.0 + Ra.dot(Hv),
                            _ZERO3, _ZERO3)
        Ra = self.R.dot(R_rel.T)
        rho = Ra.dot(r_rel)
        Jw = 0.0 - Ra.dot(Hw)
        Jv = (0.0 + skew(rho).dot(Jw)) - Ra.dot(Hv)
        return FrameJet(Ra, self.r - rho, _ZERO3, _ZERO3, Jw, Jv, _ZERO3, _ZERO3)

    def through(self, R_rel, r_rel, Hw, Hv, cols, w_rel, v_rel=None, bw=None, bv=None):
        """Jet of a joint's ``frame_b`` given this jet as its ``frame_a``.

        Parameters
        ----------
        R_rel, r_rel : pose of frame_b in frame_a coordinates.
        Hw, Hv : ndarray (3, k)
            Relative angular velocity / d(r_rel)/dt in frame_a coordinates per joint speed.
        cols : slice or index array
            Columns of the joint's speeds in the global ``u``.
        w_rel, v_rel : ndarray (3,)
            Total relative angular velocity and d(r_rel)/dt (frame_a coordinates).
        bw, bv : ndarray (3,), optional
            Relative bias accelerations in frame_a coordinates (e.g. a prescribed ``a(t)``).
        """
        Ra = self.R
        rho = Ra.dot(r_rel)
        wr = Ra.dot(w_rel).tolist()
        rh, w = rho.tolist(), self.w.tolist()
        Jw = self.Jw.copy()
        Jv = self.Jv - skew(rh).dot(self.Jw)
        if Hw.shape[1]:
            try:
                Jw[:, cols] += Ra.dot(Hw)
                Jv[:, cols] += Ra.dot(Hv)
            except TypeError:  # traced update of a float Jacobian: widen to object (see Tracing)
                Jw, Jv = self.Jw.astype(object), _obj(Jv)
                Jw[:, cols] += Ra.dot(Hw)
                Jv[:, cols] += Ra.dot(Hv)
        r0, r1, r2 = rh
        w0, w1, w2 = w
        s0, s1, s2 = vr = Ra.dot(v_rel).tolist() if v_rel is not None else [0.0, 0.0, 0.0]
        l0, l1, l2 = self.alpha.tolist()
        a0, a1, a2 = self.a.tolist()
        v0, v1, v2 = self.v.tolist()
        x0, x1, x2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0  # w x rho
        alpha = _add([l0, l1, l2], _cx(w, wr))
        a = [((a0 + (l1 * r2 - l2 * r1)) + (w1 * x2 - w2 * x1)) + 2.0 * (w1 * s2 - w2 * s1),
             ((a1 + (l2 * r0 - l0 * r2)) + (w2 * x0 - w0 * x2)) + 2.0 * (w2 * s0 - w0 * s2),
             ((a2 + (l0 * r1 - l1 * r0)) + (w0 * x1 - w1 * x0)) + 2.0 * (w0 * s1 - w1 * s0)]
        if bw is not None:
            alpha = _add(alpha, _e(Ra.dot(bw)))
        if bv is not None:
            a = _add(a, _e(Ra.dot(bv)))
        return FrameJet(Ra.dot(R_rel), self.r + rho, np.array(_add(w, wr)),
                        np.array([(v0 + x0) + s0, (v1 + x1) + s1, (v2 + x2) + s2]), Jw, Jv, np.array(alpha), np.array(a))

    def back_through(self, R_rel, r_rel, Hw, Hv, cols, w_rel, v_rel=None, bw=None, bv=None):
        """Jet of a joint's ``frame_a`` given this jet as its ``frame_b`` (same arguments as
        :meth:`through`): the joint traversed against its direction in the spanning tree."""
        Ra = self.R.dot(R_rel.T)
        rho = Ra.dot(r_rel)
        rh, wr = _e(rho), _e(Ra.dot(w_rel))
        w = _sub(_e(self.w), wr)
        Jw = self.Jw.copy()
        if Hw.shape[1]:
            try:
                Jw[:, cols] -= Ra.dot(Hw)
            except TypeError:  # traced update of a float Jacobian
                Jw = self.Jw.astype(object)
                Jw[:, cols] -= Ra.dot(Hw)
        alpha = _sub(_sub(_e(self.alpha), _cx(w, wr)), _e(Ra.dot(bw)) if bw is not None else (0.0, 0.0, 0.0))
        vr = _e(Ra.dot(v_rel)) if v_rel is not None else [0.0, 0.0, 0.0]
        wxr = _cx(w, rh)
        Jv = self.Jv + skew(rh).dot(Jw)
        if Hv.shape[1]:
            try:
                Jv[:, cols] -= Ra.dot(Hv)
            except TypeError:  # traced update of a float Jacobian
                Jv = Jv.astype(object)
                Jv[:, cols] -= Ra.dot(Hv)
        a = _sub(_sub(_sub(_sub(_e(self.a), _cx(alpha, rh)), _cx(w, wxr)), _scaled(2.0, _cx(w, vr))),
                 _e(Ra.dot(bv)) if bv is not None else (0.0, 0.0, 0.0))
        return FrameJet(Ra, self.r - rho, np.array(w), np.array(_sub(_sub(_e(self.v), wxr), vr)), Jw, Jv,
                        np.array(alpha), np.array(a))


class VecJet:
    """A vector (world coordinates) with its Jacobian ``jac`` (3, 12) w.r.t. the local
    twists ``(v_a, w_a, v_b, w_b)``, its total rate ``dot`` and its bias acceleration."""

    __slots__ = ("val", "jac", "dot", "bias")

    def __init__(self, val, jac, dot, bias):
        self.val, self.jac, self.dot, self.bias = val, jac, dot, bias

    def __sub__(self, o):
        return VecJet(self.val - o.val, self.jac - o.jac, self.dot - o.dot, self.bias - o.bias)

    def __add__(self, o):
        return VecJet(self.val + o.val, self.jac + o.jac, self.dot + o.dot, self.bias + o.bias)

    def dot_(self, o):
        """Scalar product, as a :class:`ScalarJet` (the rate's and bias' products of three on
        the entries: numpy's dot of three adds them in this order)."""
        a, b = self.val, o.val
        a0, a1, a2 = _e(a)
        b0, b1, b2 = _e(b)
        c0, c1, c2 = _e(self.dot)
        d0, d1, d2 = _e(o.dot)
        e0, e1, e2 = _e(self.bias)
        f0, f1, f2 = _e(o.bias)
        return ScalarJet(
            a.dot(b),
            b.dot(self.jac) + a.dot(o.jac),
            (c0 * b0 + c1 * b1 + c2 * b2) + (a0 * d0 + a1 * d1 + a2 * d2),
            (e0 * b0 + e1 * b1 + e2 * b2) + 2.0 * (c0 * d0 + c1 * d1 + c2 * d2) + (a0 * f0 + a1 * f1 + a2 * f2),
        )

    def cross_(self, o):
        """Vector product ``self x o``, as a :class:`VecJet`."""
        a, b = _e(self.val), _e(o.val)
        return VecJet(
            np.array(_cx(a, b)),
            skew(a).dot(o.jac) - skew(b).dot(self.jac),
            np.array(_add(_cx(self.dot, b), _cx(a, o.dot))),
            np.array(_add(_add(_cx(self.bias, b), _scaled(2.0, _cx(self.dot, o.dot))), _cx(a, o.bias))),
        )

    def times(self, c):
        """The vector scaled by a constant ``c`` (number, or a parameter when traced)."""
        return VecJet(self.val * c, self.jac * c, self.dot * c, self.bias * c)

    def scaled(self, s):
        """The vector scaled by a :class:`ScalarJet` ``s`` (product rule)."""
        return VecJet(
            self.val * s.val,
            np.outer(self.val, s.jac) + self.jac * s.val,
            self.val * s.dot + self.dot * s.val,
            self.val * s.bias + 2.0 * self.dot * s.dot + self.bias * s.val,
        )

    def norm(self):
        """Length ``|self|`` as a :class:`ScalarJet` (undefined for a zero vector)."""
        return self.dot_(self).sqrt()

    def unit(self):
        """``self / |self|`` as a :class:`VecJet`."""
        return self.scaled(self.norm().recip())


class ScalarJet:
    """A scalar with Jacobian ``jac`` (12,) w.r.t. the local twists, rate and bias."""

    __slots__ = ("val", "jac", "dot", "bias")

    def __init__(self, val, jac, dot, bias):
        self.val, self.jac, self.dot, self.bias = val, jac, dot, bias

    def __add__(self, o):
        return ScalarJet(self.val + o.val, self.jac + o.jac, self.dot + o.dot, self.bias + o.bias)

    def __sub__(self, o):
        return ScalarJet(self.val - o.val, self.jac - o.jac, self.dot - o.dot, self.bias - o.bias)

    def times(self, c):
        """The scalar scaled by a constant ``c``."""
        return ScalarJet(self.val * c, self.jac * c, self.dot * c, self.bias * c)

    def sqrt(self):
        """``sqrt(self)`` (chain rule to second order; the value must be positive)."""
        s = np.sqrt(self.val)
        h = 0.5 / s
        return ScalarJet(s, self.jac * h, self.dot * h, self.bias * h - self.dot * self.dot * h * h * h * 2.0)

    def recip(self):
        """``1 / self`` (chain rule to second order; the value must be nonzero)."""
        r = 1.0 / self.val
        r2 = r * r
        return ScalarJet(r, -self.jac * r2, -self.dot * r2, -self.bias * r2 + 2.0 * self.dot * self.dot * r2 * r)


#: the Jacobian of a frame's origin w.r.t. the local twists, frame_a's and frame_b's (read-only)
_POINT_JAC = [np.zeros((3, 12)), np.zeros((3, 12))]
for _slot, _jac in enumerate(_POINT_JAC):
    _jac[:, 6 * _slot: 6 * _slot + 3] = np.eye(3)
    _jac.setflags(write=False)


def local_point(F: FrameJet, slot: int) -> VecJet:
    """Origin of frame ``F`` as a :class:`VecJet`; ``slot`` 0 for frame_a, 1 for frame_b."""
    return VecJet(F.r, _POINT_JAC[slot], F.v, F.a)


def local_vector(F: FrameJet, e, slot: int) -> VecJet:
    """Vector ``e`` fixed in frame ``F`` (given in its coordinates) as a :class:`VecJet`.

    On numbers, made once per jet, vector (its bits) and slot: the cut joints of a loop that
    meet at one frame ask for the same axes of it (Andrews' mechanism: ten of eighteen). The
    :class:`VecJet` is shared: read, never written."""
    if type(e) is np.ndarray and e.dtype == float and F.R.dtype == float:
        memo = F.vectors
        if memo is None:
            memo = F.vectors = {}
        key = (e.tobytes(), slot)
        hit = memo.get(key)
        if hit is None:
            hit = memo[key] = _local_vector(F, e, slot)
        return hit
    return _local_vector(F, e, slot)


def _local_vector(F, e, slot):
    x = F.R.dot(e)
    x0, x1, x2 = x.tolist()
    w0, w1, w2 = F.w.tolist()
    l0, l1, l2 = F.alpha.tolist()
    minus_skew = np.array([[-0.0, x2, -x1], [-x2, -0.0, x0], [x1, -x0, -0.0]])  # -skew(x): -(-a) is a
    jac = np.zeros((3, 12), dtype=minus_skew.dtype)
    jac[:, 6 * slot + 3: 6 * slot + 6] = minus_skew
    y0, y1, y2 = w1 * x2 - w2 * x1, w2 * x0 - w0 * x2, w0 * x1 - w1 * x0  # w x x
    return VecJet(x, jac, np.array([y0, y1, y2]), np.array([(l1 * x2 - l2 * x1) + (w1 * y2 - w2 * y1),
                                                            (l2 * x0 - l0 * x2) + (w2 * y0 - w0 * y2),
                                                            (l0 * x1 - l1 * x0) + (w0 * y1 - w1 * y0)]))


def velocity_along(point: VecJet, direction: VecJet) -> ScalarJet:
    """Velocity-level constraint ``g = (d point/dt) . direction`` (e.g. no lateral slip).

    ``g`` is linear in the twists: its gradient is ``direction . jac(point)``; its time
    derivative at ``du/dt = 0`` is ``bias(point) . direction + (d point/dt) . (d direction/dt)``.
    """
    d = direction.val
    return ScalarJet(point.dot @ d, d @ point.jac, np.nan, point.bias @ d + point.dot @ direction.dot)


def slip_velocity(a: FrameJet, b: FrameJet, P: VecJet) -> VecJet:
    """Velocity of frame_b's material point at ``P`` relative to frame_a's material point at
    ``P`` (m/s, world coordinates), as a jet for :func:`velocity_along`: rolling without
    slip is ``velocity_along(slip_velocity(a, b, P), t) = 0`` for the contact tangents ``t``.

    ``P`` is the geometric contact point (a :class:`VecJet` built from the two frames); it
    moves over both bodies, so the bias carries ``w x (dP/dt - v)`` for each body. The
    returned jet's ``dot`` is the slip velocity itself, ``jac`` its gradient with respect to
    the local twists, ``bias`` its time derivative at ``du/dt = 0``; ``val`` is ``P``.

    Examples
    --------
    A wheel of radius 0.5 m spinning at 2 rad/s about y, its centre moving at 1 m/s along x,
    on a ground plane (frame_a at rest): the point touching the ground has zero velocity.

    >>> import numpy as np
    >>> from mbcomp.jets import FrameJet, local_point, slip_velocity
    >>> ground = FrameJet.ground(nu=0)
    >>> z = np.zeros(3)
    >>> wheel = FrameJet(np.eye(3), np.array([0, 0, 0.5]), np.array([0, 2.0, 0]), np.array([1.0, 0, 0]),
    ...                  np.zeros((3, 0)), np.zeros((3, 0)), z, z)
    >>> P = local_point(ground, 0)  # the contact point: the ground origin below the centre
    >>> slip_velocity(ground, wheel, P).dot
    array([0., 0., 0.])
    """
    ra, rb = P.val - a.r, P.val - b.r
    jac = np.zeros((3, 12), dtype=skew(rb).dtype)
    eye = np.eye(3)
    jac[:, 0:3] = -eye
    jac[:, 3:6] = skew(ra)
    jac[:, 6:9] = eye
    jac[:, 9:12] = -skew(rb)
    dot = b.v + _cross(b.w, rb) - a.v - _cross(a.w, ra)
    bias = (b.a + _cross(b.alpha, rb) + _cross(b.w, P.dot - b.v)
            - a.a - _cross(a.alpha, ra) - _cross(a.w, P.dot - a.v))
    return VecJet(P.val, jac, dot, bias)


_E = _EYE = np.eye(3)


def position_constraints(a: FrameJet, b: FrameJet, r0=None):
    """Three constraints ``r_b = r_a + R_a r0`` (resolved along frame_a's axes), named x, y, z."""
    d = local_point(b, 1) - local_point(a, 0)
    if r0 is not None and (is_traced(r0) or np.any(r0)):
        d = d - local_vector(a, r0, 0)
    return [(ax, d.dot_(local_vector(a, _E[i], 0))) for i, ax in enumerate("xyz")]


def rigid_constraints(a: FrameJet, b: FrameJet, R0, r0):
    """Six constraints ``r_b = r_a + R_a r0`` and ``R_b = R_a R0`` as named scalar jets:
    positions along frame_a's axes (x, y, z), rotations as dot products of frame_b's axes
    with the target axes (rx, ry, rz; first order in small rotations about x, y, z)."""
    out = position_constraints(a, b, r0)
    tgt = [local_vector(a, R0 @ _E[i], 0) for i in range(3)]
    bb = [local_vector(b, _E[i], 1) for i in range(3)]
    for name, (i, j) in (("rx", (1, 2)), ("ry", (2, 0)), ("rz", (0, 1))):
        out.append((name, bb[i].dot_(tgt[j])))
    return out
