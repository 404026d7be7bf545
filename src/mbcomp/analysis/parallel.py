"""Map one picklable function over items on an executor: what sweeps and benchmarks share.

:func:`map_on` is the small sibling of :func:`mbcomp.analysis.executors.dispatch` for work
that is not a study of simulation runs (a linearization per grid value, a tolerance sweep per
solver): each item is one task, results come back in the order of the items, and the same
executors are accepted -- ``None`` (in this process), any :class:`concurrent.futures.Executor`,
``"dask"`` (a local cluster, closed afterwards), ``"tcp://host:port"`` or a Dask ``Client``.
:func:`executor_of` turns the command line's ``--executor`` text into one of these
(``"processes"``: a :class:`~concurrent.futures.ProcessPoolExecutor`).

Examples
--------
>>> from mbcomp.analysis.parallel import map_on
>>> map_on(None, abs, [-1, 2, -3])
[1, 2, 3]
"""
from __future__ import annotations

import os
import pickle
from contextlib import contextmanager

from ..simulation.endings import sigterm_interrupts

__all__ = ["map_on", "executor_of", "executor_name", "running_on"]


def executor_of(text, workers=None):
    """``(executor, owned)`` for the command line's ``--executor`` value ``text``.

    Parameters
    ----------
    text : str or None
        ``None``/``"serial"``: in this process; ``"processes"``: a new process pool
        (:class:`~mbcomp.analysis.executors.Workers`, a
        :class:`~concurrent.futures.ProcessPoolExecutor` whose running tasks can be stopped)
        with ``workers`` processes (default: the cores, at most 4); ``"dask"`` or
        ``"tcp://host:port"``: passed on as they are.
    workers : int, optional
        Processes of the pool (``"processes"`` only).

    Returns
    -------
    executor : None, Executor or str
    owned : bool
        Whether the caller must shut the executor down (``executor.shutdown()``, or
        ``executor.terminate()`` after a signal: no worker process left behind).

    Examples
    --------
    >>> from mbcomp.analysis.parallel import executor_of
    >>> executor_of(None), executor_of("dask")
    ((None, False), ('dask', False))
    """
    if text is None or text == "serial":
        return None, False
    if text == "processes":
        from .executors import Workers

        return Workers(max_workers=workers or min(os.cpu_count() or 1, 4)), True
    if text == "dask" or text.startswith("tcp://"):
        return text, False
    raise ValueError(f"--executor {text}: use serial, processes (a process pool on this machine), dask (a local "
                     "Dask cluster) or tcp://host:port (a running Dask scheduler)")


@contextmanager
def running_on(text, workers=None):
    """The executor of the command line's ``--executor`` ``text`` (:func:`executor_of`) for a
    ``with`` block, in which SIGTERM raises as Ctrl-C does; a process pool made here is shut
    down after the block, or, when the block raises (an error, Ctrl-C, SIGTERM), its processes
    are ended at once: none is left behind.

    Examples
    --------
    >>> from mbcomp.analysis.parallel import map_on, running_on
    >>> with running_on("processes", 1) as ex:
    ...     map_on(ex, abs, [-1, 2])
    [1, 2]
    """
    with sigterm_interrupts():
        executor, owned = executor_of(text, workers)
        try:
            yield executor
        except BaseException:
            if owned:
                executor.terminate()
            raise
        if owned:
            executor.shutdown()


def executor_name(executor):
    """A short name of an executor for reports: ``serial``, ``dask``, ``processes`` (a
    :class:`~mbcomp.analysis.executors.Workers` pool), ``ProcessPoolExecutor``."""
    if executor is None:
        return "serial"
    if isinstance(executor, str):
        return "dask" if executor == "dask" else f"dask ({executor})"
    name = type(executor).__name__
    return "dask" if name == "Client" else ("processes" if name == "Workers" else name)


def map_on(executor, fn, items, progress=False):
    """``[fn(x) for x in items]``, each call a task on ``executor``, in the order of ``items``.

    Parameters
    ----------
    executor : None, concurrent.futures.Executor, "dask", "tcp://host:port" or dask Client
        Where the calls run (module notes). With a ``concurrent.futures`` executor ``fn`` and
        the items must pickle (module-level functions and classes); Dask also sends lambdas.
    fn : callable
        One argument; an exception it raises is raised here (the first in item order).
    items : iterable
    progress : bool
        A progress bar counting finished calls.

    Returns
    -------
    list
        The results, ``results[k] = fn(items[k])``.
    """
    from .executors import progress_bar, dask_client, tick

    items = list(items)
    bar = progress_bar(len(items)) if progress and items else None
    client, close = dask_client(executor)
    try:
        if client is None and executor is None:
            out = []
            for x in items:
                out.append(fn(x))
                tick(bar, 1)
            return out
        if client is not None:
            from distributed import as_completed

            futures = [client.submit(fn, x, pure=False) for x in items]
        else:
            from concurrent.futures import as_completed

            _check_pickles(executor, fn)
            futures = [executor.submit(fn, x) for x in items]
        for _ in as_completed(futures):
            tick(bar, 1)
        return [f.result() for f in futures]
    finally:
        if bar is not None:
            bar.close()
        if close is not None:
            close()


def _check_pickles(executor, fn):
    try:
        pickle.dumps(fn)
    except Exception as exc:  # noqa: BLE001 - pickle raises many types
        raise TypeError(f"{getattr(fn, '__name__', type(fn).__name__)} cannot be sent to {type(executor).__name__}'s "
                        f"worker processes ({type(exc).__name__}: {exc}) -> define the function (and what it holds, "
                        "e.g. the build function) at module level, or use executor='dask' (it sends lambdas)") from exc
