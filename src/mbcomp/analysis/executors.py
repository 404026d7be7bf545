"""Where a study's runs go: this process, a ``concurrent.futures`` executor, or Dask.

:func:`dispatch` cuts the runs into chunks (a task carries many runs: a run of a compiled
model takes milliseconds, a task's round trip about as long), orders them so that runs of the
same ``build()`` arguments share chunks, and sends each chunk to the task it is given (a study's
:func:`~mbcomp.analysis.study.run_chunk`; this module knows nothing of studies):

* ``executor=None``: in this process, one chunk after the other;
* ``"batch"``: in this process, every item in one chunk (a study's task then runs them as one
  :func:`mbcomp.batch`: one compiled call, threads);
* any :class:`concurrent.futures.Executor` (a ``ProcessPoolExecutor``): one task per chunk;
  the recipe is pickled with each task (a path or a module-level ``build`` function; a
  model holding lambdas cannot be pickled -- the error says what to pass instead);
* ``"dask"``: a :class:`dask.distributed.LocalCluster` on this machine (processes, one thread
  each), closed afterwards; ``"tcp://host:port"``: a client to that scheduler; or a
  ``dask.distributed.Client``. The recipe is scattered to every worker once (broadcast), and
  Dask reschedules the tasks of a worker that dies.

Each worker process keeps the systems it built (see :mod:`mbcomp.analysis.study`), so a model
is assembled and compiled once per worker, whatever the number of chunks.

Ctrl-C and SIGTERM stop a dispatch on every executor and keep what finished
(``info["interrupted"]``): a task running in a process's main thread listens to both while it
runs (:func:`stoppable`) and hands back the rows it finished (:class:`ChunkStopped`); tasks not
started are cancelled; a :class:`Workers` pool (``--executor processes``) is told to stop its
running tasks and, by its owner, terminated, so no worker process is left behind; a Dask task
runs in a worker's thread, which no signal reaches: it is told through a Dask ``Event`` to stop
before its next run (:func:`stop_requested`), so it hands back its finished rows when the run
it is in ends within :data:`STOP_GRACE` s (else they are lost with it); the local cluster is
closed.

Examples
--------
>>> from mbcomp.analysis.executors import chunks
>>> [len(c) for c in chunks(list(enumerate([{"a": 1}] * 10)), 4)]
[4, 4, 2]
"""
from __future__ import annotations

import math
import multiprocessing
import os
import signal
import threading
import time
import uuid
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

from ..simulation.endings import Terminated, sigterm_interrupts

__all__ = ["dispatch", "chunks", "workers_of", "dask_client", "progress_bar", "tick", "Workers", "ChunkStopped",
           "stoppable", "stop_requested", "signal_name", "CONNECT_TIMEOUT", "STOP_GRACE", "STOP_POLL"]

#: seconds a ``"tcp://host:port"`` executor waits for its Dask scheduler to answer
CONNECT_TIMEOUT = 5.0
#: seconds the running tasks of a :class:`Workers` pool have, after a signal, to hand back the
#: rows they finished (a run stops at its next step; then its worker is terminated)
STOP_GRACE = 5.0
#: seconds between a Dask task's questions whether its dispatch was stopped (a scheduler round trip)
STOP_POLL = 0.2


class ChunkStopped(Exception):
    """A task stopped by Ctrl-C or SIGTERM, carrying the ``rows`` it finished before (each
    ``(index, row, kept)``) and the ``signal`` (``"SIGINT"`` or ``"SIGTERM"``).

    Examples
    --------
    >>> import pickle
    >>> e = pickle.loads(pickle.dumps(ChunkStopped([(3, {"x": 1.0}, None)], "SIGTERM")))
    >>> e.rows, e.signal
    ([(3, {'x': 1.0}, None)], 'SIGTERM')
    """

    def __init__(self, rows, signal):
        super().__init__(f"stopped by {signal} after {len(rows)} finished")
        self.rows, self.signal = rows, signal

    def __reduce__(self):  # it travels back from a worker process
        return type(self), (self.rows, self.signal)


def signal_name(exc):
    """``"SIGTERM"`` for :class:`~mbcomp.simulation.endings.Terminated`, the ``signal`` an
    exception carries (:class:`~mbcomp.errors.SimulationInterrupted`), else ``"SIGINT"``."""
    if isinstance(exc, Terminated):
        return "SIGTERM"
    return getattr(exc, "signal", None) or "SIGINT"


#: set in a :class:`Workers` process by the pool when a signal stopped the dispatch
_STOP = None
#: a Dask task's stop event (its name) and when it was last asked, per worker thread
_LOCAL = threading.local()


def _ignore(_signum, _frame):
    """A handler that does nothing: a signal already tripped when a handler changes finds a
    Python function (``SIG_IGN`` there would raise "signal ignored due to race condition")."""


def _worker_start(stop):
    """A :class:`Workers` process ignores Ctrl-C and SIGTERM between tasks (a signal then
    would end the process and break the pool: the other workers' finished rows would be lost);
    :func:`stoppable` listens to them while a task runs."""
    global _STOP
    _STOP = stop
    signal.signal(signal.SIGINT, _ignore)
    signal.signal(signal.SIGTERM, _ignore)


def _raise_once(signum, _frame):
    signal.signal(signal.SIGINT, _ignore)  # one signal stops the task; a second is not a second error
    signal.signal(signal.SIGTERM, _ignore)
    raise Terminated("SIGTERM") if signum == signal.SIGTERM else KeyboardInterrupt


@contextmanager
def stoppable():
    """While a task runs in a process's main thread, Ctrl-C raises ``KeyboardInterrupt`` and
    SIGTERM :class:`~mbcomp.simulation.endings.Terminated` (the task turns them into
    :class:`ChunkStopped`); the handlers before are restored after. Elsewhere (a Dask worker's
    thread) it does nothing: the task asks :func:`stop_requested` between its runs (in a
    :class:`Workers` process too: a stop asked before the handlers were in place)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGINT, _raise_once)
    signal.signal(signal.SIGTERM, _raise_once)
    try:
        yield
    finally:
        for sig, handler in zip((signal.SIGINT, signal.SIGTERM), before):
            if handler is not None:
                signal.signal(sig, handler)


class Workers(ProcessPoolExecutor):
    """A process pool whose running tasks can be stopped: what ``--executor processes`` makes.

    Its processes ignore Ctrl-C and SIGTERM between tasks; :meth:`stop_running` tells the
    running tasks to stop (each hands back the rows it finished: :class:`ChunkStopped`) and
    the queued ones to return at once; :meth:`terminate` ends every process (no worker left
    behind after a signal, whatever the tasks were doing).

    Examples
    --------
    >>> from mbcomp.analysis.executors import Workers
    >>> with Workers(1) as pool:
    ...     pool.submit(abs, -2).result()
    2
    """

    def __init__(self, max_workers=None):
        ctx = multiprocessing.get_context()
        self.stop = ctx.Event()
        self.max_workers = max_workers or os.cpu_count() or 1
        super().__init__(max_workers=self.max_workers, mp_context=ctx, initializer=_worker_start,
                         initargs=(self.stop,))

    def processes(self):
        """The live worker processes (:class:`multiprocessing.Process`)."""
        return [p for p in dict(self._processes or {}).values() if p.is_alive()]

    def stop_running(self):
        """Ask every task to stop: the running ones at their next step (SIGTERM to the
        processes), the queued ones before they start."""
        self.stop.set()
        for proc in self.processes():
            try:
                os.kill(proc.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass

    def terminate(self):
        """Cancel what has not started, end every worker process and wait for them to go.
        SIGKILL: the processes ignore SIGTERM between tasks, and what a task finished was
        handed back before (:meth:`stop_running`) or is lost with the signal anyway."""
        procs = self.processes()
        self.stop.set()
        self.shutdown(wait=False, cancel_futures=True)
        for proc in procs:
            proc.kill()
        for proc in procs:
            proc.join()


def chunks(indexed_runs, size):
    """``indexed_runs`` (``(index, run)`` pairs) in lists of ``size``, runs of equal ``build()``
    arguments (names without a dot) next to each other."""
    def structure(item):
        return repr(sorted((k, v) for k, v in item[1].items() if "." not in k))

    ordered = sorted(indexed_runs, key=structure)
    return [ordered[i: i + size] for i in range(0, len(ordered), size)]


def workers_of(executor):
    """How many runs an executor runs at once: 1 in-process, a :class:`Workers` pool's
    ``max_workers``, a Dask cluster's workers, else this machine's cores."""
    if executor is None:
        return 1
    n = getattr(executor, "max_workers", None)  # a Workers pool says it
    if n:
        return int(n)
    try:
        return max(1, len(executor.scheduler_info()["workers"]))  # a dask Client
    except Exception:  # noqa: BLE001 - anything else: as many as this machine has cores
        return os.cpu_count() or 1


def dispatch(executor, task, shared, items, args=(), chunk=None, progress=False):
    """Every item through ``task(shared, part, *args)``, in chunks, on ``executor``.

    Parameters
    ----------
    executor : None, "batch", concurrent.futures.Executor, "dask", "tcp://host:port" or dask Client
        Where the tasks run (module notes).
    task : callable
        ``task(shared, part, *args) -> [(index, row, kept), ...]`` for a part, a list of
        ``(index, item)``; a module-level function (it travels to the workers by name). On a
        signal it raises :class:`ChunkStopped` with the rows it finished (see :func:`stoppable`).
    shared : object
        What every task needs (a study's recipe): scattered once to every Dask worker.
    items : list
    args : tuple
        Further arguments of every task.
    chunk : int, optional
        Items per task (default: about four tasks per worker).
    progress : bool
        A progress bar counting finished items.

    Returns
    -------
    done : list
        ``(index, row, kept)`` of every finished item, in the order of ``items``.
    info : dict
        ``executor``, ``chunks``, ``workers``, and ``interrupted``: ``None``, or ``"SIGINT"`` /
        ``"SIGTERM"`` when Ctrl-C or SIGTERM stopped the dispatch (then ``done`` holds the
        items finished before it: the tasks not started are cancelled, a process pool of
        :class:`Workers` is told to stop its running tasks, which hand back what they finished).
    """
    kind = None
    if executor == "batch":  # this process, every item in one task (which runs them as one mbcomp.batch)
        executor, chunk, kind = None, max(1, len(items)), "batch"
    client, close = dask_client(executor)
    target = client if client is not None else executor
    n = workers_of(target)
    size = chunk or max(1, math.ceil(len(items) / (4 * n)))
    parts = chunks(list(enumerate(items)), size)
    bar = progress_bar(len(items)) if progress else None
    done, futures, stopped = [], [], None
    stop = f"mbcomp-stop-{uuid.uuid4().hex}"  # a Dask dispatch's stop event
    try:
        with sigterm_interrupts():  # SIGTERM, like Ctrl-C, is an exception here: the finished rows are kept
            try:
                if target is None:
                    for part in parts:
                        done.extend(task(shared, part, *args))
                        tick(bar, len(part))
                elif client is not None:
                    _on_dask(client, task, shared, parts, args, bar, done, futures, stop)
                else:
                    _on_futures(executor, task, shared, parts, args, bar, done, futures)
            except ChunkStopped as exc:  # the serial task, stopped: its finished rows
                done.extend(exc.rows)
                stopped = exc.signal
            except (KeyboardInterrupt, Terminated) as exc:
                stopped = signal_name(exc)
                _harvest(target, futures, done, stop)
    finally:
        if bar is not None:
            bar.close()
        if close is not None:
            close()
    done.sort(key=lambda x: x[0])
    kind = kind or ("serial" if target is None else ("dask" if client is not None else type(executor).__name__))
    return done, dict(executor=kind, chunks=len(parts), workers=n, interrupted=stopped)


def _on_futures(executor, task, shared, parts, args, bar, done, futures):
    import pickle
    from concurrent.futures import as_completed

    try:
        pickle.dumps((task, shared, args))
    except Exception as exc:  # noqa: BLE001 - pickle raises many types
        raise TypeError(f"the study cannot be sent to {type(executor).__name__}'s worker processes: "
                        f"{type(exc).__name__}: {exc} -> pass the model file's path or a build function defined "
                        "at module level (not a lambda or a model holding lambda laws), metrics defined at module "
                        "level, or use executor='dask' (it sends lambdas)") from exc
    futures.extend(executor.submit(task, shared, part, *args) for part in parts)
    _collect(futures, as_completed, bar, done)


def _collect(futures, as_completed, bar, done):
    """Every row of the chunks' ``futures`` into ``done``, counted on ``bar`` as each chunk finishes."""
    for fut in as_completed(list(futures)):
        rows = fut.result()
        done.extend(rows)
        futures.remove(fut)  # what is left in futures after a signal is not collected yet
        tick(bar, len(rows))


def _on_dask(client, task, shared, parts, args, bar, done, futures, stop):
    from distributed import as_completed

    shared = client.scatter(shared, broadcast=True, hash=False)  # travels once per worker
    futures.extend(client.submit(_dask_task, stop, task, shared, part, *args, pure=False) for part in parts)
    _collect(futures, as_completed, bar, done)


def _dask_task(stop, task, shared, part, *args):
    """``task`` on a Dask worker, told to stop between its runs by the Dask ``Event`` named
    ``stop`` (:func:`stop_requested`; no signal reaches a Dask worker's task thread)."""
    _LOCAL.stop, _LOCAL.checked = stop, 0.0
    try:
        return task(shared, part, *args)
    except ChunkStopped as exc:  # its finished rows, as a result (Dask logs a task's error as a failure)
        return exc.rows
    finally:
        _LOCAL.stop = None


def stop_requested():
    """Whether the dispatch of the task calling it was stopped: a :class:`Workers` pool told
    its tasks to stop, or (on Dask, asked at most every :data:`STOP_POLL` s) the dispatch set
    its stop event. A task asks it between its runs."""
    if _STOP is not None and _STOP.is_set():
        return True
    name = getattr(_LOCAL, "stop", None)
    now = time.monotonic()
    if name is None or now - _LOCAL.checked < STOP_POLL:
        return False
    _LOCAL.checked = now
    from distributed import Event

    return Event(name).is_set()


def _harvest(target, futures, done, stop):
    """After a signal: the rows of the tasks that finished but were not collected yet, and of
    the running tasks, told to stop (a :class:`Workers` pool's at their next step, a Dask
    cluster's before their next run), each handing back its finished rows within
    :data:`STOP_GRACE` s; every other task cancelled."""
    dask = type(target).__name__ == "Client"
    if dask:
        from distributed import Event, wait

        pending = [f for f in futures if not f.done()]
        try:
            Event(stop, client=target).set()
        except Exception:  # noqa: BLE001 - a scheduler gone: nothing more comes back
            pending = []
    else:
        from concurrent.futures import wait

        pending = [f for f in futures if not f.cancel() and not f.done()]  # cancel() fails only on running ones
        if pending and isinstance(target, Workers):
            target.stop_running()
        else:
            pending = []
    try:
        if pending:
            wait(pending, timeout=STOP_GRACE)
    except (Exception, KeyboardInterrupt, Terminated):  # noqa: BLE001 - the grace spent, a second signal, a
        pass                                              # worker lost: what finished is kept below
    if dask:
        try:
            target.cancel([f for f in futures if not f.done()])
        except Exception:  # noqa: BLE001 - a scheduler gone: its tasks went with it
            pass
    for fut in futures:
        if not fut.done() or fut.cancelled():
            continue
        try:
            done.extend(fut.result())
        except ChunkStopped as exc:
            done.extend(exc.rows)
        except BaseException:  # noqa: BLE001 - a task lost to the interruption (a killed worker): no rows
            continue


def dask_client(executor):
    """``(client, close)`` for a Dask executor (``"dask"``, ``"tcp://..."`` or a Client), else
    ``(None, None)``; ``close`` shuts down what was started here."""
    if executor is None or not (isinstance(executor, str) or type(executor).__name__ == "Client"):
        return None, None
    if not isinstance(executor, str):
        return executor, None
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ImportError(f"executor={executor!r} needs Dask: pip install 'mbcomp[dask]' (dask[distributed])") from None
    if executor == "dask":
        cluster = LocalCluster(n_workers=min(os.cpu_count() or 1, 4), threads_per_worker=1, processes=True,
                               dashboard_address=":0")  # (None still tries port 8787)
        client = None
        try:
            client = Client(cluster)
            client.run(_ignore_ctrl_c)  # the cluster is this command's: Ctrl-C reaches it through this process
        except BaseException:  # Ctrl-C, SIGTERM while it starts: its processes go with it
            if client is not None:
                client.close()
            cluster.close()
            raise

        def close():
            client.close()
            cluster.close()
        return client, close
    if executor.startswith("tcp://"):
        try:
            client = Client(executor, timeout=CONNECT_TIMEOUT)
        except OSError as exc:  # refused, unknown host, timed out (TimeoutError is an OSError)
            raise ConnectionError(f"executor {executor}: no Dask scheduler answered within {CONNECT_TIMEOUT:g} s "
                                  f"({type(exc).__name__}: {exc}) -> fix: check the address, start the scheduler "
                                  "(dask scheduler --host HOST --port PORT, and workers: dask worker "
                                  "tcp://HOST:PORT), or use executor 'dask' for a local cluster") from None
        return client, client.close
    raise ValueError(f"executor={executor!r}: use None, a concurrent.futures executor, 'dask' (a local cluster), "
                     "'tcp://host:port' (a running scheduler) or a dask Client")


def _ignore_ctrl_c():
    """In a local Dask cluster's worker process (run there by :func:`dask_client`): Ctrl-C at
    the terminal, which signals every process of the command, does not kill the worker; the
    dispatch stops its tasks (:func:`stop_requested`) and closes the cluster."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def progress_bar(total):
    """A progress bar (tqdm) counting ``total`` finished runs."""
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="run", leave=False)


def tick(bar, n):
    """Count ``n`` more finished runs on ``bar`` (``None``: no bar)."""
    if bar is not None:
        bar.update(n)
