"""A run written as a Modelica result file: the MAT v4 layout OpenModelica and Dymola write.

OMEdit, Dymola, DyMat, ModelicaRes and OMPython's reader plot or read these files. The layout
(``Aclass`` version ``1.1``, ``binTrans``: the matrices of names and of data stored
variable by variable) holds six matrices, written in this order with
``scipy.io.savemat(..., format="4")``:

``Aclass`` (char, 4 rows)
    ``"Atrajectory"``, ``"1.1"``, ``""``, ``"binTrans"``: what the file is.
``name``, ``description`` (char, one column per variable)
    The variable names (``time`` first, then the result columns) and their descriptions;
    a column's unit is written at the end of its description in brackets, ``"[rad]"``, as
    OpenModelica writes it (no unit: an empty description).
``dataInfo`` (int32, 4 rows, one column per variable)
    Row 1: the data matrix holding the variable (``0`` for time, the abscissa of every
    matrix; ``1``: ``data_1``; ``2``: ``data_2``). Row 2: its row in that matrix (1-based;
    a negative index would mean the negated row: an alias, which this writer does not
    make). Row 3: interpolation (``0``: linear). Row 4: outside the time range (``0``: the
    first/last value holds -- constants; ``-1``: undefined -- trajectories).
``data_1`` (float64, one row per constant, 2 columns)
    Row 1 is the time at the start and at the end; then each column whose values do not
    change over the run (a parameter-like column), at the start and at the end.
``data_2`` (float64, one row per trajectory, one column per output time)
    Row 1 is the time; then every other column.

The matrix types are those OpenModelica's reader checks: text as uint8 characters (MAT type
51), ``dataInfo`` int32 (20), ``data_1``/``data_2`` float64 (0); ``Aclass`` is 4 x 11.
Values are written as float64, bit for bit the result's. A column is constant when all its
values are equal (NaNs included); it is then read back, as every reader does, as that value
at every time.

Examples
--------
>>> import numpy as np, os, tempfile, scipy.io
>>> from mbcomp.result import Result
>>> r = Result(np.array([0.0, 0.5, 1.0]), {"j.phi": np.array([0.0, 0.2, 0.3]), "b.m": np.full(3, 2.0)},
...            units={"j.phi": "rad"})
>>> f = scipy.io.loadmat(write_mat(r, os.path.join(tempfile.mkdtemp(), "r.mat")))
>>> f["dataInfo"].T.tolist()
[[0, 1, 0, -1], [2, 2, 0, -1], [1, 2, 0, 0]]
>>> f["data_1"].tolist(), f["data_2"][1].tolist()
([[0.0, 1.0], [2.0, 2.0]], [0.0, 0.2, 0.3])
"""
from __future__ import annotations

import os
import pathlib

import numpy as np

from .result_tables import pick_columns

__all__ = ["write_mat", "char_matrix", "ACLASS", "TIME_DESCRIPTION"]

#: the file's class: a trajectory file, version 1.1, matrices stored variable by variable
ACLASS = ("Atrajectory", "1.1", "", "binTrans")
#: the description of the time variable
TIME_DESCRIPTION = "Time [s]"


def char_matrix(strings, transposed):
    """The MAT char matrix of ``strings``, padded with blanks: one string per row, or per
    column when ``transposed`` (the ``binTrans`` layout of ``name`` and ``description``).

    Raises
    ------
    ValueError
        A string with a character MAT v4 cannot hold (only Latin-1), naming it.

    Examples
    --------
    >>> char_matrix(["ab", "c"], transposed=True).tolist()
    [['a', 'c'], ['b', ' ']]
    """
    for s in strings:
        try:
            s.encode("latin-1")
        except UnicodeEncodeError:
            raise ValueError(f"{s!r} has characters a MAT v4 file cannot hold (Latin-1 only) -> rename the column "
                             "or choose other columns (to_mat(path, columns=[...]))") from None
    width = max([1] + [len(s) for s in strings])
    rows = np.array([list(s.ljust(width)) for s in strings], dtype="U1").reshape(len(strings), width)
    return np.ascontiguousarray(rows.T if transposed else rows)


def _constant(values):
    """Whether a column holds one value at every output time (NaNs compared equal)."""
    return len(values) > 0 and bool(np.all((values == values[0]) | (np.isnan(values) & np.isnan(values[0]))))


def _description(res, name):
    unit = res.units.get(name)
    return f"[{unit}]" if unit else ""


def write_mat(res, path, columns=None):
    """Write ``res`` to ``path`` as a Modelica result file (MAT v4, module notes).

    Parameters
    ----------
    res : Result
    path : str or os.PathLike
        The ``.mat`` file; its folder must exist.
    columns : list of str, optional
        The columns to write (default: all); ``time`` is always written.

    Returns
    -------
    str or os.PathLike
        ``path``.

    Raises
    ------
    KeyError
        A column that does not exist.
    ValueError
        The run has no output rows, or a name cannot be written.
    FileNotFoundError
        The folder of ``path`` does not exist.
    """
    import scipy.io

    names = pick_columns(res, columns)
    time = np.asarray(res.time, dtype=np.float64)
    if time.size == 0:
        raise ValueError("the run has no output rows (it ended before its first output) -> nothing to write to "
                         f"{os.fspath(path)!r}")
    folder = pathlib.Path(os.path.abspath(os.fspath(path))).parent
    if not folder.is_dir():
        raise FileNotFoundError(f"cannot write {os.fspath(path)!r}: its folder {str(folder)!r} does not exist -> "
                                "create it first or write elsewhere")
    values = {n: np.asarray(res[n], dtype=np.float64).reshape(-1) for n in names}
    for n, v in values.items():
        if v.shape != time.shape:
            raise ValueError(f"column {n!r} has {v.size} values for {time.size} output times -> cannot write it")
    constants = [n for n in names if _constant(values[n])]
    trajectories = [n for n in names if n not in set(constants)]
    info = [(0, 1, 0, -1)]  # time: the abscissa of every data matrix
    row = {n: k for k, n in enumerate(constants, start=2)}
    row.update({n: k for k, n in enumerate(trajectories, start=2)})
    info += [(1 if n in set(constants) else 2, row[n], 0, 0 if n in set(constants) else -1) for n in names]
    data_1 = np.array([[time[0], time[-1]]] + [[values[n][0], values[n][-1]] for n in constants], dtype=np.float64)
    data_2 = np.vstack([time] + [values[n] for n in trajectories]).astype(np.float64, copy=False)
    contents = {
        "Aclass": char_matrix(list(ACLASS), transposed=False),
        "name": char_matrix(["time"] + names, transposed=True),
        "description": char_matrix([TIME_DESCRIPTION] + [_description(res, n) for n in names], transposed=True),
        "dataInfo": np.array(info, dtype=np.int32).T.copy(),
        "data_1": data_1,
        "data_2": np.ascontiguousarray(data_2),
    }
    scipy.io.savemat(path, contents, format="4")
    return path
