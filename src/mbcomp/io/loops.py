"""Loop closures of imported robots: one cut joint between two bodies' frames, exact.

Both importers close a kinematic loop the same way (:func:`close_loop`): a library joint
between two frames, each placed by a rigid offset on a link's (body's) frame. mbcomp keeps a
loop as exact constraint rows (``Phi = 0`` held by the assembly, no springs, no softness);
which joint of a loop the topology cuts is its choice (:mod:`mbcomp.assembly.topology`: the
joint with most freedom, so the fewest rows), and redundant rows (a planar four-bar closed
by a hinge) are found and explained by ``mbcomp.assemble(model).summary()`` as for any model.

Kinds of closure (the joint named by the caller):

- ``"point"``: the two frames' origins coincide, rotation free -> ``Spherical`` (MJCF
  ``<equality><connect>``, a URDF spherical loop joint);
- ``"weld"``: the two frames coincide -> ``Weld`` (MJCF ``<weld>``, a URDF fixed loop joint);
- ``"hinge"``: origins coincide, frame_b turns about ``axis`` (frame_a coordinates) ->
  ``Revolute(n=axis)`` (a URDF revolute or continuous loop joint: a parallel mechanism);
- ``"slider"``: frame_b slides along ``axis`` -> ``Prismatic(n=axis)``.
"""
import numpy as np

__all__ = ["close_loop", "LOOP_KINDS"]

#: the closures :func:`close_loop` makes, and the library joint of each
LOOP_KINDS = {"point": "Spherical", "weld": "Weld", "hinge": "Revolute", "slider": "Prismatic"}


def _offset(model, lib, name, frame, pose):
    """``frame`` moved by ``pose = (r, R)`` (m, rad; in ``frame``'s axes): a rigid offset named
    ``name``, or ``frame`` itself when ``pose`` is None or the identity."""
    if pose is None:
        return frame
    r, R = np.asarray(pose[0], dtype=float), np.asarray(pose[1], dtype=float)
    rotated = not np.array_equal(R, np.eye(3))
    if not rotated and not r.any():
        return frame
    off = model.add(name, lib.FixedRotation(r=r, R=R) if rotated else lib.FixedTranslation(r=r))
    model.connect(frame, off.frame_a)
    return off.frame_b


def close_loop(model, name, kind, frame_a, frame_b, pose_a=None, pose_b=None, axis=(1.0, 0.0, 0.0),
               offset_names=None, R0=None):
    """Close a kinematic loop of ``model``: a cut joint ``name`` between two frames.

    Parameters
    ----------
    model : Model
        The model the loop's components are added to.
    name : str
        The joint's component name (its rigid offsets are ``<name>_a`` and ``<name>_b``).
    kind : {"point", "weld", "hinge", "slider"}
        What the closure holds (module notes, :data:`LOOP_KINDS`).
    frame_a, frame_b : port
        Frame ports of two bodies (or of anything rigidly on them), already in the model.
    pose_a, pose_b : (r, R) or None
        Where the joint's frame_a (frame_b) sits in ``frame_a`` (``frame_b``): origin ``r`` (m)
        and axes ``R`` (3x3, joint axes -> frame axes). None: the frame itself.
    axis : (3,)
        Hinge or slider axis in the joint's frame_a coordinates (``"hinge"``, ``"slider"``).
    offset_names : (str, str) or None
        Names of the two rigid offsets; default ``<name>_a``, ``<name>_b``.
    R0 : (3, 3) or None
        ``"point"``: the joint's frame_b axes relative to its frame_a axes in the mechanism's
        start pose (frame_b -> frame_a), as a ``Guess`` start of the ``Spherical`` (used where
        the topology keeps it in the tree: it places the bodies beyond it); None: the identity.

    Returns
    -------
    Component
        The joint added (a ``Spherical``, ``Weld``, ``Revolute`` or ``Prismatic``).

    Examples
    --------
    A pendulum whose tip is pinned to the world by a point closure: one loop, three rows,
    two of them redundant with the hinge (the motion is planar); none moves.

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, RigidBody
    >>> from mbcomp.io.loops import close_loop
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("hinge", Revolute(n=(0, 0, 1))); b = m.add("arm", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=np.eye(3) * 0.01))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> c = close_loop(m, "pin", "point", w.frame_b, b.frame_a, pose_a=((1.0, 0, 0), np.eye(3)), pose_b=((1.0, 0, 0), np.eye(3)))
    >>> system = mbcomp.assemble(m)
    >>> type(c).__name__, system.topology.cut, "degrees of freedom: 0" in system.summary()
    ('Spherical', ['pin'], True)
    """
    from mbcomp import Guess, library as lib

    if kind not in LOOP_KINDS:
        raise ValueError(f"loop closure {name!r}: kind {kind!r} is not one of {sorted(LOOP_KINDS)}")
    na, nb = offset_names or (f"{name}_a", f"{name}_b")
    a = _offset(model, lib, na, frame_a, pose_a)
    b = _offset(model, lib, nb, frame_b, pose_b)
    if kind == "point":
        joint = lib.Spherical() if R0 is None else lib.Spherical(R0=Guess(np.asarray(R0, dtype=float)))
    elif kind == "weld":
        joint = lib.Weld()
    elif kind == "hinge":
        joint = lib.Revolute(n=np.asarray(axis, dtype=float))
    else:
        joint = lib.Prismatic(n=np.asarray(axis, dtype=float))
    j = model.add(name, joint)
    model.connect(a, j.frame_a)
    model.connect(j.frame_b, b)
    return j
