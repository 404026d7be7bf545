"""Consistent initialization: positions, then velocities, by Newton least squares.

Start values the user gave as plain numbers are *fixed*; values wrapped in
:class:`~mbcomp.Guess` (and unset values, guess 0) are free. Positions are corrected by
Gauss-Newton steps of minimum norm in the free directions until the loop-closure
constraints hold; then the free speeds are corrected so that the velocity constraints hold.
At the assembled configuration a rank test (QR with column pivoting) finds redundant
constraint rows, which are dropped and reported.

Examples
--------
>>> from mbcomp import assemble
>>> from mbcomp.initialization import initialize
>>> import importlib.util, pathlib
>>> # see tests/test_initialization.py for complete models
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..errors import InitializationError, Problem

__all__ = ["initialize", "InitialState"]


@dataclass
class InitialState:
    """Consistent start: coordinates ``q``, speeds ``u``, and what initialization decided."""

    q: np.ndarray
    u: np.ndarray
    row_mask: np.ndarray
    dropped: list = field(default_factory=list)  # names of redundant constraint rows
    iterations: int = 0
    rank: int = 0  # rank of the holonomic constraint Jacobian
    nonholonomic: int = 0  # number of velocity-level constraint rows


def _starts(system):
    q = np.zeros(system.nq)
    u = np.zeros(system.nu)
    qfix = np.zeros(system.nu, bool)
    ufix = np.zeros(system.nu, bool)
    cut_fixed = []  # (edge, value q, fixed, value u, fixed) on 1-DOF cut joints
    for e in system.topology.edges:
        if e.kind != "joint" or e.dof == 0 or e.drive:
            continue
        q0, qf, u0, uf = e.comp.start(system.P[e.name])
        if e.q.stop > e.q.start:
            q[e.q], u[e.u], qfix[e.u], ufix[e.u] = q0, u0, qf, uf
        elif e.name in system.topology.cut and (np.any(qf) or np.any(uf)):
            cut_fixed.append((e, q0, qf, u0, uf))
    return q, u, qfix, ufix, cut_fixed


def _position_names(system):
    """For each speed index, the name of the position coordinate it moves.

    Joints whose coordinates and speeds pair one to one (hinges, sliders) give the
    coordinate name (``crank_joint.phi``); joints with a quaternion (spherical, free
    motion) give ``"<joint> (start position/orientation)"``.
    """
    names = [""] * system.nu
    for e in system.topology.tree:
        if e.kind != "joint" or e.drive or e.dof == 0:
            continue
        c = e.comp
        qn = [f"{e.name}.{n}" for n, _ in c.coordinates]
        un = range(e.u.start, e.u.stop)
        if c.nq == c.nu:
            for i, n in zip(un, qn):
                names[i] = n
        else:
            for i in un:
                names[i] = f"{e.name} (start position/orientation)"
    return names


def _measure_rows(system, t, q, u, cut_fixed, which):
    """Residuals and Jacobian rows (finite differences on the speeds) for start values fixed
    on cut joints (1-DOF joints only)."""
    res, rows, names = [], [], []
    for e, q0, qf, u0, uf in cut_fixed:
        if e.dof != 1:
            raise InitializationError([Problem(e.name, "start values are fixed on a multi-DOF joint that closes a loop",
                                               "fix start values on tree joints instead, or mark these as Guess(...)")])
        flags, target = (qf, q0) if which == "q" else (uf, u0)
        if not np.any(flags):
            continue

        def meas(qq, uu):
            jets = system.kinematics(t, qq, uu)
            return np.array(e.comp.measure(jets[e.node_a], jets[e.node_b], system.P[e.name]))

        m0 = meas(q, u)
        k = 0 if which == "q" else 1
        res.append(m0[k] - target[0])
        row = np.zeros(system.nu)
        h = 1e-7
        for i in range(system.nu):
            du = np.zeros(system.nu)
            du[i] = h
            if which == "q":
                row[i] = (meas(system.increment(q, du), u)[0] - meas(system.increment(q, -du), u)[0]) / (2 * h)
            else:
                row[i] = (meas(q, u + du)[1] - meas(q, u - du)[1]) / (2 * h)
        rows.append(row)
        names.append(f"{e.name}.{e.comp.coordinates[0][0] if which == 'q' else e.comp.speeds[0][0]}")
    return np.array(res), np.array(rows).reshape(len(rows), system.nu), names


def _rank(A, tol=1e-9):
    if A.size == 0:
        return 0
    s = np.linalg.svd(A, compute_uv=False)
    return int(np.sum(s > tol * max(1.0, s[0])))


def initialize(system, t0=0.0, tol=1e-12, max_iter=60):
    """Consistent ``(q, u)`` honouring fixed start values; sets ``system.row_mask``.

    Raises
    ------
    InitializationError
        When fixed start values over-specify the mechanism (naming the coordinates and cut
        joints involved) or when a loop cannot be closed (naming the cut joints).
    """
    system.row_mask = None
    q, u, qfix, ufix, cut_fixed = _starts(system)
    q = system.normalize(q)
    free = ~qfix
    names_u = system.u_names
    it = 0
    scale = 1.0

    def residual(qq):
        ev = system.evaluate(t0, qq, u, masked=False)
        r2, C2, _ = _measure_rows(system, t0, qq, u, cut_fixed, "q")
        return np.concatenate((ev.Phi, r2)), np.vstack((ev.C, C2)), ev

    def newton(q, free):
        r, C, ev = residual(q)
        norm = np.linalg.norm(r) if r.size else 0.0
        it = 0
        while r.size and norm > tol * scale and it < max_iter:
            it += 1
            dfree = np.linalg.lstsq(C[:, free], -r, rcond=None)[0] if free.any() else np.zeros(0)
            du = np.zeros(system.nu)
            du[free] = dfree
            step = 1.0
            while True:
                qn = system.increment(q, step * du)
                rn, Cn, evn = residual(qn)
                nn = np.linalg.norm(rn)
                if nn < norm or step < 1e-4:
                    break
                step *= 0.5
            if nn >= norm:
                break
            q, r, C, ev, norm = qn, rn, Cn, evn, nn
        return q, r, C, ev, norm, it

    q_start = q
    q, r, C, ev, norm, it = newton(q, free)
    n_phi = ev.Phi.size
    # --- rank analysis at the reached configuration ---------------------------------------
    Cphi = ev.C
    rank_all = _rank(Cphi)
    mask = np.ones(n_phi, bool)
    dropped = []
    row_names = system.constraint_names(all_rows=True)
    if n_phi and rank_all < n_phi:
        _, _, piv = sla.qr(Cphi.T, pivoting=True, mode="economic")
        keep = np.sort(piv[:rank_all])
        mask[:] = False
        mask[keep] = True
        dropped = [row_names[i] for i in range(n_phi) if not mask[i]]
    if r.size and norm > 1e-8 * scale:
        bad_rows = sorted({row_names[i].rsplit(".", 1)[0] for i in range(n_phi) if abs(r[i]) > 1e-8})
        pos_names = _position_names(system)
        fixed = list(dict.fromkeys(pos_names[i] for i in range(system.nu)
                                   if qfix[i] and np.any(np.abs(C[:, i]) > 1e-12)))
        fixed += [f"{c[0].name}.{c[0].comp.coordinates[0][0]}" for c in cut_fixed if np.any(c[2])]
        if fixed and newton(q_start, np.ones(system.nu, bool))[4] <= 1e-8 * scale:
            raise InitializationError([Problem(
                ", ".join(fixed),
                f"fixed start values over-specify the mechanism: with them the loop through "
                f"{', '.join(bad_rows) or 'the cut joints'} cannot close (residual {norm:.3g}), without them it can",
                "fix fewer start values: wrap the others in Guess(...), e.g. phi0=Guess(0.3)")])
        raise InitializationError([Problem(
            ", ".join(bad_rows),
            f"the kinematic loop cannot be assembled (closure residual {norm:.3g} after {it} Newton steps)",
            "check lengths and joint axes of the loop (can it close at all?) or give better Guess(...) start values")])
    # --- velocities ------------------------------------------------------------------------
    system.row_mask = mask
    ev = system.evaluate(t0, q, u)
    r2, C2, _ = _measure_rows(system, t0, q, u, cut_fixed, "u")
    Cv = np.vstack((ev.A, C2))
    rv = np.concatenate((ev.Phid, ev.Psi, r2))
    ufree = ~ufix
    if rv.size and np.linalg.norm(rv) > 1e-12:
        if ufree.any():
            du = np.linalg.lstsq(Cv[:, ufree], -rv, rcond=None)[0]
            u = u.copy()
            u[ufree] += du
        ev = system.evaluate(t0, q, u)
        rv2 = np.concatenate((ev.Phid, ev.Psi, _measure_rows(system, t0, q, u, cut_fixed, "u")[0]))
        if np.linalg.norm(rv2) > 1e-8 * max(1.0, np.linalg.norm(u)):
            fixed = [names_u[i] for i in range(system.nu) if ufix[i] and np.any(np.abs(Cv[:, i]) > 1e-12)]
            raise InitializationError([Problem(
                ", ".join(fixed) or "start speeds",
                f"fixed start speeds over-specify the mechanism (velocity constraint residual {np.linalg.norm(rv2):.3g})",
                "fix fewer start speeds: wrap the others in Guess(...), e.g. w0=Guess(0.0)")])
    _check_inertia(system, ev)
    return InitialState(q, u, mask, dropped, it, _rank(ev.C), ev.B.shape[0])


def _check_inertia(system, ev):
    """The mass matrix restricted to the admissible motions must be positive definite."""
    if system.nu == 0:
        return
    C = ev.A
    N = sla.null_space(C) if C.size else np.eye(system.nu)
    if N.shape[1] == 0:
        return
    Mr = N.T @ ev.M @ N
    w, V = np.linalg.eigh(0.5 * (Mr + Mr.T))
    scale = max(1.0, np.abs(np.diag(ev.M)).max())
    if w[0] <= 1e-12 * scale:
        mode = N @ V[:, 0]
        who = [system.u_names[i] for i in np.argsort(-np.abs(mode)) if abs(mode[i]) > 1e-6][:4]
        raise InitializationError([Problem(
            ", ".join(who), "these motions carry no mass or inertia, so their accelerations are undetermined",
            "give the bodies they move mass/inertia, or prescribe the motion with a drive")],
            header="the mechanism has massless degrees of freedom")
