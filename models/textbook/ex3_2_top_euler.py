"""Seed Example 3.2 in Euler angles: the heavy symmetric top on three hinges (eqs. 3.25-3.34).

The same top as ``ex3_2_gyro_top.py`` (mass ``m``, centre of mass at ``l`` from the fixed tip
on the symmetry axis ``e3``, centroidal moments ``I1c`` transverse and ``I3`` axial, world z up,
gravity ``-g`` along z), but its orientation is the book's 3-1-3 Euler set itself
(Fig. 3.4): precession ``psi`` about the vertical ``k``, nutation ``theta`` about the node
line ``e1`` (angle between ``k`` and ``e3``), spin ``phi`` about ``e3``:
``R = Rz(psi) Rx(theta) Rz(phi)``, the same convention as ``ex3_2_gyro_top.py``.

Why a second model of the same top: on the Spherical joint the orientation is a quaternion,
and a steady precession (3.33) turns it continually, so it is not an equilibrium of those
coordinates and cannot be linearized as one. In Euler angles the Lagrangian does not contain
``psi`` (the gravity torque and the inertia are symmetric about the vertical) nor ``phi``
(the top is symmetric about ``e3``): both are cyclic. A steady precession is then
``theta = const``, ``theta' = 0`` with constant rates ``psi'`` and ``phi'`` -- an equilibrium of
the reduced dynamics in ``(theta, theta', psi', phi')``, which ``mbcomp.linearize`` analyses
(``psi`` and ``phi`` are reported as moving, cyclic coordinates). The joint speeds are the
Euler-angle rates, so ``spin.w`` is the book's relative spin ``phi'``
(``omega_3 = phi' + psi' cos theta``) and ``precession.w`` is ``psi'``.

Gimbal singularity: at ``theta = 0`` (or ``pi``) the precession and spin axes coincide, the
three hinge axes span only a plane and the mass matrix is singular (``det M`` is proportional to
``sin^2 theta``): a sleeping top (axis vertical) cannot be described, nor can a motion that
passes through the vertical. Use ``ex3_2_gyro_top.py`` for those; use this model for steady
precession with ``0 < theta < pi``.

What is modelled (library components only): ``Revolute`` ``precession`` about world z at the
origin -> ``Revolute`` ``nutation`` about the (massless) precessing frame's x axis (the node
line) -> ``Revolute`` ``spin`` about the nutated frame's z axis -> ``RigidBody`` ``top`` with
``r_cm = (0, 0, l)`` and ``I = diag(I1c, I1c, I3)`` about its centre of mass. The intermediate
frames are the hinges' own frames (no mass). By default the precession rate is the slow root
of (3.33), ``m g l = I3 psi' phi' + (I3 - I1) psi'^2 cos theta`` with ``I1 = I1c + m l^2`` the
transverse moment about the fixed point.

Outputs (aliases): ``psi``, ``theta``, ``phi`` (rad) and ``psi_dot``, ``theta_dot``, ``phi_dot``
(rad/s); the top's ``top.Q.*``, ``top.w.*`` as usual.

Run: ``mbcomp simulate models/textbook/ex3_2_top_euler.py --out top.csv``
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import Revolute, RigidBody, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12, method="DOP853")


def steady_precession_rates(m, l, I1c, I3, g, theta, spin):
    """Both roots ``psi'`` (rad/s) of the book's steady-precession condition (3.33).

    The same function as in ``ex3_2_gyro_top.py`` (each model file is self-contained).

    Parameters
    ----------
    m, l, I1c, I3, g : float
        Mass (kg), tip-to-centre-of-mass distance (m), centroidal transverse and axial moments
        of inertia (kg m^2), gravitational acceleration (m/s^2).
    theta : float
        Nutation angle (rad).
    spin : float
        Relative spin rate ``phi'`` (rad/s).

    Returns
    -------
    (float, float)
        Slow and fast precession rates (rad/s); the fast one is ``inf`` where (3.33) is linear
        (``(I3 - I1) cos theta = 0``).

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


def build(m=0.5, l=0.04, I1c=5e-4, I3=1e-3, g=9.81, theta0=1.0, spin=40.0, precession="slow",
          theta_dot0=0.0, psi0=0.0, phi0=0.0):
    """Heavy symmetric top on precession, nutation and spin hinges at the origin, world z up.

    Parameters
    ----------
    m, l, I1c, I3, g : float
        Mass (kg), distance tip -> centre of mass along the symmetry axis (m), centroidal
        transverse and axial moments of inertia (kg m^2), gravity (m/s^2, along world -z).
    theta0, theta_dot0 : float
        Start nutation angle (rad, ``0 < theta0 < pi``: the Euler angles are singular at 0 and
        pi) and its rate (rad/s).
    spin : float
        Start relative spin rate ``phi'`` (rad/s).
    precession : {"slow", "fast"} or float
        Start precession rate ``psi'`` (rad/s): a root of (3.33) or a given number.
    psi0, phi0 : float
        Start precession and spin angles (rad).

    Returns
    -------
    mbcomp.Model
        Components ``precession``, ``nutation``, ``spin`` (Revolute: coordinate ``phi``, speed
        ``w``) and ``top``; aliases ``psi``, ``theta``, ``phi``, ``psi_dot``, ``theta_dot``,
        ``phi_dot``.
    """
    if isinstance(precession, str):
        slow, fast = steady_precession_rates(m, l, I1c, I3, g, theta0, spin)
        psi_dot = {"slow": slow, "fast": fast}[precession]
    else:
        psi_dot = float(precession)
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    prec = mdl.add("precession", Revolute(n=(0, 0, 1), phi0=psi0, w0=psi_dot))
    nut = mdl.add("nutation", Revolute(n=(1, 0, 0), phi0=theta0, w0=theta_dot0))
    rot = mdl.add("spin", Revolute(n=(0, 0, 1), phi0=phi0, w0=spin))
    top = mdl.add("top", RigidBody(m=m, r_cm=(0.0, 0.0, l), I=np.diag([I1c, I1c, I3])))
    mdl.connect(world.frame_b, prec.frame_a)
    mdl.connect(prec.frame_b, nut.frame_a)
    mdl.connect(nut.frame_b, rot.frame_a)
    mdl.connect(rot.frame_b, top.frame_a)
    for alias, joint in (("psi", "precession"), ("theta", "nutation"), ("phi", "spin")):
        mdl.alias(alias, f"{joint}.phi")
        mdl.alias(f"{alias}_dot", f"{joint}.w")
    return mdl
