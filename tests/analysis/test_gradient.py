"""Adjoint gradients of an objective of a run (issue 31 item 3): :func:`mbcomp.gradient`.

Checks: on a pendulum and on the slider-crank (a closed loop, an objective with a reaction
column in its integral) the gradient equals central differences of whole tight runs of
:func:`mbcomp.simulate` (the integral by Simpson's rule on a fine output grid) to 1e-6
relative, start values and a loop length included; a parameter the objective does not depend
on has gradient exactly zero; checkpointing gives the gradient of the run kept whole; an
objective given as a Python function gives the text's; a model with modes, a parameter that is
not one and a reduction in the objective are refused naming them; the start's share
``lam^T dy0/dp`` of a loop length is the same by its three routes (reverse sweep, forward
implicit function theorem, differenced initialization), and on a loop of ball joints
(quaternions, where only the differenced initialization applies) the gradient is that of runs.
"""
import numpy as np
import pytest
from scipy.integrate import simpson

import mbcomp
from conftest import ball_loop
from conftest import load_model
from mbcomp.codegen.toolchain import c_compiler
from mbcomp.errors import ModelError
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

slider_crank = load_model("models/slider_crank.py")
BACKEND = "c" if c_compiler() else "python"
TIGHT = dict(rtol=1e-12, atol=1e-14)


def pendulum(g=9.81, L=1.0, phi0=0.5, w0=0.4, m=1.0, second=False, m2=0.5, limits=None):
    """A point mass on a 1 m rod; ``second``: another pendulum on its own hinge (no coupling)."""
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, -g, 0)))
    j = mdl.add("j", Revolute(n=(0, 0, 1), phi0=phi0, w0=w0, limits=limits))
    rod = mdl.add("rod", FixedTranslation(r=(0, -L, 0)))
    bob = mdl.add("bob", PointMass(m=m))
    mdl.connect(w.frame_b, j.frame_a); mdl.connect(j.frame_b, rod.frame_a); mdl.connect(rod.frame_b, bob.frame_a)
    if second:
        j2 = mdl.add("j2", Revolute(n=(0, 0, 1), phi0=-0.3))
        rod2 = mdl.add("rod2", FixedTranslation(r=(0, -0.7, 0)))
        bob2 = mdl.add("bob2", PointMass(m=m2))
        mdl.connect(w.frame_b, j2.frame_a); mdl.connect(j2.frame_b, rod2.frame_a)
        mdl.connect(rod2.frame_b, bob2.frame_a)
    return mdl


def run_objective(model, t_end, terminal, integrand):
    """``terminal(res)`` at t_end plus the integral of ``integrand(res)`` (Simpson, 4001 points)."""
    res = mbcomp.simulate(model, t_end=t_end, n_out=4001, **TIGHT)
    assert res.status == "success"
    return terminal(res)[-1] + simpson(integrand(res), x=res.time)


def central(build, key, base, h, t_end, terminal, integrand):
    plus = run_objective(build(**{key: base + h}), t_end, terminal, integrand)
    minus = run_objective(build(**{key: base - h}), t_end, terminal, integrand)
    return (plus - minus) / (2 * h)


def test_pendulum_gradient_is_central_differences_of_whole_runs():
    obj = {"terminal": "j.phi", "integral": "j.w**2 + 0.1 * j.phi"}
    params = ["world.g[1]", "rod.r[1]", "j.phi0", "j.w0"]
    gr = mbcomp.gradient(pendulum(), obj, params, t_end=1.5, backend=BACKEND, **TIGHT)
    term, integ = (lambda r: r["j.phi"]), (lambda r: r["j.w"] ** 2 + 0.1 * r["j.phi"])
    assert gr.value == pytest.approx(run_objective(pendulum(), 1.5, term, integ), rel=1e-9)
    # world.g[1] = -g and rod.r[1] = -L: the derivatives with respect to g and L change sign
    want = [-central(pendulum, "g", 9.81, 1e-4, 1.5, term, integ),
            -central(pendulum, "L", 1.0, 1e-5, 1.5, term, integ),
            central(pendulum, "phi0", 0.5, 1e-5, 1.5, term, integ),
            central(pendulum, "w0", 0.4, 1e-5, 1.5, term, integ)]
    np.testing.assert_allclose(gr.gradient, want, rtol=1e-6)
    assert gr["j.phi0"] == gr.gradient[2]


def run_with(build, t_end, terminal, integrand, **params):
    """:func:`run_objective` of ``build()`` with runtime parameter values ``params``."""
    res = mbcomp.simulate(build(), t_end=t_end, n_out=4001, params=params, **TIGHT)
    assert res.status == "success"
    return terminal(res)[-1] + simpson(integrand(res), x=res.time)


def test_slider_crank_gradient_is_central_differences_of_whole_runs():
    # a closed loop: the crank length moves the start state too (the loop is closed again)
    obj = {"terminal": "crank_angle**2 + slider_position", "integral": "0.01 * crank_joint.w**2 + 1e-3 * rod_joint.f.x"}
    params = ["crank_joint.phi0", "crank_joint.w0", "rod.m", "slider.m", "crank_tip.r[0]"]
    gr = mbcomp.gradient(slider_crank.build(), obj, params, t_end=1.0, backend=BACKEND, **TIGHT)
    term = lambda r: r["crank_angle"] ** 2 + r["slider_position"]  # noqa: E731
    integ = lambda r: 0.01 * r["crank_joint.w"] ** 2 + 1e-3 * r["rod_joint.f.x"]  # noqa: E731
    assert gr.value == pytest.approx(run_objective(slider_crank.build(), 1.0, term, integ), rel=1e-9)
    want = [central(slider_crank.build, "phi0", 0.3, 1e-5, 1.0, term, integ),
            central(slider_crank.build, "w0", 6.0, 1e-5, 1.0, term, integ)]
    h = 1e-5
    for name, base in (("rod.m", 2.0), ("slider.m", 0.5), ("crank_tip.r", np.array([0.2, 0.0, 0.0]))):
        step = np.array([h, 0, 0]) if np.ndim(base) else h
        want.append((run_with(slider_crank.build, 1.0, term, integ, **{name: base + step})
                     - run_with(slider_crank.build, 1.0, term, integ, **{name: base - step})) / (2 * h))
    np.testing.assert_allclose(gr.gradient, want, rtol=1e-6)


def test_a_parameter_the_objective_does_not_depend_on_has_gradient_exactly_zero():
    gr = mbcomp.gradient(pendulum(second=True), {"terminal": "j.phi", "integral": "j.w**2"},
                         ["bob2.m", "rod2.r[1]", "j2.phi0", "bob.m", "world.g[1]"], t_end=1.0, backend=BACKEND)
    assert gr["bob2.m"] == 0.0 and gr["rod2.r[1]"] == 0.0 and gr["j2.phi0"] == 0.0
    assert gr["world.g[1]"] != 0.0


@pytest.mark.parametrize("backend", sorted({BACKEND, "python"}))
def test_checkpointing_gives_the_gradient_of_the_run_kept_whole(backend):
    obj = {"terminal": "crank_angle**2", "integral": "slider_joint.v**2"}
    params = ["rod.m", "crank_joint.w0", "rod_tip.r[0]"]
    whole = mbcomp.gradient(slider_crank.build(), obj, params, t_end=1.0, backend=backend, **TIGHT)
    parts = mbcomp.gradient(slider_crank.build(), obj, params, t_end=1.0, backend=backend, checkpoints=5, **TIGHT)
    np.testing.assert_allclose(parts.gradient, whole.gradient, rtol=1e-8)
    assert parts.value == pytest.approx(whole.value, rel=1e-10)
    assert parts.stats["backward_nfev"] > whole.stats["backward_nfev"]  # the segments were integrated again


def test_an_objective_written_as_a_function_is_the_texts():
    text = {"terminal": "sqrt(abs(j.phi)) * time", "integral": "j.w**2 * bob.v.x"}
    fn = {"terminal": lambda t, c: np.sqrt(abs(c["j.phi"])) * t, "integral": lambda t, c: c["j.w"] ** 2 * c["bob.v.x"]}
    a = mbcomp.gradient(pendulum(), text, ["bob.m", "j.w0"], t_end=0.7, backend="python")
    b = mbcomp.gradient(pendulum(), fn, ["bob.m", "j.w0"], t_end=0.7, backend="python")
    np.testing.assert_allclose(b.gradient, a.gradient, rtol=1e-14)


def test_refusals_name_the_component_parameter_or_function():
    stop = pendulum(limits=(-1.0, 1.0))
    with pytest.raises(ModelError, match=r"j: Revolute has modes.*forward sensitivities"):
        mbcomp.gradient(stop, {"terminal": "j.phi"}, ["bob.m"], backend="python")
    with pytest.raises(ModelError, match=r"bob\.mass: the model has no such parameter \(similar: bob\.m"):
        mbcomp.gradient(pendulum(), {"terminal": "j.phi"}, ["bob.mass"], backend="python")
    with pytest.raises(ModelError, match=r"rod\.r: is an array of shape \(3,\).*rod\.r\[0\]"):
        mbcomp.gradient(pendulum(), {"terminal": "j.phi"}, ["rod.r"], backend="python")
    with pytest.raises(ValueError, match=r"max\(\).*not a function of one time"):
        mbcomp.gradient(pendulum(), {"terminal": "max(j.phi)"}, ["bob.m"], backend="python")
    with pytest.raises(ValueError, match=r"no column 'j.phj'; similar: j.phi"):
        mbcomp.gradient(pendulum(), {"integral": "j.phj"}, ["bob.m"], backend="python")


def test_the_start_terms_three_routes_agree_on_a_closed_loop():
    # lam^T dy0/dp for the loop lengths of the slider-crank: the reverse sweep of the rows
    # (StartTerm, what gradient() uses here), the forward implicit function theorem
    # (initial_sensitivities) and the differenced initialization (start_derivative, the fallback
    # for quaternions and fixed cut starts, here checked on a planar loop)
    from mbcomp.analysis.gradient_start import StartTerm, start_derivative
    from mbcomp.assembly.initialization import initialize
    from mbcomp.simulation.sensitivity import initial_sensitivities

    system = mbcomp.assemble(slider_crank.build())
    init = initialize(system, 0.0)
    keys = [("crank_tip", "r", (0,)), ("crank_tip", "r", (1,)), ("rod_tip", "r", (0,)), ("rod", "m", None)]
    term = StartTerm(system, init, [("crank_tip", "r"), ("rod_tip", "r"), ("rod", "m")], keys, 0.0)
    assert term.exact and term.moving == set(keys[:3])  # a mass never moves the start
    y0 = np.concatenate((init.q, init.u))
    lam = np.random.default_rng(0).standard_normal(y0.size)
    got = term.contributions(lam)
    for path, name, index in keys[:3]:
        value = float(getattr(system.P[path], name)[index])
        forward = lam @ initial_sensitivities(system, [f"{path}.{name}[{index[0]}]"], 0.0, y0)[:, 0]
        spec = {"path": path, "name": name, "index": index, "value": value}
        differenced = lam @ start_derivative(system.with_evaluator(None), spec, 0.0)
        assert abs(got[(path, name, index)]) > 0.1  # the length does move the start
        assert got[(path, name, index)] == pytest.approx(forward, rel=1e-12)
        assert differenced == pytest.approx(forward, rel=1e-8)  # central difference: h^2 ~ 1e-10


@pytest.mark.parametrize("which", ["pendulum", "slider_crank"])
def test_forward_sensitivities_and_the_adjoint_agree_to_1e_8(which):
    # issue 31 item 6: the same derivative by two independent routes (forward: simulate's
    # sensitivity equations; reverse: the adjoint's backward run)
    if which == "pendulum":
        build, params, cols = pendulum, ["bob.m", "world.g[1]", "rod.r[1]", "j.phi0", "j.w0"], ["j.phi", "j.w"]
    else:
        build = slider_crank.build
        params = ["rod.m", "crank_joint.phi0", "crank_joint.w0", "crank_tip.r[0]"]
        cols = ["crank_angle", "slider_joint.v"]
    res = mbcomp.simulate(build(), t_end=1.0, sensitivities=params, **TIGHT)
    gr = mbcomp.gradient(build(), {"terminal": f"{cols[0]} + 0.5 * {cols[1]}"}, params, t_end=1.0, backend=BACKEND,
                         **TIGHT)
    fwd = [res.sensitivity(cols[0], p)[-1] + 0.5 * res.sensitivity(cols[1], p)[-1] for p in params]
    np.testing.assert_allclose(gr.gradient, fwd, rtol=1e-8, atol=1e-8 * np.abs(fwd).max())


@pytest.mark.skipif(c_compiler() is None, reason="no C compiler")
def test_the_c_runs_give_the_gradient_of_the_scipy_runs():
    obj = {"terminal": "crank_angle**2", "integral": "0.1 * slider_joint.v**2 + 1e-3 * pin.f.y"}
    params = ["rod.m", "crank_joint.w0", "crank_tip.r[0]", "world.g[1]"]
    c = mbcomp.gradient(slider_crank.build(), obj, params, t_end=1.0, backend="c", **TIGHT)
    py = mbcomp.gradient(slider_crank.build(), obj, params, t_end=1.0, backend="python", **TIGHT)
    assert c.stats["engine"].startswith("C") and py.stats["engine"].startswith("scipy")
    np.testing.assert_allclose(c.gradient, py.gradient, rtol=1e-8)
    assert c.value == pytest.approx(py.value, rel=1e-10)


chain_3d = load_model("models/chain_3d.py")
rolling_disk = load_model("models/rolling_disk.py")


@pytest.mark.parametrize("which", ["chain_3d", "rolling_disk"])
def test_quaternion_coordinates_and_rolling_contact(which):
    # ball joints (quaternions: nq != nu, dq/dt not u) and a rolling disk (velocity rows; its
    # radius moves the consistent start): the gradient against central differences of runs
    if which == "chain_3d":
        build, objective = (lambda: chain_3d.build(N=3)), "joint3.w.x + joint2.Q.y"
        cols = lambda r: r["joint3.w.x"][-1] + r["joint2.Q.y"][-1]  # noqa: E731
        cases = [("link2.m", "link2.m", None), ("tip1.r[1]", "tip1.r", (1,)), ("joint1.w0[2]", "joint1.w0", (2,))]
    else:
        build, objective = rolling_disk.build, "lean.phi + x.s"
        cols = lambda r: r["lean.phi"][-1] + r["x.s"][-1]  # noqa: E731
        cases = [("contact.r", "contact.r", None), ("spin.w0", "spin.w0", None), ("lean.w0", "lean.w0", None)]
    gr = mbcomp.gradient(build(), {"terminal": objective}, [c[0] for c in cases], t_end=0.5, backend=BACKEND, **TIGHT)
    P = mbcomp.assemble(build()).P
    want = []
    for _, name, idx in cases:
        path, attr = name.rsplit(".", 1)
        base, h = getattr(P[path], attr), 1e-5
        vals = []
        for s in (1, -1):
            v = base + s * h if idx is None else np.where(np.arange(np.size(base)) == idx[0], base + s * h, base)
            res = mbcomp.simulate(build(), t_end=0.5, params={name: v}, **TIGHT)
            vals.append(cols(res))
        want.append((vals[0] - vals[1]) / (2 * h))
    np.testing.assert_allclose(gr.gradient, want, rtol=1e-6)




def test_a_quaternion_loop_differences_its_start_and_matches_whole_runs():
    # nq != nu with rows: the start's share is the differenced initialization (start_derivative,
    # two initializations per loop length), not the reverse sweep; the gradient is that of runs
    gr = mbcomp.gradient(ball_loop(), {"terminal": "j2.w.x"}, ["l2.r[0]", "anchor.r[2]"], t_end=0.5,
                         backend=BACKEND, **TIGHT)
    assert gr.stats["initial_runs"] == 4
    want = []
    for name, base, step in (("l2.r", [0.5, 0, 0], [1e-5, 0, 0]), ("anchor.r", [0.45, -0.45, 0.1], [0, 0, 1e-5])):
        base, step = np.array(base), np.array(step)
        ends = [mbcomp.simulate(ball_loop(), t_end=0.5, params={name: base + s * step}, **TIGHT)["j2.w.x"][-1]
                for s in (1, -1)]
        want.append((ends[0] - ends[1]) / 2e-5)
    assert np.all(np.abs(want) > 0.1)  # both lengths move the objective
    np.testing.assert_allclose(gr.gradient, want, rtol=1e-6)


def test_a_start_that_cannot_follow_a_parameter_names_it_and_the_fix():
    # the bicycle's fixed free-body start over-specifies the rear wheel's loop once its radius moves
    from mbcomp.analysis.gradient_start import start_derivative
    from mbcomp.errors import InitializationError

    system = mbcomp.assemble(load_model("models/bicycle.py").build()).with_evaluator(None)
    spec = {"path": "rear_contact", "name": "r", "index": None, "value": float(system.P["rear_contact"].r)}
    with pytest.raises(InitializationError, match=r"rear_contact\.r: moves the consistent start.*Guess"):
        start_derivative(system, spec, 0.0)


def test_runtime_values_are_the_runs():
    # values= sets the run's parameters as simulate's params= does: a pendulum under 5 m/s^2
    a = mbcomp.gradient(pendulum(), {"terminal": "j.phi"}, ["j.phi0", "rod.r[1]"], t_end=1.0, backend=BACKEND,
                        values={"world.g": [0.0, -5.0, 0.0]})
    b = mbcomp.gradient(pendulum(g=5.0), {"terminal": "j.phi"}, ["j.phi0", "rod.r[1]"], t_end=1.0, backend=BACKEND)
    np.testing.assert_allclose(a.gradient, b.gradient, rtol=1e-12)
    assert a.value == pytest.approx(b.value, rel=1e-12)
    c = mbcomp.gradient(pendulum(), {"terminal": "j.phi"}, ["j.phi0", "rod.r[1]"], t_end=1.0, backend=BACKEND)
    assert abs(c.value - a.value) > 1e-3  # the values did change the run
