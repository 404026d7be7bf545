"""Checks of a freshly generated program against the numeric path it was traced from, at the
trace point (:func:`~mbcomp.codegen.tracer.trace_point`): the evaluation program against
:meth:`~mbcomp.assembly.system.MultibodySystem.evaluate_numeric`, the Lagrange right-hand side
against the dense saddle-point solve. A difference beyond rounding is an internal error
(:class:`~mbcomp.codegen.graph.CodegenError` asking for the model).

Examples
--------
>>> import mbcomp
>>> from mbcomp.codegen.compiler import Bound, Code
>>> from mbcomp.codegen.tracer import trace
>>> from mbcomp.codegen.verify import verify_evaluation
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> system = mbcomp.assemble(m)
>>> verify_evaluation(Bound(Code(trace(system, max_nodes=1000), "python"), system), system) is None
True
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError
from .graph import CodegenError, Fallback
from .tracer import FIELDS, trace_point

__all__ = ["verify_evaluation", "verify_fun"]


def verify_evaluation(bound, system):
    """The evaluation program ``bound`` (:class:`~mbcomp.codegen.compiler.Bound`) against the numeric
    evaluation of ``system`` at the trace point; :class:`CodegenError` when they differ."""
    t, q, u = trace_point(system)
    num = system.evaluate_numeric(t, q, u, masked=False)
    try:
        flat = bound.run(t, q, u)
    except Fallback:
        return  # a state guard rejects the trace point itself (e.g. a piecewise law at zero)
    code = bound.code
    for name in FIELDS:
        a, b, shape = code.slices[name]
        ref = np.asarray(getattr(num, name), float)
        err = np.max(np.abs(flat[a:b].reshape(shape) - ref), initial=0.0)
        if not err <= 1e-9 * (1.0 + np.max(np.abs(ref), initial=0.0)):
            raise CodegenError(f"internal error: the generated program differs from the numeric evaluation in "
                               f"{name} by {err:.3g}; please report this model (use the numeric path meanwhile)")
    qd = bound.run_qrate(q, u)
    if not np.allclose(qd, system.q_rate_numeric(q, u), rtol=1e-9, atol=1e-12):
        raise CodegenError("internal error: the generated coordinate rates differ from the numeric ones")


def verify_fun(bound, system):
    """The Lagrange program ``bound`` against the numeric dense solve of ``system`` at the trace
    point; :class:`CodegenError` when they differ beyond rounding."""
    from ..formulations.lagrange import LagrangeIndex1

    t, q, u = trace_point(system)
    y = np.concatenate((q, u))
    try:
        dy = bound.run_fun(t, y, 10.0, 10.0)
    except Fallback:
        return
    form = LagrangeIndex1(system.with_evaluator(None), alpha=10.0, beta=10.0)
    try:
        ref = form.fun(t, y)
    except SimulationError:  # a singular mass matrix: initialization names the massless motion
        return
    ev = form.system.evaluate(t, q, u)
    w = np.linalg.eigvalsh(ev.M)
    if w.size and not w[0] > 1e-8 * w[-1]:  # both solves lose the digits the check compares
        return
    C = ev.A
    if C.size:  # rows dependent at this (inconsistent) point: the two solves may differ, neither is wrong
        sv = np.linalg.svd(C, compute_uv=False)
        if len(sv) < C.shape[0] or sv[-1] <= 1e-8 * sv[0]:
            return
    # the accelerations come out of forces that may nearly cancel (a stiff spring held by a
    # loop: 5.6 MN against the closure): both solves carry rounding of the forces' own size,
    # M^-1 f, not of the small result
    pushed = np.linalg.solve(ev.M, ev.f) if ev.M.size else np.zeros(0)
    err = np.max(np.abs(dy - ref), initial=0.0)
    if not err <= 1e-8 * (1.0 + np.max(np.abs(ref), initial=0.0) + np.max(np.abs(pushed), initial=0.0)):
        raise CodegenError(f"internal error: the generated right-hand side differs from the dense Lagrange solve "
                           f"by {err:.3g}; please report this model (use the numeric path meanwhile)")
