"""What drawing an imported robot as it looks costs: example-robot-data's UR5 (COLLADA meshes)
and Talos (STL meshes), each loaded with and without its visuals, its scene built, its HTML page
written and one picture drawn.

Prints one row per robot: load time with visuals (s) and its ratio to ``visuals=False`` in the
same run (the meshes are read at load: the scene then reuses them), the meshes and their
triangles, the scene's build time, the page's size (MB) and time, and one picture's time with
the meshes coarsened for it (``render.MESH_CELLS``/``MESH_FACES``) against the full meshes.
Medians of ``--repeat`` runs (the mesh cache is cleared before each load).

    PYTHONPATH=src python bench/robot_visuals.py [--repeat 3]

Needs example-robot-data and, for the UR5's COLLADA files, trimesh + pycollada
(``pip install mbcomp[robots,meshes]``).
"""
import argparse
import os
import statistics
import tempfile
import time
import warnings

import mbcomp
from mbcomp.visual import meshes, render
from mbcomp.visual.html import write_html
from mbcomp.visual.scene import build_scene, mesh_triangles

ROBOTS = [("UR5", "ur_description/urdf/ur5_robot.urdf", False), ("Talos", "talos_data/robots/talos_full_v2.urdf", True)]


def robots_dir():
    from importlib.metadata import files

    found = [f for f in (files("example-robot-data") or []) if str(f).endswith("ur5_robot.urdf")]
    return str(found[0].locate()).split("/ur_description/")[0]


def timed(f):
    t = time.perf_counter()
    out = f()
    return time.perf_counter() - t, out


def fresh_load(path, floating, visuals):
    meshes.clear_cache()  # a cold mesh cache each time
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return timed(lambda: mbcomp.load_urdf(path, floating=floating, visuals=visuals))


def picture(scene, path, cells, faces):
    old = render.MESH_CELLS, render.MESH_FACES
    render.MESH_CELLS, render.MESH_FACES = cells, faces
    try:
        return timed(lambda: render.write_picture(scene, path))[0]
    finally:
        render.MESH_CELLS, render.MESH_FACES = old


def row(name, path, floating, repeat, tmp):
    with_v = statistics.median(fresh_load(path, floating, True)[0] for _ in range(repeat))
    without = statistics.median(fresh_load(path, floating, False)[0] for _ in range(repeat))
    model = fresh_load(path, floating, True)[1]
    res = mbcomp.simulate(model, t_end=0.05, backend="numeric")
    t_scene = statistics.median(timed(lambda: build_scene(res))[0] for _ in range(repeat))
    scene = build_scene(res)
    files = [v.shape for v in scene.visuals if isinstance(v.shape, mbcomp.Mesh)]
    tris = sum(len(mesh_triangles(s)[1]) for s in files)
    page = os.path.join(tmp, f"{name}.html")
    t_page = statistics.median(timed(lambda: write_html(scene, page))[0] for _ in range(repeat))
    png = os.path.join(tmp, f"{name}.png")
    coarse = statistics.median(picture(scene, png, render.MESH_CELLS, render.MESH_FACES) for _ in range(repeat))
    full = picture(scene, png, 10**12, 10**12)  # cells far below any triangle: every triangle drawn
    print(f"{name:6s} {with_v:8.2f} {with_v / without:7.1f} {len(files):6d} {tris:9d} {t_scene:8.3f} "
          f"{os.path.getsize(page) / 1e6:8.2f} {t_page:7.2f} {coarse:8.2f} {full:8.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    root = robots_dir()
    print(f"{'robot':6s} {'load s':>8s} {'/plain':>7s} {'meshes':>6s} {'triangles':>9s} {'scene s':>8s} "
          f"{'page MB':>8s} {'page s':>7s} {'png s':>8s} {'full s':>8s}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, rel, floating in ROBOTS:
            row(name, os.path.join(root, rel), floating, args.repeat, tmp)


if __name__ == "__main__":
    main()
