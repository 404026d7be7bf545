"""The Whipple bicycle of the Meijaard et al. (2007) benchmark, composed from components.

J.P. Meijaard, J.M. Papadopoulos, A. Ruina, A.L. Schwab, *Linearized dynamics equations for
the balance and steer of a bicycle: a benchmark and review*, Proc. R. Soc. A 463 (2007)
1955-1982. Parameters: Table 1 of the paper, in ``models/data/bicycle_parameters.json`` (a
copy of ``shared/reference/bicycle_parameters.json``).

Four rigid bodies in the paper's axes (x forward, y to the right, z down; origin at the rear
contact point in the upright reference configuration; gravity +g along z)::

    world --free-------> rear_frame B (rider rigidly attached), origin at the rear hub
    rear_frame --rear_hub (hinge about y)--> rear_wheel R
    rear_frame --steer_point--> steer (hinge about the steer axis, tilted back by lambda)
                                  --> fork H --front_axle--> front_hub (hinge about y) --> front_wheel F
    world <--rear_contact-- rear_wheel,   world <--front_contact-- front_wheel   (DiskContact)

The steer axis meets the ground a trail ``c`` ahead of the front contact point, at
``(w + c, 0, 0)``; its downward direction is ``(sin lambda, 0, cos lambda)``, so a positive
steer angle turns the front wheel to the right, and a positive roll (rotation of the rear
frame about x) leans the bicycle to the right, as in the paper. The knife-edge wheels roll
without slip on the ground plane z = 0 (normal ``-z``, pointing up to the wheels): each
contact adds one holonomic and two nonholonomic rows, so the 9 speeds (6 of the free rear
frame and 3 hinges) leave 7 configuration DOF and 3 motion DOF (roll, steer, forward speed).
No friction in the hinges, no rider control: energy is conserved.

The start is exact: the bicycle upright (or rigidly rolled by ``roll0`` about the ground line
through both contact points, which keeps both wheels on the ground), moving straight at
``v`` with a roll rate ``roll_rate0`` about that line; every start value is fixed.

Outputs: ``roll`` (rad; asin of the rear frame's y axis' z component, the paper's roll angle
for small pitch), ``steer`` (rad, the steer hinge angle), ``speed`` (m/s, horizontal speed of
the rear hub), ``yaw`` (rad, heading of the rear frame's x axis), plus the contact forces
``rear_contact.N``/``.F_long``/``.F_lat`` and ``front_contact.*``.

Run::

    mbcomp info models/bicycle.py --graph bicycle_topology.svg
    mbcomp simulate models/bicycle.py --animate bike.html        # pushed: SIMULATE_PARAMS
    mbcomp simulate models/bicycle.py -p v=5 -p roll0=0.05 --out bicycle.csv --plot bicycle.png
    mbcomp simulate models/bicycle.py -p v=3 -p roll0=0.05
    mbcomp simulate models/bicycle.py -p h0=0.05 -p pitch0=0.05      # the falling bicycle

The benchmark's linear analysis gives self-stability for 4.29 < v < 6.02 m/s (weave and
capsize speeds, the paper's Table 2); see ``tests/test_bicycle.py`` for what the
nonlinear simulation shows at 3 and 5 m/s.
"""
import json
import pathlib

import numpy as np

from mbcomp import Box, Cylinder, Model
from mbcomp.kinematics import rot_axis
from mbcomp.library import DiskContact, FixedTranslation, FreeMotion, Revolute, RigidBody, World
from mbcomp.modeling.shapes import z_to

SIMULATION = dict(t_end=10.0, rtol=1e-8, atol=1e-10, backend="python", n_out=501)
#: what ``mbcomp simulate models/bicycle.py`` shows unless -p says otherwise: a push of 0.5 rad/s
#: in roll, so the self-stable bicycle leans, weaves and rights itself (build() itself starts
#: upright, the operating point that linearization and ``mbcomp stability`` need), on wheels
#: that may leave the ground. At ``-p v=2`` it falls over and the run stops at the first lift-off,
#: naming the wheel: rolling rows without friction cannot let go; ``-p h0=0.05 -p pitch0=0.05``
#: drops it (``res.events``: the rear wheel lands, then the front one)
SIMULATE_PARAMS = dict(roll_rate0=0.5, unilateral=True)

DATA = pathlib.Path(__file__).resolve().parent / "data" / "bicycle_parameters.json"


def _number(text):
    """A Table 1 entry: a decimal or ``pi/k``."""
    text = str(text).strip()
    if text.startswith("pi/"):
        return np.pi / float(text[3:])
    return float(text)


def parameters(path=DATA):
    """The benchmark parameters (SI) as a flat dict: ``w, c, lam, g, rR, mR, IRxx, IRyy, xB,
    zB, mB, IBxx, IByy, IBzz, IBxz, xH, zH, mH, IHxx, IHyy, IHzz, IHxz, rF, mF, IFxx, IFyy``."""
    raw = json.loads(pathlib.Path(path).read_text())["parameters"]
    p = {"w": raw["w_m"], "c": raw["c_m"], "lam": raw["lambda_rad"], "g": raw["g_N_per_kg"]}
    for group in ("rear_wheel_R", "rear_body_B", "front_assembly_H", "front_wheel_F"):
        for key, val in raw[group].items():
            p[key.split("_")[0]] = val
    return {k: _number(v) for k, v in p.items()}


def _inertia(xx, yy, zz, xz=0.0):
    return np.array([[xx, 0.0, xz], [0.0, yy, 0.0], [xz, 0.0, zz]])


def _tube(a, b, radius=0.02, color="steelblue"):
    """A cylinder from point ``a`` to point ``b`` (m, the body's frame_a)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return Cylinder(radius, float(np.linalg.norm(b - a)), r=(a + b) / 2, R=z_to(b - a), color=color)


def _head(p, height):
    """The point of the steer axis ``height`` (m) above the ground, from the rear hub (frame_a
    of the rear frame: x forward, z down)."""
    lam = p["lam"]
    return np.array([p["w"] + p["c"], 0.0, p["rR"]]) - height / np.cos(lam) * np.array([np.sin(lam), 0.0, np.cos(lam)])


def _rear_frame_shapes(p):
    """The rear frame drawn as a frame, not as the default rods: chain stay from the hub to the
    bottom bracket, seat and down tubes, top tube to the head tube, and the rider as a block
    at the rear body's centre of mass (the rider is rigidly part of it in the benchmark)."""
    rR = p["rR"]
    bracket, seat = np.array([0.45, 0.0, 0.0]), np.array([0.35, 0.0, -0.55])
    head_low, head_top = _head(p, 0.6), _head(p, 0.85)
    rider = np.array([p["xB"], 0.0, p["zB"] + rR])
    return [_tube((0, 0, 0), bracket), _tube((0, 0, 0), seat), _tube(bracket, seat), _tube(bracket, head_low),
            _tube(seat, head_top), Box((0.3, 0.35, 0.55), r=rider, color="orange"),
            _tube(seat, rider + (0, 0, 0.25), radius=0.05, color="orange")]


def _fork_shapes(p):
    """The front assembly: fork blades from the front axle to the crown, the steerer up the
    steer axis, the handlebar across it (frame_a of the fork is the steer axis at the ground)."""
    lam, c, rF = p["lam"], p["c"], p["rF"]
    up = -np.array([np.sin(lam), 0.0, np.cos(lam)])
    axle, crown, top = np.array([-c, 0.0, -rF]), up * (rF + 0.15) / np.cos(lam), up * 0.95 / np.cos(lam)
    return [_tube(axle + (0, 0.04, 0), crown, color="red"), _tube(axle - (0, 0.04, 0), crown, color="red"),
            _tube(crown, top, color="red"), _tube(top + (-0.1, -0.25, 0), top + (-0.1, 0.25, 0), color="black")]


def build(v=5.0, roll0=0.0, roll_rate0=0.0, unilateral=False, h0=0.0, pitch0=0.0, **overrides):
    """The benchmark bicycle moving straight at ``v`` (m/s, forward) with roll ``roll0``
    (rad) and roll rate ``roll_rate0`` (rad/s); ``overrides`` replace Table 1 entries by
    name (e.g. ``c=0.0``). ``unilateral``: the wheels lift off where their normal force would
    pull and land again (plastic impacts, ``restitution = 0``; :class:`DiskContact`'s
    ``unilateral``); the default keeps the benchmark's bilateral contacts (linearization
    needs them). Without friction at the wheels a lift-off is a contradiction (the normal
    force vanishes with a tangential one left), so ``v=2`` with a roll rate fails at its
    first lift-off, naming the wheel. ``h0`` (m, with ``unilateral``): the falling bicycle,
    dropped from ``h0`` above the ground with its nose pitched up by ``pitch0`` (rad, about
    the rear contact point) so the rear wheel lands first, the front one after it; both
    landings are perfectly rough (the wheels roll at once)."""
    p = parameters()
    unknown = sorted(set(overrides) - set(p))
    if unknown:
        raise ValueError(f"bicycle: no parameter {', '.join(unknown)}; Table 1 names are {', '.join(sorted(p))}")
    p.update({k: float(val) for k, val in overrides.items()})
    w, c, lam, rR, rF = p["w"], p["c"], p["lam"], p["rR"], p["rF"]
    v, roll0, roll_rate0 = float(v), float(roll0), float(roll_rate0)

    # rigid roll about the ground line (the x axis) keeps both contact points where they are
    if h0 < 0.0 or (h0 > 0.0 and not unilateral) or (pitch0 and not h0 > 0.0):
        raise ValueError(f"bicycle: h0={h0!r}, pitch0={pitch0!r}: a drop needs h0 > 0 m and unilateral=True (its "
                         "wheels start in the air); pitch0 only with a drop")
    R0 = rot_axis((0.0, 1.0, 0.0), float(pitch0)) @ rot_axis((1.0, 0.0, 0.0), roll0)
    hub = R0 @ np.array([0.0, 0.0, -rR]) - np.array([0.0, 0.0, float(h0)])
    w_roll = np.array([roll_rate0, 0.0, 0.0])

    m = Model()
    world = m.add("world", World(g=(0.0, 0.0, p["g"])))
    free = m.add("free", FreeMotion(r0=hub, R0=R0, v0=np.array([v, 0.0, 0.0]) + np.cross(w_roll, hub),
                                    w0=R0.T @ w_roll))
    rear_frame = m.add("rear_frame", RigidBody(m=p["mB"], r_cm=(p["xB"], 0.0, p["zB"] + rR),
                                               I=_inertia(p["IBxx"], p["IByy"], p["IBzz"], p["IBxz"]),
                                               shape=_rear_frame_shapes(p)))
    rear_hub = m.add("rear_hub", Revolute(n=(0, 1, 0), phi0=0.0, w0=-v / rR))
    rear_wheel = m.add("rear_wheel", RigidBody(m=p["mR"], I=_inertia(p["IRxx"], p["IRyy"], p["IRxx"])))
    steer_point = m.add("steer_point", FixedTranslation(r=(w + c, 0.0, rR)))
    steer = m.add("steer", Revolute(n=(np.sin(lam), 0.0, np.cos(lam)), phi0=0.0, w0=0.0, visible=False))  # the fork shows it
    fork = m.add("fork", RigidBody(m=p["mH"], r_cm=(p["xH"] - w - c, 0.0, p["zH"]),
                                   I=_inertia(p["IHxx"], p["IHyy"], p["IHzz"], p["IHxz"]), shape=_fork_shapes(p)))
    front_axle = m.add("front_axle", FixedTranslation(r=(-c, 0.0, -rF)))
    front_hub = m.add("front_hub", Revolute(n=(0, 1, 0), phi0=0.0, w0=-v / rF))
    front_wheel = m.add("front_wheel", RigidBody(m=p["mF"], I=_inertia(p["IFxx"], p["IFyy"], p["IFxx"])))
    ground_normal = (0.0, 0.0, -1.0)
    one_sided = dict(unilateral=bool(unilateral), restitution=0.0, open0=bool(h0 > 0.0))
    rear_contact = m.add("rear_contact", DiskContact(r=rR, n=ground_normal, axis=(0, 1, 0), **one_sided))
    front_contact = m.add("front_contact", DiskContact(r=rF, n=ground_normal, axis=(0, 1, 0), **one_sided))

    m.connect(world.frame_b, free.frame_a)
    m.connect(free.frame_b, rear_frame.frame_a)
    m.connect(rear_frame.frame_a, rear_hub.frame_a)
    m.connect(rear_hub.frame_b, rear_wheel.frame_a)
    m.connect(rear_frame.frame_a, steer_point.frame_a)
    m.connect(steer_point.frame_b, steer.frame_a)
    m.connect(steer.frame_b, fork.frame_a)
    m.connect(steer.frame_b, front_axle.frame_a)
    m.connect(front_axle.frame_b, front_hub.frame_a)
    m.connect(front_hub.frame_b, front_wheel.frame_a)
    m.connect(world.frame_b, rear_contact.frame_a)
    m.connect(rear_wheel.frame_a, rear_contact.frame_b)
    m.connect(world.frame_b, front_contact.frame_a)
    m.connect(front_wheel.frame_a, front_contact.frame_b)

    m.alias("steer_angle", "steer.phi")
    m.output("roll", lambda qw, qx, qy, qz: np.arcsin(np.clip(2 * (qy * qz + qw * qx), -1, 1)),
             "rear_frame.Q.w", "rear_frame.Q.x", "rear_frame.Q.y", "rear_frame.Q.z")
    m.output("yaw", lambda qw, qx, qy, qz: np.arctan2(2 * (qx * qy + qw * qz), 1 - 2 * (qy * qy + qz * qz)),
             "rear_frame.Q.w", "rear_frame.Q.x", "rear_frame.Q.y", "rear_frame.Q.z")
    m.output("speed", lambda vx, vy: np.hypot(vx, vy), "rear_frame.v.x", "rear_frame.v.y")
    return m
