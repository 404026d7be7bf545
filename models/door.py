"""A door swinging shut against its stop (issue 22): a rigid stop with Newton's restitution.

A door leaf (a uniform plate ``width`` x ``height``, mass ``m``) hangs on a vertical hinge
(z up, no gravity torque about the hinge). It is pushed shut at ``w0`` (rad/s, negative:
closing) from ``phi0`` (rad) and hits the frame's stop at ``phi = 0``; a stop at ``open``
(rad) keeps it from opening past the wall. Each impact keeps ``e^2`` of the kinetic energy
(``restitution = e``), so the rebounds shrink geometrically and the impacts come ever closer:
the door comes to rest against the frame (``res.events`` ends with ``rest``). A linear
damper on the hinge (``damping``, N m s/rad) slows it between impacts.

With no damping the impact times are exact: the first at ``phi0 / |w0|``, then every
rebound of speed ``e^k |w0|`` travels out and back; the door stays within ``[0, open]``.

Examples
--------
>>> import mbcomp
>>> res = mbcomp.simulate(mbcomp.load_model_file("models/door.py").build(), t_end=3.0, rtol=1e-10, atol=1e-12)
>>> res.events[0].kind, res.events[0].component, round(res.events[0].time, 9)
('impact', 'hinge', 1.0)
"""
import numpy as np

import mbcomp
from mbcomp.library import RigidBody, RotationalDamper, Revolute, World


def build(m=20.0, width=0.9, height=2.0, phi0=1.0, w0=-1.0, restitution=0.6, open=2.0, damping=0.0):
    """The door model (SI units: kg, m, rad, rad/s, N m s/rad)."""
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, 0, -9.81)))
    hinge = model.add("hinge", Revolute(n=(0, 0, 1), phi0=phi0, w0=w0, limits=(0.0, open), restitution=restitution))
    I_cm = m / 12.0 * np.diag([height**2, width**2 + height**2, width**2])
    leaf = model.add("leaf", RigidBody(m=m, r_cm=(width / 2, 0.0, 0.0), I=I_cm))
    model.connect(world.frame_b, hinge.frame_a)
    model.connect(hinge.frame_b, leaf.frame_a)
    if damping:
        d = model.add("damper", RotationalDamper(d=damping))
        model.connect(d.flange_a, hinge.support)
        model.connect(d.flange_b, hinge.axis)
    return model
