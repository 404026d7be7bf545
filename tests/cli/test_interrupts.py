"""Ctrl-C and SIGTERM stop ``mbcomp study`` on every executor (serial, a process pool, a local
Dask cluster) and ``mbcomp simulate``: the finished work is written, the exit status is 130
(SIGINT) or 143 (SIGTERM), one line on stderr says so, and no process of the command is left.

The commands run in a session of their own; Ctrl-C is SIGINT to that whole process group (as
a terminal sends it: the workers get it too), SIGTERM goes to the command's process only (as
``kill PID`` sends it). The model is a damped pendulum (``build(k)``: released from 0.5 k rad,
damping torque -0.1 k w) whose torque law writes ``pid k t`` to a log at every evaluation
(``--backend numeric``: the law is Python), and whose derived output ``done`` writes ``k`` and
its number of rows to a second log when the run's results are post-processed. The test writes a
``SIGNAL`` line to the first log just before it signals, at a moment when every worker is in
the middle of a run. A run *finished before the signal* when its process went on to another run
above that line; a run *finished* when it was post-processed whole (as many rows as the
others). The table must hold exactly the finished runs, each row equal to an uninterrupted
study's row for the same k. A process (serial, the pool's) is stopped mid-run, so there the
finished runs are those finished before the signal; a Dask task runs in a worker's thread that
no signal reaches: it ends the run it is in and then stops, so its table may hold those too.
"""
import csv
import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import mbcomp
from mbcomp.analysis.metrics import parse_metric

psutil = pytest.importorskip("psutil")

MODEL = '''
import os
import time

from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

SIMULATION = dict(t_end=2.0, rtol=1e-10, atol=1e-12)


def build(k=1.0):
    log = os.environ.get("MBCOMP_STUDY_LOG")

    def law(t, phi, w):
        if log:
            with open(log, "a") as fh:
                fh.write(f"{os.getpid()} {k!r} {float(t)!r}\\n")
            time.sleep(float(os.environ.get("MBCOMP_STUDY_PAUSE", "0")))  # see _run_until
        return -0.1 * k * w

    def done(phi):  # computed once a run's results are post-processed: how many rows it has
        if log:
            with open(log + ".done", "a") as fh:
                fh.write(f"{k!r} {len(phi)}\\n")
        return phi

    m = Model()
    world = m.add("world", World())
    hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.5 * k, w0=0.0))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=law))
    m.connect(world.frame_b, hinge.frame_a)
    m.connect(hinge.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(motor.flange_b, hinge.axis)
    m.output("done", done, "hinge.phi")
    return m
'''
T_END = 2.0
KS = np.linspace(1.0, 2.5, 8).tolist()
METRICS = ["final=last(hinge.phi)", "peak=max(abs(hinge.w))"]
EXIT = {signal.SIGINT: 130, signal.SIGTERM: 143}


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("interrupts") / "pendulum.py"
    path.write_text(MODEL)
    return path


@pytest.fixture(scope="module")
def reference(model_file):
    """The uninterrupted study's metrics, k -> (final, peak), in this process."""
    res = mbcomp.study(str(model_file), {"k": KS}, t_end=T_END, metrics=dict(parse_metric(m) for m in METRICS),
                       rtol=1e-10, atol=1e-12, backend="numeric")
    assert list(res["status"]) == ["success"] * len(KS)
    return {round(k, 9): (f, p) for k, f, p in zip(res["k"], res["final"], res["peak"])}


def _log(path):
    """``[(pid, k, t)]`` and the index of the SIGNAL line (complete lines only)."""
    if not path.exists():
        return [], None
    entries, marker = [], None
    for line in path.read_text().split("\n")[:-1]:
        if line == "SIGNAL":
            marker = len(entries)
            continue
        pid, k, t = line.split()
        entries.append((int(pid), round(float(k), 9), float(t)))
    return entries, marker


def _latest(entries):
    """Each process's last logged evaluation: ``{pid: (k, t)}``."""
    return {pid: (k, t) for pid, k, t in entries}


def _finished(entries):
    """The runs a process had left for another run: finished, their rows made (a law called
    at t_end is no proof: a rejected step may have tried it)."""
    return {k for _, k, _ in entries} - {k for k, _ in _latest(entries).values()}


def _completed(log):
    """The runs whose results were post-processed whole (as many rows as the longest: an
    interrupted run is post-processed too, with fewer)."""
    path = log.with_name(log.name + ".done")
    done = [line.split() for line in path.read_text().split("\n")[:-1]] if path.exists() else []
    n = max((int(rows) for _, rows in done), default=0)
    return {round(float(k), 9) for k, rows in done if int(rows) == n}


def _mid_run(entries):
    """At least two runs finished, at least two not started (a Dask worker finishes the run it
    is in after the signal: with every run started, all may finish -- CI saw 8 of 8), and every
    process still evaluating (one among the last 40 evaluations logged: a worker whose share is
    done writes no more) lies mid-run."""
    if len(_finished(entries)) < 2 or len({k for _, k, _ in entries}) > len(KS) - 2:
        return False
    latest = _latest(entries)
    active = {pid for pid, _, _ in entries[-40:]}
    return all(0.1 * T_END < latest[pid][1] < 0.6 * T_END for pid in active)  # 40 % of each run still to go


def _group_alive(pgid):
    alive = []
    for p in psutil.process_iter(["pid", "status"]):
        try:
            if os.getpgid(p.pid) == pgid and p.info["status"] != psutil.STATUS_ZOMBIE:
                alive.append(p.pid)
        except (ProcessLookupError, psutil.Error):
            continue
    return alive


def _no_process_left(pgid, grace=3.0):
    """No process of the command's group alive (``grace`` s for the exiting ones to go)."""
    deadline = time.monotonic() + grace
    while _group_alive(pgid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return _group_alive(pgid)


def _signal(proc, sig):
    if sig == signal.SIGINT:
        os.killpg(proc.pid, sig)  # Ctrl-C: the terminal signals the whole foreground group
    else:
        proc.send_signal(sig)


def _run_until(cmd, log, ready, sig, deadline_s=60, pause=0.0):
    """Start ``cmd`` in its own session, wait until ``ready(log entries)``, mark the log, send
    ``sig``; ``(returncode, stdout, stderr, pgid)``. ``pause`` (s): the model's law sleeps that
    long per evaluation, so that short runs last long enough for the poll to find them in the
    state ``ready`` waits for (a loaded machine slows the poll more than the runs)."""
    env = dict(os.environ, MBCOMP_STUDY_LOG=str(log), MBCOMP_STUDY_PAUSE=repr(pause))
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + deadline_s
        while not ready(_log(log)[0]):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the command never reached the point to interrupt it"
            time.sleep(0.02)
        with open(log, "a") as fh:
            fh.write("SIGNAL\n")
        _signal(proc, sig)
        out, err = proc.communicate(timeout=60)
        left = _no_process_left(proc.pid)
    finally:
        if proc.poll() is None:
            proc.kill()
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # nothing of a failed test survives it
        except ProcessLookupError:
            pass
    return proc.returncode, out, err, left


def _table(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


#: Ctrl-C on every executor; SIGTERM where the command must stop workers it does not signal. A
#: SIGTERM stopping a run inside the command's own process (the serial study's case) is the
#: interrupted simulation's below, and the serial study's Ctrl-C
CASES = [(signal.SIGINT, "serial"), (signal.SIGINT, "processes"), (signal.SIGINT, "dask"),
         (signal.SIGTERM, "processes"), (signal.SIGTERM, "dask")]


@pytest.mark.parametrize("sig, executor", CASES, ids=[f"{signal.Signals(s).name}-{e}" for s, e in CASES])
def test_an_interrupted_study_writes_exactly_the_finished_rows(model_file, reference, tmp_path, executor, sig):
    if executor == "dask":
        pytest.importorskip("distributed")
    log, out = tmp_path / "calls.log", tmp_path / "table.csv"
    cmd = [sys.executable, "-m", "mbcomp.cli", "study", str(model_file), "--grid", "k=1:2.5:8",
           *[a for m in METRICS for a in ("--metric", m)], "--backend", "numeric", "--executor", executor,
           "--out", str(out), "-q"] + (["--workers", "2"] if executor == "processes" else [])
    code, stdout, stderr, left = _run_until(cmd, log, _mid_run, sig, pause=5e-4)
    name = signal.Signals(sig).name
    assert code == EXIT[sig], (stdout, stderr)
    assert left == [], f"processes left behind: {left}"
    entries, marker = _log(log)
    before = _finished(entries[:marker])
    rows = _table(out)
    got = {round(float(r["k"]), 9): r for r in rows}
    assert len(got) == len(rows) and set(got) == _completed(log)  # exactly the finished runs
    assert before <= set(got) and len(before) >= 2
    assert len(rows) < len(KS)  # it stopped: not every run is there
    if executor != "dask":  # a signal stops a process's run at once: nothing finished after it
        assert set(got) == before
    for k, r in got.items():  # each row is the uninterrupted study's
        assert r["status"] == "success"
        np.testing.assert_allclose([float(r["final"]), float(r["peak"])], reference[k], rtol=1e-11, atol=0)
    line = f"mbcomp: study interrupted by {name}: {len(rows)} of {len(KS)} runs finished (their rows are kept); " \
           f"wrote {out} ({len(rows)} rows)"
    assert line in stderr.splitlines(), stderr


def _simulation_started(entries):
    """A law was evaluated past t = 1 s. That evaluation may be a stage of a step still being
    tried, so the accepted rows reach only that step's start; at rtol 1e-10 this pendulum's
    steps are about 0.09 s (33 steps over 3 s), so the rows reach past 0.5 s."""
    return any(t > 1.0 for _, _, t in entries)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_an_interrupted_simulation_writes_its_rows_and_plot(model_file, tmp_path, sig):
    """``mbcomp simulate`` of a 1e4 s run stopped once a law ran past t = 1 s: the CSV (and the plot asked
    for) hold the rows up to the last accepted step, equal to an uninterrupted run's rows at
    the same times."""
    log, out, plot = tmp_path / "calls.log", tmp_path / "run.csv", tmp_path / "run.png"
    cmd = [sys.executable, "-m", "mbcomp.cli", "simulate", str(model_file), "--t-end", "1e4", "--n-out", "1000001",
           "--backend", "numeric", "--out", str(out), "--plot", str(plot), "-q"]
    code, stdout, stderr, left = _run_until(cmd, log, _simulation_started, sig)
    name = signal.Signals(sig).name
    assert code == EXIT[sig], (stdout, stderr)
    assert left == []
    with open(out, newline="") as fh:
        rows = list(csv.reader(fh))
    header, data = rows[0], np.array(rows[1:], float)
    t = data[:, 0]
    assert 0.5 - 0.01 <= t[-1] < 1e4 and np.allclose(np.diff(t), 0.01)
    assert plot.exists() and plot.stat().st_size > 0
    last = [ln for ln in stderr.splitlines() if ln.startswith("mbcomp: ")]
    assert last == [f"mbcomp: interrupted by {name} at t = {t[-1]:g} s; wrote {out} ({len(t)} rows), {plot} up to then"]
    ref = mbcomp.simulate(mbcomp.load_model_file(model_file).build(), t_end=float(t[-1]), n_out=len(t),
                          rtol=1e-10, atol=1e-12, backend="numeric")
    np.testing.assert_allclose(ref.time, t, rtol=0, atol=1e-9)
    for col in ("hinge.phi", "hinge.w"):
        np.testing.assert_allclose(data[:, header.index(col)], ref[col], rtol=0, atol=1e-8)
