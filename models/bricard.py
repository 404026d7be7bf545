"""Bricard's orthogonal linkage: five 1 m links and the ground closed by six revolute joints.

A classic test of redundant constraints (the IFToMM benchmark problem "Bricard's
mechanism"). The joint points and axes (world frame, at the start)::

    joint1 (0, 0, 0)  y        joint4 (1, -1, 1)  y
    joint2 (1, 0, 0)  z        joint5 (0, -1, 1)  z
    joint3 (1, -1, 0) x        joint6 (0, 0, 1)   x

Consecutive joints are 1 m apart and their axes perpendicular; the ground is the sixth link,
from joint6 to joint1. Counting (Grübler-Kutzbach: 6 x 5 links - 5 x 6 joints) gives zero
degrees of freedom, but the linkage moves with one: one of the loop's six closure equations
is redundant at every position. The links are uniform slender rods of mass ``m`` (kg);
gravity ``g`` along world -y; released from rest (the start is a position of the loop:
every joint angle 0).

Modelled as the open chain world - joint1 - link1 - ... - link5 - joint6 - ground point; the
assembler cuts one joint to close the loop (``mbcomp info`` names it and the dropped row).

Run::

    mbcomp simulate models/bricard.py --out bricard.csv
    mbcomp info models/bricard.py

Examples
--------
>>> import mbcomp
>>> s = mbcomp.assemble(build())
>>> s.nq, len(s.constraint_names(all_rows=True))   # five tree hinges; the cut one's five rows
(5, 5)
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import Cylindrical, Fixed, FixedTranslation, Revolute, RigidBody, World

SIMULATION = dict(t_end=10.0, rtol=1e-8, atol=1e-10)

#: joint points (m) and axes, world frame, at the start
POINTS = np.array([(0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1)], float)
AXES = np.array([(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)], float)


def rod_inertia(m, d):
    """Inertia (kg m^2) about its centre of a slender uniform rod of mass ``m`` along the
    vector ``d`` (m; its length is |d|), in the frame ``d`` is written in."""
    L = np.linalg.norm(d)
    e = np.asarray(d, float) / L
    return m * L ** 2 / 12.0 * (np.eye(3) - np.outer(e, e)) + 1e-9 * np.outer(e, e)


def build(m=1.0, g=9.81, cylindrical=0):
    """Bricard's linkage with links of mass ``m`` (kg) under gravity ``g`` (m/s^2, along -y).

    ``cylindrical`` (1-6): that joint is a cylindrical one instead (it may also slide along its
    axis). The sliding stays zero -- the linkage moves as before -- but no closure row is
    redundant any more: the same motion without a choice of rows (a cross-check)."""
    if cylindrical not in range(7):
        raise ValueError(f"cylindrical={cylindrical!r}: give the number of a joint (1-6), or 0 for none")
    model = Model()
    world = model.add("world", World(g=(0.0, -float(g), 0.0)))
    ground6 = model.add("ground6", Fixed(r=tuple(POINTS[5])))
    prev = world.frame_b
    for k in range(6):
        kind = Cylindrical if cylindrical == k + 1 else Revolute
        joint = model.add(f"joint{k + 1}", kind(n=tuple(AXES[k])))
        model.connect(prev, joint.frame_a)
        if k == 5:
            model.connect(joint.frame_b, ground6.frame_b)
            break
        d = POINTS[k + 1] - POINTS[k]  # every frame is parallel to the world's at the start
        link = model.add(f"link{k + 1}", RigidBody(m=m, r_cm=tuple(d / 2), I=rod_inertia(m, d)))
        tip = model.add(f"tip{k + 1}", FixedTranslation(r=tuple(d)))
        model.connect(joint.frame_b, link.frame_a)
        model.connect(joint.frame_b, tip.frame_a)
        prev = tip.frame_b
    return model
