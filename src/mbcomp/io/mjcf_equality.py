"""MJCF ``<equality>`` constraints as exact loop closures (cut joints), with MuJoCo's geometry.

MuJoCo holds its equality constraints softly (``solref``/``solimp``: a stiff spring-damper
solved each step, so a loop drifts open by the constraint's violation); mbcomp closes each as
a cut joint with exact rows (:func:`mbcomp.io.loops.close_loop`), placed as MuJoCo's compiler
places them (``m.eq_data``) at ``qpos0`` (every body where the file puts it,
:class:`mbcomp.io.mjcf.BodyFrame`):

- ``<connect body1 body2 anchor>``: ``anchor`` (m) is a point in ``body1``'s frame; the point
  of ``body2`` (the world when omitted) is where that anchor is at ``qpos0``, so the file's
  pose closes the loop. -> a ``Spherical`` between the two points (kind ``"point"``), its
  start orientation the bodies' relative one at ``qpos0`` (a ``Guess``: where the topology
  keeps the ball in the tree and cuts another joint of the loop, it places body2's side).
- ``<joint joint1 joint2 polycoef>`` with a linear polynomial (``polycoef="0 a1 0 0 0"``):
  MuJoCo's ``y - y0 = a1 (x - x0)`` between ``joint1`` (``y``) and ``joint2`` (``x``) from their
  ``qpos0`` values, exactly the row of a flange constraint named as the equality
  (``IdealGear(ratio=a1)`` between hinges, ``JointCoupling`` otherwise), whose phase is the
  joints' start values (``ref``, as ``qpos0``);
- ``<weld body1 body2 relpose anchor torquescale>``: ``body2``'s point ``anchor`` (its frame)
  sits at ``relpose``'s position in ``body1``'s frame with ``body2``'s axes at ``relpose``'s
  quaternion (``w x y z``) from ``body1``'s; when ``relpose``'s quaternion is zero (its
  default) both are those at ``qpos0``. -> a ``Weld`` (kind ``"weld"``); ``torquescale="0"``
  (no rotational residual) is a ``connect`` at the anchor.

The joint is named as the equality (``connect<k>``/``weld<k>`` when unnamed, ``k`` its
position in the file); its rigid offsets ``<name>_a``, ``<name>_b``. ``solref``, ``solimp``
(softness) and ``torquescale``'s weighting do not apply to an exact closure (noted where given).
Not imported (noted, the loop stays open): inactive equalities (``active="false"``), site-based
ones (``site1``/``site2``), ``joint`` equalities with a constant or nonlinear term or without
``joint2``, and the ``tendon`` and ``flex`` kinds. A closure on a body with a free joint is
made, and noted: the topology cuts that free joint (it has the most freedom), whose start
pose ``load_mjcf`` fixes, and initialization refuses fixed starts on a multi-DOF cut joint; the
note names the fix, the pose as a ``Guess`` (``simulate(model, params={"<joint>.r0":
mbcomp.Guess(r0), "<joint>.R0": mbcomp.Guess(R0)})``).
"""
import re

import numpy as np

from ..geometry.kinematics import quat_to_matrix
from .loops import close_loop
from .mjcf_frames import numbers
from .names import ComponentNames

__all__ = ["add_equalities"]

_SOFT = ("solref", "solimp")


def _frame(model, bodies, name, what):
    """``(port, R0, p0)`` of an MJCF body (the world when ``name`` is None or ``"world"``)."""
    if name is None or name == "world":
        return model["world"].frame_b, np.eye(3), np.zeros(3)
    b = bodies.get(name)
    if b is None:
        raise ValueError(f"MJCF {what}: body {name!r} is not a body of the file -> fix the name")
    return b.port, np.asarray(b.R0, dtype=float), np.asarray(b.p0, dtype=float)


def _relpose(el, what):
    """``(pos, R)`` of a weld's ``relpose`` or None when its quaternion is zero (the default)."""
    if el.get("relpose") is None:
        return None
    v = numbers(el.get("relpose"), 7, f"{what} relpose")
    quat = np.asarray(v[3:], dtype=float)
    if not np.any(quat):
        return None
    return np.asarray(v[:3], dtype=float), quat_to_matrix(quat / np.linalg.norm(quat))


def _closure(el, model, bodies, what):
    """``(kind, frame_a, frame_b, pose_a, pose_b, R0)`` of a ``connect`` or ``weld`` element
    (``R0``: a point closure's body2 axes relative to body1's at qpos0, or as the weld's pose)."""
    (pa, Ra, ra), (pb, Rb, rb) = (_frame(model, bodies, el.get(k), what) for k in ("body1", "body2"))
    anchor = np.asarray(numbers(el.get("anchor", "0 0 0"), 3, f"{what} anchor"), dtype=float)
    if el.tag == "connect":  # body2's point: where body1's anchor is at qpos0
        return "point", pa, pb, (anchor, np.eye(3)), (Rb.T @ (ra + Ra @ anchor - rb), np.eye(3)), Ra.T @ Rb
    rel = _relpose(el, what)
    if rel is None:  # body2's anchor point in body1's frame and the relative axes, at qpos0
        rel = Ra.T @ (rb + Rb @ anchor - ra), Ra.T @ Rb
    if float(el.get("torquescale", 1.0)) == 0.0:  # no rotational residual: the anchors coincide
        return "point", pa, pb, (rel[0], np.eye(3)), (anchor, np.eye(3)), rel[1]
    return "weld", pa, pb, rel, (anchor, np.eye(3)), None


def _joint_of(model, name):
    """The 1-DOF joint component of the MJCF joint ``name`` (its component name: the file's,
    sanitized as :class:`mbcomp.io.names.ComponentNames` does), or None."""
    if name is None:
        return None
    cname = re.sub(r"\W", "_", name)
    comp = model.components().get("_" + cname if cname[:1].isdigit() else cname)
    return comp if getattr(comp, "axis_kind", None) in ("rotational", "translational") else None


def _linear_coupling(el):
    """Why a ``<joint>`` equality is not a linear coupling of two joints, or None."""
    coef = numbers(el.get("polycoef", "0 1 0 0 0"), 5, f"equality <joint> {el.get('name')!r} polycoef")
    if el.get("joint2") is None:
        return "no joint2 (it would hold joint1 at a constant)"
    if coef[0] != 0.0 or np.any(coef[2:]) or coef[1] == 0.0:
        return f"polycoef {' '.join(f'{c:g}' for c in coef)} is not linear through qpos0 (only '0 a1 0 0 0', a1 != 0)"
    return None


def _couple_joints(el, model, name, lib):
    """A ``<joint>`` equality's flange constraint ``name``: ``joint1 - y0 = a1 (joint2 - x0)``."""
    a, b = _joint_of(model, el.get("joint1")), _joint_of(model, el.get("joint2"))
    ratio = float(numbers(el.get("polycoef", "0 1 0 0 0"), 5)[1])
    both_hinges = a.axis_kind == b.axis_kind == "rotational"
    g = model.add(name, lib.IdealGear(ratio=ratio) if both_hinges else lib.JointCoupling(ratio=ratio))
    model.connect(g.flange_a, a.axis)
    model.connect(g.flange_b, b.axis)


def _skipped(el, model):
    """Why an equality element is not imported, or None."""
    if el.tag == "joint":
        if el.get("active", "true") == "false":
            return "inactive (active=false)"
        for key in ("joint1", "joint2"):
            if el.get(key) is not None and _joint_of(model, el.get(key)) is None:
                return f"{key} {el.get(key)!r} is not a hinge or slide of the model"
        return _linear_coupling(el)
    if el.tag not in ("connect", "weld"):
        return f"the {el.tag!r} kind is not imported yet"
    if el.get("active", "true") == "false":
        return "inactive (active=false)"
    if el.get("site1") or el.get("site2"):
        return "site-based equalities are not imported yet"
    if el.get("body1") is None:
        return "no body1"
    return None


def free_joints_on_loops(root, parents, free):
    """The bodies among ``free`` whose free joint lies on a loop a ``connect`` or ``weld`` of
    ``root`` closes: the body still reaches the world when its own free joint is taken away.

    The topology cuts such a free joint (it has the most freedom in the loop), and a cut joint
    has no coordinates to hold fixed start values; its start pose is then a
    :class:`~mbcomp.Guess` (``load_mjcf`` gives the file's pose, which closes the loop: nothing
    moves). A free joint on no loop (a floating robot whose legs close loops below it) keeps
    its fixed start pose.

    Parameters
    ----------
    root : xml.etree.ElementTree.Element
        The MJCF's ``<mujoco>`` element (includes read).
    parents : dict
        Body name -> its parent body's name (``None`` for a child of the worldbody).
    free : iterable of str
        The bodies with a free joint (children of the worldbody).

    Returns
    -------
    set of str

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> root = ET.fromstring('<mujoco><equality><weld body1="arm" body2="ball"/></equality></mujoco>')
    >>> sorted(free_joints_on_loops(root, {"arm": None, "ball": None, "box": None}, ["ball", "box"]))
    ['ball']
    """
    ties = [(el.get("body1"), el.get("body2")) for sec in root.findall("equality") for el in sec
            if el.tag in ("connect", "weld") and el.get("body1") and _skipped(el, None) is None]
    free, out = set(free), set()
    for cut in free:
        up = {}

        def find(x):
            while up.get(x, x) != x:
                x = up[x]
            return x

        def join(a, b):
            up[find(a)] = find(b)

        for body, parent in parents.items():
            if body != cut:  # every tree joint but this free one (a free body's parent is the world)
                join(body, parent)
        for a, b in ties:
            join(a, b)  # body2 omitted (None): the world
        if find(cut) == find(None):
            out.add(cut)
    return out


def add_equalities(root, model, bodies, notes):
    """Close every ``<equality><connect>`` and ``<weld>`` of the MJCF ``root`` in ``model`` by
    an exact cut joint (module notes); the rest is listed in ``notes``.

    Parameters
    ----------
    root : xml.etree.ElementTree.Element
        The file's ``<mujoco>`` element (includes spliced).
    model : Model
        The model :func:`mbcomp.io.mjcf.load_mjcf` builds (its world named ``world``).
    bodies : dict
        MJCF body name -> :class:`mbcomp.io.mjcf.BodyFrame` (frame port, pose at ``qpos0``).
    notes : list of str
        Where what is not imported, or imported differently, is said.

    Returns
    -------
    list of str
        The names of the closing joints (and joint couplings) added.

    Examples
    --------
    >>> import os, tempfile
    >>> import mbcomp
    >>> text = '''<mujoco><worldbody>
    ...   <body name="arm"><joint name="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 1 0 0" size="0.05"/>
    ...     <body name="link" pos="1 0 0"><joint name="knee" axis="0 1 0"/>
    ...       <geom type="capsule" fromto="0 0 0 0 0 -1" size="0.05"/></body></body></worldbody>
    ...   <equality><connect name="pin" body1="link" anchor="0 0 -1"/></equality></mujoco>'''
    >>> path = os.path.join(tempfile.mkdtemp(), "loop.xml")
    >>> _ = open(path, "w").write(text)
    >>> system = mbcomp.assemble(mbcomp.load_mjcf(path))
    >>> system.topology.cut, "degrees of freedom: 0" in system.summary()
    (['pin'], True)
    """
    from mbcomp import library as lib

    names = ComponentNames(notes)
    names.used.update(model.components())
    added, k = [], 0
    for sec in root.findall("equality"):
        for el in sec:
            k += 1
            label = el.get("name") or f"{el.tag}{k}"
            what = f"equality <{el.tag}> {label!r}"
            why = _skipped(el, model)
            if why:
                ties = [el.get(t) for t in ("body1", "body2", "joint1", "joint2", "site1", "site2", "tendon1")
                        if el.get(t)]
                notes.append(f"{what} ({', '.join(ties)}): not imported: {why} (the loop it closes stays open)")
                continue
            soft = [a for a in _SOFT if el.get(a) is not None]
            if el.get("torquescale") is not None and float(el.get("torquescale")) not in (0.0, 1.0):
                soft.append("torquescale")
            if soft:
                notes.append(f"{what}: held exactly ({', '.join(soft)}: MuJoCo's softness, not applied)")
            name = names(label, "equality")
            added.append(name)
            if el.tag == "joint":
                _couple_joints(el, model, name, lib)
                continue
            kind, fa, fb, pose_a, pose_b, R0 = _closure(el, model, bodies, what)
            close_loop(model, name, kind, fa, fb, pose_a, pose_b, R0=R0,
                       offset_names=(names(f"{name}_a", "loop frame"), names(f"{name}_b", "loop frame")))
    return added
