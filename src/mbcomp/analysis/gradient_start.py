"""The start state's share of an adjoint gradient (:func:`mbcomp.gradient`): ``lam(t0)^T dy0/dp``.

The consistent start ``y0`` of a run moves with its start values and, on a closed loop or with
velocity rows, with the parameters the constraint rows depend on. :class:`StartTerm` gives that
share for every such parameter in one reverse sweep of the rows (the implicit function theorem
in adjoint form); :func:`start_derivative` differences the initialization where that does not
apply.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.analysis.gradient_start import free_start
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> [x.tolist() for x in free_start(mbcomp.assemble(m))]     # phi0 fixed, the rate free (w0 not given)
[[False], [True]]
"""
from __future__ import annotations

import numpy as np

from ..simulation.sensitivity_start import differenced_start, free_start as start_freedom

__all__ = ["StartTerm", "start_derivative", "reached_params", "free_start"]


class StartTerm:
    """``lam(t0)^T dy0/dp`` for the parameters that move the consistent start state through
    the constraint rows ``R = [Phi, dPhi/dt, Psi]`` (the kept rows).

    Parameters
    ----------
    system : MultibodySystem
        Initialized (``init`` its :class:`~mbcomp.assembly.initialization.InitialState`).
    init : InitialState
    keep : sequence of (path, name)
        Parameters kept as program inputs where zero.
    wrt : sequence of (path, name, index)
        The runtime parameters of the gradient.
    t0 : float
        Start time (s).

    On a tree no parameter but a start value moves ``y0``; with rows, those ``R`` depends on in
    the traced evaluation (lengths, axes; never masses or inertias: :attr:`moving`). The start
    solves ``Phi = 0`` in the free coordinates and ``[dPhi/dt, Psi] = 0`` in the free speeds
    (minimum norm, as the initialization's Gauss-Newton), so by the implicit function theorem
    ``dq_f/dp = -pinv(G_f) G_p`` and ``du_f/dp = -pinv(V_uf) (V_q dq/dp + V_p)``, and
    ``lam^T dy0/dp = -(a^T G_p + b^T V_p)`` with ``b = pinv(V_uf)^T lam_uf`` and ``a =
    pinv(G_f)^T (lam_qf - V_qf^T b)``: one reverse sweep of ``R`` weighted by ``[a, b]`` for
    every parameter at once (:attr:`exact`). Where that does not apply (quaternions, drives,
    inputs, fixed start values on a cut joint) the start is differenced (two initializations
    per moving parameter).

    Examples
    --------
    >>> import sys, numpy as np, mbcomp
    >>> from mbcomp.assembly.initialization import initialize
    >>> from mbcomp.analysis.gradient_start import StartTerm
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> term = StartTerm(system, initialize(system), [], [("rod", "r", (1,))], 0.0)
    >>> term.moving, term.exact          # a tree: no parameter moves the start
    (set(), False)
    """

    def __init__(self, system, init, keep, wrt, t0):
        from ..codegen.graph import no_gc
        from ..codegen.tracer import trace

        self.moving, self.exact = set(), False
        if not ((init.row_mask is not None and init.row_mask.size > 0) or system.nonholonomic):
            return
        with no_gc():
            tr = trace(system, 3_000_000, program="eval", keep=keep)
        g, flat, at, parts = tr.graph, tr.groups["eval"], 0, {}
        for name, shape in tr.shapes.items():
            size = int(np.prod(shape))
            parts[name] = flat[at:at + size]
            at += size
        mask = np.ones(len(parts["Phi"]), bool) if init.row_mask is None else np.asarray(init.row_mask, bool)
        keep_rows = lambda xs: [x for x, k in zip(xs, mask) if k]  # noqa: E731
        rows = keep_rows(parts["Phi"]) + keep_rows(parts["Phid"]) + list(parts["Psi"])
        self.m = int(mask.sum())
        found = reached_params(g, rows, tr.layout)
        self.moving = {w for w in wrt if w in found}
        fixed_cut = any(np.any(e.comp.start(system.P[e.name])[1]) or np.any(e.comp.start(system.P[e.name])[3])
                        for e in system.topology.edges if e.kind == "joint" and e not in system.topology.tree
                        and e.dof > 0)
        if not self.moving or system.nq != system.nu or tr.drives or tr.inputs or fixed_cut:
            return
        self._programs(g, tr, rows, system, init, t0)

    def _programs(self, g, tr, rows, system, init, t0):
        from ..codegen.adjoint import reverse
        from ..codegen.printers import PY_ENV, Program
        from ..codegen.tangent import tangent
        from ..codegen.tracer import param_vector

        nq, nu = system.nq, system.nu
        ys = [g.memo.get(("in", "q", k)) for k in range(nq)] + [g.memo.get(("in", "u", k)) for k in range(nu)]
        present = [(k, x) for k, x in enumerate(ys) if x is not None]
        J = tangent(g, rows, [x for _, x in present])
        flat = [0.0] * (len(rows) * (nq + nu))
        for i, row in enumerate(J):
            for (k, _), v in zip(present, row):
                flat[i * (nq + nu) + k] = v
        moving = sorted(self.moving, key=tr.layout.index)
        with g:
            w = [g.input("d", k, 0.1) for k in range(len(rows))]
        ps = [g.memo.get(("in", "p", tr.layout.index(key))) for key in moving]
        grads = reverse(g, rows, w, [x for x in ps if x is not None])
        it = iter(grads)
        wp = [next(it) if x is not None else 0.0 for x in ps]
        env = dict(PY_ENV)
        prog = Program(g, {"D": flat, "wp": wp}, hoist=False)
        exec(prog.python_main("D", "jac") + "\n" + prog.python_main("wp", "vjp"), env)
        pv = param_vector(system, tr.layout)
        D = np.array(env["jac"](list(init.q), list(init.u), float(t0), [], pv), float).reshape(len(rows), nq + nu)
        qfree, ufree = free_start(system)
        self.D, self.qfree, self.ufree, self.nq = D, qfree, ufree, nq
        self.vjp = lambda weights: np.array(env["vjp"](list(init.q), list(init.u), float(t0), list(weights), pv), float)
        self.keys, self.exact = moving, True

    def contributions(self, lam0):
        """``{parameter key: lam0^T dy0/dp}`` for the moving parameters (exact path only)."""
        m, nq, D = self.m, self.nq, self.D
        G, V = D[:m, :nq], D[m:]
        Vq, Vu = V[:, :nq], V[:, nq:]
        lq, lu = lam0[:nq], lam0[nq:]
        b = np.linalg.pinv(Vu[:, self.ufree]).T @ lu[self.ufree] if V.shape[0] else np.zeros(0)
        a = np.linalg.pinv(G[:, self.qfree]).T @ (lq[self.qfree] - Vq[:, self.qfree].T @ b) if m else np.zeros(0)
        return dict(zip(self.keys, -self.vjp(np.concatenate((a, b)))))


def reached_params(g, rows, layout):
    """The runtime parameters ``(path, name, index)`` (of ``layout``) the nodes ``rows`` of the
    graph ``g`` depend on.

    Examples
    --------
    >>> from mbcomp.codegen.graph import Graph
    >>> from mbcomp.analysis.gradient_start import reached_params
    >>> with Graph() as g:
    ...     q, a, b = g.input("q", 0, 1.0), g.input("p", 0, 2.0, state=False), g.input("p", 1, 3.0, state=False)
    ...     r = q * a
    >>> reached_params(g, [r], [("rod", "L", None), ("bob", "m", None)])
    {('rod', 'L', None)}
    """
    found, seen = set(), set()
    stack = [o.i for o in rows if hasattr(o, "__mbcomp_traced__")]
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        key = g.keys[i]
        if key[0] == "in":
            if key[1] == "p":
                found.add(tuple(layout[key[2]]))
        elif key[0] != "c":
            stack.extend(key[1:])
    return found


def free_start(system):
    """Masks ``(qfree, ufree)`` of the coordinates and speeds the initialization may move (those
    without a fixed start value); see the module's example."""
    qfree, ufree, _ = start_freedom(system)
    return qfree, ufree


def start_derivative(numeric, spec, t0):
    """``dy0/dp`` by a central difference of the consistent initialization (closed to round-off,
    so the difference is exact to its truncation error, ~h^2) of the numeric system ``numeric``
    for the parameter ``spec`` (``{"path", "name", "index", "value"}``) at ``t0`` (s).

    It is what :class:`StartTerm` cannot cover (:func:`mbcomp.simulation.sensitivity_start.differenced_start`,
    which the sensitivities use too where the start is not determined by its rows).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.analysis.gradient_start import start_derivative
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> spec = {"path": "j", "name": "phi0", "index": None, "value": 0.5}
    >>> np.round(start_derivative(mbcomp.assemble(m), spec, 0.0), 9).tolist()
    [1.0, 0.0]
    """
    return differenced_start(numeric, spec["path"], spec["name"], spec["index"], spec["value"], t0)


