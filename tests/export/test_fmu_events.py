"""FMUs with events (issue 33 item 1): unilateral contacts, rigid end stops and stick/slip
friction exported with
event indicators, Model Exchange's Event Mode acting on them and Co-Simulation locating them
on its own DOP853's dense output.

Every FMU is validated by FMPy and run by FMPy as Model Exchange (FMPy's CVODE finds the
indicators' roots, the FMU acts in Event Mode) and as Co-Simulation (the FMU's own events);
its events and states must be ``mbcomp.simulate``'s (rtol 1e-12, atol 1e-14): event times
to 1e-9 s, states on the output grid to 1e-8. The FMU reports each component's last event
time as an output (``events.<component>.time``), so the event times of both interfaces are
read exactly, not from the output grid.

Model Exchange's event times are bound by FMPy's CVODE, not by the FMU: the bouncing ball's
32nd impact is 3e-8 s early at CVODE's rtol 1e-12 and 3e-10 s at 1e-14 (the error scales
with the tolerance), hence these runs at 1e-14.
"""
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import load_model, stop_pendulum

import fmusim_tool

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402

VERSIONS = ["3.0", "2.0"]
#: (model, end time (s), Co-Simulation output interval (s): shorter than the events' spacing)
MODELS = {
    "ball": (lambda: load_model("models/bouncing_ball.py").build(), 4.3, 2e-4),
    "pendulum": (lambda: stop_pendulum(), 3.0, 1e-3),
    "resting": (lambda: stop_pendulum(limits=(0.3, 3.0), e=0.5, phi0=1.2), 2.5, 1e-4),
    "door": (lambda: load_model("models/door.py").build(), 8.0, 1e-3),
    "block": (lambda: block(), 5.0, 1e-3),
    "shaker": (lambda: shaker(), 8.0, 1e-3),
}
COMPONENT = {"ball": "ground", "pendulum": "hinge", "resting": "hinge", "door": "hinge", "block": "s", "shaker": "s"}
STATES = {"ball": ["free.r.z", "free.v.z"], "pendulum": ["hinge.phi", "hinge.w"], "resting": ["hinge.phi", "hinge.w"],
          "door": ["hinge.phi", "hinge.w"], "block": ["s.s", "s.v"], "shaker": ["s.s", "s.v"]}


def block(mu_s=0.3, mu_k=0.25, k=20.0, v0=2.0):
    """A 2 kg block on a spring (k N/m) sliding on Coulomb friction (normal force its weight)
    from s = 0 at v0 (m/s): it sticks at its turning point, breaks back at once (the spring
    beats mu_s m g), and sticks for good when the spring no longer can."""
    from mbcomp.library import Force, PointMass, Prismatic, SlidingFriction, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.0, v0=v0, friction=SlidingFriction(mu_s, mu_k, normal=2.0 * 9.81)))
    b = m.add("b", PointMass(m=2.0))
    f = m.add("pull", Force(f=lambda t, s, v: -k * s))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    m.connect(s.axis, f.flange_b)
    return m


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """``{(model, fmi): path}``, exported once per module."""
    root, out = tmp_path_factory.mktemp("fmu_events"), {}

    def get(name, fmi):
        if (name, fmi) not in out:
            build, t_end, _ = MODELS[name]
            out[name, fmi] = root / f"{name}{fmi[0]}.fmu"
            export_fmu(build(), out[name, fmi], fmi=fmi, stop_time=t_end)
        return out[name, fmi]
    return get


@pytest.fixture(scope="module")
def reference():
    """``{model: (event times (s), kinds, result on a 0.01 s grid)}`` of ``mbcomp.simulate``."""
    cache = {}

    def get(name):
        if name not in cache:
            build, t_end, _ = MODELS[name]
            res = mbcomp.simulate(build(), t_end=t_end, rtol=1e-12, atol=1e-14, dt_out=0.01)
            cache[name] = (np.array([e.time for e in res.events]), [e.kind for e in res.events], res)
        return cache[name]
    return get


def _run(path, name, kind):
    _, t_end, dt = MODELS[name]
    comp = COMPONENT[name]
    me = kind == "ModelExchange"
    return fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=t_end, output_interval=0.01 if me else dt,
                             relative_tolerance=1e-14 if me else 1e-12,
                             output=STATES[name] + [f"events.{comp}.time", f"events.{comp}.{_indicator(name)}"])


def shaker():
    """A 2 kg slider between stops at -1 and 1 m with e = 0, pushed by 10 cos(t) N: it lands
    on a stop and stays, released when the push turns (its indicator, the stop's push, falls
    through zero at t = pi/2 + k pi), and lands on the other."""
    from mbcomp.library import Force, PointMass, Prismatic, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.5, v0=0.0, limits=(-1.0, 1.0), restitution=0.0))
    b = m.add("b", PointMass(m=2.0))
    f = m.add("push", Force(f=lambda t, s, v: 10.0 * np.cos(t)))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    m.connect(s.axis, f.flange_b)
    return m


def _indicator(name):
    return {"ball": "normal", "block": "forward", "shaker": "hi"}.get(name, "lo")


def _event_times(r, comp):
    """The distinct last-event times the FMU reported (s), in order."""
    t = r[f"events.{comp}.time"]
    return np.unique(t[t >= 0.0])


def _on_grid(r, res, var):
    """The FMU's ``var`` at mbcomp's 0.01 s output times (the event points FMPy adds dropped)."""
    t = r["time"]
    out = []
    for tk in res.time:
        k = np.flatnonzero(np.abs(t - tk) < 1e-12)
        out.append(r[var][k[-1]])
    return np.array(out)


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("name", ["ball", "pendulum", "door", "block", "shaker"])
def test_events_and_states_are_mbcomps(name, kind, fmi, made, reference):
    """The bouncing ball's 32 impacts and its Zeno rest at 4.06 s (mbcomp's CHATTER rule), the
    pendulum's rebounds on its lower stop, the door's on both of its stops, the block's stick,
    break-away and final stick, the shaker's landings and releases at pi/2 + k pi: each event where mbcomp.simulate has it (1e-9 s), the states
    on the grid to 1e-8."""
    path = made(name, fmi)
    assert validate_fmu(str(path)) == []
    times, kinds, res = reference(name)
    r = _run(path, name, kind)
    got = _event_times(r, COMPONENT[name])
    want = np.unique(times)  # an impact and the rest it ends in share their time
    assert len(got) == len(want) >= 2
    assert np.max(np.abs(got - want)) < 1e-9
    for var in STATES[name]:
        assert np.max(np.abs(_on_grid(r, res, var) - res[var])) < 1e-8, var
    if name == "ball":
        assert kinds[-1] == "rest" and kinds.count("impact") == 32
        after = r["time"] > want[-1] + 1e-9
        assert np.all(r["free.r.z"][after] == pytest.approx(0.1, abs=1e-12))  # on the ground: z = r
        assert np.all(np.abs(r["free.v.z"][after]) < 1e-12)
        assert np.all(r["events.ground.normal"][after] == pytest.approx(0.5 * 9.81, rel=1e-9))  # its weight, N
    if name == "shaker":  # released where the push 10 cos(t) turns
        assert got[[1, 3, 5]] == pytest.approx(np.pi / 2 + np.pi * np.arange(3), abs=1e-9)
    if name == "block":  # stuck for good: the spring's pull k s (N) within the static limit, the speed 0
        after = r["time"] > want[-1] + 1e-9
        assert np.all(r["s.v"][after] == 0.0) and abs(20.0 * r["s.s"][-1]) < 0.3 * 2.0 * 9.81
        # the stuck row pushes k s against the spring: the margins F_s + k s and F_s - k s (N)
        assert np.allclose(r["events.s.forward"][after], 0.3 * 2 * 9.81 + 20.0 * r["s.s"][after], rtol=1e-9)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_ball_started_on_the_ground_rests_there(kind, tmp_path):
    """Open at the start with a zero gap and no speed (mbcomp's Events.start): it engages at
    t = 0 and stays, its indicator its weight (N)."""
    m = load_model("models/bouncing_ball.py").build(h0=0.0)
    assert [e.kind for e in mbcomp.simulate(m, t_end=1.0).events] == ["engage"]
    export_fmu(m, tmp_path / "ground.fmu")
    r = fmpy.simulate_fmu(str(tmp_path / "ground.fmu"), fmi_type=kind, stop_time=1.0,
                          output=["free.r.z", "events.ground.time", "events.ground.normal"])
    # (Co-Simulation acts on the start's events in its first step: the time is 0 from then on)
    assert np.all(r["free.r.z"] == pytest.approx(0.1, abs=1e-14)) and np.all(r["events.ground.time"][1:] == 0.0)
    assert np.all(r["events.ground.normal"][1:] == pytest.approx(0.5 * 9.81, rel=1e-12))


@pytest.mark.parametrize("fmi", VERSIONS)
def test_the_closed_form_bounce_times(fmi, made):
    """The ball's impacts at ``t0 + 2 t0 e (1 - e^k) / (1 - e)``, ``t0 = sqrt(2 h0 / g)``; in
    flight the indicator is the gap ``z - r`` (m)."""
    r = _run(made("ball", fmi), "ball", "CoSimulation")
    t0, e = np.sqrt(2 * 1.0 / 9.81), 0.8
    k = np.arange(32)
    assert np.max(np.abs(_event_times(r, "ground") - (t0 + 2 * t0 * e * (1 - e**k) / (1 - e)))) < 1e-12
    flying = r["time"] < t0
    assert np.allclose(r["events.ground.normal"][flying], r["free.r.z"][flying] - 0.1, atol=1e-15)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_stop_chattering_to_rest_settles_where_mbcomp_does(kind, made, reference):
    """A pendulum falling onto a stop at 0.3 rad against gravity: its rebounds accumulate and it
    rests engaged, pressed by gravity's torque ``m g L sin(0.3)`` (the indicator, N m)."""
    times, kinds, res = reference("resting")
    assert kinds[-1] == "rest"
    speeds = np.array([abs(e.detail.get("speed_before", 0.0)) for e in res.events if e.kind == "impact"])
    r = _run(made("resting", "3.0"), "resting", kind)
    got, want = _event_times(r, "hinge"), np.unique(times)
    if kind == "CoSimulation":  # the FMU's own DOP853 and location; the last event of each step is seen
        assert len(got) >= 15 and got[-1] == pytest.approx(want[-1], abs=1e-9)
        assert np.max(np.min(np.abs(got[:, None] - want[None, :]), axis=1)) < 1e-9
    else:
        assert len(got) == len(want) == len(speeds)
        # FMPy's CVODE: a rebound's time is its angle's error over its speed (the last ones at
        # 1e-6 rad/s: 1e-7 s off for 1e-13 rad); to 1e-9 s where the speed is above 1e-3 rad/s
        fast = speeds > 1e-3
        assert fast.sum() >= 10 and np.max(np.abs(got - want)[fast]) < 1e-9
        assert np.max(np.abs(got - want)) < 2e-7
    after = r["time"] > times[-1] + 1e-9
    assert np.all(np.abs(r["hinge.phi"][after] - 0.3) < 1e-12) and np.all(np.abs(r["hinge.w"][after]) < 1e-12)
    assert np.allclose(r["events.hinge.lo"][after], 9.81 * np.sin(0.3), rtol=1e-9)


def test_the_restitution_is_a_parameter(made):
    """``ground.restitution`` tuned in the FMU to 0.5: the second impact at ``t0 (1 + 2 e)``."""
    t0 = np.sqrt(2 / 9.81)
    r = fmpy.simulate_fmu(str(made("ball", "3.0")), fmi_type="CoSimulation", stop_time=1.2, output_interval=1e-3,
                          start_values={"ground.restitution": 0.5}, output=["events.ground.time"])
    assert _event_times(r, "ground")[:2] == pytest.approx([t0, t0 * 2.0], abs=1e-12)


@pytest.mark.parametrize("fmi", VERSIONS)
def test_event_indicators_are_declared(fmi, made):
    """FMI 3.0: an ``<EventIndicator>`` per indicator, each a continuous variable; FMI 2.0:
    ``numberOfEventIndicators``. One per contact, two per stop."""
    for name, n in (("ball", 1), ("pendulum", 2)):
        with zipfile.ZipFile(made(name, fmi)) as z:
            root = ET.fromstring(z.read("modelDescription.xml"))
        if fmi == "3.0":
            refs = [e.get("valueReference") for e in root.iter("EventIndicator")]
            names = {v.get("valueReference"): v.get("name") for v in root.find("ModelVariables")}
            assert len(refs) == n and all(names[v].startswith(f"events.{COMPONENT[name]}.") for v in refs)
        else:
            assert root.get("numberOfEventIndicators") == str(n)


def test_modes_the_fmu_cannot_carry_are_refused_naming_the_component(tmp_path):
    """A contact with friction (rolling and sliding) has no FMU events yet: the export names
    the contact and the fix."""
    from mbcomp.library import ContactFriction, RigidBody, SphereContact, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    b = m.add("ball", RigidBody(m=1.0, I=np.eye(3) * 0.004), free=True)
    c = m.add("ground", SphereContact(r=0.1, unilateral=True, friction=ContactFriction(0.5, 0.3)))
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, b.frame_a)
    with pytest.raises(ValueError, match=r"cannot export ground: .*SlidingContactModes.* not supported by the FMU's "
                                         r"events yet"):
        export_fmu(m, tmp_path / "rolling.fmu")
    assert not (tmp_path / "rolling.fmu").exists()


def test_the_command_line_exports_the_bouncing_ball(tmp_path, reference):
    """``mbcomp export models/bouncing_ball.py -o ball.fmu``: FMPy validates it and runs it as
    Model Exchange and Co-Simulation with mbcomp.simulate's bounce times (1e-9 s)."""
    from mbcomp.cli.main import main

    path = tmp_path / "ball.fmu"
    assert main(["export", load_model("models/bouncing_ball.py").__file__, "-o", str(path)]) == 0
    assert validate_fmu(str(path)) == []
    times = reference("ball")[0]
    for kind in ("ModelExchange", "CoSimulation"):
        got = _event_times(_run(path, "ball", kind), "ground")
        assert len(got) == len(np.unique(times)) and np.max(np.abs(got - np.unique(times))) < 1e-9


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("name", ["ball", "pendulum", "door", "block", "shaker"])
def test_the_events_in_fmusim_too(name, fmi, made, reference):
    """The Reference-FMUs' fmusim, the second importer: as Model Exchange (its CVODE at 1e-14
    locating the indicators' roots, the FMU acting in Event Mode) and as Co-Simulation, every
    event where mbcomp.simulate has it (1e-9 s). (Measured, FMI 3.0, ME at 1e-14: the ball's
    3.1e-10 s, the others below 5e-13 s; CS below 1e-13 s.)"""
    exe, why = fmusim_tool.fmusim()
    if exe is None:  # as tests/export/test_fmu.py: fmusim needs its build's system libraries
        pytest.skip(why)
    _, t_end, dt = MODELS[name]
    comp = COMPONENT[name]
    want = np.unique(reference(name)[0])
    for interface, tol in (("me", 1e-14), ("cs", 1e-12)):
        r = fmusim_tool.run(made(name, fmi), interface, t_end, [f"events.{comp}.time"], tolerance=tol,
                            points=int(round(t_end / dt)))
        got = _event_times(r, comp)
        assert len(got) == len(want) and np.max(np.abs(got - want)) < 1e-9, interface


def test_a_fixed_step_importer_cannot_sink_the_ball(made):
    """FMPy's explicit Euler (Model Exchange) finds a touch a whole step late, the ball inside
    the ground; the impact moves it back onto the surface (without that it sank: z = 0.0994 m
    at 5 s). After every impact (the speed reversed) the ball is on the surface, z = r."""
    r = fmpy.simulate_fmu(str(made("ball", "3.0")), fmi_type="ModelExchange", solver="Euler", step_size=1e-4,
                          stop_time=5.0, output_interval=0.01, output=["free.r.z", "free.v.z"])
    t, z, v = r["time"], r["free.r.z"], r["free.v.z"]
    after = np.flatnonzero((np.diff(t) == 0.0) & (np.diff(np.sign(v)) > 0)) + 1  # an event reversing the fall
    assert len(after) >= 10 and np.all(z[after - 1] < 0.1) and np.allclose(z[after], 0.1, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_an_input_presses_a_slider_onto_a_stop_and_releases_it(kind, tmp_path):
    """A 2 kg slider between stops at -1 and 1 m (e = 0) pushed by the FMU's input u: +10 N
    lands it on the upper stop at sqrt(0.2) s, u turned to -10 N at 1 s releases it there (the
    stop's push jumps below zero between two steps: Co-Simulation acts on it at the next step's
    start, Model Exchange in the Event Mode FMPy's input event asks for) and it lands on the
    lower stop at 1 + sqrt(0.8) s."""
    from mbcomp.library import Force, PointMass, Prismatic, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.5, v0=0.0, limits=(-1.0, 1.0), restitution=0.0))
    b = m.add("b", PointMass(m=2.0))
    f = m.add("push", Force(f=mbcomp.Input("u", unit="N", description="push")))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    m.connect(s.axis, f.flange_b)
    path = tmp_path / "slider.fmu"
    assert export_fmu(m, path, stop_time=2.5)["inputs"] == ["u"] and validate_fmu(str(path)) == []
    signal = np.array([(0.0, 10.0), (1.0, 10.0), (1.0, -10.0), (2.5, -10.0)], dtype=[("time", float), ("u", float)])
    r = fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=2.5, input=signal, output=["s.s", "events.s.time"],
                          output_interval=0.01 if kind == "ModelExchange" else 1e-3,
                          relative_tolerance=1e-14 if kind == "ModelExchange" else 1e-12)
    assert _event_times(r, "s") == pytest.approx([np.sqrt(0.2), 1.0, 1.0 + np.sqrt(0.8)], abs=1e-9)
    assert r["s.s"][-1] == pytest.approx(-1.0, abs=1e-12)
