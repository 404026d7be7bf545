"""``mbcomp simulate`` never loses results: bad output paths fail before any work, and an
interrupted run writes what it computed.

The model is a frictionless pendulum (1 kg at 1 m) with a zero torque whose law records
every evaluation in ``<model>.calls`` (one time per line): the record shows whether the model
was integrated at all. With ``stop_at`` the law raises ``KeyboardInterrupt`` (Ctrl-C arriving
mid-run) once ``t >= stop_at``.
"""
import csv
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from mbcomp.cli import main

MODEL = '''
import pathlib

from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

CALLS = pathlib.Path(__file__).with_suffix(".calls")


def build(stop_at=None):
    def law(t, phi, w):
        with open(CALLS, "a") as fh:
            fh.write(f"{float(t)!r}\\n")
        if stop_at is not None and t >= stop_at:
            raise KeyboardInterrupt
        return 0.0

    m = Model()
    world = m.add("world", World())
    hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=1.0, w0=0.0))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=law))
    m.connect(world.frame_b, hinge.frame_a)
    m.connect(hinge.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(motor.flange_b, hinge.axis)
    return m
'''


@pytest.fixture
def pendulum(tmp_path):
    path = tmp_path / "pendulum.py"
    path.write_text(MODEL)
    return path


def calls(model):
    """The times (s) at which the torque law ran (complete lines only: another process may be writing)."""
    f = model.with_suffix(".calls")
    return [float(x) for x in f.read_text().split("\n")[:-1]] if f.exists() else []


def read_csv(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], float)


@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_missing_output_directory_fails_before_integrating(pendulum, tmp_path, option, capsys):
    target = tmp_path / "missing" / ("x.csv" if option == "--out" else "x.png")
    code = main(["simulate", str(pendulum), "--t-end", "1000", option, str(target), "-q"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"mbcomp: {option} {target}: the directory {target.parent} does not exist")
    assert f"mkdir -p {target.parent}" in err
    assert calls(pendulum) == []  # the torque law never ran: nothing was integrated
    assert not target.parent.exists()


def test_an_existing_directory_is_not_an_output_file(pendulum, tmp_path, capsys):
    code = main(["simulate", str(pendulum), "--out", str(tmp_path), "-q"])
    assert code == 2 and "is a directory" in capsys.readouterr().err
    assert calls(pendulum) == []


@pytest.mark.parametrize("argv", [["stability"], ["bench", "--tols", "1e-6"]])
def test_other_commands_check_their_outputs_first(pendulum, tmp_path, argv, capsys):
    target = tmp_path / "missing" / "x.json"
    code = main([argv[0], str(pendulum), *argv[1:], "--out", str(target)])
    assert code == 2 and f"the directory {target.parent} does not exist" in capsys.readouterr().err
    assert calls(pendulum) == []


def test_the_same_run_with_a_good_path_integrates(pendulum, tmp_path, capsys):
    """The control of the tests above: the law does run when the output path is fine."""
    out = tmp_path / "x.csv"
    assert main(["simulate", str(pendulum), "--t-end", "0.2", "--out", str(out), "-q"]) == 0
    t = calls(pendulum)
    assert t and max(t) > 0.19
    header, data = read_csv(out)
    assert data[-1, 0] == 0.2


def test_ctrl_c_writes_the_partial_csv_and_exits_130(pendulum, tmp_path, capsys):
    """Ctrl-C at t = 0.3 s of a 10 s run: the CSV holds the rows up to the interruption, the
    pendulum's energy is conserved in them, and the exit status says it was interrupted."""
    out = tmp_path / "x.csv"
    code = main(["simulate", str(pendulum), "-p", "stop_at=0.3", "--t-end", "10", "--n-out", "1001",
                 "--rtol", "1e-10", "--atol", "1e-12", "--out", str(out), "-q"])
    text = capsys.readouterr().out
    assert code == 130
    assert "status: interrupted" in text
    assert f"interrupted at t = " in text and f"{out} holds the partial results up to then" in text
    header, data = read_csv(out)
    t = data[:, 0]
    assert 0.2 < t[-1] <= 0.3 + 1e-12 and np.all(np.diff(t) > 0)  # 0.01 s output grid, up to the Ctrl-C
    E = data[:, header.index("energy.total")]
    assert np.abs(E - E[0]).max() < 1e-8
    phi = data[:, header.index("hinge.phi")]
    assert phi[0] == 1.0 and phi[-1] < 1.0  # it swung (from rest at 1 rad) before the interruption


def test_an_interrupted_run_without_out_says_nothing_was_written(pendulum, capsys):
    code = main(["simulate", str(pendulum), "-p", "stop_at=0.1", "--t-end", "10", "-q"])
    assert code == 130
    assert "nothing written (give --out FILE.csv to keep the partial results)" in capsys.readouterr().out


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_to_the_command_keeps_the_partial_csv(pendulum, tmp_path, sig):
    """The real thing: ``mbcomp simulate`` in a process of its own, stopped by a signal
    while it integrates a 1e5 s run."""
    out = tmp_path / "x.csv"
    proc = subprocess.Popen([sys.executable, "-m", "mbcomp.cli", "simulate", str(pendulum), "--t-end", "1e5",
                             "--n-out", "100001", "--rtol", "1e-10", "--atol", "1e-12", "--out", str(out), "-q",
                             # the law's calls show that it integrates: on the numeric path (a
                             # compiled program calls no Python law per step)
                             "--backend", "numeric"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        # a law call at t > 3 s lies in a step that began after t = 2 s (steps are well under
        # 1 s here), so the row at t = 2 s was accepted before the signal; a call just past
        # 2 s may still be a stage of the step that crosses 2 s (DOP853 takes long steps)
        while not (calls(pendulum) and max(calls(pendulum)) > 3.0):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.05)
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == (130 if sig == signal.SIGINT else 143), (stdout, stderr)  # 128 + the signal's number
    assert "status: interrupted" in stdout and "holds the partial results" in stdout
    header, data = read_csv(out)
    assert 2.0 <= data[-1, 0] < 1e5 and data[0, 0] == 0.0
    E = data[:, header.index("energy.total")]
    assert np.abs(E - E[0]).max() < 1e-8
