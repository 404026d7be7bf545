"""``peers/chain3d.py``'s 3-D chain as MJCF for MuJoCo (and so for the MuJoCo + C DOP853
construct, ``peers/mujoco_dop853.py``).

Joint k (1-based) is a ``hinge`` about axis ``(k - 1) mod 3`` of its body (x, y, z in turn),
body k+1 at ``(0, -L, 0)`` in body k, each body a box of mass ``m`` with its centre at
``(0, -L/2, 0)`` and central inertia ``chain3d.box_inertia(m, L, W)`` (diagonal in the body's
axes: ``diaginertia``); gravity ``(0, -g, 0)``. ``qpos`` are the relative hinge angles, as
mbcomp's ``joint<k>.phi`` and Pinocchio's ``q``.
"""
import numpy as np

from .chain3d import G_DEFAULT, L_DEFAULT, M_DEFAULT, W_DEFAULT, box_inertia

__all__ = ["mjcf"]


def mjcf(N, L=L_DEFAULT, W=W_DEFAULT, m=M_DEFAULT, g=G_DEFAULT):
    """The MJCF text of the N-link 3-D chain (full float precision)."""
    d = [float(x) for x in np.diag(box_inertia(m, L, W))]
    out = [f'<mujoco model="chain3d"><option gravity="0 {-g!r} 0"/><worldbody>']
    for k in range(N):
        axis = " ".join("1" if i == k % 3 else "0" for i in range(3))
        out.append(f'<body name="link{k + 1}" pos="0 {-L if k else 0.0!r} 0">'
                   f'<joint name="joint{k + 1}" type="hinge" axis="{axis}" pos="0 0 0"/>'
                   f'<inertial pos="0 {-L / 2!r} 0" mass="{m!r}" diaginertia="{d[0]!r} {d[1]!r} {d[2]!r}"/>')
    out.append("</body>" * N + "</worldbody></mujoco>")
    return "\n".join(out)
