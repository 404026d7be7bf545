"""A URDF's ``<visual>`` elements drawn: each primitive where its link frame puts it at a moved
joint (in the built scene's world coordinates), mesh names resolved as ROS tools do, what
cannot be drawn noted (never an error), per-axis and mirroring mesh scales, COLLADA's unit in
metres, and the UR5 of example-robot-data animated with every link's mesh in the page."""
import base64
import itertools
import json
import os
import re
import sys
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.io.urdf_visuals import resolve_mesh
from mbcomp.visual.meshes import read_mesh
from mbcomp.visual.render import frame_geometry
from mbcomp.visual.scene import build_scene, mesh_triangles
from robot_files import ROBOTS

CORNERS = np.array(list(itertools.product((0.0, 1.0), repeat=3)))  # index = 4x + 2y + z
QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]  # outward, ccw
TRIANGLES = [(q[0], q[1], q[2]) for q in QUADS] + [(q[0], q[2], q[3]) for q in QUADS]


def _rot(axis, a):
    """Rotation by ``a`` about a unit axis (Rodrigues), written here, not taken from mbcomp."""
    n = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def _rpy(r, p, y):
    return _rot((0, 0, 1), y) @ _rot((0, 1, 0), p) @ _rot((1, 0, 0), r)


def _write_stl(path, size=(1.0, 1.0, 1.0)):
    lines = ["solid cube"]
    for tri in TRIANGLES:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {x:.17g} {y:.17g} {z:.17g}" for x, y, z in CORNERS[list(tri)] * size]
        lines += ["endloop", "endfacet"]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines + ["endsolid cube"]) + "\n")


def _dae(size, unit, up="Z_UP", shift=(0, 0, 0)):
    """A COLLADA box of edges ``size`` (file units) from a node moved by ``shift``."""
    pos = " ".join(f"{x:.17g}" for x in (CORNERS * size).reshape(-1))
    idx = " ".join(str(i) for t in TRIANGLES for i in t)
    matrix = f"1 0 0 {shift[0]:g} 0 1 0 {shift[1]:g} 0 0 1 {shift[2]:g} 0 0 0 1"
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="unit" meter="{unit:g}"/><up_axis>{up}</up_axis></asset>
  <library_geometries><geometry id="box" name="box"><mesh>
    <source id="box-pos"><float_array id="box-pos-array" count="24">{pos}</float_array>
      <technique_common><accessor source="#box-pos-array" count="8" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
    <triangles count="12"><input semantic="VERTEX" source="#box-vtx" offset="0"/><p>{idx}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene"><node id="n" name="n"><matrix>{matrix}</matrix>
    <instance_geometry url="#box"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def _signed_volume(vertices, faces):
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _load(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return mbcomp.load_urdf(str(path), **kw)


# a hinge whose origin is moved and turned; the arm carries a box, a cylinder and a sphere at
# their own origins; a massless tool link (fixed joint) carries a box; the massless base one too
HINGE_XYZ, HINGE_RPY, AXIS = (0.3, -0.1, 0.2), (0.2, -0.3, 0.5), (0.0, 0.6, 0.8)
VISUALS = {"box": ((0.1, 0.2, 0.3), (0.4, 0.1, -0.7), '<box size="0.2 0.1 0.4"/>'),
           "cylinder": ((-0.2, 0.05, 0.1), (1.0, 0.0, 0.3), '<cylinder radius="0.05" length="0.3"/>'),
           "sphere": ((0.0, 0.3, 0.0), (0.0, 0.0, 0.0), '<sphere radius="0.07"/>')}
TOOL_XYZ, TOOL_RPY = (0.5, 0.0, 0.1), (0.0, 0.0, 1.2)
MOVING = {"hinge.phi0": 0.4, "hinge.w0": 1.5}  # a joint that moves
PRIMITIVES = """<robot name="r">
  <material name="red"><color rgba="1 0 0 0.5"/></material>
  <link name="base"><visual><origin xyz="0 0 -0.05"/><geometry><box size="0.3 0.3 0.1"/></geometry></visual></link>
  <link name="arm">
    <inertial><mass value="2"/><origin xyz="0.2 0 0"/><inertia ixx="0.01" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/>
    </inertial>
{visuals}
  </link>
  <link name="tool"><visual><origin xyz="0.01 0.02 0.03"/><geometry><box size="0.02 0.04 0.06"/></geometry>
    <material name="green"><color rgba="0 1 0 1"/></material></visual></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="{hxyz}" rpy="{hrpy}"/><axis xyz="{axis}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="arm"/><child link="tool"/>
    <origin xyz="{txyz}" rpy="{trpy}"/></joint>
</robot>
"""


def _words(v):
    return " ".join(f"{x:.17g}" for x in v)


@pytest.fixture(scope="module")
def primitives(tmp_path_factory):
    visuals = "\n".join(f'    <visual><origin xyz="{_words(xyz)}" rpy="{_words(rpy)}"/><geometry>{geo}</geometry>'
                        + ('<material name="red"/>' if kind == "box" else "") + "</visual>"
                        for kind, (xyz, rpy, geo) in VISUALS.items())
    path = tmp_path_factory.mktemp("urdf") / "r.urdf"
    path.write_text(PRIMITIVES.format(visuals=visuals, hxyz=_words(HINGE_XYZ), hrpy=_words(HINGE_RPY),
                                      axis=_words(AXIS), txyz=_words(TOOL_XYZ), trpy=_words(TOOL_RPY)))
    model = _load(path, gravity=(0, 0, 0))
    res = mbcomp.simulate(model, t_end=0.5, params=MOVING, backend="numeric")
    return model, res, build_scene(res)


def test_each_primitive_sits_where_its_link_frame_puts_it_at_a_moved_joint(primitives):
    model, res, scene = primitives
    phi = float(res["hinge.phi"][-1])
    assert abs(phi - 0.4 - 1.5 * 0.5) < 1e-9  # no gravity: the hinge turned at a constant rate
    R_arm = _rpy(*HINGE_RPY) @ _rot(AXIS, phi)  # the arm's link frame in the world
    r_arm = np.array(HINGE_XYZ)
    drawn = {d.name: d for d in frame_geometry(scene, float(res.time[-1]))}
    for i, (kind, (xyz, rpy, _)) in enumerate(VISUALS.items()):
        d = drawn[f"arm#{i}"]
        R, r = R_arm @ _rpy(*rpy), r_arm + R_arm @ np.array(xyz)
        assert np.allclose(d.R, R, rtol=0, atol=1e-12) and np.allclose(d.r, r, rtol=0, atol=1e-12), kind
    box = drawn["arm#0"]  # its eight corners: the box of 0.2 x 0.1 x 0.4 at its origin, in the world
    corners = np.unique(np.round(np.concatenate(box.parts).reshape(-1, 3), 12), axis=0)
    R, r = R_arm @ _rpy(*VISUALS["box"][1]), r_arm + R_arm @ np.array(VISUALS["box"][0])
    expected = (CORNERS - 0.5) * (0.2, 0.1, 0.4) @ R.T + r
    assert len(corners) == 8 and np.allclose(np.sort(corners, axis=0), np.sort(expected, axis=0), atol=1e-12)
    shapes = model["arm"].look.shape
    assert [type(s).__name__ for s in shapes] == ["Box", "Cylinder", "Sphere"]
    assert (shapes[0].color, shapes[0].opacity) == ("#ff0000", 0.5)  # the robot's material, by name
    assert (shapes[1].radius, shapes[1].length, shapes[2].radius) == (0.05, 0.3, 0.07)


def test_a_massless_links_visuals_ride_on_its_frame(primitives):
    model, res, scene = primitives
    phi = float(res["hinge.phi"][-1])
    R_tool = _rpy(*HINGE_RPY) @ _rot(AXIS, phi) @ _rpy(*TOOL_RPY)
    r_tool = np.array(HINGE_XYZ) + _rpy(*HINGE_RPY) @ _rot(AXIS, phi) @ np.array(TOOL_XYZ)
    drawn = {d.name: d for d in frame_geometry(scene, float(res.time[-1]))}
    assert np.allclose(drawn["tool#0"].r, r_tool + R_tool @ (0.01, 0.02, 0.03), rtol=0, atol=1e-12)
    assert np.allclose(drawn["tool#0"].R, R_tool, rtol=0, atol=1e-12)
    assert drawn["tool#0"].color == "#00ff00"
    assert np.allclose(drawn["base#0"].r, (0, 0, -0.05), rtol=0, atol=1e-15)  # the root: on the world frame
    # the joints' glyphs are hidden (the file draws the robot); the markers move nothing
    assert not any(d.component in ("hinge", "hinge_origin", "tool_joint") for d in drawn.values())
    assert mbcomp.assemble(model).q_names == ["hinge.phi"]


def test_visuals_false_keeps_the_default_looks_and_the_same_motion(primitives, tmp_path):
    model, res, _ = primitives
    path = tmp_path / "r.urdf"
    text = PRIMITIVES.format(visuals="", hxyz=_words(HINGE_XYZ), hrpy=_words(HINGE_RPY), axis=_words(AXIS),
                             txyz=_words(TOOL_XYZ), trpy=_words(TOOL_RPY))
    path.write_text(text)
    plain = _load(path, gravity=(0, 0, 0), visuals=False)
    assert plain["arm"].look.shape is None and "tool" not in plain.components()
    other = mbcomp.simulate(plain, t_end=0.5, params=MOVING, backend="numeric")
    assert np.array_equal(np.asarray(other["hinge.phi"]), np.asarray(res["hinge.phi"]))


MESH_ROBOT = """<robot name="m">
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
    </inertial>{visuals}</link>
  <joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint>
</robot>
"""


def _mesh_robot(path, *filenames, scale=None):
    s = f' scale="{scale}"' if scale else ""
    visuals = "".join(f'<visual><geometry><mesh filename="{f}"{s}/></geometry></visual>' for f in filenames)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(MESH_ROBOT.format(visuals=visuals))
    return path


def test_package_file_and_relative_mesh_names_are_resolved(tmp_path):
    ws = tmp_path / "ws" / "src"
    _write_stl(ws / "arm_pkg" / "meshes" / "a.stl")
    _write_stl(tmp_path / "elsewhere" / "tools_pkg" / "meshes" / "b.stl")
    urdf = ws / "arm_pkg" / "urdf" / "arm.urdf"
    here = str(urdf.parent)
    a, b = str(ws / "arm_pkg" / "meshes" / "a.stl"), str(tmp_path / "elsewhere" / "tools_pkg" / "meshes" / "b.stl")
    assert resolve_mesh("package://arm_pkg/meshes/a.stl", here) == a  # found upwards: an ancestor holds arm_pkg
    assert resolve_mesh("package:///arm_pkg/meshes/a.stl", here) == a  # a slash too many, as some files have
    assert resolve_mesh("../meshes/a.stl", here) == a and resolve_mesh(f"file://{a}", here) == a
    assert resolve_mesh("package://tools_pkg/meshes/b.stl", here) is None
    for given in (tmp_path / "elsewhere", tmp_path / "elsewhere" / "tools_pkg"):  # a holder or the package itself
        assert resolve_mesh("package://tools_pkg/meshes/b.stl", here, [str(given)]) == b
    model = _load(_mesh_robot(urdf, "package://arm_pkg/meshes/a.stl", "package://tools_pkg/meshes/b.stl"),
                  package_dirs=[str(tmp_path / "elsewhere")])
    assert [s.path for s in model["arm"].look.shape] == [a, b] and model.urdf_notes == []


def test_a_mesh_not_found_or_not_readable_is_noted_and_the_robot_still_runs(tmp_path):
    (tmp_path / "broken.stl").write_text("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n")
    with pytest.warns(UserWarning, match="not drawn"):
        model = mbcomp.load_urdf(str(_mesh_robot(tmp_path / "r.urdf", "package://nowhere/m.stl", "broken.stl")))
    missing = [n for n in model.urdf_notes if "'package://nowhere/m.stl' not found" in n]
    broken = [n for n in model.urdf_notes if "'broken.stl' cannot be read" in n and "line 4" in n]
    assert len(missing) == 1 and "link 'arm'" in missing[0] and "package_dirs" in missing[0] and len(broken) == 1
    assert model["arm"].look.shape is None  # nothing of its visuals drawable: the body's default look
    scene = build_scene(mbcomp.simulate(model, t_end=0.1, backend="numeric"))
    assert any(v.component == "arm" for v in scene.visuals)


def test_per_axis_and_mirroring_scales_of_an_stl(tmp_path):
    _write_stl(tmp_path / "cube.stl")
    model = _load(_mesh_robot(tmp_path / "r.urdf", "cube.stl", scale="0.001 0.002 -0.003"))
    (shape,) = model["arm"].look.shape
    assert shape.scale == (0.001, 0.002, -0.003)
    vertices, faces = mesh_triangles(shape)
    assert np.allclose(vertices.min(axis=0), (0, 0, -0.003), rtol=0, atol=1e-18)
    assert np.allclose(vertices.max(axis=0), (0.001, 0.002, 0), rtol=0, atol=1e-18)
    # mirrored, its faces still turn outward: the signed volume is the box's, positive
    assert abs(_signed_volume(vertices, faces) - 6e-9) < 1e-20
    unscaled = mesh_triangles(mbcomp.Mesh(str(tmp_path / "cube.stl"), scale=2.0))
    assert np.isclose(_signed_volume(*unscaled), 8.0, rtol=1e-14)


def test_a_collada_files_unit_and_node_transform_give_metres(tmp_path):
    pytest.importorskip("trimesh", reason="trimesh is not installed (pip install mbcomp[meshes])")
    pytest.importorskip("collada", reason="pycollada is not installed (pip install mbcomp[meshes])")
    (tmp_path / "mm.dae").write_text(_dae((20.0, 30.0, 40.0), 0.001, "Z_UP", shift=(100.0, 0.0, 0.0)))
    vertices, faces = read_mesh(tmp_path / "mm.dae")
    assert len(faces) == 12
    assert np.allclose(vertices.min(axis=0), (0.1, 0, 0), rtol=0, atol=1e-15)  # (node shift) x (millimetres)
    assert np.allclose(vertices.max(axis=0), (0.12, 0.03, 0.04), rtol=0, atol=1e-15)
    assert np.isclose(_signed_volume(vertices, faces), 0.02 * 0.03 * 0.04, rtol=1e-12)
    # <up_axis> is ignored, as RViz and Gazebo ignore it: a Y_UP file is drawn as its numbers say
    (tmp_path / "y.dae").write_text(_dae((20.0, 30.0, 40.0), 0.001, "Y_UP", shift=(100.0, 0.0, 0.0)))
    assert np.array_equal(read_mesh(tmp_path / "y.dae")[0], vertices)


BROKEN_EFFECT = """<library_effects><effect id="fx"><profile_COMMON>
    <newparam sid="tex-sampler"><sampler2D><source>missing-surface</source></sampler2D></newparam>
    <technique sid="common"><phong><diffuse><texture texture="tex-sampler" texcoord="UVMap"/></diffuse></phong>
    </technique></profile_COMMON></effect></library_effects>
  <library_materials><material id="mat" name="mat"><instance_effect url="#fx"/></material></library_materials>
  <library_geometries>"""


def test_a_collada_geometry_with_a_broken_material_is_still_read(tmp_path):
    """pycollada drops a geometry whose bound material names a missing texture (ANYmal's foot):
    its triangles are read without the materials, the node's transform kept."""
    trimesh = pytest.importorskip("trimesh", reason="trimesh is not installed (pip install mbcomp[meshes])")
    pytest.importorskip("collada", reason="pycollada is not installed (pip install mbcomp[meshes])")
    text = _dae((1.0, 2.0, 3.0), 0.5, shift=(4.0, 0.0, 0.0)).replace("<library_geometries>", BROKEN_EFFECT)
    text = text.replace('<triangles count="12">', '<triangles count="12" material="m">').replace(
        '<instance_geometry url="#box"/>', '<instance_geometry url="#box"><bind_material><technique_common>'
        '<instance_material symbol="m" target="#mat"/></technique_common></bind_material></instance_geometry>')
    (tmp_path / "broken_material.dae").write_text(text)
    assert not len(trimesh.load(tmp_path / "broken_material.dae", force="scene").geometry)  # trimesh alone: none
    vertices, faces = read_mesh(tmp_path / "broken_material.dae")
    assert len(faces) == 12 and np.allclose([vertices.min(axis=0), vertices.max(axis=0)],
                                            [(2.0, 0, 0), (2.5, 1.0, 1.5)], rtol=0, atol=1e-15)


def test_a_collada_meshs_own_colour_unless_the_urdf_gives_a_material(tmp_path):
    pytest.importorskip("trimesh", reason="trimesh is not installed (pip install mbcomp[meshes])")
    pytest.importorskip("collada", reason="pycollada is not installed (pip install mbcomp[meshes])")
    effect = BROKEN_EFFECT.replace('<newparam sid="tex-sampler"><sampler2D><source>missing-surface</source></sampler2D>'
                                   '</newparam>', "").replace(
        '<texture texture="tex-sampler" texcoord="UVMap"/>', "<color>0.2 0.4 0.6 1</color>")
    text = _dae((1.0, 1.0, 1.0), 1.0).replace("<library_geometries>", effect)
    text = text.replace('<triangles count="12">', '<triangles count="12" material="m">').replace(
        '<instance_geometry url="#box"/>', '<instance_geometry url="#box"><bind_material><technique_common>'
        '<instance_material symbol="m" target="#mat"/></technique_common></bind_material></instance_geometry>')
    (tmp_path / "blue.dae").write_text(text)
    model = _load(_mesh_robot(tmp_path / "r.urdf", "blue.dae"))
    assert model["arm"].look.shape[0].color == "#336699"  # 0.2, 0.4, 0.6 of 255
    (tmp_path / "r2.urdf").write_text((tmp_path / "r.urdf").read_text().replace(
        "</geometry>", '</geometry><material name="m"><color rgba="1 0 0 1"/></material>'))
    assert _load(tmp_path / "r2.urdf")["arm"].look.shape[0].color == "#ff0000"


def test_a_collada_mesh_without_its_reader_is_noted_with_the_install(tmp_path, monkeypatch):
    (tmp_path / "part.dae").write_text(_dae((1.0, 1.0, 1.0), 1.0))
    monkeypatch.setitem(sys.modules, "collada", None)  # as if pycollada were not installed
    model = _load(_mesh_robot(tmp_path / "r.urdf", "part.dae"))
    assert any("pip install mbcomp[meshes]" in n and "'arm'" in n for n in model.urdf_notes), model.urdf_notes
    assert model["arm"].look.shape is None


UR5_LINKS = ["base_link", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link",
             "wrist_3_link"]


@pytest.mark.skipif(ROBOTS is None, reason="example-robot-data is not installed (pip install mbcomp[robots])")
def test_the_ur5_animates_with_every_links_collada_mesh_in_metres(tmp_path):
    trimesh = pytest.importorskip("trimesh", reason="trimesh is not installed (pip install mbcomp[meshes])")
    pytest.importorskip("collada", reason="pycollada is not installed (pip install mbcomp[meshes])")
    urdf = os.path.join(ROBOTS, "ur_description", "urdf", "ur5_robot.urdf")
    model = _load(urdf)
    assert not [n for n in model.urdf_notes if "mesh" in n]
    base = model["base_link"].look.shape[0]
    direct = trimesh.load(base.path, force="mesh", process=False)  # the file's unit is the metre
    assert np.allclose([read_mesh(base.path)[0].min(axis=0), read_mesh(base.path)[0].max(axis=0)], direct.bounds,
                       rtol=0, atol=1e-12)
    assert np.allclose(direct.extents, (0.1467, 0.1833, 0.024), atol=5e-4)  # the UR5's foot: 15 cm wide, 2.4 cm high
    res = mbcomp.simulate(model, t_end=0.05, backend="numeric")
    page = res.animate(str(tmp_path / "ur5.html"))
    text = open(page, encoding="utf-8").read()
    data = json.loads(re.search(r'<script type="application/json" id="mbcomp-scene">(.*?)</script>', text, re.S)[1])
    meshes = {v["component"]: v["shape"] for v in data["visuals"] if v["shape"]["type"] == "mesh"}
    assert sorted(meshes) == sorted(UR5_LINKS)
    for link, geo in meshes.items():
        vertices, faces = read_mesh(model[link].look.shape[0].path)
        assert len(base64.b64decode(geo["faces"])) == 12 * len(faces), link  # every triangle, uint32 x 3
        assert np.array_equal(np.frombuffer(base64.b64decode(geo["vertices"]), "<f4").reshape(-1, 3),
                              vertices.astype("<f4")), link
