"""URDF import: ``load_urdf(path) -> Model`` of library bodies, joints and rigid offsets, with loops.

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
  ``damping=True`` (default); ``<dynamics friction>``: the joint's exact Coulomb friction
  (``CoulombBearing`` N m, ``SlidingFriction`` N: stick/slip events) with ``friction=True``,
  else listed (not combined with stops on one joint: listed).
- ``<mimic joint multiplier offset>``: ``q = multiplier q_leader + offset`` held exactly by a
  flange constraint ``<joint>_mimic`` (``IdealGear(ratio=multiplier)`` between two rotational
  joints, ``JointCoupling`` otherwise); its rows keep displacements from the start values, so
  the offset is the mimic joint's start value ``multiplier q_leader0 + offset``. With
  ``mimic=False`` the joint moves freely (listed), as in Pinocchio's default.
- inertias no real body has (a principal moment above the sum of the other two, or
  negative): refused naming the link, or with ``inertia="as_given"`` imported as given
  (``UncheckedRigidBody``, listed per link), as Pinocchio takes them.
- gravity: ``World(g=gravity)``, ``(0, 0, -9.81)`` m/s^2 by default (URDF carries none).
- ``<visual>``: the link's shapes (:mod:`mbcomp.io.urdf_visuals`), with ``visuals=True``.

Closed loops (mbcomp's convention; URDF itself describes trees only). Two ways of writing a
loop-closing joint are read, both documented elsewhere and both written by hand easily:

1. a ``<joint>`` whose ``<child>`` link is already the child of an earlier joint in the file
   (the form of ROS's ``urdf`` issue #13 and Pinocchio's issue #1274): the first joint naming
   a link as its child places the link (the tree); each later one closes a loop with the
   joint's own meaning -- the child link's frame is the joint frame (``<origin>`` in the
   parent link's frame) moved by the joint's coordinate. The child link's frame must then lie
   on the closing joint: a fixed, massless "tip" link on the closed body is the idiom;
2. a ``<loop_joint name type>`` element with ``<link1 link xyz rpy/>``, ``<link2 link xyz
   rpy/>`` and ``<axis xyz/>`` (Drake's URDF extension, read there as a hinge about ``axis``
   whatever its type): the frame ``xyz rpy`` on ``link1`` and the one on ``link2`` are joined
   by the joint, its axis in ``link1``'s frame; mbcomp reads its ``type`` as below.

The closing joint's ``type``: ``revolute``/``continuous`` -> a hinge, ``prismatic`` -> a
slider, ``fixed`` -> a weld, ``spherical`` or ``ball`` (mbcomp's extension: URDF has no ball
joint) -> a point coincidence; it becomes a cut joint with exact rows
(:func:`mbcomp.io.loops.close_loop`), named as in the file; which joint of the loop the
topology cuts is its choice, and redundant rows (a planar loop) are found and explained by
``mbcomp.assemble(model).summary()``. Its limits, damping, friction and mimic are not imported
(listed). The file's zero position should close every loop; else initialization assembles
the mechanism from it. Chosen because form 1 needs no new element (a tree parser sees a
link with two parents and stops, rather than silently dropping the loop) and form 2 is the
one extension element an existing parser (Drake's) reads; URDF+ (Chignoli et al., 2024)
adds ``<loop>`` elements and coupling constraints to the same effect but no parser of it is
installed here to check the reading against.

Whatever is not imported is listed, element by element, in ``model.urdf_notes`` (a list of
strings) and summed up in one ``UserWarning``.
"""
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from ..geometry.rotations import euler_to_matrix
from .urdf_visuals import hide_glyphs, link_visuals
from ..modeling.inertia import inertia_problem
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


def _num(el, attr, default):
    """The number ``attr`` of element ``el`` (``default`` where absent); a text that is no
    number is an error naming the element and the attribute (the caller adds the link or joint)."""
    text = el.get(attr)
    if text is None:
        return float(default)
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"<{el.tag} {attr}={text!r}> is not a number") from None


def _vec(el, attr, default):
    if el is None or el.get(attr) is None:
        return np.array(default, dtype=float)
    try:
        v = np.array([float(x) for x in el.get(attr).split()], dtype=float)
    except ValueError:
        v = np.zeros(0)
    if v.shape != (3,):
        raise ValueError(f"<{el.tag} {attr}={el.get(attr)!r}> must hold three numbers")
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
    m = _num(mass, "value", 0.0) if mass is not None else 0.0
    r_cm, R = _origin(inertial)
    i = inertial.find("inertia")
    get = (lambda k: _num(i, k, 0.0)) if i is not None else (lambda k: 0.0)
    Ii = np.array([[get("ixx"), get("ixy"), get("ixz")],
                   [get("ixy"), get("iyy"), get("iyz")],
                   [get("ixz"), get("iyz"), get("izz")]])
    if m == 0.0 and not Ii.any():
        return None
    return m, r_cm, R @ Ii @ R.T


def _stops(kind, jel, limits):
    """``(lo, hi)`` of the joint's ``<limit>`` when it is to be made stops, else None."""
    lim = jel.find("limit")
    if limits and kind in ("revolute", "prismatic") and lim is not None \
            and lim.get("lower") is not None and lim.get("upper") is not None:
        lo, hi = _num(lim, "lower", 0.0), _num(lim, "upper", 0.0)
        if lo < hi:
            return (lo, hi)
    return None


def _own_start(kind, jel, limits):
    """The joint's start coordinate without a mimic: 0, or the middle of its stops when 0 is
    outside them."""
    stops = _stops(kind, jel, limits)
    return 0.5 * (stops[0] + stops[1]) if stops and not stops[0] <= 0.0 <= stops[1] else 0.0


def _joint_component(lib, kind, axis, jel, limits, name, notes, start=None, friction=0.0):
    """The library joint of a URDF joint; ``start`` (rad or m): a mimic's start coordinate,
    ``friction`` (N m or N): its Coulomb friction to model (0: none)."""
    stops = _stops(kind, jel, limits)
    if start is not None and stops and not stops[0] <= start <= stops[1]:
        notes.append(f"joint {name!r}: its limits {stops} are not made stops (its mimic start {start:g} is "
                     "outside them)")
        stops = None
    if start is None and stops and not stops[0] <= 0.0 <= stops[1]:  # the file's zero position is outside
        start = 0.5 * (stops[0] + stops[1])
        notes.append(f"joint {name!r}: starts at the middle of its limits {stops} (0 is outside them)")
    if friction and stops:
        notes.append(f"joint {name!r}: <dynamics friction={friction:g}> not imported (stops and friction on one "
                     "joint are not combined yet; limits=False models it)")
        friction = 0.0
    if kind in ("revolute", "continuous", "prismatic"):
        rot = kind != "prismatic"
        kw = {} if start is None else {"phi0" if rot else "s0": float(start)}
        if stops:
            kw["limits"] = stops
        if friction:
            kw["friction"] = lib.CoulombBearing(torque_max=friction) if rot else \
                lib.SlidingFriction(mu_s=friction, normal=1.0)
        return (lib.Revolute if rot else lib.Prismatic)(n=axis, **kw)
    if kind == "floating":
        return lib.FreeMotion()
    if kind == "planar":  # <axis> is the plane's normal; s_x along the in-plane part of x (else of y)
        n = axis / np.linalg.norm(axis)
        e = np.eye(3)[0] if abs(n[0]) < 0.9 else np.eye(3)[1]
        return lib.Planar(n=axis, n_x=e - (e @ n) * n)
    raise ValueError(f"URDF joint {name!r}: type {kind!r} is not one of revolute, continuous, prismatic, "
                     f"fixed, floating, planar -> fix the file")


def _note_dynamics(jel, jname, kind, damping, friction, notes):
    """``(damping, friction)`` coefficients of the joint to model (0 when none), with notes on
    what is left out."""
    dyn = jel.find("dynamics")
    d = f = 0.0
    if dyn is not None:
        d, f = _num(dyn, "damping", 0.0), _num(dyn, "friction", 0.0)
        if f != 0.0 and (not friction or kind not in ("revolute", "continuous", "prismatic") or f < 0.0):
            notes.append(f"joint {jname!r}: <dynamics friction={f:g}> not imported"
                         + ("" if friction else " (friction=False)"))
            f = 0.0
        if d != 0.0 and (not damping or kind not in ("revolute", "continuous", "prismatic")):
            notes.append(f"joint {jname!r}: <dynamics damping={d}> not imported"
                         + ("" if damping else " (damping=False)"))
            d = 0.0
    return d, f


def _parse(path):
    """``(robot, links, children, root, loops)``: the tree joints by parent link, the root link
    and the loop-closing elements (the mbcomp convention of the module notes), in file order."""
    try:
        root = ET.parse(str(path)).getroot()
    except ET.ParseError as e:
        raise ValueError(f"{path}: not XML ({e}) -> is it a URDF file?") from None
    if root.tag != "robot":
        raise ValueError(f"{path}: the root element is <{root.tag}>, not <robot> -> is it a URDF file?")
    links = {el.get("name"): el for el in root.findall("link")}
    if not links:
        raise ValueError(f"{path}: the robot defines no links -> is it an unexpanded xacro file?")
    children, parent_of, loops = {}, {}, []
    for j in root.findall("joint"):
        p, c = j.find("parent").get("link"), j.find("child").get("link")
        for ln in (p, c):
            if ln not in links:
                raise ValueError(f"{path}: joint {j.get('name')!r} names link {ln!r}, which the file does not define")
        if c in parent_of:  # the link has a parent joint already: this joint closes a loop
            loops.append(j)
            continue
        parent_of[c] = j
        children.setdefault(p, []).append(j)
    for lj in root.findall("loop_joint"):
        for tag in ("link1", "link2"):
            el = lj.find(tag)
            if el is None or el.get("link") not in links:
                raise ValueError(f"{path}: <loop_joint> {lj.get('name')!r}: <{tag} link=...> must name a link of "
                                 "the file -> fix the file")
        loops.append(lj)
    roots = [n for n in links if n not in parent_of]
    if not roots:
        raise ValueError(f"{path}: 0 root links: every link is the child of a joint (a loop through the root?) "
                         "-> write the joint that closes that loop as a <loop_joint> (module notes)")
    if len(roots) != 1:
        raise ValueError(f"{path}: {len(roots)} root links {roots} (a URDF tree has one) -> fix the file")
    unreached = sorted(set(links) - _below(children, roots[0]))
    if unreached:
        raise ValueError(f"{path}: links {unreached} are not reached from the root link {roots[0]!r} through the "
                         "first joint naming each as its child (those joints form a cycle) -> make the joint "
                         "that closes each loop the later one in the file")
    return root, links, children, roots[0], loops


def _below(children, name):
    """The links reached from ``name`` through tree joints (``name`` included)."""
    out, stack = set(), [name]
    while stack:
        n = stack.pop()
        if n not in out:
            out.add(n)
            stack.extend(j.find("child").get("link") for j in children.get(n, []))
    return out


def load_urdf(path, floating=False, gravity=(0.0, 0.0, -9.81), limits=False, damping=True, friction=False,
              mimic=True, inertia="check", visuals=True, package_dirs=()):
    """A :class:`~mbcomp.Model` of library components from a URDF file (a tree robot, or one
    with loop-closing joints: the module notes).

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
    friction : bool
        Model ``<dynamics friction>`` as the joint's exact Coulomb friction (stick/slip events,
        ``res["<joint>.sticking"]``); off by default (noted): the events change the run.
    mimic : bool
        Hold each ``<mimic>`` exactly by a flange constraint ``<joint>_mimic``; off: the joint
        moves freely (noted), as in Pinocchio's default.
    inertia : {"check", "as_given"}
        Refuse a link whose inertia no real body has, naming it; or import it as given
        (``UncheckedRigidBody``, noted per link), as Pinocchio does.
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

    if inertia not in ("check", "as_given"):
        raise ValueError(f"load_urdf: inertia={inertia!r} is not 'check' or 'as_given'")
    robot, links, children, root, loops = _parse(path)
    notes = []
    names = _Names(notes)
    # joints keep the file's names first (res["<joint>.phi"]); a link of the same name is renamed
    free_name = names("root_joint", "joint") if floating else None
    tree = [j for js in children.values() for j in js]
    joint_names = {id(j): names(j.get("name"), "joint") for j in tree + loops}
    model = Model()
    world = model.add("world", lib.World(g=np.asarray(gravity, dtype=float)))
    link_frame = {}  # link name -> the port that is its frame
    base = world.frame_b
    if floating:
        free = model.add(free_name, lib.FreeMotion())
        model.connect(world.frame_b, free.frame_a)
        base = free.frame_b
    opts = {"limits": limits, "damping": damping, "friction": friction,
            "looks": link_visuals(robot, path, package_dirs, notes) if visuals else {},
            "starts": _mimic_starts(tree, limits) if mimic else {}}
    held = _add_tree(model, lib, _Bodies(lib, links, inertia, path, notes), (links, children, root, loops), base,
                     joint_names, link_frame, opts, names, notes)
    _couple_mimics(model, lib, tree, joint_names, held, names, notes, mimic)
    _close_loops(model, loops, link_frame, joint_names, names, notes, limits)
    for el in robot:
        if el.tag not in ("link", "joint", "material", "loop_joint"):
            notes.append(f"<{el.tag}> {el.get('name', '')!r}: not imported".replace(" ''", ""))
    if opts["looks"]:  # the robot is drawn as its file says: no joint glyphs in or across its meshes
        hide_glyphs(model)
    model.urdf_notes = notes
    if notes:
        warnings.warn(f"{path}: {len(notes)} URDF elements not imported or renamed (model.urdf_notes): "
                      + "; ".join(notes[:5]) + (" ..." if len(notes) > 5 else ""), UserWarning, stacklevel=2)
    return model


def _add_tree(model, lib, bodies, parsed, base, joint_names, link_frame, opts, names, notes):
    """The links and tree joints from the root link on ``base``, parents first; fills
    ``link_frame`` and returns the names of the joints held fixed (they move no mass)."""
    links, children, root, loops = parsed
    _add_link(model, bodies, links, root, base, link_frame, names, notes, opts["looks"])
    carries = _carries_mass(links, children, root, _loop_links(loops))
    held, stack = set(), [root]
    while stack:
        parent = stack.pop()
        for jel in children.get(parent, []):
            child, cname = jel.find("child").get("link"), joint_names[id(jel)]
            if not carries[child] and jel.get("type") != "fixed":  # a moving joint with no mass beyond it:
                notes.append(f"joint {jel.get('name')!r}: moves no mass (link {child!r} and beyond are "
                             "massless): held at 0 as a fixed joint")  # its motion would be undetermined
                held.add(jel.get("name"))
                jel = _as_fixed(jel)
            try:
                frame = _add_joint(model, lib, jel, cname, link_frame[parent], names, notes, opts,
                                   opts["starts"].get(jel.get("name")))
            except ValueError as e:  # a text of the file that is no number (not a component's ModelError)
                if type(e) is not ValueError or str(e).startswith("URDF joint"):
                    raise
                raise ValueError(f"URDF joint {jel.get('name')!r}: {e} -> fix the file") from None
            _add_link(model, bodies, links, child, frame, link_frame, names, notes, opts["looks"])
            stack.append(child)
    return held


def _carries_mass(links, children, root, pinned=()):
    """``{link: whether it or a link beyond it has mass, or ends a loop closure (in ``pinned``)}``:
    a closure determines its motion."""
    out = {}

    def visit(name):
        below = [visit(j.find("child").get("link")) for j in children.get(name, [])]
        out[name] = _inertial(links[name]) is not None or name in pinned or any(below)
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


def _add_joint(model, lib, jel, cname, parent_frame, names, notes, opts, start=None):
    """The joint's components from ``parent_frame``; returns the port that is the child link's frame.
    ``opts``: load_urdf's ``limits``, ``damping``, ``friction``; ``start``: a mimic's start (rad or m)."""
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
    d, f = _note_dynamics(jel, jname, kind, opts["damping"], opts["friction"], notes)
    j = model.add(cname, _joint_component(lib, kind, axis, jel, opts["limits"], jname, notes, start, f))
    model.connect(frame, j.frame_a)
    if d > 0.0:
        law = lib.TranslationalSpringDamper(c=0.0, d=d) if kind == "prismatic" else lib.RotationalDamper(d=d)
        damper = model.add(names(f"{cname}_damping", "joint damping"), law)
        model.connect(j.support, damper.flange_a)
        model.connect(j.axis, damper.flange_b)
    return j.frame_b


class _Bodies:
    """The component library as :func:`_add_link` uses it, with ``RigidBody`` taking the file's
    inertia as given (an ``UncheckedRigidBody``) where ``inertia="as_given"`` and the inertia is
    one no real body has (noted per link); with ``inertia="check"`` such a link is refused,
    naming the option."""

    def __init__(self, lib, links, inertia, path, notes):
        self._lib = lib
        for name, el in links.items():
            try:
                mp = _inertial(el)
            except ValueError as e:
                raise ValueError(f"{path}: link {name!r}: {e} -> fix the file") from None
            why = None if mp is None else inertia_problem(mp[2])
            if why is None:
                continue
            if inertia == "check":
                raise ValueError(f"{path}: link {name!r}: {why} -> load_urdf(..., inertia='as_given') imports it "
                                 "as the file gives it (as Pinocchio does), or correct the file")
            notes.append(f"link {name!r}: {why}: taken as given (inertia='as_given')")

    def __getattr__(self, name):
        return getattr(self._lib, name)

    def RigidBody(self, m, r_cm, I, **kw):  # noqa: N802 (the library's name)
        """A ``RigidBody``, or an ``UncheckedRigidBody`` for an inertia no real body has (one
        ``__init__`` noted as taken as given)."""
        cls = self._lib.RigidBody if inertia_problem(I) is None else self._lib.UncheckedRigidBody
        return cls(m=m, r_cm=r_cm, I=I, **kw)


def _mimic_of(jel):
    """``(leader, multiplier, offset)`` of a joint's ``<mimic>``, or None."""
    mim = jel.find("mimic")
    if mim is None:
        return None
    return mim.get("joint"), _num(mim, "multiplier", 1.0), _num(mim, "offset", 0.0)


def _mimic_starts(tree, limits):
    """``{joint: start}`` (rad or m) of the mimic joints: ``multiplier * leader's start + offset``,
    so that the coupling's row (displacements from the starts) holds URDF's
    ``q = multiplier q_leader + offset`` (the leader's start: 0, or the middle of its stops)."""
    by_name = {j.get("name"): j for j in tree}
    out = {}

    def start(name, depth):
        jel = by_name[name]
        mim = _mimic_of(jel)
        if mim is None or mim[0] not in by_name or depth > len(tree):
            return _own_start(jel.get("type"), jel, limits)
        return mim[1] * start(mim[0], depth + 1) + mim[2]

    for name, jel in by_name.items():
        if _mimic_of(jel) is not None and _mimic_of(jel)[0] in by_name:
            out[name] = start(name, 0)
    return out


_MOVING = ("revolute", "continuous", "prismatic")


def _couple_mimics(model, lib, tree, joint_names, held, names, notes, mimic=True):
    """Each ``<mimic joint multiplier offset>`` as a flange constraint between the two joints'
    axes: ``IdealGear(ratio=multiplier)`` between rotational axes, else ``JointCoupling``; the
    offset is in the start values (:func:`_mimic_starts`). Named ``<joint>_mimic``."""
    by_name = {j.get("name"): j for j in tree}
    for jel in tree:
        mim = _mimic_of(jel)
        if mim is None:
            continue
        name, (leader, ratio, _) = jel.get("name"), mim
        if not mimic:
            notes.append(f"joint {name!r}: <mimic> not imported (mimic=False: the joint moves freely)")
            continue
        lel = by_name.get(leader)
        why = None
        if lel is None or lel.get("type") not in _MOVING or leader in held:
            why = f"its leader {leader!r} is not a moving tree joint of the file"
        elif jel.get("type") not in _MOVING or name in held:
            why = "it is not a moving revolute, continuous or prismatic joint"
        elif ratio == 0.0:
            why = "multiplier 0 (it would hold the joint at its offset)"
        if why:
            notes.append(f"joint {name!r}: <mimic> not imported: {why} (the joint moves freely)")
            continue
        rotational = all(k in ("revolute", "continuous") for k in (jel.get("type"), lel.get("type")))
        law = lib.IdealGear(ratio=ratio) if rotational else lib.JointCoupling(ratio=ratio)
        cname = joint_names[id(jel)]
        g = model.add(names(f"{cname}_mimic", "mimic coupling"), law)
        model.connect(g.flange_a, model[cname].axis)
        model.connect(g.flange_b, model[joint_names[id(lel)]].axis)


_LOOP_KINDS = {"revolute": "hinge", "continuous": "hinge", "prismatic": "slider", "fixed": "weld",
               "spherical": "point", "ball": "point"}


def _loop_links(loops):
    """The links a loop closure ends on."""
    out = set()
    for el in loops:
        tags = ("link1", "link2") if el.tag == "loop_joint" else ("parent", "child")
        out.update(el.find(t).get("link") for t in tags)
    return out


def _pose(el):
    """``(xyz, R)`` of an element's own ``xyz``/``rpy`` attributes (a ``<loop_joint>``'s ends)."""
    return _vec(el, "xyz", (0, 0, 0)), rpy_matrix(_vec(el, "rpy", (0, 0, 0)))


def _close_loops(model, loops, link_frame, joint_names, names, notes, limits):
    """Each loop-closing joint as a cut joint (:func:`mbcomp.io.loops.close_loop`): its frame_a
    where the joint's frame is on the parent link (``<loop_joint>``: on ``link1``), its frame_b
    the child link's frame (``<loop_joint>``: the frame on ``link2``)."""
    from .loops import close_loop

    for el in loops:
        name, kind = el.get("name"), el.get("type")
        if kind not in _LOOP_KINDS:
            raise ValueError(f"URDF loop-closing joint {name!r}: type {kind!r} cannot close a loop (one of "
                             f"{', '.join(_LOOP_KINDS)}) -> fix the file")
        if el.tag == "loop_joint":
            a, b = el.find("link1"), el.find("link2")
            ends, poses = (a.get("link"), b.get("link")), (_pose(a), _pose(b))
        else:
            ends, poses = (el.find("parent").get("link"), el.find("child").get("link")), (_origin(el), None)
            _note_loop_extras(el, name, kind, limits, notes)
        cname = joint_names[id(el)]
        close_loop(model, cname, _LOOP_KINDS[kind], link_frame[ends[0]], link_frame[ends[1]], *poses,
                   axis=_vec(el.find("axis"), "xyz", (1, 0, 0)),
                   offset_names=(names(f"{cname}_a", "loop frame"), names(f"{cname}_b", "loop frame")))


def _note_loop_extras(el, name, kind, limits, notes):
    """Notes of what a loop-closing joint carries beyond its closure (not imported on a cut joint)."""
    dyn = el.find("dynamics")
    for what in ("damping", "friction"):
        if dyn is not None and _num(dyn, what, 0.0) != 0.0:
            notes.append(f"loop joint {name!r}: <dynamics {what}> not imported (it closes a loop)")
    if el.find("mimic") is not None:
        notes.append(f"loop joint {name!r}: <mimic> not imported (it closes a loop)")
    if limits and _stops(kind, el, limits):
        notes.append(f"loop joint {name!r}: <limit> not made stops (it closes a loop)")
