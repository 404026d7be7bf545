"""Tracing a system into a :class:`~mbcomp.codegen.graph.Graph`: the runtime parameters, the
drive inputs, and one run of the numeric evaluation on :class:`~mbcomp.codegen.graph.Sym`
scalars.

:func:`trace` runs :meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_numeric` (unmasked)
and the coordinate rates once at a generic state (:func:`trace_point`) on a traced copy of the
system (:func:`mbcomp.codegen.tracing.traced_system`) whose inputs are

* ``q``, ``u``, ``t``: the state;
* ``d``: the ``(s, v, a)`` of every drive, evaluated numerically at every call;
* ``p``: every nonzero entry of a numeric parameter (:func:`param_layout`); zero entries stay
  zeros and fold away, so which entries are zero is part of the program's *signature*, with
  the shapes and the laws (callables, strings) that are traced as they are.

Examples
--------
>>> import mbcomp
>>> from mbcomp.codegen.tracer import param_layout, trace
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> system = mbcomp.assemble(m)
>>> param_layout(system)[0]       # the runtime parameters: axis z, mass, gravity z
[('b', 'm', None), ('s', 'n', (np.int64(2),)), ('world', 'g', (np.int64(2),))]
>>> tr = trace(system, max_nodes=1000)
>>> tr.shapes["M"], [o.v for o in tr.groups["eval"][:2]]    # M = m, f = m g
((1, 1), [2.0, -19.62])
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..assembly.outputs import output_values, tolerance_terms
from ..assembly.recursive import SingularTree, lagrange_accelerations, tree_evaluation
from ..modeling.blame import blame
from ..modeling.inputs import traced_inputs
from .graph import CodegenError, Graph, Sym
from .tracing import drives, law_codes, parameter_entries, q_rates, traced_params, traced_system

__all__ = ["FIELDS", "param_layout", "param_signature", "param_vector", "trace_point", "trace"]

#: the fields of an evaluation a program computes, in the order of its flat output
FIELDS = ("M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi")

_FIX = ("write its laws with numpy functions (np.sin, np.sqrt, ...) and plain arithmetic instead of math.* or "
        "float(), or keep the numeric evaluation for this model (do not compile it)")


def _law_key(v):
    try:
        hash(v)
        return ("v", v)
    except TypeError:
        return ("id", id(v))


def _traced_kind(kind, val):
    """``"s"`` (a float scalar) or ``"a"`` (a float array) if the entry is traced, else None."""
    if kind not in ("number", "law"):
        return None
    if isinstance(val, (float, np.floating)):
        return "s"
    if isinstance(val, np.ndarray) and val.dtype.kind == "f":
        return "a"
    return None


def param_layout(system, keep=()):
    """Which parameter entries are runtime inputs, and the structural signature of the rest.

    Returns ``(layout, signature)``: ``layout`` lists ``(path, name, index)`` of every nonzero
    numeric parameter entry (``index`` None for scalars), and of every entry of the
    parameters ``keep`` (``(path, name)`` pairs: zeros too, so that a program can be
    differentiated with respect to them); ``signature`` is hashable and changes when anything
    baked into a program changes (zero pattern, shapes, laws, kept parameters)."""
    return _layout(system, keep, True)


def param_signature(system, keep=()):
    """``param_layout(system, keep)[1]``, the signature alone (without the layout's indices:
    half the time; what a program's cache key and its binding compare).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> param_signature(system) == param_layout(system)[1]
    True
    """
    return _layout(system, keep, False)[1]


def _layout(system, keep, indices):
    """``(layout, signature)`` of :func:`param_layout`; the layout empty unless ``indices``."""
    layout, sig = [], []
    keep = frozenset(keep)
    for path, name, kind, val in parameter_entries(system):  # _traced_kind inlined: ~1,000 entries at N = 100
        if kind == "number" or kind == "law":
            if type(val) is float or isinstance(val, (float, np.floating)):
                on = bool(val != 0 or (keep and (path, name) in keep))
                if on and indices:
                    layout.append((path, name, None))
                sig.append((path, name, "s", on))
                continue
            if isinstance(val, np.ndarray) and val.dtype.kind == "f":
                if keep and (path, name) in keep:
                    nz = (val != 0) | True
                else:
                    nz = val.astype(bool)  # != 0 (NaN too), 5x faster on a 3-vector
                if indices:
                    layout.extend((path, name, idx) for idx in zip(*nz.nonzero()))
                sig.append((path, name, "a", val.shape, nz.tobytes()))
                continue
        elif kind == "start":
            continue
        sig.append((path, name, "o", _law_key(val)))
    return layout, tuple(sig)


def param_vector(system, layout):
    """The values of the runtime parameters ``layout`` (see :func:`param_layout`) of ``system``."""
    P = system.P
    return [float(getattr(P[path], name)) if idx is None else float(getattr(P[path], name)[idx])
            for path, name, idx in layout]


def trace_point(system):
    """A generic state for the trace-time values: the start coordinates, nonzero speeds."""
    q = system.normalize(system.default_q())
    k = np.arange(system.nu)
    u = 0.3 * np.sin(1.7 * k + 0.4) + 0.05
    return 0.1234, q, u


def _param_inputs(g, system, layout):
    """The system's parameter values with every runtime entry (``layout``) a ``p`` input of ``g``."""
    pindex = {key: k for k, key in enumerate(layout)}
    values = {}
    for path, name, kind, val in parameter_entries(system):
        traced = _traced_kind(kind, val)
        if traced == "s" and (path, name, None) in pindex:
            values.setdefault(path, {})[name] = g.input("p", pindex[(path, name, None)], val, state=False)
        elif traced == "a":
            arr = np.zeros(val.shape, dtype=object)
            arr[...] = 0.0
            for idx in (k[2] for k in layout if k[:2] == (path, name)):
                arr[idx] = g.input("p", pindex[(path, name, idx)], val[idx], state=False)
            values.setdefault(path, {})[name] = arr
    return traced_params(system, values)


def _untraceable(exc):
    """The CodegenError for an exception raised while tracing, naming the component."""
    b = blame(exc)
    at = f"at {b.where}" if b.where != "?" else "in the framework"
    if b.component is not None:
        comp = b.component
        return CodegenError(f"cannot generate a program for component {comp.path!r} ({type(comp).__name__}): "
                            f"{type(exc).__name__}: {exc} ({at}) -> fix: {_FIX}")
    return CodegenError(f"cannot trace the model's evaluation ({type(exc).__name__}: {exc} {at}) -> fix: {_FIX}")


def trace(system, max_nodes, program="eval", baumgarte=True, keep=(), hidden=True):
    """See :func:`_trace`; the right-hand side (``program="fun"``) and the result columns
    (``"outputs"``) first try the drives' motion laws traced into the program (no per-call
    inputs: the C engine can step it, an exported FMU can hold it), and fall back to their
    ``(s, v, a)`` as inputs when a law cannot be traced. ``hidden``: the result columns with
    the post-processing's hidden ones (:func:`mbcomp.assembly.outputs.tolerance_terms`; an
    FMU's outputs leave them out)."""
    if program in ("fun", "outputs") and drives(system):
        try:
            return _trace(system, max_nodes, program, baumgarte, inline_drives=True, keep=keep, hidden=hidden)
        except CodegenError:
            pass  # a drive law a program cannot hold: evaluated in Python at every call
    return _trace(system, max_nodes, program, baumgarte, keep=keep, hidden=hidden)


def _trace(system, max_nodes, program="eval", baumgarte=True, inline_drives=False, keep=(), hidden=True):
    """Trace the evaluation and the coordinate rates of ``system`` (``program="eval"``), or
    the coordinate rates and the Lagrange right-hand side with the system's row mask
    (``program="fun"``: output group ``"fun"``, absent when the trace point is singular), or
    the result columns (``program="outputs"``: group ``"outputs"``, the columns of
    :func:`~mbcomp.assembly.outputs.output_values` then each body's rotation matrix row by
    row, named by ``output_names`` and ``rotation_paths``; the multipliers' Baumgarte gains
    are inputs as in ``"fun"`` when ``baumgarte``; absent when the trace point is singular).
    ``keep``: parameters ``(path, name)`` made inputs even where zero (see :func:`param_layout`).

    Returns a namespace: ``graph``, the output ``groups`` (``"eval"``: the :data:`FIELDS`
    flattened, ``"qrate"``), their ``guard_groups``, the fields' ``shapes``, the parameter
    ``layout`` and ``signature``, the ``drives`` in input order, the external ``inputs``
    (:class:`~mbcomp.modeling.inputs.Input`, by slot: ``d[3 n_drives + 2 + k]``), the ``baked`` parameter names
    and ``qrate_identity`` (``dq/dt = u``). Raises :class:`CodegenError` naming the component
    whose code cannot be traced."""
    layout, sig = param_layout(system, keep)
    t0, q0, u0 = trace_point(system)
    if program == "outputs":
        system.constraint_names()  # the rows' names (structure only), computed numerically once
    g = Graph(max_nodes)
    g.law_codes = law_codes(system)  # a decision a law takes is told apart (an FMU cannot hold one on a state)
    order = []

    def drive_inputs(path, comp, p):  # (s, v, a) are inputs, evaluated numerically at every call
        k = len(order)
        order.append(path)
        s, v, a = comp.motion(t0, p)
        return g.input("d", 3 * k, s), g.input("d", 3 * k + 1, v), g.input("d", 3 * k + 2, a)

    inputs = {}  # name -> (Input, node): per-call inputs after the drives and the two gains

    def input_node(inp):
        if inp.name not in inputs:
            inputs[inp.name] = (inp, g.input("d", 3 * len(order) + 2 + len(inputs), inp.value(t0)))
        return inputs[inp.name][1]

    with g, traced_inputs(input_node):
        try:
            ts = traced_system(system, _param_inputs(g, system, layout), None if inline_drives else drive_inputs)
            q = np.array([g.input("q", k, v) for k, v in enumerate(q0)] + [None], dtype=object)[:-1]
            u = np.array([g.input("u", k, v) for k, v in enumerate(u0)] + [None], dtype=object)[:-1]
            t = g.input("t", 0, t0)
            ev = tree_evaluation(ts, t, q, u, masked=False) if program == "eval" else None
            n1 = len(g.guards)
            qd = q_rates(ts, q, u)
            n2 = len(g.guards)
            ud = _lagrange(g, ts, t, q, u, len(order)) if program == "fun" else None
            cols = _outputs(g, ts, t, q, u, len(order), baumgarte, hidden) if program == "outputs" else None
        except CodegenError:
            raise
        except Exception as exc:  # noqa: BLE001 - re-raised naming the component
            raise _untraceable(exc) from exc
    shapes, outs = {}, []
    for name in FIELDS:
        arr = np.asarray(getattr(ev, name)) if ev is not None else np.zeros(0)
        shapes[name] = arr.shape
        outs.extend(arr.ravel().tolist())
    groups = {"eval": outs, "qrate": qd}
    guard_groups = {"eval": g.guards[:n1], "qrate": g.guards[n1:n2]}
    if ud is not None:
        groups["fun"] = list(qd) + list(ud)
        guard_groups["fun"] = list(g.guards)  # equal decisions are one guard: check every one
    names, paths = [], []
    if cols is not None:
        values, rotations = cols
        names, paths = list(values), list(rotations)
        groups["outputs"] = list(values.values()) + [x for R in rotations.values() for x in np.asarray(R).ravel()]
        guard_groups["outputs"] = list(g.guards)
    return SimpleNamespace(graph=g, groups=groups, shapes=shapes, layout=layout, guard_groups=guard_groups,
                           signature=sig, drives=order, inputs=[i for i, _ in inputs.values()],
                           baked=_baked_names(g, layout),
                           qrate_identity=_is_identity(g, qd, system), output_names=names, rotation_paths=paths)


def _lagrange(g, ts, t, q, u, n_drives):
    """The traced Lagrange index-1 accelerations (:func:`~mbcomp.assembly.recursive.lagrange_accelerations`)
    with the Baumgarte gains ``alpha``, ``beta`` (1/s) as the per-call inputs after the drives'
    ``(s, v, a)``; None if the trace point itself is singular (no such program then)."""
    alpha, beta = g.input("d", 3 * n_drives, 10.0), g.input("d", 3 * n_drives + 1, 10.0)
    return _unless_singular(g, lambda: lagrange_accelerations(ts, t, q, u, alpha, beta, baumgarte=True))


def _outputs(g, ts, t, q, u, n_drives, baumgarte, hidden=True):
    """The traced result columns (:func:`~mbcomp.assembly.outputs.output_values`), the gains
    inputs as in :func:`_lagrange`; None if the trace point itself is singular."""
    alpha, beta = g.input("d", 3 * n_drives, 10.0), g.input("d", 3 * n_drives + 1, 10.0)

    def make():  # the columns, then the hidden tolerance terms (the graph shares the tree pass's nodes)
        values, rotations = output_values(ts, t, q, u, alpha, beta, baumgarte=baumgarte)
        return ({**values, **tolerance_terms(ts, t, q, u)} if hidden else values), rotations
    return _unless_singular(g, make)


def _unless_singular(g, make):
    """``make()``, or None when the recursion meets a singular matrix at the trace point
    (the guards it recorded on the way are dropped with it)."""
    n = len(g.guards)
    try:
        return make()
    except SingularTree:
        g.drop_guards(n)
        return None


def _is_identity(g, qd, system):
    if system.nq != system.nu:
        return False
    for k, o in enumerate(qd):
        if type(o) is not Sym or g.keys[o.i] != ("in", "u", k):
            return False
    return True


def _baked_names(g, layout):
    """Names of the runtime parameters whose values a component converted to numbers."""
    keys, names = g.keys, set()
    stack, seen = list(g.baked), set()
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        k = keys[i]
        if k[0] == "in":
            if k[1] == "p":
                path, name, idx = layout[k[2]]
                names.add(f"{path}.{name}")
        elif k[0] != "c":
            stack.extend(k[1:])
    return sorted(names)
