"""A bowling ball thrown down an oiled lane: Coulomb friction, sliding then rolling (issue 22).

A ball (mass ``m``, radius ``r``, centroidal inertia ``I = k m r^2`` with ``k = inertia``:
0.4 for a uniform sphere) is released on the level lane (x down the lane, y to the
left, z up; gravity ``g`` down -z) at ``v0`` (m/s) along x with backspin ``w_b`` (rad/s,
``w_y = -w_b``) and side roll ``hook`` (rad/s, ``w_x = -hook``: for ``hook > 0`` the ball
curves to the left, the right-hander's hook). The lane's Coulomb friction
(``ContactFriction(mu_s, mu_k)``, oiled-lane values by default) acts at the contact point
``-r e_z`` from the centre, whose slip velocity is

    ``s = v + w x (-r e_z) = (v_x - r w_y, v_y + r w_x)``,  ``s0 = (v0 + r w_b, -r hook)``.

While it slides, the friction ``F = -mu_k m g e`` (``N = m g``: the friction is horizontal)
points against the slip's direction ``e = s0 / |s0|``, and

* the centre decelerates along ``e``: ``dv/dt = -mu_k g e``;
* the spin changes by the friction's moment about the centre, ``I dw/dt = (-r e_z) x F``:
  ``dw/dt = mu_k g (-e_y, e_x, 0) / (k r)``;
* so the slip ``ds/dt = dv/dt - r d(w x e_z)/dt = -mu_k g (1 + 1/k) e`` keeps its direction
  and its speed falls linearly: the slide ends (the contact's event ``stick``, a switch to
  its rolling mode) at ``t* = |s0| / (mu_k g (1 + 1/k))`` (``|s0| / (3.5 mu_k g)`` for a
  uniform sphere), after which the ball rolls on at the constant ``v* = v0 e_x - mu_k g t* e``
  (``5 v0 / 7`` without spin; ``(5 v0 - 2 r w_b) / 7`` with backspin).

With ``hook`` the centre's path while sliding is a parabola (a constant acceleration across
the throw: the hook), a straight line once it rolls. A spin about the vertical (z) would
change nothing here: the contact has no drilling friction. Backspin beyond ``2 r w_b > 5 v0``
(k = 0.4) brings the ball back towards the bowler.

Without hook the ball spins about y alone and every run moves polynomially in t (the
friction's moment stays along the spin axis in the body's axes too), so any method integrates
it exactly and only the event location errs; with hook the body's axes, in which the free
joint integrates the spin, turn non-polynomially, and the error follows the tolerance
(about 1e-9 s on ``t*`` at rtol 1e-10, 1e-11 s at rtol 1e-12).

The friction dissipates ``W = int mu_k m g |s| dt = mu_k m g |s0| t* / 2 = k m |s0|^2 / (2 (1 + k))``
(the slip speed falls linearly from ``|s0|`` to 0), ``m (v0 + r w_b)^2 / 7`` for a uniform
sphere without hook; at a time ``t < t*`` it has dissipated
``mu_k m g (|s0| t - mu_k g (1 + 1/k) t^2 / 2)``. It equals the kinetic energy lost between the
throw and the rolling state (the normal force and gravity do no work on a level lane).
:func:`reference` gives all of it in closed form at any ``t_end``, the reference of
``mbcomp bench models/bowling.py`` (the error is then the slide-to-roll event's location
and the integration's).

With the oiled-lane friction ``mu_k = 0.04`` and no spin the slide lasts 5.8 s and 40 m, so
on a real 18.29 m lane the ball meets the pins still skidding: real lanes are oiled only over
their front two thirds, and the ball hooks in the dry back end. This model's lane is one
long, uniformly oiled floor.

Examples
--------
>>> import mbcomp
>>> bowling = mbcomp.load_model_file("models/bowling.py")
>>> res = mbcomp.simulate(bowling.build(w_b=10.0), t_end=8.0, rtol=1e-10, atol=1e-12, n_out=2)
>>> [(e.kind, e.name, e.detail["mode"]) for e in res.events]
[('switch', 'stick', 'closed')]
>>> round(res.events[0].time, 9), round((8.0 + 0.109 * 10.0) / (3.5 * 0.04 * 9.81), 9)
(6.618610747, 6.618610747)
>>> round(float(res["ball.v.x"][-1]), 9), round((5 * 8.0 - 2 * 0.109 * 10.0) / 7, 9)
(5.402857143, 5.402857143)
"""
import numpy as np

import mbcomp
from mbcomp.library import ContactFriction, FreeMotion, RigidBody, SphereContact, World


#: how ``mbcomp simulate`` / ``mbcomp bench`` run it (the closed form: :func:`reference`)
SIMULATION = dict(t_end=8.0, rtol=1e-10, atol=1e-12)


def build(m=7.0, r=0.109, inertia=0.4, mu_s=0.2, mu_k=0.04, v0=8.0, w_b=0.0, hook=0.0, g=9.81):
    """The bowling ball on its lane (see the module notes for the axes and the spins' signs).

    Parameters
    ----------
    m, r : float
        Mass (kg) and radius (m) of the ball.
    inertia : float
        ``I / (m r^2)`` (1) about any centroidal axis: 0.4 uniform, about 0.35-0.4 cored.
    mu_s, mu_k : float
        Static and kinetic friction coefficients (1) of the lane, ``mu_k <= mu_s``.
    v0 : float
        Release speed down the lane, +x (m/s).
    w_b : float
        Backspin (rad/s): the start spin about y is ``-w_b``.
    hook : float
        Side roll (rad/s): the start spin about x is ``-hook`` (> 0 curves to +y, the left).
    g : float
        Gravity (m/s^2), along -z.
    """
    if not 0.0 < inertia:
        raise ValueError(f"bowling: inertia={inertia!r} is I / (m r^2) and must be positive "
                         "-> give 0.4 for a uniform ball (about 0.35-0.4 for a cored bowling ball)")
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, 0, -g)))
    free = model.add("free", FreeMotion(r0=(0.0, 0.0, r), v0=(v0, 0.0, 0.0), w0=(-hook, -w_b, 0.0)))
    ball = model.add("ball", RigidBody(m=m, I=inertia * m * r * r * np.eye(3)))
    lane = model.add("lane", SphereContact(r=r, unilateral=True, friction=ContactFriction(mu_s, mu_k)))
    model.connect(world.frame_b, free.frame_a)
    model.connect(free.frame_b, ball.frame_a)
    model.connect(world.frame_b, lane.frame_a)
    model.connect(lane.frame_b, ball.frame_a)
    return model


def slide(m=7.0, r=0.109, inertia=0.4, mu_k=0.04, v0=8.0, w_b=0.0, hook=0.0, g=9.81):
    """``(t_star, e, S)``: the slide's end (s), the slip's unit direction ``e`` (2,) and its start
    speed ``S = |s0|`` (m/s) (module notes; ``m`` does not enter)."""
    s0 = np.array([v0 + r * w_b, -r * hook])
    S = float(np.hypot(*s0))
    if S == 0.0:
        return 0.0, np.array([1.0, 0.0]), 0.0
    return S / (mu_k * g * (1.0 + 1.0 / inertia)), s0 / S, S


def reference(t_end=None, m=7.0, r=0.109, inertia=0.4, mu_s=0.2, mu_k=0.04, v0=8.0, w_b=0.0, hook=0.0, g=9.81):
    """The closed-form state at ``t_end`` (s; default the SIMULATION's), the same parameters as
    :func:`build` (``mu_s`` does not enter: on a level lane the rolling ball needs no friction).

    Returns
    -------
    dict
        ``t_end``; ``values``: ``ball.r.x``, ``ball.r.y`` (m, the centre), ``ball.v.x``,
        ``ball.v.y`` (m/s), ``ball.w.x``, ``ball.w.y`` (rad/s, world axes) at ``t_end``;
        ``t_roll`` (s): the slide's end ``t*`` (past ``t_end`` too); ``sticks``: ``[t*]`` if
        ``t* <= t_end``, else ``[]``; ``dissipated`` (J): the friction's work until ``t_end``;
        ``source``.

    Examples
    --------
    >>> ref = reference(t_end=8.0)          # no spin: rolls from 2 v0 / (7 mu_k g) at 5 v0 / 7
    >>> round(ref["t_roll"], 8), round(2 * 8.0 / (7 * 0.04 * 9.81), 8), round(ref["values"]["ball.v.x"], 12)
    (5.82495995, 5.82495995, 5.714285714286)
    >>> round(ref["dissipated"], 9), round(7.0 * 8.0 ** 2 / 7, 9)
    (64.0, 64.0)
    """
    t_end = SIMULATION["t_end"] if t_end is None else float(t_end)
    t_star, e, S = slide(m, r, inertia, mu_k, v0, w_b, hook, g)
    a = mu_k * g
    t = min(t_end, t_star)  # sliding time until t_end
    v = np.array([v0, 0.0]) - a * t * e
    p = np.array([v0, 0.0]) * t - 0.5 * a * t * t * e + v * (t_end - t)
    w = np.array([-hook, -w_b]) + a * t * np.array([-e[1], e[0]]) / (inertia * r)
    work = m * a * (S * t - 0.5 * a * (1.0 + 1.0 / inertia) * t * t)
    values = {"ball.r.x": p[0], "ball.r.y": p[1], "ball.v.x": v[0], "ball.v.y": v[1], "ball.w.x": w[0],
              "ball.w.y": w[1]}
    sticks = [t_star] if S > 0.0 and t_star <= t_end else []
    return dict(t_end=t_end, values={k: float(x) for k, x in values.items()}, t_roll=t_star, sticks=sticks,
                dissipated=float(work),
                source=f"closed form (models/bowling.py reference: slides until {t_star:.6g} s, then rolls)")

