"""One topology, another model of its structure: what a :class:`~mbcomp.assembly.topology.Topology`
chose from parameter values (:meth:`Rebinding.choices`), the values those choices read
(:meth:`Rebinding.probes`), and the topology rebound to another model's components
(:meth:`Rebinding.rebound`) -- the topology plans of :mod:`mbcomp.assembly.plan`.

:class:`Rebinding` is a part of :class:`~mbcomp.assembly.topology.Topology` (a base class
holding these methods; the topology's construction is in ``topology.py``).

Examples
--------
>>> import numpy as np
>>> from mbcomp.library import PointMass, RigidBody
>>> is_point(PointMass(m=2.0)), is_point(RigidBody(m=1.0, I=np.eye(3)))
(True, False)
"""
from __future__ import annotations

from dataclasses import replace
from functools import cached_property

import numpy as np

from ..modeling.component import PortRef

__all__ = ["Rebinding", "is_point"]

#: what a rebound topology shares with its template: names, numbers, nodes (never changed)
_SHARED = frozenset(("node_ports", "n_nodes", "gravity_source", "_geared", "q_names", "u_names", "q_units",
                     "u_units", "nq", "nu"))
#: every attribute :meth:`Rebinding.rebound` knows (``links`` and the graph's weights made again
#: when asked; the ports' maps when first read, from ``_ports_from``)
_REBINDS = _SHARED | {"_ports_from", "_graph_edges", "flat", "port_node", "edges", "bodies", "forces",
                      "flange_elements", "drives", "flange_constraints", "flange_inertias", "flange_owner",
                      "flange_of", "flange_rows", "tree", "cut", "unreached", "floating", "rotors", "links"}


def is_point(body):
    """Whether a body is a point mass: its centre on its frame and no inertia of its own (by
    its construction-time mass properties)."""
    _, r_cm, I = body.mass_properties(body.p)
    return not np.any(np.asarray(r_cm, float)) and not np.any(np.asarray(I, float))


class Rebinding:
    """The methods of a :class:`~mbcomp.assembly.topology.Topology` that rebind it to another
    model of its structure (see the module notes); a topology rebound makes its ports' maps
    and its graph's weights when first read.

    Examples
    --------
    >>> from mbcomp import Model
    >>> from mbcomp.assembly.topology import Topology
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> def flat(phi0):
    ...     m = Model(); w = m.add("world", World()); j = m.add("j", Revolute(phi0=phi0))
    ...     b = m.add("b", PointMass()); m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    ...     return m.validate()
    >>> first, other = Topology(flat(0.1)), flat(0.5)
    >>> first.probes(other) == first.probes(first.flat)    # the same choices: rebind
    True
    >>> again = first.rebound(other)
    >>> again.q_names, again.edge("j").comp is other.components["j"], again.choices() == Topology(other).choices()
    (['j.phi'], True, True)
    """

    def choices(self):
        """What this topology chose from its components' parameter values, hashable: the tree
        edges in order with their parent sides and drives, the cut joints, the gravity source
        and each implicit free joint's kind. Two topologies of one structure
        (:meth:`~mbcomp.modeling.model.FlatModel.structure`) with equal choices lay out the
        same nodes and coordinates."""
        return (tuple((e.name, e.parent, e.child, e.forward, e.drive) for e in self.tree), tuple(self.cut),
                self.gravity_source, tuple((e.name, type(e.comp)) for e in self.edges if e.implicit))

    def probes(self, flat):
        """The parameter values this topology's choices were made on, read from ``flat``'s
        components (a model of this one's structure, :meth:`FlatModel.structure
        <mbcomp.modeling.model.FlatModel.structure>`), hashable: whether each ground is a
        gravity source, whether the bodies at each implicit free joint are point masses and,
        where the graph has loops (a forest's tree takes every edge whatever their weights),
        whether each joint the spanning tree weighs has fixed start values. Where they equal
        those of this topology's own model, ``Topology(flat)`` is :meth:`rebound` ``(flat)``."""
        comps = flat.components
        loops = len(self.tree) < len(self._graph_edges)
        out = []
        for e in self.edges:
            if e.implicit:
                out.append(all(is_point(comps[path]) for path, _, n in self.bodies if n == e.node_b))
            elif e.kind == "ground":
                c = comps[e.name]
                out.append(c.gravity(c.p) is not None)
            elif loops and e.dof and not e.drive and e.comp.tree_edge:  # what _weight reads
                c = comps[e.name]
                _, qf, _, uf = c.start(c.p)
                out.append(bool(any(qf) or any(uf)))
        return tuple(out)

    def rebound(self, flat):
        """This topology for ``flat``, a model of the same structure whose :meth:`probes` are
        this topology's own: the frame nodes, tree, cut joints and coordinates kept; every
        component, port and edge ``flat``'s (implicit free joints made anew) -- what
        ``Topology(flat)`` builds, attribute by attribute, without its search. ``None`` when
        this topology holds an attribute it does not know how to rebind."""
        mine = vars(self)
        if mine.keys() - _REBINDS:
            return None
        comp = {id(a): b for a, b in zip(self.flat.components.values(), flat.components.values())}
        memo = {}

        def port(x):
            y = memo.get(id(x))
            if y is None:
                y = memo[id(x)] = PortRef(comp[id(x.component)], x.name, x.kind)
            return y

        edges = {}
        for e in self.edges:
            c = comp.get(id(e.comp))
            if c is None:  # an implicit free joint: a new one, as Topology makes it
                c = type(e.comp)()
                c.name = e.comp.name
            edges[id(e)] = new = object.__new__(type(e))
            new.__dict__.update(vars(e), comp=c)
        out = object.__new__(type(self))
        out.__dict__.update({k: v for k, v in mine.items() if k in _SHARED})
        out.flat, out.cut, out.floating, out.unreached = flat, list(self.cut), list(self.floating), list(self.unreached)
        out.edges = [edges[id(e)] for e in self.edges]
        out.tree = [edges[id(e)] for e in self.tree]
        out.ports_from(self, port)
        out.bodies = [(path, comp[id(c)], n) for path, c, n in self.bodies]
        out.forces = [(path, comp[id(c)], dict(nodes)) for path, c, nodes in self.forces]
        for name in ("flange_elements", "drives", "flange_constraints", "flange_inertias"):
            setattr(out, name, [(path, comp[id(c)]) for path, c in mine[name]])
        out.flange_rows = [replace(fr, comp=comp[id(fr.comp)], ports=dict(fr.ports),
                                   root={pn: port(r) for pn, r in fr.root.items()}) for fr in self.flange_rows]
        out.rotors = [(path, comp[id(c)], n, name) for path, c, n, name in self.rotors]
        return out

    def ports_from(self, template, port):
        """Take :attr:`port_node` (frame port -> node), :attr:`flange_of` (flange port -> its
        root port) and :attr:`flange_owner` (root -> ``(joint, "axis" | "support")``) from
        ``template``'s, each port made ``port(x)``, when first read (most runs read none of
        them: a 20-link chain's ~140 ports were half the cost of :meth:`rebound`)."""
        self._ports_from = (template, port)

    def rebound_map(self, name):
        """The template's map ``name`` (see :meth:`ports_from`) with every port made ``port(x)``."""
        template, port = self._ports_from
        return {port(x): port(v) if isinstance(v, PortRef) else v for x, v in getattr(template, name).items()}

    def __getstate__(self):  # pickled and deep-copied with its maps made: the rebinding's function does not pickle
        for name in ("port_node", "flange_of", "flange_owner", "_graph_edges"):
            getattr(self, name)
        state = dict(vars(self))
        state.pop("_ports_from", None)
        return state

    def __copy__(self):  # a shallow copy keeps what it has not made yet
        new = object.__new__(type(self))
        new.__dict__.update(vars(self))
        return new

    # set by the topology's construction; a rebound topology makes them when first read
    port_node = cached_property(lambda self: self.rebound_map("port_node"))
    flange_of = cached_property(lambda self: self.rebound_map("flange_of"))
    flange_owner = cached_property(lambda self: self.rebound_map("flange_owner"))

    @cached_property
    def _graph_edges(self):
        """``(node_a, node_b, name, weight)`` of every edge the tree was chosen from, the
        weights of this topology's components (a rebound topology's: :meth:`probes` read them
        only where the graph has loops)."""
        return [(e.node_a, e.node_b, e.name, self._weight(e)) for e in self.edges
                if e.kind != "joint" or e.comp.tree_edge]
