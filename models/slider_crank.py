"""Planar slider-crank: a closed kinematic loop (crank, connecting rod, slider).

The crank turns about the world z axis at the origin, the rod is hinged to the crank's tip,
the slider moves along the world x axis and is hinged to the rod's other end. Gravity acts
along -y. No damping: the total energy is conserved. One degree of freedom; the loop is
closed by a cut revolute joint whose three out-of-plane rows are redundant and dropped.

Run: ``mbcomp simulate models/slider_crank.py --out x.csv``
"""
import numpy as np

from mbcomp import Guess, Model
from mbcomp.library import FixedTranslation, Prismatic, Revolute, RigidBody, World

SIMULATION = dict(t_end=10.0, rtol=1e-8, atol=1e-10)


def rod_inertia(m, L):
    """Inertia (kg m^2) of a slender rod of mass m along x about its centre, frame axes."""
    Iz = m * L ** 2 / 12.0
    return np.diag([1e-6 * Iz, Iz, Iz])


def build(crank_length=0.2, rod_length=0.6, m_crank=1.0, m_rod=2.0, m_slider=0.5, phi0=0.3, w0=6.0,
          inertia=rod_inertia):
    """Slider-crank with crank angle ``phi0`` (rad) and rate ``w0`` (rad/s) fixed at the start;
    ``inertia(m, L)`` gives each link's inertia (kg m^2, frame axes, default :func:`rod_inertia`)."""
    m = Model()
    world = m.add("world", World(g=(0.0, -9.81, 0.0)))
    crank_joint = m.add("crank_joint", Revolute(n=(0, 0, 1), phi0=phi0, w0=w0))
    crank = m.add("crank", RigidBody(m=m_crank, r_cm=(crank_length / 2, 0, 0), I=inertia(m_crank, crank_length)))
    crank_tip = m.add("crank_tip", FixedTranslation(r=(crank_length, 0, 0)))
    rod_joint = m.add("rod_joint", Revolute(n=(0, 0, 1), phi0=Guess(-0.1)))
    rod = m.add("rod", RigidBody(m=m_rod, r_cm=(rod_length / 2, 0, 0), I=inertia(m_rod, rod_length)))
    rod_tip = m.add("rod_tip", FixedTranslation(r=(rod_length, 0, 0)))
    slider_joint = m.add("slider_joint", Prismatic(n=(1, 0, 0), s0=Guess(crank_length + rod_length)))
    slider = m.add("slider", RigidBody(m=m_slider))
    pin = m.add("pin", Revolute(n=(0, 0, 1)))

    m.connect(world.frame_b, crank_joint.frame_a)
    m.connect(crank_joint.frame_b, crank.frame_a)
    m.connect(crank_joint.frame_b, crank_tip.frame_a)
    m.connect(crank_tip.frame_b, rod_joint.frame_a)
    m.connect(rod_joint.frame_b, rod.frame_a)
    m.connect(rod_joint.frame_b, rod_tip.frame_a)
    m.connect(world.frame_b, slider_joint.frame_a)
    m.connect(slider_joint.frame_b, slider.frame_a)
    m.connect(rod_tip.frame_b, pin.frame_a)
    m.connect(slider_joint.frame_b, pin.frame_b)
    m.alias("crank_angle", "crank_joint.phi")
    m.alias("slider_position", "slider_joint.s")
    return m
