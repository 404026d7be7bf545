"""A run's results where users work: ``res.to_dataframe()``, ``res.to_xarray()`` and
``res.to_mat(path)`` (the Modelica result file OpenModelica and Dymola write).

Each export is read back and compared with the run's own columns bit for bit (float64): the
index/dimension is the output times, every column's values, units, status and events. The
``.mat`` file is read by two readers that share no code with the writer: DyMat (the reader
Modelica users plot with; it reads through scipy) and a MAT v4 reader written here from the
format's description with ``struct`` alone (headers, column-major data, the ``binTrans``
layout, ``dataInfo``'s block/row/sign, ``data_1``'s constants held over the run).
"""
import math
import struct
import sys

import numpy as np
import pytest
from conftest import stop_pendulum

import mbcomp
from mbcomp.result import Result

pytest.importorskip("pandas")
pytest.importorskip("xarray")


@pytest.fixture(scope="module")
def res():
    """A pendulum falling onto its stop: impacts (events), constant columns (the point mass's
    orientation, zero reactions along z), units on every column."""
    r = mbcomp.simulate(stop_pendulum(limits=(0.0, 3.0), e=0.5, phi0=0.8), t_end=2.0, n_out=81)
    assert r.success and len(r.events) >= 2
    return r


def test_dataframe_holds_the_run(res):
    df = res.to_dataframe()
    assert df.index.name == "time" and np.array_equal(df.index.to_numpy(), res.time)
    assert list(df.columns) == res.names
    for name in res.names:
        assert np.array_equal(df[name].to_numpy(), res[name], equal_nan=True), name
    assert df.attrs["units"] == {"time": "s", **{n: u for n, u in res.units.items() if n in res.names}}
    assert df.attrs["units"]["hinge.phi"] == "rad" and df.attrs["units"]["hinge.f.x"] == "N"
    assert df.attrs["status"] == res.status and df.attrs["stats"]["steps"] == res.stats["steps"]
    assert [e["time"] for e in df.attrs["events"]] == [e.time for e in res.events]
    assert {e["kind"] for e in df.attrs["events"]} == {e.kind for e in res.events}
    sub = res.to_dataframe(["hinge.phi", "energy.total"])
    assert list(sub.columns) == ["hinge.phi", "energy.total"] and set(sub.attrs["units"]) == {"time", "hinge.phi",
                                                                                              "energy.total"}


def test_xarray_holds_the_run(res):
    ds = res.to_xarray()
    assert dict(ds.sizes) == {"time": len(res.time)} and ds["time"].attrs["units"] == "s"
    assert np.array_equal(ds["time"].values, res.time)
    assert set(ds.data_vars) == set(res.names)
    for name in res.names:
        assert np.array_equal(ds[name].values, res[name], equal_nan=True), name
        assert ds[name].attrs.get("units") == res.units.get(name), name
    assert ds.attrs["status"] == "success" and ds.attrs["stats.steps"] == res.stats["steps"]
    assert ds.attrs["stats.method"] == res.stats["method"]
    import json

    events = json.loads(ds.attrs["events"])
    assert [(e["time"], e["component"], e["kind"]) for e in events] == [(e.time, e.component, e.kind)
                                                                       for e in res.events]


def test_a_column_that_does_not_exist_is_named(res, tmp_path):
    for export in (res.to_dataframe, res.to_xarray, lambda c: res.to_mat(tmp_path / "x.mat", c)):
        with pytest.raises(KeyError, match="no variable 'hinge.phii'.*hinge.phi"):
            export(["hinge.phii"])
    assert not (tmp_path / "x.mat").exists()


def test_missing_pandas_names_the_extra(res, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas -> ImportError
    with pytest.raises(ImportError, match=r"pip install mbcomp\[data\]"):
        res.to_dataframe()


# --- the Modelica result file ---------------------------------------------------------------
def read_mat4(path):
    """``{name: 2-D array}`` of a MAT v4 file, read with struct from the format's description:
    per matrix a header of five int32 (type M*1000 + O*100 + P*10 + T, rows, columns, imaginary
    flag, name length), the name (NUL-terminated), then rows*columns values column by column;
    and ``{name: type}``."""
    kinds = {0: "d", 1: "f", 2: "i", 3: "h", 4: "H", 5: "B"}
    out, types, raw, at = {}, {}, open(path, "rb").read(), 0
    while at < len(raw):
        mopt, rows, cols, imag, namelen = struct.unpack_from("<5i", raw, at)
        at += 20
        m, p, t = mopt // 1000, (mopt // 10) % 10, mopt % 10
        assert m == 0 and imag == 0, "little-endian, real matrices only"
        name = raw[at:at + namelen].rstrip(b"\0").decode("ascii")
        at += namelen
        code = kinds[p]
        size = struct.calcsize(code) * rows * cols
        flat = struct.unpack_from(f"<{rows * cols}{code}", raw, at)
        at += size
        matrix = np.array(flat).reshape(cols, rows).T  # stored column by column
        assert t in (0, 1), "numeric (0) or text (1) matrices"
        out[name], types[name] = matrix, mopt  # text: character codes
    return out, types


def strings(matrix, transposed):
    """The strings of a char matrix: one per column when transposed (binTrans), else per row."""
    lines = matrix.T if transposed else matrix
    return ["".join(chr(int(c)) for c in line).rstrip(" \0") for line in lines]


def columns_of(mat):
    """``{name: (values at every output time, description)}``: a variable's data matrix and row
    from dataInfo (a negative row: the negated values); a data_1 variable holds its value at the
    start and the end and, extrapolation 0, that value over the run (a constant)."""
    assert strings(mat["Aclass"], transposed=False) == ["Atrajectory", "1.1", "", "binTrans"]
    names, descriptions = strings(mat["name"], True), strings(mat["description"], True)
    info = mat["dataInfo"]
    time = mat["data_2"][0]
    assert info.shape == (4, len(names)) and names[0] == "time" and tuple(info[:, 0]) == (0, 1, 0, -1)
    assert mat["data_1"][0].tolist() == [time[0], time[-1]]
    out = {}
    for i, name in enumerate(names[1:], start=1):
        block, row, interpolation, extrapolation = (int(x) for x in info[:, i])
        values = mat[f"data_{block}"][abs(row) - 1] * math.copysign(1.0, row)
        assert interpolation == 0 and extrapolation == (0 if block == 1 else -1), name
        if block == 1:
            assert values[0] == values[1] or (np.isnan(values[0]) and np.isnan(values[1])), name
            values = np.full(time.shape, values[0])
        out[name] = (values, descriptions[i], block)
    return time, out


def test_mat_file_reads_back_with_a_reader_from_the_format(res, tmp_path):
    path = res.to_mat(tmp_path / "run.mat")
    mat, types = read_mat4(path)
    assert list(mat) == ["Aclass", "name", "description", "dataInfo", "data_1", "data_2"]  # the order OM writes
    # what OpenModelica's reader demands: text as uint8 (51), dataInfo int32 (20), data float64 (0); Aclass 4 x 11
    assert list(types.values()) == [51, 51, 51, 20, 0, 0] and mat["Aclass"].shape == (4, 11)
    time, cols = columns_of(mat)
    assert np.array_equal(time, res.time) and list(cols) == res.names
    for name, (values, description, block) in cols.items():
        assert np.array_equal(values, res[name], equal_nan=True), name
        assert description == (f"[{res.units[name]}]" if name in res.units else ""), name
        constant = bool(np.all(res[name] == res[name][0]))
        assert (block == 1) == constant, name
    assert cols["bob.r.z"][2] == 1 and cols["hinge.phi"][2] == 2  # the motion stays in its plane z = 0


def test_mat_file_reads_back_in_dymat(res, tmp_path):
    DyMat = pytest.importorskip("DyMat")
    d = DyMat.DyMatFile(str(res.to_mat(tmp_path / "run.mat")))
    assert set(d.names()) == set(res.names)
    for name in res.names:
        values, (t, tname, tdesc) = d.data(name), d.abscissa(name)
        assert tname == "time" and tdesc == "Time [s]"
        if d.block(name) == 2:
            assert np.array_equal(values, res[name], equal_nan=True) and np.array_equal(t, res.time), name
        else:  # a constant: its value at the start and the end
            assert t.tolist() == [res.time[0], res.time[-1]] and np.all(res[name] == values[0]), name
        assert d.description(name) == (f"[{res.units[name]}]" if name in res.units else ""), name


def test_mat_file_bad_input(tmp_path):
    r = Result(np.array([]), {"a.x": np.array([])})
    with pytest.raises(ValueError, match="no output rows"):
        r.to_mat(tmp_path / "e.mat")
    r = Result(np.array([0.0, 1.0]), {"a.x": np.array([0.0, 1.0])}, units={"a.x": "\u03a9"})
    with pytest.raises(ValueError, match="Latin-1"):
        r.to_mat(tmp_path / "u.mat")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        r.to_mat(tmp_path / "no" / "r.mat", columns=[])
