"""A thin uniform disk rolling without slip on level ground, in coordinates where steady rolling is an equilibrium.

Why this model exists
---------------------
The library's :class:`~mbcomp.library.RollingDisk` carries the wheel on a ``FreeMotion``
whose orientation is a quaternion. A steadily rolling wheel spins, so its quaternion keeps
changing and the dynamics depend on it: upright rolling is not an equilibrium of those
coordinates, and :func:`mbcomp.linearize` rightly refuses it ("not a steady motion in these
coordinates"). Here the same six motions are written as a chain of one-axis joints whose
angles and positions the dynamics do not depend on when the disk rolls steadily:

    world -> x (Prismatic along x) -> y (Prismatic along y) -> z (Prismatic along z)
          -> heading (Revolute about z: rolling direction psi)
          -> lean (Revolute about x: the heading frame's rolling direction, angle phi)
          -> spin (Revolute about y: the disk's axle, angle theta)
          -> disk (RigidBody, I = diag(m r^2/4, m r^2/2, m r^2/4), axle = body y)

plus ``contact``, a :class:`~mbcomp.library.DiskContact` (``r``, plane normal ``z``, axle
``y``) between the world and the disk's centre: one holonomic row (the rim touches the
ground, which determines ``z``) and two nonholonomic rows (no slip). The intermediate frames
are massless; the chain gives the disk body all six motions. In upright straight rolling at
spin rate ``W`` the position ``x`` and the spin angle ``theta`` move at constant rates and are
cyclic (the disk is axisymmetric, the ground uniform), ``y`` and ``heading`` are at rest and
ignorable, so the motion is an equilibrium of the remaining states. (A steady *turn* is not:
the translation speeds ``x.v``, ``y.v`` are world components of the centre's velocity, which
turn with the heading.)

Positive lean ``phi`` rotates the disk about the rolling direction ``x_H``: the centre moves
to ``-y_H`` (it sits at ``r (0, -sin phi, cos phi)`` from the contact point, heading axes).
The disk's angular velocity is ``psi' z + phi' x_H + theta' y_L`` and its axial component
``Omega = theta' + psi' sin(phi)``.

Known result
------------
With ``I_a = m r^2/2`` (axial), ``I_d = m r^2/4`` (diametral), Newton-Euler about the centre
in the lean frame, linearized about ``phi = phi' = psi' = 0``, ``Omega = W``:

    (I_d + m r^2) phi'' - (I_a + m r^2) W psi' - m g r phi = 0     (lean)
    I_d psi'' + I_a W phi' = 0                                     (heading)
    Omega' = 0                                                     (spin)

The heading equation integrates to the conserved combination ``I_d psi' + I_a W phi = c``;
with ``c = 0`` (upright straight start) the lean equation becomes

    (I_d + m r^2) phi'' + [(I_a + m r^2) I_a W^2 / I_d - m g r] phi = 0,

``J phi'' + K phi = 0``. Upright rolling is (marginally) stable iff ``K > 0``, i.e. for the
thin disk iff ``W^2 > g / (3 r)`` (``W > 3.3015 rad/s`` for ``r = 0.3 m``); the mass drops
out. The linearization in the states ``(lean.phi, heading.w, lean.w)`` has the roots ``0`` (a
neighbouring steady turn; the conserved combination above) and ``+-sqrt(-K/J)``; ``y``,
``heading.phi`` and ``spin.w`` influence nothing and are removed.

Run::

    mbcomp stability models/rolling_disk.py --sweep spin=1:5:9 --plot disk_sweep.png
    mbcomp stability models/rolling_disk.py -p spin=2
    mbcomp simulate models/rolling_disk.py -p spin=6 -p lean_rate0=0.05
"""
import numpy as np

from mbcomp import Guess, Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import DiskContact, Prismatic, Revolute, RigidBody, World

SIMULATION = dict(t_end=5.0, rtol=1e-9, atol=1e-11)

_E = np.eye(3)


def build(r=0.3, m=2.0, g=9.81, spin=6.0, lean0=0.0, lean_rate0=0.0, heading0=0.0, heading_rate0=0.0,
          x0=0.0, y0=0.0):
    """Thin uniform disk rolling on the ground (``z = 0``), gravity ``-g z``.

    Parameters
    ----------
    r : float
        Radius (m).
    m : float
        Mass (kg); inertia about the centre ``diag(m r^2/4, m r^2/2, m r^2/4)`` (axle = y).
    g : float
        Gravitational acceleration (m/s^2), along world ``-z``.
    spin : float
        Start spin rate ``theta'`` (rad/s) of the disk relative to the lean frame; upright it is
        the rolling rate: the centre moves forward at ``r spin``.
    lean0, lean_rate0 : float
        Start lean ``phi`` (rad, 0 upright) and lean rate (rad/s).
    heading0, heading_rate0 : float
        Start heading ``psi`` (rad, rolling direction from world x about z) and its rate (rad/s).
    x0, y0 : float
        Start contact point (m).

    Every start value is set: the angles and angular rates are fixed; the centre's position
    and velocity are those of rolling without slip (``z = r cos(lean0)``, centre velocity
    ``w x (c - P)``), given as :class:`~mbcomp.Guess` so initialization solves them from the
    contact rows.

    Returns
    -------
    mbcomp.Model
    """
    RH = rot_axis(_E[2], heading0)
    RL = RH @ rot_axis(_E[0], lean0)
    rc = r * RL[:, 2]  # centre relative to the contact point
    c0 = np.array([x0, y0, 0.0]) + rc
    w = heading_rate0 * _E[2] + lean_rate0 * RH[:, 0] + spin * RL[:, 1]  # world angular velocity
    vc = np.cross(w, rc)  # rolling: the contact point is at rest

    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    jx = mdl.add("x", Prismatic(n=(1, 0, 0), s0=Guess(float(c0[0])), v0=Guess(float(vc[0]))))
    jy = mdl.add("y", Prismatic(n=(0, 1, 0), s0=Guess(float(c0[1])), v0=Guess(float(vc[1]))))
    jz = mdl.add("z", Prismatic(n=(0, 0, 1), s0=Guess(float(c0[2])), v0=Guess(float(vc[2]))))
    heading = mdl.add("heading", Revolute(n=(0, 0, 1), phi0=float(heading0), w0=float(heading_rate0)))
    lean = mdl.add("lean", Revolute(n=(1, 0, 0), phi0=float(lean0), w0=float(lean_rate0)))
    spin_j = mdl.add("spin", Revolute(n=(0, 1, 0), phi0=0.0, w0=float(spin)))
    disk = mdl.add("disk", RigidBody(m=m, I=np.diag([0.25, 0.5, 0.25]) * m * r * r))
    contact = mdl.add("contact", DiskContact(r=r, n=(0, 0, 1), axis=(0, 1, 0)))
    mdl.connect(world.frame_b, jx.frame_a)
    mdl.connect(jx.frame_b, jy.frame_a)
    mdl.connect(jy.frame_b, jz.frame_a)
    mdl.connect(jz.frame_b, heading.frame_a)
    mdl.connect(heading.frame_b, lean.frame_a)
    mdl.connect(lean.frame_b, spin_j.frame_a)
    mdl.connect(spin_j.frame_b, disk.frame_a)
    mdl.connect(world.frame_b, contact.frame_a)
    mdl.connect(contact.frame_b, disk.frame_a)
    return mdl
