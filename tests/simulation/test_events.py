"""Events in the driver (issue 22): user event functions in scipy's convention, located on the
dense output; terminal and non-terminal, direction filtering, across integrators, formulations
and backends."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import PointMass, Prismatic, World

G = 9.81
H = 2.0


def faller(v0=0.0):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=H, v0=v0))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def event(fun, terminal=False, direction=0):
    fun.terminal, fun.direction = terminal, direction
    return fun


@pytest.mark.parametrize("method, backend", [("dop853", "c"), ("dop853", "numeric"), ("radau5", "numeric"),
                                             ("RK45", "auto"), ("dopri5", "auto")])
def test_terminal_event_is_the_fall_time(method, backend):
    ground = event(lambda t, y: y[0], terminal=True, direction=-1)
    r = mbcomp.simulate(faller(), t_end=2.0, rtol=1e-10, atol=1e-12, method=method, backend=backend,
                        events=[ground])
    t_hit = np.sqrt(2 * H / G)
    assert r.status == "success" and r.message.startswith("event <lambda> at t=0.6385508")
    assert abs(r.events[0].time - t_hit) < 1e-9
    assert abs(r.time[-1] - t_hit) < 1e-9 and abs(r["s.s"][-1]) < 1e-8   # the event's state is the last output
    assert abs(r["s.v"][-1] + G * t_hit) < 1e-8
    assert np.all(np.diff(r.time) > 0)


def test_non_terminal_crossings_filtered_by_direction():
    # thrown up at 10 m/s from 2 m: s = 3 m is crossed going up and coming down
    v0, level = 10.0, 3.0
    up = event(lambda t, y: y[0] - level, direction=1)
    down = event(lambda t, y: y[0] - level, direction=-1)
    both = event(lambda t, y: y[0] - level)
    r = mbcomp.simulate(faller(v0), t_end=2.5, rtol=1e-10, atol=1e-12, events=[up, down, both])
    disc = np.sqrt(v0**2 - 2 * G * (level - H))
    t_up, t_down = (v0 - disc) / G, (v0 + disc) / G
    got = [(round(e.time, 6), e.kind) for e in r.events]
    assert len(r.events) == 4 and all(e.kind == "user" for e in r.events)
    assert r.status == "success" and r.time[-1] == 2.5                # non-terminal: the run goes on
    ups = [e.time for e in r.events if e.time < 0.5 * (t_up + t_down)]
    downs = [e.time for e in r.events if e.time > 0.5 * (t_up + t_down)]
    assert len(ups) == 2 and len(downs) == 2, got
    assert max(abs(np.array(ups) - t_up)) < 1e-9 and max(abs(np.array(downs) - t_down)) < 1e-9


def test_terminal_count():
    crossing = event(lambda t, y: y[0] - 3.0, terminal=2)   # ends at the second crossing
    r = mbcomp.simulate(faller(10.0), t_end=2.5, rtol=1e-10, atol=1e-12, events=[crossing])
    t_down = (10.0 + np.sqrt(100.0 - 2 * G)) / G
    assert len(r.events) == 2 and abs(r.time[-1] - t_down) < 1e-9


def test_formulations_and_backends_agree_on_event_times():
    ground = event(lambda t, y: y[0], terminal=True, direction=-1)
    ts = [mbcomp.simulate(faller(), t_end=2.0, rtol=1e-10, atol=1e-12, formulation=f, backend=b,
                          events=[ground]).events[0].time
          for f in ("lagrange", "dalembert") for b in ("numeric", "c")]
    assert np.ptp(ts) < 1e-9


def test_no_events_no_records():
    r = mbcomp.simulate(faller(), t_end=0.1)
    assert r.events == [] and "events" not in r.stats
