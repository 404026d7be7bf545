"""A run's columns as a pandas ``DataFrame`` or an xarray ``Dataset`` (both optional packages).

:func:`to_dataframe` and :func:`to_xarray` are what :meth:`mbcomp.result.Result.to_dataframe`
and :meth:`~mbcomp.result.Result.to_xarray` call. Neither package is a dependency of
mbcomp: they are imported on call, and their absence is an ``ImportError`` naming
``pip install mbcomp[data]``.

Where the units go:

* ``DataFrame``: the index is ``time`` (s); ``df.attrs["units"]`` is ``{column: unit}`` for
  the columns whose unit is declared, ``"time"`` included (pandas has no per-column
  metadata; ``attrs`` is its documented place for a frame's metadata, carried through
  copies, selections and most operations). ``df.attrs`` also holds ``status``, ``message``,
  ``stats`` (a copy of ``res.stats``) and ``events`` (one dict per event: ``time``,
  ``component``, ``name``, ``kind``, ``detail``).
* ``Dataset``: dimension ``time`` (with ``units="s"``); each column a variable whose
  ``attrs["units"]`` is its unit (CF's name, which xarray, netCDF tools and pint-xarray
  read). The Dataset's attrs hold ``status``, ``message``, every scalar statistic as
  ``stats.<name>`` and the rest (lists, dicts) and the events as JSON text, so the Dataset
  writes to netCDF as it is (:func:`write_netcdf`).

Examples
--------
>>> import numpy as np
>>> from mbcomp.result import Result
>>> r = Result(np.array([0.0, 0.5]), {"j.phi": np.array([1.0, 0.9])}, units={"j.phi": "rad"})
>>> df = to_dataframe(r)
>>> df.index.name, df.attrs["units"]["j.phi"], float(df["j.phi"].iloc[-1])
('time', 'rad', 0.9)
"""
from __future__ import annotations

import json
import math
import os
import pathlib

import numpy as np

__all__ = ["to_dataframe", "to_xarray", "write_netcdf", "need", "pick_columns", "event_dicts", "run_attrs"]


def need(module):
    """Import the optional package ``module`` (``"pandas"`` or ``"xarray"``), or raise an
    ``ImportError`` that names the extra installing it.

    Examples
    --------
    >>> need("math").pi > 3
    True
    """
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(f"this needs the optional package {module!r}, which is not installed -> fix: "
                          f"pip install mbcomp[data] (or pip install {module})") from exc


def pick_columns(res, columns):
    """The column names to export: every column (``None``) or those named, each checked.

    Raises
    ------
    KeyError
        A name that is no column of ``res`` (the message names similar ones).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.result import Result
    >>> pick_columns(Result([0.0], {"a.x": np.zeros(1), "b.x": np.zeros(1)}), ["b.x"])
    ['b.x']
    """
    if columns is None:
        return list(res.names)
    if isinstance(columns, str):
        columns = [columns]
    names = []
    for name in columns:
        if name == "time":
            continue  # always there: the index / the dimension
        res[name]  # a KeyError naming similar columns when there is none  # noqa: B018
        names.append(name)
    return names


def event_dicts(res):
    """``res.events`` as plain dicts (``time`` s, ``component``, ``name``, ``kind``, ``detail``)."""
    return [dict(time=float(e.time), component=e.component, name=e.name, kind=e.kind, detail=dict(e.detail or {}))
            for e in res.events]


def to_dataframe(res, columns=None):
    """The run as a ``pandas.DataFrame``: index ``time`` (s), one column per result column.

    Parameters
    ----------
    res : Result
    columns : list of str, optional
        The columns to keep (default: all, in :attr:`Result.names` order).

    Returns
    -------
    pandas.DataFrame
        With ``attrs``: ``units`` (``{column: unit}``, ``"time": "s"``), ``status``,
        ``message``, ``stats``, ``events`` (module notes).

    Raises
    ------
    ImportError
        pandas is not installed (the message names ``pip install mbcomp[data]``).
    KeyError
        A column that does not exist.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.result import Result
    >>> r = Result(np.array([0.0, 1.0]), {"b.r.x": np.array([0.0, 2.0])}, units={"b.r.x": "m"})
    >>> to_dataframe(r).attrs["units"]
    {'time': 's', 'b.r.x': 'm'}
    """
    pd = need("pandas")
    names = pick_columns(res, columns)
    index = pd.Index(np.asarray(res.time, dtype=float), name="time")
    df = pd.DataFrame({n: np.asarray(res[n]) for n in names}, index=index, columns=names)
    units = {"time": "s"}
    units.update({n: res.units[n] for n in names if n in res.units})
    df.attrs.update(units=units, status=res.status, message=res.message, stats=dict(res.stats),
                    events=event_dicts(res))
    return df


def _attr_value(value):
    """A statistic as a netCDF-safe attribute: numbers and text as they are, a bool as 0/1,
    anything else (lists, dicts, None) as JSON text."""
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, str):
        return value
    return json.dumps(value, default=_jsonable)


def _jsonable(x):
    if hasattr(x, "tolist"):
        return x.tolist()
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return repr(x)


def run_attrs(res):
    """The Dataset attributes of a run: ``status``, ``message``, ``stats.<name>``, ``events``
    (JSON text)."""
    attrs = {"status": res.status, "message": res.message}
    attrs.update({f"stats.{k}": _attr_value(v) for k, v in res.stats.items()})
    attrs["events"] = json.dumps(event_dicts(res), default=_jsonable)
    return attrs


def to_xarray(res, columns=None):
    """The run as an ``xarray.Dataset``: dimension ``time`` (s), one variable per column.

    Parameters
    ----------
    res : Result
    columns : list of str, optional
        The columns to keep (default: all).

    Returns
    -------
    xarray.Dataset
        Each variable's ``attrs["units"]`` its unit (where declared); the Dataset's attrs the
        run's ``status``, ``message``, ``stats.<name>`` and ``events`` (module notes).

    Raises
    ------
    ImportError
        xarray is not installed (the message names ``pip install mbcomp[data]``).
    KeyError
        A column that does not exist.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.result import Result
    >>> r = Result(np.array([0.0, 1.0]), {"j.w": np.array([0.0, 3.0])}, units={"j.w": "rad/s"},
    ...            stats={"steps": 7})
    >>> ds = to_xarray(r)
    >>> ds["j.w"].attrs["units"], int(ds.attrs["stats.steps"]), ds["time"].attrs["units"]
    ('rad/s', 7, 's')
    """
    xr = need("xarray")
    names = pick_columns(res, columns)
    data = {n: ("time", np.asarray(res[n]), {"units": res.units[n]} if n in res.units else {}) for n in names}
    time = ("time", np.asarray(res.time, dtype=float), {"units": "s", "long_name": "time"})
    return xr.Dataset(data, coords={"time": time}, attrs=run_attrs(res))


#: netCDF writers xarray can use, lightest first: scipy's netCDF-3 (scipy is a dependency of mbcomp)
ENGINES = ("scipy", "h5netcdf", "netcdf4")


def write_netcdf(dataset, path):
    """Write an xarray ``Dataset`` to ``path`` (``.nc``) with the first engine that works:
    scipy's netCDF-3 writer (no extra package), else h5netcdf, else netCDF4.

    netCDF names cannot hold ``/`` (a sensitivity column ``d(j.phi)/d(b.m)``): such a variable
    is written as the name with ``/`` replaced by ``|``, its full name in its
    ``attrs["long_name"]``.

    Examples
    --------
    >>> import numpy as np, os, tempfile, xarray as xr
    >>> ds = xr.Dataset({"j.phi": ("time", np.array([0.0, 1.0]), {"units": "rad"})}, coords={"time": [0.0, 1.0]})
    >>> p = write_netcdf(ds, os.path.join(tempfile.mkdtemp(), "r.nc"))
    >>> xr.open_dataset(p)["j.phi"].attrs["units"]
    'rad'
    """
    folder = pathlib.Path(os.path.abspath(os.fspath(path))).parent
    if not folder.is_dir():
        raise FileNotFoundError(f"cannot write {os.fspath(path)!r}: its folder {str(folder)!r} does not exist")
    renames = {n: n.replace("/", "|") for n in dataset.data_vars if "/" in str(n)}
    if renames:
        dataset = dataset.copy()
        for old in renames:
            dataset[old].attrs.setdefault("long_name", old)
        dataset = dataset.rename(renames)
    errors = []
    for engine in ENGINES:
        try:
            dataset.to_netcdf(path, engine=engine)
            return path
        except (ImportError, ValueError) as exc:  # the engine is not installed, or xarray does not offer it
            errors.append(f"{engine}: {exc}")
    raise ImportError("no netCDF writer works here (" + "; ".join(errors) + ") -> fix: pip install scipy "
                      "(netCDF-3) or h5netcdf or netCDF4")
