"""MJCF import: ``load_mjcf(path) -> Model`` of library bodies, joints and rigid offsets.

MuJoCo's model files read without MuJoCo (``xml.etree``), as MuJoCo's compiler reads them:

- the file: ``<include>`` spliced, ``<default>`` classes (``class``, ``childclass``),
  ``<compiler angle eulerseq inertiafromgeom inertiagrouprange settotalmass boundmass
  boundinertia autolimits meshdir>`` (:mod:`mbcomp.io.mjcf_frames`; angles in degrees unless
  ``angle="radian"``), ``<option gravity>`` and ``<flag gravity="disable">`` -> ``World(g=...)``;
- ``<body pos quat|axisangle|euler|xyaxes|zaxis>``: a ``FixedRotation`` (or
  ``FixedTranslation``) ``<body>_offset`` from its parent's frame, its joints
  (:mod:`mbcomp.io.mjcf_joints`), then a ``RigidBody`` named as the body (``<body>_body`` where
  a joint has its name) with the mass properties of ``<inertial>`` or of its geoms, exactly as
  MuJoCo computes them (:mod:`mbcomp.io.mjcf_inertia`, meshes :mod:`mbcomp.io.mjcf_mesh`),
  and its geoms as shapes (:mod:`mbcomp.io.mjcf_shapes`). A free body is a ``FreeMotion``
  from the world starting at the file's pose. A body without mass adds no ``RigidBody``
  (its frame is its last joint's or its offset's; its shapes, if any, ride on a zero
  ``FixedTranslation`` named as the body). A joint with no mass beyond it is refused (its
  motion would be undetermined).
- names: component names follow body and joint names (``res["slider.s"]``,
  ``res["hinge_1.phi"]``); unnamed ones are ``body<k>`` and ``<body>_joint<k>``; names that are
  no identifiers are sanitized (noted).

Whatever is not imported is listed in ``model.mjcf_notes`` (a list of strings) and summed up
in one ``UserWarning``: actuators one by one with their gains, the rest grouped (sensors,
tendons, contact pairs and excludes, sites, cameras, lights, fluid forces). ``<equality>``
``connect`` and ``weld`` become exact cut joints, linear ``joint`` equalities flange couplings
(:func:`import_equalities`, :mod:`mbcomp.io.mjcf_equality`); the others are listed. :func:`body_frames` gives each body's frame port and its
world pose at ``qpos0`` (what loop-closing joints connect to).
"""
import os
import warnings
from dataclasses import dataclass

import numpy as np

from .mjcf_equality import add_equalities, free_joints_on_loops
from .mjcf_frames import Compiler, Defaults, numbers, orientation, read_tree
from .mjcf_inertia import body_mass_properties, geom_frame, geom_mass, inertial_element, scaled_total
from .mjcf_joints import add_joints, joint_spec
from .mjcf_notes import model_notes
from .mjcf_shapes import geom_shapes, materials_and_meshes
from .names import ComponentNames

__all__ = ["load_mjcf", "BodyFrame", "body_frames", "import_equalities"]

_REFUSED = ("frame", "replicate", "attach", "composite", "flexcomp")


@dataclass(frozen=True)
class BodyFrame:
    """An MJCF body in the imported model: the port that is its frame and its world pose at
    MuJoCo's ``qpos0`` (every hinge and slide at ``ref``, balls at the identity, free bodies
    where the file puts them).

    Attributes
    ----------
    port : Port
        The body's frame (origin and axes of the MJCF body): connect loop-closing joints here.
    R0 : (3, 3) ndarray
        Body axes -> world axes at ``qpos0``.
    p0 : (3,) ndarray
        Body origin at ``qpos0``, m, world coordinates.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.io.mjcf import BodyFrame
    >>> BodyFrame(port=None, R0=np.eye(3), p0=np.zeros(3)).p0.tolist()
    [0.0, 0.0, 0.0]
    """

    port: object
    R0: np.ndarray
    p0: np.ndarray


class _Body:
    """One parsed ``<body>``: its placement, joints, geoms and mass properties."""

    def __init__(self, el, name, parent, pos, R, childclass):
        self.el, self.name, self.parent, self.pos, self.R = el, name, parent, pos, R
        self.childclass, self.joints, self.geoms, self.mp, self.children = childclass, [], [], None, []
        self.p0 = pos if parent is None else parent.p0 + parent.R0 @ pos
        self.R0 = R if parent is None else parent.R0 @ R


def _walk(root, compiler, defaults):
    """``(bodies in depth-first order, the world's geoms)``."""
    world = root.find("worldbody")
    if world is None:
        raise ValueError("MJCF: no <worldbody> -> is the file a fragment meant to be included?")
    bodies, counter = [], [0]

    def visit(el, parent, childclass):
        for tag in _REFUSED:
            if el.find(tag) is not None:
                raise ValueError(f"MJCF <{tag}> in {'the worldbody' if parent is None else repr(parent.name)}: "
                                 f"not read yet -> expand it (MuJoCo's compiled model saved with mj_saveLastXML)")
        for child in el.findall("body"):
            counter[0] += 1
            name = child.get("name") or f"body{counter[0]}"
            cc = child.get("childclass", childclass)
            what = f"body {name!r}"
            b = _Body(child, name, parent, numbers(child.get("pos", "0 0 0"), 3, f"{what} pos"),
                      orientation(child.attrib, compiler, what), cc)
            for k, jel in enumerate(e for e in child if e.tag in ("joint", "freejoint")):
                attrs = defaults.attributes(jel, cc)
                if jel.tag == "freejoint":
                    attrs["type"] = "free"
                jname = jel.get("name") or f"{name}_joint{k + 1}"
                b.joints.append((jname, attrs))
            b.geoms = [(g.get("name"), defaults.attributes(g, cc)) for g in child.findall("geom")]
            bodies.append(b)
            if parent is not None:
                parent.children.append(b)
            visit(child, b, cc)

    visit(world, None, "main")
    return bodies, [(g.get("name"), defaults.attributes(g, "main")) for g in world.findall("geom")]


def _mass_properties(b, compiler, meshes):
    """``(m, r_cm, I)`` of a body (body frame) or None, and its GeomFrames."""
    frames = [(gname, geom_frame(a, compiler, f"geom {gname or '(unnamed)'!r} of body {b.name!r}"))
              for gname, a in b.geoms]
    inertial = b.el.find("inertial")
    use_geoms = compiler.inertiafromgeom == "true" or (compiler.inertiafromgeom == "auto" and inertial is None)
    if not use_geoms:
        return (None if inertial is None else inertial_element(inertial, compiler, f"body {b.name!r}")), frames
    lo, hi = compiler.groups
    parts = []
    for gname, g in frames:
        if lo <= int(float(g.attrs.get("group", 0))) <= hi:
            m, I, c = geom_mass(g, f"geom {gname or '(unnamed)'!r} of body {b.name!r}", meshes)
            parts.append((m, g.R @ I @ g.R.T, g.pos + g.R @ c))
    return body_mass_properties(parts), frames


def _check_moving_mass(bodies, props):
    """A joint whose body and the bodies beyond carry no mass: refused, naming it."""
    carried = {}
    for b in reversed(bodies):
        mp = props[id(b)]
        carried[id(b)] = (mp is not None and mp[0] > 0.0) or any(carried[id(c)] for c in b.children)
        if b.joints and not carried[id(b)]:
            raise ValueError(f"MJCF body {b.name!r}: joint {b.joints[0][0]!r} moves no mass (the body and the bodies "
                             "beyond it have none): its motion would be undetermined -> give the body an <inertial> "
                             "or geoms with mass, or remove the joint")


def _gravity(root, gravity):
    if gravity is not None:
        return np.asarray(gravity, dtype=float)
    g = np.array([0.0, 0.0, -9.81])
    for opt in root.findall("option"):
        if opt.get("gravity") is not None:
            g = numbers(opt.get("gravity"), 3, "option gravity")
        for flag in opt.findall("flag"):
            if flag.get("gravity") == "disable":
                g = np.zeros(3)
    return g


def _read(path):
    """The file read: ``(root, compiler, bodies, world geoms, (materials, meshes), {body: geom
    frames}, {body: (m, r_cm, I) or None})``, the masses scaled and checked."""
    root = read_tree(path)
    compiler = Compiler(root, os.path.dirname(os.path.abspath(os.fspath(path))))
    defaults = Defaults(root)
    bodies, world_geoms = _walk(root, compiler, defaults)
    mats, meshes = materials_and_meshes(root, compiler, defaults)
    frames, props = {}, {}
    for b in bodies:
        props[id(b)], frames[id(b)] = _mass_properties(b, compiler, meshes)
    props = scaled_total(props, compiler)
    _check_moving_mass(bodies, props)
    return root, compiler, bodies, world_geoms, (mats, meshes), frames, props


def load_mjcf(path, gravity=None, limits=False, damping=True, springs=True, armature=True, friction=False):
    """A :class:`~mbcomp.Model` of library components from an MJCF (MuJoCo) file.

    Parameters
    ----------
    path : str or path-like
        The ``.xml`` file (its ``<include>`` files relative to it).
    gravity : (3,) m/s^2, world coordinates, optional
        Overrides the file's ``<option gravity>`` (default ``0 0 -9.81``; zero where the file
        disables gravity).
    limits : bool
        Make limited hinges' and slides' ``range`` their stops (impacts at the limits). Off by
        default: MuJoCo's limits are soft constraints, stops change the motion.
    damping, springs : bool
        Model ``damping`` and ``stiffness``/``springref`` of hinges and slides as spring-dampers
        on the joints' flanges.
    armature : bool
        A hinge's or slide's ``armature`` as a ``ReflectedInertia``/``ReflectedMass`` on its
        axis: ``armature`` on ``M``'s diagonal, exactly MuJoCo's term (see
        :mod:`mbcomp.io.mjcf_joints`; a ball's or free joint's is not imported, noted).
    friction : bool
        A joint's ``frictionloss`` as its Coulomb friction with stick/slip events. Off by
        default: MuJoCo's friction loss is a soft constraint solved each step, mbcomp's
        is exact stick/slip with events -- a different (and slower to integrate) model.

    Returns
    -------
    Model
        With ``model.mjcf_notes`` (what was not imported or was renamed),
        ``model.mjcf_bodies`` (:func:`body_frames`) and ``model.mjcf_joints`` (the joints'
        component names in MuJoCo's joint order).

    Examples
    --------
    >>> import os, tempfile
    >>> import mbcomp
    >>> text = '''<mujoco><worldbody><body name="arm" pos="0 0 1">
    ...   <joint name="hinge" axis="0 1 0"/>
    ...   <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.05"/></body></worldbody></mujoco>'''
    >>> path = os.path.join(tempfile.mkdtemp(), "pendulum.xml")
    >>> _ = open(path, "w").write(text)
    >>> m = mbcomp.load_mjcf(path)
    >>> mbcomp.assemble(m).q_names
    ['hinge.phi']
    """
    from mbcomp import library as lib
    from mbcomp.modeling.model import Model

    root, compiler, bodies, world_geoms, (mats, meshes), frames, props = _read(path)
    notes = []
    names = ComponentNames(notes)
    joint_names = {id(b): [names(n, "joint") for n, _ in b.joints] for b in bodies}
    opts = {"limits": limits, "damping": damping, "springs": springs, "armature": armature, "friction": friction}
    model = Model()
    world_shapes = [s for gname, a in world_geoms
                    for s in geom_shapes(geom_frame(a, compiler, f"world geom {gname!r}"), mats, meshes,
                                         f"world geom {gname!r}", notes)]
    world = model.add("world", lib.World(g=_gravity(root, gravity), **({"shape": world_shapes} if world_shapes else {})))
    specs = {id(b): [joint_spec(a, jn, compiler, f"joint {n!r} of body {b.name!r}")
                     for (n, a), jn in zip(b.joints, joint_names[id(b)])] for b in bodies}
    # a free joint on a loop an equality closes is cut: its start pose a Guess (the file's closes the loop)
    opts["loose"] = free_joints_on_loops(root, {b.name: b.parent and b.parent.name for b in bodies},
                                         [b.name for b in bodies if any(j.kind == "free" for j in specs[id(b)])])
    out = {}
    for b in bodies:
        parent = world.frame_b if b.parent is None else out[b.parent.name].port
        port = _add_body(model, lib, b, parent, props[id(b)], frames[id(b)], specs[id(b)], opts, names, notes,
                         (mats, meshes))
        out[b.name] = BodyFrame(port=port, R0=b.R0, p0=b.p0)
    notes += _armature_note(bodies, specs, armature)
    import_equalities(root, model, out, notes)
    notes += model_notes(root, bodies)
    model.mjcf_notes, model.mjcf_bodies = notes, out
    model.mjcf_joints = [n for b in bodies for n in joint_names[id(b)]]
    if notes:
        warnings.warn(f"{path}: {len(notes)} MJCF elements not imported or renamed (model.mjcf_notes): "
                      + "; ".join(notes[:5]) + (" ..." if len(notes) > 5 else ""), UserWarning, stacklevel=2)
    return model


def _add_body(model, lib, b, parent, mp, frames, specs, opts, names, notes, assets):
    """One body's offset, joints and rigid body from its parent's frame; returns its frame port."""
    free = [j for j in specs if j.kind == "free"]
    if free and (len(specs) > 1 or b.parent is not None):
        raise ValueError(f"MJCF body {b.name!r}: a free joint must be the only joint of a child of the worldbody "
                         "-> move the body to the worldbody (or use slide and ball joints)")
    port = parent
    if not free and (np.any(b.pos) or not np.array_equal(b.R, np.eye(3))):
        rotated = not np.array_equal(b.R, np.eye(3))
        off = lib.FixedRotation(r=b.pos, R=b.R) if rotated else lib.FixedTranslation(r=b.pos)
        c = model.add(names(f"{b.name}_offset", "body offset"), off)
        model.connect(parent, c.frame_a)
        port = c.frame_b
    if specs:
        port = add_joints(model, lib, specs, port, opts, names, notes, pose=(b.R, b.pos), loose=b.name in opts["loose"])
    shapes = [s for gname, g in frames
              for s in geom_shapes(g, *assets, f"geom {gname or '(unnamed)'!r} of body {b.name!r}", notes)]
    look = {"shape": shapes} if shapes else {}
    bname = b.name if not names.taken(b.name) else f"{b.name}_body"
    if mp is not None and mp[0] > 0.0:
        m, r_cm, I = mp
        body = model.add(names(bname, "body"), lib.RigidBody(m=m, r_cm=r_cm, I=I, **look))
        model.connect(port, body.frame_a)
        return body.frame_a
    if shapes:  # a massless body drawn: its shapes on a zero offset
        c = model.add(names(bname, "body"), lib.FixedTranslation(**look))
        model.connect(port, c.frame_a)
    return port


def _armature_note(bodies, specs, armature):
    """One note for the hinges' and slides' armature left out by ``armature=False``."""
    listed = [j.name for b in bodies for j in specs[id(b)] if j.kind in ("hinge", "slide") and j.armature > 0.0]
    if armature or not listed:
        return []
    which = ", ".join(listed[:6]) + (", ..." if len(listed) > 6 else "")
    return [f"armature of {len(listed)} hinges and slides ({which}): not imported (armature=False)"]


def body_frames(model):
    """``{MJCF body name: BodyFrame}`` of a model made by :func:`load_mjcf`: each body's frame
    port and its world pose ``(R0, p0)`` at ``qpos0``.

    Examples
    --------
    >>> import os, tempfile
    >>> import mbcomp
    >>> from mbcomp.io.mjcf import body_frames
    >>> text = '''<mujoco><worldbody><body name="b" pos="0 0 2"><joint type="slide"/>
    ...   <geom size="0.1"/></body></worldbody></mujoco>'''
    >>> path = os.path.join(tempfile.mkdtemp(), "b.xml")
    >>> _ = open(path, "w").write(text)
    >>> body_frames(mbcomp.load_mjcf(path))["b"].p0.tolist()
    [0.0, 0.0, 2.0]
    """
    frames = getattr(model, "mjcf_bodies", None)
    if frames is None:
        raise ValueError("body_frames: the model was not made by mbcomp.load_mjcf (it has no mjcf_bodies)")
    return frames


def import_equalities(root, model, bodies, notes):
    """The ``<equality>`` constraints of the MJCF ``root`` into ``model`` (``bodies``: the
    :func:`body_frames` mapping): ``connect`` and ``weld`` as exact cut joints
    (:mod:`mbcomp.io.mjcf_equality`); the others listed in ``notes`` (the loop stays open)."""
    add_equalities(root, model, bodies, notes)
