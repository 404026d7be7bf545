"""MJCF joints as library joints, with their passive forces, stops, friction and armature.

MuJoCo applies a body's joints at the body, in order: the body's pose is its parent's, moved
by the body's ``pos``/orientation, then right-multiplied by each joint's motion, a joint's
``pos`` and ``axis`` given in the body's frame. A hinge at ``p`` turns about the line through
``p`` by ``q - ref``; a slide moves along ``axis`` by ``q - ref``; a ball turns about ``p`` by its
quaternion; a free joint is the body's pose itself. So a body's joints become a chain:
``FixedRotation(r = p - p_before, R = rot(axis, -ref))`` (named ``<joint>_origin``, left out
when the identity) then ``Revolute(n=axis)`` (``phi`` = MuJoCo's ``qpos``); ``Prismatic(n=axis)``
after a ``-ref axis`` shift; ``Spherical`` (``Q`` = MuJoCo's quaternion, ``w`` in the body's
axes = MuJoCo's ``qvel``); ``FreeMotion`` (``r``, ``Q``; ``v`` in world axes, ``w`` in body
axes, as MuJoCo's ``qvel``). After the last one, ``-p`` back to the body's origin.

Passive forces on hinges and slides (on the joint's ``support``/``axis`` flanges):
``stiffness``/``springref`` and ``damping`` -> ``RotationalSpringDamper`` or
``TranslationalSpringDamper`` (``<joint>_spring``, or ``<joint>_damping`` without stiffness).
``range`` with ``limited`` (or ``autolimits``) -> the joint's stops with ``limits=True``.
``frictionloss`` -> ``Revolute(friction=CoulombBearing(torque_max))`` /
``Prismatic(friction=SlidingFriction(1, normal=frictionloss))`` with ``friction=True``.
``armature`` on a hinge -> ``ReflectedInertia(J)``, on a slide -> ``ReflectedMass(m)``, on the
axis flange (``<joint>_armature``): kinetic energy ``armature qdot^2 / 2`` on the joint's own
rate, which adds ``armature`` to ``M``'s diagonal exactly as MuJoCo does (a rotor seen through
a large gear ratio; ``load_mjcf(armature=False)`` leaves it out, noted). A ball's or free
joint's armature is not imported (noted): the reflected elements need a joint of one speed.
"""
import numpy as np

from ..geometry.kinematics import rot_axis
from ..modeling.component import Guess
from .mjcf_frames import numbers

__all__ = ["JointSpec", "joint_spec", "add_joints"]

KINDS = ("hinge", "slide", "ball", "free")


class JointSpec:
    """One MJCF joint's numbers (angles in rad).

    Attributes
    ----------
    name, kind : str
        Component name; ``hinge``, ``slide``, ``ball`` or ``free``.
    pos, axis : (3,) ndarray
        Anchor (m) and unit axis, body frame.
    ref, springref, stiffness, damping, armature, frictionloss : float
        MuJoCo's values (rad or m; N m/rad or N/m; N m s/rad or N s/m; kg m^2 or kg; N m or N).
    range : (2,) ndarray or None
        The limits when the joint is limited.

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> from mbcomp.io.mjcf_frames import Compiler
    >>> from mbcomp.io.mjcf_joints import joint_spec
    >>> c = Compiler(ET.fromstring("<mujoco/>"), ".")
    >>> j = joint_spec({"range": "-90 90", "axis": "0 2 0"}, "knee", c, "joint 'knee'")
    >>> j.kind, j.axis.tolist(), [round(float(x), 6) for x in j.range]
    ('hinge', [0.0, 1.0, 0.0], [-1.570796, 1.570796])
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def joint_spec(attrs, name, compiler, what):
    """The :class:`JointSpec` of a joint's attributes (defaults applied)."""
    kind = attrs.get("type", "hinge")
    if kind not in KINDS:
        raise ValueError(f"MJCF {what}: type {kind!r} is not one of {', '.join(KINDS)} -> fix the file")
    axis = numbers(attrs.get("axis", "0 0 1"), 3, f"{what} axis")
    if kind in ("hinge", "slide") and not np.linalg.norm(axis):
        raise ValueError(f"MJCF {what}: axis='0 0 0' -> give the {kind}'s direction")
    angle = compiler.angle if kind == "hinge" else (lambda v: v)
    f = {k: float(attrs.get(k, 0.0)) for k in ("ref", "springref", "stiffness", "damping", "armature",
                                                 "frictionloss")}
    f["ref"], f["springref"] = angle(f["ref"]), angle(f["springref"])
    limited = attrs.get("limited", "auto")
    if limited == "auto":
        limited = "true" if compiler.autolimits and "range" in attrs else "false"
    rng = None
    if limited == "true" and kind in ("hinge", "slide"):
        rng = angle(numbers(attrs.get("range", "0 0"), 2, f"{what} range"))
        if not rng[0] < rng[1]:
            raise ValueError(f"MJCF {what}: limited with range={attrs.get('range', '0 0')!r} -> give lower < upper")
    return JointSpec(name=name, kind=kind, pos=numbers(attrs.get("pos", "0 0 0"), 3, f"{what} pos"),
                     axis=axis / (np.linalg.norm(axis) or 1.0), range=rng, limited=limited == "true",
                     springdamper=bool(np.all(numbers(attrs.get("springdamper", "0 0"), 2, f"{what} springdamper") > 0)), ball_range="range" in attrs and kind == "ball", **f)


class _Chain:
    """Where the next component of a body's joint chain connects, and the anchor it is at."""

    def __init__(self, model, port, names):
        self.model, self.port, self.names, self.at = model, port, names, np.zeros(3)

    def add(self, name, comp, into="frame_a", out="frame_b"):
        c = self.model.add(name, comp)
        self.model.connect(self.port, getattr(c, into))
        self.port = getattr(c, out)
        return c

    def offset(self, lib, name, r, R=None):
        if R is not None and not np.array_equal(R, np.eye(3)):
            self.add(self.names(name, "joint origin"), lib.FixedRotation(r=r, R=R))
        elif np.any(r):
            self.add(self.names(name, "joint origin"), lib.FixedTranslation(r=r))


def _stops(lib, j, opts, notes):
    """``(keyword arguments of the 1-DOF joint, start value)``: stops, friction, start at ``ref``."""
    kw, start = {}, j.ref
    if opts["limits"] and j.range is not None:
        kw["limits"] = tuple(float(x) for x in j.range)
        if not j.range[0] <= start <= j.range[1]:
            start = 0.5 * (j.range[0] + j.range[1])
            notes.append(f"joint {j.name!r}: starts at the middle of its range {kw['limits']} (qpos0 = ref "
                         f"{j.ref:g} is outside it)")
    if j.frictionloss > 0.0:
        if opts["friction"]:
            kw["friction"] = (lib.CoulombBearing(torque_max=j.frictionloss) if j.kind == "hinge"
                              else lib.SlidingFriction(mu_s=1.0, normal=j.frictionloss))
        else:
            notes.append(f"joint {j.name!r}: frictionloss={j.frictionloss:g} not imported (friction=False)")
    return kw, start


def _passive(model, lib, j, joint, opts, names, notes):
    """Spring, damper and armature on a hinge's or slide's flanges."""
    c = j.stiffness if opts["springs"] else 0.0
    d = j.damping if opts["damping"] else 0.0
    if j.springdamper:  # MuJoCo sets stiffness and damping from M at qpos0 instead of the values given
        notes.append(f"joint {j.name!r}: springdamper (stiffness and damping from a time constant) not imported")
        c = d = 0.0
    if c > 0.0 or d > 0.0:
        if j.kind == "hinge":
            law = lib.RotationalSpringDamper(c=c, d=d, phi_rel0=j.springref) if c > 0.0 else lib.RotationalDamper(d=d)
        else:
            law = lib.TranslationalSpringDamper(c=c, d=d, s_rel0=j.springref)
        el = model.add(names(f"{j.name}_{'spring' if c > 0.0 else 'damping'}", "joint spring"), law)
        model.connect(joint.support, el.flange_a)
        model.connect(joint.axis, el.flange_b)
    if j.armature > 0.0 and opts["armature"]:  # left out by armature=False: one note for all (io/mjcf.py)
        rotor = lib.ReflectedInertia(J=j.armature) if j.kind == "hinge" else lib.ReflectedMass(m=j.armature)
        rotor = model.add(names(f"{j.name}_armature", "joint armature"), rotor)
        model.connect(rotor.flange, joint.axis)


def add_joints(model, lib, specs, port, opts, names, notes, pose=None, loose=False):
    """The components of one body's joints from ``port`` (the body's offset frame; the world
    frame for a free joint, which starts at ``pose = (R, p)``, the body's pose in the file, a
    :class:`~mbcomp.Guess` when ``loose``: a free joint on a loop, which the topology cuts);
    returns the port that is the body's frame."""
    chain = _Chain(model, port, names)
    for j in specs:
        if j.kind == "free":
            start = (Guess(np.array(pose[1])), Guess(np.array(pose[0]))) if loose else (pose[1], pose[0])
            chain.add(j.name, lib.FreeMotion(r0=start[0], R0=start[1]))
            if j.stiffness or j.damping or j.armature:
                notes.append(f"joint {j.name!r}: stiffness, damping and armature of a free joint not imported")
            continue
        if j.kind == "ball":
            chain.offset(lib, f"{j.name}_origin", j.pos - chain.at)
            chain.at = j.pos
            chain.add(j.name, lib.Spherical())
            if j.stiffness or j.damping or j.armature or j.ball_range:
                notes.append(f"joint {j.name!r}: stiffness, damping, armature and range of a ball joint not imported "
                             "(the reflected armature elements need a joint of one speed)")
            continue
        kw, start = _stops(lib, j, opts, notes)
        if j.kind == "hinge":
            chain.offset(lib, f"{j.name}_origin", j.pos - chain.at, rot_axis(j.axis, -j.ref) if j.ref else None)
            chain.at = j.pos
            joint = chain.add(j.name, lib.Revolute(n=j.axis, phi0=float(start), **kw) if start else
                              lib.Revolute(n=j.axis, **kw))
        else:
            chain.offset(lib, f"{j.name}_origin", -j.ref * j.axis)
            joint = chain.add(j.name, lib.Prismatic(n=j.axis, s0=float(start), **kw) if start else
                              lib.Prismatic(n=j.axis, **kw))
        _passive(model, lib, j, joint, opts, names, notes)
    if np.any(chain.at):
        chain.offset(lib, f"{specs[-1].name}_back", -chain.at)
    return chain.port
