"""What a mechanism conserves: its energy when every component declares it conserves energy,
its momenta when nothing outside loads it -- and the momenta themselves.

The declarations are the components' own (:attr:`mbcomp.modeling.component.Component.conservative`
and :meth:`~mbcomp.modeling.component.Component.conserves_energy`, ``Joint.transmits_load``,
``ForceElement.external``, a sensor's ``sensor = True``), never inferred from names. The accuracy alarms
(:mod:`mbcomp.simulation.accuracy`) watch what these functions say is conserved.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, FreeMotion, RigidBody, Revolute
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))
>>> j = m.add("j", FreeMotion(v0=(1.0, 0, 0), w0=(0, 0, 2.0)))
>>> b = m.add("b", RigidBody(m=2.0, I=np.diag([0.1, 0.2, 0.3])))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
>>> s = mbcomp.assemble(m)
>>> nonconservative(s), momentum_conserved(s)
([], True)
>>> P, L, _, _ = momenta(s, 0.0, s.default_q(), np.array([1.0, 0, 0, 0, 0, 2.0]))
>>> P.tolist(), L.tolist()                  # m v; I w about the origin (the body is there)
([2.0, 0.0, 0.0], [0.0, 0.0, 0.6])
"""
from __future__ import annotations

import numpy as np

from ..geometry.kinematics import cross
from .topology import ROOT

__all__ = ["nonconservative", "momentum_conserved", "momenta", "impulse_work"]


def nonconservative(system):
    """The components of ``system`` whose forces change the total energy at its parameter
    values (each declares it: :meth:`~mbcomp.modeling.component.Component.conserves_energy`);
    empty: the energy of :meth:`~mbcomp.assembly.system.MultibodySystem.energies` is a
    constant of the motion."""
    comps = system.topology.flat.components
    return [name for name, comp in comps.items() if not comp.conserves_energy(system.P.get(name, comp.p))]


def momentum_conserved(system):
    """Whether nothing outside the mechanism loads it, so that its linear momentum and its
    angular momentum about the world origin are constants of the motion: no gravity, no
    drive, no external load (``ForceElement.external``), and every joint or force element
    touching the ground (frames rigidly joined to the world) passes no load
    (``Joint.transmits_load``: a free joint; a sensor, ``sensor = True``, applies none)."""
    topo = system.topology
    if np.any(system.g != 0.0) or topo.drives or any(c.external for _, c, _ in topo.forces):
        return False
    ground, grew = {ROOT}, True
    while grew:  # the frames rigidly joined to the world
        grew = False
        for e in topo.edges:
            rigid = e.kind == "ground" or (e.dof == 0 and getattr(e.comp, "tree_edge", True))
            if rigid and (e.node_a in ground) != (e.node_b in ground):
                ground |= {e.node_a, e.node_b}
                grew = True
    for e in topo.edges:
        loads = e.kind == "joint" and (e.dof > 0 or not getattr(e.comp, "tree_edge", True))
        if loads and (e.node_a in ground or e.node_b in ground) and e.comp.transmits_load:
            return False
    return not any(n in ground for _, c, ports in topo.forces if _applies_load(c) for n in ports.values())


def _applies_load(comp):
    """Whether a force element may load the frames it touches: a sensor (``sensor = True``:
    zero wrenches, outputs only) applies none, so one fixed to the world loads nothing."""
    return not comp.sensor


def momenta(system, t, q, u):
    """``(P, L, P_scale, L_scale)``: linear momentum (kg m/s) and angular momentum about the
    world origin (kg m^2/s), world frame, at ``(t, q, u)``, and the sums of the bodies'
    contributions' magnitudes (their scale)."""
    jets = system.kinematics(t, q, u)
    P, L, sP, sL = np.zeros(3), np.zeros(3), 0.0, 0.0
    for path, comp, node in system.topology.bodies:
        J = jets[node]
        m, rc, I = comp.mass_properties(system.P[path])
        rho, Iw = J.R @ rc, J.R @ I @ J.R.T
        p = m * (J.v + cross(J.w, rho))
        h = cross(J.r + rho, p) + Iw @ J.w
        P, L = P + p, L + h
        sP, sL = sP + float(np.linalg.norm(p)), sL + float(np.linalg.norm(h))
    return P, L, sP, sL


def impulse_work(system, t, q, u_minus, u_plus, loss):
    """The work (J) the prescribed motions' impulses do in an impact at ``(t, q)`` that takes
    the speeds from ``u_minus`` to ``u_plus`` and dissipates ``loss`` (J): the kinetic energy
    gained plus the loss, ``T(u+) - T(u-) + loss``. A drive keeps its prescribed speed through
    the impact, so its impulse does work (a cart driven at 1 m/s whose load hits a stop on it);
    without drives the kinetic energy drops by the loss and this is 0 to roundoff.

    Without drives it is 0, returned without evaluating: every frame's velocity is then
    ``J(q) u`` (only a drive adds a velocity of its own to the jets), so ``T(u) = u^T M u / 2``
    and ``T(u+) - T(u-) + loss`` vanishes for the loss ``(u-^T M u- - u+^T M u+) / 2`` the
    callers give (the impulse solve's, :func:`mbcomp.hybrid.stops.impact_speeds`): a rheonomic
    row's impulse too leaves the kinetic energy and the loss equal. Two evaluations per
    impact otherwise, the two sides' ``T`` rounded apart by ~1e-16 of it.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))
    >>> j = m.add("j", Prismatic(n=(1, 0, 0))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> s = mbcomp.assemble(m)                     # stopped from 1 m/s: 1 J lost, no drive
    >>> impulse_work(s, 0.0, np.zeros(1), np.array([1.0]), np.array([0.0]), 1.0)
    0.0
    """
    if not system.topology.drives:
        return 0.0
    T_minus = system.energies(system.evaluate(t, q, u_minus))[0]
    T_plus = system.energies(system.evaluate(t, q, u_plus))[0]
    return float(T_plus - T_minus + loss)
