"""URDF import checked against Pinocchio: the mass matrix and the bias forces of real robots.

mbcomp's equations are ``M du/dt = f``; Pinocchio's are ``M a + b = tau`` with
``b = rnea(q, v, 0)`` (+ the joints' viscous damping ``D v``, which Pinocchio's model reads
from ``<dynamics damping>`` too), so ``f = -b`` where both use the same speeds. Revolute and
prismatic speeds are the same in both; a continuous joint's Pinocchio position is
``(cos, sin)`` of mbcomp's angle; a free flyer's Pinocchio velocity is the base's linear and
angular velocity in base axes, mbcomp's ``FreeMotion`` takes ``dr/dt`` in world axes and the
angular velocity in base axes: ``u = T v`` with ``T = diag(R, 1, ...)``, hence
``M_pin = T^T M T`` and ``b_pin = -T^T (f - M dT/dt v)``.
"""
import functools
import os
import re
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.io.urdf import load_urdf, rpy_matrix

pin = pytest.importorskip("pinocchio", reason="Pinocchio is not installed (the reference engine of these checks)")


from robot_files import ROBOTS, needs_robots  # noqa: E402

FIXED = ["ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf",
         "ur_description/urdf/ur3_robot.urdf", "ur_description/urdf/ur10_robot.urdf",
         "kinova_description/robots/kinova.urdf", "xarm_description/urdf/xarm7.urdf",
         "z1_description/urdf/z1.urdf", "so_arm_description/urdf/so100.urdf",
         "finger_edu_description/robots/finger_edu.urdf",
         "double_pendulum_description/urdf/double_pendulum_continuous.urdf",
         "talos_data/robots/talos_left_arm.urdf", "baxter_description/urdf/baxter.urdf",
         "ur_description/urdf/ur5_gripper.urdf", "so_arm_description/urdf/so101.urdf",
         "asr_twodof_description/urdf/TwoDofs.urdf", "tiago_pro_description/robots/tiago_pro.urdf",
         "alex_description/urdf/alex_nub_hands.urdf"]
FLOATING = ["a1_description/urdf/a1.urdf", "go2_description/urdf/go2.urdf", "solo_description/robots/solo12.urdf",
            "bolt_description/robots/bolt.urdf", "talos_data/robots/talos_reduced.urdf",
            "simple_humanoid_description/urdf/simple_humanoid.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf",
            "icub_description/robots/icub_reduced.urdf", "iris_description/robots/iris.urdf",
            "romeo_description/urdf/romeo.urdf", "talos_data/robots/talos_full_v2.urdf",
            "centauro_description/urdf/centauro.urdf", "human_description/robots/human.urdf",
            "laikago_description/urdf/laikago.urdf", "solo_description/robots/solo.urdf",
            "quadruped_description/urdf/quadruped.urdf", "hextilt_description/urdf/hextilt_flying_arm_5.urdf",
            "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf", "iris_description/robots/iris_simple.urdf",
            "hector_description/robots/quadrotor_base.urdf"]

#: robots whose links' inertias no real body has (a principal moment above the sum of the other
#: two): imported with inertia="as_given", as Pinocchio takes them
AS_GIVEN_FIXED = ["allegro_hand_description/urdf/allegro_left_hand.urdf", "pr2_description/urdf/pr2.urdf",
                  "tiago_description/robots/tiago.urdf"]
AS_GIVEN_FLOATING = ["go1_description/urdf/go1.urdf", "hyq_description/robots/hyq_no_sensors.urdf",
                     "anymal_b_simple_description/robots/anymal.urdf", "b1_description/urdf/b1.urdf",
                     "romeo_description/urdf/romeo_small.urdf"]


def _sanitized(name):
    return re.sub(r"\W", "_", name)


@functools.lru_cache(maxsize=None)
def _pair(path, floating):
    """(mbcomp system, Pinocchio model) of one file, built once per test module run; the mimic
    joints free (Pinocchio's default), the inertias as the file gives them (as Pinocchio's), no
    visual shapes (the meshes change no dynamics; tests/io/test_urdf_visuals.py reads them)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the notes of what is not imported
        system = mbcomp.assemble(load_urdf(path, floating=floating, mimic=False, inertia="as_given", visuals=False))
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
    return system, model


def _random_state(system, model, rng):
    """Matching states ``(q, u)`` of mbcomp and ``(q, v)`` of Pinocchio, and ``T`` with ``u = T v``
    and ``dT/dt v``."""
    first = [n.split(".")[0] for n in system.q_names]
    first_u = [n.split(".")[0] for n in system.u_names]
    q, u = np.zeros(len(system.q_names)), np.zeros(len(system.u_names))
    qp, v = pin.neutral(model), rng.standard_normal(model.nv)
    T, Tdv = np.zeros((len(u), model.nv)), np.zeros(len(u))
    for i in range(1, model.njoints):
        iq, nq, iv = model.idx_qs[i], model.nqs[i], model.idx_vs[i]
        name = "root_joint" if model.names[i] == "root_joint" else _sanitized(model.names[i])
        if name not in first:  # held fixed by the import (it moves no mass): at 0, no speed, no column
            qp[iq:iq + nq] = (0.0,) if nq == 1 else (1.0, 0.0)
            v[iv] = 0.0
            continue
        j, k = first.index(name), first_u.index(name)
        if nq == 7:  # free flyer: Pinocchio (x y z qx qy qz qw), velocities in base axes
            r, quat = rng.uniform(-1, 1, 3), rng.standard_normal(4)
            quat /= np.linalg.norm(quat)
            qp[iq:iq + 7] = np.r_[r, quat[1:], quat[0]]
            q[j:j + 7] = np.r_[r, quat]
            R = pin.Quaternion(quat[0], *quat[1:]).toRotationMatrix()
            T[k:k + 3, iv:iv + 3], T[k + 3:k + 6, iv + 3:iv + 6] = R, np.eye(3)
            Tdv[k:k + 3] = R @ np.cross(v[iv + 3:iv + 6], v[iv:iv + 3])  # d(R v_lin)/dt at fixed v_lin
            u[k:k + 6] = T[k:k + 6, iv:iv + 6] @ v[iv:iv + 6]
            continue
        if nq == 4:  # planar about z: Pinocchio (x, y, cos, sin), in-plane velocity in the moving axes
            x, y, a = rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-3, 3)
            qp[iq:iq + 4], q[j:j + 3] = (x, y, np.cos(a), np.sin(a)), (x, y, a)
            c, s = np.cos(a), np.sin(a)
            T[k:k + 2, iv:iv + 2], T[k + 2, iv + 2] = ((c, -s), (s, c)), 1.0
            vx, vy, w = v[iv:iv + 3]
            Tdv[k:k + 2] = T[k:k + 2, iv:iv + 2] @ (-w * vy, w * vx)
            u[k:k + 3] = T[k:k + 3, iv:iv + 3] @ v[iv:iv + 3]
            continue
        a = rng.uniform(-3, 3)
        qp[iq:iq + nq] = a if nq == 1 else (np.cos(a), np.sin(a))  # nq 2: a continuous joint
        q[j], T[k, iv], u[k] = a, 1.0, v[iv]
    return q, u, qp, v, T, Tdv


def _differences(path, floating, n_states=3):
    """Largest relative differences of the mass matrix and of the bias forces over random states."""
    system, model = _pair(path, floating)
    data = model.createData()
    rng = np.random.default_rng(34)
    dM = db = 0.0
    for _ in range(n_states):
        q, u, qp, v, T, Tdv = _random_state(system, model, rng)
        ev = system.evaluate(0.0, q, u)
        M = T.T @ ev.M @ T
        b = -T.T @ (ev.f - ev.M @ Tdv)
        Mp = pin.crba(model, data, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        bp = pin.rnea(model, data, qp, v, np.zeros(model.nv)) + model.damping * v
        dM = max(dM, np.abs(M - Mp).max() / np.abs(Mp).max())
        db = max(db, np.abs(b - bp).max() / np.abs(bp).max())
    return dM, db


def _forward_difference(path, floating, n_states=2):
    """Largest relative difference of the accelerations: mbcomp's recursive (articulated-body)
    solve against Pinocchio's ``aba`` with the damping torque ``-D v`` applied, in mbcomp's
    speeds (``du/dt = T a + dT/dt v``)."""
    from mbcomp.assembly.recursive import lagrange_accelerations

    system, model = _pair(path, floating)
    data = model.createData()
    rng = np.random.default_rng(35)
    worst = 0.0
    for _ in range(n_states):
        q, u, qp, v, T, Tdv = _random_state(system, model, rng)
        ud = lagrange_accelerations(system, 0.0, q, u)
        a = pin.aba(model, data, qp, v, -model.damping * v)
        expect = T @ a + Tdv
        worst = max(worst, np.abs(ud - expect).max() / np.abs(expect).max())
    return worst


@needs_robots
@pytest.mark.parametrize("rel", FIXED[:6] + FLOATING[:6] + AS_GIVEN_FIXED[:1] + AS_GIVEN_FLOATING[:2])
def test_forward_dynamics_matches_pinocchio(rel):
    d = _forward_difference(os.path.join(ROBOTS, rel), floating=rel in FLOATING + AS_GIVEN_FLOATING)
    assert d < 1e-10, f"{rel}: accelerations {d:.1e} relative"


@needs_robots
@pytest.mark.parametrize("rel", FIXED + AS_GIVEN_FIXED)
def test_fixed_base_robot_matches_pinocchio(rel):
    dM, db = _differences(os.path.join(ROBOTS, rel), floating=False)
    assert dM < 1e-10 and db < 1e-10, f"{rel}: mass matrix {dM:.1e}, bias forces {db:.1e} relative"


@needs_robots
@pytest.mark.parametrize("rel", FLOATING + AS_GIVEN_FLOATING)
def test_floating_base_robot_matches_pinocchio(rel):
    dM, db = _differences(os.path.join(ROBOTS, rel), floating=True)
    assert dM < 1e-10 and db < 1e-10, f"{rel}: mass matrix {dM:.1e}, bias forces {db:.1e} relative"


PENDULUM = """<robot name="pendulum"><link name="base"/>
<link name="arm"><inertial><mass value="{m}"/><origin xyz="0 0 -{l}"/>
<inertia ixx="0.08" iyy="{Iyy}" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint></robot>"""


def _write(tmp_path, text, name="robot.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_pendulum_closed_form(tmp_path):
    """A hinge about y with the centre of mass l below it: M = m l^2 + Iyy, f = -m g l sin(phi)
    (phi > 0 turns z toward x, lifting the bob along +x: gravity pulls back)."""
    m, l, Iyy, g = 2.0, 0.5, 0.07, 9.81
    model = load_urdf(_write(tmp_path, PENDULUM.format(m=m, l=l, Iyy=Iyy)))
    system = mbcomp.assemble(model)
    assert system.q_names == ["hinge.phi"] and model.urdf_notes == []
    for phi in (0.3, -1.2, 2.5):
        ev = system.evaluate(0.0, np.array([phi]), np.array([0.7]))
        assert ev.M[0, 0] == pytest.approx(m * l * l + Iyy, rel=1e-14)
        assert ev.f[0] == pytest.approx(-m * g * l * np.sin(phi), rel=1e-13)


ODD = """<robot name="odd">
<link name="base"><inertial><mass value="3"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="a-link"><inertial><origin xyz="0.1 -0.2 0.3" rpy="0.4 -0.7 1.1"/><mass value="1.5"/>
<inertia ixx="0.03" iyy="0.05" izz="0.06" ixy="0.001" ixz="-0.002" iyz="0.003"/></inertial></link>
<link name="slider"><inertial><origin xyz="0 0.05 0" rpy="1.0 0.2 -0.3"/><mass value="0.8"/>
<inertia ixx="0.004" iyy="0.005" izz="0.006" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="massless"/>
<link name="tip"><inertial><mass value="0.2"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j-1" type="revolute"><parent link="base"/><child link="a-link"/><origin xyz="0.2 0 0.5" rpy="0.3 0.2 0.1"/>
<axis xyz="0.6 0 0.8"/><limit lower="-1" upper="1" effort="1" velocity="1"/><dynamics damping="0.4" friction="0.1"/></joint>
<joint name="slide" type="prismatic"><parent link="a-link"/><child link="slider"/><origin xyz="0 0.3 0" rpy="-0.5 0 0.9"/>
<axis xyz="0 1 0"/><limit lower="-0.1" upper="0.2" effort="1" velocity="1"/><dynamics damping="2.0"/></joint>
<joint name="weld" type="fixed"><parent link="slider"/><child link="massless"/><origin xyz="0 0 0.1" rpy="0 1.5 0"/></joint>
<joint name="wrist" type="revolute"><parent link="massless"/><child link="tip"/><origin xyz="0.05 0 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j-1" multiplier="2"/></joint>
<transmission name="t1"/></robot>"""


def test_rotated_inertia_offsets_damping_and_names_match_pinocchio(tmp_path):
    """Inertia given in a rotated inertial frame, rotated joint origins, an oblique axis, a
    prismatic joint, a massless link behind a fixed joint, damping on both kinds of joint and
    a joint name that is no identifier: the same M and bias forces as Pinocchio's model of the
    same file, and the notes name what was left out or renamed."""
    path = _write(tmp_path, ODD)
    with pytest.warns(UserWarning, match="not imported"):
        model = load_urdf(path, mimic=False)
    system = mbcomp.assemble(model)
    assert system.q_names == ["j_1.phi", "slide.s", "wrist.phi"]
    notes = "\n".join(model.urdf_notes)
    for said in ("'j-1': named 'j_1'", "'a-link': named 'a_link'", "'j-1': <dynamics friction=0.1> not imported "
                 "(friction=False)", "'wrist': <mimic> not imported (mimic=False", "<transmission> 't1'"):
        assert said in notes
    pm = pin.buildModelFromUrdf(path)
    assert list(pm.damping) == [0.4, 2.0, 0.0]
    dM, db = _differences(path, floating=False, n_states=5)
    assert dM < 1e-12 and db < 1e-12, (dM, db)


def test_damping_off_leaves_the_bias_of_pinocchio_without_damping(tmp_path):
    path = _write(tmp_path, ODD)
    with pytest.warns(UserWarning):
        system = mbcomp.assemble(load_urdf(path, damping=False, mimic=False))
    pm = pin.buildModelFromUrdf(path)
    q, v = np.array([0.3, 0.05, -0.4]), np.array([0.5, -0.2, 1.0])
    ev = system.evaluate(0.0, q, v)
    bp = pin.rnea(pm, pm.createData(), q, v, np.zeros(3))
    np.testing.assert_allclose(-ev.f, bp, rtol=1e-12, atol=1e-14)


def test_limits_become_stops_only_when_asked(tmp_path):
    path = _write(tmp_path, ODD)
    with pytest.warns(UserWarning):
        plain, stopped = load_urdf(path), load_urdf(path, limits=True)
    assert plain["j_1"].p.limits is None and plain["slide"].p.limits is None
    assert stopped["j_1"].p.limits.tolist() == [-1.0, 1.0]
    assert stopped["slide"].p.limits.tolist() == [-0.1, 0.2]
    assert stopped["j_1"].p.phi0 is None  # 0 inside the limits: the file's zero position
    shifted = ODD.replace('lower="-1" upper="1" effort="1" velocity="1"/><dynamics damping="0.4"',
                          'lower="0.2" upper="0.8" effort="1" velocity="1"/><dynamics damping="0.4"')
    with pytest.warns(UserWarning):
        model = load_urdf(_write(tmp_path, shifted, "shifted.urdf"), limits=True)
    assert model["j_1"].p.phi0 == pytest.approx(0.5)  # 0 is outside: a start no stop refuses
    assert any("'j-1': starts at the middle of its limits" in n for n in model.urdf_notes)
    assert mbcomp.assemble(model).evaluate(0.0, np.array([0.5, 0, 0]), np.zeros(3)).M.shape == (3, 3)


def test_rpy_is_fixed_axes_roll_pitch_yaw():
    """URDF's rpy: roll about x, then pitch about y, then yaw about z, all fixed axes."""
    from mbcomp.geometry.kinematics import rot_axis

    r, p, y = 0.3, -0.8, 1.9
    expect = rot_axis([0, 0, 1], y) @ rot_axis([0, 1, 0], p) @ rot_axis([1, 0, 0], r)
    np.testing.assert_allclose(rpy_matrix((r, p, y)), expect, atol=1e-15)


def test_bad_files_are_refused_with_the_reason(tmp_path):
    with pytest.raises(ValueError, match="not <robot>"):
        load_urdf(_write(tmp_path, "<sdf/>", "a.urdf"))
    two_roots = "<robot name='x'><link name='a'/><link name='b'/></robot>"
    with pytest.raises(ValueError, match="no links"):
        load_urdf(_write(tmp_path, "<robot name='empty'/>", "e.urdf"))
    with pytest.raises(ValueError, match="2 root links"):
        load_urdf(_write(tmp_path, two_roots, "b.urdf"))
    loop = ODD.replace('<transmission name="t1"/>', '<joint name="close" type="planar"><parent link="base"/>'
                       '<child link="tip"/></joint>')
    with pytest.raises(ValueError, match="'close': type 'planar' cannot close a loop"):
        load_urdf(_write(tmp_path, loop, "d.urdf"))
    cycle = two_roots.replace("</robot>", '<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>'
                              '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint></robot>')
    with pytest.raises(ValueError, match="0 root links"):
        load_urdf(_write(tmp_path, cycle, "f.urdf"))
    odd_kind = ODD.replace('type="prismatic"', 'type="screw"')
    with pytest.raises(ValueError, match="'slide': type 'screw'"):
        load_urdf(_write(tmp_path, odd_kind, "c.urdf"))
    with pytest.raises(ValueError, match=r"not XML \(unclosed token: line 1, column 7\) -> is it a URDF file"):
        load_urdf(_write(tmp_path, "<robot><link", "x.urdf"))
    bad_mass = PENDULUM.format(m="two", l=0.5, Iyy=0.1)
    with pytest.raises(ValueError, match=r"link 'arm': <mass value='two'> is not a number -> fix the file"):
        load_urdf(_write(tmp_path, bad_mass, "m.urdf"))
    bad_axis = PENDULUM.format(m=2, l=0.5, Iyy=0.1).replace('<axis xyz="0 1 0"/>', '<axis xyz="0 1"/>')
    with pytest.raises(ValueError, match=r"joint 'hinge': <axis xyz='0 1'> must hold three numbers -> fix the file"):
        load_urdf(_write(tmp_path, bad_axis, "a.urdf"))


def test_top_level_name():
    assert mbcomp.load_urdf is load_urdf


PLANAR = """<robot name="puck"><link name="table"/>
<link name="puck"><inertial><origin xyz="0.1 -0.05 0.02" rpy="0.2 0.1 0.4"/><mass value="2"/>
<inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="arm"><inertial><origin xyz="0.3 0 0"/><mass value="0.5"/>
<inertia ixx="0.001" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="slide_turn" type="planar"><parent link="table"/><child link="puck"/><origin xyz="0 0 0.1" rpy="0.3 0 0"/>
<axis xyz="0 0 1"/></joint>
<joint name="elbow" type="continuous"><parent link="puck"/><child link="arm"/><origin xyz="0.2 0 0"/>
<axis xyz="0 1 0"/></joint></robot>"""


def test_planar_joint_matches_pinocchio(tmp_path):
    """A planar joint (plane tilted by its origin's roll) carrying a pendulum arm: mbcomp's
    in-plane speeds are along the joint frame's axes, Pinocchio's along the moving axes."""
    path = _write(tmp_path, PLANAR)
    system, _ = _pair(path, False)
    assert system.q_names == ["slide_turn.s_x", "slide_turn.s_y", "slide_turn.phi", "elbow.phi"]
    dM, db = _differences(path, floating=False, n_states=5)
    assert dM < 1e-12 and db < 1e-12, (dM, db)


def test_a_joint_moving_no_mass_is_held_fixed_and_said(tmp_path):
    """A hinge carrying only massless links would leave its angle undetermined (a zero row of
    M): it is held at 0 as a fixed joint at its origin, and the notes say so; the rest keeps
    Pinocchio's mass matrix (its row of that joint dropped)."""
    sensor = ODD.replace('<transmission name="t1"/>', '<link name="camera"/><link name="lens"/>'
                         '<joint name="pan" type="revolute"><parent link="tip"/><child link="camera"/>'
                         '<origin xyz="0 0 0.2"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
                         '<joint name="lens_mount" type="fixed"><parent link="camera"/><child link="lens"/></joint>')
    path = _write(tmp_path, sensor)
    with pytest.warns(UserWarning, match="moves no mass"):
        model = load_urdf(path)
    system = mbcomp.assemble(model)
    assert system.q_names == ["j_1.phi", "slide.s", "wrist.phi"]
    pm = pin.buildModelFromUrdf(path)
    assert pm.nv == 4  # Pinocchio keeps the hinge, with a zero row and column
    q, v = np.array([0.3, 0.05, -0.4, 0.7]), np.array([0.5, -0.2, 1.0, 0.0])
    Mp = pin.crba(pm, pm.createData(), q)
    Mp = np.triu(Mp) + np.triu(Mp, 1).T
    assert np.abs(Mp[3]).max() == 0.0
    ev = system.evaluate(0.0, q[:3], v[:3])
    np.testing.assert_allclose(ev.M, Mp[:3, :3], rtol=1e-12, atol=1e-15)
    bp = pin.rnea(pm, pm.createData(), q, v, np.zeros(4)) + pm.damping * v
    np.testing.assert_allclose(-ev.f, bp[:3], rtol=1e-12, atol=1e-14)


@needs_robots
def test_impossible_inertias_are_refused_naming_the_link_and_the_option():
    """go1's links have inertias no real body has: refused by default, naming the link and
    ``inertia="as_given"``; with it, imported with one note per such link."""
    path = os.path.join(ROBOTS, AS_GIVEN_FLOATING[0])
    with pytest.raises(ValueError, match=r"link '\w+': principal moments .* inertia='as_given'"):
        load_urdf(path, floating=True)
    with pytest.warns(UserWarning):
        model = load_urdf(path, floating=True, inertia="as_given")
    taken = [n for n in model.urdf_notes if "taken as given" in n]
    unchecked = [c for c in model.components().values() if type(c).__name__ == "UncheckedRigidBody"]
    assert taken and len(unchecked) == len(taken)
