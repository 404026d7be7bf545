"""Seed Example 6.3: two-link robot arm with joint torques (models/textbook/ex6_3_robot_arm.py).

Checks: an independent Lagrange derivation in sympy (absolute angles, generalized forces from
the virtual work of both motors including motor 2's reaction on link 1) reproduces the book's
(6.53)-(6.54) exactly -- the book is right here; the component model follows (6.53)-(6.54)
integrated with scipy at tight tolerance, for time-dependent torques and for the model's
default PD joint controllers; the energy changes by the motors' work,
``dE/dt = tau1 alpha1' + tau2 (alpha2' - alpha1')``; torque-free, energy and the angular
momentum about the shoulder axis are conserved.
"""
import functools
import types

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import cumulative_simpson, solve_ivp

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex6_3_robot_arm.py")
P = dict(m1=2.0, l1=0.5, a1=0.25, I1=2.0 * 0.5 ** 2 / 12, m2=1.0, a2=0.2, I2=1.0 * 0.4 ** 2 / 12)
T_END = 5.0

# ------------------------------------------------------------- independent Lagrange derivation
@functools.cache
def derivation():
    """The symbolic derivation (sympy) as a namespace of its names (``S.EQ``, ...), made once on
    first use: not at import, which pytest does in every worker while it collects."""
    t = sp.Symbol("t", real=True)
    m1, l1, a1, I1, m2, a2, I2, tau1, tau2 = sp.symbols("m1 l1 a1 I1 m2 a2 I2 tau1 tau2", real=True)
    q1, q2 = sp.Function("alpha1")(t), sp.Function("alpha2")(t)
    U1, U2, D1, D2 = sp.symbols("alpha1_d alpha2_d alpha1_dd alpha2_dd")
    A1s, A2s = sp.symbols("alpha1 alpha2")

    def _e(q):
        return sp.Matrix([sp.cos(q), sp.sin(q)])

    r_G1 = a1 * _e(q1)
    r_G2 = l1 * _e(q1) + a2 * _e(q2)
    v1, v2 = r_G1.diff(t), r_G2.diff(t)
    T_kin = sp.simplify((m1 * v1.dot(v1) + I1 * q1.diff(t) ** 2 + m2 * v2.dot(v2) + I2 * q2.diff(t) ** 2) / 2)
    # virtual work: tau1 on link 1 (reaction on ground), tau2 on link 2 with reaction -tau2 on link 1
    dq1, dq2 = sp.symbols("dq1 dq2")
    dW = sp.expand(tau1 * dq1 + tau2 * (dq2 - dq1))
    Q = {q1: dW.coeff(dq1), q2: dW.coeff(dq2)}

    def _plain(expr):
        return (expr.subs({q1.diff(t, 2): D1, q2.diff(t, 2): D2}).subs({q1.diff(t): U1, q2.diff(t): U2})
                .subs({q1: A1s, q2: A2s}))

    EQ = [sp.expand(_plain(sp.diff(T_kin.diff(q.diff(t)), t) - T_kin.diff(q) - Q[q])) for q in (q1, q2)]
    c12, s12 = sp.cos(A1s - A2s), sp.sin(A1s - A2s)
    BOOK_6_53 = ((I1 + m1 * a1 ** 2 + m2 * l1 ** 2) * D1 + m2 * a2 * l1 * D2 * c12 + m2 * a2 * l1 * U2 ** 2 * s12
                 - (tau1 - tau2))
    BOOK_6_54 = (m2 * a2 ** 2 + I2) * D2 + m2 * a2 * l1 * D1 * c12 - m2 * a2 * l1 * U1 ** 2 * s12 - tau2
    _pars = (m1, l1, a1, I1, m2, a2, I2)
    _state = (A1s, A2s, U1, U2)
    _dT = sp.lambdify(_state + (D1, D2) + _pars, _plain(T_kin.diff(t)), "numpy")
    _T = sp.lambdify(_state + _pars, _plain(T_kin), "numpy")
    # angular momentum about the shoulder axis: the Lagrangian is invariant under alpha1, alpha2 -> +eps
    _Hz = sp.lambdify(_state + _pars, _plain(T_kin.diff(q1.diff(t)) + T_kin.diff(q2.diff(t))), "numpy")
    return types.SimpleNamespace(**locals())


def book_rhs(tau1_law, tau2_law, p=P):
    """(6.53)-(6.54) solved for the accelerations; y = (alpha1, alpha2, alpha1', alpha2').
    The motor laws see their own joint: tau1(t, alpha1, alpha1'), tau2(t, alpha2 - alpha1, alpha2' - alpha1')."""
    J1 = p["I1"] + p["m1"] * p["a1"] ** 2 + p["m2"] * p["l1"] ** 2
    J2 = p["m2"] * p["a2"] ** 2 + p["I2"]
    k = p["m2"] * p["a2"] * p["l1"]

    def rhs(t_, y):
        x1, x2, w1, w2 = y
        T1, T2 = tau1_law(t_, x1, w1), tau2_law(t_, x2 - x1, w2 - w1)
        c, s = np.cos(x1 - x2), np.sin(x1 - x2)
        M = np.array([[J1, k * c], [k * c, J2]])
        b = np.array([T1 - T2 - k * w2 ** 2 * s, T2 + k * w1 ** 2 * s])
        return [w1, w2, *np.linalg.solve(M, b)]

    return rhs


def _pv():
    return tuple(P[k] for k in ("m1", "l1", "a1", "I1", "m2", "a2", "I2"))


def _build(**kw):
    return MOD.build(m1=P["m1"], l1=P["l1"], a1=P["a1"], I1=P["I1"], m2=P["m2"], a2=P["a2"], I2=P["I2"], **kw)


def _absolute(res):
    a1_, a2_ = res["alpha1"], res["alpha1"] + res["elbow_angle"]
    w1_, w2_ = res["alpha1_dot"], res["alpha1_dot"] + res["elbow_rate"]
    d1_, d2_ = res["shoulder.w.der"], res["shoulder.w.der"] + res["elbow.w.der"]
    return a1_, a2_, w1_, w2_, d1_, d2_


def _open_loop_1(t_, phi, w):
    return 1.5 * np.sin(2.0 * t_)


def _open_loop_2(t_, phi, w):
    return 0.6 * np.cos(3.0 * t_)


def _pd_1(t_, phi, w):
    return 8.0 * (1.0 - phi) - 1.5 * w


def _pd_2(t_, phi, w):
    return 3.0 * (0.8 - phi) - 0.5 * w


CASES = {
    # time-dependent motor torques from a moving start
    "open_loop": (dict(tau1=_open_loop_1, tau2=_open_loop_2, alpha1_0=0.3, alpha2_0=1.2,
                       alpha1_dot0=1.0, alpha2_dot0=-2.0), _open_loop_1, _open_loop_2, (0.3, 1.2, 1.0, -2.0)),
    # the model file's default PD joint controllers from rest (laws restated here)
    "default_pd": (dict(), _pd_1, _pd_2, (0.0, 0.0, 0.0, 0.0)),
}


@pytest.fixture(scope="module", params=list(CASES), ids=list(CASES))
def case(request):
    kw, law1, law2, y0 = CASES[request.param]
    res = mbcomp.simulate(_build(**kw), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=1001, method="DOP853")
    assert res.success, res.message
    sol = solve_ivp(book_rhs(law1, law2), (0.0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=res.time)
    assert sol.success
    return res, sol.y, law1, law2


def test_lagrange_derivation_reproduces_eqs_6_53_6_54():
    S = derivation()
    assert sp.simplify(S.EQ[0] - S.BOOK_6_53) == 0
    assert sp.simplify(S.EQ[1] - S.BOOK_6_54) == 0
    # generalized forces (6.43)-(6.44)
    assert sp.simplify(S.Q[S.q1] - (S.tau1 - S.tau2)) == 0 and S.Q[S.q2] == S.tau2


def test_summary_two_dof():
    text = mbcomp.assemble(_build()).summary()
    assert "degrees of freedom: 2 " in text
    assert "tree joints (minimal coordinates): shoulder, elbow" in text


def test_trajectory_matches_eqs_6_53_6_54(case):
    res, (x1, x2, w1, w2), _, _ = case
    a1_, a2_, w1_, w2_, _, _ = _absolute(res)
    assert np.ptp(x1) > 0.5 and np.ptp(x2 - x1) > 0.5  # both joints move substantially
    np.testing.assert_allclose(a1_, x1, rtol=0, atol=1e-7)
    np.testing.assert_allclose(a2_, x2, rtol=0, atol=1e-7)
    np.testing.assert_allclose(w1_, w1, rtol=0, atol=1e-7)
    np.testing.assert_allclose(w2_, w2, rtol=0, atol=1e-7)


def test_model_accelerations_satisfy_eqs_6_53_6_54(case):
    S = derivation()
    res, _, law1, law2 = case
    a1_, a2_, w1_, w2_, d1_, d2_ = _absolute(res)
    T1 = np.array([law1(ti, x, w) for ti, x, w in zip(res.time, a1_, w1_)])
    T2 = np.array([law2(ti, x, w) for ti, x, w in zip(res.time, a2_ - a1_, w2_ - w1_)])
    subs = dict(zip((S.A1s, S.A2s, S.U1, S.U2, S.D1, S.D2, S.tau1, S.tau2), (a1_, a2_, w1_, w2_, d1_, d2_, T1, T2)))
    subs.update(dict(zip(S._pars, _pv())))
    for eq in (S.BOOK_6_53, S.BOOK_6_54):
        f = sp.lambdify(list(subs), eq, "numpy")
        np.testing.assert_allclose(f(*subs.values()), 0.0, atol=1e-9)


def test_energy_balance_input_power_of_the_torques(case):
    S = derivation()
    res, _, law1, law2 = case
    a1_, a2_, w1_, w2_, d1_, d2_ = _absolute(res)
    T1 = np.array([law1(ti, x, w) for ti, x, w in zip(res.time, a1_, w1_)])
    T2 = np.array([law2(ti, x, w) for ti, x, w in zip(res.time, a2_ - a1_, w2_ - w1_)])
    power = T1 * w1_ + T2 * (w2_ - w1_)  # motor 2 works on the relative rotation
    E = res["energy.total"]
    # horizontal plane: the potential energy is constant (V = 0 in the book), kinetic = (6.41)
    assert np.ptp(res["energy.potential"]) < 1e-12
    np.testing.assert_allclose(res["energy.kinetic"], S._T(a1_, a2_, w1_, w2_, *_pv()), rtol=0, atol=1e-12)
    dE = S._dT(a1_, a2_, w1_, w2_, d1_, d2_, *_pv())
    assert np.abs(power).max() > 1.0
    np.testing.assert_allclose(dE, power, rtol=0, atol=1e-9)
    work = cumulative_simpson(power, x=res.time, initial=0.0)
    np.testing.assert_allclose(E - E[0], work, rtol=0, atol=1e-6 * np.abs(power).max())


def test_torque_free_arm_conserves_energy_and_angular_momentum():
    S = derivation()
    res = mbcomp.simulate(_build(tau1=0.0, tau2=0.0, alpha1_0=0.3, alpha2_0=1.2, alpha1_dot0=2.0,
                                 alpha2_dot0=-3.0), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=501, method="DOP853")
    assert res.success, res.message
    a1_, a2_, w1_, w2_, _, _ = _absolute(res)
    assert np.ptp(a2_ - a1_) > 1.0  # the elbow folds and unfolds: energy moves between the links
    E = res["energy.total"]
    T1 = 0.5 * (P["I1"] + P["m1"] * P["a1"] ** 2) * w1_ ** 2
    assert np.ptp(T1) > 0.1 * E.max()
    assert np.abs(E - E[0]).max() < 1e-9 * np.abs(res["energy.kinetic"]).max()
    Hz = S._Hz(a1_, a2_, w1_, w2_, *_pv())
    assert np.abs(Hz - Hz[0]).max() < 1e-9 * np.abs(Hz[0])
