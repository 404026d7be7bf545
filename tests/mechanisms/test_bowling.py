"""The bowling ball (models/bowling.py): sliding on an oiled lane, then rolling.

Checked against the model's closed form (its ``reference``, derived in the module notes):

* the slide's end ``t* = |s0| / (mu_k g (1 + 1/k))`` (the contact's ``stick`` switch) to 1e-10 s
  and the state at ``t_end`` (centre position, velocity, world spin) to 1e-9, at rtol 1e-10 for
  the throws spinning about y alone, at rtol 1e-12 with hook (see ``CASES``);
* the energy balance (kinetic + potential + the friction's dissipated work constant) and the
  dissipated work against ``W = k m |s0|^2 / (2 (1 + k))``: the friction ``mu_k m g`` times the
  slip distance ``int |s| dt = |s0| t* / 2`` (the slip speed falls linearly to 0), and
  independently the kinetic energy lost between the start and the closed-form rolling state.
"""
import doctest
import functools

import numpy as np
import pytest

import mbcomp

BOWLING = mbcomp.load_model_file("models/bowling.py")
TOL = dict(rtol=1e-10, atol=1e-12)
G = 9.81

# (build parameters, t_end s, rtol): plain throw, backspin, hook with backspin (on a dry lane,
# mu_k = 0.2, where real balls hook), a cored ball (k = 0.36).
# The throws spinning about y alone move polynomially in t (the friction's moment stays along the
# spin axis in the body's axes too), so rtol 1e-10 meets the bounds below with room (errors ~1e-13).
# With hook the ball spins about a tilted axis: the body's axes, in which FreeMotion integrates w and
# resolves the friction's moment, turn non-polynomially, and at rtol 1e-10 the integration's error
# reaches the bounds (hook: 1.2e-10 s on the stick, 2.4e-9 on the state; on the oiled lane, sliding
# 7 s, 1e-9 and 3e-9), converging with rtol (hook at rtol 1e-12: 1.3e-12 s and 2.1e-11; cored: 1.5e-12
# and 7e-12); those cases run at rtol 1e-12 against the same bounds. The dry lane ends the hook's
# slide at 1.4 s instead of 7.0 s: a quarter of the steps (9.5 s -> 2.6 s of CPU).
CASES = {"plain": (dict(), 8.0, 1e-10),
         "backspin": (dict(w_b=25.0), 8.0, 1e-10),
         "hook": (dict(w_b=10.0, hook=30.0, mu_k=0.2), 2.0, 1e-12),
         "cored": (dict(inertia=0.36, hook=15.0, mu_k=0.06, v0=7.0), 5.0, 1e-12)}


@functools.lru_cache(maxsize=None)
def run(case):
    """``(parameters, t_end, result)`` of one case at its rtol (each run once per session)."""
    kw, t_end, rtol = CASES[case]
    return kw, t_end, mbcomp.simulate(BOWLING.build(**kw), t_end=t_end, n_out=81, rtol=rtol, atol=rtol * 1e-2)


@pytest.fixture(params=list(CASES))
def thrown(request):
    return run(request.param)


def _kinetic(m, r, k, v, w):
    """``m |v|^2 / 2 + k m r^2 |w|^2 / 2`` (J)."""
    return 0.5 * m * float(np.dot(v, v)) + 0.5 * k * m * r * r * float(np.dot(w, w))


def test_slide_ends_at_the_closed_form_time(thrown):
    """One event, the contact's slide-to-roll switch ``stick`` (mode ``closed``), at
    ``reference()["sticks"]`` to 1e-10 s; for the plain throw also ``2 v0 / (7 mu_k g)`` written out
    (``reference`` against the textbook formula, not only the model against its own file)."""
    kw, t_end, res = thrown
    ref = BOWLING.reference(t_end=t_end, **kw)
    assert res.status == "success"
    assert [(e.kind, e.component, e.name, e.detail["mode"]) for e in res.events] == [("switch", "lane", "stick",
                                                                                      "closed")]
    assert len(ref["sticks"]) == 1 and abs(res.events[0].time - ref["sticks"][0]) < 1e-10
    if not kw:
        assert abs(ref["sticks"][0] - 2 * 8.0 / (7 * 0.04 * G)) < 1e-12


def test_state_at_t_end_matches_the_closed_form(thrown):
    """Centre position and velocity, world spin at ``t_end`` against ``reference`` to 1e-9 (m,
    m/s, rad/s); the ball rolls at the end: its contact point's slip ``v + w x (-r e_z)`` is 0."""
    kw, t_end, res = thrown
    ref = BOWLING.reference(t_end=t_end, **kw)
    for name, value in ref["values"].items():
        assert abs(res[name][-1] - value) < 1e-9, name
    r = kw.get("r", 0.109)
    v = np.array([res[f"ball.v.{c}"][-1] for c in "xyz"])
    w = np.array([res[f"ball.w.{c}"][-1] for c in "xyz"])
    assert np.linalg.norm(v + np.cross(w, [0.0, 0.0, -r])) < 1e-9
    assert res["lane.sticking"][-1] == 1.0


def test_energy_balance_and_dissipated_work(thrown):
    """``energy.balance`` stays below 1e-9 J (of ~200 J); the dissipated work at ``t_end`` equals
    ``k m |s0|^2 / (2 (1 + k))`` (the friction work's closed form, written out here) and the
    kinetic energy lost from the start to the closed-form rolling state (energy bookkeeping:
    an independent route to the same number) to 1e-9 J; before ``t*`` it follows
    ``mu_k m g (|s0| t - mu_k g (1 + 1/k) t^2 / 2)``."""
    kw, t_end, res = thrown
    p = dict(m=7.0, r=0.109, inertia=0.4, mu_k=0.04, v0=8.0, w_b=0.0, hook=0.0) | kw
    m, r, k = p["m"], p["r"], p["inertia"]
    S = np.hypot(p["v0"] + r * p["w_b"], r * p["hook"])
    work = k * m * S * S / (2 * (1 + k))
    ref = BOWLING.reference(t_end=t_end, **kw)["values"]
    lost = (_kinetic(m, r, k, [p["v0"], 0.0], [-p["hook"], -p["w_b"]])
            - _kinetic(m, r, k, [ref["ball.v.x"], ref["ball.v.y"]], [ref["ball.w.x"], ref["ball.w.y"]]))
    assert abs(work - lost) < 1e-9 * work
    assert np.max(np.abs(res["energy.balance"])) < 1e-9
    assert abs(res["energy.dissipated"][-1] - work) < 1e-9
    t = res.time
    t_star = BOWLING.reference(t_end=t_end, **kw)["t_roll"]
    a = p["mu_k"] * G
    slide = t < t_star
    expected = m * a * (S * t[slide] - 0.5 * a * (1 + 1 / k) * t[slide] ** 2)
    assert np.max(np.abs(res["energy.dissipated"][slide] - expected)) < 1e-9


def test_hook_bends_the_path_while_sliding_then_straight():
    """With side roll the centre's path while sliding is the parabola ``p = v0 t e_x - mu_k g
    t^2 e / 2`` (constant acceleration along the fixed slip direction ``e``), checked at every
    output point to 1e-9 m; once rolling it is a straight line at constant velocity."""
    kw, _, res = run("hook")
    t_star, e, _ = BOWLING.slide(**kw)
    t, a = res.time, kw["mu_k"] * G
    slide = t < t_star
    assert slide.sum() > 40  # the parabola is checked at more than 40 output points
    x, y = res["ball.r.x"], res["ball.r.y"]
    assert np.max(np.abs(x[slide] - (8.0 * t[slide] - 0.5 * a * t[slide] ** 2 * e[0]))) < 1e-9
    assert np.max(np.abs(y[slide] - (-0.5 * a * t[slide] ** 2 * e[1]))) < 1e-9
    assert e[1] < 0 and y[-1] > 0.5  # hook > 0 curves left (+y)
    roll = ~slide
    assert np.ptp(res["ball.v.x"][roll]) < 1e-10 and np.ptp(res["ball.v.y"][roll]) < 1e-10


def test_reference_at_t_end_before_the_stick_has_no_event():
    """``reference`` at a ``t_end`` inside the slide: no stick, and a run there has none either;
    the state agrees to 1e-9 (the sliding formulas alone)."""
    ref = BOWLING.reference(t_end=2.0, w_b=5.0)
    assert ref["sticks"] == [] and ref["t_roll"] > 2.0
    res = mbcomp.simulate(BOWLING.build(w_b=5.0), t_end=2.0, n_out=2, **TOL)
    assert res.events == []
    for name, value in ref["values"].items():
        assert abs(res[name][-1] - value) < 1e-9, name


def test_nonpositive_inertia_is_refused():
    with pytest.raises(ValueError, match="bowling: inertia=0.0"):
        BOWLING.build(inertia=0.0)


def test_model_doctests():
    """The model file's examples (a run against the backspin formulas, ``reference`` against the
    textbook ``2 v0 / (7 mu_k g)``) pass."""
    failed, tried = doctest.testmod(BOWLING, verbose=False)[:2]
    assert tried > 0 and failed == 0
