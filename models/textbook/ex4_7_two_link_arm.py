"""Seed Example 4.7: two-link arm, a massless motor-driven link carrying a swinging rod.

Link 1 is (approximately) massless and turns about the vertical world axis ``Z`` (angle
``alpha``, rate ``omega = alpha'``), driven by a motor whose torque falls with speed,

    Md = M0 - dM * omega                      (book, section 4.7)

The motor is one line: a ``Torque`` law on the vertical joint's axis flange. At distance
``a`` from the vertical axis (along link 1, frame axis ``y1``) link 1 carries hinge ``A``
whose axis is ``x1`` (perpendicular to link 1 and to ``Z``). Link 2 is a uniform slender rod
(mass ``m``, length ``l``, inertia ``m l^2/12`` about its centre for the two transverse axes,
zero about its own axis ``z2``) hanging from ``A``; ``beta`` is its swing angle about ``x1``,
``beta = 0`` hanging straight down, ``beta > 0`` swinging away from the vertical axis (the
centre of mass is at ``A + (l/2) sin(beta) y1 - (l/2) cos(beta) Z``). Gravity acts along ``-Z``.

Book's equations of motion (Newton-Euler, eqs. 4.20-4.22, program of Fig. 4.7)::

    m (a^2 + l^2/3 sin^2 b + a l sin b) alpha'' + (m a l/2) alpha' beta' cos b
        + (5/12) m l^2 alpha' beta' sin b cos b - (M0 - dM alpha') = 0         (4.20)
    (2/3) l beta'' - (2/3) l alpha'^2 sin b cos b - a alpha'^2 cos b + g sin b = 0   (4.21)

(4.21) is right; in (4.20) the two velocity-product coefficients are wrong (``m a l`` and
``(2/3) m l^2`` are correct): the i2 component of the acceleration (4.4) omits the Coriolis
part ``-(l/2) alpha' beta' cos b`` of ``Omega_2 x v_G``. See
``tests/test_textbook_ex4_7.py``, which derives the equations with Lagrange in sympy.

Book program parameters (default): m = 2 kg, a = 0.1 m, l = 0.5 m, dM = 0.5 N m s/rad,
M0 = 1 N m, g = 9.81 m/s^2, 10 s from rest with beta = 0.

Run: ``mbcomp simulate models/textbook/ex4_7_two_link_arm.py --plot arm.png``
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import FixedTranslation, Revolute, RigidBody, Torque, World

SIMULATION = dict(t_end=10.0, rtol=1e-9, atol=1e-11)


def build(m=2.0, a=0.1, l=0.5, dM=0.5, M0=1.0, g=9.81, alpha0=0.0, omega0=0.0, beta0=0.0, beta_dot0=0.0):
    """Two-link arm of seed Example 4.7.

    Parameters
    ----------
    m : float
        Mass of link 2, the rod (kg).
    a : float
        Distance from the vertical axis to hinge A along link 1 (m).
    l : float
        Length of link 2 (m); its centre of mass is at l/2 from A.
    dM, M0 : float
        Motor law ``Md = M0 - dM * omega``: stall torque ``M0`` (N m) and slope ``dM``
        (N m s/rad), ``omega`` (rad/s) the rate of link 1 about the vertical.
    g : float
        Gravitational acceleration (m/s^2), along world -Z.
    alpha0, omega0, beta0, beta_dot0 : float
        Start angle (rad) and rate (rad/s) of link 1 about Z and of link 2 about hinge A.

    Returns
    -------
    mbcomp.Model
        Aliases ``alpha``, ``omega`` (link 1), ``beta``, ``beta_dot`` (link 2 at hinge A),
        ``Md`` is not stored; it is ``M0 - dM * omega``.
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    base = mdl.add("base", Revolute(n=(0, 0, 1), phi0=alpha0, w0=omega0))
    motor = mdl.add("motor", Torque(tau=lambda t, phi, w: M0 - dM * w))
    link1 = mdl.add("link1", FixedTranslation(r=(0.0, a, 0.0)))  # massless link 1: base -> hinge A
    hinge_A = mdl.add("hinge_A", Revolute(n=(1, 0, 0), phi0=beta0, w0=beta_dot0))
    It = m * l ** 2 / 12.0
    link2 = mdl.add("link2", RigidBody(m=m, r_cm=(0.0, 0.0, -l / 2), I=np.diag([It, It, 0.0])))

    mdl.connect(world.frame_b, base.frame_a)
    mdl.connect(motor.flange_b, base.axis)  # reaction on the ground (frame_a of the base joint)
    mdl.connect(base.frame_b, link1.frame_a)
    mdl.connect(link1.frame_b, hinge_A.frame_a)
    mdl.connect(hinge_A.frame_b, link2.frame_a)
    mdl.alias("alpha", "base.phi")
    mdl.alias("omega", "base.w")
    mdl.alias("beta", "hinge_A.phi")
    mdl.alias("beta_dot", "hinge_A.w")
    return mdl
