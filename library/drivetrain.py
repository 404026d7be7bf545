"""Drivetrain elements on joint-axis flanges: an elastic gear mesh with backlash, bearing
friction and the seed's DC motor.

``ElastoGear``, ``BearingFriction`` and ``MotorTorque`` are :class:`~mbcomp.FlangeElement`
force laws (no constraint, no state of their own); ``Motor`` is ``MotorTorque`` with the
armature's rotor (a composite ``Model``). Connect their flanges to 1-DOF rotational joints' ``axis`` (and ``support``) flanges.
Angles are in rad, rates in rad/s, torques in N m. The laws are plain arithmetic with
``abs`` and ``tanh``, so they trace into the compiled program without guards (the backlash's
corners are written with ``abs``, not with ``if``).
"""
import numpy as np

from mbcomp import Flange, FlangeElement, Model, Param
from mbcomp.errors import Problem
from .gears import Inertia
from .laws import neg, pos, smax, smin

__all__ = ["ElastoGear", "BearingFriction", "MotorTorque", "Motor"]



class ElastoGear(FlangeElement):
    """Elastic gear mesh with backlash between ``flange_a`` and ``flange_b``.

    Gear convention as Modelica's ``IdealGear``: the rigid mesh has ``s_a = ratio * s_b``.
    The mesh deflection, measured on flange_a's side, is ``e = s_a - ratio * s_b`` (rad),
    its rate ``de = w_a - ratio * w_b`` (rad/s). With ``h = backlash / 2`` the tooth torque
    ``tau`` (N m) is

    * ``0`` while ``|e| <= h`` (the teeth fly freely across the gap),
    * on the positive flank (``e > h``), with spring torque ``tau_c = c (e - h)`` and damping
      torque ``tau_d = d de``: ``tau = max(0, tau_c + min(tau_c, tau_d))``,
    * on the negative flank (``e < -h``), ``tau_c = c (e + h)``:
      ``tau = min(0, tau_c + max(tau_c, tau_d))``,

    the damping limited as in Modelica's ``ElastoBacklash``: it never pulls the teeth
    together (``tau`` keeps the sign of the flank in contact) and never exceeds the spring
    torque, so ``tau`` is continuous in ``e`` and only the stiffness jumps, from 0 to ``c``, at
    contact (on purpose: no smoothing). Without backlash (``backlash = 0``) both flanks
    always touch and the mesh is a linear spring-damper, ``tau = c e + d de``.

    The element applies ``-tau`` to flange_a and ``ratio * tau`` to flange_b (so
    ``tau_b = -ratio * tau_a``: the mesh does no work along its rigid motion). Potential
    energy ``c (|e| - h)^2 / 2`` in contact, 0 in the gap; the damping only takes energy out.

    Examples
    --------
    >>> from mbcomp.library import ElastoGear
    >>> g = ElastoGear(c=100.0, d=0.0, backlash=0.02, ratio=2.0)
    >>> states = {"flange_a": (0.05, 0.0), "flange_b": (0.0, 0.0)}   # e = 0.05 rad
    >>> out = g.flange_forces(0.0, states, g.p)                       # 100 * (0.05 - 0.01)
    >>> round(out["flange_a"], 12), round(out["flange_b"], 12)
    (-4.0, 8.0)
    >>> g.flange_forces(0.0, {"flange_a": (0.005, 0.0), "flange_b": (0.0, 0.0)}, g.p)["flange_b"]
    0.0
    """

    axis_kind = "rotational"
    conservative = True
    dissipative = True
    flange_a = Flange("driving side, s_a = ratio * s_b when rigid (e.g. a joint's axis)")
    flange_b = Flange("driven side (e.g. another joint's axis)")
    c = Param(1.0, unit="N m/rad", doc="mesh stiffness, on flange_a's side", check="nonnegative")
    d = Param(0.0, unit="N m s/rad", doc="mesh damping in contact, on flange_a's side", check="nonnegative")
    backlash = Param(0.0, unit="rad", doc="total backlash (width of the dead zone of e), on flange_a's side",
                     check="nonnegative")
    ratio = Param(1.0, unit="1", doc="gear ratio s_a / s_b of the rigid mesh", check="nonzero")
    output_units = {"tau": "N m", "deflection": "rad", "w_rel": "rad/s"}

    def conserves_energy(self, p):
        return p.d == 0.0

    @staticmethod
    def deflection(states, p):
        """``(e, de)``: mesh deflection ``s_a - ratio s_b`` (rad) and its rate (rad/s)."""
        (sa, va), (sb, vb) = states["flange_a"], states["flange_b"]
        return sa - p.ratio * sb, va - p.ratio * vb

    def torque(self, e, de, p):
        """Tooth torque ``tau`` (N m) of the class's law at deflection ``e`` and rate ``de``."""
        h = 0.5 * p.backlash
        tp, tn, td = p.c * pos(e - h), p.c * neg(e + h), p.d * de
        if p.backlash > 0:  # a guard on a parameter: one side per run
            return pos(tp + smin(tp, td)) + neg(tn + smax(tn, td))
        return tp + tn + td

    def flange_forces(self, t, states, p):
        tau = self.torque(*self.deflection(states, p), p)
        return {"flange_a": -tau, "flange_b": p.ratio * tau}

    def potential(self, states, p):
        e, _ = self.deflection(states, p)
        h = 0.5 * p.backlash
        return 0.5 * p.c * (pos(e - h) + neg(e + h)) ** 2

    def outputs(self, t, states, p):
        """Tooth torque ``tau`` (N m, > 0 on the positive flank), ``deflection`` ``e`` (rad)
        and its rate ``w_rel`` (rad/s)."""
        e, de = self.deflection(states, p)
        return {"tau": self.torque(e, de, p), "deflection": e, "w_rel": de}


class BearingFriction(FlangeElement):
    """Bearing friction between the two sides of one joint: viscous plus regularized Coulomb.

    With ``w_rel = w_b - w_a`` (rad/s) the friction torque is
    ``tau = d w_rel + tau_c tanh(w_rel / w_smooth)`` (N m), applied as ``+tau`` to flange_a
    and ``-tau`` to flange_b (it opposes the relative rotation, as ``RotationalDamper``).
    Connect flange_a to ``joint.support`` and flange_b to ``joint.axis``.

    The ``tanh`` replaces the sign of ``w_rel`` below ``w_smooth``: the joint never sticks, it
    creeps at rates of order ``w_smooth`` under loads below ``tau_c``. Exact stick/slip
    (a stuck joint locked until its torque exceeds ``tau_c``) needs events and mode
    switches: that is the hybrid-systems issue's, not this element's.

    Examples
    --------
    >>> from mbcomp.library import BearingFriction
    >>> f = BearingFriction(d=0.1, tau_c=2.0, w_smooth=1e-3)
    >>> out = f.flange_forces(0.0, {"flange_a": (0.0, 0.0), "flange_b": (0.0, 10.0)}, f.p)
    >>> float(out["flange_a"]), float(out["flange_b"])                     # 0.1 * 10 + 2
    (3.0, -3.0)
    """

    axis_kind = "rotational"
    dissipative = True
    flange_a = Flange("support side (the joint's support flange)")
    flange_b = Flange("moving side (the joint's axis flange)")
    d = Param(0.0, unit="N m s/rad", doc="viscous friction coefficient", check="nonnegative")
    tau_c = Param(0.0, unit="N m", doc="Coulomb (sliding) friction torque", check="nonnegative")
    w_smooth = Param(1e-3, unit="rad/s", doc="relative rate below which the Coulomb torque fades to zero (tanh)",
                     check="positive")
    output_units = {"tau": "N m", "w_rel": "rad/s"}

    def conserves_energy(self, p):
        return p.d == 0.0 and p.tau_c == 0.0

    def torque(self, w_rel, p):
        """Friction torque (N m) at relative rate ``w_rel`` (rad/s)."""
        return p.d * w_rel + p.tau_c * np.tanh(w_rel / p.w_smooth)

    def flange_forces(self, t, states, p):
        tau = self.torque(states["flange_b"][1] - states["flange_a"][1], p)
        return {"flange_a": tau, "flange_b": -tau}

    def outputs(self, t, states, p):
        """Friction torque ``tau`` (N m, > 0 opposes a positive ``w_rel``) and ``w_rel`` (rad/s)."""
        w_rel = states["flange_b"][1] - states["flange_a"][1]
        return {"tau": self.torque(w_rel, p), "w_rel": w_rel}


LAWS = ("linear",)


class MotorTorque(FlangeElement):
    """The torque of a DC motor on a rotational joint axis: the seed's linear torque-speed law.

    Seed textbook, section 4.7 (*Example Problem: Dynamics of Two-Link Arms*): the driving
    torque falls with the speed ``w`` (rad/s) as ``Md = M0 - dM w``. Written with the motor's
    data sheet values, ``M0 = tau_stall`` (torque at ``w = 0``) and
    ``dM = tau_stall / w_no_load`` (``Md = 0`` at ``w = w_no_load``)::

        tau = tau_stall (1 - w / w_no_load)

    for every ``w``: above the no-load speed the motor brakes, backwards it pulls harder
    (a DC motor at constant voltage). ``w`` is the rate of the joint whose axis flange_b is
    on; the torque acts on the joint's frame_b, its reaction on frame_a (the stator).
    This element has no inertia: :class:`Motor` is this law together with the armature's
    rotor (an :class:`~mbcomp.library.Inertia` on the same flange).

    Examples
    --------
    >>> from mbcomp.library import MotorTorque
    >>> m = MotorTorque(tau_stall=2.0, w_no_load=100.0)
    >>> m.flange_forces(0.0, {"flange_b": (0.0, 25.0)}, m.p)                # 2 * (1 - 0.25)
    {'flange_b': 1.5}
    """

    axis_kind = "rotational"
    flange_b = Flange("the driven flange (a rotational joint's axis)")
    tau_stall = Param(1.0, unit="N m", doc="stall torque M0 (torque at zero speed)", check="positive")
    w_no_load = Param(1.0, unit="rad/s", doc="no-load speed (speed at zero torque)", check="positive")
    law = Param("linear", unit="1", kind="any", doc="torque-speed law: 'linear' (seed section 4.7)")
    output_units = {"tau": "N m", "w": "rad/s"}

    def check_params(self, p):
        if p.law in LAWS:
            return []
        return [Problem(f"{self.path}.law", f"unknown torque-speed law {p.law!r}",
                        f"use one of {', '.join(map(repr, LAWS))}, or a Torque with tau=lambda t, phi, w: ... "
                        "for any other law")]

    def torque(self, w, p):
        """Motor torque (N m) at speed ``w`` (rad/s)."""
        return p.tau_stall * (1.0 - w / p.w_no_load)

    def flange_forces(self, t, states, p):
        return {"flange_b": self.torque(states["flange_b"][1], p)}

    def outputs(self, t, states, p):
        """Motor torque ``tau`` (N m) and speed ``w`` (rad/s)."""
        w = states["flange_b"][1]
        return {"tau": self.torque(w, p), "w": w}


def _armature(J_armature):
    """``J_armature`` as a float >= 0 (kg m^2), or a ``ValueError`` naming the fix."""
    try:
        J = float(J_armature)
    except (TypeError, ValueError):
        J = float("nan")
    if not (np.isfinite(J) and J >= 0.0):
        raise ValueError(f"Motor: J_armature={J_armature!r} must be a number >= 0 (kg m^2, the armature's "
                         "inertia about the joint axis) -> fix: e.g. J_armature=1e-4, or 0 for none")
    return J


class Motor(Model):
    """DC motor on a rotational joint axis: the seed's torque-speed law and an armature inertia.

    A composite of :class:`MotorTorque` (named ``torque``: ``tau = tau_stall (1 - w /
    w_no_load)``, seed section 4.7, with ``w`` the joint's rate in rad/s) and, when
    ``J_armature > 0``, the armature's rotor, an :class:`~mbcomp.library.Inertia` (named
    ``armature``) on the same flange: it turns with the joint's frame_b about the joint's
    axis, so on a fixed axis ``(J_load + J_armature) dw/dt = tau``. The stator is the joint's
    frame_a (the torque's reaction acts there).

    Parameters
    ----------
    tau_stall : float
        Stall torque ``M0`` (N m, > 0): the torque at zero speed.
    w_no_load : float
        No-load speed (rad/s, > 0): the speed at zero torque.
    J_armature : float, optional
        Axial inertia of the armature (kg m^2, >= 0; 0: no rotor is added).
    law : str, optional
        Torque-speed law: ``'linear'`` (the only one; a ``Torque`` with a law for any other).
    gyroscopic : bool, optional
        Put the armature's gyroscopic moment on the carrying frame (a motor on a turning body).

    Port ``flange_b``: connect it to a Revolute's ``axis``. Result columns ``<name>.tau``
    (N m), ``<name>.w`` (rad/s) and ``<name>.power`` (W); run-time parameters
    ``<name>.torque.tau_stall``, ``<name>.torque.w_no_load``, ``<name>.armature.J``.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, RigidBody, Motor
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))
    >>> j = m.add("j", Revolute(n=(0, 0, 1))); disk = m.add("disk", RigidBody(m=1.0, I=np.eye(3) * 0.03))
    >>> mot = m.add("motor", Motor(tau_stall=2.0, w_no_load=100.0, J_armature=0.02))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, disk.frame_a); m.connect(mot.flange_b, j.axis)
    >>> res = mbcomp.simulate(m, t_end=1.0)
    >>> exact = 100.0 * (1 - np.exp(-1.0 * 2.0 / ((0.03 + 0.02) * 100.0)))   # w(t), J + J_a = 0.05
    >>> bool(abs(res["motor.w"][-1] - exact) < 1e-6)
    True
    """

    def __init__(self, tau_stall=1.0, w_no_load=1.0, J_armature=0.0, law="linear", gyroscopic=False):
        super().__init__()
        J = _armature(J_armature)
        torque = self.add("torque", MotorTorque(tau_stall=tau_stall, w_no_load=w_no_load, law=law))
        if J > 0.0:
            rotor = self.add("armature", Inertia(J=J, gyroscopic=gyroscopic))
            self.connect(rotor.flange, torque.flange_b)
        self.expose("flange_b", torque.flange_b)
        for column in ("tau", "w", "power"):
            self.alias(column, f"torque.{column}")
