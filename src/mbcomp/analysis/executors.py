"""Where a study's runs go: this process, a ``concurrent.futures`` executor, or Dask.

:func:`dispatch` cuts the runs into chunks (a task carries many runs: a run of a compiled
model takes milliseconds, a task's round trip about as long), orders them so that runs of the
same ``build()`` arguments share chunks, and sends each chunk to :func:`~mbcomp.analysis.study.run_chunk`:

* ``executor=None``: in this process, one chunk after the other;
* any :class:`concurrent.futures.Executor` (a ``ProcessPoolExecutor``): one task per chunk;
  the recipe is pickled with each task (a path or a module-level ``build`` function; a
  model holding lambdas cannot be pickled -- the error says what to pass instead);
* ``"dask"``: a :class:`dask.distributed.LocalCluster` on this machine (processes, one thread
  each), closed afterwards; ``"tcp://host:port"``: a client to that scheduler; or a
  ``dask.distributed.Client``. The recipe is scattered to every worker once (broadcast), and
  Dask reschedules the tasks of a worker that dies.

Each worker process keeps the systems it built (:data:`mbcomp.analysis.study._PREPARED`), so
a model is assembled and compiled once per worker, whatever the number of chunks.

Examples
--------
>>> from mbcomp.analysis.executors import chunks
>>> [len(c) for c in chunks(list(enumerate([{"a": 1}] * 10)), 4)]
[4, 4, 2]
"""
from __future__ import annotations

import math
import os

__all__ = ["dispatch", "chunks", "workers_of", "dask_client", "progress_bar", "tick"]


def chunks(indexed_runs, size):
    """``indexed_runs`` (``(index, run)`` pairs) in lists of ``size``, runs of equal ``build()``
    arguments (names without a dot) next to each other."""
    def structure(item):
        return repr(sorted((k, v) for k, v in item[1].items() if "." not in k))

    ordered = sorted(indexed_runs, key=structure)
    return [ordered[i: i + size] for i in range(0, len(ordered), size)]


def workers_of(executor):
    """How many runs an executor runs at once (1 in-process)."""
    if executor is None:
        return 1
    n = getattr(executor, "_max_workers", None)
    if n:
        return int(n)
    try:
        return max(1, len(executor.scheduler_info()["workers"]))  # a dask Client
    except Exception:  # noqa: BLE001 - anything else: as many as this machine has cores
        return os.cpu_count() or 1


def dispatch(executor, recipe, runs, job, chunk=None, progress=False):
    """``(rows, kept, info)``: every run's row (parameter values first) in the order of
    ``runs``, what each kept, and ``{"executor", "chunks", "workers"}``."""
    from .study import run_chunk

    client, close = dask_client(executor)
    target = client if client is not None else executor
    n = workers_of(target)
    size = chunk or max(1, math.ceil(len(runs) / (4 * n)))
    parts = chunks(list(enumerate(runs)), size)
    args = (job["t_end"], job["metrics"], job["outputs"], job["keep"], job["options"])
    bar = progress_bar(len(runs)) if progress else None
    done = []
    try:
        if target is None:
            for part in parts:
                done.extend(run_chunk(recipe, part, *args))
                tick(bar, len(part))
        elif client is not None:
            done = _on_dask(client, recipe, parts, args, bar)
        else:
            done = _on_futures(executor, recipe, parts, args, bar)
    finally:
        if bar is not None:
            bar.close()
        if close is not None:
            close()
    done.sort(key=lambda x: x[0])
    rows = [dict(runs[i], **row) for i, row, _ in done]
    kind = "serial" if target is None else ("dask" if client is not None else type(executor).__name__)
    return rows, [k for _, _, k in done], dict(executor=kind, chunks=len(parts), workers=n)


def _on_futures(executor, recipe, parts, args, bar):
    import pickle
    from concurrent.futures import as_completed

    from .study import run_chunk

    try:
        pickle.dumps((recipe, args))
    except Exception as exc:  # noqa: BLE001 - pickle raises many types
        raise TypeError(f"the study cannot be sent to {type(executor).__name__}'s worker processes: "
                        f"{type(exc).__name__}: {exc} -> pass the model file's path or a build function defined "
                        "at module level (not a lambda or a model holding lambda laws), metrics defined at module "
                        "level, or use executor='dask' (it sends lambdas)") from exc
    return _collect([executor.submit(run_chunk, recipe, part, *args) for part in parts], as_completed, bar)


def _collect(futures, as_completed, bar):
    """Every row of the chunks' ``futures``, counted on ``bar`` as each chunk finishes."""
    done = []
    for fut in as_completed(futures):
        rows = fut.result()
        done.extend(rows)
        tick(bar, len(rows))
    return done


def _on_dask(client, recipe, parts, args, bar):
    from distributed import as_completed

    from .study import run_chunk

    shared = client.scatter(recipe, broadcast=True, hash=False)  # the recipe travels once per worker
    return _collect([client.submit(run_chunk, shared, part, *args, pure=False) for part in parts], as_completed, bar)


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
        client = Client(cluster)

        def close():
            client.close()
            cluster.close()
        return client, close
    if executor.startswith("tcp://"):
        client = Client(executor)
        return client, client.close
    raise ValueError(f"executor={executor!r}: use None, a concurrent.futures executor, 'dask' (a local cluster), "
                     "'tcp://host:port' (a running scheduler) or a dask Client")


def progress_bar(total):
    """A progress bar (tqdm) counting ``total`` finished runs."""
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="run", leave=False)


def tick(bar, n):
    """Count ``n`` more finished runs on ``bar`` (``None``: no bar)."""
    if bar is not None:
        bar.update(n)
