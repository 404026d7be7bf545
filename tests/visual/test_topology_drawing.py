"""The topology drawing shows what ``mbcomp info`` counts: the spanning tree, the cut joints
with the rows they keep and the redundant rows dropped, nonholonomic rows, the coordinates.

Each check compares the drawing (its description, its SVG, its layout) against the
assembled system and its summary, which are computed independently of the drawing.
"""
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.summary import observer, summary
from mbcomp.cli.main import main
from mbcomp.visual.topology_drawing import draw_topology, topology_graph
from mbcomp.visual.topology_layout import NODE_BOX, Y_STEP, layout, routes

from conftest import ROOT, load_model

ANDREWS_CUTS = {"pin_E_triangle", "pin_E_EG", "pin_E_HE"}
SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def andrews():
    system = mbcomp.assemble(load_model("models/andrews.py").build())
    return system, topology_graph(system)


@pytest.fixture(scope="module")
def andrews_svg(tmp_path_factory, andrews):
    path = tmp_path_factory.mktemp("topo") / "andrews.svg"
    draw_topology(andrews[0], path, title="andrews")
    return ET.parse(path).getroot()


def _summary_line(text, head):
    return next(line for line in text.splitlines() if line.startswith(head))[len(head):]


def _texts(root):
    return [t.text or "" for t in root.iter(SVG + "text")]


def _group(root, gid):
    return next(g for g in root.iter(SVG + "g") if g.get("id") == gid)


def _dashed(group):
    return any("stroke-dasharray" in (p.get("style") or "") for p in group.iter(SVG + "path"))


def test_andrews_three_loops_are_its_three_cut_joints(andrews):
    system, d = andrews
    cut = [e for e in d["edges"] if e["kind"] == "cut"]
    assert {e["name"] for e in cut} == ANDREWS_CUTS == set(system.topology.cut)
    # every pin keeps the planar rows and drops the out-of-plane ones; the kept rows are the rank
    for e in cut:
        assert e["kept"] == ["x", "y"] and e["dropped"] == ["z", "tilt_1", "tilt_2"]
        assert sorted(e["kept"] + e["dropped"]) == sorted(e["rows"])
    assert sum(len(e["kept"]) for e in cut) == d["rank"] == 6
    # all three loops close at point E, on the rod: one group is the end of every cut joint
    rod = next(n["id"] for n in d["nodes"] if n["bodies"] == ["rod"])
    assert all(rod in (e["a"], e["b"]) for e in cut)


def test_tree_edges_are_the_topologys_tree_joints_with_their_coordinates(andrews):
    system, d = andrews
    topo = system.topology
    tree_joints = [e.name for e in topo.tree if e.kind == "joint" and e.dof > 0]
    tree = [e for e in d["edges"] if e["kind"] == "tree"]
    assert sorted(e["name"] for e in tree) == sorted(tree_joints) and len(tree) == 7
    named = [f"{e['name']}.{c}" for e in tree for c in e["coordinates"]]
    assert sorted(named) == sorted(system.q_names) == sorted(d["coordinates"])
    # the tree joins the 7 body groups and the world: 8 nodes, a tree has one edge fewer
    assert len(d["nodes"]) == len(tree) + 1
    assert [n["kind"] for n in d["nodes"]].count("body") == 7


def test_dropped_rows_are_those_mbcomp_info_prints(andrews):
    system, d = andrews
    printed = _summary_line(summary(system), "redundant constraint rows dropped: ").split(", ")
    assert len(printed) == 9 and sorted(d["dropped"]) == sorted(printed)
    per_edge = [f"{e['name']}.{r}" for e in d["edges"] for r in e["dropped"]]
    assert sorted(per_edge) == sorted(printed)
    assert system.row_mask is None  # described, not initialized


def test_bicycle_contacts_carry_its_nonholonomic_rows(tmp_path):
    system = mbcomp.assemble(load_model("models/bicycle.py").build())
    d = topology_graph(system)
    init = initialize(observer(system))
    printed = int(_summary_line(summary(system), "nonholonomic constraints (velocity level): ").split(";")[0])
    contacts = [e for e in d["edges"] if e["nonholonomic"]]
    assert {e["name"] for e in contacts} == {"rear_contact", "front_contact"}
    assert all(e["kind"] == "cut" for e in contacts)
    assert len(d["nonholonomic"]) == sum(len(e["nonholonomic"]) for e in contacts) == init.nonholonomic == printed == 4
    assert d["dof"] == 7 and d["dropped"] == []
    path = draw_topology(system, tmp_path / "bicycle.svg")
    root = ET.parse(path).getroot()
    for name in ("rear_contact", "front_contact"):
        assert _dashed(_group(root, f"cut-{name}"))
        label = " ".join(_texts(_group(root, f"label-cut-{name}")))
        assert "nonholonomic" in label and "longitudinal" in label


def test_svg_names_every_joint_and_dashes_exactly_the_cut_joints(andrews, andrews_svg):
    system, d = andrews
    text = " ".join(_texts(andrews_svg))
    for e in system.topology.edges:
        if e.kind == "joint":
            assert re.search(rf"\b{re.escape(e.name)}\b", text), e.name
    dashed = [g.get("id") for g in andrews_svg.iter(SVG + "g")
              if (g.get("id") or "").startswith(("cut-", "tree-")) and _dashed(g)]
    assert sorted(dashed) == sorted(f"cut-{n}" for n in ANDREWS_CUTS)
    assert len([g for g in andrews_svg.iter(SVG + "g") if (g.get("id") or "").startswith("tree-")]) == 7
    assert "1 degree of freedom" in text and "= -8" in text  # the title: DOF and Gruebler's count


def test_layout_layers_the_tree_and_routes_loops_around_other_links(andrews):
    _, d = andrews
    pos = layout(d)
    for e in d["edges"]:
        if e["kind"] == "tree":  # a child one layer below its parent
            assert pos[e["b"]][1] == pytest.approx(pos[e["a"]][1] - Y_STEP)
    xy = np.array(list(pos.values()))
    gaps = np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1))[np.triu_indices(len(xy), 1)]
    assert gaps.min() > 2 * NODE_BOX[0]  # no two links drawn on each other
    for e in d["edges"]:
        if e["kind"] != "cut":
            continue
        points = routes(d, pos)[e["name"]]["points"]
        for n, p in pos.items():
            if n not in (e["a"], e["b"]):  # a dashed loop passes no other link's box
                inside = (np.abs(points - p) < NODE_BOX).all(axis=1)
                assert not inside.any(), (e["name"], n)


def test_model_and_its_system_draw_the_same_picture(tmp_path):
    model = load_model("models/slider_crank.py").build()
    a = model.draw(tmp_path / "a.svg")
    b = draw_topology(mbcomp.assemble(model), tmp_path / "b.svg")
    assert a.read_text() == b.read_text()
    assert draw_topology(model, tmp_path / "c.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_driven_joint_is_a_tree_joint_without_coordinate():
    from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Revolute, World

    m = mbcomp.Model()
    w, j = m.add("world", World()), m.add("hinge", Revolute())
    rod, bob = m.add("rod", FixedTranslation(r=(0, -1.0, 0))), m.add("bob", PointMass(m=1.0))
    j2, bob2 = m.add("elbow", Revolute()), m.add("bob2", PointMass(m=1.0))
    rod2 = m.add("rod2", FixedTranslation(r=(0, -1.0, 0)))
    drive = m.add("motor", PrescribedMotion(s="0.5*t"))
    m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    m.connect(rod.frame_b, j2.frame_a); m.connect(j2.frame_b, rod2.frame_a); m.connect(rod2.frame_b, bob2.frame_a)
    m.connect(drive.flange_b, j.axis)
    d = topology_graph(mbcomp.assemble(m))
    hinge, elbow = (next(e for e in d["edges"] if e["name"] == n) for n in ("hinge", "elbow"))
    assert hinge["kind"] == elbow["kind"] == "tree"
    assert hinge["drive"] == "motor" and hinge["coordinates"] == [] and elbow["coordinates"] == ["phi"]
    assert d["coordinates"] == ["elbow.phi"] and d["dof"] == 1


def test_cli_info_graph_writes_the_drawing(tmp_path, capsys):
    out = tmp_path / "andrews.svg"
    assert main(["info", str(ROOT / "models/andrews.py"), "--graph", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "redundant constraint rows dropped" in printed and f"topology drawn to {out}" in printed
    root = ET.parse(out).getroot()
    assert {g.get("id") for g in root.iter(SVG + "g")} >= {f"cut-{n}" for n in ANDREWS_CUTS}


@pytest.mark.parametrize("name", ["topo.txt", "topo"])
def test_bad_suffix_is_a_clear_error_before_any_work(tmp_path, capsys, name):
    out = tmp_path / name
    assert main(["info", str(ROOT / "models/andrews.py"), "--graph", str(out)]) == 2
    captured = capsys.readouterr()
    assert all(s in captured.err for s in (".svg", ".png", ".pdf", str(out)))
    assert "model summary" not in captured.out and not out.exists()
    with pytest.raises(ValueError, match=r"\.svg, \.png, \.pdf"):
        draw_topology(load_model("models/slider_crank.py").build(), out)


# --------------------------------------------------------------------------- gears

def _geared_pair(ratio=3.0):
    """Two shafts on Revolutes from one base, tied by an IdealGear ``w1 = ratio w2``."""
    from mbcomp.library import Fixed, IdealGear, Revolute, RigidBody

    m = mbcomp.Model()
    base = m.add("base", Fixed())
    for name in ("j1", "j2"):
        j = m.add(name, Revolute())
        b = m.add(f"{name}_body", RigidBody(m=1.0, I=np.eye(3)))
        m.connect(base.frame_b, j.frame_a)
        m.connect(j.frame_b, b.frame_a)
    g = m.add("gear", IdealGear(ratio=ratio))
    m.connect(g.flange_a, m["j1"].axis)
    m.connect(g.flange_b, m["j2"].axis)
    return m


def _planetary():
    from mbcomp.library import Fixed, PlanetaryGear, Torque

    m = mbcomp.Model()
    base = m.add("base", Fixed())
    pg = m.add("pg", PlanetaryGear(z_sun=20, z_ring=80))
    m.connect(base.frame_b, pg.frame_a)
    tq = m.add("T_sun", Torque(tau=1.0))
    m.connect(tq.flange_b, pg.sun)
    return m


@pytest.mark.parametrize("build, gear, joints", [
    (_geared_pair, "gear", {"j1", "j2"}),
    (_planetary, "pg.mesh", {"pg.sun", "pg.carrier", "pg.ring"}),
])
def test_gear_rows_are_dotted_paths_between_the_joints_they_tie(tmp_path, build, gear, joints):
    """Each gear row is drawn as a dotted path from one geared joint's line to the next, the
    gear is named with its type and ratio, and the title counts its rows as info does."""
    system = mbcomp.assemble(build())
    d = topology_graph(system)
    rows = [n for n in system.constraint_names() if n.rsplit(".", 1)[0] == gear]
    (g,) = d["gears"]
    assert g["name"] == gear and [f"{gear}.{r['name']}" for r in g["rows"]] == rows
    assert set(g["rows"][0]["joints"]) == joints  # the joints whose axis flanges the gear's flanges are on
    path = tmp_path / "gears.svg"
    draw_topology(system, path)
    root = ET.parse(path).getroot()
    text = " ".join(_texts(root))
    ratio = "3" if gear == "gear" else "-4"  # Willis: ratio = -z_ring / z_sun
    assert f"{gear}: IdealGear ratio {ratio} (1 row)" in text
    for r in g["rows"]:
        assert _dashed(_group(root, f"gear-{gear}-{r['name']}"))
    n_rows = len(system.constraint_names(all_rows=True))
    assert f"1 gear, {n_rows} constraint row" in text
    assert f"{d['dof']} degree" in text and d["dof"] == len(joints) - 1


def test_gear_paths_run_from_joint_line_to_joint_line():
    d = topology_graph(mbcomp.assemble(_planetary()))
    pos = layout(d)
    from mbcomp.visual.topology_layout import gear_routes

    (route,) = gear_routes(d, pos, routes(d, pos)).values()
    pts = route["points"]
    edges = {e["name"]: e for e in d["edges"]}

    def on_line(p, e):
        a, b = np.asarray(pos[e["a"]]), np.asarray(pos[e["b"]])
        t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
        return np.linalg.norm(a + t * (b - a) - p) < 1e-9

    ends = [pts[0], pts[24], pts[-1]]  # two arcs: three anchors, one on each geared joint's line
    for name in ("pg.sun", "pg.carrier", "pg.ring"):
        assert sum(on_line(p, edges[name]) for p in ends) == 1, name
    assert route["label"][1] < min(p[1] for p in ends)  # bowed below the anchors (away from the world)
