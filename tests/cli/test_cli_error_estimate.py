"""``mbcomp simulate --error-estimate`` prints the global error the Python call measures
(``simulate(..., error_estimate=True)``, tests/simulation/test_error_estimate.py)."""
import re

import mbcomp
from mbcomp.cli import main


def test_the_cli_prints_the_estimated_global_error(capsys, monkeypatch):
    monkeypatch.chdir(mbcomp.__file__.rsplit("/src/", 1)[0])
    assert main(["simulate", "models/slider_crank.py", "--t-end", "0.5", "--rtol", "1e-6", "--atol", "1e-8",
                 "--error-estimate", "-q"]) == 0
    out = capsys.readouterr().out
    found = re.search(r"estimated global error (\S+) (\S+) \(in (\S+); against a run at rtol=(\S+)\)", out)
    assert found, out
    mod = mbcomp.load_model_file("models/slider_crank.py")
    res = mbcomp.simulate(mod.build(), **{**getattr(mod, "SIMULATION", {}), "t_end": 0.5, "rtol": 1e-6,
                                           "atol": 1e-8}, error_estimate=True)
    assert found.group(3) == res.stats["global_error_column"]
    assert abs(float(found.group(1)) - res.stats["global_error"]) <= 1e-3 * res.stats["global_error"]
    assert float(found.group(4)) == 1e-8
    # the estimate is of the error a 1e-6 run makes: larger than 1e-6 of the speeds' scale would mean a bug
    assert 1e-9 < res.stats["global_error"] < 1e-2


def test_without_the_flag_nothing_is_estimated(capsys, monkeypatch):
    monkeypatch.chdir(mbcomp.__file__.rsplit("/src/", 1)[0])
    assert main(["simulate", "models/slider_crank.py", "--t-end", "0.2", "-q"]) == 0
    assert "estimated global error" not in capsys.readouterr().out
