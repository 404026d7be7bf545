"""The default method finds stiffness in C and goes on by a stiff method (issue 32 item 4).

``method="auto"`` (simulate's default) is DOP853 in C with Hairer's stiffness test; where the
test fires (15 accepted steps held by stability) the run goes on by LSODA with the exact
Jacobian (Radau where the formulation projects). Checks: on a chain whose bobs slide on
damped stiff springs (eigenvalues near -1e5 1/s against the pendulum's few 1/s) it switches
early, needs a small fraction of DOP853's evaluations and agrees with a tight reference to
its tolerance; on a pendulum that is not stiff it never switches and is bit for bit the
``dop853`` run.
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.codegen.toolchain import c_compiler

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="no C compiler: no C engine to test")

pendulum = load_model("models/n_link_pendulum.py")
spring_chain = load_model("models/spring_chain.py")


def damped_spring_chain(N=2):
    """``models/spring_chain.py`` with dampers of 1e5 N s/m: modes near -10 and -1e5 1/s (stiff)."""
    return spring_chain.build(N=N, c=1e6, d=1e5)


def test_the_default_switches_on_a_stiff_chain_and_stays_accurate():
    model = damped_spring_chain()
    opts = dict(t_end=0.5, n_out=11, rtol=1e-6, atol=1e-8)
    auto = mbcomp.simulate(model, **opts)
    plain = mbcomp.simulate(model, method="dop853", **opts)
    ref = mbcomp.simulate(model, method="Radau", t_end=0.5, n_out=11, rtol=1e-11, atol=1e-13)
    assert auto.status == plain.status == "success"
    # the test fires within the first milliseconds (the stiff modes decay at 1e5 1/s at once)
    assert 0.0 < auto.stats["stiff_from"] < 0.01
    assert "stiff_from" not in plain.stats
    assert auto.stats["nfev"] < plain.stats["nfev"] / 20, (auto.stats["nfev"], plain.stats["nfev"])
    for k in range(2):
        col = f"j{k}.phi"
        # LSODA's error at rtol 1e-6 over 0.5 s: a few 1e-5 rad (the reference is 1e-9 good)
        np.testing.assert_allclose(auto[col], ref[col], atol=1e-4, rtol=0)
        np.testing.assert_allclose(plain[col], ref[col], atol=1e-6, rtol=0)


def test_the_default_never_switches_on_a_pendulum_and_equals_dop853():
    model = pendulum.build(5)
    auto = mbcomp.simulate(model, t_end=3.0, n_out=31)
    plain = mbcomp.simulate(model, t_end=3.0, n_out=31, method="dop853")
    assert "stiff_from" not in auto.stats
    for k in range(1, 6):
        np.testing.assert_array_equal(auto[f"joint{k}.phi"], plain[f"joint{k}.phi"])
    assert auto.stats["nfev"] == plain.stats["nfev"]


def test_a_small_stiff_state_goes_on_by_radau5_in_c_a_large_one_by_lsoda():
    """``auto`` hands a stiff run of at most HANDOVER_STATES states to radau5, whose loop runs
    in C (Newton iterations counted, no Python steps), and a larger one to LSODA (Python steps):
    both from the step found stiff, both as accurate as their tolerance promises against a
    tight Radau reference."""
    from mbcomp.solvers.compiled_rk import HANDOVER_STATES

    opts = dict(t_end=0.3, n_out=7, rtol=1e-6, atol=1e-8)
    for N, by_radau in ((2, True), (HANDOVER_STATES // 4 + 1, False)):
        model = damped_spring_chain(N)
        auto = mbcomp.simulate(model, **opts)
        ref = mbcomp.simulate(model, method="Radau", t_end=0.3, n_out=7, rtol=1e-11, atol=1e-13)
        assert auto.status == "success" and 0.0 < auto.stats["stiff_from"] < 0.01
        assert (auto.stats.get("nnewton", 0) > 0 and auto.stats["python_steps"] == 0) == by_radau, (N, auto.stats)
        for k in range(N):
            np.testing.assert_allclose(auto[f"j{k}.phi"], ref[f"j{k}.phi"], atol=1e-4, rtol=0)
