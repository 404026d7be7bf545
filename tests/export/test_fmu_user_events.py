"""User events in an FMU (issue 33 item 1's last part): ``export_fmu(model, path, events=[f])``.

Each function ``f(t, y)`` is traced into the FMU's C as the event indicator
``events.user.<name>`` with the output ``events.user.<name>.time``; a crossing in its
direction fires it, a terminal one ends the simulation (ME: ``terminateSimulation``; CS: the
step stops at the event). Checked against closed forms (free fall: sqrt(2 h / g)) and against
``mbcomp.simulate(model, events=[f])`` at rtol 1e-12: the run ends at the event to 1e-9 s and
the states agree to 1e-8, under FMPy's ME (CVODE, rtol 1e-14) and CS, FMI 3.0 and 2.0.
"""

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import stop_pendulum
from pendulum_model import pendulum

import sanitized

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy import simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, World  # noqa: E402
from mbcomp.modeling.events import End  # noqa: E402
from mbcomp.modeling.modes import Modes  # noqa: E402

G, S0, FLOOR = 9.81, 1.0, 0.5
RUNS = [("3.0", "ModelExchange"), ("3.0", "CoSimulation"), ("2.0", "ModelExchange"), ("2.0", "CoSimulation")]


def free_fall():
    """A 1 kg mass on a vertical Prismatic at s = 1 m, at rest, falling under g."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=S0))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def floor(t, y):
    return y[0] - FLOOR


floor.terminal, floor.direction = True, -1


def rising(t, y):  # the swing's speed rising through zero: the left turning points only
    return y[1]


rising.direction = 1


def second(t, y):  # the angle falling through zero; the second time ends the run
    return y[0]


second.terminal, second.direction = 2, -1


class Latch(Modes):
    def events(self, q, u, mode):
        return [("latched", 1.0 - q[0], -1)]

    def action(self, name, mode):
        return End("the door latched")


class Door(Revolute):
    def modes(self, p):
        return Latch("open")


def door():
    """A door (1 kg at 1 m on a hinge, opening against gravity at 5 rad/s) that latches at 1 rad."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    j = m.add("hinge", Door(n=(0, 0, 1), phi0=0.0, w0=5.0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """The FMUs, exported once each on first use: ``made(key, fmi)``."""
    root, cache = tmp_path_factory.mktemp("user_events"), {}
    models = {"fall": (free_fall, [floor]), "swing": (pendulum, [rising, second]), "door": (door, None),
              "clock": (pendulum, [clock])}

    def get(key, fmi="3.0"):
        if (key, fmi) not in cache:
            build, events = models[key]
            path = root / f"{key}{fmi[0]}.fmu"
            cache[key, fmi] = (path, export_fmu(build(), path, fmi=fmi, derivatives=False, events=events))
        return cache[key, fmi][0]
    return get


def run(path, fmi, kind, stop, names, **kw):
    opts = dict(relative_tolerance=1e-14) if kind == "ModelExchange" else {}
    if fmi == "3.0" and kind == "CoSimulation":
        opts["early_return_allowed"] = True  # FMPy then records the early return's time (the event's)
    return simulate_fmu(str(path), fmi_type=kind, stop_time=stop, output_interval=0.01, output=names,
                        **{**opts, **kw})


@pytest.mark.parametrize("fmi,kind", RUNS)
def test_a_free_fall_ends_where_the_mass_falls_through_the_floor_at_its_closed_form(made, fmi, kind):
    t_e = np.sqrt(2 * (S0 - FLOOR) / G)
    r = run(made("fall", fmi), fmi, kind, 1.0, ["s.s", "s.v", "events.user.floor.time"])
    t, s, v, last = r[-1]
    assert abs(t - t_e) < 1e-9 and abs(s - FLOOR) < 1e-8 and abs(v + G * t_e) < 1e-8, (t - t_e, s - FLOOR, v + G * t_e)
    if kind == "CoSimulation":  # ME's last row is recorded before its Event Mode: the time is set there
        assert abs(last - t_e) < 1e-9
    assert np.all(r["s.s"][:-1] > FLOOR)


@pytest.mark.parametrize("fmi", ["3.0", "2.0"])
def test_the_free_fall_ends_at_the_floor_in_fmusim_too(made, fmi):
    """The Reference-FMUs' fmusim, the second importer: Model Exchange (its CVODE at 1e-14) and
    FMI 2.0 Co-Simulation (fmi2Discard, fmi2Terminated) end at sqrt(2 h / g) to 1e-9 s; FMI 3.0
    Co-Simulation without an early return labels its last row with the communication point, the
    values the event's."""
    import fmusim_tool

    exe, why = fmusim_tool.fmusim()
    if exe is None:  # as tests/export/test_fmu_events.py: fmusim needs its build's system libraries
        pytest.skip(why)
    t_e = np.sqrt(2 * (S0 - FLOOR) / G)
    for interface, tol in (("me", 1e-14), ("cs", 1e-12)):
        r = fmusim_tool.run(made("fall", fmi), interface, 1.0, ["s.s", "s.v"], tolerance=tol, points=100)
        end = np.ceil(t_e / 0.01) * 0.01 if (fmi, interface) == ("3.0", "cs") else t_e
        assert abs(r["time"][-1] - end) < 1e-9, (fmi, interface, r["time"][-1] - end)
        assert abs(r["s.s"][-1] - FLOOR) < 1e-8 and abs(r["s.v"][-1] + G * t_e) < 1e-8, (fmi, interface)


def test_without_an_early_return_the_fmi3_step_still_stops_at_the_event(made):
    """FMPy not allowing an early return labels its last row with the communication point; the
    FMU's values are the event's, the run terminated there."""
    t_e = np.sqrt(2 * (S0 - FLOOR) / G)
    r = simulate_fmu(str(made("fall")), fmi_type="CoSimulation", stop_time=1.0, output_interval=0.01,
                     output=["s.s", "events.user.floor.time"])
    assert r["time"][-1] == pytest.approx(np.ceil(t_e / 0.01) * 0.01, abs=1e-12)
    assert abs(r["s.s"][-1] - FLOOR) < 1e-8 and abs(r["events.user.floor.time"][-1] - t_e) < 1e-9


@pytest.fixture(scope="module")
def swing():
    return mbcomp.simulate(pendulum(), t_end=5.0, events=[rising, second], rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("fmi,kind", RUNS)
def test_a_counted_terminal_event_and_a_rising_one_fire_where_simulate_records_them(made, swing, fmi, kind):
    """``second`` (falling, terminal=2) ends the run at its second firing, past a rising crossing it
    ignores; ``rising`` (+1) fires at the left turning point only, not at the right one between."""
    rec = {n: [e.time for e in swing.events if e.name == n] for n in ("rising", "second")}
    assert len(rec["rising"]) == 1 and len(rec["second"]) == 2 and swing.status == "success"
    names = ["j.phi", "j.w", "events.user.rising.time", "events.user.second.time"]
    r = run(made("swing", fmi), fmi, kind, 5.0, names)
    t, phi, w = r[-1][0], r[-1][1], r[-1][2]
    assert abs(t - rec["second"][1]) < 1e-9 and abs(t - swing.time[-1]) < 1e-9
    assert abs(phi - swing["j.phi"][-1]) < 1e-8 and abs(w - swing["j.w"][-1]) < 1e-8, (phi, w)
    assert np.any(r["j.w"] < 0) and np.any(r["j.w"][r["time"] > rec["rising"][0]] > 0)  # both crossings in the run
    fired = np.unique(r["events.user.rising.time"])
    assert len(fired) == 2 and fired[0] == -1.0 and abs(fired[1] - rec["rising"][0]) < 1e-9
    seconds = np.unique(r["events.user.second.time"])
    assert abs(seconds[1] - rec["second"][0]) < 1e-9 and seconds[0] == -1.0


def clock(t, y):  # linear in time: FMPy's CVODE lands exactly on its root, z = 0
    return t - 0.3


clock.terminal, clock.direction = True, 1


@pytest.mark.parametrize("fmi,kind", RUNS)
def test_a_rising_event_whose_root_the_importer_lands_on_exactly_fires_there(made, fmi, kind):
    """``t - 0.3`` rising: CVODE stops at z = 0 exactly (FMI's domain z <= 0 not yet left); it
    fires there as simulate's crossing (from below zero to at or above it) -- it did not, and the
    Model Exchange run went on to its end."""
    r = run(made("clock", fmi), fmi, kind, 1.0, ["j.phi"])
    assert abs(r["time"][-1] - 0.3) < 1e-9, r["time"][-1]


@pytest.mark.parametrize("fmi,kind", RUNS)
def test_a_joint_whose_event_ends_the_run_latches_the_fmu_where_simulate_ends(made, fmi, kind):
    res = mbcomp.simulate(door(), t_end=2.0, rtol=1e-12, atol=1e-14)
    assert res.message.startswith("hinge: the door latched") and res.time[-1] < 0.5
    r = run(made("door", fmi), fmi, kind, 2.0, ["hinge.phi", "hinge.w", "events.hinge.time"])
    t, phi, w, last = r[-1]
    assert abs(t - res.time[-1]) < 1e-9 and abs(phi - 1.0) < 1e-8 and abs(w - res["hinge.w"][-1]) < 1e-8
    if kind == "CoSimulation":
        assert abs(last - res.time[-1]) < 1e-9


def test_user_events_beside_end_stops_fire_as_simulate_records(tmp_path):
    """The stop pendulum (limits 0 and 3 rad, e = 0.7) with a user event at 0.4 rad falling,
    terminal at its second firing: it falls through, bounces off the stop (its rise through
    0.4 rad ignored) and falls through again -- FMU (FMI 3.0 ME and CS) as simulate."""
    def low(t, y):
        return y[0] - 0.4
    low.terminal, low.direction = 2, -1
    res = mbcomp.simulate(stop_pendulum(), t_end=3.0, events=[low], rtol=1e-12, atol=1e-14)
    hits = [e.time for e in res.events if e.name == "low"]
    assert len(hits) == 2 and any(e.component == "hinge" for e in res.events)
    path = tmp_path / "stops.fmu"
    export_fmu(stop_pendulum(), path, derivatives=False, events=[low])
    for kind in ("ModelExchange", "CoSimulation"):
        r = run(path, "3.0", kind, 3.0, ["hinge.phi", "hinge.w", "events.hinge.time"])
        assert abs(r["time"][-1] - hits[1]) < 1e-9, kind
        assert abs(r["hinge.phi"][-1] - 0.4) < 1e-8 and abs(r["hinge.w"][-1] - res["hinge.w"][-1]) < 1e-8, kind


def test_the_fmus_validate_and_declare_the_event_variables(made):
    from fmpy import read_model_description

    for fmi in ("3.0", "2.0"):
        path = made("swing", fmi)
        assert validate_fmu(str(path)) == [], fmi
        md = read_model_description(str(path))
        v = {x.name: x for x in md.modelVariables}
        assert v["events.user.rising.time"].causality == "output" and v["events.user.rising.time"].unit == "s"
        assert v["events.user.second"].variability == "continuous"
        assert md.numberOfEventIndicators == 2


def test_after_the_terminal_event_a_further_step_is_refused(made):
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    path = made("fall")
    md = read_model_description(str(path))
    s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="fall")
    messages = []
    s.instantiate(loggingOn=True, logMessage=lambda *a: messages.append(a[-1].decode() if a[-1] else ""))
    s.enterInitializationMode()
    s.exitInitializationMode()
    _, terminate, early, last = s.doStep(0.0, 1.0)
    assert terminate and not early and abs(last - np.sqrt(2 * (S0 - FLOOR) / G)) < 1e-9
    with pytest.raises(FMICallException):
        s.doStep(last, 0.1)
    assert any("the simulation ended there" in m for m in messages), messages
    s.terminate()
    s.freeInstance()


def test_model_exchange_terminates_at_the_event_and_refuses_to_go_on(made):
    """An importer driving Model Exchange by hand: the mass moved below the floor, Event Mode says
    terminateSimulation; continuous time mode is then refused with the reason."""
    from ctypes import c_double

    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Model

    path = made("fall")
    md = read_model_description(str(path))
    s = FMU3Model(guid=md.guid, unzipDirectory=extract(str(path)),
                  modelIdentifier=md.modelExchange.modelIdentifier, instanceName="fall")
    messages = []
    s.instantiate(loggingOn=True, logMessage=lambda *a: messages.append(a[-1].decode() if a[-1] else ""))
    s.enterInitializationMode()
    s.exitInitializationMode()
    assert not s.updateDiscreteStates()[1]  # at the start (s = 1 m, above the floor): going on
    s.enterContinuousTimeMode()
    s.setTime(0.3)
    s.setContinuousStates((c_double * 2)(FLOOR - 1e-3, -3.0), 2)
    s.enterEventMode()
    assert s.updateDiscreteStates()[1]  # fell through the floor: terminate
    with pytest.raises(FMICallException):
        s.enterContinuousTimeMode()
    assert any("fmi3EnterContinuousTimeMode: the simulation ended there, at t=0.3" in m for m in messages), messages
    s.terminate()
    s.freeInstance()


def untraceable(t, y):
    import math
    return math.sin(y[0])


def branching(t, y):
    if y[0] > 0.0:
        return y[0] - 0.1
    return y[0] + 0.1


def dup(t, y):
    return y[0]


def bad_direction(t, y):
    return y[0]


bad_direction.direction = 2


def bad_terminal(t, y):
    return y[0]


bad_terminal.terminal = -1


@pytest.mark.parametrize("events,message", [
    ([untraceable], "event untraceable: cannot be traced into the FMU's C"),
    ([branching], "cannot export event branching (test_fmu_user_events.py:"),
    ([dup, dup], "two functions are named 'dup'"),
    ([bad_direction], "event bad_direction: direction=2 -> fix: -1"),
    ([bad_terminal], "event bad_terminal: terminal=-1 -> fix: True/False, or a positive count"),
    ([lambda t, y: y[0]], "its name '<lambda>' is no identifier"),
    (floor, "events must be a list of functions"),
])
def test_events_the_fmu_cannot_carry_are_refused_naming_the_function(events, message, tmp_path):
    with pytest.raises(ValueError) as err:
        export_fmu(pendulum(), tmp_path / "x.fmu", derivatives=False, events=events)
    assert message in str(err.value), str(err.value)
    assert not (tmp_path / "x.fmu").exists()


def test_the_branching_function_is_named_at_its_if_line(tmp_path):
    import inspect

    line = inspect.getsourcelines(branching)[1] + 1  # the `if`
    with pytest.raises(ValueError, match=rf"branching \(test_fmu_user_events.py:{line}\)"):
        export_fmu(pendulum(), tmp_path / "x.fmu", derivatives=False, events=[branching])


def turned(t, y):  # the four-bar's crank past 2 pi: one turn
    return y[0] - 2 * np.pi


turned.terminal, turned.direction = True, 1


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_a_user_event_of_a_model_with_loops_ends_it_where_simulate_does(kind, made, tmp_path):
    """The four-bar (a loop: its closure rows always in force in the event C) ends where its
    crank completes a turn, as mbcomp.simulate(events=[turned]) ends: to 1e-9 s, the state to
    1e-8, the loop closed (the coupler's angle as simulate has it)."""
    from conftest import load_model

    model = load_model("models/four_bar.py").build()
    res = mbcomp.simulate(model, t_end=2.0, events=[turned], rtol=1e-12, atol=1e-14)
    assert res.message.startswith("event turned at t=")
    path = tmp_path / "turn.fmu"
    export_fmu(model, path, derivatives=False, events=[turned])
    names = ["crank_joint.phi", "coupler_joint.phi", "crank_joint.w"]
    # Model Exchange at CVODE's rtol 1e-12 (2e-10 s off): at 1e-13 its steps stall on the loop's
    # Baumgarte-held [q, u] (mxstep), the right-hand side's rounding above what it is asked for
    r = run(path, "3.0", kind, 2.0, names + ["events.user.turned.time"],
            **(dict(relative_tolerance=1e-12) if kind == "ModelExchange" else {}))
    assert abs(r["time"][-1] - res.time[-1]) < 1e-9, r["time"][-1] - res.time[-1]
    for n in names:
        assert abs(r[n][-1] - res[n][-1]) < 1e-8, n


HARNESS = r"""
#include "MODEL_C"
static int errors;
static void logger(void *env, fmi3Status s, fmi3String cat, fmi3String msg)
{ (void)env; (void)cat; if (s >= fmi3Error) { errors++; fprintf(stderr, "[FMU] %s\n", msg); } }
int main(void)
{
    double H = 1e-2, t = 0.0, x[NXS + 1], dx[NXS + 1], z[MB_NZ + 1], z0[MB_NZ + 1];
    fmi3Boolean e1, term = 0, early, up, nom, vals, nd; fmi3Float64 last = 0.0, next;
    fmi3Status st = fmi3OK;
    int i, refused, ended;
    fmi3FMUState saved = NULL;
    fmi3Instance c = fmi3InstantiateCoSimulation("h", GUID, NULL, 0, 0, 0, 1, NULL, 0, NULL, logger, NULL);
    if (!c || fmi3EnterInitializationMode(c, 1, 1e-12, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) return 2;
    for (; t < 5.0 && st == fmi3OK && !term; t += H) {
        st = fmi3DoStep(c, t, H, 1, &e1, &term, &early, &last);
        if (!st && t > 1.1 && !saved) st = fmi3GetFMUState(c, &saved);
    }
    ended = term;
    refused = fmi3DoStep(c, last, H, 1, &e1, &term, &early, &last) == fmi3Error;
    errors -= refused;
    printf("cs %d %d %d %.17g", (int)st, ended, refused, last);
    for (i = 0; i < NXS; i++) printf(" %.17g", ((Inst *)c)->y[i]);
    if (fmi3SetFMUState(c, saved) || fmi3FreeFMUState(c, &saved)) return 4;
    fmi3FreeInstance(c);
    c = fmi3InstantiateModelExchange("m", GUID, NULL, 0, 0, NULL, logger);
    if (!c || fmi3EnterInitializationMode(c, 1, 1e-12, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) return 3;
    st = fmi3UpdateDiscreteStates(c, &up, &term, &nom, &vals, &nd, &next);
    if (!st) st = fmi3EnterContinuousTimeMode(c);
    if (!st) st = fmi3GetEventIndicators(c, z0, MB_NZ);
    for (t = 0.0, H = 1e-4; t < 5.0 && st == fmi3OK && !term;) {
        st = fmi3GetContinuousStates(c, x, NXS);
        if (!st) st = fmi3GetContinuousStateDerivatives(c, dx, NXS);
        for (i = 0; i < NXS; i++) x[i] += H * dx[i];
        t += H;
        if (!st) st = fmi3SetTime(c, t);
        if (!st) st = fmi3SetContinuousStates(c, x, NXS);
        if (!st) st = fmi3GetEventIndicators(c, z, MB_NZ);
        for (i = 0; i < MB_NZ && !st; i++)
            if ((z0[i] > 0.0) != (z[i] > 0.0)) {
                st = fmi3EnterEventMode(c);
                if (!st) st = fmi3UpdateDiscreteStates(c, &up, &term, &nom, &vals, &nd, &next);
                if (!st && !term) st = fmi3EnterContinuousTimeMode(c);
                if (!st) st = fmi3GetEventIndicators(c, z, MB_NZ);
                break;
            }
        memcpy(z0, z, sizeof z);
    }
    printf("\nme %d %d %.17g %d\n", (int)st, (int)term, t, errors);
    fmi3FreeInstance(c);
    return 0;
}
"""


def test_the_user_events_c_is_clean_under_asan_and_ubsan(made, swing, tmp_path):
    """The swinging pendulum's FMU C with its two user events, built with AddressSanitizer and
    UBSan: Co-Simulation ends at the terminal event (simulate's time), a further step is refused,
    a saved state restored and freed; Model Exchange under an explicit Euler importer terminates
    near it; no error, no sanitizer report, no warning."""
    out = sanitized.run(sanitized.build(made("swing"), HARNESS, tmp_path, quiet=("fmu_", "fmi3.c")))
    assert out.returncode == 0, out.stderr[-3000:]
    cs, me = (line.split() for line in out.stdout.strip().splitlines())
    assert cs[:3] == ["cs", "0", "1"] and cs[3] == "1" and abs(float(cs[4]) - swing.time[-1]) < 1e-9
    assert abs(float(cs[5]) - swing["j.phi"][-1]) < 1e-8
    assert me[:3] == ["me", "0", "1"] and abs(float(me[3]) - swing.time[-1]) < 1e-3 and me[4] == "0"
