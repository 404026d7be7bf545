"""A failing law is named by its own name, wherever inside numpy or scipy the error surfaced."""
import numpy as np

import mbcomp
from conftest import torque_pendulum
from mbcomp.modeling.blame import blame


def singular_gain(t, phi, w):
    """A torque law that inverts a matrix that becomes singular at t = 0.3 s."""
    K = np.array([[1.0, 0.0], [0.0, max(0.0, 0.3 - t)]])
    return -float(np.linalg.inv(K)[1, 1]) * 1e-3 * w


def test_numpy_raising_inside_a_law_blames_the_law():
    try:
        singular_gain(0.5, 0.0, 1.0)
    except np.linalg.LinAlgError as exc:
        b = blame(exc)
    assert b.law == "singular_gain" and "test_blame.py" in b.where and b.component is None


def test_the_run_names_component_and_law_not_numpy():
    m = torque_pendulum(singular_gain)
    # rtol 1e-6 keeps the output grid's last kept point past 0.2 s (at the default 1e-8 the
    # step that failed began at 0.17 s: a step's stages reach ahead of its accepted end)
    res = mbcomp.simulate(m, t_end=1.0, n_out=101, rtol=1e-6, atol=1e-8)
    assert res.status == "failed"
    assert "motor" in res.message and "singular_gain" in res.message and "LinAlgError" in res.message
    assert 0.2 < res.time[-1] < 0.3  # results up to the last accepted step before the law failed


def test_the_frameworks_own_numpy_failure_is_no_law():
    """A LinAlgError raised by numpy inside mbcomp's own code (no user or component code in
    between) names no law, so the driver reports it as the linear-algebra failure it is."""
    from mbcomp.assembly.manifold import solve_speeds
    from mbcomp.simulation.endings import raised_in_a_law

    try:
        solve_speeds(np.array([[np.nan, 1.0]]), np.array([1.0]), np.zeros(2))
    except np.linalg.LinAlgError as exc:
        inner = exc.with_traceback(exc.__traceback__.tb_next)  # drop this test's own frame
    assert blame(inner).law == "?" and not raised_in_a_law(inner)
