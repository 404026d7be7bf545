"""Reverse-mode differentiation of the traced graph (issue 31 item 3): :func:`mbcomp.codegen.adjoint.reverse`
and the vector-Jacobian program of the Lagrange right-hand side (:class:`AdjointCode`).

Checks: on every graph operation reverse mode gives forward mode's derivatives (the same
partials); the printed program's ``lam^T dfun/dy`` equals ``J^T lam`` from the exact Jacobian
program (:class:`~mbcomp.codegen.jacobian.JacobianCode`) to 1e-12 on a double pendulum and the
slider-crank loop, and its ``lam^T dfun/dp`` equals forward mode's ``df/dp`` (tangent) and a
central difference of ``fun`` in the parameter; a parameter kept at zero is differentiated; a
parameter the right-hand side does not depend on has product exactly zero.
"""
import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import compile_system
from mbcomp.codegen.adjoint import AdjointCode, reverse
from mbcomp.codegen.graph import Graph
from mbcomp.codegen.jacobian import JacobianCode
from mbcomp.codegen.printers import PY_ENV, Program
from mbcomp.codegen.tangent import tangent
from mbcomp.codegen.toolchain import c_compiler
from mbcomp.codegen.tracer import trace
from mbcomp.library import FixedTranslation, Damper, PointMass, Prismatic, Revolute, World
from test_tangent import CASES, X, Y

slider_crank = load_model("models/slider_crank.py")
BACKENDS = ["python", pytest.param("c", marks=pytest.mark.skipif(c_compiler() is None, reason="no C compiler"))]


@pytest.mark.parametrize("op, traced, exact", CASES, ids=[f"{c[0]}{k}" for k, c in enumerate(CASES)])
def test_reverse_mode_gives_forward_modes_derivative_of_each_operation(op, traced, exact):
    with Graph() as g:
        x, y = g.input("q", 0, X), g.input("u", 0, Y)
        f = traced(x, y)
        w = g.input("d", 0, 0.7)
        h = f * f  # a node used twice on the way back: adjoints add up
    fwd = tangent(g, [f, h], [x, y])
    rev = reverse(g, [f, h], [w, 2.0], [x, y])
    for k in range(2):
        want = 0.7 * getattr(fwd[0][k], "v", fwd[0][k]) + 2.0 * getattr(fwd[1][k], "v", fwd[1][k])
        assert getattr(rev[k], "v", rev[k]) == pytest.approx(want, rel=1e-14, abs=1e-15)


def double_pendulum():
    m = mbcomp.Model()
    w = m.add("world", World())
    j1 = m.add("j1", Revolute(phi0=0.7, w0=0.3))
    r1 = m.add("r1", FixedTranslation(r=(0, -1.0, 0)))
    b1 = m.add("b1", PointMass(m=1.5))
    j2 = m.add("j2", Revolute(phi0=-0.4, w0=-0.2))
    r2 = m.add("r2", FixedTranslation(r=(0.1, -0.8, 0)))
    b2 = m.add("b2", PointMass(m=0.7))
    m.connect(w.frame_b, j1.frame_a); m.connect(j1.frame_b, r1.frame_a); m.connect(r1.frame_b, b1.frame_a)
    m.connect(r1.frame_b, j2.frame_a); m.connect(j2.frame_b, r2.frame_a); m.connect(r2.frame_b, b2.frame_a)
    return m


def system_at_start(model):
    system = mbcomp.assemble(model)
    init = initialize(system)
    return system, np.concatenate((init.q, init.u))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("which", ["double_pendulum", "slider_crank"])
def test_vjp_is_the_exact_jacobian_transposed_times_lam(backend, which):
    system, y0 = system_at_start(double_pendulum() if which == "double_pendulum" else slider_crank.build())
    n = y0.size
    jac = JacobianCode.build(system, backend).bind(system)
    vjp = AdjointCode.build(system, backend).bind(system)
    rng = np.random.default_rng(3)
    for _ in range(4):
        y = y0 + 0.05 * rng.standard_normal(n)
        lam = rng.standard_normal(n)
        for alpha, beta in ((0.0, 0.0), (10.0, 7.0)):
            J = jac(0.3, y, alpha, beta)
            out = vjp(0.3, y, [alpha, beta, *lam])
            want = J.T @ lam
            np.testing.assert_allclose(out[:n], want, rtol=1e-12, atol=1e-12 * np.abs(J).max() * np.abs(lam).max())


@pytest.mark.parametrize("backend", BACKENDS)
def test_vjp_in_the_parameters_is_forward_modes_and_a_central_difference(backend):
    system, y0 = system_at_start(slider_crank.build())
    code = AdjointCode.build(system, backend)
    vjp = code.bind(system)
    n = y0.size
    lam = np.array([0.3, -1.2, 0.5, 2.0, 0.7, -0.4])[:n]
    y = y0 + 0.02
    out = vjp(0.1, y, [10.0, 10.0, *lam])
    # forward mode on a trace of its own, printed without hoisting
    tr = trace(system, 10**6, program="fun")
    g = tr.graph
    ps = [g.memo[("in", "p", k)] for k in range(len(tr.layout))]
    J = tangent(g, tr.groups["fun"], ps)
    flat = [v for row in J for v in row]
    env = dict(PY_ENV)
    exec(Program(g, {"dp": flat}, hoist=False).python_main("dp", "dp"), env)
    nq = system.nq
    fp = np.array(env["dp"](list(y[:nq]), list(y[nq:]), 0.1, [10.0, 10.0], [x.v for x in ps])).reshape(n, len(ps))
    assert code.layout == tr.layout
    np.testing.assert_allclose(out[n:], fp.T @ lam, rtol=1e-12, atol=1e-12 * np.abs(fp).max())
    # and against the right-hand side itself: the rod's mass, by a central difference
    k = code.layout.index(("rod", "m", None))
    h = 1e-5
    funs = []
    for s in (1, -1):
        sys2 = compile_system(system.with_params({"rod.m": 2.0 + s * h}), "python")
        sys2.row_mask = system.row_mask
        funs.append(sys2.evaluator.lagrange_fun(0.1, y, 10.0, 10.0))
    fd = (funs[0] - funs[1]) / (2 * h) @ lam
    assert out[n + k] == pytest.approx(fd, rel=1e-7)


def damped_slider(d):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.1, v0=1.0))
    b = m.add("b", PointMass(m=2.0))
    damper = m.add("damper", Damper(d=d))
    m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    m.connect(w.frame_b, damper.frame_a); m.connect(b.frame_a, damper.frame_b)
    return m


def test_a_parameter_kept_at_zero_is_differentiated_and_an_unused_one_is_exactly_zero():
    system, y0 = system_at_start(damped_slider(0.0))
    code = AdjointCode.build(system, "python", keep=[("damper", "d")])
    k = code.layout.index(("damper", "d", None))
    out = code.bind(system)(0.0, y0, [0.0, 0.0, 0.0, 1.0])
    # du/dt = -d v / m along the axis (gravity across it): d/dd = -v / m
    assert out[2 + k] == pytest.approx(-1.0 / 2.0, rel=1e-14)
    # gravity along y is across the axis (x): it does not enter du/dt, its product is exactly 0
    kg = code.layout.index(("world", "g", (1,)))
    assert out[2 + kg] == 0.0
