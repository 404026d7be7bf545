"""A URDF link's ``<visual>`` elements as shapes: how an imported robot looks.

:func:`link_visuals` reads every link's ``<visual>`` elements (a link may have several) into
shapes of :mod:`mbcomp.modeling.shapes` placed in the link's frame (``r``, ``R`` from the
visual's ``<origin xyz rpy>``):

- ``<box size>`` -> :class:`~mbcomp.modeling.shapes.Box`, ``<cylinder radius length>`` ->
  :class:`~mbcomp.modeling.shapes.Cylinder` (along the visual's z axis, centred, as URDF's),
  ``<sphere radius>`` -> :class:`~mbcomp.modeling.shapes.Sphere`, ``<mesh filename scale>`` ->
  :class:`~mbcomp.modeling.shapes.Mesh` (one scale factor per axis; STL, OBJ and, with
  ``pip install mbcomp[meshes]``, COLLADA, drawn in the colour of its largest part unless the
  visual gives a material);
- ``<material>``: its ``<color rgba>`` (given in the visual, or by name from a material defined
  at the robot's top level or earlier in the file) is the shape's colour and opacity.

Mesh file names are resolved as ROS tools do: ``package://pkg/rest`` in the ``package_dirs``
the caller gives (each either the package's directory, named ``pkg``, or a directory holding
it), in ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH`` (``share/pkg``), then upwards from the
URDF file's directory (an ancestor named ``pkg``, or holding a directory ``pkg``);
``file://`` and plain names absolute or relative to the URDF's directory. Each mesh is read at
load (once per file: the scene reuses it), so that a mesh that cannot be found or read is a
note in ``model.urdf_notes`` -- never an error: visuals do not change the motion. A link whose
visuals all fail keeps the library's default look of its body.

Where the shapes hang (:func:`mbcomp.io.urdf.load_urdf`): a link with mass is a ``RigidBody``
whose ``frame_a`` is the link frame, so its shapes are its ``shape=``. A massless link has no
body; its frame is a port of the component that carries it (the joint, the joint's origin
offset, the world). A shape can ride on any component's frame port, but giving that component
``shape=`` would replace its own look and mix the link into the joint; a body of zero mass
would enter the dynamics. So the link gets a *marker*: a ``FixedTranslation`` of length 0 named
as the link, on its frame, carrying its shapes -- no coordinate, no mass, no constraint.
The joints' and offsets' own glyphs are hidden when the file has visuals (:func:`hide_glyphs`).

Examples
--------
>>> import xml.etree.ElementTree as ET
>>> robot = ET.fromstring('''<robot name="r"><material name="blue"><color rgba="0 0 1 1"/></material>
... <link name="arm"><visual><origin xyz="0 0 0.5"/><geometry><box size="0.1 0.1 1"/></geometry>
... <material name="blue"/></visual></link></robot>''')
>>> [(type(s).__name__, s.r, s.color) for s in link_visuals(robot, "robot.urdf", notes=[])["arm"]]
[('Box', (0.0, 0.0, 0.5), '#0000ff')]
"""
from __future__ import annotations

import os

import numpy as np

from ..geometry.rotations import euler_to_matrix
from ..modeling.shapes import Box, Cylinder, Mesh, Sphere, rgb
from ..visual.meshes import MeshReaderMissing, mesh_color, read_mesh

__all__ = ["link_visuals", "resolve_mesh", "materials", "hide_glyphs"]


def _numbers(el, attr, n, default=None):
    text = el.get(attr) if el is not None else None
    if text is None:
        if default is None:
            raise ValueError(f"<{el.tag if el is not None else '?'}> has no {attr}=")
        return default
    v = [float(x) for x in text.split()]  # ValueError on "${...}" (an unexpanded xacro)
    if len(v) != n:
        raise ValueError(f"{attr}={text!r} must hold {n} number{'s' if n > 1 else ''}")
    return v


def _rgba(material):
    """``(colour "#rrggbb", opacity)`` of a ``<material>`` element's ``<color rgba>``, or None."""
    color = material.find("color") if material is not None else None
    if color is None or color.get("rgba") is None:
        return None
    r, g, b, a = np.clip(_numbers(color, "rgba", 4), 0.0, 1.0)
    return rgb((r, g, b)), float(a)


def materials(robot):
    """``{name: (colour, opacity)}`` of the named materials with a colour: the robot's
    top-level ones, then those first defined inside a visual (URDF lets later visuals use them).

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> materials(ET.fromstring('<robot><material name="m"><color rgba="1 0 0 0.5"/></material></robot>'))
    {'m': ('#ff0000', 0.5)}
    """
    out = {}
    for el in [*robot.findall("material"), *robot.iter("material")]:
        name = el.get("name")
        if name and name not in out:
            try:
                looks = _rgba(el)
            except ValueError:
                looks = None
            if looks is not None:
                out[name] = looks
    return out


def _package_roots(pkg, urdf_dir, package_dirs):
    """The directories that may be the package ``pkg``, in the order they are tried."""
    env = [d for var in ("ROS_PACKAGE_PATH",) for d in os.environ.get(var, "").split(os.pathsep) if d]
    ament = [os.path.join(d, "share") for d in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if d]
    up, d = [], os.path.abspath(urdf_dir)
    while True:
        up.append(d)
        parent = os.path.dirname(d)
        if parent == d:
            break
        d = parent
    for base in [*map(os.fspath, package_dirs), *env, *ament, *up]:
        if os.path.basename(os.path.normpath(base)) == pkg:
            yield base
        yield os.path.join(base, pkg)


def resolve_mesh(filename, urdf_dir, package_dirs=()):
    """The file a URDF ``<mesh filename>`` names, or ``None`` when it is not found.

    Parameters
    ----------
    filename : str
        ``package://pkg/path``, ``model://pkg/path`` (Gazebo's), ``file://path`` or a path
        (absolute, or relative to ``urdf_dir``).
    urdf_dir : str
        The directory of the URDF file.
    package_dirs : iterable of str
        Where to look for packages first: each the package's own directory or one holding it
        (as Pinocchio's ``package_dirs``).

    Examples
    --------
    >>> import os, tempfile
    >>> top = tempfile.mkdtemp(); os.makedirs(os.path.join(top, "arm_pkg", "meshes"))
    >>> _ = open(os.path.join(top, "arm_pkg", "meshes", "base.stl"), "w").write("solid\\n")
    >>> os.makedirs(os.path.join(top, "arm_pkg", "urdf"))
    >>> found = resolve_mesh("package://arm_pkg/meshes/base.stl", os.path.join(top, "arm_pkg", "urdf"))
    >>> os.path.relpath(found, top)
    'arm_pkg/meshes/base.stl'
    """
    for scheme in ("package://", "model://"):
        if filename.startswith(scheme):
            pkg, _, rest = filename[len(scheme):].lstrip("/").partition("/")
            for root in _package_roots(pkg, urdf_dir, package_dirs):
                candidate = os.path.abspath(os.path.join(root, rest))
                if os.path.isfile(candidate):
                    return candidate
            return None
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    candidate = os.path.abspath(os.path.join(urdf_dir, filename))  # an absolute filename stays itself
    return candidate if os.path.isfile(candidate) else None


class _Reader:
    """Meshes of one URDF: found, read once, and what failed (for the notes)."""

    def __init__(self, urdf_dir, package_dirs, notes):
        self.urdf_dir, self.package_dirs, self.notes = urdf_dir, tuple(package_dirs), notes
        self.no_reader = []  # links whose COLLADA meshes need the optional packages

    def mesh(self, el, link, placement):
        filename = el.get("filename")
        if not filename:
            raise ValueError("<mesh> has no filename=")
        path = resolve_mesh(filename, self.urdf_dir, self.package_dirs)
        if path is None:
            self.notes.append(f"link {link!r}: mesh {filename!r} not found (looked in the package_dirs given, "
                              "ROS_PACKAGE_PATH and upwards from the URDF's directory): not drawn -> pass "
                              "package_dirs=[...] to load_urdf")
            return None
        scale = _numbers(el, "scale", 3, (1.0, 1.0, 1.0))
        try:
            shape = Mesh(path, scale=scale, **placement)
            read_mesh(path)
            if "color" not in placement and mesh_color(path) is not None:  # the file's own colour
                shape = shape.placed(color=mesh_color(path))
        except MeshReaderMissing:
            self.no_reader.append(link)
            return None
        except (OSError, ValueError) as e:
            self.notes.append(f"link {link!r}: mesh {filename!r} cannot be read ({e}): not drawn")
            return None
        return shape

    def close(self):
        if self.no_reader:
            links = sorted(set(self.no_reader))
            self.notes.append(f"{len(self.no_reader)} COLLADA (.dae) meshes of links {links[:6]}"
                              + (" ..." if len(links) > 6 else "")
                              + " not drawn: reading them needs trimesh and pycollada -> pip install mbcomp[meshes]")


def _visual(vis, link, named, reader, notes):
    """The shape of one ``<visual>`` element, or None (noted) when it cannot be drawn."""
    origin = vis.find("origin")
    xyz = _numbers(origin, "xyz", 3, (0.0, 0.0, 0.0))
    roll, pitch, yaw = _numbers(origin, "rpy", 3, (0.0, 0.0, 0.0))
    placement = {"r": xyz, "R": euler_to_matrix("321", (yaw, pitch, roll))}
    material = vis.find("material")
    looks = _rgba(material)
    if looks is None and material is not None and material.get("name"):
        looks = named.get(material.get("name"))
        if looks is None:
            notes.append(f"link {link!r}: material {material.get('name')!r} has no colour in the file: "
                         "drawn in the scene's colours")
    if looks is not None:
        placement.update(color=looks[0], opacity=looks[1])
    geometry = vis.find("geometry")
    el = next(iter(geometry), None) if geometry is not None else None
    if el is None:
        raise ValueError("<visual> has no <geometry>")
    if el.tag == "box":
        return Box(_numbers(el, "size", 3), **placement)
    if el.tag == "cylinder":
        return Cylinder(_numbers(el, "radius", 1)[0], _numbers(el, "length", 1)[0], **placement)
    if el.tag == "sphere":
        return Sphere(_numbers(el, "radius", 1)[0], **placement)
    if el.tag == "mesh":
        return reader.mesh(el, link, placement)
    raise ValueError(f"<{el.tag}> is no URDF geometry (box, cylinder, sphere, mesh)")


def link_visuals(robot, path, package_dirs=(), notes=None):
    """``{link name: tuple of shapes in the link's frame}`` of a parsed URDF.

    Parameters
    ----------
    robot : xml.etree.ElementTree.Element
        The ``<robot>`` element.
    path : str
        The URDF file (its directory anchors relative and ``package://`` mesh names).
    package_dirs : iterable of str
        Where packages are searched first (:func:`resolve_mesh`).
    notes : list of str, optional
        Appended with what is not drawn (a mesh not found or not readable, a bad element).

    Returns
    -------
    dict
        Empty when the file has no ``<visual>`` at all (its links keep the library's default
        looks); else every link: its shapes (an empty tuple: nothing drawn), or ``None`` when
        it has visuals but none could be drawn (the default look stands in).
    """
    notes = [] if notes is None else notes
    if robot.find("link/visual") is None:
        return {}
    named = materials(robot)
    reader = _Reader(os.path.dirname(os.path.abspath(os.fspath(path))), package_dirs, notes)
    out = {}
    for link in robot.findall("link"):
        name, shapes, tried = link.get("name"), [], 0
        for vis in link.findall("visual"):
            tried += 1
            try:
                shape = _visual(vis, name, named, reader, notes)
            except ValueError as e:
                notes.append(f"link {name!r}: a <visual> not drawn ({e})")
                shape = None
            if shape is not None:
                shapes.append(shape)
        out[name] = tuple(shapes) if shapes or not tried else None
    reader.close()
    return out


def hide_glyphs(model):
    """Hide the joints', offsets' and dampers' default glyphs of a robot drawn by its visuals
    (hinge cylinders, rods between joints, inside the meshes or sticking out of them): every
    component of ``model`` on its default look but the bodies and the ground. Components given
    shapes (a massless link's marker) stay.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1)))
    >>> hide_glyphs(m); w.look.visible, j.look.visible
    (True, False)
    """
    for comp in model.components().values():
        if comp.role not in ("body", "ground") and comp.look.shape is None:
            comp.look.visible = False
