"""MJCF ``<equality>`` loops closed exactly, checked against MuJoCo.

Two mechanisms written here (contacts disabled: only the loop and gravity act): a four-bar
closed by ``<connect>`` to the world, and a parallel gripper (a parallelogram) whose second
finger's knuckle is ``<weld>``-ed to the jaw. Checked: the tree's mass matrix and bias forces
against MuJoCo's ``mj_fullM``/``qfrc_bias``; the closures' offsets against MuJoCo's compiled
``eq_data``; over the same 10 s run mbcomp's loop residual (exact rows: < 1e-10) against
MuJoCo's equality violation (soft: it opens by what its ``solref`` lets it), and the motions
against each other to MuJoCo's softness.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.geometry.kinematics import quat_to_matrix
from mbcomp.io.mjcf import load_mjcf
from mujoco_matrices import full_mass_matrix

mujoco = pytest.importorskip("mujoco", reason="MuJoCo is not installed (the reference engine of these checks)")

T_END = 10.0


def e(phi):
    return np.array([np.cos(phi), 0.0, -np.sin(phi)])


def angle_of(v):
    return np.arctan2(-v[2], v[0])


def _f(x):
    return repr(float(x))


def fourbar_angles(th2, a, b, c, d):
    """Coupler and rocker angles of the four-bar at crank angle ``th2`` (ground from 0 to
    ``(d, 0, 0)``; the branch with the coupler above the ground line)."""
    A, O4 = a * e(th2), np.array([d, 0.0, 0.0])
    D = O4 - A
    L = np.linalg.norm(D)
    x = (b * b - c * c + L * L) / (2 * L)
    B = A + x * D / L + np.sqrt(b * b - x * x) * np.array([D[2], 0.0, -D[0]]) / L
    return angle_of(B - A), angle_of(B - O4)


def fourbar_xml(a=0.3, b=1.0, c=0.8, d=1.0, th2=1.2):
    """crank -> coupler -> rocker as a chain of hinges about y, the rocker's far end connected
    to the world (where it is at qpos0: the ground pivot (d, 0, 0))."""
    th3, th4 = fourbar_angles(th2, a, b, c, d)
    return f"""<mujoco model="fourbar"><compiler angle="radian"/>
<option timestep="0.0005" integrator="RK4"><flag contact="disable"/></option>
<worldbody>
<body name="crank" euler="0 {_f(th2)} 0"><joint name="crank_joint" axis="0 1 0"/>
 <geom type="capsule" fromto="0 0 0 {_f(a)} 0 0" size="0.02" mass="1"/>
 <body name="coupler" pos="{_f(a)} 0 0" euler="0 {_f(th3 - th2)} 0"><joint name="coupler_joint" axis="0 1 0"/>
  <geom type="capsule" fromto="0 0 0 {_f(b)} 0 0" size="0.02" mass="2"/>
  <body name="rocker" pos="{_f(b)} 0 0" euler="0 {_f(th4 + np.pi - th3)} 0"><joint name="rocker_joint" axis="0 1 0"/>
   <geom type="capsule" fromto="0 0 0 {_f(c)} 0 0" size="0.02" mass="1.5"/></body></body></body>
</worldbody>
<equality><connect name="ground_pin" body1="rocker" anchor="{_f(c)} 0 0"/></equality></mujoco>"""


def gripper_xml(L=0.5, d=0.3, psi0=0.7):
    """Two parallel fingers of length L hinged on a palm ``d`` apart, released ``psi0`` off
    hanging; the jaw hinged on finger a, a knuckle hinged on finger b, the knuckle welded to
    the jaw: a parallelogram whose jaw keeps its orientation."""
    th = np.pi / 2 + psi0
    return f"""<mujoco model="parallel_gripper"><compiler angle="radian"/>
<option timestep="0.0005" integrator="RK4"><flag contact="disable"/></option>
<worldbody>
<body name="palm" pos="0 0 1"><geom type="box" size="0.2 0.05 0.02" mass="1"/>
 <body name="link_a" euler="0 {_f(th)} 0"><joint name="hinge_a" axis="0 1 0"/>
  <geom type="capsule" fromto="0 0 0 {_f(L)} 0 0" size="0.015" mass="0.4"/>
  <body name="jaw" pos="{_f(L)} 0 0" euler="0 {_f(-th)} 0"><joint name="jaw_a" axis="0 1 0"/>
   <geom type="box" pos="{_f(d / 2)} 0 -0.05" size="{_f(d / 2)} 0.03 0.05" mass="0.8"/></body></body>
 <body name="link_b" pos="{_f(d)} 0 0" euler="0 {_f(th)} 0"><joint name="hinge_b" axis="0 1 0"/>
  <geom type="capsule" fromto="0 0 0 {_f(L)} 0 0" size="0.015" mass="0.4"/>
  <body name="knuckle" pos="{_f(L)} 0 0" euler="0 {_f(-th)} 0"><joint name="jaw_b" axis="0 1 0"/>
   <geom type="box" pos="0 0 -0.05" size="0.03 0.03 0.05" mass="0.3"/></body></body></body>
</worldbody>
<equality><weld name="grip" body1="jaw" body2="knuckle"/></equality></mujoco>"""


def _write(tmp_path, text, name="loop.xml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def _tree_matches_mujoco(path, mj, n_states=5):
    """Largest relative differences of the tree's M and bias forces (the file without its
    ``<equality>``: mbcomp may cut another joint of a loop than MuJoCo's equality) against
    MuJoCo's at random states (every joint a hinge or a slide: MuJoCo's qpos is mbcomp's q, in
    MuJoCo's joint order)."""
    text = open(path).read()
    tree = path.replace(".xml", "_tree.xml")
    with open(tree, "w") as f:
        f.write(text[:text.index("<equality>")] + text[text.index("</equality>") + len("</equality>"):])
    system = mbcomp.assemble(load_mjcf(tree))
    assert system.topology.cut == []
    d = mujoco.MjData(mj)
    coord = {int(mujoco.mjtJoint.mjJNT_HINGE): "phi", int(mujoco.mjtJoint.mjJNT_SLIDE): "s"}
    order = [system.q_names.index(f"{mj.joint(i).name}.{coord[int(mj.jnt_type[i])]}") for i in range(mj.njnt)]
    rng = np.random.default_rng(46)
    dM = db = 0.0
    for _ in range(n_states):
        d.qpos[:], d.qvel[:] = rng.uniform(-2, 2, mj.nq), rng.standard_normal(mj.nv)
        mujoco.mj_forward(mj, d)
        q, u = np.zeros(mj.nq), np.zeros(mj.nv)
        q[order], u[order] = d.qpos, d.qvel
        ev = system.evaluate(0.0, q, u)
        M, b = ev.M[np.ix_(order, order)], -ev.f[order]
        Mj = full_mass_matrix(mujoco, mj, d)
        dM = max(dM, np.abs(M - Mj).max() / np.abs(Mj).max())
        db = max(db, np.abs(b - d.qfrc_bias).max() / np.abs(d.qfrc_bias).max())
    return dM, db


def _violation(mj, d, i):
    """MuJoCo's violation of equality ``i`` (m, rad): the distance of its two anchor points and,
    for a weld, the angle between body2's axes and body1's rotated by the relative pose."""
    data, b1, b2 = mj.eq_data[i], mj.eq_obj1id[i], mj.eq_obj2id[i]
    R1, R2 = d.xmat[b1].reshape(3, 3), d.xmat[b2].reshape(3, 3)
    if mj.eq_type[i] == mujoco.mjtEq.mjEQ_CONNECT:
        return np.linalg.norm(d.xpos[b1] + R1 @ data[:3] - d.xpos[b2] - R2 @ data[3:6]), 0.0
    rel = np.zeros(9)
    mujoco.mju_quat2Mat(rel, data[6:10])
    dR = (R1 @ rel.reshape(3, 3)).T @ R2
    return (np.linalg.norm(d.xpos[b1] + R1 @ data[3:6] - d.xpos[b2] - R2 @ data[:3]),
            np.arccos(np.clip((np.trace(dR) - 1) / 2, -1, 1)))


def _mujoco_run(mj, every=0.01):
    """MuJoCo's run from qpos0 over T_END s: qpos and the equality violations every ``every`` s."""
    d = mujoco.MjData(mj)
    k_out = int(round(every / mj.opt.timestep))
    qpos, viol = [], []
    for k in range(int(round(T_END / mj.opt.timestep)) + 1):
        if k % k_out == 0:
            mujoco.mj_kinematics(mj, d)
            qpos.append(d.qpos.copy())
            viol.append([_violation(mj, d, i) for i in range(mj.neq)])
        mujoco.mj_step(mj, d)
    return np.array(qpos), np.array(viol)


def _mbcomp_run(model):
    return mbcomp.simulate(model, t_end=T_END, n_out=int(T_END / 0.01) + 1, stabilization="projection",
                           rtol=1e-10, atol=1e-12)


def test_fourbar_closed_by_connect_matches_mujoco_and_stays_closed(tmp_path):
    """The connect becomes a ball cut joint (3 rows, the out-of-plane one redundant: 1 degree
    of freedom); M and the bias forces of the tree equal MuJoCo's to 1e-12; over 10 s the loop
    stays closed to 1e-10 where MuJoCo's opens by ~3e-4 m, and the crank angles agree to
    MuJoCo's softness (2e-3 rad over a 0.5 rad swing)."""
    path = _write(tmp_path, fourbar_xml())
    model = load_mjcf(path)
    assert model.mjcf_notes == []
    system = mbcomp.assemble(model)
    assert system.topology.cut == ["ground_pin"] and type(model["ground_pin"]).__name__ == "Spherical"
    summary = system.summary()
    assert "degrees of freedom: 1" in summary and "redundant constraint rows dropped: ground_pin.y" in summary
    mj = mujoco.MjModel.from_xml_path(path)
    dM, db = _tree_matches_mujoco(path, mj)
    assert dM < 1e-12 and db < 1e-12, (dM, db)
    res = _mbcomp_run(model)
    qpos, viol = _mujoco_run(mj)
    ours, theirs = np.max(res["residual.position"]), viol[:, 0, 0].max()
    assert ours < 1e-10 and theirs > 1e4 * ours, (ours, theirs)
    assert np.ptp(qpos[:, 0]) > 0.4 and np.abs(qpos[:, 0] - res["crank_joint.phi"]).max() < 2e-3


def test_parallel_gripper_closed_by_weld_keeps_its_jaw_level(tmp_path):
    """The weld closes a parallelogram (6 rows, 3 of them redundant in the plane: 1 degree of
    freedom); mbcomp keeps the jaw's orientation exactly and the loop closed to 1e-10 over 10 s
    where MuJoCo's weld opens by ~4e-4 m and ~3e-3 rad; the fingers' angles agree to
    MuJoCo's softness (5e-3 rad over a 1.4 rad swing)."""
    path = _write(tmp_path, gripper_xml())
    model = load_mjcf(path)
    system = mbcomp.assemble(model)
    summary = system.summary()
    assert "degrees of freedom: 1" in summary and "3 constraint rows are redundant" in summary
    mj = mujoco.MjModel.from_xml_path(path)
    dM, db = _tree_matches_mujoco(path, mj)
    assert dM < 1e-12 and db < 1e-12, (dM, db)
    res = _mbcomp_run(model)
    Q = np.stack([res[f"jaw.Q.{k}"] for k in "wxyz"], axis=1)
    assert np.abs(np.abs(Q @ Q[0]) - 1.0).max() < 1e-10
    qpos, viol = _mujoco_run(mj)
    ours = np.max(res["residual.position"])
    assert ours < 1e-10 and viol[:, 0, 0].max() > 1e4 * ours and viol[:, 0, 1].max() > 1e4 * ours
    assert np.ptp(qpos[:, 0]) > 1.0 and np.abs(qpos[:, 0] - res["hinge_a.phi"]).max() < 5e-3


SPATIAL = """<mujoco><worldbody>
<body name="a" pos="0.1 0.2 0.3" euler="10 20 30"><joint axis="0 1 0"/><geom size="0.1" mass="1"/>
  <body name="b" pos="0.5 0 0" euler="-30 40 5"><joint axis="1 0 0"/><geom size="0.1" mass="1"/></body></body>
<body name="c" pos="1 1 1" quat="0.9 0.1 0.2 0.3"><joint type="ball"/><geom size="0.1" mass="1"/></body>
</worldbody><equality>
<connect name="pin" body1="b" body2="c" anchor="0.1 0.2 0.3"/>
<weld name="glue" body1="b" body2="c" anchor="0.3 0.2 0.1"/>
<weld name="posed" body1="a" body2="c" relpose="1 2 3 0.5 0.5 0.5 0.5" anchor="0.3 0.2 0.1"/>
<connect name="tether" body1="b" anchor="0.1 0.2 0.3"/>
<weld name="loose" body1="a" body2="c" torquescale="0"/>
</equality></mujoco>"""


def _offset(model, name):
    """``(r, R)`` of a closure's rigid offset (identity when the pose needed none)."""
    comp = model.components().get(name)
    if comp is None:
        return np.zeros(3), np.eye(3)
    return comp.p.r, getattr(comp.p, "R", np.eye(3))


def test_closures_sit_where_mujocos_compiler_puts_them(tmp_path):
    """Spatial bodies (rotated, a ball-jointed one): each closure's two frames on the bodies are
    MuJoCo's compiled ``eq_data`` -- connect: body1's anchor and body2's point at qpos0 (the
    world's when body2 is omitted); weld: body2's anchor, and body2's anchor point and axes in
    body1's frame (at qpos0, or ``relpose``); ``torquescale=0``: a connect at the anchors."""
    path = _write(tmp_path, SPATIAL)
    model = load_mjcf(path)
    mj = mujoco.MjModel.from_xml_path(path)
    rel = np.zeros(9)
    for i, name in enumerate(("pin", "glue", "posed", "tether", "loose")):
        data = mj.eq_data[i]
        (ra, Ra), (rb, Rb) = _offset(model, f"{name}_a"), _offset(model, f"{name}_b")
        if mj.eq_type[i] == mujoco.mjtEq.mjEQ_CONNECT:
            expect_a, expect_b, R = data[:3], data[3:6], np.eye(3)
        else:
            mujoco.mju_quat2Mat(rel, data[6:10])
            expect_a, expect_b, R = data[3:6], data[:3], rel.reshape(3, 3)
        kind = type(model[name]).__name__
        assert kind == ("Spherical" if name in ("pin", "tether", "loose") else "Weld"), name
        if name == "loose":
            R = np.eye(3)
        np.testing.assert_allclose(ra, expect_a, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(rb, expect_b, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(Ra, R, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(Rb, np.eye(3), atol=0, err_msg=name)
    consistent = load_mjcf(_write(tmp_path, "".join(ln for ln in SPATIAL.splitlines(True) if "posed" not in ln),
                                  "closed.xml"))
    system = mbcomp.assemble(consistent)  # every closure at qpos0 closed by construction: Phi = 0 there
    rows = system.evaluate_rows(0.0, system.default_q(), np.zeros(len(system.u_names)))
    assert len(rows.Phi) >= 12 and np.abs(rows.Phi).max() < 1e-12


def test_what_is_not_closed_is_said(tmp_path):
    text = fourbar_xml().replace("</equality>", """<connect name="off" body1="coupler" anchor="0 0 0" active="false"/>
<joint name="lock" joint1="crank_joint"/><weld name="soft" body1="crank" body2="coupler" solref="0.01 1"/>
<connect name="sites" site1="s1" site2="s2"/></equality>""")
    with pytest.raises(ValueError):  # the sites do not exist: MuJoCo itself refuses this file
        mujoco.MjModel.from_xml_string(text)
    with pytest.warns(UserWarning, match="MJCF elements"):
        model = load_mjcf(_write(tmp_path, text))
    notes = "\n".join(model.mjcf_notes)
    for said in ("equality <connect> 'off' (coupler): not imported: inactive",
                 "equality <joint> 'lock' (crank_joint): not imported: no joint2",
                 "equality <weld> 'soft': held exactly (solref: MuJoCo's softness, not applied)",
                 "equality <connect> 'sites' (s1, s2): not imported: site-based"):
        assert said in notes, said
    bad = fourbar_xml().replace('body1="rocker"', 'body1="nobody"')
    with pytest.raises(ValueError, match="equality <connect> 'ground_pin': body 'nobody' is not a body"):
        load_mjcf(_write(tmp_path, bad, "bad.xml"))


FINGERS = """<mujoco model="fingers"><compiler angle="radian"/>
<option timestep="0.0005" integrator="RK4" gravity="0 -4 -9.81"><flag contact="disable"/></option>
<worldbody><body name="palm" pos="0 0 1" euler="0.3 0 0"><geom type="box" size="0.1 0.05 0.02" mass="1"/>
 <body name="left" pos="-0.05 0 0"><joint name="finger_l" axis="0 1 0"/>
  <geom type="capsule" fromto="0 0 0 0 0 -0.12" size="0.01" mass="0.1"/></body>
 <body name="right" pos="0.05 0 0" euler="0 0 0.4"><joint name="finger_r" axis="0 1 0" ref="0.2"/>
  <geom type="capsule" fromto="0 0 0 0.02 0 -0.12" size="0.01" mass="0.12"/></body>
 <body name="plunger" pos="0 0 -0.05"><joint name="plunge" type="slide" axis="0 0.6 -0.8"/>
  <geom type="box" size="0.02 0.02 0.02" mass="0.2"/></body></body></worldbody>
<equality><joint name="mirror" joint1="finger_r" joint2="finger_l" polycoef="0 -1.5 0 0 0"/>
<joint name="drive" joint1="plunge" joint2="finger_l" polycoef="0 0.05 0 0 0"/></equality></mujoco>"""


def test_linear_joint_equalities_couple_exactly_and_match_mujoco(tmp_path):
    """``<joint>`` equalities with a linear ``polycoef`` between two hinges (an IdealGear; one
    hinge with ``ref``: the phase is qpos0's) and a slide on a hinge (a JointCoupling): over
    10 s ``y - y0 = a1 (x - x0)`` holds to 1e-10 in mbcomp, where MuJoCo's soft rows give way
    by what its solref lets them (light fingers: ~3e-2 rad at the default 0.02 s); as MuJoCo's
    rows stiffen (solref 0.002 s) its motion comes to mbcomp's (the semantics are the same)."""
    path = _write(tmp_path, FINGERS)
    model = load_mjcf(path)
    assert type(model["mirror"]).__name__ == "IdealGear" and type(model["drive"]).__name__ == "JointCoupling"
    mj = mujoco.MjModel.from_xml_path(path)
    dM, db = _tree_matches_mujoco(path, mj)
    assert dM < 1e-12 and db < 1e-12, (dM, db)
    res = _mbcomp_run(model)
    left = res["finger_l.phi"]
    ours = max(np.abs(res["finger_r.phi"] - 0.2 + 1.5 * left).max(), np.abs(res["plunge.s"] - 0.05 * left).max())
    assert np.ptp(left) > 0.1 and ours < 1e-10
    apart = []
    for solref in (None, "0.002 1"):
        text = FINGERS if solref is None else FINGERS.replace('0 0 0"/>', f'0 0 0" solref="{solref}"/>')
        qpos, _ = _mujoco_run(mujoco.MjModel.from_xml_string(text))
        theirs = max(np.abs(qpos[:, 1] - 0.2 + 1.5 * qpos[:, 0]).max(), np.abs(qpos[:, 2] - 0.05 * qpos[:, 0]).max())
        assert theirs > 1e4 * ours, (ours, theirs)
        apart.append(np.abs(qpos[:, 0] - left).max())
    assert apart[1] < 0.1 * apart[0] and apart[1] < 0.05 * np.ptp(left), apart


FREE = """<mujoco><option><flag contact="disable"/></option><worldbody>
<body name="arm" pos="0 0 1"><joint name="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" mass="1"/></body>
<body name="ball" pos="0.5 0 1"><freejoint name="float"/><geom type="sphere" size="0.05" mass="0.5"/></body>
</worldbody><equality><weld body1="arm" body2="ball"/></equality></mujoco>"""


def test_a_free_body_welded_runs_as_loaded(tmp_path):
    """A free body welded to a hinged arm: the free joint lies on the loop, so the topology cuts
    it and a cut joint has no coordinates to hold fixed starts; load_mjcf gives its start pose
    as a Guess (the file's pose closes the loop: nothing moves), and the model runs as loaded:
    the loop closed to 1e-10 and the hinge's angle that of the arm with the ball attached."""
    model = load_mjcf(_write(tmp_path, FREE))
    system = mbcomp.assemble(model)
    assert system.topology.cut == ["float"]
    assert isinstance(model["float"].p.r0, mbcomp.Guess) and isinstance(model["float"].p.R0, mbcomp.Guess)
    res = mbcomp.simulate(model, t_end=1.0, stabilization="projection", rtol=1e-10, atol=1e-12)
    assert np.max(res["residual.position"]) < 1e-10
    rigid = """<mujoco><worldbody><body name="arm" pos="0 0 1"><joint name="hinge" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" mass="1"/><geom type="sphere" pos="0.5 0 0" size="0.05" mass="0.5"/>
</body></worldbody></mujoco>"""
    one = mbcomp.simulate(load_mjcf(_write(tmp_path, rigid, "rigid.xml")), t_end=1.0, rtol=1e-10, atol=1e-12)
    assert np.ptp(one["hinge.phi"]) > 1.0 and np.abs(res["hinge.phi"] - one["hinge.phi"]).max() < 1e-7


#: a floating pelvis whose leg closes a loop below it (Cassie's shape): the free joint is on no loop
FLOATING_LEG = """<mujoco><option><flag contact="disable"/></option><worldbody>
<body name="pelvis" pos="0 0 1"><freejoint name="root"/><geom type="box" size="0.1 0.1 0.05" mass="5"/>
 <body name="thigh" pos="0 0 -0.05"><joint name="hip" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.02" mass="1"/>
  <body name="shin" pos="0 0 -0.4"><joint name="knee" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.02" mass="1"/></body></body>
 <body name="rod" pos="0.1 0 -0.05"><joint name="rod_hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.01" mass="0.2"/></body>
</body></worldbody><equality><connect name="achilles" body1="rod" body2="shin" anchor="0 0 -0.5"/></equality></mujoco>"""


def test_a_floating_base_above_a_leg_loop_keeps_its_fixed_start_pose(tmp_path):
    """The free joint of a pelvis whose leg closes a loop below it is on no loop: its start
    pose stays fixed (not a Guess), the loop's own joint is cut, and the robot falls freely with
    its leg swinging: its centre of mass falls on a parabola of exactly g while the loop stays
    closed."""
    model = load_mjcf(_write(tmp_path, FLOATING_LEG))
    assert not isinstance(model["root"].p.r0, mbcomp.Guess)
    system = mbcomp.assemble(model)
    assert "root" not in system.topology.cut and "achilles" in system.topology.cut
    res = mbcomp.simulate(model, t_end=0.5, params={"hip.w0": 2.0}, stabilization="projection", rtol=1e-10,
                          atol=1e-12, n_out=11)
    assert res.status == "success" and np.max(res["residual.position"]) < 1e-10
    z_cm = 0.0
    for b in ("pelvis", "thigh", "shin", "rod"):
        Q = np.stack([res[f"{b}.Q.{c}"] for c in "wxyz"], axis=1)
        r_cm = np.asarray(model[b].p.r_cm, dtype=float)
        z_cm = z_cm + model[b].p.m * (res[f"{b}.r.z"] + np.array([quat_to_matrix(q) @ r_cm for q in Q])[:, 2])
    total = sum(model[b].p.m for b in ("pelvis", "thigh", "shin", "rod"))
    assert np.ptp(res["knee.phi"]) > 0.1  # the leg swings (its start rate), the loop moving its other joints
    c2, c1, c0 = np.polyfit(res.time, z_cm / total, 2)  # the centre of mass: a parabola of curvature -g
    assert abs(c2 + 0.5 * 9.81) < 1e-8
    assert np.abs(np.polyval((c2, c1, c0), res.time) - z_cm / total).max() < 1e-9


ROD = """<mujoco><compiler angle="radian"/><option timestep="0.0005" integrator="RK4"><flag contact="disable"/></option>
<worldbody><body name="thigh" pos="0 0 1" euler="0.3 0.2 0.1"><joint name="hip" axis="0 1 0"/>
 <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.03" mass="2"/>
 <body name="rod" pos="0.1 0 0" euler="1.0 -0.5 0.7"><joint name="rod_ball" type="ball"/>
  <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.01" mass="0.1"/></body>
 <body name="shin" pos="0 0 -0.5" euler="-0.4 0.8 0.2"><joint name="knee" axis="0 1 0"/>
  <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/>
  <body name="heel" pos="0 0 -0.3" euler="0.9 0.1 -1.2"><joint name="heel_joint" axis="1 0 0"/>
   <geom type="box" size="0.05 0.03 0.02" mass="0.3"/></body></body></body></worldbody>
<equality><connect name="achilles" body1="rod" body2="heel" anchor="0.5 0 0"/></equality></mujoco>"""


def test_a_connect_kept_in_the_tree_places_its_side_as_at_qpos0(tmp_path):
    """A rod on a ball joint connected to a heel (Cassie's achilles rod, spatial and rotated):
    the topology cuts the file's ball joint and keeps the connect's ball in the tree, whose start
    orientation (the bodies' relative axes at qpos0) places the heel's side: the loop is closed
    at the start (1e-12) and stays closed (1e-10) over 10 s where MuJoCo's opens (~2.5e-3 m);
    MuJoCo's hip angle comes to mbcomp's as its connect stiffens (solref 0.02 -> 0.002 s: from
    ~2e-2 to ~5e-4 rad over the first second)."""
    path = _write(tmp_path, ROD)
    model = load_mjcf(path)
    system = mbcomp.assemble(model)
    assert system.topology.cut == ["rod_ball"]
    rows = system.evaluate_rows(0.0, system.default_q(), np.zeros(len(system.u_names)))
    assert np.abs(rows.Phi).max() < 1e-12
    res = _mbcomp_run(model)
    ours = np.max(res["residual.position"])
    assert ours < 1e-10 and np.ptp(res["hip.phi"]) > 0.2
    apart = []  # over the first second (the 3-DOF spatial loop is chaotic: differences grow later)
    for solref in (None, "0.002 1"):
        text = ROD if solref is None else ROD.replace('anchor="0.5 0 0"/>', f'anchor="0.5 0 0" solref="{solref}"/>')
        qpos, viol = _mujoco_run(mujoco.MjModel.from_xml_string(text))
        assert viol[:, 0, 0].max() > 1e4 * ours, (ours, viol[:, 0, 0].max())
        apart.append(np.abs(qpos[:101, 0] - res["hip.phi"][:101]).max())
    assert apart[1] < 0.1 * apart[0] and apart[1] < 1e-3, apart
