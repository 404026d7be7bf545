"""The multiplier form as a DAE of index 1, 2 (GGL) and 3 under every DAE solver.

Each formulation x solver pair integrates the slider-crank (a closed loop, with gravity and
no damping) and must follow a tight-tolerance reference from a different method (the index-1
ODE with projection, DOP853 at rtol 1e-11), hold the constraints the form enforces, conserve
energy, and report the same reactions as the ODE path. Requests a solver cannot honour are
refused with a message naming the fix.
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model

SC = load_model("models/slider_crank.py")
T_END = 0.5
PAIRS = [  # (method, index, stabilization, extra options, tolerance on the crank angle)
    ("radau5", 1, "baumgarte", {}, 1e-6),
    ("radau5", 1, "projection", {}, 1e-6),
    ("radau5", 2, "none", {}, 1e-6),
    ("radau5", 3, "none", {}, 1e-6),
    ("ida", 1, "baumgarte", {}, 2e-5),
    ("ida", 2, "none", {}, 2e-5),
    ("genalpha", 3, "none", {"h": 2e-4}, 1e-4),
]


@pytest.fixture(scope="module")
def reference():
    return mbcomp.simulate(SC.build(), t_end=T_END, rtol=1e-11, atol=1e-12, method="DOP853",
                           stabilization="projection", n_out=26)


@pytest.mark.parametrize("method, index, stab, extra, tol", PAIRS,
                         ids=[f"{m}-index{i}-{s}" for m, i, s, _, _ in PAIRS])
def test_pair_follows_the_reference(reference, method, index, stab, extra, tol):
    r = mbcomp.simulate(SC.build(), t_end=T_END, rtol=1e-8, atol=1e-10, method=method, index=index,
                        stabilization=stab, n_out=26, **extra)
    assert r.success, r.message
    assert r.stats["index"] == index and r.stats["steps"] > 0 and r.stats["nfev"] > 0
    for col, scale in (("crank_joint.phi", 1.0), ("slider_joint.s", 1.0), ("crank_joint.w", 10.0)):
        np.testing.assert_allclose(r[col], reference[col], rtol=0, atol=tol * scale, err_msg=col)
    # energy: no dissipation in the model, every pair keeps it to its accuracy
    E = r["energy.total"]
    assert np.max(np.abs(E - E[0])) < 50 * tol * (1 + abs(E[0]))
    # reactions come from the same index-1 solve at each output point: same as the ODE path
    np.testing.assert_allclose(r["pin.f.x"], reference["pin.f.x"], rtol=0,
                               atol=1e3 * tol * (1 + np.abs(reference["pin.f.x"]).max()))


@pytest.mark.parametrize("method, index", [("radau5", 3), ("radau5", 2), ("genalpha", 3)])
def test_position_level_forms_hold_the_loop_closed(method, index):
    """Index 3 and GGL enforce Phi = 0 at every step (to the Newton tolerance): no drift, with
    no projection at all. The last output point is a step end; the others are interpolated,
    so there the residual is the interpolation error, bounded by the tolerance."""
    extra = {"h": 2e-4} if method == "genalpha" else {}
    r = mbcomp.simulate(SC.build(), t_end=T_END, rtol=1e-6, atol=1e-8, method=method, index=index,
                        stabilization="none", n_out=26, **extra)
    assert r.success, r.message
    res = r["residual.position"]
    assert res[-1] < 1e-9
    assert np.nanmax(res) < 1e-6


@pytest.mark.parametrize("kw, words", [
    (dict(method="genalpha"), ["fixed step", "h"]),
    (dict(method="genalpha", h=1e-3, index=1), ["index-3", "index=3"]),
    (dict(method="ida", index=3), ["index <= 2", "radau5"]),
    (dict(method="RK45", index=2), ["ODE", "radau5"]),
    (dict(method="radau5", formulation="dalembert"), ["dalembert", "scipy method"]),
    (dict(method="radau5", index=4), ["index=4", "1 (acceleration level)"]),
])
def test_a_request_the_solver_cannot_honour_names_the_fix(kw, words):
    with pytest.raises(ValueError) as info:
        mbcomp.simulate(SC.build(), t_end=0.01, **kw)
    for w in words:
        assert w in str(info.value)


def test_cli_runs_a_dae_method(tmp_path, capsys):
    from mbcomp.cli import main

    out = tmp_path / "r.csv"
    code = main(["simulate", "models/slider_crank.py", "--t-end", "0.2", "--method", "radau5", "--index", "3",
                 "--rtol", "1e-8", "--atol", "1e-10", "--out", str(out), "-q"])
    assert code == 0
    ref = mbcomp.simulate(SC.build(), t_end=0.2, rtol=1e-11, atol=1e-12, method="DOP853",
                          stabilization="projection", n_out=2)
    import csv

    rows = list(csv.DictReader(open(out)))
    assert abs(float(rows[-1]["crank_joint.phi"]) - ref["crank_joint.phi"][-1]) < 1e-6
