"""A run with events is integrated in segments (issue 30 item 1): the step holding an event is
cut there, its outputs up to the event come from that step's dense output, the events act and
the next segment starts over the new active set. Every output is checked against the closed
form of a falling point mass: a run ended by a user's terminal event (its outputs in the cut
step were the event's state before: 0.94 m off with status "success") and a run bouncing on
a joint stop (outputs on both sides of every impact), on both formulations and several
integrators; and the events never touch the run (detect and locate read it, the driver acts)."""
import numpy as np
import pytest

import mbcomp
from mbcomp.hybrid.events import Events
from mbcomp.library import PointMass, Prismatic, World

G = 9.81
H = 1.0


def faller(**stop):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=H, **stop))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def ground(t, y):
    return y[0]


ground.terminal, ground.direction = True, -1

CASES = [("lagrange", "RK45"), ("lagrange", "dop853"), ("lagrange", "radau5"), ("dalembert", "RK45"),
         ("dalembert", "DOP853")]


@pytest.mark.parametrize("formulation, method", CASES)
def test_outputs_before_a_terminal_event_are_the_motion_not_the_events_state(formulation, method):
    r = mbcomp.simulate(faller(), t_end=2.0, rtol=1e-10, atol=1e-12, n_out=2001, events=[ground],
                        formulation=formulation, method=method)
    t_hit = np.sqrt(2 * H / G)
    assert r.status == "success" and r.message.startswith("event ground at t=0.45152364")
    assert abs(r.time[-1] - t_hit) < 1e-9 and len(r.time) == 453     # outputs to 0.451 s, then the event
    assert np.max(np.abs(r["s.s"] - (H - 0.5 * G * r.time ** 2))) < 1e-8
    assert np.max(np.abs(r["s.v"] + G * r.time)) < 1e-8


def _bouncing(t, e):
    """``(s, v)`` of a mass dropped from H onto a rigid stop at s = 0 with restitution ``e``."""
    t = np.asarray(t, float)
    s, v = np.empty_like(t), np.empty_like(t)
    t0, v0 = np.sqrt(2 * H / G), np.sqrt(2 * G * H)   # the first landing
    first = t < t0
    s[first], v[first] = H - 0.5 * G * t[first] ** 2, -G * t[first]
    start, speed = t0, e * v0
    while np.any(~first & (t >= start)):
        span = 2 * speed / G
        sel = (t >= start) & (t < start + span)
        tau = t[sel] - start
        s[sel], v[sel] = speed * tau - 0.5 * G * tau ** 2, speed - G * tau
        start, speed = start + span, e * speed
        if span < 1e-3:
            break
    return s, v


@pytest.mark.parametrize("formulation, method", CASES)
def test_outputs_on_both_sides_of_each_impact_follow_the_bounces(formulation, method):
    e = 0.5
    r = mbcomp.simulate(faller(limits=(0.0, 2.0), restitution=e), t_end=1.5, rtol=1e-10, atol=1e-12, n_out=1501,
                        formulation=formulation, method=method)
    assert r.status == "success", r.message
    impacts = [ev.time for ev in r.events if ev.kind == "impact"]
    t0 = np.sqrt(2 * H / G)
    assert abs(impacts[0] - t0) < 1e-9 and abs(impacts[1] - (t0 + 2 * e * np.sqrt(2 * H / G))) < 1e-8
    sel = r.time < impacts[3]                      # the first three bounces, each with outputs inside
    s, v = _bouncing(r.time[sel], e)
    assert np.max(np.abs(r["s.s"][sel] - s)) < 1e-7
    assert np.max(np.abs(r["s.v"][sel] - v)) < 1e-6


def test_the_events_detect_and_act_without_touching_the_run():
    """:meth:`Events.check` and :meth:`Events.act` leave the run's formulation, stepper and
    outputs as they were: the driver keeps the outputs and starts the next segment."""
    from mbcomp.formulations import build
    from mbcomp.simulation.stepping import Run
    from mbcomp.solvers import STEPPERS

    system = mbcomp.assemble(faller(limits=(0.0, 2.0), restitution=0.5))
    system.row_mask = None
    events = Events(system, lambda s: build("lagrange", "ode", s), rtol=1e-10, atol=1e-12)
    form = events.make_form(events.system_now())
    q0, u0 = np.array([H]), np.array([0.0])
    form, y0 = events.start(form, form.initial_state(0.0, q0, u0), 0.0, q0, u0)
    run = Run(form, STEPPERS["RK45"], np.linspace(0.0, 1.0, 11), y0, rtol=1e-10, atol=1e-12)
    run.start()
    events.arm(run.t, run.ys[0])
    cut = None
    while cut is None:
        assert run.advance()
        before = (run.form, run.stepper, len(run.ys), run.stepper.t)
        cut = events.check(run)
        assert (run.form, run.stepper, len(run.ys), run.stepper.t) == before
    assert abs(cut.t - np.sqrt(2 * H / G)) < 1e-9 and cut.action is not None
    outcome = events.act(cut)
    assert (run.form, run.stepper, len(run.ys)) == before[:3]
    assert not outcome.ends and outcome.form is not run.form
    assert abs(outcome.state[1] - 0.5 * np.sqrt(2 * G * H)) < 1e-8    # the rebound: e times the landing speed
