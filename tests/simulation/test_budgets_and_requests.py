"""Budgets end a run with its results kept; a slow explicit run says why once; numbers
simulate cannot honour are refused with the fix (issue 18)."""
import re
import time
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, Torque, TranslationalSpringDamper, World


def pendulum(phi0=1.0):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=phi0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m, j


def stiff_pendulum(c=1e7, m_slider=1.0):
    """A 1 m pendulum (about 3 1/s) whose bob slides on the rod against a stiff spring
    (sqrt(c / m) 1/s)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=1e-3))
    bob = m.add("bob", PointMass(m=m_slider))
    k = m.add("k", TranslationalSpringDamper(c=c))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, s.frame_a)
    m.connect(s.frame_b, bob.frame_a)
    m.connect(s.support, k.flange_a)
    m.connect(s.axis, k.flange_b)
    return m


def test_a_step_budget_ends_the_run_with_the_results_of_the_full_run_so_far():
    m, _ = pendulum()
    full = mbcomp.simulate(m, t_end=20.0, n_out=2001)
    cut = mbcomp.simulate(m, t_end=20.0, n_out=2001, max_steps=100)
    assert cut.status == "budget" and "step budget of 100 steps ran out" in cut.message
    n = len(cut.time)
    assert 1 < n < len(full.time) and cut.stats["steps"] >= 100
    np.testing.assert_allclose(cut["j.phi"], full["j.phi"][:n], rtol=0, atol=1e-12)


def test_a_wall_time_budget_ends_a_slow_run_in_time_and_says_which_budget():
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = mbcomp.simulate(stiff_pendulum(), t_end=100.0, backend="numeric", max_wall_time=1.0)
    spent = time.perf_counter() - t0
    assert res.status == "budget" and "wall-time budget of 1 s ran out" in res.message
    assert spent < 1.0 + 3.0  # one step and the post-processing past the budget
    assert res.time[-1] < 100.0 and np.isfinite(res["j.phi"]).all()


def test_a_stiff_spring_is_named_with_its_rate_when_the_run_is_cut_short():
    c, mass = 1e7, 1.0
    with pytest.warns(RuntimeWarning, match="looks stiff"):
        res = mbcomp.simulate(stiff_pendulum(c, mass), t_end=100.0, backend="numeric", max_wall_time=1.0)
    hint = res.stats["stiffness_hint"]
    assert hint in res.message and "element 'k'" in hint and "method='radau5'" in hint
    rate = float(re.search(r"largest rate is about ([0-9.e+]+) 1/s", hint).group(1))
    assert rate == pytest.approx(np.sqrt(c / mass), rel=0.02)  # the spring's own frequency dominates


def test_a_discontinuous_law_is_named_as_a_jump_not_as_stiffness():
    m, j = pendulum()
    fr = m.add("fr", Torque(tau=lambda t, phi, w: -2.0 * np.sign(w)))  # Coulomb friction, unregularized
    m.connect(j.axis, fr.flange_b)
    with pytest.warns(RuntimeWarning, match="jump in the right-hand side"):
        res = mbcomp.simulate(m, t_end=30.0, max_steps=400)  # a step budget: a wall-time one ran out under load
    assert res.status == "budget" and "(element 'fr')" in res.stats["stiffness_hint"]
    assert "tanh" in res.stats["stiffness_hint"]


def test_a_smooth_run_at_a_loose_tolerance_gets_no_stiffness_hint():
    m, _ = pendulum()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = mbcomp.simulate(m, t_end=3000.0, rtol=1e-4, atol=1e-6, backend="numeric", max_steps=300)
    assert res.status == "budget" and "stiffness_hint" not in res.stats


@pytest.mark.parametrize("kwargs, text", [
    (dict(rtol=-1e-6), "rtol=-1e-06 must be a positive"),
    (dict(rtol=1e-20), "below what double precision can deliver"),
    (dict(atol=0.0), "atol=0.0 must be a positive"),
    (dict(alpha=-5.0), "Baumgarte gain alpha=-5.0 must be a finite number >= 0"),
    (dict(beta=np.nan), "Baumgarte gain beta=nan"),
    (dict(n_out=0), "n_out=0 must be an integer >= 2"),
    (dict(n_out=True), "n_out=True must be an integer >= 2"),
    (dict(dt_out=-0.1), "dt_out=-0.1 must be a positive"),
    (dict(max_step=0.0), "max_step=0.0 must be a positive"),
    (dict(max_wall_time=0), "max_wall_time=0 must be a positive"),
    (dict(max_steps=2.5), "max_steps=2.5 must be a positive integer"),
])
def test_numbers_simulate_cannot_honour_are_refused_with_the_fix(kwargs, text):
    m, _ = pendulum()
    with pytest.raises(ValueError, match=re.escape(text)) as err:
        mbcomp.simulate(m, t_end=1.0, **kwargs)
    assert "->" in str(err.value)


@pytest.mark.parametrize("dt_out, expected", [(5.0, [0.0, 1.0]), (0.3, [0.0, 0.3, 0.6, 0.9, 1.0]),
                                              (0.25, [0.0, 0.25, 0.5, 0.75, 1.0])])
def test_the_output_grid_always_ends_at_t_end(dt_out, expected):
    m, _ = pendulum()
    res = mbcomp.simulate(m, t_end=1.0, dt_out=dt_out)
    np.testing.assert_allclose(res.time, expected, atol=1e-15)
    ref = mbcomp.simulate(m, t_end=1.0, n_out=2)
    assert res["j.phi"][-1] == pytest.approx(ref["j.phi"][-1], abs=1e-7)


def test_simulate_given_a_path_or_a_model_module_says_to_build_the_model(tmp_path):
    with pytest.raises(TypeError, match=r"load_model_file\('models/slider_crank.py'\)\.build\(\)"):
        mbcomp.simulate("models/slider_crank.py")
    mod = mbcomp.load_model_file("models/slider_crank.py")
    with pytest.raises(TypeError, match=r"call its build\(\)"):
        mbcomp.simulate(mod)
    with pytest.raises(TypeError, match="not NoneType"):
        mbcomp.simulate(None)


def test_a_law_branch_the_trace_did_not_take_is_counted_and_said():
    m, j = pendulum()
    fr = m.add("fr", Torque(tau=lambda t, phi, w: -0.5 * w if w > 0 else -0.1 * w))  # a Python branch on w
    m.connect(j.axis, fr.flange_b)
    res = mbcomp.simulate(m, t_end=5.0)
    ref = mbcomp.simulate(m, t_end=5.0, backend="numeric")
    assert res.stats["backend"] == "c" and res.stats["fallbacks"] > res.stats["nfev"] // 2
    assert "evaluations left the generated program for the numeric path" in res.message
    assert "left the generated program" not in ref.message
    np.testing.assert_allclose(res["j.phi"], ref["j.phi"], atol=1e-6)   # same motion either way


def test_a_run_failing_for_steps_names_the_element_that_makes_it_fast():
    """Found by the fuzz: 'DOP853: max_steps=100000 steps were not enough' named nothing. (That
    cap of the compiled loop's calls no longer ends a run, issue 30 item 7: a step budget does.)"""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Prismatic(n=(1, 0, 0), s0=0.01))
    b = m.add("b", PointMass(m=1e-4))
    sp = m.add("sp", TranslationalSpringDamper(c=1e9))      # sqrt(c / m) = 3.16e6 1/s
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    m.connect(j.support, sp.flange_a)
    m.connect(j.axis, sp.flange_b)
    with pytest.warns(RuntimeWarning, match="the motion itself is fast"):
        res = mbcomp.simulate(m, t_end=10.0, n_out=3, max_steps=300_000)
    assert res.status == "budget" and "the step budget of 300000 steps ran out" in res.message
    rate = float(re.search(r"every rate is near ([0-9.e+]+) 1/s \(element 'sp'\)", res.message).group(1))
    assert rate == pytest.approx(np.sqrt(1e9 / 1e-4), rel=0.02)
