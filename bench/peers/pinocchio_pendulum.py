"""Pinocchio peer for the planar N-link pendulum of ``models/n_link_pendulum.py``.

The same mechanism built in code: N revolute joints about z (``JointModelRZ``), joint k+1
placed at ``(0, -L, 0)`` in link k, each link a uniform rod of mass ``m`` with its centre at
``(0, -L/2, 0)`` and central inertia ``diag(m L^2/12, 0, m L^2/12)``, gravity ``(0, -g, 0)``.
Pinocchio's configuration of a revolute joint is its angle relative to the parent, so
``y = [q, u]`` is mbcomp's state (relative angles, relative rates) unchanged.

``build(N) -> Peer``: ``rhs(t, y)`` returns ``[u, aba(q, u, 0)]`` through ``pin.aba`` called
from Python; ``aba_c_loop(y, batch)`` times ABA in pinocchio's own C++ loop
(``pin.abaInParallel`` on one thread over a batch of identical states: no Python per call),
seconds per ABA.
"""
import numpy as np

from .cpu_clock import cpu

__all__ = ["build", "available"]


def available():
    """``None`` if pinocchio imports, else why not."""
    try:
        import pinocchio  # noqa: F401
    except ImportError as exc:
        return f"pinocchio not installed ({exc}); pip install pin"
    return None


class Peer:
    name = "pinocchio"

    def __init__(self, N, L, m, g):
        import pinocchio as pin

        c0 = cpu()
        self.pin = pin
        model = pin.Model()
        model.gravity = pin.Motion(np.array([0.0, -g, 0.0]), np.zeros(3))
        It = m * L ** 2 / 12.0
        parent = 0
        for k in range(N):
            placement = pin.SE3(np.eye(3), np.array([0.0, -L if k else 0.0, 0.0]))
            jid = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{k + 1}")
            model.appendBodyToJoint(jid, pin.Inertia(m, np.array([0.0, -L / 2, 0.0]), np.diag([It, 0.0, It])),
                                    pin.SE3.Identity())
            parent = jid
        self.model, self.data = model, model.createData()
        self.N = N
        self._tau = np.zeros(model.nv)
        self.build_seconds = cpu() - c0
        self.note = ""

    def rhs(self, t, y):
        N = self.N
        q, u = y[:N], y[N:]
        return np.concatenate((u, self.pin.aba(self.model, self.data, q, u, self._tau)))

    def aba_c_loop(self, y, batch=1000, repeats=5):
        """Median seconds per ABA inside pinocchio's C++ batch loop (one thread)."""
        pin, N = self.pin, self.N
        pool = pin.ModelPool(self.model, 1)
        Q = np.asfortranarray(np.tile(y[:N, None], (1, batch)))
        V = np.asfortranarray(np.tile(y[N:, None], (1, batch)))
        T = np.zeros_like(V)
        A = np.zeros_like(V)
        pin.abaInParallel(1, pool, Q, V, T, A)
        times = []
        for _ in range(repeats):
            c0 = cpu()
            pin.abaInParallel(1, pool, Q, V, T, A)
            times.append((cpu() - c0) / batch)
        return float(np.median(times)), A[:, 0].copy()


#: the longest chain built: ``createData`` of a serial chain grows like N^3 in memory here
#: (145 MB at N = 100, 1.8 GB at 300, ~65 GB predicted at 1000: the OOM killer ended N = 1000)
MAX_LINKS = 400


def build(N, L=0.5, m=1.0, g=9.81):
    if N > MAX_LINKS:
        raise MemoryError(f"not built: pinocchio's Data for a {N}-link chain would need ~{1.8 * (N / 300) ** 3:.0f} GB "
                          f"(grows like N^3: 1.8 GB at N = 300)")
    return Peer(int(N), L, m, g)
