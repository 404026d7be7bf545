"""Locking joints: a model with no more freedom than a scene needs (``Model.lock``, ``mbcomp.reduce``).

``model.lock(["knee", ...], at={...})`` returns a *new* model (the one it is called on is not
changed) in which each locked joint is a :class:`Locked`: a 0-DOF joint holding its frame_b
where the joint's own ``relative(q, p)`` put it at the given coordinates, under the joint's
name and with its frames. A 0-DOF joint is a rigid offset, so the assembly
(:mod:`mbcomp.assembly.topology`) merges the bodies on both sides into one link: fewer
coordinates, and the recursive algorithms see one composite body, as Pinocchio's
``buildReducedModel`` does. :func:`reduce` locks every moving joint but those kept.

What hangs on a locked joint's flanges is decided from the roles (:mod:`mbcomp.modeling.roles`),
never from names:

* a :class:`~mbcomp.modeling.roles.FlangeElement` (damper, spring, motor torque, elastic
  stop, a law on the axis) whose flanges are all on locked joints is dropped and said: its
  force acts between two frames the lock holds together, so it moves nothing;
* a :class:`~mbcomp.modeling.roles.FlangeConstraint` (gear, mimic) whose flanges are all on
  locked joints is dropped and said (the lock holds its flanges); one that also ties a kept
  joint is an error naming both: the lock would hold the kept joint too, silently;
* a :class:`~mbcomp.modeling.roles.Drive` on a locked joint is an error naming both: it
  prescribes motion the lock forbids (remove the drive, or keep the joint);
* a :class:`~mbcomp.modeling.roles.FlangeInertia` (a rotor) on a locked joint stays, as a
  :class:`HeldRotor` body of inertia ``J n n^T`` on the frame it turned with; a reflected one
  (turning at the joint's own rate, which the lock makes zero: MuJoCo's armature) is dropped and said;
* the joint's own modes (stops, stick-slip friction: :meth:`~mbcomp.modeling.roles.Joint.modes`)
  end with it (said).

What was dropped is listed in ``model.lock_notes`` (and one ``UserWarning``); what was locked,
at which coordinates, in :attr:`mbcomp.Model.locked` and the model summary (``mbcomp info``).

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j1 = m.add("j1", Revolute(n=(0, 0, 1))); rod = m.add("rod", FixedTranslation(r=(1, 0, 0)))
>>> j2 = m.add("j2", Revolute(n=(0, 0, 1))); bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j1.frame_a); m.connect(j1.frame_b, rod.frame_a)
>>> m.connect(rod.frame_b, j2.frame_a); m.connect(j2.frame_b, bob.frame_a)
>>> held = m.lock(["j2"], at={"j2": 0.5})
>>> mbcomp.assemble(held).q_names, mbcomp.assemble(m).q_names
(['j1.phi'], ['j1.phi', 'j2.phi'])
>>> held.locked
{'j2': {'phi': 0.5}}
"""
from __future__ import annotations

import copy
import difflib
import warnings

import numpy as np

from ..errors import ModelError, Problem
from .component import Param
from .free_joint import rotation_matrix_problem
from .roles import Body, Joint

__all__ = ["Locked", "HeldRotor", "lock", "reduce", "locked_joints", "moving_joints"]


class Locked(Joint):
    """A joint held still: frame_b fixed in frame_a at the pose the joint had at its held
    coordinates (``R_b = R_a R``, ``r_b = r_a + R_a r``): a 0-DOF joint, a rigid offset.

    Made by :meth:`mbcomp.Model.lock` in place of the joint it holds, under that joint's name
    and with its frames. Its result columns are the held coordinates (constant) and zero
    speeds under the joint's own names (``res["knee.phi"]`` stays), beside the reaction
    ``<name>.f``/``<name>.tau`` every tree joint has: the load the lock carries.

    Parameters
    ----------
    joint_class : str
        The class of the joint it holds (for messages and the summary).
    held : sequence of (str, float)
        The held joint's coordinates and their values (rad or m; a quaternion's entries 1).
    speeds : sequence of str
        The held joint's speed names (zero columns).
    dropped : sequence of str
        What was dropped with the lock (for the summary).
    units : dict, optional
        ``{column suffix: unit}`` of the held coordinates and speeds (the joint's declared
        units: the result's and the FMU's column units, :attr:`output_units`).

    Its pose is its parameters ``r`` and ``R``, runtime values as any rigid offset's; the
    held columns record the coordinates it was locked at.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.modeling.lock import Locked
    >>> j = Locked(r=(0, 0, 0.1), joint_class="Revolute", held=[("phi", 0.3)], speeds=["w"])
    >>> j.nq, j.relative(np.zeros(0), j.p)[1].tolist(), j.held
    (0, [0.0, 0.0, 0.1], (('phi', 0.3),))
    """

    r = Param((0.0, 0.0, 0.0), unit="m", shape=(3,), doc="origin of frame_b, frame_a coordinates")
    R = Param(np.eye(3), unit="1", shape=(3, 3), check=rotation_matrix_problem,
              doc="orientation of frame_b: frame_b -> frame_a")

    def __init__(self, joint_class="Joint", held=(), speeds=(), dropped=(), units=None, **values):
        super().__init__(**values)
        self.output_units = dict(units or {})
        self.joint_class = str(joint_class)
        self.held = tuple((str(n), float(v)) for n, v in held)
        self.held_speeds = tuple(str(n) for n in speeds)
        self.dropped = tuple(str(d) for d in dropped)

    def relative(self, q, p):
        return p.R, p.r

    def constraints(self, a, b, p):
        raise ModelError([Problem(self.path, f"the locked {self.joint_class} closes a loop whose every other joint is "
                                             "rigid, locked or driven: the loop has no freedom left to close",
                                  "keep one joint of that loop free (lock fewer joints, or reduce(..., keep=[...]) "
                                  "with one of them)")], header="cannot assemble")

    def outputs(self, a, b, p, lam):
        out = dict(self.held)
        out.update((n, 0.0) for n in self.held_speeds)
        return out


class HeldRotor(Body):
    """A rotor (:class:`~mbcomp.modeling.roles.FlangeInertia`) whose joint was locked: its
    axial inertia ``J n n^T`` (kg m^2, no mass) on the frame it turned with, now a part of
    that rigid body (its gyroscopic moment acts, as on any body).

    Examples
    --------
    >>> from mbcomp.modeling.lock import HeldRotor
    >>> HeldRotor(J=2.0, n=(0, 0, 1)).mass_properties(HeldRotor(J=2.0, n=(0, 0, 1)).p)[2].diagonal().tolist()
    [0.0, 0.0, 2.0]
    """

    J = Param(1.0, unit="kg m^2", doc="axial moment of inertia", check="positive")
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), check="nonzero", doc="rotor axis, frame_a coordinates")

    def mass_properties(self, p):
        n = p.n / np.linalg.norm(p.n)
        return 0.0, np.zeros(3), p.J * np.outer(n, n)


def moving_joints(flat):
    """``{path: joint}`` of the joints of a flat model that have speeds and can be tree edges:
    what :func:`reduce` locks unless kept (contacts and rigid offsets are not moving joints)."""
    return {path: c for path, c in flat.components.items()
            if c.role == "joint" and c.nu > 0 and c.tree_edge}


def locked_joints(model):
    """``{joint path: {coordinate: value}}`` of the :class:`Locked` joints of ``model``
    (rad or m; a quaternion's entries 1), in model order: what :attr:`mbcomp.Model.locked` returns."""
    return {path: dict(c.held) for path, c in model.flatten().components.items() if isinstance(c, Locked)}


def _names_problem(flat, name, what):
    """The problem of a name that is no component of ``flat``: close names listed."""
    joints = list(moving_joints(flat))
    close = difflib.get_close_matches(name, joints, n=5, cutoff=0.5)
    hint = f"did you mean {', '.join(map(repr, close))}?" if close else \
        f"the model's joints: {', '.join(joints[:12])}{' ...' if len(joints) > 12 else ''}"
    if name.endswith(".free") and name[:-5] in flat.free:
        return Problem(name, f"is the implicit free joint of the body {name[:-5]!r} (added free=True): it is no "
                             "component of the model", f"join {name[:-5]} to the world by an explicit FreeMotion "
                                                        f"and {what} that")
    return Problem(repr(name), f"names no component of the model", f"{what} a joint by its path: {hint}")


def _resolve(flat, joints, what):
    """``{path: joint}`` of the named joints (paths or the components themselves), or the problems."""
    if isinstance(joints, (str, Joint)):
        joints = [joints]
    by_id = {id(c): p for p, c in flat.components.items()}
    out, probs = {}, []
    for j in joints:
        path = by_id.get(id(j)) if not isinstance(j, str) else j
        if path is None:
            probs.append(Problem(repr(j), "is no component of this model", f"{what} the model's own joints, by path"))
            continue
        comp = flat.components.get(path)
        if comp is None:
            probs.append(_names_problem(flat, path, what))
        elif comp.role != "joint":
            probs.append(Problem(path, f"is a {type(comp).__name__} ({comp.role}), not a joint",
                                 f"{what} joints only (Revolute, Prismatic, FreeMotion, ...)"))
        elif isinstance(comp, Locked):
            probs.append(Problem(path, "is locked already", f"{what} it once"))
        elif not comp.tree_edge or comp.nu == 0:
            kind = "a rigid offset" if comp.tree_edge else "a constraint-only joint (a contact)"
            probs.append(Problem(path, f"is {kind} ({type(comp).__name__}): it has no coordinates to hold",
                                 f"{what} joints with degrees of freedom"))
        else:
            out[path] = comp
    return out, probs


def _pose(path, joint, value):
    """``(q, R, r, problem)``: the joint's coordinates from ``value`` (None: its start values)
    and the pose ``relative(q, p)`` gives."""
    names = [n for n, _ in joint.coordinates]
    if value is None:
        q = np.array(joint.start(joint.p)[0], dtype=float)
    else:
        q = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
        if q.size != joint.nq:
            plural = "s" * (joint.nq != 1)
            return None, None, None, Problem(f"at[{path!r}]", f"has {q.size} value{'s' * (q.size != 1)}, the "
                                             f"{type(joint).__name__} has {joint.nq} coordinate{plural} "
                                             f"({', '.join(names)})", f"give {joint.nq} value{plural}, in that order")
        if not np.isfinite(q).all():
            return None, None, None, Problem(f"at[{path!r}]", f"{q.tolist()} is not finite", "give finite values")
    R, r = joint.relative(q, joint.p)
    R, r = np.array(R, dtype=float), np.array(r, dtype=float)
    wrong = rotation_matrix_problem(R)
    if wrong:
        return None, None, None, Problem(f"at[{path!r}]", f"the {type(joint).__name__}'s pose at {q.tolist()} "
                                         f"{wrong}", "give coordinates of a pose (a quaternion of unit length)")
    return q, R, r, None


def _on_flanges(flat, locked):
    """What hangs on the locked joints' flanges: ``(dropped, rotors, problems)``, with
    ``dropped`` ``{path: (why, the locked joints it was on)}``, ``rotors`` ``{path: (inertia, joint path, port)}``."""
    find, parent = flat.flange_groups()
    path_of = {id(c): p for p, c in flat.components.items()}  # paths in the model being locked (maybe nested)
    owner = {}  # group -> [(joint path, port name)]
    for x in list(parent):
        if x.component.role == "joint":
            owner.setdefault(find(x), []).append((path_of[id(x.component)], x.name))
    touched = {find(x) for x in list(parent)
               if x.component.role == "joint" and path_of[id(x.component)] in locked}
    elements = {}  # path -> (component, [its flange ports])
    for x in list(parent):
        if find(x) in touched and x.component.role != "joint":
            elements.setdefault(path_of[id(x.component)], (x.component, []))
    for path, (comp, ports) in elements.items():
        ports.extend(x for x in list(parent) if x.component is comp)
    dropped, rotors, probs = {}, {}, []
    for path, (comp, ports) in elements.items():
        joints = sorted({j for x in ports for j, _ in owner.get(find(x), [])})
        kept = [j for j in joints if j not in locked]
        held = [j for j in joints if j in locked]
        kind = type(comp).__name__
        if comp.role == "drive":
            probs.append(Problem(path, f"the {kind} drives joint {held[0]!r}, which is to be locked: a drive "
                                       "prescribes motion the lock forbids",
                                 f"remove {path} before locking, or keep {held[0]} free"))
        elif kept and comp.role in ("flange_force", "flange_constraint"):
            probs.append(Problem(path, f"the {kind} ties locked {', '.join(held)} to kept {', '.join(kept)}: the "
                                       "lock would hold or load the kept joint through it",
                                 f"lock {', '.join(kept)} too, or keep {', '.join(held)} free"))
        elif comp.role == "flange_inertia" and comp.reflected(comp.p):
            dropped[path] = (f"{kind} {path!r} on locked {', '.join(held)}: dropped (it turns at the joint's own "
                             "rate, which the lock makes zero)", held)
        elif comp.role == "flange_inertia":
            port = next(name for x in ports for j, name in owner.get(find(x), []) if j in locked)
            rotors[path] = (comp, held[0], port)
        elif comp.role in ("flange_force", "flange_constraint"):
            what = "its force acts inside the rigid body the lock makes" if comp.role == "flange_force" else \
                "the lock holds every flange it ties"
            dropped[path] = (f"{kind} {path!r} on locked {', '.join(held)}: dropped ({what})", held)
        else:  # a role with flanges this module has no rule for: refused rather than left on a flange that is gone
            probs.append(Problem(path, f"a {kind} (role {comp.role!r}) is on the flanges of locked {', '.join(held)}, "
                                       "and locking has no rule for that role", f"remove {path} before locking"))
    return dropped, rotors, probs


def _holders(flat, locked, at):
    """``{path: Locked}`` of the joints to lock at ``at``'s coordinates, or the problems."""
    holders, probs = {}, []
    at = dict(at or {})
    keys = {}
    path_of = {id(c): p for p, c in flat.components.items()}
    for k in at:
        path = k if isinstance(k, str) else path_of.get(id(k), repr(k))
        keys[path] = at[k]
        if path not in locked:
            probs.append(Problem(f"at[{path!r}]", "gives coordinates of a joint not being locked",
                                 f"add {path} to the joints to lock, or leave it out of at"))
    for path, joint in locked.items():
        q, R, r, wrong = _pose(path, joint, keys.get(path))
        if wrong:
            probs.append(wrong)
            continue
        modes = joint.modes(joint.p)  # declared: stops, stick-slip friction
        dropped = [f"{path}'s own modes ({type(modes).__name__}: its stops or friction)"] if modes is not None else []
        holders[path] = Locked(r=r, R=R, joint_class=type(joint).__name__, dropped=dropped,
                               held=zip((n for n, _ in joint.coordinates), q.tolist()),
                               speeds=[n for n, _ in joint.speeds], units=dict(joint.coordinates + joint.speeds))
    return holders, probs


def lock(model, joints, at=None):
    """A new model with ``joints`` held still (:meth:`mbcomp.Model.lock`, which documents it).

    Parameters
    ----------
    model : Model
        Not changed.
    joints : str, Joint or sequence of them
        The joints to lock, by path (``"arm.elbow"``) or as the model's components.
    at : dict, optional
        ``{joint: coordinates}`` (rad or m, the joint's coordinate order; a scalar for a
        1-DOF joint); a joint not in it is held at its start values (0 where none are given).

    Returns
    -------
    Model
        The copy, with :class:`Locked` joints, ``lock_notes`` (what was dropped) and
        :attr:`~mbcomp.Model.locked`.
    """
    flat = model.flatten()
    locked, probs = _resolve(flat, joints, "lock")
    holders, more = _holders(flat, locked, at)
    dropped, rotors, worse = _on_flanges(flat, locked)
    probs += more + worse
    if probs:
        raise ModelError(probs, header="cannot lock")
    notes = list(getattr(model, "lock_notes", []))
    for path, lk in holders.items():
        notes += [f"joint {path!r} locked: {d} no longer act" for d in lk.dropped]
        lk.dropped += tuple(why for why, held in dropped.values() if path in held)
    memo = {id(locked[p]): h for p, h in holders.items()}
    if model.parent is not None:  # a model nested in another: its copy stands alone (the enclosing one is not copied)
        memo[id(model.parent)] = None
    new = copy.deepcopy(model, memo)
    for path, h in holders.items():  # the lock takes the joint's place: its name, its owner's copy
        h.name, h.parent = locked[path].name, memo[id(locked[path].parent)]
    for path in list(dropped) + list(rotors):
        new.remove(path)
    notes += [why for why, _ in dropped.values()]
    notes += _held_rotors(new, flat, locked, holders, rotors, memo)
    new.lock_notes = notes
    fresh = notes[len(getattr(model, "lock_notes", [])):]
    if fresh:
        warnings.warn(f"model.lock: {len(fresh)} elements dropped or changed (model.lock_notes): "
                      + "; ".join(fresh[:4]) + (" ..." if len(fresh) > 4 else ""), UserWarning, stacklevel=3)
    return new


def _held_rotors(new, flat, locked, holders, rotors, memo):
    """Each rotor on a locked joint put back as a :class:`HeldRotor` body on the frame it turned
    with (frame_b for the joint's ``axis``, frame_a for its ``support``); the notes saying so."""
    notes = []
    for path, (inertia, jpath, port) in rotors.items():
        joint, holder = locked[jpath], holders[jpath]
        J, _ = inertia.rotor(inertia.p)
        n_a = np.asarray(joint.axis_world(np.eye(3), joint.p), dtype=float)
        n = holder.p.R.T @ n_a if port == "axis" else n_a
        owner = memo[id(inertia.parent)]
        body = owner.add(inertia.name, HeldRotor(J=J, n=n))
        owner.connect(body.frame_a, holder.frame_b if port == "axis" else holder.frame_a)
        notes.append(f"{type(inertia).__name__} {path!r} on locked {jpath}: kept as a body of inertia J n n^T on "
                     f"{jpath}.{'frame_b' if port == 'axis' else 'frame_a'}")
    return notes


def reduce(model, keep, at=None):
    """A new model with every moving joint locked but those in ``keep``: the complement of
    :meth:`mbcomp.Model.lock`, as Pinocchio's ``buildReducedModel`` (a humanoid's arm study
    without its legs and fingers).

    Parameters
    ----------
    model : Model
        Not changed.
    keep : sequence of str or Joint
        The joints that keep their freedom (paths, or the model's components).
    at : dict, optional
        ``{joint: coordinates}`` of locked joints (default: their start values, else 0).

    Returns
    -------
    Model
        As :meth:`~mbcomp.Model.lock` returns. Moving joints are the joints with speeds that
        can be tree edges (contacts stay); a body added ``free=True`` keeps its implicit
        free joint (lock an explicit ``FreeMotion``).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> a = m.add("a", Revolute()); b = m.add("b", Revolute())
    >>> pa = m.add("pa", PointMass()); pb = m.add("pb", PointMass())
    >>> m.connect(w.frame_b, a.frame_a); m.connect(a.frame_b, pa.frame_a)
    >>> m.connect(pa.frame_a, b.frame_a); m.connect(b.frame_b, pb.frame_a)
    >>> mbcomp.assemble(mbcomp.reduce(m, keep=["b"])).q_names
    ['b.phi']
    """
    flat = model.flatten()
    kept, probs = _resolve(flat, keep, "keep")
    if probs:
        raise ModelError(probs, header="cannot reduce")
    return lock(model, [p for p in moving_joints(flat) if p not in kept], at=at)
