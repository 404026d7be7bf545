"""The generated program (mbcomp.codegen) against the numeric evaluation it was traced from.

* At random states (and random times) every quantity the formulations use -- ``M``, ``f``,
  ``Phi``, ``dPhi/dt``, ``C``, ``c_b``, the nonholonomic rows and the coordinate rates --
  equals the numeric :meth:`MultibodySystem.evaluate` to 1e-12 (relative to the quantity's
  size), for a closed loop (slider-crank), ball joints with quaternions (3-D chain), and a
  model with a line spring-damper, a rotational spring-damper, a ``Torque`` law, a
  ``WorldForce`` law and a ``PrescribedMotion`` drive, and a Chaplygin sleigh (nonholonomic
  rows from a user-written joint); for the Python and (if a compiler is installed) the C printer.
* Simulations with the compiled system follow the numeric ones (both formulations).
* Parameters are runtime arguments: changing a mass, a length or a spring rate reuses the
  program (no new trace) and gives the numeric system's new values; changing what is baked
  (a hinge axis, a zero pattern) traces again and is still right.
* Decisions on state values become guards: a failed guard falls back to the numeric path.
* Errors: an untraceable law names the component; no compiler is a clear error.
"""
import importlib
import math

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import CodegenError, c_compiler, compile_system
from mbcomp.formulations import DAlembert, LagrangeIndex1
from mbcomp.initialization import initialize
from mbcomp.library import (Fixed, FixedTranslation, PrescribedMotion, Revolute, RigidBody, RotationalSpringDamper,
                            SpringDamper, Torque, World, WorldForce)

from conftest import load_model, load_module

FIELDS = ("M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi")
BACKENDS = ["python", pytest.param("c", marks=pytest.mark.skipif(c_compiler() is None, reason="no C compiler"))]


def mixed_model(law=None):
    """Spin hinge driven by a PrescribedMotion, an arm on a second hinge with a rotational
    spring-damper and a motor Torque law, a line spring-damper to a fixed anchor and a
    velocity-dependent WorldForce law on the arm's tip."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    spin = m.add("spin", Revolute(n=(0, 1, 0)))
    drive = m.add("drive", PrescribedMotion(s="0.5*sin(2*t)"))
    hub = m.add("hub", RigidBody(m=0.5, I=np.diag([0.01, 0.02, 0.01])))
    j = m.add("j", Revolute(n=(1, 0, 0), phi0=0.4, w0=0.2))
    arm = m.add("arm", RigidBody(m=1.2, r_cm=(0, -0.3, 0.05), I=np.diag([0.02, 0.005, 0.02])))
    tip = m.add("tip", FixedTranslation(r=(0.1, -0.6, 0)))
    anchor = m.add("anchor", Fixed(r=(0.4, -0.2, 0.3)))
    sd = m.add("sd", SpringDamper(c=40.0, d=0.7, s_unstretched=0.2))
    rsd = m.add("rsd", RotationalSpringDamper(c=3.0, d=0.05, phi_rel0=0.1))
    motor = m.add("motor", Torque(tau=law or (lambda t, phi, w: 0.5 * np.sin(3 * t) - 0.2 * w + 0.1 * phi ** 2)))
    push = m.add("push", WorldForce(f=lambda t, fr: (0.0, 0.0, -0.5 * fr.v[2])))
    m.connect(w.frame_b, spin.frame_a)
    m.connect(drive.flange_b, spin.axis)
    m.connect(spin.frame_b, hub.frame_a)
    m.connect(spin.frame_b, j.frame_a)
    m.connect(j.frame_b, arm.frame_a)
    m.connect(j.frame_b, tip.frame_a)
    m.connect(anchor.frame_b, sd.frame_a)
    m.connect(tip.frame_b, sd.frame_b)
    m.connect(rsd.flange_b, j.axis)
    m.connect(rsd.flange_a, j.support)
    m.connect(motor.flange_b, j.axis)
    m.connect(push.frame_b, tip.frame_b)
    return m


MODELS = {
    "slider_crank": lambda: load_model("models/slider_crank.py").build(),
    "chain_3d": lambda: load_model("models/chain_3d.py").build(N=3),
    "pendulum_10": lambda: load_model("models/n_link_pendulum.py").build(N=10),
    "mixed": mixed_model,
    "sleigh (nonholonomic, user-written joint)": lambda: load_module("tests/mechanisms/test_nonholonomic.py").sleigh(),
}


def assert_same(ev_num, ev_gen, tol=1e-12):
    for name in FIELDS:
        ref = np.asarray(getattr(ev_num, name), float)
        got = getattr(ev_gen, name)
        assert got.shape == ref.shape, name
        scale = 1.0 + np.abs(ref).max(initial=0.0)
        np.testing.assert_allclose(got, ref, rtol=0, atol=tol * scale, err_msg=name)


@pytest.fixture(scope="module")
def systems():
    out = {}
    for name, build in MODELS.items():
        s = mbcomp.assemble(build())
        initialize(s)
        out[name] = s
    return out


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list(MODELS))
def test_program_equals_numeric_evaluation(systems, name, backend, tmp_path):
    s = systems[name]
    c = compile_system(s, backend, cache_dir=str(tmp_path))
    assert c.stats["n_ops"] > 0 and c.stats["traces"] == 1
    rng = np.random.default_rng(7)
    for k in range(6):
        q = s.normalize(rng.normal(size=s.nq))  # off the loop manifold too: Phi != 0 is compared
        u = rng.normal(size=s.nu)
        t = rng.uniform(0.0, 3.0)
        for masked in (True, False):
            assert_same(s.evaluate(t, q, u, masked=masked), c.evaluate(t, q, u, masked=masked))
        np.testing.assert_allclose(c.q_rate(q, u), s.q_rate(q, u), rtol=0, atol=1e-14)
    assert c.stats["fallbacks"] == 0
    if name == "slider_crank":  # a loop: constraint rows are really there
        assert c.evaluate(0.0, q, u).C.shape[0] > 0


def test_a_compiled_system_is_the_same_system_with_a_program_evaluator(systems):
    """compile_system swaps the evaluator only: same class, topology, parameters and row mask;
    the input stays numeric, and the compiled system's numeric evaluation is still there."""
    s = systems["slider_crank"]
    c = compile_system(s)
    assert type(c) is type(s) and c is not s
    assert c.topology is s.topology and c.row_mask is s.row_mask and c.P == s.P
    assert (s.backend, c.backend, c.with_params({"crank.m": 2.0}).backend) == ("numeric", "python", "python")
    rng = np.random.default_rng(3)
    q, u = s.normalize(rng.normal(size=s.nq)), rng.normal(size=s.nu)
    ev_gen, ev_num = c.evaluate(0.2, q, u), c.evaluate_numeric(0.2, q, u)
    assert type(ev_gen) is not type(ev_num) and type(s.evaluate(0.2, q, u)) is type(ev_num)
    assert_same(s.evaluate(0.2, q, u), ev_num, tol=0.0)  # the numeric path itself, bit for bit
    assert_same(ev_num, ev_gen)
    np.testing.assert_array_equal(c.q_rate_numeric(q, u), s.q_rate(q, u))


def test_graph_shares_and_folds():
    """Hash-consing, folding and hoisting on the expression graph itself."""
    from mbcomp.codegen import Graph
    from mbcomp.codegen.printers import python_source

    with Graph() as g:
        x, y = g.input("q", 0, 0.3), g.input("q", 1, -1.2)
        p1, p2 = g.input("p", 0, 2.0, state=False), g.input("p", 1, 5.0, state=False)
        assert x * y is y * x and np.cos(x) is np.cos(x)  # one node per (operation, operands)
        assert x + 0 is x and x * 1 is x and x * 0 == 0.0 and x - x == 0.0 and -(-x) is x
        n = len(g)
        s = (x * y + p1) + p2  # parameter terms gather: x*y + (p1 + p2)
        assert s is x * y + (p1 + p2) and len(g) == n + 3
        assert s.v == pytest.approx(0.3 * -1.2 + 7.0)
        src = python_source(g, [s, x * 0.0, p1 * p2], "f")
    assert "+" in src and src.count(" * ") == 2, src  # x*y and p1*p2, nothing for x*0
    ns = {}
    exec(src, dict(importlib.import_module("mbcomp.codegen.printers").PY_ENV), ns)
    assert ns["f"]([0.3, -1.2], [], 0.0, [], [2.0, 5.0]) == pytest.approx([0.3 * -1.2 + 7.0, 0.0, 10.0])


@pytest.mark.parametrize("formulation", ["lagrange", "dalembert"])
def test_simulation_with_the_compiled_system_follows_the_numeric_one(formulation):
    sc = load_model("models/slider_crank.py")
    kw = dict(t_end=1.0, rtol=1e-9, atol=1e-11, n_out=101, formulation=formulation)
    r_num = mbcomp.simulate(mbcomp.assemble(sc.build()), **kw)
    fast = compile_system(mbcomp.assemble(sc.build()))
    r_gen = mbcomp.simulate(fast, **kw)
    assert r_num.success and r_gen.success
    for col in ("slider_joint.s", "crank_joint.phi", "crank_joint.w", "crank_joint.tau.z", "energy.total"):
        scale = 1.0 + np.abs(r_num[col]).max()
        np.testing.assert_allclose(r_gen[col], r_num[col], rtol=0, atol=1e-8 * scale, err_msg=col)
    assert fast.stats["fallbacks"] == 0


def test_rhs_of_both_formulations_accept_the_compiled_system(systems):
    s = systems["mixed"]
    c = compile_system(s)
    init = initialize(s)
    y = np.concatenate((init.q, init.u))
    np.testing.assert_allclose(LagrangeIndex1(c).fun(0.3, y), LagrangeIndex1(s).fun(0.3, y), rtol=1e-12, atol=1e-12)
    d_num, d_gen = DAlembert(s), DAlembert(c)
    yd = d_num.initial_state(0.3, init.q, init.u)
    d_gen.initial_state(0.3, init.q, init.u)
    np.testing.assert_allclose(d_gen.fun(0.3, yd), d_num.fun(0.3, yd), rtol=1e-12, atol=1e-12)


def test_changing_a_parameter_rederives_nothing(systems):
    s = systems["mixed"]
    c = compile_system(s)
    rng = np.random.default_rng(11)
    q, u, t = rng.normal(size=s.nq), rng.normal(size=s.nu), 0.7
    for change in ({"arm.m": 2.5}, {"tip.r": (0.3, -0.9, 0.0)}, {"sd.c": 95.0, "rsd.d": 0.4},
                   {"arm.I": np.diag([0.03, 0.01, 0.04])}, {"world.g": (0.0, -1.62, 0.0)}):
        c2 = c.with_params(change)
        assert c2.stats["traces"] == 1, change  # the same program, new runtime arguments
        assert_same(s.with_params(change).evaluate(t, q, u), c2.evaluate(t, q, u))
        e1, e2 = c.evaluate(t, q, u), c2.evaluate(t, q, u)
        assert not np.allclose(np.append(e1.M, e1.f), np.append(e2.M, e2.f), rtol=1e-6)  # the change matters


def test_changing_what_is_baked_traces_again(systems):
    s = systems["mixed"]
    c = compile_system(s)
    rng = np.random.default_rng(12)
    q, u, t = rng.normal(size=s.nq), rng.normal(size=s.nu), 0.4
    for change in ({"j.n": (1.0, 0.2, 0.0)},  # a hinge axis (normalized numerically: a guard)
                   {"arm.r_cm": (0.02, -0.3, 0.05)},  # a zero entry becomes nonzero
                   {"rsd.phi_rel0": 0.0}):  # a nonzero entry becomes zero
        c2 = c.with_params(change)
        assert_same(s.with_params(change).evaluate(t, q, u), c2.evaluate(t, q, u))
        assert c2.stats["traces"] == 2, change


def test_a_decision_on_the_state_is_a_guard_with_numeric_fallback():
    """A Coulomb-like torque ``-0.3 sign(w)`` written with ``if``: the program keeps the
    branch seen while tracing and checks it at run time; the other branch falls back."""
    law = lambda t, phi, w: -0.3 if w > 0 else 0.3  # noqa: E731
    s = mbcomp.assemble(mixed_model(law))
    c = compile_system(s)
    # the evaluation checks the law's branch; the Lagrange program also checks that the
    # joint's articulated inertia is positive (its pivot)
    assert c.stats["state_guards"]["eval"] == 1
    q = s.default_q()
    for wj in (0.8, -0.8):
        u = np.array([wj])
        assert_same(s.evaluate(0.1, q, u), c.evaluate(0.1, q, u))
    assert c.stats["fallbacks"] == 1
    for wj in (0.8, -0.8):  # the whole right-hand side takes the same branches
        y = np.concatenate((q, [wj]))
        np.testing.assert_allclose(LagrangeIndex1(c).fun(0.1, y), LagrangeIndex1(s).fun(0.1, y), rtol=1e-12)
    assert c.stats["fallbacks"] == 3  # the program's call, then its evaluation, for w < 0
    assert c.stats["fun_state_guards"] == 2


def test_an_untraceable_law_names_the_component():
    s = mbcomp.assemble(mixed_model(lambda t, phi, w: math.sin(phi)))
    with pytest.raises(CodegenError, match=r"'motor' \(Torque\).*numpy functions"):
        compile_system(s)
    # the numeric path is unaffected
    assert np.isfinite(s.evaluate(0.0, s.default_q(), np.zeros(s.nu)).f).all()


def test_graph_size_limit_is_a_clear_error(systems):
    with pytest.raises(CodegenError, match="max_nodes=50"):
        compile_system(systems["chain_3d"], max_nodes=50)


@pytest.mark.skipif(c_compiler() is None, reason="no C compiler")
def test_c_library_is_cached_on_disk(systems, tmp_path):
    s = systems["slider_crank"]
    first = compile_system(s, "c", cache_dir=str(tmp_path))
    second = compile_system(s, "c", cache_dir=str(tmp_path))
    assert (first.stats["cache"], second.stats["cache"]) == ("miss", "hit")
    assert len(list(tmp_path.glob("mbcomp_*.so"))) == 1
    rng = np.random.default_rng(5)
    q, u = rng.normal(size=s.nq), rng.normal(size=s.nu)
    assert_same(compile_system(s, "python").evaluate(0.1, q, u), second.evaluate(0.1, q, u), tol=1e-14)


def test_no_compiler_is_a_clear_error_and_auto_falls_back(systems, monkeypatch):
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", "")
    assert c_compiler() is None
    with pytest.raises(CodegenError, match="needs a C compiler.*backend='python'"):
        compile_system(systems["slider_crank"], "c")
    assert compile_system(systems["slider_crank"], "auto").stats["backend"] == "python"


def test_simulate_backend_option_gives_the_numeric_trajectory():
    """``simulate(..., backend="python")`` generates the program itself; same answer, and a
    model the tracer cannot handle is named (not a numpy traceback)."""
    sc = load_model("models/slider_crank.py")
    kw = dict(t_end=0.5, rtol=1e-9, atol=1e-11, n_out=11)
    r_num = mbcomp.simulate(sc.build(), **kw)
    r_gen = mbcomp.simulate(sc.build(), backend="python", **kw)
    assert r_gen.stats["backend"] == "python" and r_gen.success
    np.testing.assert_allclose(r_gen["slider_joint.s"], r_num["slider_joint.s"], rtol=0, atol=1e-8)
    with pytest.raises(ValueError, match="backend 'fortran' is unknown"):
        mbcomp.simulate(sc.build(), backend="fortran", **kw)


@pytest.mark.skipif(c_compiler() is None, reason="no C compiler")
def test_a_drive_law_is_traced_into_the_right_hand_side_so_the_engine_steps_driven_models(systems, tmp_path):
    """The mixed model's PrescribedMotion law is part of the Lagrange program (no per-call
    drive inputs): the C engine steps it, and the motion equals the numeric path's."""
    s = systems["mixed"]
    c = compile_system(s, "c", cache_dir=str(tmp_path))
    assert "c_integrate" in c.evaluator.capabilities
    fast = mbcomp.simulate(c, t_end=3.0, method="dop853", rtol=1e-11, atol=1e-12)
    ref = mbcomp.simulate(s, t_end=3.0, method="DOP853", rtol=1e-11, atol=1e-12, backend="numeric")
    assert fast.stats["stretches"] > 0
    np.testing.assert_allclose(fast["j.phi"], ref["j.phi"], atol=1e-9)
    np.testing.assert_allclose(fast["spin.phi"], 0.5 * np.sin(2 * fast.time), atol=1e-12)  # the law itself


@pytest.mark.skipif(c_compiler() is None, reason="no C compiler")
def test_a_drive_law_a_program_cannot_hold_stays_a_per_call_input(tmp_path):
    """A drive law that converts its time to a float cannot be traced: the program takes its
    (s, v, a) at every call instead (no engine), and the run is still right."""
    import math

    s = mbcomp.assemble(mixed_model(), params={"drive.s": lambda t: 0.5 * math.sin(2 * float(t)),
                                   "drive.v": lambda t: math.cos(2 * float(t)),
                                   "drive.a": lambda t: -2.0 * math.sin(2 * float(t))})
    initialize(s)
    c = compile_system(s, "c", cache_dir=str(tmp_path))
    assert "lagrange_fun" in c.evaluator.capabilities and "c_integrate" not in c.evaluator.capabilities
    fast = mbcomp.simulate(c, t_end=1.0, method="dop853", rtol=1e-10, atol=1e-12)
    ref = mbcomp.simulate(s, t_end=1.0, method="DOP853", rtol=1e-10, atol=1e-12, backend="numeric")
    np.testing.assert_allclose(fast["j.phi"], ref["j.phi"], atol=1e-8)


def test_simulate_makes_the_evaluation_program_only_when_evaluations_are_asked_for_often():
    """The default path (Lagrange, the engine, the output program) evaluates a handful of
    times: a lazy evaluator answers those numerically and never makes the O(N^2) evaluation
    program; D'Alembert in Python evaluates at every step and gets it after LAZY_EVALUATIONS."""
    from mbcomp.codegen.evaluator import LAZY_EVALUATIONS
    from mbcomp.simulation.setup import system_of

    chain = load_model("models/n_link_pendulum.py")
    s = system_of(chain.build(N=4), None, "python")
    res = mbcomp.simulate(s, t_end=0.5, method="RK45")
    ran = res.system.evaluator  # simulate runs on its own copy of s (s is left as it was)
    assert res.success and ran.bound is None and 0 < ran.numeric_calls < LAZY_EVALUATIONS
    # the right-hand side program was made (and used); programs are a cache the run's copy shares with s
    assert "n_ops_fun" in s.evaluator.stats
    ref = mbcomp.simulate(chain.build(N=4), t_end=0.5, method="RK45", backend="numeric")
    np.testing.assert_allclose(res[s.q_names[-1]], ref[s.q_names[-1]], atol=1e-9)
    d = system_of(chain.build(N=4), None, "python")
    ran = mbcomp.simulate(d, t_end=0.5, method="RK45", formulation="dalembert").system.evaluator
    assert ran.bound is not None and ran.numeric_calls == LAZY_EVALUATIONS
