"""Meshes from files: a unit cube written as ASCII STL, binary STL and OBJ reads to the same
solid (8 vertices, 12 triangles, area 6, volume 1), malformed files name their line, and a
body's Mesh shape reaches the scene's JSON scaled."""
import base64
import itertools
import struct

import numpy as np
import pytest

import mbcomp
from mbcomp.visual.meshes import read_mesh

CORNERS = np.array(list(itertools.product((0.0, 1.0), repeat=3)))  # index = 4x + 2y + z
QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]  # outward, ccw


def _triangles():
    return [CORNERS[[a, b, c]] for q in QUADS for a, b, c in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]


def write_ascii_stl(path):
    lines = ["solid cube"]
    for tri in _triangles():
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        lines += [f"  facet normal {n[0]:g} {n[1]:g} {n[2]:g}", "    outer loop"]
        lines += [f"      vertex {x:e} {y:e} {z:e}" for x, y, z in tri]
        lines += ["    endloop", "  endfacet"]
    path.write_text("\n".join(lines + ["endsolid cube"]) + "\n")


def write_binary_stl(path):
    tris = _triangles()
    out = bytearray(b"solid but binary".ljust(80, b" ")) + struct.pack("<I", len(tris))
    for tri in tris:
        out += struct.pack("<12fH", 0, 0, 0, *tri.reshape(-1), 0)
    path.write_bytes(bytes(out))


def write_obj(path):
    # vertices in another order, quads with v/vt/vn corners and negative indices on one face
    lines = ["# a cube", "o cube"] + [f"v {x} {y} {z}" for x, y, z in CORNERS] + ["vt 0 0", "vn 0 0 1"]
    for q in QUADS[:-1]:
        lines.append("f " + " ".join(f"{i + 1}/1/1" for i in q))
    lines.append("f " + " ".join(f"{i - 8}//1" for i in QUADS[-1]))
    path.write_text("\n".join(lines) + "\n")


def area_and_volume(vertices, faces):
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    return 0.5 * np.linalg.norm(cross, axis=1).sum(), np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


@pytest.mark.parametrize("writer,name", [(write_ascii_stl, "cube.stl"), (write_binary_stl, "cube.STL"),
                                         (write_obj, "cube.obj")])
def test_a_unit_cube_reads_to_the_same_solid_from_every_format(tmp_path, writer, name):
    path = tmp_path / name
    writer(path)
    vertices, faces = read_mesh(path)
    assert vertices.dtype == np.float64 and vertices.shape[1] == 3
    assert faces.shape == (12, 3) and np.issubdtype(faces.dtype, np.integer)
    used = np.unique(vertices[np.unique(faces)], axis=0)
    assert np.array_equal(used, np.unique(CORNERS, axis=0))
    area, volume = area_and_volume(vertices, faces)
    assert area == pytest.approx(6.0, abs=1e-12)
    assert volume == pytest.approx(1.0, abs=1e-12)  # outward, counter-clockwise triangles kept


def test_a_missing_file_names_its_path_and_component(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"arm: mesh file .*nothing\.stl.* not found"):
        read_mesh(tmp_path / "nothing.stl", component="arm")


@pytest.mark.parametrize("name,text,line", [
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n", 3),
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", 5),
    ("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", 3),
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", 4),
    ("bad.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nvertex 0 1 0\nendloop\n", 5),
    ("bad.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n", 6),
    ("bad.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertx 0 0 0\n", 4),
])
def test_a_malformed_file_names_the_line(tmp_path, name, text, line):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError, match=rf"bad\.(obj|stl).*, line {line}:"):
        read_mesh(path)


@pytest.mark.parametrize("name,text", [("empty.stl", ""), ("empty.obj", "# nothing\n"),
                                       ("points.obj", "v 0 0 0\n"), ("none.stl", "solid s\nendsolid s\n")])
def test_an_empty_file_is_an_error_naming_it(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError, match=rf"{name.split('.')[0]}\.(stl|obj).* (is empty|has no triangles)"):
        read_mesh(path)


def test_a_body_with_a_mesh_shape_puts_the_scaled_vertices_in_the_scene(tmp_path):
    from mbcomp.library import Revolute, RigidBody, World
    from mbcomp.visual.scene import build_scene

    path = tmp_path / "cube.obj"
    write_obj(path)
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(n=(0, 0, 1), w0=1.0))
    b = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=np.eye(3) * 0.01, shape=mbcomp.Mesh(path, scale=0.1)))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    scene = build_scene(mbcomp.simulate(m, t_end=0.1))
    (shape,) = [v["shape"] for v in scene.to_json()["visuals"] if v["component"] == "arm"]
    assert shape["type"] == "mesh"
    vertices = np.frombuffer(base64.b64decode(shape["vertices"]), dtype="<f4").reshape(-1, 3)
    faces = np.frombuffer(base64.b64decode(shape["faces"]), dtype="<u4").reshape(-1, 3)
    assert np.allclose(vertices, 0.1 * CORNERS, atol=1e-7)
    assert faces.shape == (12, 3)
    area, volume = area_and_volume(vertices.astype(float), faces.astype(int))
    assert area == pytest.approx(0.06, rel=1e-6) and volume == pytest.approx(1e-3, rel=1e-6)
