"""MJCF files read as MuJoCo's compiler reads them: includes, ``<compiler>``, default classes, orientations.

What :func:`mbcomp.load_mjcf` builds on (no mujoco needed):

- :func:`read_tree`: the ``<mujoco>`` root with every ``<include file>`` replaced by the
  children of the included file's root (the path relative to the including file, else to
  the main file's directory, as MuJoCo resolves it);
- :class:`Compiler`: the ``<compiler>`` settings that change the numbers (``angle``,
  ``eulerseq``, ``inertiafromgeom``, ``inertiagrouprange``, ``settotalmass``, ``boundmass``,
  ``boundinertia``, ``autolimits``, ``meshdir``/``assetdir``);
- :class:`Defaults`: the default classes (``main`` at the top, nested ``<default class>``
  inheriting from their parent), giving an element's attributes with its class's defaults
  under them (``class=``, else the nearest ancestor body's ``childclass``, else ``main``);
- :func:`orientation`: a frame's rotation from ``quat`` (w x y z), ``axisangle``, ``euler``
  (``eulerseq``: lowercase axes rotate with the frame, uppercase stay fixed), ``xyaxes`` or
  ``zaxis`` (the shortest rotation taking z there), in the compiler's angle unit.
"""
import os
import xml.etree.ElementTree as ET

import numpy as np

from ..geometry.kinematics import quat_to_matrix, rot_axis

__all__ = ["Compiler", "Defaults", "read_tree", "orientation", "numbers", "z_to_vector"]


def numbers(text, n=None, what="attribute"):
    """The floats of an MJCF attribute's text (``n`` of them when given, else any count)."""
    try:
        v = np.array([float(x) for x in str(text).split()], dtype=float)
    except ValueError:
        raise ValueError(f"MJCF {what}={text!r}: not numbers -> fix the file") from None
    if n is not None and v.size != n:
        raise ValueError(f"MJCF {what}={text!r}: {n} numbers expected, {v.size} given -> fix the file")
    return v


def read_tree(path):
    """The ``<mujoco>`` root element of ``path`` with its includes spliced in (recursively).

    Raises ``ValueError`` when the root is not ``<mujoco>`` or an included file is missing.
    """
    path = os.path.abspath(os.fspath(path))
    root = _parse(path)
    _splice(root, os.path.dirname(path), os.path.dirname(path), [path])
    return root


def _parse(path):
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise ValueError(f"{path}: not XML ({e}) -> is it an MJCF file?") from None
    if root.tag != "mujoco":
        raise ValueError(f"{path}: the root element is <{root.tag}>, not <mujoco> -> is it an MJCF (MuJoCo) file?")
    return root


def _splice(el, here, main_dir, chain):
    for i, child in reversed(list(enumerate(el))):
        if child.tag != "include":
            _splice(child, here, main_dir, chain)
            continue
        name = child.get("file")
        if not name:
            raise ValueError(f"{chain[-1]}: <include> without file= -> fix the file")
        found = [p for p in (os.path.join(here, name), os.path.join(main_dir, name)) if os.path.isfile(p)]
        if not found:
            raise ValueError(f"{chain[-1]}: <include file={name!r}>: no such file (looked in {here!r} and "
                             f"{main_dir!r}) -> fix the path or copy the file there")
        inc = os.path.abspath(found[0])
        if inc in chain:
            raise ValueError(f"{chain[-1]}: <include file={name!r}> includes itself (through {chain})")
        sub = _parse(inc)
        _splice(sub, os.path.dirname(inc), main_dir, chain + [inc])
        el.remove(child)
        for k, grand in enumerate(list(sub)):
            el.insert(i + k, grand)


class Compiler:
    """The ``<compiler>`` settings of an MJCF root (MuJoCo's defaults where not given).

    Attributes
    ----------
    degrees : bool
        ``angle="degree"`` (MuJoCo's default): angles in the file are in degrees.
    eulerseq : str
        Three of ``xyzXYZ`` (default ``"xyz"``).
    inertiafromgeom : str
        ``"auto"`` (geoms where a body has no ``<inertial>``), ``"true"`` or ``"false"``.
    groups : (int, int)
        ``inertiagrouprange``: geoms of these groups carry mass (default 0..5).

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> from mbcomp.io.mjcf_frames import Compiler
    >>> c = Compiler(ET.fromstring('<mujoco><compiler angle="radian" eulerseq="XYZ"/></mujoco>'), ".")
    >>> c.degrees, c.eulerseq, c.angle(1.5)
    (False, 'XYZ', 1.5)
    """

    def __init__(self, root, base_dir):
        a = {}
        for el in root.findall("compiler"):
            a.update(el.attrib)
        self.attrib = a
        unit = a.get("angle", "degree")
        if unit not in ("degree", "radian"):
            raise ValueError(f"MJCF <compiler angle={unit!r}>: must be 'degree' or 'radian'")
        self.degrees = unit == "degree"
        self.eulerseq = a.get("eulerseq", "xyz")
        if len(self.eulerseq) != 3 or set(self.eulerseq) - set("xyzXYZ"):
            raise ValueError(f"MJCF <compiler eulerseq={self.eulerseq!r}>: three of x, y, z, X, Y, Z expected")
        if a.get("coordinate", "local") != "local":
            raise ValueError("MJCF <compiler coordinate='global'>: global coordinates are not read (MuJoCo >= 2.3 "
                             "refuses them too) -> convert the file to local coordinates")
        self.inertiafromgeom = a.get("inertiafromgeom", "auto")
        g = numbers(a.get("inertiagrouprange", "0 5"), 2, "inertiagrouprange")
        self.groups = (int(g[0]), int(g[1]))
        self.settotalmass = float(a.get("settotalmass", -1.0))
        self.boundmass = float(a.get("boundmass", 0.0))
        self.boundinertia = float(a.get("boundinertia", 0.0))
        self.autolimits = a.get("autolimits", "true") == "true"
        asset = a.get("assetdir", "")
        self.meshdir = os.path.join(base_dir, a.get("meshdir", asset))

    def angle(self, value):
        """``value`` (the file's angle unit) in rad."""
        return np.deg2rad(value) if self.degrees else value


class Defaults:
    """MJCF default classes: ``{class: {tag: attributes}}``, nested classes inheriting.

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> from mbcomp.io.mjcf_frames import Defaults
    >>> root = ET.fromstring('<mujoco><default><joint damping="1"/><default class="leg">'
    ...                      '<joint stiffness="5"/></default></default></mujoco>')
    >>> d = Defaults(root)
    >>> d.attributes(ET.fromstring('<joint class="leg" damping="2"/>'), "main")
    {'damping': '2', 'stiffness': '5'}
    """

    def __init__(self, root):
        self.classes = {"main": {}}
        for top in root.findall("default"):
            name = top.get("class", "main")
            self._read(top, name, self.classes["main"])

    def _read(self, el, name, inherited):
        own = {tag: dict(attrs) for tag, attrs in inherited.items()}
        for child in el:
            if child.tag == "default":
                continue
            own.setdefault(child.tag, {}).update(child.attrib)
        self.classes[name] = own
        for child in el.findall("default"):
            cname = child.get("class")
            if cname is None:
                raise ValueError(f"MJCF: a nested <default> inside class {name!r} has no class= -> name it")
            self._read(child, cname, own)

    def attributes(self, el, childclass):
        """The attributes of element ``el`` with its class's defaults under them (``<freejoint>``
        takes none, as in MuJoCo)."""
        if el.tag == "freejoint":
            return dict(el.attrib)
        cls = el.get("class", childclass)
        if cls not in self.classes:
            raise ValueError(f"MJCF <{el.tag} name={el.get('name')!r}>: class {cls!r} is not defined by any "
                             f"<default class> (defined: {sorted(self.classes)}) -> fix the class name")
        out = dict(self.classes[cls].get(el.tag, {}))
        out.update({k: v for k, v in el.attrib.items() if k != "class"})
        return out


def _quat_matrix(q):
    n = np.linalg.norm(q)
    if n == 0.0:
        raise ValueError("MJCF quat='0 0 0 0': a zero quaternion -> give a unit one (w x y z)")
    return quat_to_matrix(q / n)


def z_to_vector(v):
    """The rotation taking the z axis to the direction ``v`` along the shortest arc (MuJoCo's
    frame of a ``zaxis`` or ``fromto``); a half turn about x when ``v`` points along -z."""
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if n == 0.0:
        raise ValueError("MJCF: a zero direction (zaxis or fromto of zero length) -> fix the file")
    v = v / n
    axis = np.cross((0.0, 0.0, 1.0), v)
    s = np.linalg.norm(axis)
    if s < 1e-10:
        return np.eye(3) if v[2] > 0 else rot_axis((1.0, 0.0, 0.0), np.pi)
    return rot_axis(axis / s, np.arctan2(s, v[2]))


def _euler(angles, seq):
    R = np.eye(3)
    for a, ax in zip(angles, seq):
        Ri = rot_axis(np.eye(3)["xyz".index(ax.lower())], a)
        R = R @ Ri if ax.islower() else Ri @ R  # lowercase: axes moved by the rotations before
    return R


def orientation(attrs, compiler, what):
    """The rotation (child axes -> parent axes) given by ``attrs`` (one of ``quat``,
    ``axisangle``, ``euler``, ``xyaxes``, ``zaxis``; identity when none), angles in the
    compiler's unit.

    Examples
    --------
    >>> import numpy as np, xml.etree.ElementTree as ET
    >>> from mbcomp.io.mjcf_frames import Compiler, orientation
    >>> c = Compiler(ET.fromstring("<mujoco/>"), ".")          # degrees, eulerseq xyz
    >>> np.round(orientation({"euler": "0 0 90"}, c, "body") @ [1, 0, 0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    given = [k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in attrs]
    if len(given) > 1:
        raise ValueError(f"MJCF {what}: orientation given twice ({', '.join(given)}) -> keep one")
    if not given:
        return np.eye(3)
    k = given[0]
    if k == "quat":
        return _quat_matrix(numbers(attrs[k], 4, f"{what} quat"))
    if k == "axisangle":
        v = numbers(attrs[k], 4, f"{what} axisangle")
        if not np.linalg.norm(v[:3]):
            raise ValueError(f"MJCF {what}: axisangle with a zero axis -> fix the file")
        return rot_axis(v[:3] / np.linalg.norm(v[:3]), compiler.angle(v[3]))
    if k == "euler":
        return _euler(compiler.angle(numbers(attrs[k], 3, f"{what} euler")), compiler.eulerseq)
    if k == "zaxis":
        return z_to_vector(numbers(attrs[k], 3, f"{what} zaxis"))
    v = numbers(attrs[k], 6, f"{what} xyaxes")
    x = v[:3] / np.linalg.norm(v[:3])
    y = v[3:] - (v[3:] @ x) * x
    if not np.linalg.norm(y):
        raise ValueError(f"MJCF {what}: xyaxes with parallel axes -> fix the file")
    y = y / np.linalg.norm(y)
    return np.column_stack((x, y, np.cross(x, y)))
