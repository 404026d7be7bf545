"""Exact Jacobians from the traced graph (issue 31 item 1): forward-mode differentiation of
the graph (:mod:`mbcomp.codegen.tangent`) and the Lagrange right-hand side's Jacobian program
(:mod:`mbcomp.codegen.jacobian`) that :meth:`LagrangeIndex1.jac` gives scipy's implicit methods.

Checks: every graph operation's derivative against sympy's; the printed derivative program
against the nodes' trace-time values; a double pendulum's ``d fun / dy`` against the sympy-exact
one from :func:`mbcomp.equations` to 1e-12 relative; Taylor tests (the central-difference error
of ``J d`` falls as ``h^2`` over three decades) on a pendulum and the slider-crank loop; the
formulation's ``jac`` is the program's where one runs and differences on the numeric backend.
"""
import numpy as np
import pytest
import sympy as sp

import mbcomp
from conftest import double_pendulum
from conftest import load_model
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import compile_system
from mbcomp.codegen.graph import Graph
from mbcomp.codegen.printers import python_source, PY_ENV
from mbcomp.codegen.tangent import OPERATIONS, tangent
from mbcomp.codegen.toolchain import c_compiler
from mbcomp.formulations import LagrangeIndex1

slider_crank = load_model("models/slider_crank.py")
BACKENDS = ["python", pytest.param("c", marks=pytest.mark.skipif(c_compiler() is None, reason="no C compiler"))]

# (graph operation, the traced expression of inputs x, y, its sympy counterpart); values where
# every operation is defined: x = 0.3, y = 1.7
X, Y = 0.3, 1.7
CASES = [
    ("+", lambda x, y: x + y, lambda x, y: x + y),
    ("-", lambda x, y: x - y, lambda x, y: x - y),
    ("*", lambda x, y: x * y, lambda x, y: x * y),
    ("/", lambda x, y: x / y, lambda x, y: x / y),
    ("neg", lambda x, y: -(x * y), lambda x, y: -(x * y)),
    ("pow", lambda x, y: y ** x, lambda x, y: y ** x),
    ("pow", lambda x, y: y ** 3.5, lambda x, y: y ** sp.Rational(7, 2)),
    ("abs", lambda x, y: abs(x - y), lambda x, y: sp.Abs(x - y)),
    ("cos", lambda x, y: np.cos(x * y), lambda x, y: sp.cos(x * y)),
    ("sin", lambda x, y: np.sin(x * y), lambda x, y: sp.sin(x * y)),
    ("tan", lambda x, y: np.tan(x * y), lambda x, y: sp.tan(x * y)),
    ("asin", lambda x, y: np.arcsin(x / y), lambda x, y: sp.asin(x / y)),
    ("acos", lambda x, y: np.arccos(x / y), lambda x, y: sp.acos(x / y)),
    ("atan", lambda x, y: np.arctan(x * y), lambda x, y: sp.atan(x * y)),
    ("sqrt", lambda x, y: np.sqrt(x * y), lambda x, y: sp.sqrt(x * y)),
    ("exp", lambda x, y: np.exp(x * y), lambda x, y: sp.exp(x * y)),
    ("log", lambda x, y: np.log(x * y), lambda x, y: sp.log(x * y)),
    ("sinh", lambda x, y: np.sinh(x * y), lambda x, y: sp.sinh(x * y)),
    ("cosh", lambda x, y: np.cosh(x * y), lambda x, y: sp.cosh(x * y)),
    ("tanh", lambda x, y: np.tanh(x * y), lambda x, y: sp.tanh(x * y)),
    ("atan2", lambda x, y: np.arctan2(x, y), lambda x, y: sp.atan2(x, y)),
    ("hypot", lambda x, y: np.hypot(x, y), lambda x, y: sp.sqrt(x * x + y * y)),
]


def test_every_operation_of_the_graph_has_a_case():
    assert {op for op, _, _ in CASES} == set(OPERATIONS) - {"c", "in"}


@pytest.mark.parametrize("op, traced, exact", CASES, ids=[f"{c[0]}{k}" for k, c in enumerate(CASES)])
def test_the_derivative_of_each_operation_is_sympys(op, traced, exact):
    with Graph() as g:
        x, y = g.input("q", 0, X), g.input("u", 0, Y)
        f = traced(x, y)
    assert g.keys[f.i][0] == op  # the case exercises the operation it names
    J = tangent(g, [f], [x, y])
    xs, ys = sp.symbols("x y", real=True)
    e = exact(xs, ys)
    for k, s in enumerate((xs, ys)):
        want = float(sp.diff(e, s).subs({xs: sp.Rational(3, 10), ys: sp.Rational(17, 10)}).evalf(30))
        got = J[0][k].v if not isinstance(J[0][k], float) else J[0][k]
        assert got == pytest.approx(want, rel=1e-14, abs=1e-15)
    # the derivative nodes are ordinary nodes: the Python printer prints them unchanged
    env = dict(PY_ENV)
    exec(python_source(g, J[0], "d"), env)
    np.testing.assert_allclose(env["d"]([X], [Y], 0.0, [], []), [getattr(v, "v", v) for v in J[0]], rtol=1e-15)


def test_structural_zeros_stay_numbers_and_nodes_are_shared():
    with Graph() as g:
        x, y, z = g.input("q", 0, 0.4), g.input("q", 1, 0.9), g.input("u", 0, 2.0)
        k = g.input("p", 0, 3.0, state=False)
        f = [k * np.sin(x) * z, y * y, k * k]
    n0 = len(g)
    J = tangent(g, f, [x, y, z])
    assert J[0][1] == 0.0 and J[1][0] == 0.0 and J[1][2] == 0.0 and J[2] == [0.0, 0.0, 0.0]
    assert all(type(v) is float for v in (J[0][1], J[1][0], J[2][0]))
    # d(y*y)/dy = y + y: one new node; d(k sin(x) z)/dz = k sin(x), a node that was already there
    assert J[0][2] is g.nodes[g.keys[f[0].i][1]] or J[0][2].i < n0
    assert J[1][1].v == pytest.approx(1.8, rel=1e-15)


def test_inputs_must_be_input_nodes():
    with Graph() as g:
        x = g.input("q", 0, 1.0)
        y = x * x
    with pytest.raises(ValueError, match="inputs\\[0\\] is not an input node"):
        tangent(g, [y], [y])


def test_an_input_given_as_none_has_a_zero_column_and_moves_no_other():
    """``graph.memo.get`` gives None for an input the tracer did not make: its column is zero."""
    with Graph() as g:
        x, y = g.input("q", 0, 0.5), g.input("u", 0, 2.0)
        f = [np.sin(x) * y, y * y]
    full = tangent(g, f, [x, y])
    J = tangent(g, f, [x, None, y])
    assert [row[1] for row in J] == [0.0, 0.0]
    assert [[getattr(v, "v", v) for v in (row[0], row[2])] for row in J] == \
        [[getattr(v, "v", v) for v in row] for row in full]


def _form(model, backend):
    s = mbcomp.assemble(model)
    init = initialize(s)
    form = LagrangeIndex1(compile_system(s, backend))
    return form, form.initial_state(0.0, init.q, init.u)


@pytest.mark.parametrize("backend", BACKENDS)
def test_double_pendulum_jacobian_is_sympy_exact(backend):
    model = double_pendulum()
    eqs = mbcomp.equations(model)
    q, u = sp.Matrix(eqs.q), sp.Matrix(eqs.u)
    rhs = sp.Matrix.vstack(u, eqs.M.LUsolve(eqs.f))
    Jx = rhs.jacobian(sp.Matrix.vstack(q, u))
    form, _ = _form(model, backend)
    y = np.array([0.7, -0.4, 1.3, -0.8])
    at = dict(zip(list(q) + list(u), [sp.Rational(repr(float(v))) for v in y]))
    ref = np.array(Jx.subs(at).evalf(30), dtype=float)
    J = form.system.evaluator.lagrange_jac(0.0, y, 0.0, 0.0)
    assert J is not None  # the exact program, not differences
    np.testing.assert_allclose(J, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_array_equal(form.jac(0.0, y), J)  # what scipy's implicit methods get


def _taylor_errors(form, y, hs):
    J = form.system.evaluator.lagrange_jac(0.0, y, *form.output_gains())
    assert J is not None
    d = np.random.default_rng(3).standard_normal(y.size)
    return [np.abs((form.fun(0.0, y + h * d) - form.fun(0.0, y - h * d)) / (2 * h) - J @ d).max() for h in hs]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("which", ["pendulum", "slider_crank"])
def test_taylor_the_central_difference_error_falls_as_h_squared(which, backend):
    model = double_pendulum() if which == "pendulum" else slider_crank.build()
    form, y = _form(model, backend)
    y = y + 0.05 * np.sin(np.arange(y.size) + 1.0)  # off the constraint manifold: Baumgarte terms act
    hs = [1e-2, 1e-3, 1e-4, 1e-5]  # three decades in the asymptotic range, above rounding
    err = _taylor_errors(form, y, hs)
    rates = np.log10(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(rates > 1.9) and np.all(rates < 2.1), (err, rates)


def test_the_numeric_backend_keeps_differences_and_a_generated_one_the_program():
    model = slider_crank.build()
    form, y = _form(model, "python")
    s = mbcomp.assemble(model)
    init = initialize(s)
    num = LagrangeIndex1(s)
    y0 = num.initial_state(0.0, init.q, init.u)
    np.testing.assert_array_equal(num.jac(0.0, y0), num.difference_columns(0.0, y0, range(y0.size)))
    J = form.jac(0.0, y)
    np.testing.assert_array_equal(J, form.system.evaluator.lagrange_jac(0.0, y, *form.output_gains()))
    # the exact Jacobian against the differences: agree to the differences' own error
    np.testing.assert_allclose(J, num.jac(0.0, y0), rtol=1e-5, atol=1e-5 * np.abs(J).max())


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_bound_program_returns_its_own_matrix_and_none_where_an_entry_is_not_finite(backend):
    from mbcomp.codegen.jacobian import JacobianCode

    system = mbcomp.assemble(double_pendulum())
    jac = JacobianCode.build(system, backend).bind(system)
    y1, y2 = np.array([0.7, -0.4, 1.3, -0.8]), np.array([0.1, 0.2, -0.3, 0.4])
    J1 = jac(0.0, y1, 0.0, 0.0)
    keep = J1.copy()
    J2 = jac(0.0, y2, 0.0, 0.0)
    np.testing.assert_array_equal(J1, keep)  # the second call did not write into the first's matrix
    assert np.abs(J2 - J1).max() > 0.1
    np.testing.assert_array_equal(jac(0.0, y1, 0.0, 0.0), keep)  # the same state, the same matrix
    # a rate of 1e160 squares to infinity in the centripetal terms: no exact Jacobian there
    assert jac(0.0, np.array([0.7, -0.4, 1e160, -0.8]), 0.0, 0.0) is None
