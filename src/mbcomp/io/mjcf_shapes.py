"""MJCF geoms as mbcomp shapes: what ``--animate`` draws of an imported model.

Each geom of a visible group (0, 1, 2: what MuJoCo's viewer shows by default) becomes shapes
on its body, in body axes: sphere -> :class:`~mbcomp.Sphere`; box -> :class:`~mbcomp.Box`
(edges twice MuJoCo's half sizes); cylinder -> :class:`~mbcomp.Cylinder`; capsule -> a
cylinder and a sphere on each end; ellipsoid -> a unit sphere's triangles scaled by the
radii (:class:`~mbcomp.Mesh` given inline); mesh -> :class:`~mbcomp.Mesh` of the asset's STL
or OBJ file (``<compiler meshdir>``), uniformly scaled; plane -> :class:`~mbcomp.modeling.shapes.Grid`.
Colours: the geom's ``rgba`` (its own or its class's), else its material's, else MuJoCo's grey;
the alpha is the opacity. What cannot be drawn is said in the notes.
"""
import functools
import os

import numpy as np

from .mjcf_frames import numbers

__all__ = ["geom_shapes", "materials_and_meshes"]

_GREY = "0.5 0.5 0.5 1"


def materials_and_meshes(root, compiler, defaults):
    """``({material: rgba (4,)}, {mesh name: {path, scale, refpos, refquat, method}})`` of the
    ``<asset>`` sections (a mesh's file under ``<compiler meshdir>``, its ``inertia`` as ``method``)."""
    mats, meshes = {}, {}
    for asset in root.findall("asset"):
        for el in asset.findall("material"):
            a = defaults.attributes(el, "main")
            if "rgba" in a and el.get("name"):
                mats[el.get("name")] = numbers(a["rgba"], 4, f"material {el.get('name')!r} rgba")
        for el in asset.findall("mesh"):
            a = defaults.attributes(el, "main")
            f = a.get("file")
            if f is None:
                continue
            name = el.get("name") or os.path.splitext(os.path.basename(f))[0]
            meshes[name] = {"path": os.path.join(compiler.meshdir, f),
                            "scale": numbers(a.get("scale", "1 1 1"), 3, f"mesh {name!r} scale"),
                            "refpos": numbers(a.get("refpos", "0 0 0"), 3, f"mesh {name!r} refpos"),
                            "refquat": numbers(a.get("refquat", "1 0 0 0"), 4, f"mesh {name!r} refquat"),
                            "method": a.get("inertia", "legacy")}
    return mats, meshes


def _color(attrs, mats):
    if "rgba" in attrs:
        c = numbers(attrs["rgba"], 4, "geom rgba")
    elif attrs.get("material") in mats:
        c = mats[attrs["material"]]
    else:
        c = numbers(_GREY, 4)
    return {"color": tuple(float(x) for x in np.clip(c[:3], 0, 1)), "opacity": float(np.clip(c[3], 0, 1))}


@functools.lru_cache(maxsize=1)
def _unit_sphere(n=12):
    """Vertices and triangles of a unit sphere (``n`` latitude bands, ``2 n`` meridians)."""
    th = np.linspace(0.0, np.pi, n + 1)
    ph = np.linspace(0.0, 2.0 * np.pi, 2 * n, endpoint=False)
    v = [(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)) for t in th[1:-1] for p in ph]
    v = [(0.0, 0.0, 1.0)] + v + [(0.0, 0.0, -1.0)]
    m, f = 2 * n, []
    for k in range(m):
        f.append((0, 1 + k, 1 + (k + 1) % m))
    for band in range(n - 2):
        a, b = 1 + band * m, 1 + (band + 1) * m
        for k in range(m):
            k1 = (k + 1) % m
            f += [(a + k, b + k, b + k1), (a + k, b + k1, a + k1)]
    last, base = len(v) - 1, 1 + (n - 2) * m
    for k in range(m):
        f.append((base + k, last, base + (k + 1) % m))
    return np.array(v), np.array(f)


def geom_shapes(g, mats, meshes, what, notes):
    """The shapes of :class:`~mbcomp.io.mjcf_inertia.GeomFrame` ``g`` (body axes); ``[]`` for a
    hidden group or an invisible geom, with a note where a visible geom cannot be drawn."""
    from mbcomp.modeling.shapes import Box, Cylinder, Grid, Mesh, Sphere

    if int(float(g.attrs.get("group", 0))) > 2:
        return []
    look = _color(g.attrs, mats)
    if look["opacity"] == 0.0:
        return []
    place = {"r": g.pos, "R": g.R, **look}
    s = g.size
    if g.kind == "sphere":
        return [Sphere(s[0], **place)]
    if g.kind == "box":
        return [Box(tuple(2.0 * s), **place)]
    if g.kind == "cylinder":
        return [Cylinder(s[0], 2.0 * s[1], **place)]
    if g.kind == "capsule":
        ends = [Sphere(s[0], r=g.pos + k * s[1] * g.R[:, 2], **look) for k in (-1.0, 1.0)]
        return ([Cylinder(s[0], 2.0 * s[1], **place)] if s[1] > 0 else []) + ends
    if g.kind == "ellipsoid":
        v, f = _unit_sphere()
        return [Mesh(vertices=v * s, faces=f, **place)]
    if g.kind == "plane":
        size = 2.0 * max(s[0], s[1])
        return [Grid(size=size if size > 0 else None, r=g.pos, R=g.R, color=look["color"])]
    if g.kind == "mesh":
        return _mesh(g, meshes, place, what, notes)
    notes.append(f"{what}: a {g.kind} geom is not drawn")
    return []


def _mesh(g, meshes, place, what, notes):
    from mbcomp.modeling.shapes import Mesh

    name = g.attrs.get("mesh")
    if name not in meshes:
        notes.append(f"{what}: mesh {name!r} has no <mesh file> asset: not drawn")
        return []
    path, scale = meshes[name]["path"], meshes[name]["scale"]
    if np.any(meshes[name]["refpos"]) or not np.array_equal(meshes[name]["refquat"], (1, 0, 0, 0)):
        notes.append(f"{what}: mesh {os.path.basename(path)!r} with refpos/refquat not drawn")
        return []
    if not path.lower().endswith((".stl", ".obj")) or not np.allclose(scale, scale[0]):
        notes.append(f"{what}: mesh {os.path.basename(path)!r} (scale {scale.tolist()}) not drawn: STL or OBJ "
                     "files with a uniform scale are")
        return []
    return [Mesh(path, scale=float(scale[0]), **place)]
