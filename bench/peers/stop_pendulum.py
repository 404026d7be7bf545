"""The event case of ``bench/peers.py``: a pendulum falling onto a rigid stop, in Pinocchio
with a hand-written scipy event loop.

The mechanism is ``bench/events.py``'s ``pendulum``: a point mass of 1 kg on a massless rod of
1 m, hinged about z, gravity ``(0, -9.81, 0)``, released at rest at 0.8 rad onto a stop at
0 rad (``Revolute(limits=(0, 3), restitution=0.7)`` in mbcomp) for 5 s: five impacts whose
times are known in closed form (``events.pendulum_times``).

The peer: Pinocchio's ABA as ``rhs`` (``JointModelRZ``, the mass at ``(0, -1, 0)``) in
``solve_ivp`` with the event ``phi = 0`` (terminal, falling); at each event the run restarts
from ``phi = 0``, ``w+ = -e w-`` (Newton's restitution at the stop), what a user of an
explicit-ODE library writes. ``impact_times(method, rtol, atol)`` returns the located times.
"""
import numpy as np
from scipy.integrate import solve_ivp

from .cpu_clock import cpu
from .pinocchio_pendulum import available  # the same peer: the same check

__all__ = ["build", "available"]




class Peer:
    name = "pinocchio"

    def __init__(self, length, mass, g, e, phi0, t_end):
        import pinocchio as pin

        c0 = cpu()
        self.pin, self.e, self.phi0, self.t_end = pin, e, phi0, t_end
        model = pin.Model()
        model.gravity = pin.Motion(np.array([0.0, -g, 0.0]), np.zeros(3))
        jid = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "hinge")
        model.appendBodyToJoint(jid, pin.Inertia(mass, np.array([0.0, -length, 0.0]), np.zeros((3, 3))),
                                pin.SE3.Identity())
        self.model, self.data = model, model.createData()
        self._tau = np.zeros(1)
        self.build_seconds = cpu() - c0

    def rhs(self, t, y):
        return np.concatenate((y[1:], self.pin.aba(self.model, self.data, y[:1], y[1:], self._tau)))

    def impact_times(self, method, rtol, atol, max_impacts=100):
        """``(times, nfev, message)``: the impacts located in ``[0, t_end]``."""
        def hit(t, y):
            return y[0]
        hit.terminal, hit.direction = True, -1.0
        t, y, out, nfev = 0.0, np.array([self.phi0, 0.0]), [], 0
        while t < self.t_end and len(out) < max_impacts:
            sol = solve_ivp(self.rhs, (t, self.t_end), y, method=method, rtol=rtol, atol=atol, events=hit)
            nfev += sol.nfev
            if sol.status < 0:
                return out, nfev, sol.message
            if sol.status == 0:
                break
            t = float(sol.t_events[0][0])
            w = float(sol.y_events[0][0][1])
            out.append(t)
            y = np.array([0.0, -self.e * w])
        return out, nfev, ""


def build(length=1.0, mass=1.0, g=9.81, e=0.7, phi0=0.8, t_end=5.0):
    return Peer(length, mass, g, e, phi0, t_end)
