"""Each library component's default picture: the component staged in the smallest model that
holds it, simulated for an instant and drawn by mbcomp's own renderer (``Result.snapshot``)
with the helpers of the stage hidden, so what is seen is the component's ``visuals``.

Pictures are cached on disk under a key of the class's source (its whole MRO within mbcomp),
the renderer's and this file's, so a rebuild draws only the components whose code changed.
A component that draws nothing of its own (a sensor, a gear, a force law on a flange) or that
cannot be staged alone gets no picture and a note saying why.

Examples
--------
>>> from mbcomp.library import Revolute, IdealGear
>>> stage(Revolute)[1]          # the helpers hidden in the picture
['world', 'body']
>>> stage(IdealGear) is None    # a flange constraint has no shapes of its own
True
"""
from __future__ import annotations

import hashlib
import inspect
import os
import pathlib
import shutil
import tempfile

import numpy as np

__all__ = ["stage", "picture_key", "draw", "picture", "no_picture_reason"]

_HERE = pathlib.Path(__file__).resolve()


def _draws(cls):
    """Whether the class overrides ``visuals`` (draws shapes of its own)."""
    import mbcomp

    return cls.visuals is not mbcomp.Component.visuals


def no_picture_reason(cls):
    """Why ``cls`` has no picture (``None`` when it has one)."""
    import mbcomp

    if issubclass(cls, mbcomp.Model):
        return None if cls.__name__ in _COMPOSITES else "an assembly: see the components it is made of"
    if not _draws(cls):
        return "draws no shapes of its own: it is seen through the components it joins"
    if stage(cls) is None:
        return "cannot be drawn alone"
    return None


def _body():
    from mbcomp.library import RigidBody

    return RigidBody(m=1.0, r_cm=(0.1, 0, 0), I=np.diag([1e-3, 2e-3, 2e-3]))


def _ground(m, cls):
    from mbcomp.library import PointMass

    w = m.add("world", cls())
    m.add("body", PointMass(m=1.0), free=True)
    return w, ["body"]


def _free_body(m, cls):
    from mbcomp.library import World

    m.add("world", World(g=(0, 0, 0)))
    m.add("body", cls(), free=True)
    return ["world"]


def _joint(m, cls):
    from mbcomp.library import World

    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("joint", cls())
    b = m.add("body", _body())
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return ["world", "body"]


def _contact(m, cls):
    """A wheel or ball (the contact draws it) on the ground plane, standing on it."""
    import mbcomp
    from mbcomp.library import FreeMotion, World

    c = cls()
    r = float(getattr(c.p, "r", 0.1) or 0.1)
    w = m.add("world", World(g=(0, 0, -9.81)))
    free = m.add("free", FreeMotion(r0=mbcomp.Guess((0, 0, r))))
    b = m.add("body", _body())
    m.add("contact", c)
    m.connect(w.frame_b, free.frame_a)
    m.connect(free.frame_b, b.frame_a)
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, b.frame_a)
    return ["world", "free", "body"]


def _force(m, cls):
    """A two-frame force element between the ground and a body 0.5 m away on a slider."""
    from mbcomp.library import Prismatic, World

    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("slider", Prismatic(n=(1, 0, 0), s0=0.5))
    b = m.add("body", _body())
    f = m.add("element", cls())
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    m.connect(w.frame_b, f.frame_a)
    m.connect(b.frame_a, f.frame_b)
    return ["world", "slider", "body"]


def _flange_inertia(m, cls):
    """A rotor on a hinge's axis."""
    from mbcomp.library import Fixed, Revolute

    base = m.add("base", Fixed())
    j = m.add("hinge", Revolute())
    rotor = m.add("rotor", cls())
    m.connect(base.frame_b, j.frame_a)
    m.connect(rotor.flange, j.axis)
    return ["base", "hinge"]


def _composite(m, cls):
    """An assembly joined to the ground by its ``plane`` frame (RollingDisk, RollingSphere)."""
    from mbcomp.library import World

    w = m.add("world", World(g=(0, 0, -9.81)))
    c = m.add("part", cls())
    m.connect(w.frame_b, c.plane)
    return ["world"]


_COMPOSITES = {"RollingDisk", "RollingSphere"}


def stage(cls):
    """``(model, hidden)``: a small model holding one default ``cls`` and the names of the
    helper components the picture hides; ``None`` for a class that draws nothing alone."""
    import mbcomp

    m = mbcomp.Model()
    if cls.__name__ in _COMPOSITES:
        return m, _composite(m, cls)
    if issubclass(cls, mbcomp.Model) or not _draws(cls):
        return None
    ports = cls.ports()
    frames = [n for n, p in ports.items() if type(p).__name__ == "Frame"]
    if cls.role == "ground":
        _, hidden = _ground(m, cls)
        return m, hidden
    if cls.role == "body":
        return m, _free_body(m, cls)
    if cls.role == "joint" and (getattr(cls, "draws_body", False) or getattr(cls, "tree_edge", True) is False):
        return m, _contact(m, cls)
    if cls.role == "joint" and frames == ["frame_a", "frame_b"]:
        return m, _joint(m, cls)
    if cls.role == "force" and frames == ["frame_a", "frame_b"]:
        return m, _force(m, cls)
    if cls.role == "flange_inertia":
        return m, _flange_inertia(m, cls)
    return None


def _source(obj):
    try:
        return inspect.getsource(obj)
    except (OSError, TypeError):
        return repr(obj)


def picture_key(cls):
    """A digest of what a picture depends on: the class's source and its bases' within
    mbcomp, the renderer's and the scene's, and this file's."""
    import mbcomp.visual.render as render
    import mbcomp.visual.scene as scene

    h = hashlib.sha256()
    for klass in cls.__mro__:
        if klass.__module__.startswith("mbcomp"):
            h.update(_source(klass).encode())
    for mod in (render, scene):
        h.update(_source(mod).encode())
    h.update(_HERE.read_bytes())
    return h.hexdigest()[:16]


def draw(cls, path):
    """Stage ``cls``, simulate an instant and write its picture to ``path``; an error when
    the picture would not show the component (its stage hides it, or it draws nothing)."""
    import warnings

    import mbcomp
    from mbcomp.visual.render import frame_geometry, write_picture
    from mbcomp.visual.scene import build_scene

    model, hidden = stage(cls)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = mbcomp.simulate(model, t_end=1e-3, n_out=2, backend="numeric")
    scene = build_scene(res, hide=hidden, title=cls.__name__)
    shown = {d.component.split(".")[0] for d in frame_geometry(scene, 0.0)}
    if not shown or shown & set(hidden):
        raise RuntimeError(f"the picture of {cls.__name__} would show {sorted(shown) or 'nothing'}, not the "
                           f"component alone: fix its stage in docs/_ext/component_pictures.py")
    return write_picture(scene, os.fspath(path), t=0.0)


def picture(cls, cache_dir):
    """The cached picture of ``cls`` (a path in ``cache_dir``), drawn if missing; ``None`` and
    the reason when it has none."""
    why = no_picture_reason(cls)
    if why is not None:
        return None, why
    cache_dir = pathlib.Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    path = cache_dir / f"{cls.__name__}-{picture_key(cls)}.png"
    if not path.exists():
        fd, tmp = tempfile.mkstemp(suffix=".png", dir=cache_dir)
        os.close(fd)
        try:
            draw(cls, tmp)
            shutil.move(tmp, path)  # whole files only: a parallel build never reads half a picture
            for stale in cache_dir.glob(f"{cls.__name__}-*.png"):  # the pictures of earlier sources
                if stale != path:
                    stale.unlink(missing_ok=True)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return path, None
