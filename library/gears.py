"""Ideal transmissions between joint axes: gears, rack and pinion, pulleys, belts, rotors, planetary sets.

Each transmission is a :class:`~mbcomp.roles.FlangeConstraint`: one holonomic row tying the
coordinates of the joint axes its flanges are connected to (any 1-DOF joints' ``axis``
flanges: shafts on Revolutes, a rack on a Prismatic; across the spanning tree too, a gear
pair then closes a loop). The row holds the displacements from the start: the phase of the
mesh is the joints' start values. The flow each transmission puts on a flange (torque N m,
force N; on the joint's frame_b about/along its axis, the reaction on frame_a) is a result
column, ``<name>.tau_a`` etc.; ideal transmissions neither store nor dissipate energy, so
``sum flow * rate = 0``. The multiplier is ``lambda.<name>.mesh``.

:class:`Inertia` is a rotor on a rotational joint axis (:class:`~mbcomp.roles.FlangeInertia`),
:class:`ReflectedInertia` and :class:`ReflectedMass` a rotor seen through a large gear ratio on
a joint's own rate (MuJoCo's armature), and :class:`PlanetaryGear` a sun-carrier-ring set built
from these (a ``Model``).
"""
import numpy as np

from mbcomp import Box, Cylinder, FlangeConstraint, FlangeInertia, Flange, Model, Param
from mbcomp.modeling.shapes import STEEL, z_to
from .joints import Revolute

__all__ = ["IdealGear", "RackPinion", "IdealPulley", "Belt", "Inertia", "PlanetaryGear", "JointCoupling",
           "ReflectedInertia", "ReflectedMass"]


class IdealGear(FlangeConstraint):
    """Ideal gear between two rotational joint axes: ``phi_a - phi_s = ratio (phi_b - phi_s)``.

    ``phi_a``, ``phi_b`` are the angles of the axes connected to ``flange_a`` and ``flange_b``
    (rad, from their start values) and ``phi_s`` that of ``support`` (the gear housing: a
    planetary set's carrier; unconnected, the housing is fixed: ``phi_s = 0``). Modelica's
    convention: ``ratio`` is the speed of ``a`` over that of ``b``, negative for an external
    spur pair turning in opposite senses (``-z_b / z_a``). The torques it puts on the axes are
    ``tau_b = -ratio tau_a`` and ``tau_support = (ratio - 1) tau_a``: the power balance
    ``tau_a w_a + tau_b w_b + tau_s w_s = 0``.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import Fixed, Revolute, RigidBody, IdealGear, Torque
    >>> m = mbcomp.Model(); base = m.add("base", Fixed())
    >>> j1 = m.add("j1", Revolute()); j2 = m.add("j2", Revolute())
    >>> b1 = m.add("b1", RigidBody(m=1.0, I=np.eye(3))); b2 = m.add("b2", RigidBody(m=1.0, I=np.eye(3) * 4))
    >>> g = m.add("gear", IdealGear(ratio=2.0)); tq = m.add("motor", Torque(tau=1.0))
    >>> m.connect(base.frame_b, j1.frame_a); m.connect(j1.frame_b, b1.frame_a)
    >>> m.connect(base.frame_b, j2.frame_a); m.connect(j2.frame_b, b2.frame_a)
    >>> m.connect(g.flange_a, j1.axis); m.connect(g.flange_b, j2.axis); m.connect(tq.flange_b, j1.axis)
    >>> res = mbcomp.simulate(m, t_end=1.0)
    >>> round(float(res["j1.w"][-1]), 9)   # tau / (I1 + I2 / ratio^2) * t
    0.5
    """

    flange_a = Flange("first rotational axis (e.g. the input shaft's Revolute axis)")
    flange_b = Flange("second rotational axis (e.g. the output shaft's Revolute axis)")
    support = Flange("the housing's or carrier's rotational axis (fixed when unconnected)", optional=True)
    ratio = Param(1.0, unit="1", doc="speed ratio w_a / w_b relative to the support (negative: opposite senses)",
                  check="nonzero")
    flange_kinds = {"flange_a": "rotational", "flange_b": "rotational", "support": "rotational"}
    output_units = {"tau_a": "N m", "tau_b": "N m", "tau_support": "N m"}

    def rows(self, flanges, p):
        a, b, s = flanges["flange_a"], flanges["flange_b"], flanges["support"]
        return [("mesh", (a - s) - p.ratio * (b - s))]

    def outputs(self, t, states, p, flows):
        """Torques on the axes (N m): ``tau_a``, ``tau_b`` and ``tau_support``."""
        return {"tau_a": flows["flange_a"], "tau_b": flows["flange_b"], "tau_support": flows["support"]}


class RackPinion(FlangeConstraint):
    """Rack and pinion: the rack's travel ``s_b = radius phi_a`` (m) for the pinion's angle ``phi_a``.

    ``flange_a`` on the pinion's rotational axis (a Revolute), ``flange_b`` on the rack's
    translational axis (a Prismatic); displacements from their start values. The pinion's
    torque and the rack's force satisfy ``tau_a = -radius f_b`` (no power lost). A rope on a
    drum is the same constraint: :class:`IdealPulley`.

    Examples
    --------
    >>> from mbcomp.library import RackPinion
    >>> from mbcomp.roles import FlangeSum
    >>> rp = RackPinion(radius=0.05)
    >>> rp.rows({"flange_a": FlangeSum({"flange_a": 1.0}), "flange_b": FlangeSum({"flange_b": 1.0})}, rp.p)
    [('mesh', 1.0*flange_b + -0.05*flange_a)]
    """

    flange_a = Flange("the pinion's rotational axis (a Revolute's axis)")
    flange_b = Flange("the rack's translational axis (a Prismatic's axis)")
    radius = Param(0.05, unit="m", doc="pitch radius of the pinion", check="positive")
    flange_kinds = {"flange_a": "rotational", "flange_b": "translational"}
    output_units = {"tau_a": "N m", "f_b": "N"}

    def rows(self, flanges, p):
        return [("mesh", flanges["flange_b"] - p.radius * flanges["flange_a"])]

    def outputs(self, t, states, p, flows):
        """The pinion's torque ``tau_a`` (N m) and the rack's force ``f_b`` (N)."""
        return {"tau_a": flows["flange_a"], "f_b": flows["flange_b"]}


class JointCoupling(FlangeConstraint):
    """Two 1-DOF joint axes of any kind moving together: ``s_a = ratio s_b`` (displacements from
    the start values), URDF's ``<mimic>`` where :class:`IdealGear` (rotational) does not apply.

    ``flange_a``, ``flange_b`` on the axes of Revolutes (rad) or Prismatics (m), either kind on
    either side; ``ratio`` is then in 1, m/rad or rad/m. The torque or force it puts on
    ``flange_a`` is ``f_a = -lambda`` (the result column ``lambda.<name>.mesh``; N m or N by the
    axis, so no output columns of its own), on ``flange_b`` ``f_b = -ratio f_a`` (no power lost:
    ``f_a v_a + f_b v_b = 0``). An offset between the coordinates is the joints' start values
    (``s_a0 = ratio s_b0 + offset``).

    Examples
    --------
    Two fingers of a gripper on one slide: the second mirrors the first.

    >>> from mbcomp.library import JointCoupling
    >>> from mbcomp.roles import FlangeSum
    >>> c = JointCoupling(ratio=-1.0)
    >>> c.rows({"flange_a": FlangeSum({"flange_a": 1.0}), "flange_b": FlangeSum({"flange_b": 1.0})}, c.p)
    [('mesh', 1.0*flange_a + 1.0*flange_b)]
    """

    flange_a = Flange("the coupled (following) joint's axis (a Revolute's or a Prismatic's)")
    flange_b = Flange("the leading joint's axis (a Revolute's or a Prismatic's)")
    ratio = Param(1.0, unit="1", doc="s_a / s_b (1, m/rad or rad/m by the axes' kinds)", check="nonzero")

    def rows(self, flanges, p):
        return [("mesh", flanges["flange_a"] - p.ratio * flanges["flange_b"])]


class IdealPulley(FlangeConstraint):
    """A drum winding a rope (Modelica's ``IdealRollingWheel``): the rope's end travels
    ``s_b = radius phi_a`` (m) for the drum's angle ``phi_a`` (rad).

    ``flange_a`` on the drum's rotational axis (a Revolute), ``flange_b`` on the translational
    axis the rope's end moves along (a Prismatic; displacements from the start values). Point
    the Prismatic's axis away from the drum: a positive drum angle then pays rope out. The
    rope is ideal: inextensible, massless, and never slack (it pushes as well as pulls, as
    Modelica's). Its flows satisfy ``tau_a = -radius f_b``; the rope's ``tension`` is
    ``-f_b`` (N, > 0 while it pulls the load towards the drum).

    Examples
    --------
    A hoist: a drum of inertia J lowers a mass m under gravity with
    ``a = m g r^2 / (J + m r^2)``.

    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, Inertia, Prismatic, PointMass, IdealPulley
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> drum = m.add("drum", Revolute(n=(0, 0, 1)))
    >>> rotor = m.add("drum_J", Inertia(J=0.02))
    >>> hook = m.add("hook", Prismatic(n=(0, -1, 0))); load = m.add("load", PointMass(m=3.0))
    >>> rope = m.add("rope", IdealPulley(radius=0.05))
    >>> m.connect(w.frame_b, drum.frame_a); m.connect(rotor.flange, drum.axis)
    >>> m.connect(w.frame_b, hook.frame_a); m.connect(hook.frame_b, load.frame_a)
    >>> m.connect(rope.flange_a, drum.axis); m.connect(rope.flange_b, hook.axis)
    >>> res = mbcomp.simulate(m, t_end=1.0)
    >>> a = 3.0 * 9.81 * 0.05 ** 2 / (0.02 + 3.0 * 0.05 ** 2)
    >>> bool(abs(res["hook.s"][-1] - a / 2) < 1e-9), bool(abs(res["rope.tension"][-1] - 3.0 * (9.81 - a)) < 1e-9)
    (True, True)
    """

    flange_a = Flange("the drum's rotational axis (a Revolute's axis)")
    flange_b = Flange("the rope end's translational axis (a Prismatic's axis, pointing away from the drum)")
    radius = Param(0.05, unit="m", doc="radius of the drum (to the rope's centre line)", check="positive")
    flange_kinds = {"flange_a": "rotational", "flange_b": "translational"}
    output_units = {"tau_a": "N m", "f_b": "N", "tension": "N"}

    def rows(self, flanges, p):
        return [("rope", flanges["flange_b"] - p.radius * flanges["flange_a"])]

    def outputs(self, t, states, p, flows):
        """The drum's torque ``tau_a`` (N m), the force on the rope's end ``f_b`` (N) and the
        rope's ``tension`` ``-f_b`` (N)."""
        return {"tau_a": flows["flange_a"], "f_b": flows["flange_b"], "tension": -flows["flange_b"]}


class Belt(FlangeConstraint):
    """Two pulleys joined by a belt that does not slip: ``r_a phi_a = r_b phi_b`` (same sense).

    ``flange_a``, ``flange_b`` on the two pulleys' rotational axes; angles from their start
    values. The belt's tension difference ``F`` gives ``tau_a = -r_a F``, ``tau_b = r_b F``,
    so ``tau_a / r_a + tau_b / r_b = 0``. A crossed belt (opposite senses) is an
    :class:`IdealGear` with ``ratio = -r_b / r_a``.

    Examples
    --------
    >>> from mbcomp.library import Belt
    >>> Belt(r_a=0.1, r_b=0.3).p.r_b
    0.3
    """

    flange_a = Flange("the first pulley's rotational axis")
    flange_b = Flange("the second pulley's rotational axis")
    r_a = Param(0.1, unit="m", doc="radius of pulley a", check="positive")
    r_b = Param(0.1, unit="m", doc="radius of pulley b", check="positive")
    flange_kinds = {"flange_a": "rotational", "flange_b": "rotational"}
    output_units = {"tau_a": "N m", "tau_b": "N m", "f": "N"}

    def rows(self, flanges, p):
        return [("mesh", p.r_a * flanges["flange_a"] - p.r_b * flanges["flange_b"])]

    def outputs(self, t, states, p, flows):
        """Torques on the pulleys ``tau_a``, ``tau_b`` (N m) and the tension difference ``f``
        (N, tight side minus slack side, > 0 when it drives pulley b forward)."""
        return {"tau_a": flows["flange_a"], "tau_b": flows["flange_b"], "f": flows["flange_b"] / p.r_b}


class Inertia(FlangeInertia):
    """A rotor of axial inertia ``J`` on a rotational joint axis (a shaft without a body).

    The rotor turns with the frame the flange moves (a Revolute's frame_b on its ``axis``)
    about the joint's axis ``n``: inertia tensor ``J n n^T``, no mass, no transverse
    inertia. On an axis fixed in the world it is a body of axial inertia ``J`` on frame_b. A
    joint whose axis turns a rotor may leave its frame_b open (a shaft with no body on it).
    On a moving carrier its kinetic energy is ``J (n . w)^2 / 2`` with ``w`` the absolute
    angular velocity; ``gyroscopic=True`` also puts the gyroscopic moment
    ``w x (J n (n . w))`` on the carrying frame (a spinning rotor on a turning body), which
    ``False`` drops (it does no work: the energy is the same). A rotor geared to the joint by a
    large ratio (on the joint's own rate ``J s_dot^2 / 2``, MuJoCo's armature) is
    :class:`ReflectedInertia`.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import Fixed, Revolute, Inertia, Torque
    >>> m = mbcomp.Model(); base = m.add("base", Fixed()); j = m.add("j", Revolute())
    >>> rotor = m.add("rotor", Inertia(J=0.5)); tq = m.add("tq", Torque(tau=2.0))
    >>> m.connect(base.frame_b, j.frame_a)              # j.frame_b may stay open: the rotor is the shaft
    >>> m.connect(rotor.flange, j.axis); m.connect(tq.flange_b, j.axis)
    >>> round(float(mbcomp.simulate(m, t_end=1.0)["j.w"][-1]), 9)   # tau / J * t
    4.0
    """

    flange = Flange("a rotational joint's axis (or support) flange")
    J = Param(1.0, unit="kg m^2", doc="axial moment of inertia", check="positive")
    gyroscopic = Param(False, unit="1", kind="any",
                       doc="put the gyroscopic moment on the carrying frame (True/False)")

    def rotor(self, p):
        return p.J, bool(p.gyroscopic)

    def visuals(self, p, view):
        """A steel disk of axial inertia ``J`` (thickness a quarter of its radius:
        ``J = rho pi r^5 / 8``; radius kept within 0.03..0.25 of the scale) with a bar across
        it, about the joint's axis, on the frame the flange turns (``view.axis``); nothing
        where the scene cannot place it."""
        n = view.axis("flange") if hasattr(view, "axis") else None
        if n is None:
            return []
        r = float(np.clip((8.0 * p.J / (np.pi * STEEL)) ** 0.2, 0.03 * view.scale, 0.25 * view.scale))
        R = z_to(n)
        return [Cylinder(r, r / 4, R=R, frame="flange", color="darkgrey"),
                Box((1.9 * r, 0.15 * r, 0.3 * r), R=R, frame="flange", color="silver")]


class _Reflected(FlangeInertia):
    """A rotor (or mass) reflected onto its joint's own rate: ``reflected`` True."""

    flange = Flange("a 1-DOF tree joint's axis flange (the joint's own rate: no support flange)")

    def reflected(self, p):
        return True


class ReflectedInertia(_Reflected):
    """A motor's rotor seen through a gearbox of large ratio: ``J s_dot^2 / 2`` on a rotational
    joint's own rate (MuJoCo's hinge ``armature``).

    A rotor of inertia ``J_r`` (kg m^2) on the joint's frame_a (the motor's housing) geared to
    frame_b by ``N`` turns at ``n . w_a + N s_dot`` (rad/s); its energy
    ``J_r (n . w_a + N s_dot)^2 / 2`` tends to ``N^2 J_r s_dot^2 / 2`` as ``N`` grows, the cross
    terms with the carrier's rate ``n . w_a`` fading as ``1 / N``. This element is that limit
    with ``J = N^2 J_r``: it adds ``J`` to the mass matrix's diagonal entry of the joint's speed
    and nothing else (no gyroscopic or carrier terms), exactly MuJoCo's armature. Its torque
    ``-J s_ddot`` acts through the gearbox inside the joint: the joint's reaction on frame_b
    about its axis carries it (``<joint>.tau`` along ``n``), frame_a feels the opposite. It
    needs the ``axis`` flange of a 1-speed joint in the spanning tree, not driven (a
    :class:`~mbcomp.library.Revolute`); a locked joint drops it (it turns at the locked rate,
    zero). :class:`Inertia` is the rotor turning with frame_b instead (``J (n . w_b)^2 / 2``).

    Examples
    --------
    A pendulum of inertia ``I = m l^2`` about its hinge with a reflected rotor ``J``: the
    rotor slows it to ``(I + J) phi_ddot = -m g l sin(phi)``.

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass, ReflectedInertia
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=2.0)); motor = m.add("motor", ReflectedInertia(J=0.5))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> m.connect(motor.flange, j.axis)
    >>> ev = mbcomp.assemble(m).evaluate(0.0, np.array([0.5]), np.array([1.0]))
    >>> float(ev.M[0, 0]), round(float(ev.f[0] / ev.M[0, 0]), 9)   # m l^2 + J, -m g l sin(phi) / (m l^2 + J)
    (2.5, -3.762531627)
    """

    J = Param(1.0, unit="kg m^2", doc="reflected inertia N^2 J_rotor on the joint's own rate", check="positive")

    def rotor(self, p):
        return p.J, False


class ReflectedMass(_Reflected):
    """:class:`ReflectedInertia` on a translational joint: ``m s_dot^2 / 2`` on a slider's own
    rate (MuJoCo's slide ``armature``: a rotor driving a screw or belt, seen as a mass).

    Adds ``m`` to the mass matrix's diagonal entry of the joint's speed and nothing else; its
    force ``-m s_ddot`` acts inside the joint (the joint's reaction on frame_b along ``n``
    carries it). Needs the ``axis`` flange of a 1-speed tree joint (a
    :class:`~mbcomp.library.Prismatic`), not driven; a locked joint drops it.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass, ReflectedMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> s = m.add("s", Prismatic(n=(0, 1, 0))); load = m.add("load", PointMass(m=3.0))
    >>> screw = m.add("screw", ReflectedMass(m=1.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, load.frame_a); m.connect(screw.flange, s.axis)
    >>> round(float(mbcomp.simulate(m, t_end=1.0)["s.v"][-1]), 9)   # -m g t / (m + m_reflected)
    -7.3575
    """

    axis_kind = "translational"
    m = Param(1.0, unit="kg", doc="reflected mass on the joint's own rate", check="positive")

    def rotor(self, p):
        return p.m, False


class PlanetaryGear(Model):
    """A planetary (epicyclic) gear set: sun, carrier and ring on one axis, massless planets.

    Three :class:`Revolute` shafts about ``n`` from the frame ``frame_a`` (the housing),
    each with a rotor :class:`Inertia` (``J_sun``, ``J_carrier``, ``J_ring``), tied by an
    :class:`IdealGear` with the carrier as its support and ``ratio = -z_ring / z_sun``:
    Willis' equation ``(w_sun - w_carrier) = -(z_ring / z_sun) (w_ring - w_carrier)``. In
    steady state (or with massless shafts) the torques on ring and sun stand in the ratio
    ``tau_ring / tau_sun = z_ring / z_sun``, and the carrier takes ``-(tau_sun + tau_ring)``.

    Ports: ``frame_a`` (the housing frame), ``sun``, ``carrier``, ``ring`` (the shafts'
    rotational axis flanges: connect torques, drives, dampers, other gears) and
    ``sun_frame``, ``carrier_frame``, ``ring_frame`` (frames fixed to the shafts, on their
    axis at the housing's origin, to attach bodies).
    Result columns: ``<name>.sun.phi``, ``.carrier.w`` etc. (the Revolutes), the gear's
    torques ``<name>.mesh.tau_a`` (sun), ``.tau_b`` (ring), ``.tau_support`` (carrier).

    Parameters
    ----------
    z_sun, z_ring : int
        Teeth of the sun and of the ring (``z_ring > z_sun``).
    J_sun, J_carrier, J_ring : float
        Axial inertias of the three shafts (kg m^2, > 0).
    n : array_like (3,)
        The common axis, ``frame_a`` coordinates.
    w_sun0, w_carrier0 : float
        Start speeds of sun and carrier (rad/s; the ring's follows from Willis' equation).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import Fixed, PlanetaryGear, Torque
    >>> m = mbcomp.Model(); base = m.add("base", Fixed())
    >>> pg = m.add("pg", PlanetaryGear(z_sun=20, z_ring=60, w_carrier0=1.0))
    >>> m.connect(base.frame_b, pg.frame_a)
    >>> res = mbcomp.simulate(m, t_end=0.5)
    >>> round(float(res["pg.ring.w"][-1]), 9)   # sun at rest: w_r = w_c (1 + z_s / z_r)
    1.333333333
    """

    def __init__(self, z_sun=20, z_ring=60, J_sun=1e-3, J_carrier=1e-2, J_ring=1e-2, n=(0.0, 0.0, 1.0),
                 w_sun0=0.0, w_carrier0=0.0):
        super().__init__()
        if not (0 < z_sun < z_ring):
            raise ValueError(f"PlanetaryGear: z_sun={z_sun!r} and z_ring={z_ring!r} must satisfy 0 < z_sun < z_ring "
                             "-> fix: e.g. z_sun=20, z_ring=60")
        ratio = -float(z_ring) / float(z_sun)
        w_ring0 = w_carrier0 + (w_sun0 - w_carrier0) / ratio
        n = tuple(np.asarray(n, float))
        for name, J, w0 in (("sun", J_sun, w_sun0), ("carrier", J_carrier, w_carrier0), ("ring", J_ring, w_ring0)):
            shaft = self.add(name, Revolute(n=n, phi0=0.0, w0=w0))
            rotor = self.add(f"J_{name}", Inertia(J=J))  # the rotor carries the shaft: frame_b may stay open
            self.connect(rotor.flange, shaft.axis)
            self.expose(name, shaft.axis)
            self.expose(f"{name}_frame", shaft.frame_b)
        mesh = self.add("mesh", IdealGear(ratio=ratio))
        self.connect(mesh.flange_a, self["sun"].axis)
        self.connect(mesh.flange_b, self["ring"].axis)
        self.connect(mesh.support, self["carrier"].axis)
        for name in ("carrier", "ring"):
            self.connect(self["sun"].frame_a, self[name].frame_a)
        self.expose("frame_a", self["sun"].frame_a)
