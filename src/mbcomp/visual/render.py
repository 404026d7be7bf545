"""Pictures and films of a scene drawn by matplotlib's 3-D axes, without a browser or a display.

:func:`frame_geometry` is the pure part: every placed shape as world-coordinate polygons
(boxes, cylinders, spheres, rods as low-poly surfaces; meshes as their triangles) or lines
(helices, grids, trails) at a time ``t``. Between two output times a link's pose is
*interpolated*: its origin linearly, its orientation by spherical linear interpolation (slerp)
of the two quaternions, so an output time gives exactly the result's numbers.
:func:`write_picture` draws one frame to a PNG/SVG/PDF/JPG; :func:`write_film` draws the
frames at ``t0 + k speed/fps`` to a GIF (Pillow) or an MP4 (ffmpeg). matplotlib is imported
only by these two, and only its object API (``Figure`` on an Agg canvas) is used.

Pictures show the world with its up direction (``scene.up``, against gravity) vertical, equal
scales on the three axes and the view from the side on which the mechanism is widest.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, RigidBody
>>> from mbcomp.visual.scene import build_scene
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0))); j = m.add("j", Revolute(n=(0, 0, 1), w0=1.0))
>>> arm = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=[[1e-3, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, arm.frame_a)
>>> scene = build_scene(mbcomp.simulate(m, t_end=1.0))
>>> [d.kind for d in frame_geometry(scene, 0.5) if d.component == "arm"]
['faces']
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..geometry.kinematics import quat_to_matrix
from ..modeling.shapes import Box, Cylinder, Grid, Helix, Mesh, Rod, Sphere
from .meshes import cluster
from .scene import mesh_triangles

__all__ = ["Drawn", "frame_geometry", "pose_at", "film_times", "write_picture", "write_film"]

#: sides of a cylinder (a rod has half as many); bands and sectors of a sphere
SIDES, BANDS, SECTORS = 16, 8, 12
#: picture size (inch) and resolution (dots per inch): 640 x 480 pixels
FIGSIZE, DPI = (6.4, 4.8), 100
#: file meshes are drawn coarsened by vertex clustering (:func:`~mbcomp.visual.meshes.cluster`) in
#: cubes of ``scene.scale / MESH_CELLS`` (about a pixel), coarser (x1.5 at a time, up to
#: ``scene.scale / 30``) until the picture holds at most MESH_FACES of their triangles: a robot's
#: meshes have 10^5 triangles, which matplotlib draws in seconds a frame
MESH_CELLS, MESH_FACES = 300, 40000


@dataclass(frozen=True)
class Drawn:
    """One shape (or trail) at one time, in world coordinates (m).

    Attributes
    ----------
    name, component : str
        The placed shape's name (``"crank#0"``; ``"trail:<spec>"`` for a trail) and component.
    kind : str
        ``"faces"``: ``parts`` are polygon groups, arrays (m, k, 3) of m polygons of k corners;
        ``"lines"``: ``parts`` are polylines, arrays (n, 3).
    parts : list of ndarray
    color : str
        ``"#rrggbb"``.
    opacity : float
    R, r : ndarray
        The shape's axes -> world and their origin (m) at the time.
    ends : tuple of ndarray or None
        A span's two ends (m, world): the shape's origin and the origin of its ``to`` frame.
    value : float or None
        The colouring column's value at the time (``scene.colors``), if one colours it.
    """

    name: str
    component: str
    kind: str
    parts: list
    color: str
    opacity: float
    R: np.ndarray
    r: np.ndarray
    ends: tuple | None = None
    value: float | None = None


def _bracket(time, t):
    """``(k, s)``: ``t`` lies at the fraction ``s`` of the way from output ``k`` to ``k + 1``."""
    n = len(time)
    if n == 1 or t <= time[0]:
        return 0, 0.0
    if t >= time[-1]:
        return n - 1, 0.0
    k = int(np.searchsorted(time, t, side="right")) - 1
    span = time[k + 1] - time[k]
    return k, (0.0 if span <= 0 else float((t - time[k]) / span))


def _slerp(q0, q1, s):
    """Spherical linear interpolation of unit quaternions (the shorter way round)."""
    d = float(q0 @ q1)
    if d < 0:
        q1, d = -q1, -d
    if d > 1.0 - 1e-10:  # within 3e-5 rad: normalized linear interpolation errs by < 1e-14 rad
        q = (1 - s) * q0 + s * q1
        return q / np.linalg.norm(q)
    th = math.acos(min(d, 1.0))
    return (math.sin((1 - s) * th) * q0 + math.sin(s * th) * q1) / math.sin(th)


def pose_at(scene, link, t):
    """``(R, r)`` of a link at time ``t`` (s): orientation (link -> world) and origin (m), the
    result's numbers at an output time, interpolated between outputs (origin linearly,
    quaternion by slerp).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.visual.scene import Scene, Link
    >>> poses = np.array([[0, 0, 0, 1, 0, 0, 0], [2, 0, 0, 0, 0, 0, 1]], dtype=float)
    >>> s = Scene(np.array([0.0, 1.0]), [Link("world", None), Link("b", poses)], [], {}, np.array([0, 0, 1.0]), 1.0)
    >>> R, r = pose_at(s, 1, 0.5); r.tolist(), np.round(R[:, 0], 12) + 0.0  # half of a half turn
    ([1.0, 0.0, 0.0], array([0., 1., 0.]))
    """
    poses = scene.links[link].poses
    if poses is None:
        return np.eye(3), np.zeros(3)
    k, s = _bracket(scene.time, t)
    if s == 0.0:
        return quat_to_matrix(poses[k, 3:]), poses[k, :3].copy()
    a, b = poses[k], poses[k + 1]
    return quat_to_matrix(_slerp(a[3:], b[3:], s)), (1 - s) * a[:3] + s * b[:3]


def _check_time(scene, t):
    """The time ``t`` (s; ``None``: the last output) checked against the run."""
    t0, t1 = float(scene.time[0]), float(scene.time[-1])
    if t is None:
        return t1
    try:
        t = float(t)
    except (TypeError, ValueError):
        raise ValueError(f"t={t!r} is no time -> give a number of seconds in [{t0:g}, {t1:g}]") from None
    tol = 1e-9 * max(1.0, abs(t0), abs(t1))
    if not (np.isfinite(t) and t0 - tol <= t <= t1 + tol):
        raise ValueError(f"t={t!r} s is outside the run, which has outputs from t0={t0:g} s to t_end={t1:g} s -> "
                         "pick a time in that range (t=None for the last output)")
    return min(max(t, t0), t1)


# ---------------------------------------------------------------------------------------------
# shapes as polygons and lines in their own axes


def _ring(radius, z, n):
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(n, z)])


def _cylinder(radius, length, n=SIDES):
    """Side quads (n, 4, 3) and the two caps (2, n, 3) of a cylinder along z, centred."""
    lo, hi = _ring(radius, -length / 2, n), _ring(radius, length / 2, n)
    nxt = np.roll(np.arange(n), -1)
    sides = np.stack([lo, lo[nxt], hi[nxt], hi], axis=1)
    return [sides, np.stack([lo[::-1], hi])]


def _box(size):
    h = np.asarray(size, dtype=float) / 2
    c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float) * h
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return [c[np.array(quads)]]


def _sphere(radius):
    th = np.linspace(0.0, np.pi, BANDS + 1)[:, None]
    ph = np.linspace(0.0, 2 * np.pi, SECTORS + 1)[None, :]
    p = radius * np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th) + 0 * ph], axis=-1)
    quads = np.stack([p[:-1, :-1], p[1:, :-1], p[1:, 1:], p[:-1, 1:]], axis=2)
    return [quads.reshape(-1, 4, 3)]


def _grid(size, divisions):
    """Polylines of a square grid in the x-y plane, each line its own two-point polyline."""
    x = np.linspace(-size / 2, size / 2, divisions + 1)
    e = size / 2
    return [np.array([[a, -e, 0.0], [a, e, 0.0]]) for a in x] + [np.array([[-e, a, 0.0], [e, a, 0.0]]) for a in x]


def _local(v, meshes):
    """``(kind, parts)`` of a placed shape that is not a span, in the shape's axes (m)."""
    s = v.shape
    if isinstance(s, Box):
        return "faces", _box(s.size)
    if isinstance(s, Cylinder):
        return "faces", _cylinder(s.radius, s.length)
    if isinstance(s, Sphere):
        return "faces", _sphere(s.radius)
    if isinstance(s, Grid):
        return "lines", _grid(s.size if s.size is not None else 1.0, s.divisions)
    if isinstance(s, Mesh):
        key = id(s) if s.inline else (s.path, s.scale)
        if key not in meshes:
            meshes[key] = mesh_triangles(s, v.component)
        vertices, faces = meshes[key]
        return "faces", [vertices[faces]]
    raise ValueError(f"{v.component}: cannot draw a {type(s).__name__} shape -> use Box, Cylinder, Sphere, Mesh, "
                     "Helix, Rod or Grid")


def _across(d):
    """Two unit vectors normal to ``d`` and to each other."""
    d = d / np.linalg.norm(d)
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, d)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(d, e1)


def _span(shape, a, b):
    """``(kind, parts)`` of a helix (a line) or a rod (a thin cylinder) from ``a`` to ``b`` (m, world)."""
    d = b - a
    if np.linalg.norm(d) < 1e-12:
        return "lines", []
    e1, e2 = _across(d)
    if isinstance(shape, Helix):
        s = np.linspace(0.0, 1.0, 24 * shape.turns + 1)[:, None]
        th = 2 * np.pi * shape.turns * s
        return "lines", [a + s * d + shape.radius * (np.cos(th) * e1 + np.sin(th) * e2)]
    R = np.column_stack([e1, e2, d / np.linalg.norm(d)])
    parts = _cylinder(shape.radius, float(np.linalg.norm(d)), SIDES // 2)
    return "faces", [p @ R.T + (a + b) / 2 for p in parts]


# ---------------------------------------------------------------------------------------------
# the scene at a time


def _coarse_meshes(scene):
    """``{(path, scale): (vertices, faces)}`` of the scene's file meshes, coarsened for a picture
    (:data:`MESH_CELLS`, :data:`MESH_FACES`)."""
    full = {}
    for v in scene.visuals:
        if isinstance(v.shape, Mesh) and not v.shape.inline and (v.shape.path, v.shape.scale) not in full:
            full[(v.shape.path, v.shape.scale)] = mesh_triangles(v.shape, v.component)
    cell = scene.scale / MESH_CELLS
    while True:
        out = {k: cluster(*vf, cell) for k, vf in full.items()}
        if sum(len(f) for _, f in out.values()) <= MESH_FACES or cell * 1.5 > scene.scale / 30:
            return out
        cell *= 1.5


class _Geometry:
    """A scene's shapes in their own axes, read once (meshes, grids), and its trails' paths at
    every output; :meth:`at` places them at a time."""

    def __init__(self, scene):
        self.scene, meshes = scene, {}
        meshes = _coarse_meshes(scene)
        self.local = [None if isinstance(v.shape, (Helix, Rod)) else _local(v, meshes) for v in scene.visuals]
        self.paths = [np.array([scene.point(tr["link"], tr["r"], k) for k in range(len(scene.time))])
                      for tr in scene.trails]
        self.values = {c["component"]: c["values"] for c in scene.colors}

    def _value(self, component, t):
        values = self.values.get(component)
        return None if values is None else float(np.interp(t, self.scene.time, values))

    def at(self, t):
        """Every visual and trail at time ``t`` (s), in world coordinates."""
        scene, out = self.scene, []
        for v, local in zip(scene.visuals, self.local):
            Rl, rl = pose_at(scene, v.link, t)
            R, r = Rl @ quat_to_matrix(np.array(v.q, dtype=float)), rl + Rl @ np.array(v.r, dtype=float)
            ends = None
            if local is None:
                Rt, rt = pose_at(scene, v.to_link, t)
                ends = (r, rt + Rt @ np.array(v.to_r, dtype=float))
                kind, parts = _span(v.shape, *ends)
            else:
                kind, parts = local[0], [p @ R.T + r for p in local[1]]
            out.append(Drawn(v.name, v.component, kind, parts, v.color, float(v.shape.opacity), R, r, ends,
                             self._value(v.component, t)))
        k, _ = _bracket(scene.time, t)
        for tr, path in zip(scene.trails, self.paths):
            R, r = pose_at(scene, tr["link"], t)
            here = r + R @ np.asarray(tr["r"], dtype=float)
            line = np.vstack([path[:k + 1], here[None, :]])
            out.append(Drawn(f"trail:{tr['name']}", tr["name"], "lines", [line], tr["color"], 1.0,
                             np.eye(3), here))
        return out


def frame_geometry(scene, t=None):
    """Every shape of ``scene`` (and every trail) at time ``t`` as world geometry.

    Parameters
    ----------
    scene : Scene
    t : float, optional
        Time, s, within the run (the last output by default). Between two outputs each link's
        pose is interpolated (origin linearly, orientation by slerp).

    Returns
    -------
    list of Drawn
        In the order of ``scene.visuals``, then the trails (each up to ``t``).

    Raises
    ------
    ValueError
        ``t`` outside ``[t0, t_end]``, naming the range.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.modeling.shapes import Sphere
    >>> from mbcomp.visual.scene import Scene, Link, Placed
    >>> poses = np.array([[0, 0, 0, 1, 0, 0, 0], [2, 0, 0, 1, 0, 0, 0]], dtype=float)
    >>> ball = Placed("b#0", "b", "body", Sphere(0.1), 1, (0, 0, 0), (1, 0, 0, 0), "#1f77b4")
    >>> s = Scene(np.array([0.0, 1.0]), [Link("world", None), Link("b", poses)], [ball], {}, np.array([0, 0, 1.0]), 1.0)
    >>> frame_geometry(s, 0.25)[0].r.tolist()
    [0.5, 0.0, 0.0]
    """
    return _Geometry(scene).at(_check_time(scene, t))


def film_times(scene, fps=25, speed=1.0):
    """The times (s) of a film's frames: ``t0 + k speed/fps`` while before ``t_end``, and
    ``t_end`` last -- ``ceil((t_end - t0) fps / speed) + 1`` frames (1 for a single output).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.visual.scene import Scene, Link
    >>> s = Scene(np.linspace(0, 1.0, 11), [Link("world", None)], [], {}, np.array([0, 0, 1.0]), 1.0)
    >>> film_times(s, fps=4).tolist(), len(film_times(s, fps=3, speed=0.5))
    ([0.0, 0.25, 0.5, 0.75, 1.0], 7)
    """
    if not (fps > 0 and speed > 0):
        raise ValueError(f"fps={fps!r} and speed={speed!r} must be positive numbers")
    t0, t1 = float(scene.time[0]), float(scene.time[-1])
    n = math.ceil((t1 - t0) * fps / speed - 1e-9)
    return np.append(t0 + np.arange(max(n, 0)) * (speed / fps), t1)


# ---------------------------------------------------------------------------------------------
# the matplotlib side


def _upright(up):
    """Rotation (world -> picture axes) taking ``up`` to the picture's z and the world axis most
    normal to it (x first) to the picture's x."""
    z = np.asarray(up, dtype=float) / np.linalg.norm(up)
    e = min(np.eye(3)[[0, 2, 1]], key=lambda a: round(abs(float(a @ z)), 9))
    x = e - (e @ z) * z
    x /= np.linalg.norm(x)
    return np.vstack([x, np.cross(z, x), z])


def _rgba(color, opacity, shade=1.0):
    c = np.array([int(color[i:i + 2], 16) / 255 for i in (1, 3, 5)])
    return (*np.clip(c * shade, 0, 1), opacity)


def _clip(segment, lo, hi):
    """The part of a straight segment (2, 3) within the box ``lo..hi`` in x and y, or ``None``."""
    a, d = segment[0], segment[-1] - segment[0]
    s0, s1 = 0.0, 1.0
    for j in (0, 1):
        if abs(d[j]) < 1e-15:
            if not lo[j] <= a[j] <= hi[j]:
                return None
            continue
        u, w = sorted(((lo[j] - a[j]) / d[j], (hi[j] - a[j]) / d[j]))
        s0, s1 = max(s0, u), min(s1, w)
    return None if s0 >= s1 else np.array([a + s0 * d, a + s1 * d])


def _normals(group):
    """Unit normals (m, 3) of planar convex polygons (m, k, 3) from two diagonals."""
    k = group.shape[1]
    if k == 3:
        n = np.cross(group[:, 1] - group[:, 0], group[:, 2] - group[:, 0])
    else:
        h, q = k // 2, k // 4
        n = np.cross(group[:, h] - group[:, 0], group[:, h + q] - group[:, q])
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)


class _Drawing:
    """A figure (Agg canvas, no display) with one polygon collection for every surface, lines
    for grids, helices and trails, fixed limits over the whole run; :meth:`update` redraws it at
    a time."""

    ELEV = 20.0

    def __init__(self, scene, geometry):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

        self.scene, self.geometry, self.U = scene, geometry, _upright(scene.up)
        self.grids = {v.name for v in scene.visuals if isinstance(v.shape, Grid)}
        self.figure = Figure(figsize=FIGSIZE)
        FigureCanvasAgg(self.figure)
        ax = self.ax = self.figure.add_subplot(projection="3d", computed_zorder=False)
        azim = self._frame_axes()
        cam = np.array([math.cos(math.radians(self.ELEV)) * math.cos(math.radians(azim)),
                        math.cos(math.radians(self.ELEV)) * math.sin(math.radians(azim)),
                        math.sin(math.radians(self.ELEV))])
        light = cam + np.array([0.0, 0.0, 0.6])
        self.light = self.U.T @ (light / np.linalg.norm(light))  # world
        self.ground = ax.add_collection(Line3DCollection([], linewidths=0.6, zorder=0), autolim=False)
        self.faces = ax.add_collection(Poly3DCollection([], linewidths=0.3, zorder=1), autolim=False)
        self.lines = ax.add_collection(Line3DCollection([], zorder=2), autolim=False)
        self.maps = self._colorbars()
        self.title = ax.set_title("")

    #: a run whose motion spans more than this many times the mechanism's size is followed
    #: (the limits move with the mechanism) instead of shown whole
    FOLLOW = 2.5

    def _frame_axes(self):
        """Equal scales, limits that hold the whole run (grids are cut to them) or, for a
        mechanism that travels far (a bicycle), a box of its own size that follows it; axis
        names; returns the view's azimuth."""
        ax, time = self.ax, self.scene.time
        pts, floor, extent = [np.zeros((0, 3))], [np.zeros((0, 3))], np.zeros(3)
        for k in np.unique(np.linspace(0, len(time) - 1, min(len(time), 13)).astype(int)):
            here = []
            for d in self.geometry.at(float(time[k])):
                (floor if d.name in self.grids else here).extend(np.asarray(p).reshape(-1, 3) for p in d.parts
                                                                 if not d.name.startswith("trail:"))
            if here:
                H = np.vstack(here) @ self.U.T
                extent = np.maximum(extent, H.max(axis=0) - H.min(axis=0))
                pts.append(H)
        P, G = np.vstack(pts), np.vstack(floor) @ self.U.T
        if len(P) == 0:
            P = G if len(G) else np.zeros((1, 3))
        lo, hi = P.min(axis=0), P.max(axis=0)
        self.follow = float(np.max(hi - lo)) > self.FOLLOW * max(float(np.max(extent)), self.scene.scale)
        if self.follow:
            lo, hi = -extent / 2, extent / 2
        if len(G) and not self.follow:
            lo[2], hi[2] = min(lo[2], G[:, 2].min()), max(hi[2], G[:, 2].max())
        span = max(float(np.max(hi - lo)), self.scene.scale, 1e-9)
        least = np.array([0.3, 0.3, 0.04]) * span  # a flat mechanism still shows some ground
        mid, half = (lo + hi) / 2, np.maximum(hi - lo, least) / 2 + 0.03 * span
        self.half = half
        self._limits(mid)
        ax.set_box_aspect(2 * half)
        for j, setter in enumerate((ax.set_xlabel, ax.set_ylabel, ax.set_zlabel)):
            w = self.U[j]
            i = int(np.argmax(np.abs(w)))
            setter(f"{'-' if w[i] < 0 else ''}{'xyz'[i]} (m)" if abs(w[i]) > 0.999 else "(m)")
        azim = -65.0 if hi[1] - lo[1] <= hi[0] - lo[0] else -25.0  # look across the widest side
        ax.view_init(elev=self.ELEV, azim=azim)
        return azim

    def _limits(self, mid):
        """Set the axes' limits to the box of half-sizes ``self.half`` about ``mid`` (m, plot axes)."""
        self.box = (mid - self.half, mid + self.half)
        for j, setter in enumerate((self.ax.set_xlim, self.ax.set_ylim, self.ax.set_zlim)):
            setter(mid[j] - self.half[j], mid[j] + self.half[j])

    def _colorbars(self):
        """``{component: (colormap, norm)}`` of the coloured components, each with a colour bar."""
        import matplotlib
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        maps = {}
        for c in self.scene.colors:
            lo, hi = c["min"], c["max"]
            norm = Normalize(lo, hi if hi > lo else lo + max(abs(lo), 1.0) * 1e-9)
            cmap = matplotlib.colormaps["viridis"]
            maps[c["component"]] = (cmap, norm)
            self.figure.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=self.ax, shrink=0.6, pad=0.15,
                                 label=f"{c['component']}: {c['column']}")
        return maps

    def _color(self, d, shade):
        if d.component in self.maps and d.value is not None:
            cmap, norm = self.maps[d.component]
            rgb = np.array(cmap(norm(d.value))[:3]) if np.isfinite(d.value) else np.full(3, 0.5)
            return (*np.clip(rgb * shade, 0, 1), d.opacity)
        return _rgba(d.color, d.opacity, shade)

    def update(self, t):
        """Draw the scene at time ``t`` (s)."""
        polys, colors, lines, line_colors, widths, ground, ground_colors = [], [], [], [], [], [], []
        drawn = self.geometry.at(t)
        if self.follow:  # centre on the mechanism now, its ground level kept in view
            here = [np.asarray(p).reshape(-1, 3) for d in drawn if d.name not in self.grids
                    and not d.name.startswith("trail:") for p in d.parts]
            if here:
                H = np.vstack(here) @ self.U.T
                self._limits((H.min(axis=0) + H.max(axis=0)) / 2)
        for d in drawn:
            if d.opacity <= 0:
                continue
            if d.kind == "faces":
                for group in d.parts:
                    shade = 0.35 + 0.65 * np.abs(_normals(group) @ self.light)
                    polys += list(group @ self.U.T)
                    colors += [self._color(d, s) for s in shade]
            elif d.name not in self.grids:
                lines += [p @ self.U.T for p in d.parts]
                line_colors += [self._color(d, 1.0)] * len(d.parts)
                widths += [1.2 if d.name.startswith("trail:") else 1.5] * len(d.parts)
            else:
                cut = [c for c in (_clip(p @ self.U.T, *self.box) for p in d.parts) if c is not None]
                ground += cut
                ground_colors += [self._color(d, 0.8)] * len(cut)
        self.faces.set_verts(polys)
        self.faces.set_facecolor(colors)
        self.faces.set_edgecolor(colors)
        self.lines.set_segments(lines)
        self.lines.set_color(line_colors)
        self.lines.set_linewidths(widths or [1.0])
        self.ground.set_segments(ground)
        self.ground.set_color(ground_colors)
        self.title.set_text(f"{self.scene.title + '   ' if self.scene.title else ''}t = {t:.3f} s")


def write_picture(scene, path, t=None, dpi=DPI):
    """Draw ``scene`` at time ``t`` (s; the last output by default) to a picture whose suffix
    matplotlib knows (``.png``, ``.svg``, ``.pdf``, ``.jpg``); returns ``path``.

    Between outputs the pose is interpolated (see :func:`pose_at`); ``t`` outside the run is a
    ``ValueError`` naming the range.

    Examples
    --------
    >>> import os, tempfile, mbcomp
    >>> from mbcomp.library import World, Revolute, RigidBody
    >>> from mbcomp.visual.scene import build_scene
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0))); j = m.add("j", Revolute(n=(0, 0, 1), w0=1.0))
    >>> arm = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=[[1e-3, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, arm.frame_a)
    >>> path = write_picture(build_scene(mbcomp.simulate(m, t_end=1.0)), os.path.join(tempfile.mkdtemp(), "a.png"))
    >>> os.path.getsize(path) > 1000
    True
    """
    t = _check_time(scene, t)
    drawing = _Drawing(scene, _Geometry(scene))
    drawing.update(t)
    drawing.figure.savefig(os.fspath(path), dpi=dpi)
    return path


def write_film(scene, path, fps=25, speed=1.0, dpi=DPI):
    """Write the film of ``scene`` to a ``.gif`` (matplotlib's Pillow writer) or ``.mp4``
    (its ffmpeg writer); returns ``path``.

    Frames are at :func:`film_times` (``speed`` > 1 is faster than real time) and play at
    ``fps`` frames per second.

    Raises
    ------
    ValueError
        Another suffix, or ``.mp4`` when matplotlib's ffmpeg writer is not available (naming it
        and how to install it).

    Examples
    --------
    >>> import os, tempfile, mbcomp
    >>> from mbcomp.library import World, Revolute, RigidBody
    >>> from mbcomp.visual.scene import build_scene
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0))); j = m.add("j", Revolute(n=(0, 0, 1), w0=3.0))
    >>> arm = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=[[1e-3, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, arm.frame_a)
    >>> scene = build_scene(mbcomp.simulate(m, t_end=0.2))
    >>> path = write_film(scene, os.path.join(tempfile.mkdtemp(), "a.gif"), fps=10)
    >>> os.path.getsize(path) > 1000
    True
    """
    from matplotlib import animation

    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext == ".gif":
        writer = animation.PillowWriter(fps=fps)
    elif ext == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise ValueError(f"cannot write {os.fspath(path)}: matplotlib's 'ffmpeg' writer is not available (ffmpeg "
                             "is not installed) -> install ffmpeg (apt-get install ffmpeg / conda install ffmpeg) "
                             "or write a .gif")
        writer = animation.FFMpegWriter(fps=fps)
    else:
        raise ValueError(f"cannot write {os.fspath(path)!r}: a film is a .gif or an .mp4")
    times = film_times(scene, fps, speed)
    drawing = _Drawing(scene, _Geometry(scene))
    with writer.saving(drawing.figure, os.fspath(path), dpi):
        for t in times:
            drawing.update(float(t))
            writer.grab_frame()
    return path
