"""The HTML player in a real browser: headless Chromium opens the written file (file://, no
network) and the poses the three.js scene graph holds are the result's own numbers.

Skipped when Chromium (/usr/bin/chromium) or playwright is missing. With the environment
variable ``MBCOMP_SCREENSHOTS`` set to a folder, the test also saves 960x540 screenshots there
(``slider_crank.png``, ``bicycle.png``, and ``bicycle_cli.png`` of the command line's file:
the README's pictures are ``slider_crank.png`` and ``bicycle_cli.png``).
"""
import os
import pathlib
import shutil

import numpy as np
import pytest

import mbcomp
from mbcomp.visual.html import write_html
from mbcomp.visual.scene import build_scene

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
CHROMIUM = "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else shutil.which("chromium")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"]

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium (apt-get install chromium)")


@pytest.fixture(scope="module")
def browser():
    sync = pytest.importorskip("playwright.sync_api")
    with sync.sync_playwright() as p:  # playwright gives the browser a fresh profile of its own
        b = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        yield b
        b.close()


def ball_in_bowl():
    """A ball rolling in a spherical bowl (radius 1 m, bottom at the origin), released 0.5 rad
    up the wall with a sideways speed: the player draws the bowl as a translucent mesh."""
    from mbcomp.library import FreeMotion, RigidBody, SphereContact, World
    from mbcomp.library.surfaces import SphereSurface

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    free = m.add("free", FreeMotion(r0=(0.9 * np.sin(0.5), 0, 1 - 0.9 * np.cos(0.5)), v0=(0, 0.8, 0)))
    ball = m.add("ball", RigidBody(m=0.5, I=0.002 * np.eye(3)))
    c = m.add("contact", SphereContact(r=0.1, surface=SphereSurface(R=1.0, center=(0, 0, 1.0))))
    m.connect(w.frame_b, free.frame_a)
    m.connect(free.frame_b, ball.frame_a)
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, ball.frame_a)
    return m


CASES = {
    "ball_in_bowl": dict(model=ball_in_bowl, t_end=1.5, trails=["ball"], color_by=None, shot=0.7),
    "slider_crank": dict(file="slider_crank.py", build={}, t_end=1.0, trails=["rod_joint.frame_a", "rod_tip.frame_b"],
                         color_by={"rod": "pin.f"}, shot=0.3),
    "bicycle": dict(file="bicycle.py", build=dict(v=4.0, roll0=0.05), t_end=2.0, trails=["rear_contact"],
                    color_by=None, shot=1.6),
}


def _open(name, browser, folder):
    """(name, result, page) of a case's player opened in the browser, ready."""
    case = CASES[name]
    model = case["model"]() if "model" in case else mbcomp.load_model_file(str(MODELS / case["file"])).build(**case["build"])
    res = mbcomp.simulate(model, t_end=case["t_end"])
    scene = build_scene(res, trails=case["trails"], color_by=case["color_by"], title=name)
    path = write_html(scene, folder / f"{name}.html")
    page = browser.new_page(viewport={"width": 960, "height": 540})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(pathlib.Path(path).as_uri())
    page.wait_for_function("window.mbcomp !== undefined")
    page.evaluate("window.mbcomp.ready.then(() => true)")
    assert not errors, errors
    return name, res, page


@pytest.fixture(scope="module", params=sorted(CASES))
def player(request, browser, tmp_path_factory):
    """Each case's player, opened in the browser."""
    name, res, page = _open(request.param, browser, tmp_path_factory.mktemp("html"))
    yield name, res, page
    page.close()


@pytest.fixture(scope="module")
def bowl_player(browser, tmp_path_factory):
    """The ball-in-a-bowl case's player alone."""
    name, res, page = _open("ball_in_bowl", browser, tmp_path_factory.mktemp("bowl"))
    yield name, res, page
    page.close()


def _column_pose(res, body, k):
    r = np.array([res[f"{body}.r.{a}"][k] for a in "xyz"])
    q = np.array([res[f"{body}.Q.{a}"][k] for a in "wxyz"])
    return r, q


def _assert_pose(got, r, q, what):
    assert np.allclose(got["r"], r, rtol=0, atol=1e-9), f"{what}: r {got['r']} != {r}"
    dq = min(np.max(np.abs(np.array(got["q"]) - q)), np.max(np.abs(np.array(got["q"]) + q)))
    assert dq < 1e-9, f"{what}: q {got['q']} != +-{q}"


def test_bodies_posed_exactly_at_output_times(player):
    name, res, page = player
    bodies = page.evaluate("window.mbcomp.bodies()")
    assert sorted(bodies) == sorted(path for path, _, _ in res.system.topology.bodies)
    assert page.evaluate("window.mbcomp.duration()") == pytest.approx(res.time[-1] - res.time[0], abs=1e-12)
    digests = []
    for k in (10, len(res.time) - 5):
        assert page.evaluate(f"window.mbcomp.setTime({float(res.time[k])!r})") == float(res.time[k])
        assert page.evaluate("window.mbcomp.time()") == float(res.time[k])
        for b in bodies:
            _assert_pose(page.evaluate(f"window.mbcomp.bodyPose({b!r})"), *_column_pose(res, b, k), f"{name} {b} t[{k}]")
        px = page.evaluate("window.mbcomp.pixels()")
        assert px["nonBackground"] > 0.01 * px["width"] * px["height"], f"{name}: the canvas is blank at t[{k}]"
        digests.append(px["hash"])
    assert digests[0] != digests[1], f"{name}: the frames at two times look the same"


def test_the_bowl_is_drawn_where_the_ball_rolls(bowl_player):
    """The bowl's mesh, as the browser holds it (world positions of its vertices), lies on the
    sphere of radius 1 m about (0, 0, 1) (float32 vertices: 1e-6 m), and the ball's centre,
    read back from the scene graph, stays 0.9 m from that centre."""
    name, res, page = bowl_player
    page.evaluate(f"window.mbcomp.setTime({float(res.time[-1])!r})")
    pts = np.array(page.evaluate("""(() => {
        const {player, THREE} = window.mbcomp, out = [];
        for (const o of player.byComponent["contact"]) {
          const pos = o.geometry && o.geometry.attributes.position;
          if (!pos || o.geometry.type !== "BufferGeometry" || !o.material.transparent) continue;
          o.updateWorldMatrix(true, false);
          for (let i = 0; i < pos.count; i++) {
            const v = new THREE.Vector3().fromBufferAttribute(pos, i).applyMatrix4(o.matrixWorld);
            out.push([v.x, v.y, v.z]);
          }
        }
        return out; })()"""))
    assert len(pts) > 100
    np.testing.assert_allclose(np.linalg.norm(pts - (0, 0, 1.0), axis=1), 1.0, atol=2e-6)
    assert pts[:, 2].min() < 1e-6 and pts[:, 2].max() > 0.5 - 1e-6  # from the bottom to 60 degrees up, at least
    c = np.array(page.evaluate("window.mbcomp.bodyPose('ball')")["r"])
    assert abs(np.linalg.norm(c - (0, 0, 1.0)) - 0.9) < 1e-6


def _slerp(q0, q1, a):
    q1 = q1 if q0 @ q1 >= 0 else -q1
    theta = np.arccos(np.clip(q0 @ q1, -1, 1))
    if theta < 1e-12:
        return q0
    return (np.sin((1 - a) * theta) * q0 + np.sin(a * theta) * q1) / np.sin(theta)


def test_between_outputs_linear_position_slerp_orientation(player):
    name, res, page = player
    k, a = len(res.time) // 3, 0.3
    t = (1 - a) * res.time[k] + a * res.time[k + 1]
    page.evaluate(f"window.mbcomp.setTime({float(t)!r})")
    for b in page.evaluate("window.mbcomp.bodies()"):
        (r0, q0), (r1, q1) = _column_pose(res, b, k), _column_pose(res, b, k + 1)
        a_exact = (t - res.time[k]) / (res.time[k + 1] - res.time[k])
        got = page.evaluate(f"window.mbcomp.bodyPose({b!r})")
        _assert_pose(got, r0 + a_exact * (r1 - r0), _slerp(q0, q1, a_exact), f"{name} {b} between outputs")


def test_play_advances_time_and_screenshot(player):
    name, res, page = player
    page.evaluate(f"window.mbcomp.setTime({float(res.time[0])!r})")
    page.evaluate("window.mbcomp.play()")
    page.wait_for_timeout(300)
    page.evaluate("window.mbcomp.pause()")
    t = page.evaluate("window.mbcomp.time()")
    assert res.time[0] < t <= res.time[-1], f"{name}: playing did not advance the time (t = {t})"
    folder = os.environ.get("MBCOMP_SCREENSHOTS")
    if folder:
        page.evaluate(f"window.mbcomp.setTime({CASES[name]['shot']!r})")
        os.makedirs(folder, exist_ok=True)
        page.screenshot(path=os.path.join(folder, f"{name}.png"))


def test_the_command_lines_bicycle_rides_and_leans(browser, tmp_path):
    """``mbcomp simulate models/bicycle.py --animate bike.html`` (the issue's own command, its
    SIMULATE_PARAMS push, 3 s): in the page the rear frame rides forward at about the model's
    5 m/s and leans (roll = asin of its y axis' z component, the model's ``roll`` column) by
    the CSV's roll, over 0.05 rad at the largest, then back towards upright."""
    from mbcomp.cli import main

    html, csv_path = tmp_path / "bike.html", tmp_path / "bike.csv"
    assert main(["simulate", str(MODELS / "bicycle.py"), "--t-end", "3", "-q", "--out", str(csv_path),
                 "--animate", str(html), "--trails", "rear_wheel"]) == 0
    header = csv_path.read_text().splitlines()[0].split(",")
    rows = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    t, roll = rows[:, header.index("time")], rows[:, header.index("roll")]
    page = browser.new_page(viewport={"width": 960, "height": 540})
    page.goto(html.as_uri())
    page.wait_for_function("window.mbcomp !== undefined")
    page.evaluate("window.mbcomp.ready.then(() => true)")
    seen = []
    for k in range(0, len(t), 25):
        page.evaluate(f"window.mbcomp.setTime({float(t[k])!r})")
        got = page.evaluate("window.mbcomp.bodyPose('rear_frame')")
        w, x, y, z = got["q"]
        seen.append((t[k], got["r"][0], np.arcsin(2 * (y * z + w * x))))  # R[2, 1] of the quaternion
        assert seen[-1][2] == pytest.approx(roll[k], abs=1e-9)
    speeds = np.diff([s[1] for s in seen]) / np.diff([s[0] for s in seen])
    assert np.all((speeds > 4.5) & (speeds < 5.5)), speeds
    lean = np.abs([s[2] for s in seen])
    assert lean.max() > 0.05 and lean[-1] < lean.max()
    folder = os.environ.get("MBCOMP_SCREENSHOTS")
    if folder:
        page.evaluate(f"window.mbcomp.setTime({float(seen[int(np.argmax(lean))][0])!r})")
        os.makedirs(folder, exist_ok=True)
        page.screenshot(path=os.path.join(folder, "bicycle_cli.png"))
    page.close()
