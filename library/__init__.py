"""mbcomp's standard component library, written only against mbcomp's public API.

Importable as ``mbcomp.library``. Every class here is an example of a role contract
(:mod:`mbcomp.roles`); user libraries are written the same way.
"""
from .sources import World, Fixed
from .parts import FixedTranslation, FixedRotation, RigidBody, PointMass, UncheckedRigidBody
from .joints import Revolute, Prismatic, Cylindrical, Spherical, Weld, FreeMotion
from .compound_joints import Universal, Planar
from .forces import Spring, Damper, SpringDamper, WorldForce, WorldTorque
from .contact import DiskContact, SphereContact, RollingDisk, RollingSphere
from .plane_contact import PlaneContact
from .rods import SphericalSpherical, UniversalSpherical
from .gears import (IdealGear, RackPinion, Belt, Inertia, PlanetaryGear, IdealPulley, JointCoupling, ReflectedInertia,
                    ReflectedMass)
from .axis import (RotationalSpring, RotationalDamper, RotationalSpringDamper,
                   TranslationalSpringDamper, Torque, Force, PrescribedMotion)
from .sensors import RelativeSensor, AbsoluteSensor, AbsoluteAngles, CutForceAndTorque
from .drivetrain import ElastoGear, BearingFriction, Motor, MotorTorque
from .stops import ElasticStop
from .friction import SlidingFriction, CoulombBearing, ContactFriction  # parameters of joints and contacts, not components

__all__ = [
    "World", "Fixed", "FixedTranslation", "FixedRotation", "RigidBody", "PointMass",
    "Revolute", "Prismatic", "Cylindrical", "Spherical", "Weld", "FreeMotion",
    "Spring", "Damper", "SpringDamper", "WorldForce", "WorldTorque",
    "RotationalSpring", "RotationalDamper", "RotationalSpringDamper", "TranslationalSpringDamper",
    "Torque", "Force", "PrescribedMotion",
    "DiskContact", "SphereContact", "RollingDisk", "RollingSphere", "PlaneContact",
    "ElastoGear", "BearingFriction", "Motor",
    "RelativeSensor", "AbsoluteSensor", "AbsoluteAngles", "CutForceAndTorque",
    "Universal", "Planar",
    "SphericalSpherical", "UniversalSpherical",
    "IdealGear", "RackPinion", "Belt", "Inertia", "PlanetaryGear",
    "MotorTorque",
    "IdealPulley",
    "ReflectedInertia", "ReflectedMass",
    "ElasticStop",
    "JointCoupling", "UncheckedRigidBody",
]
