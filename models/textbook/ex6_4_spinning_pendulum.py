"""Seed Example 6.4: a thin bar hinged to a link that spins at a constant prescribed rate.

Link 1 turns about the vertical world axis ``Z`` with the constant rate ``Omega``; the spin is
prescribed (``PrescribedMotion`` with ``s = Omega*t`` on the spin hinge's axis), which removes
that degree of freedom (book: M = 6*2 - (5 + 5) - 1 = 1). Link 1 carries an inertia ``I_Z``
about ``Z`` (a disc; it only adds the constant ``I_Z Omega^2 / 2`` to the kinetic energy). On
the spin axis link 1 carries the hinge ``A`` with horizontal axis ``x1``; a uniform thin bar of
mass ``m`` and length ``l`` hangs from ``A``; ``beta`` is its angle from the downward vertical
about ``x1``. Gravity acts along ``-Z``. With ``I = m l^2 / 3`` the bar's moment of inertia
about ``A`` for a transverse axis (zero about its own axis), Lagrange gives

    I beta'' - I Omega^2 sin(beta) cos(beta) + m g (l/2) sin(beta) = 0            (6.63)

For ``Omega^2 > 3 g / (2 l)`` the hanging position is unstable and the bar swings about the
tilted equilibrium ``cos(beta*) = 3 g / (2 l Omega^2)``. The drive torque (output
``spin_drive.tau``) is the rate of change of the angular momentum about ``Z``,
``2 I Omega sin(beta) cos(beta) beta'``.

Run: ``mbcomp simulate models/textbook/ex6_4_spinning_pendulum.py --plot spin.png``
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import PrescribedMotion, Revolute, RigidBody, World

SIMULATION = dict(t_end=5.0, rtol=1e-9, atol=1e-11)


def build(m=1.0, l=0.6, Omega=6.0, m1=0.5, I_Z=0.02, beta0=0.2, beta_dot0=0.0, g=9.81):
    """Spinning pendulum of seed Example 6.4.

    Parameters
    ----------
    m, l : float
        Mass (kg) and length (m) of the thin bar.
    Omega : float
        Constant spin rate of link 1 about the vertical (rad/s).
    m1, I_Z : float
        Mass (kg, centred on the spin axis at hinge A) and moment of inertia about the
        vertical axis (kg m^2) of link 1.
    beta0, beta_dot0 : float
        Start angle (rad) of the bar from the downward vertical and its rate (rad/s).
    g : float
        Gravitational acceleration (m/s^2), along world -Z.

    Returns
    -------
    mbcomp.Model
        Aliases ``beta``, ``beta_dot`` (the bar at hinge A), ``spin_angle`` (= Omega t) and
        ``drive_torque`` (N m about +Z on link 1, from the prescribed motion).
    """
    It = m * l ** 2 / 12.0
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    spin = mdl.add("spin", Revolute(n=(0, 0, 1)))
    drive = mdl.add("spin_drive", PrescribedMotion(s=f"{float(Omega)!r}*t"))
    link1 = mdl.add("link1", RigidBody(m=m1, r_cm=(0.0, 0.0, 0.0), I=np.diag([I_Z / 2, I_Z / 2, I_Z])))
    hinge_A = mdl.add("hinge_A", Revolute(n=(1, 0, 0), phi0=beta0, w0=beta_dot0))
    bar = mdl.add("bar", RigidBody(m=m, r_cm=(0.0, 0.0, -l / 2), I=np.diag([It, It, 0.0])))

    mdl.connect(world.frame_b, spin.frame_a)
    mdl.connect(drive.flange_b, spin.axis)
    mdl.connect(spin.frame_b, link1.frame_a)
    mdl.connect(spin.frame_b, hinge_A.frame_a)  # hinge A lies on the spin axis
    mdl.connect(hinge_A.frame_b, bar.frame_a)
    mdl.alias("beta", "hinge_A.phi")
    mdl.alias("beta_dot", "hinge_A.w")
    mdl.alias("spin_angle", "spin.phi")
    mdl.alias("drive_torque", "spin_drive.tau")
    return mdl
