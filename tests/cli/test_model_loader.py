"""``mbcomp.load_model_file`` / ``mbcomp.load_model``: the one way to load a model file
(the CLI, the tests and the benches use it), with errors that name the file and the fix."""
import pytest

import mbcomp
import mbcomp.cli
from mbcomp.cli import main

SC = "models/slider_crank.py"


def test_load_model_passes_build_arguments_through():
    model = mbcomp.load_model(SC, m_slider=1.5, phi0=0.7)
    assert isinstance(model, mbcomp.Model)
    system = mbcomp.assemble(model)
    assert system.P["slider"].m == 1.5 and system.P["crank"].m == 1.0
    res = mbcomp.simulate(model, t_end=1e-9)
    assert res["crank_joint.phi"][0] == 0.7  # the fixed start angle given to build()


def test_load_model_file_returns_a_fresh_module_each_time():
    a, b = mbcomp.load_model_file(SC), mbcomp.load_model_file(SC)
    assert a is not b and a.build is not b.build and a.SIMULATION == b.SIMULATION == dict(t_end=10.0, rtol=1e-8,
                                                                                          atol=1e-10)
    assert mbcomp.cli.load_model_file is mbcomp.load_model_file
    assert {"load_model", "load_model_file"} <= set(mbcomp.__all__)


def test_missing_file(tmp_path):
    path = tmp_path / "nope.py"
    with pytest.raises(mbcomp.ModelError) as err:
        mbcomp.load_model(path)
    (p,) = err.value.problems
    assert p.where == str(path) and p.what == "the model file does not exist" and "build(**params)" in p.fix


def test_file_without_build(tmp_path):
    path = tmp_path / "half.py"
    path.write_text("X = 1\n")
    with pytest.raises(mbcomp.ModelError) as err:
        mbcomp.load_model_file(path)
    (p,) = err.value.problems
    assert p.where == str(path) and "defines no build" in p.what and "def build(**params)" in p.fix


@pytest.mark.parametrize("body, kind", [("return None", "None"), ("return mbcomp.assemble(m)", "a MultibodySystem (")])
def test_build_that_returns_no_model(tmp_path, body, kind):
    path = tmp_path / "wrong.py"
    path.write_text("import mbcomp\nfrom mbcomp.library import World\n\n"
                    f"def build():\n    m = mbcomp.Model()\n    m.add('world', World())\n    {body}\n")
    mbcomp.load_model_file(path)  # loading is fine: build() is there
    with pytest.raises(mbcomp.ModelError) as err:
        mbcomp.load_model(path)
    (p,) = err.value.problems
    assert str(path) in p.where and p.what.startswith(f"build() returned {kind}")
    assert p.what.endswith("; it must return an mbcomp.Model") and "return m" in p.fix


def test_not_a_python_file(tmp_path):
    path = tmp_path / "model.txt"
    path.write_text("def build(): pass\n")
    with pytest.raises(mbcomp.ModelError, match="is not a Python file"):
        mbcomp.load_model_file(path)


@pytest.mark.parametrize("command", ["info", "simulate", "stability"])
def test_the_cli_reports_loader_errors_and_exits_2(tmp_path, command, capsys):
    path = tmp_path / "nope.py"
    assert main([command, str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mbcomp: ") and str(path) in err and "does not exist" in err and "fix" in err


@pytest.mark.parametrize("argv, words", [
    (["-p", "m_slider"], ["-p expects name=value", "'m_slider'"]),
    (["-p", "mass=2"], ["build() takes no parameter mass", "m_slider", "component.param=value"]),
])
def test_bad_parameters_are_input_errors(argv, words, capsys):
    assert main(["info", SC, *argv]) == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err, (w, err)
