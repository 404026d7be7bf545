"""Seed Example 6.5 (Lagrange multiplier): the pendulum's rod tension as a multiplier.

The book frees the pendulum of Fig. 6.2 in the radial direction (Fig. 6.7): ``r`` and
``theta`` become generalized coordinates with

    T = (1/2) m (r'^2 + r^2 theta'^2),   V = -m g r cos(theta),

then imposes the constraint ``r = l`` (6.78) with a multiplier ``lambda``:

    m r'' - m r theta'^2 - m g cos(theta) + lambda = 0          (6.76)
    d/dt (m r^2 theta') + m g r sin(theta) = 0                  (6.77)
    lambda = m l theta'^2 + m g cos(theta)                      (6.79)  (the rod tension)
    m l^2 theta'' + m g l sin(theta) = 0                        (6.80)  (= 6.20)

Three ways to model it with library components, chosen by ``rod``:

``"constraint"`` (default, the book's construction)
    The bob rides on a radial ``Prismatic`` (coordinate ``r``, start ``Guess(l)``) on the
    hinge ``Revolute`` (coordinate ``theta``): the unconstrained (r, theta) system of
    Fig. 6.7. The constraint ``r = l`` is a kinematic loop: a massless rod of length ``l``
    on its own world hinge, joined to the bob by a ``Spherical`` pin. mbcomp cuts the pin
    and keeps its position constraints with Lagrange multipliers; resolved in the rod's
    frame, the multiplier of the row along the rod is the rod force: ``lambda.pin.y`` is
    ``-lambda`` of (6.79) (the constraint force on the bob is ``-C^T lambda``, and the row's
    direction ``+y_rod`` points from the bob to the hinge).
``"prescribed"``
    The same (r, theta) system with ``r = l`` imposed by a ``PrescribedMotion`` on the radial
    slider: the rheonomic constraint with its multiplier eliminated; the drive force along
    ``+r`` (outward) is ``drive.f = -lambda``.
``"rigid"``
    The plain pendulum (``Revolute`` + ``FixedTranslation`` + ``PointMass``): ``r`` is not
    a coordinate at all; the tension is the hinge reaction ``hinge.f.y`` (the force on the
    hinge's frame_b along ``+y_b``, which points from the bob to the hinge).

Gravity along world ``-y``; ``theta`` from the downward vertical, counter-clockwise about ``z``.

Run: ``mbcomp simulate models/textbook/ex6_5_pendulum.py``
"""
from mbcomp import Guess, Model
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Prismatic, Revolute, Spherical, World

SIMULATION = dict(t_end=3.0, rtol=1e-10, atol=1e-12)
RODS = ("constraint", "prescribed", "rigid")


def build(m=1.3, l=0.8, g=9.81, theta0=1.2, theta_dot0=0.0, rod="constraint"):
    """Pendulum of seed Example 6.5 with the rod as a constraint.

    Parameters
    ----------
    m : float
        Mass of the bob (kg), a particle.
    l : float
        Rod length (m).
    g : float
        Gravitational acceleration (m/s^2), along world ``-y``.
    theta0, theta_dot0 : float
        Start angle from the downward vertical (rad) and rate (rad/s).
    rod : {"constraint", "prescribed", "rigid"}
        How ``r = l`` is imposed (see the module docstring).

    Returns
    -------
    mbcomp.Model
        Aliases ``theta``, ``theta_dot`` (hinge ``hinge``), and ``r`` (radial slider
        ``radial``) unless ``rod == "rigid"``.
    """
    if rod not in RODS:
        raise ValueError(f"rod must be one of {RODS}, got {rod!r}")
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0, w0=theta_dot0))
    bob = mdl.add("bob", PointMass(m=m))
    mdl.connect(world.frame_b, hinge.frame_a)
    if rod == "rigid":
        link = mdl.add("rod", FixedTranslation(r=(0.0, -l, 0.0)))
        mdl.connect(hinge.frame_b, link.frame_a)
        mdl.connect(link.frame_b, bob.frame_a)
    else:
        # the unconstrained (r, theta) system of Fig. 6.7: r along -y of the hinge frame
        radial = mdl.add("radial", Prismatic(n=(0, -1, 0), s0=Guess(l), v0=Guess(0.0)))
        mdl.connect(hinge.frame_b, radial.frame_a)
        mdl.connect(radial.frame_b, bob.frame_a)
        mdl.alias("r", "radial.s")
        if rod == "prescribed":
            drive = mdl.add("drive", PrescribedMotion(s=l))
            mdl.connect(drive.flange_b, radial.axis)
        else:
            rod_hinge = mdl.add("rod_hinge", Revolute(n=(0, 0, 1), phi0=Guess(theta0), w0=Guess(theta_dot0)))
            link = mdl.add("rod", FixedTranslation(r=(0.0, -l, 0.0)))
            pin = mdl.add("pin", Spherical())
            mdl.connect(world.frame_b, rod_hinge.frame_a)
            mdl.connect(rod_hinge.frame_b, link.frame_a)
            mdl.connect(link.frame_b, pin.frame_a)
            mdl.connect(bob.frame_a, pin.frame_b)
    mdl.alias("theta", "hinge.phi")
    mdl.alias("theta_dot", "hinge.w")
    return mdl
