"""Runs passing singular positions (``singular="pass"``): how they are stepped and evaluated.

The passages are stepped on the Python path (scipy's DOP853 over the compiled ``fun``, every
step watched by the rank monitor on its own dense output), and the rank monitor makes the
evaluation program at the start instead of after the lazy evaluator's 200 numeric evaluations
(docs/design/generated-programs.md, "Passing singular positions"; ``bench/singular_engine.py``).

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
from mbcomp.assembly.system import MultibodySystem
from mbcomp.codegen import c_compiler
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


@needs_c
def test_ten_parallelograms_pass_every_flat_position_at_its_time():
    # over 20 output grids and N = 2..10 the Python path's worst were 1.3e-4 s, 8.9e-4 rad and
    # 4.9e-4 J (a step ending next to a flat position); C stretches located passages on their
    # cubic between the stretch's ends 2.6e-3 s off at this request (bench/singular_engine.py)
    N = 10
    r = mbcomp.simulate(nfb.build(N=N), **nfb.SIMULATION)
    assert r.success, r.message
    theta, flats = exact(N, r.time)
    passages = r.stats["singular_passages"]
    assert len(flats) == 20 and len(passages) == 20
    np.testing.assert_allclose([p["t"] for p in passages], flats, atol=5e-4)
    assert all(p["rank_drop"] == N for p in passages)
    assert np.max(np.abs(r["theta"] - theta)) < 2e-3
    E = r["energy.total"]
    assert np.max(np.abs(E - E[0])) < 2e-3


@needs_c
def test_the_program_answers_the_monitor_from_the_start(monkeypatch):
    # the same run with the evaluations numeric until the lazy evaluator's 200 ran out (before):
    # the same steps and passages; the evaluations are the program's, not numeric
    def run():
        calls = []
        numeric = MultibodySystem.evaluate_numeric

        def counted(self, *a, **kw):
            calls.append(1)
            return numeric(self, *a, **kw)

        with monkeypatch.context() as m:
            m.setattr(MultibodySystem, "evaluate_numeric", counted)
            r = mbcomp.simulate(nfb.build(N=3), **{**nfb.SIMULATION, "t_end": 3.0})
        return r, len(calls)

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
