"""The N-four-bar (models/n_four_bar.py): N parallelograms through their flat positions.

Independent reference: the chain moves as one parallelogram (every crank at the same angle
theta, couplers level), so theta obeys the one-degree-of-freedom equation derived here from
the energy: ``J theta'' = -dV/dtheta`` with ``J = m L^2 ((N + 1) / 3 + N)`` (cranks about their
pivots, couplers translating with the tips) and ``V = m g L sin(theta) ((N + 1) / 2 + N)``.
Every time theta passes a multiple of pi, all 2N + 1 links lie on the ground line and the
closure Jacobian loses rank N (each parallelogram's row along the links): ``singular="pass"``
must go through all of them on the parallelogram branch and record each; ``"stop"`` (the
default) must end the run at the first with the clear message.
"""
import functools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model

nfb = load_model("models/n_four_bar.py")
T_END = 20.0
TOL = dict(rtol=1e-8, atol=1e-10)


@functools.lru_cache(maxsize=None)
def exact(N, t_end=T_END, m=1.0, L=1.0, g=9.81, w0=1.0):
    """The output times (10 a second), theta(t) there and the times theta crosses a multiple
    of pi (the flat positions)."""
    J = m * L ** 2 * ((N + 1) / 3 + N)
    k = m * g * L * ((N + 1) / 2 + N)
    flat = lambda t, y: np.sin(y[0])  # noqa: E731
    ts = np.linspace(0.0, t_end, int(round(10 * t_end)) + 1)
    sol = solve_ivp(lambda t, y: [y[1], -k * np.cos(y[0]) / J], (0, t_end), [np.pi / 2, w0], t_eval=ts,
                    events=flat, rtol=1e-13, atol=1e-13, method="DOP853")
    return ts, sol.y[0], sol.t_events[0]


RUNS = {
    "dalembert": dict(formulation="dalembert", method="DOP853"),
    "lagrange projection": dict(method="dop853"),  # singular="pass": projection by default
    "genalpha": dict(method="genalpha", h=2e-3),
}
# N = 40 (rank drop 40 at every flat position) runs the Lagrange form over its first three flat
# passages with the Python backend: 7 s of CPU with a cold program cache or a warm one (15 s over six), where
# the C program of N = 40 takes 40 s of gcc when the cache is cold (over 20 s: 24 s of CPU, an
# error of 3.7e-6 rad against 2.3e-7 over 6 s; the C path runs at N = 2). D'Alembert (108 s
# with a cold program cache: its evaluation program is O(N^2)) and generalized-alpha (200 s)
# at N = 40 are measured by bench/singular.py: within 2.9e-4 and 4.8e-5 rad of the exact
# motion, every passage recorded.
CASES = [(2, name, T_END, {}) for name in RUNS] + [(40, "lagrange projection", 3.0, dict(backend="python"))]


@pytest.mark.parametrize("N, name, t_end, extra", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_pass_goes_through_every_flat_position_on_the_exact_motion(N, name, t_end, extra):
    ts, theta, flats = exact(N, t_end)
    r = mbcomp.simulate(nfb.build(N=N), t_end=t_end, n_out=len(ts), singular="pass", **{**TOL, **RUNS[name], **extra})
    assert r.success, r.message
    assert len(flats) >= 0.9 * t_end  # about one flat passage a second
    err = np.max(np.abs(r["theta"] - theta))
    assert err < 1e-3, err
    # every passage recorded once, at its time, with the rank drop and the loops' joints
    passages = r.stats["singular_passages"]
    assert len(passages) == len(flats)
    np.testing.assert_allclose([p["t"] for p in passages], flats, atol=1e-3)
    assert all(p["rank_drop"] == N for p in passages)
    assert set(passages[0]["joints"]) == {f"crank{k}_pivot" for k in range(1, N + 1)}
    # no energy lost or gained through the passages
    E = r["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-2 * N


def test_stop_reports_the_first_flat_position():
    N, flats = 2, exact(2)[2]
    r = mbcomp.simulate(nfb.build(N=N), t_end=T_END, **TOL)
    assert r.status == "failed" and "singular position at t=" in r.message
    t_reported = float(r.message.split("singular position at t=")[1].split(":")[0])
    assert abs(t_reported - flats[0]) < 1e-6
    assert r.time[-1] <= flats[0]


def test_pass_refuses_what_cannot_pass():
    with pytest.raises(ValueError, match="stabilization='projection'"):
        mbcomp.simulate(nfb.build(N=2), t_end=1.0, singular="pass", stabilization="baumgarte")
    with pytest.raises(ValueError, match="Newton matrix is singular"):
        mbcomp.simulate(nfb.build(N=2), t_end=1.0, singular="pass", method="radau5")
    with pytest.raises(ValueError, match="'stop'.*'pass'"):
        mbcomp.simulate(nfb.build(N=2), t_end=1.0, singular="go")


def test_the_command_line_passes_and_reports(capsys):
    from mbcomp.cli.main import main

    assert main(["simulate", str(nfb.__file__), "-q", "--t-end", "1.5", "-p", "N=2"]) == 0  # the file asks "pass"
    out = capsys.readouterr().out
    assert out.count("passed a singular position at t = ") == 2
    assert main(["simulate", str(nfb.__file__), "-q", "--t-end", "1.5", "-p", "N=2", "--singular", "stop"]) == 1
