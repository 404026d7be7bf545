"""Every model in ``models/`` simulated with both reductions of the one assembled system -
Lagrange multipliers (index 1, projection) and D'Alembert projection onto independent
speeds - agrees to the integration tolerance in positions, velocities and joint reactions.

The two paths share only the evaluation of M, f and the constraint Jacobians; the
reductions, the integrated state (all speeds vs independent speeds), the position
correction and the way reactions are obtained (multipliers of the saddle-point system vs a
least-squares solve after projection) are independent, so agreement is a real check.
"""
import pathlib

import numpy as np
import pytest

import mbcomp

from conftest import ROOT, load_model

MODELS = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "models").rglob("*.py") if p.name != "__init__.py")
T_END = 0.4
TOL = dict(rtol=1e-10, atol=1e-12, method="DOP853")


def _compared(res):
    names = list(res.stats["coordinates"]) + [n for n in res.names if n.rsplit(".", 2)[-2:-1] in (["f"], ["tau"])]
    names += [n for n in res.names if n.endswith((".w", ".v")) and not n.startswith(("energy", "residual"))]
    return [n for n in dict.fromkeys(names) if np.all(np.isfinite(res[n]))]


@pytest.mark.parametrize("path", MODELS)
def test_lagrange_and_dalembert_agree(path):
    mod = load_model(path)
    model = mod.build()
    t_end = min(T_END, getattr(mod, "SIMULATION", {}).get("t_end", T_END))
    a = mbcomp.simulate(model, t_end=t_end, n_out=41, stabilization="projection", **TOL)
    b = mbcomp.simulate(model, t_end=t_end, n_out=41, formulation="dalembert", **TOL)
    assert a.success and b.success, (a.message, b.message)
    names = _compared(a)
    assert names
    worst = []
    for n in names:
        scale = max(1.0, float(np.max(np.abs(a[n]))))
        err = float(np.max(np.abs(a[n] - b[n]))) / scale
        worst.append((err, n))
    err, n = max(worst)
    assert err < 1e-6, f"{path}: {n} differs by {err:.3g} (relative to max(1, |value|))"
    # both keep the loop closed
    assert np.max(b["residual.position"]) < 1e-9


def test_dalembert_rechooses_independent_speeds_at_dead_centres():
    """Start the slider-crank with the slider speed as the independent one: at each dead
    centre the slider stops while the crank turns, so the crank rate cannot be solved from
    it. The formulation must re-choose before the first dead centre (pivoted QR then picks
    the crank, which never becomes singular), and still agree with the Lagrange path and
    keep energy."""
    mod = load_model("models/slider_crank.py")
    model = mod.build()
    a = mbcomp.simulate(model, t_end=2.0, n_out=101, stabilization="projection", **TOL)
    b = mbcomp.simulate(model, t_end=2.0, n_out=101, formulation="dalembert", independent=["slider_joint.v"], **TOL)
    assert b.success, b.message
    # count dead centres passed: sign changes of the slider velocity
    v = a["slider_joint.v"]
    passes = int(np.sum(np.sign(v[1:]) != np.sign(v[:-1])))
    assert passes >= 2
    assert b.stats["repartitions"] >= 1
    assert b.stats["independent_speeds"] == ["crank_joint.w"]
    np.testing.assert_allclose(b["crank_angle"], a["crank_angle"], atol=1e-6)
    np.testing.assert_allclose(b["slider_joint.s"], a["slider_joint.s"], atol=1e-6)
    E = b["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-6 * max(1.0, np.max(np.abs(b["energy.kinetic"])))


def test_dalembert_rejects_a_bad_choice_of_independent_speeds():
    mod = load_model("models/slider_crank.py")
    with pytest.raises(ValueError, match="mobility"):
        mbcomp.simulate(mod.build(), t_end=0.1, formulation="dalembert",
                        independent=["slider_joint.v", "crank_joint.w"])
    with pytest.raises(ValueError, match="not speeds of the model"):
        mbcomp.simulate(mod.build(), t_end=0.1, formulation="dalembert", independent=["crank.w"])
