"""Events watched inside the C stepping loop (issue 32 item 5): the runtime's driver evaluates
event functions after every accepted step and locates a crossing on the step's dense output
(``mbrt_events``), so a run with stops steps in C stretches. Held to closed forms (motion linear
or quadratic in t: every method integrates it exactly, the error is the location's), to the run
without events (the same steps: the outputs before the first event bit for bit), and to the
Python event loop over scipy's DOP853."""
import numpy as np
import pytest
from scipy.special import ellipk

import mbcomp
from conftest import stop_pendulum
from mbcomp.codegen import c_compiler, compile_system
from mbcomp.library import PointMass, Prismatic, Revolute, RigidBody, World
from mbcomp.library.joints import StopModes
from mbcomp.modeling.events import EventRow

pytestmark = pytest.mark.skipif(not c_compiler(), reason="no C compiler")

G = 9.81


def rotor(e=0.8, w0=1.0, limits=(-0.5, 0.5)):
    """A rotor (J = 2 about z) from 0 at w0, no gravity; stops if ``limits``."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    lim = dict(limits=limits, restitution=e) if limits else {}
    j = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=w0, **lim))
    b = m.add("disk", RigidBody(m=1.0, I=np.diag([1.0, 1.0, 2.0])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


pendulum = stop_pendulum  # tests/conftest.py


def faller(v0=1.0):
    """A mass on a vertical slider thrown up at v0 from s = 0 (gravity along -z)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=0.0, v0=v0))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def engine(model):
    return compile_system(mbcomp.assemble(model), "c").evaluator.integrator(0.0, 0.0)


def impacts(res):
    return np.array([r.time for r in res.events if r.kind == "impact"])


# --- the runtime ---------------------------------------------------------------------------
def test_the_c_loop_locates_a_crossing_in_its_direction_only():
    """phi = 2 t (no gravity): ``1 - phi`` falls through zero at t = 0.5 s; the stretch ends
    there, its outputs before it written and none after; watched rising, it never fires."""
    eng = engine(rotor(limits=None, w0=2.0))
    t_out = np.linspace(0.05, 0.95, 10)
    ev = eng.linear_events([0], [-1.0], [1.0], [-1], tol=1e-14)
    r = eng.integrate(8, 0.0, np.array([0.0, 2.0]), 1.0, t_out, 1e-10, 1e-12, events=ev)
    assert r.status == 8 and r.which == 0
    assert abs(r.t_event - 0.5) < 1e-13 and abs(r.y_event[0] - 1.0) < 1e-12 and r.y_event[1] == 2.0
    assert len(r.Y) == 5 and np.allclose(r.Y[:, 0], 2.0 * t_out[:5], rtol=0, atol=1e-13)
    up = eng.linear_events([0], [-1.0], [1.0], [1], tol=1e-14)
    r = eng.integrate(8, 0.0, np.array([0.0, 2.0]), 1.0, t_out, 1e-10, 1e-12, events=up)
    assert r.status == 0 and r.which == -1 and len(r.Y) == 10


@pytest.mark.parametrize("order", [5, 8])
def test_outputs_before_the_event_are_the_smooth_runs_bit_for_bit(order):
    """Watching events changes no step: a pendulum's outputs up to its first crossing equal
    those of the same integration without events."""
    eng = engine(pendulum(limits=None))
    y0, t_out = np.array([0.8, 0.0]), np.linspace(0.0, 2.0, 41)[1:]
    plain = eng.integrate(order, 0.0, y0, 2.0, t_out, 1e-9, 1e-11)
    ev = eng.linear_events([0], [1.0], [0.0], [-1], tol=1e-14)
    hit = eng.integrate(order, 0.0, y0, 2.0, t_out, 1e-9, 1e-11, events=ev)
    quarter = ellipk(np.sin(0.4) ** 2) / np.sqrt(G)  # the quarter period from 0.8 rad
    assert hit.status == 8 and abs(hit.t_event - quarter) < 1e-7
    k = len(hit.Y)
    assert k == np.searchsorted(t_out, hit.t_event, side="right") and np.array_equal(hit.Y, plain.Y[:k])


def test_a_return_inside_the_first_step_is_not_tunnelled():
    """A mass thrown up at 1 m/s from s = 0 returns at 2 v0 / g; with one first step of 1 s
    (quadratic motion: accepted, exact) the event acted on at the start (``fresh``) is found
    where it comes back, not at the start."""
    eng = engine(faller())
    ev = eng.linear_events([0], [1.0], [0.0], [-1], tol=1e-14)
    r = eng.integrate(8, 0.0, np.array([0.0, 1.0]), 1.0, np.array([1.0]), 1e-9, 1e-11, h0=1.0, events=ev, fresh=0)
    assert r.status == 8 and r.naccept == 1 and abs(r.t_event - 2.0 / G) < 1e-13
    assert abs(r.y_event[1] + 1.0) < 1e-12  # coming down at v0


def test_bad_events_are_refused_naming_the_fix():
    eng = engine(rotor(limits=None))
    with pytest.raises(ValueError, match="state entries 0..1"):
        eng.linear_events([2], [1.0], [0.0], [-1], tol=1e-12)
    with pytest.raises(ValueError, match="directions are -1, 0 or"):
        eng.linear_events([0], [1.0], [0.0], [2], tol=1e-12)
    with pytest.raises(ValueError, match="tol"):
        eng.linear_events([0], [1.0], [0.0], [-1], tol=0.0)
    ev = eng.linear_events([0], [1.0], [0.0], [-1], tol=1e-12)
    r = eng.integrate(8, 0.0, np.array([0.1, 1.0]), 1.0, np.array([1.0]), 1e-9, 1e-11, events=ev, fresh=3)
    assert r.status == 6 and "fresh < n_ev" in r.message


# --- runs ------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["auto", "dop853", "dopri5"])
def test_a_rotor_between_stops_runs_in_c_stretches_to_the_closed_form(method):
    """Impacts at 0.5, 0.5 + 1/0.8, ... (linear motion: exact to the location's 1e-12), and
    the run takes no step on the Python path."""
    res = mbcomp.simulate(rotor(), t_end=6.0, rtol=1e-8, atol=1e-10, method=method)
    t = impacts(res)
    exact = 0.5 + np.concatenate(([0.0], np.cumsum(1.0 / 0.8 ** np.arange(1, len(t)))))
    assert res.status == "success" and len(t) == 4
    assert np.max(np.abs(t - exact)) < 1e-12
    steppers = res.stats["stretches"]
    assert steppers > 0 and res.stats.get("python_steps", 0) == 0


def test_the_c_and_python_event_loops_agree_on_the_pendulum():
    """A pendulum onto a stop at its bottom (e = 0.7): impact times from the C loop and from the
    Python loop over scipy's DOP853 agree with the closed form (elliptic quarter and half
    periods) and each other, and every impact keeps e^2 of the kinetic energy."""
    k0, t, exact = np.sin(0.4), 0.0, []
    t = ellipk(k0 ** 2) / np.sqrt(G)
    for k in range(5):
        exact.append(t)
        t += 2 * ellipk((0.7 ** (k + 1) * k0) ** 2) / np.sqrt(G)
    c = mbcomp.simulate(pendulum(), t_end=5.0, rtol=1e-10, atol=1e-12)
    py = mbcomp.simulate(pendulum(), t_end=5.0, rtol=1e-10, atol=1e-12, method="DOP853")
    tc, tp = impacts(c), impacts(py)
    assert len(tc) == len(tp) == 5
    assert np.max(np.abs(tc - exact)) < 1e-9 and np.max(np.abs(tp - exact)) < 1e-8
    assert np.max(np.abs(tc - tp)) < 1e-8
    for rec in (r for r in c.events if r.kind == "impact"):
        assert rec.detail["energy_loss"] > 0
    w = [abs(r.detail["w_before"]) if "w_before" in r.detail else None for r in c.events]
    if all(x is not None for x in w):  # not every record carries the speeds
        assert np.allclose(w[1:], 0.7 * np.array(w[:-1]), rtol=1e-9)


def test_outputs_before_the_first_impact_equal_the_run_without_stops():
    """simulate with stops (watched in C) and without: the same steps, so the outputs up to the
    first impact are equal (the 1e-12 comparison with simulate of issue 32)."""
    with_stops = mbcomp.simulate(pendulum(), t_end=1.0, rtol=1e-9, atol=1e-11, n_out=201)
    without = mbcomp.simulate(pendulum(limits=None), t_end=1.0, rtol=1e-9, atol=1e-11, n_out=201)
    t1 = impacts(with_stops)[0]
    before = with_stops.time < t1
    assert before.sum() > 50
    for col in ("hinge.phi", "hinge.w"):
        assert np.max(np.abs(with_stops[col][before] - without[col][before])) <= 1e-12


class _Marked(StopModes):
    """Stops with one more watched event, ``"mark"`` at phi = 0.4 rad falling, that does nothing."""

    def event_rows(self, mode):
        rows = super().event_rows(mode)
        return rows + [EventRow("mark", "q", 0, 1.0, 0.4, -1)] if mode == "free" else rows

    def action(self, name, mode):
        return None if name == "mark" else super().action(name, mode)


class _MarkedRevolute(Revolute):
    def modes(self, p):
        return _Marked(p.limits[0], p.limits[1], p.restitution) if p.limits is not None else None


def test_an_event_that_does_not_act_is_passed():
    """An event located in C whose action is None: the run goes on past it (one step on the
    Python path) and meets the stop where the run without the mark does."""
    marked = mbcomp.simulate(pendulum(joint=_MarkedRevolute), t_end=3.0, rtol=1e-10, atol=1e-12)
    plain = mbcomp.simulate(pendulum(), t_end=3.0, rtol=1e-10, atol=1e-12)
    assert marked.status == plain.status == "success"
    tm, tp = impacts(marked), impacts(plain)
    assert len(tm) == len(tp) >= 2 and np.max(np.abs(tm - tp)) < 1e-9
    assert marked.stats.get("python_steps", 0) > 0  # it passed the marks on the Python path


def test_a_stop_on_a_closed_loop_agrees_with_the_python_loop():
    """The slider-crank's slider hits a stop (e = 0.6): the C loop's impacts (Baumgarte, and the
    projection made after every step in C) equal the Python loop's over scipy's DOP853 within
    the tolerances, and the C run takes no Python step."""
    crank = mbcomp.load_model_file("models/slider_crank.py")
    stops = {"slider_joint.limits": (0.5, 1.5), "slider_joint.restitution": 0.6}
    for stab in ("baumgarte", "projection"):
        c = mbcomp.simulate(crank.build(), t_end=2.0, rtol=1e-9, atol=1e-11, stabilization=stab, params=stops)
        py = mbcomp.simulate(crank.build(), t_end=2.0, rtol=1e-9, atol=1e-11, stabilization=stab, params=stops,
                             method="DOP853")
        tc, tp = impacts(c), impacts(py)
        assert c.status == py.status == "success" and len(tc) == len(tp) == 2
        assert np.max(np.abs(tc - tp)) < 1e-8 and c.stats.get("python_steps", 0) == 0
        assert np.max(np.abs(c["slider_joint.s"] - py["slider_joint.s"])) < 1e-6


class _PastTheJoint(StopModes):
    """Stops whose lower row reads q[1] of a 1-DOF joint (a wrong declaration)."""

    def event_rows(self, mode):
        return [EventRow("lo", "q", 1, 1.0, self.lo, -1)] if mode == "free" else []


class _BadRevolute(Revolute):
    def modes(self, p):
        return _PastTheJoint(p.limits[0], p.limits[1], p.restitution)


def test_an_event_row_past_the_joint_is_a_model_problem_naming_it():
    """A declared row that points past the joint's own coordinates would make the C loop watch
    another joint's entry: the run is refused, naming the joint, the row and the fix."""
    with pytest.raises(mbcomp.errors.ModelError, match=r"hinge.*EventRow 'lo' reads q\[1\].*1 coordinates.*from 0 to 0"):
        mbcomp.simulate(pendulum(joint=_BadRevolute), t_end=1.0)
