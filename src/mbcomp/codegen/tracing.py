"""What the two tracers share: the traced system, its parameters, drives and coordinate rates.

Both the program tracer (:mod:`mbcomp.codegen.tracer`, :class:`~mbcomp.codegen.graph.Sym`
scalars) and the symbolic one (:mod:`mbcomp.codegen.symbolic`, sympy scalars) run the
system's own numeric :meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_numeric` on
traced values. They build the system they trace the same way (:func:`traced_system`):

* parameter values: the assembled system's, with the traced ones put in
  (:func:`traced_params`; :func:`parameter_entries` lists what a tracer may trace);
* drives: a drive's law is not traced through the component -- its motion ``(s, v, a)`` is
  given to a stand-in (:class:`DriveInputs`): three program inputs evaluated numerically at
  every call, or the law's exact expressions;
* gravity: recomputed from the traced parameters of the gravity source.

A failure while tracing is blamed on its component with :func:`mbcomp.modeling.blame.blame`.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.tracing import traced_params, traced_system
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> system = mbcomp.assemble(m)
>>> moon = traced_system(system, traced_params(system, {"world": {"g": np.array([0, 0, -1.62])}}))
>>> float(moon.evaluate(0.0, np.zeros(1), np.zeros(1)).f[0]), float(system.g[2])   # the original is unchanged
(-3.24, -9.81)
"""
from __future__ import annotations

import copy
import functools
import types
from types import SimpleNamespace

import numpy as np

__all__ = ["DriveInputs", "drives", "parameter_entries", "traced_params", "traced_system", "q_rates", "law_codes"]


class DriveInputs:
    """Stands in for a drive while tracing: its motion is the given ``(s, v, a)``.

    Everything else (name, path, parameters) is the drive's.

    Examples
    --------
    >>> from mbcomp.codegen.tracing import DriveInputs
    >>> from mbcomp.library import PrescribedMotion
    >>> d = PrescribedMotion(s="t**2")
    >>> DriveInputs(d, ("s", "v", "a")).motion(2.0, d.p), d.motion(2.0, d.p)
    (('s', 'v', 'a'), (4.0, 4.0, 2.0))
    """

    def __init__(self, comp, sva):
        self.comp, self.sva = comp, tuple(sva)

    def motion(self, t, p):
        return self.sva

    def __getattr__(self, name):
        return getattr(self.comp, name)


def drives(system):
    """Names of the drives, in the order of the tree joints they drive (each drive drives one
    tree joint).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.tracing import drives
    >>> from mbcomp.library import World, Revolute, PrescribedMotion, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute())
    >>> d = m.add("d", PrescribedMotion(s="t")); b = m.add("b", PointMass())
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a); m.connect(d.flange_b, j.axis)
    >>> drives(mbcomp.assemble(m))
    ['d']
    """
    return list(dict.fromkeys(e.drive for e in system.topology.tree if e.drive))


def _codes(code, out, name):
    """``code`` and the code objects defined inside it (a law's helpers, comprehensions)."""
    out[code] = name
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            _codes(c, out, name)


def law_codes(system):
    """``{code object: "component.param"}`` of every law of ``system``: a parameter value that is
    a Python function, a bound method, a ``functools.partial`` of one or a callable object whose
    ``__call__`` is one, with the code defined inside them (what a tracer attributes a decision
    to: :attr:`mbcomp.codegen.graph.Graph.law_codes`).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation, Torque
    >>> def tau(t, phi, w):
    ...     return 1.0 if phi > 0 else -1.0
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute())
    >>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); b = m.add("b", PointMass(m=1.0))
    >>> motor = m.add("motor", Torque(tau=tau))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, b.frame_a)
    >>> m.connect(j.axis, motor.flange_b)
    >>> law_codes(mbcomp.assemble(m))[tau.__code__]
    'motor.tau'
    """
    out = {}
    for path, p in system.P.items():
        for pname, v in vars(p).items():
            if isinstance(v, functools.partial):
                v = v.func
            fn = v.__func__ if isinstance(v, types.MethodType) else v
            if not isinstance(fn, types.FunctionType) and callable(fn) and not isinstance(fn, type):
                fn = getattr(type(fn), "__call__", None)
            if isinstance(fn, types.FunctionType):
                _codes(fn.__code__, out, f"{path}.{pname}")
    return out


def parameter_entries(system):
    """``(path, name, kind, value)`` of every parameter of every component but the drives
    (their motion is an input), sorted by path and name; ``kind`` is the declared
    :class:`~mbcomp.modeling.component.Param` kind (``"number"`` when undeclared).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.tracing import parameter_entries
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); s = m.add("s", Prismatic()); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> [(path, name, kind) for path, name, kind, _ in parameter_entries(mbcomp.assemble(m)) if path == "b"]
    [('b', 'm', 'number')]
    """
    owners = system.owners()
    driving = set(drives(system))
    declared = {}  # class -> its parameters: params() copies them at each call (~1 us; 60 components at N = 20)
    for path in sorted(system.P):
        if path in driving:
            continue
        decl = declared.get(type(owners[path]))
        if decl is None:
            decl = declared[type(owners[path])] = owners[path].params()
        for name, value in sorted(vars(system.P[path]).items()):
            par = decl.get(name)
            yield path, name, (par.kind if par is not None else "number"), value


def traced_params(system, values):
    """The system's parameter values ``{path: namespace}`` with ``values`` (``{path: {name:
    value}}``) put in; the namespaces of other components are the system's own.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.tracing import traced_params
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); s = m.add("s", Prismatic()); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> P = traced_params(system, {"b": {"m": "traced"}})
    >>> P["b"].m, system.P["b"].m, P["s"] is system.P["s"]
    ('traced', 2.0, True)
    """
    P = dict(system.P)
    for path, vals in values.items():
        P[path] = SimpleNamespace(**{**vars(P[path]), **vals})
    return P


def traced_system(system, P, drive_motion=None):
    """The system a tracer evaluates: ``system`` with parameter values ``P``, gravity from
    ``P``, and each drive replaced by a :class:`DriveInputs` whose motion is
    ``drive_motion(path, drive, P[path])`` (default: the drive's own motion is traced).

    The result is numeric (:class:`~mbcomp.assembly.system.NumericEvaluator`) even if ``system`` was
    compiled; ``system`` itself is not changed. An exception of a component (a drive's motion,
    the gravity law) propagates for the tracer to blame.
    """
    topo = system.topology
    topology = None
    if drive_motion is not None and drives(system):
        comps = dict(topo.flat.components)
        for path in drives(system):
            comps[path] = DriveInputs(comps[path], drive_motion(path, comps[path], P[path]))
        topology = copy.copy(topo)  # the same topology (and its methods), other components
        topology.flat = copy.copy(topo.flat)
        topology.flat.components = comps
    g = None
    if topo.gravity_source:
        g = topo.flat.components[topo.gravity_source].gravity(P[topo.gravity_source])
        g = np.zeros(3) if g is None else np.asarray(g)
        if g.dtype != object:
            g = g.astype(float)
    return system.variant(topology=topology, P=P, g=g)


def q_rates(system, q, u):
    """The traced ``dq/dt`` (a list, one entry per coordinate): ``u``'s own entries for joints
    whose rates are their speeds, else the joint's ``q_rate`` on the traced values.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen.tracing import q_rates
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); s = m.add("s", Prismatic()); b = m.add("b", PointMass())
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> u = np.array(["v"], dtype=object)
    >>> q_rates(mbcomp.assemble(m), np.array(["s"], dtype=object), u)
    ['v']
    """
    from ..modeling.roles import Joint

    out = [None] * system.nq
    for e in system.topology.tree:
        if e.q.stop > e.q.start:
            if type(e.comp).q_rate is Joint.q_rate:  # the default: dq/dt = u
                vals = u[e.u]
            else:
                vals = e.comp.q_rate(q[e.q], u[e.u], system.P[e.name])
            out[e.q.start:e.q.stop] = list(vals)
    return out
