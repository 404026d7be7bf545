"""Random mechanisms for the fuzz tests (``tests/fuzz``) and ``bench/fuzz.py``.

A mechanism is first drawn as a *spec*: plain nested dicts, lists and floats that hypothesis
prints when a case fails, so that ``build(spec)`` in a test reproduces it exactly. A spec is

* ``g``: gravity (m/s^2, world);
* ``bodies``: a tree of 1-8 bodies; body ``i`` hangs from ``parent`` (``-1``: the world, else
  an earlier body) through an optional rigid offset (``FixedTranslation`` by ``offset`` m, or
  ``FixedRotation`` by ``offset`` and the rotation of the unit quaternion ``rot``) and a joint
  of kind ``joint`` (every joint of the library: ``Revolute``, ``Prismatic``, ``Cylindrical``,
  ``Spherical``, ``FreeMotion``, ``Weld``) with axis ``axis`` (unit or not, never zero) and
  start values ``start``; the body is a ``RigidBody`` (mass ``m`` kg, centre ``r_cm`` m,
  inertia ``I`` kg m^2 about the centre: positive definite, triangle inequality held) or a
  ``PointMass`` (``m`` may be 0: a massless point) on a rigid ``arm`` (m) or at the joint;
* ``lines``: line springs and dampers between two body frames (``-1``: the world frame), with
  rate ``c`` (N/m, up to 1e7), damping ``d`` (N s/m) and unstretched length ``s0`` (m; 0 with
  coincident attachment points is the zero-length case);
* ``flanges``: rotational/translational spring-dampers, torques and forces (laws: a constant,
  a sine of time, a PD law) and prescribed motions on the 1-D joints' axes;
* ``loop``: ``None`` or a closing ``Spherical``/``Revolute`` between two bodies, built
  geometrically consistent at the start from the tree's own kinematics, then moved by
  ``misfit`` (m; non-zero: a loop that cannot close) with the tree's starts given as
  :class:`mbcomp.Guess` values when ``guess`` is set.

Component names: ``world``, ``j<i>`` (joints), ``b<i>`` (bodies), ``off<i>``, ``arm<i>`` (offsets),
``line<k>``, ``fl<k>``, ``loop``, ``loop_a``, ``loop_b``.

Examples
--------
>>> spec = {"g": (0.0, -9.81, 0.0), "bodies": [dict(parent=-1, offset=None, rot=None,
...          joint="Revolute", axis=(0.0, 0.0, 2.0), start={"phi0": 0.3, "w0": 0.0},
...          body="PointMass", m=1.0, r_cm=None, I=None)], "lines": [], "flanges": [], "loop": None}
>>> sorted(build(spec).components())
['b0', 'j0', 'world']
"""
from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

import mbcomp
from mbcomp import Guess
from mbcomp.library import (Damper, FixedRotation, FixedTranslation, Force, FreeMotion, PointMass, Prismatic,
                            PrescribedMotion, Revolute, RigidBody, RotationalSpringDamper, Spherical,
                            Spring, SpringDamper, Torque, TranslationalSpringDamper, Cylindrical, Weld, World)

JOINTS = {"Revolute": Revolute, "Prismatic": Prismatic, "Cylindrical": Cylindrical, "Spherical": Spherical,
          "FreeMotion": FreeMotion, "Weld": Weld}
ROTATIONAL = ("Revolute",)  # joints whose axis flange is rotational (Cylindrical has no flange)
TRANSLATIONAL = ("Prismatic",)

DOF = {"Revolute": 1, "Prismatic": 1, "Cylindrical": 2, "Spherical": 3, "FreeMotion": 6, "Weld": 0}

__all__ = ["mechanisms", "build", "tree_speeds", "JOINTS"]


def tree_speeds(spec):
    """The number of speeds of a spec's tree not prescribed by a drive (0: nothing moves
    freely, every joint welded or driven)."""
    driven = {f["joint"] for f in spec["flanges"] if f["kind"] == "prescribed"}
    return sum(DOF[b["joint"]] for i, b in enumerate(spec["bodies"]) if i not in driven)


# --- numbers ------------------------------------------------------------------------------
def _log(lo, hi):
    """Floats spread evenly in log10 between ``lo`` and ``hi`` (> 0)."""
    return st.floats(np.log10(lo), np.log10(hi)).map(lambda e: float(10.0 ** e))


_unit = st.floats(-1.0, 1.0, allow_subnormal=False)
_small = st.floats(-1.0, 1.0, allow_subnormal=False)


@st.composite
def _vector(draw, lo=0.05, hi=1.0):
    """A 3-vector of length in [lo, hi] (m), direction uniform enough."""
    v = np.array([draw(_unit) for _ in range(3)])
    while np.linalg.norm(v) < 1e-3:
        v = np.array([draw(_unit) for _ in range(3)]) + np.array([0.0, 0.0, 1.0])
    return tuple(float(x) for x in v / np.linalg.norm(v) * draw(st.floats(lo, hi)))


@st.composite
def _axis(draw):
    """A nonzero axis: a unit vector, a coordinate axis, or a scaled one (0.01..100)."""
    kind = draw(st.sampled_from(["unit", "coord", "scaled"]))
    if kind == "coord":
        v = [0.0, 0.0, 0.0]
        v[draw(st.integers(0, 2))] = draw(st.sampled_from([1.0, -1.0]))
        return tuple(v)
    v = np.array(draw(_vector(1.0, 1.0)))
    return tuple(float(x) for x in (v * draw(_log(0.01, 100.0)) if kind == "scaled" else v))


@st.composite
def _quaternion(draw):
    q = np.array([draw(_unit) for _ in range(4)]) + np.array([1e-3, 0.0, 0.0, 0.0])
    return tuple(float(x) for x in q / np.linalg.norm(q))


def rotation(q):
    """Rotation matrix of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@st.composite
def _inertia(draw, m):
    """A valid inertia about the centre (kg m^2) of mass ``m``: principal moments from
    nonnegative second moments (the triangle inequality holds), rotated at random; a
    slender body (one moment 1e-6 of the others) sometimes."""
    a, b, c = (draw(st.floats(0.01, 1.0)) for _ in range(3))
    if draw(st.integers(0, 9)) == 0:
        a = b = 1e-6 * c
    R = rotation(draw(_quaternion()))
    I = m * R @ np.diag([b + c, a + c, a + b]) @ R.T
    return tuple(tuple(float(x) for x in row) for row in 0.5 * (I + I.T))


# --- the parts of a spec ------------------------------------------------------------------
@st.composite
def _start(draw, joint):
    """Start values of one joint (rad, m, rad/s, m/s)."""
    phi, s, w, v = (draw(_small) for _ in range(4))
    if joint == "Revolute":
        return {"phi0": phi, "w0": 3 * w}
    if joint == "Prismatic":
        return {"s0": 0.3 * s, "v0": v}
    if joint == "Cylindrical":
        return {"phi0": phi, "w0": 3 * w, "s0": 0.3 * s, "v0": v}
    if joint == "Spherical":
        return {"R0": tuple(map(tuple, rotation(draw(_quaternion())))), "w0": tuple(draw(_vector(0.0, 3.0)))}
    if joint == "FreeMotion":
        return {"r0": tuple(draw(_vector(0.0, 1.0))), "v0": tuple(draw(_vector(0.0, 1.0))),
                "R0": tuple(map(tuple, rotation(draw(_quaternion())))), "w0": tuple(draw(_vector(0.0, 3.0)))}
    return {}


@st.composite
def _body(draw, i, nasty):
    """One body of the tree (see the module notes)."""
    joint = draw(st.sampled_from(sorted(JOINTS)))
    off = draw(st.sampled_from(["none", "translation", "rotation"]))
    m = draw(_log(1e-6, 1e6)) if nasty and draw(st.booleans()) else draw(st.floats(0.1, 10.0))
    # outside the nasty cases a point mass sits on a rigid arm of a joint that turns it about
    # one axis at most (on a spherical joint the rotation about the arm would carry no inertia)
    point = draw(st.integers(0, 3)) == 0 and (nasty or joint in ("Revolute", "Prismatic", "Cylindrical", "Weld"))
    if point and nasty and draw(st.integers(0, 2)) == 0:
        m = 0.0  # a massless point
    return dict(parent=draw(st.integers(-1, i - 1)),
                offset=None if off == "none" else draw(_vector(0.05, 1.0)),
                rot=draw(_quaternion()) if off == "rotation" else None,
                joint=joint, axis=draw(_axis()), start=draw(_start(joint)),
                body="PointMass" if point else "RigidBody", m=m,
                arm=draw(_vector(0.1, 1.0)) if point and (not nasty or draw(st.integers(0, 3))) else None,
                r_cm=None if point else draw(_vector(0.0, 0.5)), I=None if point else draw(_inertia(m)))


@st.composite
def _line(draw, n, nasty):
    """A line spring/damper between two frames (``-1``: the world)."""
    a = draw(st.integers(-1, n - 1))
    b = draw(st.integers(-1, n - 1).filter(lambda k: k != a))
    kind = draw(st.sampled_from(["Spring", "Damper", "SpringDamper"]))
    c = draw(_log(1e3, 1e7)) if nasty and draw(st.booleans()) else draw(_log(0.1, 100.0))
    s0 = 0.0 if draw(st.booleans()) else draw(st.floats(0.0, 1.0))
    return dict(kind=kind, a=a, b=b, c=c, d=draw(st.floats(0.0, 5.0)), s0=s0)


_LAWS = st.one_of(st.tuples(st.just("const"), st.floats(-5.0, 5.0)),
                  st.tuples(st.just("sine"), st.floats(-5.0, 5.0), st.floats(0.1, 20.0)),
                  st.tuples(st.just("pd"), st.floats(0.0, 50.0), st.floats(0.0, 5.0)))


@st.composite
def _flange(draw, bodies):
    """A flange element on a 1-D joint's axis, or ``None`` when the tree has none."""
    rot = [i for i, b in enumerate(bodies) if b["joint"] in ROTATIONAL]
    tra = [i for i, b in enumerate(bodies) if b["joint"] in TRANSLATIONAL]
    if not rot + tra:
        return None
    i = draw(st.sampled_from(rot + tra))
    kind = draw(st.sampled_from(["spring_damper", "effort", "effort", "prescribed"]))
    return dict(joint=i, rotational=i in rot, kind=kind, c=draw(_log(0.1, 1e4)), d=draw(st.floats(0.0, 5.0)),
                law=draw(_LAWS), amplitude=draw(st.floats(-1.0, 1.0)), rate=draw(st.floats(0.1, 10.0)))


@st.composite
def _loop(draw, n):
    a = draw(st.integers(-1, n - 1))
    return dict(a=a, b=draw(st.integers(0, n - 1).filter(lambda k: k != a)),
                joint=draw(st.sampled_from(["Spherical", "Revolute"])), d_a=draw(_vector(0.0, 0.5)),
                axis=draw(_axis()), misfit=draw(st.sampled_from([0.0, 0.0, 0.0, 0.3])),
                guess=draw(st.integers(0, 3)) > 0)


@st.composite
def mechanisms(draw, max_bodies=8, nasty=True, loops=0.25):
    """Strategy: a random mechanism spec (see the module notes) of 1 to ``max_bodies`` bodies;
    ``nasty`` lets extreme mass ratios, stiff springs and massless points in; ``loops`` is the
    share of mechanisms (of two bodies or more) with a loop closure."""
    n = draw(st.integers(2 if loops >= 1.0 else 1, max_bodies))
    bodies = [draw(_body(i, nasty)) for i in range(n)]
    lines = draw(st.lists(_line(n, nasty), max_size=2)) if n > 1 or draw(st.booleans()) else []
    flanges = [f for f in draw(st.lists(_flange(bodies), max_size=2)) if f is not None]
    g = draw(st.sampled_from([(0.0, -9.81, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, -9.81)]))
    loop = draw(_loop(n)) if n >= 2 and (loops >= 1.0 or draw(st.floats(0.0, 1.0)) < loops) else None
    return {"g": g, "bodies": bodies, "lines": lines, "flanges": flanges, "loop": loop}


# --- building -----------------------------------------------------------------------------
def _law(law):
    """A flange law ``f(t, x, xd)`` from its spec ``(kind, ...)``."""
    kind, a, *rest = law
    if kind == "const":
        return float(a)
    if kind == "sine":
        w = float(rest[0])
        return lambda t, x, xd: a * np.sin(w * t)
    d = float(rest[0])
    return lambda t, x, xd: -a * x - d * xd


def _tree(m, spec, guess=False):
    """Add the world and the tree of ``spec["bodies"]`` to model ``m``: the frames of the
    bodies (index -1: the world's)."""
    world = m.add("world", World(g=spec["g"]))
    frames, joints = [], []
    for i, b in enumerate(spec["bodies"]):
        parent = world.frame_b if b["parent"] < 0 else frames[b["parent"]]
        if b["offset"] is not None:
            off = (FixedTranslation(r=b["offset"]) if b["rot"] is None else
                   FixedRotation(r=b["offset"], R=rotation(b["rot"])))
            off = m.add(f"off{i}", off)
            m.connect(parent, off.frame_a)
            parent = off.frame_b
        start = {k: (Guess(v) if guess else v) for k, v in b["start"].items()}
        axis = {} if b["joint"] in ("Spherical", "FreeMotion", "Weld") else {"n": b["axis"]}
        j = m.add(f"j{i}", JOINTS[b["joint"]](**axis, **start))
        body = (PointMass(m=b["m"]) if b["body"] == "PointMass" else
                RigidBody(m=b["m"], r_cm=b["r_cm"], I=np.array(b["I"])))
        body = m.add(f"b{i}", body)
        m.connect(parent, j.frame_a)
        if b.get("arm") is not None:
            arm = m.add(f"arm{i}", FixedTranslation(r=b["arm"]))
            m.connect(j.frame_b, arm.frame_a)
            m.connect(arm.frame_b, body.frame_a)
        else:
            m.connect(j.frame_b, body.frame_a)
        frames.append(j.frame_b)
        joints.append(j)
    return world, frames, joints


def _poses(spec):
    """World poses ``(R, r)`` at the start of the bodies' frames, index -1 the world's, from
    the tree alone (assembled by mbcomp: its kinematics at the joints' start values)."""
    from mbcomp.modeling.component import PortRef

    m = mbcomp.Model()
    _tree(m, spec)
    system = mbcomp.assemble(m)
    jets = system.kinematics(0.0, system.default_q(), np.zeros(system.nu))
    comps = system.topology.flat.components
    out = {-1: (np.eye(3), np.zeros(3))}
    for i in range(len(spec["bodies"])):
        J = jets[system.topology.port_node[PortRef(comps[f"j{i}"], "frame_b", "frame")]]
        out[i] = (np.array(J.R), np.array(J.r))
    return out


def _close(m, spec, frames):
    """The loop of ``spec["loop"]``: frame a -> ``loop_a`` (offset ``d_a``) -> ``loop`` ->
    ``loop_b`` (an offset with rotation making frame b of the closure coincide with frame a
    at the start, moved by ``misfit`` along x) -> frame b."""
    lp = spec["loop"]
    poses = _poses(spec)
    (Ra, ra), (Rb, rb) = poses[lp["a"]], poses[lp["b"]]
    P = ra + Ra @ np.array(lp["d_a"])
    off_b = Rb.T @ (P - rb) + np.array([lp["misfit"], 0.0, 0.0])
    la = m.add("loop_a", FixedTranslation(r=lp["d_a"]))
    lb = m.add("loop_b", FixedRotation(r=tuple(off_b), R=Rb.T @ Ra))
    closing = (Spherical(R0=Guess(np.eye(3))) if lp["joint"] == "Spherical" else
               Revolute(n=lp["axis"], phi0=Guess(0.0)))
    j = m.add("loop", closing)
    m.connect(frames[lp["a"]], la.frame_a)
    m.connect(la.frame_b, j.frame_a)
    m.connect(frames[lp["b"]], lb.frame_a)
    m.connect(lb.frame_b, j.frame_b)


def _flange_element(f):
    """The component of a flange spec."""
    if f["kind"] == "spring_damper":
        return (RotationalSpringDamper(c=f["c"], d=f["d"]) if f["rotational"] else
                TranslationalSpringDamper(c=f["c"], d=f["d"]))
    if f["kind"] == "prescribed":
        return PrescribedMotion(s=f"{f['amplitude']!r}*sin({f['rate']!r}*t)")
    return Torque(tau=_law(f["law"])) if f["rotational"] else Force(f=_law(f["law"]))


def build(spec):
    """The :class:`mbcomp.Model` of a spec (see the module notes)."""
    m = mbcomp.Model()
    world, frames, joints = _tree(m, spec, guess=bool(spec["loop"] and spec["loop"]["guess"]))
    frames = dict(enumerate(frames))
    frames[-1] = world.frame_b
    for k, ln in enumerate(spec["lines"]):
        comp = {"Spring": lambda: Spring(c=ln["c"], s_unstretched=ln["s0"]), "Damper": lambda: Damper(d=ln["d"]),
                "SpringDamper": lambda: SpringDamper(c=ln["c"], d=ln["d"], s_unstretched=ln["s0"])}[ln["kind"]]()
        comp = m.add(f"line{k}", comp)
        m.connect(frames[ln["a"]], comp.frame_a)
        m.connect(frames[ln["b"]], comp.frame_b)
    for k, f in enumerate(spec["flanges"]):
        comp = m.add(f"fl{k}", _flange_element(f))
        j = joints[f["joint"]]
        m.connect(comp.flange_b, j.axis)
        if f["kind"] == "spring_damper":
            m.connect(comp.flange_a, j.support)
    if spec["loop"] is not None:
        _close(m, spec, frames)
    return m
