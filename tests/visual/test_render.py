"""Pictures and films of a run drawn by matplotlib: the geometry drawn at a time is where the
result puts the bodies (at outputs exactly, between outputs interpolated), pictures at two
times differ, films have the frames their rule says, and the errors name what is wrong."""
import math
import pathlib

import numpy as np
import pytest

import mbcomp
from mbcomp.visual.render import _upright, film_times, frame_geometry
from mbcomp.visual.scene import build_scene

CRANK, ROD = 0.2, 0.6


@pytest.fixture(scope="module")
def crank():
    model = mbcomp.load_model_file("models/slider_crank.py").build()
    return mbcomp.simulate(model, t_end=2.0)


@pytest.fixture(scope="module")
def crank_scene(crank):
    return build_scene(crank, color_by={"rod": "rod_joint.phi"})


def drawn(scene, t, component):
    (d,) = [d for d in frame_geometry(scene, t) if d.component == component]
    return d


def test_the_geometry_at_an_output_is_where_the_result_puts_the_mechanism(crank, crank_scene):
    for k in (0, 137, len(crank.time) - 1):
        t, phi = float(crank.time[k]), float(crank["crank_joint.phi"][k])
        tip = CRANK * np.array([math.cos(phi), math.sin(phi), 0.0])
        assert np.allclose(drawn(crank_scene, t, "rod_joint").r, tip, atol=1e-12)  # the hinge on the crank's tip
        body = np.array([crank[f"crank.r.{a}"][k] for a in "xyz"])
        assert np.allclose(drawn(crank_scene, t, "crank").r, body + tip / 2, atol=1e-12)  # rod centred on the crank
        s = float(crank["slider_joint.s"][k])
        assert np.allclose(drawn(crank_scene, t, "slider").r, [s, 0, 0], atol=1e-12)
        assert np.allclose(drawn(crank_scene, t, "pin").r, [s, 0, 0], atol=1e-6)  # the loop closes in the picture
        # every corner of the crank's cylinder lies within its radius of the segment origin..tip
        pts = np.vstack([p.reshape(-1, 3) for p in drawn(crank_scene, t, "crank").parts])
        along = np.clip(pts @ tip / (tip @ tip), 0, 1)
        radius = crank_scene.visuals[[v.component for v in crank_scene.visuals].index("crank")].shape.radius
        assert np.max(np.linalg.norm(pts - np.outer(along, tip), axis=1)) <= radius * (1 + 1e-9)


def test_between_outputs_positions_are_interpolated_linearly_and_angles_by_slerp(crank, crank_scene):
    k, s = 211, 0.3
    t = (1 - s) * crank.time[k] + s * crank.time[k + 1]
    x = (1 - s) * crank["slider.r.x"][k] + s * crank["slider.r.x"][k + 1]
    assert drawn(crank_scene, t, "slider").r[0] == pytest.approx(x, abs=1e-12)
    R = drawn(crank_scene, t, "crank_joint").R  # on the world, then the crank's own rotation about z:
    assert np.allclose(R, drawn(crank_scene, crank.time[k], "crank_joint").R)
    R0 = drawn(crank_scene, crank.time[k], "crank").R.T
    step = (drawn(crank_scene, crank.time[k + 1], "crank").R @ R0, drawn(crank_scene, t, "crank").R @ R0)
    whole, turned = (math.atan2(Rc[1, 0], Rc[0, 0]) for Rc in step)
    assert whole == pytest.approx(crank["crank_joint.phi"][k + 1] - crank["crank_joint.phi"][k], rel=1e-5)
    assert turned == pytest.approx(s * whole, abs=1e-13)  # slerp: the angle about the fixed axis is linear
    assert np.allclose(step[1][:, 2], [0, 0, 1], atol=1e-12)  # and about that axis
    assert drawn(crank_scene, t, "rod").value == pytest.approx(
        (1 - s) * crank["rod_joint.phi"][k] + s * crank["rod_joint.phi"][k + 1], abs=1e-12)


def test_a_spring_is_drawn_between_its_two_frames():
    from mbcomp.library import FixedTranslation, Revolute, RigidBody, Spring, World

    m = mbcomp.Model()
    w = m.add("world", World())
    anchor = m.add("anchor", FixedTranslation(r=(0, 1, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.2))
    arm = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=np.diag([1e-4, 0.08, 0.08])))
    tip = m.add("tip", FixedTranslation(r=(1, 0, 0)))
    spring = m.add("spring", Spring(c=50.0, s_unstretched=0.8))
    for a, b in ((w.frame_b, anchor.frame_a), (w.frame_b, j.frame_a), (j.frame_b, arm.frame_a),
                 (j.frame_b, tip.frame_a), (anchor.frame_b, spring.frame_a), (tip.frame_b, spring.frame_b)):
        m.connect(a, b)
    res = mbcomp.simulate(m, t_end=1.0)
    scene = build_scene(res)
    k = len(res.time) // 2
    d = drawn(scene, float(res.time[k]), "spring")
    phi = float(res["j.phi"][k])
    assert np.allclose(d.ends[0], [0, 1, 0], atol=1e-12)
    assert np.allclose(d.ends[1], [math.cos(phi), math.sin(phi), 0], atol=1e-9)
    assert np.linalg.norm(d.ends[1] - d.ends[0]) == pytest.approx(res["spring.length"][k], rel=1e-9)
    coil = d.parts[0]
    assert np.allclose(coil[0] - d.ends[0], coil[-1] - d.ends[1], atol=1e-12)  # whole turns, end to end


def test_up_is_drawn_vertical():
    rng = np.random.default_rng(1)
    for up in [(0, 1, 0), (0, 0, 1), (0, -1, 0), (1, 0, 0), *rng.normal(size=(5, 3))]:
        U = _upright(up)
        assert np.allclose(U @ U.T, np.eye(3)) and np.linalg.det(U) == pytest.approx(1.0)
        assert np.allclose(U @ up / np.linalg.norm(up), [0, 0, 1])


def test_snapshots_at_two_times_differ_and_show_the_mechanism(crank, tmp_path):
    from matplotlib.image import imread

    a, b = tmp_path / "t05.png", tmp_path / "t1.png"
    crank.snapshot(a, t=0.5)
    crank.snapshot(b, t=1.0)
    A, B = imread(a)[..., :3], imread(b)[..., :3]
    assert A.shape == B.shape == (480, 640, 3)
    for img in (A, B):
        coloured = np.ptp(img, axis=2) > 0.2  # the bodies' colours, not the greys of axes and grid
        assert coloured.mean() > 0.003
    assert np.mean(np.any(np.abs(A - B) > 0.1, axis=2)) > 0.002


def test_a_time_outside_the_run_is_an_error_naming_the_range(crank, tmp_path):
    for t in (2.5, -0.1, float("nan")):
        with pytest.raises(ValueError, match=r"outside the run.*t0=0 s to t_end=2 s"):
            crank.snapshot(tmp_path / "x.png", t=t)
    assert not (tmp_path / "x.png").exists()


def test_a_gif_has_one_frame_per_film_time(crank, tmp_path):
    from PIL import Image

    fps, speed = 7, 1.5
    times = film_times(build_scene(crank), fps, speed)
    n = math.ceil(2.0 * fps / speed) + 1  # t0 + k speed/fps before t_end, and t_end
    assert len(times) == n == 11 and times[-1] == 2.0
    assert np.allclose(np.diff(times[:-1]), speed / fps)
    path = crank.animate(tmp_path / "crank.gif", fps=fps, speed=speed)
    with Image.open(path) as img:
        assert img.n_frames == n
        assert img.info["duration"] == pytest.approx(1000 / fps, abs=10)  # GIF delays are in 1/100 s


def test_an_mp4_without_ffmpeg_says_which_writer_is_missing(crank, tmp_path, monkeypatch):
    from matplotlib import animation

    monkeypatch.setattr(animation.writers, "is_available", lambda name: False)
    with pytest.raises(ValueError, match=r"cannot write .*crank\.mp4: matplotlib's 'ffmpeg' writer is not available "
                                         r"\(ffmpeg is not installed\) -> install ffmpeg .* or write a \.gif"):
        crank.animate(tmp_path / "crank.mp4")


def test_an_mp4_with_ffmpeg_is_written(crank, tmp_path):
    from matplotlib import animation

    if not animation.writers.is_available("ffmpeg"):
        pytest.skip("ffmpeg is not installed")
    path = crank.animate(tmp_path / "crank.mp4", fps=10, speed=2.0)
    data = open(path, "rb").read()
    assert data[4:8] == b"ftyp" and len(data) > 5000
    import shutil
    import subprocess

    if shutil.which("ffprobe"):  # the film has the frames of its rule: one per 1/fps of film time, and t_end
        out = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                              "stream=nb_read_frames", "-of", "csv=p=0", path], capture_output=True, text=True, check=True)
        assert int(out.stdout.strip()) == len(film_times(build_scene(crank), fps=10, speed=2.0))


def test_a_travelling_mechanism_is_followed_not_shrunk(tmp_path):
    """The bicycle rides 10 m in 2 s, eight times its size: each picture frames the bicycle
    where it is (its coloured parts fill a good part of the picture at both times) instead of
    the whole road, where it would be a speck."""
    from matplotlib.image import imread

    mod = mbcomp.load_model_file(str(pathlib.Path(__file__).resolve().parents[2] / "models" / "bicycle.py"))
    res = mbcomp.simulate(mod.build(**mod.SIMULATE_PARAMS), t_end=2.0)
    for t in (0.2, 1.8):
        img = imread(res.snapshot(tmp_path / f"bike{t}.png", t=t))[..., :3]
        dark_or_coloured = (np.ptp(img, axis=2) > 0.2) | (img.max(axis=2) < 0.3)  # frame, rider, tyres
        assert dark_or_coloured.mean() > 0.04, f"t={t}: {dark_or_coloured.mean():.4f}"
