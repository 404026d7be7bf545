"""Seed Example 1.5: a box hinged at a corner falls over, with torsional damping at the hinge.

The book (Figs. 1.22-1.25, eqs. 1.61-1.62, program of Fig. 1.24): a homogeneous box of width
``a`` and height ``b`` (a planar problem) is hinged at its lower-left corner ``O``. Its
centre of mass lies at ``L = sqrt(a^2 + b^2) / 2`` from ``O``, at the angle
``phi0 = atan(a / b)`` from the upward vertical; the box turns clockwise by ``theta``. The
law of angular momentum about ``O`` gives

- (1.61) ``m g L sin(theta + phi0) - C theta' = Io theta''``,
- (1.62) state form ``x1' = x2``, ``x2' = e sin(x1 + phi0) - c x2`` with ``e = m g L / Io``,
  ``c = C / Io``,

where ``Io`` is the moment of inertia about the hinge ``O``. The book's program (m=1 kg,
a=0.1 m, b=0.2 m, C=0.001 N m s/rad, theta(0)=0, theta'(0)=0, 200 steps of 1 ms) sets
``I = m (a^2 + b^2) / 12``: the **centroidal** moment. About the corner it is
``Io = m (a^2 + b^2) / 12 + m L^2 = m (a^2 + b^2) / 3``, four times larger, so the book's
program lets the box fall twice as fast (exactly so without damping, theta_book(t) =
theta(2 t)). Finding verified in ``tests/test_textbook_ex1_5.py``.

What is modelled (the physics, not the program): a :class:`~mbcomp.library.Revolute` hinge
at the world origin whose axis is ``-z``, so that its angle ``phi`` is the book's clockwise
``theta``; a :class:`~mbcomp.library.RotationalDamper` (coefficient ``C``) between the
hinge's support and axis flanges; and a :class:`~mbcomp.library.RigidBody` built with
:mod:`mbcomp.inertia` from a box ``a x b x depth`` whose centre sits at ``(a/2, b/2, 0)`` in
the hinge frame (box edges along x and y, the corner at the hinge). Gravity acts along -y.
The inertia about the hinge follows from the parallel-axis shift, nothing is typed by hand.

Outputs (aliases, the book's names): ``theta`` = ``hinge.phi`` (rad, clockwise from the
start pose), ``omega`` = ``hinge.w`` (rad/s).

Run: ``mbcomp simulate models/textbook/ex1_5_falling_box.py --out ex1_5.csv``
(the book's program covers only t = 0 ... 0.2 s; the default here shows a few swings).
"""
import numpy as np

from mbcomp import Model
from mbcomp.inertia import box
from mbcomp.library import Revolute, RigidBody, RotationalDamper, World

SIMULATION = dict(t_end=3.0, rtol=1e-10, atol=1e-12)


def box_part(m=1.0, a=0.1, b=0.2, depth=0.05):
    """Mass properties of the box in the hinge frame: corner at the origin, edges along x, y, z.

    Parameters
    ----------
    m : float
        Mass, kg.
    a, b : float
        Width (along x) and height (along y), m.
    depth : float
        Thickness along z (the hinge axis), m; it does not enter the planar motion.

    Returns
    -------
    mbcomp.inertia.MassProperties
        Centre of mass ``(a/2, b/2, 0)`` m, inertia about it, hinge-frame axes.
    """
    return box(m, a, b, depth).placed(r=(a / 2, b / 2, 0.0))


def build(m=1.0, a=0.1, b=0.2, C=0.001, g=9.81, theta0=0.0, omega0=0.0, depth=0.05):
    """The hinged falling box of Example 1.5 (book values by default).

    Parameters
    ----------
    m : float
        Box mass, kg.
    a, b : float
        Box width and height, m.
    C : float
        Torsional damping coefficient at the hinge, N m s/rad.
    g : float
        Gravity, m/s^2 (acts along -y).
    theta0, omega0 : float
        Start angle (rad, clockwise) and rate (rad/s), both fixed.
    depth : float
        Box thickness along the hinge axis, m (no effect on the motion).
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    # axis -z: a positive angle turns the box clockwise in the x-y plane, as the book's theta
    hinge = mdl.add("hinge", Revolute(n=(0, 0, -1), phi0=theta0, w0=omega0))
    damper = mdl.add("damper", RotationalDamper(d=C))
    body = mdl.add("box", RigidBody.from_mass_properties(box_part(m, a, b, depth)))
    mdl.connect(world.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, body.frame_a)
    mdl.connect(hinge.support, damper.flange_a)
    mdl.connect(hinge.axis, damper.flange_b)
    mdl.alias("theta", "hinge.phi")
    mdl.alias("omega", "hinge.w")
    return mdl


def phi0(a=0.1, b=0.2):
    """Angle (rad) between the upward vertical and the hinge -> centre-of-mass line at theta = 0."""
    return float(np.arctan2(a, b))
