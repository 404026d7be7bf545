"""What the surfaces of :mod:`mbcomp.library.surfaces` look like: grids of points on each
surface, in frame_a coordinates (m), which :meth:`Surface.visuals
<mbcomp.library.surfaces.Surface.visuals>` triangulates into a translucent
:class:`~mbcomp.modeling.shapes.Mesh` (``Mesh.from_grid``).

Each function takes the surface, the ball's radius ``r`` (m), the scene's length ``scale``
(m) and the ``track`` of the ball's centre over the run ((k, 3), frame_a coordinates, or
``None`` before a run) and returns points of shape (m, n, 3) *on* the surface (its own
parametrization, so the signed distance of every point is zero to rounding):

* :func:`sphere_cap`: a cap about the bowl's bottom ``-pole`` (a dome's top ``+pole``) of
  half-angle 60 degrees, widened to the track's widest angle plus the ball's reach;
* :func:`half_pipe`: the half of a cylinder on the track's side of the axis (the whole tube
  for a ball outside it), widened to the track's angles, along the track's extent;
* :func:`whole_torus`: the whole torus;
* :func:`height_grid`: ``h`` on a 41 x 41 grid over the track's x-y extent (a square of side
  ``scale`` about the origin before a run); a cell where ``h`` is undefined (nan) is left out.

Examples
--------
>>> import numpy as np
>>> from mbcomp.library.surfaces import SphereSurface
>>> bowl = SphereSurface(R=1.0, center=(0, 0, 1.0))
>>> P = sphere_cap(bowl, 0.1, 1.0, None)
>>> P.shape, bool(np.allclose(np.linalg.norm(P - (0, 0, 1.0), axis=-1), 1.0))
((25, 49, 3), True)
"""
import numpy as np

__all__ = ["sphere_cap", "half_pipe", "whole_torus", "height_grid"]


def _ring(k, centre, track, d=None):
    """``(e1, e2, phi)``: unit vectors across the unit ``k`` (``e1`` along ``d``, or towards
    the track's mean about ``centre``) and the track's angles about ``k`` from ``e1`` (rad)."""
    if d is None and track is not None:
        m = (track - centre).mean(axis=0)
        d = m - (m @ k) * k
    if d is None or np.linalg.norm(d) < 1e-12:
        d = np.eye(3)[int(np.argmin(np.abs(k)))]
        d = d - (d @ k) * k
    e1 = d / np.linalg.norm(d)
    e2 = np.cross(k, e1)
    phi = None if track is None else np.arctan2((track - centre) @ e2, (track - centre) @ e1)
    return e1, e2, phi


def _around(e1, e2, f):
    """``cos f e1 + sin f e2`` for an array of angles ``f`` (rad): shape ``f.shape + (3,)``."""
    return np.cos(f)[..., None] * e1 + np.sin(f)[..., None] * e2


def sphere_cap(s, r, scale, track):
    """A cap of the :class:`~mbcomp.library.surfaces.SphereSurface` ``s`` about ``-pole``
    (inside) or ``+pole`` (outside): half-angle 60 degrees, or the track's widest angle from
    that point plus ``r / R + 0.2`` rad, up to the whole sphere (25 x 49 points)."""
    d = -s.pole if s.inside else s.pole
    theta = np.pi / 3
    if track is not None:
        u = (track - s.center) / np.linalg.norm(track - s.center, axis=1)[:, None]
        theta = max(theta, float(np.arccos(np.clip(u @ d, -1.0, 1.0)).max()) + r / s.R + 0.2)
    e1, e2, _ = _ring(d, s.center, None)
    t, f = np.meshgrid(np.linspace(0.0, min(theta, np.pi), 25), np.linspace(0.0, 2 * np.pi, 49), indexing="ij")
    return s.center + s.R * (np.cos(t)[..., None] * d + np.sin(t)[..., None] * _around(e1, e2, f))


def half_pipe(s, r, scale, track):
    """Of the :class:`~mbcomp.library.surfaces.CylinderSurface` ``s``: the half on the track's
    side of the axis (inside; the whole tube outside), widened to cover the track's angles
    plus ``r / R + 0.3`` rad, along the track's extent on the axis and ``max(3 r, scale / 10)``
    beyond (``scale`` long about ``center`` before a run); 25 x 37 points."""
    k = s.axis
    e1, e2, phi = _ring(k, s.center, track)
    half = np.pi / 2 if s.inside else np.pi
    if phi is not None:
        half = min(max(half, float(np.abs(phi).max()) + r / s.R + 0.3), np.pi)
    along = [-scale / 2, scale / 2] if track is None else (track - s.center) @ k
    margin = max(3 * r, 0.1 * scale)
    a, f = np.meshgrid(np.linspace(np.min(along) - margin, np.max(along) + margin, 25),
                       np.linspace(-half, half, 37), indexing="ij")
    return s.center + a[..., None] * k + s.R * _around(e1, e2, f)


def whole_torus(s, r, scale, track):
    """The whole :class:`~mbcomp.library.surfaces.TorusSurface` ``s`` (65 points around the
    axis, 25 around the tube)."""
    e1, e2, _ = _ring(s.axis, s.center, None)
    f, t = np.meshgrid(np.linspace(0.0, 2 * np.pi, 65), np.linspace(0.0, 2 * np.pi, 25), indexing="ij")
    return s.center + (s.R + s.a * np.cos(t))[..., None] * _around(e1, e2, f) + s.a * np.sin(t)[..., None] * s.axis


def height_grid(s, r, scale, track):
    """The :class:`~mbcomp.library.surfaces.HeightField` ``s``'s ``h`` on a 41 x 41 grid over
    the track's x-y extent and ``max(3 r, scale / 4)`` beyond (a square of side ``scale``
    about the origin before a run); nan where ``h`` is undefined."""
    if track is None:
        lo, hi = np.full(2, -scale / 2), np.full(2, scale / 2)
    else:
        margin = max(3 * r, scale / 4)
        lo, hi = track[:, :2].min(axis=0) - margin, track[:, :2].max(axis=0) + margin
    X, Y = np.meshgrid(np.linspace(lo[0], hi[0], 41), np.linspace(lo[1], hi[1], 41), indexing="ij")
    with np.errstate(invalid="ignore", divide="ignore"):
        Z = np.vectorize(lambda x, y: float(s._eval(x, y).val))(X, Y)
    return np.stack([X, Y, Z], axis=-1)
