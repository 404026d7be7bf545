"""Study throughput: runs per second of :func:`mbcomp.study` in this process, on a process pool and on Dask.

N short slider-crank runs (``models/slider_crank.py``, ``t_end`` 0.2 s by default), a Monte
Carlo sample over the crank's mass and start speed (``crank.m ~ Normal(1.0, 0.05)`` kg,
``crank_joint.w0 ~ Uniform(5.7, 6.3)`` rad/s, seed 0), each run reporting its peak pin force
(N) and final crank angle (rad), go through one :func:`mbcomp.study` call per executor:

* ``serial``: ``executor=None``, one run after the other in this process;
* ``ProcessPool(2)``: a :class:`concurrent.futures.ProcessPoolExecutor` with two processes;
* ``dask``: ``executor="dask"`` (a ``LocalCluster`` started and closed by the call: its
  start-up is inside the wall time and measured on its own as well), default ``chunk``;
* ``dask chunk=1``: the same with one run per task (the cost of a task round trip).

Columns: runs, wall (s), runs/s, speed-up against serial, overhead per run (ms) =
(workers x (wall - cluster start-up) - sum of the runs' CPU times) / runs, i.e. the worker time
not spent inside a run (sending, scheduling, collecting; for serial: building the table), and
the cluster start-up (s). The tables of all executors are compared value for value (``==`` on
every metric, status and parameter column, no tolerance).

This machine has 2 cores: the parallel speed-up is bounded by 2, and the process that collects
results and the Dask scheduler share those cores with the workers. The first run in each worker
process also pays for loading the model and its compiled program (from the disk cache the serial
run filled), which is counted as run CPU time, not overhead.

Prints a markdown table, writes ``bench/study.csv``.

Run: python bench/study.py [--runs 1000] [--t-end 0.2]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices; threads only cost on a shared machine

import argparse  # noqa: E402
import csv  # noqa: E402
import pathlib  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402

import mbcomp  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
MODEL = str(HERE.parent / "models" / "slider_crank.py")
GRID = {"crank.m": mbcomp.Normal(1.0, 0.05), "crank_joint.w0": mbcomp.Uniform(5.7, 6.3)}


def peak_pin_force(res):
    """Largest in-plane pin force over the run (N)."""
    return float(np.max(np.hypot(res["pin.f.x"], res["pin.f.y"])))


def final_angle(res):
    """Crank angle at the end of the run (rad)."""
    return float(res["crank_joint.phi"][-1])


METRICS = {"peak_pin_force": peak_pin_force, "final_angle": final_angle}


def cluster_start_up():
    """``(start, close)`` seconds of a LocalCluster as ``executor="dask"`` starts it, ready for tasks."""
    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=min(os.cpu_count() or 1, 4), threads_per_worker=1, processes=True,
                           dashboard_address=None)
    client = Client(cluster)
    client.wait_for_workers(len(cluster.workers))
    client.submit(sum, [1, 2]).result()  # one task through: the cluster answers
    start = time.perf_counter() - t0
    t0 = time.perf_counter()
    client.close()
    cluster.close()
    return start, time.perf_counter() - t0


def one(label, executor, runs, t_end, chunk=None, start_up=0.0):
    """One study; its row of the table and the StudyResult."""
    s = mbcomp.study(MODEL, GRID, t_end=t_end, metrics=METRICS, samples=runs, seed=0, executor=executor, chunk=chunk)
    wall = s.stats["wall_time"]
    workers = s.stats["workers"]
    cpu = float(np.sum(s["cpu_time"]))
    overhead = (workers * (wall - start_up) - cpu) / runs
    row = dict(executor=label, runs=runs, workers=workers, chunks=s.stats["chunks"], wall_s=wall,
               runs_per_s=runs / wall, cpu_s=cpu, overhead_ms=1e3 * overhead, start_up_s=start_up,
               failed=len(s.failed))
    print(f"  {label}: {wall:.1f} s", flush=True)
    return row, s


def same_table(a, b):
    """True when two StudyResults agree exactly in every column but the CPU time."""
    for c in a.columns:
        if c == "cpu_time":
            continue
        if not all(x == y for x, y in zip(a[c], b[c])) or len(a[c]) != len(b[c]):
            return False
    return True


def markdown(rows):
    serial = rows[0]["wall_s"]
    lines = ["| executor | runs | workers | chunks | wall s | runs/s | speed-up | overhead/run ms | start-up s |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['executor']} | {r['runs']} | {r['workers']} | {r['chunks']} | {r['wall_s']:.2f} | "
                     f"{r['runs_per_s']:.1f} | {serial / r['wall_s']:.2f} | {r['overhead_ms']:.2f} | "
                     f"{r['start_up_s']:.2f} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1000, help="runs per executor (default 1000)")
    ap.add_argument("--t-end", type=float, default=0.2, help="end time of each run, s (default 0.2)")
    ap.add_argument("--out", default=str(HERE / "study.csv"))
    a = ap.parse_args(argv)

    print(f"{a.runs} slider-crank runs of {a.t_end} s per executor; {os.cpu_count()} cores", flush=True)
    start, close = cluster_start_up()
    print(f"  LocalCluster start-up {start:.2f} s, close {close:.2f} s", flush=True)
    rows, tables = [], []
    with ProcessPoolExecutor(2) as pool:
        for label, ex, chunk, up in [("serial", None, None, 0.0), ("ProcessPool(2)", pool, None, 0.0),
                                     ("dask", "dask", None, start), ("dask chunk=1", "dask", 1, start)]:
            row, s = one(label, ex, a.runs, a.t_end, chunk, up)
            rows.append(row)
            tables.append(s)
    for r in rows:
        r["speed_up"] = rows[0]["wall_s"] / r["wall_s"]
        r["equal_to_serial"] = same_table(tables[0], tables[rows.index(r)])
    print()
    print(markdown(rows))
    print()
    equal = all(r["equal_to_serial"] for r in rows)
    print(f"tables equal to the serial one, bit for bit (all columns but cpu_time): {equal} "
          f"({', '.join(r['executor'] + '=' + str(r['equal_to_serial']) for r in rows[1:])})")
    pf = tables[0]["peak_pin_force"]
    print(f"peak pin force over the sample: mean {pf.mean():.4f} N, std {pf.std(ddof=1):.4f} N; "
          f"mean CPU time per run {1e3 * rows[0]['cpu_s'] / a.runs:.1f} ms")
    print(f"Notes: {os.cpu_count()} cores, so the speed-up is bounded by {os.cpu_count()}; the collecting process and "
          "the Dask scheduler share the cores with the workers. 'dask' wall times include the LocalCluster start-up "
          f"({start:.2f} s, subtracted in the overhead column) and its close. overhead/run = (workers x (wall - "
          "start-up) - summed run CPU) / runs.")
    with open(a.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    print(f"wrote {a.out}")
    return 0 if equal else 1


if __name__ == "__main__":
    raise SystemExit(main())
