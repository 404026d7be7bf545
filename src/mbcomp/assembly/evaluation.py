"""What one evaluation of a mechanism gives: :class:`Evaluation`, the record every formulation,
solve and column reads at one ``(t, q, u)`` (mass matrix, forces, the constraint rows and
their biases, the frames' jets), whether it came from the numeric path
(:meth:`mbcomp.assembly.system.MultibodySystem.evaluate_numeric`) or a generated program; and
:class:`Rows`, the loop-closure rows alone (what a Newton closure reads,
:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_rows`).

The numeric evaluation is made of two parts that the rows-only one shares, so that its rows
are the full evaluation's bit for bit: :func:`cut_rows` (the holonomic rows from the frames'
jets) and :func:`completed` (the rows masked, the velocity-level rows, the record).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Evaluation", "Rows", "cut_rows", "completed"]


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


@dataclass
class Rows:
    """The loop-closure (holonomic) rows at one ``(t, q, u)``, every row (no row mask): what
    a Newton closure of the positions reads, without the mass matrix and forces.

    Made by :meth:`MultibodySystem.evaluate_rows
    <mbcomp.assembly.system.MultibodySystem.evaluate_rows>`; the full evaluation at the same
    point is :meth:`MultibodySystem.evaluate_from
    <mbcomp.assembly.system.MultibodySystem.evaluate_from>` of it. ``Phi`` (m, rad),
    ``Phid`` (m/s, rad/s), ``C`` (rows x nu) and ``cb`` are those of ``evaluate(t, q, u,
    masked=False)`` bit for bit.

    Attributes
    ----------
    jets : dict or None
        The frames' jets the rows were computed from (numeric rows), else None.
    local : list or None
        Per cut edge ``(edge, row names, local Jacobian)`` (numeric rows), else None.
    evaluation : Evaluation or None
        The evaluator's full unmasked evaluation when it made one to give the rows (a
        generated program, an evaluator without a rows-only path), else None.

    Examples
    --------
    A pendulum closed on itself by a spherical joint at its pivot: three rows, all zero at any
    angle, equal to the full evaluation's.

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass, Spherical
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(n=(0, 0, 1))); rod = m.add("rod", FixedTranslation(r=(1, 0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0)); back = m.add("back", FixedTranslation(r=(-1, 0, 0)))
    >>> pin = m.add("pin", Spherical())
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> m.connect(rod.frame_b, back.frame_a); m.connect(back.frame_b, pin.frame_a); m.connect(pin.frame_b, w.frame_b)
    >>> s = mbcomp.assemble(m); q, u = np.array([0.3]), np.array([0.0])
    >>> rows = s.evaluate_rows(0.0, q, u)
    >>> rows.Phi.shape, bool(np.abs(rows.Phi).max() < 1e-15)
    ((3,), True)
    >>> bool(np.array_equal(rows.C, s.evaluate(0.0, q, u, masked=False).C))
    True
    """

    t: float
    q: np.ndarray
    u: np.ndarray
    Phi: np.ndarray
    Phid: np.ndarray
    C: np.ndarray
    cb: np.ndarray
    jets: dict = None
    local: list = None
    evaluation: object = None

    @classmethod
    def of(cls, ev):
        """The rows of the full unmasked evaluation ``ev`` (kept as :attr:`evaluation`)."""
        return cls(ev.t, ev.q, ev.u, ev.Phi, ev.Phid, ev.C, ev.cb, evaluation=ev)


def cut_rows(system, t, q, u, jets, dt):
    """The :class:`Rows` of ``system``'s cut joints and flange constraints
    (``system.cut_constraints``) at the frames' ``jets``, every row; ``dt`` the arrays'
    dtype (float, or object when traced)."""
    Phi, Phid, Crows, cb, local = [], [], [], [], []
    for e, cons in system.cut_constraints(jets, t, q):
        if not cons:
            continue
        jac = np.array([c.jac for _, c in cons])
        Crows.append(jac.dot(np.concatenate([X for n in e.nodes for X in (jets[n].Jv, jets[n].Jw)])))
        Phi += [c.val for _, c in cons]
        Phid += [c.dot for _, c in cons]
        cb += [c.bias for _, c in cons]
        local.append((e, [n for n, _ in cons], jac))
    C = np.vstack(Crows) if Crows else np.zeros((0, system.nu), dt)
    return Rows(t, q, u, np.array(Phi, dt), np.array(Phid, dt), C, np.array(cb, dt), jets, local)


def completed(system, rows, M, f, masked, dt):
    """The :class:`Evaluation` of ``system`` at the point of ``rows`` (:func:`cut_rows`'s) with
    mass matrix ``M`` and forces ``f``: the holonomic rows masked by ``system.row_mask`` when
    ``masked``, the nonholonomic rows (``system.velocity_constraints``) added."""
    jets, u = rows.jets, rows.u
    C, Phi, Phid, cb = rows.C, rows.Phi, rows.Phid, rows.cb
    if masked and system.row_mask is not None:
        C, Phi, Phid, cb = C[system.row_mask], Phi[system.row_mask], Phid[system.row_mask], cb[system.row_mask]
    Brows, gval, Bb, local_nh = [], [], [], []
    for e, cons in system.velocity_constraints(jets):
        if not cons:
            continue
        jac = np.array([c.jac for _, c in cons])
        a, b = jets[e.node_a], jets[e.node_b]
        Brows.append(jac @ np.vstack((a.Jv, a.Jw, b.Jv, b.Jw)))
        gval += [c.val for _, c in cons]
        Bb += [c.bias for _, c in cons]
        local_nh.append((e, [n for n, _ in cons], jac))
    B = np.vstack(Brows) if Brows else np.zeros((0, system.nu), dt)
    gval = np.array(gval, dt)
    return Evaluation(rows.t, rows.q, u, jets, M, f, Phi, Phid, C, cb, B, B @ u - gval, np.array(Bb, dt), gval,
                      rows.local, local_nh)
