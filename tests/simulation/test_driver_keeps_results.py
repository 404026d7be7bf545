"""A run that cannot go on still returns its results: a law that raises, Ctrl-C, SIGTERM.

An interrupted run raises :class:`mbcomp.errors.SimulationInterrupted` (a
``KeyboardInterrupt``: a script must not carry on as if the run had finished) carrying the
partial result; the other endings return it.

Every case uses a pendulum driven by a torque law that misbehaves from t = 0.3 s and is zero
before: up to the last accepted step the run is the undisturbed pendulum's, so the kept
results must equal an undisturbed run's at the same times (same steps, same dense output),
stop before 0.3 s, and the message must say what stopped the run and when.
"""
import os
import re
import signal
import threading

import numpy as np
import pytest

import mbcomp
from conftest import torque_pendulum
from mbcomp.errors import SimulationInterrupted
from mbcomp.library import WorldForce

T_BAD = 0.3
METHODS = ["RK45", "LSODA", "radau5", "ida", "genalpha"]


def run(law, method):
    extra = dict(h=1e-3) if method == "genalpha" else {}
    return mbcomp.simulate(torque_pendulum(law), t_end=1.0, method=method, n_out=101, rtol=1e-8, atol=1e-10, **extra)


def interrupted(call, signal_name):
    """The partial result an interrupted ``call()`` carries (it must raise, naming the signal)."""
    with pytest.raises(SimulationInterrupted) as info:
        call()
    assert info.value.signal == signal_name and str(info.value) == info.value.result.message
    return info.value.result


def quiet(t, phi, w):
    return 0.0


@pytest.fixture(scope="module")
def undisturbed():
    return {method: run(quiet, method) for method in METHODS}


def assert_kept_as_undisturbed(res, ref):
    n = len(res.time)
    assert 1 < n < len(ref.time)
    assert res.time[-1] < T_BAD and res.time[-1] >= T_BAD - 0.05  # up to the last accepted step
    np.testing.assert_array_equal(res.time, ref.time[:n])
    for name in ("hinge.phi", "hinge.w", "bob.r.x", "energy.total"):
        np.testing.assert_allclose(res[name], ref[name][:n], rtol=0, atol=1e-12, err_msg=name)


def torque_table(t, phi, w):
    if t >= T_BAD:
        raise ValueError("the torque table ends at 0.3 s")
    return 0.0


@pytest.mark.parametrize("method", METHODS)
def test_a_law_that_raises_ends_the_run_as_a_failed_result_naming_component_law_and_time(method, undisturbed):
    res = run(torque_table, method)
    assert res.status == "failed"
    assert "Torque 'motor'" in res.message and "torque_table raised ValueError" in res.message, res.message
    assert "the torque table ends at 0.3 s" in res.message and "test_driver_keeps_results.py" in res.message
    t_raised = float(re.search(r"raised ValueError at t=([0-9.e+-]+)", res.message).group(1))
    assert T_BAD <= t_raised < T_BAD + 0.05  # the time of the evaluation that raised
    assert f"results up to t={res.time[-1]:g} s are kept" in res.message
    assert_kept_as_undisturbed(res, undisturbed[method])


def test_a_force_law_that_raises_is_named_too(undisturbed):
    """A WorldForce on the bob whose law fails at 0.3 s (zero before): same pendulum."""
    def push(t, frame):
        if t >= T_BAD:
            raise RuntimeError("sensor lost")
        return (0.0, 0.0, 0.0)

    m = torque_pendulum(quiet)
    f = m.add("push", WorldForce(f=push))
    m.connect(m["bob"].frame_a, f.frame_b)
    res = mbcomp.simulate(m, t_end=1.0, method="RK45", n_out=101, rtol=1e-8, atol=1e-10)
    assert res.status == "failed"
    assert res.message.startswith("WorldForce 'push': push raised RuntimeError at t=0.3"), res.message
    assert_kept_as_undisturbed(res, undisturbed["RK45"])


@pytest.mark.parametrize("method", METHODS)
def test_ctrl_c_raises_with_the_partial_result_as_interrupted(method, undisturbed):
    def ctrl_c(t, phi, w):
        if t >= T_BAD:
            raise KeyboardInterrupt
        return 0.0

    res = interrupted(lambda: run(ctrl_c, method), "SIGINT")
    assert res.status == "interrupted" and not res.success
    assert res.message.startswith("interrupted by Ctrl-C"), res.message
    assert_kept_as_undisturbed(res, undisturbed[method])


def main_thread_only():
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")


@pytest.mark.parametrize("method", ["RK45", "ida"])
def test_sigterm_returns_the_partial_result_and_restores_the_handler(method, undisturbed):
    main_thread_only()
    received = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: received.append(signum))  # never kill the run
    sent = []

    def terminate(t, phi, w):
        if t >= T_BAD and not sent:
            sent.append(t)
            os.kill(os.getpid(), signal.SIGTERM)
        return 0.0

    try:
        mine = signal.getsignal(signal.SIGTERM)
        res = interrupted(lambda: run(terminate, method), "SIGTERM")
        assert signal.getsignal(signal.SIGTERM) is mine  # restored after the run
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert sent and not received  # the driver's handler took the signal, not the previous one
    assert res.status == "interrupted"
    assert res.message.startswith("interrupted by SIGTERM"), res.message
    assert_kept_as_undisturbed(res, undisturbed[method])


def test_sigterm_from_a_timer_interrupts_a_long_run():
    """A run that would take most of a minute, stopped by SIGTERM from another thread 0.3 s
    (wall clock) after it started integrating: interrupted, with what was reached kept."""
    main_thread_only()
    timers = []

    def law(t, phi, w):  # starts the timer once the integration runs
        if t > 0.0 and not timers:
            timers.append(threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM)))
            timers[0].start()
        return 0.0

    previous = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    try:
        # on the numeric path, where the law runs at every step (a compiled program calls it
        # only while tracing, which would start the timer before the integration)
        res = interrupted(lambda: mbcomp.simulate(torque_pendulum(law), t_end=2000.0, method="RK45", dt_out=0.01,
                                                  rtol=1e-10, atol=1e-12, backend="numeric"), "SIGTERM")
    finally:
        timers[0].cancel()
        signal.signal(signal.SIGTERM, previous)
    assert res.status == "interrupted" and "SIGTERM" in res.message
    assert 0.1 < res.time[-1] < 2000.0
    # what was kept is the pendulum: energy conserved to the tolerance
    assert np.ptp(res["energy.total"]) < 1e-6


def test_sigterm_stops_the_compiled_engine_with_what_it_reached():
    """The C engine integrates stretches of outputs without Python: a SIGTERM 0.5 s into a
    run that would take minutes ends it at a stretch's end, interrupted, and what was
    reached is the pendulum (energy conserved to the tolerance)."""
    main_thread_only()
    from mbcomp.codegen import c_compiler

    if c_compiler() is None:
        pytest.skip("no C compiler: no compiled engine")
    fast = mbcomp.codegen.compile_system(mbcomp.assemble(torque_pendulum(quiet)), "c")
    mbcomp.simulate(fast, t_end=0.1, method="dop853")  # programs made and loaded before the clock starts
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGTERM))
    try:
        timer.start()
        res = interrupted(lambda: mbcomp.simulate(fast, t_end=1e6, method="dop853", dt_out=10.0, rtol=1e-10,
                                                  atol=1e-12), "SIGTERM")
    finally:
        timer.cancel()
        signal.signal(signal.SIGTERM, previous)
    assert res.status == "interrupted" and "SIGTERM" in res.message
    assert res.stats["backend"] == "c" and res.stats["stretches"] > 0 and res.stats["nfev"] > 0
    assert 1000.0 < res.time[-1] < 1e6
    # DOP853 is not symplectic: its energy error grows linearly with time (~4e-9 J per 1000 s
    # here), so the check covers the first 1000 s, however far a fast machine got
    assert np.ptp(res["energy.total"][res.time <= 1000.0]) < 1e-7


def test_a_run_in_a_worker_thread_installs_no_handler():
    """Signals can only be handled in the main thread: there the driver leaves them alone."""
    out = {}
    before = signal.getsignal(signal.SIGTERM)
    worker = threading.Thread(target=lambda: out.update(res=run(quiet, "RK45")))
    worker.start()
    worker.join()
    assert out["res"].success and signal.getsignal(signal.SIGTERM) is before
    assert abs(out["res"]["hinge.phi"][-1] - run(quiet, "RK45")["hinge.phi"][-1]) < 1e-12
