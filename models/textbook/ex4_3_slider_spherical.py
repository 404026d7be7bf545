"""Seed Sections 4.3-4.5: a slider plus a spherical joint (Figs. 4.1, 4.2, 4.4), 5 DOF.

The book's examples of constraint equations:

- Example 1, slider (Fig. 4.1): four constraint forces and couples ``Rx, Rz, Mx, Mz`` give
  four constraint equations ``rx = 0, rz = 0, theta_x = 0, theta_z = 0``; the slider
  translates along y (``ry``) and turns about y (``phi``) freely (a cylindrical pair).
- Example 2, spherical joint (Fig. 4.2): three constraint forces ``Rx, Ry, Rz`` give three
  constraint equations ``rx = ry = rz = 0``; three rotations (Euler angles) remain.
- Combined (Fig. 4.4): body 1 on the slider, body 2 on a ball joint on body 1:
  ``M = 6 N - C = 6*2 - (4 + 3) = 5`` degrees of freedom, generalized coordinates ``ry``,
  ``phi`` and three rotation coordinates of the ball joint; with ``L`` prescribed motions
  (Section 4.5) ``M = 6 N - C - L``.

What is modelled: world z up (gravity -z). The slider is a sub-model ``slider`` made of a
:class:`~mbcomp.library.Prismatic` (``slider.translation``, along world y) and a
:class:`~mbcomp.library.Revolute` (``slider.rotation``, about the same y axis) joined at a
massless intermediate frame. Body 1 (``body1``, a sleeve with an arm along its x axis) sits on
the revolute's frame_b; at the arm's end (``arm``, offset ``a`` along body-1 x) a
:class:`~mbcomp.library.Spherical` joint (``ball``) carries body 2 (``body2``, a rod hanging along
its -z axis). Optionally ``drive_rotation`` prescribes ``phi(t)`` (a string in ``t``), which
removes one DOF (``L = 1``).

Grübler's count as ``mbcomp info`` reports it counts the massless intermediate frame of the
slider as a third rigid group and the slider's two 1-DOF joints with 5 constraints each:
``6*3 - (5 + 5 + 3) = 5``, the same as the book's ``6*2 - (4 + 3) = 5`` (the extra frame's 6
coordinates are removed by 6 extra constraint equations).

Reactions (force/torque on each joint's frame_b, resolved in frame_b, about its origin):
``slider.translation.f.*``/``tau.*`` are in axes parallel to the world (the intermediate frame
does not rotate): ``Rx = f.x``, ``Rz = f.z``, ``Mx = tau.x``, ``Mz = tau.z``, while ``f.y`` and
``tau.y`` (the free directions) are zero; ``ball.f.*`` are the three ball-joint forces (body-2
axes), ``ball.tau.*`` are zero.

Run: ``mbcomp info models/textbook/ex4_3_slider_spherical.py`` (5 DOF) or
``mbcomp info models/textbook/ex4_3_slider_spherical.py -p drive_rotation="0.5*sin(3*t)"`` (4).
"""
import numpy as np

from mbcomp import Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import FixedTranslation, PrescribedMotion, Prismatic, Revolute, RigidBody, Spherical, World

SIMULATION = dict(t_end=3.0, rtol=1e-10, atol=1e-12, method="DOP853")


def cylindrical_slider(n=(0.0, 1.0, 0.0), s0=None, v0=None, phi0=None, w0=None):
    """The book's frictionless slider (Fig. 4.1): translation along and rotation about ``n``.

    A sub-model with ports ``frame_a`` (guide) and ``frame_b`` (sliding body), components
    ``translation`` (Prismatic, coordinate ``s`` in m) and ``rotation`` (Revolute, ``phi`` in
    rad), and the rotation's flanges exposed as ``axis``/``support``.

    Parameters
    ----------
    n : sequence of float
        Slide and rotation axis, frame_a coordinates.
    s0, v0, phi0, w0 : float or mbcomp.Guess, optional
        Start position (m), velocity (m/s), angle (rad), angular rate (rad/s).

    Returns
    -------
    mbcomp.Model
    """
    sub = Model()
    tr = sub.add("translation", Prismatic(n=n, s0=s0, v0=v0))
    rot = sub.add("rotation", Revolute(n=n, phi0=phi0, w0=w0))
    sub.connect(tr.frame_b, rot.frame_a)
    sub.expose("frame_a", tr.frame_a)
    sub.expose("frame_b", rot.frame_b)
    sub.expose("axis", rot.axis)
    sub.expose("support", rot.support)
    return sub


def build(m1=2.0, a=0.3, m2=1.5, b=0.6, r2=0.02, g=9.81, ry0=0.0, ry_dot0=0.4, phi0=0.3, phi_dot0=1.5,
          tilt0=0.5, w_ball0=(1.0, -0.8, 2.5), drive_rotation=None):
    """Body 1 on a cylindrical slider along world y, body 2 on a ball joint at body 1's arm.

    Parameters
    ----------
    m1 : float
        Mass of body 1 (kg): a slender arm of length ``a`` along body-1 x from the slide axis.
    a : float
        Distance from the slide axis to the ball joint (m).
    m2, b, r2 : float
        Mass (kg), length (m) and radius (m) of body 2, a solid cylinder hanging from the ball.
    g : float
        Gravity (m/s^2) along world -z.
    ry0, ry_dot0 : float
        Start slide position (m) and velocity (m/s) along world y.
    phi0, phi_dot0 : float
        Start rotation (rad) and rate (rad/s) of body 1 about the slide axis.
    tilt0 : float
        Start tilt (rad) of body 2 about body-1 x (ball joint start orientation).
    w_ball0 : sequence of float
        Start angular velocity of body 2 relative to body 1 (rad/s, body-2 axes).
    drive_rotation : str, optional
        Law ``phi(t)`` (rad, string in ``t``) prescribing the slider's rotation (``L = 1``).

    Returns
    -------
    mbcomp.Model
    """
    I1 = m1 * a ** 2 / 12.0
    I2t = m2 * (3 * r2 ** 2 + b ** 2) / 12.0
    I2a = m2 * r2 ** 2 / 2.0
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    if drive_rotation is not None:
        slider = mdl.add("slider", cylindrical_slider(s0=ry0, v0=ry_dot0))
        drive = mdl.add("drive", PrescribedMotion(s=drive_rotation))
        mdl.connect(drive.flange_b, slider.axis)
    else:
        slider = mdl.add("slider", cylindrical_slider(s0=ry0, v0=ry_dot0, phi0=phi0, w0=phi_dot0))
    body1 = mdl.add("body1", RigidBody(m=m1, r_cm=(a / 2, 0.0, 0.0), I=np.diag([1e-3 * I1, I1, I1])))
    arm = mdl.add("arm", FixedTranslation(r=(a, 0.0, 0.0)))
    ball = mdl.add("ball", Spherical(R0=rot_axis((1.0, 0.0, 0.0), tilt0), w0=w_ball0))
    body2 = mdl.add("body2", RigidBody(m=m2, r_cm=(0.0, 0.0, -b / 2), I=np.diag([I2t, I2t, I2a])))
    mdl.connect(world.frame_b, slider.frame_a)
    mdl.connect(slider.frame_b, body1.frame_a)
    mdl.connect(slider.frame_b, arm.frame_a)
    mdl.connect(arm.frame_b, ball.frame_a)
    mdl.connect(ball.frame_b, body2.frame_a)
    mdl.alias("r_y", "slider.translation.s")
    mdl.alias("phi", "slider.rotation.phi")
    mdl.alias("R_x", "slider.translation.f.x")
    mdl.alias("R_z", "slider.translation.f.z")
    mdl.alias("M_x", "slider.translation.tau.x")
    mdl.alias("M_z", "slider.translation.tau.z")
    return mdl
