"""Seed Example 5.5 (D'Alembert principle): two sliders on springs in a rotating slotted disk.

A disk turns about its centre ``O`` (angle ``theta`` about the disk axis ``z``). A straight,
frictionless slot through ``O`` carries two sliders: slider 1 (mass ``m1``) at distance
``rho1`` from ``O`` on the ``+e_r`` side, slider 2 (mass ``m2``) at ``rho2`` on the ``-e_r``
side (``r1 = rho1 e_r``, ``r2 = -rho2 e_r``, eqs. 5.28-5.29). Each slider is tied to the centre
by a spring of rate ``k`` and unstretched length ``a`` (active forces 5.32-5.33). The book's
disk is massless and free to rotate, so the system has 3 DOF ``(rho1, rho2, theta)`` and the
book's equations of motion are

    m1 (rho1'' - theta'^2 rho1) + k (rho1 - a) = 0                        (5.35)
    m2 (rho2'' - theta'^2 rho2) + k (rho2 - a) = 0                        (5.37)
    m1 (rho1 theta'' + 2 rho1' theta') rho1
        + m2 (rho2 theta'' + 2 rho2' theta') rho2 = 0                      (5.39)
    d/dt [ (m1 rho1^2 + m2 rho2^2) theta' ] = 0                           (5.40)

(5.35) and (5.37) print the spring rate as ``K``; it is the ``k`` of Fig. 5.6 and 5.32-5.33.
The text of (5.39) lost its brackets in print; the form above is the D'Alembert sum (5.38).

What is modelled (library components only): a ``Revolute`` about world ``z`` for the disk,
an optional disk body (``J`` about its axis; ``J = 0`` is the book's massless disk), two
``Prismatic`` joints on the disk frame along ``+x`` and ``-x`` (coordinates ``rho1``,
``rho2``), a ``PointMass`` on each, and a ``TranslationalSpringDamper`` (rate ``k``,
unstretched ``a``) between each slot's support and axis flanges, i.e. between ``O`` and the
slider along the slot. The disk lies in the horizontal plane; gravity (along ``-z``) is
carried by the slots and does no work. With ``omega`` given, the disk is instead driven at
the constant rate ``omega`` by a ``PrescribedMotion`` (an extension: then 5.35 and 5.37 are
two decoupled linear oscillators and the drive torque is ``dH/dt``).

Run: ``mbcomp simulate models/textbook/ex5_5_slotted_disk.py --plot disk.png``
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import PointMass, PrescribedMotion, Prismatic, Revolute, RigidBody, TranslationalSpringDamper, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12)


def build(m1=1.0, m2=1.5, k=40.0, a=0.2, J=0.0, omega=None, g=9.81,
          rho1_0=0.3, rho1_dot0=0.0, rho2_0=0.15, rho2_dot0=0.2, theta0=0.0, theta_dot0=4.0):
    """Slotted disk with two spring-loaded sliders (seed Example 5.5, Fig. 5.6).

    Parameters
    ----------
    m1, m2 : float
        Slider masses (kg).
    k : float
        Rate of each spring (N/m), acting along the slot between the centre and the slider.
    a : float
        Unstretched spring length (m).
    J : float
        Moment of inertia of the disk about its axis (kg m^2); 0 is the book's massless disk.
        (The disk body is a thin disk: transverse moments ``J/2``.)
    omega : float or None
        None (book): the disk turns freely. A number: the disk is driven at this constant
        rate (rad/s) from ``theta0``; ``theta_dot0`` is then ignored.
    g : float
        Gravitational acceleration (m/s^2) along world ``-z``, normal to the disk plane.
    rho1_0, rho1_dot0, rho2_0, rho2_dot0 : float
        Start distances of the sliders from the centre (m) and their rates (m/s).
    theta0, theta_dot0 : float
        Start angle (rad) and rate (rad/s) of the disk about world ``z``.

    Returns
    -------
    mbcomp.Model
        Aliases ``theta``, ``theta_dot`` (disk), ``rho1``, ``rho1_dot``, ``rho2``, ``rho2_dot``.
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    driven = omega is not None
    hinge = mdl.add("disk_hinge", Revolute(n=(0, 0, 1), phi0=None if driven else theta0,
                                           w0=None if driven else theta_dot0))
    disk = mdl.add("disk", RigidBody(m=0.0, I=np.diag([J / 2, J / 2, J])))
    slot1 = mdl.add("slot1", Prismatic(n=(1, 0, 0), s0=rho1_0, v0=rho1_dot0))
    slot2 = mdl.add("slot2", Prismatic(n=(-1, 0, 0), s0=rho2_0, v0=rho2_dot0))
    slider1 = mdl.add("slider1", PointMass(m=m1))
    slider2 = mdl.add("slider2", PointMass(m=m2))
    spring1 = mdl.add("spring1", TranslationalSpringDamper(c=k, s_rel0=a))
    spring2 = mdl.add("spring2", TranslationalSpringDamper(c=k, s_rel0=a))

    mdl.connect(world.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, disk.frame_a)
    for slot, slider, spring in ((slot1, slider1, spring1), (slot2, slider2, spring2)):
        mdl.connect(hinge.frame_b, slot.frame_a)
        mdl.connect(slot.frame_b, slider.frame_a)
        mdl.connect(slot.support, spring.flange_a)
        mdl.connect(slot.axis, spring.flange_b)
    if driven:
        drive = mdl.add("drive", PrescribedMotion(s=lambda t: theta0 + omega * t))
        mdl.connect(drive.flange_b, hinge.axis)
    mdl.alias("theta", "disk_hinge.phi")
    mdl.alias("theta_dot", "disk_hinge.w")
    mdl.alias("rho1", "slot1.s")
    mdl.alias("rho1_dot", "slot1.v")
    mdl.alias("rho2", "slot2.s")
    mdl.alias("rho2_dot", "slot2.v")
    return mdl
