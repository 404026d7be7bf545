"""Each run's consistent start for :func:`mbcomp.batch`, in this process or in forked workers.

A batch run starts where :func:`mbcomp.simulate` starts: the run's system
(``system.with_params(row)``), consistent initialization with the numeric evaluation
(:func:`~mbcomp.hybrid.contacts.initialize_in_modes`, the same call ``simulate`` makes), the
Lagrange formulation and its start state -- :func:`run_start`. That is Python, and it is most
of a batch's Python time (a closed loop's Newton closure evaluates its rows about seven times
and completes the last: ~1.8 ms a slider-crank run, against ~0.6 ms of C integration), so it would be serial
Python beside C threads that wait for it.

:class:`ForkedStarts` computes the starts of many runs in worker processes forked from this
one (Linux; the workers inherit the system and its programs, nothing is pickled but the
table's indices going out and each run's ``(y0, row mask, message)`` coming back), blocks of
runs in order, while this process integrates the blocks already started. The same code on the
same numbers: the starts are bit for bit those made in this process
(``tests/analysis/test_batch_starts.py``). A worker that dies leaves the starts not received to
this process (a ``concurrent.futures`` pool: broken, not hung).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.analysis.batch_starts import run_start
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5, w0=1.0)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> req = dict(t_start=0.0, stabilization="baumgarte", alpha=10.0, beta=10.0, method="dop853")
>>> s, form, y0 = run_start(mbcomp.assemble(m), {"j.phi0": 0.2}, req)
>>> y0.tolist()   # a hinge's start values as they are: [phi, w]
[0.2, 1.0]
"""
from __future__ import annotations

import itertools
import multiprocessing
import signal
import sys
import warnings

import numpy as np

from ..errors import InitializationError, ModelError, SimulationError
from ..formulations import build
from ..hybrid.contacts import initialize_in_modes
from ..solvers import STEPPERS

__all__ = ["run_start", "start_or_message", "starts_of_runs", "ForkedStarts", "fork_workers", "MIN_FORKED_RUNS"]

#: fewer runs than this start in this process unless workers are asked for (a pool costs ~15 ms
#: to fork and close, and the choice needs a block integrated first)
MIN_FORKED_RUNS = 256

_JOBS = {}  # token -> (system, values, request): what a forked worker reads (inherited, not pickled)
_TOKENS = itertools.count()


def run_start(system, params, req):
    """``(run system, formulation, y0)``: what ``simulate`` makes at the start of a smooth run.

    Parameters
    ----------
    system : MultibodySystem
        The batch's system (not changed).
    params : dict
        The run's parameter values, ``{"component.parameter": value}``.
    req : dict
        ``t_start`` (s), ``stabilization``, ``alpha``, ``beta`` (1/s), ``method``.

    Returns
    -------
    tuple
        The run's system (its ``row_mask`` set by the initialization), the Lagrange
        formulation, and the start state ``[q, u]`` (ndarray).
    """
    s = system.with_params(params)
    init = initialize_in_modes(s, req["t_start"])
    form = run_form(s, req)
    y0 = np.asarray(form.full(req["t_start"], form.initial_state(req["t_start"], init.q, init.u)), float)
    return s, form, y0


def run_form(s, req):
    """The Lagrange formulation of the run system ``s`` (row mask set) for the request ``req``."""
    return build("lagrange", "ode", s, stabilization=req["stabilization"], alpha=req["alpha"], beta=req["beta"],
                 method=req["method"], max_index=STEPPERS[req["method"]].max_index)


def start_or_message(system, params, req):
    """``(run system, formulation, y0, None)`` of :func:`run_start`, or ``(None, None, None,
    message)`` when the run cannot start (its initialization's error, or a law raising at the
    start), named."""
    try:
        return (*run_start(system, params, req), None)
    except (InitializationError, ModelError, SimulationError) as exc:
        return None, None, None, f"{type(exc).__name__}: {exc}"
    except Exception as exc:  # noqa: BLE001 - a law raising at the start: this run's error row, named
        return None, None, None, f"the run could not start: {type(exc).__name__}: {exc}"


def fork_workers(n_runs, wanted):
    """Worker processes for the starts of ``n_runs`` runs: ``wanted`` (``processes=``), or
    None -- decide by measuring (``wanted`` None and :data:`MIN_FORKED_RUNS` runs or more) --
    or 0: none asked, too few runs to measure, or forking not safe here (no ``fork``: not
    Linux; a daemon process -- a Dask or multiprocessing worker -- may not have children)."""
    if wanted is not None:
        wanted = int(wanted)
        if wanted < 0:
            raise ValueError(f"processes={wanted}: give 0 (the starts in this process) or a number of worker "
                             "processes, or None (decided by measuring)")
    if wanted == 0 or (wanted is None and n_runs < MIN_FORKED_RUNS) or not sys.platform.startswith("linux"):
        return 0
    if multiprocessing.current_process().daemon or "fork" not in multiprocessing.get_all_start_methods():
        return 0
    return wanted


def _worker_init():
    """A worker ignores Ctrl-C (the batch itself stops them) and dies on SIGTERM."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _starts_of(args):
    """In a worker: :func:`starts_of_runs` of job ``token``'s runs ``range(a, b)``."""
    token, a, b = args
    return starts_of_runs(*_JOBS[token], a, b)


def starts_of_runs(system, values, req, a, b):
    """``[(y0, row mask, message)]`` of the runs ``range(a, b)`` of the table ``values``, and
    the texts of the warnings their starts raised, ``[(category, text)]`` (once each)."""
    out = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for i in range(a, b):
            s, _, y0, message = start_or_message(system, {name: col[i] for name, col in values.items()}, req)
            out.append((y0, None if s is None else s.row_mask, message))
    return out, list(dict.fromkeys((w.category, str(w.message)) for w in caught))


class ForkedStarts:
    """The starts of runs ``first, first + 1, ...`` computed by ``workers`` forked processes,
    ``block`` runs a task, handed back in order by :meth:`take`.

    Parameters
    ----------
    system : MultibodySystem
        The batch's system (with its programs made: a worker only evaluates).
    values : dict
        The table, ``{name: per-run values}``.
    req : dict
        As for :func:`run_start`.
    first, n_runs, block, workers : int
        Runs ``first .. n_runs - 1``, ``block`` a task, on ``workers`` processes.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> req = dict(t_start=0.0, stabilization="baumgarte", alpha=10.0, beta=10.0, method="dop853")
    >>> with ForkedStarts(mbcomp.assemble(m), {"j.phi0": [0.1, 0.2, 0.3]}, req, 0, 3, 2, 2) as starts:
    ...     [float(y0[0]) for y0, mask, message in starts.take(0, 3)]
    [0.1, 0.2, 0.3]
    """

    def __init__(self, system, values, req, first, n_runs, block, workers):
        import concurrent.futures

        self.job = (system, values, req)
        token = next(_TOKENS)
        _JOBS[token] = self.job
        self.next = first
        self.pool = concurrent.futures.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"),
                                                           initializer=_worker_init)
        try:  # the first submit forks every worker (the fork start method), which inherit the job
            self.tasks = [self.pool.submit(_starts_of, (token, a, min(a + block, n_runs)))
                          for a in range(first, n_runs, block)]
        except BaseException:
            self.pool.shutdown(wait=True, cancel_futures=True)
            raise
        finally:
            del _JOBS[token]
        self.ranges = [(a, min(a + block, n_runs)) for a in range(first, n_runs, block)]
        self.ready = []
        self.warned = set()
        self.broken = None

    def take(self, a, b):
        """``[(y0, row mask, message)]`` of runs ``a .. b - 1`` (in order: ``a`` is the first
        run not taken yet); a run that cannot start has ``y0`` None and its message. Should a
        worker die (killed: its task is lost), the starts not received yet are made in this
        process, with a warning."""
        if a != self.next:
            raise ValueError(f"ForkedStarts.take({a}, {b}): runs are taken in order, the next is {self.next}")
        while len(self.ready) < b - a:
            task, (lo, hi) = self.tasks.pop(0), self.ranges.pop(0)
            out, warned = self._result(task, lo, hi)
            self.ready.extend(out)
            for category, text in warned:
                if text not in self.warned:  # each text once, as in this process
                    self.warned.add(text)
                    warnings.warn(text, category, stacklevel=2)
        got, self.ready = self.ready[: b - a], self.ready[b - a:]
        self.next = b
        return got

    def _result(self, task, lo, hi):
        from concurrent.futures.process import BrokenProcessPool

        if self.broken is None:
            try:
                return task.result()
            except BrokenProcessPool as exc:
                self.broken = exc
                warnings.warn(f"mbcomp.batch: a worker process making the runs' starts ended ({exc}); the starts from "
                              f"run {lo} on are made in this process", RuntimeWarning, stacklevel=3)
        return starts_of_runs(*self.job, lo, hi)

    def close(self):
        """Stop the workers (the starts not taken are dropped; a task under way is finished)."""
        self.pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
