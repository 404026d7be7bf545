"""Flange constraints and rotors: rows tying joint-axis coordinates, and inertia on joint axes.

A :class:`~mbcomp.modeling.roles.FlangeConstraint` (an ideal gear, a rack and pinion, a belt)
declares its rows as linear forms over its flanges' coordinates. Each flange is a 1-DOF
joint's ``axis`` (coordinate ``s`` of the joint: an angle in rad or a displacement in m), a
joint's ``support`` (fixed to frame_a: ``s = 0``) or an unconnected optional flange (fixed,
0). The coordinate of an axis flange is written as a jet over the *local twists of the
joint's two frames*, exactly as a cut joint writes its rows (:mod:`mbcomp.assembly.jets`),
with ``n`` the joint's axis (world, fixed in frame_a):

* rotational: ``ds/dt = n . (w_b - w_a)``; Jacobian ``-n`` on ``w_a``, ``n`` on ``w_b``;
  bias ``n . (alpha_b - alpha_a) + (w_a x n) . (w_b - w_a)``;
* translational, ``s = n . d`` with ``d = r_b - r_a``: ``ds/dt = n . (v_b - v_a) +
  (w_a x n) . d``; Jacobian ``-n`` on ``v_a``, ``n x d`` on ``w_a``, ``n`` on ``v_b``; bias
  ``n . (a_b - a_a) + (alpha_a x n + w_a x (w_a x n)) . d + 2 (w_a x n) . (v_b - v_a)``.

On a tree joint these are exactly ``ds/du = e_i`` and zero bias; on a driven joint the
drive's rate and acceleration (the frames' jets carry the prescribed motion). The value is
the joint's coordinate ``q_i`` (tree), the drive's ``s(t)``, or the joint's ``measure``
(a translational cut joint; a rotational cut joint's angle is measured in (-pi, pi] and
would jump, so the topology keeps geared joints in the tree and refuses a geared rotational
joint that must be cut).

A row ``sum_k c_k s_k`` over flanges on several joints is a covector over the twists of all
their frames: :class:`FlangeRows` is the "edge" that carries it (``nodes``: the frames, in
slot order), so the assembler treats it as it treats a cut joint (``C = jac [J_1; J_2; ...]``,
reactions as wrenches on those frames, covectors on the recursive algorithms' links). The
row kept is ``c(s) - c(s0) = 0`` (``s0``: the flanges' start coordinates).

A :class:`~mbcomp.modeling.roles.FlangeInertia` is a rotor ``J n n^T`` on the frame its flange
moves: :func:`rotors` lists them for the mass matrix, the forces, the reactions and the energy.
A reflected one (its ``reflected`` True: MuJoCo's armature) turns at its tree joint's own speed
``u_k``: :func:`reflected_rotors` lists ``(k, J)`` for ``M[k, k] += J``, the momenta and the
energy; it puts no wrench on a frame (its torque ``-J du_k/dt`` acts inside the joint, so the
joint's reaction carries it).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import Fixed, Revolute, RigidBody, IdealGear
>>> m = mbcomp.Model(); base = m.add("base", Fixed())
>>> j1 = m.add("j1", Revolute()); j2 = m.add("j2", Revolute(phi0=0.3))
>>> b1 = m.add("b1", RigidBody(m=1.0, I=np.eye(3))); b2 = m.add("b2", RigidBody(m=1.0, I=np.eye(3)))
>>> g = m.add("gear", IdealGear(ratio=2.0))
>>> m.connect(base.frame_b, j1.frame_a); m.connect(j1.frame_b, b1.frame_a)
>>> m.connect(base.frame_b, j2.frame_a); m.connect(j2.frame_b, b2.frame_a)
>>> m.connect(g.flange_a, j1.axis); m.connect(g.flange_b, j2.axis)
>>> s = mbcomp.assemble(m)
>>> s.constraint_names(), s.evaluate(0.0, np.array([0.6, 0.3]), np.array([2.0, 1.0])).C.tolist()
(['gear.mesh'], [[1.0, -2.0]])
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError, Problem
from ..geometry.kinematics import cross
from ..modeling.component import PortRef
from ..modeling.roles import FlangeSum
from .jets import ScalarJet

__all__ = ["FlangeRows", "flange_constraint_edges", "flange_starts", "flange_rows", "flange_flows", "rotors",
           "rotor_nodes", "reflected_rotors", "reflected_joints"]


@dataclass
class FlangeRows:
    """A flange constraint as the assembler sees it: a cut "edge" over several frames.

    Attributes
    ----------
    name : str
        The component's path (row names ``<name>.<row>``).
    comp : FlangeConstraint
    nodes : tuple of int
        Frame nodes the rows' Jacobians are taken over (6 columns each: ``v``, ``w``).
    ports : dict
        Flange port -> ``(edge name, slot of its frame_a in nodes, slot of its frame_b)``,
        or ``None`` for a fixed flange (a support, an unconnected optional flange).
    root : dict
        Flange port -> its flange node (the topology's ``flange_of``).
    """

    name: str
    comp: object
    nodes: tuple
    ports: dict
    root: dict = field(default_factory=dict)
    kind: str = "flange"


def _kind_problem(path, comp, port, want, joint):
    return Problem(f"{path}.{port}", f"this {type(comp).__name__} needs a {want} axis on {port}, but {joint.path} "
                                     f"({type(joint).__name__}) has a {joint.axis_kind} axis",
                   f"connect {port} to a {'Revolute' if want == 'rotational' else 'Prismatic'}'s axis")


def flange_constraint_edges(topo, members):
    """The :class:`FlangeRows` of every flange constraint of ``topo`` (``topo.flange_constraints``:
    ``(path, comp)``) and the problems found: a flange on no joint, on the wrong kind of axis.

    ``members`` maps flange node -> its ports."""
    out, probs = [], []
    edges = {e.name: e for e in topo.edges}
    for path, comp in topo.flange_constraints:
        nodes, ports, roots = [], {}, {}
        for pname, port in comp.ports().items():
            if port.kind != "flange":
                continue
            root = topo.flange_of[PortRef(comp, pname, "flange")]
            roots[pname] = root
            owner = topo.flange_owner.get(root)
            if owner is None:
                if len(members[root]) > 1 or not port.optional:
                    probs.append(Problem(f"{path}.{pname}", "flange is connected to no joint axis",
                                         "connect it to a Revolute/Prismatic axis or support flange"))
                ports[pname] = None
                continue
            e = edges[owner[0]]
            want = comp.flange_kinds.get(pname)
            if want and e.comp.axis_kind != want:
                probs.append(_kind_problem(path, comp, pname, want, e.comp))
            if owner[1] != "axis":
                ports[pname] = None
                continue
            slots = []
            for n in (e.node_a, e.node_b):
                if n not in nodes:
                    nodes.append(n)
                slots.append(nodes.index(n))
            ports[pname] = (e.name, *slots)
        out.append(FlangeRows(path, comp, tuple(nodes), ports, roots))
    return out, probs


def geared_joints(topo):
    """``{joint name: how much its spanning-tree weight is lowered}`` for the joints whose axis
    a flange constraint ties (0.25: kept in the tree before plain joints of as many speeds) or
    a reflected rotor turns (1.5: it needs the joint's own speed, so the joint comes before
    rigid offsets and welds, and a loop is cut elsewhere wherever it can be)."""
    out = {v[0]: 0.25 for fr in topo.flange_rows for v in fr.ports.values() if v is not None}
    out.update({name: out.get(name, 0.0) + 1.5 for name in reflected_joints(topo)})
    return out


def cut_rotational(topo):
    """Problems of geared rotational joints that close a loop (their angle would wrap)."""
    probs = []
    for fr in topo.flange_rows:
        for pname, v in fr.ports.items():
            if v is not None and v[0] in topo.cut and topo.edge(v[0]).comp.axis_kind == "rotational":
                probs.append(Problem(f"{fr.name}.{pname}", f"{v[0]} closes a kinematic loop, so its angle is "
                                     "measured in (-pi, pi] and a gear row on it would jump by 2 pi",
                                     f"cut another joint of the loop (give {v[0]} fixed start values, or remove "
                                     "a redundant joint), or gear a joint that is in the spanning tree"))
    return probs


def flange_starts(system):
    """Start coordinate ``s0`` of every geared axis flange, by joint name (numbers): the joint's
    start value, or its drive's position at t = 0."""
    out = {}
    for fr in system.topology.flange_rows:
        for v in fr.ports.values():
            if v is None or v[0] in out:
                continue
            e = system.edge(v[0])
            if e.drive:
                out[v[0]] = float(system.topology.flat.components[e.drive].motion(0.0, system.P[e.drive])[0])
            else:
                out[v[0]] = float(e.comp.start(system.P[e.name])[0][0])
    return out


def _axis_jet(system, e, a, b, t, q):
    """``(val, jac (12,), dot, bias)`` of joint ``e``'s coordinate over its frames ``a``, ``b``."""
    n = e.comp.axis_world(a.R, system.P[e.name])
    wn = cross(a.w, n)
    z = np.zeros(3)
    if e.comp.axis_kind == "rotational":
        dw = b.w - a.w
        jac = np.concatenate((z, -n, z, n))
        dot = n @ dw
        bias = n @ (b.alpha - a.alpha) + wn @ dw
    else:
        d, dv = b.r - a.r, b.v - a.v
        jac = np.concatenate((-n, cross(n, d), n, z))
        dot = n @ dv + wn @ d
        bias = n @ (b.a - a.a) + (cross(a.alpha, n) + cross(a.w, wn)) @ d + 2.0 * (wn @ dv)
    if e.drive:
        val = system.topology.flat.components[e.drive].motion(t, system.P[e.drive])[0]
    elif e.q.stop > e.q.start:
        val = q[e.q.start]
    else:
        val = e.comp.measure(a, b, system.P[e.name])[0]
    return val, jac, dot, bias


def flange_rows(system, fr, jets, t, q):
    """``[(row name, ScalarJet)]`` of flange constraint ``fr`` (a :class:`FlangeRows`) at the
    frames' ``jets``: Jacobian over ``fr.nodes`` (6 columns each), value ``c(s) - c(s0)``."""
    comp = fr.comp
    forms = comp.rows({pn: FlangeSum({pn: 1.0}) for pn in fr.ports}, system.P[fr.name])
    k = 6 * len(fr.nodes)
    axes = {}
    for pn, v in fr.ports.items():
        if v is not None:
            e = system.edge(v[0])
            axes[pn] = _axis_jet(system, e, jets[e.node_a], jets[e.node_b], t, q)
    out = []
    for rname, form in forms:
        val = dot = bias = 0.0
        jac = np.zeros(k, object)
        for pn, c in form.terms.items():
            if pn not in fr.ports:
                raise KeyError(f"{fr.name}: row {rname!r} names {pn!r}, which is not one of its flanges")
            if fr.ports[pn] is None:
                continue
            s, jk, sd, sb = axes[pn]
            _, ia, ib = fr.ports[pn]
            val = val + c * (s - system.flange_s0[fr.ports[pn][0]])
            dot, bias = dot + c * sd, bias + c * sb
            jac[6 * ia:6 * ia + 6] = jac[6 * ia:6 * ia + 6] + c * jk[:6]
            jac[6 * ib:6 * ib + 6] = jac[6 * ib:6 * ib + 6] + c * jk[6:]
        out.append((rname, ScalarJet(val, np.array(list(jac)), dot, bias)))
    return out


def flange_flows(system, fr, lam_rows):
    """The torque or force constraint ``fr`` puts on each of its flanges, ``-sum_r lam_r c_{r,k}``
    (``lam_rows``: row name -> multiplier, sign of ``M du/dt + A^T lam = f``; a dropped row
    is missing and counts 0)."""
    forms = fr.comp.rows({pn: FlangeSum({pn: 1.0}) for pn in fr.ports}, system.P[fr.name])
    flows = {pn: 0.0 for pn in fr.ports}
    for rname, form in forms:
        lam = lam_rows.get(rname, 0.0)
        for pn, c in form.terms.items():
            flows[pn] = flows[pn] - c * lam
    return flows


def flange_states(system, fr, jets, t, q, u):
    """``{port: (s, v)}`` of a flange constraint's flanges (a fixed flange: ``(0, 0)``)."""
    return {pn: ((0.0, 0.0) if v is None else system.flange_state(fr.root[pn], jets, t, q, u))
            for pn, v in fr.ports.items()}


def _rotor_owner(topo, comp):
    """``(edge name, "axis" | "support")`` of the joint flange a rotor is on, or None."""
    pname = next(n for n, port in comp.ports().items() if port.kind == "flange")
    return topo.flange_owner.get(topo.flange_of[PortRef(comp, pname, "flange")])


def reflected_joints(topo):
    """Names of the joints whose axis carries a reflected rotor (kept in the spanning tree
    where the model allows: the rotor needs the joint's own speed)."""
    out = set()
    for path, comp in topo.flange_inertias:
        owner = _rotor_owner(topo, comp)
        if owner is not None and comp.reflected(comp.p):
            out.add(owner[0])
    return out


def _reflected_problem(topo, path, comp, e, port):
    """Why a reflected rotor cannot sit where it is (None when it can): it needs the axis of a
    joint with one speed of its own (a tree joint, not driven)."""
    kind = type(comp).__name__
    if port != "axis":
        why, fix = f"is on {e.name}'s support flange, which does not turn", f"connect it to {e.name}.axis"
    elif e.drive:
        why, fix = (f"is on {e.name}, whose motion {e.drive} prescribes (no speed of its own)",
                    "use Inertia (a rotor on frame_b: the drive's effort carries it), or remove the drive")
    elif e.name in topo.cut:
        why, fix = (f"is on {e.name}, which closes a kinematic loop (no speed of its own)",
                    f"keep {e.name} in the spanning tree: cut another joint of the loop")
    elif e.u.stop - e.u.start != 1:
        why, fix = (f"is on {e.name} ({type(e.comp).__name__}), a joint of {e.u.stop - e.u.start} speeds",
                    "put it on a 1-DOF joint's axis (Revolute, Prismatic)")
    else:
        return None
    return Problem(path, f"the {kind} turns at its joint's own rate, but it {why}", fix)


def rotor_nodes(topo):
    """``[(path, comp, node, edge name)]`` of every rotor (:class:`FlangeInertia`) of ``topo``:
    the frame its flange moves (the joint's frame_b on ``axis``, frame_a on ``support``).
    Raises :class:`~mbcomp.errors.ModelError` for a reflected rotor on no joint speed of its own."""
    out, probs = [], []
    for path, comp in topo.flange_inertias:
        owner = _rotor_owner(topo, comp)
        if owner is None:
            continue  # reported by the topology
        e = topo.edge(owner[0])
        if comp.reflected(comp.p):
            probs.append(_reflected_problem(topo, path, comp, e, owner[1]))
        out.append((path, comp, e.node_b if owner[1] == "axis" else e.node_a, e.name))
    probs = [p for p in probs if p is not None]
    if probs:
        raise ModelError(probs)
    return out


def reflected_rotors(system):
    """``[(speed column, J)]`` of the reflected rotors (:meth:`FlangeInertia.reflected`): each
    turns at its tree joint's own speed ``u_k`` (kinetic energy ``J u_k^2 / 2``), so it adds
    ``J`` (kg m^2 or kg) to ``M[k, k]`` and nothing to the forces."""
    out = []
    for path, comp, node, ename in system.topology.rotors:
        if comp.reflected(system.P[path]):
            out.append((system.edge(ename).u.start, comp.rotor(system.P[path])[0]))
    return out


def rotors(system, jets):
    """``[(node, Iw, gyroscopic)]``: each rotor's inertia ``J n n^T`` (kg m^2, world axes) on
    the frame node it turns with, and whether its gyroscopic moment acts (reflected rotors:
    :func:`reflected_rotors`)."""
    out = []
    for path, comp, node, ename in system.topology.rotors:
        if comp.reflected(system.P[path]):
            continue
        e = system.edge(ename)
        J, gyro = comp.rotor(system.P[path])
        n = e.comp.axis_world(jets[e.node_a].R, system.P[ename])
        out.append((node, J * np.outer(n, n), bool(gyro)))
    return out


def rotor_wrench(J, Iw, gyro):
    """The rotor's inertial torque at ``du/dt = 0`` (N m, world): ``Iw alpha (+ w x Iw w)``."""
    h = Iw @ J.alpha
    return h + cross(J.w, Iw @ J.w) if gyro else h
