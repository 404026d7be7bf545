"""Seed Example 3.3 (section 3.3, Fig. 3.5): stability of a spinning rectangular plate.

The book takes the principal axes 1, 2, 3 of a free plate (no moments), a steady spin
``w0`` about axis 1 and small perturbations ``eta_i``: ``w1 = w0 + eta1``, ``w2 = eta2``,
``w3 = eta3`` (3.38). Euler's equations (3.37) linearize to

- (3.39) ``I1 eta1' = 0``, ``I2 eta2' + (I1 - I3) w0 eta3 = 0``, ``I3 eta3' + (I2 - I1) w0 eta2 = 0``,
- (3.44) ``lambda^2 = (I1 - I3)(I2 - I1) w0^2 / (I2 I3)``,

so the spin is (marginally) stable, an oscillation of angular frequency
``sqrt(-lambda^2)``, when ``I1`` is the largest or the smallest moment, and unstable, with
the perturbation growing like ``exp(lambda t)``, when ``I1`` is the intermediate moment
(the "tennis racket" effect). Axes (1, 2, 3) must be a right-handed cyclic order of the
principal axes; (3.44) is symmetric in 2 and 3 anyway.

What is modelled: a plate ``a x b x h`` (edges along its own x, y, z; ``a > b > h`` makes
``Ix < Iy < Iz``: x the smallest, y the intermediate, z the largest moment), built with
:func:`mbcomp.inertia.box`, on a :class:`~mbcomp.library.FreeMotion` joint from the world
origin, without gravity (``World(g=(0, 0, 0))``). It starts at the origin, at rest in
translation, axes aligned with the world, with angular velocity (plate axes)
``w0 e_spin + eps w0 (e_other1 + e_other2)``. Nothing about Euler's equations is written in
the model: they come out of the body's inertia.

Outputs (aliases): ``omega_x``, ``omega_y``, ``omega_z`` = ``free.w.*``, the angular velocity
in plate axes (rad/s) -- the book's ``w1, w2, w3`` in the order of the chosen spin axis.

Run: ``mbcomp simulate models/textbook/ex3_3_spinning_plate.py -p axis=intermediate --out x.csv``
"""
import numpy as np

from mbcomp import Model
from mbcomp.inertia import box
from mbcomp.library import FreeMotion, RigidBody, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12)

AXES = {"smallest": 0, "intermediate": 1, "largest": 2, "x": 0, "y": 1, "z": 2}


def plate_part(m=1.0, a=0.3, b=0.2, h=0.01):
    """Mass properties of the plate in its own frame (centre at the origin, edges along x, y, z).

    Parameters
    ----------
    m : float
        Mass, kg.
    a, b, h : float
        Edge lengths along x, y, z, m.
    """
    return box(m, a, b, h)


def spin_axes(axis):
    """The book's cyclic axes (1, 2, 3) as plate-axis indices for spin axis ``axis``.

    ``axis`` is ``"smallest"``, ``"intermediate"``, ``"largest"`` (moments of the default
    plate, ``a > b > h``) or ``"x"``, ``"y"``, ``"z"``.
    """
    if axis not in AXES:
        raise ValueError(f"axis {axis!r} is not one of {', '.join(AXES)} -> fix: choose the spin axis by "
                         f"name ('smallest', 'intermediate', 'largest') or plate axis ('x', 'y', 'z')")
    k = AXES[axis]
    return k, (k + 1) % 3, (k + 2) % 3


def start_rate(axis="intermediate", omega0=10.0, eps=1e-3):
    """Start angular velocity in plate axes (rad/s): ``w0`` about the spin axis plus
    ``eps w0`` about each of the two other axes."""
    i1, i2, i3 = spin_axes(axis)
    w = np.zeros(3)
    w[i1], w[i2], w[i3] = omega0, eps * omega0, eps * omega0
    return w


def build(axis="intermediate", omega0=10.0, eps=1e-3, m=1.0, a=0.3, b=0.2, h=0.01):
    """A free rectangular plate spun about one principal axis with a small perturbation.

    Parameters
    ----------
    axis : str
        Spin axis: ``"smallest"``, ``"intermediate"``, ``"largest"``, or ``"x"``, ``"y"``, ``"z"``.
    omega0 : float
        Spin rate, rad/s.
    eps : float
        Relative perturbation: ``eps * omega0`` rad/s about each of the other two axes.
    m : float
        Plate mass, kg.
    a, b, h : float
        Edge lengths along the plate's x, y, z, m (``a > b > h`` for the axis names above).
    """
    w0 = start_rate(axis, omega0, eps)
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, 0.0)))
    free = mdl.add("free", FreeMotion(r0=(0.0, 0.0, 0.0), R0=np.eye(3), v0=(0.0, 0.0, 0.0), w0=w0))
    plate = mdl.add("plate", RigidBody.from_mass_properties(plate_part(m, a, b, h)))
    mdl.connect(world.frame_b, free.frame_a)
    mdl.connect(free.frame_b, plate.frame_a)
    for c in "xyz":
        mdl.alias(f"omega_{c}", f"free.w.{c}")
    return mdl
