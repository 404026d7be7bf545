"""Triangle meshes from files: ASCII STL, binary STL and Wavefront OBJ.

:func:`read_mesh` returns the vertices (in the file's units) and the triangles of a file; the
scene scales them by the :class:`~mbcomp.modeling.shapes.Mesh`'s ``scale``. STL repeats a
vertex in every triangle that uses it, so its vertices are merged when their coordinates are
equal; an OBJ's vertices are kept as listed. Polygons of an OBJ are fanned into triangles
(``f 1 2 3 4`` -> ``1 2 3``, ``1 3 4``).

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

import os
import struct

import numpy as np

__all__ = ["read_mesh"]


def read_mesh(path, component=None):
    """The vertices and triangles of an STL (ASCII or binary) or OBJ file.

    Parameters
    ----------
    path : str or os.PathLike
        The file; ``.stl`` or ``.obj`` (any case).
    component : str, optional
        The component whose shape it is, named in the errors.

    Returns
    -------
    vertices : ndarray (n, 3) float64
        Coordinates in the file's units.
    faces : ndarray (m, 3) int
        Indices into ``vertices`` (0-based), counter-clockwise as the file gives them.

    Raises
    ------
    FileNotFoundError
        The file does not exist (naming the path and the component).
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
                                ".stl or .obj file, an absolute path or one relative to the working directory")
    ext = os.path.splitext(path)[1].lower()
    with open(path, "rb") as f:
        data = f.read()
    name = f"{where}mesh file {path!r}"
    if ext == ".stl":
        vertices, faces = _binary_stl(data, name) if _is_binary_stl(data) else _ascii_stl(data, name)
    elif ext == ".obj":
        vertices, faces = _obj(data, name)
    else:
        raise ValueError(f"{name}: unknown suffix {ext or '(none)'!r} -> a mesh is an .stl or .obj file")
    if len(faces) == 0:
        raise ValueError(f"{name} has no triangles (it is empty or holds no facets / f lines) -> export the "
                         "part again as STL or OBJ")
    return vertices, faces


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
