"""The formulations' compiled kernels against their Python paths.

* D'Alembert's right-hand side in one C call (``mbrt_dalembert_rhs`` over the evaluation
  program, capability ``"dalembert_fun"``) gives the Python path's ``dy/dt`` and the same
  conditioning verdict (``_ill``) on closed loops (four-bar, slider-crank, Andrews' squeezer),
  open trees (with and without quaternions), nonholonomic rows and drives, at consistent and
  perturbed states; whole runs agree, re-choosing the partition at the same dead centres;
  the singular projected mass matrix is reported with the Python path's words.
* The C projection (``mbrt_project``) lands where :meth:`LagrangeIndex1.project` lands.

The Python path is the reference: the same formulation object with its C call switched off
(``_c = False``), on the same compiled system, so only the reduction differs.
"""
import numpy as np
import pytest

import mbcomp
from conftest import compiled, load_model, load_module
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import c_compiler
from mbcomp.codegen.engine import coordinate_map, mech_of
from mbcomp.errors import SimulationError
from mbcomp.formulations import build
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Revolute, World

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="no C compiler")


def _driven_crank():
    """The slider-crank with its crank angle prescribed: no independent speed left (ni = 0),
    and a drive whose values enter the program per call."""
    m = load_model("models/slider_crank.py").build()
    d = m.add("drive", PrescribedMotion(s="0.3 + 6*t + 0.5*sin(3*t)"))
    m.connect(m["crank_joint"].axis, d.flange_b)
    return m


MODELS = {
    "four_bar": lambda: load_model("models/four_bar.py").build(),
    "bicycle": lambda: load_model("models/bicycle.py").build(),
    "slider_crank": lambda: load_model("models/slider_crank.py").build(),
    "andrews": lambda: load_model("models/andrews.py").build(),
    "n_link_pendulum": lambda: load_model("models/n_link_pendulum.py").build(),
    "chain_3d": lambda: load_model("models/chain_3d.py").build(),
    "sleigh": lambda: load_module("tests/mechanisms/test_nonholonomic.py").sleigh(),
    "rolling_disk": lambda: load_model("models/rolling_disk.py").build(),
    "driven_crank": _driven_crank,
    "pendulum_cart": lambda: load_model("models/textbook/ex3_1_pendulum_cart.py").build(),
}


def _pair(make):
    """Two D'Alembert formulations of one C-compiled, initialized system: C call and Python."""
    s = compiled(make())
    init = initialize(s, 0.0)
    a, b = build("dalembert", "ode", s), build("dalembert", "ode", s)
    y0 = a.initial_state(0.0, init.q, init.u)
    b.initial_state(0.0, init.q, init.u)
    b._c = False
    return s, a, b, y0


@pytest.mark.parametrize("name", sorted(MODELS))
def test_dalembert_c_call_is_the_python_right_hand_side(name):
    """At the consistent start and at 15 perturbed states (off the manifold, as a trial stage
    is): dy/dt to 1e-12 relative to its size, the same ``_ill`` verdict, no fallback."""
    s, a, b, y0 = _pair(MODELS[name])
    assert s.evaluator.offers("dalembert_fun")
    assert "n_ops_fun" not in s.evaluator.stats  # asking made no Lagrange program
    rng = np.random.default_rng(11)
    for k in range(16):
        y = y0 + (1e-2 * rng.standard_normal(y0.size) if k else 0.0)
        t = 0.1 + 0.05 * k
        da, db = a.fun(t, y), b.fun(t, y)
        assert np.max(np.abs(da - db)) <= 1e-12 * (1.0 + np.max(np.abs(db))), (name, k)
        assert a._ill == b._ill
    assert a._c and not b._c and s.evaluator.stats["fallbacks"] == 0 and a.nlu == b.nlu


@pytest.mark.parametrize("name", ["slider_crank", "andrews"])
def test_the_partition_figures_are_the_python_ones(name):
    """The growth ``max |A_d^-1 A_i|`` and the 2-norm condition number of ``A_d`` from the C
    call equal numpy's at the same evaluation (the Jacobi SVD to 1e-12)."""
    s, a, _, y0 = _pair(MODELS[name])
    status, dy, growth, cond = s.evaluator.dalembert_fun(0.2, y0, a.dep, a.ind)
    assert status == 0
    u, _ = a.speeds(0.2, y0[: a.nq], y0[a.nq:])
    A = s.evaluate(0.2, y0[: a.nq], u).A
    Ad = A[:, a.dep]
    assert growth == pytest.approx(np.abs(np.linalg.solve(Ad, A[:, a.ind])).max(), rel=1e-12)
    assert cond == pytest.approx(np.linalg.cond(Ad), rel=1e-12)


def test_a_run_with_repartitions_is_the_python_run():
    """The slider-crank started with the slider's speed independent (dead centres ahead):
    the C-call run and the Python run re-choose the crank at the same time and agree to the
    integration tolerance; energy is conserved."""
    mod = load_model("models/slider_crank.py")
    kw = dict(t_end=1.0, n_out=51, rtol=1e-10, atol=1e-12, method="DOP853", formulation="dalembert",
              independent=["slider_joint.v"], backend="c")
    a = mbcomp.simulate(mod.build(), **kw)
    from mbcomp.codegen.evaluator import ProgramEvaluator

    offers = ProgramEvaluator.offers
    mp = pytest.MonkeyPatch()
    mp.setattr(ProgramEvaluator, "offers", lambda self, name: name != "dalembert_fun" and offers(self, name))
    try:
        b = mbcomp.simulate(mod.build(), **kw)
    finally:
        mp.undo()
    assert a.success and b.success, (a.message, b.message)
    assert a.stats["repartitions"] == b.stats["repartitions"] >= 1
    assert a.stats["independent_speeds"] == b.stats["independent_speeds"] == ["crank_joint.w"]
    for n in a.stats["coordinates"]:
        np.testing.assert_allclose(a[n], b[n], atol=1e-8)
    E = a["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-7 * max(1.0, np.max(np.abs(a["energy.kinetic"])))


def _massless_end():
    """A pendulum with a second hinge at the bob carrying a point mass on its own axis: that
    hinge's angle carries no inertia."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    j2 = m.add("j2", Revolute(phi0=0.1))
    dot = m.add("dot", PointMass(m=0.5))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(rod.frame_b, j2.frame_a)
    m.connect(j2.frame_b, dot.frame_a)
    return m


def test_a_singular_projected_mass_matrix_is_reported_in_the_same_words():
    """(Consistent initialization refuses this model; a formulation built without it meets
    the singular matrix in its right-hand side.)"""
    s = compiled(_massless_end())
    q, u = s.default_q(), np.zeros(s.nu)
    a, b = build("dalembert", "ode", s), build("dalembert", "ode", s)
    y0 = a.initial_state(0.0, q, u)
    b.initial_state(0.0, q, u)
    b._c = False
    with pytest.raises(SimulationError) as ea:
        a.fun(0.25, y0)
    with pytest.raises(SimulationError) as eb:
        b.fun(0.25, y0)
    assert str(ea.value) == str(eb.value) and "projected mass matrix is singular at t=0.25" in str(ea.value)


def test_a_failed_guard_takes_the_python_path():
    """A torque law with a branch on the speed, traced on one branch: on the other the C call
    reports a failed guard and the Python path (numeric evaluation) answers."""
    from conftest import torque_pendulum

    law = lambda t, phi, w: -0.3 if w > 0 else 0.3  # noqa: E731 - a Coulomb-like torque
    s, a, b, y0 = _pair(lambda: torque_pendulum(law))
    for w in (1.0, -1.0):
        y = np.array([0.5, w])
        np.testing.assert_allclose(a.fun(0.0, y), b.fun(0.0, y), rtol=1e-13)
    assert s.evaluator.stats["fallbacks"] >= 1


@pytest.mark.parametrize("name", ["four_bar", "slider_crank", "andrews", "sleigh", "n_link_pendulum", "chain_3d",
                                  "bicycle"])
def test_c_projection_lands_where_the_python_projection_lands(name):
    """``mbrt_project`` (quaternions normalized, Newton with minimum-norm steps by Cholesky of
    ``C C^T`` moving the coordinates as the joints do, then the speed correction) against
    :meth:`LagrangeIndex1.project` (least squares by SVD) from states 1e-3 off the manifold
    (quaternions off unit length too): the same state to 1e-12, on the manifold."""
    s = compiled(MODELS[name]())
    init = initialize(s, 0.0)
    form = build("lagrange", "ode", s, stabilization="projection")
    assert coordinate_map(s) is not None
    mech = mech_of(s.evaluator.bound, s)
    y0 = form.initial_state(0.0, init.q, init.u)
    rng = np.random.default_rng(5)
    for _ in range(10):
        y = y0 + 1e-3 * rng.standard_normal(y0.size)
        status, yc, norm = mech.project(0.3, y, 1e-12, 1e-9)
        assert status == 0
        yp = form.project(0.3, y)
        np.testing.assert_allclose(yc, yp, rtol=0, atol=1e-12 * (1 + np.abs(yp).max()))
        ev = s.evaluate(0.3, yc[: s.nq], yc[s.nq:])
        assert np.linalg.norm(ev.Phi) <= 1e-9 and np.abs(np.concatenate((ev.Phid, ev.Psi))).max(initial=0) <= 1e-12


def test_the_coordinate_map_follows_the_joints_own_increments():
    """Additive joints give the empty map (q + du), ball joints a quaternion segment, free
    joints a position and a quaternion segment; a joint moving its coordinate any other way
    (here q + 2 du) gives None: its projection stays in Python."""
    from types import SimpleNamespace

    assert coordinate_map(mbcomp.assemble(MODELS["four_bar"]())).shape == (0, 4)
    chain = coordinate_map(mbcomp.assemble(MODELS["chain_3d"]()))
    assert chain.tolist() == [[1, 0, 0, 1], [1, 4, 3, 1], [1, 8, 6, 1], [1, 12, 9, 1]]
    sphere = coordinate_map(mbcomp.assemble(load_model("models/textbook/ex4_3_rolling_sphere.py").build()))
    assert sphere.tolist() == [[0, 0, 0, 3], [1, 3, 3, 1]]
    odd = SimpleNamespace(increment=lambda q, du, p: q + 2.0 * du)
    edge = SimpleNamespace(q=slice(0, 1), u=slice(0, 1), comp=odd, name="odd")
    fake = SimpleNamespace(topology=SimpleNamespace(tree=[edge]), P={"odd": None}, nq=1, nu=1)
    assert coordinate_map(fake) is None


# --------------------------------------------------------------------------- DAE forms (Radau5)
DAE_CASES = [(1, "baumgarte"), (1, "none"), (2, None), (3, None)]


def _dae_pair(make, index, stab):
    s = compiled(make())
    init = initialize(s, 0.0)
    kw = dict(index=index) | (dict(stabilization=stab) if stab else {})
    a, b = build("lagrange", "dae", s, **kw), build("lagrange", "dae", s, **kw)
    y0 = a.initial_state(0.0, init.q, init.u)
    b._c_prog = (s.row_mask, None)  # the Python path
    return s, a, b, y0


@pytest.mark.parametrize("index, stab", DAE_CASES)
@pytest.mark.parametrize("name", ["four_bar", "slider_crank", "andrews", "chain_3d", "sleigh", "rolling_disk"])
def test_dae_residual_and_jacobian_in_one_c_call_are_the_python_ones(name, index, stab):
    """Index1 (with and without Baumgarte), GGL and Index3 on loops, quaternions and
    nonholonomic rows, at the consistent start and perturbed states: the residual to 1e-13 of
    its size; the Jacobian's exact columns (``a``, ``lam``) equal, its finite-difference
    columns to 1e-6 of its size (they divide the residuals' rounding by h ~ 1.5e-8); the
    same count of evaluations."""
    s, a, b, y0 = _dae_pair(MODELS[name], index, stab)
    assert s.evaluator.offers("dae_fun") and "n_ops_fun" not in s.evaluator.stats
    rng = np.random.default_rng(4)
    nqu = s.nq + s.nu
    for k in range(4):
        y = y0 + (1e-3 * rng.standard_normal(y0.size) if k else 0.0)
        fa, fb = a.fun(0.2, y), b.fun(0.2, y)
        assert np.max(np.abs(fa - fb)) <= 1e-13 * (1 + np.max(np.abs(fb)))
        Ja, Jb = a.jac(0.2, y), b.jac(0.2, y)
        exact = slice(nqu, nqu + s.nu + a.m)
        np.testing.assert_allclose(Ja[:, exact], Jb[:, exact], rtol=0, atol=1e-13 * (1 + np.abs(Jb).max()))
        assert np.max(np.abs(Ja - Jb)) <= 1e-6 * (1 + np.max(np.abs(Jb)))
    assert a._c_prog[1] is not None and a.nfev == b.nfev and s.evaluator.stats["fallbacks"] == 0


@pytest.mark.parametrize("index", [1, 2, 3])
def test_the_c_jacobian_is_the_difference_quotient_of_the_c_residual(index):
    """The finite-difference columns made in C equal the quotients of the C residual called
    column by column (h = 1.5e-8 max(1, |y_i|)): the same numbers."""
    s, a, _, y0 = _dae_pair(MODELS["slider_crank"], index, None)
    a.fun(0.3, y0)  # makes the C call
    prog = a._c_prog[1]
    _, F0, J, nfev = prog(0.3, y0, jac=True)
    cols = list(range(s.nq + s.nu)) + (list(range(a.n - a.mh, a.n)) if index == 2 else [])
    assert nfev == 1 + len(cols)
    for i in cols:
        h = 1.5e-8 * max(1.0, abs(y0[i]))
        yy = y0.copy()
        yy[i] += h
        np.testing.assert_array_equal(J[:, i], (prog(0.3, yy)[1] - F0) / h)


@pytest.mark.parametrize("index", [1, 2, 3])
def test_a_radau5_run_on_the_c_residual_is_the_python_run(index):
    """The slider-crank for 0.5 s by radau5 at each index: the C residual/Jacobian and the
    Python ones take the same steps (to one or two) to the same motion (1e-7)."""
    from mbcomp.codegen.evaluator import ProgramEvaluator

    kw = dict(method="radau5", index=index, t_end=0.5, n_out=26, rtol=1e-8, atol=1e-10, backend="c")
    model = load_model("models/slider_crank.py")
    a = mbcomp.simulate(model.build(), **kw)
    offers = ProgramEvaluator.offers
    mp = pytest.MonkeyPatch()
    mp.setattr(ProgramEvaluator, "offers", lambda self, name: name != "dae_fun" and offers(self, name))
    try:
        b = mbcomp.simulate(model.build(), **kw)
    finally:
        mp.undo()
    assert a.success and b.success, (a.message, b.message)
    assert abs(a.stats["steps"] - b.stats["steps"]) <= 2
    for n in a.stats["coordinates"]:
        np.testing.assert_allclose(a[n], b[n], atol=1e-7)
