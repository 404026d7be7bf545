"""A study's table as a pandas ``DataFrame``, an xarray ``Dataset``, or HTML for a notebook.

What :meth:`~mbcomp.analysis.study.StudyResult.to_dataframe`,
:meth:`~mbcomp.analysis.study.StudyResult.to_xarray` and
:meth:`~mbcomp.analysis.study.StudyResult._repr_html_` call. pandas and xarray are optional:
imported on call, their absence an ``ImportError`` naming ``pip install mbcomp[data]``.

* ``DataFrame``: one row per run (index ``run``, in the order of the runs), the parameters,
  the metrics, ``status``, ``message`` and ``cpu_time`` (s) as columns. A failed run is a row
  like any other, its metrics NaN where they could not be computed and its status telling
  why. ``df.attrs`` holds ``parameters``, ``metrics`` (the column names of each kind) and the
  study's ``stats``.
* ``Dataset``: when the runs are a full grid (every combination of the parameters' values,
  each once: what a grid of value lists gives), each parameter is a dimension whose
  coordinate holds its values in the grid's order, and each metric (and ``status``,
  ``message``, ``cpu_time``) a variable over them, so ``ds["top"].sel({"j.w0": 2.0})`` picks a
  slice (one parameter whose values differ run to run is a grid of one dimension). Otherwise
  (a Monte Carlo sample of several parameters, a list of runs, a study stopped part way) the
  dimension is ``run`` and the parameters are coordinates along it. The Dataset's attrs hold
  the scalar statistics.

Examples
--------
>>> import numpy as np
>>> from mbcomp.analysis.study import StudyResult
>>> rows = [{"a": 1.0, "b": 10.0, "y": 11.0, "status": "success", "message": "", "cpu_time": 0.1},
...         {"a": 1.0, "b": 20.0, "y": 21.0, "status": "success", "message": "", "cpu_time": 0.1},
...         {"a": 2.0, "b": 10.0, "y": 12.0, "status": "success", "message": "", "cpu_time": 0.1},
...         {"a": 2.0, "b": 20.0, "y": np.nan, "status": "failed", "message": "x", "cpu_time": 0.1}]
>>> s = StudyResult(["a", "b"], ["y"], rows, [{"a": r["a"], "b": r["b"]} for r in rows], None, {"runs": 4})
>>> grid_axes(s)
{'a': [1.0, 2.0], 'b': [10.0, 20.0]}
>>> float(to_xarray(s)["y"].sel(a=2.0, b=10.0)), str(to_xarray(s)["status"].sel(a=2.0, b=20.0).values)
(12.0, 'failed')
"""
from __future__ import annotations

import html

import numpy as np

from ..simulation.result_html import STYLE, table_html
from ..simulation.result_tables import need

__all__ = ["to_dataframe", "to_xarray", "grid_axes", "study_html", "MAX_ROWS"]

#: rows the notebook summary shows at most (the first and last half of them)
MAX_ROWS = 10
#: text columns of a study's table
TEXT = ("status", "message")


def _column(study, name):
    """A column as a 1-D array: float where every value is a number, else objects."""
    values = study[name]
    return values if name not in TEXT else np.array([str(v) for v in values], dtype=object)


def to_dataframe(study):
    """The study as a ``pandas.DataFrame``: one row per run (module notes).

    Examples
    --------
    >>> from mbcomp.analysis.study import StudyResult
    >>> rows = [{"k": 1.0, "y": 2.0, "status": "failed", "message": "why", "cpu_time": 0.0}]
    >>> df = to_dataframe(StudyResult(["k"], ["y"], rows, [{"k": 1.0}], None, {}))
    >>> df.loc[0, "status"], list(df.columns)
    ('failed', ['k', 'y', 'status', 'message', 'cpu_time'])
    """
    pd = need("pandas")
    df = pd.DataFrame({c: _column(study, c) for c in study.columns}, columns=study.columns,
                      index=pd.RangeIndex(len(study), name="run"))
    df.attrs.update(parameters=list(study.parameters), metrics=list(study.metrics), stats=dict(study.stats))
    return df


def _hashable(v):
    try:
        hash(v)
    except TypeError:
        return False
    return True


def grid_axes(study):
    """``{parameter: its values in the grid's order}`` when the runs are a full grid (each
    combination once), else ``None``."""
    if not study.parameters or not len(study):
        return None
    axes = {}
    for p in study.parameters:
        values = [run.get(p) for run in study.runs]
        if not all(v is not None and _hashable(v) for v in values):
            return None
        axes[p] = list(dict.fromkeys(values))
    combos = {tuple(run[p] for p in study.parameters) for run in study.runs}
    size = int(np.prod([len(v) for v in axes.values()]))
    return axes if len(combos) == len(study) == size else None


def _stat_attrs(study):
    return {k: (int(v) if isinstance(v, (bool, np.bool_)) else v) for k, v in study.stats.items()
            if isinstance(v, (int, float, str, np.integer, np.floating, bool, np.bool_))}


def to_xarray(study):
    """The study as an ``xarray.Dataset``: the parameters as dimensions for a full grid, else
    a ``run`` dimension (module notes).

    Examples
    --------
    >>> from mbcomp.analysis.study import StudyResult
    >>> rows = [{"k": v, "y": 2 * v, "status": "success", "message": "", "cpu_time": 0.0} for v in (1.0, 1.0)]
    >>> ds = to_xarray(StudyResult(["k"], ["y"], rows, [{"k": 1.0}, {"k": 1.0}], None, {}))
    >>> dict(ds.sizes), ds["k"].dims   # the same value twice: no grid, one run after the other
    ({'run': 2}, ('run',))
    """
    xr = need("xarray")
    axes = grid_axes(study)
    names = list(study.metrics) + ["status", "message", "cpu_time"]
    if axes is None:
        coords = {p: ("run", np.array([run.get(p) for run in study.runs], dtype=object if _mixed(study, p) else None))
                  for p in study.parameters}
        coords["run"] = np.arange(len(study))
        data = {n: ("run", _column(study, n)) for n in names}
        return xr.Dataset(data, coords=coords, attrs=_stat_attrs(study))
    dims = list(axes)
    shape = tuple(len(v) for v in axes.values())
    where = [tuple(axes[p].index(run[p]) for p in dims) for run in study.runs]
    data = {}
    for n in names:
        column = _column(study, n)
        grid = np.empty(shape, dtype=column.dtype)
        for k, at in enumerate(where):
            grid[at] = column[k]
        data[n] = (dims, grid)
    return xr.Dataset(data, coords={p: v for p, v in axes.items()}, attrs=_stat_attrs(study))


def _mixed(study, p):
    """Whether parameter ``p``'s values are not all plain numbers (kept as objects)."""
    return not all(isinstance(run.get(p), (int, float, np.integer, np.floating)) for run in study.runs)


def _short(text, width=80):
    text = str(text)
    return text if len(text) <= width else text[: width - 3] + "..."


def study_html(study):
    """The study's summary in a notebook: runs, failures, wall time, the first and last rows
    (the message shortened), and the failed runs' statuses and messages."""
    n, failed = len(study), study.failed
    stats = study.stats
    head = (f"<b>mbcomp StudyResult</b>: {n} runs, "
            f'<span class="{"bad" if failed else "ok"}">{len(failed)} not successful</span>')
    if "wall_time" in stats:
        head += f", wall time {stats['wall_time']:.3g} s"
    if "executor" in stats:
        head += f", executor {html.escape(str(stats['executor']))}"
    picks = list(range(n)) if n <= MAX_ROWS else list(range(MAX_ROWS // 2)) + [None] + list(range(n - MAX_ROWS // 2, n))
    columns = {c: study[c] for c in study.columns}
    rows = [["..."] * (len(study.columns) + 1) if i is None else
            [i] + [_short(columns[c][i]) if c == "message" else columns[c][i] for c in study.columns] for i in picks]
    parts = [STYLE, '<div class="mbcomp-repr">', head, table_html(["run"] + study.columns, rows)]
    if failed:
        shown = failed[:MAX_ROWS]
        parts.append(f"<div>not successful{'' if len(shown) == len(failed) else f' (the first {len(shown)})'}:</div>")
        parts.append(table_html(["run", "status", "message"],
                                [[i, columns["status"][i], _short(columns["message"][i], 160)] for i in shown]))
    parts.append("</div>")
    return "".join(parts)

