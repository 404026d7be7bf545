"""The Jacobian printed as loops over directions (:mod:`mbcomp.codegen.direction_loops`), the C
program behind ``LagrangeIndex1.jac`` (issue 31 item 7).

Cross-checks against the scalar forward mode (:func:`mbcomp.codegen.tangent.tangent`, printed
by the Python printer) at states away from the trace point: random graphs with every kind of
node the plan treats differently (shared, single-use, unit-only, ``x op x``, outputs that are
inputs, constants or repeated, parameters), a planar chain and a 3-D chain's right-hand side;
the guards of the traced branch; non-finite partials reach the output as NaN; the loops do no
more multiply-adds than the scalar forward mode has operations.
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.codegen.direction_loops import DirectionPlan, TangentLoops
from mbcomp.codegen.graph import Graph
from mbcomp.codegen.printers import PY_ENV, Program
from mbcomp.codegen.tangent import tangent
from mbcomp.codegen.toolchain import c_compiler
from mbcomp.codegen.tracer import param_vector, trace

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="no C compiler")

pendulum = load_model("models/n_link_pendulum.py")
chain_3d = load_model("models/chain_3d.py")

UNARY = [np.sin, np.cos, np.exp, np.tanh, np.arctan, lambda v: np.sqrt(v * v + 1.0), lambda v: v * v]
BINARY = [lambda a, b: a * b, lambda a, b: a + b, lambda a, b: a - b, lambda a, b: a / (b * b + 2.0),
          lambda a, b: np.arctan2(a, b + 3.0), lambda a, b: np.hypot(a, b + 0.5), lambda a, b: a * a - b]


def _random_graph(seed, nq, nu):
    """A random graph over ``nq + nu`` state inputs and two parameters: values reused by later
    nodes at random (shared and single-use nodes), outputs among them plus an input, a constant,
    a parameter-only value and a repeated output."""
    rng = np.random.default_rng(seed)
    with Graph() as g:
        ins = [g.input("q", k, rng.uniform(-1, 1)) for k in range(nq)] + \
              [g.input("u", k, rng.uniform(-1, 1)) for k in range(nu)]
        p = [g.input("p", k, rng.uniform(0.5, 2.0), state=False) for k in range(2)]
        pool = list(ins)
        for _ in range(60):
            if rng.random() < 0.4:
                v = UNARY[rng.integers(len(UNARY))](pool[rng.integers(len(pool))])
            else:
                a, b = pool[rng.integers(len(pool))], pool[rng.integers(len(pool))]
                v = BINARY[rng.integers(len(BINARY))](a, b)
            if rng.random() < 0.3:
                v = v * p[rng.integers(2)]
            pool.append(v)
        outs = [pool[k] for k in rng.choice(np.arange(len(ins), len(pool)), 8, replace=False)]
        outs += [ins[0], 2.5, p[0] * p[1], outs[0]]
    return g, outs, ins, p


def _python_jacobian(g, outs, ins):
    """The scalar forward mode's Jacobian program, printed by the Python printer."""
    flat = [v for row in tangent(g, outs, ins) for v in row]
    prog = Program(g, {"jac": flat})
    env = dict(PY_ENV)
    exec(prog.python_main("jac", "jac"), env)
    from mbcomp.codegen.printers import ParamProgram

    return lambda q, u, pv: np.array(env["jac"](list(q), list(u), 0.0, [], ParamProgram(prog).run(pv)), float)


def _run(loops, q, u, pv, n_out, d=()):
    qb, ub = np.append(np.asarray(q, float), 0.0), np.append(np.asarray(u, float), 0.0)
    h = np.append(np.array(loops.pre.run(list(pv)), float), 0.0)
    pb, db = np.append(np.asarray(pv, float), 0.0), np.append(np.asarray(d, float), 0.0)
    w, out = np.zeros(loops.n_work + 1), np.full(n_out * loops.plan.n_dir + 1, np.nan)
    rc = loops.cfun(qb.ctypes.data, ub.ctypes.data, 0.0, db.ctypes.data, h.ctypes.data, pb.ctypes.data,
                    w.ctypes.data, out.ctypes.data)
    return rc, out[:-1].reshape(n_out, loops.plan.n_dir)


@pytest.mark.parametrize("seed", range(6))
def test_random_graphs_match_the_scalar_forward_mode_away_from_the_trace_point(seed, tmp_path):
    nq, nu = 4, 3
    g, outs, ins, p = _random_graph(seed, nq, nu)
    ref = _python_jacobian(g, outs, ins)
    loops = TangentLoops(g, outs, ins, [(0, nq), (nq, nq + nu)], g.guards, f"t_rand{seed}", str(tmp_path), "test")
    rng = np.random.default_rng(100 + seed)
    for _ in range(3):
        q, u, pv = rng.uniform(-1, 1, nq), rng.uniform(-1, 1, nu), rng.uniform(0.5, 2.0, 2)
        rc, J = _run(loops, q, u, pv, len(outs))
        assert rc == 0
        want = ref(q, u, pv).reshape(len(outs), nq + nu)
        np.testing.assert_allclose(J, want, rtol=1e-13, atol=1e-13 * np.abs(want).max())
    # the constant, the parameter-only value: zero rows; the input: a unit row; the repeat: a copy
    np.testing.assert_array_equal(J[9], 0.0)
    np.testing.assert_array_equal(J[10], 0.0)
    np.testing.assert_array_equal(J[8], np.eye(nq + nu)[0])
    np.testing.assert_array_equal(J[11], J[0])


@pytest.mark.parametrize("which, n", [("planar", 12), ("3d", 3)])
def test_a_chains_jacobian_is_the_scalar_forward_modes(which, n, tmp_path):
    """Blocks, slot reuse and eliminated nodes on a real right-hand side: the compiled C system's
    Lagrange program (a planar chain of 12 links, a 3-D chain of 3 on ball joints with quaternion
    coordinates) at a generic state."""
    model = pendulum.build(n) if which == "planar" else chain_3d.build(n)
    system = mbcomp.assemble(model)
    tr = trace(system, 3_000_000, program="fun")
    g, fun = tr.graph, tr.groups["fun"]
    nq = len(tr.groups["qrate"])
    nn = len(fun)
    ins = [g.memo.get(("in", "q", k)) for k in range(nq)] + [g.memo.get(("in", "u", k)) for k in range(nn - nq)]
    loops = TangentLoops(g, fun, ins, [(0, nq), (nq, nn)], tr.guard_groups["fun"], f"t_chain_{which}",
                         str(tmp_path), "test")
    plan = loops.plan
    assert plan.statements and len(plan.statements) < len(plan.hull) + 1
    flat = [v for row in tangent(g, fun, ins) for v in row]
    prog = Program(g, {"jac": flat}, guard_groups={"jac": list(tr.guard_groups["fun"])})
    assert plan.n_element_ops() <= prog.n_ops("jac")  # no more work than the scalar forward mode
    env = dict(PY_ENV)
    exec(prog.python_main("jac", "jac"), env)
    from mbcomp.codegen.printers import ParamProgram

    pv = param_vector(system, tr.layout)
    rng = np.random.default_rng(7)
    q, u = 0.3 + 0.5 * rng.standard_normal(nq), rng.standard_normal(nn - nq)
    rc, J = _run(loops, q, u, pv, nn, d=[0.0, 0.0])
    want = np.array(env["jac"](list(q), list(u), 0.0, [0.0, 0.0], ParamProgram(prog).run(pv)), float).reshape(nn, nn)
    assert rc == 0
    np.testing.assert_allclose(J, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_a_failed_guard_returns_one_and_a_non_finite_partial_gives_nan(tmp_path):
    with Graph() as g:
        x, y = g.input("q", 0, 0.5), g.input("u", 0, 2.0)
        if x > 0.0:  # the traced branch: a guard x > 0
            f = [np.sqrt(x * y) * y, np.abs(x - 0.5) + y]
        else:
            f = [x, y]
    assert g.guards
    loops = TangentLoops(g, f, [x, y], [(0, 1), (1, 2)], g.guards, "t_guard", str(tmp_path), "test")
    rc, J = _run(loops, [0.5], [2.0], [], 2)
    assert rc == 0
    assert J[0, 0] == pytest.approx(0.5 * 2.0 * 2.0 / np.sqrt(1.0), rel=1e-15)
    assert np.isnan(J[1, 0]) and J[1, 1] == 1.0  # |x - 0.5| at its kink: no derivative, NaN
    assert _run(loops, [-0.5], [2.0], [], 2)[0] == 1  # the other branch: not this program


def test_the_plan_is_checked():
    with Graph() as g:
        x = g.input("q", 0, 1.0)
        y = x * x
    with pytest.raises(ValueError, match="inputs\\[0\\] is not an input node"):
        DirectionPlan(g, [y], [y], [(0, 1)])
