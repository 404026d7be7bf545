"""``mbcomp study`` on the command line: grids, metrics, executors (serial, a process pool, Dask),
a model file without a ``__main__`` guard, exit codes; ``--executor`` on ``stability --sweep``.

One LocalCluster (2 worker processes, loopback) serves the module; the issue's Done-when
command starts its own (``--executor dask``).
"""
import csv
import pickle
import textwrap
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import mbcomp
from mbcomp.analysis.metrics import Metric, MetricError, parse_metric
from mbcomp.cli.main import main
from mbcomp.cli.study import parse_grid

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
SLIDER = str(ROOT / "models/slider_crank.py")

#: a model file with top-level code (a run, a print) and no ``if __name__ == "__main__":`` guard
NO_GUARD = textwrap.dedent('''
    import mbcomp
    from mbcomp.library import World, Revolute, FixedTranslation, PointMass

    def build(L=1.0):
        m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
        j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.0)); rod = m.add("rod", FixedTranslation(r=(L, 0, 0)))
        bob = m.add("bob", PointMass(m=1.0))
        m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
        return m

    res = mbcomp.simulate(build(), t_end=0.05)
    print("top-level code ran:", res.status)
''')


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  host="127.0.0.1") as lc:
        yield lc.scheduler_address


def _table(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _study(args, capsys=None):
    code = main(["study", *args, "-q"])
    return code, (capsys.readouterr() if capsys else None)


def test_done_when_dask_table_equals_serial(tmp_path, capsys):
    """The issue's command: 9 rows through a local Dask cluster, the metric equal to the serial run's."""
    cmd = [SLIDER, "--grid", "crank_joint.w0=2:10:9", "--metric", "peak=max(abs(pin.f.y))"]
    assert _study(cmd + ["--executor", "dask", "--out", str(tmp_path / "s.csv")])[0] == 0
    out = capsys.readouterr().out
    assert "runs 9, failed 0" in out and "executor dask" in out
    assert _study(cmd + ["--out", str(tmp_path / "serial.csv")])[0] == 0
    dask_rows, serial_rows = _table(tmp_path / "s.csv"), _table(tmp_path / "serial.csv")
    assert len(dask_rows) == 9 and [r["crank_joint.w0"] for r in dask_rows] == [f"{v:g}" for v in range(2, 11)]
    assert [r["peak"] for r in dask_rows] == [r["peak"] for r in serial_rows]
    assert {r["status"] for r in dask_rows} == {"success"}


def test_parsed_metrics_travel_to_dask_bit_for_bit(cluster):
    """The Metric objects the CLI builds pickle to Dask workers and give the serial numbers exactly."""
    from distributed import Client

    metrics = dict(parse_metric(m) for m in ("peak=max(abs(pin.f.y))", "final=last(crank_joint.phi)"))
    grid = {"crank_joint.w0": [2.0, 6.0, 10.0], "crank.m": [0.8, 1.2]}
    serial = mbcomp.study(SLIDER, grid, t_end=1.0, metrics=metrics)
    with Client(cluster) as client:
        far = mbcomp.study(SLIDER, grid, t_end=1.0, metrics=metrics, executor=client)
    for name in ("peak", "final"):
        assert np.array_equal(serial[name], far[name]) and np.isfinite(serial[name]).all()
    assert serial["peak"][0] != serial["peak"][1]  # crank mass changes the pin force


@pytest.mark.parametrize("where", ["processes", "dask"])
def test_model_file_without_main_guard(tmp_path, capsys, cluster, where):
    """Top-level code but no __main__ guard: the study runs on a process pool and on Dask as in serial."""
    model = tmp_path / "noguard.py"
    model.write_text(NO_GUARD)
    executor = cluster if where == "dask" else "processes"
    cmd = [str(model), "--grid", "j.w0=0.5,1,2", "--grid", "L=0.5,1", "--metric", "top=max(j.phi)", "--t-end", "0.5"]
    assert _study(cmd + ["--out", str(tmp_path / "serial.csv")])[0] == 0
    extra = ["--workers", "2"] if where == "processes" else []
    code, out = _study(cmd + ["--executor", executor, *extra, "--out", str(tmp_path / "far.csv")], capsys)
    assert code == 0 and "runs 6, failed 0" in out.out
    far, serial = _table(tmp_path / "far.csv"), _table(tmp_path / "serial.csv")
    assert [(r["j.w0"], r["L"], r["top"]) for r in far] == [(r["j.w0"], r["L"], r["top"]) for r in serial]
    assert float(far[0]["top"]) < float(far[4]["top"])  # a faster start swings higher


def test_monte_carlo_and_fixed_values(tmp_path):
    """U(lo,hi) with --samples/--seed draws numpy's sample; -p fixes a value for every run."""
    out = tmp_path / "mc.csv"
    code, _ = _study([SLIDER, "--grid", "crank.m=U(0.9,1.1)", "--samples", "4", "--seed", "7", "-p", "crank_joint.w0=3",
                      "--metric", "final=last(crank_joint.phi)", "--t-end", "0.2", "--out", str(out)])
    rows = _table(out)
    drawn = np.random.default_rng(7).uniform(0.9, 1.1, 4)
    assert code == 0 and [float(r["crank.m"]) for r in rows] == pytest.approx(drawn, rel=1e-11)
    assert {r["crank_joint.w0"] for r in rows} == {"3"}


def test_exit_status_and_plot(tmp_path, capsys):
    """Every run failing -> exit 1 naming the bad value; some failing -> 0; --plot draws the chart."""
    code, out = _study([SLIDER, "--grid", "crank.m=-1,-2", "--metric", "p=max(pin.f.y)", "--t-end", "0.1"], capsys)
    assert code == 1 and "runs 2, failed 2" in out.out and "crank.m" in out.out
    png = tmp_path / "s.png"
    code, out = _study([SLIDER, "--grid", "crank.m=-1,1", "--metric", "p=max(pin.f.y)", "--t-end", "0.1",
                        "--plot", str(png)], capsys)
    assert code == 0 and "runs 2, failed 1" in out.out and png.stat().st_size > 1000


def test_unknown_column_fails_in_its_row(tmp_path, capsys):
    code, out = _study([SLIDER, "--grid", "crank_joint.w0=2,3", "--metric", "bad=max(pin.f.yy)", "--t-end", "0.1",
                        "--out", str(tmp_path / "t.csv")], capsys)
    rows = _table(tmp_path / "t.csv")
    assert code == 0 and rows[0]["bad"] == "nan"
    assert "no column 'pin.f.yy'; similar: pin.f.y" in rows[0]["message"] and "pin.f.yy" in out.out


# --- grids and metrics ----------------------------------------------------------------------------
def test_parse_grid_forms():
    def build(L=1.0, n=3, r=(0.1, 0.0)): ...
    assert parse_grid("a.b=0:1:3") == ("a.b", [0.0, 0.5, 1.0])
    assert parse_grid("L=0.5,2", build) == ("L", [0.5, 2])
    assert parse_grid("r=0.1,0;0.2,0", build) == ("r", [(0.1, 0), (0.2, 0)])
    assert parse_grid("a.b=N(1, 0.05)") == ("a.b", mbcomp.Normal(1.0, 0.05))
    with pytest.raises(ValueError, match=r"build\(\) takes no parameter mass; it takes: L \(default 1.0\)"):
        parse_grid("mass=1,2", build)
    with pytest.raises(ValueError, match="whole number >= 1"):
        parse_grid("a.b=0:1:2.5")
    with pytest.raises(ValueError, match="lo < hi"):
        parse_grid("a.b=U(2,1)")
    with pytest.raises(ValueError, match="'abc' is not a number"):
        parse_grid("L=1,abc", build)


def test_distribution_needs_samples(capsys):
    code, out = _study([SLIDER, "--grid", "crank.m=U(0.9,1.1)"], capsys)
    assert code == 2 and "--grid crank.m is a distribution: add --samples N" in out.err


def test_metric_language():
    from mbcomp.simulation.result import Result

    res = Result(np.array([0.0, 1.0, 2.0]), {"pin.f.y": np.array([1.0, -4.0, 2.0]), "crank_angle": np.array([0, 1, 3.0])})
    assert Metric("max(abs(pin.f.y))")(res) == 4.0
    assert Metric("-min(pin.f.y) / 2 + 1")(res) == 3.0
    assert Metric("rms(crank_angle) ** 2")(res) == pytest.approx(10 / 3, rel=1e-15)
    assert Metric("at(crank_angle, 1.5) - last(time)")(res) == 0.0
    assert Metric("range('pin.f.y')")(res) == 6.0
    assert pickle.loads(pickle.dumps(Metric("mean(pin.f.y)")))(res) == pytest.approx(-1 / 3, rel=1e-15)
    with pytest.raises(MetricError, match=r"gives 3 values, not one"):
        Metric("abs(pin.f.y)")(res)
    with pytest.raises(MetricError, match=r"no column 'pin.fy'; similar: pin.f.y"):
        Metric("max(pin.fy)")(res)


@pytest.mark.parametrize("text, message", [
    ("maxx(a.b)", r"no function 'maxx' \(did you mean max\?\)"),
    ("__import__('os').system('true')", r"is not allowed in a metric"),
    ("max(a.b)[0]", r"'max\(a.b\)\[0\]' is not allowed"),
    ("max(a.b, 2)", r"max\(\) takes 1 argument, got 2"),
    ("max(abs(a.b)", r"is not an expression"),
    ("a.b if 1 else 2", r"is not allowed"),
])
def test_metric_refusals(text, message):
    with pytest.raises(MetricError, match=message):
        Metric(text)


def test_bad_metric_is_an_input_error(capsys):
    code, out = _study([SLIDER, "--grid", "crank.m=1", "--metric", "p=lambda: 1"], capsys)
    assert code == 2 and "is not allowed in a metric" in out.err


# --- --executor on stability --sweep ------------------------------------------------------------
def test_stability_sweep_on_dask_equals_serial(cluster, capsys):
    model = str(ROOT / "models/bicycle.py")
    assert main(["stability", model, "--sweep", "v=3:7:5"]) == 0
    serial = capsys.readouterr().out
    assert main(["stability", model, "--sweep", "v=3:7:5", "--executor", cluster]) == 0
    far = capsys.readouterr().out
    assert far == serial and "stability changes at v = " in far


def test_stability_executor_refusals(capsys):
    model = str(ROOT / "models/bicycle.py")
    assert main(["stability", model, "--executor", "processes"]) == 2
    assert "there is no --sweep" in capsys.readouterr().err
    assert main(["stability", model, "--sweep", "v=3:7:5", "--executor", "nowhere"]) == 2
    assert "--executor nowhere: use serial, processes" in capsys.readouterr().err


def test_processes_executor_is_a_process_pool():
    from mbcomp.analysis.parallel import executor_of

    ex, owned = executor_of("processes", 2)
    try:
        assert isinstance(ex, ProcessPoolExecutor) and owned and ex._max_workers == 2
    finally:
        ex.shutdown()


def test_bench_on_a_process_pool(tmp_path, capsys):
    """``mbcomp bench --executor processes``: the same rows (but CPU times) as the serial bench."""
    def bench(name, *extra):
        out = tmp_path / f"{name}.csv"
        assert main(["bench", SLIDER, "--combos", "ODE i1 Baumgarte / DOP853,D'Alembert / Radau", "--tols", "1e-4,1e-6",
                     "--t-end", "0.2", "--out", str(out), "--plot", str(tmp_path / f"{name}.png"), *extra]) == 0
        return [{k: v for k, v in r.items() if k != "cpu_s"} for r in _table(out)]

    serial, far = bench("serial"), bench("far", "--executor", "processes", "--workers", "2")
    assert far == serial and len(far) == 4 and {r["status"] for r in far} == {"success"}
