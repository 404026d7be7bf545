"""The scene of a run: every shape placed on a *link* (a rigid group of frames) and the pose of
every link at the result's output times.

A link is a set of frame nodes joined by rigid offsets (0-DOF tree edges: ``FixedTranslation``,
``FixedRotation``, ``Weld``, ground frames). The world's link is static; a link that carries a
body takes the body's result columns as its pose (``<body>.r.*``, ``<body>.Q.*``, exactly the
numbers of the result); a massless link that carries a shape (the cross of two hinges with no
body) is posed by the system's kinematics at each output time. A shape rides on a link at a
constant local pose, found once at the first output time.

The scene is immutable and independent of its consumers: the HTML player
(:mod:`mbcomp.visual.html`) reads :meth:`Scene.to_json`, the matplotlib pictures
(:mod:`mbcomp.visual.render`) read :meth:`Scene.placement` and :meth:`Scene.point`.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, RigidBody, FixedTranslation
>>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.5))
>>> arm = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0))); tip = m.add("tip", FixedTranslation(r=(1, 0, 0)))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, arm.frame_a); m.connect(j.frame_b, tip.frame_a)
>>> res = mbcomp.simulate(m, t_end=0.5)
>>> scene = build_scene(res)
>>> [link.name for link in scene.links]
['world', 'arm']
>>> R, r = scene.link_pose(1, 0); round(float(R[0, 0]), 6)  # cos(0.5)
0.877583
"""
from __future__ import annotations

import base64
import fnmatch
from dataclasses import dataclass, field

import numpy as np

from ..assembly.topology import ROOT
from ..geometry.kinematics import matrix_to_quat, quat_to_matrix
from ..modeling.component import PortRef
from ..modeling.shapes import SPANS, Grid, Mesh

__all__ = ["Scene", "Link", "Placed", "build_scene", "PALETTE"]

#: body colours, in the order bodies are added
PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#d62728"]


@dataclass(frozen=True)
class Link:
    """A rigid group of frames and its pose at every output time.

    Attributes
    ----------
    name : str
        ``"world"``, the body's path, or the first port of a massless group.
    poses : ndarray (n, 7) or None
        Origin (m, world) and orientation quaternion ``w, x, y, z`` (link -> world) at each
        output time; ``None`` for the static world.
    """

    name: str
    poses: np.ndarray | None


@dataclass(frozen=True)
class Placed:
    """A shape placed on a link: local pose ``r`` (m), ``q`` (quaternion w, x, y, z: shape ->
    link); a span also ends at ``to_r`` (m) on link ``to_link``."""

    name: str
    component: str
    role: str
    shape: object
    link: int
    r: tuple
    q: tuple
    color: str
    to_link: int | None = None
    to_r: tuple | None = None


@dataclass(frozen=True)
class Scene:
    """Shapes on links, link poses over time, and what the viewer shows beside them.

    Attributes
    ----------
    time : ndarray (n,)
        Output times, s.
    links : list of Link
    visuals : list of Placed
    bodies : dict
        ``{body: (link, r, q)}``: each body's frame_a on its link.
    up : ndarray (3,)
        The world's up direction (against gravity; z without gravity).
    scale : float
        Length scale of the mechanism, m.
    trails : list of dict
        ``{"name", "link", "r", "color"}``: points whose path is drawn.
    colors : list of dict
        ``{"component", "column", "values"}``: shapes coloured by a result column.
    title : str
    """

    time: np.ndarray
    links: list
    visuals: list
    bodies: dict
    up: np.ndarray
    scale: float
    trails: list = field(default_factory=list)
    colors: list = field(default_factory=list)
    title: str = ""

    def link_pose(self, i, k):
        """``(R, r)`` of link ``i`` at output ``k``: orientation (link -> world), origin (m)."""
        poses = self.links[i].poses
        if poses is None:
            return np.eye(3), np.zeros(3)
        return quat_to_matrix(poses[k, 3:]), poses[k, :3].copy()

    def point(self, link, r, k):
        """World position (m) of the point ``r`` (link axes) of ``link`` at output ``k``."""
        R, o = self.link_pose(link, k)
        return o + R @ np.asarray(r, dtype=float)

    def placement(self, v, k):
        """``(R, r)`` of a placed shape's axes at output ``k`` (shape -> world, m)."""
        R, o = self.link_pose(v.link, k)
        return R @ quat_to_matrix(np.array(v.q)), o + R @ np.array(v.r)

    def to_json(self):
        """The scene as plain data for the player: arrays as base64 of little-endian float64
        (float32 for mesh vertices, uint32 for faces), quaternions ``w, x, y, z``."""
        return {
            "version": 1, "title": self.title, "scale": self.scale, "up": self.up.tolist(),
            "n": len(self.time), "time": _b64(self.time),
            "links": [{"name": L.name, "poses": None if L.poses is None else _b64(L.poses)} for L in self.links],
            "visuals": [_visual_json(v) for v in self.visuals],
            "bodies": {b: {"link": i, "r": list(r), "q": list(q)} for b, (i, r, q) in self.bodies.items()},
            "trails": [dict(t, r=list(t["r"])) for t in self.trails],
            "colors": [{"component": c["component"], "column": c["column"], "values": _b64(c["values"]),
                        "min": c["min"], "max": c["max"]} for c in self.colors],
        }


def _b64(a, dtype="<f8"):
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _visual_json(v):
    geo = v.shape.geometry()
    if isinstance(v.shape, Mesh):
        vertices, faces = mesh_triangles(v.shape, v.component)
        geo = {"type": "mesh", "vertices": _b64(vertices, "<f4"), "faces": _b64(faces, "<u4")}
    out = {"name": v.name, "component": v.component, "role": v.role, "shape": geo, "color": v.color,
           "opacity": v.shape.opacity, "link": v.link, "r": list(v.r), "q": list(v.q)}
    if v.to_link is not None:
        out["to"] = {"link": v.to_link, "r": list(v.to_r)}
    return out


def mesh_triangles(shape, component=None):
    """``(vertices (n, 3) m, faces (m, 3))`` of a :class:`Mesh` shape in its own axes: its
    inline arrays or its file's (``component`` is named in a file's errors), times its scale."""
    if shape.inline:
        return shape.triangles()
    from .meshes import read_mesh

    return shape.scaled(*read_mesh(shape.path, component=component))


def build_scene(res, system=None, hide=(), trails=(), color_by=None, title=None):
    """The :class:`Scene` of a result.

    Parameters
    ----------
    res : Result
        A result of :func:`mbcomp.simulate` (it knows its assembled system), or any result
        with the system's coordinate and speed columns when ``system`` is given.
    system : MultibodySystem, optional
        The assembled system the result came from (``res``'s own by default).
    hide : iterable of str
        Glob patterns of component paths not to draw (``"*_joint"``, ``"world"``).
    trails : iterable of str
        Points whose path is drawn: a port path (``"rod_tip.frame_b"``) or a component
        (its ``frame_a``, or its only frame).
    color_by : dict, optional
        ``{component: column}``: colour the component's shapes by a result column over
        time; a vector's prefix (``"pin.f"`` for ``pin.f.x|y|z``) means its magnitude.
    title : str, optional

    Raises
    ------
    ValueError
        A trail, a colouring component or column that the model or result does not have,
        naming it and what exists.
    """
    system = system if system is not None else getattr(res, "system", None)
    if system is None:
        raise ValueError("this result does not know its model's system (it was not made by mbcomp.simulate) "
                         "-> pass system=mbcomp.assemble(model)")
    t = np.asarray(res.time, dtype=float)
    if len(t) == 0:
        raise ValueError("the result has no output times, so there is nothing to show -> run a simulation that "
                         "reaches at least its first output")
    Y = _states(res, system)
    topo = system.topology
    jets0 = system.kinematics(t[0], Y[0, :system.nq], Y[0, system.nq:])
    group = _rigid_groups(topo)
    links, link_of, local = _links(system, res, t, Y, group, jets0)
    scale = _scale(jets0, links)
    view_of = _Views(topo, res, group, jets0, scale, (links, link_of, local), system)
    visuals = _place(system, topo, view_of, link_of, local, hide, scale)
    visuals = _fit_grid(visuals, links, t, np.asarray(_up(system)), scale)
    bodies = {path: (link_of[node], *local[node]) for path, _, node in topo.bodies}
    return Scene(t, links, visuals, bodies, _up(system), scale, _trails(topo, trails, link_of, local),
                 _colors(res, color_by, topo), title or "")


def _states(res, system):
    """The state rows ``[q, u]`` at the output times, from the result's columns."""
    names = list(system.q_names) + list(system.u_names)
    missing = [n for n in names if n not in res]
    if missing:
        raise ValueError(f"the result has no column {missing[0]!r} of the system's state -> pass the system the "
                         "result was computed with")
    return np.column_stack([np.asarray(res[n], dtype=float) for n in names]) if names else np.zeros((len(res.time), 0))


def _rigid_groups(topo):
    """``{node: root node}``: nodes joined by rigid tree edges share a root (ROOT for the world)."""
    parent = {}

    def find(x):
        while parent.get(x, x) != x:
            x = parent[x]
        return x
    for e in topo.tree:
        if e.dof == 0:
            a, b = find(e.parent), find(e.child)
            if a != b:  # the world's group keeps ROOT as its root
                child, root = (a, b) if b == ROOT else (b, a)
                parent[child] = root
    nodes = {ROOT} | {e.child for e in topo.tree} | {e.parent for e in topo.tree}
    return {n: find(n) for n in nodes}


def _links(system, res, t, Y, group, jets0):
    """Links (world first, then one per body's group, then massless groups), the link of every
    node and every node's local pose ``(r, q)`` in its link."""
    topo = system.topology
    links, index, anchor = [Link("world", None)], {ROOT: 0}, {ROOT: ROOT}
    for path, _, node in topo.bodies:
        g = group.get(node, node)
        if g not in index:
            index[g], anchor[g] = len(links), node
            links.append(Link(path, _body_poses(res, path)))
    rest = sorted({g for g in group.values() if g not in index})
    if rest:
        poses = _kinematic_poses(system, t, Y, rest)
        for g in rest:
            index[g], anchor[g] = len(links), g
            links.append(Link(_node_name(topo, g), poses[g]))
    link_of, local = {}, {}
    for node, g in group.items():
        link_of[node] = index[g]
        Ra, ra = jets0[anchor[g]].R, jets0[anchor[g]].r
        Rn, rn = jets0[node].R, jets0[node].r
        local[node] = (tuple(Ra.T @ (rn - ra)), tuple(matrix_to_quat(Ra.T @ Rn)))
    return links, link_of, local


def _body_poses(res, path):
    cols = [f"{path}.r.{a}" for a in "xyz"] + [f"{path}.Q.{a}" for a in "wxyz"]
    return np.column_stack([np.asarray(res[c], dtype=float) for c in cols])


def _kinematic_poses(system, t, Y, nodes):
    """Poses (n, 7) of frame nodes with no body, by the kinematics at each output time."""
    out = {g: np.empty((len(t), 7)) for g in nodes}
    for k in range(len(t)):
        jets = system.kinematics(t[k], Y[k, :system.nq], Y[k, system.nq:])
        for g in nodes:
            out[g][k, :3], out[g][k, 3:] = jets[g].r, matrix_to_quat(jets[g].R)
    return out


def _node_name(topo, node):
    return min(p if isinstance(p, str) else p.path for p in topo.node_ports[node])


def _scale(jets0, links):
    """Length scale (m): the diagonal of the box around the frames at the start, or of the
    motion when they start in one point."""
    pts = np.array([np.asarray(j.r, dtype=float) for j in jets0.values()])
    size = float(np.linalg.norm(np.ptp(pts, axis=0))) if len(pts) > 1 else 0.0
    if size > 1e-6:
        return size
    moving = [L.poses[:, :3] for L in links if L.poses is not None]
    size = float(np.linalg.norm(np.ptp(np.vstack(moving), axis=0))) if moving else 0.0
    return size if size > 1e-6 else 1.0


class _Views:
    """What a component's :meth:`visuals` may ask: the scale, the frames fixed to a port, and
    whether another component draws the body on it."""

    def __init__(self, topo, res, group, jets0, scale, placed=None, system=None):
        self.topo, self.res, self.group, self.jets0, self.scale = topo, res, group, jets0, scale
        self.system = system
        self.placed = placed  # (links, link_of, local): the poses of every frame node over the run
        self.drawn = {group.get(n, n) for path, comp, nodes in _framed(topo) if comp.draws_body
                      for n in nodes.values()}

    def of(self, comp):
        outer = self

        class View:
            scale = outer.scale

            @staticmethod
            def attached(port):
                return outer.attached(comp, port)

            @staticmethod
            def covered(port):
                return outer.group.get(_node(outer.topo, comp, port)) in outer.drawn

            @staticmethod
            def range(column):
                return outer.range(comp, column)

            @staticmethod
            def track(port, of):
                return outer.track(comp, port, of)

            @staticmethod
            def axis(port):
                return outer.axis(comp, port)
        return View()

    def axis(self, comp, port):
        """The axis (unit, in the axes of the frame the flange ``port`` moves) of the joint
        whose axis or support flange ``port`` is on; ``None`` for a flange on no joint."""
        owner = _flange_owner(self.topo, comp, port)
        if owner is None or self.system is None:
            return None
        e, node = owner
        n = e.comp.axis_world(self.jets0[e.node_a].R, self.system.P[e.name])
        return self.jets0[node].R.T @ (np.asarray(n, dtype=float) / np.linalg.norm(n))

    def _world(self, node):
        """``(R (n, 3, 3), r (n, 3))`` of a frame node at every output (frame -> world, m)."""
        links, link_of, local = self.placed
        poses = links[link_of[node]].poses
        lr, lq = local[node]
        if poses is None:
            return quat_to_matrix(np.array(lq))[None], np.array(lr)[None]
        Rl = np.array([quat_to_matrix(q) for q in poses[:, 3:]])
        return Rl @ quat_to_matrix(np.array(lq)), poses[:, :3] + Rl @ np.array(lr)

    def track(self, comp, port, of):
        """The origin of the component's frame ``of`` at every output time, m, in the axes of
        its frame ``port`` at that time (shape (n, 3)): where a ball's centre went on the
        surface it rolls on; ``None`` when the scene has no poses."""
        if self.placed is None:
            return None
        Ra, ra = self._world(_node(self.topo, comp, port))
        _, rb = self._world(_node(self.topo, comp, of))
        n = max(len(ra), len(rb))
        return np.einsum("kji,kj->ki", np.broadcast_to(Ra, (n, 3, 3)), np.broadcast_to(rb - ra, (n, 3)))

    def range(self, comp, column):
        """``(min, max)`` of the component's result column ``<comp>.<column>`` over the run
        (its finite values), or ``None`` where the result has none."""
        name = f"{comp.path}.{column}"
        if name not in self.res:
            return None
        values = np.asarray(self.res[name], dtype=float)
        values = values[np.isfinite(values)]
        return (float(values.min()), float(values.max())) if values.size else None

    def attached(self, comp, port):
        node = _node(self.topo, comp, port)
        g = self.group.get(node, node)
        R, r = self.jets0[node].R, self.jets0[node].r
        return [R.T @ (self.jets0[n].r - r) for n in sorted(self.jets0) if n != node and self.group.get(n) == g]


def _node(topo, comp, port):
    return topo.port_node[PortRef(comp, port, "frame")]


def _framed(topo):
    """``(path, comp, {port: node})`` of every component with frames."""
    for path, comp in topo.flat.components.items():
        ports = {pn: _node(topo, comp, pn) for pn, pt in comp.ports().items() if pt.kind == "frame"}
        if ports:
            yield path, comp, ports


def _flange_owner(topo, comp, port):
    """``(joint edge, frame node)``: the joint a flange port is on and the frame it moves (the
    joint's frame_b for its ``axis`` flange, frame_a for its ``support``), or ``None``."""
    root = topo.flange_of.get(PortRef(comp, port, "flange"))
    owner = topo.flange_owner.get(root) if root is not None else None
    if owner is None:
        return None
    e = topo.edge(owner[0])
    return e, (e.node_b if owner[1] == "axis" else e.node_a)


def _flanged(topo):
    """``(path, comp, {port: node})`` of every component with flanges and no frames (a rotor,
    a gear, an axis spring): each flange on a joint rides on the frame it moves. Its shapes
    are placed in those frames (``frame=<flange port>``) and ``view.axis(port)`` gives the
    joint's axis there."""
    for path, comp in topo.flat.components.items():
        kinds = {pt.kind for pt in comp.ports().values()}
        if "frame" in kinds or "flange" not in kinds:
            continue
        ports = {pn: owner[1] for pn, pt in comp.ports().items() if pt.kind == "flange"
                 for owner in [_flange_owner(topo, comp, pn)] if owner is not None}
        if ports:
            yield path, comp, ports


def _place(system, topo, views, link_of, local, hide, scale):
    """Every component's shapes, placed on links."""
    out, n_body = [], 0
    for path, comp, ports in [*_framed(topo), *_flanged(topo)]:
        if any(fnmatch.fnmatchcase(path, pat) for pat in hide):
            continue
        p = system.P.get(path, comp.p) if hasattr(system, "P") else comp.p
        role = comp.role or "component"
        default = PALETTE[n_body % len(PALETTE)] if role == "body" else "#808080"
        n_body += role == "body"
        for i, s in enumerate(comp.shapes(p, views.of(comp))):
            frame = s.frame or ("frame_a" if "frame_a" in ports else next(iter(ports)))
            if frame not in ports:
                raise ValueError(f"{path}: a shape is placed on {s.frame!r}, which {type(comp).__name__} does not "
                                 f"have -> use one of its frames: {', '.join(ports)}")
            node = ports[frame]
            lr, lq = local[node]
            Rl = quat_to_matrix(np.array(lq))
            r = np.array(lr) + Rl @ np.array(s.r)
            q = matrix_to_quat(Rl @ s.rotation)
            extra = {}
            if isinstance(s, SPANS):
                if s.to not in ports:
                    raise ValueError(f"{path}: a {type(s).__name__} ends on {s.to!r}, which {type(comp).__name__} "
                                     f"does not have -> use one of its frames: {', '.join(ports)}")
                extra = {"to_link": link_of[ports[s.to]], "to_r": tuple(map(float, local[ports[s.to]][0]))}
            out.append(Placed(f"{path}#{i}", path, role, s, link_of[node], tuple(map(float, r)),
                              tuple(map(float, q)), s.color or default, **extra))
    return out


def _up(system):
    g = np.asarray(system.g, dtype=float)
    return -g / np.linalg.norm(g) if np.linalg.norm(g) > 0 else np.array([0.0, 0.0, 1.0])


def _fit_grid(visuals, links, t, up, scale):
    """Grids of unset size sized to the motion; a floor moved down to below the motion (at
    the origin's level, or ``0.1 scale`` below the lowest link origin where the motion goes
    lower); a contact's plane kept exactly; one grid of several in the same place."""
    pts = [np.zeros(3)] + [L.poses[:, :3] for L in links if L.poses is not None]
    P = np.vstack([np.atleast_2d(p) for p in pts])
    out, seen = [], set()
    for v in visuals:
        if isinstance(v.shape, Grid) and v.link == 0:
            n = quat_to_matrix(np.array(v.q))[:, 2]
            h = (P - np.array(v.r)) @ n
            low = min(0.0, float(h.min()) - 0.1 * scale) if v.shape.floor else 0.0
            flat = P - np.outer(h, n)
            centre = (flat.min(axis=0) + flat.max(axis=0)) / 2
            centre -= (centre - np.array(v.r)) @ n * n
            size = v.shape.size or 1.5 * max(float(np.max(np.ptp(flat, axis=0))), scale)
            key = (tuple(np.round(centre + low * n, 9)), tuple(np.round(n, 9)))
            if key in seen:
                continue
            seen.add(key)
            v = Placed(v.name, v.component, v.role, v.shape.placed(size=size), v.link,
                       tuple(map(float, centre + low * n)), v.q, v.color)
        out.append(v)
    return out


def _trails(topo, specs, link_of, local):
    """The trail points: ``{"name", "link", "r", "color"}``."""
    out = []
    comps = topo.flat.components
    for i, spec in enumerate(specs):
        path, _, port = spec.rpartition(".") if spec not in comps else (spec, "", None)
        comp = comps.get(path)
        if comp is None:
            raise ValueError(f"trail {spec!r}: no component {path or spec!r} in the model -> use a port path such as "
                             f"'{next(iter(comps))}.frame_a' or a component name")
        frames = [pn for pn, pt in comp.ports().items() if pt.kind == "frame"]
        if port is None:
            port = "frame_a" if "frame_a" in frames else (frames[0] if len(frames) == 1 else None)
        if port not in frames:
            raise ValueError(f"trail {spec!r}: {path} has no frame {port!r} -> use one of: {', '.join(frames)}")
        node = _node(topo, comp, port)
        out.append({"name": spec, "link": link_of[node], "r": local[node][0], "color": PALETTE[(i + 3) % len(PALETTE)]})
    return out


def _colors(res, color_by, topo):
    """Columns that colour components: ``{"component", "column", "values", "min", "max"}``."""
    out = []
    for comp, column in (color_by or {}).items():
        if comp not in topo.flat.components:
            raise ValueError(f"color_by: no component {comp!r} in the model")
        if column in res:
            values = np.asarray(res[column], dtype=float)
        elif all(f"{column}.{a}" in res for a in "xyz"):
            values = np.sqrt(sum(np.asarray(res[f"{column}.{a}"], dtype=float) ** 2 for a in "xyz"))
        else:
            close = [n for n in res.names if n.startswith(column.split(".")[0])][:6]
            raise ValueError(f"color_by {comp!r}: the result has no column {column!r} (nor {column}.x|y|z) -> "
                             f"use one of: {', '.join(close) or 'Result.names'}")
        finite = values[np.isfinite(values)]
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        out.append({"component": comp, "column": column, "values": values, "min": lo, "max": hi})
    return out
