"""Mass properties of MJCF mesh geoms, as MuJoCo's compiler computes them (``mjCMesh``).

The mesh's vertices (an STL or OBJ file; OBJ coordinates rounded to single precision as
MuJoCo's reader does) are moved by the asset's ``refpos``/``refquat`` (``v' = R^T (v - refpos)``)
and scaled axis by axis (a left-handed scale reverses the triangles). Then, for the
``inertia`` attribute ``legacy`` (MuJoCo's default) or ``exact``:

1. ``c_f``: the triangles' centroid weighted by their areas;
2. the centre of mass: the triangles' pyramids with apex ``c_f`` (volume
   ``(t - c_f) . n A / 3``, ``t`` the triangle's centre, ``n`` its unit normal, ``A`` its area;
   ``legacy`` takes the absolute value), each weighing at ``3 t / 4 + c_f / 4``;
3. the volume and the inertia about that centre: pyramids with apex at the centre, each of
   volume ``V`` adding ``V / 20 (2 (D_a D_b + E_a E_b + F_a F_b) + D_a E_b + D_b E_a + D_a F_b +
   D_b F_a + E_a F_b + E_b F_a)`` to the second moments (vertices ``D, E, F`` from the centre).

The geom's mass is ``density`` times that volume (or its ``mass``), its inertia density times
the moments, centred at the centre of mass in the geom's axes. ``convex`` (the hull's
inertia) and ``shell`` are refused, naming the fix.
"""
import functools

import numpy as np

from ..geometry.kinematics import quat_to_matrix

__all__ = ["mesh_volume_inertia"]


def _triangles(v, f):
    """Each triangle's area, unit normal (zero where degenerate) and centre."""
    D, E, F = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(E - D, F - D)
    norm = np.linalg.norm(n, axis=1)
    unit = np.divide(n, norm[:, None], out=np.zeros_like(n), where=norm[:, None] > 0)
    return 0.5 * norm, unit, (D + E + F) / 3.0


def _vertices(path, scale, refpos, refquat):
    from ..visual.meshes import read_mesh

    v, f = read_mesh(path)
    if str(path).lower().endswith(".obj"):
        v = v.astype(np.float32).astype(np.float64)  # MuJoCo's OBJ reader keeps floats
    if np.any(refpos):
        v = v - refpos
    if not np.array_equal(refquat, (1.0, 0.0, 0.0, 0.0)):
        v = v @ quat_to_matrix(refquat / np.linalg.norm(refquat))
    v = v * scale
    if np.prod(scale) < 0:
        f = f[:, ::-1]
    return v, f


@functools.lru_cache(maxsize=512)
def _cached(path, scale, refpos, refquat, method):
    v, f = _vertices(path, np.array(scale), np.array(refpos), np.array(refquat))
    area, n, t = _triangles(v, f)
    if area.sum() <= 0.0:
        raise ValueError(f"MJCF mesh {path!r}: its surface area is zero -> fix the mesh file")
    cf = (area[:, None] * t).sum(axis=0) / area.sum()
    vol = np.einsum("ij,ij->i", t - cf, n) * area / 3.0
    if method == "legacy":
        vol = np.abs(vol)
    if vol.sum() <= 0.0:
        raise ValueError(f"MJCF mesh {path!r}: volume {vol.sum():g} m^3 <= 0 (misoriented or flat triangles) "
                         "-> fix the mesh, or give the body an <inertial>")
    com = (vol[:, None] * (0.75 * t + 0.25 * cf)).sum(axis=0) / vol.sum()
    w = v - com
    area, n, t = _triangles(w, f)
    vol = np.einsum("ij,ij->i", t, n) * area / 3.0
    if method == "legacy":
        vol = np.abs(vol)
    D, E, F = w[f[:, 0]], w[f[:, 1]], w[f[:, 2]]
    S = D + E + F
    second = (np.einsum("k,ka,kb->ab", vol, D, D) + np.einsum("k,ka,kb->ab", vol, E, E)
              + np.einsum("k,ka,kb->ab", vol, F, F) + np.einsum("k,ka,kb->ab", vol, S, S)) / 20.0
    inertia = np.trace(second) * np.eye(3) - second
    return float(vol.sum()), com, inertia


def mesh_volume_inertia(path, scale=(1.0, 1.0, 1.0), refpos=(0.0, 0.0, 0.0), refquat=(1.0, 0.0, 0.0, 0.0),
                        method="legacy", what="mesh"):
    """``(volume m^3, centre of mass (3,) m, inertia per unit density (3, 3) m^5)`` of a mesh
    file in the geom's axes, the inertia about the centre of mass, as MuJoCo computes them.

    Examples
    --------
    >>> import os, tempfile
    >>> from mbcomp.io.mjcf_mesh import mesh_volume_inertia
    >>> path = os.path.join(tempfile.mkdtemp(), "cube.obj")
    >>> corners = [(x, y, z) for x in (0, 2) for y in (0, 1) for z in (0, 1)]
    >>> quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    >>> text = "".join(f"v {x} {y} {z}\\n" for x, y, z in corners)
    >>> text += "".join(f"f {a} {b} {c}\\nf {a} {c} {d}\\n" for a, b, c, d in quads)
    >>> _ = open(path, "w").write(text)
    >>> V, c, I = mesh_volume_inertia(path)
    >>> round(V, 12), c.round(12).tolist(), round(float(I[2, 2]), 12)     # 2 (4 + 1) / 12
    (2.0, [1.0, 0.5, 0.5], 0.833333333333)
    """
    if method not in ("legacy", "exact"):
        raise ValueError(f"MJCF {what}: inertia={method!r} is not computed (legacy and exact are) -> give the "
                         "body an <inertial>, or inertia='legacy' or 'exact' to the mesh")
    key = (str(path), tuple(float(x) for x in scale), tuple(float(x) for x in refpos),
           tuple(float(x) for x in refquat), method)
    V, com, inertia = _cached(*key)
    return V, com.copy(), inertia.copy()
