"""What the probe of issue 30 (item 7) found on the command line and in ``Model.connect``,
each now a clear error naming the parameter or port and the fix -- or, for units, the same
run as the plain SI number.

* ``-p m_crank="250 g"`` raised a TypeError inside ``models/slider_crank.py`` (build() computed
  ``m * L**2`` with the text): a build() number is now given in SI, the unit converted;
* ``--grid crank_joint.w0=2:10`` (the point count forgotten) was read as one value ``"2:10"``;
* ``--executor tcp://127.0.0.1:1`` (no scheduler) gave a raw OSError traceback after 30 s;
  a bad ``--x`` gave a traceback after the whole study had run;
* ``m.connect(a.frame_b, a.frame_b)`` was accepted.
"""
import csv
import pathlib
import time

import numpy as np
import pytest

import mbcomp
from mbcomp.cli.main import main
from mbcomp.cli.params import build_value
from mbcomp.errors import ModelError

ROOT = pathlib.Path(__file__).resolve().parents[2]
SLIDER = str(ROOT / "models/slider_crank.py")


def _columns(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], float)


def test_a_build_parameter_with_a_unit_is_the_same_run_as_its_si_value(tmp_path, capsys):
    """``-p m_crank="250 g"`` and ``-p m_crank=0.25`` give the same table; 1 kg (the default)
    gives another one, so the value did reach the model."""
    tables = {}
    for value in ("250 g", "0.25", "1.0"):
        out = tmp_path / f"{value.replace(' ', '_')}.csv"
        code = main(["simulate", SLIDER, "-p", f"m_crank={value}", "--t-end", "0.3", "--n-out", "31",
                     "--out", str(out), "-q"])
        assert code == 0, capsys.readouterr()
        tables[value] = _columns(out)
    (h1, a), (h2, b), (_, c) = tables["250 g"], tables["0.25"], tables["1.0"]
    assert h1 == h2 and np.array_equal(a, b)
    phi = h1.index("crank_joint.w")
    assert abs(a[-1, phi] - c[-1, phi]) > 1e-3  # the crank's mass changes the motion


def test_build_values_with_units_in_si():
    def build(length=0.5, r=(0.1, 0.0, 0.0), w0=1.0):
        ...

    assert build_value(build, "length", "30 cm") == 0.3
    assert build_value(build, "w0", "60 rpm") == pytest.approx(2 * np.pi, rel=1e-15)
    assert build_value(build, "r", "(10, 0, 5) mm") == (0.01, 0.0, 0.005)
    with pytest.raises(ValueError, match=r"-p length=3 furlong: unknown unit 'furlong'.*-> give a number in SI"):
        build_value(build, "length", "3 furlong")


def test_a_bad_unit_on_the_command_line_names_the_parameter(capsys):
    code = main(["simulate", SLIDER, "-p", "m_crank=250 furlong", "-q"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("mbcomp: -p m_crank=250 furlong: unknown unit 'furlong'")
    assert "e.g. -p m_crank=1.0" in err


@pytest.mark.parametrize("values, why", [("2:10", "needs the number of points n"), ("2:10:", "needs the number of points n"),
                                         ("2:4:6:8", "needs three parts, not 4")])
def test_a_grid_range_without_its_point_count_is_an_error(tmp_path, capsys, values, why):
    out = tmp_path / "t.csv"
    code = main(["study", SLIDER, "--grid", f"crank_joint.w0={values}", "--out", str(out), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and f"--grid 'crank_joint.w0={values}': a range lo:hi:n {why}" in err
    assert "-> fix: e.g. --grid crank_joint.w0=" in err and not out.exists()


def test_a_grid_range_with_its_point_count_still_works():
    from mbcomp.cli.study import parse_grid

    assert parse_grid("crank_joint.w0=2:10:3") == ("crank_joint.w0", [2.0, 6.0, 10.0])


def test_an_unreachable_dask_scheduler_is_a_one_line_error_within_seconds(tmp_path, capsys, monkeypatch):
    """The connection's own timeout ends the wait (1 s here, CONNECT_TIMEOUT = 5 s by default),
    not distributed's 30 s."""
    pytest.importorskip("distributed")
    from mbcomp.analysis import executors

    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1.0)
    out = tmp_path / "t.csv"
    start = time.monotonic()
    code = main(["study", SLIDER, "--grid", "crank_joint.w0=2:4:2", "--t-end", "0.05", "--executor",
                 "tcp://127.0.0.1:1", "--out", str(out), "-q"])
    wall = time.monotonic() - start
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("mbcomp: executor tcp://127.0.0.1:1: no Dask scheduler answered within 1 s")
    assert "-> fix: check the address" in err and len(err.strip().splitlines()) == 1
    assert wall < 15  # the connection's timeout (1 s), not distributed's 30 s
    assert not out.exists()


@pytest.mark.parametrize("flag", ["--x", "--y"])
def test_a_chart_column_that_is_not_in_the_table_is_refused_before_the_runs(tmp_path, capsys, flag):
    out, plot = tmp_path / "t.csv", tmp_path / "t.png"
    code = main(["study", SLIDER, "--grid", "crank_joint.w0=2:4:2", "--metric", "peak=max(abs(pin.f.y))",
                 "--t-end", "0.05", "--out", str(out), "--plot", str(plot), flag, "nonexist", "-q"])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{flag} nonexist: the table has no column 'nonexist'; its numeric columns are crank_joint.w0, peak" in err
    assert not out.exists() and not plot.exists()  # refused before any run


def test_x_without_a_plot_is_refused(capsys):
    code = main(["study", SLIDER, "--grid", "crank_joint.w0=2:4:2", "--x", "crank_joint.w0", "-q"])
    assert code == 2 and "no --plot was given -> fix: add --plot FILE.png" in capsys.readouterr().err


def _pendulum():
    from mbcomp.library import FixedTranslation, Revolute, Torque, World

    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute())
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    motor = m.add("motor", Torque(tau=0.0))
    m.connect(w.frame_b, j.frame_a)
    return m, j, rod, motor


def test_a_frame_connected_to_itself_is_refused_naming_it():
    m, j, rod, _ = _pendulum()
    with pytest.raises(ModelError) as info:
        m.connect(rod.frame_b, rod.frame_b)
    (p,) = info.value.problems
    assert p.where == "rod.frame_b" and "connected to itself" in p.what and "frame_a" in p.fix
    m.connect(j.frame_b, rod.frame_a)  # the control: two different frames connect


def test_a_flange_connected_to_itself_is_refused():
    m, j, _, motor = _pendulum()
    with pytest.raises(ModelError, match=r"motor.flange_b: is connected to itself .* -> fix: connect motor.flange_b "
                                         r"to a flange of another component"):
        m.connect(motor.flange_b, motor.flange_b)


def test_the_same_frame_reached_twice_through_expose_is_refused():
    """A sub-model exposes its joint's frame_a as ``hinge``: connecting ``sub.hinge`` to that
    very frame is connecting the frame to itself."""
    from mbcomp.library import Revolute

    sub = mbcomp.Model()
    j = sub.add("j", Revolute())
    sub.expose("hinge", j.frame_a)
    top = mbcomp.Model()
    top.add("sub", sub)
    with pytest.raises(ModelError) as info:
        top.connect(sub.hinge, j.frame_a)
    assert info.value.problems[0].where == "sub.j.frame_a"
