"""The Monte Carlo showcase's machinery (``bench/slider_crank_monte_carlo.py``) on a small sample.

* the same seed gives the same table in this process and on a two-process pool, value for value;
* the drawn parameters are the distributions asked for: every sample mean lies within
  3 sigma / sqrt(n) of the distribution's mean, uniform draws inside their interval;
* physics: the crank is thrown up at ``crank_joint.w0`` and swings back; a faster throw carries
  more kinetic energy, and the rod's inertial load on the pin grows with the speeds, so on a
  1-D grid of start speeds the peak pin force rises strictly (Spearman's rank correlation 1);
* the chart and its summary numbers are written.
"""
import math
import pathlib
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest
from scipy.stats import spearmanr

import mbcomp
from mbcomp.analysis.study import runs_of

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
import slider_crank_monte_carlo as mc  # noqa: E402

N = 50


@pytest.fixture(scope="module")
def serial():
    return mc.monte_carlo(samples=N, seed=0, executor=None)


def test_pool_gives_the_serial_table_bit_for_bit(serial):
    with ProcessPoolExecutor(2) as pool:
        pooled = mc.monte_carlo(samples=N, seed=0, executor=pool)
    assert pooled.stats["executor"] == "ProcessPoolExecutor" and serial.stats["executor"] == "serial"
    assert serial.failed == [] and len(serial) == N
    for column in serial.columns:
        if column != "cpu_time":
            assert list(pooled[column]) == list(serial[column]), column
    # another seed draws other values: the equality above is not of constants
    other = runs_of(mc.TOLERANCES, samples=N, seed=1)
    assert [r["crank.m"] for r in other] != list(serial["crank.m"])


def test_sample_means_within_three_standard_errors(serial):
    for name, dist in mc.TOLERANCES.items():
        x = serial[name]
        if isinstance(dist, mbcomp.Normal):
            mean, sigma = dist.mu, dist.sigma
        else:
            mean, sigma = (dist.lo + dist.hi) / 2, (dist.hi - dist.lo) / math.sqrt(12)
            assert dist.lo <= x.min() and x.max() <= dist.hi, name
        assert abs(x.mean() - mean) < 3 * sigma / math.sqrt(N), (name, x.mean(), mean)
        assert np.unique(x).size == N, name  # drawn per sample, not repeated


def test_peak_pin_force_rises_with_crank_speed():
    speeds = np.linspace(5.0, 7.0, 7)
    s = mbcomp.study(mc.MODEL, {"crank_joint.w0": list(speeds)}, t_end=mc.T_END,
                     metrics={"peak_pin_force": mc.peak_pin_force})
    force = s["peak_pin_force"]
    assert s.failed == []
    rho = spearmanr(speeds, force).statistic
    assert rho == 1.0, force
    assert force[-1] - force[0] > 1.0, force  # N: a clear rise, not round-off


def test_chart_and_summary(serial, tmp_path):
    st = mc.summary(serial["peak_pin_force"])
    f = serial["peak_pin_force"]
    assert st["mean"] == pytest.approx(f.mean()) and st["std"] > 0
    assert f.min() < st["p99"] <= f.max()
    png = mc.chart(serial, tmp_path / "mc.png")
    assert pathlib.Path(png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    slopes = mc.sensitivities(serial)
    assert slopes["crank_joint.w0"] > 0  # the same physics as the grid test, seen through the sample
