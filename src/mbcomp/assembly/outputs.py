"""The result columns at one state by the recursive algorithms: O(N) per output time.

The post-processing (:mod:`mbcomp.simulation.postprocess`) needs, at every output time, the
coordinates and speeds, the accelerations and multipliers, every joint's reaction wrench,
the bodies' poses and twists, the energies and the constraint residuals. The dense route
(jets carrying the full ``3 x nu`` Jacobians, ``M`` and a saddle-point solve) costs O(N^2)
to O(N^3) per time and ~3 ms for a small model in Python. Here the same columns come from
one kinematic pass of the tree (:func:`~mbcomp.assembly.recursive.tree_pass`, jets without
Jacobian columns), the Lagrange solve by the articulated-body algorithm (which also gives the
multipliers and every link's twist rate), and one backward pass summing the frames'
wrenches into joint reactions. Everything is plain numpy on floats *or* traced values, so
:mod:`mbcomp.codegen` prints it as one more program and runs it over the whole output grid
in a C loop.

Two kinds of values are returned: scalar *columns* by name (the result's columns, see
:mod:`mbcomp.simulation.result`) and each body's rotation matrix (the post-processing turns
the matrices of the whole grid into quaternions at once: the choice of Shepperd's branch is
a decision on values that a straight-line program would have to guard).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.assembly.outputs import output_values
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> cols, rot = output_values(mbcomp.assemble(m), 0.0, np.array([0.0]), np.array([2.0]))
>>> round(float(cols["j.f.y"]), 9), float(cols["energy.kinetic"])  # m (g + w^2 l) upward on the rod; m v^2 / 2
(27.62, 4.0)
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..geometry.kinematics import cross
from ..modeling.component import PortRef
from ..modeling.roles import FlangeElement, ForceElement, FrameState, Joint
from .flange_rows import flange_flows, flange_states
from .recursive import generalized_forces, generalized_momenta, lagrange_solution, tree_links, tree_pass

__all__ = ["output_values", "result_columns", "MeasuredFrame", "HIDDEN", "tolerance_terms"]

_XYZ = ("x", "y", "z")


def output_values(system, t, q, u, alpha=0.0, beta=0.0, baumgarte=False):
    """Every numeric result column at ``(t, q, u)``, and the bodies' rotation matrices.

    Parameters
    ----------
    system : MultibodySystem
        Assembled (its row mask chooses the independent constraint rows).
    t : float
        Time (s).
    q, u : ndarray
        A consistent state (coordinates, speeds); floats or traced values.
    alpha, beta : float
        Baumgarte gains (1/s) of the multipliers' solve, used when ``baumgarte``; the
        formulation's own (:meth:`~mbcomp.formulations.base.Formulation.output_gains`).

    Returns
    -------
    columns : dict
        Column name -> value, in the post-processing's column order (a dict keeps it).
    rotations : dict
        Body path -> rotation matrix (3, 3) of its frame (body to world).

    Raises
    ------
    SingularTree
        When the recursive solve meets a singular matrix; the caller uses the dense route.
    """
    sol = lagrange_solution(system, t, q, u, alpha, beta, baumgarte)
    ev = _sampled_evaluation(system, t, q, u, sol.tp.jets)
    rates = _link_rates(tree_links(system), sol.acc)
    reac = system.reactions(ev, rates, sol.lam)
    return result_columns(system, ev, sol.ud, sol.lam, reac, rates)


#: the prefix of the output program's hidden columns: read by the post-processing, never kept
HIDDEN = "~"


def tolerance_terms(system, t, q, u):
    """``{"~f.i": f_i, "~p.i": (M u)_i}``: the generalized forces and momenta (N or N m;
    kg m/s or kg m^2/s) at ``(t, q, u)`` by the recursive pass (O(N), equal to the dense
    evaluation's ``f`` and ``M u`` to rounding) -- what
    :func:`mbcomp.simulation.accuracy.tolerance_energy` weighs the tolerances with, carried by
    the output program as hidden columns (:data:`HIDDEN`) so that it evaluates nothing again."""
    tp = tree_pass(system, t, q, u)
    f, p = generalized_forces(tp, system.nu), generalized_momenta(tp, u, system.nu)
    return {**{f"{HIDDEN}f.{i}": x for i, x in enumerate(f)}, **{f"{HIDDEN}p.{i}": x for i, x in enumerate(p)}}


def result_columns(system, ev, ud, lam, reac, rates=None):
    """The columns and rotations of :func:`output_values` from what any route computed: an
    evaluation-like ``ev`` (``t, q, u, jets, local_nh, B``, all position rows ``Phi_all``,
    ``Phid_all``, the nonholonomic residual ``Psi``), the speeds' rates ``ud``, the
    multipliers ``lam`` and the reactions ``reac`` (:meth:`MultibodySystem.reactions`).
    ``rates`` is the function ``(node, r) -> (a_lin, a_ang)`` of :func:`_link_rates` (jets
    without Jacobian columns); None: from ``ud`` and the jets' Jacobians (the dense route)."""
    cols, rotations = {}, {}
    _coordinates(system, cols, ev.t, ev.q, ev.u, ev.jets, ud)
    _reactions(system, cols, ev, lam, reac)
    _flange_constraints(system, cols, ev, lam)
    _elements(system, cols, ev, rates if rates is not None else _jacobian_rates(ev.jets, ud))
    for path, _comp, node in system.topology.bodies:
        J = ev.jets[node]
        _vector(cols, f"{path}.r", J.r)
        _vector(cols, f"{path}.v", J.v)
        _vector(cols, f"{path}.w", J.w)
        rotations[path] = J.R
    T, V = system.energies(ev)
    cols["energy.kinetic"], cols["energy.potential"], cols["energy.total"] = T, V, T + V
    if system.topology.bodies:
        P, L = system.momenta(ev)
        _vector(cols, "momentum", P)
        _vector(cols, "angular_momentum", L)
    cols["residual.position"] = _norm(ev.Phi_all)
    cols["residual.velocity"] = _norm(ev.Phid_all)
    cols["residual.nonholonomic"] = _norm(ev.Psi)
    names = system.constraint_names() + [f"{e.name}.{r}" for e, rows, _ in ev.local_nh for r in rows]
    for i, name in enumerate(names):
        cols[f"lambda.{name}"] = lam[i] if i < len(lam) else np.nan
    return cols, rotations


def _vector(cols, prefix, vec):
    for j, ax in enumerate(_XYZ):
        cols[f"{prefix}.{ax}"] = vec[j]


def _norm(x):
    return np.sqrt(sum(v * v for v in x)) if len(x) else 0.0


def _coordinates(system, cols, t, q, u, jets, ud):
    """Coordinates, speeds, measured coordinates of 1-DOF joints without their own (cut or
    driven), and the speeds' rates (the dense route's :func:`_joint_columns`)."""
    topo = system.topology
    for i, name in enumerate(system.q_names):
        cols[name] = q[i]
    for i, name in enumerate(system.u_names):
        cols[name] = u[i]
    for e in topo.edges:
        if e.kind != "joint" or e.dof != 1 or e.q.stop > e.q.start:
            continue
        if e.drive:
            s, v, _ = topo.flat.components[e.drive].motion(t, system.P[e.drive])
        else:
            s, v = e.comp.measure(jets[e.node_a], jets[e.node_b], system.P[e.name])
        cols[f"{e.name}.{e.comp.coordinates[0][0]}"] = s
        cols[f"{e.name}.{e.comp.speeds[0][0]}"] = v
    for i, name in enumerate(system.u_names):
        cols[f"{name}.der"] = ud[i]


def _sampled_evaluation(system, t, q, u, jets):
    """What :meth:`MultibodySystem.reactions`, ``energies`` and ``row_multipliers`` read of an
    evaluation, from the recursive pass: the jets (no Jacobian columns), the cut joints'
    local row Jacobians, all position rows and the nonholonomic residual."""
    local, local_nh, Phi, Phid = [], [], [], []
    for e, cons in system.cut_constraints(jets, t, q):
        if cons:
            local.append((e, [n for n, _ in cons], np.array([c.jac for _, c in cons])))
            Phi += [c.val for _, c in cons]
            Phid += [c.dot for _, c in cons]
    Psi = []
    for e, cons in system.velocity_constraints(jets):
        if cons:
            local_nh.append((e, [n for n, _ in cons], np.array([c.jac for _, c in cons])))
            Psi += [c.val for _, c in cons]
    return SimpleNamespace(t=t, q=q, u=u, jets=jets, local=local, local_nh=local_nh, Phi_all=Phi, Phid_all=Phid,
                           Psi=Psi, B=np.zeros((len(Psi), 0)))


def _link_rates(links, acc):
    """The speeds' part of each frame's acceleration, for :meth:`MultibodySystem.reactions`:
    a function of (node, point r) giving ``(a_lin, a_ang)`` from its link's twist rate
    ``(dw, dv_O)`` about the world origin (``a = dv_O + dw x r``; zero on the ground)."""
    def rates(node, r):
        i = links.link_of.get(node, -1)
        if i < 0 or acc[i] is None:
            return 0.0, 0.0
        dw, dv = acc[i][:3], acc[i][3:]
        return dv + cross(dw, r), dw
    return rates


def _jacobian_rates(jets, ud):
    """:func:`_link_rates` from the speeds' rates ``ud`` and jets carrying Jacobians (as
    :meth:`MultibodySystem.reactions` does on the dense route)."""
    def rates(node, r):
        J = jets[node]
        dw = J.Jw @ ud
        return J.Jv @ ud + cross(dw, r - J.r), dw
    return rates


class MeasuredFrame(FrameState):
    """A :class:`~mbcomp.modeling.roles.FrameState` that also knows the frame's accelerations:
    what a force element's :meth:`~mbcomp.modeling.roles.ForceElement.outputs` receives (never
    its ``wrenches`` or ``potential``: forces do not depend on accelerations). Sensors
    (:mod:`mbcomp.library.sensors`) read them.

    Attributes
    ----------
    a : ndarray (3,)
        Acceleration of the origin, m/s^2, world coordinates (computed when first read).
    alpha : ndarray (3,)
        Angular acceleration, rad/s^2, world coordinates (computed when first read).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.assembly.jets import FrameJet
    >>> J = FrameJet.ground(0)
    >>> f = MeasuredFrame(J, lambda node, r: (np.array([0.0, 1.0, 0.0]), np.zeros(3)), "n")
    >>> f.a.tolist(), f.alpha.tolist()
    ([0.0, 1.0, 0.0], [0.0, 0.0, 0.0])
    """

    __slots__ = ("_jet", "_rates", "_node", "_acc")

    def __init__(self, jet, rates, node):
        super().__init__(jet.r, jet.R, jet.v, jet.w)
        self._jet, self._rates, self._node, self._acc = jet, rates, node, None

    def _accelerations(self):
        if self._acc is None:
            J = self._jet
            a_lin, a_ang = self._rates(self._node, J.r)
            self._acc = (a_lin + J.a, a_ang + J.alpha)
        return self._acc

    @property
    def a(self):
        return self._accelerations()[0]

    @property
    def alpha(self):
        return self._accelerations()[1]


def _reactions(system, cols, ev, lam, reac):
    """Reaction columns, joints' own outputs and drive efforts (the dense route's
    :func:`_reaction_columns`)."""
    topo = system.topology
    for ename, (fb, tb) in reac.items():
        _vector(cols, f"{ename}.f", fb)
        _vector(cols, f"{ename}.tau", tb)
    own = [e for e in topo.edges if e.kind == "joint" and type(e.comp).outputs is not Joint.outputs]
    if own:
        lam_rows = system.row_multipliers(ev, lam)
        for e in own:
            extra = e.comp.outputs(ev.jets[e.node_a], ev.jets[e.node_b], system.P[e.name], lam_rows.get(e.name, {}))
            for key, val in extra.items():
                cols[f"{e.name}.{key}"] = val
    _reaction_outputs(system, cols, ev, reac)
    for e in topo.edges:
        if not e.drive:
            continue
        fb, tb = reac[e.name]
        axis_b = ev.jets[e.node_b].R.T @ e.comp.axis_world(ev.jets[e.node_a].R, system.P[e.name])
        effort = tb @ axis_b if e.comp.axis_kind == "rotational" else fb @ axis_b
        cols[f"{e.drive}.{'tau' if e.comp.axis_kind == 'rotational' else 'f'}"] = effort
        cols[f"{e.drive}.power"] = effort * cols[f"{e.name}.{e.comp.speeds[0][0]}"]


def _reaction_outputs(system, cols, ev, reac):
    """Columns a joint makes of its own reaction when it is a tree edge (it has no multipliers
    there): a joint class with ``reaction_outputs(a, b, p, f, tau)`` (jets of its frames, the
    reaction exerted on frame_b through it, N and N m, frame_b coordinates, torque about
    frame_b's origin) returning ``{suffix: value}``, e.g. a cut-force sensor. A cut joint makes
    the same columns from its multipliers in :meth:`Joint.outputs`."""
    topo = system.topology
    for e in topo.edges:
        if e.kind != "joint" or not e.comp.has_reaction_outputs or e.name in topo.cut or e.name not in reac:
            continue
        fb, tb = reac[e.name]
        for key, val in e.comp.reaction_outputs(ev.jets[e.node_a], ev.jets[e.node_b], system.P[e.name], fb,
                                                tb).items():
            cols[f"{e.name}.{key}"] = val


def _flange_constraints(system, cols, ev, lam):
    """A flange constraint's own columns (:meth:`FlangeConstraint.outputs`: e.g. a gear's
    torques on its axes, from its rows' multipliers, :func:`flange_rows.flange_flows`)."""
    rows = system.topology.flange_rows
    if not rows:
        return
    lam_rows = system.row_multipliers(ev, lam)
    for fr in rows:
        flows = flange_flows(system, fr, lam_rows.get(fr.name, {}))
        states = flange_states(system, fr, ev.jets, ev.t, ev.q, ev.u)
        for key, val in fr.comp.outputs(ev.t, states, system.P[fr.name], flows).items():
            cols[f"{fr.name}.{key}"] = val


#: time (s) of the central difference of an element's potential along the motion (its rate)
POTENTIAL_DT = 1e-6


def _moved(frame, dt):
    """The frame state ``dt`` seconds along its motion (to first order)."""
    w = frame.w
    R = frame.R + dt * np.array([cross(w, frame.R[:, k]) for k in range(3)]).T
    return type(frame)(frame.r + dt * frame.v, R, frame.v, frame.w)


def _mixed(comp, base):
    """Whether an element with a potential may also do other work: not declared conservative,
    or its answer depends on its parameters (a spring-damper's rate)."""
    return type(comp).potential is not base.potential and (
        not comp.conservative or type(comp).conserves_energy is not base.conserves_energy)


def _elements(system, cols, ev, rates):
    """Force and flange elements' own outputs (:meth:`ForceElement.outputs`, its frames as
    :class:`MeasuredFrame`: with accelerations by ``rates``, see :func:`_link_rates`), the power each
    delivers to the mechanism (W: force times its point's velocity, torque times its frame's
    angular velocity, a flange's flow times its rate), for those with a potential that
    potential (J), and for those that may do work beyond it (a spring-damper) the power
    beyond the potential's rate, ``power_nc`` (W; the rate by a central difference of
    :data:`POTENTIAL_DT` along the motion, exact for a potential quadratic in a flange's
    coordinate)."""
    topo, jets, dt = system.topology, ev.jets, POTENTIAL_DT
    for path, comp, ports in topo.forces:
        frames = {pn: system.frame_state(jets[n]) for pn, n in ports.items()}
        p = system.P[path]
        measured = {pn: MeasuredFrame(jets[n], rates, n) for pn, n in ports.items()}
        for key, val in comp.outputs(ev.t, measured, p).items():
            cols[f"{path}.{key}"] = val
        power = 0.0
        for pn, (f, tau) in comp.wrenches(ev.t, frames, p).items():
            power = power + np.asarray(f) @ frames[pn].v + np.asarray(tau) @ frames[pn].w
        cols[f"{path}.power"] = power
        if type(comp).potential is not ForceElement.potential:
            cols[f"{path}.potential"] = comp.potential(frames, p)
        if _mixed(comp, ForceElement):
            ahead = comp.potential({pn: _moved(f, dt) for pn, f in frames.items()}, p)
            back = comp.potential({pn: _moved(f, -dt) for pn, f in frames.items()}, p)
            cols[f"{path}.power_nc"] = power + (ahead - back) / (2 * dt)
    for path, comp in topo.flange_elements:
        roots = {pn: topo.flange_of[PortRef(comp, pn, "flange")] for pn, pt in comp.ports().items()
                 if pt.kind == "flange"}
        states = {pn: system.flange_state(r, jets, ev.t, ev.q, ev.u) for pn, r in roots.items()}
        p = system.P[path]
        for key, val in comp.outputs(ev.t, states, p).items():
            cols[f"{path}.{key}"] = val
        power = 0.0
        for pn, flow in comp.flange_forces(ev.t, states, p).items():
            power = power + flow * states[pn][1]
        cols[f"{path}.power"] = power
        if type(comp).potential is not FlangeElement.potential:
            cols[f"{path}.potential"] = comp.potential(states, p)
        if _mixed(comp, FlangeElement):
            ahead = comp.potential({pn: (s + dt * v, v) for pn, (s, v) in states.items()}, p)
            back = comp.potential({pn: (s - dt * v, v) for pn, (s, v) in states.items()}, p)
            cols[f"{path}.power_nc"] = power + (ahead - back) / (2 * dt)
