"""Seed Example 3.2: steady precession of a gyro top (eqs. 3.25-3.34, Fig. 3.4).

A symmetric top (mass ``m``, centre of mass at distance ``l`` from the fixed tip ``o`` on the
symmetry axis ``e3``, centroidal moments ``I1c`` transverse and ``I3`` axial) spins on a fixed
point under gravity. With precession ``psi`` about the vertical ``k``, nutation ``theta``
(angle between ``k`` and ``e3``) and spin ``phi`` about ``e3``, the book's condition for steady
precession (theta, psi', phi' constant) is

- (3.33) ``m g l = I3 psi' phi' + (I3 - I1) psi'^2 cos theta``,
- (3.34) ``psi' phi' = m g l / I3`` for ``theta = pi/2``,

where ``I1`` is the transverse moment **about the fixed point** (``I1 = I1c + m l^2``; the book's
``Ho = Io w``, eq. 3.27) and ``phi'`` is the spin rate relative to the precessing frame
(``omega_3 = phi' + psi' cos theta``). For ``sin theta != 0`` (the book prints "for
sin theta = 0", a misprint) the condition is a quadratic in ``psi'``: a slow and a fast
precession rate for each spin rate fast enough.

What is modelled: a :class:`~mbcomp.library.Spherical` joint at the world origin (world z up,
gravity ``-g`` along z) carrying a :class:`~mbcomp.library.RigidBody` whose symmetry axis is the
body z axis, ``r_cm = (0, 0, l)``, ``I = diag(I1c, I1c, I3)`` about the centre of mass. The start
orientation is the 3-1-3 Euler set ``R0 = Rz(psi0) Rx(theta0) Rz(phi0)`` and the start angular
velocity (body axes) follows from ``psi'``, ``theta'``, ``phi'``; by default ``psi'`` is the slow
root of (3.33), so the top precesses steadily. ``precession`` may be ``"slow"``, ``"fast"`` or
a number (e.g. ``0.0``: the top is released with spin only and nutates).

Outputs: the body's orientation ``top.Q.*`` (nutation ``theta = arccos(e3 . k)``, with
``e3 . k = 1 - 2 (Q.x^2 + Q.y^2)``), ``omega_3`` (alias of ``ball.w.z``: body-axis spin, rad/s,
conserved), ``top.w.*`` (world), reactions ``ball.f.*`` (force on the top at the tip, top axes).

Run: ``mbcomp simulate models/textbook/ex3_2_gyro_top.py --out top.csv``
"""
import numpy as np

from mbcomp import Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import RigidBody, Spherical, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12, method="DOP853")

_EX, _EZ = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)


def steady_precession_rates(m, l, I1c, I3, g, theta, spin):
    """Both roots ``psi'`` (rad/s) of the book's steady-precession condition (3.33).

    Parameters
    ----------
    m, l, I1c, I3, g : float
        Mass (kg), tip-to-centre-of-mass distance (m), centroidal transverse and axial moments
        of inertia (kg m^2), gravitational acceleration (m/s^2).
    theta : float
        Nutation angle (rad) between the vertical and the symmetry axis.
    spin : float
        Relative spin rate ``phi'`` (rad/s).

    Returns
    -------
    (float, float)
        Slow and fast precession rates (rad/s); the fast one is ``inf`` where (3.33) degenerates
        to a linear equation (``(I3 - I1) cos theta = 0``, e.g. eq. 3.34).

    Raises
    ------
    ValueError
        If the spin is too slow for a steady precession at ``theta``.
    """
    I1 = I1c + m * l ** 2  # about the fixed point
    a = (I3 - I1) * np.cos(theta)
    b = I3 * spin
    c = -m * g * l
    disc = b * b - 4 * a * c
    if disc < 0:
        raise ValueError(f"spin {spin} rad/s is too slow for a steady precession at theta = {theta} rad")
    q = -0.5 * (b + np.copysign(np.sqrt(disc), b))  # numerically stable roots
    slow = c / q
    fast = q / a if a != 0 else np.inf
    return slow, fast


def body_rates(theta, phi, psi_dot, theta_dot, phi_dot):
    """Angular velocity (rad/s, body axes) for 3-1-3 Euler angles and their rates."""
    return np.array([theta_dot * np.cos(phi) + psi_dot * np.sin(theta) * np.sin(phi),
                     -theta_dot * np.sin(phi) + psi_dot * np.sin(theta) * np.cos(phi),
                     phi_dot + psi_dot * np.cos(theta)])


def build(m=0.5, l=0.04, I1c=5e-4, I3=1e-3, g=9.81, theta0=1.0, spin=40.0, precession="slow",
          theta_dot0=0.0, psi0=0.0, phi0=0.0):
    """Heavy symmetric top on a ball joint at the origin, world z vertical.

    Parameters
    ----------
    m, l, I1c, I3, g : float
        Mass (kg), distance tip -> centre of mass along the symmetry axis (m), centroidal
        transverse and axial moments of inertia (kg m^2), gravity (m/s^2, along world -z).
    theta0, theta_dot0 : float
        Start nutation angle (rad) and its rate (rad/s).
    spin : float
        Start relative spin rate ``phi'`` (rad/s).
    precession : {"slow", "fast"} or float
        Start precession rate ``psi'`` (rad/s): a root of (3.33) or a given number.
    psi0, phi0 : float
        Start precession and spin angles (rad).

    Returns
    -------
    mbcomp.Model
    """
    if isinstance(precession, str):
        slow, fast = steady_precession_rates(m, l, I1c, I3, g, theta0, spin)
        psi_dot = {"slow": slow, "fast": fast}[precession]
    else:
        psi_dot = float(precession)
    R0 = rot_axis(_EZ, psi0) @ rot_axis(_EX, theta0) @ rot_axis(_EZ, phi0)
    w0 = body_rates(theta0, phi0, psi_dot, theta_dot0, spin)
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    ball = mdl.add("ball", Spherical(R0=R0, w0=w0))
    top = mdl.add("top", RigidBody(m=m, r_cm=(0.0, 0.0, l), I=np.diag([I1c, I1c, I3])))
    mdl.connect(world.frame_b, ball.frame_a)
    mdl.connect(ball.frame_b, top.frame_a)
    mdl.alias("omega_3", "ball.w.z")
    return mdl
