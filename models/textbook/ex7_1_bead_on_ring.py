"""Seed Example 7.1 (stability of steady states): a bead on a ring spinning about a vertical diameter.

A smooth circular ring of radius ``r`` turns at the constant rate ``omega`` about its vertical
diameter; a bead of mass ``m`` slides on it. ``alpha`` is the bead's angle on the ring from
the lowest point. The book's energies and equation of motion are

    T = (1/2) m (r^2 alpha'^2 + omega^2 r^2 sin^2 alpha)                 (7.20)
    V = -m g r cos(alpha)         (printed with ``theta``: a misprint)    (7.21)
    m r^2 alpha'' - m omega^2 r^2 sin(alpha) cos(alpha) + m g r sin(alpha) = 0   (7.23)

Steady states (7.28): ``alpha = 0`` and ``cos(alpha) = g / (r omega^2)`` (the latter only for
``omega^2 >= g/r``); the book omits ``alpha = pi`` (the bead at the top), which (7.27) also
admits. Linearization (7.33): ``lambda^2 = omega^2 cos(2 alpha) - (g/r) cos(alpha)``.

What is modelled (library components only): a ``Revolute`` about the world vertical ``y``
(the ring's diameter, through the ring centre at the world origin) driven by a
``PrescribedMotion`` ``s = omega t``; the ring itself is massless (its motion is prescribed, its
inertia would only change the drive torque). On the ring frame a ``Revolute`` about the ring's
normal ``z`` at the centre carries a ``FixedTranslation`` ``(0, -r, 0)`` to a ``PointMass``:
the bead, at ``(r sin alpha, -r cos alpha, 0)`` in ring axes. The bead hinge's angle is the
book's ``alpha``. Gravity along ``-y``. The energy is not conserved (the drive works); the
Jacobi integral ``h = T - m omega^2 r^2 sin^2(alpha) + V`` is.

Run: ``mbcomp simulate models/textbook/ex7_1_bead_on_ring.py -p omega=6``
"""
from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Revolute, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12)


def build(m=0.1, r=0.5, g=9.81, omega=6.0, alpha0=0.5, alpha_dot0=0.0):
    """Bead on a ring rotating at constant rate (seed Example 7.1, Fig. 7.1).

    Parameters
    ----------
    m : float
        Bead mass (kg), a particle.
    r : float
        Ring radius (m).
    g : float
        Gravitational acceleration (m/s^2), along world ``-y``.
    omega : float
        Constant spin rate of the ring about the vertical world ``y`` axis (rad/s).
        ``omega^2 > g/r`` makes the lowest point unstable.
    alpha0, alpha_dot0 : float
        Start angle of the bead from the lowest point of the ring (rad) and its rate (rad/s).

    Returns
    -------
    mbcomp.Model
        Aliases ``alpha``, ``alpha_dot`` (bead on the ring), ``psi`` (ring spin angle).
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    spin = mdl.add("spin", Revolute(n=(0, 1, 0)))
    drive = mdl.add("drive", PrescribedMotion(s=lambda t: omega * t))
    bead_hinge = mdl.add("bead_hinge", Revolute(n=(0, 0, 1), phi0=alpha0, w0=alpha_dot0))
    radius = mdl.add("radius", FixedTranslation(r=(0.0, -r, 0.0)))
    bead = mdl.add("bead", PointMass(m=m))
    mdl.connect(world.frame_b, spin.frame_a)
    mdl.connect(drive.flange_b, spin.axis)
    mdl.connect(spin.frame_b, bead_hinge.frame_a)
    mdl.connect(bead_hinge.frame_b, radius.frame_a)
    mdl.connect(radius.frame_b, bead.frame_a)
    mdl.alias("alpha", "bead_hinge.phi")
    mdl.alias("alpha_dot", "bead_hinge.w")
    mdl.alias("psi", "spin.phi")
    return mdl
