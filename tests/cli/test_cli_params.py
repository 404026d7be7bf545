"""``-p name=value``: values parsed into the kind build()'s default declares (numbers,
booleans, lists, strings, "<number> <unit>" passed on), or an error naming the parameter,
its default and the fix; unknown names list build()'s parameters."""
import ast
import math
import csv

import numpy as np
import pytest

from mbcomp.cli import main, parse_value
from mbcomp.cli.loader import split_params

MODEL = '''
import pathlib
from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

RECORD = pathlib.Path(__file__).with_suffix(".args")


def build(length=0.5, n=2, damped=False, r=(0.1, 0.0, 0.0), rs=[1.0, 2.0], mode="fast", angle=0.0,
          gain: float = None, anything=None):
    RECORD.write_text(repr(dict(length=length, n=n, damped=damped, r=r, rs=rs, mode=mode, angle=angle,
                                gain=gain, anything=anything)))
    m = Model()
    w = m.add("world", World())
    j = m.add("hinge", Revolute(phi0=0.3))
    rod = m.add("rod", FixedTranslation(r=(0, -length, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m
'''


@pytest.fixture
def model(tmp_path):
    path = tmp_path / "recorder.py"
    path.write_text(MODEL)
    return path


def build_args(model, *pairs):
    """The arguments ``mbcomp info MODEL -p ...`` passed to build()."""
    argv = ["info", str(model)]
    for p in pairs:
        argv += ["-p", p]
    assert main(argv) == 0
    return ast.literal_eval(model.with_suffix(".args").read_text())


def test_values_reach_build_parsed_as_their_defaults_declare(model, capsys):
    got = build_args(model, "length=1e-3", "n=3", "damped=TRUE", "r=0.2,0,1", "rs=[3, 4.5]", "mode='slow'",
                     "angle=30 deg", "gain=2.5", "anything=abc")
    assert got == dict(length=0.001, n=3, damped=True, r=(0.2, 0, 1), rs=[3, 4.5], mode="slow", angle=pytest.approx(math.radians(30), rel=1e-15),
                       gain=2.5, anything="abc")
    assert type(got["n"]) is int and type(got["r"]) is tuple and type(got["rs"]) is list


def test_list_spellings_agree_and_follow_the_default_type(model):
    for text in ("0.2,0,1", "(0.2, 0, 1)", "[0.2, 0, 1]", "0.2, 0, 1"):
        assert build_args(model, f"r={text}")["r"] == (0.2, 0, 1)
        assert build_args(model, f"rs={text}")["rs"] == [0.2, 0, 1]


def test_string_parameter_keeps_the_text_even_when_it_looks_like_a_number(model):
    assert build_args(model, "mode=1.5")["mode"] == "1.5"
    assert build_args(model, 'mode="a b"')["mode"] == "a b"
    got = build_args(model, "damped=0", "length=-2.5E+1")
    assert got["damped"] is False and got["length"] == -25.0


@pytest.mark.parametrize("pair, message", [
    ("length=abc", "-p length=abc: 'abc' is not a number; build() takes length (default 0.5) -> give a number, "
                   "e.g. -p length=0.5"),
    ("length=0.1,0.2", "-p length=0.1,0.2: '0.1,0.2' is not a number; build() takes length (default 0.5) -> give "
                       "a number, e.g. -p length=0.5"),
    ("damped=yes", "-p damped=yes: 'yes' is not true or false; build() takes damped (default False) -> give true "
                   "or false, e.g. -p damped=true"),
    ("r=abc", "-p r=abc: 'abc' is not a list of numbers; build() takes r (default (0.1, 0.0, 0.0)) -> give numbers "
              "separated by commas, e.g. -p r=0.1,0,0"),
    ("gain=fast", "-p gain=fast: 'fast' is not a number; build() takes gain (default None) -> give a number, "
                  "e.g. -p gain=0.3"),
    ("n=nan", "-p n=nan: 'nan' is not a number; build() takes n (default 2) -> give a number, e.g. -p n=2"),
])
def test_a_value_of_the_wrong_kind_is_an_error_naming_parameter_default_and_fix(model, capsys, pair, message):
    assert main(["info", str(model), "-p", pair]) == 2
    assert capsys.readouterr().err.strip() == f"mbcomp: {message}"
    assert not model.with_suffix(".args").exists()  # build() never ran


def test_unknown_name_lists_build_parameters(model, capsys):
    assert main(["simulate", str(model), "-q", "-p", "lenght=0.3"]) == 2
    assert capsys.readouterr().err.strip() == (
        "mbcomp: -p lenght=0.3: build() takes no parameter lenght; it takes: length (default 0.5), n (default 2), "
        "damped (default False), r (default (0.1, 0.0, 0.0)), rs (default [1.0, 2.0]), mode (default 'fast'), "
        "angle (default 0.0), gain (default None), anything (default None) -> fix: use one of these names, or "
        "component.param=value for a component parameter")


def test_every_command_parses_the_same_way():
    def build(k=1.0, on=False, **rest): ...
    assert split_params(["k=2e3", "on=True", "extra=(1, 2)", "spring.c=1e2", "bob.on=false"], build) == (
        {"k": 2000.0, "on": True, "extra": (1, 2)}, {"spring.c": 100.0, "bob.on": False})
    assert parse_value("RK45") == "RK45" and parse_value("'30 deg'") == "30 deg"


def test_parsed_value_has_its_physical_effect(tmp_path):
    """``-p phi0=0.5`` starts the slider-crank's crank at 0.5 rad, ``-p w0=1e-3`` at 1e-3 rad/s."""
    out = tmp_path / "x.csv"
    assert main(["simulate", "models/slider_crank.py", "--t-end", "0.01", "-q", "-p", "phi0=0.5", "-p", "w0=1e-3",
                 "--out", str(out)]) == 0
    with open(out) as fh:
        rows = list(csv.reader(fh))
    head, first = rows[0], np.array(rows[1], float)
    assert first[head.index("crank_joint.phi")] == 0.5
    assert first[head.index("crank_joint.w")] == pytest.approx(1e-3, rel=1e-12)
