"""A 3-D serial chain built the same way in mbcomp and in Pinocchio (``bench/derivatives.py``).

N links on revolute joints whose axes cycle through x, y, z of the parent link's frame
(joint k about axis ``(k - 1) mod 3``), so the motion is spatial: every joint's axis is turned
by the joints above it and every link's inertia enters in full 3-D. Joint k+1 sits at
``(0, -L, 0)`` in link k; each link is a box of mass ``m``, length ``L`` along its -y axis and
square section ``W x W``, its centre at ``(0, -L/2, 0)`` and central inertia
``m/12 diag(L^2 + W^2, 2 W^2, L^2 + W^2)`` (three different moments would do as well; these
are a slender box's); gravity ``(0, -g, 0)``.

Coordinates: both sides use the joints' relative angles and rates, so ``y = [q, u]`` is the
same vector for mbcomp (``joint<k>.phi``, ``joint<k>.w``) and Pinocchio (``JointModelRX/RY/RZ``:
``q``, ``v``).

``build_model(N)`` gives the mbcomp Model; ``build(N) -> Peer`` the Pinocchio model and data
(``Peer.model``, ``Peer.data``, ``Peer.pin``, ``Peer.rhs(t, y)`` through ``pin.aba``).
"""
import numpy as np

from .cpu_clock import cpu

__all__ = ["build", "build_model", "available", "AXES"]

AXES = ("x", "y", "z")
L_DEFAULT, W_DEFAULT, M_DEFAULT, G_DEFAULT = 0.5, 0.05, 1.0, 9.81


def available():
    """``None`` if pinocchio imports, else why not."""
    try:
        import pinocchio  # noqa: F401
    except ImportError as exc:
        return f"pinocchio not installed ({exc}); pip install pin"
    return None


def box_inertia(m, L, W):
    """Central inertia (kg m^2) of a box of mass ``m`` (kg), length ``L`` along y and square
    section ``W`` (m)."""
    return m / 12.0 * np.diag([L * L + W * W, 2.0 * W * W, L * L + W * W])


def build_model(N, L=L_DEFAULT, W=W_DEFAULT, m=M_DEFAULT, g=G_DEFAULT, phi0=0.3, w0=0.0):
    """The mbcomp Model of the chain (components ``joint<k>``, ``link<k>``, ``tip<k>``)."""
    from mbcomp import Model
    from mbcomp.library import FixedTranslation, Revolute, RigidBody, World

    mdl = Model()
    world = mdl.add("world", World(g=(0.0, -g, 0.0)))
    prev = world.frame_b
    for k in range(1, N + 1):
        axis = np.eye(3)[(k - 1) % 3]
        joint = mdl.add(f"joint{k}", Revolute(n=tuple(axis), phi0=phi0, w0=w0))
        link = mdl.add(f"link{k}", RigidBody(m=m, r_cm=(0.0, -L / 2, 0.0), I=box_inertia(m, L, W)))
        mdl.connect(prev, joint.frame_a)
        mdl.connect(joint.frame_b, link.frame_a)
        if k < N:
            tip = mdl.add(f"tip{k}", FixedTranslation(r=(0.0, -L, 0.0)))
            mdl.connect(joint.frame_b, tip.frame_a)
            prev = tip.frame_b
    return mdl


class Peer:
    name = "pinocchio"

    def __init__(self, N, L, W, m, g):
        import pinocchio as pin

        c0 = cpu()
        self.pin = pin
        model = pin.Model()
        model.gravity = pin.Motion(np.array([0.0, -g, 0.0]), np.zeros(3))
        joints = (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)
        parent = 0
        for k in range(N):
            placement = pin.SE3(np.eye(3), np.array([0.0, -L if k else 0.0, 0.0]))
            jid = model.addJoint(parent, joints[k % 3](), placement, f"joint{k + 1}")
            model.appendBodyToJoint(jid, pin.Inertia(m, np.array([0.0, -L / 2, 0.0]), box_inertia(m, L, W)),
                                    pin.SE3.Identity())
            parent = jid
        self.model, self.data = model, model.createData()
        self.N = N
        self._tau = np.zeros(model.nv)
        self.build_seconds = cpu() - c0
        self.note = ""

    def rhs(self, t, y):
        N = self.N
        return np.concatenate((y[N:], self.pin.aba(self.model, self.data, y[:N], y[N:], self._tau)))


def build(N, L=L_DEFAULT, W=W_DEFAULT, m=M_DEFAULT, g=G_DEFAULT):
    return Peer(int(N), L, W, m, g)
