"""``simulate(..., error_estimate=True)``: the global error measured by a companion run at
100x tighter tolerances (issue 30, item 5).

Reference: a 1 m pendulum released from 3 rad (near the top, where its period depends
steeply on its amplitude), its exact motion by scipy's DOP853 at 1e-13 on the pendulum
equation, written here without mbcomp. Its energy stays right to 1e-9, so no energy alarm
rings, while its phase drifts by millimetres in 200 s: the estimate must see that error, and
be the size of the true one.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.simulation.error_estimate import RTOL_FLOOR, TIGHTER


def pendulum(phi0):
    """The 1 m, 1 kg pendulum of tests/simulation/test_accuracy_alarm.py released from ``phi0`` (rad)."""
    from test_accuracy_alarm import pendulum as accuracy_pendulum

    return accuracy_pendulum(phi0=phi0)


def exact(phi0, t):
    sol = solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, t[-1]), [phi0, 0.0], t_eval=t, rtol=1e-13,
                    atol=1e-13, method="DOP853")
    return sol.y


@pytest.mark.parametrize("formulation,method", [("lagrange", "dop853"), ("dalembert", "dop853"),
                                                ("lagrange", "radau5"), ("dalembert", "DOP853")])
def test_the_estimate_is_the_true_phase_error_that_no_alarm_sees(formulation, method):
    kw = dict(rtol=1e-6, atol=1e-8) if method == "radau5" else {}
    r = mbcomp.simulate(pendulum(3.0), t_end=200.0, n_out=201, formulation=formulation, method=method,
                        error_estimate=True, **kw)
    phi, w = exact(3.0, r.time)
    true = {"j.phi": np.max(np.abs(r["j.phi"] - phi)), "j.w": np.max(np.abs(r["j.w"] - w))}
    est = r.stats["error_estimate"]
    assert r.status == "success", r.message  # the energy is right: no alarm can see the phase error
    E = r["energy.total"]
    assert np.ptp(E) / E[0] < 1e-5  # relative energy drift, while the phase is off by > 1e-4 below
    for col in ("j.phi", "j.w"):
        assert true[col] > 1e-4  # a real error, well above the energy's
        assert 0.9 * true[col] < est[col] < 1.1 * true[col], (col, est[col], true[col])
    assert r.stats["global_error"] == max(est["j.phi"], est["j.w"])
    assert r.stats["global_error_column"] in ("j.phi", "j.w")
    assert r.stats["error_estimate_rtol"] == pytest.approx(TIGHTER * kw.get("rtol", 1e-8))
    assert set(est) >= {"j.phi", "j.w", "energy.total", "bob.frame_a.r.x"} if "bob.frame_a.r.x" in r else True


def test_a_small_error_is_estimated_small():
    """1 rad, 20 s at the defaults: the true error is ~1e-7 rad; the estimate is that too."""
    r = mbcomp.simulate(pendulum(1.0), t_end=20.0, n_out=101, error_estimate=True)
    phi, _ = exact(1.0, r.time)
    true = np.max(np.abs(r["j.phi"] - phi))
    assert true < 1e-5 and 0.5 * true < r.stats["error_estimate"]["j.phi"] < 2 * true


def test_at_the_rtol_floor_the_estimate_says_it_cannot_check():
    r = mbcomp.simulate(pendulum(1.0), t_end=1.0, n_out=11, rtol=1e-12, atol=1e-14, error_estimate=True)
    assert r.stats["error_estimate_rtol"] == RTOL_FLOOR
    assert "floor" in r.stats["error_estimate_note"]


def test_without_the_option_there_is_no_companion_run():
    r = mbcomp.simulate(pendulum(1.0), t_end=1.0, n_out=11)
    assert "global_error" not in r.stats and "error_estimate" not in r.stats
