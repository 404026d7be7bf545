"""scipy's integrators as mbcomp steppers (mbcomp.solvers.scipy_adapter).

The driver moves the state after accepted steps (projection) through ``reset_state``: a
one-step method continues from the moved state with its stored derivative refreshed, a
multistep method restarts only when the move exceeds ``RESTART_DRIFT`` tolerance units. Checked on ``y' = -2 y``
(exact solution known from any state) and on a four-bar kept on its manifold by projection.
"""
from types import SimpleNamespace

import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.simulation import ALL_METHODS
from mbcomp.solvers import SCIPY_STEPPERS, STEPPERS
from mbcomp.solvers.base import RESTART_DRIFT

DECAY = SimpleNamespace(fun=lambda t, y: -2.0 * y)
TOL = dict(rtol=1e-10, atol=1e-12)


def step_to(s, t):
    while s.status == "running" and s.t < t:
        assert s.step() is None
    return s


def finish(s):
    while s.status == "running":
        assert s.step() is None
    return s


@pytest.mark.parametrize("name", ["RK23", "RK45", "DOP853", "Radau"])
def test_a_one_step_method_continues_from_the_moved_state(name):
    s = step_to(SCIPY_STEPPERS[name](DECAY, 0.0, [1.0], 1.0, **TOL), 0.3)
    t1, y1 = s.t, 1.5 * s.y  # the "projection" moves the state by half
    s.reset_state(y1)
    assert s.solver.f == pytest.approx(-2.0 * y1)  # the stored derivative is the moved state's
    finish(s)
    assert s.stats["restarts"] == 0 and s.status == "finished" and s.t == 1.0
    assert s.y[0] == pytest.approx(y1[0] * np.exp(-2.0 * (1.0 - t1)), rel=1e-7)


@pytest.mark.parametrize("name", ["BDF", "LSODA"])
def test_a_multistep_method_restarts_only_when_the_move_exceeds_the_tolerance(name):
    s = step_to(SCIPY_STEPPERS[name](DECAY, 0.0, [1.0], 1.0, **TOL), 0.3)
    work = dict(s.stats)
    y0 = s.y.copy()
    unit = TOL["atol"] + TOL["rtol"] * abs(y0[0])  # one tolerance unit at this state
    s.reset_state(y0 + 0.5 * RESTART_DRIFT * unit)  # within the drift budget: it keeps its own state
    assert s.stats["restarts"] == 0 and s.y[0] == y0[0]
    s.reset_state(y0 + 2.0 * RESTART_DRIFT * unit)  # beyond it: restart from the moved state
    assert s.stats["restarts"] == 1 and s.y[0] == y0[0] + 2.0 * RESTART_DRIFT * unit
    t1, y1 = s.t, 1.5 * s.y
    s.reset_state(y1)
    assert s.stats["restarts"] == 2 and s.y[0] == y1[0]
    finish(s)
    assert s.y[0] == pytest.approx(y1[0] * np.exp(-2.0 * (1.0 - t1)), rel=1e-7)
    # the work of the replaced solver is kept in the counters
    assert s.stats["nsteps"] > work["nsteps"] and s.stats["nfev"] > work["nfev"] and s.stats["nlu"] >= work["nlu"]


def test_a_collapsing_step_size_is_a_failure_naming_method_and_time():
    """``y' = y^2, y(0) = 1`` blows up at t = 1: the step fails there, with a message."""
    s = SCIPY_STEPPERS["RK45"](SimpleNamespace(fun=lambda t, y: y * y), 0.0, [1.0], 2.0, **TOL)
    msg = None
    while s.status == "running":
        msg = s.step()
    assert s.status == "failed"
    assert msg.startswith("the integrator RK45 failed at t=") and "step size collapsed" in msg
    assert float(msg.split("t=")[1].split(":")[0]) == pytest.approx(1.0, abs=1e-3)


def test_every_method_is_one_registry_entry_with_declared_capabilities():
    assert ALL_METHODS == tuple(STEPPERS) == ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA", "auto", "dop853",
                                               "dopri5", "radau5", "ida", "genalpha")
    multistep = {name for name, cls in STEPPERS.items() if not cls.one_step}
    assert multistep == {"BDF", "LSODA", "ida"}
    assert {name for name, cls in STEPPERS.items() if cls.problem == "ode"} == set(SCIPY_STEPPERS) | {"auto", "dop853", "dopri5"}
    assert {name for name, cls in STEPPERS.items() if cls.needs_outputs} == {"auto", "dop853", "dopri5"}


def test_projection_with_bdf_rarely_restarts_and_keeps_the_loop_closed():
    """A four-bar with projection after every step: BDF keeps its own state while the
    correction stays within the drift budget (restarting at order 1 after every few steps
    cost 10-50x the work and accuracy), the outputs stay on the loop; RK45 never restarts."""
    fb = load_model("models/four_bar.py")
    runs = {m: mbcomp.simulate(fb.build(), t_end=0.1, n_out=11, method=m, stabilization="projection",
                               rtol=1e-6, atol=1e-8, backend="python") for m in ("BDF", "RK45")}
    for m, res in runs.items():
        assert res.success, res.message
        assert res.stats["projections"] > 0 and np.max(res["residual.position"]) < 1e-10, m
    assert runs["BDF"].stats["restarts"] <= 0.05 * runs["BDF"].stats["steps"] and runs["RK45"].stats["restarts"] == 0
    np.testing.assert_allclose(runs["BDF"]["crank_angle"], runs["RK45"]["crank_angle"], atol=1e-3)
