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
With damping ``d`` the swing between impacts is ``w(t) = w e^(-t/tau)``,
``phi(t) = phi + w tau (1 - e^(-t/tau))`` with ``tau = J / d`` (``J = m width^2 / 3`` about the
hinge), so every impact time is closed-form too: :func:`reference` chains them to the state at
``t_end``, the reference ``mbcomp bench models/door.py`` measures the methods against (the
error is then the event location's and the integration's between impacts).

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


#: how ``mbcomp bench`` runs it (the closed form: :func:`reference`)
SIMULATION = dict(t_end=8.0, rtol=1e-10, atol=1e-12)


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


def reference(t_end=None, m=20.0, width=0.9, height=2.0, phi0=1.0, w0=-1.0, restitution=0.6, open=2.0,
              damping=0.0):
    """The closed-form state at ``t_end`` (s): ``dict(t_end, values={"hinge.phi": rad,
    "hinge.w": rad/s}, impacts=[s], source)``, impacts chained as in the module notes (the
    same parameters as :func:`build`; ``height`` does not enter). A rebound too slow to
    reach a stop again decays towards rest (damped) without an impact.

    Examples
    --------
    >>> ref = reference(t_end=3.0)          # shut at t = 1, back out at 0.6 rad/s for 2 s
    >>> ref["impacts"], round(ref["values"]["hinge.phi"], 12), ref["values"]["hinge.w"]
    ([1.0], 1.2, 0.6)
    """
    import math

    t_end = SIMULATION["t_end"] if t_end is None else t_end
    tau = m * width**2 / 3.0 / damping if damping else math.inf
    t, phi, w, impacts = 0.0, phi0, w0, []
    while True:
        target = 0.0 if w < 0 else open
        dt = _time_to(target - phi, w, tau)
        if w == 0.0 or t + dt > t_end:
            phi, w = _swing(phi, w, tau, t_end - t)
            return dict(t_end=t_end, values={"hinge.phi": phi, "hinge.w": w}, impacts=impacts,
                        source=f"closed form (models/door.py reference: {len(impacts)} impacts before t_end)")
        t, phi, w = t + dt, target, -restitution * _swing(phi, w, tau, dt)[1]
        impacts.append(t)


def _swing(phi, w, tau, dt):
    """``(phi, w)`` after ``dt`` s of the damped free swing (``tau = inf``: undamped)."""
    import math

    if math.isinf(tau):
        return phi + w * dt, w
    decay = math.exp(-dt / tau)
    return phi + w * tau * (1.0 - decay), w * decay


def _time_to(dphi, w, tau):
    """Time (s) to turn by ``dphi`` (same sign as ``w``) at speed ``w`` decaying with ``tau``;
    ``inf`` when the swing stops short of it."""
    import math

    if w == 0.0:
        return math.inf
    if math.isinf(tau):
        return dphi / w
    reach = 1.0 - dphi / (w * tau)
    return -tau * math.log(reach) if reach > 0.0 else math.inf
