"""mbcomp.batch: many parameter sets in one compiled call, each run what simulate gives.

Every run of a batch is held to :func:`mbcomp.simulate` with the same parameters to 1e-12
(states and output columns), on the 5-link pendulum (an open chain, chaotic: any difference in
the steps would grow) and the slider-crank (a closed loop: consistent initialization per run).
A failed run is reported with its reason and the others are kept; threads give the numbers one
thread gives; bad input is refused naming the column and the fix."""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen.toolchain import c_compiler
from conftest import load_model

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="a batch needs a C compiler")

PENDULUM = load_model("models/n_link_pendulum.py").build
SLIDER = load_model("models/slider_crank.py").build
REQUEST = dict(t_end=2.0, rtol=1e-8, atol=1e-10, n_out=121)


def close_to_simulate(model, table, outputs, **request):
    """Each run of the batch against simulate of its parameters; the worst differences per column."""
    b = mbcomp.batch(model, table, outputs=outputs, threads=2, **request)
    assert list(b.status) == ["success"] * len(b)
    worst = {}
    for i in range(len(b)):
        r = mbcomp.simulate(model, params={k: v[i] for k, v in table.items()}, **request)
        assert r.status == "success"
        np.testing.assert_array_equal(b.time, r.time)
        for name in b.names:
            scale = max(1.0, float(np.max(np.abs(r[name]))))
            worst[name] = max(worst.get(name, 0.0), float(np.max(np.abs(b[name][i] - r[name]))) / scale)
    return b, worst


def test_pendulum_runs_equal_simulate_run_by_run():
    model = PENDULUM(N=5)
    table = {"joint1.phi0": [0.2, 0.9, -0.4, 1.3], "joint3.w0": [0.0, 1.0, -2.0, 0.5], "link2.m": [1.0, 0.5, 2.0, 1.5],
             "tip1.r": [(0.0, -0.5, 0.0), (0.0, -0.7, 0.0), (0.0, -0.3, 0.0), (0.0, -0.5, 0.0)]}
    outputs = ["joint1.f.y", "link5.r.x", "link5.Q.w", "energy.kinetic", "phi3"]
    b, worst = close_to_simulate(model, table, outputs, **REQUEST)
    assert set(outputs) <= set(b.names) and b["joint1.phi"].shape == (4, 121)
    assert max(worst.values()) <= 1e-12, worst
    # the runs differ (the table reached the runs): the swings after 2 s are not one swing
    assert np.ptp(b["joint1.phi"][:, -1]) > 0.1


def test_slider_crank_runs_equal_simulate_run_by_run():
    table = {"crank_joint.phi0": [0.3, 1.0, 2.5], "crank_joint.w0": [6.0, 2.0, -4.0], "rod.m": [2.0, 1.0, 3.5]}
    b, worst = close_to_simulate(SLIDER(), table, ["pin.f.y", "rod.r.x", "crank_angle", "residual.position"],
                                 **REQUEST)
    assert max(worst.values()) <= 1e-12, worst
    # each start went through consistent initialization: the loop closed at every start
    assert np.all(np.abs(b["residual.position"][:, 0]) < 1e-9)
    assert np.allclose(b["crank_joint.phi"][:, 0], table["crank_joint.phi0"], atol=1e-12)


def test_threads_give_the_numbers_one_thread_gives():
    rng = np.random.default_rng(7)
    table = {"joint1.phi0": rng.uniform(-1, 1, 24), "joint2.phi0": rng.uniform(-1, 1, 24)}
    one = mbcomp.batch(PENDULUM(N=3), table, t_end=1.0, threads=1, block=5)
    two = mbcomp.batch(PENDULUM(N=3), table, t_end=1.0, threads=2, block=7)
    for name in one.names:
        np.testing.assert_array_equal(one[name], two[name])
    np.testing.assert_array_equal(one.stats["nfev"], two.stats["nfev"])


@pytest.mark.filterwarnings("ignore:mbcomp. this model looks stiff")   # simulate's note near the dead centre
def test_a_failed_run_says_which_and_why_and_the_others_stand():
    # a crank longer than the rod: the rod stands vertical at the dead centre and the rows lose rank
    table = {"crank_tip.r": [(0.2, 0, 0), (0.6, 0, 0), (0.2, 0, 0)], "crank_joint.w0": [6.0, 6.0, 5.0]}
    alone = mbcomp.batch(SLIDER(), table, t_end=1.0, n_out=11, fallback=False)
    assert list(alone.status) == ["success", "failed", "success"]
    assert "guard of the program failed" in alone.message[1] and 0.3 < alone.t_reached[1] < 0.6
    reached = alone.time <= alone.t_reached[1]
    s = alone["slider_joint.s"][1]
    assert np.isfinite(s[reached]).all() and np.isnan(s[~reached]).all()
    ok = mbcomp.batch(SLIDER(), {k: [v[0], v[2]] for k, v in table.items()}, t_end=1.0, n_out=11)
    np.testing.assert_array_equal(alone["slider_joint.s"][[0, 2]], ok["slider_joint.s"])
    # with the fallback, simulate finishes that run: it names the singular position, as simulate does
    fell = mbcomp.batch(SLIDER(), table, t_end=1.0, n_out=11)
    r = mbcomp.simulate(SLIDER(), t_end=1.0, n_out=11, params={"crank_tip.r": (0.6, 0, 0)})
    assert fell.stats["simulate_reruns"] == [1] and fell.status[1] == r.status == "failed"
    assert "singular position" in fell.message[1]
    n = len(r.time)
    np.testing.assert_allclose(fell["slider_joint.s"][1, :n], r["slider_joint.s"], rtol=0, atol=1e-12)


def test_a_step_budget_ends_only_the_runs_that_need_more():
    table = {"crank_joint.w0": [1.0, 20.0, 2.0]}
    free = mbcomp.batch(SLIDER(), table, t_end=2.0, n_out=21)
    steps = free.stats["nsteps"] + free.stats["nreject"]
    budget = int((steps[0] + steps[1]) // 2)
    assert steps[1] > budget >= max(steps[0], steps[2])
    capped = mbcomp.batch(SLIDER(), table, t_end=2.0, n_out=21, max_steps=budget)
    assert list(capped.status) == ["success", "budget", "success"] and "max_steps" in capped.message[1]
    for i in (0, 2):
        np.testing.assert_array_equal(capped["slider_joint.s"][i], free["slider_joint.s"][i])
    kept = np.isfinite(capped["slider_joint.s"][1])
    assert 0 < kept.sum() < 21
    np.testing.assert_array_equal(capped["slider_joint.s"][1, kept], free["slider_joint.s"][1, kept])


def test_a_run_that_cannot_start_is_an_error_row():
    table = {"link3.m": [1.0, 0.0], "link3.I": [np.diag([0.02, 0.0, 0.02]), np.zeros((3, 3))]}
    b = mbcomp.batch(PENDULUM(N=3), table, t_end=0.5, n_out=5)
    assert list(b.status) == ["success", "error"] and "massless" in b.message[1] and "joint3" in b.message[1]
    assert np.isnan(b["joint3.phi"][1]).all() and np.isfinite(b["joint3.phi"][0]).all()


@pytest.mark.parametrize("table, words", [
    ({"jiont1.phi0": [0.1]}, ["jiont1", "joint1"]),
    ({"joint1.ph0": [0.1]}, ["joint1", "ph0", "phi0"]),
    ({"tip1.r": [0.5]}, ["tip1.r", "shape"]),
    ({"joint1.phi0": [0.1, 0.2], "link1.m": [1.0]}, ["different lengths"]),
    ({"joint1.phi0": [float("nan")]}, ["joint1.phi0", "finite"]),
    ({"N": [3]}, ["study"]),
])
def test_bad_tables_are_refused_naming_the_column(table, words):
    with pytest.raises(ValueError) as err:
        mbcomp.batch(PENDULUM(N=2), table, t_end=0.1)
    assert all(w in str(err.value) for w in words), str(err.value)


def test_what_a_batch_cannot_run_is_refused_with_the_fix():
    from mbcomp.library import World, Revolute, FixedTranslation, PointMass

    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.5, limits=(-1.0, 1.0)))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a), m.connect(j.frame_b, rod.frame_a), m.connect(rod.frame_b, bob.frame_a)
    with pytest.raises(ValueError, match=r"j have modes.*mbcomp.study"):
        mbcomp.batch(m, {"bob.m": [1.0]}, t_end=0.1)
    from mbcomp.library import Torque

    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(n=(0, 0, 1)))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=2.0))
    motor = m.add("motor", Torque(tau=mbcomp.Input("motor_torque", unit="N m")))
    m.connect(w.frame_b, j.frame_a), m.connect(j.frame_b, rod.frame_a), m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    with pytest.raises(ValueError, match=r"external inputs \(motor_torque\).*simulate"):
        mbcomp.batch(m, {"bob.m": [1.0]}, t_end=0.1)
    with pytest.raises(ValueError, match="dop853"):
        mbcomp.batch(PENDULUM(N=2), {"link1.m": [1.0]}, method="radau5")
    with pytest.raises(ValueError, match="projection"):
        mbcomp.batch(PENDULUM(N=2), {"link1.m": [1.0]}, stabilization="projection")
    with pytest.raises(ValueError, match=r"no column 'joint1.fy'.*joint1.f.y"):
        mbcomp.batch(PENDULUM(N=2), {"link1.m": [1.0]}, outputs=["joint1.fy"])


CRANK = str(load_model("models/slider_crank.py").__file__)


def peak_pin(res):
    return float(np.abs(res["pin.f.y"]).max())


def crank_length(length=0.2):
    return SLIDER(crank_length=length)


def test_a_batch_study_gives_the_serial_table():
    grid = {"length": [0.2, 0.25], "crank_joint.w0": [2.0, 6.0, 9.0], "rod.m": [1.5, 2.0]}
    metrics = {"peak": peak_pin, "final": lambda r: r["slider_joint.s"][-1]}
    serial = mbcomp.study(crank_length, grid, t_end=0.5, metrics=metrics)
    batched = mbcomp.study(crank_length, grid, t_end=0.5, metrics=metrics, executor="batch", keep="outputs",
                           outputs=["pin.f.y"])
    assert batched.stats["executor"] == "batch" and list(batched["status"]) == ["success"] * 12
    assert batched.runs == serial.runs   # two structures (build arguments), each one batch, rows in grid order
    for name in metrics:
        np.testing.assert_allclose(batched[name], serial[name], rtol=1e-12, atol=0)
    np.testing.assert_allclose(np.abs(batched.results[5]["pin.f.y"]).max(), batched["peak"][5], rtol=1e-15)
    with pytest.raises(ValueError, match="keep=all"):
        mbcomp.study(crank_length, grid, t_end=0.5, executor="batch", keep="all")


def test_a_dask_study_runs_a_batch_per_worker():
    distributed = pytest.importorskip("distributed")
    lc = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  host="127.0.0.1")
    client = distributed.Client(lc)
    try:
        grid = {"crank_joint.w0": np.linspace(2.0, 10.0, 9).tolist()}
        serial = mbcomp.study(CRANK, grid, t_end=0.5, metrics={"peak": peak_pin})
        on_dask = mbcomp.study(CRANK, grid, t_end=0.5, metrics={"peak": peak_pin}, executor=client, batch=True)
    finally:
        client.close()
        lc.close()
    assert on_dask.stats["executor"] == "dask" and list(on_dask["status"]) == ["success"] * 9
    np.testing.assert_allclose(on_dask["peak"], serial["peak"], rtol=1e-12, atol=0)


def test_initialization_by_the_program_starts_equal_to_rounding():
    table = {"crank_joint.phi0": [0.3, 1.0, 2.5, 4.0], "crank_joint.w0": [6.0, 2.0, -4.0, 1.0]}
    exact = mbcomp.batch(SLIDER(), table, **REQUEST)
    fast = mbcomp.batch(SLIDER(), table, initialization="program", **REQUEST)
    for name in ("crank_joint.phi", "slider_joint.s", "pin.phi", "crank_joint.w", "slider_joint.v", "pin.w"):
        np.testing.assert_allclose(fast[name][:, 0], exact[name][:, 0], rtol=0, atol=1e-13)   # the closed starts
        np.testing.assert_allclose(fast[name], exact[name], rtol=0, atol=1e-6)    # then within the tolerances
    with pytest.raises(ValueError, match="initialization"):
        mbcomp.batch(SLIDER(), table, initialization="numeric")


def test_ctrl_c_stops_every_run_and_keeps_what_finished():
    import _thread
    import threading

    rng = np.random.default_rng(3)
    # 4,000 runs: about 3.4 s on a free 2-core machine, ten times the 0.3 s before the interrupt
    # (400 runs finished in 0.34 s there: a faster machine would end before it)
    table = {"joint1.phi0": rng.uniform(-1, 1, 4000)}
    model = PENDULUM(N=3)
    mbcomp.batch(model, {"joint1.phi0": [0.1]}, t_end=10.0)   # compiled before the clock starts (the same grid:
    # a longer one needs the output program, whose compile the interrupt would otherwise stop)
    for delay in (0.3, 0.9, 2.7):  # a loaded machine may still be preparing the runs at 0.3 s: later then
        timer = threading.Timer(delay, _thread.interrupt_main)
        timer.start()
        err = None
        try:
            mbcomp.batch(model, table, t_end=10.0, threads=2, block=16)
        except mbcomp.errors.SimulationInterrupted as exc:
            err = exc
        except KeyboardInterrupt:  # it landed before the runs began: nothing to keep yet
            continue
        finally:
            timer.cancel()
        assert err is not None, "the batch of 4,000 runs ended before the interrupt"
        done = [i for i, s in enumerate(err.result.status) if s == "success"]
        if done:
            break
    res = err.result
    assert err.signal == "SIGINT" and 0 < len(done) < 4000
    assert set(res.status) <= {"success", "interrupted"}
    late = [i for i, s in enumerate(res.status) if s == "interrupted"]
    assert all(np.isnan(res["joint1.phi"][i, -1]) for i in late)
    again = mbcomp.batch(model, {"joint1.phi0": table["joint1.phi0"][done[-3:]]}, t_end=10.0)
    np.testing.assert_array_equal(again["joint1.phi"], res["joint1.phi"][done[-3:]])


def test_ctrl_c_in_a_batch_study_keeps_the_finished_rows():
    import _thread

    grid = {"joint1.phi0": np.linspace(-1.0, 1.0, 3000).tolist()}
    build = lambda: PENDULUM(N=3)  # noqa: E731
    ended = []

    def end(r):  # the metric; once armed, Ctrl-C after the 100th run read (past the first block of 64)
        ended.append(1)
        if len(ended) == 100:
            _thread.interrupt_main()
        return r["joint1.phi"][-1]

    mbcomp.study(build, {"joint1.phi0": [0.1]}, t_end=10.0, executor="batch", metrics={"end": end})  # compiled
    from mbcomp.analysis.study import StudyInterrupted

    ended.clear()
    with pytest.raises(StudyInterrupted) as err:
        mbcomp.study(build, grid, t_end=10.0, executor="batch", metrics={"end": end})
    part = err.value.result
    assert 64 <= len(part) < 3000 and list(part["status"]) == ["success"] * len(part)   # the first block at least
    again = mbcomp.batch(build(), {"joint1.phi0": [r["joint1.phi0"] for r in part.runs[:3]]}, t_end=10.0)
    np.testing.assert_array_equal(part["end"][:3], again["joint1.phi"][:, -1])
