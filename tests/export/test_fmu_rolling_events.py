"""FMUs with events for one-sided contacts with rolling rows on bodies with quaternion
coordinates (issue 33 item 1): a ``SphereContact``/``DiskContact(unilateral=True)`` on a
``FreeMotion`` body.

A closed contact holds its normal row and its rolling rows (velocity rows); touch-down is
Newton's restitution on the normal row with the rolling rows held through it (perfectly rough);
``dq/dt`` is the quaternion rate and the state is moved onto the rows through the coordinate
map. Every FMU runs in FMPy as Model Exchange (its CVODE at rtol 1e-14 finding the indicators'
roots) and as Co-Simulation (the FMU's own DOP853 locating them) against ``mbcomp.simulate``
(rtol 1e-12, atol 1e-14): event times to 1e-9 s, states on the output grid to 1e-8, and each
case's physics (closed forms, invariants). The frictionless tumbling bicycle (v = 2 m/s)'s first release is
Painleve-like (closed its rear wheel would pull, open it would fall into the ground): the FMU
fails there with an error naming the contact, on both interfaces.
"""
import re

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.kinematics import rot_axis
from mbcomp.library import (ContactFriction, DiskContact, FixedTranslation, FreeMotion, PlaneContact, RigidBody,
                            SphereContact, World, WorldForce)

from conftest import load_model

import fmusim_tool
import sanitized

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402

G = 9.81
#: the spinning ball: radius (m), mass (kg), speed (m/s) and spin (rad/s) before, drop height (m)
R_BALL, M_BALL, VX, WY, DROP = 0.1, 1.0, 2.0, -30.0, 0.2
J_BALL = 0.4 * M_BALL * R_BALL ** 2


def spinning_ball(e=0.0):
    """A ball (J = 2/5 m r^2) on a free joint (quaternions) dropped from DROP m above the ground
    at VX m/s with backspin WY rad/s, onto a rough one-sided contact with restitution e."""
    md = mbcomp.Model()
    w = md.add("world", World(g=(0, 0, -G)))
    free = md.add("free", FreeMotion(r0=(0, 0, R_BALL + DROP), v0=(VX, 0, 0), w0=(0, WY, 0)))
    ball = md.add("ball", RigidBody(m=M_BALL, I=J_BALL * np.eye(3)))
    c = md.add("ground", SphereContact(r=R_BALL, unilateral=True, restitution=e, open0=True))
    md.connect(w.frame_b, free.frame_a)
    md.connect(free.frame_b, ball.frame_a)
    md.connect(w.frame_b, c.frame_a)
    md.connect(c.frame_b, ball.frame_a)
    return md


#: the disk: radius (m), mass (kg), lean (rad, about the rolling direction x), spin (rad/s), drop (m)
R_DISK, M_DISK, LEAN, SPIN, DISK_DROP = 0.3, 2.0, 0.3, 8.0, 0.05
I_DISK = np.diag([0.25, 0.5, 0.25]) * M_DISK * R_DISK ** 2


def leaning_disk():
    """A thin disk leaning LEAN rad, spinning SPIN rad/s about its axis (y) with its centre at
    rest, dropped DISK_DROP m onto the ground (DiskContact, e = 0): its rim slips at r SPIN
    until it lands."""
    md = mbcomp.Model()
    w = md.add("world", World(g=(0, 0, -G)))
    R = rot_axis(np.array([1.0, 0.0, 0.0]), LEAN)
    rc = R @ np.array([0.0, 0.0, R_DISK])  # the centre from the contact point
    spin = SPIN * R[:, 1]
    free = md.add("free", FreeMotion(r0=rc + np.array([0.0, 0.0, DISK_DROP]), R0=R, w0=R.T @ spin))
    wheel = md.add("wheel", RigidBody(m=M_DISK, I=I_DISK))
    c = md.add("contact", DiskContact(r=R_DISK, unilateral=True, restitution=0.0, open0=True))
    md.connect(w.frame_b, free.frame_a)
    md.connect(free.frame_b, wheel.frame_a)
    md.connect(w.frame_b, c.frame_a)
    md.connect(c.frame_b, wheel.frame_a)
    return md


def overhanging_rod(theta=0.1):
    """A 2 m rod (1 kg) on a free joint with point contacts (frictionless, e = 0) at its left end
    ``a`` (closed at the start) and 1 m along ``b`` (open), its centre of mass 0.5 m beyond b,
    tilted theta rad up: it falls about a until b lands; on a and b its weight would need a
    to pull, so a lets go at b's landing (the bicycle's front wheel lifting the rear one)."""
    md = mbcomp.Model()
    w = md.add("world", World(g=(0, 0, -G)))
    R = rot_axis(np.array([0.0, 1.0, 0.0]), -theta)
    free = md.add("free", FreeMotion(r0=R @ np.array([1.5, 0.0, 0.0]), R0=R))
    rod = md.add("rod", RigidBody(m=1.0, I=np.diag([0.01, 1 / 3, 1 / 3])))
    ends = [md.add(n, FixedTranslation(r=(x, 0, 0))) for n, x in (("ta", -1.5), ("tb", -0.5))]
    contacts = [md.add("a", PlaneContact(unilateral=True, restitution=0.0, open0=False)),
                md.add("b", PlaneContact(unilateral=True, restitution=0.0, open0=True))]
    md.connect(w.frame_b, free.frame_a)
    md.connect(free.frame_b, rod.frame_a)
    for end, c in zip(ends, contacts):
        md.connect(rod.frame_a, end.frame_a)
        md.connect(w.frame_b, c.frame_a)
        md.connect(c.frame_b, end.frame_b)
    return md


def lifted_ball():
    """The ball rolling at VX m/s on the ground (closed at the start, w_y = VX / r) lifted by an
    upward force 2 m g t (N): its normal force m g (1 - 2 t) falls through zero at 0.5 s, where
    the contact lets go with no tangential force left (rolling uniformly needs none)."""
    md = mbcomp.Model()
    w = md.add("world", World(g=(0, 0, -G)))
    free = md.add("free", FreeMotion(r0=(0, 0, R_BALL), v0=(VX, 0, 0), w0=(0, VX / R_BALL, 0)))
    ball = md.add("ball", RigidBody(m=M_BALL, I=J_BALL * np.eye(3)))
    c = md.add("ground", SphereContact(r=R_BALL, unilateral=True, restitution=0.0, open0=False))
    lift = md.add("lift", WorldForce(f=lambda t, frame: (0.0, 0.0, 2.0 * M_BALL * G * t)))
    md.connect(w.frame_b, free.frame_a)
    md.connect(free.frame_b, ball.frame_a)
    md.connect(w.frame_b, c.frame_a)
    md.connect(c.frame_b, ball.frame_a)
    md.connect(lift.frame_b, ball.frame_a)
    return md


def bicycle():
    return load_model("models/bicycle.py").build(v=2.0, roll_rate0=0.5, unilateral=True)


#: the falling bicycle: dropped from H_BIKE m at 5 m/s, nose up PITCH_BIKE rad about the rear contact point
H_BIKE, PITCH_BIKE = 0.05, 0.05


def falling_bicycle():
    return load_model("models/bicycle.py").build(v=5.0, unilateral=True, h0=H_BIKE, pitch0=PITCH_BIKE)


BIKE_STATES = ([f"free.r.{a}" for a in "xyz"] + [f"free.Q.{a}" for a in "wxyz"] + [f"free.{v}.{a}" for v in "vw"
                                                                                      for a in "xyz"]
               + [f"{j}.{v}" for j in ("rear_hub", "steer", "front_hub") for v in ("phi", "w")])


#: (model, end time (s), Co-Simulation output interval (s), components, states compared)
CASES = {
    "ball": (spinning_ball, 0.5, 1e-3, ["ground"], ["free.r.x", "free.r.z", "free.Q.y", "free.v.x", "free.v.z",
                                                     "free.w.y"]),
    "bounce": (lambda: spinning_ball(e=0.5), 1.0, 1e-3, ["ground"], ["free.r.x", "free.r.z", "free.Q.y", "free.v.x",
                                                                      "free.v.z", "free.w.y"]),
    "disk": (leaning_disk, 1.5, 1e-3, ["contact"], [f"free.{v}.{a}" for v, axes in (("r", "xyz"), ("Q", "wxyz"),
                                                                                      ("v", "xyz"), ("w", "xyz"))
                                                     for a in axes]),
    "rod": (overhanging_rod, 0.6, 1e-3, ["a", "b"], ["free.r.x", "free.r.z", "free.Q.w", "free.Q.y", "free.v.z",
                                                      "free.w.y"]),
    "lift": (lifted_ball, 1.0, 1e-3, ["ground"], ["free.r.x", "free.r.z", "free.Q.w", "free.Q.y", "free.v.x",
                                                   "free.v.z", "free.w.y"]),
    "bicycle": (bicycle, 1.2, 1e-3, ["rear_contact", "front_contact"], []),
    "falling": (falling_bicycle, 1.0, 1e-3, ["rear_contact", "front_contact"], BIKE_STATES),
}
#: the bicycle's first release (s; mbcomp.simulate at rtol 1e-12): the frictionless rear wheel lets go
BICYCLE_RELEASE = 0.8941342891


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """``{(case, fmi): path}``, exported once per module (without derivative programs)."""
    root, out = tmp_path_factory.mktemp("fmu_rolling"), {}

    def get(name, fmi="3.0"):
        if (name, fmi) not in out:
            build, t_end, _, _, _ = CASES[name]
            out[name, fmi] = root / f"{name}{fmi[0]}.fmu"
            export_fmu(build(), out[name, fmi], fmi=fmi, stop_time=t_end, derivatives=False)
        return out[name, fmi]
    return get


@pytest.fixture(scope="module")
def reference():
    """``{case: (event times (s), events, result on a 0.01 s grid)}`` of ``mbcomp.simulate``."""
    cache = {}

    def get(name):
        if name not in cache:
            build, t_end, _, _, _ = CASES[name]
            res = mbcomp.simulate(build(), t_end=t_end, rtol=1e-12, atol=1e-14, dt_out=0.01)
            cache[name] = (np.unique([e.time for e in res.events]), res.events, res)
        return cache[name]
    return get


def _run(path, name, kind, extra=(), **kw):
    _, t_end, dt, comps, states = CASES[name]
    me = kind == "ModelExchange"
    return fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=t_end, output_interval=0.01 if me else dt,
                             relative_tolerance=1e-14 if me else 1e-12,
                             output=states + [f"events.{c}.time" for c in comps] + list(extra), **kw)


def _event_times(r, comps):
    """The distinct last-event times the FMU reported for ``comps`` (s), in order."""
    t = np.concatenate([r[f"events.{c}.time"] for c in comps])
    return np.unique(t[t >= 0.0])


def _on_grid(r, res, var):
    """The FMU's ``var`` at mbcomp's output times (after the events FMPy records there)."""
    out = []
    for tk in res.time:
        k = np.flatnonzero(np.abs(r["time"] - tk) < 1e-12)
        out.append(r[var][k[-1]])
    return np.array(out)


def _agrees(r, name, reference, times_too=True):
    """The FMU's event times (1e-9 s) and states on the grid (1e-8) are mbcomp.simulate's."""
    want, _, res = reference(name)
    if times_too:
        got = _event_times(r, CASES[name][3])
        assert len(got) == len(want) >= 1 and np.max(np.abs(got - want)) < 1e-9, (got, want)
    for var in CASES[name][4]:
        assert np.max(np.abs(_on_grid(r, res, var) - res[var])) < 1e-8, var


@pytest.mark.parametrize("fmi", ["3.0", "2.0"])
@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_spinning_ball_lands_rough_and_rolls(kind, fmi, made, reference):
    """The ball lands at sqrt(2 h / g) with a perfectly rough impact: its angular momentum about
    the contact point is kept, v_x+ = (m r v_x + J w_y) / (m r + J / r), and it rolls on
    uniformly (w_y = v_x / r, its indicator, the normal force, its weight m g)."""
    path = made("ball", fmi)
    assert validate_fmu(str(path)) == []
    r = _run(path, "ball", kind, extra=["events.ground.normal"])
    _agrees(r, "ball", reference)
    t_hit = _event_times(r, ["ground"])[0]
    assert abs(t_hit - np.sqrt(2 * DROP / G)) < 1e-9
    v_after = (M_BALL * R_BALL * VX + J_BALL * WY) / (M_BALL * R_BALL + J_BALL / R_BALL)
    after = r["time"] > t_hit + 1e-9
    assert np.allclose(r["free.v.x"][after], v_after, rtol=1e-10, atol=0)
    assert np.allclose(r["free.w.y"][after], v_after / R_BALL, rtol=1e-10, atol=0)  # rolling
    assert np.allclose(r["free.r.z"][after], R_BALL, rtol=0, atol=1e-12)
    assert np.allclose(r["events.ground.normal"][after], M_BALL * G, rtol=1e-9)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_spinning_ball_bounces_rough_then_rests_rolling(kind, made, reference):
    """e = 0.5: the first impact stops the slip, the rebounds keep the rolling speed, and the
    bounces (21 of them) settle at 0.6058 s in the resting mode (the rebound too small to
    rise REST_HEIGHT atol). Model Exchange: every impact where mbcomp has it, to 1e-9 s while
    the ball lands faster than 1e-4 m/s (FMPy's CVODE then finds a touch to its position
    error over the speed: 3e-8 s at the last one, 1.9e-6 m/s); Co-Simulation sees the last
    event of each communication step, each to 1e-9 s."""
    want, events, res = reference("bounce")
    impacts = [e for e in events if e.kind == "impact"]
    assert len(impacts) == 21 and events[-1].kind == "rest"
    r = _run(made("bounce"), "bounce", kind)
    got = _event_times(r, ["ground"])
    if kind == "ModelExchange":
        fast = np.array([abs(e.detail["speed_before"]) > 1e-4 for e in impacts])
        assert len(got) == len(want) == 21 and fast.sum() >= 14
        assert np.max(np.abs(got - want)[fast]) < 1e-9 and np.max(np.abs(got - want)) < 1e-7
    else:
        assert len(got) >= 8 and abs(got[-1] - want[-1]) < 1e-9
        assert np.max(np.min(np.abs(got[:, None] - want[None, :]), axis=1)) < 1e-9
    _agrees(r, "bounce", reference, times_too=False)
    v_roll = (M_BALL * R_BALL * VX + J_BALL * WY) / (M_BALL * R_BALL + J_BALL / R_BALL)
    after = r["time"] > want[-1] + 1e-9
    assert np.allclose(r["free.v.x"][after], v_roll, rtol=1e-10, atol=0)
    assert np.allclose(r["free.r.z"][after], R_BALL, rtol=0, atol=1e-12)
    assert np.all(np.abs(r["free.v.z"][after]) < 1e-12)


def _disk_invariants(r, k):
    """``(gap (m), slip speed (m/s), angular momentum about the contact point (kg m^2/s))`` of the
    disk at the rows ``k`` of an FMU result."""
    out = []
    for i in np.atleast_1d(k):
        Q = np.array([r[f"free.Q.{a}"][i] for a in "wxyz"])
        Q /= np.linalg.norm(Q)
        Rm = _quat_matrix(Q)
        c = np.array([r[f"free.r.{a}"][i] for a in "xyz"])
        v = np.array([r[f"free.v.{a}"][i] for a in "xyz"])
        w = Rm @ np.array([r[f"free.w.{a}"][i] for a in "xyz"])  # the body's axes -> the world's
        axis, n = Rm[:, 1], np.array([0.0, 0.0, 1.0])
        lng = np.cross(axis, n) / np.linalg.norm(np.cross(axis, n))
        P = c + R_DISK * np.cross(axis, lng)  # the rim point nearest the ground
        slip = v + np.cross(w, P - c)
        H = Rm @ I_DISK @ Rm.T @ w + M_DISK * np.cross(c - P, v)
        out.append((P[2], np.linalg.norm(slip - (slip @ n) * n), H))
    return out


def _quat_matrix(Q):
    w, x, y, z = Q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_leaning_spinning_disk_lands_rough_and_rolls(kind, made, reference):
    """The disk's touch-down (its two rolling rows held through the impact) keeps its angular
    momentum about the contact point (the impulse acts there: to 1e-10 of it); it then rolls
    without slip on the ground (the rim point's slip below 1e-9 m/s, its height 0) as
    mbcomp.simulate has it."""
    r = _run(made("disk"), "disk", kind)
    _agrees(r, "disk", reference)
    t_hit = _event_times(r, ["contact"])[0]
    at = np.flatnonzero(np.abs(r["time"] - t_hit) < 1e-12)
    if kind == "ModelExchange":  # FMPy records the state before and after the event
        assert len(at) == 2
        (_, slip0, h0), (gap1, slip1, h1) = _disk_invariants(r, at)
        assert slip0 > 0.1 and slip1 < 1e-9 and abs(gap1) < 1e-12
        assert np.linalg.norm(h1 - h0) < 1e-10 * np.linalg.norm(h0)
    rolling = np.flatnonzero(r["time"] > t_hit + 1e-9)
    gap, slip, _ = zip(*_disk_invariants(r, rolling))
    assert np.max(np.abs(gap)) < 1e-10 and np.max(slip) < 1e-8


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_landing_that_unloads_a_closed_contact_opens_it(kind, made, reference):
    """The overhanging rod: b lands (e = 0) at 0.187 s, and with a and b closed its weight would
    need a to pull -- a is opened there (a release, the most pulling closed contact first;
    kept closed, a would hold the rod down), then the rod turns about b with a rising."""
    want, events, _ = reference("rod")
    assert [(e.component, e.kind) for e in events] == [("b", "impact"), ("b", "engage"), ("a", "release")]
    r = _run(made("rod"), "rod", kind)
    assert r["events.a.time"][-1] == r["events.b.time"][-1]  # the same instant
    _agrees(r, "rod", reference)
    after = r["time"] > want[-1] + 1e-9
    # the rod turns about y by phi: its end a, 1.5 m behind the centre, at z + 1.5 sin(phi)
    qw, qy = r["free.Q.w"], r["free.Q.y"]
    a_height = r["free.r.z"] + 3.0 * qw * qy / (qw * qw + qy * qy)
    assert abs(a_height[0]) < 1e-12 and np.all(np.diff(a_height[after]) > 0.0)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_rolling_ball_lifted_off_lets_go_where_its_normal_force_vanishes(kind, made, reference):
    """The lifted ball lets go at 0.5 s (its normal force m g (1 - 2 t); FMPy's CVODE lands on
    that linear root exactly, a push of 0.0: FMI's domain z <= 0 releases it), rises as
    z = r + g (t - 0.5)^3 / 3 and keeps its speed and spin: a rolling contact's release without a
    tangential force is no Painleve case."""
    r = _run(made("lift"), "lift", kind)
    _agrees(r, "lift", reference)
    assert _event_times(r, ["ground"]) == pytest.approx([0.5], abs=1e-12)
    t, after = r["time"], r["time"] > 0.5
    assert np.allclose(r["free.r.z"][after], R_BALL + G * (t[after] - 0.5) ** 3 / 3, rtol=0, atol=1e-12)
    assert np.allclose(r["free.v.x"], VX, rtol=1e-12) and np.allclose(r["free.w.y"], VX / R_BALL, rtol=1e-12)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_the_frictionless_bicycle_fails_where_its_rear_wheel_lets_go(kind, made):
    """At 0.894134289 s the rear wheel's normal force falls through zero with its lateral force
    (about 34 N) left: closed it would pull, open it would fall into the ground (perfectly rough
    rolling rows cannot let go). The FMU stops there with an error naming the contact and the fix,
    on both interfaces, and never runs on."""
    logged = []

    def log(env, status, category, message):
        logged.append((int(status), message.decode()))

    with pytest.raises(Exception, match="failed with status 3"):
        _run(made("bicycle"), "bicycle", kind, logger=log)
    errors = [m for s, m in logged if s >= 3]
    assert len(errors) == 1
    # the words of mbcomp.simulate's error (hybrid/events.py), the time to 12 digits
    m = re.match(r"rear_contact: let go at t=([0-9.]+) s, but open it accelerates into what it touches "
                 r"\((-[0-9.e+-]+) m/s\^2\) while closed it would pull: .* -> give the contact Coulomb friction "
                 r"\(friction=ContactFriction\(mu_s, mu_k\)\) so it slides before it lifts off$", errors[0])
    assert m, errors[0]
    assert float(m.group(2)) < -0.1
    # where mbcomp.simulate has the release (Model Exchange: where FMPy's CVODE found the root)
    assert abs(float(m.group(1)) - BICYCLE_RELEASE) < 1e-9


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_the_falling_bicycle_lands_rear_wheel_first_and_rolls_on(kind, made, reference):
    """The Whipple bicycle dropped 5 cm at 5 m/s, nose up 0.05 rad: quaternions, two wheels
    with rolling rows, two rough landings. The rear wheel lands at sqrt(2 (h0 - r_R (1 - cos
    0.05)) / g), the front one at 0.1379 s, both where mbcomp.simulate has them (1e-9 s), every
    state on the grid to 1e-8; then the bicycle rolls on both wheels (their indicators, the
    normal forces, positive)."""
    want, events, _ = reference("falling")
    assert [(e.component, e.kind) for e in events] == [("rear_contact", "impact"), ("rear_contact", "engage"),
                                                       ("front_contact", "impact"), ("front_contact", "engage")]
    r = _run(made("falling"), "falling", kind, extra=["events.rear_contact.normal", "events.front_contact.normal"])
    _agrees(r, "falling", reference)
    p = load_model("models/bicycle.py").parameters()
    t_rear = np.sqrt(2 * (H_BIKE - p["rR"] * (1 - np.cos(PITCH_BIKE))) / p["g"])
    assert abs(r["events.rear_contact.time"][-1] - t_rear) < 1e-9
    after = r["time"] > want[-1] + 1e-9
    assert np.all(r["events.rear_contact.normal"][after] > 0) and np.all(r["events.front_contact.normal"][after] > 0)


def test_the_falling_bicycle_in_fmusim_too(made, reference):
    """The second importer, Model Exchange (its CVODE at 1e-14) and Co-Simulation: both
    landings where mbcomp.simulate has them (1e-9 s) and the end state to 1e-8."""
    exe, why = fmusim_tool.fmusim()
    if exe is None:
        pytest.skip(why)
    want, _, res = reference("falling")
    for interface, tol in (("me", 1e-14), ("cs", 1e-12)):
        r = fmusim_tool.run(made("falling"), interface, 1.0, ["events.rear_contact.time", "events.front_contact.time"]
                            + BIKE_STATES, tolerance=tol, points=100)
        got = _event_times(r, ["rear_contact", "front_contact"])
        assert len(got) == len(want) == 2 and np.max(np.abs(got - want)) < 1e-9, interface
        for var in BIKE_STATES:
            assert abs(r[var][-1] - res[var][-1]) < 1e-8, (interface, var)


def test_a_contact_with_friction_is_still_refused_naming_it(tmp_path):
    """A rolling contact with Coulomb friction (stick/slip) has no FMU events yet: the export
    names the contact, what it has and the fix, and writes nothing."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    b = m.add("ball", RigidBody(m=1.0, I=np.eye(3) * 0.004), free=True)
    c = m.add("ground", SphereContact(r=0.1, unilateral=True, friction=ContactFriction(0.5, 0.3)))
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, b.frame_a)
    with pytest.raises(ValueError, match=r"cannot export ground: .*a contact with friction, "
                                         r"friction=ContactFriction\(\.\.\.\).* -> export without it"):
        export_fmu(m, tmp_path / "rough.fmu", derivatives=False)
    assert not (tmp_path / "rough.fmu").exists()


def test_the_ball_in_fmusim_too(made, reference):
    """The Reference-FMUs' fmusim (the second importer), Model Exchange (its CVODE at 1e-14)
    and Co-Simulation: the touch-down where mbcomp.simulate has it (1e-9 s)."""
    exe, why = fmusim_tool.fmusim()
    if exe is None:
        pytest.skip(why)
    want = reference("ball")[0]
    for interface, tol in (("me", 1e-14), ("cs", 1e-12)):
        r = fmusim_tool.run(made("ball"), interface, 0.5, ["events.ground.time", "free.v.x"], tolerance=tol, points=500)
        got = _event_times(r, ["ground"])
        assert len(got) == len(want) == 1 and abs(got[0] - want[0]) < 1e-9, interface
        assert r["free.v.x"][-1] == pytest.approx(0.5714285714285714, rel=1e-10), interface


#: the FMU's own C (its model file includes fmu_core.c, fmu_events.c, fmi3.c) driven through FMI 3.0:
#: Co-Simulation steps of 1 ms to t_end, then Model Exchange by explicit Euler (0.1 ms) entering Event
#: Mode at every indicator's sign change; prints each run's end and the last state
HARNESS = r"""
#include "MODEL_C"
static int errors;
static void logger(void *env, fmi3Status s, fmi3String cat, fmi3String msg)
{ (void)env; (void)cat; if (s >= fmi3Error) { errors++; fprintf(stderr, "[FMU] %s\n", msg); } }
int main(int argc, char **argv)
{
    double T = argc > 1 ? atof(argv[1]) : 1.0, H = 1e-3, t = 0.0, x[NXS + 1], dx[NXS + 1], z[MB_NZ + 1], z0[MB_NZ + 1];
    fmi3Boolean e1, e2, e3, up, term, nom, vals, nd; fmi3Float64 last, next;
    fmi3Status st = fmi3OK;
    int i, events = 0;
    fmi3Instance c = fmi3InstantiateCoSimulation("h", GUID, NULL, 0, 0, 0, 0, NULL, 0, NULL, logger, NULL);
    if (!c || fmi3EnterInitializationMode(c, 1, 1e-12, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) return 2;
    for (; t < T - 1e-12 && st == fmi3OK; t += H) st = fmi3DoStep(c, t, H, 1, &e1, &e2, &e3, &last);
    printf("cs %d %.17g", (int)st, t);
    for (i = 0; i < NXS; i++) printf(" %.17g", ((Inst *)c)->y[i]);
    fmi3FreeInstance(c);
    c = fmi3InstantiateModelExchange("m", GUID, NULL, 0, 0, NULL, logger);
    if (!c || fmi3EnterInitializationMode(c, 1, 1e-12, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) return 3;
    st = fmi3UpdateDiscreteStates(c, &up, &term, &nom, &vals, &nd, &next);
    if (!st) st = fmi3EnterContinuousTimeMode(c);
    if (!st) st = fmi3GetEventIndicators(c, z0, MB_NZ);
    for (t = 0.0; t < T - 1e-12 && st == fmi3OK;) {
        st = fmi3GetContinuousStates(c, x, NXS);
        if (!st) st = fmi3GetContinuousStateDerivatives(c, dx, NXS);
        for (i = 0; i < NXS; i++) x[i] += 0.1 * H * dx[i];
        t += 0.1 * H;
        if (!st) st = fmi3SetTime(c, t);
        if (!st) st = fmi3SetContinuousStates(c, x, NXS);
        if (!st) st = fmi3GetEventIndicators(c, z, MB_NZ);
        for (i = 0; i < MB_NZ && !st; i++)
            if ((z0[i] > 0.0) != (z[i] > 0.0)) {
                events++;
                st = fmi3EnterEventMode(c);
                if (!st) st = fmi3UpdateDiscreteStates(c, &up, &term, &nom, &vals, &nd, &next);
                if (!st) st = fmi3EnterContinuousTimeMode(c);
                if (!st) st = fmi3GetEventIndicators(c, z, MB_NZ);
                break;
            }
        memcpy(z0, z, sizeof z);
    }
    printf("\nme %d %.17g %d %d\n", (int)st, t, events, errors);
    fmi3FreeInstance(c);
    return 0;
}
"""


def test_the_events_c_is_clean_under_asan_and_ubsan(made, tmp_path):
    """The rough bouncing ball's FMU C (rolling rows, quaternions, impacts, the rest, the
    settling after each event) built with AddressSanitizer and UBSan: Co-Simulation to 1 s ends
    resting and rolling (z = r, v_x the rough landing's closed form), Model Exchange under an
    explicit Euler importer acts on its events; no error, no sanitizer report, no warning."""
    run = sanitized.run(sanitized.build(made("bounce"), HARNESS, tmp_path, quiet=("fmu_events", "mbrt_mech")), 1.0)
    assert run.returncode == 0, run.stderr[-3000:]
    cs, me = (line.split() for line in run.stdout.strip().splitlines())
    y = np.array(cs[3:], float)  # [r, Q, v, w]
    assert cs[:2] == ["cs", "0"] and y[2] == pytest.approx(R_BALL, abs=1e-12) and abs(y[9]) < 1e-12
    assert y[7] == pytest.approx((M_BALL * R_BALL * VX + J_BALL * WY) / (M_BALL * R_BALL + J_BALL / R_BALL), rel=1e-10)
    assert me[:2] == ["me", "0"] and int(me[3]) >= 21 and me[4] == "0"
