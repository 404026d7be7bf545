"""Run monitors (mbcomp.simulation.monitors): the shared minimum search along the dense
output, the relative rank measure, which monitors a model gets, and what they report.

The monitors' end-to-end behaviour on singular positions (a four-bar passing flat, started
flat, a disk falling flat) is checked in tests/mechanisms/test_four_bar.py and tests/mechanisms/test_rolling.py.
"""
from types import SimpleNamespace

import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.assembly.initialization import initialize
from mbcomp.simulation.monitors import ConstraintRank, JointSingularities, RedundantRows, StepWindow, monitors_for

fb = load_model("models/four_bar.py")
disk = load_model("models/rolling_disk.py")
chain = load_model("models/n_link_pendulum.py")


def parabola(t):
    """Dense output ``[q, u]`` with ``q = (t - 0.37)^2``: a minimum 0 at t = 0.37 s."""
    return np.array([(t - 0.37) ** 2, 2.0 * (t - 0.37)])


def test_the_window_locates_a_minimum_that_lies_between_step_ends():
    """Step ends at 0.1, 0.3, 0.6 s: the middle value 0.0049 is a local minimum of the
    step-end values; the true minimum (0 at 0.37 s) lies inside the last step."""
    w = StepWindow(bracket=0.01)
    for t0, t1 in ((0.0, 0.1), (0.1, 0.3), (0.3, 0.6)):
        w.push(t0, t1, {"q": parabola(t1)[0]}, parabola)
    assert w.dips() == ["q"]
    t, v = w.locate(lambda tt, q, u: q[0], nq=1, nu=1)
    assert abs(t - 0.37) < 1e-6 and v < 1e-12


def test_the_window_reads_each_step_from_its_own_dense_output():
    """Two steps with different interpolants: the search must use the first step's before its
    end and the second's after it (a step's dense output is not valid outside it)."""
    w = StepWindow(bracket=1.0)
    first = lambda t: np.array([abs(t - 0.25) + 0.5, 0.0])  # noqa: E731 - minimum 0.5 at 0.25 in step 1
    second = lambda t: np.array([abs(t - 0.45) + 0.1, 0.0])  # noqa: E731 - minimum 0.1 at 0.45 in step 2
    w.push(0.0, 0.1, {"q": 0.9}, first)
    w.push(0.1, 0.3, {"q": 0.55}, first)
    w.push(0.3, 0.6, {"q": 0.6}, second)
    t, v = w.locate(lambda tt, q, u: q[0], nq=1, nu=1)
    assert abs(t - 0.45) < 1e-6 and abs(v - 0.1) < 1e-6  # slope 1: the value is off by as much as t


@pytest.mark.parametrize("values, bracket", [((0.3, 0.2, 0.1), 1.0), ((0.3, 0.2, 0.25), 0.1)])
def test_no_dip_in_falling_values_or_above_the_bracket(values, bracket):
    w = StepWindow(bracket)
    for i, v in enumerate(values):
        w.push(float(i), float(i + 1), {"q": v}, parabola)
    assert w.dips() == []


def test_the_rank_measure_is_the_relative_smallest_singular_value():
    rank = ConstraintRank(SimpleNamespace(row_mask=None))
    assert rank.sigma(SimpleNamespace(C=np.diag([2.0, 2e-3]))) == pytest.approx(1e-3, rel=1e-12)
    assert rank.sigma(SimpleNamespace(C=np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]))) == 0.0  # 3 rows, rank 2
    assert rank.sigma(SimpleNamespace(C=np.zeros((0, 3)))) == 1.0  # no rows: nothing to lose
    # rows dropped: the full Jacobian's r-th singular value (r kept rows), whichever rows are
    # kept -- two nearly dependent kept rows are RowChoice's matter, not a singular position
    C = np.array([[1.0, 0.0], [1.0, 1e-4], [0.0, 1.0]])
    sv = np.linalg.svd(C, compute_uv=False)
    for keep in ([True, True, False], [True, False, True]):
        masked = ConstraintRank(SimpleNamespace(row_mask=np.array(keep)))
        assert masked.sigma(SimpleNamespace(C=C)) == pytest.approx(sv[1] / sv[0], rel=1e-12)
    assert ConstraintRank(SimpleNamespace(row_mask=np.array([True, True, True]))).sigma(SimpleNamespace(C=C)) == 0.0


def initialized(model):
    system = mbcomp.assemble(model)
    initialize(system)
    return system


def test_each_model_gets_the_monitors_it_needs():
    assert monitors_for(initialized(chain.build(N=2)), 1e-8) == []  # an open chain cannot reach a singular position
    # a planar loop closed by a 3-D joint: its out-of-plane rows are dropped as redundant
    loop = monitors_for(initialized(fb.build()), 1e-8)
    assert [type(x) for x in loop] == [RedundantRows, ConstraintRank]
    flat = monitors_for(initialized(fb.build(gap=0.0, phi0=np.pi)), 1e-8)
    assert [type(x) for x in flat] == [RedundantRows, ConstraintRank]
    # started flat: the row along the links is dropped too
    assert (~flat[0].system.row_mask).sum() == (~loop[0].system.row_mask).sum() + 1
    rolling = monitors_for(initialized(disk.build()), 1e-8)
    assert [type(x) for x in rolling] == [JointSingularities, ConstraintRank]
    assert [e.name for e in rolling[0].edges] == ["contact"]


def test_the_closest_approach_is_reported_for_loops_only():
    """An upright rolling disk keeps its contact rows far from rank loss; an open chain has
    no constraint Jacobian to report on."""
    res = mbcomp.simulate(disk.build(), t_end=0.2, n_out=5)
    assert res.success and 0.1 < res.stats["min_constraint_sigma"] <= 1.0
    assert "min_constraint_sigma" not in mbcomp.simulate(chain.build(N=2), t_end=0.1, n_out=3).stats



def test_the_rank_monitor_reads_the_start_and_the_rows_alone_with_the_same_bits(monkeypatch):
    # the monitors take initialization's rows where the first step starts and the rows alone (no
    # mass matrix) at step ends: the same run as with full evaluations everywhere, bit for bit,
    # with fewer full evaluations (Andrews' squeezer: its one step is looked into, sigma 0.198)
    from mbcomp.assembly.system import MultibodySystem
    from mbcomp.simulation import driver, monitors

    build = load_model("models/andrews.py").build
    kw = dict(t_end=0.03, n_out=2, rtol=1e-7, atol=1e-9)
    mbcomp.simulate(build(), **kw)  # the programs made and verified
    calls = []
    real = MultibodySystem.evaluate_numeric

    def counted(self, *a, **k):
        calls.append(1)
        return real(self, *a, **k)
    monkeypatch.setattr(MultibodySystem, "evaluate_numeric", counted)
    now = mbcomp.simulate(build(), **kw)
    n_now = len(calls)
    calls.clear()
    for_ = monitors.monitors_for
    with monkeypatch.context() as m:  # as before: full unmasked evaluations, the start evaluated again
        m.setattr(monitors.StepEnd, "rows", property(lambda e: e.system.evaluate(e.t, e.q, e.u, masked=False)))
        m.setattr(driver, "monitors_for", lambda system, atol, singular="stop", start=None: for_(system, atol, singular))
        before = mbcomp.simulate(build(), **kw)
    assert now.stats["min_constraint_sigma"] == before.stats["min_constraint_sigma"] < monitors.ConstraintRank.BRACKET
    assert now.stats["steps"] == before.stats["steps"]
    for name in now.names:
        np.testing.assert_array_equal(now[name], before[name])
    assert n_now + 2 <= len(calls)
