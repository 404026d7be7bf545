"""Andrews' squeezing mechanism: the planar seven-body mechanism of Hairer & Wanner.

The reference problem of E. Hairer, G. Wanner, *Solving Ordinary Differential Equations
II* (2nd ed. 1996), sec. VII.7, and of the IVP test set (Mazzia, Magherini, Iavernaro,
release 2.3, problem ``andrews``); statement, geometry and the published equations in
``shared/reference/andrews.md``, numbers in ``andrews.json``. Seven rigid bodies move in the
x-y plane, joined by revolute joints (axes along world z), 1 degree of freedom, three
closed loops that all meet at the point E. A constant torque ``mom`` drives the crank about
O; a linear spring (rate ``c0``, rest length ``l0``) pulls point D of the triangle body
towards the fixed point C. No gravity, no damping; the mechanism starts at rest in the
published consistent position and is run for 0.03 s (the crank turns about 2.5 times).

Geometry (all in the plane, world frame = the published frame, origin O)
-------------------------------------------------------------------------
Ground points O = (0, 0), A = (xa, ya), B = (xb, yb), C = (xc, yc) (``Fixed`` frames).
Each body frame has its origin at the body's hinge on its parent (the tree below); the
offsets are ``FixedTranslation`` components, positions in the body's own frame:

====  =========  ======  ========================  ===================  ======================
body  component  hinge   joint (coordinate)        other points         centre of mass
====  =========  ======  ========================  ===================  ======================
1     crank      O       ``hinge_O`` (beta)        F = (rr, 0)          (ra, 0)
2     rod        F       ``hinge_F`` (Theta)       E = (-d, 0)          (-da, 0)
3     triangle   B       ``hinge_B`` (gamma)       E = (0, -ss),        (sa, sb) *
                                                   D = (sd, -sc)
5     link_AG    A       ``hinge_A_AG`` (delta)    G = (zt, 0)          (ta, tb) *
4     link_EG    G       ``hinge_G`` (Phi)         E = (0, -e)          (0, -(e - ea))
7     link_AH    A       ``hinge_A_AH`` (epsilon)  H = (0, -u)          (ua, ub) *
6     link_HE    H       ``hinge_H`` (Omega)       E = (zf, 0)          (zf - fa, 0)
====  =========  ======  ========================  ===================  ======================

This reproduces the published kinematics exactly (andrews.md, "from g(q)"):
F = rr e(beta), E = F - d e(beta + Theta) = B + ss (sin gamma, -cos gamma)
= A + zt e(delta) + e (sin(Phi + delta), -cos(Phi + delta))
= A + u (sin epsilon, -cos epsilon) + zf e(Omega + epsilon), with e(a) = (cos a, sin a), and
D = B + sd e(gamma) + sc (sin gamma, -cos gamma). The positions of the centres of mass of
bodies 2, 4 and 6 follow from the published mass matrix (M11, M21, M54, M76 fix them on the
lines F-E, G-E and H-E at da from F, ea from E and fa from E). Bodies 1, 3, 5 and 7 turn about
fixed points, so only their moment of inertia about the pivot enters the published equations
(m1 ra^2 + i1, m3 (sa^2 + sb^2) + i3, m5 (ta^2 + tb^2) + i5, m7 (ua^2 + ub^2) + i7);
* the direction of the centre of mass of bodies 3, 5, 7 in their frames is not given by the
published equations: (sa, sb), (ta, tb), (ua, ub) are assumed. It changes no published
quantity (motion, multipliers at E) - only the reactions at the fixed pivots B and A.
Each body's inertia about its centre of mass is ``i_k`` about z (diag(i/2, i/2, i): a thin
plate; the in-plane components play no role in planar motion).

Spanning tree and loops
-----------------------
Tree (the published coordinates are exactly the tree-joint angles; every ``Revolute`` has
``n = z`` and zero where the body frame is parallel to its parent frame):

* ``hinge_O``: world -> crank, angle ``beta`` (absolute angle of OF);
* ``hinge_F``: crank -> rod, angle ``Theta`` (relative, crank -> rod at F);
* ``hinge_B``: ground B -> triangle, angle ``gamma``;
* ``hinge_A_AG``: ground A -> link_AG, angle ``delta``; ``hinge_G``: link_AG -> link_EG, ``Phi``
  (relative at G);
* ``hinge_A_AH``: ground A -> link_AH, angle ``epsilon``; ``hinge_H``: link_AH -> link_HE,
  ``Omega`` (relative at H).

The three loops are closed at E by cut revolute joints between the rod's end E and the other
three bodies' points E: ``pin_E_triangle``, ``pin_E_EG``, ``pin_E_HE`` (5 rows each, resolved in
the rod's frame; the 9 out-of-plane rows are redundant and dropped by initialization, the
remaining 6 are the published g(q) = 0 rotated into the rod frame, sign reversed). The tree
joints carry fixed start values (``beta`` and all start rates) and the cut joints none, so
the minimum spanning tree is always this one.

Published quantity -> component
-------------------------------
``beta, Theta, gamma, Phi, delta, Omega, epsilon`` -> ``hinge_O.phi, hinge_F.phi,
hinge_B.phi, hinge_G.phi, hinge_A_AG.phi, hinge_H.phi, hinge_A_AH.phi`` (aliases of those
names; their rates ``<hinge>.w``, accelerations ``<hinge>.w.der``); ``mom`` -> ``torque``
(``Torque`` on ``hinge_O.axis``); ``c0, l0`` -> ``spring`` (``Spring`` from ``triangle_D`` to
ground ``C``); the published multipliers are the x/y constraint forces at E (mbcomp's
``lambda.pin_E_*`` are the same forces resolved in the rod's frame with the opposite sign).
The work of the torque is not a potential: energy balance is ``energy.total - mom (beta -
beta(0))`` = constant.

Run: ``mbcomp simulate models/andrews.py --out andrews.csv``
"""
import numpy as np

from mbcomp import Guess, Model
from mbcomp.library import Fixed, FixedTranslation, Revolute, RigidBody, Spring, Torque, World

#: Parameters (SI), the test set's PARAMETER statement (andrews.json "parameters").
PARAMETERS = dict(
    m1=0.04325, m2=0.00365, m3=0.02373, m4=0.00706, m5=0.0705, m6=0.00706, m7=0.05498,
    xa=-0.06934, ya=-0.00227, xb=-0.03635, yb=0.03273, xc=0.014, yc=0.072, c0=4530.0,
    i1=2.194e-06, i2=4.41e-07, i3=5.255e-06, i4=5.667e-07, i5=1.169e-05, i6=5.667e-07, i7=1.912e-05,
    d=0.028, da=0.0115, e=0.02, ea=0.01421, rr=0.007, ra=0.00092, l0=0.07785, ss=0.035, sa=0.01874,
    sb=0.01043, sc=0.018, sd=0.02, ta=0.02308, tb=0.00916, u=0.04, ua=0.01228, ub=0.00449, zf=0.02,
    zt=0.04, fa=0.01421, mom=0.033,
)

#: Published consistent initial positions (rad), andrews.json "initial_values_as_printed".
INITIAL = dict(
    beta=-0.0617138900142764496358948458001,
    Theta=0.0,
    gamma=0.455279819163070380255912382449,
    Phi=0.222668390165885884674473185609,
    delta=0.487364979543842550225598953530,
    Omega=-0.222668390165885884674473185609,
    epsilon=1.23054744454982119249735015568,
)

#: Published coordinate -> tree joint whose angle it is.
COORDINATES = dict(beta="hinge_O", Theta="hinge_F", gamma="hinge_B", Phi="hinge_G", delta="hinge_A_AG",
                   Omega="hinge_H", epsilon="hinge_A_AH")

# rtol/atol: at 1e-10/1e-12 Lagrange+projection (DOP853, Radau) and D'Alembert (DOP853, Radau) all
# reproduce the published positions at t = 0.03 to <= 7e-10 relative (the reference itself is good
# to ~1e-10); 1e-8/1e-10 is the loosest setting that still gives ~1e-8 (tests/test_andrews.py).
SIMULATION = dict(t_end=0.03, rtol=1e-10, atol=1e-12)

#: Published solution at t = 0.03 s (PSIDE, rtol = atol = 1e-14; positions reliable to about
#: 1e-10 relative): the reference of ``mbcomp bench models/andrews.py``.
REFERENCE = dict(t_end=0.03, source="Mazzia et al., IVP Test Set 2.3, problem 'andrews' (PSIDE 1e-14)",
                 values={
                     "beta": 15.81077119629904,
                     "Theta": -15.75637105984298,
                     "gamma": 0.04082224013073101,
                     "Phi": -0.5347301163226948,
                     "delta": 0.5244099658805303,
                     "Omega": 0.5347301163226948,
                     "epsilon": 1.048080741042263,
                 })


def _plate(i):
    """Inertia about the centre of mass of a planar body with moment ``i`` about z (kg m^2)."""
    return np.diag([0.5 * i, 0.5 * i, i])


def build(beta0=None, **params):
    """Andrews' mechanism; ``params`` override :data:`PARAMETERS` (e.g. ``mom=0.02``).

    ``beta0`` (rad) changes the start angle of the crank; the other angles then start from
    the published values as guesses and initialization closes the loops. The start is at rest.
    """
    unknown = set(params) - set(PARAMETERS)
    if unknown:
        raise TypeError(f"andrews.build: unknown parameters {sorted(unknown)}; known: {', '.join(PARAMETERS)}")
    p = dict(PARAMETERS, **params)
    q0 = dict(INITIAL)
    fixed_beta = q0["beta"] if beta0 is None else float(beta0)
    # the published values are consistent: with the default beta0 the loops close at start to ~1e-17
    start = {k: (fixed_beta if k == "beta" else Guess(v)) for k, v in q0.items()}

    m = Model()
    world = m.add("world", World(g=(0.0, 0.0, 0.0)))
    ground_A = m.add("A", Fixed(r=(p["xa"], p["ya"], 0.0)))
    ground_B = m.add("B", Fixed(r=(p["xb"], p["yb"], 0.0)))
    ground_C = m.add("C", Fixed(r=(p["xc"], p["yc"], 0.0)))
    z = (0.0, 0.0, 1.0)

    def hinge(name, coord):
        # fixed start rate 0 (the mechanism starts at rest) keeps the joint in the spanning tree
        return m.add(name, Revolute(n=z, phi0=start[coord], w0=0.0))

    def body(name, mass, r_cm, i):
        return m.add(name, RigidBody(m=mass, r_cm=(r_cm[0], r_cm[1], 0.0), I=_plate(i)))

    def point(name, r):
        return m.add(name, FixedTranslation(r=(r[0], r[1], 0.0)))

    # body 1: crank OF about O
    hinge_O = hinge("hinge_O", "beta")
    crank = body("crank", p["m1"], (p["ra"], 0.0), p["i1"])
    crank_F = point("crank_F", (p["rr"], 0.0))
    m.connect(world.frame_b, hinge_O.frame_a)
    m.connect(hinge_O.frame_b, crank.frame_a)
    m.connect(hinge_O.frame_b, crank_F.frame_a)
    torque = m.add("torque", Torque(tau=p["mom"]))
    m.connect(torque.flange_b, hinge_O.axis)

    # body 2: rod FE, relative angle Theta at F
    hinge_F = hinge("hinge_F", "Theta")
    rod = body("rod", p["m2"], (-p["da"], 0.0), p["i2"])
    rod_E = point("rod_E", (-p["d"], 0.0))
    m.connect(crank_F.frame_b, hinge_F.frame_a)
    m.connect(hinge_F.frame_b, rod.frame_a)
    m.connect(hinge_F.frame_b, rod_E.frame_a)

    # body 3: triangle BDE about B, spring D-C
    hinge_B = hinge("hinge_B", "gamma")
    triangle = body("triangle", p["m3"], (p["sa"], p["sb"]), p["i3"])
    triangle_E = point("triangle_E", (0.0, -p["ss"]))
    triangle_D = point("triangle_D", (p["sd"], -p["sc"]))
    m.connect(ground_B.frame_b, hinge_B.frame_a)
    m.connect(hinge_B.frame_b, triangle.frame_a)
    m.connect(hinge_B.frame_b, triangle_E.frame_a)
    m.connect(hinge_B.frame_b, triangle_D.frame_a)
    spring = m.add("spring", Spring(c=p["c0"], s_unstretched=p["l0"]))
    m.connect(triangle_D.frame_b, spring.frame_a)
    m.connect(ground_C.frame_b, spring.frame_b)

    # body 5: AG about A (delta); body 4: EG, relative angle Phi at G
    hinge_A_AG = hinge("hinge_A_AG", "delta")
    link_AG = body("link_AG", p["m5"], (p["ta"], p["tb"]), p["i5"])
    AG_G = point("AG_G", (p["zt"], 0.0))
    m.connect(ground_A.frame_b, hinge_A_AG.frame_a)
    m.connect(hinge_A_AG.frame_b, link_AG.frame_a)
    m.connect(hinge_A_AG.frame_b, AG_G.frame_a)
    hinge_G = hinge("hinge_G", "Phi")
    link_EG = body("link_EG", p["m4"], (0.0, -(p["e"] - p["ea"])), p["i4"])
    EG_E = point("EG_E", (0.0, -p["e"]))
    m.connect(AG_G.frame_b, hinge_G.frame_a)
    m.connect(hinge_G.frame_b, link_EG.frame_a)
    m.connect(hinge_G.frame_b, EG_E.frame_a)

    # body 7: AH about A (epsilon); body 6: HE, relative angle Omega at H
    hinge_A_AH = hinge("hinge_A_AH", "epsilon")
    link_AH = body("link_AH", p["m7"], (p["ua"], p["ub"]), p["i7"])
    AH_H = point("AH_H", (0.0, -p["u"]))
    m.connect(ground_A.frame_b, hinge_A_AH.frame_a)
    m.connect(hinge_A_AH.frame_b, link_AH.frame_a)
    m.connect(hinge_A_AH.frame_b, AH_H.frame_a)
    hinge_H = hinge("hinge_H", "Omega")
    link_HE = body("link_HE", p["m6"], (p["zf"] - p["fa"], 0.0), p["i6"])
    HE_E = point("HE_E", (p["zf"], 0.0))
    m.connect(AH_H.frame_b, hinge_H.frame_a)
    m.connect(hinge_H.frame_b, link_HE.frame_a)
    m.connect(hinge_H.frame_b, HE_E.frame_a)

    # the three loops close at E: cut revolute joints from the rod's end
    for name, other in (("pin_E_triangle", triangle_E), ("pin_E_EG", EG_E), ("pin_E_HE", HE_E)):
        pin = m.add(name, Revolute(n=z))
        m.connect(rod_E.frame_b, pin.frame_a)
        m.connect(other.frame_b, pin.frame_b)

    for coord, joint in COORDINATES.items():
        m.alias(coord, f"{joint}.phi")
    return m
