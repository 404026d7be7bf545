"""The roles a component can play, and the small contract of each.

mbcomp is not a general equation compiler: the assembler knows these roles only.
A library component subclasses exactly one of them and implements its methods; all
vectors are numpy arrays, lengths in m, angles in rad, forces in N, torques in N m.

* :class:`Ground` - a frame fixed in the world (``pose``), optionally the gravity field.
* :class:`Body` - mass properties on ``frame_a`` (``mass_properties``).
* :class:`Joint` - relative motion of ``frame_b`` w.r.t. ``frame_a`` in its own coordinates
  (used as a spanning-tree edge) *and* the same motion as constraint equations between two
  poses (used when the joint closes a kinematic loop). Rigid offsets are 0-DOF joints.
* :class:`ForceElement` - wrenches on its frames from their kinematics, time and parameters,
  plus its potential energy.
* :class:`FlangeElement` - forces along 1-D flanges (joint axes) from their coordinates.
* :class:`FlangeConstraint` - rows tying flange coordinates (ideal gears, rack and pinion,
  belts): linear forms :class:`FlangeSum` over its flanges, holonomic.
* :class:`FlangeInertia` - a rotor of axial inertia on a joint's axis (mass without a body).
* :class:`Drive` - prescribes the coordinate of the joint axis its flange is connected to.

Examples
--------
A user-written force element: a constant world-frame force on a frame.

>>> import numpy as np
>>> from mbcomp import ForceElement, Frame, Param
>>> class Push(ForceElement):
...     '''Constant force ``f`` (N, world coordinates) on frame_b.'''
...     frame_b = Frame("frame the force acts on (at its origin)")
...     f = Param((0.0, 0.0, 0.0), unit="N", shape=(3,), doc="force, world coordinates")
...     def wrenches(self, t, frames, p):
...         return {"frame_b": (p.f, np.zeros(3))}
>>> Push(f=(1, 0, 0)).p.f
array([1., 0., 0.])
"""
from __future__ import annotations

import numpy as np

from ..modeling.component import Component, Flange, Frame, Guess, PortRef

__all__ = ["Ground", "Body", "Joint", "MissingFlange", "ForceElement", "FlangeElement", "Drive", "FrameState",
           "FlangeConstraint", "FlangeInertia", "FlangeSum"]


class FrameState:
    """Kinematic state of a frame handed to force laws.

    Attributes
    ----------
    r : ndarray (3,)  origin position, m, world coordinates
    R : ndarray (3, 3)  orientation, frame -> world
    v : ndarray (3,)  origin velocity, m/s, world coordinates
    w : ndarray (3,)  angular velocity, rad/s, world coordinates
    """

    __slots__ = ("r", "R", "v", "w")

    def __init__(self, r, R, v, w):
        self.r, self.R, self.v, self.w = r, R, v, w


class Ground(Component):
    """A frame fixed in the world. Subclasses implement :meth:`pose`."""

    role = "ground"
    frame_b = Frame("the fixed frame")

    def pose(self, p):
        """Return ``(R, r)``: orientation (frame -> world) and origin position (m)."""
        raise NotImplementedError

    def gravity(self, p):
        """Gravity acceleration (m/s^2, world coordinates), or ``None`` if not a field source."""
        return None


class Body(Component):
    """Mass properties attached to ``frame_a``."""

    role = "body"
    frame_a = Frame("the body's reference frame (left open only for a body added with free=True, which "
                    "floats freely)", optional=True)

    def mass_properties(self, p):
        """Return ``(m, r_cm, I_cm)``: mass (kg), centre of mass (m, frame_a coordinates),
        inertia about the centre of mass (kg m^2, frame_a axes)."""
        raise NotImplementedError

    def visuals(self, p, view):
        """A link from joint to joint (rods from frame_a's origin to each frame fixed to it), or
        alone the cylinder or box of the body's mass and inertia, or a steel sphere of its mass
        (:func:`mbcomp.modeling.shapes.body_shapes`); nothing where another component draws
        the body (a wheel's contact: ``view.covered``)."""
        from .shapes import body_shapes

        if view.covered("frame_a"):
            return []
        m, r_cm, I = self.mass_properties(p)
        return body_shapes(m, r_cm, I, view.attached("frame_a"), view.scale)


class MissingFlange(PortRef):
    """``joint.axis`` or ``joint.support`` of a joint that has no such flange (a
    :class:`Spherical`, a free joint): :meth:`Model.connect <mbcomp.Model.connect>` refuses it,
    naming the element that was to act on it and the joint.

    Examples
    --------
    >>> from mbcomp.library import Spherical
    >>> Spherical().axis
    <missing flange <unnamed Spherical>.axis>
    """

    __slots__ = ()

    def __repr__(self):
        return f"<missing flange {self.path}>"


class Joint(Component):
    """Relative motion between ``frame_a`` and ``frame_b``.

    Class attributes ``coordinates`` and ``speeds`` list ``(name, unit)`` of the joint's
    position coordinates ``q`` and speeds ``u`` (``len(q) >= len(u)``; a quaternion has 4
    coordinates and 3 speeds). ``axis_kind`` is ``"rotational"``/``"translational"`` for
    1-DOF joints with ``axis``/``support`` flanges, else ``None``.
    """

    role = "joint"
    frame_a = Frame("first frame of the joint")
    frame_b = Frame("second frame of the joint")
    coordinates: tuple = ()
    speeds: tuple = ()
    axis_kind = None
    tree_edge = True  # False: a constraint-only joint (no coordinates), always a cut joint
    #: False for a joint that passes no force or torque between its frames (a free joint):
    #: bodies joined to the ground only through such joints feel no external load from it
    transmits_load = True

    def __getattr__(self, name):
        # reached only when normal lookup fails: ``ball.axis`` of a joint without 1-D flanges
        # is a MissingFlange, which Model.connect refuses naming both sides (not an AttributeError)
        if name in ("axis", "support"):
            return MissingFlange(self, name, "flange")
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def nq(self):
        return len(self.coordinates)

    @property
    def nu(self):
        return len(self.speeds)

    # --- tree edge ----------------------------------------------------------------------
    def relative(self, q, p):
        """Pose of frame_b in frame_a: ``(R_rel, r_rel)`` with ``R_b = R_a R_rel`` and
        ``r_b = r_a + R_a r_rel``."""
        raise NotImplementedError

    def motion(self, q, p):
        """``(Hw, Hv)``, each (3, nu): relative angular velocity and d(r_rel)/dt, both in
        frame_a coordinates, per unit speed. Their time derivative at constant ``u`` is zero,
        or given by :meth:`motion_bias`."""
        return np.zeros((3, self.nu)), np.zeros((3, self.nu))

    def motion_bias(self, q, u, p):
        """``(bw, bv)``: the time derivatives of ``Hw u`` and ``Hv u`` at constant speeds ``u``
        (frame_a coordinates; rad/s^2, m/s^2), for a joint whose motion subspace turns with its
        own coordinates whatever speeds are chosen (a universal joint's second axis, a rod's
        end on its sphere); ``None`` (the default) where they vanish. Declared by overriding
        (:attr:`has_motion_bias`); the assembler adds them to frame_b's bias accelerations."""
        return None

    @property
    def has_motion_bias(self):
        return type(self).motion_bias is not Joint.motion_bias

    def q_rate(self, q, u, p):
        """Coordinate rates ``dq/dt`` from speeds ``u``."""
        return np.asarray(u, dtype=float)

    def increment(self, q, du, p):
        """Coordinates moved by ``du`` along the speeds (used by Newton corrections)."""
        return np.asarray(q, float) + du

    def start(self, p):
        """``(q0, q_fixed, u0, u_fixed)``: start values and which speeds-sized entries the
        user fixed (``q_fixed`` has one flag per *speed* direction)."""
        return np.zeros(self.nq), np.zeros(self.nu, bool), np.zeros(self.nu), np.zeros(self.nu, bool)

    # --- loop closure -------------------------------------------------------------------
    def constraints(self, a, b, p):
        """Position constraints between the two frames when the joint closes a loop.

        Parameters
        ----------
        a, b : FrameJet
            Jets of frame_a and frame_b.

        Returns
        -------
        list of (str, ScalarJet)
            Named scalar constraints ``c(pose_a, pose_b) = 0`` built with
            :func:`mbcomp.jets.local_point` / :func:`mbcomp.jets.local_vector` (slot 0 for a,
            1 for b).
        """
        raise NotImplementedError

    # --- nonholonomic (velocity-level) constraints -----------------------------------------
    def velocity_constraints(self, a, b, p):
        """Velocity-level constraints ``g = B(q) u - b(q, t) = 0`` between the two frames,
        whether the joint is a tree edge or closes a loop (rolling, knife edges).

        Returns
        -------
        list of (str, ScalarJet)
            ``val`` the residual ``g``, ``jac`` its gradient with respect to the local twists
            ``(v_a, w_a, v_b, w_b)``, ``bias`` its time derivative at ``du/dt = 0``; build
            them with :func:`mbcomp.jets.velocity_along`. Empty for holonomic joints.
        """
        return []

    def outputs(self, a, b, p, lam):
        """Extra named result columns of this joint at one output time (optional).

        Parameters
        ----------
        a, b : FrameJet
            Jets of frame_a and frame_b.
        lam : dict
            Multiplier of each of this joint's constraint rows by row name (holonomic rows
            from :meth:`constraints` when the joint is cut, and rows of
            :meth:`velocity_constraints`), sign convention ``M du/dt + A^T lam = f``; a row
            dropped as redundant is missing.

        Returns
        -------
        dict
            ``{suffix: float}``, reported as ``<joint>.<suffix>`` (e.g. a contact's normal force).
        """
        return {}

    def reaction_outputs(self, a, b, p, f, tau):
        """Result columns a joint makes of its own reaction when it is a tree edge (it has no
        multipliers there; a cut joint makes them from ``lam`` in :meth:`outputs`): ``a``,
        ``b`` the frames' jets, ``f`` (N) and ``tau`` (N m, about frame_b's origin) the
        reaction exerted on frame_b through the joint, frame_b coordinates. Returns
        ``{suffix: float}`` (default: none; a cut-force sensor overrides it)."""
        return {}

    @property
    def has_reaction_outputs(self):
        return type(self).reaction_outputs is not Joint.reaction_outputs

    def result_notes(self, name, t, outputs):
        """Notes this joint adds to a simulation result's message (optional).

        Called once per run by the post-processing, for every joint, with the joint's result
        columns. A joint uses it to say what only it knows about its results, e.g. a contact
        whose normal force pulls where a real contact would let go (the framework cannot tell
        which columns mean what).

        Parameters
        ----------
        name : str
            The joint's name in the model (the column prefix).
        t : ndarray (n,)
            Output times (s).
        outputs : dict
            ``{suffix: ndarray (n,)}``: every column ``<name>.<suffix>`` of this joint
            (coordinates, speeds, reactions ``f.x``.., and the entries of :meth:`outputs`).

        Returns
        -------
        list of str
            One sentence per note (default: none).

        Examples
        --------
        >>> import numpy as np
        >>> from mbcomp.modeling.roles import Joint
        >>> Joint().result_notes("hinge", np.array([0.0, 1.0]), {"phi": np.zeros(2)})
        []
        """
        return []

    #: what breaks down near a zero of :meth:`singularity`, and how to avoid it (for messages)
    singularity_reason = "the joint reached a singular position"
    singularity_fix = "change the geometry or the start so it is avoided"

    def singularity(self, a, b, p):
        """Distance (dimensionless, >= 0) of the two frames from a position where this joint's
        own equations break down (e.g. a rolling disk lying flat), or ``None``. Checked by the
        simulation driver on accepted steps; the run fails below 1e-3 with
        :attr:`singularity_reason` and :attr:`singularity_fix`."""
        return None

    @property
    def has_singularity(self):
        return type(self).singularity is not Joint.singularity

    @property
    def has_velocity_constraints(self):
        return type(self).velocity_constraints is not Joint.velocity_constraints

    # --- modes (mbcomp.modeling.modes; the run: mbcomp.hybrid) ------------------------------
    def modes(self, p):
        """The joint's modes with parameters ``p``: a :class:`~mbcomp.modeling.modes.Modes`
        (its start mode, events, the action at each event, the rows each mode holds, its
        declared force and slip), or ``None`` (the default) for a joint without modes: the
        run then watches nothing of it. Declared, not inferred: a stop, a one-sided contact
        or a stick-slip friction returns one where its parameters give it modes."""
        return None

    # --- 1-D axis -----------------------------------------------------------------------
    def axis_world(self, R_a, p):
        """Unit axis (world coordinates) along which an axis flange force/torque acts."""
        raise NotImplementedError

    def measure(self, a, b, p):
        """Coordinate and rate ``(s, v)`` of a 1-DOF joint computed from its frames' jets."""
        raise NotImplementedError


def split_start(value, n):
    """Helper for :meth:`Joint.start`: ``(array, fixed)`` from a start value or :class:`Guess`."""
    if value is None:
        return np.zeros(n), False
    if isinstance(value, Guess):
        return np.atleast_1d(np.asarray(value.value, float)), False
    return np.atleast_1d(np.asarray(value, float)), True


class ForceElement(Component):
    """Wrenches on its frames. Subclasses declare ``Frame`` ports and implement
    :meth:`wrenches` (and :meth:`potential` if conservative)."""

    role = "force"
    conservative = False  # a law of time and state does work; springs declare True
    #: True for an element whose forces beyond its potential's only take energy out (dampers,
    #: friction): the energy balance counts their work as ``energy.dissipated``, every other
    #: element's as ``energy.work``
    dissipative = False
    #: True for a load from outside the mechanism (a force or torque given in the world,
    #: with no reaction on another of its frames): it changes the mechanism's momentum
    external = False
    #: True for a sensor: an element that applies no force at all (its ``wrenches`` are zero)
    #: and only reports ``outputs``; it loads nothing it touches
    sensor = False

    def wrenches(self, t, frames, p):
        """Return ``{port_name: (f, tau)}``: force (N) at the frame origin and torque (N m),
        both in world coordinates. ``frames`` maps port name -> :class:`FrameState`."""
        raise NotImplementedError

    def potential(self, frames, p):
        """Potential energy in J (0 for non-conservative elements)."""
        return 0.0

    def outputs(self, t, frames, p):
        """Named result columns of this element at one output time (optional), reported as
        ``<element>.<suffix>``: e.g. a spring's tension ``f`` (N) and ``length`` (m). The
        frames here also carry their accelerations ``a`` (m/s^2) and ``alpha`` (rad/s^2),
        world (:class:`mbcomp.assembly.outputs.MeasuredFrame`: sensors read them). Its
        ``power`` (W, delivered to the mechanism) and, when it has a :meth:`potential`, its
        ``potential`` (J) are added by the post-processing for every element.

        Returns
        -------
        dict
            ``{suffix: float}`` (default: none).
        """
        return {}


class FlangeElement(Component):
    """Forces along 1-D flanges. Subclasses declare ``Flange`` ports."""

    role = "flange_force"
    conservative = False  # a law of time and state does work; springs declare True
    #: ``"rotational"`` (torques, N m) or ``"translational"`` (forces, N): the kind of joint
    #: axis its flanges must be on (the topology refuses a Torque on a Prismatic); ``None``: any
    axis_kind = None
    #: as :attr:`ForceElement.dissipative`
    dissipative = False

    def flange_forces(self, t, states, p):
        """Return ``{port_name: flow}``: force (N) or torque (N m) the element applies to each
        flange, from ``states`` mapping port name -> ``(s, v)``."""
        raise NotImplementedError

    def potential(self, states, p):
        """Potential energy in J (0 for non-conservative elements)."""
        return 0.0

    def outputs(self, t, states, p):
        """Named result columns at one output time (optional, as :meth:`ForceElement.outputs`),
        e.g. a motor's torque ``tau`` (N m); ``power`` and ``potential`` are added for every
        element. ``states`` maps flange name -> ``(s, v)``."""
        return {}


class Drive(Component):
    """Prescribed motion of the joint axis connected to ``flange_b``: a rheonomic
    constraint that removes the joint's degree of freedom (not a servo)."""

    role = "drive"
    conservative = False  # a prescribed motion feeds or takes energy
    flange_b = Flange("connect to a 1-DOF joint's axis flange")

    def motion(self, t, p):
        """``(s, v, a)``: coordinate, rate and acceleration of the driven axis at time t."""
        raise NotImplementedError


class FlangeSum:
    """A linear form ``sum_k c_k s_k`` over the coordinates ``s_k`` of a component's flanges.

    :meth:`FlangeConstraint.rows` receives one per flange (``flanges["flange_a"]`` is
    ``1 * s_a``) and combines them with ``+``, ``-``, unary ``-`` and multiplication or
    division by numbers (parameters, possibly traced); the assembler turns each form into a
    constraint row (value, Jacobian, rate and bias) from the flanges' joints.

    Examples
    --------
    >>> from mbcomp.roles import FlangeSum
    >>> a, b = FlangeSum({"flange_a": 1.0}), FlangeSum({"flange_b": 1.0})
    >>> (a - 3.0 * b).terms
    {'flange_a': 1.0, 'flange_b': -3.0}
    """

    __slots__ = ("terms",)

    def __init__(self, terms):
        self.terms = dict(terms)

    def __add__(self, o):
        out = dict(self.terms)
        for k, c in o.terms.items():
            out[k] = out[k] + c if k in out else c
        return FlangeSum(out)

    def __neg__(self):
        return FlangeSum({k: -c for k, c in self.terms.items()})

    def __sub__(self, o):
        return self + (-o)

    def __mul__(self, c):
        if isinstance(c, FlangeSum):
            raise TypeError("a flange constraint row is linear in the flanges' coordinates: multiply a FlangeSum "
                            "by numbers (parameters) only")
        return FlangeSum({k: v * c for k, v in self.terms.items()})

    __rmul__ = __mul__

    def __truediv__(self, c):
        return self * (1.0 / c)

    def __repr__(self):
        return " + ".join(f"{c!r}*{k}" for k, c in self.terms.items()) or "0"


class FlangeConstraint(Component):
    """Constraint rows between the coordinates of 1-D flanges (joint axes): ideal gears, rack
    and pinion, belts. Subclasses declare ``Flange`` ports and implement :meth:`rows`.

    Each row is a :class:`FlangeSum` ``c(s) = sum_k c_k s_k``; the assembler keeps
    ``c(s) - c(s0) = 0``, a *holonomic* row whose constant comes from the flanges' start
    coordinates ``s0`` (each joint's start value; 0 on a support flange or an unconnected
    optional flange), so the mechanism loses one configuration degree of freedom per row and
    the gear's phase is the start's. A flange's coordinate is its joint's relative coordinate
    (angle in rad or displacement in m), on any joint axis: in the spanning tree, closing a
    loop (translational), or driven. Multipliers are result columns ``lambda.<name>.<row>``;
    the flow (torque N m or force N) the component puts on each flange is
    ``-sum_rows lam_r c_{r,k}`` (with ``M du/dt + A^T lam = f``), handed to :meth:`outputs`.
    """

    role = "flange_constraint"
    #: per flange port, ``"rotational"`` or ``"translational"``: the kind of joint axis it
    #: must be on (checked by the topology); a port not listed takes either
    flange_kinds: dict = {}
    output_units: dict = {}

    def rows(self, flanges, p):
        """Return ``[(row name, FlangeSum)]`` from ``flanges`` (port name -> :class:`FlangeSum`)."""
        raise NotImplementedError

    def outputs(self, t, states, p, flows):
        """Named result columns at one output time (optional), reported as ``<name>.<suffix>``.

        Parameters
        ----------
        states : dict
            Flange port -> ``(s, v)``: coordinate and rate.
        flows : dict
            Flange port -> the torque (N m) or force (N) this component puts on the flange
            (on the joint's frame_b along/about its axis, the reaction on frame_a).
        """
        return {}


class FlangeInertia(Component):
    """A rotor on a rotational joint axis: mass without a body. Subclasses declare one
    ``Flange`` port and implement :meth:`rotor`.

    The rotor turns with the frame its flange moves (the joint's frame_b for its ``axis``,
    frame_a for its ``support``) about the joint's axis ``n``: its inertia tensor is
    ``J n n^T`` on that frame (no mass, no transverse inertia, which belong to the carrying
    body), so its kinetic energy is ``J (n . w)^2 / 2`` with ``w`` that frame's absolute
    angular velocity. With ``gyroscopic`` the carrying frame also feels the gyroscopic moment
    ``w x (J n (n . w))``; without it, the moment is dropped (it does no work, so the energy
    is unchanged). On an axis fixed in the world both are a body of axial inertia ``J``.

    A *reflected* rotor (:meth:`reflected` True: a motor's rotor seen through a gearbox of
    large ratio, MuJoCo's joint ``armature``) instead turns at its joint's own rate ``s_dot``:
    kinetic energy ``J s_dot^2 / 2``, which adds ``J`` to the mass matrix's diagonal entry of
    the joint's speed and nothing else (no force: ``J`` is constant). Its torque ``-J s_ddot``
    acts inside the joint (the gearbox's output on frame_b, the housing's reaction on frame_a),
    so the joint's reaction carries it. It needs the ``axis`` flange of a joint with one speed
    of its own (not driven; the topology keeps such a joint in the spanning tree wherever a loop
    can be cut elsewhere): ``J`` in kg m^2 on a rotational axis, kg on a translational one (a
    reflected mass; the class's ``axis_kind`` says which).
    """

    role = "flange_inertia"
    axis_kind = "rotational"

    def rotor(self, p):
        """Return ``(J, gyroscopic)``: axial inertia (kg m^2; a reflected mass on a translational
        axis: kg) and whether the gyroscopic moment acts on the carrying frame (False for a
        reflected rotor)."""
        raise NotImplementedError

    def reflected(self, p):
        """Whether the rotor turns at its joint's own rate ``s_dot`` (kinetic energy
        ``J s_dot^2 / 2``, a rotor reflected through a gear: MuJoCo's armature) instead of with
        the frame its flange moves (False, the default). Declared by the class, never inferred
        from values."""
        return False
