"""The stiff case of ``bench/peers.py``: a chain whose bobs slide on damped stiff springs,
built the same way in mbcomp and in Pinocchio.

N links on hinges about z; link k is a massless rod of length ``L`` along its hinge frame's
x axis, at whose end a slider along the same x axis carries a point mass ``m`` held by a
spring ``c`` (N/m) and a damper ``d`` (N s/m) on the slider's own coordinate ``s`` (force
``-(c s + d ds/dt)``); the next hinge sits on the bob. A spring ``c_tie`` (N/m, rest length
``0.5`` m) ties the last bob to the world origin; gravity ``(0, -g, 0)``. The sliders' modes
are near ``-c/d = -10`` and ``-d/m = -1e5`` 1/s, the pendulum's a few 1/s: stiff. Start:
hinge 0 at 0.6 rad, hinge k at 0.1 k rad, sliders at 1e-3 m, at rest. mbcomp's side is
``models/spring_chain.py`` (also the model of ``tests/solvers/test_stiff_switch.py``).

Coordinates: ``y = [phi_0, s_0, phi_1, s_1, ..., rates in the same order]`` on both sides
(mbcomp's ``j<k>.phi``, ``s<k>.s``; Pinocchio's ``JointModelRZ``, ``JointModelPX`` in tree
order). Pinocchio's right-hand side: the spring-damper forces on the slider coordinates and
the tie's force mapped by the last bob's world-aligned Jacobian, then ``pin.aba``.
"""
import pathlib

import numpy as np

from .cpu_clock import cpu
from .pinocchio_pendulum import available  # the same peer: the same check

MODEL_FILE = pathlib.Path(__file__).resolve().parents[2] / "models" / "spring_chain.py"

__all__ = ["build_model", "build", "available", "start", "state_names", "DEFAULTS"]

DEFAULTS = dict(N=2, c=1e6, d=1e5, m=1.0, L=0.5, c_tie=100.0, tie_length=0.5, g=9.81)




def start(N):
    """``(phi0, s0)`` of every link: rad, m."""
    return [0.6 if k == 0 else 0.1 * k for k in range(N)], [1e-3] * N


def state_names(N):
    q = [n for k in range(N) for n in (f"j{k}.phi", f"s{k}.s")]
    return q + [n for k in range(N) for n in (f"j{k}.w", f"s{k}.v")]


def build_model(N=2, c=1e6, d=1e5, m=1.0, L=0.5, c_tie=100.0, tie_length=0.5, g=9.81):
    """The mbcomp Model: ``models/spring_chain.py`` (components ``j<k>``, ``rod<k>``, ``s<k>``,
    ``bob<k>``, ``k<k>``, ``tie``) with these values."""
    import mbcomp

    chain = mbcomp.load_model_file(str(MODEL_FILE))
    return chain.build(N=N, c=c, d=d, m=m, L=L, c_tie=c_tie, tie_length=tie_length, g=g)


class Peer:
    name = "pinocchio"

    def __init__(self, N, c, d, m, L, c_tie, tie_length, g):
        import pinocchio as pin

        c0 = cpu()
        self.pin, self.N, self.c, self.d = pin, N, c, d
        self.c_tie, self.tie_length = c_tie, tie_length
        model = pin.Model()
        model.gravity = pin.Motion(np.array([0.0, -g, 0.0]), np.zeros(3))
        parent = 0
        for k in range(N):
            jr = model.addJoint(parent, pin.JointModelRZ(), pin.SE3.Identity(), f"j{k}")
            js = model.addJoint(jr, pin.JointModelPX(), pin.SE3(np.eye(3), np.array([L, 0.0, 0.0])), f"s{k}")
            model.appendBodyToJoint(js, pin.Inertia(m, np.zeros(3), np.zeros((3, 3))), pin.SE3.Identity())
            parent = js
        self.last = parent
        self.model, self.data = model, model.createData()
        self.slides = np.arange(1, 2 * N, 2)  # the sliders' indices in q and v
        self.build_seconds = cpu() - c0
        self.note = ""

    def rhs(self, t, y):
        pin, n = self.pin, 2 * self.N
        q, v = y[:n], y[n:]
        tau = np.zeros(n)
        tau[self.slides] = -(self.c * q[self.slides] + self.d * v[self.slides])
        pin.computeJointJacobians(self.model, self.data, q)
        r = self.data.oMi[self.last].translation
        dist = np.sqrt(r @ r)
        F = -self.c_tie * (dist - self.tie_length) * r / dist
        J = pin.getJointJacobian(self.model, self.data, self.last, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        tau += J[:3].T @ F
        return np.concatenate((v, pin.aba(self.model, self.data, q, v, tau)))


def build(N=2, c=1e6, d=1e5, m=1.0, L=0.5, c_tie=100.0, tie_length=0.5, g=9.81):
    return Peer(int(N), c, d, m, L, c_tie, tie_length, g)
