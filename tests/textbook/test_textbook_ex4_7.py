"""Seed Example 4.7: two-link arm with a massless motor-driven link (models/textbook/ex4_7_two_link_arm.py).

The component model (Revolute + massless FixedTranslation + Revolute + RigidBody rod, motor
``Torque(tau=lambda t, phi, w: M0 - dM*w)``) is checked against

* the equations of motion derived here independently with Lagrange's equations in sympy
  (positions from rotation matrices, kinetic energy from the centre-of-mass velocity and the
  body angular velocity), integrated with scipy at tight tolerance;
* the power balance ``dE/dt = Md * omega`` (the motor is the only non-conservative force);
* the book's Newton-Euler result (4.20)-(4.22).

Finding (book derivation error): in (4.20) -- and in ``f1`` of (4.22) and the Matlab program of
Fig. 4.7 -- the two velocity-product (Coriolis) coefficients are wrong:
``(m a l / 2) alpha' beta' cos b`` must be ``m a l alpha' beta' cos b`` and
``(5/12) m l^2 alpha' beta' sin b cos b`` must be ``(2/3) m l^2 alpha' beta' sin b cos b``.
Together they are ``dJ/dt * alpha'`` with ``J(b) = m (a^2 + a l sin b + l^2/3 sin^2 b)`` the
moment of inertia about the vertical axis (the mass-matrix entry the book has right): the
torque balance about Z is ``d/dt (J alpha') = Md``. The cause is the acceleration (4.4): its
i2 component keeps ``-(l/2) alpha' beta' cos b`` from differentiating the i2 component of
(4.3) but drops the equal term ``-(Omega_2 x v_G) . i2 = -(l/2) alpha' beta' cos b`` from the
rotation of the j2 velocity component ``(l/2) beta'`` by ``alpha' cos b`` about k2. With the
correct i2 acceleration the book's own elimination (4.11), (4.19) gives the Lagrange
equation. The mass-matrix terms of (4.20), the motor term, and all of (4.21) (= f3 of the
program) are right. The book's equations violate the power balance; the model satisfies it.
"""
import functools
import types

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import cumulative_simpson, solve_ivp

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex4_7_two_link_arm.py")
P = dict(m=2.0, a=0.1, l=0.5, dM=0.5, M0=1.0, g=9.81)  # the book's program (Fig. 4.7)
T_END = 10.0

# ---------------------------------------------------------------- independent Lagrange derivation
@functools.cache
def derivation():
    """The symbolic derivation (sympy) as a namespace of its names (``S.EQ``, ...), made once on
    first use: not at import, which pytest does in every worker while it collects."""
    t = sp.Symbol("t", real=True)
    m, a, l, g, M0, dM = sp.symbols("m a l g M0 dM", positive=True)
    al, be = sp.Function("alpha")(t), sp.Function("beta")(t)
    ald, bed = al.diff(t), be.diff(t)
    A1, B1, A2, B2 = sp.symbols("alpha_d beta_d alpha_dd beta_dd")  # plain symbols for rates, accelerations

    def _rz(q):
        return sp.Matrix([[sp.cos(q), -sp.sin(q), 0], [sp.sin(q), sp.cos(q), 0], [0, 0, 1]])

    def _rx(q):
        return sp.Matrix([[1, 0, 0], [0, sp.cos(q), -sp.sin(q)], [0, sp.sin(q), sp.cos(q)]])

    R1 = _rz(al)                # link 1 -> world: rotation alpha about the vertical Z
    R2 = R1 * _rx(be)           # link 2 -> world: then beta about x1 (hinge A)
    r_A = R1 * sp.Matrix([0, a, 0])
    r_G = r_A + R2 * sp.Matrix([0, 0, -l / 2])  # rod hangs from A; beta > 0 swings it outwards
    v_G = r_G.diff(t)
    W = sp.simplify(R2.T * R2.diff(t))  # skew(omega_2) in link-2 axes
    w2 = sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])
    I_G = sp.diag(m * l ** 2 / 12, m * l ** 2 / 12, 0)  # slender rod about its centre, link-2 axes
    T_kin = sp.simplify((m * v_G.dot(v_G) + (w2.T * I_G * w2)[0]) / 2)
    V_pot = m * g * r_G[2]
    Lag = T_kin - V_pot
    Q = {al: M0 - dM * ald, be: 0}  # motor torque Md does virtual work Md*delta(alpha); hinge A is free

    def _plain(expr):
        """Replace derivatives by plain symbols (accelerations first)."""
        return expr.subs({al.diff(t, 2): A2, be.diff(t, 2): B2}).subs({ald: A1, bed: B1})

    EQ = {q: sp.expand(_plain(sp.diff(Lag.diff(q.diff(t)), t) - Lag.diff(q) - Q[q])) for q in (al, be)}
    EQ_ALPHA, EQ_BETA = EQ[al], EQ[be]
    _acc = sp.solve([EQ_ALPHA, EQ_BETA], [A2, B2], dict=True)[0]
    _args = (al, be, A1, B1, m, a, l, g, M0, dM)
    _f = sp.lambdify(_args, [_plain(_acc[A2]), _plain(_acc[B2])], "numpy")
    _energy = sp.lambdify(_args, _plain(T_kin + V_pot), "numpy")
    _denergy = sp.lambdify(_args[:4] + (A2, B2) + _args[4:], _plain((T_kin + V_pot).diff(t)), "numpy")
    sb, cb = sp.sin(be), sp.cos(be)

    # ---------------------------------------------------------------- the book, as printed
    BOOK_4_20 = (m * a ** 2 * A2 + m * l ** 2 / 3 * A2 * sb ** 2 + m * a * l * A2 * sb
                 + sp.Rational(5, 12) * m * l ** 2 * A1 * B1 * sb * cb + m * a * l / 2 * A1 * B1 * cb
                 - (M0 - dM * A1))
    BOOK_4_21 = sp.Rational(2, 3) * l * B2 - sp.Rational(2, 3) * l * A1 ** 2 * sb * cb - a * A1 ** 2 * cb + g * sb
    # acceleration of the rod's centre, link-2 components (i2, j2, k2), eq. (4.4)
    BOOK_4_4 = sp.Matrix([-a * A2 - l / 2 * A2 * sb - l / 2 * A1 * B1 * cb,
                          l / 2 * B2 - a * A1 ** 2 * cb - l / 2 * A1 ** 2 * sb * cb,
                          l / 2 * B1 ** 2 + a * A1 ** 2 * sb + l / 2 * A1 ** 2 * sb ** 2])
    return types.SimpleNamespace(**locals())


def book_rhs(_, x, p=P):
    """State equations (4.22) as programmed in Fig. 4.7: x = (omega, beta, beta')."""
    om, b, bd = x
    kk = p["m"] * (p["a"] ** 2 + p["l"] ** 2 / 3 * np.sin(b) ** 2 + p["a"] * p["l"] * np.sin(b))
    f1 = (-5 / 12 * p["m"] * p["l"] ** 2 * om * bd * np.sin(b) * np.cos(b)
          - p["m"] * p["a"] * p["l"] / 2 * om * bd * np.cos(b) - p["dM"] * om + p["M0"]) / kk
    f3 = (om ** 2 * np.sin(b) * np.cos(b) + 3 / 2 / p["l"] * p["a"] * om ** 2 * np.cos(b)
          - 3 / 2 * p["g"] / p["l"] * np.sin(b))
    return [f1, bd, f3]


def lagrange_rhs(_, y, p=P):
    """y = (alpha, beta, alpha', beta') from the sympy Lagrange equations."""
    S = derivation()
    aa, bb, ad, bd = y
    add, bdd = S._f(aa, bb, ad, bd, p["m"], p["a"], p["l"], p["g"], p["M0"], p["dM"])
    return [ad, bd, add, bdd]


def _motor_power(om, p=P):
    return (p["M0"] - p["dM"] * om) * om


@pytest.fixture(scope="module")
def result():
    r = mbcomp.simulate(MOD.build(), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=2001, method="DOP853")
    assert r.success, r.message
    return r


@pytest.fixture(scope="module")
def lagrange(result):
    sol = solve_ivp(lagrange_rhs, (0.0, T_END), [0.0, 0.0, 0.0, 0.0], method="DOP853",
                    rtol=1e-13, atol=1e-13, t_eval=result.time)
    assert sol.success
    return sol.y


def test_model_has_two_dof_and_book_aliases():
    text = mbcomp.assemble(MOD.build()).summary()
    assert "degrees of freedom: 2 " in text  # book: 2*6 - (5 + 5) = 2
    assert "rigid offsets merged into their bodies (no coordinates): link1" in text
    assert "bodies (1): link2" in text  # link 1 is massless


def test_trajectory_matches_independent_lagrange_equations(result, lagrange):
    alpha, beta, omega, beta_d = lagrange
    assert omega.max() > 1.5 and np.ptp(beta) > 0.05  # spins up towards M0/dM = 2 rad/s, rod swings out
    np.testing.assert_allclose(result["alpha"], alpha, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["omega"], omega, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["beta"], beta, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["beta_dot"], beta_d, rtol=0, atol=1e-7)


def test_power_balance_motor_work_equals_energy_change(result):
    """dE/dt = Md omega at every output point (E = T + V from sympy, differentiated along the
    model's own rates and accelerations), and mbcomp's energy equals the sympy T + V."""
    S = derivation()
    p = P
    pars = (p["m"], p["a"], p["l"], p["g"], p["M0"], p["dM"])
    state = (result["alpha"], result["beta"], result["omega"], result["beta_dot"])
    E = result["energy.total"]
    np.testing.assert_allclose(E, S._energy(*state, *pars), rtol=0, atol=1e-12)
    dE = S._denergy(*state, result["base.w.der"], result["hinge_A.w.der"], *pars)
    power = _motor_power(result["omega"])
    assert np.abs(power).max() > 0.4 and np.ptp(E) > 0.05  # the motor spins the arm up and lifts the rod
    np.testing.assert_allclose(dE, power, rtol=0, atol=1e-9)
    # integrated: E(t) - E(0) = int Md omega dt (Simpson on the output grid; its error, set by the
    # 0.04 s start transient sampled at 5 ms, is about 5e-6 J)
    work = cumulative_simpson(power, x=result.time, initial=0.0)
    np.testing.assert_allclose(E - E[0], work, rtol=0, atol=2e-5)


def test_lagrange_mass_matrix_and_beta_equation_agree_with_book():
    S = derivation()
    # (4.20): the alpha'' coefficient m (a^2 + l^2/3 sin^2 b + a l sin b) and the motor term are right
    assert sp.simplify(S.EQ_ALPHA.coeff(S.A2) - S.BOOK_4_20.coeff(S.A2)) == 0
    rest = {S.A1: 0, S.A2: 0, S.B1: 0}
    assert sp.simplify(S.EQ_ALPHA.subs(rest) - S.BOOK_4_20.subs(rest)) == 0
    assert sp.simplify(S.EQ_ALPHA.coeff(S.B2)) == 0 and S.BOOK_4_20.coeff(S.B2) == 0
    # (4.21) = Lagrange beta equation / (m l / 2): beta'', centrifugal and gravity terms all right
    assert sp.simplify(S._plain(S.EQ_BETA) - S.m * S.l / 2 * S.BOOK_4_21) == 0


def test_book_velocity_product_coefficients_in_4_20_are_wrong():
    """The alpha' beta' terms of (4.20) are not d/dt(J) alpha' with J the Z-inertia of the rod."""
    S = derivation()
    lag = sp.expand(S._plain(S.EQ_ALPHA)).coeff(S.A1 * S.B1)
    book = sp.expand(S.BOOK_4_20).coeff(S.A1 * S.B1)
    J = sp.expand(S._plain(S.EQ_ALPHA)).coeff(S.A2)                  # = m (a^2 + a l sin b + l^2/3 sin^2 b)
    assert sp.simplify(lag - sp.diff(J, S.be)) == 0               # Lagrange: d(J alpha')/dt = Md
    assert sp.simplify(book - sp.diff(J, S.be)) != 0              # the book's is not
    lag_a, book_a = sp.Poly(lag, S.a).all_coeffs(), sp.Poly(book, S.a).all_coeffs()
    # the a-term: book m a l/2 cos b, correct m a l cos b  (wrong)
    assert sp.simplify(lag_a[0] - S.m * S.l * S.cb) == 0
    assert sp.simplify(book_a[0] - S.m * S.l / 2 * S.cb) == 0
    # the a-free term: book 5/12 m l^2 sin b cos b, correct 2/3 m l^2 sin b cos b  (wrong)
    assert sp.simplify(lag_a[1] - sp.Rational(2, 3) * S.m * S.l ** 2 * S.sb * S.cb) == 0
    assert sp.simplify(book_a[1] - sp.Rational(5, 12) * S.m * S.l ** 2 * S.sb * S.cb) == 0
    # both errors are the same omission: book - correct = -(m l/2) cos b (a + (l/2) sin b)
    assert sp.simplify(book - lag + S.m * S.l / 2 * S.cb * (S.a + S.l / 2 * S.sb)) == 0


def test_error_comes_from_the_i2_component_of_acceleration_4_4():
    S = derivation()
    acc2 = S._plain(S.R2.T * S.v_G.diff(S.t))  # true acceleration of G in link-2 axes
    diff = (S.BOOK_4_4 - acc2).applyfunc(sp.simplify)
    assert diff[1] == 0 and diff[2] == 0                      # j2, k2 components right
    # i2: the book lacks the Coriolis part (Omega_2 x v_G).i2 = -(l/2) alpha' beta' cos b
    om2 = S._plain(S.w2)
    vG2 = S._plain(S.R2.T * S.v_G)
    assert sp.simplify(diff[0] - (-om2.cross(vG2)[0])) == 0
    assert sp.simplify(diff[0] - S.l / 2 * S.A1 * S.B1 * S.cb) == 0
    # the book's elimination (4.11), (4.15)-(4.19): Md sin b = (m l^2/12)(alpha'' sin^2 b + 2 alpha' beta' sin b cos b)
    # - R_Ax (a + (l/2) sin b), with R_Ax = m * (i2 acceleration). With the true acceleration it is Lagrange's
    # equation, with the printed (4.4) it is (4.20).
    def eliminated(acc_x):
        Md = S.M0 - S.dM * S.A1
        return (S.m * S.l ** 2 / 12 * (S.A2 * S.sb ** 2 + 2 * S.A1 * S.B1 * S.sb * S.cb)
                - S.m * acc_x * (S.a + S.l / 2 * S.sb)) - Md

    assert sp.simplify(eliminated(acc2[0]) - S._plain(S.EQ_ALPHA)) == 0
    assert sp.simplify(eliminated(S.BOOK_4_4[0]) - S.BOOK_4_20) == 0


def test_model_accelerations_satisfy_4_21_and_violate_4_20_by_the_coriolis_error(result):
    p = P
    al_, b, om, bd = result["alpha"], result["beta"], result["omega"], result["beta_dot"]
    add, bdd = result["base.w.der"], result["hinge_A.w.der"]
    s, c = np.sin(b), np.cos(b)
    r421 = 2 / 3 * p["l"] * bdd - 2 / 3 * p["l"] * om ** 2 * s * c - p["a"] * om ** 2 * c + p["g"] * s
    np.testing.assert_allclose(r421, 0.0, atol=1e-8)
    m_, a_, l_ = p["m"], p["a"], p["l"]
    r420 = (m_ * (a_ ** 2 + l_ ** 2 / 3 * s ** 2 + a_ * l_ * s) * add + 5 / 12 * m_ * l_ ** 2 * om * bd * s * c
            + m_ * a_ * l_ / 2 * om * bd * c - (p["M0"] - p["dM"] * om))
    predicted = -m_ * l_ / 2 * om * bd * c * (a_ + l_ / 2 * s)  # from the coefficient errors above
    assert np.abs(predicted).max() > 1e-3
    np.testing.assert_allclose(r420, predicted, rtol=0, atol=1e-9)


def test_book_program_violates_power_balance(result):
    """Integrating the book's (4.22) as printed: its energy drifts from the motor's work,
    the measure of the wrong coefficients; the model's balance holds (test above)."""
    p = P
    sol = solve_ivp(book_rhs, (0.0, T_END), [0.0, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=result.time, dense_output=True)
    assert sol.success
    om, b, bd = sol.y
    T = 0.5 * p["m"] * (p["a"] ** 2 + p["a"] * p["l"] * np.sin(b) + p["l"] ** 2 / 3 * np.sin(b) ** 2) * om ** 2 \
        + p["m"] * p["l"] ** 2 / 6 * bd ** 2
    E = T - p["m"] * p["g"] * p["l"] / 2 * np.cos(b)
    defect = E - E[0] - cumulative_simpson(_motor_power(om), x=sol.t, initial=0.0)
    assert np.abs(defect).max() > 1e-3
    # and the trajectories differ visibly from the true motion
    assert np.abs(b - result["beta"]).max() > 1e-3
