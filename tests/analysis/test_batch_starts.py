"""A batch's starts made by forked worker processes (mbcomp.analysis.batch_starts).

The workers run the same initialization on the same numbers, so a batch whose starts they make
is bit for bit the batch whose starts this process makes (states, statuses, messages, counts);
the choice to use them follows the measured costs (a closed loop's Newton closure is worth
workers, an open chain's start is not); an interrupt stops them and keeps the finished runs;
a daemon process (a Dask worker) does not fork."""
import multiprocessing
import os
import time

import numpy as np
import pytest

import mbcomp
from mbcomp.analysis.batch_starts import ForkedStarts, fork_workers, run_start
from mbcomp.codegen.toolchain import c_compiler
from conftest import load_model

pytestmark = [pytest.mark.skipif(c_compiler() is None, reason="a batch needs a C compiler"),
              pytest.mark.skipif(not fork_workers(1, 2), reason="no safe fork here (not Linux)")]

PENDULUM = load_model("models/n_link_pendulum.py").build
SLIDER = load_model("models/slider_crank.py").build


def slider_table(n, seed=0):
    rng = np.random.default_rng(seed)
    return {"crank_joint.phi0": rng.uniform(0.0, 2 * np.pi, n), "crank_joint.w0": rng.uniform(2.0, 8.0, n),
            "rod.m": rng.uniform(1.5, 2.5, n)}


def assert_same_batch(a, b):
    assert a.names == b.names
    for name in a.names:
        np.testing.assert_array_equal(a[name], b[name])
    assert list(a.status) == list(b.status) and a.message == b.message
    for key in ("nfev", "nsteps", "nreject", "c_status"):
        np.testing.assert_array_equal(a.stats[key], b.stats[key])


def test_forked_starts_are_the_starts_made_here_bit_for_bit():
    table = slider_table(40)
    # run 7 cannot start: with its crank 5 m long the loop cannot close at the crank's fixed angle
    table["crank_tip.r"] = [(0.2, 0.0, 0.0)] * 40
    table["crank_tip.r"][7] = (5.0, 0.0, 0.0)
    here = mbcomp.batch(SLIDER(), table, t_end=0.5, n_out=26, outputs=["pin.f.y"], processes=0, block=8)
    forked = mbcomp.batch(SLIDER(), table, t_end=0.5, n_out=26, outputs=["pin.f.y"], processes=2, block=8)
    assert here.stats["processes"] == 0 and forked.stats["processes"] == 2
    assert here.status[7] == "error" and "crank_joint.phi" in here.message[7], here.message[7]
    assert "over-specify" in here.message[7]
    assert_same_batch(here, forked)
    # ... and each start is the consistent start simulate makes: the loop closed, the crank angle as given
    q0 = forked["crank_joint.phi"][:, 0]
    ok = forked.status == "success"
    np.testing.assert_array_equal(q0[ok], np.asarray(table["crank_joint.phi0"])[ok])
    r = mbcomp.simulate(SLIDER(), t_end=0.5, n_out=26, params={k: v[3] for k, v in table.items()})
    np.testing.assert_array_equal(forked["slider_joint.s"][3], r["slider_joint.s"])


def test_forked_starts_in_order_and_each_start_as_run_start_makes_it():
    model = SLIDER()
    system = mbcomp.assemble(model)
    table = slider_table(7, seed=3)
    req = dict(t_start=0.0, stabilization="baumgarte", alpha=10.0, beta=10.0, method="dop853")
    with ForkedStarts(system, table, req, 2, 7, 2, 2) as starts:
        got = starts.take(2, 5) + starts.take(5, 7)
        with pytest.raises(ValueError, match="in order"):
            starts.take(2, 3)
    for i, (y0, mask, message) in zip(range(2, 7), got):
        s, _, want = run_start(system, {k: v[i] for k, v in table.items()}, req)
        assert message is None
        np.testing.assert_array_equal(y0, want)
        np.testing.assert_array_equal(mask, s.row_mask)
        assert not mask.all()   # the slider-crank's redundant rows are dropped, per run


@pytest.mark.skipif(len(getattr(os, "sched_getaffinity", lambda _: [])(0)) < 2,
                    reason="workers pay only with two cores or more (Linux)")
def test_workers_are_used_where_the_starts_are_the_bottleneck():
    # a closed loop: ~2 ms of Newton closure a start against ~0.6 ms a run in C -> workers
    loop = mbcomp.batch(SLIDER(), slider_table(300), t_end=10.0, rtol=1e-6, atol=1e-8, threads=2)
    assert loop.stats["processes"] >= 2, loop.stats
    # an open chain: ~0.5 ms a start against ~1.1 ms a run in C -> the starts stay here (making
    # the output program, in the first run, is not a start's cost)
    rng = np.random.default_rng(0)
    chain = mbcomp.batch(PENDULUM(N=5), {f"joint{k}.phi0": rng.uniform(-0.3, 0.3, 300) for k in range(1, 6)},
                         t_end=10.0, rtol=1e-6, atol=1e-8, threads=2, outputs=["joint1.f.y"])
    assert chain.stats["processes"] == 0, chain.stats
    # the C threads' CPU time is measured (it decides): at most all threads busy all the time
    for res in (loop, chain):
        assert 0 < res.stats["c_cpu_time"] <= 2 * res.stats["integrate_time"] * 1.05 + 0.05, res.stats


def test_ctrl_c_stops_the_workers_and_keeps_what_finished():
    import _thread
    import threading

    table = slider_table(3000, seed=5)
    mbcomp.batch(SLIDER(), {k: v[:2] for k, v in table.items()}, t_end=2.0)   # compiled before the clock
    err = None
    for delay in (0.3, 0.9, 2.7):   # a loaded machine may still be starting at 0.3 s: later then
        timer = threading.Timer(delay, _thread.interrupt_main)
        timer.start()
        try:
            mbcomp.batch(SLIDER(), table, t_end=2.0, processes=2, block=16)
        except mbcomp.errors.SimulationInterrupted as exc:
            err = exc
        except KeyboardInterrupt:
            continue
        finally:
            timer.cancel()
        assert err is not None, "the batch of 3,000 runs ended before the interrupt"
        if (err.result.status == "success").any():
            break
    deadline = time.monotonic() + 10.0
    while multiprocessing.active_children() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not multiprocessing.active_children()   # no worker left behind
    res = err.result
    done = np.flatnonzero(res.status == "success")
    assert 0 < len(done) < 3000 and set(res.status) <= {"success", "interrupted"}
    again = mbcomp.batch(SLIDER(), {k: v[done[-2:]] for k, v in table.items()}, t_end=2.0, processes=0)
    np.testing.assert_array_equal(again["slider_joint.s"], res["slider_joint.s"][done[-2:]])


def _in_a_daemon(queue):
    queue.put((fork_workers(1000, 2), fork_workers(1000, None)))


def test_no_fork_in_a_daemon_and_bad_counts_are_refused():
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    p = ctx.Process(target=_in_a_daemon, args=(queue,), daemon=True)
    p.start()
    assert queue.get(timeout=60) == (0, 0)   # a daemon may not have children: the starts stay in it
    p.join(10)
    assert fork_workers(1000, None) is None and fork_workers(10, None) == 0 and fork_workers(10, 3) == 3
    with pytest.raises(ValueError, match="processes=-1"):
        mbcomp.batch(SLIDER(), {"rod.m": [1.0]}, t_end=0.1, processes=-1)


def test_a_warning_raised_in_a_worker_reaches_the_caller():
    import warnings

    # run 2's 1 ug tip link makes the mass matrix ill-conditioned: initialization warns, naming it
    table = {"link3.m": [1.0, 1.0, 1e-9, 1.0], "link3.I": [np.diag([0.02, 0.0, 0.02])] * 2 + [np.diag([1e-12] * 3)]
             + [np.diag([0.02, 0.0, 0.02])]}
    said = {}
    for processes in (0, 2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = mbcomp.batch(PENDULUM(N=3), table, t_end=0.2, n_out=3, processes=processes)
        assert res.stats["processes"] == processes and list(res.status) == ["success"] * 4
        said[processes] = {str(w.message) for w in caught if "ill-conditioned" in str(w.message)}
    assert len(said[0]) == 1 and "link3 (1e-09 kg)" in next(iter(said[0]))
    assert said[2] == said[0]   # made in a worker (run 2 is past the first run), said here


def test_forked_starts_by_the_evaluation_program_are_the_same_too():
    # initialization="program": the workers inherit the compiled evaluation program the first run bound
    table = slider_table(24, seed=9)
    here = mbcomp.batch(SLIDER(), table, t_end=0.5, n_out=11, initialization="program", processes=0)
    forked = mbcomp.batch(SLIDER(), table, t_end=0.5, n_out=11, initialization="program", processes=2)
    assert forked.stats["processes"] == 2
    assert_same_batch(here, forked)


def test_a_worker_killed_mid_batch_leaves_its_starts_to_this_process():
    import signal

    table = slider_table(600, seed=11)
    killed = []

    def kill_a_worker(run):   # the metric: at the first run read, a worker is killed (SIGKILL: its task is lost)
        if not killed:
            workers = multiprocessing.active_children()
            assert workers
            os.kill(workers[0].pid, signal.SIGKILL)
            killed.append(workers[0].pid)
        return run["slider_joint.s"][-1]

    with pytest.warns(RuntimeWarning, match="worker process making the runs' starts ended"):
        hit = mbcomp.batch(SLIDER(), table, t_end=0.2, n_out=5, processes=2, block=16, reduce=kill_a_worker)
    calm = mbcomp.batch(SLIDER(), table, t_end=0.2, n_out=5, processes=0, block=16)
    assert killed and hit.stats["processes"] == 2
    assert_same_batch(hit, calm)   # every run, its start made by whichever process
    np.testing.assert_array_equal(hit.reduced, calm["slider_joint.s"][:, -1])
