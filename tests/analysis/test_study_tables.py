"""A study's table where users work: ``StudyResult.to_dataframe()``, ``.to_xarray()`` (the
parameters as dimensions of a grid, else a ``run`` dimension) and its notebook summary.

The study is a point thrown up a vertical slider, s(t) = v0 t - g t^2 / 2, over a grid of
start speeds and masses, two of the masses negative: those runs fail (a bad parameter value)
and must stay in every table as rows with their status and message, the others holding the
closed form."""
from html.parser import HTMLParser

import numpy as np
import pytest

import mbcomp
from mbcomp.library import PointMass, Prismatic, World

pytest.importorskip("pandas")
pytest.importorskip("xarray")

G, T = 9.81, 0.5


def thrown():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=0.0, v0=0.0))
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def final_s(res):
    return res["s.s"][-1]


@pytest.fixture(scope="module")
def study():
    return mbcomp.study(thrown, {"s.v0": [1.0, 3.0], "b.m": [1.0, -1.0]}, t_end=T, metrics={"final": final_s},
                        rtol=1e-10, atol=1e-12, n_out=3)


def test_dataframe_one_row_per_run_failed_runs_kept(study):
    df = study.to_dataframe()
    assert df.index.name == "run" and list(df.index) == [0, 1, 2, 3]
    assert list(df.columns) == ["s.v0", "b.m", "final", "status", "message", "cpu_time"]
    assert df.attrs["parameters"] == ["s.v0", "b.m"] and df.attrs["metrics"] == ["final"]
    ok = df["b.m"] > 0
    assert list(df["status"][ok]) == ["success"] * 2 and list(df["status"][~ok]) == ["error"] * 2
    np.testing.assert_allclose(df["final"][ok], df["s.v0"][ok] * T - 0.5 * G * T ** 2, rtol=0, atol=1e-9)
    assert df["final"][~ok].isna().all()
    assert all("b.m" in m for m in df["message"][~ok])  # the failure names the parameter
    for c in study.columns:  # the frame holds the table itself
        assert list(df[c]) == list(study[c]) or np.array_equal(df[c].to_numpy(float), study[c], equal_nan=True)


def test_xarray_grid_has_the_parameters_as_dimensions(study):
    ds = study.to_xarray()
    assert ds["final"].dims == ("s.v0", "b.m") and dict(ds.sizes) == {"s.v0": 2, "b.m": 2}
    assert ds["s.v0"].values.tolist() == [1.0, 3.0] and ds["b.m"].values.tolist() == [1.0, -1.0]
    df = study.to_dataframe()
    for _, row in df.iterrows():
        at = {"s.v0": row["s.v0"], "b.m": row["b.m"]}
        assert str(ds["status"].sel(at).values) == row["status"]
        assert np.array_equal(ds["final"].sel(at).values, row["final"], equal_nan=True)
    assert ds.attrs["runs"] == 4 and ds.attrs["failed"] == 2


def test_xarray_of_a_sample_has_a_run_dimension():
    # two parameters drawn together: 3 runs, no grid of 3 x 3 (one drawn parameter would be a grid of one
    # dimension: its values, each once)
    out = mbcomp.study(thrown, {"s.v0": mbcomp.Uniform(1.0, 3.0), "b.m": mbcomp.Uniform(1.0, 2.0)}, samples=3, seed=2,
                       t_end=T,
                       metrics={"final": final_s}, n_out=3)
    ds, df = out.to_xarray(), out.to_dataframe()
    assert ds["final"].dims == ("run",) and ds["s.v0"].dims == ("run",)
    assert np.array_equal(ds["s.v0"].values, df["s.v0"].to_numpy()) and np.array_equal(ds["final"].values,
                                                                                      df["final"].to_numpy())


class Cells(HTMLParser):
    """The text of every table of an HTML fragment: a list of tables, each a list of rows."""

    def __init__(self):
        super().__init__()
        self.tables, self.cell = [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self.cell = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.tables[-1][-1].append(self.cell)
            self.cell = None

    def handle_data(self, data):
        if self.cell is not None:
            self.cell += data


def test_notebook_summary_shows_every_run_and_the_failures(study):
    p = Cells()
    p.feed(study._repr_html_())
    rows, failures = p.tables
    assert rows[0] == ["run"] + study.columns and len(rows) == 1 + len(study)
    final = rows[0].index("final")
    for i, row in enumerate(rows[1:]):
        assert float(row[final]) == study["final"][i] or (row[final] == "nan" and np.isnan(study["final"][i]))
    assert [r[:2] for r in failures[1:]] == [[str(i), "error"] for i in study.failed] and study.failed == [1, 3]
