"""Spatial slider-crank: a closed loop with a spherical and a universal joint (after
Modelica's ``SpatialSliderCrank``).

Geometry (world axes, m)::

    crank      Revolute about the world x axis at the origin; its tip at (c, a, 0) in the crank
               frame, so P_crank(phi) = (c, a cos(phi), a sin(phi))
    rod        length L, Spherical at the crank tip, Universal at the slider (hinge n_a = z of
               the slider frame, then n_b = y of the rod frame; the rod lies along its x axis)
    slider     Prismatic along the world x axis through (0, h_y, h_z):
               P_slider(s) = (s, h_y, h_z)

The loop closes by the rod length, ``|P_crank(phi) - P_slider(s)| = L``, so with the slider
ahead of the crank ``s = c + sqrt(L^2 - (a cos(phi) - h_y)^2 - (a sin(phi) - h_z)^2)``. The
universal joint keeps the rod from spinning about its own axis (two spherical joints would
leave that spin free). Seven joint coordinates, six loop rows: one degree of freedom.
Gravity acts along -z; no damping, so the total energy is conserved. The start values the
loop needs (slider position, rod orientation) are computed here from the crank angle and
handed over as ``Guess`` values.

Run: ``mbcomp simulate models/spatial_slider_crank.py --out x.csv``
"""
import numpy as np

from mbcomp import Guess, Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import (FixedTranslation, Prismatic, Revolute, RigidBody, Spherical, Universal,
                            World)

SIMULATION = dict(t_end=2.0, rtol=1e-9, atol=1e-11, stabilization="projection")


def rod_inertia(m, L, radius=0.01):
    """Inertia (kg m^2) of a uniform rod of mass m along x about its centre, frame axes."""
    I = m * L ** 2 / 12.0
    return np.diag([m * radius ** 2 / 2, I, I])


def slider_position(phi, crank_length=0.1, crank_offset=0.05, rod_length=0.5, h_y=0.1, h_z=0.05):
    """The slider coordinate s (m) at crank angle phi (rad), slider ahead of the crank."""
    dy, dz = crank_length * np.cos(phi) - h_y, crank_length * np.sin(phi) - h_z
    return crank_offset + np.sqrt(rod_length ** 2 - dy ** 2 - dz ** 2)


def _rod_start(phi, s, crank_length, crank_offset, h_y, h_z):
    """Universal angles (phi_a, phi_b) and the Spherical's relative orientation (crank frame ->
    rod frame) that point the rod's x axis from the slider at s to the crank tip at phi."""
    tip = np.array([crank_offset, crank_length * np.cos(phi), crank_length * np.sin(phi)])
    d = tip - np.array([s, h_y, h_z])
    d /= np.linalg.norm(d)
    phi_a, phi_b = np.arctan2(d[1], d[0]), -np.arcsin(d[2])   # d = rot(z, phi_a) rot(y, phi_b) x
    R_rod = rot_axis((0, 0, 1), phi_a) @ rot_axis((0, 1, 0), phi_b)
    return phi_a, phi_b, rot_axis((1, 0, 0), phi).T @ R_rod


def build(crank_length=0.1, crank_offset=0.05, rod_length=0.5, h_y=0.1, h_z=0.05,
          m_crank=1.0, m_rod=0.5, m_slider=0.8, phi0=0.0, w0=20.0, g=9.81):
    """Spatial slider-crank with the crank angle ``phi0`` (rad) and rate ``w0`` (rad/s) fixed
    at the start; lengths in m, masses in kg, gravity ``g`` (m/s^2) along -z."""
    if rod_length <= crank_length + np.hypot(h_y, h_z):
        raise ValueError(f"spatial_slider_crank: rod_length={rod_length!r} m is too short for the crank to turn "
                         f"-> fix: make it longer than crank_length + |(h_y, h_z)| = "
                         f"{crank_length + np.hypot(h_y, h_z):.4g} m")
    s0 = slider_position(phi0, crank_length, crank_offset, rod_length, h_y, h_z)
    ua0, ub0, R_ball = _rod_start(phi0, s0, crank_length, crank_offset, h_y, h_z)
    m = Model()
    world = m.add("world", World(g=(0.0, 0.0, -g)))
    crank_joint = m.add("crank_joint", Revolute(n=(1, 0, 0), phi0=phi0, w0=w0))
    crank = m.add("crank", RigidBody(m=m_crank, r_cm=(crank_offset / 2, crank_length / 2, 0),
                                     I=np.diag([1e-3, 1e-4, 1e-3])))
    crank_tip = m.add("crank_tip", FixedTranslation(r=(crank_offset, crank_length, 0)))
    ball = m.add("ball", Spherical(R0=Guess(R_ball)))
    rod = m.add("rod", RigidBody(m=m_rod, r_cm=(rod_length / 2, 0, 0), I=rod_inertia(m_rod, rod_length)))
    rod_end = m.add("rod_end", FixedTranslation(r=(rod_length, 0, 0)))
    rail = m.add("rail", FixedTranslation(r=(0.0, h_y, h_z)))
    slider_joint = m.add("slider_joint", Prismatic(n=(1, 0, 0), s0=Guess(s0)))
    slider = m.add("slider", RigidBody(m=m_slider, I=np.diag([1e-4, 1e-4, 1e-4])))
    cardan = m.add("cardan", Universal(n_a=(0, 0, 1), n_b=(0, 1, 0), phi_a0=Guess(ua0), phi_b0=Guess(ub0)))

    m.connect(world.frame_b, crank_joint.frame_a)
    m.connect(crank_joint.frame_b, crank.frame_a)
    m.connect(crank.frame_a, crank_tip.frame_a)
    m.connect(crank_tip.frame_b, ball.frame_a)
    m.connect(rod.frame_a, rod_end.frame_a)
    m.connect(rod_end.frame_b, ball.frame_b)
    m.connect(world.frame_b, rail.frame_a)
    m.connect(rail.frame_b, slider_joint.frame_a)
    m.connect(slider_joint.frame_b, slider.frame_a)
    m.connect(slider.frame_a, cardan.frame_a)
    m.connect(cardan.frame_b, rod.frame_a)
    m.alias("crank_angle", "crank_joint.phi")
    m.alias("slider_position", "slider_joint.s")
    return m
