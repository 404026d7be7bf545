"""Bad event requests are refused before anything runs, naming the event and the fix: a
non-function, a function of the wrong arity, scipy attributes out of range; a joint started
outside its stops is a model problem naming the joint's start value."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import Prismatic, Revolute, RigidBody, World


def _arm(joint):
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", joint)
    b = m.add("b", RigidBody(m=1.0, r_cm=(1, 0, 0), I=0.1 * np.eye(3)))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def _down(t, y):
    return y[0]


def _with(**attrs):
    def crossing(t, y):
        return y[0]
    for k, v in attrs.items():
        setattr(crossing, k, v)
    return crossing


@pytest.mark.parametrize("events, error, message", [
    ([3], TypeError, r"events\[0\]=3 is not a function"),
    ("x", TypeError, "must be a list of event functions"),
    (_down, TypeError, "must be a list of event functions"),
    ([lambda t: 0.0], TypeError, r"takes 1 positional argument\(s\).*\(t, y\)"),
    ([_with(direction=2)], ValueError, "direction=2 must be -1"),
    ([_with(terminal=-1)], ValueError, "terminal=-1 must be True/False or a count"),
])
def test_bad_events_are_refused_before_the_run(events, error, message):
    with pytest.raises(error, match=message):
        mbcomp.simulate(_arm(Revolute(phi0=0.3)), t_end=0.1, events=events)


def test_good_events_are_kept_and_found():
    """A pendulum from 0.3 rad: phi crosses zero going down first (a quarter period later)."""
    res = mbcomp.simulate(_arm(Revolute(phi0=0.3)), t_end=3.0, events=[_with(direction=-1, terminal=True)],
                          rtol=1e-10, atol=1e-12)
    (ev,) = res.events
    assert ev.kind == "user" and res["j.phi"][-1] == pytest.approx(0.0, abs=1e-9) and res.time[-1] == ev.time


@pytest.mark.parametrize("joint, where", [(Revolute(phi0=1.0, limits=(-0.5, 0.5)), "j.phi0"),
                                          (Prismatic(n=(1, 0, 0), s0=-2.0, limits=(-1.0, 1.0)), "j.s0")])
def test_a_start_outside_the_stops_is_a_model_problem(joint, where):
    with pytest.raises(mbcomp.ModelError, match=rf"{where}: .*outside the stops"):
        mbcomp.simulate(_arm(joint), t_end=0.1)


def test_an_fmu_of_a_model_with_stops_carries_their_events(tmp_path):
    """The door's FMU watches both of its stops: an event indicator per limit (issue 33; the
    FMU's events against mbcomp's are tests/export/test_fmu_events.py)."""
    from conftest import load_model

    info = mbcomp.export_fmu(load_model("models/door.py").build(), tmp_path / "door.fmu", kind="cs")
    assert info["events"] == ["events.hinge.lo", "events.hinge.hi"] and (tmp_path / "door.fmu").exists()


def test_evaluations_are_counted_over_every_mode():
    """A run with impacts rebuilds its formulation at each change of mode; the evaluations of
    all of them are counted (DOP853 takes 12 per step), not only the last mode's."""
    from conftest import load_model

    res = mbcomp.simulate(load_model("models/door.py").build(), t_end=8.0, rtol=1e-8)
    assert len(res.events) >= 2
    assert res.stats["nfev"] >= 11 * res.stats["steps"]
