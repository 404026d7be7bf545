"""Seed Example 3.1: a pendulum hinged to a massless cart whose motion u(t) is prescribed.

The book (Fig. 3.1, eqs. 3.12-3.20): a uniform rod (mass ``m``, length ``L``, centroidal
inertia ``Ic = m L^2 / 12``) is hinged at one end to a cart of negligible mass that runs on a
frictionless floor with prescribed position ``u(t)``. With the unit vectors of (3.16),
``e_r = sin th e_x - cos th e_y`` (hinge -> centre of mass) and ``e_th = cos th e_x + sin th e_y``,
the book prints

- (3.18) ``(Ic + m L^2/4) th'' + m g L/2 sin th = m L/2 u'' cos th``  (equation of motion),
- (3.19) ``Fr = m L/2 th'^2 + m g cos th - m u'' sin th``             (rod tension),
- (3.20) ``F_th = -2 Ic th'' / L``                                   (hinge force along e_th).

What is modelled: the cart is the ``frame_b`` of a :class:`~mbcomp.library.Prismatic` joint
along world x whose coordinate is imposed by a :class:`~mbcomp.library.PrescribedMotion`
drive, ``u(t) = A sin(Omega t)`` (the book leaves u(t) open); it carries no body (optionally
a massless ``RigidBody``). The rod hangs from a :class:`~mbcomp.library.Revolute` about world
z; gravity acts along -y. The hinge angle ``phi`` (counter-clockwise about +z) is the book's
``th`` of (3.16): ``phi > 0`` swings the rod towards +x.

Findings (re-derived in ``tests/test_textbook_ex3_1.py``): in the convention of (3.16) the
right-hand side of (3.18) must carry a minus sign,
``(Ic + m L^2/4) th'' + m g L/2 sin th = -m L/2 u'' cos th`` (a cart accelerating to +x
leaves the rod behind, towards -x); the printed (3.18) holds for the mirrored angle
``-th``. (3.19) and (3.20) are right in the (3.16) convention, with ``Fr`` the tension
(the force on the rod along ``-e_r``, although (3.14) writes it as ``+Fr e_r``); (3.15)
``L/2 F_th = Ic th''`` has the wrong sign (the moment of ``F_th e_th`` at the hinge about the
centre of mass is ``-L/2 F_th``), which (3.20) silently corrects.

Outputs (aliases, the book's names): ``theta`` = ``hinge.phi`` (rad), ``u`` = ``cart.s`` (m),
``F_theta`` = ``hinge.f.x`` and ``F_r`` = ``hinge.f.y`` (N; the force on the rod at the hinge,
resolved in the rod frame whose x axis is ``e_th`` and y axis is ``-e_r``), ``F_drive`` =
``drive.f`` (N, the horizontal force that moves the cart).

Run: ``mbcomp simulate models/textbook/ex3_1_pendulum_cart.py --out ex3_1.csv``
"""
import numpy as np

from mbcomp import Model
from mbcomp.library import PrescribedMotion, Prismatic, Revolute, RigidBody, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12, method="DOP853")


def build(m=1.4, L=0.8, g=9.81, A=0.2, Omega=6.0, theta0=0.3, theta_dot0=-0.5, cart_body=False):
    """Pendulum on a massless cart with prescribed motion ``u(t) = A sin(Omega t)``.

    Parameters
    ----------
    m : float
        Rod mass (kg).
    L : float
        Rod length (m); uniform slender rod, ``Ic = m L^2 / 12`` (kg m^2) about its centre.
    g : float
        Gravitational acceleration (m/s^2), along world -y.
    A, Omega : float
        Amplitude (m) and angular frequency (rad/s) of the cart motion along world x.
    theta0, theta_dot0 : float
        Start angle (rad) and rate (rad/s) of the rod, counter-clockwise about world z from
        hanging straight down (the book's theta of eq. 3.16).
    cart_body : bool
        Attach an explicit massless ``RigidBody`` as the cart (same physics).

    Returns
    -------
    mbcomp.Model
    """
    Ic = m * L ** 2 / 12.0
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    cart = mdl.add("cart", Prismatic(n=(1, 0, 0)))
    drive = mdl.add("drive", PrescribedMotion(s=f"{A!r}*sin({Omega!r}*t)"))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0, w0=theta_dot0))
    # rod frame = hinge frame_b: the rod hangs along its -y axis; slender along y
    rod = mdl.add("rod", RigidBody(m=m, r_cm=(0.0, -L / 2, 0.0), I=np.diag([Ic, 0.0, Ic])))
    mdl.connect(world.frame_b, cart.frame_a)
    mdl.connect(drive.flange_b, cart.axis)
    mdl.connect(cart.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, rod.frame_a)
    if cart_body:
        cart_mass = mdl.add("cart_mass", RigidBody(m=0.0))
        mdl.connect(cart.frame_b, cart_mass.frame_a)
    mdl.alias("theta", "hinge.phi")
    mdl.alias("u", "cart.s")
    mdl.alias("F_theta", "hinge.f.x")
    mdl.alias("F_r", "hinge.f.y")
    mdl.alias("F_drive", "drive.f")
    return mdl
