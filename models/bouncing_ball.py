"""A ball bouncing on the ground (issue 22): a unilateral plane contact with Newton's restitution.

A ball (a point mass ``m`` with radius ``r`` for the contact) is dropped from rest, its lowest
point ``h0`` (m) above the ground z = 0 (gravity ``g`` down -z). It falls freely, hits the
ground with an impact (``restitution = e``: the speed after is ``e`` times the speed before),
flies up to ``e^2`` times the height it fell from, and so on: apex heights ``h0 e^(2k)``, the
first impact at ``t0 = sqrt(2 h0 / g)`` and the k-th (k = 0, 1, ...) at
``t0 + 2 t0 e (1 - e^k) / (1 - e)``. The impacts accumulate (Zeno) at
``t_inf = t0 (1 + 2 e / (1 - e))``; the run settles the ball there, at rest on the ground
(``res.events`` ends with ``rest``), and every impact's loss is in ``energy.impacts``.

The ball moves on a ``FreeTranslation`` (its start ``r0``); the contact is :class:`mbcomp.library.PlaneContact` (frictionless, ``unilateral=True``,
``open0=True``: the ball starts in the air).

Examples
--------
>>> import numpy as np, mbcomp
>>> res = mbcomp.simulate(mbcomp.load_model_file("models/bouncing_ball.py").build(), t_end=1.0, rtol=1e-10, atol=1e-12)
>>> res.events[0].kind, round(res.events[0].time, 9), round(float(np.sqrt(2 / 9.81)), 9)
('impact', 0.451523641, 0.451523641)
"""
import mbcomp
from mbcomp.library import PlaneContact, PointMass, World
from mbcomp.modeling.free_joint import FreeTranslation


def build(m=0.5, r=0.1, h0=1.0, restitution=0.8, g=9.81):
    """The bouncing ball (SI units: kg, m, m, 1, m/s^2)."""
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, 0, -g)))
    free = model.add("free", FreeTranslation(r0=(0.0, 0.0, h0 + r), v0=(0.0, 0.0, 0.0)))
    ball = model.add("ball", PointMass(m=m))
    ground = model.add("ground", PlaneContact(r=r, unilateral=True, restitution=restitution, open0=True))
    model.connect(world.frame_b, free.frame_a)
    model.connect(free.frame_b, ball.frame_a)
    model.connect(world.frame_b, ground.frame_a)
    model.connect(ground.frame_b, ball.frame_a)
    return model
