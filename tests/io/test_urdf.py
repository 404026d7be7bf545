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


def _robots_dir():
    try:
        from importlib.metadata import PackageNotFoundError, files
        found = [f for f in (files("example-robot-data") or []) if str(f).endswith("ur5_robot.urdf")]
    except PackageNotFoundError:
        found = []
    if not found:
        return None
    return str(found[0].locate()).split("/ur_description/")[0]


ROBOTS = _robots_dir()
needs_robots = pytest.mark.skipif(ROBOTS is None, reason="example-robot-data is not installed "
                                                         "(pip install mbcomp[robots])")

FIXED = ["ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf",
         "ur_description/urdf/ur3_robot.urdf", "ur_description/urdf/ur10_robot.urdf",
         "kinova_description/robots/kinova.urdf", "xarm_description/urdf/xarm7.urdf",
         "z1_description/urdf/z1.urdf", "so_arm_description/urdf/so100.urdf",
         "finger_edu_description/robots/finger_edu.urdf",
         "double_pendulum_description/urdf/double_pendulum_continuous.urdf",
         "talos_data/robots/talos_left_arm.urdf", "baxter_description/urdf/baxter.urdf"]
FLOATING = ["a1_description/urdf/a1.urdf", "go2_description/urdf/go2.urdf", "solo_description/robots/solo12.urdf",
            "bolt_description/robots/bolt.urdf", "talos_data/robots/talos_reduced.urdf",
            "simple_humanoid_description/urdf/simple_humanoid.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf",
            "icub_description/robots/icub_reduced.urdf", "iris_description/robots/iris.urdf"]


def _sanitized(name):
    return re.sub(r"\W", "_", name)


@functools.lru_cache(maxsize=None)
def _pair(path, floating):
    """(mbcomp system, Pinocchio model) of one file, built once per test module run."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the notes of what is not imported
        system = mbcomp.assemble(load_urdf(path, floating=floating))
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


@needs_robots
@pytest.mark.parametrize("rel", FIXED)
def test_fixed_base_robot_matches_pinocchio(rel):
    dM, db = _differences(os.path.join(ROBOTS, rel), floating=False)
    assert dM < 1e-10 and db < 1e-10, f"{rel}: mass matrix {dM:.1e}, bias forces {db:.1e} relative"


@needs_robots
@pytest.mark.parametrize("rel", FLOATING)
def test_floating_base_robot_matches_pinocchio(rel):
    dM, db = _differences(os.path.join(ROBOTS, rel), floating=True)
    assert dM < 1e-10 and db < 1e-10, f"{rel}: mass matrix {dM:.1e}, bias forces {db:.1e} relative"
