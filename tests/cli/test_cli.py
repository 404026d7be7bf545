"""The command line: simulate writes a CSV whose physics holds; info reports the DOF."""
import csv
import subprocess
import sys

import numpy as np

from mbcomp.cli import main


def read_csv(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], float)


def test_simulate_writes_csv_with_conserved_energy(tmp_path, capsys):
    out = tmp_path / "x.csv"
    code = main(["simulate", "models/slider_crank.py", "--t-end", "0.5", "--rtol", "1e-9", "--atol", "1e-11",
                 "--out", str(out), "-q"])
    assert code == 0
    header, data = read_csv(out)
    assert header[0] == "time" and "crank_joint.phi" in header and "crank_angle" in header
    assert "rod_joint.f.x" in header  # the loop-closing joint's reaction
    E = data[:, header.index("energy.total")]
    assert np.abs(E - E[0]).max() < 1e-6
    assert data[-1, 0] == 0.5
    assert "status: success" in capsys.readouterr().out


def test_build_and_runtime_parameters_agree(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert main(["simulate", "models/slider_crank.py", "--t-end", "0.3", "-p", "m_slider=1.5", "--out", str(a), "-q"]) == 0
    assert main(["simulate", "models/slider_crank.py", "--t-end", "0.3", "-p", "slider.m=1.5", "--out", str(b), "-q"]) == 0
    ha, da = read_csv(a)
    hb, db = read_csv(b)
    i = ha.index("slider_joint.s")
    np.testing.assert_allclose(da[:, i], db[:, hb.index("slider_joint.s")], atol=1e-12)
    ref = tmp_path / "c.csv"
    main(["simulate", "models/slider_crank.py", "--t-end", "0.3", "--out", str(ref), "-q"])
    hc, dc = read_csv(ref)
    assert np.abs(dc[:, hc.index("slider_joint.s")] - da[:, i]).max() > 1e-6  # the mass mattered


def test_info_reports_one_dof():
    out = subprocess.run([sys.executable, "-m", "mbcomp.cli", "info", "models/slider_crank.py"],
                         capture_output=True, text=True, check=True).stdout
    assert "degrees of freedom: 1" in out
    assert "cut joints (loop closure): rod_joint" in out


def test_bad_parameter_is_a_clear_error(capsys):
    code = main(["simulate", "models/slider_crank.py", "-p", "slider.m=-2", "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "slider.m" in err and "fix" in err


def test_bench_writes_a_work_precision_table_against_a_reference(tmp_path, capsys):
    """``mbcomp bench`` on Andrews: two combinations at two tolerances, judged against the
    published solution; the tighter tolerance is closer to it, and the table says which."""
    import csv

    from mbcomp.cli import main

    out, png = tmp_path / "wp.csv", tmp_path / "wp.png"
    code = main(["bench", "models/andrews.py", "--tols", "1e-5,1e-8", "--combos", "ODE i1 projection / DOP853,DAE i3 / radau5",
                 "--out", str(out), "--plot", str(png), "--target", "1e-6"])
    assert code == 0 and png.stat().st_size > 0
    rows = list(csv.DictReader(open(out)))
    for combo in {r["combo"] for r in rows}:
        errs = {float(r["value"]): float(r["error"]) for r in rows if r["combo"] == combo}
        assert errs[1e-8] < 1e-6 < errs[1e-5] or errs[1e-8] < errs[1e-5], (combo, errs)
        assert errs[1e-8] < 1e-6
    text = capsys.readouterr().out
    assert "andrews: fastest CPU time reaching relative position error <= 1e-06" in text


def test_simulate_writes_sensitivity_columns(tmp_path, capsys):
    """``--sensitivity`` (repeatable) puts d(<coordinate or speed>)/d(<param>) in the CSV, equal
    to mbcomp.simulate's ``res.sensitivity`` and to a central difference of two tight runs."""
    import mbcomp

    out = tmp_path / "s.csv"
    code = main(["simulate", "models/slider_crank.py", "--t-end", "0.5", "--rtol", "1e-10", "--atol", "1e-12",
                 "--sensitivity", "rod.m", "--sensitivity", "crank_joint.phi0", "--out", str(out), "-q"])
    assert code == 0
    header, data = read_csv(out)
    s = data[:, header.index("d(crank_joint.phi)/d(rod.m)")]
    build = mbcomp.load_model_file("models/slider_crank.py").build
    runs = [mbcomp.simulate(build(), t_end=0.5, params={"rod.m": 2.0 + d}, rtol=1e-12, atol=1e-14)["crank_angle"]
            for d in (1e-5, -1e-5)]
    fd = (runs[0] - runs[1]) / 2e-5
    assert np.max(np.abs(s - fd)) < 1e-6 * np.max(np.abs(fd))
    api = mbcomp.simulate(build(), t_end=0.5, rtol=1e-10, atol=1e-12, sensitivities=["rod.m", "crank_joint.phi0"])
    for col, param in (("crank_joint.phi", "rod.m"), ("slider_joint.v", "crank_joint.phi0")):  # CSV: 12 digits
        np.testing.assert_allclose(data[:, header.index(f"d({col})/d({param})")], api.sensitivity(col, param),
                                   rtol=1e-11, atol=0)
    assert "sensitivities with respect to rod.m, crank_joint.phi0: 12 columns" in capsys.readouterr().out
