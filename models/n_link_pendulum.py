"""Planar N-link pendulum: N uniform rods in a chain of hinges (the scaling benchmark).

Link ``k`` (``k = 1..N``) is a uniform slender rod of mass ``m`` and length ``L`` hanging along
its frame's ``-y`` axis from the hinge ``joint<k>`` (a ``Revolute`` about ``z``); the hinge of
link ``k+1`` sits at the lower end of link ``k`` (a massless ``FixedTranslation`` ``(0, -L,
0)``). Gravity acts along world ``-y``, so the chain swings in the world ``x-y`` plane. The
joint angles are *relative*: the absolute angle of link ``k`` from the downward vertical is
``phi_1 + ... + phi_k``. No friction: the total energy is conserved. ``N`` is a build
parameter, so one file gives every size of the benchmark (``bench/scaling.py``).

Run: ``mbcomp simulate models/n_link_pendulum.py --out chain.csv``

Examples
--------
>>> import mbcomp
>>> s = mbcomp.assemble(build(N=3))
>>> s.nq, s.nu
(3, 3)
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import FixedTranslation, Revolute, RigidBody, World

SIMULATION = dict(t_end=3.0, rtol=1e-8, atol=1e-10)


def rod_inertia(m, L):
    """Inertia (kg m^2) about the centre of a slender rod of mass ``m`` (kg) and length ``L`` (m)
    lying along its frame's y axis (zero about the rod's own axis)."""
    It = m * L ** 2 / 12.0
    return np.diag([It, 0.0, It])


def build(N=5, L=0.5, m=1.0, g=9.81, phi0=0.3, w0=0.0):
    """Planar chain of ``N`` uniform rods on hinges about world ``z``.

    Parameters
    ----------
    N : int
        Number of links (>= 1).
    L : float
        Length of every link (m).
    m : float
        Mass of every link (kg), a uniform slender rod (inertia ``m L^2 / 12`` about its centre).
    g : float
        Gravitational acceleration (m/s^2), along world ``-y``.
    phi0 : float or sequence of N floats
        Start angle of every hinge relative to the link above (rad); a number gives every hinge
        the same angle (a curled chain).
    w0 : float or sequence of N floats
        Start relative angular rates (rad/s).

    Returns
    -------
    mbcomp.Model
        Components ``joint1..jointN`` (hinges), ``link1..linkN`` (rods), ``tip1..tip<N-1>``
        (hinge offsets); aliases ``phi<k>`` for the joint angles.
    """
    N = int(N)
    if N < 1:
        raise ValueError(f"N = {N}: the pendulum needs at least one link -> give N >= 1")
    phis = np.broadcast_to(np.asarray(phi0, float), (N,))
    ws = np.broadcast_to(np.asarray(w0, float), (N,))
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    prev = world.frame_b
    for k in range(1, N + 1):
        joint = mdl.add(f"joint{k}", Revolute(n=(0, 0, 1), phi0=float(phis[k - 1]), w0=float(ws[k - 1])))
        link = mdl.add(f"link{k}", RigidBody(m=m, r_cm=(0.0, -L / 2, 0.0), I=rod_inertia(m, L)))
        mdl.connect(prev, joint.frame_a)
        mdl.connect(joint.frame_b, link.frame_a)
        if k < N:
            tip = mdl.add(f"tip{k}", FixedTranslation(r=(0.0, -L, 0.0)))
            mdl.connect(joint.frame_b, tip.frame_a)
            prev = tip.frame_b
        mdl.alias(f"phi{k}", f"joint{k}.phi")
    return mdl
