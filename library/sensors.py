"""Sensors: components that add named result columns and change nothing in the motion.

:class:`RelativeSensor`, :class:`AbsoluteSensor` and :class:`AbsoluteAngles` are force
elements with zero wrenches whose :meth:`outputs` read the frames' state (the post-processing
hands them accelerations too: ``frame.a``, ``frame.alpha``, m/s^2 and rad/s^2, world
coordinates). :class:`CutForceAndTorque` is a 0-DOF joint (like :class:`Weld`) that reports
the wrench it transmits.

Conventions (those of Modelica's ``MultiBody.Sensors``):

* ``resolve_in`` names the frame a vector's components are given in: ``"frame_a"``,
  ``"frame_b"`` or ``"world"``.
* A relative velocity and acceleration are time derivatives **taken in frame_a** (the
  observer): ``v_rel = d/dt (R_a^T (r_b - r_a))`` and ``a_rel = d/dt v_rel``, both as frame_a
  components, then resolved in ``resolve_in``. Resolving in another frame does not change
  which derivative it is.
* Rotations: ``R`` maps a frame's coordinates to world coordinates. Angles of a sequence
  ``"xyz"`` are ``(phi1, phi2, phi3)`` with ``R = R_x(phi1) R_y(phi2) R_z(phi3)``: rotate the
  world about its x axis by phi1, then about the new y axis by phi2, then about the newest z
  axis by phi3 (Modelica's ``Frames.axesRotations``).

Examples
--------
>>> import numpy as np
>>> R = matrix_from_angles((0.1, -0.2, 0.3), "zyx")
>>> np.round(angles_from_matrix(R, "zyx"), 12).tolist()
[0.1, -0.2, 0.3]
"""
import numpy as np

from mbcomp import ForceElement, Frame, Param
from mbcomp.errors import Problem, SimulationError
from mbcomp.jets import is_traced
from mbcomp.kinematics import rot_axis

from .parts import _Rigid

__all__ = ["RelativeSensor", "AbsoluteSensor", "AbsoluteAngles", "CutForceAndTorque",
           "angles_from_matrix", "matrix_from_angles"]

_XYZ = "xyz"
_E = np.eye(3)


def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _columns(out, prefix, vec):
    for k, ax in enumerate(_XYZ):
        out[f"{prefix}.{ax}"] = vec[k]


def _units(prefixes):
    return {f"{pre}.{ax}": unit for pre, unit in prefixes for ax in _XYZ}


def _choice(comp, p, allowed):
    """The problem of a ``resolve_in`` value outside ``allowed``, as a list."""
    if isinstance(p.resolve_in, str) and p.resolve_in in allowed:
        return []
    return [Problem(f"{comp.path}.resolve_in", f"is {p.resolve_in!r}, not a frame this sensor knows",
                    f"give one of {', '.join(repr(a) for a in allowed)}")]


def _accelerations(comp, frame):
    """``(a, alpha)`` of a frame handed to ``outputs``, or a clear error when the caller gave a
    plain FrameState (the post-processing gives accelerations; a direct call may not)."""
    a, alpha = getattr(frame, "a", None), getattr(frame, "alpha", None)
    if a is None or alpha is None:
        raise SimulationError(f"{comp.path}: the sensor's outputs need the frames' accelerations (frame.a, "
                              "frame.alpha), which this caller did not give -> fix: read the sensor's columns "
                              "from a simulation result (mbcomp.simulate) or pass frames that carry a and alpha")
    return np.asarray(a), np.asarray(alpha)


class _Sensor(ForceElement):
    """A force element that applies nothing (zero wrenches) and only reports outputs."""

    conservative = True  # no force, no work
    #: applies nothing (zero wrenches): the contract tests check that instead of a force law
    sensor = True

    def wrenches(self, t, frames, p):
        z = np.zeros(3)
        return {pn: (z, z) for pn in frames}


class RelativeSensor(_Sensor):
    """Relative kinematics of frame_b with respect to frame_a, resolved in a chosen frame.

    Outputs (``<sensor>.<name>``):

    * ``r_rel.x|y|z`` (m): origin of frame_b relative to frame_a's origin;
    * ``v_rel.x|y|z`` (m/s): the time derivative of ``r_rel`` taken in frame_a (as seen by an
      observer fixed in frame_a, Modelica's convention), then resolved in ``resolve_in``;
    * ``a_rel.x|y|z`` (m/s^2): the time derivative of ``v_rel`` taken in frame_a, resolved
      likewise;
    * ``w_rel.x|y|z`` (rad/s): angular velocity of frame_b relative to frame_a (``w_b - w_a``);
    * ``angle`` (rad, in [0, pi]): the angle of the rotation from frame_a to frame_b.

    It applies no force.

    Parameters
    ----------
    resolve_in : {"frame_a", "frame_b", "world"}
        The frame whose coordinates the vectors are given in.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.roles import FrameState
    >>> from mbcomp.library import RelativeSensor
    >>> class F(FrameState):          # a frame state with accelerations, as a run hands it
    ...     __slots__ = ("a", "alpha")
    >>> a = F(np.zeros(3), np.eye(3), np.zeros(3), np.array([0, 0, 2.0])); a.a = a.alpha = np.zeros(3)
    >>> b = F(np.array([1.0, 0, 0]), np.eye(3), np.zeros(3), np.zeros(3)); b.a = b.alpha = np.zeros(3)
    >>> out = RelativeSensor().outputs(0.0, {"frame_a": a, "frame_b": b}, RelativeSensor().p)
    >>> [float(out["v_rel.y"]), float(out["a_rel.x"])]  # b at rest, seen from a turning frame_a
    [-2.0, -4.0]
    """

    frame_a = Frame("the observer frame (origin the reference point)")
    frame_b = Frame("the observed frame")
    resolve_in = Param("frame_a", unit="1", kind="any", doc='frame of the vectors: "frame_a", "frame_b" or "world"')

    output_units = dict(_units((("r_rel", "m"), ("v_rel", "m/s"), ("a_rel", "m/s^2"), ("w_rel", "rad/s"))),
                        angle="rad")

    def check_params(self, p):
        return _choice(self, p, ("frame_a", "frame_b", "world"))

    def outputs(self, t, frames, p):
        """The columns listed in the class's docstring."""
        A, B = frames["frame_a"], frames["frame_b"]
        (aa, alpha_a), (ab, _) = _accelerations(self, A), _accelerations(self, B)
        d, dd = B.r - A.r, B.v - A.v
        w = A.w
        wd = _cross(w, d)
        v_w = dd - wd                                                     # d/dt in frame_a, world components
        a_w = (ab - aa) - _cross(alpha_a, d) - 2.0 * _cross(w, dd) + _cross(w, wd)
        Rt = {"frame_a": A.R.T, "frame_b": B.R.T, "world": None}[p.resolve_in]
        res = (lambda x: x) if Rt is None else (lambda x: Rt @ x)
        out = {}
        for name, vec in (("r_rel", d), ("v_rel", v_w), ("a_rel", a_w), ("w_rel", B.w - w)):
            _columns(out, name, res(vec))
        out["angle"] = _rotation_angle(A.R.T @ B.R)
        return out


def _rotation_angle(R):
    """The angle (rad, [0, pi]) of rotation matrix ``R``: ``atan2(|sin|, cos)``, accurate near 0 and pi."""
    s = 0.5 * np.sqrt((R[2, 1] - R[1, 2]) ** 2 + (R[0, 2] - R[2, 0]) ** 2 + (R[1, 0] - R[0, 1]) ** 2)
    return np.arctan2(s, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0))


class AbsoluteSensor(_Sensor):
    """Absolute kinematics of one frame: position, velocity, acceleration (time derivatives in
    the world), angular velocity and angular acceleration, resolved in a chosen frame.

    Outputs: ``r.x|y|z`` (m), ``v.x|y|z`` (m/s), ``a.x|y|z`` (m/s^2) of frame_a's origin,
    ``w.x|y|z`` (rad/s) and ``alpha.x|y|z`` (rad/s^2) of frame_a. It applies no force.

    Parameters
    ----------
    resolve_in : {"world", "frame_a"}
        The frame whose coordinates the vectors are given in (the derivatives are the world's
        either way).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.roles import FrameState
    >>> from mbcomp.library import AbsoluteSensor
    >>> class F(FrameState):
    ...     __slots__ = ("a", "alpha")
    >>> f = F(np.array([1.0, 2, 3]), np.eye(3), np.zeros(3), np.zeros(3))
    >>> f.a, f.alpha = np.array([0, 0, -9.81]), np.zeros(3)
    >>> s = AbsoluteSensor()
    >>> float(s.outputs(0.0, {"frame_a": f}, s.p)["a.z"])
    -9.81
    """

    frame_a = Frame("the measured frame")
    resolve_in = Param("world", unit="1", kind="any", doc='frame of the vectors: "world" or "frame_a"')

    output_units = _units((("r", "m"), ("v", "m/s"), ("a", "m/s^2"), ("w", "rad/s"), ("alpha", "rad/s^2")))

    def check_params(self, p):
        return _choice(self, p, ("world", "frame_a"))

    def outputs(self, t, frames, p):
        """The columns listed in the class's docstring."""
        F = frames["frame_a"]
        a, alpha = _accelerations(self, F)
        res = (lambda x: F.R.T @ x) if p.resolve_in == "frame_a" else (lambda x: x)
        out = {}
        for name, vec in (("r", F.r), ("v", F.v), ("a", a), ("w", F.w), ("alpha", alpha)):
            _columns(out, name, res(vec))
        return out


def _sequence(seq):
    """Axis indices of a rotation sequence text (``"xyz"``, ``"zxz"``), or None when invalid."""
    if not isinstance(seq, str) or len(seq) != 3 or any(c not in _XYZ for c in seq):
        return None
    idx = tuple(_XYZ.index(c) for c in seq)
    return idx if idx[0] != idx[1] and idx[1] != idx[2] else None


def matrix_from_angles(angles, sequence="xyz"):
    """The rotation matrix ``R = R_i(phi1) R_j(phi2) R_k(phi3)`` (frame -> world) of the
    angles (rad) about the axes of ``sequence`` (e.g. ``"xyz"``, ``"zxz"``).

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(matrix_from_angles((np.pi / 2, 0, 0), "xyz") @ [0, 1, 0], [0, 0, 1])
    True
    """
    idx = _sequence(sequence)
    if idx is None:
        raise ValueError(f"sequence {sequence!r}: give three of 'x', 'y', 'z' with no axis twice in a row")
    R = np.eye(3)
    for i, phi in zip(idx, angles):
        R = R @ rot_axis(_E[i], phi)
    return R


def angles_from_matrix(R, sequence="xyz"):
    """The angles ``(phi1, phi2, phi3)`` (rad) with ``R = R_i(phi1) R_j(phi2) R_k(phi3)``.

    For three different axes (Cardan/Tait-Bryan, ``"xyz"``) ``phi2`` is in [-pi/2, pi/2] and
    ``phi1``, ``phi3`` in (-pi, pi]; at ``|phi2| = pi/2`` (gimbal lock) only ``phi1 +- phi3``
    is determined. For a repeated axis (Euler, ``"zxz"``) ``phi2`` is in [0, pi] and the lock
    is at 0 and pi. Every angle comes from ``atan2``: accurate everywhere else.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(angles_from_matrix(matrix_from_angles((0.3, 1.2, -2.0), "zxz"), "zxz"), 12).tolist()
    [0.3, 1.2, -2.0]
    """
    idx = _sequence(sequence)
    if idx is None:
        raise ValueError(f"sequence {sequence!r}: give three of 'x', 'y', 'z' with no axis twice in a row")
    i, j, k = idx
    if i != k:  # Cardan: s = +1 when (i, j, k) is cyclic
        s = 1.0 if (j - i) % 3 == 1 else -1.0
        phi2 = np.arctan2(s * R[i, k], np.sqrt(R[j, k] ** 2 + R[k, k] ** 2))
        return np.array([np.arctan2(-s * R[j, k], R[k, k]), phi2, np.arctan2(-s * R[i, j], R[i, i])])
    m = 3 - i - j  # Euler: the third axis
    s = 1.0 if (j - i) % 3 == 1 else -1.0
    phi2 = np.arctan2(np.sqrt(R[j, i] ** 2 + R[m, i] ** 2), R[i, i])
    return np.array([np.arctan2(R[j, i], -s * R[m, i]), phi2, np.arctan2(R[i, j], s * R[i, m])])


class AbsoluteAngles(_Sensor):
    """The orientation of frame_a in the world as three angles of a rotation sequence.

    Outputs ``angles.1|2|3`` (rad): ``(phi1, phi2, phi3)`` with ``R_a = R_i(phi1) R_j(phi2)
    R_k(phi3)`` for ``sequence = "ijk"`` (``R_a``: frame_a -> world), as Modelica's
    ``AbsoluteAngles``: rotate the world about axis i by phi1, then about the rotated axis j
    by phi2, then about the twice-rotated axis k by phi3. Ranges and the gimbal lock: see
    :func:`angles_from_matrix`. It applies no force.

    Parameters
    ----------
    sequence : str
        Three of ``"x"``, ``"y"``, ``"z"``, no axis twice in a row: ``"xyz"`` (Cardan angles,
        the default), ``"zyx"`` (yaw, pitch, roll), ``"zxz"`` (Euler angles), ...

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.roles import FrameState
    >>> from mbcomp.library import AbsoluteAngles
    >>> from mbcomp.library.sensors import matrix_from_angles
    >>> f = FrameState(np.zeros(3), matrix_from_angles((0.1, 0.2, 0.3), "xyz"), np.zeros(3), np.zeros(3))
    >>> s = AbsoluteAngles(sequence="xyz")
    >>> [round(float(x), 12) for x in s.outputs(0.0, {"frame_a": f}, s.p).values()]
    [0.1, 0.2, 0.3]
    """

    frame_a = Frame("the frame whose orientation is measured")
    sequence = Param("xyz", unit="1", kind="any", doc='rotation axes in order, e.g. "xyz" (Cardan) or "zxz" (Euler)')

    output_units = {"angles.1": "rad", "angles.2": "rad", "angles.3": "rad"}

    def check_params(self, p):
        if _sequence(p.sequence) is not None:
            return []
        return [Problem(f"{self.path}.sequence", f"is {p.sequence!r}, not a rotation sequence",
                        "give three of 'x', 'y', 'z' with no axis twice in a row, e.g. 'xyz' or 'zxz'")]

    def outputs(self, t, frames, p):
        """``angles.1|2|3`` (rad) of the class's docstring."""
        phi = angles_from_matrix(frames["frame_a"].R, p.sequence)
        return {f"angles.{n + 1}": phi[n] for n in range(3)}


class CutForceAndTorque(_Rigid):
    """A rigid connection (0 DOF, frame_b = frame_a) that measures the wrench it transmits.

    Outputs ``force.x|y|z`` (N) and ``torque.x|y|z`` (N m, about the common origin): the force
    and torque the frame_a side exerts, through the sensor, on whatever is connected at
    frame_b. That is Modelica's ``CutForceAndTorque`` (its ``force = frame_a.f``: in
    Modelica's flow convention the cut force acting on the sensor at frame_a, which the
    massless sensor passes on to frame_b), and it is mbcomp's reaction ``<name>.f``/``tau``
    of every joint (exerted on frame_b through the joint), only resolved in ``resolve_in``.
    Example: a bob of mass ``m`` hanging from the sensor measures ``force = m (a_bob - g)``:
    ``+m |g|`` upward at rest.

    As a tree edge the columns come from the reaction (``reaction_outputs``); as a cut joint
    (closing a loop) from its multipliers (:meth:`outputs`). Being rigid it is a tree edge
    wherever it can be; ``cut=True`` makes this instance only close loops (six constraint
    rows; the bodies on both sides keep their own coordinates, a body otherwise joined to
    nothing is added ``free=True``).

    Parameters
    ----------
    resolve_in : {"frame_a", "world"}
        The frame whose coordinates the force and torque are given in.
    cut : bool
        Constructor option (not a parameter): always a cut joint.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass, CutForceAndTorque
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> cut = m.add("cut", CutForceAndTorque()); bob = m.add("bob", PointMass(m=2.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a)
    >>> m.connect(rod.frame_b, cut.frame_a); m.connect(cut.frame_b, bob.frame_a)
    >>> res = mbcomp.simulate(m, t_end=0.1, backend="numeric", n_out=3)
    >>> round(float(res["cut.force.y"][0]), 9)                  # m |g| upward at rest
    19.62
    """

    resolve_in = Param("frame_a", unit="1", kind="any", doc='frame of force and torque: "frame_a" or "world"')

    output_units = _units((("force", "N"), ("torque", "N m")))

    def __init__(self, *, cut=False, **values):
        super().__init__(**values)
        if cut:  # this instance only closes loops (its frames keep the coordinates they have)
            self.tree_edge = False

    def check_params(self, p):
        return _choice(self, p, ("frame_a", "world"))

    def _columns(self, a, f_world, tau_world, p):
        res = (lambda x: a.R.T @ x) if p.resolve_in == "frame_a" else (lambda x: x)
        out = {}
        _columns(out, "force", res(f_world))
        _columns(out, "torque", res(tau_world))
        return out

    def outputs(self, a, b, p, lam):
        """As a cut joint: the constraint wrench on frame_b, ``-(d c/d twist_b)^T lam`` over its
        rows (N, N m); a tree edge has no rows here (see ``reaction_outputs``)."""
        if not lam:
            return {}
        wb = np.zeros(6, dtype=object if any(is_traced(x) for x in lam.values()) else float)
        for name, c in self.constraints(a, b, p):
            if name in lam:  # a row dropped as redundant carries no force
                wb = wb - np.asarray(c.jac)[6:] * lam[name]
        return self._columns(a, wb[:3], wb[3:], p)

    def reaction_outputs(self, a, b, p, f, tau):
        """As a tree edge: from the joint's reaction ``(f, tau)`` on frame_b (frame_b
        coordinates; :mod:`mbcomp.assembly.outputs` calls this)."""
        return self._columns(a, b.R @ f, b.R @ tau, p)
