"""Triangle meshes from files: ASCII STL, binary STL, Wavefront OBJ and COLLADA (``.dae``).

:func:`read_mesh` returns the vertices (in the file's units) and the triangles of a file; the
scene scales them by the :class:`~mbcomp.modeling.shapes.Mesh`'s ``scale``. STL repeats a
vertex in every triangle that uses it, so its vertices are merged when their coordinates are
equal; an OBJ's vertices are kept as listed. Polygons of an OBJ are fanned into triangles
(``f 1 2 3 4`` -> ``1 2 3``, ``1 3 4``). STL and OBJ are read here; COLLADA through trimesh
and pycollada, optional (``pip install mbcomp[meshes]``): its scene's node transforms are
applied and its ``<unit meter="...">`` turns its coordinates into metres, so :func:`read_mesh`
gives a COLLADA file's vertices in m. Its ``<up_axis>`` is ignored, as ROS's viewers (RViz,
Gazebo, MoveIt's geometric_shapes) ignore it: robot description files are drawn that way, and
a ``Y_UP`` file of a robot package would otherwise be turned by 90 degrees.

A file is read once per process while it is unchanged (its path, size and modification time
are the key): a URDF's loader checks its meshes and the scene draws them without reading again.

Examples
--------
>>> import os, tempfile
>>> path = os.path.join(tempfile.mkdtemp(), "tri.obj")
>>> _ = open(path, "w").write("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
>>> vertices, faces = read_mesh(path)
>>> vertices.shape, faces.tolist()
((3, 3), [[0, 1, 2]])
"""
from __future__ import annotations

import io
import os
import struct
import xml.etree.ElementTree as ET
from functools import lru_cache

import numpy as np

__all__ = ["read_mesh", "mesh_color", "clear_cache", "MeshReaderMissing", "cluster"]

#: the install that reads COLLADA files
MESHES_FIX = "pip install mbcomp[meshes] (trimesh and pycollada)"


class MeshReaderMissing(ImportError):
    """A mesh file's format needs an optional package that is not installed (COLLADA: trimesh
    and pycollada); the message names the file and the install.

    Examples
    --------
    >>> issubclass(MeshReaderMissing, ImportError)
    True
    """


def read_mesh(path, component=None):
    """The vertices and triangles of an STL (ASCII or binary), OBJ or COLLADA file.

    Parameters
    ----------
    path : str or os.PathLike
        The file; ``.stl``, ``.obj`` or ``.dae`` (any case).
    component : str, optional
        The component whose shape it is, named in the errors.

    Returns
    -------
    vertices : ndarray (n, 3) float64, read-only
        Coordinates in the file's units (a COLLADA file's in m, by its ``<unit>``).
    faces : ndarray (m, 3) int, read-only
        Indices into ``vertices`` (0-based), counter-clockwise as the file gives them.

    Raises
    ------
    FileNotFoundError
        The file does not exist (naming the path and the component).
    MeshReaderMissing
        A ``.dae`` file without trimesh and pycollada installed (naming the install).
    ValueError
        An unknown suffix, an empty file, or a malformed line (naming the file and the line).

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "tri.stl")
    >>> _ = open(path, "w").write("solid t\\nfacet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\n"
    ...                           "vertex 1 0 0\\nvertex 0 1 0\\nendloop\\nendfacet\\nendsolid t\\n")
    >>> vertices, faces = read_mesh(path)
    >>> vertices.tolist(), faces.tolist()
    ([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]], [[0, 2, 1]])
    """
    path = os.fspath(path)
    where = f"{component}: " if component else ""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{where}mesh file {path!r} not found (from {os.getcwd()!r}) -> give an existing "
                                ".stl, .obj or .dae file, an absolute path or one relative to the working directory")
    st = os.stat(path)
    try:
        return _read(os.path.abspath(path), st.st_size, st.st_mtime_ns)[:2]
    except (ValueError, MeshReaderMissing) as e:  # the cached reader names no component
        raise type(e)(f"{where}{e}") from None


def mesh_color(path):
    """The colour a mesh file gives its largest part, ``"#rrggbb"``, or ``None`` (STL and OBJ
    files: none read). A COLLADA file's materials colour its parts; the colour covering the
    largest area stands for the file (a scene draws a shape in one colour).

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "tri.obj")
    >>> _ = open(path, "w").write("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
    >>> mesh_color(path) is None
    True
    """
    path = os.fspath(path)
    st = os.stat(path)
    return _read(os.path.abspath(path), st.st_size, st.st_mtime_ns)[2]


def clear_cache():
    """Forget every mesh read: the next :func:`read_mesh` reads its file again (a file is
    otherwise read once while its size and modification time stay; a benchmark's cold read).

    Examples
    --------
    >>> clear_cache()
    """
    _read.cache_clear()


@lru_cache(maxsize=256)
def _read(path, size, mtime_ns):
    """The arrays (read-only: the cache hands out the same ones) and the colour of one version of
    a file."""
    ext = os.path.splitext(path)[1].lower()
    name = f"mesh file {path!r}"
    color = None
    if ext == ".dae":
        vertices, faces, color = _collada(path, name)
    else:
        with open(path, "rb") as f:
            data = f.read()
        if ext == ".stl":
            vertices, faces = _binary_stl(data, name) if _is_binary_stl(data) else _ascii_stl(data, name)
        elif ext == ".obj":
            vertices, faces = _obj(data, name)
        else:
            raise ValueError(f"{name}: unknown suffix {ext or '(none)'!r} -> a mesh is an .stl, .obj or .dae file")
    if len(faces) == 0:
        raise ValueError(f"{name} has no triangles (it is empty or holds no facets / f lines) -> export the "
                         "part again as STL or OBJ")
    vertices, faces = np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int64)
    vertices.flags.writeable = faces.flags.writeable = False
    return vertices, faces, color


def _collada(path, name):
    """A COLLADA file's triangles in m: its nodes' transforms applied (trimesh), times its
    ``<unit meter>``; its ``<up_axis>`` ignored (see the module's notes); and its main colour."""
    try:
        import collada  # noqa: F401  (trimesh reads COLLADA through it)
        import trimesh
    except ImportError:
        raise MeshReaderMissing(f"{name}: reading COLLADA (.dae) needs trimesh and pycollada -> "
                                f"{MESHES_FIX}, or convert the file to STL or OBJ") from None
    try:
        scene = trimesh.load(path, force="scene", process=False)
        if not len(scene.geometry):  # pycollada drops a geometry whose material is broken: read it without
            scene = trimesh.load(io.BytesIO(_without_materials(path)), file_type="dae", force="scene", process=False)
        mesh = scene.to_geometry() if len(scene.geometry) else None
    except Exception as e:  # pycollada's and trimesh's many error types: a broken file  # noqa: BLE001
        raise ValueError(f"{name}: not a readable COLLADA file ({type(e).__name__}: {str(e)[:200]}) -> export "
                         "the part again") from None
    if mesh is None or not hasattr(mesh, "faces") or len(mesh.faces) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), None
    return (np.asarray(mesh.vertices, dtype=float) * _collada_unit(path, name), np.asarray(mesh.faces),
            _main_color(scene.geometry.values()))


def _main_color(parts):
    """``"#rrggbb"`` of the material colour covering the largest area of trimesh ``parts``."""
    area = {}
    for g in parts:
        visual = getattr(g, "visual", None)
        material = getattr(visual, "material", None)
        try:
            rgba = material.main_color if material is not None else visual.main_color
            key = "#" + "".join(f"{int(c):02x}" for c in np.asarray(rgba)[:3])
        except (AttributeError, TypeError, ValueError):
            continue
        area[key] = area.get(key, 0.0) + float(g.area)
    return max(area, key=area.get) if area else None


def _without_materials(path):
    """A COLLADA file's text without its ``<bind_material>`` elements (the triangles stay): an
    effect that names a missing texture (ANYmal's foot) otherwise drops its geometry."""
    root = ET.parse(path).getroot()
    for parent in root.iter():
        for child in [c for c in parent if c.tag.rsplit("}", 1)[-1] == "bind_material"]:
            parent.remove(child)
    return ET.tostring(root)


def _collada_unit(path, name):
    """Metres per unit of a COLLADA file: ``<asset><unit meter="...">``, 1 when absent."""
    try:
        for _, el in ET.iterparse(path, events=("end",)):
            tag = el.tag.rsplit("}", 1)[-1]
            if tag == "unit":
                unit = float(el.get("meter", "1"))
                if not (np.isfinite(unit) and unit > 0):
                    raise ValueError(f"{name}: <unit meter={el.get('meter')!r}> is no positive length")
                return unit
            if tag == "asset":  # the asset (first in the file) is over: no unit given
                return 1.0
    except ET.ParseError as e:
        raise ValueError(f"{name}: not a readable COLLADA file (XML: {e})") from None
    return 1.0


def cluster(vertices, faces, cell):
    """A coarser mesh by vertex clustering: the vertices in each cube of edge ``cell`` (m)
    merged into their mean, the triangles that collapse (two corners in one cube) and repeats
    dropped. Details below ``cell`` go; the shape at the scale of ``cell`` stays (every kept
    vertex moves less than ``cell * sqrt(3)``). Pictures use it with ``cell`` about a pixel.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    cell : float
        Edge of the clustering cubes, in the units of ``vertices``; ``cell <= 0`` keeps the mesh.

    Returns
    -------
    vertices : (k, 3) float
    faces : (l, 3) int
        Each kept triangle turned as it was.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.001, 0.001, 0]])
    >>> f = np.array([[0, 1, 2], [3, 1, 2], [0, 1, 3]])
    >>> cv, cf = cluster(v, f, 0.01); len(cv), len(cf)    # vertex 3 merges into vertex 0
    (3, 1)
    """
    vertices, faces = np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)
    if cell <= 0 or len(faces) == 0:
        return vertices, faces
    keys = np.floor((vertices - vertices.min(axis=0)) / cell).astype(np.int64)
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    counts = np.bincount(inverse)
    merged = np.zeros((len(counts), 3))
    np.add.at(merged, inverse, vertices)
    merged /= counts[:, None]
    f = inverse[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])]
    if len(f):
        _, first = np.unique(np.sort(f, axis=1), axis=0, return_index=True)
        f = f[np.sort(first)]
    used = np.unique(f)
    renumber = np.full(len(merged), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    return merged[used], renumber[f]


def _is_binary_stl(data):
    """A binary STL is an 80-byte header, a triangle count and 50 bytes per triangle."""
    if len(data) < 84:
        return False
    n = struct.unpack("<I", data[80:84])[0]
    return len(data) == 84 + 50 * n


def _binary_stl(data, name):
    n = struct.unpack("<I", data[80:84])[0]
    rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                        count=n, offset=84)
    corners = rec["v"].astype(np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(corners)):
        bad = int(np.argmax(~np.all(np.isfinite(corners), axis=1))) // 3
        raise ValueError(f"{name}: triangle {bad + 1} of the binary STL has a coordinate that is not finite")
    return _merge(corners)


def _merge(corners):
    """Vertices with equal coordinates merged; triangles of three consecutive corners."""
    if len(corners) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=int)
    vertices, inverse = np.unique(corners, axis=0, return_inverse=True)
    return vertices, inverse.reshape(-1, 3).astype(int)


def _text_lines(data, name):
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return text.splitlines()


def _ascii_stl(data, name):
    lines = _text_lines(data, name)
    first = next((ln.split() for ln in lines if ln.strip()), [])
    if not first or first[0].lower() != "solid":
        if not first:
            raise ValueError(f"{name} is empty -> export the part again as STL or OBJ")
        raise ValueError(f"{name}: line 1 starts with {first[0][:20]!r}, neither an ASCII STL ('solid') nor a binary "
                         "STL (its size does not match its triangle count) -> export the part again")
    corners, loop = [], None
    for no, line in enumerate(lines, 1):
        words = line.split()
        if not words:
            continue
        key = words[0].lower()
        if key == "vertex":
            if loop is None:
                raise ValueError(f"{name}, line {no}: a vertex outside 'outer loop' ... 'endloop': {line.strip()!r}")
            loop.append(_floats(words[1:], 3, name, no, line))
        elif key == "outer":
            loop = []
        elif key == "endloop":
            if loop is None or len(loop) != 3:
                raise ValueError(f"{name}, line {no}: a facet has {0 if loop is None else len(loop)} vertices, "
                                 "not 3 -> an STL holds triangles only")
            corners.extend(loop)
            loop = None
        elif key not in ("solid", "endsolid", "facet", "endfacet"):
            raise ValueError(f"{name}, line {no}: unknown keyword {words[0][:20]!r} in an ASCII STL: {line.strip()!r}")
    if loop is not None:
        raise ValueError(f"{name}: the file ends inside a facet (an 'outer loop' with no 'endloop') -> it is cut "
                         "short; export it again")
    return _merge(np.array(corners, dtype=float).reshape(-1, 3))


def _floats(words, n, name, no, line):
    """The first ``n`` numbers of a line, or an error naming the line."""
    try:
        values = [float(w) for w in words[:n]]
    except ValueError:
        values = []
    if len(values) != n or not all(np.isfinite(values)):
        raise ValueError(f"{name}, line {no}: expected {n} numbers, got {line.strip()!r}")
    return values


def _obj(data, name):
    vertices, faces = [], []
    for no, line in enumerate(_text_lines(data, name), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        if words[0] == "v":
            vertices.append(_floats(words[1:], 3, name, no, line))
        elif words[0] == "f":
            idx = [_obj_index(w, len(vertices), name, no, line) for w in words[1:]]
            if len(idx) < 3:
                raise ValueError(f"{name}, line {no}: a face needs at least 3 vertices, got {line.strip()!r}")
            faces.extend([idx[0], idx[i], idx[i + 1]] for i in range(1, len(idx) - 1))
        # other statements (vt, vn, g, o, s, usemtl, mtllib, l, ...) carry nothing to draw
    return np.array(vertices, dtype=float).reshape(-1, 3), np.array(faces, dtype=int).reshape(-1, 3)


def _obj_index(word, n, name, no, line):
    """A face corner ``i``, ``i/t``, ``i//n`` or ``i/t/n`` as a 0-based vertex index; negative
    ``i`` counts back from the last vertex defined so far."""
    try:
        i = int(word.split("/")[0])
    except ValueError:
        raise ValueError(f"{name}, line {no}: {word!r} is no vertex index in {line.strip()!r}") from None
    k = i - 1 if i > 0 else n + i
    if i == 0 or not 0 <= k < n:
        raise ValueError(f"{name}, line {no}: vertex index {i} is out of range (the file has defined {n} vertices "
                         f"so far) in {line.strip()!r}")
    return k
