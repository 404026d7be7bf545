"""``mbcomp simulate``: ``--plot-vars`` chooses the plotted columns; ``--max-steps`` /
``--max-time`` stop the run, write the partial results and exit 3; the summary prints the
energy balance error of a damped system and the energy drift of a conservative one."""
import csv

import numpy as np
import pytest

from mbcomp.cli import main
from mbcomp.cli.simulate import EXIT_BUDGET, _energy_line
from mbcomp.result import Result
from mbcomp.simulation import plotting

CRANK = "models/slider_crank.py"

DAMPED = '''
from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Revolute, RotationalDamper, World


def build(d=0.5):
    m = Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    damper = m.add("damper", RotationalDamper(d=d))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.support, damper.flange_a)
    m.connect(j.axis, damper.flange_b)
    return m
'''


def read_csv(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], float)


def test_plot_vars_draws_exactly_the_matching_columns(tmp_path, monkeypatch, capsys):
    drawn = []
    real = plotting.draw

    def spy(result, names, path=None, title=None):
        drawn.append((list(names), list(result.names)))
        return real(result, names, path, title)

    monkeypatch.setattr(plotting, "draw", spy)
    png = tmp_path / "p.png"
    assert main(["simulate", CRANK, "--t-end", "0.05", "-q", "--plot", str(png),
                 "--plot-vars", "slider_joint.*", "*.tau.z"]) == 0
    (names, columns), = drawn
    want = [n for n in columns if n.startswith("slider_joint.")]
    want += [n for n in columns if n.endswith(".tau.z") and n not in want]
    assert names == want and "slider_joint.s" in names and "pin.tau.z" in names
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_plot_vars_matching_nothing_keeps_the_csv_and_names_similar_columns(tmp_path, capsys):
    out, png = tmp_path / "x.csv", tmp_path / "x.png"
    code = main(["simulate", CRANK, "--t-end", "0.05", "-q", "--out", str(out), "--plot", str(png),
                 "--plot-vars", "slider_jont.s"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and out.exists() and not png.exists()
    assert err.startswith("mbcomp: --plot-vars: no column matches 'slider_jont.s'; similar: slider_joint.s, ")
    assert err.endswith(f"(Result.names lists them) ({out} is written)")


def test_plot_vars_without_plot_is_refused_before_the_run(capsys):
    assert main(["simulate", CRANK, "-q", "--plot-vars", "pin.*"]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.strip() == ("mbcomp: --plot-vars chooses the columns --plot draws, and no --plot "
                                                 "was given -> fix: add --plot FILE.png")


@pytest.mark.parametrize("budget", [["--max-steps", "5"], ["--max-time", "0.001"]])
def test_a_spent_budget_writes_the_partial_results_and_exits_3(tmp_path, capsys, budget):
    out, png = tmp_path / "x.csv", tmp_path / "x.png"
    code = main(["simulate", CRANK, "--t-end", "50", "-q", "--out", str(out), "--plot", str(png)] + budget)
    stdout = capsys.readouterr().out
    assert code == EXIT_BUDGET == 3
    head, data = read_csv(out)
    assert data[-1, 0] < 50.0 and png.exists()
    assert "status: budget (" in stdout
    assert f"budget spent at t = {data[-1, 0]:g} s: {out} holds the partial results up to then" in stdout


def test_damped_run_prints_the_energy_balance_error_not_a_drift(tmp_path, capsys):
    model = tmp_path / "damped.py"
    model.write_text(DAMPED)
    out = tmp_path / "d.csv"
    assert main(["simulate", str(model), "--t-end", "3", "--n-out", "1501", "-q", "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    head, data = read_csv(out)
    bal = np.abs(data[:, head.index("energy.balance")]).max()
    E = data[:, head.index("energy.total")]
    assert abs(E[-1] - E[0]) > 1.0  # the damper took energy out: a "drift" would be meaningless
    assert f"energy balance error max|E - E0 - W + D| = {bal:.3e} J (" in stdout
    assert "energy drift" not in stdout
    main(["simulate", CRANK, "--t-end", "0.05", "-q"])
    assert "energy drift max|E - E0| = " in capsys.readouterr().out  # conservative: the drift line stays


def test_energy_balance_error_is_relative_to_the_energy_exchanged():
    t = np.array([0.0, 1.0, 2.0])
    cols = {"energy.kinetic": np.array([0.0, 3.0, 1.0]), "energy.potential": np.array([4.0, 2.0, 0.0]),
            "energy.total": np.array([4.0, 5.0, 1.0]), "energy.work": np.array([0.0, 1.0, 5.0]),
            "energy.dissipated": np.array([0.0, 0.0, 2.0]), "energy.balance": np.array([0.0, 0.0, -0.02])}
    # scale: max(max T + range of V = 3 + 4, max|W| = 5, max D = 2) = 7 J
    assert _energy_line(Result(t, cols)) == "energy balance error max|E - E0 - W + D| = 2.000e-02 J (2.9e-03 of the 7 J exchanged)"


def test_csv_units_writes_each_columns_unit_in_its_header(tmp_path):
    out = tmp_path / "crank.csv"
    assert main(["simulate", CRANK, "--t-end", "0.2", "--out", str(out), "--csv-units"]) == 0
    with open(out) as fh:
        header = next(csv.reader(fh))
    assert header[0] == "time [s]"
    assert "crank_joint.phi [rad]" in header and "crank_joint.w [rad/s]" in header
    assert "energy.total [J]" in header and "rod_joint.f.x [N]" in header
    plain = tmp_path / "plain.csv"
    assert main(["simulate", CRANK, "--t-end", "0.2", "--out", str(plain)]) == 0
    with open(plain) as fh:
        assert "crank_joint.phi" in next(csv.reader(fh))
