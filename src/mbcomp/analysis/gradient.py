"""The gradient of a scalar objective of a run with respect to many parameters at the cost of
about two runs: the continuous adjoint over the generated programs (:func:`gradient`).

The objective of a run from ``t0`` to ``T`` is ``J = phi(T, y(T)) + integral_t0^T g(t, y) dt``
over the Lagrange index-1 state ``y = [q, u]`` (``dy/dt = f(t, y, p)`` with Baumgarte gains:
the run :func:`mbcomp.simulate` makes by default; projection and the other formulations are
not differentiated here); ``phi`` and ``g`` are written over the run's result columns
(coordinates, speeds, their rates, reactions, energies, aliases, ``time``) in the study
metrics' expression language (:mod:`mbcomp.analysis.metrics`, pointwise: numbers, columns,
``+ - * / **``, ``abs``, ``sqrt``) or as Python functions ``f(t, c)`` of the time and the
columns ``c[name]`` that can be traced (numpy functions and plain arithmetic).

1. **Forward** (checkpointing): the run is integrated (scipy's ``solve_ivp``, ``method``)
   over the system's one-call right-hand side (the generated program), in ``checkpoints``
   segments of equal length, keeping the state at the start of each.
2. **Backward**, segment by segment from the last: the segment is integrated again from its
   checkpoint with its dense output kept (the same steps as the first time: the same call),
   and the adjoint ``lam`` and the parameter gradient ``mu`` are integrated from ``t_k+1``
   back to ``t_k``::

       dlam/dt = -(df/dy)^T lam - (dg/dy)^T         lam(T) = (dphi/dy)^T
       dmu/dt  = -(df/dp)^T lam - (dg/dp)^T         mu(T)  = (dphi/dp)^T

   with the vector-Jacobian products from one call of the adjoint program
   (:class:`mbcomp.codegen.adjoint.AdjointCode`: reverse accumulation over the traced
   right-hand side; its cost does not grow with the number of parameters) and the
   objective's gradient from its own program (the objective traced on the result columns'
   program and differentiated the same way). With one segment (the default) the forward
   run's dense output is kept and nothing is integrated twice.
3. ``dJ/dp = mu(t0) + lam(t0)^T dy0/dp``: a start value (``joint.phi0``) moves ``y0`` (its
   exact derivative, :func:`mbcomp.simulation.sensitivity.initial_sensitivities`); on a closed loop or with
   velocity rows so do the parameters the constraint rows depend on, and their share is one
   more reverse sweep, of the rows (:class:`~mbcomp.analysis.gradient_start.StartTerm`: the
   implicit function theorem in adjoint form); masses and inertias never move ``y0``.

Runs with modes (joint stops, contacts, friction: events) are not smooth: their gradients
need the jump conditions at the events, which the forward sensitivities give; :func:`gradient`
refuses them naming the component.

Examples
--------
A pendulum of length 1 m (a point mass) from 0.5 rad: the gradient of its final angle with
respect to the gravity and the start angle.

>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> gr = mbcomp.gradient(m, {"terminal": "j.phi"}, ["world.g[1]", "j.phi0"], t_end=0.5, backend="python")
>>> round(gr.value, 6), [round(float(v), 6) for v in gr.gradient]
(0.01467, [0.039478, 0.078708])
"""
from __future__ import annotations

import difflib
import re
import time as _time
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ..errors import ModelError, Problem
from ..simulation.sensitivity import initial_sensitivities
from .gradient_start import StartTerm, start_derivative
from .metrics import FUNCTIONS, Metric

__all__ = ["gradient", "Gradient"]

_POINTWISE = ("abs", "sqrt")
_NAME = re.compile(r"^\s*([^\[\]\s]+)\.([A-Za-z_]\w*)\s*(?:\[\s*([0-9,\s]+)\])?\s*$")


@dataclass
class Gradient:
    """The value of an objective and its gradient (:func:`gradient`).

    Attributes
    ----------
    value : float
        ``J = phi(T, y(T)) + integral g dt`` (the objective's units).
    gradient : ndarray (n_params,)
        ``dJ/dp`` in the order of :attr:`params` (objective units per parameter unit).
    params : list of str
        The parameters, as given.
    stats : dict
        ``forward_nfev``, ``backward_nfev`` (right-hand side / adjoint program calls),
        ``forward_steps``, ``backward_steps``, ``checkpoints``, ``initial_runs`` (initializations
        differenced for ``dy0/dp``) and wall times in s: ``setup`` (assembly, tracing,
        compiling), ``forward``, ``backward``, ``initial``, ``total``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.analysis.gradient import Gradient
    >>> g = Gradient(1.5, np.array([2.0, 0.0]), ["rod.m", "world.g[1]"])
    >>> g["rod.m"], g.as_dict()
    (2.0, {'rod.m': 2.0, 'world.g[1]': 0.0})
    """

    value: float
    gradient: np.ndarray
    params: list
    stats: dict = field(default_factory=dict)

    def __getitem__(self, name):
        if name not in self.params:
            raise KeyError(f"{name!r} is not one of the gradient's parameters {self.params}")
        return float(self.gradient[self.params.index(name)])

    def as_dict(self):
        """``{parameter: dJ/dp}``."""
        return {p: float(v) for p, v in zip(self.params, self.gradient)}


def gradient(model, objective, params, *, t_end=1.0, t_start=0.0, values=None, rtol=1e-10, atol=1e-12,
             alpha=10.0, beta=10.0, method="DOP853", checkpoints=1, backend="auto", cache_dir=None):
    """The gradient of a scalar objective of a run with respect to parameters, by the adjoint.

    Parameters
    ----------
    model : Model or MultibodySystem
        A model without modes (no joint stops, contacts or friction with events).
    objective : dict
        ``{"terminal": phi, "integral": g}`` (either may be left out): ``J = phi at t_end +
        integral of g from t_start to t_end``. Each is a text in the metrics' language over the
        result columns (pointwise: numbers, columns, ``time``, ``+ - * / **``, ``abs``,
        ``sqrt``), e.g. ``"crank_angle**2"``, or a function ``f(t, c)`` of the time (s) and the
        columns ``c["name"]`` written with numpy functions and plain arithmetic (it is traced).
    params : sequence of str
        ``"component.param"`` for a number, ``"component.param[i]"`` (or ``[i, j]``) for an
        entry of an array (``"tip.r[1]"``, ``"body.I[2, 2]"``), or a start value
        (``"joint.phi0"``, ``"joint.w0"``). A parameter that is zero is differentiated too.
    t_end, t_start : float
        The run's time span (s).
    values : dict, optional
        Runtime parameter values ``{"component.param": value}`` of the run (as
        :func:`mbcomp.simulate`'s ``params``).
    rtol, atol : float
        Tolerances of the forward run and of the adjoint's backward run.
    alpha, beta : float
        Baumgarte gains (1/s), as :func:`mbcomp.simulate`'s.
    method : str
        The explicit method of both runs: ``"DOP853"`` (default) runs them in C, in the
        runtime's DOP853, when the system has the C engine (``stats["engine"]`` says which);
        otherwise, and for any other ``solve_ivp`` method (``"RK45"``), scipy's ``solve_ivp``.
    checkpoints : int
        Segments of the forward run whose start states are kept; each is integrated again in
        the backward pass (memory: one segment's dense output). 1 (default): the forward
        run's dense output is kept whole and nothing is integrated twice.
    backend : {"auto", "c", "python"}
        The generated programs' language (``"auto"``: C when a compiler exists).
    cache_dir : str, optional
        The compiled programs' cache.

    Returns
    -------
    Gradient
        The objective's value, ``dJ/dp`` in the order of ``params`` and the run's statistics.

    Raises
    ------
    ModelError
        A component with modes (naming it), a parameter the model does not have or that is
        not a number (naming it and the fix), drives or inputs evaluated in Python per call.
    ValueError
        An objective that is not pointwise or names a column the run does not have.
    SimulationError
        A run that fails (a step size underflow, a state where the programs do not hold).

    Examples
    --------
    A mass ``m`` sliding from ``v0 = 1`` m/s on a damper of rate ``d = 0`` (differentiated all
    the same): ``x(T) = x0 + v0 T - d v0 T^2 / (2 m) + O(d^2)``, so ``dx(T)/dd = -v0 T^2 / (2 m)``
    and ``dx(T)/dm = 0`` at ``d = 0``.

    >>> import mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass, Damper
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.1, v0=1.0)); b = m.add("b", PointMass(m=2.0))
    >>> d = m.add("d", Damper(d=0.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> m.connect(w.frame_b, d.frame_a); m.connect(b.frame_a, d.frame_b)
    >>> gr = mbcomp.gradient(m, {"terminal": "s.s"}, ["d.d", "b.m"], t_end=2.0, backend="python")
    >>> round(gr["d.d"], 9), gr["b.m"]        # T = 2 s, m = 2 kg
    (-1.0, 0.0)
    """
    clock0 = _time.perf_counter()
    if not t_end > t_start:
        raise ValueError(f"t_end ({t_end}) must be greater than t_start ({t_start})")
    checkpoints = int(checkpoints)
    if checkpoints < 1:
        raise ValueError(f"checkpoints={checkpoints}: give at least 1 segment")
    pb = _programs(model, objective, params, values, t_start, alpha, beta, backend, cache_dir, method)
    stats = {"checkpoints": checkpoints, "setup": _time.perf_counter() - clock0}
    grid = np.linspace(t_start, t_end, checkpoints + 1)
    if pb.engine is not None:
        value, lam0, mu = _c_runs(pb, grid, rtol, atol, stats, cache_dir)
    else:
        clock = _time.perf_counter()
        starts, whole, stats["forward_nfev"], stats["forward_steps"] = _forward(pb, grid, method, rtol, atol)
        stats["forward"] = _time.perf_counter() - clock
        clock = _time.perf_counter()
        value, lam0, mu = _backward(pb, grid, starts, whole, method, rtol, atol, stats)
        stats.update(backward=_time.perf_counter() - clock, engine=f"scipy {method}")
    clock = _time.perf_counter()
    grad = np.zeros(len(pb.specs))
    runs = 0
    exact = pb.start.contributions(lam0) if pb.start.exact else {}
    starts = [i for i, s in enumerate(pb.specs) if s["kind"] == "start"]
    if starts:  # start values move y0: its derivative from the residual program, all at once
        S0 = initial_sensitivities(pb.system, [str(params[i]) for i in starts], t_start, pb.y0)
        for j, i in enumerate(starts):
            grad[i] += lam0 @ S0[:, j]
    for i, s in enumerate(pb.specs):
        if s["kind"] == "number":
            grad[i] = mu[pb.wrt.index(s["key"])] + exact.get(s["key"], 0.0)
            if s["key"] in pb.start.moving and not pb.start.exact:
                grad[i] += lam0 @ start_derivative(pb.numeric, s, t_start)
                runs += 2
    stats.update(initial_runs=runs, initial=_time.perf_counter() - clock, total=_time.perf_counter() - clock0)
    return Gradient(float(value), grad, [str(p) for p in params], stats)


def _programs(model, objective, params, values, t_start, alpha, beta, backend, cache_dir, method):
    """The run's system, start state, right-hand side and the adjoint and objective programs."""
    from ..assembly.initialization import initialize
    from ..codegen import c_compiler
    from ..codegen.adjoint import AdjointCode
    from ..codegen.graph import no_gc
    from ..codegen.tracer import trace
    from ..formulations import LagrangeIndex1
    from ..simulation.setup import system_of

    if backend == "auto":
        backend = "c" if c_compiler() is not None else "python"
    if backend not in ("c", "python"):
        raise ValueError(f"backend {backend!r}: the adjoint needs a generated program; use 'auto', 'c' or 'python'")
    terminal, running = _objective_parts(objective)
    system = system_of(model, values, backend)
    _refuse_modes(system)
    numeric = system.with_evaluator(None)
    from ..codegen.tracing import parameter_entries

    entries = {(p, n): (kind, val) for p, n, kind, val in parameter_entries(numeric)}
    specs = [_param_spec(entries, name) for name in params]
    keep = sorted({(s["path"], s["name"]) for s in specs if s["kind"] == "number"})
    wrt = [s["key"] for s in specs if s["kind"] == "number"]
    init = initialize(system, t_start)
    form = LagrangeIndex1(system, alpha=alpha, beta=beta)
    with no_gc():
        tr = trace(system, 3_000_000, program="fun", keep=keep)
    if "fun" not in tr.groups or tr.drives or tr.inputs:
        raise ModelError([Problem("model", "has no generated right-hand side to differentiate (drives or inputs "
                                  "evaluated in Python at every call, or a singular start)",
                                  "give the drives' motion laws with numpy functions, or difference whole runs")])
    code = AdjointCode(tr, backend, cache_dir, keep=keep, wrt=wrt)
    parts, outputs = {}, None
    for which, f in (("terminal", terminal), ("integral", running)):
        if f is None:
            continue
        try:  # on the right-hand side's trace when the objective reads states and time only
            node, on, group = _objective_node(tr, _state_columns(tr, system), f, which), tr, "fun"
        except _NoColumn:  # other columns: the output program's trace
            if outputs is None:
                with no_gc():
                    outputs = trace(system, 3_000_000, program="outputs", keep=keep)
                if "outputs" not in outputs.groups:
                    raise ModelError([Problem("model", "the result columns cannot be traced at the start (a singular "
                                              "position)", "start the run away from the singular position")])
            node, on, group = _objective_node(outputs, _output_columns(outputs, system), f, which), outputs, "outputs"
        parts[which] = AdjointCode(on, backend, cache_dir, objective=node, group=group, keep=keep,
                                   wrt=wrt).bind(system)
    vjp = code.bind(system)
    if vjp is None or any(b is None for b in parts.values()):
        raise ModelError([Problem("model", "a parameter value changes a decision the programs were traced with",
                                  "report this: the programs are traced with the run's own values")])
    engine = form.compiled_integrator() if backend == "c" and method == "DOP853" else None
    return SimpleNamespace(
        system=system, numeric=numeric, specs=specs, wrt=wrt, fun=form.fun, vjp=vjp, parts=parts, engine=engine,
        y0=np.asarray(form.initial_state(t_start, init.q, init.u), float), gains=np.array([alpha, beta], float),
        start=StartTerm(system, init, keep, wrt, t_start))


def _forward(pb, grid, method, rtol, atol):
    """The start state of every segment of ``grid`` (and the state at its end), the dense
    output of the whole run when there is one segment, the calls and steps."""
    starts, whole, nfev, nsteps = [pb.y0], None, 0, 0
    for k in range(len(grid) - 1):
        sol = _run(pb.fun, grid[k], grid[k + 1], starts[-1], method, rtol, atol, len(grid) == 2)
        nfev, nsteps = nfev + sol.nfev, nsteps + sol.t.size - 1
        starts.append(sol.y[:, -1].copy())
        whole = sol.sol
    return starts, whole, nfev, nsteps


#: Chebyshev nodes per forward step at which the C path keeps the state for the backward run
#: (a polynomial of degree 9 through the 7th-order dense output of DOP853 over about one step)
NODES = 10


def _c_runs(pb, grid, rtol, atol, stats, cache_dir):
    """The C path: both runs in the runtime's DOP853. Forward, segment by segment, the
    checkpoints and each segment's steps; backward, from the last segment: the segment again
    from its checkpoint with the state kept at :data:`NODES` Chebyshev nodes of each of as
    many equal sub-segments as it took steps, then ``[lam, mu, J]`` back over it
    (:class:`~mbcomp.codegen.adjoint.AdjointIntegrator`). ``(J, lam(t0), mu(t0))``."""
    from ..codegen.adjoint import AdjointIntegrator, chebyshev_nodes
    from ..errors import SimulationError

    clock = _time.perf_counter()
    eng, n, P = pb.engine, pb.y0.size, len(pb.wrt)
    starts, steps, nfev = [pb.y0], [], 0
    for k in range(len(grid) - 1):
        out = _engine_run(eng, grid[k], starts[-1], grid[k + 1], np.array([grid[k + 1]]), rtol, atol)
        starts.append(out.Y[-1].copy())
        steps.append(max(1, out.naccept))
        nfev += out.nfev
    stats.update(forward_nfev=nfev, forward_steps=sum(steps), forward=_time.perf_counter() - clock)
    clock = _time.perf_counter()
    adj = AdjointIntegrator(pb.vjp, pb.parts.get("integral"), pb.gains, cache_dir)
    value, z = 0.0, np.zeros(n + P + 1)
    if "terminal" in pb.parts:
        out = _call(pb.parts["terminal"], grid[-1], starts[-1], pb.gains, "the objective's terminal part")
        value, z[:n], z[n:n + P] = out[0], out[1:1 + n], out[1 + n:]
    x, _ = chebyshev_nodes(NODES)
    renfev = 0
    for k in reversed(range(len(grid) - 1)):
        S, L = steps[k], (grid[k + 1] - grid[k]) / steps[k]
        times = np.minimum(grid[k] + (np.arange(S)[:, None] + x[None, :]) * L, grid[k + 1]).ravel()
        t_out, where = np.unique(times, return_inverse=True)
        out = _engine_run(eng, grid[k], starts[k], grid[k + 1], t_out, rtol, atol)
        renfev += out.nfev
        try:
            z = adj.integrate(grid[k], grid[k + 1], out.Y[where].reshape(S, NODES, n), z, rtol, atol)
        except ArithmeticError as exc:
            raise SimulationError(f"the adjoint's backward run failed: {exc} -> fix: gradients need a smooth run; "
                                  "shorten it or move it away from that state") from exc
    stats.update(recompute_nfev=renfev, backward_nfev=adj.nfev, backward_steps=adj.naccept,
                 backward=_time.perf_counter() - clock, engine="C DOP853 (runtime)")
    return value + z[n + P], z[:n], z[n:n + P]


def _engine_run(eng, t0, y0, t1, t_out, rtol, atol):
    from ..codegen.engine import STATUS
    from ..errors import SimulationError

    out = eng.integrate(8, t0, y0, t1, t_out, rtol, atol)
    if out.status != 0 or len(out.Y) != len(t_out):
        raise SimulationError(f"the forward run stopped at t = {out.t_last:.6g} s ({STATUS.get(out.status, '?')}: "
                              f"{out.message}) -> fix: gradients need a smooth run that the C engine steps through")
    return out


def _backward(pb, grid, starts, whole, method, rtol, atol, stats):
    """``(J, lam(t0), mu(t0))``: the adjoint and the parameter gradient integrated back from
    ``t_end``, segment by segment (each integrated forward again from its start unless the
    whole run's dense output is kept); the integral part of ``J`` rides along."""
    from scipy.integrate import solve_ivp

    n, P = pb.y0.size, len(pb.wrt)
    gains, vjp, g_run = pb.gains, pb.vjp, pb.parts.get("integral")
    value, z = 0.0, np.zeros(n + P + 1)
    if "terminal" in pb.parts:
        out = _call(pb.parts["terminal"], grid[-1], starts[-1], gains, "the objective's terminal part")
        value, z[:n], z[n:n + P] = out[0], out[1:1 + n], out[1 + n:]
    nfev = nsteps = 0
    for k in reversed(range(len(grid) - 1)):
        dense = whole
        if dense is None:
            sol = _run(pb.fun, grid[k], grid[k + 1], starts[k], method, rtol, atol, True)
            nfev, dense = nfev + sol.nfev, sol.sol

        def rhs(t, zz, dense=dense):
            y = dense(t)
            dz = np.empty_like(zz)
            dz[:n + P] = _call(vjp, t, y, np.concatenate((gains, zz[:n])), "the adjoint program")
            dz[n + P] = 0.0
            if g_run is not None:
                go = _call(g_run, t, y, gains, "the objective's integral part")
                dz[:n + P] += go[1:]
                dz[n + P] = go[0]
            return -dz

        back = solve_ivp(rhs, (grid[k + 1], grid[k]), z, method=method, rtol=rtol, atol=atol)
        if back.status != 0:
            from ..errors import SimulationError

            raise SimulationError(f"the adjoint's backward run failed at t = {back.t[-1]:.6g} s: {back.message} "
                                  "-> fix: loosen rtol/atol, or shorten the run")
        nfev, nsteps = nfev + back.nfev, nsteps + back.t.size - 1
        z = back.y[:, -1]
    stats.update(backward_nfev=nfev, backward_steps=nsteps)
    return value + z[n + P], z[:n], z[n:n + P]


def _run(fun, t0, t1, y0, method, rtol, atol, dense):
    from scipy.integrate import solve_ivp

    sol = solve_ivp(fun, (t0, t1), y0, method=method, rtol=rtol, atol=atol, dense_output=dense)
    if sol.status != 0:
        from ..errors import SimulationError

        raise SimulationError(f"the forward run failed at t = {sol.t[-1]:.6g} s: {sol.message} "
                              "-> fix: loosen rtol/atol, or check the model with mbcomp.simulate")
    return sol


def _call(bound, t, y, d, what):
    out = bound(t, y, d)
    if out is None:
        from ..errors import SimulationError

        raise SimulationError(f"{what} does not hold at t = {t:.6g} s (a failed guard: a law's branch or a singular "
                              "matrix, or a non-finite value) -> fix: gradients need a smooth run; shorten it or "
                              "move it away from that state")
    return out


def _objective_parts(objective):
    """``(terminal, integral)`` of an objective dict, each None, a Metric or a callable."""
    if not isinstance(objective, dict) or not objective or set(objective) - {"terminal", "integral"}:
        raise ValueError(f"objective {objective!r}: give a dict {{'terminal': phi, 'integral': g}} (either may be "
                         "left out), each a text such as 'crank_angle**2' or a function f(t, c) of the columns")
    out = []
    for key in ("terminal", "integral"):
        f = objective.get(key)
        if isinstance(f, str):
            f = Metric(f)
            _check_pointwise(f.tree, f.text)
        elif f is not None and not callable(f):
            raise ValueError(f"objective {key!r}: {f!r} is neither a text nor a function f(t, c)")
        out.append(f)
    return tuple(out)


def _check_pointwise(node, text):
    if node[0] == "call":
        if node[1] not in _POINTWISE:
            raise ValueError(f"objective {text!r}: {node[1]}() ({FUNCTIONS[node[1]][2]}) is not a function of one "
                             "time -> write the terminal part (at t_end) and the integral part separately, with "
                             f"numbers, columns, + - * / ** and {', '.join(_POINTWISE)}")
        for a in node[2]:
            _check_pointwise(a, text)
    elif node[0] == "neg":
        _check_pointwise(node[1], text)
    elif node[0] == "bin":
        _check_pointwise(node[2], text)
        _check_pointwise(node[3], text)


class _NoColumn(ValueError):
    """An objective names a column the trace at hand does not have."""


class _Columns:
    """The traced result columns by name (and the model's aliases); a missing one names the similar."""

    def __init__(self, cols, what):
        self.cols, self.what = cols, what

    def __getitem__(self, name):
        if name in self.cols:
            return self.cols[name]
        close = difflib.get_close_matches(name, list(self.cols), n=4, cutoff=0.6)
        raise _NoColumn(f"objective {self.what}: the run has no column {name!r}"
                        + (f"; similar: {', '.join(close)}" if close else "")
                        + " -> fix: use a coordinate, speed, rate, reaction or energy column, an alias, or time")

    def __contains__(self, name):
        return name in self.cols

    def keys(self):
        return self.cols.keys()


def _with_aliases(cols, system):
    for alias, var in system.topology.flat.aliases.items():
        if var in cols:
            cols[alias] = cols[var]
    return cols


def _state_columns(tr, system):
    """The coordinates and speeds of a right-hand side's trace: its ``q`` and ``u`` inputs."""
    g = tr.graph
    cols = {name: g.memo[("in", "q", k)] for k, name in enumerate(system.q_names) if ("in", "q", k) in g.memo}
    cols.update({name: g.memo[("in", "u", k)] for k, name in enumerate(system.u_names) if ("in", "u", k) in g.memo})
    return _with_aliases(cols, system)


def _output_columns(tr, system):
    """The result columns of an output program's trace."""
    names = tr.output_names
    return _with_aliases(dict(zip(names, tr.groups["outputs"][:len(names)])), system)


def _objective_node(tr, cols, f, which):
    """The objective part ``f`` (Metric or callable) as a node of the trace's graph, over the
    columns ``cols`` (name -> node) and ``time``."""
    g = tr.graph
    t = g.memo.get(("in", "t", 0))
    with g:
        if t is None:
            t = g.input("t", 0, 0.0)
        columns = _Columns(dict(cols, time=t), f"{which} part")
        if isinstance(f, Metric):
            node = _pointwise(f.tree, columns)
        else:
            node = f(t, columns)
    node = np.asarray(node, dtype=object)
    if node.size != 1:
        raise ValueError(f"objective {which} part gives {node.size} values, not one")
    node = node.reshape(())[()]
    if not hasattr(node, "__mbcomp_traced__"):
        node = float(node)  # a constant objective
    return node


def _pointwise(node, columns):
    kind = node[0]
    if kind == "num":
        return node[1]
    if kind == "col":
        return columns[node[1]]
    if kind == "neg":
        return -_pointwise(node[1], columns)
    if kind == "bin":
        a, b = _pointwise(node[2], columns), _pointwise(node[3], columns)
        return _binary(node[1], a, b)
    arg = _pointwise(node[2][0], columns)
    return np.abs(arg) if node[1] == "abs" else np.sqrt(arg)


def _binary(op, a, b):
    if op == "Add":
        return a + b
    if op == "Sub":
        return a - b
    if op == "Mult":
        return a * b
    if op == "Div":
        return a / b
    return a ** b


def _param_spec(entries, text):
    """What a parameter name means: ``{"kind": "number" | "start", "path", "name", "index",
    "key", "value"}`` (``entries``: ``{(path, name): (kind, value)}`` of the system's
    parameters); a ``ModelError`` naming it and the fix otherwise."""
    m = _NAME.match(str(text))
    if m is None:
        raise ModelError([Problem(str(text), "is not a parameter name",
                                  "write component.param, component.param[i] for an array entry, or a start value "
                                  "such as joint.phi0")])
    path, name, idx = m.group(1), m.group(2), m.group(3)
    if (path, name) not in entries:
        close = difflib.get_close_matches(f"{path}.{name}", [f"{p}.{n}" for p, n in entries], n=4, cutoff=0.6)
        raise ModelError([Problem(str(text), "the model has no such parameter"
                                  + (f" (similar: {', '.join(close)})" if close else ""),
                                  "give component.param of a component of the model")])
    kind, val = entries[(path, name)]
    index = tuple(int(k) for k in idx.split(",") if k.strip()) if idx else None
    if kind == "start":
        if isinstance(val, (float, np.floating)) and index is None:
            return {"kind": "start", "path": path, "name": name, "index": None, "key": None, "value": float(val)}
        if isinstance(val, np.ndarray) and val.dtype.kind == "f" and index is not None and len(index) == val.ndim \
                and all(0 <= k < n for k, n in zip(index, val.shape)):
            return {"kind": "start", "path": path, "name": name, "index": index, "key": None,
                    "value": float(val[index])}
        if isinstance(val, np.ndarray) and val.dtype.kind == "f":
            raise ModelError([Problem(str(text), f"is a start value of shape {val.shape}",
                                      f"give one entry, e.g. {path}.{name}[{', '.join('0' for _ in val.shape)}]")])
        raise ModelError([Problem(str(text), f"start value {val!r} is not a fixed number (a Guess or None: the "
                                  "start state does not follow it)", f"fix it with a number, e.g. {path}.{name}=0.3")])
    if isinstance(val, (float, np.floating)) and index is None:
        return {"kind": "number", "path": path, "name": name, "index": None, "key": (path, name, None),
                "value": float(val)}
    if isinstance(val, np.ndarray) and val.dtype.kind == "f":
        if index is None or len(index) != val.ndim or any(not 0 <= k < s for k, s in zip(index, val.shape)):
            raise ModelError([Problem(str(text), f"is an array of shape {val.shape}",
                                      f"give one entry, e.g. {path}.{name}[{', '.join('0' for _ in val.shape)}]")])
        return {"kind": "number", "path": path, "name": name, "index": index, "key": (path, name, index),
                "value": float(val[index])}
    raise ModelError([Problem(str(text), f"is not a number ({type(val).__name__}): it cannot be differentiated",
                              "give a numeric parameter or an entry of a numeric array")])


def _refuse_modes(system):
    for e in system.topology.edges:
        if e.kind == "joint" and e.comp.modes(system.P[e.name]) is not None:
            raise ModelError([Problem(e.name, f"{type(e.comp).__name__} has modes (stops, contacts or friction with "
                                      "events): its runs are not smooth and the adjoint does not cross events",
                                      "differentiate through events with the forward sensitivities, "
                                      "simulate(..., sensitivities=[...]); or remove its limits/contact")])
