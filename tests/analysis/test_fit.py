"""Parameter identification (:func:`mbcomp.fit`) on the damped slider-crank of
``bench/fit_slider_crank.py``: the rod's mass, the rod's inertia ``rod.I[2, 2]`` and the crank
damper's rate from the crank angle alone.

* noisy angles (1 mrad, seeded): the three parameters come back within 1 % and within 3 of their
  own standard errors, and the residual's rms is the noise's;
* noise-free angles: the parameters come back to 1e-6 (the runs' tolerance is the limit);
* the Jacobian the optimizer gets is the central difference of whole runs, and the difference's
  error falls as h^2 (the sensitivities are the derivative of the residual, not an approximation);
* irregular times, served by a spline through a fine output grid: the residual and Jacobian
  agree with those at exact output times to 1e-9;
* the command line fits from a CSV file and writes the JSON;
* bad data and bad names are errors naming the column, parameter and fix.
"""
import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import mbcomp
from mbcomp.analysis.fit import LeastSquares, read_data
from mbcomp.cli import main

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
import fit_slider_crank as ex  # noqa: E402

NAMES = ["rod.m", "rod.I[2, 2]", "damper.d"]
TRUE = np.array([ex.TRUE[p] for p in NAMES])
START = np.array([ex.START[p] for p in NAMES])


@pytest.fixture(scope="module")
def model():
    return mbcomp.assemble(ex.build())


@pytest.fixture(scope="module")
def clean(model):
    return ex.measurements(model, t_end=1.5, points=61, noise=0.0)


def test_recovers_three_parameters_from_noisy_angles_within_1_percent(model):
    noise = 1e-3
    data = ex.measurements(model, t_end=3.0, points=301, noise=noise, seed=0)
    f = mbcomp.fit(model, data, dict(ex.START), bounds=ex.BOUNDS)
    assert f.success and f.params == NAMES
    err = f.values - TRUE
    assert np.all(np.abs(err / TRUE) < 0.01), f.table()
    assert np.all(np.abs(err) < 3 * f.std_errors), f.table()           # the standard errors are honest
    assert np.all(f.std_errors / TRUE < 0.01) and np.all(f.std_errors > 0)
    rms = np.sqrt(np.mean(f.residual["crank_angle"] ** 2))
    assert 0.8 * noise < rms < 1.2 * noise                               # the model explains all but the noise
    # one run per residual (the Jacobian reused), and one more when the optimizer's last trial was
    # rejected: the standard errors are taken at the accepted values
    assert f.optimizer.nfev <= f.runs <= f.optimizer.nfev + 1 and f.runs < 30
    assert np.isclose(f.cost, 0.5 * np.sum(f.residual["crank_angle"] ** 2))


def test_noise_free_angles_give_the_parameters_exactly(model, clean):
    f = mbcomp.fit(model, clean, dict(ex.START), bounds=ex.BOUNDS)
    assert f.success
    assert np.all(np.abs(f.values / TRUE - 1) < 1e-6), f.values / TRUE - 1
    assert np.all(f.std_errors / TRUE < 1e-6)


def test_jacobian_is_the_central_difference_of_whole_runs(model, clean):
    ls = LeastSquares(model, clean, NAMES, rtol=1e-12, atol=1e-14)
    r, J = ls.evaluate(START)
    assert ls.exact_times and J.shape == (61, 3) and ls.runs == 1
    assert np.all(np.max(np.abs(J), axis=0) > 0.1)                      # every parameter moves the angle
    errors = []
    for h in (1e-3, 1e-4):
        fd = np.column_stack([(ls.residual(START + h * START[j] * e) - ls.residual(START - h * START[j] * e))
                              / (2 * h * START[j]) for j, e in enumerate(np.eye(3))])
        errors.append(np.max(np.abs(fd - J), axis=0) / np.max(np.abs(J), axis=0))
    assert np.all(errors[1] < 1e-7)
    assert np.all(errors[1] < errors[0] / 30)                            # falls as h^2 (100x for 10x)
    assert ls.runs == 1 + 2 * 3 * 2


def test_irregular_times_are_served_by_a_spline_as_accurate_as_exact_outputs(model, clean):
    exact = LeastSquares(model, clean, NAMES)
    spline = LeastSquares(model, clean, NAMES, n_out=2001)             # another grid: the spline serves the times
    assert exact.exact_times and not spline.exact_times
    r0, J0 = exact.evaluate(TRUE)
    r1, J1 = spline.evaluate(TRUE)
    assert np.max(np.abs(r1 - r0)) < 1e-9                               # rad
    assert np.all(np.max(np.abs(J1 - J0), axis=0) < 1e-8 * np.max(np.abs(J0), axis=0))
    rng = np.random.default_rng(3)                                      # genuinely irregular times: the spline
    t = np.sort(rng.uniform(0.0, 1.5, 40))
    ls = LeastSquares(model, {"time": t, "crank_angle": np.zeros_like(t)}, NAMES)
    assert not ls.exact_times and ls.n_out >= 2001


def test_a_parameter_the_angle_does_not_see_has_an_infinite_standard_error(model, clean):
    # the crank's inertia about its own x axis plays no part in the plane motion: its
    # sensitivity is exactly zero and J^T J singular; the other parameter keeps a finite error
    names = ["damper.d", "crank.I[0, 0]"]
    ls = LeastSquares(model, clean, names)
    r, J = ls.evaluate([0.04, 1e-6])
    assert np.all(J[:, 1] == 0.0) and np.max(np.abs(J[:, 0])) > 1.0
    f = mbcomp.fit(model, clean, {"damper.d": 0.04, "crank.I[0, 0]": 1e-6}, bounds={"crank.I[0, 0]": (0, 0.1)},
                   solver_options={"max_nfev": 8})
    assert np.isinf(f.std_errors[1]) and np.isfinite(f.std_errors[0])
    assert "cannot determine crank.I[0, 0]" in f.message
    assert abs(f["damper.d"] / 0.05 - 1) < 1e-6


def test_command_line_fits_from_a_csv(model, tmp_path):
    data = ex.measurements(model, t_end=1.0, points=41, noise=0.0)
    csv = tmp_path / "meas.csv"
    np.savetxt(csv, np.column_stack([data["time"], data["crank_angle"]]), delimiter=",",
               header="time [s],crank_angle [rad]", comments="", fmt="%.15g")
    out = tmp_path / "fitted.json"
    run = subprocess.run([sys.executable, "-m", "mbcomp.cli", "fit", str(ROOT / "bench" / "fit_slider_crank.py"),
                          "--data", str(csv), "--param", "rod.m", "--param", "damper.d", "-p", "rod.m=1.6",
                          "-p", "damper.d=0.04", "--bounds", "rod.m=0.1:10", "--bounds", "damper.d=0:",
                          "--column", "crank_angle", "--out", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "rod.m" in run.stdout and "std error" in run.stdout and "converged" in run.stdout
    doc = json.loads(out.read_text())
    assert doc["params"]["rod.m"]["start"] == 1.6 and doc["success"]
    assert abs(doc["params"]["rod.m"]["value"] - 2.0) < 1e-6 and abs(doc["params"]["damper.d"]["value"] - 0.05) < 1e-7


def test_command_line_bad_input(tmp_path, capsys):
    csv = tmp_path / "meas.csv"
    csv.write_text("time,crank_angle\n0,0.3\n0.1,abc\n")
    model = str(ROOT / "bench" / "fit_slider_crank.py")
    assert main(["fit", model, "--data", str(csv), "--param", "rod.m"]) == 2
    assert "line 3, column 'crank_angle': 'abc' is not a number" in capsys.readouterr().err
    assert main(["fit", model, "--data", str(csv)]) == 2
    assert "no parameter to fit" in capsys.readouterr().err
    assert main(["fit", model, "--data", str(csv), "--param", "rod.m", "--bounds", "rod.m=1"]) == 2
    assert "NAME=LO:HI" in capsys.readouterr().err
    assert main(["fit", model, "--data", str(csv), "--param", "m_rod"]) == 2
    assert "a build() argument cannot be fitted" in capsys.readouterr().err


def test_bad_data_errors_name_the_column_and_the_fix(model, clean):
    t = clean["time"]
    y = clean["crank_angle"]
    cases = [({"t": t, "crank_angle": y}, "no time column 'time'"),
             ({"time": t[::-1], "crank_angle": y}, "times must increase strictly"),
             ({"time": np.r_[t[:3], t[2:-1]], "crank_angle": y}, "times must increase strictly"),
             ({"time": t, "crank_angle": np.r_[y[:5], np.nan, y[6:]]}, "column 'crank_angle' holds nan at t = "),
             ({"time": t, "crank_angle": y[:-1]}, "has 60 values for 61 times"),
             ({"time": t}, "nothing to fit")]
    for data, message in cases:
        with pytest.raises(ValueError, match="fix|give|add") as info:
            read_data(data)
        assert message in str(info.value)
    with pytest.raises(ValueError, match="no column 'crank_angel'.*did you mean 'crank_angle'"):
        read_data(clean, columns=["crank_angel"])


def test_bad_names_and_bounds_are_errors_with_the_fix(model, clean):
    with pytest.raises(ValueError, match="'rod.mass': component 'rod' has no parameter 'mass'.* -> use one of I, m"):
        mbcomp.fit(model, clean, ["rod.mass"])
    with pytest.raises(ValueError, match="the model has no component 'rood'"):
        mbcomp.fit(model, clean, ["rood.m"])
    with pytest.raises(ValueError, match=r"rod.I.*array of shape \(3, 3\).*rod.I\[0, 0\]"):
        mbcomp.fit(model, clean, ["rod.I"])
    with pytest.raises(ValueError, match="rod.m starts at 2, outside its bounds"):
        mbcomp.fit(model, clean, ["rod.m"], bounds={"rod.m": (3.0, 5.0)})
    with pytest.raises(ValueError, match="'rod.x' is not a fitted parameter"):
        mbcomp.fit(model, clean, ["rod.m"], bounds={"rod.x": (0, 1)})
    with pytest.raises(ValueError, match="data column 'slider_pos' is no result column.*slider_position"):
        mbcomp.fit(model, {"time": clean["time"], "slider_pos": clean["crank_angle"]}, ["rod.m"])
    with pytest.raises(ValueError, match="triangle inequality.*bounds="):    # rod.I[2, 2] beyond I_xx + I_yy
        mbcomp.fit(model, clean, {"rod.I[2, 2]": 0.2})
    with pytest.raises(TypeError, match="call it"):
        mbcomp.fit(ex.build, clean, ["rod.m"])


def test_an_array_held_in_values_has_its_fitted_entry_start_there(model, clean):
    held = np.diag([0.07, 0.07, 0.05])
    ls = LeastSquares(model, clean, ["rod.I[2, 2]"], values={"rod.I": held})
    assert ls.start_values().tolist() == [0.05]
    r, J = ls.evaluate([0.06])                           # the held array with its entry replaced: the truth
    assert np.max(np.abs(r)) < 1e-8
    with pytest.raises(ValueError, match="'rod.m' is both fitted and held fixed"):
        LeastSquares(model, clean, ["rod.m"], values={"rod.m": 2.0})
