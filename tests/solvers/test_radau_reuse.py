"""Radau5 reuses its Jacobian and LU factors (Hairer & Wanner II, sec. IV.8; RADAU5's THET rule).

Checks, each of which can fail:

* a linear problem (exact Jacobian forever, Newton converges at once) is stepped with a
  single Jacobian, and accurately (analytic solution);
* Prothero-Robinson ``y' = -k(t) (y - cos t) - sin t`` whose stiffness ``k`` grows from 1
  to 1e6 along the run: a Jacobian kept from the non-stiff part would make Newton diverge,
  so the stepper must notice and compute new ones; the answer stays ``cos t``;
* the 4-link chain (index 1 and 3 DAE forms, finite-difference Jacobians) keeps its
  accuracy against DOP853 at 1e-12 -- the tolerance of the Radau5 pendulum tests -- while
  forming at most one Jacobian per three steps and factoring fewer times than it steps.
"""
import functools
import pathlib

import numpy as np
import pytest
from types import SimpleNamespace

import mbcomp
from conftest import step_through
from mbcomp.solvers.radau import THETA_JAC, Radau5

ROOT = pathlib.Path(__file__).resolve().parents[2]


def run(problem, y0, t_end, **kw):
    s = Radau5(problem, 0.0, y0, t_end, **kw)
    return (s, *step_through(s))


def test_threshold_is_in_hairers_range():
    # RADAU5 suggests 0.001 (cheap Jacobians) up to 0.1 (costly ones)
    assert 1e-3 <= THETA_JAC <= 0.1


def test_linear_problem_needs_one_jacobian():
    # y' = A y, eigenvalues -1 and -1e4 (stiff): Newton with the exact Jacobian converges in
    # one correction, so the rate stays below THET and the Jacobian is never formed again
    A = np.array([[-1.0, 0.0], [1e4 - 1.0, -1e4]])
    prob = SimpleNamespace(n=2, fun=lambda t, y: A @ y, jac=lambda t, y: A)
    s, ts, ys = run(prob, [1.0, 1.0], 10.0, rtol=1e-8, atol=1e-10)
    exact = np.exp(-ts)  # y0 = (1, 1) lies on the slow eigenvector: both components exp(-t)
    assert np.abs(ys - exact[:, None]).max() < 1e-7
    assert s.stats["njev"] == 1
    assert s.stats["nsteps"] > 10
    # the factors are kept while h is kept; every refactorization is one real + one complex LU
    assert s.stats["nlu"] % 2 == 0 and s.stats["nlu"] < 2 * s.stats["nsteps"]


def k_stiff(t):
    """Stiffness growing smoothly from 1 to 1e6 around t = 1 (over ~0.05 s)."""
    return 1.0 + 1e6 / (1.0 + np.exp(-(t - 1.0) / 0.01))


def test_jacobian_is_renewed_when_the_problem_turns_stiff():
    fun = lambda t, y: -k_stiff(t) * (y - np.cos(t)) - np.sin(t)  # noqa: E731
    for jac in (lambda t, y: np.array([[-k_stiff(t)]]), None):  # analytic, then finite differences
        prob = SimpleNamespace(n=1, fun=fun, jac=jac)
        s, ts, ys = run(prob, [1.0], 3.0, rtol=1e-8, atol=1e-10)
        assert s.status == "finished"
        assert np.abs(ys[:, 0] - np.cos(ts)).max() < 1e-7  # 3e-9 (5e-9 with a Jacobian per step)
        # the Jacobian of the non-stiff start (k = 1) is useless at k = 1e6: renewed on the way
        assert s.stats["njev"] >= 3
        assert s.stats["njev"] < s.stats["nsteps"]


@functools.lru_cache(maxsize=None)
def chain_runs(index):
    model = mbcomp.load_model_file(ROOT / "models/n_link_pendulum.py")
    opts = dict(t_end=3.0, n_out=31, backend="python")
    ref = mbcomp.simulate(model.build(N=4), method="DOP853", rtol=1e-12, atol=1e-14, **opts)
    res = mbcomp.simulate(model.build(N=4), method="radau5", index=index, stabilization="none", rtol=1e-8,
                          atol=1e-10, **opts)
    return ref, res


@pytest.mark.parametrize("index", [1, 3])
def test_chain_keeps_accuracy_with_few_jacobians(index):
    ref, res = chain_runs(index)
    assert res.success, res.message
    names = ref.stats["coordinates"]
    err = max(np.abs(np.asarray(res[n]) - np.asarray(ref[n])).max() for n in names)
    assert err < 1e-6, err  # the Radau5 pendulum tests' position tolerance at rtol 1e-8
    st = res.stats
    assert st["steps"] > 300  # a real run (order 5 at rtol 1e-8 over ~2 swings)
    assert st["njev"] <= st["steps"] / 3, (st["njev"], st["steps"])
    assert st["nlu_integrator"] < 2 * st["steps"], (st["nlu_integrator"], st["steps"])
