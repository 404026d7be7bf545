"""What one evaluation of a mechanism gives: :class:`Evaluation`, the record every formulation,
solve and column reads at one ``(t, q, u)`` (mass matrix, forces, the constraint rows and
their biases, the frames' jets), whether it came from the numeric path
(:meth:`mbcomp.assembly.system.MultibodySystem.evaluate_numeric`) or a generated program.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Evaluation"]


@dataclass
class Evaluation:
    """Everything the formulations need at one ``(t, q, u)``."""

    t: float
    q: np.ndarray
    u: np.ndarray
    jets: dict
    M: np.ndarray
    f: np.ndarray
    Phi: np.ndarray  # position constraints (m rows)
    Phid: np.ndarray  # their time derivative
    C: np.ndarray  # (m, nu)
    cb: np.ndarray  # bias: d2Phi/dt2 = C du + cb
    B: np.ndarray  # nonholonomic rows (k, nu): B u = b
    b: np.ndarray
    Bb: np.ndarray  # bias: d/dt(B u - b) = B du + Bb
    Psi: np.ndarray  # nonholonomic (velocity-constraint) residual B u - b
    local: list  # per cut edge: (edge, rows, jac (r,12))
    local_nh: list  # per edge with velocity constraints: (edge, rows, jac (k,12))

    @property
    def A(self):
        """All constraint rows acting on du/dt: holonomic ``C`` then nonholonomic ``B``."""
        return np.vstack((self.C, self.B)) if self.B.size else self.C
