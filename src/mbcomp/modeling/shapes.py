"""Shapes a component is drawn with: what the animation, the snapshots and the films show.

A shape is geometry placed in one of its component's frames: ``frame`` names the port,
``r`` (m) and ``R`` (shape axes -> frame axes) place the shape's own axes in that frame.
A *span* (:class:`Helix`, :class:`Rod`) is stretched between the origins of two frames of its
component (``frame`` and ``to``), as a spring or a massless rod is. Every class is immutable.

Components declare their default shapes (:meth:`Component.visuals
<mbcomp.modeling.component.Component.visuals>`); a user replaces them with
``shape=mbcomp.Box(...)`` (or a list of shapes) at construction, recolours them with
``color=...`` and hides a component with ``visible=False``.

Examples
--------
>>> import mbcomp
>>> mbcomp.Box((0.4, 0.05, 0.05), r=(0.2, 0, 0), color="steelblue").size
(0.4, 0.05, 0.05)
>>> mbcomp.Cylinder(radius=0.01, length=0.1).axis
'z'
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, fields, replace

import numpy as np

__all__ = ["Shape", "Box", "Cylinder", "Sphere", "Mesh", "Helix", "Rod", "Grid", "rgb"]

#: named colours the scene knows, besides "#rrggbb" and (r, g, b) in 0..1
COLORS = {
    "steelblue": "#4682b4", "grey": "#808080", "gray": "#808080", "silver": "#c0c0c0", "black": "#000000",
    "white": "#ffffff", "red": "#ff0000", "green": "#008000", "blue": "#0000ff", "orange": "#ff7f0e",
    "yellow": "#e5c100", "purple": "#9467bd", "brown": "#8c564b", "pink": "#e377c2", "olive": "#bcbd22",
    "cyan": "#17becf", "gold": "#d4a017", "darkgrey": "#404040", "lightgrey": "#d3d3d3",
}


def rgb(color, where="color"):
    """``"#rrggbb"`` of a colour given as a name (:data:`COLORS`), ``"#rrggbb"``, ``"#rgb"`` or
    an ``(r, g, b)`` triple in 0..1; ``None`` stays ``None``.

    Examples
    --------
    >>> rgb("steelblue"), rgb((1, 0, 0.5)), rgb("#abc")
    ('#4682b4', '#ff0080', '#aabbcc')
    """
    if color is None:
        return None
    if isinstance(color, str):
        c = COLORS.get(color.lower(), color.lower())
        if c.startswith("#") and len(c) == 4 and all(ch in "0123456789abcdef" for ch in c[1:]):
            return "#" + "".join(ch * 2 for ch in c[1:])
        if c.startswith("#") and len(c) == 7 and all(ch in "0123456789abcdef" for ch in c[1:]):
            return c
    else:
        try:
            v = np.asarray(color, dtype=float)
        except (TypeError, ValueError):
            v = None
        if v is not None and v.shape == (3,) and np.all((v >= 0) & (v <= 1)):
            return "#" + "".join(f"{int(round(x * 255)):02x}" for x in v)
    raise ValueError(f"{where}={color!r} is no colour -> use a name ({', '.join(sorted(COLORS)[:6])}, ...), "
                     "'#rrggbb' or an (r, g, b) triple in 0..1")


def _vec(value, n, name, cls):
    try:
        v = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{cls}: {name}={value!r} must be {n} finite numbers")
    return tuple(float(x) for x in v)


def _positive(value, name, cls, allow_none=False):
    if value is None and allow_none:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{cls}: {name}={value!r} must be a positive, finite number (m)")
    return v


@dataclass(frozen=True)
class Shape:
    """Base of every shape: where it sits and how it looks.

    Parameters
    ----------
    r : (3,) float
        Origin of the shape's axes, m, in the axes of ``frame``.
    R : (3, 3) float, optional
        Orientation of the shape's axes: shape -> frame (identity by default).
    frame : str, optional
        The port of the component the shape rides on (``frame_a``, or the component's only
        frame, by default).
    color : str or (3,) float, optional
        ``"#rrggbb"``, a name, or an ``(r, g, b)`` triple in 0..1; the scene picks one if ``None``.
    opacity : float
        0 (invisible) .. 1 (opaque).

    Examples
    --------
    >>> from mbcomp.modeling.shapes import Sphere
    >>> Sphere(0.1, r=(1, 0, 0)).placed(frame="frame_b").frame
    'frame_b'
    """

    r: tuple = (0.0, 0.0, 0.0)
    R: tuple | None = None
    frame: str | None = None
    color: str | None = None
    opacity: float = 1.0

    def __post_init__(self):
        cls = type(self).__name__
        object.__setattr__(self, "r", _vec(self.r, 3, "r", cls))
        if self.R is not None:
            R = np.asarray(self.R, dtype=float)
            if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
                raise ValueError(f"{cls}: R must be a 3x3 rotation matrix (shape axes -> frame axes)")
            object.__setattr__(self, "R", tuple(map(tuple, R.tolist())))
        object.__setattr__(self, "color", rgb(self.color, f"{cls}.color"))
        if not 0.0 <= float(self.opacity) <= 1.0:
            raise ValueError(f"{cls}: opacity={self.opacity!r} must be in 0..1")
        self._check()

    def _check(self):
        """Subclasses check their own sizes."""

    def placed(self, **changes):
        """A copy with other placement or looks (``r``, ``R``, ``frame``, ``color``, ``opacity``)."""
        return replace(self, **changes)

    @property
    def rotation(self):
        """``R`` as an ndarray (3, 3)."""
        return np.eye(3) if self.R is None else np.array(self.R)

    def geometry(self):
        """The type and sizes, as a plain dict (the scene's JSON)."""
        base = {f.name for f in fields(Shape)}
        out = {"type": type(self).__name__.lower()}
        for f in fields(self):
            if f.name not in base:
                v = getattr(self, f.name)
                out[f.name] = list(v) if isinstance(v, tuple) else v
        return out


@dataclass(frozen=True)
class Box(Shape):
    """A box of edge lengths ``size`` (m) along the shape's x, y, z, centred on its origin.

    Examples
    --------
    >>> Box((1, 2, 3)).geometry()
    {'type': 'box', 'size': [1.0, 2.0, 3.0]}
    """

    size: tuple = (0.1, 0.1, 0.1)

    def __init__(self, size=(0.1, 0.1, 0.1), **placement):
        object.__setattr__(self, "size", size)
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "size", tuple(_positive(s, "size", "Box") for s in _vec(self.size, 3, "size", "Box")))


@dataclass(frozen=True)
class Cylinder(Shape):
    """A cylinder of ``radius`` and ``length`` (m) along the shape's z axis, centred on its
    origin (a disk when short, a rod when long).

    Examples
    --------
    >>> Cylinder(0.3, 0.02).geometry()
    {'type': 'cylinder', 'radius': 0.3, 'length': 0.02, 'axis': 'z'}
    """

    radius: float = 0.05
    length: float = 0.1
    axis: str = field(default="z", init=False)

    def __init__(self, radius=0.05, length=0.1, **placement):
        object.__setattr__(self, "radius", radius)
        object.__setattr__(self, "length", length)
        object.__setattr__(self, "axis", "z")
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "radius", _positive(self.radius, "radius", "Cylinder"))
        object.__setattr__(self, "length", _positive(self.length, "length", "Cylinder"))


@dataclass(frozen=True)
class Sphere(Shape):
    """A sphere of ``radius`` (m) about the shape's origin.

    Examples
    --------
    >>> Sphere(0.1).radius
    0.1
    """

    radius: float = 0.05

    def __init__(self, radius=0.05, **placement):
        object.__setattr__(self, "radius", radius)
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "radius", _positive(self.radius, "radius", "Sphere"))


@dataclass(frozen=True)
class Mesh(Shape):
    """A triangle mesh: from an STL (ASCII or binary), OBJ or COLLADA (``.dae``, read through
    the optional trimesh and pycollada: ``pip install mbcomp[meshes]``) file (``path``), or given
    inline (``vertices`` (n, 3) and ``faces`` (m, 3) indices, 0-based), its coordinates times
    ``scale`` in m, in the shape's axes. ``scale`` is one factor or three, one per axis (a
    URDF's ``scale="0.001 0.001 0.001"``); a negative factor mirrors the mesh. A file is read
    when a scene is built (:func:`mbcomp.visual.meshes.read_mesh`); a missing file is reported
    then with its path. :meth:`from_grid` triangulates a grid of points (a patch of a surface).

    Examples
    --------
    >>> Mesh("part.stl", scale=1e-3).scale
    0.001
    >>> Mesh("left_leg.dae", scale=(1, -1, 1)).scale
    (1.0, -1.0, 1.0)
    >>> tri = Mesh(vertices=[(0, 0, 0), (1, 0, 0), (0, 1, 0)], faces=[(0, 1, 2)], opacity=0.5)
    >>> vertices, faces = tri.triangles(); vertices.shape, faces.tolist()
    ((3, 3), [[0, 1, 2]])
    """

    path: str = ""
    scale: float = 1.0
    vertices: tuple | None = None
    faces: tuple | None = None

    def __init__(self, path="", scale=1.0, vertices=None, faces=None, **placement):
        object.__setattr__(self, "path", os.fspath(path))
        object.__setattr__(self, "scale", scale)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", faces)
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "scale", _scale(self.scale))
        if self.vertices is None and self.faces is None:
            if not str(self.path).lower().endswith(MESH_SUFFIXES):
                raise ValueError(f"Mesh: path={self.path!r} must be an .stl, .obj or .dae file (or give vertices= "
                                 "and faces=)")
            return
        if self.path:
            raise ValueError("Mesh: give either a path or vertices= and faces=, not both")
        v, f = _inline_mesh(self.vertices, self.faces)
        object.__setattr__(self, "vertices", tuple(map(tuple, v.tolist())))
        object.__setattr__(self, "faces", tuple(map(tuple, f.tolist())))

    @property
    def inline(self):
        """True for a mesh given by its vertices and faces (no file)."""
        return self.vertices is not None

    def triangles(self):
        """``(vertices (n, 3) in m, faces (m, 3) int)`` of an inline mesh, times ``scale`` (a
        file's are read by the scene: :func:`mbcomp.visual.meshes.read_mesh`)."""
        if not self.inline:
            raise ValueError(f"Mesh({self.path!r}) is read from its file by the scene -> use "
                             "mbcomp.visual.meshes.read_mesh")
        return self.scaled(np.array(self.vertices, dtype=float), np.array(self.faces, dtype=np.int64))

    def scaled(self, vertices, faces):
        """``(vertices * scale, faces)``: the mesh's coordinates (its file's units) in m, each
        axis times its factor; a mirror (an odd number of negative factors) turns the faces'
        corners the other way, so they stay counter-clockwise seen from outside.

        Examples
        --------
        >>> v, f = Mesh("part.stl", scale=(2, -1, 1)).scaled(np.ones((3, 3)), np.array([[0, 1, 2]]))
        >>> v[0].tolist(), f.tolist()
        ([2.0, -1.0, 1.0], [[0, 2, 1]])
        """
        factors = np.broadcast_to(np.asarray(self.scale, dtype=float), (3,))
        faces = np.asarray(faces)
        return np.asarray(vertices, dtype=float) * factors, (faces[:, [0, 2, 1]] if np.prod(factors) < 0 else faces)

    def geometry(self):
        """The type and, for a file, its path and scale (the scene writes the triangles)."""
        if self.inline:
            return {"type": "mesh", "vertices": len(self.vertices), "faces": len(self.faces)}
        return {"type": "mesh", "path": self.path, "scale": list(self.scale) if isinstance(self.scale, tuple)
                else self.scale}

    @classmethod
    def from_grid(cls, points, **placement):
        """The mesh of a grid of points ``points[i, j]`` (m, shape (m, n, 3)): two triangles per
        cell; cells with a non-finite corner (a height function undefined there) are left out.

        Examples
        --------
        >>> import numpy as np
        >>> x, y = np.meshgrid(np.linspace(0, 1, 3), np.linspace(0, 1, 4), indexing="ij")
        >>> patch = Mesh.from_grid(np.stack([x, y, 0 * x], axis=-1), opacity=0.4)
        >>> len(patch.vertices), len(patch.faces)   # 3 x 4 points, 2 x 3 cells of two triangles
        (12, 12)
        """
        P = np.asarray(points, dtype=float)
        if P.ndim != 3 or P.shape[2] != 3 or min(P.shape[:2]) < 2:
            raise ValueError(f"Mesh.from_grid: points must have shape (m, n, 3) with m, n >= 2, not {P.shape}")
        m, n = P.shape[:2]
        idx = np.arange(m * n).reshape(m, n)
        a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
        faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
        flat = P.reshape(-1, 3)
        ok = np.all(np.isfinite(flat), axis=1)
        faces = faces[np.all(ok[faces], axis=1)]
        if not len(faces):
            raise ValueError("Mesh.from_grid: no cell has four finite corners")
        used = np.unique(faces)
        renumber = np.full(len(flat), -1)
        renumber[used] = np.arange(len(used))
        return cls(vertices=flat[used], faces=renumber[faces], **placement)


#: the mesh files :class:`Mesh` takes (any case): STL, Wavefront OBJ, COLLADA
MESH_SUFFIXES = (".stl", ".obj", ".dae")


def _scale(value):
    """A mesh's ``scale``: one nonzero factor (a float) or three (a tuple), finite."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.shape not in ((), (3,)) or not np.all(np.isfinite(v)) or not np.all(v != 0):
        raise ValueError(f"Mesh: scale={value!r} must be one nonzero finite number or three (one per axis; "
                         "negative mirrors)")
    return float(v) if v.shape == () else tuple(float(x) for x in v)


def _inline_mesh(vertices, faces):
    """The checked arrays of an inline mesh."""
    try:
        v = np.asarray(vertices, dtype=float)
        f = np.asarray(faces)
    except (TypeError, ValueError):
        v, f = np.zeros((0, 0)), np.zeros((0, 0))
    if v.ndim != 2 or v.shape[1:] != (3,) or not len(v) or not np.all(np.isfinite(v)):
        raise ValueError("Mesh: vertices= must be an (n, 3) array of finite coordinates (m, the shape's axes)")
    if f.ndim != 2 or f.shape[1:] != (3,) or not len(f) or f.dtype.kind not in "iu" or f.min() < 0 \
            or f.max() >= len(v):
        raise ValueError(f"Mesh: faces= must be an (m, 3) array of whole vertex indices in 0..{len(v) - 1}")
    return v, f.astype(np.int64)


@dataclass(frozen=True)
class Helix(Shape):
    """A coil spring stretched from the origin of ``frame`` to the origin of ``to`` (a span):
    coil ``radius`` (m), ``turns``, wire radius ``wire`` (m).

    Examples
    --------
    >>> Helix(0.02, turns=8, to="frame_b").to
    'frame_b'
    """

    radius: float = 0.05
    turns: int = 10
    wire: float | None = None
    to: str = "frame_b"

    def __init__(self, radius=0.05, turns=10, wire=None, to="frame_b", **placement):
        for k, v in dict(radius=radius, turns=turns, wire=wire, to=to).items():
            object.__setattr__(self, k, v)
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "radius", _positive(self.radius, "radius", "Helix"))
        object.__setattr__(self, "wire", _positive(self.wire, "wire", "Helix", allow_none=True) or self.radius / 8)
        if int(self.turns) != self.turns or self.turns < 1:
            raise ValueError(f"Helix: turns={self.turns!r} must be a whole number >= 1")
        object.__setattr__(self, "turns", int(self.turns))


@dataclass(frozen=True)
class Rod(Shape):
    """A rod of ``radius`` (m) stretched from the origin of ``frame`` to the origin of ``to``
    (a span: a damper, a massless link).

    Examples
    --------
    >>> Rod(0.01).geometry()["type"]
    'rod'
    """

    radius: float = 0.02
    to: str = "frame_b"

    def __init__(self, radius=0.02, to="frame_b", **placement):
        object.__setattr__(self, "radius", radius)
        object.__setattr__(self, "to", to)
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "radius", _positive(self.radius, "radius", "Rod"))


@dataclass(frozen=True)
class Grid(Shape):
    """The ground: a square grid through the shape's origin, normal to the shape's z axis;
    ``size`` (m) ``None`` lets the scene fit it to the motion. A ``floor`` (the world's) is
    moved down by the scene to below the motion; otherwise (a contact's plane) it stays
    exactly where it is placed.

    Examples
    --------
    >>> Grid().divisions, Grid(floor=False).floor
    (20, False)
    """

    size: float | None = None
    divisions: int = 20
    floor: bool = True

    def __init__(self, size=None, divisions=20, floor=True, **placement):
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "divisions", divisions)
        object.__setattr__(self, "floor", bool(floor))
        super().__init__(**placement)

    def _check(self):
        object.__setattr__(self, "size", _positive(self.size, "size", "Grid", allow_none=True))
        if int(self.divisions) != self.divisions or self.divisions < 1:
            raise ValueError(f"Grid: divisions={self.divisions!r} must be a whole number >= 1")


SPANS = (Helix, Rod)


def shapes_given(shape, where):
    """The tuple of shapes a component was given (``shape=``): one shape, a list of shapes,
    or ``None`` (the component's default shapes)."""
    if shape is None:
        return None
    items = list(shape) if isinstance(shape, (list, tuple)) else [shape]
    bad = [s for s in items if not isinstance(s, Shape)]
    if bad:
        raise TypeError(f"{where}: shape={bad[0]!r} is not a shape -> use mbcomp.Box, Cylinder, Sphere, Mesh, "
                        "Helix or Rod (or a list of them)")
    return tuple(items)


def z_to(n):
    """A rotation matrix (shape -> frame) taking the shape's z axis to the direction ``n``.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(z_to((1, 0, 0)) @ (0, 0, 1), 12).tolist()
    [1.0, 0.0, 0.0]
    """
    z = np.asarray(n, dtype=float) / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


#: density (kg/m^3) a point mass's sphere is sized by: steel
STEEL = 7800.0


def body_shapes(m, r_cm, I, attached, scale):
    """A body's default shapes on its ``frame_a``: a rod from the origin to each frame fixed to
    it (a link from joint to joint) and, off those rods, a rod and a ball to the centre of
    mass; alone, a cylinder or box of the body's mass and inertia at the centre of mass; a
    point mass (no inertia of its own) is a steel sphere of its mass in either case.

    Parameters
    ----------
    m : float
        Mass, kg.
    r_cm : (3,) float
        Centre of mass, m, frame_a.
    I : (3, 3) float
        Inertia about the centre of mass, kg m^2, frame_a axes.
    attached : list of (3,) float
        Origins of the frames rigidly fixed to frame_a, m, frame_a.
    scale : float
        The scene's length scale, m.

    Examples
    --------
    >>> import numpy as np
    >>> [type(s).__name__ for s in body_shapes(1.0, (0.1, 0, 0), np.zeros((3, 3)), [(0.2, 0, 0)], 1.0)]
    ['Cylinder', 'Sphere']
    """
    rad = 0.02 * scale
    r_cm = np.asarray(r_cm, dtype=float)
    out = []
    points = [np.asarray(a, dtype=float) for a in attached if np.linalg.norm(a) > 1e-9 * scale]
    for a in points:
        out.append(Cylinder(rad, float(np.linalg.norm(a)), r=a / 2, R=z_to(a)))
    if not points or _is_point(m, I, scale):
        return out + _alone(m, r_cm, np.asarray(I, dtype=float), scale)
    if min(_segment_distance(r_cm, a) for a in points) > 2 * rad:
        if np.linalg.norm(r_cm) > 1e-9 * scale:
            out.append(Cylinder(rad * 0.6, float(np.linalg.norm(r_cm)), r=r_cm / 2, R=z_to(r_cm)))
        out.append(Sphere(2.5 * rad, r=r_cm))
    return out


def _is_point(m, I, scale):
    return np.max(np.abs(np.asarray(I, dtype=float))) <= 1e-12 * max(m * scale**2, 1e-300)


def _segment_distance(x, a):
    """Distance (m) of the point ``x`` from the segment 0..a."""
    s = float(np.clip(x @ a / (a @ a), 0.0, 1.0))
    return float(np.linalg.norm(x - s * a))


def _alone(m, r_cm, I, scale):
    """A body with nothing fixed to it: its equivalent cylinder or box, or a sphere."""
    if m <= 0:
        return []
    if _is_point(m, I, scale):
        radius = float(np.clip((3 * m / (4 * np.pi * STEEL)) ** (1 / 3), 0.04 * scale, 0.15 * scale))
        return [Sphere(radius, r=r_cm)]
    lam, V = np.linalg.eigh((I + I.T) / 2)
    if np.linalg.det(V) < 0:
        V[:, 0] = -V[:, 0]
    lam = np.maximum(lam, 0.0)
    for k in range(3):  # two equal principal moments: a rotor or a rod, a cylinder about the third
        i, j = [x for x in range(3) if x != k]
        if abs(lam[i] - lam[j]) <= 0.02 * max(lam[i], lam[j]) and abs(lam[k] - lam[i]) > 0.02 * max(lam[k], lam[i]):
            radius = np.sqrt(2 * lam[k] / m)
            h = np.sqrt(max(12 * lam[i] / m - 3 * radius**2, (0.05 * radius) ** 2))
            return [Cylinder(float(max(radius, 0.015 * max(h, scale))), float(h), r=r_cm, R=z_to(V[:, k]))]
    edges = [np.sqrt(max(6 * (lam[(k + 1) % 3] + lam[(k + 2) % 3] - lam[k]) / m, 0.0)) for k in range(3)]
    floor = 0.02 * max(max(edges), scale)
    return [Box(tuple(float(max(e, floor)) for e in edges), r=r_cm, R=V)]
