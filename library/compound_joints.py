"""Joints of more than one degree of freedom built from elementary motions: the universal
(Cardan, Hooke) joint and the planar joint.

Like :mod:`mbcomp.library.joints`, each joint is its relative motion (tree edge), its
constraint equations (cut joint) and its default shapes; the assembler computes the
reactions (``f``/``tau`` on frame_b through the joint, frame_b axes) for both.
"""
import numpy as np

from mbcomp import Box, Cylinder, Joint, Param
from mbcomp.errors import Problem
from mbcomp.jets import local_point, local_vector, position_constraints
from mbcomp.kinematics import cross, rot_axis
from mbcomp.modeling.shapes import z_to
from mbcomp.roles import split_start

#: largest |cos| of the angle between two directions that must be perpendicular
_PERPENDICULAR_TOL = 1e-9


def _unit(v):
    return v / np.linalg.norm(v)


def _perpendicular_problem(comp, p, first, second, fix):
    """A :class:`Problem` list: ``p.<second>`` must be perpendicular to ``p.<first>``."""
    a, b = (np.asarray(getattr(p, name), dtype=float) for name in (first, second))
    cos = float(_unit(a) @ _unit(b))
    if abs(cos) <= _PERPENDICULAR_TOL:
        return []
    angle = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return [Problem(f"{comp.path}.{second}",
                    f"{second}={b.tolist()} is at {angle:.6g} deg to {first}={a.tolist()}, not at 90 deg", fix)]


def _starts(p, names):
    """Start coordinates or speeds from the parameters ``names`` (one number each):
    ``(values, fixed flags)``."""
    pairs = [split_start(getattr(p, name), 1) for name in names]
    return np.concatenate([v for v, _ in pairs]), np.array([f for _, f in pairs])


class Universal(Joint):
    """Universal (Cardan, Hooke) joint: two perpendicular hinges through one point.

    frame_b is turned first about ``n_a`` (frame_a coordinates) by ``phi_a``, then about
    ``n_b`` (coordinates of the intermediate frame, the cross piece, which coincide with
    frame_a's at ``phi_a = 0`` and with frame_b's always) by ``phi_b``:
    ``R_rel = rot(n_a, phi_a) rot(n_b, phi_b)``; the origins coincide. ``n_a`` is fixed in
    frame_a, ``n_b`` in frame_b, and they stay perpendicular. Coordinates ``phi_a``,
    ``phi_b`` (rad), speeds ``w_a``, ``w_b`` (their rates, rad/s). No 1-D flanges.

    As a loop-closing (cut) joint: three rows ``x``, ``y``, ``z`` (coincident origins, m)
    and ``cross`` (``n_a . n_b`` in world coordinates, 1).

    On the spanning tree the relative angular velocity ``w_a n_a + w_b rot(n_a, phi_a) n_b``
    (frame_a axes) changes at constant speeds by ``w_a w_b n_a x rot(n_a, phi_a) n_b``: a
    velocity-product term no choice of two speeds avoids (the plane of the possible relative
    angular velocities turns with ``phi_a``). :meth:`motion_bias` returns it; the
    assembler must add it to frame_b's bias acceleration for a Universal on the tree.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import Universal
    >>> j = Universal(n_a=(1, 0, 0), n_b=(0, 1, 0), phi_a0=np.pi / 2, phi_b0=0.0)
    >>> R, r = j.relative([np.pi / 2, 0.0], j.p)
    >>> np.round(R @ [0, 1, 0], 12).tolist()       # n_b turned with the cross piece
    [0.0, 0.0, 1.0]
    >>> Universal(n_a=(1, 0, 0), n_b=(1, 1, 0)).problems()[0].where.endswith("n_b")   # not perpendicular
    True
    """

    coordinates = (("phi_a", "rad"), ("phi_b", "rad"))
    speeds = (("w_a", "rad/s"), ("w_b", "rad/s"))
    n_a = Param((1.0, 0.0, 0.0), unit="1", shape=(3,), check="nonzero",
                doc="first hinge axis (fixed in frame_a), frame_a coordinates")
    n_b = Param((0.0, 1.0, 0.0), unit="1", shape=(3,), check="nonzero",
                doc="second hinge axis (fixed in frame_b), perpendicular to n_a; frame_b coordinates")
    phi_a0 = Param(None, unit="rad", kind="start", doc="start angle about n_a (fixed unless a Guess)")
    w_a0 = Param(None, unit="rad/s", kind="start", doc="start rate about n_a (fixed unless a Guess)")
    phi_b0 = Param(None, unit="rad", kind="start", doc="start angle about n_b (fixed unless a Guess)")
    w_b0 = Param(None, unit="rad/s", kind="start", doc="start rate about n_b (fixed unless a Guess)")

    def check_params(self, p):
        return _perpendicular_problem(self, p, "n_a", "n_b",
                                      "give n_b perpendicular to n_a, e.g. n_a=(1, 0, 0), n_b=(0, 1, 0)")

    def visuals(self, p, view):
        """Two short crossed cylinders: the hinge along n_a on frame_a, the one along n_b on frame_b."""
        radius, length = 0.015 * view.scale, 0.1 * view.scale
        return [Cylinder(radius, length, R=z_to(p.n_a), color="grey"),
                Cylinder(radius, length, R=z_to(p.n_b), frame="frame_b", color="grey")]

    def start(self, p):
        q, qf = _starts(p, ("phi_a0", "phi_b0"))
        u, uf = _starts(p, ("w_a0", "w_b0"))
        return q, qf, u, uf

    def relative(self, q, p):
        return rot_axis(p.n_a, q[0]) @ rot_axis(p.n_b, q[1]), np.zeros(3)

    def _second_axis(self, q, p):
        """``n_b`` in frame_a coordinates: turned about ``n_a`` by ``phi_a``."""
        return rot_axis(p.n_a, q[0]) @ _unit(p.n_b)

    def motion(self, q, p):
        return np.column_stack((_unit(p.n_a), self._second_axis(q, p))), np.zeros((3, 2))

    def motion_bias(self, q, u, p):
        """``(bw, bv)``: the rates of ``Hw u`` and ``Hv u`` at constant speeds ``u`` (frame_a
        axes; rad/s^2 and m/s^2): ``w_a w_b n_a x rot(n_a, phi_a) n_b`` and zero."""
        return cross(_unit(p.n_a), self._second_axis(q, p)) * (u[0] * u[1]), np.zeros(3)

    def constraints(self, a, b, p):
        crossing = local_vector(a, _unit(p.n_a), 0).dot_(local_vector(b, _unit(p.n_b), 1))
        return position_constraints(a, b) + [("cross", crossing)]


class Planar(Joint):
    """Planar joint: frame_b slides in the plane through frame_a's origin normal to ``n``
    and turns about ``n``.

    With ``e_x`` along ``n_x`` and ``e_y = n x e_x`` (frame_a axes), frame_b's origin is at
    ``s_x e_x + s_y e_y`` and ``R_rel = rot(n, phi)``. Coordinates ``s_x``, ``s_y`` (m),
    ``phi`` (rad); speeds ``v_x``, ``v_y`` (m/s, the origin's velocity along ``e_x``,
    ``e_y``) and ``w`` (rad/s, about ``n``). No 1-D flanges.

    As a loop-closing (cut) joint: three rows, ``off`` (frame_b's origin out of the plane, m)
    and ``tilt_1``, ``tilt_2`` (frame_b's ``n`` along ``e_x``, ``e_y`` of frame_a, 1).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import Planar
    >>> j = Planar(n=(0, 0, 1), n_x=(1, 0, 0), x0=0.3, y0=-0.2, phi0=np.pi / 2)
    >>> R, r = j.relative([0.3, -0.2, np.pi / 2], j.p)
    >>> r.tolist(), np.round(R @ [1, 0, 0], 12).tolist()
    ([0.3, -0.2, 0.0], [0.0, 1.0, 0.0])
    """

    coordinates = (("s_x", "m"), ("s_y", "m"), ("phi", "rad"))
    speeds = (("v_x", "m/s"), ("v_y", "m/s"), ("w", "rad/s"))
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), check="nonzero",
              doc="normal of the plane (rotation axis), frame_a coordinates")
    n_x = Param((1.0, 0.0, 0.0), unit="1", shape=(3,), check="nonzero",
                doc="direction of s_x in the plane (perpendicular to n), frame_a coordinates")
    x0 = Param(None, unit="m", kind="start", doc="start position along n_x (fixed unless a Guess)")
    y0 = Param(None, unit="m", kind="start", doc="start position along n x n_x (fixed unless a Guess)")
    phi0 = Param(None, unit="rad", kind="start", doc="start angle about n (fixed unless a Guess)")
    vx0 = Param(None, unit="m/s", kind="start", doc="start velocity along n_x (fixed unless a Guess)")
    vy0 = Param(None, unit="m/s", kind="start", doc="start velocity along n x n_x (fixed unless a Guess)")
    w0 = Param(None, unit="rad/s", kind="start", doc="start angular rate about n (fixed unless a Guess)")

    def check_params(self, p):
        return _perpendicular_problem(self, p, "n", "n_x",
                                      "give n_x in the plane, perpendicular to n, e.g. n=(0, 0, 1), n_x=(1, 0, 0)")

    def visuals(self, p, view):
        """A thin square plate normal to n, on frame_a (the plane the joint keeps)."""
        side = 0.3 * view.scale
        return [Box((side, side, 0.01 * view.scale), R=z_to(p.n), color="grey", opacity=0.5)]

    def _axes(self, p):
        """``(e_x, e_y, n)``: unit vectors of the plane and its normal, frame_a coordinates."""
        n = _unit(p.n)
        e_x = _unit(p.n_x)
        return e_x, cross(n, e_x), n

    def start(self, p):
        q, qf = _starts(p, ("x0", "y0", "phi0"))
        u, uf = _starts(p, ("vx0", "vy0", "w0"))
        return q, qf, u, uf

    def relative(self, q, p):
        e_x, e_y, n = self._axes(p)
        return rot_axis(n, q[2]), e_x * q[0] + e_y * q[1]

    def motion(self, q, p):
        e_x, e_y, n = self._axes(p)
        z = np.zeros(3)
        return np.column_stack((z, z, n)), np.column_stack((e_x, e_y, z))

    def constraints(self, a, b, p):
        e_x, e_y, n = self._axes(p)
        d = local_point(b, 1) - local_point(a, 0)
        n_b = local_vector(b, n, 1)
        return [("off", d.dot_(local_vector(a, n, 0))),
                ("tilt_1", n_b.dot_(local_vector(a, e_x, 0))), ("tilt_2", n_b.dot_(local_vector(a, e_y, 0)))]
