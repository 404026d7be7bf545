"""Robot files on the command line: ``mbcomp info|simulate|export robot.urdf`` with ``-p`` going
to ``load_urdf``'s keywords (:mod:`mbcomp.cli.robots`), on the UR5 of example-robot-data."""
import csv
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from mbcomp.cli import main

import robot_files


UR5 = robot_files.UR5
needs_ur5 = robot_files.needs_robots


def _moving_joints(path):
    """The names of the file's revolute/continuous/prismatic joints, in file order (read
    independently of the importer)."""
    return [j.get("name") for j in ET.parse(path).getroot().findall("joint")
            if j.get("type") in ("revolute", "continuous", "prismatic")]


def _csv(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], float)


def _coordinates_line(out):
    return next(line for line in out.splitlines() if line.startswith("coordinates ("))


@needs_ur5
def test_info_lists_the_ur5_joints_coordinates_and_what_was_not_imported(capsys):
    assert main(["info", UR5]) == 0
    out = capsys.readouterr().out
    joints = _moving_joints(UR5)
    assert len(joints) == 6 and "degrees of freedom: 6" in out
    assert _coordinates_line(out) == "coordinates (6 q, 6 speeds): " + ", ".join(f"{j}.phi" for j in joints)
    assert "tree joints (minimal coordinates): " + ", ".join(joints) in out
    transmissions = [t.get("name") for t in ET.parse(UR5).getroot().findall("transmission")]
    assert len(transmissions) == 6
    assert all(f"<transmission> '{t}': not imported" in out for t in transmissions)
    assert "model.urdf_notes" in out


@needs_ur5
def test_floating_adds_a_free_joint_of_seven_positions_and_six_speeds(capsys):
    assert main(["info", UR5]) == 0
    fixed = _coordinates_line(capsys.readouterr().out)
    assert main(["info", UR5, "-p", "floating=true"]) == 0
    floating = _coordinates_line(capsys.readouterr().out)
    assert fixed.startswith("coordinates (6 q, 6 speeds): ")
    root = ", ".join(f"root_joint.{c}" for c in ("r.x", "r.y", "r.z", "Q.w", "Q.x", "Q.y", "Q.z"))
    assert floating == f"coordinates (13 q, 12 speeds): {root}, " + fixed.split(": ", 1)[1]


@needs_ur5
def test_simulate_ur5_conserves_energy_and_gravity_rescales_time(tmp_path, capsys):
    """The UR5's joints have no damping (``<dynamics damping="0.0">``), so the falling arm keeps
    its energy; and released at rest, ``q'' = a(q, q') `` scales exactly with gravity:
    ``q_g(t) = q_{g/4}(2 t)`` -- the ``-p gravity`` reached the model."""
    dyn = [float(d.get("damping", 0)) for d in ET.parse(UR5).getroot().iter("dynamics")]
    assert dyn and not any(dyn)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    tol = ["--rtol", "1e-11", "--atol", "1e-12", "-q"]
    assert main(["simulate", UR5, "--t-end", "0.5", "--out", str(a), *tol]) == 0
    assert main(["simulate", UR5, "--t-end", "1.0", "--out", str(b), "-p", "gravity=0,0,-2.4525", *tol]) == 0
    assert "status: success" in capsys.readouterr().out
    ha, da = _csv(a)
    hb, db = _csv(b)
    E = da[:, ha.index("energy.total")]
    assert np.ptp(E) < 1e-7 * max(1.0, np.abs(E).max())
    q = [f"{j}.phi" for j in _moving_joints(UR5)]
    moved = da[-1, [ha.index(n) for n in q]] - da[0, [ha.index(n) for n in q]]
    assert np.abs(moved).max() > 0.1  # the arm did fall
    np.testing.assert_allclose(db[-1, [hb.index(n) for n in q]], da[-1, [ha.index(n) for n in q]], rtol=0, atol=1e-8)


def test_export_takes_the_gravity_given_with_p(tmp_path, capsys):
    """A URDF exports as an FMU with the loader's keyword (the one-link pendulum: the export's
    C is the same code path for any robot, and small to compile)."""
    path, fmu = tmp_path / "pendulum.urdf", tmp_path / "pendulum.fmu"
    path.write_text(PENDULUM)
    assert main(["export", str(path), "-o", str(fmu), "-p", "gravity=0,0,-1.62"]) == 0
    out = capsys.readouterr().out
    assert "states (2): hinge.phi, hinge.w" in out
    with zipfile.ZipFile(fmu) as z:
        desc = ET.fromstring(z.read("modelDescription.xml"))
    g = {v.get("name"): float(v.get("start")) for v in desc.iter() if (v.get("name") or "").startswith("world.g")}
    assert g == {"world.g[3]": -1.62}  # x and y are zeros folded into the program


@needs_ur5
@pytest.mark.parametrize("pair, words", [
    ("flaoting=true", ["load_urdf()", "no parameter flaoting", "floating (default False)",
                       "gravity (default (0.0, 0.0, -9.81))", "limits (default False)", "damping (default True)"]),
    ("floating=maybe", ["floating=maybe", "not true or false", "default False", "-p floating=true"]),
    ("gravity=down", ["gravity=down", "not a list of numbers", "-p gravity=0,0,-9.81"]),
])
def test_a_bad_p_for_a_urdf_names_the_keyword_and_the_fix(pair, words, capsys):
    assert main(["info", UR5, "-p", pair]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err


PENDULUM = """<robot name="pendulum"><link name="base"/>
<link name="arm"><inertial><mass value="2"/><origin xyz="0 0 -0.5"/>
<inertia ixx="0.08" iyy="0.07" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint></robot>"""


def test_an_xml_file_is_read_by_its_root_element(tmp_path, capsys):
    """``.xml`` with a ``<robot>`` root is a URDF; the small pendulum's period at small amplitude
    is ``2 pi sqrt((m l^2 + Iyy) / (m g l))``."""
    path = tmp_path / "pendulum.xml"
    path.write_text(PENDULUM)
    out = tmp_path / "p.csv"
    m, l, Iyy, g = 2.0, 0.5, 0.07, 9.81
    period = 2 * np.pi * np.sqrt((m * l * l + Iyy) / (m * g * l))
    assert main(["simulate", str(path), "--t-end", str(period), "--rtol", "1e-11", "--atol", "1e-12", "--out", str(out),
                 "-p", "hinge.phi0=1e-4", "-q"]) == 0
    h, d = _csv(out)
    phi = d[:, h.index("hinge.phi")]
    assert phi[0] == 1e-4 and abs(phi[-1] - 1e-4) < 1e-10 and phi.min() < -0.99e-4


def test_neither_urdf_nor_mjcf_nor_xml_is_a_clear_error(tmp_path, capsys):
    other, broken = tmp_path / "scene.xml", tmp_path / "broken.urdf"
    other.write_text("<scene/>")
    broken.write_text("<robot><link name='a'></robot>")
    assert main(["info", str(other)]) == 2
    assert "root element <scene>: neither a URDF (<robot>) nor an MJCF (<mujoco>) file" in capsys.readouterr().err
    assert main(["info", str(broken)]) == 2
    assert "broken.urdf: not XML (mismatched tag" in capsys.readouterr().err
    assert main(["info", str(tmp_path / "missing.urdf")]) == 2
    assert "the robot file does not exist" in capsys.readouterr().err


@needs_ur5
def test_study_runs_a_urdf_in_worker_processes(tmp_path, capsys):
    """``mbcomp study`` sends the robot file to its workers: the fixed-base arm falls (its elbow
    turns), the floating one falls freely as a whole -- no joint turns (the equivalence
    principle: gravity alone accelerates every link alike)."""
    out = tmp_path / "s.csv"
    assert main(["study", UR5, "--grid", "floating=false,true", "--metric", "peak=max(abs(elbow_joint.phi))",
                 "--t-end", "0.5", "--rtol", "1e-11", "--atol", "1e-12", "--executor", "processes", "--workers", "2",
                 "--out", str(out), "-q"]) == 0
    with open(out) as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    data = {r[head.index("floating")]: float(r[head.index("peak")]) for r in rows[1:]}
    assert data["False"] > 0.5 and data["True"] < 1e-9, data


@needs_ur5
def test_bench_on_workers_refuses_a_robot_file_naming_the_fix(tmp_path, capsys):
    """``mbcomp bench --executor`` sends the model file's path to its workers, which read
    Python model files only: refused before any work, with the way out."""
    assert main(["bench", UR5, "--executor", "processes", "--out", str(tmp_path / "b.csv"),
                 "--plot", str(tmp_path / "b.png")]) == 2
    err = capsys.readouterr().err
    assert "a robot file (URDF) is no Python model file" in err and "run without --executor" in err
    assert not (tmp_path / "b.csv").exists()
