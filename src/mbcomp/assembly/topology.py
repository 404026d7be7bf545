"""Topology: which frames are one, the spanning tree from the ground, cut joints, DOF.

Built once from a validated :class:`~mbcomp.model.FlatModel`; immutable afterwards.

* Connected frame ports are merged into *frame nodes* (union-find); the world is node
  ``ROOT``. Every two-frame component that is a :class:`~mbcomp.roles.Joint` (rigid offsets are
  0-DOF joints) is an edge; every :class:`~mbcomp.roles.Ground` is an edge from ``ROOT``.
* A minimum spanning tree (Kruskal) keeps rigid offsets, driven joints and joints
  with fixed start values in the tree and cuts the joints with most freedom: a cut joint with
  ``k`` DOF adds ``6 - k`` constraints, so this gives the fewest constraint equations. Ties
  are broken as networkx breaks them (:func:`spanning_tree` gives the tree of
  ``networkx.minimum_spanning_tree(topo.graph, algorithm="kruskal")``), without importing
  networkx (~0.15 s) on the way to every simulation.
* A *constraint-only joint* (``tree_edge = False``: constraint rows, no coordinates; the
  library's rolling contacts) is never a tree edge; it is always cut.
* A group of frames carrying mass but joined to nothing that reaches the world is an error,
  unless one of its bodies is marked free (``Model.add(..., free=True)``): that body gets an
  implicit :class:`~mbcomp.modeling.free_joint.FreeMotion` from the world (a wheel touching
  the ground only through a rolling contact floats in the tree).
* A joint whose two frames are one frame node is an error; an open frame of a rigid offset
  (a marker) is a frame node of its own (:attr:`Topology.open_frames`).

Examples
--------
>>> from mbcomp import Model
>>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
>>> m = Model(); w = m.add("world", World()); j = m.add("j", Revolute())
>>> L = m.add("L", FixedTranslation(r=(1, 0, 0))); b = m.add("b", PointMass())
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, L.frame_a); m.connect(L.frame_b, b.frame_a)
>>> topo = Topology(m.validate())
>>> [e.name for e in topo.tree], topo.cut
(['world', 'j', 'L'], [])
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

from ..errors import ModelError, Problem
from ..modeling.component import PortRef
from ..modeling.free_joint import FreeMotion, FreeTranslation
from .flange_rows import cut_rotational, flange_constraint_edges, geared_joints, rotor_nodes
from .rebinding import Rebinding, is_point

__all__ = ["Topology", "Edge", "TreeLinks", "ROOT", "spanning_tree", "no_gravity_note"]

ROOT = -1


@dataclass
class Edge:
    """A two-frame component (joint, rigid offset) or a ground frame (``node_a = ROOT``)."""

    name: str
    comp: object
    node_a: int
    node_b: int
    kind: str  # "joint" | "ground"
    dof: int = 0
    parent: int = None
    child: int = None
    forward: bool = True  # frame_a on the parent side
    drive: str = None  # name of the Drive prescribing this joint's coordinate
    q: slice = field(default_factory=lambda: slice(0, 0))
    u: slice = field(default_factory=lambda: slice(0, 0))
    implicit: bool = False

    @property
    def nodes(self):
        """The frames a cut edge's rows are taken over, in slot order (frame_a, frame_b); a
        flange constraint's rows (:class:`~mbcomp.assembly.flange_rows.FlangeRows`) have more."""
        return (self.node_a, self.node_b)


class _UnionFind:
    def __init__(self):
        self.parent = {}

    def find(self, x):
        """The root of ``x``'s set, the object first added (``x`` joins as its own set).
        Every stored parent is such an object, so past ``x`` itself roots are told by
        identity (a port's ``__eq__`` is a Python call; the assembly finds ~40 times a port)."""
        parent = self.parent
        p = parent.get(x)
        if p is None:
            parent[x] = x
            return x
        if p is x or p == x:
            return p
        while True:  # path halving
            g = parent[p]
            if g is p:
                return p
            parent[x] = g
            x = g
            p = parent[x]
            if p is x:
                return x

    def union(self, a, b):
        self.parent[self.find(a)] = self.find(b)


def spanning_tree(nodes, edges):
    """Kruskal's minimum spanning forest of a multigraph, with networkx's tie-breaking.

    Equal weights are ordered as ``networkx.MultiGraph(...).edges(keys=True)`` lists the
    edges (nodes in the order given, each node's neighbours in the order they were first
    joined to it, parallel edges in the order added), then stably sorted by weight: the tree
    is the one ``networkx.minimum_spanning_tree(G, algorithm="kruskal")`` gives for the graph
    built by adding ``nodes`` and then ``edges`` in order.

    Parameters
    ----------
    nodes : iterable of hashable
        Every node, in insertion order.
    edges : iterable of (u, v, key, weight)
        The edges in insertion order; keys unique.

    Returns
    -------
    list of (u, v, key)
        The tree edges in the order Kruskal's algorithm accepted them.

    Examples
    --------
    >>> spanning_tree([0, 1, 2], [(0, 1, "a", 1.0), (1, 2, "b", 1.0), (0, 2, "c", 1.0), (2, 2, "d", 0.0)])
    [(0, 1, 'a'), (0, 2, 'c')]
    """
    adj = {n: {} for n in nodes}
    for u, v, key, w in edges:
        kd = adj[u].get(v)
        if kd is None:
            kd = adj[u][v] = adj[v][u] = {}
        kd[key] = w
    ordered, seen = [], set()
    for n, nbrs in adj.items():
        for m, kd in nbrs.items():
            if m not in seen:
                ordered += [(w, n, m, key) for key, w in kd.items()]
        seen.add(n)
    ordered.sort(key=lambda e: e[0])  # stable: ties keep the listing order
    trees, tree = _UnionFind(), []
    for _, n, m, key in ordered:
        if trees.find(n) != trees.find(m):
            trees.union(n, m)
            tree.append((n, m, key))
    return tree


def _components(nodes, edges):
    """The node sets joined by ``edges`` (``(u, v, key, weight)``), one per connected group."""
    groups = _UnionFind()
    for n in nodes:
        groups.find(n)
    for u, v, _, _ in edges:
        groups.union(u, v)
    members = {}
    for n in nodes:
        members.setdefault(groups.find(n), set()).add(n)
    return list(members.values())


def _frame_nodes(frames):
    """Number the groups of connected frames (by the path of their root port) and list each
    group's ports; ``({port: node}, {node: sorted port paths})``. One pass over the ports:
    the list per node used to scan every port (a 1000-link chain assembled in 43 s, now 0.1 s)."""
    roots = sorted({frames.find(x) for x in frames.parent}, key=lambda r: r.path)
    index = {r: i for i, r in enumerate(roots)}
    port_node = {x: index[frames.find(x)] for x in frames.parent}
    members = {i: [] for i in index.values()}
    for x, i in port_node.items():
        members[i].append(x.path)
    return port_node, {i: sorted(paths) for i, paths in members.items()}


def _self_joined(path, comp, ports):
    """The problem of a joint whose two frames are one frame node (``ports``)."""
    others = [x for x in ports if x.rsplit(".", 1)[0] != path]
    how = f" (joined through {', '.join(others)})" if others else " (connected to each other)"
    return Problem(path, f"both frames of this {type(comp).__name__}, frame_a and frame_b, are the same frame{how}, "
                         "so it joins nothing to nothing",
                   f"connect {path}.frame_a and {path}.frame_b to two different frames (e.g. the world or the "
                   "previous link on frame_a, the next body on frame_b)")


def _wrong_axis(element, joint):
    """The problem of a flange element acting on a joint axis of the other kind."""
    unit = {"rotational": "torque (N m)", "translational": "force (N)"}
    right = {"rotational": "a Revolute", "translational": "a Prismatic"}
    return Problem(element.path, f"this {type(element).__name__} applies a {unit[element.axis_kind]}, but "
                                 f"{joint.path} ({type(joint).__name__}) has a {joint.axis_kind} axis",
                   f"connect it to {right[element.axis_kind]}, or use the {joint.axis_kind} element (Force and "
                   "TranslationalSpringDamper on a Prismatic, Torque and the Rotational* elements on a Revolute)")


def _floating(topo, comp_nodes):
    """The problem of a group of frames with mass joined to nothing that reaches the world."""
    bodies = [path for path, _, n in topo.bodies if n in comp_nodes]
    if len(bodies) == 1:
        what = ("is joined to nothing that reaches the world (through joints; springs and forces do not "
                "hold it), so it would fall freely")
    else:
        what = ("are joined to each other but not to the world (a floating assembly; springs and forces do "
                "not hold it), so they would fall freely together")
    first = bodies[0].rsplit(".", 1)[-1]
    return Problem(", ".join(bodies), what,
                   f"connect it to the mechanism (a joint from world.frame_b or another body), or, if it floats on "
                   f"purpose, mark it: model.add({first!r}, ..., free=True) (start values {bodies[0]}.free.r0, "
                   f".v0), or join it to the world through a FreeMotion")


def no_gravity_note(topo):
    """A note for a result when the model has no gravity source (no ``World``), else ``None``.

    Parameters
    ----------
    topo : Topology

    Returns
    -------
    str or None

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp import Model
    >>> from mbcomp.library import Fixed, Revolute, RigidBody
    >>> m = Model(); base = m.add("base", Fixed()); j = m.add("j", Revolute())
    >>> b = m.add("b", RigidBody(m=1.0, I=np.eye(3)))
    >>> m.connect(base.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> no_gravity_note(Topology(m.validate()))[:45]
    'the model has no World, so there is no gravit'
    """
    if topo.gravity_source is not None:
        return None
    return ("the model has no World, so there is no gravity: bodies feel only the model's forces -> "
            "add model.add('world', World()) for gravity (World(g=(0, 0, 0)) says 'no gravity' explicitly)")


class Topology(Rebinding):
    """Frame nodes, spanning tree, cut joints and coordinates of a flat model (and, from
    :class:`~mbcomp.assembly.rebinding.Rebinding`, the same topology rebound to another model
    of its structure)."""

    def __init__(self, flat):
        self.flat = flat
        comps = flat.components
        probs = []
        frames, flanges = _UnionFind(), _UnionFind()
        for path, comp in comps.items():
            for pname, port in comp.ports().items():
                uf = frames if port.kind == "frame" else flanges
                uf.find(PortRef(comp, pname, port.kind))
        for a, b in flat.connections:
            (frames if a.kind == "frame" else flanges).union(a, b)
        self.port_node, self.node_ports = _frame_nodes(frames)
        self.n_nodes = len(self.node_ports)

        def node(comp, pname):
            return self.port_node[PortRef(comp, pname, "frame")]

        self.edges, self.bodies, self.forces, self.flange_elements, self.drives = [], [], [], [], []
        self.flange_constraints, self.flange_inertias = [], []  # gears; rotors (assembly/flange_rows.py)
        self.gravity_source = None
        for path, comp in comps.items():
            role = comp.role
            if role == "ground":
                self.edges.append(Edge(path, comp, ROOT, node(comp, "frame_b"), "ground"))
                if comp.gravity(comp.p) is not None:
                    if self.gravity_source is not None:
                        probs.append(Problem(path, f"a second gravity source besides {self.gravity_source}",
                                             "keep one World in the model"))
                    else:
                        self.gravity_source = path
            elif role == "joint":
                self.edges.append(Edge(path, comp, node(comp, "frame_a"), node(comp, "frame_b"), "joint", dof=comp.nu))
                if self.edges[-1].node_a == self.edges[-1].node_b:
                    probs.append(_self_joined(path, comp, self.node_ports[self.edges[-1].node_a]))
            elif role == "body":
                self.bodies.append((path, comp, node(comp, "frame_a")))
            elif role == "force":
                self.forces.append((path, comp, {pn: node(comp, pn) for pn, pt in comp.ports().items()
                                                  if pt.kind == "frame"}))
            elif role == "flange_force":
                self.flange_elements.append((path, comp))
            elif role == "drive":
                self.drives.append((path, comp))
            elif role == "flange_constraint":
                self.flange_constraints.append((path, comp))
            elif role == "flange_inertia":
                self.flange_inertias.append((path, comp))
            else:
                probs.append(Problem(path, f"{type(comp).__name__} has no known role",
                                     "subclass one of Ground, Body, Joint, ForceElement, FlangeElement, FlangeConstraint, "
                                     "FlangeInertia, Drive"))

        probs += self._flanges(flanges)
        if probs:
            raise ModelError(probs)

        self._spanning_tree()
        probs = cut_rotational(self)
        if probs:
            raise ModelError(probs)
        self._coordinates()
        probs = self._rigid_contacts()
        if probs:
            raise ModelError(probs)
        self.rotors = rotor_nodes(self)

    def _rigid_contacts(self):
        """A constraint-only joint (a contact) whose two frames are one rigid link (both
        fixed to the world, or moved by the same joint): its rows can never change and the
        force it carries is undetermined (a ball held fixed and touching the floor: the hold
        and the floor share its weight in any proportion)."""
        link_of, probs = self.links.link_of, []
        for e in self.edges:
            if e.kind == "joint" and not e.comp.tree_edge and link_of.get(e.node_a, -2) == link_of.get(e.node_b, -3):
                k = link_of[e.node_a]
                where = "the world" if k < 0 else f"one rigid link (moved by {self.links.edges[k].name})"
                probs.append(Problem(e.name, f"both frames this {type(e.comp).__name__} joins are fixed to {where}: "
                                     "it can never move, and the force it carries is undetermined",
                                     "remove it, or give a body it touches freedom (a joint between its two sides)"))
        return probs

    def _flanges(self, flanges):
        """Which joint axis each flange node belongs to, and which joint each drive drives;
        the problems found on the way."""
        probs = []
        self.flange_owner = {}  # flange root -> (edge name, "axis" | "support")
        self.flange_of = {}  # PortRef -> flange root
        members = {}
        for x in flanges.parent:
            members.setdefault(flanges.find(x), []).append(x)
        edge_by_name = {e.name: e for e in self.edges}
        for root, ports in members.items():
            owners = [x for x in ports if x.component.role == "joint"]
            # a flange constraint's flanges are checked with its rows (flange_rows.py)
            users = [x for x in ports if x.component.role not in ("joint", "flange_constraint")]
            for x in ports:
                self.flange_of[x] = root
            if len(owners) > 1:
                probs.append(Problem(", ".join(x.path for x in owners),
                                     "joint flanges are connected directly to each other",
                                     "connect each joint flange to elements (springs, drives), not to another joint"))
            elif not owners and users:
                probs.append(Problem(", ".join(x.path for x in users), "flange is connected to no joint axis",
                                     "connect it to a Revolute/Prismatic axis or support flange"))
            elif owners:
                self.flange_owner[root] = (owners[0].component.path, owners[0].name)
                kind = owners[0].component.axis_kind
                probs += [_wrong_axis(x.component, owners[0].component) for x in users
                          if kind and getattr(x.component, "axis_kind", None) not in (None, kind)]
        for path, comp in self.drives:
            root = self.flange_of[PortRef(comp, "flange_b", "flange")]
            owner = self.flange_owner.get(root)
            if owner is None or owner[1] != "axis":
                probs.append(Problem(f"{path}.flange_b", "drive is not connected to a joint's axis flange",
                                     "connect it to joint.axis of a Revolute or Prismatic"))
                continue
            e = edge_by_name[owner[0]]
            if e.drive is not None:
                probs.append(Problem(path, f"a second drive on joint {e.name!r} (already driven by {e.drive!r}): a "
                                           "joint's coordinate can be prescribed only once",
                                     f"keep one drive per joint: remove {path} or {e.drive}"))
            e.drive = path
        self.flange_rows, more = flange_constraint_edges(self, members)
        return probs + more

    # --------------------------------------------------------------------------------------
    def _weight(self, e):
        if e.kind == "ground" or e.dof == 0:
            return 0.0
        if e.drive:
            return -100.0
        w = float(e.dof)
        q0, qf, u0, uf = e.comp.start(e.comp.p)
        if any(qf) or any(uf):
            w -= 0.5
        w -= self._geared.get(e.name, 0.0)  # a geared angle cut would wrap; a reflected rotor needs the speed
        return w

    def _spanning_tree(self):
        self._geared = geared_joints(self)
        nodes = [ROOT, *range(self.n_nodes)]
        # the multigraph: (node_a, node_b, name, weight) of every edge that may be a tree edge
        self._graph_edges = graph = [(e.node_a, e.node_b, e.name, self._weight(e)) for e in self.edges
                                     # constraint-only joints (the library's contacts) are always cut
                                     if e.kind != "joint" or e.comp.tree_edge]
        self._float(nodes, graph)
        tree_edges = {n: [] for n in nodes}  # node -> [(neighbour, name)] along the tree
        for a, b, k in spanning_tree(nodes, graph):
            tree_edges[a].append((b, k))
            tree_edges[b].append((a, k))
        tree_keys = {k for pairs in tree_edges.values() for _, k in pairs}
        by_name = {e.name: e for e in self.edges}
        self.tree, self.cut = [], []
        # breadth-first from the root gives parents before children
        visited = {ROOT}
        frontier = [ROOT]
        while frontier:
            nxt = []
            for n in frontier:
                for m, k in sorted(tree_edges[n], key=lambda x: x[1]):
                    if m in visited:
                        continue
                    e = by_name[k]
                    e.parent, e.child = n, m
                    e.forward = e.node_a == n
                    visited.add(m)
                    self.tree.append(e)
                    nxt.append(m)
            frontier = nxt
        self.cut = [e.name for e in self.edges if e.name not in tree_keys]
        self.unreached = sorted(set(range(self.n_nodes)) - visited)
        probs = []
        for name in self.cut:
            e = by_name[name]
            if e.drive:
                probs.append(Problem(e.name, "driven joint closes a kinematic loop and cannot be a tree joint",
                                     "drive a different joint of the loop"))
        if probs:
            raise ModelError(probs)

    def _float(self, nodes, graph):
        """An implicit :class:`FreeMotion` from the world for each body marked ``free``
        (``Model.add(..., free=True)``) in a group of frames joined to nothing that reaches
        the world; such a group with mass and no body marked free is an error (a forgotten
        connection would fall freely), and so is a body marked free that is joined to the world."""
        marked = [(path, n) for path, _, n in self.bodies if path in self.flat.free]
        mass_nodes = {n for _, _, n in self.bodies}
        self.floating, probs = [], []
        for comp_nodes in sorted(_components(nodes, graph), key=min):
            mine = [(path, n) for path, n in marked if n in comp_nodes]
            if ROOT in comp_nodes:
                probs += [Problem(path, "is marked free but is joined to the world through joints",
                                  f"drop free=True from model.add({path.rsplit('.', 1)[-1]!r}, ...), or disconnect "
                                  "it") for path, _ in mine]
                continue
            if not any(n in mass_nodes for n in comp_nodes):
                continue  # massless and unconnected: nothing moves it (checked in the system)
            if not mine:
                probs.append(_floating(self, comp_nodes))
                continue
            probs += [Problem(path, f"is marked free, and so is {mine[0][0]}, which it is joined to: one free "
                                    "joint moves them all", f"mark only {mine[0][0]} free")
                      for path, _ in mine[1:]]
            path, n = mine[0]
            point = comp_nodes == {n} and all(is_point(c) for _, c, nn in self.bodies if nn == n)
            fm = FreeTranslation() if point else FreeMotion()  # a lone point mass has no rotation to move
            fm.name = name = f"{path}.free"
            dof = 3 if point else 6
            self.edges.append(Edge(name, fm, ROOT, n, "joint", dof=dof, implicit=True))
            self.floating.append(name)
            graph.append((ROOT, n, name, float(dof)))
        if probs:
            raise ModelError(probs)

    @property
    def open_frames(self):
        """Port paths of joints' frames connected to nothing: the open ends of rigid offsets
        (``FixedTranslation.frame_b`` as a marker), which the model's validation allows."""
        return sorted(paths[0] for paths in self.node_ports.values()
                      if len(paths) == 1 and self._owner(paths[0]).role == "joint")

    def _owner(self, port_path):
        return self.flat.components[port_path.rsplit(".", 1)[0]]

    @cached_property
    def links(self):
        """The moving links of the spanning tree (:class:`TreeLinks`; made once)."""
        return TreeLinks(self)

    @property
    def graph(self):
        """The multigraph the tree was chosen from, as a ``networkx.MultiGraph``: frame nodes
        (``ROOT`` the world), one edge per possible tree edge keyed by its name, with its
        ``weight``. Built on each access (networkx is imported only here)."""
        import networkx as nx

        G = nx.MultiGraph()
        G.add_nodes_from([ROOT, *range(self.n_nodes)])
        for a, b, name, w in self._graph_edges:
            G.add_edge(a, b, key=name, weight=w)
        return G

    def _coordinates(self):
        nq = nu = 0
        self.q_names, self.u_names, self.q_units, self.u_units = [], [], [], []
        for e in self.tree:
            if e.kind != "joint" or e.drive or e.dof == 0:
                continue
            c = e.comp
            e.q, e.u = slice(nq, nq + c.nq), slice(nu, nu + c.nu)
            nq, nu = nq + c.nq, nu + c.nu
            self.q_names += [f"{e.name}.{n}" for n, _ in c.coordinates]
            self.q_units += [u for _, u in c.coordinates]
            self.u_names += [f"{e.name}.{n}" for n, _ in c.speeds]
            self.u_units += [u for _, u in c.speeds]
        self.nq, self.nu = nq, nu

    def edge(self, name) -> Edge:
        for e in self.edges:
            if e.name == name:
                return e
        raise KeyError(name)



class TreeLinks:
    """The moving links of a topology's spanning tree: a *link* is the set of frames rigidly
    moved by one tree joint with speeds (everything down the tree up to the next joint with
    speeds), numbered in tree order (parents first); frames fixed to the ground have link -1.
    Drives make their joint a rigid (rheonomic) part of the parent link. What the recursive
    algorithms (:mod:`mbcomp.assembly.recursive`) walk.

    Attributes
    ----------
    edges : list of Edge
        The tree joints with speeds, parents before children; link ``i`` is ``edges[i]``'s child side.
    parent : list of int
        Parent link of each link (-1: the ground).
    link_of : dict
        Frame node -> link (-1 for the ground and frames fixed to it).
    cols : list of slice
        Each link's columns in ``u``.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j1 = m.add("j1", Revolute()); b1 = m.add("b1", PointMass())
    >>> j2 = m.add("j2", Revolute()); b2 = m.add("b2", PointMass())
    >>> m.connect(w.frame_b, j1.frame_a); m.connect(j1.frame_b, b1.frame_a)
    >>> m.connect(b1.frame_a, j2.frame_a); m.connect(j2.frame_b, b2.frame_a)
    >>> t = mbcomp.assemble(m).topology.links
    >>> [e.name for e in t.edges], t.parent
    (['j1', 'j2'], [-1, 0])
    """

    def __init__(self, topology):
        self.edges, self.parent, self.cols = [], [], []
        link_of = {ROOT: -1}
        for e in topology.tree:
            up = link_of[e.parent]
            if e.u.stop > e.u.start:
                link_of[e.child] = len(self.edges)
                self.edges.append(e)
                self.parent.append(up)
                self.cols.append(e.u)
            else:
                link_of[e.child] = up
        self.link_of = link_of
        self.n = len(self.edges)

    def ancestors(self, i):
        """Link ``i`` and its ancestors, from ``i`` to the root."""
        out = []
        while i >= 0:
            out.append(i)
            i = self.parent[i]
        return out
