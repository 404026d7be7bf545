"""``mbcomp simulate --out FILE``: the suffix picks the writer -- ``.csv``, ``.mat`` (a Modelica
result file), ``.nc`` (netCDF through xarray) -- and every kind holds the same run; an unknown
suffix is bad input, refused before the model is loaded, naming the kinds there are."""
import numpy as np
import pytest
import scipy.io

from mbcomp.cli import main
from mbcomp.result import Result
from mbcomp.simulation.result_tables import write_netcdf

xr = pytest.importorskip("xarray")

CRANK = "models/slider_crank.py"


def mat_columns(path):
    """``{name: values}`` of a Modelica result file (binTrans: one name per column; dataInfo row 1 the
    data matrix, row 2 the row in it; a constant in data_1 spread over the run)."""
    f = scipy.io.loadmat(path, chars_as_strings=False)
    names = ["".join(c).rstrip() for c in f["name"].T]
    time = f["data_2"][0]
    out = {}
    for i, name in enumerate(names):
        block, row = f["dataInfo"][0, i], f["dataInfo"][1, i]
        matrix = f["data_2"] if block == 0 else f[f"data_{block}"]  # block 0: time, the abscissa of both
        values = matrix[abs(row) - 1] * np.sign(row)
        out[name] = np.full(time.shape, values[0]) if block == 1 else values
    return out


def test_out_suffix_picks_the_writer_and_both_binary_kinds_hold_the_run(tmp_path, capsys):
    """``.mat`` and ``.nc`` (``.csv``, the kind every other CLI test reads, stays as it was)."""
    paths = {kind: tmp_path / f"run.{kind}" for kind in ("mat", "nc")}
    for kind, path in paths.items():
        assert main(["simulate", CRANK, "--t-end", "0.2", "-q", "--out", str(path)]) == 0
        assert path.is_file()
    said = capsys.readouterr().out
    assert "(Modelica result file:" in said and "(netCDF:" in said
    mat = mat_columns(paths["mat"])
    with xr.open_dataset(paths["nc"]) as ds:
        assert set(mat) == set(ds.variables) and len(mat) > 40
        for name, values in mat.items():  # the same run, bit for bit in both kinds
            assert np.array_equal(ds[name].values, values, equal_nan=True), name
        assert ds["crank_joint.phi"].attrs["units"] == "rad" and ds.attrs["status"] == "success"
        assert ds["time"].values[-1] == 0.2


@pytest.mark.parametrize("name", ["run.txt", "run"])
def test_unknown_suffix_is_refused_before_the_run(tmp_path, capsys, name):
    assert main(["simulate", CRANK, "--t-end", "0.2", "-q", "--out", str(tmp_path / name)]) == 2
    out = capsys.readouterr()
    assert "unknown suffix" in out.err and ".csv" in out.err and ".mat" in out.err and ".nc" in out.err
    assert "status:" not in out.out and not (tmp_path / name).exists()  # nothing ran, nothing written


def test_netcdf_names_with_a_slash(tmp_path):
    """netCDF names cannot hold '/': a sensitivity column is written with '|' and its name in long_name."""
    r = Result(np.array([0.0, 1.0]), {"a.x": np.array([0.0, 1.0]), "d(a.x)/d(b.m)": np.array([0.0, -0.5])},
               units={"a.x": "m"})
    with xr.open_dataset(write_netcdf(r.to_xarray(), tmp_path / "s.nc")) as ds:
        assert ds["d(a.x)|d(b.m)"].attrs["long_name"] == "d(a.x)/d(b.m)"
        assert ds["d(a.x)|d(b.m)"].values.tolist() == [0.0, -0.5] and ds["a.x"].attrs["units"] == "m"
