"""Runs passing singular positions (``singular="pass"``): how they are stepped and evaluated.

The passages are stepped in C (:class:`mbcomp.formulations.passing.PassingEngine`, the runtime's
``mbrt_pass_integrate``): DOP853 through the flat positions with the range-space solve where
the program's guard fails, the rows' closest approaches located on the C integrator's own dense
output and judged by the rank monitor, no restart next to them. Without an engine (no compiler,
a program without one) they are stepped on the Python path (scipy's DOP853 over the compiled
``fun``, every step watched by the rank monitor on its own dense output), where the rank monitor
makes the evaluation program at the start instead of after the lazy evaluator's 200 numeric
evaluations (docs/design/generated-programs.md, "Passing singular positions in C";
``bench/singular_engine.py``).

Independent reference: the N-four-bar (models/n_four_bar.py) moves as one parallelogram, so
its crank angle obeys ``J theta'' = -g cos(theta) m L ((N + 1) / 2 + N)``,
``J = m L^2 ((N + 1) / 3 + N)``; its flat positions are where ``sin(theta) = 0``.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import c_compiler
from mbcomp.formulations import LagrangeIndex1
from mbcomp.simulation import monitors
from mbcomp.simulation.setup import system_of

nfb = load_model("models/n_four_bar.py")
needs_c = pytest.mark.skipif(not c_compiler(), reason="needs a C compiler")


def exact(N, ts):
    """theta at ``ts`` and the flat instants of the one-degree-of-freedom reduction."""
    J = (N + 1) / 3 + N
    k = 9.81 * ((N + 1) / 2 + N)
    sol = solve_ivp(lambda t, y: [y[1], -k * np.cos(y[0]) / J], (0.0, ts[-1]), [np.pi / 2, 1.0], t_eval=ts,
                    events=lambda t, y: np.sin(y[0]), rtol=1e-13, atol=1e-13, method="DOP853")
    return sol.y[0], sol.t_events[0]


def python_path(monkeypatch):
    """No engine for a passing run: the Python path (scipy's DOP853 step by step)."""
    monkeypatch.setattr(LagrangeIndex1, "_passing_engine", lambda form, evaluator: None)


def check_run(r, N, t_tol, theta_tol, energy_tol):
    """Every flat passage of the N-four-bar run ``r`` recorded at its time (s), theta on the exact
    motion (rad), the energy kept (J)."""
    assert r.success, r.message
    theta, flats = exact(N, r.time)
    passages = r.stats["singular_passages"]
    assert len(passages) == len(flats)
    np.testing.assert_allclose([p["t"] for p in passages], flats, atol=t_tol)
    assert all(p["rank_drop"] == N for p in passages)
    assert np.max(np.abs(r["theta"] - theta)) < theta_tol
    E = r["energy.total"]
    assert np.max(np.abs(E - E[0])) < energy_tol


@needs_c
def test_ten_parallelograms_pass_every_flat_position_in_c(monkeypatch):
    # measured: C 4.6e-6 rad, 6.8e-7 s, 8.6e-6 J; the Python path 4.2e-6 rad, 7.1e-7 s, 9.3e-6 J;
    # C stretches handing passages to Python (before) 4.4e-4 rad (bench/singular_engine.py)
    N = 10
    r = mbcomp.simulate(nfb.build(N=N), **nfb.SIMULATION)
    assert len(exact(N, r.time)[1]) == 20
    assert r.stats["stretches"] == 32 and r.stats["python_steps"] == 0  # every step in C
    assert r.stats["retaken_steps"] == 20  # each flat position located, its step taken again whole
    check_run(r, N, 5e-6, 2e-5, 1e-4)
    python_path(monkeypatch)
    p = mbcomp.simulate(nfb.build(N=N), **nfb.SIMULATION)
    assert p.stats["stretches"] == 0
    check_run(p, N, 5e-6, 2e-5, 1e-4)
    np.testing.assert_allclose([x["t"] for x in r.stats["singular_passages"]],
                               [x["t"] for x in p.stats["singular_passages"]], atol=5e-6)  # 3e-7 s measured


@needs_c
def test_the_c_range_space_solve_is_the_formulations_next_to_a_flat_position():
    # the C loop's right-hand side where the program's guard fails against LagrangeIndex1.solve
    # with PASS_RANK (numpy's eigh): 20 rows of the N = 10 chain, 10 of them losing rank
    N = 10
    system = system_of(nfb.build(N=N), None, "c")
    init = initialize(system)
    form = LagrangeIndex1(system, "projection", singular="pass")
    y0 = form.initial_state(0.0, init.q, init.u)
    engine = form.compiled_integrator()
    ts = np.array([0.5, 0.7, 0.72, 0.7203, 0.72031, 0.7204, 0.75])  # the flat position at 0.720308 s
    r = engine.integrate(8, 0.0, y0, ts[-1], ts, 1e-10, 1e-12)
    assert r.status == 0 and len(engine.minima) == 1
    for t, y in zip(ts, r.Y):
        q, u = system.normalize(y[: system.nq]), y[system.nq:]
        ud, _ = form.solve(system.evaluate(t, q, u))
        dy = engine.range_rate(t, np.concatenate((q, u)))
        scale = np.max(np.abs(ud))
        np.testing.assert_allclose(dy[system.nq:], ud, atol=2e-6 * scale)  # 7e-8 relative measured next to it
        np.testing.assert_allclose(dy[: system.nq], system.q_rate(q, u), atol=1e-14)


@needs_c
@pytest.mark.parametrize("N, n_out", [(10, 2001), (7, 2001), (10, 301)])
def test_collapsing_steps_and_rough_outputs_next_to_a_flat_position_are_not_left_to_chance(N, n_out):
    # without going back from collapsing steps and integrating a passage step's outputs again:
    # N = 10, 2001 outputs: 4.1 J and 1.8e-3 rad at the outputs just after a passage (the
    # continuous extension's extra stages at rough multipliers); N = 7: 1,100 range-space solves
    # at one flat position (steps of 1e-6 s), 3.8e-4 rad; N = 10, 301 outputs: 8.9e-4 rad, 1.1e-3 J
    r = mbcomp.simulate(nfb.build(N=N), **{**nfb.SIMULATION, "n_out": n_out})
    assert r.stats["python_steps"] == 0 and r.stats["outputs_integrated_again"] > 0
    assert r.stats["range_evaluations"] < 600  # 1,100-1,600 at one flat position where steps collapsed; <= 322 now
    check_run(r, N, 1e-4, 1e-4, 1e-3)  # measured <= 2.1e-6 s, 1.4e-5 rad, 4.2e-5 J


@needs_c
def test_a_step_hiding_a_flat_position_between_ends_of_one_sign_is_halved():
    # rtol 1e-5: a step of 0.38 s held a flat position 13 ms after its start and the next
    # maximum of log det before its end, so the event function had one sign at both ends:
    # 3 of 20 passages went unrecorded before the chord between a step's ends was looked at
    N = 2
    r = mbcomp.simulate(nfb.build(N=N), **{**nfb.SIMULATION, "rtol": 1e-5, "atol": 1e-7})
    assert r.stats["python_steps"] == 0 and r.stats["steps_halved"] > 0
    check_run(r, N, 1e-2, 5e-2, 5e-2)  # rtol 1e-5: 1.3e-3 s, 9e-3 rad, 7e-3 J measured (Python path: 4.9e-2 rad)


@needs_c
def test_the_program_answers_the_monitor_from_the_start(monkeypatch):
    # on the Python path, the same run with the evaluations numeric until the lazy evaluator's
    # 200 ran out (before): the same steps and passages; the evaluations are the program's
    python_path(monkeypatch)

    def run():  # the lazy evaluator's own count (initialization's rows-only evaluations count as full ones)
        r = mbcomp.simulate(nfb.build(N=3), **{**nfb.SIMULATION, "t_end": 3.0})
        return r, r.system.evaluator.numeric_calls

    now, n_now = run()
    with monkeypatch.context() as m:
        m.setattr(monitors, "evaluate_by_program", lambda system: None)
        before, n_before = run()
    assert now.success and before.success
    assert n_before >= 200 > 50 > n_now  # initialization's and a few post-processing ones
    t_now = [p["t"] for p in now.stats["singular_passages"]]
    t_before = [p["t"] for p in before.stats["singular_passages"]]
    assert len(t_now) == len(t_before) == len(exact(3, now.time)[1]) == 3
    np.testing.assert_allclose(t_now, t_before, atol=1e-6)  # 1e-8 s measured
    assert np.max(np.abs(now["theta"] - before["theta"])) < 1e-6  # 2e-9 rad measured


@needs_c
def test_only_a_run_passing_singular_positions_evaluates_by_program_at_once():
    for singular, by_program in (("stop", False), ("pass", True)):
        system = system_of(nfb.build(N=2), None, "c")
        init = initialize(system)
        monitors.ConstraintRank(system, singular)
        system.evaluate(0.0, init.q, init.u, masked=False)
        assert (system.evaluator.bound is not None) == by_program  # lazy: numeric evaluations first
