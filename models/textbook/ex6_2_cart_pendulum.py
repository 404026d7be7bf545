"""Seed Example 6.2: a cart on a spring carrying a pendulum (two degrees of freedom, Fig. 6.3).

The cart (mass ``m1``) slides along the world ``x`` axis on a ``Prismatic`` joint and is tied
to the ground by a linear spring of rate ``k`` (a ``TranslationalSpringDamper`` between the
slider's support and axis flanges, unstretched at ``x = 0``). A point mass ``m2`` hangs from
the cart on a massless rod of length ``L`` (``FixedTranslation``) on a ``Revolute`` about
``z``. Gravity acts along ``-y``; the book's ``theta`` is measured from the downward
vertical, which is the revolute angle here (the rod points along ``-y`` at ``phi = 0`` and
``phi > 0`` swings the bob towards ``+x``). The book's energies and equations of motion are

    T = (1/2)(m1 + m2) x'^2 + m2 L x' th' cos th + (1/2) m2 L^2 th'^2       (6.24)
    V = (1/2) k x^2 - m2 g L cos th                                         (6.25)
    (m1 + m2) x'' + m2 L th'' cos th - m2 L th'^2 sin th + k x = 0          (6.36)
    m2 L^2 th'' + m2 L x'' cos th + m2 g L sin th = 0                       (6.37)

Run: ``mbcomp simulate models/textbook/ex6_2_cart_pendulum.py --plot cart.png``
"""
from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, TranslationalSpringDamper, World

SIMULATION = dict(t_end=5.0, rtol=1e-10, atol=1e-12)


def build(m1=2.0, m2=0.7, L=0.9, k=35.0, g=9.81, x0=0.15, xd0=-0.3, th0=1.1, thd0=0.8):
    """Cart-pendulum of seed Example 6.2.

    Parameters
    ----------
    m1 : float
        Cart mass (kg).
    m2 : float
        Pendulum bob mass (kg), a particle.
    L : float
        Pendulum length (m), massless rod.
    k : float
        Spring rate (N/m) tying the cart to the ground, unstretched at ``x = 0``.
    g : float
        Gravitational acceleration (m/s^2), along world ``-y``.
    x0, xd0 : float
        Start position (m) and velocity (m/s) of the cart along world ``x``.
    th0, thd0 : float
        Start angle from the downward vertical (rad) and rate (rad/s) of the pendulum.

    Returns
    -------
    mbcomp.Model
        Aliases ``x``, ``x_dot`` (cart) and ``theta``, ``theta_dot`` (pendulum).
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0, -g, 0)))
    slider = mdl.add("slider", Prismatic(n=(1, 0, 0), s0=x0, v0=xd0))
    spring = mdl.add("spring", TranslationalSpringDamper(c=k))
    cart = mdl.add("cart", PointMass(m=m1))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=th0, w0=thd0))
    rod = mdl.add("rod", FixedTranslation(r=(0, -L, 0)))
    bob = mdl.add("bob", PointMass(m=m2))
    mdl.connect(world.frame_b, slider.frame_a)
    mdl.connect(slider.frame_b, cart.frame_a)
    mdl.connect(slider.support, spring.flange_a)
    mdl.connect(slider.axis, spring.flange_b)
    mdl.connect(slider.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, bob.frame_a)
    mdl.alias("x", "slider.s")
    mdl.alias("x_dot", "slider.v")
    mdl.alias("theta", "hinge.phi")
    mdl.alias("theta_dot", "hinge.w")
    return mdl
