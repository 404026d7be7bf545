"""The HTML player's file without a browser: the scene inside decodes to the result's own
numbers, three.js and its licence are inlined, nothing is fetched, and the size stays small."""
import base64
import json
import pathlib
import re

import numpy as np
import pytest

import mbcomp
from mbcomp.visual.html import THREE_VERSION, VENDOR, write_html
from mbcomp.visual.scene import build_scene

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def _scene_json(text):
    m = re.search(r'<script type="application/json" id="mbcomp-scene">(.*?)</script>', text, re.S)
    assert m, "the page has no scene"
    return json.loads(m.group(1))


def _f64(b64):
    return np.frombuffer(base64.b64decode(b64), dtype="<f8")


@pytest.fixture(scope="module")
def crank(tmp_path_factory):
    res = mbcomp.simulate(mbcomp.load_model_file(str(MODELS / "slider_crank.py")).build(), t_end=1.0)
    path = write_html(build_scene(res, trails=["rod_tip.frame_b"], color_by={"rod": "pin.f"}, title="a </script> b"),
                      tmp_path_factory.mktemp("html") / "crank.html", speed=0.5)
    return res, pathlib.Path(path).read_text(encoding="utf-8")


def test_embedded_scene_decodes_to_the_result_columns(crank):
    res, text = crank
    data = _scene_json(text)
    assert np.array_equal(_f64(data["time"]), np.asarray(res.time, dtype=float))
    assert data["title"] == "a </script> b" and data["speed"] == 0.5
    n = len(res.time)
    for body, b in data["bodies"].items():
        poses = _f64(data["links"][b["link"]]["poses"]).reshape(n, 7)
        assert b["r"] == [0.0, 0.0, 0.0] and b["q"] == [1.0, 0.0, 0.0, 0.0]  # each body anchors its own link
        cols = [f"{body}.r.{a}" for a in "xyz"] + [f"{body}.Q.{a}" for a in "wxyz"]
        assert np.array_equal(poses, np.column_stack([res[c] for c in cols])), body
    colour = data["colors"][0]
    f = np.sqrt(sum(np.asarray(res[f"pin.f.{a}"]) ** 2 for a in "xyz"))
    assert np.array_equal(_f64(colour["values"]), f) and colour["max"] == f.max()


def test_three_and_its_licence_are_inlined(crank):
    _, text = crank
    licence = (VENDOR / "LICENSE").read_text(encoding="utf-8")
    assert "Copyright © 2010-2024 three.js authors" in text and "MIT License" in text
    assert licence.splitlines()[-1] in text
    assert f"three@{THREE_VERSION}" in text
    imports = json.loads(re.search(r'<script type="importmap">(.*?)</script>', text, re.S).group(1))["imports"]
    three = base64.b64decode(imports["three"].split(",", 1)[1])
    assert three == (VENDOR / "build" / "three.module.min.js").read_bytes()
    assert f'REVISION="{THREE_VERSION.split(".")[1]}"'.encode() in three or b'"170"' in three


def test_nothing_is_fetched(crank):
    _, text = crank
    assert "http://" not in text and "https://" not in text
    assert not re.search(r"<(script|link|img|iframe)[^>]*\s(src|href)=", text)
    imports = json.loads(re.search(r'<script type="importmap">(.*?)</script>', text, re.S).group(1))["imports"]
    assert all(url.startswith("data:text/javascript;base64,") for url in imports.values())
    orbit = base64.b64decode(imports["three/addons/controls/OrbitControls.js"].split(",", 1)[1]).decode()
    sources = re.findall(r"from\s+'([^']+)'|from\s+\"([^\"]+)\"", orbit)
    assert {a or b for a, b in sources} == {"three"}  # resolved by the import map, not a URL
    player = text.split('<script type="module">', 1)[1]
    assert set(re.findall(r'from "([^"]+)"', player)) == set(imports)


def test_scene_text_cannot_end_its_script_element(crank):
    _, text = crank
    m = re.search(r'id="mbcomp-scene">(.*?)</script>', text, re.S)
    assert "<" not in m.group(1)  # "</script>" of the title is written \\u003c/script\\u003e


def test_twenty_bodies_for_ten_seconds_stay_under_5_mb(tmp_path):
    model = mbcomp.load_model_file(str(MODELS / "n_link_pendulum.py")).build(N=20)
    res = mbcomp.simulate(model, t_end=10.0, n_out=1001, rtol=1e-6, atol=1e-8)
    path = write_html(build_scene(res), tmp_path / "chain.html")
    data = _scene_json(pathlib.Path(path).read_text(encoding="utf-8"))
    assert sum(L["poses"] is not None for L in data["links"]) == 20 and data["n"] == 1001
    size = pathlib.Path(path).stat().st_size
    assert size < 5e6, f"{size / 1e6:.2f} MB"


def test_missing_folder_names_the_path(tmp_path):
    res = mbcomp.simulate(mbcomp.load_model_file(str(MODELS / "slider_crank.py")).build(), t_end=0.1)
    bad = tmp_path / "no_such_folder" / "x.html"
    with pytest.raises(FileNotFoundError, match="no_such_folder"):
        write_html(build_scene(res), bad)
    assert not bad.parent.exists()
