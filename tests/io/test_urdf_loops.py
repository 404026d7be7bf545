"""URDF with loop-closing joints, mimic joints and joint friction: exact closures and couplings.

The mechanisms are planar in the x-z plane with hinges about y; a hinge's angle ``phi`` turns
the link's x axis to ``e(phi) = (cos phi, 0, -sin phi)`` (URDF's rotation about +y). Files are
written with full-precision numbers so that the file's zero position closes every loop.
"""
import warnings

import numpy as np
import pytest
from scipy.special import ellipj, ellipk

import mbcomp
from mbcomp.io.urdf import load_urdf


def e(phi):
    return np.array([np.cos(phi), 0.0, -np.sin(phi)])


def angle_of(v):
    """The angle ``phi`` with ``v = |v| e(phi)`` (v in the x-z plane)."""
    return np.arctan2(-v[2], v[0])


def wrap(a):
    return np.angle(np.exp(1j * np.asarray(a)))


def fourbar_angles(th2, a, b, c, d, th4_near):
    """Coupler and rocker angles of the four-bar ground ``d`` (from O2 = 0 to O4 = (d, 0, 0)),
    crank ``a`` at angle ``th2``, coupler ``b``, rocker ``c``: B on the circles about A and O4,
    the assembly branch nearest ``th4_near``."""
    A, O4 = a * e(th2), np.array([d, 0.0, 0.0])
    D = O4 - A
    L = np.linalg.norm(D)
    x = (b * b - c * c + L * L) / (2 * L)
    h = np.sqrt(b * b - x * x)
    u = D / L
    n = np.array([u[2], 0.0, -u[0]])
    best = []
    for s in (1.0, -1.0):
        B = A + x * u + s * h * n
        th3, th4 = angle_of(B - A), angle_of(B - O4)
        best.append((abs(wrap(th4 - th4_near)), th3, th4))
    return min(best)[1:]


def _f(x):
    return repr(float(x))


def link(name, m=0.0, length=0.0, Iyy=None):
    """A link of mass ``m`` as a bar along its x axis (centre of mass at ``length/2``)."""
    if m == 0.0:
        return f'<link name="{name}"/>'
    Iyy = m * length * length / 12 if Iyy is None else Iyy
    return (f'<link name="{name}"><inertial><origin xyz="{_f(length / 2)} 0 0"/><mass value="{_f(m)}"/>'
            f'<inertia ixx="1e-4" iyy="{_f(Iyy)}" izz="{_f(Iyy + 1e-4)}" ixy="0" ixz="0" iyz="0"/></inertial></link>')


def joint(name, kind, parent, child, xyz=(0, 0, 0), pitch=0.0, axis="0 1 0", extra=""):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{" ".join(map(_f, xyz))}" rpy="0 {_f(pitch)} 0"/><axis xyz="{axis}"/>{extra}</joint>')


def fourbar(a, b, c, d, th2, th4_near, masses=(1.0, 2.0, 1.5), closing="revolute"):
    """A four-bar as URDF: ground -> crank -> coupler (-> its massless tip at B), ground -> rocker,
    and the joint ``close`` from the rocker's end to the coupler's tip, which has a parent
    already: it closes the loop. The file's zero position is the mechanism at crank angle th2."""
    th3, th4 = fourbar_angles(th2, a, b, c, d, th4_near)
    text = "\n".join([
        '<robot name="fourbar">', link("ground"), link("crank", masses[0], a), link("coupler", masses[1], b),
        link("rocker", masses[2], c), link("coupler_tip"),
        joint("crank_joint", "continuous", "ground", "crank", pitch=th2),
        joint("coupler_joint", "continuous", "crank", "coupler", (a, 0, 0), th3 - th2),
        joint("tip", "fixed", "coupler", "coupler_tip", (b, 0, 0)),
        joint("rocker_joint", "continuous", "ground", "rocker", (d, 0, 0), th4),
        joint("close", closing, "rocker", "coupler_tip", (c, 0, 0), th3 - th4), "</robot>"])
    return text, th3, th4


def _write(tmp_path, text, name="robot.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def _run(model, t_end=10.0, **kw):
    return mbcomp.simulate(model, t_end=t_end, n_out=1001, stabilization="projection", rtol=1e-10, atol=1e-12, **kw)


def test_grashof_fourbar_closed_by_a_revolute_follows_freudenstein(tmp_path):
    """A crank-rocker four-bar (s + l = 1.3 <= p + q = 1.8, the crank shortest) swinging under
    gravity for 10 s: the loop stays closed (residual < 1e-10) and the rocker's angle is the
    closed-form one of the crank's at every output; the planar loop's redundant rows (3 of the
    cut hinge's 5) are found and named."""
    a, b, c, d, th2_0 = 0.3, 1.0, 0.8, 1.0, 1.2
    text, th3_0, th4_0 = fourbar(a, b, c, d, th2_0, 1.5)
    model = load_urdf(_write(tmp_path, text))
    assert model.urdf_notes == []
    system = mbcomp.assemble(model)
    summary = system.summary()
    assert "degrees of freedom: 1" in summary and "3 constraint rows are redundant" in summary
    assert len(system.topology.cut) == 1 and "5 constraint rows, rank 2" in summary
    res = _run(model)
    assert np.max(res["residual.position"]) < 1e-10
    th2, th4 = th2_0 + res["crank_joint.phi"], th4_0 + res["rocker_joint.phi"]
    assert np.ptp(th2) > 0.4  # it moves
    worst, near = 0.0, th4_0
    for t2, t4 in zip(th2, th4):
        _, near = fourbar_angles(t2, a, b, c, d, near)
        worst = max(worst, abs(wrap(near - t4)))
    assert worst < 1e-9, worst


def test_parallelogram_keeps_its_coupler_level_and_swings_as_an_exact_pendulum(tmp_path):
    """A parallelogram (crank = rocker, coupler = ground) released from rest 1 rad off hanging:
    the coupler only translates (its orientation is the start's to 1e-10), and the crank is a
    pendulum of constant inertia ``J = 2 J_p + m_c a^2`` and moment ``g a (m_r + m_c)``:
    ``psi(t) = 2 arcsin(k sn(K - w t, k))``, ``k = sin(psi_0 / 2)``."""
    a, d, m_r, m_c, g, psi0 = 0.5, 0.8, 1.0, 2.0, 9.81, 1.0
    th2 = np.pi / 2 + psi0
    text, th3_0, th4_0 = fourbar(a, d, a, d, th2, th2, masses=(m_r, m_c, m_r))
    assert abs(wrap(th4_0 - th2)) < 1e-14 and abs(th3_0) < 1e-14
    model = load_urdf(_write(tmp_path, text))
    res = _run(model, t_end=5.0)
    assert np.max(res["residual.position"]) < 1e-10
    Q = np.stack([res[f"coupler.Q.{k}"] for k in "wxyz"], axis=1)
    assert np.abs(np.abs(Q @ Q[0]) - 1.0).max() < 1e-10  # the same orientation throughout
    J = 2 * (m_r * a * a / 12 + m_r * a * a / 4) + m_c * a * a
    w = np.sqrt(g * a * (m_r + m_c) / J)
    k = np.sin(psi0 / 2)
    sn = ellipj(ellipk(k * k) - w * res["time"], k * k)[0]
    psi = 2 * np.arcsin(k * sn)
    assert np.abs(th2 + res["crank_joint.phi"] - np.pi / 2 - psi).max() < 1e-7


def fivebar(l1, l2, d, th1, th2, closing='<loop_joint name="close" type="continuous">'):
    """A five-bar (a planar 2-DOF parallel manipulator): ground pivots at 0 and (d, 0, 0), two
    proximal links l1 at angles th1, th2, two distal links l2 meeting at P; the closure at P
    written as a ``<loop_joint>`` (Drake's convention: frames on link1 and link2)."""
    A1, A2 = l1 * e(th1), np.array([d, 0, 0]) + l1 * e(th2)
    D = A2 - A1
    L = np.linalg.norm(D)
    h = np.sqrt(l2 * l2 - L * L / 4)
    P = A1 + D / 2 + h * np.array([D[2], 0, -D[0]]) / L  # the elbow-up branch
    p1, p2 = angle_of(P - A1), angle_of(P - A2)
    text = "\n".join([
        '<robot name="fivebar">', link("ground"), link("prox1", 1.0, l1), link("prox2", 1.0, l1),
        link("dist1", 0.7, l2), link("dist2", 0.7, l2),
        joint("q1", "continuous", "ground", "prox1", pitch=th1),
        joint("q2", "continuous", "ground", "prox2", (d, 0, 0), th2),
        joint("e1", "continuous", "prox1", "dist1", (l1, 0, 0), p1 - th1),
        joint("e2", "continuous", "prox2", "dist2", (l1, 0, 0), p2 - th2),
        f'{closing}<link1 link="dist1" xyz="{_f(l2)} 0 0"/>'
        f'<link2 link="dist2" xyz="{_f(l2)} 0 0" rpy="0 {_f(p1 - p2)} 0"/><axis xyz="0 1 0"/></loop_joint>',
        "</robot>"])
    return text


def test_fivebar_closed_by_a_loop_joint_element_conserves_energy(tmp_path):
    """A five-bar closed at its tip by Drake's ``<loop_joint>`` (a hinge): 2 degrees of freedom,
    3 redundant rows; over 10 s under gravity without damping the loop stays closed to 1e-10 and
    the energy is conserved; the two distal links' ends coincide (checked on the body poses)."""
    l1, l2, d = 0.4, 0.6, 0.3
    model = load_urdf(_write(tmp_path, fivebar(l1, l2, d, 1.9, 1.2)))
    system = mbcomp.assemble(model)
    assert "degrees of freedom: 2" in system.summary() and "3 constraint rows are redundant" in system.summary()
    res = _run(model)
    assert np.max(res["residual.position"]) < 1e-10
    E = res["energy.total"]
    assert np.ptp(res["energy.kinetic"]) > 0.5 and np.abs(E - E[0]).max() < 1e-8 * np.abs(res["energy.kinetic"]).max()
    ends = []
    for body in ("dist1", "dist2"):
        r = np.stack([res[f"{body}.r.{k}"] for k in "xyz"], axis=1)
        Q = np.stack([res[f"{body}.Q.{k}"] for k in "wxyz"], axis=1)
        x = np.stack([1 - 2 * (Q[:, 2] ** 2 + Q[:, 3] ** 2), 2 * (Q[:, 1] * Q[:, 2] + Q[:, 0] * Q[:, 3]),
                      2 * (Q[:, 1] * Q[:, 3] - Q[:, 0] * Q[:, 2])], axis=1)  # the body's x axis, world frame
        ends.append(r + l2 * x)
    assert np.abs(ends[0] - ends[1]).max() < 1e-10


def test_a_spherical_closure_of_a_planar_loop_has_one_redundant_row(tmp_path):
    """The same five-bar closed by a point coincidence (``type="spherical"``, mbcomp's extension
    for a ball loop joint): 3 rows, one of them (out of the plane) redundant; the motion is the
    hinge-closed one's (to the integration tolerance) since the planar motion needs no more."""
    l1, l2, d = 0.4, 0.6, 0.3
    hinge = load_urdf(_write(tmp_path, fivebar(l1, l2, d, 1.9, 1.2), "h.urdf"))
    ball = load_urdf(_write(tmp_path, fivebar(l1, l2, d, 1.9, 1.2, '<loop_joint name="close" type="spherical">'),
                            "b.urdf"))
    summary = mbcomp.assemble(ball).summary()
    assert "degrees of freedom: 2" in summary and "1 constraint rows are redundant" in summary
    rh, rb = _run(hinge, t_end=2.0), _run(ball, t_end=2.0)
    assert np.max(rb["residual.position"]) < 1e-10
    assert np.abs(rh["q1.phi"] - rb["q1.phi"]).max() < 1e-7 and np.abs(rh["q2.phi"] - rb["q2.phi"]).max() < 1e-7


def test_loop_joint_extras_are_noted_and_a_bad_loop_element_refused(tmp_path):
    text = fivebar(0.4, 0.6, 0.3, 1.9, 1.2).replace('<link2 link="dist2"', '<link2 link="nowhere"')
    with pytest.raises(ValueError, match=r"<loop_joint> 'close': <link2 link=...> must name a link"):
        load_urdf(_write(tmp_path, text))
    a, b, c, d = 0.3, 1.0, 0.8, 1.0
    text, _, _ = fourbar(a, b, c, d, 1.2, 1.5)
    text = text.replace('type="revolute"><parent link="rocker"/><child link="coupler_tip"/>',
                        'type="revolute"><parent link="rocker"/><child link="coupler_tip"/>'
                        '<dynamics damping="0.3"/><limit lower="-1" upper="1" effort="1" velocity="1"/>')
    with pytest.warns(UserWarning, match="it closes a loop"):
        model = load_urdf(_write(tmp_path, text, "extras.urdf"), limits=True)
    assert any("'close': <dynamics damping>" in n for n in model.urdf_notes)
    assert any("'close': <limit> not made stops" in n for n in model.urdf_notes)


GRIPPER = """<robot name="gripper">
<link name="palm"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="wrist"><inertial><origin xyz="0.02 0.01 0.1"/><mass value="0.8"/>
<inertia ixx="0.004" iyy="0.005" izz="0.003" ixy="0.0002" ixz="0" iyz="0"/></inertial></link>
<link name="left"><inertial><origin xyz="0.05 0 0.02"/><mass value="0.2"/>
<inertia ixx="0.0004" iyy="0.0005" izz="0.0003" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="right"><inertial><origin xyz="0.05 0 -0.01"/><mass value="0.3"/>
<inertia ixx="0.0004" iyy="0.0006" izz="0.0003" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="jaw1"><inertial><origin xyz="0 0.03 0"/><mass value="0.25"/>
<inertia ixx="0.0002" iyy="0.0002" izz="0.0002" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="jaw2"><inertial><origin xyz="0 -0.02 0.01"/><mass value="0.15"/>
<inertia ixx="0.0002" iyy="0.0003" izz="0.0002" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="tilt" type="continuous"><parent link="palm"/><child link="wrist"/><origin xyz="0 0 0.1" rpy="0.3 0 0"/>
<axis xyz="1 0 0"/></joint>
<joint name="finger1" type="revolute"><parent link="wrist"/><child link="left"/><origin xyz="0 0.04 0.2"/>
<axis xyz="0 0.6 0.8"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="finger2" type="revolute"><parent link="wrist"/><child link="right"/><origin xyz="0 -0.04 0.2" rpy="0 0.2 0"/>
<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="finger1" multiplier="-1.5" offset="0.1"/></joint>
<joint name="slide1" type="prismatic"><parent link="wrist"/><child link="jaw1"/><origin xyz="0.03 0 0.25"/>
<axis xyz="0.8 0 0.6"/><limit lower="-0.1" upper="0.1" effort="1" velocity="1"/></joint>
<joint name="slide2" type="prismatic"><parent link="wrist"/><child link="jaw2"/><origin xyz="-0.03 0 0.25" rpy="0 0 0.5"/>
<axis xyz="1 0 0"/><limit lower="-0.1" upper="0.1" effort="1" velocity="1"/><mimic joint="slide1" multiplier="-0.5" offset="0.01"/></joint>
</robot>"""


def _mimics(path):
    """``{joint: (leader, multiplier, offset)}`` of a file's mimic joints."""
    import xml.etree.ElementTree as ET

    out = {}
    for j in ET.parse(path).getroot().findall("joint"):
        m = j.find("mimic")
        if m is not None:
            out[j.get("name")] = (m.get("joint"), float(m.get("multiplier", 1)), float(m.get("offset", 0)))
    return out


def test_mimic_joints_follow_their_leaders_exactly(tmp_path):
    """``q = multiplier q_leader + offset`` over a 3 s run of a gripper under gravity (a revolute
    pair through an IdealGear, a prismatic pair and a revolute following a prismatic leader
    through a JointCoupling), to 1e-10; the couplings are named ``<joint>_mimic``."""
    text = GRIPPER.replace("</robot>", '<link name="thumb"><inertial><origin xyz="0.04 0 0"/><mass value="0.1"/>'
                           '<inertia ixx="0.0001" iyy="0.0001" izz="0.0001" ixy="0" ixz="0" iyz="0"/></inertial></link>'
                           '<joint name="thumb_joint" type="continuous"><parent link="wrist"/><child link="thumb"/>'
                           '<origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><mimic joint="slide1" multiplier="3"/></joint></robot>')
    path = _write(tmp_path, text)
    model = load_urdf(path, gravity=(0.0, -9.81, -3.0))
    assert type(model["finger2_mimic"]).__name__ == "IdealGear"
    assert type(model["slide2_mimic"]).__name__ == "JointCoupling"
    assert type(model["thumb_joint_mimic"]).__name__ == "JointCoupling"
    res = _run(model, t_end=3.0)
    moved = 0.0
    for name, (leader, mult, off) in _mimics(path).items():
        coord = "s" if name.startswith("slide") else "phi"
        lead = res[f"{leader}.{'s' if leader.startswith('slide') else 'phi'}"]
        moved = max(moved, np.ptp(lead))
        assert np.abs(res[f"{name}.{coord}"] - (mult * lead + off)).max() < 1e-10, name
    assert moved > 0.1


def _reduced(system, path, pm, q_pin, v_pin):
    """mbcomp's mass matrix and bias forces in Pinocchio's independent speeds (the mimic joints
    dropped): ``u = G v`` with ``G[mimic, leader] = multiplier``; ``M_red = G^T M G``,
    ``b_red = -G^T f`` (``G`` is constant)."""
    mimics = _mimics(path)
    q, u = np.zeros(len(system.q_names)), np.zeros(len(system.u_names))
    G = np.zeros((len(u), pm.nv))
    for k, (qn, un) in enumerate(zip(system.q_names, system.u_names)):
        joint = qn.split(".")[0]
        lead, mult, off = mimics.get(joint, (joint, 1.0, 0.0))
        i = pm.getJointId(lead)
        iq = pm.idx_qs[i]
        a = q_pin[iq] if pm.nqs[i] == 1 else np.arctan2(q_pin[iq + 1], q_pin[iq])  # nq 2: a continuous joint
        q[k] = mult * a + off
        G[k, pm.idx_vs[i]] = mult
    u = G @ v_pin
    ev = system.evaluate(0.0, q, u)
    return G.T @ ev.M @ G, -G.T @ ev.f


@pytest.mark.parametrize("robot", ["gripper", "panda"])
def test_mimic_matches_pinocchio_reduced_model(tmp_path, robot):
    """Pinocchio's model with ``mimic=True`` (the mimic joints without their own speeds): its
    mass matrix and bias forces (``rnea``: no joint damping, so none imported either) equal
    mbcomp's reduced by the couplings, to 1e-12."""
    pin = pytest.importorskip("pinocchio", reason="Pinocchio is not installed (the reference engine of this check)")
    if robot == "panda":
        from test_urdf import ROBOTS
        if ROBOTS is None:
            pytest.skip("example-robot-data is not installed (pip install mbcomp[robots])")
        path = f"{ROBOTS}/panda_description/urdf/panda.urdf"
    else:
        path = _write(tmp_path, GRIPPER)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        system = mbcomp.assemble(load_urdf(path, damping=False))
    pm = pin.buildModelFromUrdf(path, mimic=True)
    data = pm.createData()
    rng = np.random.default_rng(46)
    for _ in range(4):
        qp, vp = pin.neutral(pm), rng.standard_normal(pm.nv)
        for i in range(1, pm.njoints):
            a, iq = rng.uniform(-0.1, 0.1), pm.idx_qs[i]
            if pm.nqs[i] == 1:
                qp[iq] = a
            elif pm.nqs[i] == 2:
                qp[iq:iq + 2] = np.cos(a), np.sin(a)
        M, b = _reduced(system, path, pm, qp, vp)
        Mp = pin.crba(pm, data, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        bp = pin.rnea(pm, data, qp, vp, np.zeros(pm.nv))
        assert np.abs(M - Mp).max() < 1e-12 * np.abs(Mp).max()
        assert np.abs(b - bp).max() < 1e-12 * np.abs(bp).max()


PENDULUM = """<robot name="pendulum"><link name="base"/>
<link name="arm"><inertial><mass value="{m}"/><origin xyz="0 0 -{l}"/>
<inertia ixx="0.02" iyy="{Iyy}" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/><origin rpy="0 {phi0} 0"/>
<axis xyz="0 1 0"/><dynamics friction="{f}"/></joint></robot>"""


def test_joint_friction_holds_below_break_away_and_slips_above(tmp_path):
    """A pendulum held by its bearing's Coulomb friction ``f`` at ``phi0`` from hanging (the
    file's zero position): with ``m g l sin(phi0) < f`` it stays at rest, stuck; above, it slips
    at once, with the closed-form start acceleration ``-(m g l sin(phi0) - f) / J`` and the
    work of friction ``f |phi - 0|`` in the energy balance while it turns one way."""
    m, l, Iyy, g, f = 2.0, 0.5, 0.03, 9.81, 4.0
    J = Iyy + m * l * l
    below = np.arcsin(0.9 * f / (m * g * l))
    held = load_urdf(_write(tmp_path, PENDULUM.format(m=m, l=l, Iyy=Iyy, phi0=below, f=f)), friction=True)
    res = mbcomp.simulate(held, t_end=1.0)
    assert np.abs(res["hinge.phi"]).max() == 0.0 and res["hinge.sticking"].min() == 1.0
    assert res["hinge.friction"][0] == pytest.approx(m * g * l * np.sin(below), rel=1e-12)  # holds gravity
    above = 0.8
    model = load_urdf(_write(tmp_path, PENDULUM.format(m=m, l=l, Iyy=Iyy, phi0=above, f=f), "slip.urdf"),
                      friction=True)
    res = mbcomp.simulate(model, t_end=0.2, n_out=201, rtol=1e-10, atol=1e-12)
    assert res["hinge.sticking"].max() == 0.0 and res["hinge.friction"][0] == f
    assert res["hinge.w.der"][0] == pytest.approx(-(m * g * l * np.sin(above) - f) / J, rel=1e-12)
    phi, w = res["hinge.phi"], res["hinge.w"]
    turning = w < 0.0
    work = J * w ** 2 / 2 - m * g * l * (np.cos(above + phi) - np.cos(above)) + f * np.abs(phi)
    assert turning[1:].all() and np.abs(work).max() < 1e-9


def test_joint_friction_is_noted_when_off(tmp_path):
    with pytest.warns(UserWarning, match="friction"):
        model = load_urdf(_write(tmp_path, PENDULUM.format(m=2, l=0.5, Iyy=0.03, phi0=0.5, f=4.0)))
    assert model["hinge"].p.friction is None
    assert any("'hinge': <dynamics friction=4> not imported (friction=False)" in n for n in model.urdf_notes)


SLIDER = """<robot name="sled"><link name="rail"/>
<link name="block"><inertial><mass value="{m}"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
</inertial></link><joint name="slide" type="prismatic"><parent link="rail"/><child link="block"/><axis xyz="1 0 0"/>
<limit lower="-5" upper="5" effort="1" velocity="1"/><dynamics friction="{f}"/></joint></robot>"""


def test_prismatic_friction_decelerates_at_f_over_m_and_sticks(tmp_path):
    """A block pushed along a horizontal rail at 2 m/s with sliding friction f (N): it slows at
    exactly ``f / m``, stops at ``t = m v0 / f`` after ``m v0^2 / (2 f)`` and stays stuck."""
    m, f, v0 = 2.0, 3.0, 2.0
    model = load_urdf(_write(tmp_path, SLIDER.format(m=m, f=f)), friction=True)
    res = mbcomp.simulate(model, t_end=2.0, n_out=201, params={"slide.v0": v0}, rtol=1e-10, atol=1e-12)
    t, v, s = res["time"], res["slide.v"], res["slide.s"]
    t_stop = m * v0 / f
    moving = t < t_stop - 1e-9
    assert np.abs(v[moving] - (v0 - f / m * t[moving])).max() < 1e-9
    assert np.abs(v[t > t_stop + 1e-9]).max() < 1e-12 and res["slide.sticking"][-1] == 1.0
    assert s[-1] == pytest.approx(m * v0 ** 2 / (2 * f), abs=1e-9)


def _pose_matrix(xyz, rpy):
    from mbcomp.io.urdf import rpy_matrix

    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rpy_matrix(rpy), xyz
    return T


def _rpy_of(R):
    """URDF's roll, pitch, yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (|pitch| < pi/2)."""
    return np.arctan2(R[2, 1], R[2, 2]), -np.arcsin(R[2, 0]), np.arctan2(R[1, 0], R[0, 0])


SPATIAL_LINK = ('<link name="{0}"><inertial><origin xyz="0.1 0.05 -0.02"/><mass value="1"/>'
                '<inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0.001" ixz="0" iyz="0"/></inertial></link>')


def _origin_attrs(xyz, rpy):
    return f'xyz="{" ".join(map(_f, xyz))}" rpy="{" ".join(map(_f, rpy))}"'


@pytest.mark.parametrize("form", ["joint", "loop_joint"])
@pytest.mark.parametrize("kind", ["fixed", "revolute", "spherical"])
def test_spatial_closures_sit_where_the_file_puts_them(tmp_path, form, kind):
    """A spatial robot of two branches (rotated origins, an oblique axis) joined by a closing
    joint written so that the file's zero position closes it: every row of the loop vanishes
    there (to 1e-12) for both forms and three kinds, whichever joint the topology cuts; the same
    file with the closing frame 1 cm off does not close (the check reads the frames)."""
    rng = np.random.default_rng(7)
    o = {k: (rng.uniform(-0.5, 0.5, 3), rng.uniform(-1.2, 1.2, 3)) for k in ("a1", "a2", "b1", "c")}
    T_a2 = _pose_matrix(*o["a1"]) @ _pose_matrix(*o["a2"])  # the links' frames at the zero position
    T_c = T_a2 @ _pose_matrix(*o["c"])  # the closing joint's frame: on link a2 at o["c"]
    T_rel = np.linalg.inv(_pose_matrix(*o["b1"])) @ T_c  # ... in link b1's frame
    rel_rpy = _rpy_of(T_rel[:3, :3])
    np.testing.assert_allclose(_pose_matrix(T_rel[:3, 3], rel_rpy), T_rel, atol=1e-13)

    def origin(key, axis):
        return (f'<origin {_origin_attrs(*o[key])}/><axis xyz="{axis}"/>')

    def robot(shift):
        at_b1 = _origin_attrs(T_rel[:3, 3] + shift, rel_rpy)
        text = ('<robot name="spatial"><link name="base"/>' + "".join(SPATIAL_LINK.format(n) for n in ("a1", "a2", "b1"))
                + '<joint name="j1" type="revolute"><parent link="base"/><child link="a1"/>' + origin("a1", "0 0 1")
                + '</joint><joint name="j2" type="revolute"><parent link="a1"/><child link="a2"/>'
                + origin("a2", "0.6 0 0.8") + '</joint><joint name="k1" type="revolute"><parent link="base"/>'
                '<child link="b1"/>' + origin("b1", "0 1 0") + "</joint>")
        if form == "joint":  # a massless tip on a2 at the closing frame, then b1 -> tip: tip has a parent
            return text + ('<link name="tip"/><joint name="tip_mount" type="fixed"><parent link="a2"/>'
                           f'<child link="tip"/><origin {_origin_attrs(*o["c"])}/></joint>'
                           f'<joint name="close" type="{kind}"><parent link="b1"/><child link="tip"/>'
                           f'<origin {at_b1}/><axis xyz="0 0 1"/></joint></robot>')
        return text + (f'<loop_joint name="close" type="{kind}"><link1 link="a2" {_origin_attrs(*o["c"])}/>'
                       f'<link2 link="b1" {at_b1}/><axis xyz="0 0 1"/></loop_joint></robot>')

    def worst_row(text, name):
        system = mbcomp.assemble(load_urdf(_write(tmp_path, text, name)))
        assert len(system.topology.cut) == 1
        rows = system.evaluate_rows(0.0, system.default_q(), np.zeros(len(system.u_names)))
        return np.abs(rows.Phi).max()

    assert worst_row(robot(np.zeros(3)), "closed.urdf") < 1e-12
    assert worst_row(robot(np.array([0.01, 0.0, 0.0])), "open.urdf") > 1e-3


def test_what_friction_and_mimic_cannot_model_is_said(tmp_path):
    """Stops and friction on one joint (not combined yet): the friction is listed, the stops
    kept; a mimic of a joint the file does not have, and a mimic with multiplier 0, are listed
    and the joint moves freely; with mimic=False every mimic is listed."""
    with pytest.warns(UserWarning, match="friction"):
        model = load_urdf(_write(tmp_path, SLIDER.format(m=2.0, f=3.0)), friction=True, limits=True)
    assert model["slide"].p.friction is None and model["slide"].p.limits.tolist() == [-5.0, 5.0]
    assert any("'slide': <dynamics friction=3> not imported (stops and friction" in n for n in model.urdf_notes)
    odd = GRIPPER.replace('<mimic joint="finger1" multiplier="-1.5" offset="0.1"/>', '<mimic joint="nowhere"/>') \
        .replace('multiplier="-0.5" offset="0.01"', 'multiplier="0"')
    with pytest.warns(UserWarning, match="mimic"):
        model = load_urdf(_write(tmp_path, odd, "odd.urdf"))
    notes = "\n".join(model.urdf_notes)
    assert "'finger2': <mimic> not imported: its leader 'nowhere' is not a moving tree joint" in notes
    assert "'slide2': <mimic> not imported: multiplier 0" in notes
    assert not any(name.endswith("_mimic") for name in model.components())
    system = mbcomp.assemble(model)
    assert "finger2.phi" in system.q_names and "degrees of freedom: 5" in system.summary()
