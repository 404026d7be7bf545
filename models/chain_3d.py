"""Three-dimensional N-link chain on ball joints (the 3-D scaling benchmark).

Link ``k`` (``k = 1..N``) is a uniform solid cylinder of mass ``m``, length ``L`` and radius
``a`` hanging along its frame's ``-y`` axis from the ball joint ``joint<k>`` (a ``Spherical``
joint, quaternion coordinates, 3 DOF); the ball joint of link ``k+1`` sits at the lower end of
link ``k`` (a massless ``FixedTranslation`` ``(0, -L, 0)``). Gravity acts along world ``-y``.

A slight initial twist makes the motion genuinely three-dimensional: every joint starts
turned by ``tilt`` about an axis in the horizontal plane whose direction turns by 90 degrees
from joint to joint, and the top joint spins about the vertical with ``spin`` (rad/s). No
friction: the total energy and the vertical (``y``) component of the angular momentum about
the top pivot are conserved (gravity and the pivot force exert no torque about the vertical
axis through the pivot). ``N`` is a build parameter.

Run: ``mbcomp simulate models/chain_3d.py --out chain3d.csv``

Examples
--------
>>> import mbcomp
>>> s = mbcomp.assemble(build(N=2))
>>> s.nq, s.nu
(8, 6)
"""
import numpy as np

from mbcomp import Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import FixedTranslation, RigidBody, Spherical, World

SIMULATION = dict(t_end=2.0, rtol=1e-8, atol=1e-10)


def cylinder_inertia(m, L, a):
    """Inertia (kg m^2) about the centre of a solid cylinder of mass ``m`` (kg), length ``L`` (m)
    and radius ``a`` (m) whose axis is its frame's y axis."""
    It = m * (3.0 * a ** 2 + L ** 2) / 12.0
    return np.diag([It, 0.5 * m * a ** 2, It])


def build(N=4, L=0.5, m=1.0, a=0.02, g=9.81, tilt=0.2, spin=1.5):
    """Chain of ``N`` cylinders on ball joints, slightly twisted out of a plane.

    Parameters
    ----------
    N : int
        Number of links (>= 1).
    L, a : float
        Length and radius of every link (m).
    m : float
        Mass of every link (kg).
    g : float
        Gravitational acceleration (m/s^2), along world ``-y``.
    tilt : float
        Start rotation of every joint (rad) about a horizontal axis of its frame_a: the x axis
        for odd ``k``, the z axis for even ``k``.
    spin : float
        Start angular rate of the top joint about the vertical (rad/s, frame_b axes ~ y).

    Returns
    -------
    mbcomp.Model
        Components ``joint1..jointN`` (ball joints), ``link1..linkN`` (cylinders),
        ``tip1..tip<N-1>`` (joint offsets).
    """
    N = int(N)
    if N < 1:
        raise ValueError(f"N = {N}: the chain needs at least one link -> give N >= 1")
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    prev = world.frame_b
    for k in range(1, N + 1):
        axis = (1.0, 0.0, 0.0) if k % 2 else (0.0, 0.0, 1.0)
        w0 = (0.0, spin, 0.0) if k == 1 else (0.0, 0.0, 0.0)
        joint = mdl.add(f"joint{k}", Spherical(R0=rot_axis(axis, tilt), w0=w0))
        link = mdl.add(f"link{k}", RigidBody(m=m, r_cm=(0.0, -L / 2, 0.0), I=cylinder_inertia(m, L, a)))
        mdl.connect(prev, joint.frame_a)
        mdl.connect(joint.frame_b, link.frame_a)
        if k < N:
            tip = mdl.add(f"tip{k}", FixedTranslation(r=(0.0, -L, 0.0)))
            mdl.connect(joint.frame_b, tip.frame_a)
            prev = tip.frame_b
    return mdl
