"""Locked joints on real robots: ``Model.lock`` / ``mbcomp.reduce`` against Pinocchio's
``buildReducedModel`` (mass matrix and bias forces of the reduced models at random states),
and against the full model with the same joints held by drives (the same motion of what is
kept, the same loads in what is held).

Conventions as in ``tests/io/test_urdf.py``: ``f = -b`` with ``b = rnea(q, v, 0) + D v``;
the kept joints here are revolute (speeds equal in both). A locked free flyer is held at
Pinocchio's ``(x, y, z, qx, qy, qz, qw)``, mbcomp's ``(x, y, z, qw, qx, qy, qz)``. Joints the
URDF import holds fixed (they move no mass) are locked at 0 in Pinocchio's model too.
"""
import os
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.io.urdf import load_urdf

pin = pytest.importorskip("pinocchio", reason="Pinocchio is not installed (the reference engine of these checks)")


from robot_files import ROBOTS, needs_robots  # noqa: E402

TALOS_ARM = [f"arm_left_{k}_joint" for k in range(1, 8)]
#: (file, floating, what to do: ("lock", joints) or ("keep", joints), coordinates left)
CASES = {
    "ur5 wrist locked": ("ur_description/urdf/ur5_robot.urdf", False,
                         ("lock", ["wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]), 3),
    "talos full, one arm kept": ("talos_data/robots/talos_full_v2.urdf", True, ("keep", TALOS_ARM), 7),
    "solo12 base locked": ("solo_description/robots/solo12.urdf", True, ("lock", ["root_joint"]), 12),
    "a1 base and a leg locked": ("a1_description/urdf/a1.urdf", True,
                                 ("lock", ["root_joint", "FL_hip_joint", "FL_thigh_joint", "FL_calf_joint"]), 9),
}


def _load(rel, floating):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the import's notes of what it leaves out
        return load_urdf(os.path.join(ROBOTS, rel), floating=floating, visuals=False)


def _held_values(model, names, rng):
    """Random coordinates for the joints to lock: ``{name: mbcomp's at}`` and Pinocchio's q of each."""
    at, qp = {}, {}
    for n in names:
        if model[n].nq == 7:  # the free flyer
            r, quat = rng.uniform(-1, 1, 3), rng.standard_normal(4)
            quat /= np.linalg.norm(quat)
            at[n], qp[n] = np.r_[r, quat], np.r_[r, quat[1:], quat[0]]
        else:
            a = rng.uniform(-1.5, 1.5)
            at[n], qp[n] = a, np.array([a])
    return at, qp


def _reduced_pair(case, seed=34):
    """(mbcomp reduced system, Pinocchio reduced model, the full mbcomp model, the reduced model)."""
    rel, floating, (how, names), _ = CASES[case]
    model = _load(rel, floating)
    moving = [n.split(".")[0] for n in mbcomp.assemble(model).u_names]
    moving = list(dict.fromkeys(moving))
    locked = names if how == "lock" else [n for n in moving if n not in names]
    at, qp = _held_values(model, locked, np.random.default_rng(seed))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always", UserWarning)
        reduced = model.lock(locked, at=at) if how == "lock" else mbcomp.reduce(model, keep=names, at=at)
    dampers = [n for n in reduced.lock_notes if n.startswith("RotationalDamper")]  # the file's <dynamics damping>
    assert len(said) == (1 if reduced.lock_notes else 0) and (not dampers or "dropped" in str(said[0].message))
    path = os.path.join(ROBOTS, rel)
    pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
    q_ref = pin.neutral(pm)
    ids = []
    for i in range(1, pm.njoints):
        name = pm.names[i]
        if name in qp or name not in moving:  # locked, or held fixed by the import (at 0)
            ids.append(i)
            if name in qp:
                q_ref[pm.idx_qs[i]:pm.idx_qs[i] + pm.nqs[i]] = qp[name]
    return mbcomp.assemble(reduced), pin.buildReducedModel(pm, ids, q_ref), model, reduced


def _differences(system, rm, n_states=3, seed=35):
    """Largest relative differences of M and of the bias forces over random states (revolute
    joints kept: Pinocchio's q and v are mbcomp's, in the order of their names)."""
    names = [rm.names[i] for i in range(1, rm.njoints)]
    assert all(rm.nqs[i] == 1 for i in range(1, rm.njoints)), "the kept joints here are revolute"
    order = [system.q_names.index(f"{n}.phi") for n in names]
    data, rng = rm.createData(), np.random.default_rng(seed)
    dM = db = 0.0
    for _ in range(n_states):
        qp, v = rng.uniform(-3, 3, rm.nq), rng.standard_normal(rm.nv)
        q, u = np.zeros(rm.nq), np.zeros(rm.nv)
        q[order], u[order] = qp, v
        ev = system.evaluate(0.0, q, u)
        M, f = ev.M[np.ix_(order, order)], ev.f[order]
        Mp = pin.crba(rm, data, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        bp = pin.rnea(rm, data, qp, v, np.zeros(rm.nv)) + rm.damping * v
        dM = max(dM, np.abs(M - Mp).max() / np.abs(Mp).max())
        db = max(db, np.abs(-f - bp).max() / np.abs(bp).max())
    return dM, db


@needs_robots
@pytest.mark.parametrize("case", list(CASES))
def test_reduced_robot_matches_pinocchios_reduced_model(case):
    system, rm, full, reduced = _reduced_pair(case)
    n_left = CASES[case][3]
    assert len(system.q_names) == rm.nq == n_left < len(mbcomp.assemble(full).q_names)
    dM, db = _differences(system, rm)
    assert dM < 1e-10 and db < 1e-10, f"{case}: mass matrix {dM:.1e}, bias forces {db:.1e} relative"
    assert set(reduced.locked) <= set(full.flatten().components)  # the locks keep the file's joint names


@needs_robots
def test_talos_reduced_to_one_arm_says_what_was_locked():
    system, rm, full, reduced = _reduced_pair("talos full, one arm kept")
    assert system.q_names == [f"{n}.phi" for n in TALOS_ARM]
    n_locked = len(reduced.locked)
    assert n_locked == len(dict.fromkeys(n.split(".")[0] for n in mbcomp.assemble(full).u_names)) - 7
    assert reduced.locked["root_joint"].keys() == {"r.x", "r.y", "r.z", "Q.w", "Q.x", "Q.y", "Q.z"}
    assert any("'torso_1_joint_damping' on locked torso_1_joint: dropped" in n for n in reduced.lock_notes)
    text = system.summary()
    assert f"locked: {n_locked} joints held as rigid connections (root_joint (FreeMotion at r.x=" in text


@needs_robots
def test_locked_wrist_moves_the_arm_as_drives_holding_it_do():
    """The UR5 falling under gravity from rest, its wrist locked, against the full UR5 whose
    wrist joints are held at the same angles by drives: the kept joints' motion agrees to the
    integrators' tolerance (rtol 1e-8) and the loads in the held joints (the locks' cut
    wrenches, the driven joints' reactions with the drives' torques) agree as well."""
    from mbcomp.library import PrescribedMotion

    at = {"wrist_1_joint": 0.3, "wrist_2_joint": -0.7, "wrist_3_joint": 1.1}
    rel = CASES["ur5 wrist locked"][0]
    held = _load(rel, False).lock(list(at), at=at)
    driven = _load(rel, False)
    for n, v in at.items():
        d = driven.add(f"hold_{n}", PrescribedMotion(s=v))
        driven.connect(d.flange_b, driven[n].axis)
    kw = dict(t_end=0.5, backend="numeric", dt_out=0.05, rtol=1e-8, atol=1e-10)
    a, b = mbcomp.simulate(held, **kw), mbcomp.simulate(driven, **kw)
    assert a.status == b.status == "success"
    for n in ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint"):
        assert np.abs(a[f"{n}.phi"]).max() > 0.1  # it falls: a motion to compare
        np.testing.assert_allclose(a[f"{n}.phi"], b[f"{n}.phi"], rtol=0, atol=1e-6)
    for n in at:
        np.testing.assert_array_equal(a[f"{n}.phi"], at[n])
        for c in ("f.x", "f.y", "f.z", "tau.x", "tau.y", "tau.z"):
            scale = max(np.abs(b[f"{n}.{c[:-2]}.{ax}"]).max() for ax in "xyz")
            np.testing.assert_allclose(a[f"{n}.{c}"], b[f"{n}.{c}"], rtol=0, atol=1e-6 * scale)
