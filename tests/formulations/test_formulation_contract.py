"""Every formulation built by ``build`` keeps the contract the driver relies on.

* ``full(initial_state(q, u))`` gives back ``[q, u]``: the state round-trips, whatever it
  holds (all speeds, independent speeds, accelerations and multipliers);
* ``project`` leaves a consistent state alone and puts a perturbed one back on
  ``Phi = 0`` and ``[dPhi/dt, Psi] = 0``;
* at a consistent state with speeds, the two ODE formulations -- the saddle-point solve of
  ``LagrangeIndex1`` and the projection onto independent speeds of ``DAlembert``, which share
  only the evaluation of ``M``, ``f`` and the constraint rows -- give the same accelerations
  and multipliers;
* ``projects`` follows the rules (something to project: loops, quaternions, velocity rows);
* requests nothing can step are refused with a message naming the fix.

Models: a four-bar and a slider-crank (loops), a planar five-link pendulum (open tree,
``nq == nu``), a 3-D chain (open tree with quaternions, ``nq != nu``), the Chaplygin sleigh
(nonholonomic rows only) and the rolling disk (its contact is a constraint-only joint with
holonomic and nonholonomic rows).
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model, load_module
from mbcomp.assembly.initialization import initialize
from mbcomp.formulations import FORMULATIONS, DAlembert, Formulation, LagrangeIndex1, build, check
from mbcomp.formulations.dae import GGL, Index1, Index3, Mechanical

MODELS = {
    "four_bar": lambda: load_model("models/four_bar.py").build(),
    "slider_crank": lambda: load_model("models/slider_crank.py").build(),
    "n_link_pendulum": lambda: load_model("models/n_link_pendulum.py").build(),
    "chain_3d": lambda: load_model("models/chain_3d.py").build(),
    "sleigh": lambda: load_module("tests/mechanisms/test_nonholonomic.py").sleigh(),
    "rolling_disk": lambda: load_model("models/rolling_disk.py").build(),
}
#: (formulation, problem, index) -> class built
TABLE = {
    ("lagrange", "ode", 1): LagrangeIndex1,
    ("dalembert", "ode", None): DAlembert,
    ("lagrange", "dae", 1): Index1,
    ("lagrange", "dae", 2): GGL,
    ("lagrange", "dae", 3): Index3,
    ("lagrange", "mechanical", 3): Mechanical,
}
TOL = 1e-10


@pytest.fixture(scope="module", params=sorted(MODELS))
def case(request):
    system = mbcomp.assemble(MODELS[request.param]())
    init = initialize(system)
    return request.param, system, init


def _forms(system, stabilization="projection"):
    for (formulation, problem, index), cls in TABLE.items():
        if cls is Mechanical and system._nonholonomic:
            continue  # refused: see test_mechanical_form_refuses_velocity_constraints
        yield cls, build(formulation, problem, system, index=index, stabilization=stabilization)


def _moving_state(system, init, seed=1):
    """A consistent state with nonzero speeds: random independent speeds, dependent ones solved."""
    d = DAlembert(system)
    d.initial_state(0.0, init.q, init.u)
    v = np.random.default_rng(seed).normal(size=d.ind.size)
    u, _ = d.speeds(0.0, init.q, v)
    return init.q, u


def _residuals(system, t, q, u):
    ev = system.evaluate(t, q, u)
    return np.linalg.norm(ev.Phi), np.linalg.norm(np.concatenate((ev.Phid, ev.Psi)))


def test_build_chooses_the_formulation_of_the_table(case):
    _, system, _ = case
    for cls, form in _forms(system):
        assert type(form) is cls and isinstance(form, Formulation)
        assert form.system is system and form.problem in ("ode", "dae", "mechanical")
        assert form.nfev == 0 and form.nlu == 0


def test_full_gives_back_the_coordinates_and_speeds(case):
    _, system, init = case
    q, u = _moving_state(system, init)
    for cls, form in _forms(system):
        y0 = form.initial_state(0.3, q, u)
        np.testing.assert_allclose(form.full(0.3, y0), np.concatenate((q, u)), rtol=0, atol=1e-12,
                                   err_msg=cls.__name__)


def test_project_keeps_a_consistent_state(case):
    _, system, init = case
    q, u = _moving_state(system, init)
    for cls, form in _forms(system):
        y0 = form.initial_state(0.0, q, u)
        np.testing.assert_allclose(form.project(0.0, y0), y0, rtol=0, atol=1e-12, err_msg=cls.__name__)


@pytest.mark.parametrize("cls", [LagrangeIndex1, DAlembert, Index1])
def test_project_puts_a_perturbed_state_back_on_the_manifold(case, cls):
    name, system, init = case
    q, u = _moving_state(system, init)
    formulation, problem, index = next(k for k, c in TABLE.items() if c is cls)
    form = build(formulation, problem, system, index=index, stabilization="projection")
    y0 = form.initial_state(0.0, q, u)
    nspeeds = form.ind.size if cls is DAlembert else system.nu  # the speeds the state holds
    rng = np.random.default_rng(7)
    y = y0.copy()
    y[: system.nq] += 1e-3 * rng.normal(size=system.nq)  # off Phi = 0, quaternions off unit length
    y[system.nq: system.nq + nspeeds] += 1e-2 * rng.normal(size=nspeeds)
    if system.topology.cut:  # the perturbation really left the manifold
        assert _residuals(system, 0.0, system.normalize(y[: system.nq]), form.full(0.0, y)[system.nq:])[0] > 1e-5
    qu = form.full(0.0, form.project(0.0, y))
    qp, up = qu[: system.nq], qu[system.nq:]
    pos, vel = _residuals(system, 0.0, qp, up)
    assert pos < TOL and vel < TOL, (name, cls.__name__, pos, vel)
    np.testing.assert_allclose(system.normalize(qp), qp, rtol=0, atol=1e-14)  # unit quaternions
    if form.projects:  # the correction is small: of the size of the perturbation
        assert np.max(np.abs(qp - y0[: system.nq])) < 1e-2


def test_the_two_ode_formulations_give_the_same_accelerations(case):
    """Saddle point (multipliers) against projection onto independent speeds (no multipliers)."""
    name, system, init = case
    q, u = _moving_state(system, init, seed=3)
    lag = LagrangeIndex1(system, "none")
    dal = DAlembert(system)
    yd = dal.initial_state(0.2, q, u)
    ud = lag.fun(0.2, np.concatenate((q, u)))[system.nq:]
    dyd = dal.fun(0.2, yd)
    np.testing.assert_allclose(dyd[system.nq:], ud[dal.ind], rtol=1e-9, atol=1e-9, err_msg=name)
    ev = system.evaluate(0.2, q, u)
    ud_l, lam_l = lag.solve(ev, stabilize=False)
    ud_d, lam_d = dal.solve(ev)
    scale = 1.0 + np.abs(ud_l).max()
    np.testing.assert_allclose(ud_d, ud_l, rtol=0, atol=1e-9 * scale, err_msg=name)
    np.testing.assert_allclose(lam_d, lam_l, rtol=0, atol=1e-8 * (1.0 + np.abs(lam_l).max(initial=0.0)),
                               err_msg=name)
    # the accelerations satisfy the acceleration-level constraints A du/dt + bias = 0
    bias = np.concatenate((ev.cb, ev.Bb))
    if bias.size:
        assert np.abs(ev.A @ ud_d + bias).max() < 1e-9 * scale


EXPECTED_PROJECTS = {  # (LagrangeIndex1 and Index1 with "projection", DAlembert)
    "four_bar": (True, True),          # loop
    "slider_crank": (True, True),      # loop
    "n_link_pendulum": (False, False),  # open planar tree: nothing to project
    "chain_3d": (True, True),          # quaternions
    "sleigh": (True, False),           # velocity rows only: D'Alembert satisfies them exactly
    "rolling_disk": (True, True),      # the contact: holonomic and velocity rows
}


def test_projects_follows_the_rules(case):
    name, system, _ = case
    lagrange, dalembert = EXPECTED_PROJECTS[name]
    assert LagrangeIndex1(system, "projection").projects is lagrange
    assert Index1(system, "projection").projects is lagrange
    assert DAlembert(system).projects is dalembert
    for stab in ("baumgarte", "none"):
        assert LagrangeIndex1(system, stab).projects is False
        assert Index1(system, stab).projects is False
    for form in (GGL(system), Index3(system)):  # they keep the constraints themselves
        assert form.projects is False and form.project(0.0, "untouched") == "untouched"


def test_only_dalembert_repartitions_and_reports_its_speeds(case):
    _, system, init = case
    for cls, form in _forms(system):
        y0 = form.initial_state(0.0, init.q, init.u)
        if cls is DAlembert:
            stats = form.run_stats()
            assert stats["repartitions"] == 0
            assert stats["independent_speeds"] == [system.u_names[i] for i in form.ind]
            assert len(form.ind) == system.nu - len(form.dep)
            # asked again where the first choice was made, pivoting keeps it: nothing to restart
            dep = form.dep.copy()
            assert form.repartition(0.0, y0) is None and np.array_equal(form.dep, dep)
            assert form.run_stats()["repartitions"] == 0
        else:
            assert form.run_stats() == {}
            assert form.needs_repartition(0.0, y0) is False and form.repartition(0.0, y0) is None


@pytest.mark.parametrize("args, kw, words", [
    (("kane", "ode"), {}, ["'kane' is unknown", "lagrange, dalembert"]),
    (("dalembert", "dae"), dict(method="radau5"), ["dalembert", "'radau5'", "scipy method"]),
    (("dalembert", "mechanical"), {}, ["dalembert", "scipy method"]),
    (("lagrange", "ode"), dict(index=2, method="RK45"), ["'RK45' integrates ODEs", "index-2", "radau5"]),
    (("lagrange", "ode"), dict(index=3), ["integrates ODEs", "genalpha"]),
    (("lagrange", "mechanical"), dict(index=1, method="genalpha"), ["index-3", "index=3"]),
    (("lagrange", "dae"), dict(index=3, method="ida", max_index=2), ["index <= 2", "radau5"]),
    (("lagrange", "dae"), dict(index=4), ["index=4", "1 (acceleration level)"]),
    (("lagrange", "sde"), {}, ["'sde' is unknown", "ode, dae, mechanical"]),
])
def test_a_request_nothing_can_step_names_the_fix(args, kw, words):
    system = mbcomp.assemble(MODELS["four_bar"]())
    for call in (lambda: check(*args, **kw), lambda: build(args[0], args[1], system, **kw)):
        with pytest.raises(ValueError) as info:
            call()
        for w in words:
            assert w in str(info.value)


def test_check_gives_the_index_to_report():
    assert FORMULATIONS == ("lagrange", "dalembert")
    assert check("lagrange", "ode") == 1 and check("dalembert", "ode") is None
    assert check("lagrange", "dae") == 1 and check("lagrange", "dae", index=2) == 2
    assert check("lagrange", "mechanical") == 3 and check("lagrange", "dae", index=3, max_index=3) == 3


def test_mechanical_form_refuses_velocity_constraints():
    system = mbcomp.assemble(MODELS["sleigh"]())
    with pytest.raises(ValueError, match="holonomic constraints only.*radau5"):
        build("lagrange", "mechanical", system)


def test_unknown_stabilization_is_refused():
    system = mbcomp.assemble(MODELS["four_bar"]())
    for problem in ("ode", "dae"):
        with pytest.raises(ValueError, match="stabilization 'stiff' is unknown"):
            build("lagrange", problem, system, stabilization="stiff")
