"""The result of :func:`mbcomp.batch`: arrays per column, a status and message per run.

Examples
--------
>>> import numpy as np
>>> from mbcomp.analysis.batch_result import BatchResult
>>> t = np.linspace(0.0, 1.0, 3)
>>> res = BatchResult(t, {"x": np.array([[0.0, 1.0, 2.0], [0.0, 2.0, np.nan]])}, ["success", "failed"],
...                   ["reached t_end", "step size too small"], {"k": [1.0, 2.0]}, np.array([1.0, 0.5]), {})
>>> res["x"].shape, res.failed, res.run(0)["x"].tolist()
((2, 3), [1], [0.0, 1.0, 2.0])
"""
from __future__ import annotations

import numpy as np

__all__ = ["BatchResult", "RunView", "OneRun", "STATUS_OF"]

#: the batch runner's codes (:data:`mbcomp.codegen.batch.STATUS`) as a run's status
STATUS_OF = {0: "success", 1: "failed", 2: "failed", 3: "budget", 4: "failed", 5: "interrupted", 6: "failed",
             7: "failed"}


class _Columns:
    """Columns by name (``self._columns``) and ``"time"``, read like a
    :class:`~mbcomp.simulation.result.Result`; ``_missing(name)`` says what an unknown name lacks."""

    @property
    def names(self):
        """Every column's name."""
        return list(self._columns)

    def __getitem__(self, name):
        if name == "time":
            return self.time
        try:
            return self._columns[name]
        except KeyError:
            raise KeyError(self._missing(name)) from None

    def __contains__(self, name):
        return name == "time" or name in self._columns


class BatchResult(_Columns):
    """Columns of many runs on one output grid.

    Attributes
    ----------
    time : ndarray (n_out,)
        Output times (s), the same for every run.
    status : ndarray of str (n_runs,)
        ``"success"``, ``"failed"`` (the message says where and why), ``"budget"`` (``max_steps``
        spent), ``"interrupted"``, ``"error"`` (the run could not start: an initialization
        failure, a parameter value the model refuses).
    message : list of str
        Per run: why it ended.
    params : dict
        The table: ``{name: per-run values}``.
    t_reached : ndarray (n_runs,)
        Time each run reached (s); its columns after it are NaN.
    reduced : list or None
        Per run, what ``batch(..., reduce=f)`` returned (None for a run not finished).
    stats : dict
        ``runs``, ``failed``, ``threads``, ``processes`` (worker processes that made the starts),
        ``setup_time`` (Python: parameters, consistent initialization, or waiting for the
        workers' starts), ``integrate_time`` (the C calls), ``c_cpu_time`` (their threads' CPU
        time), ``outputs_time``, ``wall_time`` (s); per run ``nfev``, ``nsteps``, ``nreject``, ``c_calls``; ``simulate_reruns`` (runs
        finished by :func:`mbcomp.simulate` after a program guard failed).

    Examples
    --------
    >>> import numpy as np
    >>> res = BatchResult(np.array([0.0, 1.0]), {"x": np.ones((2, 2))}, ["success"] * 2, ["reached t_end"] * 2,
    ...                   {"k": [1.0, 2.0]}, np.ones(2), {})
    >>> res.names, len(res), res.run(1).status
    (['x'], 2, 'success')
    """

    def __init__(self, time, columns, status, message, params, t_reached, stats, reduced=None):
        self.time = np.asarray(time)
        self.reduced = reduced
        self._columns = dict(columns)
        self.status = np.array(list(status), dtype=object)
        self.message = list(message)
        self.params = dict(params)
        self.t_reached = np.asarray(t_reached, float)
        self.stats = dict(stats)

    def __len__(self):
        return len(self.status)

    def _missing(self, name):
        close = [n for n in self._columns if str(name).split(".")[0] in n][:8]
        return (f"no column {name!r} in the batch; similar: {', '.join(close) or 'none'} (ask for output "
                "columns with batch(..., outputs=[...]))")

    @property
    def failed(self):
        """Indices of the runs that did not end in ``"success"``."""
        return [i for i, s in enumerate(self.status) if s != "success"]

    def run(self, i):
        """Run ``i`` as a :class:`RunView` (what a study's metrics read)."""
        return RunView(self, int(i))

    def replace_run(self, i, result, message):
        """Put a :class:`~mbcomp.simulation.result.Result` of the same grid in as run ``i``
        (its columns by name; the grid's rows it did not reach are NaN)."""
        n = min(len(result.time), len(self.time))
        for name, arr in self._columns.items():
            arr[i] = np.nan
            if name in result:
                arr[i, :n] = np.asarray(result[name])[:n]
        self.status[i] = result.status
        self.message[i] = message
        self.t_reached[i] = float(result.time[n - 1]) if n else np.nan


class RunView:
    """One run of a :class:`BatchResult`, read like a :class:`~mbcomp.simulation.result.Result`:
    ``time``, ``status``, ``message``, ``view["column"]`` (``(n_out,)``), ``names``.

    Examples
    --------
    >>> import numpy as np
    >>> res = BatchResult(np.array([0.0, 1.0]), {"x": np.array([[1.0, 2.0], [3.0, 4.0]])}, ["success"] * 2,
    ...                   ["reached t_end"] * 2, {"k": [1.0, 2.0]}, np.ones(2), {})
    >>> v = res.run(1)
    >>> v["x"].tolist(), v.params, "x" in v
    ([3.0, 4.0], {'k': 2.0}, True)
    """

    def __init__(self, batch, i):
        self.batch, self.index = batch, i
        self.time, self.status, self.message = batch.time, batch.status[i], batch.message[i]
        self.params = {name: col[i] for name, col in batch.params.items()}

    @property
    def names(self):
        return self.batch.names

    def __getitem__(self, name):
        return self.time if name == "time" else self.batch[name][self.index]

    def __contains__(self, name):
        return name in self.batch


class OneRun(_Columns):
    """One run's columns on their own (what ``batch(..., reduce=f)`` hands ``f``), read like a
    :class:`~mbcomp.simulation.result.Result`: ``time``, ``status``, ``message``, ``params``,
    ``run["column"]`` (``(n_out,)``, NaN past where the run ended), ``names``.

    Examples
    --------
    >>> import numpy as np
    >>> r = OneRun(np.array([0.0, 1.0]), {"x": np.array([1.0, 2.0])}, "success", "reached t_end", {"k": 2.0})
    >>> r["x"].tolist(), "x" in r, r.names, r.params
    ([1.0, 2.0], True, ['x'], {'k': 2.0})
    """

    def __init__(self, time, columns, status, message, params):
        self.time, self._columns = time, dict(columns)
        self.status, self.message, self.params = status, message, dict(params)

    def _missing(self, name):
        return f"no column {name!r} in this run; it has {', '.join(self._columns)}"
