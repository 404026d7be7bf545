"""Recursive multibody algorithms on the spanning tree: CRBA, RNEA and the articulated-body
algorithm, in spatial vectors about the world origin.

The jet recursion (:meth:`~mbcomp.assembly.system.MultibodySystem.kinematics`) carries a
3 x nu Jacobian per frame, and the mass matrix is then the sum over bodies of ``J^T M_b J``:
O(N^2) work per frame and O(N^3) for ``M`` on an N-link chain. The algorithms here walk the
same tree with the same joint contracts (:meth:`MultibodySystem.child_jet` with jets of the
joint's own width), but keep per joint only its motion subspace ``S`` (6 x k), so that

* the generalized forces ``f`` are ``S^T`` times the wrenches summed from the leaves up
  (RNEA; O(N));
* ``M`` is the composite-rigid-body algorithm (CRBA; O(N d) entries, d the tree's depth);
* ``M x = S^T W`` is solved by the articulated-body algorithm (ABA; O(N) per right-hand
  side after an O(N) factorization), which gives the Lagrange index-1 accelerations of a
  tree with ``m`` constraint rows in O(N + m d): one solve for the unconstrained
  accelerations, the ``m x m`` matrix ``A M^-1 A^T`` from the rows' own paths, and one solve
  with the constraint wrenches added.

Spatial vectors
---------------
All spatial quantities are resolved in world coordinates *about the world origin* O, so no
coordinate transforms appear in the recursions (adding a child's inertia or wrench to its
parent is a plain sum):

* a twist ``V = (w, v_O)``: angular velocity (rad/s) and the velocity (m/s) of the body
  point at O, ``v_O = v_P + r_P x w`` for a point P at ``r_P``;
* a wrench ``W = (tau_O, F)``: the moment about O (N m) and the force (N),
  ``tau_O = tau_P + r_P x F``; power is ``W . V``;
* a body's spatial inertia about O, for mass m (kg), centre of mass c (m) and inertia
  ``I_c`` about c (kg m^2, world axes)::

      I_O = [[I_c - m [c]x [c]x,  m [c]x],
             [     -m [c]x     ,  m 1  ]]

Links
-----
A *link* is the set of frames rigidly moved by one tree joint with speeds (everything down
the tree up to the next joint with speeds). :class:`~mbcomp.assembly.topology.TreeLinks`
(a topology's :attr:`~mbcomp.assembly.topology.Topology.links`) numbers them in tree order
(parents first); frames fixed to the ground have link -1. Drives make their joint a rigid
(rheonomic) part of the parent link: its motion is in the jets' bias terms.

Everything here is plain numpy on float *or* traced (object) arrays, so it runs numerically
and is printed into the generated programs (:mod:`mbcomp.codegen`); decisions on values
(a pivot that must be positive) are comparisons, which become runtime guards when traced.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.assembly.recursive import lagrange_accelerations, tree_evaluation
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> s = mbcomp.assemble(m)
>>> ev = tree_evaluation(s, 0.0, np.array([0.5]), np.array([1.0]))
>>> float(ev.M[0, 0]), round(float(ev.f[0]), 9)         # m l^2, -m g l sin(phi)
(2.0, -9.406329067)
>>> round(float(lagrange_accelerations(s, 0.0, np.array([0.5]), np.array([1.0]))[0]), 9)  # -g sin(phi)/l
-4.703164534
"""
from __future__ import annotations

import numpy as np

from .jets import FrameJet, is_traced
from .flange_rows import rotor_wrench, rotors
from .topology import ROOT
from ..geometry.kinematics import cross, skew

__all__ = ["SingularTree", "tree_links", "tree_pass", "tree_evaluation", "articulated",
           "tree_solve", "constraint_rows", "lagrange_accelerations", "lagrange_solution", "PIVOT_TOL"]

#: a Cholesky pivot at or below ``PIVOT_TOL`` times the matrix's trace counts as singular
PIVOT_TOL = 1e-13
#: ... and for the constraint rows' ``A M^-1 A^T``, at or below ``ROWS_PIVOT_TOL``: the rows
#: are losing rank (pivot ~ sigma^2 of the mass-weighted rows: a smallest relative singular
#: value of about 1e-2). The recursive solve then declines -- a guard when traced, so the
#: compiled engine ends its stretch there and the driver steps the dense solve, watching every
#: step: kept rows that degrade while others would not are chosen again
#: (:class:`mbcomp.simulation.rows.RowChoice`), a position where no choice keeps the rank is
#: located and reported (:class:`mbcomp.simulation.monitors.ConstraintRank`)
ROWS_PIVOT_TOL = 1e-4


class SingularTree(ArithmeticError):
    """A matrix of the recursion (a joint's articulated inertia ``S^T I^A S``, or the
    constraint rows' ``A M^-1 A^T``) is singular: the caller falls back to the dense solve,
    which gives the diagnosis (massless motion, redundant rows) or a minimum-norm answer."""


def tree_links(system):
    """The :class:`~mbcomp.assembly.topology.TreeLinks` of ``system``'s topology (made once
    per topology: :attr:`~mbcomp.assembly.topology.Topology.links`)."""
    return system.topology.links


def _dtype(*xs):
    return object if any(is_traced(x) for x in xs) else float


def _narrow(J):
    """A jet's pose and motion without Jacobian columns."""
    z = np.zeros((3, 0))
    return FrameJet(J.R, J.r, J.w, J.v, z, z, J.alpha, J.a)


class TreePass:
    """One kinematic pass down the tree at ``(t, q, u)`` (see :func:`tree_pass`).

    Attributes
    ----------
    jets : dict
        Frame node -> :class:`~mbcomp.assembly.jets.FrameJet` with no Jacobian columns
        (pose, velocity and bias acceleration only).
    S : list of ndarray (6, k)
        Each link's motion subspace: the twist about O per unit joint speed.
    I : list of ndarray (6, 6)
        Each link's own spatial inertia about O (its bodies' sum).
    W : list of ndarray (6,)
        Each link's own bias wrench about O: gravity, applied forces and the inertial
        (velocity-product) wrench ``-dh/dt`` at ``du/dt = 0``.
    """

    def __init__(self, links, jets, S, I, W, dt, t=0.0, q=None):
        self.links, self.jets, self.S, self.I, self.W, self.dt = links, jets, S, I, W, dt
        self.t, self.q = t, q  # for the rows of flange constraints (assembly/flange_rows.py)


def _link_jets(system, links, t, q, u):
    """The narrow jets of every frame and the links' motion subspaces ``S``."""
    jets = {ROOT: FrameJet.ground(0)}
    S = []
    for e in system.topology.tree:
        pj = jets[e.parent]
        k = e.u.stop - e.u.start
        if k == 0:
            jets[e.child] = system.child_jet(e, pj, t, q, u, slice(0, 0))
            continue
        z = np.zeros((3, k))
        cj = system.child_jet(e, FrameJet(pj.R, pj.r, pj.w, pj.v, z, z, pj.alpha, pj.a), t, q, u, slice(0, k))
        # the columns give the twist of the child frame's origin; about O: v_O = v_c + r_c x w
        S.append(np.vstack((cj.Jw, cj.Jv + skew(cj.r) @ cj.Jw)))
        jets[e.child] = _narrow(cj)
    return jets, S


def _body_terms(system, links, jets, I, W):
    """Add every body's spatial inertia and bias wrench (gravity and inertial) to its link."""
    g = system.g
    for path, comp, node in system.topology.bodies:
        i = links.link_of.get(node, -1)
        if i < 0:
            continue
        J = jets[node]
        m, rho, Iw = system.body_inertia(comp, path, J)
        c = J.r + rho
        Cx = skew(c)
        I[i] = I[i] + np.block([[Iw - m * (Cx @ Cx), m * Cx], [-m * Cx, m * np.eye(3)]])
        a_c = J.a + cross(J.alpha, rho) + cross(J.w, cross(J.w, rho))
        F = m * (g - a_c)
        tau = cross(c, F) - (Iw @ J.alpha + cross(J.w, Iw @ J.w))
        W[i] = W[i] + np.concatenate((tau, F))
    for node, Iw, gyro in rotors(system, jets):  # a rotor J n n^T: no mass, so no force
        i = links.link_of.get(node, -1)
        if i >= 0:
            z = np.zeros((3, 3))
            I[i] = I[i] + np.block([[Iw, z], [z, z]])
            W[i] = W[i] + np.concatenate((-rotor_wrench(jets[node], Iw, gyro), np.zeros(3)))


def tree_pass(system, t, q, u):
    """The kinematic pass of the recursive algorithms: a :class:`TreePass` holding the frames'
    poses and motions, the links' motion subspaces ``S``, spatial inertias ``I`` and bias
    wrenches ``W`` (gravity, applied forces of force and flange elements, inertial terms)."""
    links = tree_links(system)
    dt = _dtype(t, q, u)
    jets, S = _link_jets(system, links, t, q, u)
    I = [np.zeros((6, 6), dt) for _ in range(links.n)]
    W = [np.zeros(6, dt) for _ in range(links.n)]
    _body_terms(system, links, jets, I, W)
    for node, (F, T) in system.applied(t, q, u, jets).items():
        i = links.link_of.get(node, -1)
        if i >= 0:
            W[i] = W[i] + np.concatenate((T + cross(jets[node].r, F), F))
    return TreePass(links, jets, S, I, W, dt, t, q)


def _summed(links, vals):
    """Per link, the sum of ``vals`` over its subtree (children are after their parents)."""
    out = list(vals)
    for i in range(links.n - 1, -1, -1):
        p = links.parent[i]
        if p >= 0:
            out[p] = out[p] + out[i]
    return out


def generalized_forces(tp, nu):
    """``f = S^T W^C``: the generalized forces from the subtree-summed bias wrenches (RNEA)."""
    f = np.zeros(nu, tp.dt)
    for i, WC in enumerate(_summed(tp.links, tp.W)):
        f[tp.links.cols[i]] = tp.S[i].T @ WC
    return f


def mass_matrix(tp, nu):
    """``M`` by the composite-rigid-body algorithm: ``M[i, j] = S_i^T I^C_j S_j`` for ``i`` an
    ancestor of (or equal to) ``j``, zero between links on different branches."""
    links = tp.links
    M = np.zeros((nu, nu), tp.dt)
    for j, IC in enumerate(_summed(links, tp.I)):
        F = IC @ tp.S[j]
        cj = links.cols[j]
        for i in links.ancestors(j):
            blk = tp.S[i].T @ F
            M[links.cols[i], cj] = blk
            if i != j:
                M[cj, links.cols[i]] = blk.T
    return M


def _row_entries(links, jets, edge, jac):
    """A constraint row's gradient w.r.t. the local twists ``(v_a, w_a, v_b, w_b)`` as
    spatial covectors on the links of ``edge``'s two frames: ``[(link, (c_w, c_v))]`` (a flange
    constraint's rows: over the frames ``edge.nodes``, 6 columns each)."""
    out = []
    for slot, node in enumerate(edge.nodes):
        i = links.link_of.get(node, -1)
        if i < 0:
            continue
        cv, cw = jac[6 * slot: 6 * slot + 3], jac[6 * slot + 3: 6 * slot + 6]
        out.append((i, np.concatenate((cw + cross(jets[node].r, cv), cv))))
    return out


def constraint_rows(system, tp, masked=True):
    """The constraint rows at a :class:`TreePass`: ``(holonomic, nonholonomic)``, each a list
    of ``(entries, val, dot, bias)`` per row, ``entries`` as in :func:`_row_entries`
    (holonomic rows masked by ``system.row_mask`` when ``masked``)."""
    links, jets = tp.links, tp.jets
    hol = [(_row_entries(links, jets, e, c.jac), c.val, c.dot, c.bias)
           for e, cons in system.cut_constraints(jets, tp.t, tp.q) for _, c in cons]
    if masked and system.row_mask is not None:
        hol = [r for r, keep in zip(hol, system.row_mask) if keep]
    nh = [(_row_entries(links, jets, e, c.jac), c.val, c.dot, c.bias)
          for e, cons in system.velocity_constraints(jets) for _, c in cons]
    return hol, nh


def _rows_dense(tp, rows, nu):
    """The rows' Jacobian w.r.t. ``u``: each covector times the motion subspaces on its path."""
    A = np.zeros((len(rows), nu), tp.dt)
    for r, (entries, *_) in enumerate(rows):
        for i, cov in entries:
            for j in tp.links.ancestors(i):
                A[r, tp.links.cols[j]] = A[r, tp.links.cols[j]] + cov @ tp.S[j]
    return A


def tree_evaluation(system, t, q, u, masked=True):
    """The :class:`~mbcomp.assembly.system.Evaluation` at ``(t, q, u)`` by the recursive
    algorithms (CRBA for ``M``, RNEA for ``f``, constraint rows along their paths): the same
    values as :meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_numeric` to rounding, in
    O(N d) work instead of O(N^3). ``jets``, ``local`` and ``local_nh`` are None (reactions
    use the numeric evaluation)."""
    from .system import Evaluation

    nu = system.nu
    tp = tree_pass(system, t, q, u)
    hol, nh = constraint_rows(system, tp, masked)
    dt = tp.dt
    C, B = _rows_dense(tp, hol, nu), _rows_dense(tp, nh, nu)
    Phi, Phid, cb = (np.array([r[k] for r in hol], dt) for k in (1, 2, 3))
    Psi, Bb = np.array([r[1] for r in nh], dt), np.array([r[3] for r in nh], dt)
    return Evaluation(t, q, u, None, mass_matrix(tp, nu), generalized_forces(tp, nu), Phi, Phid, C, cb, B,
                      B @ u - Psi, Bb, Psi, None, None)


# --- the articulated-body algorithm -------------------------------------------------------
def _chol_inverse(D, what):
    """Inverse of a small symmetric positive definite matrix by a guarded Cholesky."""
    k = D.shape[0]
    if k == 1:
        d = D[0, 0]
        if not d > 0:  # a runtime guard when traced
            raise SingularTree(what)
        return np.array([[1.0 / d]], dtype=D.dtype)
    L = _cholesky(D, what)
    eye = np.eye(k)
    return np.array([_chol_solve(L, eye[:, c]) for c in range(k)], dtype=D.dtype).T


def _cholesky(G, what, rel=PIVOT_TOL):
    """Lower Cholesky factor of ``G`` (numeric or traced), raising :class:`SingularTree` at a
    pivot at or below ``rel`` times the trace."""
    n = G.shape[0]
    tol = rel * sum(G[k, k] for k in range(n))
    L = np.zeros((n, n), G.dtype)
    for j in range(n):
        d = G[j, j] - sum(L[j, k] * L[j, k] for k in range(j))
        if not d > tol:
            raise SingularTree(what)
        L[j, j] = np.sqrt(d)
        for i in range(j + 1, n):
            L[i, j] = (G[i, j] - sum(L[i, k] * L[j, k] for k in range(j))) / L[j, j]
    return L


def _chol_solve(L, b):
    n = L.shape[0]
    y = [None] * n
    for i in range(n):
        y[i] = (b[i] - sum(L[i, k] * y[k] for k in range(i))) / L[i, i]
    x = [None] * n
    for i in range(n - 1, -1, -1):
        x[i] = (y[i] - sum(L[k, i] * x[k] for k in range(i + 1, n))) / L[i, i]
    return np.array(x, dtype=L.dtype)


def articulated(tp):
    """The articulated-body factorization of ``M``: per link ``U = I^A S`` and ``D^-1`` with
    ``D = S^T I^A S``. Raises :class:`SingularTree` if a joint moves nothing with inertia."""
    links = tp.links
    IA = list(tp.I)
    U, Dinv = [None] * links.n, [None] * links.n
    for i in range(links.n - 1, -1, -1):
        Ui = IA[i] @ tp.S[i]
        Di = _chol_inverse(tp.S[i].T @ Ui, links.edges[i].name)
        U[i], Dinv[i] = Ui, Di
        p = links.parent[i]
        if p >= 0:
            IA[p] = IA[p] + IA[i] - Ui @ Di @ Ui.T
    return U, Dinv


def tree_solve(tp, factor, W):
    """``x = M^-1 S^T W^C``: the speeds' rates caused by the link wrenches ``W`` (list of
    6-vectors or None) and the twist rates they give each link (``(x, acc)``), by the
    articulated-body algorithm's two passes over ``factor`` (:func:`articulated`)."""
    links, S = tp.links, tp.S
    U, Dinv = factor
    n = links.n
    pA = [(-w if w is not None else None) for w in W]
    tau = [None] * n
    for i in range(n - 1, -1, -1):
        p = links.parent[i]
        if pA[i] is None:
            continue
        tau[i] = -(S[i].T @ pA[i])
        if p >= 0:
            carried = pA[i] + U[i] @ (Dinv[i] @ tau[i])
            pA[p] = carried if pA[p] is None else pA[p] + carried
    acc, xs = [None] * n, []
    for i in range(n):
        p = links.parent[i]
        ap = acc[p] if p >= 0 else None
        rhs = tau[i] if tau[i] is not None else np.zeros(S[i].shape[1])
        if ap is not None:
            rhs = rhs - U[i].T @ ap
        xi = Dinv[i] @ rhs
        acc[i] = S[i] @ xi if ap is None else ap + S[i] @ xi
        xs.append(xi)
    x = np.concatenate(xs) if xs else np.zeros(0)
    return x, acc


def _placed(links, entries, scale=1.0):
    W = [None] * links.n
    for i, cov in entries:
        W[i] = cov * scale if W[i] is None else W[i] + cov * scale
    return W


def _row_rate(entries, acc):
    """A row's rate ``A_r x`` from the links' twist rates."""
    return sum(cov @ acc[i] for i, cov in entries)


def lagrange_accelerations(system, t, q, u, alpha=0.0, beta=0.0, baumgarte=False):
    """``du/dt`` of the Lagrange index-1 form (see :mod:`mbcomp.formulations.lagrange`) by the
    recursive algorithms: ``x0 = M^-1 f`` and, with constraint rows ``A``, the multipliers
    from ``(A M^-1 A^T) lam = A x0 - rhs`` and ``du/dt = M^-1 (f - A^T lam)``; O(N + m d) for
    m rows. ``baumgarte`` adds the stabilization terms with ``alpha``, ``beta`` (1/s).

    Raises :class:`SingularTree` when ``M`` or ``A M^-1 A^T`` is singular (the caller's dense
    solve then decides). Links are ordered as the tree; the result is in ``u``'s order."""
    return lagrange_solution(system, t, q, u, alpha, beta, baumgarte).ud


def lagrange_solution(system, t, q, u, alpha=0.0, beta=0.0, baumgarte=False):
    """The Lagrange index-1 solve of :func:`lagrange_accelerations` with what it computes on
    the way: a namespace with ``ud`` (``du/dt``, ``u``'s order), ``lam`` (the multipliers of
    the masked holonomic rows, then of the nonholonomic rows, with the sign of
    ``M du/dt + A^T lam = f``), ``tp`` (the :class:`TreePass`) and ``acc`` (every link's twist
    rate ``(dw/dt, dv_O/dt)`` caused by ``du/dt``, world, about the origin)."""
    from types import SimpleNamespace

    links = tree_links(system)
    tp = tree_pass(system, t, q, u)
    factor = articulated(tp)
    x, acc = tree_solve(tp, factor, tp.W)
    hol, nh = constraint_rows(system, tp)
    rows = hol + nh
    lam = np.zeros(0, tp.dt)
    if rows:
        rhs = []
        for k, (entries, val, dot, bias) in enumerate(rows):
            if k < len(hol):
                rhs.append(-bias - (2.0 * alpha * dot + beta * beta * val if baumgarte else 0.0))
            else:
                rhs.append(-bias - (alpha * val if baumgarte else 0.0))
        m = len(rows)
        G = np.zeros((m, m), tp.dt)
        for r, (entries, *_) in enumerate(rows):
            _, acc_r = tree_solve(tp, factor, _placed(links, entries))
            for s in range(r, m):
                G[s, r] = G[r, s] = _row_rate(rows[s][0], acc_r)
        b = np.array([_row_rate(rows[s][0], acc) - rhs[s] for s in range(m)], dtype=tp.dt)
        lam = _chol_solve(_cholesky(G, "constraint rows", ROWS_PIVOT_TOL), b)
        W = list(tp.W)
        for r, (entries, *_) in enumerate(rows):
            for i, cov in entries:
                W[i] = W[i] - cov * lam[r]
        x, acc = tree_solve(tp, factor, W)
    return SimpleNamespace(ud=_in_u_order(links, x, system.nu, tp.dt), lam=lam, tp=tp, acc=acc)


def _in_u_order(links, x, nu, dt):
    out = np.zeros(nu, dt)
    k = 0
    for cols in links.cols:
        n = cols.stop - cols.start
        out[cols] = x[k:k + n]
        k += n
    return out
