"""``models/robot_arm_pd.py``: the URDF arm under PD control settles where statics says.

The equilibrium is computed independently of mbcomp: the potential energy of the links'
weights is written from the URDF's numbers (read here with ElementTree) by hand -- the three
pitch hinges turn about y, so a point ``a`` along a link's z axis is at height
``a cos(q2 + ... + qk)`` above its hinge -- and ``K (q* - q) = dV/dq`` is solved by
``scipy.optimize.root`` with the exact Jacobian. The simulation must settle at that root (pure
PD) and at ``q*`` itself (PD + gravity compensation).
"""
import csv
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from scipy.optimize import root

import mbcomp
from mbcomp.cli import main

from conftest import load_model

ARM = load_model("models/robot_arm_pd.py")
SETTLE = dict(t_end=12.0, rtol=1e-11, atol=1e-12, n_out=3)


def _pitch_chain():
    """``(z0, [(hinge offset along z to the next hinge, link mass, its centre of mass along z)])``
    of the shoulder, elbow and wrist links, from the URDF file."""
    robot = ET.parse(ARM.URDF).getroot()
    links = {ln.get("name"): ln for ln in robot.findall("link")}
    joints = {j.get("name"): j for j in robot.findall("joint")}

    def z(el):
        x, y, zz = (float(v) for v in el.find("origin").get("xyz").split())
        assert x == y == 0.0
        return zz

    chain = []
    for k, joint in enumerate(ARM.JOINTS[1:], start=1):
        assert joints[joint].find("axis").get("xyz") == "0 1 0"
        link = links[ARM.LINKS[k]]
        nxt = ARM.JOINTS[k + 1] if k + 1 < len(ARM.JOINTS) else None
        chain.append((z(joints[nxt]) if nxt else 0.0, float(link.find("inertial/mass").get("value")),
                      z(link.find("inertial"))))
    return chain


def _gravity_torques(q, g):
    """``dV/dq`` and its Jacobian for ``q = (yaw, shoulder, elbow, wrist)``: the yaw moves no
    weight; hinge ``i`` carries every link beyond it (cumulative angles ``s_k``)."""
    chain = _pitch_chain()
    s = np.cumsum(q[1:])
    # V = g sum_k m_k (sum_{j<k} L_j cos s_j + c_k cos s_k)  (+ constants)
    dV_ds = np.zeros(3)
    d2 = np.zeros(3)
    for k, (_, m, c) in enumerate(chain):
        for j in range(k):
            dV_ds[j] -= g * m * chain[j][0] * np.sin(s[j])
            d2[j] -= g * m * chain[j][0] * np.cos(s[j])
        dV_ds[k] -= g * m * c * np.sin(s[k])
        d2[k] -= g * m * c * np.cos(s[k])
    # q_i moves s_k for k >= i: dV/dq_i = sum_{k >= i} dV/ds_k
    upper = np.triu(np.ones((3, 3)))
    tau = np.r_[0.0, upper @ dV_ds]
    J = np.zeros((4, 4))
    J[1:, 1:] = upper @ np.diag(d2) @ upper.T
    return tau, J


def _statics(target, kp, g):
    target, K = np.asarray(target, float), np.diag(kp)
    sol = root(lambda q: K @ (target - q) - _gravity_torques(q, g)[0], target,
               jac=lambda q: -K - _gravity_torques(q, g)[1], tol=1e-14)
    assert sol.success, sol.message
    return sol.x


def _settled(res):
    q = np.array([res[f"{j}.phi"][-1] for j in ARM.JOINTS])
    w = np.array([res[f"{j}.w"][-1] for j in ARM.JOINTS])
    return q, w


def test_the_hand_written_gravity_torques_are_the_models():
    """The independent statics' ingredients against mbcomp's evaluation of the bare arm (no PD
    force at ``kp = kd = 0``): ``f = -g(q)`` at rest."""
    system = mbcomp.assemble(ARM.build(kp=0.0, kd=0.0))
    for q in ([0.3, 0.8, -0.6, 0.4], [-1.0, -0.2, 1.4, -0.9]):
        ev = system.evaluate(0.0, np.array(q), np.zeros(4))
        np.testing.assert_allclose(ev.f, -_gravity_torques(np.array(q), 9.81)[0], rtol=0, atol=1e-12)


@pytest.mark.parametrize("target, kp", [((0.5, 0.8, -0.6, 0.4), (40.0, 80.0, 40.0, 10.0)),
                                        ((-0.3, -0.5, 1.1, 0.2), (20.0, 60.0, 30.0, 5.0))])
def test_pure_pd_settles_where_the_pd_torque_holds_the_weight(target, kp):
    expect = _statics(target, kp, 9.81)
    assert np.abs(expect - np.asarray(target)).max() > 0.05  # the arm sags visibly: the test can tell
    res = mbcomp.simulate(ARM.build(target=target, kp=kp), **SETTLE)
    assert res.success, res.message
    q, w = _settled(res)
    assert np.abs(w).max() < 1e-8
    np.testing.assert_allclose(q, expect, rtol=0, atol=1e-6)


def test_gravity_compensation_settles_at_the_target_exactly():
    target = (-0.3, -0.5, 1.1, 0.2)
    res = mbcomp.simulate(ARM.build(target=target, gravity_compensation=True), **SETTLE)
    assert res.success, res.message
    q, w = _settled(res)
    assert np.abs(w).max() < 1e-8
    np.testing.assert_allclose(q, target, rtol=0, atol=1e-6)


def test_mbcomp_simulate_runs_the_model_file(tmp_path, capsys):
    out = tmp_path / "arm.csv"
    assert main(["simulate", "models/robot_arm_pd.py", "-p", "gravity_compensation=true", "--t-end", "8",
                 "--n-out", "81", "--out", str(out), "-q"]) == 0
    assert "status: success" in capsys.readouterr().out
    with open(out) as fh:
        rows = list(csv.reader(fh))
    got = [float(rows[-1][rows[0].index(f"{j}.phi")]) for j in ARM.JOINTS]
    np.testing.assert_allclose(got, (0.5, 0.8, -0.6, 0.4), rtol=0, atol=1e-5)  # the default target, settled
