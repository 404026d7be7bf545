"""Topology plans: a model rebuilt with the structure of one assembled before gets that
topology rebound to its own components instead of searched again.

A :class:`~mbcomp.assembly.topology.Topology` is a function of the model's structure -- what
:meth:`FlatModel.structure <mbcomp.modeling.model.FlatModel.structure>` fingerprints: the
component paths and classes, the attributes besides the parameters, the connections, the
bodies marked free -- and of a few parameter values its choices read
(:meth:`Topology.probes <mbcomp.assembly.topology.Topology.probes>`: which grounds give
gravity, which joints have fixed start values, which free bodies are point masses).
:func:`topology_of` keeps the topologies it built by structure (:class:`TopologyPlans`);
a model of a structure seen before whose probes equal a kept topology's gets that topology
rebound (:meth:`Topology.rebound <mbcomp.assembly.topology.Topology.rebound>`: the frame
nodes, tree, cut joints and coordinates kept, every component, port and edge the new
model's) -- the topology ``Topology(flat)`` builds, attribute by attribute
(``tests/assembly/test_plan.py``). Anything else -- a new structure, other probes, a probe
that raises -- builds the topology afresh (and reports the model's problems as it does).

Examples
--------
>>> from mbcomp import Model
>>> from mbcomp.library import World, Revolute, PointMass
>>> def flat(m, phi0):
...     mdl = Model(); w = mdl.add("world", World()); j = mdl.add("j", Revolute(phi0=phi0))
...     b = mdl.add("b", PointMass(m=m)); mdl.connect(w.frame_b, j.frame_a); mdl.connect(j.frame_b, b.frame_a)
...     return mdl.validate()
>>> plans = TopologyPlans()
>>> first = plans.topology(flat(1.0, 0.1))
>>> again = plans.topology(flat(2.0, 0.5))       # other values: the first topology rebound
>>> plans.hits, plans.misses, [e.name for e in again.tree], again.edges[1].comp is first.edges[1].comp
(1, 1, ['world', 'j'], False)
"""
from __future__ import annotations

from collections import OrderedDict

from .topology import Topology

__all__ = ["TopologyPlans", "PLANS", "topology_of"]


class TopologyPlans:
    """Topologies by model structure: ``topology(flat)`` is ``Topology(flat)``, rebound from
    a kept one where the structure and the probes match (see the module notes).

    Holds at most ``size`` structures (the least recently used leaves first) and, per
    structure, at most ``per_structure`` topologies of other probes. ``hits`` and ``misses``
    count the answers.

    Examples
    --------
    >>> from mbcomp import Model
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> def flat():
    ...     m = Model(); w = m.add("world", World()); s = m.add("s", Prismatic()); b = m.add("b", PointMass())
    ...     m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    ...     return m.validate()
    >>> plans = TopologyPlans(size=4)
    >>> t1, t2 = plans.topology(flat()), plans.topology(flat())
    >>> t1.q_names == t2.q_names, t2.flat.components["s"] is t1.flat.components["s"], len(plans)
    (True, False, 1)
    """

    def __init__(self, size=16, per_structure=4):
        self.size, self.per_structure = size, per_structure
        self._entries = OrderedDict()  # structure -> ([(probes, template)], refs)
        self.hits = self.misses = 0

    def topology(self, flat):
        """The :class:`~mbcomp.assembly.topology.Topology` of the validated flat model ``flat``."""
        key, refs = flat.structure()
        got = self._entries.get(key)
        if got is not None:
            self._entries.move_to_end(key)
            for probes, template in got[0]:
                try:
                    mine = template.probes(flat)
                except Exception:  # noqa: BLE001 -- a component's own error: built afresh, which raises it
                    break
                if mine == probes:
                    topo = template.rebound(flat)
                    if topo is not None:
                        self.hits += 1
                        return topo
        self.misses += 1
        topo = Topology(flat)
        self._keep(key, refs, topo, flat)
        return topo

    def _keep(self, key, refs, topo, flat):
        """Keep a copy of ``topo`` (not the one handed out: its user may change it) as the
        template of its structure and probes."""
        try:
            probes = topo.probes(flat)
        except Exception:  # noqa: BLE001 -- not kept: the next model of this structure is built afresh
            return
        template = topo.rebound(flat)
        if template is None:
            return
        got = self._entries.setdefault(key, ([], refs))
        kept = [(p, t) for p, t in got[0] if p != probes] + [(probes, template)]
        got[0][:] = kept[-self.per_structure:]
        while len(self._entries) > self.size:
            self._entries.popitem(last=False)

    def clear(self):
        """Forget every structure."""
        self._entries.clear()

    def __len__(self):
        return len(self._entries)


#: the process's topologies by structure (what ``assemble`` reuses)
PLANS = TopologyPlans()


def topology_of(flat):
    """The topology of the validated flat model ``flat``: ``Topology(flat)``, rebound from
    the one of a model of the same structure assembled before in this process where its
    parameter-dependent choices agree (:data:`PLANS`).

    Examples
    --------
    >>> from mbcomp import Model
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> m = Model(); w = m.add("world", World()); j = m.add("j", Revolute()); b = m.add("b", PointMass())
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> topology_of(m.validate()).q_names
    ['j.phi']
    """
    return PLANS.topology(flat)
