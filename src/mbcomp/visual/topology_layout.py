"""Where the topology drawing puts things: the spanning tree layered by depth, and the cut
joints routed as curves around the tree.

Pure geometry on the plain description of :func:`mbcomp.visual.topology_drawing.topology_graph`
(numpy and networkx, no matplotlib). Lengths are in inches of the drawing.

* :func:`layout` places the rigid groups as a tidy tree from the world: leaves ``X_STEP``
  apart in depth-first order, each parent centred over its children, layers ``Y_STEP`` apart.
  The children of each parent are reordered so that the loops are drawn short and clear
  (the least total :func:`route` cost of the cut joints).
* :func:`routes` gives each cut joint a cubic Bezier curve: of a few bends to either side of
  the straight line, the one that passes no other group, crosses the fewest tree joints and
  leaves its label clear of the groups, the tree joints' labels and the other cut labels.

Examples
--------
>>> desc = {"nodes": [{"id": -1}, {"id": 0}, {"id": 1}],
...         "edges": [{"name": "j0", "kind": "tree", "a": -1, "b": 0},
...                   {"name": "j1", "kind": "tree", "a": -1, "b": 1},
...                   {"name": "pin", "kind": "cut", "a": 0, "b": 1}]}
>>> pos = layout(desc)
>>> pos[0], pos[1], pos[-1]
((0.0, -2.1), (2.9, -2.1), (1.45, 0.0))
>>> r = routes(desc, pos)["pin"]
>>> r["label"][1] < -2.1  # bent below the two links, away from the tree joints
True
"""
from __future__ import annotations

import itertools

import numpy as np

ROOT = -1  # the world's group (mbcomp.assembly.topology.ROOT)

__all__ = ["layout", "routes", "tree_label_points", "X_STEP", "Y_STEP"]

#: inches between neighbouring leaves and between tree layers
X_STEP, Y_STEP = 2.9, 2.1
#: most sibling orders tried for one parent
MAX_ORDERS = 720
#: where along a tree joint (from the parent) its label sits
TREE_LABEL_AT = 0.52
#: half sizes (inches) of the boxes kept clear around a group and a label: (half width, half height)
NODE_BOX, TREE_LABEL_BOX, CUT_LABEL_BOX = (0.6, 0.35), (0.55, 0.22), (0.9, 0.3)
#: costs: a curve through another group, across a tree joint or a label, a label on a label;
#: and per inch of curve
COST = dict(node=10.0, crossing=3.0, through_label=2.0, label=6.0, inch=1.0)


def _tree(desc):
    """``(children, depth)`` of the groups along the tree joints from the world's group
    (groups the tree does not reach hang one layer below the deepest, under the world)."""
    import networkx as nx

    G = nx.Graph()
    G.add_nodes_from(n["id"] for n in desc["nodes"])
    G.add_edges_from((e["a"], e["b"]) for e in desc["edges"] if e["kind"] == "tree")
    bfs = nx.bfs_tree(G, ROOT, sort_neighbors=sorted)
    children = {n: list(bfs.successors(n)) if n in bfs else [] for n in G.nodes}
    depth = dict(nx.shortest_path_length(bfs, ROOT))
    lost = [n for n in G.nodes if n not in depth]
    bottom = max(depth.values()) + 1
    depth.update({n: bottom for n in lost})
    children[ROOT] = children[ROOT] + lost
    return children, depth


def _place(children, depth, order):
    """Positions of a tidy tree with the children of each group in ``order``: leaves
    ``X_STEP`` apart in depth-first order, each parent centred over its children."""
    pos, next_x = {}, [0.0]

    def visit(n):
        kids = order.get(n, children[n])
        for k in kids:
            visit(k)
        if kids:
            pos[n] = (0.5 * (pos[kids[0]][0] + pos[kids[-1]][0]), -depth[n] * Y_STEP)
        else:
            pos[n] = (next_x[0], -depth[n] * Y_STEP)
            next_x[0] += X_STEP

    visit(ROOT)
    return pos


def layout(desc):
    """Positions ``{group: (x, y)}`` (inches) of the rigid groups: the world on top, each
    group one layer below its parent along the tree, siblings ordered so that the cut joints
    are short and clear (each parent's children tried in every order up to ``MAX_ORDERS``,
    two passes, keeping the least total :func:`routes` cost).

    Parameters
    ----------
    desc : dict
        ``nodes`` (each with ``id``) and ``edges`` (each with ``kind``, ``a``, ``b``), as
        :func:`~mbcomp.visual.topology_drawing.topology_graph` describes them.

    Returns
    -------
    dict
        ``{group id: (x, y)}``; the world's group at ``y = 0``, layers at ``-Y_STEP * depth``.

    Examples
    --------
    >>> desc = {"nodes": [{"id": -1}, {"id": 0}], "edges": [{"name": "j", "kind": "tree", "a": -1, "b": 0}]}
    >>> layout(desc)
    {0: (0.0, -2.1), -1: (0.0, 0.0)}
    """
    children, depth = _tree(desc)
    order = {n: list(k) for n, k in children.items()}
    if not any(e["kind"] == "cut" for e in desc["edges"]):
        return _place(children, depth, order)
    for _ in range(2):
        for n, kids in children.items():
            if len(kids) < 2:
                continue
            best = None
            for perm in itertools.islice(itertools.permutations(order[n]), MAX_ORDERS):
                trial = dict(order)
                trial[n] = list(perm)
                pos = _place(children, depth, trial)
                cost = sum(r["cost"] for r in routes(desc, pos).values())
                if best is None or cost < best[0] - 1e-9:
                    best = (cost, list(perm))
            order[n] = best[1]
    return _place(children, depth, order)


def tree_label_points(desc, pos):
    """``{tree joint: (x, y)}``: where each tree joint's label sits (``TREE_LABEL_AT`` along it)."""
    out = {}
    for e in desc["edges"]:
        if e["kind"] == "tree":
            (xa, ya), (xb, yb) = pos[e["a"]], pos[e["b"]]
            out[e["name"]] = (xa + TREE_LABEL_AT * (xb - xa), ya + TREE_LABEL_AT * (yb - ya))
    return out


def _bezier(ctrl, n=25):
    """``n`` points along the cubic Bezier curve with control points ``ctrl`` (4 x 2)."""
    t = np.linspace(0.0, 1.0, n)[:, None]
    p0, p1, p2, p3 = np.asarray(ctrl, float)
    return (1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * p1 + 3 * (1 - t) * t ** 2 * p2 + t ** 3 * p3


def _crossings(points, segments):
    """How many of the ``segments`` (array (m, 2, 2): from, to) the polyline ``points`` crosses."""
    if not len(segments):
        return 0
    seg = np.asarray(segments, float)
    a, b = points[:-1, None, :], points[1:, None, :]
    p, q = seg[None, :, 0, :], seg[None, :, 1, :]

    def side(u, v, w):
        return np.sign((v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0]))

    hit = (side(a, b, p) * side(a, b, q) < 0) & (side(p, q, a) * side(p, q, b) < 0)
    return int(hit.any(axis=0).sum())


def _inside(points, centres, half):
    """How many of the boxes (``centres``, half sizes ``half``) hold any of the ``points``."""
    if not len(centres):
        return 0
    d = np.abs(np.asarray(points, float)[:, None, :] - np.asarray(centres, float)[None, :, :])
    return int(np.any((d[..., 0] < half[0]) & (d[..., 1] < half[1]), axis=0).sum())


def _candidates(a, b):
    """Cubic control points of the curves tried between ``a`` and ``b``: bends of three sizes
    to either side of the straight line (a loop below ``a`` when ``a`` is ``b``)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    length = np.hypot(*d)
    if length < 1e-9:  # a cut joint inside one rigid group
        return [np.array([a, a + (-s, -1.1 * s), a + (s, -1.1 * s), b]) for s in (0.7, 1.1, 1.5)]
    normal = np.array([d[1], -d[0]]) / length
    out = []
    for size in (0.35 + 0.18 * length, 0.8 + 0.3 * length, 1.4 + 0.45 * length):
        for sign in (1.0, -1.0):
            c = 0.5 * (a + b) + sign * size * normal
            out.append(np.array([a, a + 2 / 3 * (c - a), b + 2 / 3 * (c - b), b]))
    return out


def _cost(ctrl, ends, pos, obstacles):
    """What a curve ``ctrl`` between the groups ``ends`` costs (see ``COST``), its label point
    and its points."""
    points = _bezier(ctrl)
    label = points[len(points) // 2]
    others = [p for n, p in pos.items() if n not in ends]
    segs = [s for s, touch in obstacles["segments"] if not touch & set(ends)]
    around = (lambda half: (half[0] + CUT_LABEL_BOX[0], half[1] + CUT_LABEL_BOX[1]))
    cost = COST["inch"] * np.hypot(*np.diff(points, axis=0).T).sum()
    cost += COST["node"] * _inside(points[2:-2], others, NODE_BOX)
    cost += COST["crossing"] * (_crossings(points, segs) + _crossings(points, obstacles["curves"]))
    cost += COST["through_label"] * _inside(points, obstacles["tree_labels"], TREE_LABEL_BOX)
    cost += COST["label"] * (_inside([label], list(pos.values()), around(NODE_BOX))
                             + _inside([label], obstacles["tree_labels"], around(TREE_LABEL_BOX))
                             + _inside([label], obstacles["cut_labels"], around(CUT_LABEL_BOX))
                             + min(_inside(obstacles["tree_points"], [label], CUT_LABEL_BOX), 1))
    return cost, label, points


def _polyline_segments(points):
    return np.stack((points[:-1], points[1:]), axis=1)


def routes(desc, pos):
    """The curve of every cut joint: ``{name: {"ctrl", "label", "cost", "points"}}``.

    ``ctrl`` are the four control points (inches) of a cubic Bezier curve from group ``a``
    to group ``b``, ``label`` where its label goes (the curve's middle), ``cost`` what it
    costs (``COST``: length, groups passed, tree joints and other cut joints crossed,
    labels covered), ``points`` the curve sampled. Each cut joint takes its cheapest curve
    given the others' (two passes).

    Examples
    --------
    >>> desc = {"nodes": [{"id": -1}, {"id": 0}],
    ...         "edges": [{"name": "j", "kind": "tree", "a": -1, "b": 0}, {"name": "c", "kind": "cut", "a": -1, "b": 0}]}
    >>> r = routes(desc, layout(desc))["c"]
    >>> abs(r["label"][0]) > 0.5  # bent to the side, off the tree joint
    True
    """
    tree = [e for e in desc["edges"] if e["kind"] == "tree"]
    t = np.linspace(0.0, 1.0, 9)[:, None]
    base = dict(segments=[(np.array([pos[e["a"]], pos[e["b"]]]), {e["a"], e["b"]}) for e in tree],
                tree_labels=list(tree_label_points(desc, pos).values()),
                tree_points=[p for e in tree for p in (1 - t) * np.asarray(pos[e["a"]]) + t * np.asarray(pos[e["b"]])])
    chosen = {}
    for _ in range(2):
        for e in (e for e in desc["edges"] if e["kind"] == "cut"):
            others = [r for name, r in chosen.items() if name != e["name"]]
            obstacles = dict(base, cut_labels=[r["label"] for r in others],
                             curves=[s for r in others for s in _polyline_segments(r["points"])])
            ends = (e["a"], e["b"])
            cost, label, points, ctrl = min((_cost(c, ends, pos, obstacles) + (c,)
                                             for c in _candidates(pos[e["a"]], pos[e["b"]])), key=lambda r: r[0])
            chosen[e["name"]] = dict(ctrl=ctrl, label=(float(label[0]), float(label[1])), cost=float(cost),
                                    points=points)
    return chosen


#: where a gear row's dotted path meets a tree joint's line (fraction from the parent group),
#: between the parent's box and the joint's label
GEAR_AT = 0.3


def _joint_anchor(e, pos, curves):
    """The point (inches) where a gear row meets joint ``e``'s line or curve."""
    if e["kind"] == "cut" and e["name"] in curves:
        points = np.asarray(curves[e["name"]]["points"], float)
        return points[len(points) // 4]
    a, b = np.asarray(pos[e["a"]], float), np.asarray(pos[e["b"]], float)
    return a + GEAR_AT * (b - a)


def gear_routes(desc, pos, curves):
    """The dotted path of every gear row: ``{(gear, row): {"points", "label"}}``.

    ``points`` (k, 2) inches: quadratic arcs, bowed downwards, from one geared joint's line to
    the next, left to right (the joints the row ties, ``desc["gears"]``), so a row over two
    joints is one arc and a planetary row over three is two; a row on one joint (its other
    flange on a support or the ground) is a short hook. ``label`` where its label goes (the
    path's lowest point, or beside the hook's end).

    Examples
    --------
    >>> desc = {"nodes": [{"id": -1}, {"id": 0}, {"id": 1}],
    ...         "edges": [{"name": "j1", "kind": "tree", "a": -1, "b": 0},
    ...                   {"name": "j2", "kind": "tree", "a": -1, "b": 1}],
    ...         "gears": [{"name": "g", "rows": [{"name": "mesh", "joints": ["j1", "j2"]}]}]}
    >>> r = gear_routes(desc, layout(desc), {})[("g", "mesh")]
    >>> r["points"].shape, bool(r["label"][1] < r["points"][0][1])   # one arc, bowed below its ends
    ((25, 2), True)
    """
    edges = {e["name"]: e for e in desc["edges"]}
    out = {}
    t = np.linspace(0.0, 1.0, 25)[:, None]
    for g in desc.get("gears", []):
        for row in g["rows"]:
            anchors = [_joint_anchor(edges[j], pos, curves) for j in row["joints"] if j in edges]
            if not anchors:
                continue
            if len(anchors) == 1:
                a = anchors[0]
                points = np.array([a, a + (0.35, 0.15), a + (0.7, 0.15)])
                out[(g["name"], row["name"])] = dict(points=points, label=tuple(points[-1] + (0.2, 0.0)))
                continue
            arcs = []
            anchors.sort(key=lambda x: (x[0], x[1]))
            for a, b in zip(anchors[:-1], anchors[1:]):
                d = b - a
                bow = 0.3 * np.array([d[1], -d[0]])
                mid = (a + b) / 2 + (bow if bow[1] <= 0 else -bow)  # bowed downwards, away from the parents
                arcs.append((1 - t) ** 2 * a + 2 * (1 - t) * t * mid + t ** 2 * b)
            points = np.vstack(arcs)
            low = points[np.argmin(points[:, 1])]
            out[(g["name"], row["name"])] = dict(points=points, label=(float(low[0]), float(low[1])))
    return out
