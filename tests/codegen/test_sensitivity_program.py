"""The sensitivity programs (:mod:`mbcomp.codegen.sensitivity`) against sympy-exact derivatives:
``d fun/dp`` of a double pendulum with respect to masses, a rod length and gravity, and its
``d fun/dy``, to 1e-12 (issue 31 item 6); the residuals' derivatives of a closed loop against
central differences."""
import numpy as np
import pytest
import sympy as sp

import mbcomp
from conftest import double_pendulum
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import c_compiler
from mbcomp.codegen.sensitivity import ColumnCode, SensitivityCode, parameter_ref
from mbcomp.library import PointMass, World

BACKENDS = ["python"] + (["c"] if c_compiler() else [])


@pytest.fixture(scope="module")
def sympy_parameter_jacobian():
    """``d fun/dp`` of the double pendulum at one state, sympy-exact: the equations with the
    parameters as symbols, the state put in first (the solve is then in the parameters only)."""
    m1, m2, L2, g = sp.symbols("m1 m2 L2 g", positive=True)
    eqs = mbcomp.equations(double_pendulum(), params={"b1.m": m1, "b2.m": m2, "r2.r": [0, -L2, 0],
                                                      "world.g": [0, -g, 0]}, simplify=False)
    y = np.array([0.7, -0.4, 1.3, -0.8])
    at = dict(zip(list(eqs.q) + list(eqs.u), [sp.Rational(repr(float(v))) for v in y]))
    udot = eqs.M.subs(at).LUsolve(eqs.f.subs(at))
    rhs = sp.Matrix.vstack(sp.Matrix([at[u] for u in eqs.u]), udot)
    Jp = rhs.jacobian(sp.Matrix([m1, m2, L2, g]))
    values = {m1: sp.Rational(3, 2), m2: sp.Rational(1, 2), L2: sp.Rational(7, 10), g: sp.Rational(981, 100)}
    return y, np.array(Jp.subs(values).evalf(30), dtype=float)


@pytest.mark.parametrize("backend", BACKENDS)
def test_double_pendulum_parameter_derivatives_are_sympy_exact(backend, sympy_parameter_jacobian):
    y, ref = sympy_parameter_jacobian
    system = mbcomp.assemble(double_pendulum())
    # r2.r[1] = -L2: its column is minus the L2 one; g_y = -g likewise
    code = SensitivityCode.build(system, ["b1.m", "b2.m", "r2.r[1]", "world.g[1]"], backend)
    f, J, P = code.bind(system).rhs(0.0, y, 0.0, 0.0)
    want = ref * np.array([1.0, 1.0, -1.0, -1.0])
    np.testing.assert_allclose(P, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    # the jvp program (what runs use): f_y S + f_p along random columns, against the full matrices
    S = np.random.default_rng(0).standard_normal((4, 4))
    f2, D = code.bind(system).jvp(0.0, y, S, 0.0, 0.0)
    np.testing.assert_allclose(f2, f, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(D, J @ S + P, rtol=1e-12, atol=1e-12 * np.abs(D).max())


@pytest.mark.parametrize("backend", BACKENDS)
def test_closed_loop_residual_derivatives_match_central_differences(backend):
    """The slider-crank's ``[Phi, Phid, Psi]`` derivatives with respect to q, u and a loop
    length: the program against central differences of the numeric evaluation."""
    system = mbcomp.assemble(mbcomp.load_model_file("models/slider_crank.py").build())
    initialize(system)  # the independent rows (the loop's out-of-plane rows are redundant)
    names = ["rod_tip.r[0]"]
    bound = SensitivityCode.build(system, names, backend).bind(system)
    y = np.array([0.3, 0.8, 0.1, 6.0, -0.5, 1.9])
    r, Dq, Du, Dp = bound.residuals(0.0, y)

    def res(sysm, yy):
        ev = sysm.evaluate(0.0, yy[:3], yy[3:], masked=False)
        return np.concatenate((ev.Phi, ev.Phid, ev.Psi))
    np.testing.assert_allclose(r, res(system, y), atol=1e-14)
    h = 1e-6
    for i in range(6):
        e = np.zeros(6)
        e[i] = h
        fd = (res(system, y + e) - res(system, y - e)) / (2 * h)
        np.testing.assert_allclose((Dq if i < 3 else Du)[:, i % 3], fd, atol=1e-8)
    ref = parameter_ref(system, names[0])
    r0 = np.array(system.P["rod_tip"].r, float)
    plus, minus = (system.with_params({"rod_tip.r": r0 + s * np.array([h, 0, 0])}) for s in (1, -1))
    np.testing.assert_allclose(Dp[:, 0], (res(plus, y) - res(minus, y)) / (2 * h), atol=1e-8)
    assert ref.value == 0.6


def test_a_law_is_no_parameter_to_differentiate():
    """A torque law (a callable) is not a number: asking for its sensitivity names it."""
    from mbcomp.library import Torque

    m = double_pendulum()
    motor = m.add("motor", Torque(tau=lambda t, phi, w: -0.1 * w))
    m.connect(motor.flange_b, m["j1"].axis)
    system = mbcomp.assemble(m)
    with pytest.raises(ValueError, match="sensitivity parameter 'motor.tau' is function .* not a number"):
        SensitivityCode.build(system, ["motor.tau"], "python")


def test_column_program_energy_derivatives_are_exact():
    """T = m v^2 / 2 for a sliding mass: dT/dv = m v, dT/dm = v^2 / 2; V = -m g.r."""
    from mbcomp.library import Prismatic

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    s = m.add("s", Prismatic(n=(0, 0, 1)))
    b = m.add("b", PointMass(m=2.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    system = mbcomp.assemble(m)
    code = ColumnCode.build(system, ["b.m", "world.g[2]"], "python")
    D = code.bind(system)(0.0, np.array([1.5, 2.0]), 0.0, 0.0)
    T, V = code.names.index("energy.kinetic"), code.names.index("energy.potential")
    np.testing.assert_allclose(D[T], [0.0, 4.0, 2.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(D[V], [19.62, 0.0, 9.81 * 1.5, -2.0 * 1.5], atol=1e-12)
