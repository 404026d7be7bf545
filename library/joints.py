"""Joints: relative kinematics, loop-closure constraints, and 1-D axis flanges.

Each joint is three short pieces: its relative motion (tree edge), its constraint
equations (cut joint), and its axis (where drives and springs act). Reactions are computed
by the assembler for every joint: ``f``/``tau`` exerted on frame_b through the joint,
resolved in frame_b.

:class:`FreeMotion` (six DOF) is the framework's own joint
(:mod:`mbcomp.modeling.free_joint`: the topology inserts it for floating bodies); it is
re-exported here, so ``mbcomp.library.FreeMotion`` is that class.
"""
import numpy as np

from mbcomp import Cylinder, Flange, Joint, Param, Sphere
from mbcomp.errors import Problem
from mbcomp.jets import local_point, local_vector, position_constraints, rigid_constraints
from mbcomp.kinematics import by_axis, cross, matrix_to_quat, perpendicular_pair, quat_rate, quat_to_matrix, rot_axis
from mbcomp.modeling.events import AxisRow, EventRow, Impact, Switch
from mbcomp.modeling.modes import Modes
from mbcomp.modeling.free_joint import FreeMotion, quat_increment  # noqa: F401  (FreeMotion: re-exported)
from mbcomp.modeling.shapes import z_to
from mbcomp.roles import split_start

from .checks import rotation_matrix
from .friction import _Friction
from .parts import _Rigid

_E = np.eye(3)


def _axis(p):
    """The unit axis of ``p.n``: made once per value of a numeric axis (read-only, shared), afresh
    for a traced one."""
    n = p.n
    if type(n) is np.ndarray and n.dtype.kind == "f":
        return by_axis("unit", n, _unit)[0]
    return n / np.linalg.norm(n)


def _unit(n):
    return (n / np.linalg.norm(n),)


def _start1(value):
    """``split_start(value, 1)`` of a 1-DOF joint's start value: a plain number without its
    array calls (the same array), anything else (None, a Guess, an array) by it."""
    if type(value) is float:
        return np.array([value]), True
    return split_start(value, 1)


def _limits_ok(lim):
    return None if lim[0] < lim[1] else f"lower limit {lim[0]:g} must be below the upper {lim[1]:g}"


class StopModes(Modes):
    """The modes of rigid stops on a 1-DOF joint's coordinate ``s`` (rad or m).

    Mode ``"free"`` between the limits, with events ``"lo"`` (``s - lo`` falling through zero)
    and ``"hi"`` (``hi - s`` falling) whose action is an impact with Newton's restitution;
    modes ``"lo"``/``"hi"``: engaged at that limit (a row ``s = lo`` or ``s = hi``), left when
    the row would pull (``"release"``), and the mode a chattering impact settles in.

    Parameters
    ----------
    lo, hi : float
        The limits (rad or m), ``lo < hi``.
    restitution : float
        Newton's coefficient (1) of the impacts.

    Examples
    --------
    >>> m = StopModes(-0.5, 0.5, restitution=0.8)
    >>> m.start, m.events([0.2], [1.0], "free")
    ('free', [('lo', 0.7, -1), ('hi', 0.3, -1)])
    >>> m.action("hi", "free"), m.rows("hi"), m.action("release", "hi")
    (Impact(restitution=0.8, engage='hi'), [AxisRow(name='hi', sign=-1.0, at=0.5)], Switch(mode='free'))
    """

    def __init__(self, lo, hi, restitution):
        super().__init__("free")
        self.lo, self.hi, self.restitution = float(lo), float(hi), float(restitution)

    linear_events = True

    def event_rows(self, mode):
        """The distances (rad or m) to each limit while free, as rows of ``s``."""
        if mode != "free":
            return []
        return [EventRow("lo", "q", 0, 1.0, self.lo, -1), EventRow("hi", "q", 0, -1.0, self.hi, -1)]

    def events(self, q, u, mode):
        """The distances (rad or m) to each limit while free (:meth:`event_rows`' values)."""
        return [(r.name, r.value(q, u), r.direction) for r in self.event_rows(mode)]

    def action(self, name, mode):
        """An impact engaging the limit hit; free again at a ``"release"``."""
        if name == "release":
            return Switch("free")
        return Impact(self.restitution, engage=name)

    def rows(self, mode):
        """The :class:`~mbcomp.modeling.events.AxisRow` of the engaged limit."""
        if mode not in ("lo", "hi"):
            return []
        return [AxisRow(mode, 1.0 if mode == "lo" else -1.0, self.lo if mode == "lo" else self.hi)]

    def rest(self, name, mode):
        """Engaged at the limit whose impacts chatter."""
        return name if name in ("lo", "hi") else None


class _Stops:
    """Rigid stops on a 1-DOF joint's coordinate: ``limits=(lo, hi)``, ``restitution=e``
    (:class:`StopModes`). A compliant stop is a flange element on the axis
    (:class:`mbcomp.library.ElasticStop`), with no events.
    """

    def modes(self, p):
        if p.limits is None:
            return super().modes(p)
        return StopModes(p.limits[0], p.limits[1], p.restitution)

    def check_params(self, p):
        """A start coordinate outside the limits is a problem naming both (the stops would
        never let the joint there)."""
        if p.limits is None:
            return []
        s0 = self.start(p)[0]
        lo, hi = p.limits
        if s0.size and not lo <= float(s0[0]) <= hi:
            name = self.coordinates[0][0]
            return [Problem(f"{self.path}.{name}0", f"start value {float(s0[0]):g} is outside the stops "
                            f"limits=({lo:g}, {hi:g})", f"start {name} between {lo:g} and {hi:g}, or widen the limits")]
        return []


class Revolute(_Friction, _Stops, Joint):
    """Hinge: frame_b rotates about ``n`` (frame_a coordinates) by angle ``phi``.

    Coordinates ``phi`` (rad) and speed ``w`` (rad/s). Flanges ``axis``/``support`` let
    drives, springs and dampers act on ``phi``.

    Examples
    --------
    >>> from mbcomp.library import Revolute
    >>> j = Revolute(n=(0, 0, 1), phi0=0.5, w0=1.0)
    >>> j.start(j.p)[0]
    array([0.5])
    """

    coordinates = (("phi", "rad"),)
    speeds = (("w", "rad/s"),)
    axis_kind = "rotational"
    axis = Flange("rotational axis flange (phi, torque about the axis)", optional=True)
    support = Flange("support flange at phi = 0 (fixed to frame_a)", optional=True)
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), doc="hinge axis direction, frame_a coordinates", check="nonzero")
    phi0 = Param(None, unit="rad", kind="start", doc="start angle (fixed; wrap in Guess to let init move it)")
    w0 = Param(None, unit="rad/s", kind="start", doc="start angular rate (fixed unless a Guess)")
    limits = Param(None, unit="rad", shape=(2,), check=_limits_ok,
                   doc="rigid stops (lo, hi) on phi: impacts there, resting engaged (none by default)")
    restitution = Param(0.0, unit="1", check=lambda e: None if 0 <= e <= 1 else "must be in [0, 1]",
                        doc="Newton's restitution coefficient of the stops")
    friction = Param(None, unit="1", kind="any",
                     doc="Coulomb friction with stick/slip events: CoulombBearing(torque_max, torque_c) (N m)")

    def visuals(self, p, view):
        """A short cylinder along the hinge axis, on frame_a."""
        return [Cylinder(0.025 * view.scale, 0.1 * view.scale, R=z_to(p.n), color="grey")]

    def start(self, p):
        q, qf = _start1(p.phi0)
        u, uf = _start1(p.w0)
        return q, np.array([qf]), u, np.array([uf])

    def relative(self, q, p):
        return rot_axis(p.n, q[0]), np.zeros(3)

    def motion(self, q, p):
        return _axis(p)[:, None], np.zeros((3, 1))

    def constraints(self, a, b, p):
        n = _axis(p)
        t1, t2 = perpendicular_pair(n)
        nb = local_vector(b, n, 1)
        return position_constraints(a, b) + [
            ("tilt_1", nb.dot_(local_vector(a, t1, 0))), ("tilt_2", nb.dot_(local_vector(a, t2, 0)))]

    def axis_world(self, R_a, p):
        return R_a @ _axis(p)

    def measure(self, a, b, p):
        n = _axis(p)
        t1, t2 = perpendicular_pair(n)
        tb = b.R @ t1
        phi = np.arctan2((a.R @ t2) @ tb, (a.R @ t1) @ tb)
        return phi, (b.w - a.w) @ (a.R @ n)


class Prismatic(_Friction, _Stops, Joint):
    """Slider: frame_b translates along ``n`` (frame_a coordinates) by ``s``.

    Coordinate ``s`` (m), speed ``v`` (m/s); flanges ``axis``/``support`` along the axis.

    Examples
    --------
    >>> from mbcomp.library import Prismatic
    >>> j = Prismatic(n=(1, 0, 0), s0=0.2)
    >>> j.relative([0.2], j.p)[1]
    array([0.2, 0. , 0. ])
    """

    coordinates = (("s", "m"),)
    speeds = (("v", "m/s"),)
    axis_kind = "translational"
    axis = Flange("translational axis flange (s, force along the axis)", optional=True)
    support = Flange("support flange at s = 0 (fixed to frame_a)", optional=True)
    n = Param((1.0, 0.0, 0.0), unit="1", shape=(3,), doc="sliding axis direction, frame_a coordinates", check="nonzero")
    s0 = Param(None, unit="m", kind="start", doc="start position (fixed unless a Guess)")
    v0 = Param(None, unit="m/s", kind="start", doc="start velocity (fixed unless a Guess)")
    limits = Param(None, unit="m", shape=(2,), check=_limits_ok,
                   doc="rigid stops (lo, hi) on s: impacts there, resting engaged (none by default)")
    restitution = Param(0.0, unit="1", check=lambda e: None if 0 <= e <= 1 else "must be in [0, 1]",
                        doc="Newton's restitution coefficient of the stops")
    friction = Param(None, unit="1", kind="any",
                     doc="Coulomb friction with stick/slip events: SlidingFriction(mu_s, mu_k, normal) (N)")

    def visuals(self, p, view):
        """A rod along the sliding axis on frame_a (the guide), over the run's travel
        (``view.range("s")``) and a tenth of the scale beyond, or a scale long about the origin."""
        lo, hi = view.range("s") or (-view.scale / 2, view.scale / 2)
        n = np.asarray(p.n, dtype=float) / np.linalg.norm(p.n)
        margin = 0.1 * view.scale
        return [Cylinder(0.012 * view.scale, hi - lo + 2 * margin, r=n * (lo + hi) / 2, R=z_to(n), color="grey")]

    def start(self, p):
        q, qf = _start1(p.s0)
        u, uf = _start1(p.v0)
        return q, np.array([qf]), u, np.array([uf])

    def relative(self, q, p):
        return np.eye(3), _axis(p) * q[0]

    def motion(self, q, p):
        return np.zeros((3, 1)), _axis(p)[:, None]

    def constraints(self, a, b, p):
        n = _axis(p)
        t1, t2 = perpendicular_pair(n)
        d = local_point(b, 1) - local_point(a, 0)
        rot = rigid_constraints(a, b, np.eye(3), np.zeros(3))[3:]
        return [("off_1", d.dot_(local_vector(a, t1, 0))), ("off_2", d.dot_(local_vector(a, t2, 0)))] + rot

    def axis_world(self, R_a, p):
        return R_a @ _axis(p)

    def measure(self, a, b, p):
        n = a.R @ _axis(p)
        d = b.r - a.r
        return d @ n, (b.v - a.v) @ n + d @ cross(a.w, n)


class Cylindrical(Joint):
    """Cylindrical joint: frame_b slides along ``n`` by ``s`` and turns about it by ``phi``.

    Two degrees of freedom (four constraints: two transverse offsets, two tilts); the
    book's "slider" that keeps its rotation about the rail. Coordinates ``s`` (m) and
    ``phi`` (rad), speeds ``v`` (m/s) and ``w`` (rad/s), axis ``n`` in frame_a coordinates.
    It has no 1-D flange; to drive or spring one of its motions, compose a
    :class:`Prismatic` and a :class:`Revolute` on the same axis instead.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import Cylindrical
    >>> j = Cylindrical(n=(0, 0, 1), s0=0.1, phi0=np.pi / 2)
    >>> R, r = j.relative([0.1, np.pi / 2], j.p)
    >>> np.round(R @ [1, 0, 0], 12).tolist(), r.tolist()
    ([0.0, 1.0, 0.0], [0.0, 0.0, 0.1])
    """

    coordinates = (("s", "m"), ("phi", "rad"))
    speeds = (("v", "m/s"), ("w", "rad/s"))
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), doc="axis direction, frame_a coordinates", check="nonzero")
    s0 = Param(None, unit="m", kind="start", doc="start position along the axis (fixed unless a Guess)")
    phi0 = Param(None, unit="rad", kind="start", doc="start angle about the axis (fixed unless a Guess)")
    v0 = Param(None, unit="m/s", kind="start", doc="start sliding velocity (fixed unless a Guess)")
    w0 = Param(None, unit="rad/s", kind="start", doc="start angular rate (fixed unless a Guess)")

    def visuals(self, p, view):
        """A rod along the axis through frame_a's origin, with a sleeve on frame_b."""
        return [Cylinder(0.012 * view.scale, view.scale, R=z_to(p.n), color="grey"),
                Cylinder(0.03 * view.scale, 0.1 * view.scale, R=z_to(p.n), frame="frame_b", color="grey")]

    def start(self, p):
        (s, sf), (phi, pf) = split_start(p.s0, 1), split_start(p.phi0, 1)
        (v, vf), (w, wf) = split_start(p.v0, 1), split_start(p.w0, 1)
        return np.concatenate((s, phi)), np.array([sf, pf]), np.concatenate((v, w)), np.array([vf, wf])

    def relative(self, q, p):
        n = _axis(p)
        return rot_axis(n, q[1]), n * q[0]

    def motion(self, q, p):
        n = _axis(p)[:, None]
        z = np.zeros((3, 1))
        return np.hstack((z, n)), np.hstack((n, z))

    def constraints(self, a, b, p):
        n = _axis(p)
        t1, t2 = perpendicular_pair(n)
        d = local_point(b, 1) - local_point(a, 0)
        nb = local_vector(b, n, 1)
        return [("off_1", d.dot_(local_vector(a, t1, 0))), ("off_2", d.dot_(local_vector(a, t2, 0))),
                ("tilt_1", nb.dot_(local_vector(a, t1, 0))), ("tilt_2", nb.dot_(local_vector(a, t2, 0)))]


class Spherical(Joint):
    """Ball joint: frame_b rotates freely about the common origin.

    Coordinates: unit quaternion ``Q`` (frame_b -> frame_a), singularity free; speeds: the
    relative angular velocity ``w`` (rad/s) resolved in frame_b.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import Spherical
    >>> j = Spherical(w0=(0, 0, 10.0))
    >>> j.start(j.p)[2]
    array([ 0.,  0., 10.])
    """

    coordinates = (("Q.w", "1"), ("Q.x", "1"), ("Q.y", "1"), ("Q.z", "1"))
    speeds = (("w.x", "rad/s"), ("w.y", "rad/s"), ("w.z", "rad/s"))
    R0 = Param(None, unit="1", shape=(3, 3), kind="start", check=rotation_matrix,
               doc="start orientation of frame_b relative to frame_a (fixed unless a Guess)")
    w0 = Param(None, unit="rad/s", shape=(3,), kind="start", doc="start relative angular velocity, frame_b axes")

    def visuals(self, p, view):
        """A ball at the joint's centre (frame_a's origin)."""
        return [Sphere(0.04 * view.scale, color="grey")]

    def start(self, p):
        R, rf = split_start(p.R0, 9)
        u, uf = split_start(p.w0, 3)
        Q = matrix_to_quat(R.reshape(3, 3)) if R.size == 9 else np.array([1.0, 0, 0, 0])
        return Q, np.full(3, rf), (u if u.size == 3 else np.zeros(3)), np.full(3, uf)

    def relative(self, q, p):
        return quat_to_matrix(q), np.zeros(3)

    def motion(self, q, p):
        return quat_to_matrix(q), np.zeros((3, 3))

    def q_rate(self, q, u, p):
        return quat_rate(q, u)

    def increment(self, q, du, p):
        return quat_increment(q, du)

    def constraints(self, a, b, p):
        return position_constraints(a, b)


class Weld(_Rigid):
    """Rigid connection: frame_b coincides with frame_a (0 DOF); its reaction is the
    full cut wrench.

    Examples
    --------
    >>> from mbcomp.library import Weld
    >>> Weld().nq
    0
    """
