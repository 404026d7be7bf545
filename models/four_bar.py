"""Planar four-bar linkage near its flat (change-point) position: where formulations fail.

Geometry (all in the world x-y plane, hinges about z, gravity ``-g`` along y, ``g=0`` for none)::

            C
           / \\            A = (0, 0)            crank pivot (world origin)
    coupler   rocker       D = (l1 - gap, 0)     rocker pivot (a Fixed ground frame)
         /     \\          B = A + l2 (cos phi, sin phi)   crank tip, phi = ``crank_angle``
        B       \\         |BC| = l3 (coupler), |CD| = l4 (rocker)
       /         \\
      A - - - - - D       ground link A-D

The nominal lengths satisfy the Grashof *change-point* condition ``l1 + l2 = l3 + l4`` (the
shortest plus the longest link equal the other two; by default ``l4`` is derived from it).
Then at crank angle ``phi = pi`` the crank points along -x, ``|BD| = l1 + l2 = l3 + l4``
and coupler and rocker lie stretched along the ground line: all four links are collinear.
This flat position is singular: the loop-closure Jacobian loses rank (the closure
equation along the links has a zero row, since every hinge moves the loop end
perpendicular to the line), the mechanism has momentarily two degrees of freedom, and the
two assembly modes (C above / below the line BD) meet there (a bifurcation). With the crank
strictly the shortest link it is the only flat position in a turn.

``gap`` (m, >= 0) shortens the ground link to ``l1 - gap``. For ``gap > 0`` the linkage is
a Grashof crank-rocker (``l2`` shortest, ``l1`` longest, ``s + l < p + q``): the crank turns
fully and the linkage never becomes flat. Its closest approach is at ``phi = pi``, where
``|BD|`` is largest, and there::

    l3 + l4 - |BD|_max = gap          (exactly; a clean, linear distance to the flat position)

equivalently the coupler-rocker angle at C misses 180 deg by
``delta = arccos(((l3+l4-gap)**2 - l3**2 - l4**2) / (2 l3 l4))`` (~ ``sqrt(2 gap (l3+l4)/(l3 l4))``).
Next to that position (exactly at it for ``gap = 0``) crank and coupler fold
(``|AC| = l3 - l2``): the rocker's limit position, largest rocker angle
``pi - arccos(((l1-gap)**2 + l4**2 - (l3-l2)**2) / (2 (l1-gap) l4))``. The rocker reverses
there, more abruptly the smaller the gap: with the defaults its peak angular acceleration is
~49/sqrt(gap) rad/s^2 and the loop-closure force (multiplier) ~4.6/gap N. ``gap = 0`` is
exactly the change-point linkage and passes through the singular position; ``gap < 0`` would
make ``|BD| = l3 + l4`` unreachable (the crank could not turn fully) and is refused.

The crank starts at ``phi0`` (fixed) with rate ``w0`` (fixed); coupler and rocker angles are
computed in the assembly mode ``branch`` (+1: C to the left of B->D, i.e. above the ground
line at the start; -1: mirrored) and handed to initialization as guesses. With the defaults
the crank passes ``phi = pi`` at t ~ 0.18 s and again every ~0.55 s (t ~ 0.73 s). Links are slender
uniform rods of mass ``rho * length``; no damping, so the total energy is conserved.

Modelled as one loop world - crank_joint - coupler_joint - pin (at C) - rocker_joint - pivot_d;
the assembler's spanning tree makes one of the four hinges the cut joint (``mbcomp info``
names it) and drops its three out-of-plane rows as redundant. Every hinge gets its
assembled angle as a ``Guess``, so initialization stays in the requested assembly mode.

Run::

    mbcomp simulate models/four_bar.py -p gap=1e-3 --out four_bar.csv --plot four_bar.png
    mbcomp simulate models/four_bar.py -p gap=1e-3 --formulation dalembert
    mbcomp info models/four_bar.py -p gap=0.01
"""
import numpy as np

from mbcomp import Guess, Model
from mbcomp.library import Fixed, FixedTranslation, Revolute, RigidBody, World

SIMULATION = dict(t_end=1.0, rtol=1e-8, atol=1e-10)


def rod_inertia(m, L):
    """Inertia (kg m^2) of a slender rod of mass m along x about its centre, frame axes."""
    Iz = m * L ** 2 / 12.0
    return np.diag([1e-6 * Iz, Iz, Iz])


def lengths(gap=1e-3, l1=1.0, l2=0.4, l3=0.8, l4=None):
    """``(ground, crank, coupler, rocker)`` lengths (m) actually built: ground ``l1 - gap``."""
    if l4 is None:
        l4 = l1 + l2 - l3
    if not gap >= 0.0:
        raise ValueError(f"gap={gap!r}: must be >= 0 (gap < 0 makes the crank unable to turn fully)")
    if not abs(l1 + l2 - l3 - l4) <= 1e-12 * (l1 + l2):
        raise ValueError(f"l1 + l2 = {l1 + l2:g} but l3 + l4 = {l3 + l4:g}: the nominal lengths must satisfy the "
                         "change-point condition l1 + l2 = l3 + l4 (leave l4=None to derive it)")
    L = (l1 - gap, l2, l3, l4)
    if min(L) <= 0.0 or not (l2 < min(l1 - gap, l3, l4) and l1 - gap >= max(l3, l4)):
        raise ValueError(f"lengths (ground, crank, coupler, rocker) = {L}: need the crank shortest and the "
                         "ground longest (a crank-rocker); e.g. l1=1.0, l2=0.4, l3=0.8")
    return L


def assembly(phi, gap=1e-3, l1=1.0, l2=0.4, l3=0.8, l4=None, branch=1):
    """Coupler angle relative to the crank and rocker angle (rad) at crank angle ``phi``.

    Closed-form loop closure: C is the intersection of the circles (B, l3) and (D, l4) on the
    side ``branch`` of the line B->D. Returns ``(coupler_rel, rocker)``.
    """
    L1, L2, L3, L4 = lengths(gap, l1, l2, l3, l4)
    B = L2 * np.array([np.cos(phi), np.sin(phi)])
    D = np.array([L1, 0.0])
    d = np.linalg.norm(D - B)
    e = (D - B) / d
    a = (L3 ** 2 - L4 ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(max(L3 ** 2 - a ** 2, 0.0))
    C = B + a * e + branch * h * np.array([-e[1], e[0]])
    theta3 = np.arctan2(C[1] - B[1], C[0] - B[0])
    theta4 = np.arctan2(C[1] - D[1], C[0] - D[0])
    return float(np.angle(np.exp(1j * (theta3 - phi)))), float(theta4)


def build(gap=1e-3, l1=1.0, l2=0.4, l3=0.8, l4=None, rho=1.0, g=9.81, phi0=np.pi / 2, w0=8.0, branch=1):
    """Four-bar with ground ``l1 - gap``, crank ``l2``, coupler ``l3``, rocker ``l4`` (m;
    ``l4=None``: ``l1 + l2 - l3``), rods of ``rho`` kg/m, gravity ``g`` (m/s^2) along -y, crank
    start angle ``phi0`` (rad) and rate ``w0`` (rad/s) fixed, assembly mode ``branch`` (+1/-1)."""
    L1, L2, L3, L4 = lengths(gap, l1, l2, l3, l4)
    if branch not in (1, -1):
        raise ValueError(f"branch={branch!r}: use +1 (C left of B->D) or -1 (mirrored)")
    rel0, th40 = assembly(phi0, gap, l1, l2, l3, l4, branch)
    mc, mk, mr = rho * L2, rho * L3, rho * L4

    m = Model()
    world = m.add("world", World(g=(0.0, -float(g), 0.0)))
    pivot_d = m.add("pivot_d", Fixed(r=(L1, 0.0, 0.0)))
    crank_joint = m.add("crank_joint", Revolute(n=(0, 0, 1), phi0=phi0, w0=w0))
    crank = m.add("crank", RigidBody(m=mc, r_cm=(L2 / 2, 0, 0), I=rod_inertia(mc, L2)))
    crank_tip = m.add("crank_tip", FixedTranslation(r=(L2, 0, 0)))
    coupler_joint = m.add("coupler_joint", Revolute(n=(0, 0, 1), phi0=Guess(rel0)))
    coupler = m.add("coupler", RigidBody(m=mk, r_cm=(L3 / 2, 0, 0), I=rod_inertia(mk, L3)))
    coupler_tip = m.add("coupler_tip", FixedTranslation(r=(L3, 0, 0)))
    rocker_joint = m.add("rocker_joint", Revolute(n=(0, 0, 1), phi0=Guess(th40)))
    rocker = m.add("rocker", RigidBody(m=mr, r_cm=(L4 / 2, 0, 0), I=rod_inertia(mr, L4)))
    rocker_tip = m.add("rocker_tip", FixedTranslation(r=(L4, 0, 0)))
    pin = m.add("pin", Revolute(n=(0, 0, 1), phi0=Guess(float(np.angle(np.exp(1j * (th40 - phi0 - rel0)))))))

    m.connect(world.frame_b, crank_joint.frame_a)
    m.connect(crank_joint.frame_b, crank.frame_a)
    m.connect(crank_joint.frame_b, crank_tip.frame_a)
    m.connect(crank_tip.frame_b, coupler_joint.frame_a)
    m.connect(coupler_joint.frame_b, coupler.frame_a)
    m.connect(coupler_joint.frame_b, coupler_tip.frame_a)
    m.connect(pivot_d.frame_b, rocker_joint.frame_a)
    m.connect(rocker_joint.frame_b, rocker.frame_a)
    m.connect(rocker_joint.frame_b, rocker_tip.frame_a)
    m.connect(coupler_tip.frame_b, pin.frame_a)  # closes the loop at C
    m.connect(rocker_tip.frame_b, pin.frame_b)
    m.alias("crank_angle", "crank_joint.phi")
    m.alias("rocker_angle", "rocker_joint.phi")
    return m
