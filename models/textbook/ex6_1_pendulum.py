"""Seed Example 6.1 (Lagrange's equation): the simple pendulum of Fig. 6.2.

A particle of mass ``m`` on a massless rod of length ``l`` swings about a horizontal hinge;
``theta`` is measured from the downward vertical. The book's energies and equation are

    T = (1/2) m l^2 theta'^2                                   (6.17)
    V = -m g l cos(theta)       (datum at the hinge level)     (6.18)
    m l^2 theta'' + m g l sin(theta) = 0                        (6.20)

What is modelled (library components only): a ``Revolute`` about world ``z`` at the world
origin (the hinge), a ``FixedTranslation`` ``(0, -l, 0)`` (the massless rod, pointing down at
``theta = 0``) and a ``PointMass``. Gravity acts along ``-y``; the revolute angle is the
book's ``theta`` (positive counter-clockwise about ``z``). mbcomp's potential energy has its
datum at the world origin, i.e. at the hinge level as in (6.18).

Run: ``mbcomp simulate models/textbook/ex6_1_pendulum.py --plot pendulum.png``
"""
from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

SIMULATION = dict(t_end=4.0, rtol=1e-10, atol=1e-12)


def build(m=1.0, l=0.8, g=9.81, theta0=1.2, theta_dot0=0.0):
    """Simple pendulum of seed Example 6.1.

    Parameters
    ----------
    m : float
        Mass of the bob (kg), a particle.
    l : float
        Rod length (m), massless rod.
    g : float
        Gravitational acceleration (m/s^2), along world ``-y``.
    theta0, theta_dot0 : float
        Start angle from the downward vertical (rad) and start rate (rad/s).

    Returns
    -------
    mbcomp.Model
        Aliases ``theta``, ``theta_dot`` (the hinge angle and rate).
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0, w0=theta_dot0))
    rod = mdl.add("rod", FixedTranslation(r=(0.0, -l, 0.0)))
    bob = mdl.add("bob", PointMass(m=m))
    mdl.connect(world.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, bob.frame_a)
    mdl.alias("theta", "hinge.phi")
    mdl.alias("theta_dot", "hinge.w")
    return mdl
