"""``mbcomp simulate --animate``: the player written holds the run's own trajectory; bad
animation options are refused before the run, and an animation that cannot be made keeps the
CSV."""
import base64
import json
import re

import numpy as np
import pytest

from mbcomp.cli import main

CRANK = "models/slider_crank.py"


def _scene(html):
    text = re.search(r'<script type="application/json" id="mbcomp-scene">(.*?)</script>', html, re.S).group(1)
    return json.loads(text.replace("<\\/", "</"))


def test_animate_writes_the_runs_trajectory(tmp_path, capsys):
    out, csv_path = tmp_path / "crank.html", tmp_path / "crank.csv"
    assert main(["simulate", CRANK, "--t-end", "0.2", "-q", "--out", str(csv_path), "--animate", str(out),
                 "--trails", "rod_tip.frame_b", "--color-by", "rod=pin.f"]) == 0
    scene = _scene(out.read_text())
    rows = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    header = csv_path.read_text().splitlines()[0].split(",")
    n = scene["n"]
    link = scene["bodies"]["slider"]["link"]
    poses = np.frombuffer(base64.b64decode(scene["links"][link]["poses"]), "<f8").reshape(n, 7)
    assert np.allclose(poses[:, 0], rows[:, header.index("slider.r.x")], rtol=1e-11, atol=1e-12)  # CSV: 12 digits
    assert [t["name"] for t in scene["trails"]] == ["rod_tip.frame_b"]
    assert scene["colors"][0]["column"] == "pin.f" and scene["title"] == "slider_crank.py"
    assert f"wrote {out}" in capsys.readouterr().out


@pytest.mark.parametrize("args, message", [
    (["--animate", "x.png"], "a picture is one frame"),
    (["--animate", "x.avi"], "unknown suffix '.avi'"),
    (["--trails", "crank"], "no --animate was given"),
    (["--animate", "x.html", "--color-by", "rod"], "COMPONENT=COLUMN"),
])
def test_bad_animation_options_are_refused_before_the_run(tmp_path, capsys, args, message):
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    assert main(["simulate", CRANK, "--t-end", "0.05", "-q"] + args) == 2
    err = capsys.readouterr().err
    assert message in err and "status" not in err


def test_an_animation_that_cannot_be_made_keeps_the_csv(tmp_path, capsys):
    csv_path = tmp_path / "r.csv"
    code = main(["simulate", CRANK, "--t-end", "0.05", "-q", "--out", str(csv_path),
                 "--animate", str(tmp_path / "a.html"), "--trails", "no_such_part"])
    assert code == 2 and csv_path.exists()
    assert "no component 'no_such_part'" in capsys.readouterr().err


def _roll(csv_path):
    header = csv_path.read_text().splitlines()[0].split(",")
    rows = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    return rows[:, header.index("time")], rows[:, header.index("roll")]


def test_simulate_params_push_the_bicycle_unless_p_says_otherwise(tmp_path):
    """``mbcomp simulate models/bicycle.py`` starts with the file's SIMULATE_PARAMS push
    (roll rate 0.5 rad/s: roll ~ 0.5 t at first), while ``-p roll_rate0=0`` rides upright."""
    pushed, upright = tmp_path / "pushed.csv", tmp_path / "upright.csv"
    assert main(["simulate", "models/bicycle.py", "--t-end", "0.2", "-q", "--out", str(pushed)]) == 0
    t, roll = _roll(pushed)
    k = np.searchsorted(t, 0.02)
    assert roll[k] == pytest.approx(0.5 * t[k], rel=0.05)
    assert main(["simulate", "models/bicycle.py", "--t-end", "0.2", "-q", "-p", "roll_rate0=0",
                 "--out", str(upright)]) == 0
    assert np.max(np.abs(_roll(upright)[1])) < 1e-9


def test_a_bad_simulate_params_names_the_fix(tmp_path, capsys):
    model = tmp_path / "m.py"
    model.write_text("import mbcomp\nfrom mbcomp.library import World\nSIMULATE_PARAMS = dict(speed=2)\n"
                     "def build(v=1.0):\n    m = mbcomp.Model(); m.add('world', World()); return m\n")
    assert main(["simulate", str(model), "-q"]) == 2
    assert "SIMULATE_PARAMS sets speed, which build() does not take" in capsys.readouterr().err
