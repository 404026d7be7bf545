"""URDF import: ``load_urdf(path) -> Model`` of library bodies, joints and rigid offsets.

What it maps (URDF frames: every link has a frame; a joint's ``<origin>`` places the joint
frame in the parent link's frame; the child link's frame is the joint frame moved by the
joint's coordinate):

- ``<link>`` with ``<inertial>``: a ``RigidBody`` on the link frame, mass ``m`` (kg), centre of
  mass from ``<origin xyz>`` (m, link frame) and inertia (kg m^2) given about the centre of mass
  in the inertial frame ``<origin rpy>``, rotated into link axes ``I = R I' R^T``. A link
  without mass gets no body: its frame is the frame of the joint that carries it.
- ``<joint>``: its ``<origin>`` as a ``FixedTranslation`` (``FixedRotation`` when rotated) named
  ``<joint>_origin``, then ``revolute``/``continuous`` -> ``Revolute(n=axis)``, ``prismatic``
  -> ``Prismatic(n=axis)``, ``fixed`` -> the offset alone (named as the joint), ``floating``
  -> ``FreeMotion``, ``planar`` -> ``Planar(n=axis)`` (``s_x`` along the in-plane part of the
  joint frame's x axis, else of its y axis). ``<axis>`` defaults to ``1 0 0``. Joint names are kept as component
  names (``res["shoulder_pan_joint.phi"]``); a name that is no Python identifier is
  sanitized (the change is listed in ``model.urdf_notes``).
- a moving joint with no mass beyond it (a sensor frame on a hinge): held at 0 as a fixed
  joint (noted), since its motion would be undetermined.
- ``<limit lower upper>``: the joint's stops (``limits``) only with ``limits=True``; a joint
  whose zero position lies outside them starts at their middle (noted).
- ``<dynamics damping>``: a ``RotationalDamper`` (revolute, continuous) or a
  ``TranslationalSpringDamper`` with ``c = 0`` (prismatic) on the joint's flanges with
  ``damping=True`` (default); ``friction`` and ``<mimic>`` are not imported (listed).
- gravity: ``World(g=gravity)``, ``(0, 0, -9.81)`` m/s^2 by default (URDF carries none).
- ``<visual>``: the link's shapes (:mod:`mbcomp.io.urdf_visuals`), with ``visuals=True``.

Whatever is not imported is listed, element by element, in ``model.urdf_notes`` (a list of
strings) and summed up in one ``UserWarning``.
"""
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from ..geometry.rotations import euler_to_matrix
from .urdf_visuals import hide_glyphs, link_visuals
from .names import ComponentNames as _Names

__all__ = ["load_urdf", "rpy_matrix"]


def rpy_matrix(rpy):
    """The rotation matrix of URDF's roll-pitch-yaw angles: ``Rz(yaw) Ry(pitch) Rx(roll)``, the
    yaw-pitch-roll sequence ``"321"`` of :func:`mbcomp.geometry.rotations.euler_to_matrix`.

    Parameters
    ----------
    rpy : (3,) rad
        Roll, pitch, yaw about the fixed x, y, z axes, in that order.

    Returns
    -------
    (3, 3) ndarray
        Child axes -> parent axes.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.io.urdf import rpy_matrix
    >>> np.round(rpy_matrix((0, 0, np.pi / 2)) @ [1, 0, 0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    r, p, y = (float(a) for a in rpy)
    return euler_to_matrix("321", (y, p, r))


def _vec(el, attr, default):
    if el is None or el.get(attr) is None:
        return np.array(default, dtype=float)
    v = np.array([float(x) for x in el.get(attr).split()], dtype=float)
    if v.shape != (3,):
        raise ValueError(f"URDF: {attr}={el.get(attr)!r} must hold three numbers")
    return v


def _origin(el):
    o = None if el is None else el.find("origin")
    return _vec(o, "xyz", (0, 0, 0)), rpy_matrix(_vec(o, "rpy", (0, 0, 0)))


def _inertial(link):
    """``(m, r_cm, I)`` of a link (link frame), or None when it carries no mass."""
    inertial = link.find("inertial")
    if inertial is None:
        return None
    mass = inertial.find("mass")
    m = float(mass.get("value")) if mass is not None else 0.0
    r_cm, R = _origin(inertial)
    i = inertial.find("inertia")
    get = (lambda k: float(i.get(k, 0.0))) if i is not None else (lambda k: 0.0)
    Ii = np.array([[get("ixx"), get("ixy"), get("ixz")],
                   [get("ixy"), get("iyy"), get("iyz")],
                   [get("ixz"), get("iyz"), get("izz")]])
    if m == 0.0 and not Ii.any():
        return None
    return m, r_cm, R @ Ii @ R.T


def _joint_component(lib, kind, axis, jel, limits, name, notes):
    lim = jel.find("limit")
    stops = None
    if limits and kind in ("revolute", "prismatic") and lim is not None \
            and lim.get("lower") is not None and lim.get("upper") is not None:
        lo, hi = float(lim.get("lower")), float(lim.get("upper"))
        if lo < hi:
            stops = (lo, hi)
    start = {}
    if stops and not stops[0] <= 0.0 <= stops[1]:  # the file's zero position is outside its limits
        start = {"phi0" if kind == "revolute" else "s0": 0.5 * (stops[0] + stops[1])}
        notes.append(f"joint {name!r}: starts at the middle of its limits {stops} (0 is outside them)")
    if kind in ("revolute", "continuous"):
        return lib.Revolute(n=axis, limits=stops, **start) if stops else lib.Revolute(n=axis)
    if kind == "prismatic":
        return lib.Prismatic(n=axis, limits=stops, **start) if stops else lib.Prismatic(n=axis)
    if kind == "floating":
        return lib.FreeMotion()
    if kind == "planar":  # <axis> is the plane's normal; s_x along the in-plane part of x (else of y)
        n = axis / np.linalg.norm(axis)
        e = np.eye(3)[0] if abs(n[0]) < 0.9 else np.eye(3)[1]
        return lib.Planar(n=axis, n_x=e - (e @ n) * n)
    raise ValueError(f"URDF joint {name!r}: type {kind!r} is not one of revolute, continuous, prismatic, "
                     f"fixed, floating, planar -> fix the file")


def _note_dynamics(jel, jname, kind, damping, notes):
    """The joint's damping coefficient to model (0 when none), with notes on what is left out."""
    dyn = jel.find("dynamics")
    d = 0.0
    if dyn is not None:
        d = float(dyn.get("damping", 0.0))
        if float(dyn.get("friction", 0.0)) != 0.0:
            notes.append(f"joint {jname!r}: <dynamics friction> not imported")
        if d != 0.0 and (not damping or kind not in ("revolute", "continuous", "prismatic")):
            notes.append(f"joint {jname!r}: <dynamics damping={d}> not imported"
                         + ("" if damping else " (damping=False)"))
            d = 0.0
    if jel.find("mimic") is not None:
        notes.append(f"joint {jname!r}: <mimic> not imported yet (the joint moves freely)")
    return d


def _parse(path):
    root = ET.parse(str(path)).getroot()
    if root.tag != "robot":
        raise ValueError(f"{path}: the root element is <{root.tag}>, not <robot> -> is it a URDF file?")
    links = {el.get("name"): el for el in root.findall("link")}
    if not links:
        raise ValueError(f"{path}: the robot defines no links -> is it an unexpanded xacro file?")
    joints = root.findall("joint")
    children = {}
    for j in joints:
        p, c = j.find("parent").get("link"), j.find("child").get("link")
        for ln in (p, c):
            if ln not in links:
                raise ValueError(f"{path}: joint {j.get('name')!r} names link {ln!r}, which the file does not define")
        children.setdefault(p, []).append(j)
    child_links = [j.find("child").get("link") for j in joints]
    twice = sorted({c for c in child_links if child_links.count(c) > 1})
    if twice:
        raise ValueError(f"{path}: links {twice} are the child of more than one joint (a closed loop): "
                         "load_urdf reads trees only, loop-closing joints are not imported yet")
    roots = [n for n in links if n not in child_links]
    if len(roots) != 1:
        raise ValueError(f"{path}: {len(roots)} root links {roots} (a URDF tree has one) -> fix the file")
    return root, links, children, roots[0]


def load_urdf(path, floating=False, gravity=(0.0, 0.0, -9.81), limits=False, damping=True, visuals=True,
              package_dirs=()):
    """A :class:`~mbcomp.Model` of library components from a URDF file (a tree robot).

    Parameters
    ----------
    path : str or path-like
        The ``.urdf`` file.
    floating : bool
        Join the root link to the world by a ``FreeMotion`` named ``root_joint`` (a legged or
        flying robot); else the root link is welded to the world frame.
    gravity : (3,) m/s^2, world coordinates
        URDF has no gravity; the default points along -z.
    limits : bool
        Make ``<limit lower upper>`` the revolute and prismatic joints' stops (impacts at
        the limits). Off by default: many files' limits are loose, and stops change the motion.
    damping : bool
        Model ``<dynamics damping>`` of revolute and prismatic joints by a damper named
        ``<joint>_damping`` (N m s/rad or N s/m) on the joint's flanges.
    visuals : bool
        Draw each link as its ``<visual>`` elements say (:mod:`mbcomp.io.urdf_visuals`: boxes,
        cylinders, spheres, meshes; a massless link's on a component named as the link, a
        ``FixedTranslation`` of length 0 on its frame); False: the library's default looks,
        no mesh file read (faster).
    package_dirs : iterable of str
        Where ``package://`` mesh names are searched first (each a package's directory or one
        holding packages), as Pinocchio's ``package_dirs``.

    Returns
    -------
    Model
        With ``model.urdf_notes``: a list of what was not imported or was renamed.

    Examples
    --------
    >>> import os, tempfile
    >>> import mbcomp
    >>> text = '''<robot name="pendulum"><link name="base"/>
    ... <link name="arm"><inertial><mass value="2"/><origin xyz="0 0 -0.5"/>
    ... <inertia ixx="0.1" iyy="0.1" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
    ... <joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/>
    ... <axis xyz="0 1 0"/></joint></robot>'''
    >>> path = os.path.join(tempfile.mkdtemp(), "pendulum.urdf")
    >>> _ = open(path, "w").write(text)
    >>> m = mbcomp.load_urdf(path)
    >>> mbcomp.assemble(m).q_names
    ['hinge.phi']
    """
    from mbcomp import library as lib
    from mbcomp.modeling.model import Model

    robot, links, children, root = _parse(path)
    notes = []
    names = _Names(notes)
    # joints keep the file's names first (res["<joint>.phi"]); a link of the same name is renamed
    free_name = names("root_joint", "joint") if floating else None
    joint_names = {id(j): names(j.get("name"), "joint") for js in children.values() for j in js}
    model = Model()
    world = model.add("world", lib.World(g=np.asarray(gravity, dtype=float)))
    link_frame = {}  # link name -> the port that is its frame
    base = world.frame_b
    if floating:
        free = model.add(free_name, lib.FreeMotion())
        model.connect(world.frame_b, free.frame_a)
        base = free.frame_b
    looks = link_visuals(robot, path, package_dirs, notes) if visuals else {}
    _add_link(model, lib, links, root, base, link_frame, names, notes, looks)
    carries = _carries_mass(links, children, root)
    stack = [root]
    while stack:
        parent = stack.pop()
        for jel in children.get(parent, []):
            child, cname = jel.find("child").get("link"), joint_names[id(jel)]
            if not carries[child] and jel.get("type") != "fixed":  # a moving joint with no mass beyond it:
                notes.append(f"joint {jel.get('name')!r}: moves no mass (link {child!r} and beyond are "
                             "massless): held at 0 as a fixed joint")  # its motion would be undetermined
                jel = _as_fixed(jel)
            frame = _add_joint(model, lib, jel, cname, link_frame[parent], names, notes, limits, damping)
            _add_link(model, lib, links, child, frame, link_frame, names, notes, looks)
            stack.append(child)
    for el in robot:
        if el.tag not in ("link", "joint", "material"):
            notes.append(f"<{el.tag}> {el.get('name', '')!r}: not imported".replace(" ''", ""))
    if looks:  # the robot is drawn as its file says: no joint glyphs in or across its meshes
        hide_glyphs(model)
    model.urdf_notes = notes
    if notes:
        warnings.warn(f"{path}: {len(notes)} URDF elements not imported or renamed (model.urdf_notes): "
                      + "; ".join(notes[:5]) + (" ..." if len(notes) > 5 else ""), UserWarning, stacklevel=2)
    return model


def _carries_mass(links, children, root):
    """``{link: whether it or a link beyond it has mass}``."""
    out = {}

    def visit(name):
        below = [visit(j.find("child").get("link")) for j in children.get(name, [])]
        out[name] = _inertial(links[name]) is not None or any(below)
        return out[name]

    visit(root)
    return out


def _as_fixed(jel):
    """A copy of the joint element ``jel`` as a fixed joint at its origin (same name)."""
    fixed = ET.Element("joint", {"name": jel.get("name"), "type": "fixed"})
    fixed.extend(list(jel))
    return fixed


def _add_link(model, lib, links, name, frame, link_frame, names, notes, looks):
    mp = _inertial(links[name])
    if mp is None:
        link_frame[name] = frame
        if looks.get(name):  # a massless link's visuals: on a marker, a rigid offset of length 0 on its frame
            marker = model.add(names(name, "link"), lib.FixedTranslation(r=(0.0, 0.0, 0.0), shape=looks[name]))
            model.connect(frame, marker.frame_a)
        return
    m, r_cm, I = mp
    body = model.add(names(name, "link"), lib.RigidBody(m=m, r_cm=r_cm, I=I, shape=looks.get(name)))
    model.connect(frame, body.frame_a)
    link_frame[name] = body.frame_a


def _add_joint(model, lib, jel, cname, parent_frame, names, notes, limits, damping):
    """The joint's components from ``parent_frame``; returns the port that is the child link's frame."""
    jname, kind = jel.get("name"), jel.get("type")
    xyz, R = _origin(jel)
    axis = _vec(jel.find("axis"), "xyz", (1, 0, 0))
    rotated = not np.allclose(R, np.eye(3), rtol=0, atol=0)
    if kind == "fixed":
        off = lib.FixedRotation(r=xyz, R=R) if rotated else lib.FixedTranslation(r=xyz)
        c = model.add(cname, off)
        model.connect(parent_frame, c.frame_a)
        return c.frame_b
    frame = parent_frame
    if rotated or xyz.any():
        off = lib.FixedRotation(r=xyz, R=R) if rotated else lib.FixedTranslation(r=xyz)
        o = model.add(names(f"{cname}_origin", "joint origin"), off)
        model.connect(parent_frame, o.frame_a)
        frame = o.frame_b
    d = _note_dynamics(jel, jname, kind, damping, notes)
    j = model.add(cname, _joint_component(lib, kind, axis, jel, limits, jname, notes))
    model.connect(frame, j.frame_a)
    if d > 0.0:
        law = lib.TranslationalSpringDamper(c=0.0, d=d) if kind == "prismatic" else lib.RotationalDamper(d=d)
        damper = model.add(names(f"{cname}_damping", "joint damping"), law)
        model.connect(j.support, damper.flange_a)
        model.connect(j.axis, damper.flange_b)
    return j.frame_b
