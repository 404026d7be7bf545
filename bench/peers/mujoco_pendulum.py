"""MuJoCo peer for the planar N-link pendulum of ``models/n_link_pendulum.py``.

An MJCF string generated for N links: nested bodies, body k+1 at ``(0, -L, 0)`` in body k,
each with a ``hinge`` about z at its origin and an ``<inertial>`` of mass ``m`` at
``(0, -L/2, 0)`` with ``diaginertia`` ``(m L^2/12, eps, m L^2/12)``; gravity ``(0, -g, 0)``;
no damping, armature, limits or geoms (so no contacts). ``rhs(t, y)`` writes ``qpos = q``,
``qvel = u`` and calls ``mj_forward``, whose ``qacc`` is ``du/dt`` (the integrator option is
never used). A hinge's ``qpos`` is its angle relative to the parent body, so ``y = [q, u]``
is mbcomp's state unchanged.

Two departures, both without effect on the motion:

* ``eps = 1e-9 m L^2/12`` instead of 0 about the rod's own axis: MuJoCo's compiler refuses a
  moving body with a zero principal inertia ("mass and inertia of moving bodies must be
  larger than mjMINVAL"). The angular velocity is always along z, a principal axis, so the
  inertia about y never enters the equations of motion.
* Above ``XML_MAX_LINKS`` links the same bodies are built with ``mujoco.MjSpec`` in code:
  MuJoCo's XML parser (tinyxml2) refuses elements nested deeper than about 500
  (XML_ELEMENT_DEPTH_EXCEEDED), and a chain is one level of nesting per link.
"""
import numpy as np

from .cpu_clock import cpu

__all__ = ["build", "available", "mjcf"]

#: the deepest chain written as MJCF (tinyxml2's nesting limit is 500 elements)
XML_MAX_LINKS = 400
EPS = 1e-9


def available():
    try:
        import mujoco  # noqa: F401
    except ImportError as exc:
        return f"mujoco not installed ({exc}); pip install mujoco"
    return None


def mjcf(N, L=0.5, m=1.0, g=9.81):
    """The MJCF text of the N-link pendulum (full float precision)."""
    It = m * L ** 2 / 12.0
    out = [f'<mujoco model="n_link_pendulum"><option gravity="0 {-g!r} 0"/><worldbody>']
    for k in range(N):
        out.append(f'<body name="link{k + 1}" pos="0 {-L if k else 0.0!r} 0">'
                   f'<joint name="joint{k + 1}" type="hinge" axis="0 0 1" pos="0 0 0"/>'
                   f'<inertial pos="0 {-L / 2!r} 0" mass="{m!r}" diaginertia="{It!r} {EPS * It!r} {It!r}"/>')
    out.append("</body>" * N + "</worldbody></mujoco>")
    return "\n".join(out)


def _spec_model(N, L, m, g):
    import mujoco

    It = m * L ** 2 / 12.0
    spec = mujoco.MjSpec()
    spec.option.gravity = [0.0, -g, 0.0]
    parent = spec.worldbody
    for k in range(N):
        body = parent.add_body(name=f"link{k + 1}", pos=[0.0, -L if k else 0.0, 0.0], mass=m, ipos=[0.0, -L / 2, 0.0],
                               inertia=[It, EPS * It, It], explicitinertial=True)
        body.add_joint(name=f"joint{k + 1}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0])
        parent = body
    return spec.compile()


class Peer:
    name = "mujoco"

    def __init__(self, N, L, m, g):
        import mujoco

        c0 = cpu()
        self.mj = mujoco
        if N <= XML_MAX_LINKS:
            self.model = mujoco.MjModel.from_xml_string(mjcf(N, L, m, g))
            self.note = ""
        else:
            self.model = _spec_model(N, L, m, g)
            self.note = f"built with MjSpec (MJCF nesting > {XML_MAX_LINKS} links is refused by the XML parser)"
        self.data = mujoco.MjData(self.model)
        self.N = N
        self.build_seconds = cpu() - c0

    def rhs(self, t, y):
        d, N = self.data, self.N
        d.time = t
        d.qpos[:] = y[:N]
        d.qvel[:] = y[N:]
        self.mj.mj_forward(self.model, d)
        return np.concatenate((y[N:], d.qacc))


def build(N, L=0.5, m=1.0, g=9.81):
    return Peer(int(N), L, m, g)
