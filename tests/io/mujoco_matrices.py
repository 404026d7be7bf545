"""MuJoCo's dense mass matrix across its versions (the MJCF tests' shared reference call)."""
import numpy as np


def full_mass_matrix(mujoco, mj, d):
    """``M`` (nv, nv) of MuJoCo model ``mj`` at data ``d`` (after ``mj_forward``): MuJoCo 3's
    ``mj_fullM(m, dst, qM)`` or MuJoCo 4's ``mj_fullM(m, d, dst)``."""
    M = np.zeros((mj.nv, mj.nv))
    if hasattr(d, "qM"):
        mujoco.mj_fullM(mj, M, d.qM)
    else:
        mujoco.mj_fullM(mj, d, M)
    return M
