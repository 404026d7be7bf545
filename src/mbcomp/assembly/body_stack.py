"""Every body's inertia terms at once, on numbers: the products of the body-by-body code
(:meth:`~mbcomp.assembly.system.MultibodySystem.body_inertia`, Kane's mass matrix and forces,
the recursive algorithms' spatial inertias) made as stacked numpy products, one call for all
bodies instead of one per body.

numpy's stacked matrix products are BLAS's product of each matrix (the same bits as ``.dot``
body by body), the 3-vectors' products and differences are the same elementwise operations,
and the bodies' terms are summed one by one in the bodies' order: the results are those of the
body-by-body code bit for bit (``tests/assembly``, ``tests/library/test_contracts.py``). Traced
evaluations keep the body-by-body code: its structure is the generated program's.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.assembly.body_stack import kane_terms
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> s = mbcomp.assemble(m)
>>> M, f = kane_terms(s, s.kinematics(0.0, np.array([0.5]), np.array([1.0])), 1)
>>> float(M[0, 0]), round(float(f[0]), 9)         # m l^2, -m g l sin(phi)
(2.0, -9.406329067)
"""
from __future__ import annotations

import numpy as np

__all__ = ["skews", "spatial_inertias", "kane_terms"]

#: a cross product's rows: (a x b)_i = a_{i+1} b_{i+2} - a_{i+2} b_{i+1}
_NEXT, _LAST = np.array([1, 2, 0]), np.array([2, 0, 1])
_EYE = np.eye(3)
_EYE.setflags(write=False)


def _cross(a, b):
    """Row by row cross products of (k, 3) arrays (kinematics.cross's operations)."""
    return a[:, _NEXT] * b[:, _LAST] - a[:, _LAST] * b[:, _NEXT]


def skews(c):
    """Each row's cross matrix (kinematics.skew's), (k, 3, 3)."""
    S = np.zeros((len(c), 3, 3))
    S[:, 0, 1], S[:, 0, 2], S[:, 1, 0] = -c[:, 2], c[:, 1], c[:, 2]
    S[:, 1, 2], S[:, 2, 0], S[:, 2, 1] = -c[:, 0], -c[:, 1], c[:, 0]
    return S


def _placed(system, bodies, Rs):
    """``(m, rho, Iw)`` stacked: masses (k, 1, 1), centres of mass (k, 3) and inertias about
    them (k, 3, 3) of ``bodies`` (``(path, comp)``) on frames turned by ``Rs`` (world)."""
    props = [comp.mass_properties(system.P[path]) for path, comp in bodies]
    R = np.array(Rs)
    rho = (R @ np.array([p[1] for p in props], float)[:, :, None])[:, :, 0]
    Iw = R @ np.array([p[2] for p in props], float) @ R.transpose(0, 2, 1)
    return np.array([p[0] for p in props], float)[:, None, None], rho, Iw, props


def spatial_inertias(system, links, jets):
    """The bodies' ``(link, m, c, Iw)`` and spatial inertias about O (k, 6, 6) of the bodies on
    links (:func:`mbcomp.assembly.recursive.tree_pass` without forces, numbers)."""
    on = []
    for path, comp, node in system.topology.bodies:
        i = links.link_of.get(node, -1)
        if i >= 0:
            on.append((i, path, comp, jets[node]))
    if not on:
        return [], None
    m, rho, Iw, props = _placed(system, [b[1:3] for b in on], [b[3].R for b in on])
    c = np.array([b[3].r for b in on]) + rho
    Cx = skews(c)
    mC = m * Cx
    out = np.empty((len(on), 6, 6))
    out[:, :3, :3] = Iw - m * (Cx @ Cx)
    out[:, :3, 3:] = mC
    out[:, 3:, :3] = -mC
    out[:, 3:, 3:] = m * _EYE
    return [(b[0], p[0], c[k], Iw[k]) for k, (b, p) in enumerate(zip(on, props))], out


def kane_terms(system, jets, nu):
    """``M`` (nu, nu) and the inertial and gravity part of ``f`` (nu,) summed over the bodies
    (Kane's form: :meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_numeric` on numbers;
    rotors not included), at the frames' ``jets`` (every Jacobian nu columns wide)."""
    M, f = np.zeros((nu, nu)), np.zeros(nu)
    bodies = system.topology.bodies
    if not bodies:
        return M, f
    Js = [jets[node] for _, _, node in bodies]
    m, rho, Iw, _ = _placed(system, [b[:2] for b in bodies], [J.R for J in Js])
    Jw = np.array([J.Jw for J in Js], float)
    Jv = np.array([J.Jv for J in Js], float) - skews(rho) @ Jw
    w, alpha = np.array([J.w for J in Js]), np.array([J.alpha for J in Js])
    a = (np.array([J.a for J in Js]) + _cross(alpha, rho)) + _cross(w, _cross(w, rho))
    h = (Iw @ alpha[:, :, None])[:, :, 0] + _cross(w, (Iw @ w[:, :, None])[:, :, 0])
    JvT, JwT = Jv.transpose(0, 2, 1), Jw.transpose(0, 2, 1)
    fb = (JvT @ (m[:, :, 0] * (system.g - a))[:, :, None])[:, :, 0] - (JwT @ h[:, :, None])[:, :, 0]
    for x in fb:
        f += x
    k = len(bodies)
    if k > 8:
        # M = sum_b m Jv^T Jv + Jw^T Iw Jw as two stacked products: one BLAS call each instead of
        # one nu x nu outer product per body (a 1000-link chain: 3.6 s -> 0.2 s per evaluation)
        M = Jv.reshape(3 * k, nu).T.dot((m * Jv).reshape(3 * k, nu)) + Jw.reshape(3 * k, nu).T.dot(
            (Iw @ Jw).reshape(3 * k, nu))
        return 0.5 * (M + M.T), f  # exactly symmetric, as the per-body products were
    for x in m * (JvT @ Jv) + JwT @ Iw @ Jw:
        M += x
    return M, f
