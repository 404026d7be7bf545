"""The recursive algorithms (CRBA, RNEA, ABA) against the jet recursion and the dense
saddle-point solve, on every kind of model in models/, and their program sizes."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.recursive import lagrange_accelerations, tree_evaluation
from mbcomp.codegen import compile_system
from mbcomp.formulations import LagrangeIndex1

from conftest import load_model

MODELS = ["n_link_pendulum", "chain_3d", "four_bar", "slider_crank", "andrews", "bicycle", "rolling_disk"]
FIELDS = ("M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi")


@pytest.fixture(scope="module", params=MODELS)
def state(request):
    s = mbcomp.assemble(load_model(f"models/{request.param}.py").build())
    initialize(s)
    rng = np.random.default_rng(3)
    q = s.normalize(s.default_q() + 0.05 * rng.standard_normal(s.nq))
    return request.param, s, q, rng.standard_normal(s.nu)


def test_tree_evaluation_is_the_jet_evaluation(state):
    """CRBA's M, RNEA's f and the constraint rows along their paths equal the Kane sums."""
    name, s, q, u = state
    a, b = s.evaluate_numeric(0.3, q, u), tree_evaluation(s, 0.3, q, u)
    for field in FIELDS:
        ref = np.asarray(getattr(a, field))
        np.testing.assert_allclose(getattr(b, field), ref, rtol=0, atol=1e-12 * (1 + np.abs(ref).max(initial=0)),
                                   err_msg=f"{name}: {field}")


def test_articulated_body_accelerations_solve_the_saddle_point_system(state):
    """ABA + the rows' Schur complement give the dense solve's du/dt, with and without Baumgarte."""
    name, s, q, u = state
    for stab in ("baumgarte", "none"):
        form = LagrangeIndex1(s, stabilization=stab)
        ref, _ = form.solve(s.evaluate(0.3, q, u))
        ud = lagrange_accelerations(s, 0.3, q, u, form.alpha, form.beta, baumgarte=stab == "baumgarte")
        np.testing.assert_allclose(ud, ref, rtol=1e-9, atol=1e-9 * (1 + np.abs(ref).max()), err_msg=name)


def test_the_right_hand_side_program_grows_linearly_with_a_chain():
    """The Lagrange program of an N-link chain is O(N) (ABA), the evaluation program O(N^2)
    (the dense M by CRBA), where the Kane sums were O(N^3)."""
    ops = {}
    for N in (10, 40):
        s = mbcomp.assemble(load_model("models/n_link_pendulum.py").build(N=N))
        c = compile_system(s, "python")
        c.evaluator.capabilities  # the Lagrange program is made at its first use
        ops[N] = (c.stats["n_ops_fun"], c.stats["n_ops"])
    fun_ratio, eval_ratio = ops[40][0] / ops[10][0], ops[40][1] / ops[10][1]
    assert 3.0 < fun_ratio < 5.0, ops     # linear: 4x the links
    assert 5.0 < eval_ratio < 17.0, ops   # at most quadratic (16x; the Kane sums' cubic was 64x)
