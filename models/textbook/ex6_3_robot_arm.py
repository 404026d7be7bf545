"""Seed Example 6.3: two-link robot arm in a horizontal plane, driven by two joint motors.

Link 1 (mass ``m1``, inertia ``I1`` about its centre of mass ``G1`` at distance ``a1`` from the
shoulder, length ``l1``) turns about the vertical axis through the shoulder ``O``; link 2
(mass ``m2``, inertia ``I2`` about ``G2`` at distance ``a2`` from the elbow) is hinged at the end
of link 1. Both hinges are vertical, so gravity (world ``-z``) does no work (V = 0). Motor 1
exerts ``tau1`` on link 1 (reaction on the ground), motor 2 exerts ``tau2`` on link 2 (reaction
on link 1). The book's coordinates are absolute angles from the world x axis: ``alpha1`` of
link 1 (= the shoulder angle) and ``alpha2`` of link 2 (= shoulder + elbow angle), with the
generalized forces ``Q1 = tau1 - tau2``, ``Q2 = tau2`` (6.43)-(6.44), and

    (I1 + m1 a1^2 + m2 l1^2) alpha1'' + m2 a2 l1 alpha2'' cos(alpha1 - alpha2)
        + m2 a2 l1 alpha2'^2 sin(alpha1 - alpha2) = tau1 - tau2                   (6.53)
    (m2 a2^2 + I2) alpha2'' + m2 a2 l1 alpha1'' cos(alpha1 - alpha2)
        - m2 a2 l1 alpha1'^2 sin(alpha1 - alpha2) = tau2                          (6.54)

Modelled with two ``Revolute`` joints about z, two ``RigidBody`` links and two ``Torque``
actuators on the joints' axis flanges; each torque is a constant or a one-line law
``tau(t, phi, w)`` of time and its own joint's relative angle and rate. The default laws are
PD position controllers driving the arm from rest at ``(alpha1, alpha2) = (0, 0)`` towards
the joint targets ``q1_ref``, ``q2_ref``.

Run: ``mbcomp simulate models/textbook/ex6_3_robot_arm.py --plot arm.png``
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import FixedTranslation, Revolute, RigidBody, Torque, World

SIMULATION = dict(t_end=5.0, rtol=1e-9, atol=1e-11)


def _link_inertia(m, L):
    """Slender link of mass m (kg) and length L (m) along x: inertia about its centre (kg m^2)."""
    It = m * L ** 2 / 12.0
    return np.diag([0.0, It, It])


def build(m1=2.0, l1=0.5, a1=0.25, I1=None, m2=1.0, l2=0.4, a2=0.2, I2=None,
          alpha1_0=0.0, alpha2_0=0.0, alpha1_dot0=0.0, alpha2_dot0=0.0,
          tau1=None, tau2=None, q1_ref=1.0, q2_ref=0.8, kp=(8.0, 3.0), kd=(1.5, 0.5), g=9.81):
    """Two-link robot arm of seed Example 6.3.

    Parameters
    ----------
    m1, l1, a1, I1 : float
        Link 1: mass (kg), shoulder-to-elbow length (m), shoulder-to-G1 distance (m), inertia
        about G1 for the vertical axis (kg m^2; default ``m1 l1^2/12``, a slender link).
    m2, l2, a2, I2 : float
        Link 2: mass (kg), length (m, only for the default inertia), elbow-to-G2 distance (m),
        inertia about G2 (kg m^2; default ``m2 l2^2/12``).
    alpha1_0, alpha2_0, alpha1_dot0, alpha2_dot0 : float
        Start values of the book's absolute angles (rad) and rates (rad/s).
    tau1, tau2 : float or callable, optional
        Shoulder and elbow motor torques (N m, about +z): constants or laws ``tau(t, phi, w)``
        of the joint's own relative angle (rad) and rate (rad/s); default PD laws
        ``kp[i] (q_ref - phi) - kd[i] w``.
    q1_ref, q2_ref : float
        Targets (rad) of the default PD laws: shoulder angle and elbow (relative) angle.
    kp, kd : tuple of float
        Gains of the default PD laws (N m/rad, N m s/rad).
    g : float
        Gravity (m/s^2), along world -z, normal to the plane of motion.

    Returns
    -------
    mbcomp.Model
        Aliases ``alpha1`` (shoulder angle), ``alpha1_dot``, ``elbow_angle`` (= alpha2 - alpha1)
        and ``elbow_rate``.
    """
    I1 = _link_inertia(m1, l1) if I1 is None else np.diag([0.0, I1, I1])
    I2 = _link_inertia(m2, l2) if I2 is None else np.diag([0.0, I2, I2])
    if tau1 is None:
        tau1 = lambda t, phi, w: kp[0] * (q1_ref - phi) - kd[0] * w  # noqa: E731
    if tau2 is None:
        tau2 = lambda t, phi, w: kp[1] * (q2_ref - phi) - kd[1] * w  # noqa: E731

    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    shoulder = mdl.add("shoulder", Revolute(n=(0, 0, 1), phi0=alpha1_0, w0=alpha1_dot0))
    link1 = mdl.add("link1", RigidBody(m=m1, r_cm=(a1, 0.0, 0.0), I=I1))
    upper = mdl.add("upper", FixedTranslation(r=(l1, 0.0, 0.0)))
    elbow = mdl.add("elbow", Revolute(n=(0, 0, 1), phi0=alpha2_0 - alpha1_0, w0=alpha2_dot0 - alpha1_dot0))
    link2 = mdl.add("link2", RigidBody(m=m2, r_cm=(a2, 0.0, 0.0), I=I2))
    motor1 = mdl.add("motor1", Torque(tau=tau1))
    motor2 = mdl.add("motor2", Torque(tau=tau2))

    mdl.connect(world.frame_b, shoulder.frame_a)
    mdl.connect(shoulder.frame_b, link1.frame_a)
    mdl.connect(shoulder.frame_b, upper.frame_a)
    mdl.connect(upper.frame_b, elbow.frame_a)
    mdl.connect(elbow.frame_b, link2.frame_a)
    mdl.connect(motor1.flange_b, shoulder.axis)  # on link 1, reaction on the ground
    mdl.connect(motor2.flange_b, elbow.axis)     # on link 2, reaction on link 1
    mdl.alias("alpha1", "shoulder.phi")
    mdl.alias("alpha1_dot", "shoulder.w")
    mdl.alias("elbow_angle", "elbow.phi")
    mdl.alias("elbow_rate", "elbow.w")
    return mdl
