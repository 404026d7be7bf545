"""Studies: many runs of one model over a grid or a Monte Carlo sample, on any executor.

:func:`study` expands a *grid* into runs, sends them in chunks to an executor (in-process,
any :class:`concurrent.futures.Executor`, or Dask: :mod:`mbcomp.analysis.executors`), and
collects one row per run: the parameter values, the *metrics* (functions of the
:class:`~mbcomp.simulation.result.Result`, evaluated where the run happened, so only numbers
travel back), status, message and CPU time. A run that fails is a row with its status and
message, never a lost study.

Parameters of a run are of two kinds, told apart by their names:

* ``"<component>.<parameter>"`` (``"crank.m"``, ``"crank_joint.w0"``): a runtime parameter.
  The model is assembled and compiled once per worker and structure; each run only changes
  the parameter vector (nothing re-derived or re-compiled);
* a bare name (``"length"``): an argument of the model's ``build()``. The structure may
  change: the model is built once per distinct set of build arguments (compiled programs are
  cached on disk by structure, so equal structures compile once).

What a worker needs to make the model -- a model file's path, a ``build`` function or a model
-- travels as a small *recipe*; each worker process keeps what it built from it
(:data:`_PREPARED`), so a chunk of runs pays assembly and compilation at most once.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.0)); rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> s = mbcomp.study(m, {"j.w0": [1.0, 2.0]}, t_end=0.5, metrics={"top": lambda r: r["j.phi"].max()})
>>> s.columns
['j.w0', 'top', 'status', 'message', 'cpu_time']
>>> [round(float(x), 4) for x in s["top"]], list(s["status"])   # the highest angle reached (rad)
([0.051, 0.2053], ['success', 'success'])
"""
from __future__ import annotations

import itertools
import math
import os
import time
import uuid
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError, SimulationError, SimulationInterrupted
from ..simulation.endings import Terminated
from .executors import ChunkStopped, dispatch, signal_name, stop_requested, stoppable

__all__ = ["study", "Uniform", "Normal", "StudyResult", "StudyInterrupted", "runs_of"]


class StudyInterrupted(SimulationInterrupted):
    """Ctrl-C (SIGINT) or SIGTERM stopped :func:`study`; :attr:`result` is the
    :class:`StudyResult` of the runs that finished before (their rows are those an
    uninterrupted study gives them), :attr:`signal` ``"SIGINT"`` or ``"SIGTERM"``.

    A :class:`KeyboardInterrupt` (through :class:`~mbcomp.errors.SimulationInterrupted`), so a
    script that does not catch it stops.

    Examples
    --------
    >>> e = StudyInterrupted(None, "SIGINT", "study interrupted by SIGINT: 3 of 9 runs finished")
    >>> isinstance(e, KeyboardInterrupt), e.signal
    (True, 'SIGINT')
    """


# --- what to run ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Uniform:
    """A parameter drawn uniformly from ``[lo, hi]`` in a Monte Carlo study.

    Examples
    --------
    >>> import numpy as np
    >>> Uniform(1.0, 2.0).sample(np.random.default_rng(0), 3).round(3).tolist()
    [1.637, 1.27, 1.041]
    """

    lo: float
    hi: float

    def sample(self, rng, n):
        return rng.uniform(self.lo, self.hi, n)


@dataclass(frozen=True)
class Normal:
    """A parameter drawn from a normal distribution ``N(mu, sigma^2)`` in a Monte Carlo study.

    Examples
    --------
    >>> import numpy as np
    >>> Normal(10.0, 0.5).sample(np.random.default_rng(0), 2).round(3).tolist()
    [10.063, 9.934]
    """

    mu: float
    sigma: float

    def sample(self, rng, n):
        return rng.normal(self.mu, self.sigma, n)


def runs_of(grid, samples=None, seed=None):
    """The runs of a grid, a list of ``{parameter: value}``.

    Parameters
    ----------
    grid : dict or list of dict
        ``{name: values}``: the full factorial of the value lists (a scalar is one value);
        ``{name: Uniform(...) | Normal(...) | value}``: a Monte Carlo sample of ``samples``
        runs from ``numpy.random.default_rng(seed)`` (drawn here, so every executor runs the
        same values); or a list of run dicts as they are.
    samples, seed : int, optional
        Monte Carlo only (``samples`` required there).

    Examples
    --------
    >>> runs_of({"a": [1, 2], "b": [10.0, 20.0]})
    [{'a': 1, 'b': 10.0}, {'a': 1, 'b': 20.0}, {'a': 2, 'b': 10.0}, {'a': 2, 'b': 20.0}]
    >>> len(runs_of({"a": Uniform(0, 1), "b": 3.0}, samples=5, seed=1))
    5
    """
    if isinstance(grid, (list, tuple)):
        if not all(isinstance(r, dict) for r in grid):
            raise TypeError("a grid given as a list must hold one dict {parameter: value} per run")
        return [dict(r) for r in grid]
    if not isinstance(grid, dict) or not grid:
        raise TypeError(f"grid must be a dict of parameter -> values (or a list of run dicts), not {grid!r:.60}")
    random = {k: v for k, v in grid.items() if isinstance(v, (Uniform, Normal))}
    if random:
        if not samples or samples < 1:
            raise ValueError(f"a Monte Carlo grid ({', '.join(random)} random) needs samples=<number of runs> "
                             "(and seed=<int> to repeat it)")
        lists = [k for k, v in grid.items() if k not in random and np.ndim(v) > 0 and not isinstance(v, str)]
        if lists:
            raise ValueError(f"a Monte Carlo grid takes distributions or fixed values; {', '.join(lists)} "
                             "given as lists -> run one study per value, or draw them too")
        rng = np.random.default_rng(seed)
        drawn = {k: d.sample(rng, samples) for k, d in random.items()}
        return [{k: (float(drawn[k][i]) if k in drawn else v) for k, v in grid.items()} for i in range(samples)]
    names = list(grid)
    axes = [list(v) if np.ndim(v) > 0 and not isinstance(v, str) else [v] for v in grid.values()]
    return [dict(zip(names, combo)) for combo in itertools.product(*axes)]


# --- where the model comes from ---------------------------------------------------------------
@dataclass(frozen=True)
class Recipe:
    """How a worker makes the model: ``kind`` ``"file"`` (a model file's path), ``"build"``
    (a ``build(**kwargs)`` callable) or ``"model"`` (a model or assembled system), and a
    ``token`` naming this study's recipe in the workers' caches."""

    kind: str
    source: object
    token: str = field(default_factory=lambda: uuid.uuid4().hex)


def recipe_of(model_or_build):
    """The :class:`Recipe` of what :func:`study` was given."""
    from ..assembly.system import MultibodySystem
    from ..modeling.model import Model

    if isinstance(model_or_build, (str, os.PathLike)):
        return Recipe("file", os.path.abspath(os.fspath(model_or_build)))
    if isinstance(model_or_build, (Model, MultibodySystem)):
        return Recipe("model", model_or_build)
    if callable(model_or_build):
        return Recipe("build", model_or_build)
    raise TypeError(f"study() takes a Model, a build(**kwargs) function or a model file's path, not "
                    f"{type(model_or_build).__name__}")


#: what each process built from a recipe: (token, build arguments) -> compiled system
_PREPARED = {}


def prepared(recipe, build_kwargs, backend):
    """The system of ``recipe`` with ``build_kwargs``, assembled and compiled once per process."""
    key = (recipe.token, tuple(sorted(build_kwargs.items())), backend)
    if key not in _PREPARED:
        from ..assembly.system import MultibodySystem
        from ..simulation.setup import system_of

        if recipe.kind == "file":
            from ..modeling.loader import load_model

            model = load_model(recipe.source, **build_kwargs)
        elif recipe.kind == "build":
            model = recipe.source(**build_kwargs)
        else:
            if build_kwargs:
                raise ValueError(f"build() arguments {sorted(build_kwargs)} need a build function or a model file, "
                                 "not a built model -> pass the build function (or the file's path), or name "
                                 "component parameters as '<component>.<parameter>'")
            model = recipe.source
        system = model if isinstance(model, MultibodySystem) else None
        _PREPARED[key] = system_of(model if system is None else system, None, backend)
    return _PREPARED[key]


# --- one chunk of runs, where it runs -----------------------------------------------------------
def run_chunk(recipe, chunk, t_end, metrics, outputs, keep, options):
    """Rows ``(index, row, kept)`` of the runs ``chunk`` (a list of ``(index, run dict)``): see
    :func:`study`. Ctrl-C or SIGTERM stops it: it raises
    :class:`~mbcomp.analysis.executors.ChunkStopped` with the rows of the runs that finished
    (the run it stopped is no row)."""
    rows = []
    try:
        with stoppable():
            for index, run in chunk:
                if stop_requested():  # the dispatch was stopped (a Dask task: no signal reaches it)
                    raise Terminated("stop requested")
                rows.append((index,) + _one(recipe, run, t_end, metrics, outputs, keep, options))
    except (KeyboardInterrupt, Terminated) as exc:  # SimulationInterrupted is a KeyboardInterrupt
        raise ChunkStopped(rows, signal_name(exc)) from None
    return rows


def _one(recipe, run, t_end, metrics, outputs, keep, options):
    """``(row, kept)``: one run's metrics, status, message and CPU time, and what is kept."""
    from ..simulation.driver import simulate

    cpu = time.process_time()
    build_kwargs = {k: v for k, v in run.items() if "." not in k}
    params = {k: v for k, v in run.items() if "." in k}
    row, kept = {name: math.nan for name in metrics}, None
    try:
        system = prepared(recipe, build_kwargs, options.get("backend", "auto"))
        res = simulate(system, t_end=t_end, params=params, **options)
        status, message = res.status, res.message
        for name, fn in metrics.items():
            try:
                row[name] = float(fn(res))
            except Exception as exc:  # noqa: BLE001 - a user's metric: reported in its row
                message += f"; metric {name!r} failed ({type(exc).__name__}: {exc})"
        if keep == "all":
            kept = res
        elif keep == "outputs":
            kept = {"time": res.time, **{n: res[n] for n in outputs if n in res}}
    except (ModelError, SimulationError, ValueError, TypeError) as exc:  # bad values, a law failing at the start
        status, message = "error", f"{type(exc).__name__}: {exc}"
    row.update(status=status, message=message, cpu_time=time.process_time() - cpu)
    return row, kept


#: simulate options a batch honours (:func:`mbcomp.batch`); others need ``simulate`` per run
BATCH_OPTIONS = ("t_start", "rtol", "atol", "n_out", "dt_out", "method", "stabilization", "alpha", "beta",
                 "max_step", "max_steps", "backend")


def run_batch_chunk(recipe, chunk, t_end, metrics, outputs, keep, options):
    """Rows ``(index, row, kept)`` of the runs ``chunk`` as :func:`mbcomp.batch` calls, one per
    set of ``build()`` arguments (and of parameter names): the runs of a structure integrate
    in one C call. Metrics read each run as it ends (``batch(..., reduce=...)``: a
    :class:`~mbcomp.analysis.batch_result.OneRun`, ``r["column"]``, ``r.time``, ``r.status``; a
    run finished by ``simulate``, its ``Result``), so no table of every column of every run is
    kept; ``cpu_time`` is the batch's wall time per run.
    A batch that cannot start (a model it cannot run) gives every run of it an ``"error"`` row."""
    from .batch import batch

    unknown = sorted(set(options) - set(BATCH_OPTIONS))
    if unknown or keep == "all":
        raise ValueError(f"a batch study cannot honour {', '.join(unknown) or 'keep=all'} (a batch returns arrays, "
                         "not Results, and runs simulate's default path only) -> use executor=None, a process pool "
                         "or 'dask' without batch")
    groups = {}
    for index, run in chunk:
        key = (tuple(sorted((k, v) for k, v in run.items() if "." not in k)), tuple(sorted(k for k in run if "." in k)))
        groups.setdefault(key, []).append((index, run))
    rows = []
    for (build_args, names), part in groups.items():
        opts = {k: v for k, v in options.items() if k != "backend"}
        wall = time.perf_counter()
        try:
            system = prepared(recipe, dict(build_args), options.get("backend", "auto"))
            res = batch(system, [{n: run[n] for n in names} for _, run in part], t_end=t_end,
                        outputs="all" if metrics or keep else None, threads=1 if _in_worker() else None,
                        reduce=lambda r: _batch_row(r, metrics, outputs, keep), **opts)
        except SimulationInterrupted as exc:  # Ctrl-C, SIGTERM: the runs that finished are rows
            share = (time.perf_counter() - wall) / len(part)
            done = [(index,) + _with_cpu(exc.result.reduced[k], share) for k, (index, _) in enumerate(part)
                    if exc.result.status[k] == "success" and exc.result.reduced[k] is not None]
            raise ChunkStopped(rows + done, exc.signal) from None
        except (ModelError, SimulationError, ValueError, TypeError) as exc:
            err = {name: math.nan for name in metrics}
            rows += [(i, dict(err, status="error", message=f"{type(exc).__name__}: {exc}", cpu_time=0.0), None)
                     for i, _ in part]
            continue
        share = (time.perf_counter() - wall) / len(part)
        rows += [(index,) + _with_cpu(res.reduced[k], share) for k, (index, _) in enumerate(part)]
    return rows


def _with_cpu(row_kept, seconds):
    """A batch run's ``(row, kept)`` with its share of the batch's time as ``cpu_time``."""
    row, kept = row_kept
    return dict(row, cpu_time=seconds), kept


def _in_worker():
    """Whether this runs in a study's worker (another process, or a Dask worker's thread): a batch
    there keeps to one thread, the executor spreading the work over the cores."""
    import multiprocessing
    import threading

    return multiprocessing.parent_process() is not None or threading.current_thread() is not threading.main_thread()


def _batch_row(view, metrics, outputs, keep):
    """``(row, kept)`` of one run of a batch (see :func:`_one`), as the batch hands it over."""
    row, message = {name: math.nan for name in metrics}, view.message
    for name, fn in metrics.items():
        try:
            row[name] = float(fn(view))
        except Exception as exc:  # noqa: BLE001 - a user's metric: reported in its row
            message += f"; metric {name!r} failed ({type(exc).__name__}: {exc})"
    kept = {"time": view.time, **{n: view[n] for n in outputs if n in view}} if keep == "outputs" else None
    row.update(status=view.status, message=message)
    return row, kept


# --- the result -------------------------------------------------------------------------------
class StudyResult:
    """The table of a study: one row per run, in the order of the runs.

    Attributes
    ----------
    columns : list of str
        Parameter columns, metric columns, ``status``, ``message``, ``cpu_time`` (s).
    runs : list of dict
        The runs' parameter values.
    results : list or None
        Per run, the kept :class:`~mbcomp.simulation.result.Result` (``keep="all"``) or
        ``{"time": ..., output: ...}`` (``keep="outputs"``); ``None`` if nothing was kept.
    stats : dict
        ``runs``, ``failed``, ``wall_time`` (s), ``executor``, ``chunks``.
    """

    def __init__(self, parameters, metrics, rows, runs, results, stats):
        self.parameters, self.metrics = list(parameters), list(metrics)
        self.columns = self.parameters + self.metrics + ["status", "message", "cpu_time"]
        self.runs, self.results, self.stats = runs, results, stats
        self._data = {c: [r.get(c) for r in rows] for c in self.columns}

    def __len__(self):
        return len(self.runs)

    def __getitem__(self, column):
        if column not in self._data:
            raise KeyError(f"no column {column!r}; the columns are {', '.join(self.columns)}")
        vals = self._data[column]
        return np.array(vals, dtype=object if column in ("status", "message") else float) \
            if all(isinstance(v, (int, float, np.floating, np.integer)) for v in vals) or column in (
                "status", "message") else np.array(vals, dtype=object)

    @property
    def failed(self):
        """Indices of the runs that did not end in ``"success"``."""
        return [i for i, s in enumerate(self._data["status"]) if s != "success"]

    def to_csv(self, path):
        """Write the table to ``path`` (one header row, one row per run)."""
        import csv

        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(self.columns)
            for i in range(len(self)):
                w.writerow([_cell(self._data[c][i]) for c in self.columns])
        return path

    def to_dataframe(self):
        """The table as a ``pandas.DataFrame``: one row per run (index ``run``), the parameters,
        metrics, ``status``, ``message`` and ``cpu_time`` as columns, failed runs kept with their
        status; ``df.attrs``: ``parameters``, ``metrics``, ``stats``
        (:func:`mbcomp.analysis.study_tables.to_dataframe`). Needs pandas
        (``pip install mbcomp[data]``).

        Examples
        --------
        >>> rows = [{"k": 1.0, "y": 2.0, "status": "success", "message": "", "cpu_time": 0.0}]
        >>> StudyResult(["k"], ["y"], rows, [{"k": 1.0}], None, {}).to_dataframe().loc[0, "y"]
        np.float64(2.0)
        """
        from .study_tables import to_dataframe

        return to_dataframe(self)

    def to_xarray(self):
        """The table as an ``xarray.Dataset``: for a full grid the parameters are dimensions
        (``ds["metric"].sel({"j.w0": 2.0})``), else a ``run`` dimension with the parameters
        as coordinates (:func:`mbcomp.analysis.study_tables.to_xarray`). Needs xarray.

        Examples
        --------
        >>> rows = [{"k": v, "y": 2 * v, "status": "success", "message": "", "cpu_time": 0.0} for v in (1.0, 3.0)]
        >>> ds = StudyResult(["k"], ["y"], rows, [{"k": 1.0}, {"k": 3.0}], None, {}).to_xarray()
        >>> ds["y"].dims, float(ds["y"].sel(k=3.0))
        (('k',), 6.0)
        """
        from .study_tables import to_xarray

        return to_xarray(self)

    def _repr_html_(self):
        """The study's summary in a notebook (:func:`mbcomp.analysis.study_tables.study_html`)."""
        from .study_tables import study_html

        return study_html(self)

    def plot(self, x, y, path=None):
        """``y`` against ``x`` (columns), failed runs marked; saved to ``path`` when given."""
        from .study_plots import line_plot

        return line_plot(self, x, y, path)

    def heatmap(self, x, y, z, path=None):
        """``z`` over the 2-D grid of ``x`` and ``y``; saved to ``path`` when given."""
        from .study_plots import heat_map

        return heat_map(self, x, y, z, path)


def _cell(v):
    return f"{v:.12g}" if isinstance(v, (float, np.floating)) else v


# --- the study ----------------------------------------------------------------------------------
def study(model_or_build, grid, *, t_end=1.0, metrics=None, outputs=(), keep=None, executor=None, samples=None,
          seed=None, chunk=None, progress=False, batch=False, **simulate_options):
    """Run a model over a grid or a Monte Carlo sample; one row per run.

    Parameters
    ----------
    model_or_build : Model, MultibodySystem, callable or path
        The model, a ``build(**kwargs) -> Model`` function, or a model file's path (the form
        every executor can send: a file is loaded in each worker).
    grid : dict or list of dict
        See :func:`runs_of`: value lists (full factorial), distributions (:class:`Uniform`,
        :class:`Normal`; with ``samples`` and ``seed``), or the runs themselves. Names with a
        dot are component parameters, others ``build()`` arguments (module notes).
    t_end : float
        End of every run (s).
    metrics : dict, optional
        ``{name: f(Result) -> float}``, evaluated where the run happened.
    outputs : list of str, optional
        Columns kept per run with ``keep="outputs"``.
    keep : {None, "outputs", "all"}
        What of each run comes back besides its row: nothing, the ``outputs`` columns, or the
        whole :class:`~mbcomp.simulation.result.Result`.
    executor : None, "batch", concurrent.futures.Executor, "dask", "tcp://host:port" or dask Client
        Where the runs go (:mod:`mbcomp.analysis.executors`); ``"batch"``: in this process, the
        runs of each structure as one :func:`mbcomp.batch` (one compiled call, threads).
    chunk : int, optional
        Runs per task (default: about four tasks per worker).
    batch : bool
        Each task's runs as one :func:`mbcomp.batch` on its worker (one thread each), e.g. a
        batch per Dask worker. A batch runs smooth models on ``simulate``'s default path
        (``dop853``/``dopri5``, no events or inputs) and hands metrics a
        :class:`~mbcomp.analysis.batch_result.OneRun` as each run ends; ``keep="all"`` is refused.
    progress : bool
        A progress bar counting finished runs.
    **simulate_options
        Passed to every :func:`mbcomp.simulate` (``rtol``, ``method``, ``n_out``, ...).

    Raises
    ------
    StudyInterrupted
        Ctrl-C or SIGTERM stopped the study (on any executor): ``.result`` holds the rows of
        the runs that finished.

    Returns
    -------
    StudyResult
        One row per run; ``status`` is the run's own (``"success"``, ``"inaccurate"``,
        ``"failed"``, ``"budget"``, ...) or ``"error"`` when it raised before integrating (a bad
        parameter value, an initialization failure, a law failing at the start), with the
        exception's message naming the component.
    """
    metrics = dict(metrics or {})
    for name, fn in metrics.items():
        if not callable(fn):
            raise TypeError(f"metric {name!r} must be a function of a Result, not {type(fn).__name__}")
    if keep not in (None, "outputs", "all"):
        raise ValueError(f"keep={keep!r}: use None, 'outputs' (the outputs columns) or 'all' (whole Results)")
    runs = runs_of(grid, samples, seed)
    recipe = recipe_of(model_or_build)
    params = list(dict.fromkeys(k for r in runs for k in r))
    wall = time.perf_counter()
    args = (t_end, metrics, list(outputs), keep, simulate_options)
    task = run_batch_chunk if batch or executor == "batch" else run_chunk
    done, info = dispatch(executor, task, recipe, runs, args, chunk, progress)
    stopped = info.pop("interrupted")
    finished = [runs[i] for i, _, _ in done]
    rows = [dict(runs[i], **row) for i, row, _ in done]
    stats = dict(runs=len(finished), failed=sum(1 for r in rows if r["status"] != "success"),
                 wall_time=time.perf_counter() - wall, **info)
    res = StudyResult(params, metrics, rows, finished, [k for _, _, k in done] if keep else None, stats)
    if stopped:
        raise StudyInterrupted(res, stopped, f"study interrupted by {stopped}: {len(finished)} of {len(runs)} runs "
                                             "finished (their rows are kept)")
    return res
