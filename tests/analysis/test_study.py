"""mbcomp.study: grids, build arguments, failed runs as rows, Monte Carlo seeds, what is kept,
and the executors -- a real Dask LocalCluster (2 worker processes on loopback) giving the
serial table bit for bit, also when a worker is killed mid-study (issue 19)."""
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import mbcomp
from mbcomp.library import PointMass, Prismatic, Torque, World

G = 9.81
CRANK = os.path.join(os.path.dirname(__file__), "..", "..", "models", "slider_crank.py")
BUILDS = []


def thrown(height=0.0):
    """A 1 kg point on a vertical slider ``s`` starting at ``height`` (m): s(t) = h + v0 t - g t^2 / 2."""
    BUILDS.append(height)
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=height, v0=0.0))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def final_s(res):
    return res["s.s"][-1]


def test_a_full_factorial_of_start_speeds_and_build_heights_follows_the_parabola():
    BUILDS.clear()
    out = mbcomp.study(thrown, {"height": [0.0, 2.0], "s.v0": [1.0, 3.0, 5.0]}, t_end=0.5,
                       metrics={"final": final_s}, rtol=1e-10, atol=1e-12)
    assert out.columns == ["height", "s.v0", "final", "status", "message", "cpu_time"] and len(out) == 6
    h, v0 = out["height"], out["s.v0"]
    np.testing.assert_allclose(out["final"], h + 0.5 * v0 - 0.5 * G * 0.25, atol=1e-9)
    assert sorted(BUILDS) == [0.0, 2.0]       # built once per structure, runtime values changed in place
    assert list(out["status"]) == ["success"] * 6 and np.all(out["cpu_time"] > 0)


def test_a_run_that_fails_is_a_row_naming_the_component_and_the_others_stand():
    def motor(t, phi, w):
        if w > 2.5:
            raise ValueError("the motor's table ends at 2.5 rad/s")
        return 0.0

    from conftest import turntable

    out = mbcomp.study(lambda: turntable(motor), {"j.w0": [1.0, 2.0, 3.0], "bob.m": [1.0, -1.0]}, t_end=0.2,
                       metrics={"turned": lambda r: r["j.phi"][-1]}, backend="numeric")
    status = dict(zip(zip(out["j.w0"], out["bob.m"]), out["status"]))
    msg = dict(zip(zip(out["j.w0"], out["bob.m"]), out["message"]))
    assert status[(1.0, 1.0)] == status[(2.0, 1.0)] == "success"
    assert "motor" in msg[(3.0, 1.0)] and "table ends at 2.5" in msg[(3.0, 1.0)]   # the law's raise, named
    assert status[(1.0, -1.0)] == "error" and "bob.m" in msg[(1.0, -1.0)]           # a bad value, named
    turned = dict(zip(zip(out["j.w0"], out["bob.m"]), out["turned"]))
    assert turned[(1.0, 1.0)] == pytest.approx(0.2, rel=1e-9) and turned[(2.0, 1.0)] == pytest.approx(0.4, rel=1e-9)
    assert out.stats["failed"] == 4


def test_monte_carlo_draws_repeat_with_the_seed_and_keep_what_was_asked():
    grid = {"s.v0": mbcomp.Uniform(1.0, 3.0), "height": 1.0}
    a = mbcomp.study(thrown, grid, samples=8, seed=3, t_end=0.2, keep="outputs", outputs=["s.s"])
    b = mbcomp.study(thrown, grid, samples=8, seed=3, t_end=0.2)
    c = mbcomp.study(thrown, grid, samples=8, seed=4, t_end=0.2)
    assert np.array_equal(a["s.v0"], b["s.v0"]) and not np.array_equal(a["s.v0"], c["s.v0"])
    assert np.all((a["s.v0"] >= 1.0) & (a["s.v0"] <= 3.0))
    kept = a.results[0]
    assert set(kept) == {"time", "s.s"} and kept["s.s"][0] == 1.0 and b.results is None
    full = mbcomp.study(thrown, {"s.v0": [2.0]}, t_end=0.2, keep="all").results[0]
    assert isinstance(full, mbcomp.Result) and full.success


def test_bad_requests_are_refused_with_the_fix():
    with pytest.raises(ValueError, match="needs samples="):
        mbcomp.study(thrown, {"s.v0": mbcomp.Normal(1.0, 0.1)})
    with pytest.raises(TypeError, match="metric 'x' must be a function"):
        mbcomp.study(thrown, {"s.v0": [1.0]}, metrics={"x": 3})
    with pytest.raises(TypeError, match="study\\(\\) takes a Model"):
        mbcomp.study(42, {"s.v0": [1.0]})


def test_a_process_pool_needs_what_it_can_pickle_and_says_so():
    model = thrown()
    model.add("t", Torque(tau=lambda t, s, v: 0.0))   # a lambda law: pickle cannot send it
    with ProcessPoolExecutor(1) as ex:
        with pytest.raises(TypeError, match="pass the model file's path"):
            mbcomp.study(model, {"s.v0": [1.0]}, executor=ex)


def test_without_dask_the_error_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ImportError, match=r"pip install 'mbcomp\[dask\]'"):
        mbcomp.study(CRANK, {"crank_joint.w0": [6.0]}, executor="dask")


def peak_pin(res):
    return float(np.abs(res["pin.f.y"]).max())


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    lc = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  host="127.0.0.1")
    client = distributed.Client(lc)
    yield client
    client.close()
    lc.close()


def test_a_local_cluster_gives_the_serial_table_bit_for_bit(cluster):
    grid = {"crank_joint.w0": np.linspace(2.0, 10.0, 9).tolist()}
    serial = mbcomp.study(CRANK, grid, t_end=0.5, metrics={"peak": peak_pin})
    on_dask = mbcomp.study(CRANK, grid, t_end=0.5, metrics={"peak": peak_pin}, executor=cluster)
    assert on_dask.stats["executor"] == "dask" and on_dask.stats["workers"] == 2
    assert np.array_equal(serial["peak"], on_dask["peak"]) and list(on_dask["status"]) == ["success"] * 9


def slow_peak(res):
    """The peak pin force, after 0.1 s of waiting: a study long enough to kill a worker in."""
    time.sleep(0.1)
    return peak_pin(res)


def test_a_worker_killed_mid_study_loses_no_run(cluster):
    grid = {"crank_joint.w0": np.linspace(3.0, 9.0, 40).tolist()}
    serial = mbcomp.study(CRANK, grid, t_end=1.0, metrics={"peak": peak_pin})
    box = {}
    worker = threading.Thread(target=lambda: box.update(res=mbcomp.study(
        CRANK, grid, t_end=1.0, metrics={"peak": slow_peak}, executor=cluster, chunk=2)))
    pids = cluster.run(os.getpid)
    worker.start()
    time.sleep(0.8)                                       # ~2 s of runs in all: both workers busy now
    assert worker.is_alive()
    victim = sorted(pids.values())[0]
    os.kill(victim, signal.SIGKILL)
    worker.join(timeout=240)
    assert not worker.is_alive()
    out = box["res"]
    assert len(out) == 40 and list(out["status"]) == ["success"] * 40
    assert np.array_equal(out["peak"], serial["peak"])
    assert victim not in cluster.run(os.getpid).values()  # the nanny started a new worker process


def test_runs_with_new_parameter_values_reuse_the_traced_programs(monkeypatch):
    """Nothing re-derived per run: after the first run of a structure, runs that change only
    component parameters trace nothing (they used to trace the right-hand side three times)."""
    from mbcomp.codegen import tracer

    grid = {"crank.m": mbcomp.Normal(1.0, 0.05), "crank_joint.w0": mbcomp.Uniform(5.7, 6.3)}
    mbcomp.study(CRANK, grid, samples=2, seed=0, t_end=0.2)        # this process's first runs
    traced = []
    real = tracer._trace
    monkeypatch.setattr(tracer, "_trace", lambda *a, **k: traced.append(a[2] if len(a) > 2 else "eval") or real(*a, **k))
    out = mbcomp.study(CRANK, grid, samples=12, seed=1, t_end=0.2)
    assert list(out["status"]) == ["success"] * 12
    assert len(traced) <= 3        # the new study's one structure: right-hand side, outputs (once each)


def test_a_law_given_as_a_run_parameter_that_cannot_be_traced_runs_numerically():
    import math

    from conftest import torque_pendulum
    from mbcomp.simulation.setup import system_of

    system = system_of(torque_pendulum(lambda t, phi, w: 0.1 * np.sin(t)), None, "auto")
    with pytest.warns(RuntimeWarning, match="running on the numeric evaluation"):
        res = mbcomp.simulate(system, t_end=1.0, params={"motor.tau": lambda t, phi, w: 0.1 * math.sin(t)})
    ref = mbcomp.simulate(torque_pendulum(lambda t, phi, w: 0.1 * np.sin(t)), t_end=1.0, backend="numeric")
    assert res.stats["backend"] == "numeric" and np.abs(res["hinge.phi"] - ref["hinge.phi"]).max() < 1e-12


RAISING = '''
import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World


def tau(t, phi, w):
    if w > 2.5:
        raise ValueError("the motor's table ends at 2.5 rad/s")
    return 0.0


def build():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1)))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=tau))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    return m
'''


def test_a_law_raising_on_a_worker_comes_back_as_a_row_naming_the_component(cluster, tmp_path):
    path = tmp_path / "raising.py"
    path.write_text(RAISING)
    out = mbcomp.study(str(path), {"j.w0": [1.0, 3.0]}, t_end=0.2, executor=cluster, backend="numeric",
                       metrics={"turned": lambda r: r["j.phi"][-1]})
    assert out.stats["executor"] == "dask" and list(out["status"]) == ["success", "error"]
    assert "Torque 'motor'" in out["message"][1] and "table ends at 2.5" in out["message"][1]
    assert out["turned"][0] == pytest.approx(0.2, rel=1e-9) and np.isnan(out["turned"][1])
