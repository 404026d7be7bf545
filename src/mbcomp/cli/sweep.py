"""``mbcomp stability MODEL.py --sweep name=start:stop:count``: stability against a parameter.

The swept parameter is either a build() parameter (no dot: the model, and its start state,
is built at each value) or a component parameter (``component.param``: one model, the value
set at run time, nothing re-derived). At each value the model is linearized about its start
state or, with ``--steady``, about a steady state solved there: the one nearest the model's
start values at the first value, then the one nearest the branch followed so far
(continuation). :func:`mbcomp.analysis.stability.sweep` locates where the classification
changes. With ``--executor`` (:func:`sweep_on_executor`) the values' linearizations about the
start states are tasks on workers, each worker making the model from the file's path.

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> args = make_parser().parse_args(["stability", "models/bicycle.py", "--sweep", "v=0:10:11"])
>>> args.sweep, args.func.__name__
('v=0:10:11', 'cmd_stability')
"""
from __future__ import annotations

import inspect
import pathlib

import numpy as np

from ..errors import ModelError, SimulationError
from .loader import call_build, model_module, takes
from .messages import dominant_eigenvalues, one_line

__all__ = ["stability_sweep", "sweep_on_executor", "parse_sweep", "Sweep"]

_SWEEP_HINT = "write --sweep name=start:stop:count with start < stop and an integer count >= 2, e.g. spin=1:5:9"


def parse_sweep(spec):
    """``"name=start:stop:count"`` -> ``(name, grid)`` with ``grid = linspace(start, stop, count)``.

    Examples
    --------
    >>> from mbcomp.cli.sweep import parse_sweep
    >>> parse_sweep("spin=1:5:5")
    ('spin', array([1., 2., 3., 4., 5.]))
    """
    text = str(spec).strip()
    name, sep, rng = text.partition("=")
    name, parts = name.strip(), rng.split(":")
    if not sep or not name or len(parts) != 3:
        raise ValueError(f"--sweep {text!r}: {_SWEEP_HINT}")
    try:
        start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise ValueError(f"--sweep {text!r}: start and stop must be numbers and count an integer; "
                         f"{_SWEEP_HINT}") from None
    if not (np.isfinite(start) and np.isfinite(stop) and start < stop and count >= 2):
        raise ValueError(f"--sweep {text!r}: {_SWEEP_HINT}")
    return name, np.linspace(start, stop, count)


class Sweep:
    """One ``--sweep`` run: the models along the grid (:meth:`make`) and their linearizations
    (:meth:`analyze`), for :func:`mbcomp.analysis.stability.sweep`.

    ``solved`` maps each parameter value to the steady-state unknowns followed there (with
    ``--steady``).
    """

    def __init__(self, args, mod, build_kw, runtime, steady, title):
        from ..analysis import stability as st

        self.args, self.mod, self.build_kw, self.steady, self.title = args, mod, build_kw, steady, title
        self.name, self.grid = parse_sweep(args.sweep)
        self.current = None  # the value whose model make() built last
        self.solved = {}
        self.names = list(steady[1]) if steady is not None else []
        name = self.name
        if "." in name:  # a component parameter: one model, the value set at run time
            self.base = st.system_for(call_build(mod, build_kw, args.model), runtime or None, args.backend)
            try:
                self.base.with_params({name: float(self.grid[0])})
            except ModelError as exc:
                raise ValueError(f"--sweep {name}: {one_line(exc)}") from None
            self.params = None
        else:  # a build() parameter: the model (and its start state) built at each value
            if not takes(mod.build, name):
                names = ", ".join(inspect.signature(mod.build).parameters) or "none"
                raise ValueError(f"--sweep {name}: build() of {title} takes no parameter {name!r} -> fix: sweep one "
                                 f"of {names}, or a component parameter as component.param")
            self.base = None
            self.params = runtime or None

    def make(self, v):
        """The model (or system) at parameter value ``v``."""
        self.current = v
        if self.base is not None:
            return self.base.with_params({self.name: v})
        return call_build(self.mod, {**self.build_kw, self.name: v}, self.args.model)

    def analyze(self, mdl):
        """Linearization of ``mdl``: about its start state, or about the followed steady state."""
        from ..analysis import stability as st

        if self.steady is None:
            return st.linearize(mdl, params=self.params, backend=self.args.backend)
        fixed, unknown = self.steady
        v = self.current
        system = st.system_for(mdl, self.params, self.args.backend)  # traced once for both steps
        sols = st.steady_states(system, unknown, fixed)
        if not sols:
            raise SimulationError(f"no steady state with {self.args.steady} at {self.name} = {v!r}")
        if self.solved:  # continuation: the branch followed at the nearest value solved so far
            ref = self.solved[min(self.solved, key=lambda x: abs(x - v))]
        else:  # first value: the branch nearest the model's start values
            ref = self.start_values(mdl)
        width = np.array([unknown[n][1] - unknown[n][0] for n in self.names])
        pick = min(sols, key=lambda s: np.abs((self._values(s) - ref) / width).max())
        self.solved[v] = self._values(pick)
        return st.linearize(system, state=pick)

    def _values(self, state):
        return np.array([state.values[n] for n in self.names])

    def start_values(self, mdl):
        """The steady-state unknowns at the model's consistent start state."""
        from ..assembly.initialization import initialize
        from ..assembly.system import MultibodySystem, assemble

        unknown = self.steady[1]
        system = mdl if isinstance(mdl, MultibodySystem) else assemble(mdl, self.params)
        init = initialize(system, 0.0)
        out = []
        for n in self.names:
            if n in system.q_names:
                out.append(init.q[system.q_names.index(n)])
            elif n in system.u_names:
                out.append(init.u[system.u_names.index(n)])
            else:
                out.append(0.5 * sum(unknown[n]))  # steady_states names the bad name
        return np.array(out, float)

    def run(self):
        """:func:`mbcomp.analysis.stability.sweep` over the grid."""
        from ..analysis import stability as st

        if self.steady is not None:  # check the names of --steady once, before the sweep records failures as "failed"
            fixed, unknown = self.steady
            st.steady_states(self.make(float(self.grid[0])), unknown, fixed, params=self.params, starts=2)
        return st.sweep(self.make, self.name, self.grid, analyze=self.analyze)


def _table(run, sw):
    """The per-value table: classification, followed steady state, dominant eigenvalues."""
    name, grid, steady = run.name, run.grid, run.steady
    print(f"{run.title}: stability against {name} = {grid[0]:g} .. {grid[-1]:g} ({len(grid)} values)"
          + (f", steady state {run.args.steady} solved at each value" if steady else ""))
    head = f"{name:>12}  {'classification':<22}"
    if steady is not None:
        head += "  " + "  ".join(f"{n:>14}" for n in run.names)
    print(head + "  eigenvalues with the largest real part (1/s)")
    for k, v in enumerate(sw.values):
        row = f"{v:>12.6g}  {sw.classifications[k]:<22}"
        if steady is not None:
            z = run.solved.get(float(v))
            row += "  " + "  ".join(f"{x:>14.8g}" if z is not None else f"{'-':>14}" for x in
                                    (z if z is not None else run.names))
        print(row + "  " + (dominant_eigenvalues(sw.eigenvalues[k]) if sw.classifications[k] != "failed" else "-"))
    print()


def _changes(run, sw):
    """Where the classification changes, and the ranges; returns ``(segments, stable, marginal)``."""
    name, grid = run.name, run.grid
    if sw.changes:
        for c in sw.changes:
            print(f"stability changes at {name} = {c['value']!r} ({c['from']} -> {c['to']}, {c['kind']}, "
                  f"{c['method']})")
    else:
        print(f"no stability change for {name} in [{grid[0]:g}, {grid[-1]:g}]")
    segs = sw.ranges()
    for lo, hi, cls in segs:
        print(f"  {name} in [{lo!r}, {hi!r}]: {cls}")
    stable = [(lo, hi) for lo, hi, cls in segs if cls == "asymptotically stable"]
    marginal = [(lo, hi) for lo, hi, cls in segs if cls == "marginally stable"]
    print("stable ranges (asymptotically stable): "
          + (", ".join(f"[{lo!r}, {hi!r}]" for lo, hi in stable) or "none"))
    if marginal:
        print("marginally stable ranges: " + ", ".join(f"[{lo!r}, {hi!r}]" for lo, hi in marginal))
    return segs, stable, marginal


def _write(run, sw, segs, stable, marginal):
    """``--out`` (JSON) and ``--plot`` (eigenvalues against the parameter)."""
    from ..analysis import stability as st

    args = run.args
    if args.out:
        data = sw.to_dict()
        data.update(model=run.title, ranges=[dict(lo=lo, hi=hi, classification=c) for lo, hi, c in segs],
                    stable_ranges=stable, marginally_stable_ranges=marginal)
        if run.steady is not None:
            data["steady"] = [None if float(v) not in run.solved else dict(zip(run.names, map(float, run.solved[float(v)])))
                              for v in sw.values]
        st.to_json(data, args.out)
        print(f"wrote {args.out}")
    if args.plot:
        sw.plot(args.plot, title=f"{run.title}: eigenvalues against {run.name}")
        print(f"wrote {args.plot}")


def stability_sweep(args, mod, build_kw, runtime, steady, title):
    """Run ``--sweep``, print the table, the changes and the ranges, write ``--out``/``--plot``.

    ``steady`` is ``None`` or ``(fixed, unknown)`` from :func:`mbcomp.analysis.stability.parse_steady`.
    Returns the exit status (0).
    """
    run = Sweep(args, mod, build_kw, runtime, steady, title)
    sw = run.run()
    _table(run, sw)
    _write(run, sw, *_changes(run, sw))
    return 0


#: (model path, build arguments, runtime values, backend) -> this process's system, for _FileModel
_BASES = {}


class _FileModel:
    """The model of a ``--sweep`` at one value, made from the model file's path: what an
    executor's worker receives (a module-level class, so it pickles) -- the same model as
    :meth:`Sweep.make` makes in this process."""

    def __init__(self, path, build_kw, runtime, name, backend):
        self.path, self.build_kw, self.runtime = str(pathlib.Path(path).resolve()), dict(build_kw), dict(runtime)
        self.name, self.backend = name, backend

    def __call__(self, v):
        from ..analysis import stability as st

        mod = _module_at(self.path)
        if "." not in self.name:
            return call_build(mod, {**self.build_kw, self.name: v}, self.path)
        key = (self.path, repr(sorted(self.build_kw.items())), repr(sorted(self.runtime.items())), self.backend)
        if key not in _BASES:
            _BASES[key] = st.system_for(call_build(mod, self.build_kw, self.path), self.runtime or None, self.backend)
        return _BASES[key].with_params({self.name: v})


class _StartLinearization:
    """Linearization about the start state, as :meth:`Sweep.analyze` does
    without ``--steady`` (module-level: it pickles)."""

    def __init__(self, params, backend):
        self.params, self.backend = params, backend

    def __call__(self, mdl):
        from ..analysis import stability as st

        return st.linearize(mdl, params=self.params, backend=self.backend)


_MODULES = {}


def _module_at(path):
    if path not in _MODULES:
        _MODULES[path] = model_module(path)
    return _MODULES[path]


def sweep_on_executor(args, mod, build_kw, runtime, steady, title):
    """``--sweep`` with ``--executor``: the grid's linearizations as tasks on the executor,
    printed and written as the serial sweep is."""
    from ..analysis import stability as st
    from ..analysis.parallel import running_on

    if steady is not None:
        raise ValueError("--executor with --steady: the steady state is followed from one value to the next "
                         "(continuation), which runs in order -> drop --executor, or drop --steady to linearize "
                         "about each start state")
    run = Sweep(args, mod, build_kw, runtime, None, title)  # checks the name and the first value
    make = _FileModel(args.model, build_kw, runtime, run.name, args.backend)
    with running_on(args.executor, args.workers) as executor:  # Ctrl-C, SIGTERM: no worker left behind
        sw = st.sweep(make, run.name, run.grid, analyze=_StartLinearization(run.params, args.backend),
                      executor=executor, progress=True)
    _table(run, sw)
    _write(run, sw, *_changes(run, sw))
    return 0
