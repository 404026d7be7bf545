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

The factorization uses the products' structure (:func:`articulated`): symmetric matrices are
computed on one triangle, pivots below the root keep their Cholesky factor, and a ball joint is
solved over its angular velocity about its centre, where its motion subspace is ``[1; 0]``.

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

from .evaluation import Evaluation
from .jets import FrameJet, is_traced
from .body_stack import skews, spatial_inertias
from .flange_rows import reflected_rotors, rotor_wrench, rotors
from .pivots import PIVOT_TOL, Pivot, SingularTree, ball_pivot, chol_solve, cholesky, lower_product
from .topology import ROOT
from ..geometry.kinematics import cross, skew

__all__ = ["SingularTree", "tree_links", "tree_pass", "tree_evaluation", "articulated", "ancestry", "speed_columns", "mass_matrix",
           "tree_solve", "constraint_rows", "lagrange_accelerations", "lagrange_solution", "PIVOT_TOL"]

#: ... and for the constraint rows' ``A M^-1 A^T``, at or below ``ROWS_PIVOT_TOL``: the rows
#: are losing rank (pivot ~ sigma^2 of the mass-weighted rows: a smallest relative singular
#: value of about 1e-2). The recursive solve then declines -- a guard when traced, so the
#: compiled engine ends its stretch there and the driver steps the dense solve, watching every
#: step: kept rows that degrade while others would not are chosen again
#: (:class:`mbcomp.simulation.rows.RowChoice`), a position where no choice keeps the rank is
#: located and reported (:class:`mbcomp.simulation.monitors.ConstraintRank`)
ROWS_PIVOT_TOL = 1e-4


def tree_links(system):
    """The :class:`~mbcomp.assembly.topology.TreeLinks` of ``system``'s topology (made once
    per topology: :attr:`~mbcomp.assembly.topology.Topology.links`)."""
    return system.topology.links


def _dtype(*xs):
    return object if any(is_traced(x) for x in xs) else float


#: no Jacobian columns (shared by the narrow jets: an empty array is never written)
_NO_COLUMNS = np.zeros((3, 0))
_EYE = np.eye(3)
_EYE.setflags(write=False)


def _narrow(J):
    """A jet's pose and motion without Jacobian columns."""
    return FrameJet(J.R, J.r, J.w, J.v, _NO_COLUMNS, _NO_COLUMNS, J.alpha, J.a)


class TreePass:
    """One kinematic pass down the tree at ``(t, q, u)`` (see :func:`tree_pass`).

    Attributes
    ----------
    jets : dict
        Frame node -> :class:`~mbcomp.assembly.jets.FrameJet` with no Jacobian columns
        (pose, velocity and bias acceleration only).
    S : list of ndarray (6, k)
        Each link's motion subspace: the twist about O per unit joint speed.
    Jw, r : lists
        Per link, for a joint of three speeds whose twist at its child frame's origin
        ``r`` (m, world) has no linear part (a ball joint: ``S = [Jw; r x Jw]``), ``Jw``
        (3, k); None otherwise (see :func:`articulated`).
    I : list of ndarray (6, 6)
        Each link's own spatial inertia about O (its bodies' sum).
    W : list of ndarray (6,)
        Each link's own bias wrench about O: gravity, applied forces and the inertial
        (velocity-product) wrench ``-dh/dt`` at ``du/dt = 0``.
    bodies : list of tuple
        ``(link, m, c, Iw)`` of every body on a link: its link, mass (kg), centre of mass
        (m) and inertia about it (kg m^2), world -- what the inertias were summed from.
    reflected : list of tuple
        ``(speed column, J)`` of the reflected rotors (kg m^2 or kg on the joint's own speed:
        :func:`~mbcomp.assembly.flange_rows.reflected_rotors`), on ``M``'s diagonal.
    """

    def __init__(self, links, jets, S, I, W, dt, t=0.0, q=None, Jw=None, r=None, bodies=()):
        self.links, self.jets, self.S, self.I, self.W, self.dt = links, jets, S, I, W, dt
        self.bodies = list(bodies)
        self.t, self.q = t, q  # for the rows of flange constraints (assembly/flange_rows.py)
        # per link, a ball-like joint's angular columns Jw (its twist at the child frame's
        # origin r has no linear part; None for other joints) and that origin r (m, world)
        self.Jw = [None] * len(S) if Jw is None else Jw
        self.r = [None] * len(S) if r is None else r
        self._columns = {}  # speed_columns by nu: asked by the inertia check, the CRBA and the scale
        self.reflected = []

    def pivot_extra(self, i):
        """The reflected rotors' inertia on link ``i``'s own speeds: ``[(its column among them,
        J)]`` (added to the articulated-body pivot ``D`` of that joint, as to ``M``'s diagonal)."""
        if not self.reflected:
            return []
        if "reflected" not in self._columns:  # summed by speed column (two rotors on one axis), made once
            at = self._columns["reflected"] = {}
            for k, J in self.reflected:
                at[k] = at[k] + J if k in at else J
        at, cols = self._columns["reflected"], self.links.cols[i]
        return [(k - cols.start, at[k]) for k in range(cols.start, cols.stop) if k in at]

    def columns(self, nu):
        """:func:`speed_columns` of this pass, made once (the same arrays again: read, never written)."""
        if nu not in self._columns:
            self._columns[nu] = _speed_columns(self, nu)
        return self._columns[nu]

    def ancestry(self):
        """:func:`ancestry` of the pass's links, made once (the mass matrix and the moving scale
        both ask; read, never written)."""
        if "ancestry" not in self._columns:
            self._columns["ancestry"] = ancestry(self.links)
        return self._columns["ancestry"]


def _exact_zeros(A):
    """True if every entry of ``A`` is the number 0 (a structural zero when traced)."""
    return all(not is_traced(x) and x == 0 for x in A.flat)


def _child_pose(system, e, pj, t, q):
    """:meth:`~mbcomp.assembly.system.MultibodySystem.child_jet`'s pose and the joint's own
    Jacobian columns alone from a parent without columns, by the same operations
    (:meth:`FrameJet.pose_through`, :meth:`FrameJet.offset_pose`): no rates, no bias terms."""
    p = system.P[e.name]
    if e.dof == 0:  # rigid offsets and ground frames: constant transforms
        R, r = e.comp.pose(p) if e.kind == "ground" else e.comp.relative(None, p)
        return pj.offset_pose(R, r) if e.forward else pj.offset_pose(R.T, -(R.T.dot(r)))
    if e.kind == "ground" or e.drive:  # no speeds of its own (a drive's coordinate is its law's)
        R, r = (e.comp.pose(p) if e.kind == "ground" else
                e.comp.relative(np.array([system.topology.flat.components[e.drive].motion(t, system.P[e.drive])[0]]), p))
        Hw = Hv = _NO_COLUMNS
    else:
        qj = q[e.q]
        R, r = e.comp.relative(qj, p)
        Hw, Hv = e.comp.motion(qj, p)
    return pj.pose_through(R, r, Hw, Hv, e.forward)


def _link_jets(system, links, t, q, u, pose_only=False):
    """The narrow jets of every frame, the links' motion subspaces ``S`` and, per link, a
    ball-like joint's angular columns and origin (see :class:`TreePass`); ``pose_only``: the
    poses and subspaces alone (the motions zero), for the inertias."""
    jets = {ROOT: FrameJet.ground(0)}
    S, Jw, r, own = [], [], [], []
    for e in system.topology.tree:
        pj = jets[e.parent]
        k = e.u.stop - e.u.start
        if pose_only:
            cj = _child_pose(system, e, pj, t, q)
        elif k == 0:
            cj = system.child_jet(e, pj, t, q, u, slice(0, 0))
        else:
            z = np.zeros((3, k))
            cj = system.child_jet(e, FrameJet(pj.R, pj.r, pj.w, pj.v, z, z, pj.alpha, pj.a), t, q, u, slice(0, k))
        if k == 0:
            jets[e.child] = cj
            continue
        own.append(cj)
        ball = k == 3 and _exact_zeros(cj.Jv)
        Jw.append(cj.Jw if ball else None)
        r.append(cj.r if ball else None)
        jets[e.child] = _narrow(cj)
    return jets, _subspaces(own, pose_only), Jw, r


def _subspaces(own, numbers):
    """Each link's motion subspace from its joint's columns at its child frame: the columns
    give the twist of the frame's origin; about O, ``v_O = v_c + r_c x w``. A pose pass
    (``numbers``) whose links all have as many speeds: every link at once (stacked products,
    BLAS's per matrix: the same bits)."""
    if numbers and own and len({J.Jw.shape[1] for J in own}) == 1:
        Jw, Jv, r = (np.array([getattr(J, x) for J in own]) for x in ("Jw", "Jv", "r"))
        return list(np.concatenate((Jw, Jv + skews(r) @ Jw), axis=1))
    return [np.concatenate((J.Jw, J.Jv + skew(J.r).dot(J.Jw))) for J in own]


def _spatial_inertia(m, Iw, Cx):
    """``[[Iw - m Cx Cx, m Cx], [-m Cx, m 1]]``: a body's spatial inertia about O (its centre's
    cross matrix ``Cx``); numbers assembled in place (numpy.block's checks: half of a pass)."""
    mC = m * Cx
    if mC.dtype == object or np.asarray(Iw).dtype == object:
        return np.block([[Iw - m * (Cx @ Cx), mC], [-mC, m * np.eye(3)]])
    out = np.empty((6, 6))
    out[:3, :3] = Iw - m * Cx.dot(Cx)
    out[:3, 3:] = mC
    out[3:, :3] = -mC
    out[3:, 3:] = m * _EYE
    return out


def _body_terms(system, links, jets, I, W, numbers=False):
    """Add every body's spatial inertia and bias wrench (gravity and inertial) to its link
    (``W`` None: the inertias only; ``numbers``: the pass is not traced); returns the bodies'
    ``(link, m, c, Iw)`` (:class:`TreePass`)."""
    g = system.g
    bodies = []
    if W is None and numbers:
        bodies, spatial = spatial_inertias(system, links, jets)
        for (i, *_), Ib in zip(bodies, spatial if spatial is not None else ()):
            I[i] = I[i] + Ib
    for path, comp, node in system.topology.bodies if not (W is None and numbers) else ():
        i = links.link_of.get(node, -1)
        if i < 0:
            continue
        J = jets[node]
        m, rho, Iw = system.body_inertia(comp, path, J)
        c = J.r + rho
        bodies.append((i, m, c, Iw))
        I[i] = I[i] + _spatial_inertia(m, Iw, skew(c))
        if W is None:
            continue
        a_c = J.a + cross(J.alpha, rho) + cross(J.w, cross(J.w, rho))
        F = m * (g - a_c)
        tau = cross(c, F) - (Iw @ J.alpha + cross(J.w, Iw @ J.w))
        W[i] = W[i] + np.concatenate((tau, F))
    for node, Iw, gyro in rotors(system, jets):  # a rotor J n n^T: no mass, so no force
        i = links.link_of.get(node, -1)
        if i >= 0:
            z = np.zeros((3, 3))
            I[i] = I[i] + np.block([[Iw, z], [z, z]])
            if W is not None:
                W[i] = W[i] + np.concatenate((-rotor_wrench(jets[node], Iw, gyro), np.zeros(3)))
    return bodies


def tree_pass(system, t, q, u, forces=True):
    """The kinematic pass of the recursive algorithms: a :class:`TreePass` holding the frames'
    poses and motions, the links' motion subspaces ``S``, spatial inertias ``I`` and bias
    wrenches ``W`` (gravity, applied forces of force and flange elements, inertial terms;
    ``forces=False``: zero, for a caller that needs only the inertias -- no law is called)."""
    links = tree_links(system)
    dt = _dtype(t, q, u)
    jets, S, Jw, r = _link_jets(system, links, t, q, u, pose_only=not forces and dt is float)
    I = [np.zeros((6, 6), dt) for _ in range(links.n)]
    W = [np.zeros(6, dt) for _ in range(links.n)]
    bodies = _body_terms(system, links, jets, I, W if forces else None, dt is float)
    for node, (F, T) in system.applied(t, q, u, jets).items() if forces else ():
        i = links.link_of.get(node, -1)
        if i >= 0:
            W[i] = W[i] + np.concatenate((T + cross(jets[node].r, F), F))
    tp = TreePass(links, jets, S, I, W, dt, t, q, Jw, r, bodies)
    tp.reflected = reflected_rotors(system)
    return tp


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


def generalized_momenta(tp, u, nu):
    """``M u`` in O(N): each link's twist ``V_k`` from the speeds (its ancestors' ``S_j u_j``
    summed), the momenta ``I_k V_k`` summed over each subtree, ``S_i^T`` of the sum -- the
    composite-rigid-body algorithm's ``M`` times ``u`` without forming ``M``."""
    links = tp.links
    V = []
    for i in range(links.n):  # parents before their children
        v = tp.S[i] @ u[links.cols[i]]
        p = links.parent[i]
        V.append(v if p < 0 else V[p] + v)
    out = np.zeros(nu, tp.dt)
    for i, H in enumerate(_summed(links, [tp.I[i] @ V[i] for i in range(links.n)])):
        out[links.cols[i]] = tp.S[i].T @ H
    for k, J in tp.reflected:  # a reflected rotor: J u_k
        out[k] = out[k] + J * u[k]
    return out


def ancestry(links):
    """``A[i, j]``: link ``i`` is link ``j`` or one of its ancestors (bool, links x links;
    parents are numbered before their children, so each column is its parent's plus itself)."""
    A = np.zeros((links.n, links.n), bool)
    for j, p in enumerate(links.parent):
        if p >= 0:
            A[:, j] = A[:, p]
        A[j, j] = True
    return A


def speed_columns(tp, nu):
    """``(S, link)``: every link's motion subspace at its speeds' columns (6 x nu, numbers) and
    each column's link (nu,), or None when the links' columns are not the ``nu`` speeds each
    once (a speed no tree joint has) or the pass is traced."""
    return tp.columns(nu)


def _speed_columns(tp, nu):
    links = tp.links
    if tp.dt == object or not links.n:
        return None
    cols = [range(nu)[c] for c in links.cols]
    order = [i for c in cols for i in c]
    if order == list(range(nu)):  # the links' columns in the speeds' order (a tree numbered so)
        return np.concatenate(tp.S, axis=1), np.repeat(np.arange(links.n), [len(c) for c in cols])
    if len(order) != nu or sorted(order) != list(range(nu)):
        return None
    S, link = np.zeros((6, nu)), np.empty(nu, int)
    for j, c in enumerate(cols):
        S[:, c], link[c] = tp.S[j], j
    return S, link


def mass_matrix(tp, nu):
    """:func:`composite_inertia` plus the reflected rotors' ``J`` on the diagonal."""
    M = composite_inertia(tp, nu)
    for k, J in tp.reflected:
        M[k, k] = M[k, k] + J
    return M


def composite_inertia(tp, nu):
    """``M`` by the composite-rigid-body algorithm: ``M[i, j] = S_i^T I^C_j S_j`` for ``i`` an
    ancestor of (or equal to) ``j``, zero between links on different branches. On numbers,
    every block at once: ``S^T F`` (``F_j = I^C_j S_j``) kept where :func:`ancestry` holds
    (mirrored below the links' own blocks): O(N^2) products in BLAS instead of a Python loop
    over the ancestor pairs (0.5 s at N = 1000)."""
    links = tp.links
    columns = speed_columns(tp, nu)
    if columns is not None:
        S, link = columns
        IC = _summed(links, tp.I)
        F = np.zeros((6, nu))
        for j, c in enumerate(links.cols):
            F[:, c] = IC[j].dot(tp.S[j])
        A = tp.ancestry()[np.ix_(link, link)]
        G = np.where(A, S.T @ F, 0.0)
        own = link[:, None] == link[None, :]
        return G + np.where(own, 0.0, G).T
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
def articulated(tp):
    """The articulated-body factorization of ``M``: per link ``U = I^A S`` (None where the
    pivot keeps ``W``) and the factored pivot ``D = S^T I^A S`` (:class:`Pivot`). Raises
    :class:`SingularTree` if a joint moves nothing with inertia. The articulated inertias
    passed to the parents are symmetric: their lower triangles are computed and mirrored."""
    links = tp.links
    IA = list(tp.I)
    U, piv = [None] * links.n, [None] * links.n
    for i in range(links.n - 1, -1, -1):
        p = links.parent[i]
        what = links.edges[i].name
        if tp.Jw[i] is not None:
            piv[i] = ball_pivot(IA[i], tp.Jw[i], tp.r[i], what)
        else:
            U[i] = IA[i] @ tp.S[i]
            D = lower_product(tp.S[i], U[i])
            for a, J in tp.pivot_extra(i):  # a reflected rotor: J on its joint's own speed
                D[a, a] = D[a, a] + J
            piv[i] = Pivot(D, U[i], what, dense=p < 0)
        if p >= 0:
            IA[p] = IA[p] + IA[i] - piv[i].passed(U[i])
    return U, piv


def _joint_force(tp, i, P, pA):
    """``tau = -S^T pA`` of link ``i`` (a ball joint's over its world angular velocity:
    ``-(pA_1 - r x pA_2)``, the moment about its centre)."""
    if P.Jinv is None:
        return -(tp.S[i].T @ pA)
    return -(pA[:3] - cross(tp.r[i], pA[3:]))


def _twist(tp, i, P, z):
    """The joint's speeds ``x`` and their twist about O from the solve's result ``z``."""
    if P.Jinv is None:
        return z, tp.S[i] @ z
    return P.Jinv @ z, np.concatenate((z, cross(tp.r[i], z)))


def tree_solve(tp, factor, W):
    """``x = M^-1 S^T W^C``: the speeds' rates caused by the link wrenches ``W`` (list of
    6-vectors or None) and the twist rates they give each link (``(x, acc)``), by the
    articulated-body algorithm's two passes over ``factor`` (:func:`articulated`)."""
    links = tp.links
    U, piv = factor
    n = links.n
    pA = [(-w if w is not None else None) for w in W]
    tau, y = [None] * n, [None] * n
    for i in range(n - 1, -1, -1):
        p = links.parent[i]
        if pA[i] is None:
            continue
        P = piv[i]
        tau[i] = _joint_force(tp, i, P, pA[i])
        if p >= 0:
            if P.W is None:
                carried = pA[i] + U[i] @ (P.Dinv @ tau[i])
            else:
                y[i] = P.forward(tau[i])
                carried = pA[i] + P.W @ np.array(y[i], dtype=P.W.dtype)
            pA[p] = carried if pA[p] is None else pA[p] + carried
    acc, xs = [None] * n, []
    for i in range(n):
        p = links.parent[i]
        ap = acc[p] if p >= 0 else None
        P = piv[i]
        k = len(P.rinv) if P.W is not None else P.Dinv.shape[0]
        if P.W is None:
            rhs = tau[i] if tau[i] is not None else np.zeros(k)
            if ap is not None:
                rhs = rhs - U[i].T @ ap
            z = P.Dinv @ rhs
        else:  # D^-1 (tau - U^T a) = L^-T (L^-1 tau - W^T a), L^-1 tau kept from the first pass
            yi = y[i] if y[i] is not None else (P.forward(tau[i]) if tau[i] is not None else [0.0] * k)
            if ap is not None:
                yi = np.array(yi, dtype=object if P.W.dtype == object else float) - P.W.T @ ap
            z = P.backward(yi)
        xi, twist = _twist(tp, i, P, z)
        acc[i] = twist if ap is None else ap + twist
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
        lam = chol_solve(cholesky(G, "constraint rows", ROWS_PIVOT_TOL), b)
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
