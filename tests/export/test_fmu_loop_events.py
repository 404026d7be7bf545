"""FMUs with events for models with kinematic loops (issue 33 item 1): a stop on a joint inside
a loop.

The loop's closure rows (the cut joint's independent rows, as the consistent initialization
chose them: ``system.row_mask``) are always in force in the FMU (``fmu_events.c``'s
``hy_add_permanent``): the accelerations hold them with the stop's row when it is engaged, an
impact holds them (the impulse through the loop), the projection after an event keeps the loop
closed, and the importer's start value on a loop coordinate is kept with the loop closed by the
model's guesses. Each FMU runs in FMPy as Model Exchange (CVODE at rtol 1e-14) and as
Co-Simulation (the FMU's DOP853), FMI 3.0 and 2.0, against ``mbcomp.simulate`` (rtol 1e-12,
atol 1e-14): event times to 1e-9 s, states on the 0.01 s grid to 1e-8, the loop's closure from
the FMU's states (closed-form geometry) to 1e-9 throughout.
"""

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import load_model, load_module

import sanitized

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402

#: the slider-crank (models/slider_crank.py: crank 0.2 m, rod 0.6 m): the slider's stops and restitution
SLIDER = {"slider_joint.limits": (0.45, 0.9), "slider_joint.restitution": 0.5}
#: the four-bar (models/four_bar.py, gap 0.1 m, dropped from phi = pi/2 at rest): the crank's stops (e = 0)
CRANK = {"crank_joint.limits": (1.0, 2.5), "crank_joint.restitution": 0.0}
#: the four-bar's crank torque -PULL t (N m): it overcomes gravity's push on the upper stop and releases it
PULL = 2.0
GAP = 0.1


def slider_crank(phi0=0.3):
    return load_model("models/slider_crank.py").build(phi0=phi0)


def four_bar():
    """The four-bar falling from rest onto its crank's upper stop (e = 0: it lands and rests,
    the loop locked), pulled back by the torque -PULL t on the crank: released where the pull
    overcomes gravity, it lands on the lower stop."""
    from mbcomp.library import Torque

    m = load_module("models/four_bar.py").build(gap=GAP, w0=0.0, phi0=np.pi / 2)
    pull = m.add("pull", Torque(tau=lambda t, phi, w: -PULL * t))
    m.connect(m.components()["crank_joint"].axis, pull.flange_b)
    return m


def _slider_gap(r):
    """The slider's position less the crank's geometry's (m): ``s - (L2 cos phi + sqrt(L3^2 - (L2 sin phi)^2))``."""
    phi, L2, L3 = r["crank_joint.phi"], 0.2, 0.6
    return r["slider_joint.s"] - L2 * np.cos(phi) - np.sqrt(L3 ** 2 - (L2 * np.sin(phi)) ** 2)


def _four_bar_gap(r):
    """The rocker's pivot reached through crank, coupler and rocker less where it is (m, both axes)."""
    L1, L2, L3, L4 = load_module("models/four_bar.py").lengths(GAP)
    a1 = r["crank_joint.phi"]
    a2 = a1 + r["coupler_joint.phi"]
    a3 = a2 + r["pin.phi"]
    return np.hypot(L2 * np.cos(a1) + L3 * np.cos(a2) - L4 * np.cos(a3) - L1,
                    L2 * np.sin(a1) + L3 * np.sin(a2) - L4 * np.sin(a3))


#: (model, parameters, end time (s), Co-Simulation output interval (s), joint with the stop, states, loop gap)
CASES = {
    "slider": (slider_crank, SLIDER, 2.5, 1e-3, "slider_joint",
               ["crank_joint.phi", "slider_joint.s", "pin.phi", "crank_joint.w", "slider_joint.v", "pin.w"],
               _slider_gap),
    "fourbar": (four_bar, CRANK, 3.0, 1e-3, "crank_joint",
                ["crank_joint.phi", "coupler_joint.phi", "pin.phi", "crank_joint.w", "coupler_joint.w", "pin.w"],
                _four_bar_gap),
}


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """``{(case, fmi): path}``, exported once per module (without derivative programs)."""
    root, out = tmp_path_factory.mktemp("fmu_loops"), {}

    def get(name, fmi="3.0"):
        if (name, fmi) not in out:
            build, params, t_end = CASES[name][:3]
            out[name, fmi] = root / f"{name}{fmi[0]}.fmu"
            export_fmu(build(), out[name, fmi], fmi=fmi, params=params, stop_time=t_end, derivatives=False)
        return out[name, fmi]
    return get


@pytest.fixture(scope="module")
def reference():
    """``{case: (event times (s), events, result on a 0.01 s grid)}`` of ``mbcomp.simulate``."""
    cache = {}

    def get(name):
        if name not in cache:
            build, params, t_end = CASES[name][:3]
            res = mbcomp.simulate(build(), params=params, t_end=t_end, rtol=1e-12, atol=1e-14, dt_out=0.01)
            cache[name] = (np.unique([e.time for e in res.events]), res.events, res)
        return cache[name]
    return get


def _run(path, name, kind, **kw):
    _, _, t_end, dt, joint, states, _ = CASES[name]
    me = kind == "ModelExchange"
    return fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=t_end, output_interval=0.01 if me else dt,
                             relative_tolerance=1e-14 if me else 1e-12,
                             output=states + [f"events.{joint}.{k}" for k in ("time", "lo", "hi")], **kw)


def _on_grid(r, res, var):
    """The FMU's ``var`` at mbcomp's output times (after the events FMPy records there)."""
    return np.array([r[var][np.flatnonzero(np.abs(r["time"] - tk) < 1e-12)[-1]] for tk in res.time])


def _event_times(r, name):
    """The distinct last-event times the FMU reported for the case's joint (s), in order."""
    t = r[f"events.{CASES[name][4]}.time"]
    return np.unique(t[t >= 0.0])


def _agrees(r, name, want, res):
    """The FMU's event times (1e-9 s), states on the grid (1e-8) are mbcomp.simulate's, its loop closed (1e-9 m)."""
    got = _event_times(r, name)
    assert len(got) == len(want) >= 2 and np.max(np.abs(got - want)) < 1e-9, (got, want)
    for var in CASES[name][5]:
        assert np.max(np.abs(_on_grid(r, res, var) - res[var])) < 1e-8, var
    assert np.max(np.abs(CASES[name][6](r))) < 1e-9


@pytest.mark.parametrize("fmi", ["3.0", "2.0"])
@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_slider_crank_rebounds_off_its_slider_stop(kind, fmi, made, reference):
    """The slider hits its lower stop (0.45 m) three times, each an impact through the loop (the
    impulse on the crank and rod too) with e = 0.5: the slider's speed after is -0.5 times its
    speed before; mbcomp.simulate's event times and states, the loop closed."""
    want, events, res = reference("slider")
    assert [e.kind for e in events] == ["impact"] * 3
    path = made("slider", fmi)
    assert validate_fmu(str(path)) == []
    r = _run(path, "slider", kind)
    _agrees(r, "slider", want, res)
    if kind == "ModelExchange":  # FMPy records the state before and after each event
        for t_hit in _event_times(r, "slider"):
            k = np.flatnonzero(r["time"] == t_hit)
            assert len(k) == 2 and abs(r["slider_joint.s"][k[1]] - 0.45) < 1e-12
            v0, v1 = r["slider_joint.v"][k]
            assert v0 < -0.1 and v1 == pytest.approx(-0.5 * v0, rel=1e-9)


@pytest.mark.parametrize("fmi", ["3.0", "2.0"])
@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_four_bar_lands_on_its_crank_stop_rests_and_is_released(kind, fmi, made, reference):
    """The four-bar lands on the crank's upper stop (2.5 rad, e = 0) and rests there, the loop
    locked; the stop's push falls at the pull's rate (2 N m/s: the torque acts on the stopped
    coordinate itself) through zero, the stop releases and the crank lands on its lower stop
    (1 rad). Event times, states and the loop closed as mbcomp.simulate has them."""
    want, events, res = reference("fourbar")
    assert [e.kind for e in events] == ["impact", "engage", "release", "impact", "engage"]
    r = _run(made("fourbar", fmi), "fourbar", kind)
    _agrees(r, "fourbar", want, res)
    t = r["time"]
    resting = (t > want[0] + 1e-9) & (t < want[1] - 1e-9)
    assert resting.sum() > 50
    assert np.all(np.abs(r["crank_joint.phi"][resting] - 2.5) < 1e-12)
    assert np.all(np.abs(r["crank_joint.w"][resting]) < 1e-12)
    push = r["events.crank_joint.hi"][resting]
    slope, at0 = np.polyfit(t[resting], push, 1)
    assert slope == pytest.approx(-PULL, rel=1e-9) and np.max(np.abs(at0 + slope * t[resting] - push)) < 1e-9
    assert -at0 / slope == pytest.approx(want[1], abs=1e-9)  # released where the push is zero
    landed = t > want[2] + 1e-9
    assert np.all(np.abs(r["crank_joint.phi"][landed] - 1.0) < 1e-12)


def test_a_bicycle_rolling_on_bilateral_contacts_bounces_on_a_steer_stop(tmp_path):
    """The benchmark bicycle (models/bicycle.py, v = 3 m/s, roll rate 0.5 rad/s) on its bilateral
    rolling contacts -- holonomic normal rows and nonholonomic rolling rows, always in force
    (``HY_P_ROWS``, ``HY_P_NH``) -- with steer stops at +-0.01 rad (e = 0.5): its rebounds
    accumulate to rest on the upper stop at 0.1447 s, which releases it at 0.9856 s. Co-Simulation
    (FMI 3.0) has every event where mbcomp.simulate has it (1e-9 s; the last of each 1 ms step)
    and the states on the grid to 1e-8. (Model Exchange: FMPy's CVODE stalls after the release,
    see docs/design/fmu.md.)"""
    params = {"steer.limits": (-0.01, 0.01), "steer.restitution": 0.5}

    def bike():
        return load_model("models/bicycle.py").build(v=3.0, roll_rate0=0.5)

    res = mbcomp.simulate(bike(), params=params, t_end=1.0, rtol=1e-12, atol=1e-14, dt_out=0.01)
    kinds = [e.kind for e in res.events]
    assert kinds.count("rest") == 1 and kinds.count("release") == 1 and kinds.count("impact") >= 10
    want = np.unique([e.time for e in res.events])
    info = export_fmu(bike(), tmp_path / "bike.fmu", params=params, stop_time=1.0, derivatives=False)
    r = fmpy.simulate_fmu(str(tmp_path / "bike.fmu"), fmi_type="CoSimulation", stop_time=1.0, output_interval=1e-3,
                          relative_tolerance=1e-12, output=info["states"] + ["events.steer.time"])
    t = r["events.steer.time"]
    got = np.unique(t[t >= 0.0])
    assert len(got) >= 10 and np.max(np.min(np.abs(got[:, None] - want[None, :]), axis=1)) < 1e-9
    assert got[-1] == pytest.approx(want[-1], abs=1e-9)
    for var in info["states"]:
        assert np.max(np.abs(_on_grid(r, res, var) - res[var])) < 1e-8, var


@pytest.fixture(scope="module")
def started():
    """mbcomp.simulate's slider-crank started at phi0 = 0.5 rad: ``(event times (s), result)``."""
    res = mbcomp.simulate(slider_crank(phi0=0.5), params=SLIDER, t_end=2.5, rtol=1e-12, atol=1e-14, dt_out=0.01)
    return np.unique([e.time for e in res.events]), res


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_start_on_a_loop_coordinate_is_kept_with_the_loop_closed(kind, made, started):
    """The importer sets the crank's start angle to 0.5 rad (the FMU's start is 0.3): the
    slider and the pin move to close the loop (their starts are the model's guesses) and the
    run is the model's with phi0 = 0.5 (mbcomp.simulate): events, states, the loop closed."""
    want, res = started
    r = _run(made("slider"), "slider", kind, start_values={"crank_joint.phi": 0.5})
    assert r["crank_joint.phi"][0] == 0.5
    _agrees(r, "slider", want, res)


def test_start_values_the_loop_cannot_meet_are_an_error_naming_them(made):
    """The crank at 0.5 rad and the slider at 0.3 m (the loop reaches 0.4 .. 0.8 m): the FMU
    cannot close the loop with both kept and says so, naming them, at initialization."""
    logged = []

    def log(env, status, category, message):
        logged.append((int(status), message.decode()))

    with pytest.raises(Exception, match="failed with status 3"):
        _run(made("slider"), "slider", "CoSimulation", start_values={"crank_joint.phi": 0.5, "slider_joint.s": 0.3},
             logger=log)
    errors = [m for s, m in logged if s >= 3]
    assert errors and "the start values set (crank_joint.phi = 0.5, slider_joint.s = 0.3) and the model's fixed ones " \
                      "cannot all hold" in errors[-1], errors


def test_what_a_loop_cannot_carry_is_refused_naming_it(tmp_path):
    """A stop on the four-bar's cut joint (its rocker hinge: no coordinate of its own) and a
    one-sided contact on the slider-crank's pin, whose height the loop already holds (its row
    depends on the loop's rows): each export names the joint and writes nothing."""
    from mbcomp.library import Fixed, PlaneContact

    with pytest.raises(ValueError, match=r"^cannot export rocker_joint: the modes of Revolute \(StopModes\) act on the "
                                         r"joint's own coordinate, but rocker_joint is the cut joint closing a loop .* "
                                         r"-> put them on another joint of the loop$"):
        export_fmu(load_module("models/four_bar.py").build(gap=GAP), tmp_path / "cut.fmu",
                   params={"rocker_joint.limits": (0.5, 2.0)}, derivatives=False)
    m = slider_crank()
    floor = m.add("floor", Fixed(r=(0.0, -0.05, 0.0)))
    c = m.add("guard", PlaneContact(n=(0, 1, 0), unilateral=True, open0=True))
    m.connect(floor.frame_b, c.frame_a)
    m.connect(m.components()["rod_tip"].frame_b, c.frame_b)
    with pytest.raises(ValueError, match=r"^cannot export guard: a contact whose row 'guard.normal' depends on the "
                                         r"loop's rows at the start: not supported by the FMU's events yet"):
        export_fmu(m, tmp_path / "guard.fmu", derivatives=False)
    assert not list(tmp_path.iterdir())


#: the rough ball's sanitizer harness (tests/export/test_fmu_rolling_events.py), the start values
#: of the first two states (argv[2], argv[3]) set before the initialization when given
START = r"""
    if (argc > 2) { fmi3ValueReference vr = VR_X; fmi3Float64 v = atof(argv[2]); fmi3SetFloat64(c, &vr, 1, &v, 1); }
    if (argc > 3) { fmi3ValueReference vr = VR_X + 1; fmi3Float64 v = atof(argv[3]); fmi3SetFloat64(c, &vr, 1, &v, 1); }
    if (!c || fmi3EnterInitializationMode(c, 1, 1e-12, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) {
        if (c) fmi3FreeInstance(c);
        return 2;
    }"""


def test_the_loop_events_c_is_clean_under_asan_and_ubsan(made, reference, started, tmp_path):
    """The slider-crank's FMU C (the loop's rows in force, impacts through the loop, the
    projection, the start values moved onto the loop) built with AddressSanitizer and UBSan:
    Co-Simulation to 2.5 s ends where mbcomp.simulate does (1e-8), from the FMU's start and from
    the crank's start set to 0.5 rad; Model Exchange under an explicit Euler importer acts on its
    events; starts the loop cannot meet end the initialization with the error naming them; no
    sanitizer report, no warning."""
    from test_fmu_rolling_events import HARNESS

    init = ("    if (!c || fmi3EnterInitializationMode(c, 1, 1e-12, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) "
            "return 2;")
    assert init in HARNESS
    exe = sanitized.build(made("slider"), HARNESS.replace(init, START), tmp_path, quiet=("fmu_events", "fmu_core"))
    states = CASES["slider"][5]
    for args, want in (((), reference("slider")[2]), (("0.5",), started[1]), (("0.5", "0.3"), None)):
        run = sanitized.run(exe, "2.5", *args)
        if want is None:  # the crank at 0.5 rad and the slider at 0.3 m: out of the loop's reach
            assert run.returncode == 2 and "the start values set (crank_joint.phi = 0.5, slider_joint.s = 0.3)" \
                in run.stderr, run.stderr[-3000:]
            continue
        assert run.returncode == 0, run.stderr[-3000:]
        cs, me = (line.split() for line in run.stdout.strip().splitlines())
        assert cs[:2] == ["cs", "0"] and float(cs[2]) == pytest.approx(2.5, abs=1e-9)
        y = dict(zip(states, map(float, cs[3:])))
        assert all(abs(y[v] - want[v][-1]) < 1e-8 for v in states), (y, [want[v][-1] for v in states])
        assert me[:2] == ["me", "0"] and int(me[3]) >= 3 and me[4] == "0"
