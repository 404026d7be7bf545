"""MJCF import checked against MuJoCo: mass matrices, bias forces and accelerations of dm-control's models.

mbcomp's equations are ``M du/dt = f``; MuJoCo's ``M qacc = qfrc_passive - qfrc_bias +
qfrc_actuator + qfrc_constraint`` with ``qfrc_bias = C(q, v) v + g(q)``. The models are
compiled by MuJoCo from the same file (mbcomp reads it without MuJoCo), then compared with
MuJoCo's fluid forces (``opt.density``, ``opt.viscosity``) set to 0 and, unless said, its
armature removed (``dof_armature = 0``, and ``load_mjcf(armature=False)``: mbcomp's rotor is on
the absolute rate, see :mod:`mbcomp.io.mjcf_joints`); the joints' springs and dampers are in
``f``, so ``f = -qfrc_bias + qfrc_spring + qfrc_damper``. The states are the same numbers:
mbcomp's hinge and slide coordinates are MuJoCo's ``qpos`` (``ref`` included), a ball's and a
free joint's quaternion is MuJoCo's (w x y z), their speeds MuJoCo's ``qvel`` (a ball's
angular velocity in body axes; a free joint's linear velocity in world axes, angular in body
axes), matched by joint name (``model.mjcf_joints``, MuJoCo's joint order).
"""
import functools
import os
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.io.mjcf import body_frames, load_mjcf

mujoco = pytest.importorskip("mujoco", reason="MuJoCo is not installed (the reference engine of these checks)")


def _suite_dir():
    try:
        import dm_control
    except ImportError:
        return None
    return os.path.join(os.path.dirname(dm_control.__file__), "suite")


SUITE = _suite_dir()
needs_suite = pytest.mark.skipif(SUITE is None, reason="dm-control is not installed (pip install mbcomp[robots])")

MODELS = ["pendulum", "cartpole", "acrobot", "cheetah", "walker", "hopper", "reacher", "finger", "swimmer",
          "point_mass", "ball_in_cup", "fish", "humanoid", "quadruped", "manipulator", "stacker", "humanoid_CMU"]


@functools.lru_cache(maxsize=None)
def _pair(path, armature=False):
    """(mbcomp model, system, MuJoCo model) of one file, fluid off, armature off unless asked."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        model = load_mjcf(path, armature=armature)
    system = mbcomp.assemble(model)
    mj = mujoco.MjModel.from_xml_path(path)
    mj.opt.density = mj.opt.viscosity = 0.0
    mj.tendon_stiffness[:] = mj.tendon_damping[:] = 0.0  # tendons are not imported (noted)
    if not armature:
        mj.dof_armature[:] = 0.0
    return model, system, mj


def _layout(model, system, mj):
    """For each MuJoCo joint: its type, qpos and dof addresses and mbcomp's q and u indices."""
    out = []
    for k, cname in enumerate(model.mjcf_joints):
        q = [i for i, n in enumerate(system.q_names) if n.split(".")[0] == cname]
        u = [i for i, n in enumerate(system.u_names) if n.split(".")[0] == cname]
        out.append((int(mj.jnt_type[k]), int(mj.jnt_qposadr[k]), int(mj.jnt_dofadr[k]), q, u))
    return out


def _random_state(layout, mj, rng):
    """Equal states: MuJoCo's (qpos, qvel) and mbcomp's (q, u), and the permutation ``u = P qvel``."""
    qpos, qvel = mj.qpos0.copy(), rng.standard_normal(mj.nv)
    nq = sum(len(q) for *_, q, _ in layout)
    q, P = np.zeros(nq), np.zeros((sum(len(u) for *_, u in layout), mj.nv))
    for typ, qa, da, qi, ui in layout:
        if typ == mujoco.mjtJoint.mjJNT_FREE:
            quat = rng.standard_normal(4)
            qpos[qa:qa + 7] = np.r_[rng.uniform(-1, 1, 3), quat / np.linalg.norm(quat)]
        elif typ == mujoco.mjtJoint.mjJNT_BALL:
            quat = rng.standard_normal(4)
            qpos[qa:qa + 4] = quat / np.linalg.norm(quat)
        else:
            qpos[qa] = qpos[qa] + rng.uniform(-1.5, 1.5)
        width = len(ui)
        q[qi] = qpos[qa:qa + len(qi)]
        P[ui, da:da + width] = np.eye(width)
    return qpos, qvel, q, P @ qvel, P


def _mujoco_terms(mj, qpos, qvel):
    d = mujoco.MjData(mj)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(mj, d)
    return _full_mass_matrix(mj, d), -d.qfrc_bias + d.qfrc_spring + d.qfrc_damper


def _full_mass_matrix(mj, d):
    M = np.zeros((mj.nv, mj.nv))
    if hasattr(d, "qM"):  # MuJoCo 3: mj_fullM(m, dst, qM)
        mujoco.mj_fullM(mj, M, d.qM)
    else:  # MuJoCo 4: mj_fullM(m, d, dst)
        mujoco.mj_fullM(mj, d, M)
    return M


def _differences(path, n_states=3, armature=False):
    """Largest relative differences of M and of f over random states."""
    model, system, mj = _pair(path, armature)
    layout = _layout(model, system, mj)
    rng = np.random.default_rng(34)
    dM = df = 0.0
    for _ in range(n_states):
        qpos, qvel, q, u, P = _random_state(layout, mj, rng)
        ev = system.evaluate(0.0, q, u)
        M, f = _mujoco_terms(mj, qpos, qvel)
        dM = max(dM, np.abs(P.T @ ev.M @ P - M).max() / np.abs(M).max())
        df = max(df, np.abs(P.T @ ev.f - f).max() / np.abs(f).max())
    return dM, df


def _forward_difference(path, n_states=2):
    """Largest relative difference of mbcomp's accelerations (articulated-body solve) and
    MuJoCo's ``qacc`` with contacts and constraints (limits, friction loss, equalities) off."""
    from mbcomp.assembly.recursive import lagrange_accelerations

    model, system, mj = _pair(path)
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT \
        | mujoco.mjtDisableBit.mjDSBL_ACTUATION
    layout = _layout(model, system, mj)
    rng = np.random.default_rng(35)
    worst = 0.0
    for _ in range(n_states):
        qpos, qvel, q, u, P = _random_state(layout, mj, rng)
        d = mujoco.MjData(mj)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(mj, d)
        ud = lagrange_accelerations(system, 0.0, q, u)
        worst = max(worst, np.abs(P.T @ ud - d.qacc).max() / np.abs(d.qacc).max())
    return worst


@needs_suite
@pytest.mark.parametrize("name", MODELS)
def test_suite_model_matches_mujoco(name):
    dM, df = _differences(os.path.join(SUITE, name + ".xml"))
    print(f"{name}: nv {_pair(os.path.join(SUITE, name + '.xml'))[2].nv}, M {dM:.1e}, f {df:.1e}")
    assert dM < 1e-9 and df < 1e-9, f"{name}: mass matrix {dM:.1e}, bias forces {df:.1e} relative"


@needs_suite
@pytest.mark.parametrize("name", ["cartpole", "cheetah", "humanoid", "quadruped"])
def test_forward_dynamics_matches_mujoco(name):
    d = _forward_difference(os.path.join(SUITE, name + ".xml"))
    print(f"{name}: qacc {d:.1e}")
    assert d < 1e-9, f"{name}: accelerations {d:.1e} relative"
