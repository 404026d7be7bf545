"""Seed Section 4.3, Example 3: a sphere rolling without slipping on a plane (Fig. 4.3).

The book's constraints for a ball of radius ``a`` on the plane z = 0 (``theta_x``,
``theta_y`` its rotations, so ``theta_x'``, ``theta_y'`` its angular velocity components):

    r_cz = a                                           (holonomic)
    (v_Ax)_rel = r_cx' - theta_y' a = 0                (no slip along x)
    (v_Ay)_rel = r_cy' + theta_x' a = 0                (no slip along y)

with three unknown constraint forces ``R_x, R_y, R_z`` at the contact point A. Section 4.4
classifies the two velocity conditions as nonholonomic.

What is modelled: the library composite ``RollingSphere`` (a free ball, a ``SphereContact``
with the ground plane, start velocities in rolling terms), so the three rows are the
contact's ``normal``, ``slip_1`` (along x) and ``slip_2`` (along y); the reactions are the
contact outputs ``N`` (the book's R_z), ``F_1`` (R_x) and ``F_2`` (R_y). An optional
horizontal force ``push`` (N, along x) acts at the ball's centre, so the friction force is
not zero: with a uniform ball the centre accelerates at ``(5/7) push / m`` and the contact
pulls back with ``R_x = -(2/7) push``.

Run: ``mbcomp info models/textbook/ex4_3_rolling_sphere.py``
"""
from mbcomp import Model
from mbcomp.library import RollingSphere, World, WorldForce

SIMULATION = dict(t_end=2.0, rtol=1e-10, atol=1e-12)


def build(m=1.0, a=0.1, g=9.81, vx0=0.5, vy0=0.2, spin0=3.0, push=0.0):
    """Seed Example 4.3-3.

    Parameters
    ----------
    m, a : float
        Mass (kg) and radius (m) of the uniform ball.
    g : float
        Gravitational acceleration (m/s^2), along world ``-z``.
    vx0, vy0 : float
        Start velocity of the centre (m/s, world x and y); the rolling angular velocity
        follows from no slip.
    spin0 : float
        Start spin about the vertical (rad/s), which rolling leaves free.
    push : float
        Constant horizontal force (N) along world x at the ball's centre.

    Returns
    -------
    mbcomp.Model
        Aliases ``r_cx``, ``r_cy``, ``r_cz`` (centre, m), ``R_x``, ``R_y``, ``R_z`` (contact
        force on the ball, N).
    """
    mdl = Model()
    world = mdl.add("world", World(g=(0.0, 0.0, -g)))
    ball = mdl.add("ball", RollingSphere(r=a, m=m, v0=(vx0, vy0), spin_rate0=spin0))
    mdl.connect(world.frame_b, ball.plane)
    if push:
        force = mdl.add("push", WorldForce(f=(push, 0.0, 0.0)))
        mdl.connect(ball.center, force.frame_b)
    for axis in "xyz":
        mdl.alias(f"r_c{axis}", f"ball.ball.r.{axis}")
    for book, ours in (("R_x", "F_1"), ("R_y", "F_2"), ("R_z", "N")):
        mdl.alias(book, f"ball.contact.{ours}")
    return mdl
