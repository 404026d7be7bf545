"""The topology's spanning tree is networkx's minimum spanning tree, ties broken alike.

:func:`mbcomp.assembly.topology.spanning_tree` replaces ``networkx.minimum_spanning_tree``
(networkx costs ~0.15 s to import on the way to every simulation). Which joint of a loop of
equal joints is cut decides the coordinates a model is simulated in, so the replacement
must pick the same tree as networkx, on every model file and on random multigraphs full of
equal weights, parallel edges and self-loops.
"""
import random

import networkx as nx
import pytest

from conftest import ROOT, load_model
from mbcomp.assembly.topology import ROOT as WORLD
from mbcomp.assembly.topology import Topology, spanning_tree

MODEL_FILES = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "models").rglob("*.py"))


def networkx_tree(nodes, edges):
    """The keys of networkx's Kruskal tree of the multigraph ``edges`` = [(u, v, key, weight)]."""
    G = nx.MultiGraph()
    G.add_nodes_from(nodes)
    for u, v, key, w in edges:
        G.add_edge(u, v, key=key, weight=w)
    return {key for *_, key in nx.minimum_spanning_tree(G, algorithm="kruskal").edges(keys=True)}


@pytest.mark.parametrize("path", MODEL_FILES)
def test_every_model_is_cut_where_networkx_cuts_it(path):
    mod = load_model(path)
    if not hasattr(mod, "build"):
        pytest.skip("no build()")
    topo = Topology(mod.build().validate())
    tree = {key for *_, key in nx.minimum_spanning_tree(topo.graph, algorithm="kruskal").edges(keys=True)}
    assert tree == {e.name for e in topo.edges} - set(topo.cut)


def test_random_multigraphs_with_ties_give_networkx_tree():
    rng = random.Random(7)
    for _ in range(500):
        nodes = [WORLD, *range(rng.randint(1, 8))]
        edges = [(rng.choice(nodes), rng.choice(nodes), f"e{i}", rng.choice([-100.0, 0.0, 1.0, 2.5, 3.0, 6.0]))
                 for i in rng.sample(range(100), rng.randint(0, 14))]
        assert {key for *_, key in spanning_tree(nodes, edges)} == networkx_tree(nodes, edges), edges
