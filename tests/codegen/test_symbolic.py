"""Symbolic equations of motion (``mbcomp.equations``), traced from the numeric evaluation.

* The seed's Examples 6.1, 6.2, 6.3, 6.4: with the masses, lengths, inertias, spring rate,
  gravity, motor torques and spin rate made symbolic through ``params``, the traced ``M`` and
  ``f`` equal the book's equations written as ``A(q) q'' = b(q, q')`` exactly (sympy simplifies
  every difference to zero); 6.3 after the change from the model's relative joint angles to
  the book's absolute angles, 6.4 with the spin prescribed (only beta remains).
* Example 4.7: ``M q'' - f`` equals the independent Lagrange derivation of
  ``tests/textbook/test_textbook_ex4_7.py`` and differs from the book's (4.20) by exactly its wrong
  velocity-product terms; (4.21) is right.
* Numeric identity: the lambdified symbolic ``M``, ``f``, ``dq/dt`` (and for the slider-crank
  ``Phi``, ``C``, ``cb``) equal ``evaluate`` at random states to 1e-12, for a 3-D model with a
  spherical joint (quaternion coordinates, with and without a prescribed motion) and a loop.
* Errors: an untraceable law (``math.sin``) names its component; unknown parameters are named.
"""
import math

import numpy as np
import pytest
import sympy as sp

import mbcomp
from conftest import load_model, load_module

EX61 = load_model("models/textbook/ex6_1_pendulum.py")
EX62 = load_model("models/textbook/ex6_2_cart_pendulum.py")
EX63 = load_model("models/textbook/ex6_3_robot_arm.py")
EX64 = load_model("models/textbook/ex6_4_spinning_pendulum.py")
EX47 = load_model("models/textbook/ex4_7_two_link_arm.py")
EX43 = load_model("models/textbook/ex4_3_slider_spherical.py")
CRANK = load_model("models/slider_crank.py")


def linear_form(eqs, acc):
    """Book equations ``sum_j A_ij acc_j + h_i = 0`` -> ``(A, -h)``."""
    A = sp.Matrix([[sp.expand(e).coeff(d) for d in acc] for e in eqs])
    h = sp.Matrix([sp.expand(e).subs({d: 0 for d in acc}) for e in eqs])
    return A, -h


def assert_zero(matrix):
    """Every entry simplifies to zero."""
    for i, e in enumerate(matrix):
        assert sp.simplify(e) == 0, f"entry {i}: {sp.simplify(e)} != 0"


# ------------------------------------------------------------------------------ Example 6.1
def test_ex6_1_pendulum_is_eq_6_20():
    m, l, g = sp.symbols("m l g", positive=True)
    eqs = mbcomp.equations(EX61.build(), params={"bob.m": m, "rod.r": (0, -l, 0), "world.g": (0, -g, 0)})
    th, thd, thdd = eqs.symbol("hinge.phi"), eqs.symbol("hinge.w"), eqs.symbol("hinge.w.der")
    assert eqs.q == (th,) and eqs.u == (thd,)
    book = m * l ** 2 * thdd + m * g * l * sp.sin(th)  # (6.20)
    A, b = linear_form([book], [thdd])
    assert_zero(eqs.M - A)
    assert_zero(eqs.f - b)
    assert_zero(eqs.residual - sp.Matrix([book]))
    assert eqs.qdot == sp.Matrix([thd]) and eqs.C.shape == (0, 1)
    assert sp.simplify(eqs.T - m * l ** 2 * thd ** 2 / 2) == 0  # (6.17)
    assert sp.simplify(eqs.V + m * g * l * sp.cos(th)) == 0  # (6.18), datum at the hinge


# ------------------------------------------------------------------------------ Example 6.2
def test_ex6_2_cart_pendulum_is_eqs_6_36_6_37():
    m1, m2, L, k, g = sp.symbols("m1 m2 L k g", positive=True)
    eqs = mbcomp.equations(EX62.build(), params={"cart.m": m1, "bob.m": m2, "rod.r": (0, -L, 0),
                                                 "spring.c": k, "world.g": (0, -g, 0)})
    x, th = eqs.q
    xd, thd = eqs.u
    xdd, thdd = eqs.ud
    assert (x.name, th.name) == ("slider.s", "hinge.phi")
    c, s = sp.cos(th), sp.sin(th)
    book = [(m1 + m2) * xdd + m2 * L * thdd * c - m2 * L * thd ** 2 * s + k * x,  # (6.36)
            m2 * L ** 2 * thdd + m2 * L * xdd * c + m2 * g * L * s]  # (6.37)
    A, b = linear_form(book, [xdd, thdd])
    assert_zero(eqs.M - A)
    assert_zero(eqs.f - b)
    assert sp.simplify(eqs.T - ((m1 + m2) * xd ** 2 / 2 + m2 * L * xd * thd * c + m2 * L ** 2 * thd ** 2 / 2)) == 0  # (6.24)
    assert sp.simplify(eqs.V - (k * x ** 2 / 2 - m2 * g * L * c)) == 0  # (6.25)


# ------------------------------------------------------------------------------ Example 6.3
def test_ex6_3_robot_arm_is_eqs_6_53_6_54_in_absolute_angles():
    m1, l1, a1, I1, m2, a2, I2, tau1, tau2 = sp.symbols("m1 l1 a1 I1 m2 a2 I2 tau1 tau2", positive=True)
    eqs = mbcomp.equations(EX63.build(), params={
        "link1.m": m1, "link1.r_cm": (a1, 0, 0), "link1.I": sp.diag(0, I1, I1), "upper.r": (l1, 0, 0),
        "link2.m": m2, "link2.r_cm": (a2, 0, 0), "link2.I": sp.diag(0, I2, I2),
        "motor1.tau": tau1, "motor2.tau": tau2})
    q1, q2 = eqs.q  # shoulder angle, elbow (relative) angle
    u1, u2 = eqs.u
    assert (q1.name, q2.name) == ("shoulder.phi", "elbow.phi")
    # the book's absolute angles: alpha1 = q1, alpha2 = q1 + q2, so alpha = T q
    T = sp.Matrix([[1, 0], [1, 1]])
    al1, al2, w1, w2, d1, d2 = sp.symbols("alpha1 alpha2 w1 w2 d1 d2")
    c12, s12 = sp.cos(al1 - al2), sp.sin(al1 - al2)
    book = [(I1 + m1 * a1 ** 2 + m2 * l1 ** 2) * d1 + m2 * a2 * l1 * d2 * c12 + m2 * a2 * l1 * w2 ** 2 * s12
            - (tau1 - tau2),  # (6.53)
            (m2 * a2 ** 2 + I2) * d2 + m2 * a2 * l1 * d1 * c12 - m2 * a2 * l1 * w1 ** 2 * s12 - tau2]  # (6.54)
    A, b = linear_form(book, [d1, d2])
    to_model = {al1: q1, al2: q1 + q2, w1: u1, w2: u1 + u2}
    A, b = A.subs(to_model), b.subs(to_model)
    # the same equations in the model's coordinates: velocities map by T, forces by T^T
    assert_zero(eqs.M - T.T * A * T)
    assert_zero(eqs.f - T.T * b)
    # the generalized forces of the motors in relative angles are simply tau1, tau2 (6.43)-(6.44)
    assert sp.expand(eqs.f.subs({u1: 0, u2: 0})) == sp.Matrix([tau1, tau2])


# ------------------------------------------------------------------------------ Example 6.4
def test_ex6_4_spinning_pendulum_is_eq_6_63():
    m, l, g, Om = sp.symbols("m l g Omega", positive=True)
    It = m * l ** 2 / 12
    eqs = mbcomp.equations(EX64.build(), params={
        "bar.m": m, "bar.r_cm": (0, 0, -l / 2), "bar.I": sp.diag(It, It, 0), "world.g": (0, 0, -g),
        "spin_drive.s": Om * sp.Symbol("t")})  # the prescribed spin: only beta remains
    (be,), (bd,), (bdd,) = eqs.q, eqs.u, eqs.ud
    assert be.name == "hinge_A.phi" and eqs.M.shape == (1, 1)
    I = m * l ** 2 / 3
    book = I * bdd - I * Om ** 2 * sp.sin(be) * sp.cos(be) + m * g * l / 2 * sp.sin(be)  # (6.63)
    A, b = linear_form([book], [bdd])
    assert_zero(eqs.M - A)
    assert_zero(eqs.f - b)
    assert eqs.t not in (eqs.M.free_symbols | eqs.f.free_symbols)  # the spin angle Omega t drops out


# ------------------------------------------------------------------------------ Example 4.7
@pytest.fixture(scope="module")
def ex47():
    """The independent Lagrange derivation and the book's (4.20), (4.21) of test_textbook_ex4_7
    (its namespace of symbols and equations)."""
    return load_module("tests/textbook/test_textbook_ex4_7.py").derivation()


def test_ex4_7_equals_lagrange_and_shows_the_book_4_20_error(ex47):
    L = ex47
    It = L.m * L.l ** 2 / 12
    eqs = mbcomp.equations(EX47.build(), params={
        "link2.m": L.m, "link2.r_cm": (0, 0, -L.l / 2), "link2.I": sp.diag(It, It, 0), "world.g": (0, 0, -L.g),
        "link1.r": (0, L.a, 0), "motor.tau": lambda t, phi, w: L.M0 - L.dM * w})
    al, be = eqs.q
    assert (al.name, be.name) == ("base.phi", "hinge_A.phi")
    # the derivation's symbols: alpha(t), beta(t), rates A1, B1, accelerations A2, B2
    to_lagrange = {al: L.al, be: L.be, eqs.u[0]: L.A1, eqs.u[1]: L.B1, eqs.ud[0]: L.A2, eqs.ud[1]: L.B2}
    r = (eqs.M * sp.Matrix(eqs.ud) - eqs.f).xreplace(to_lagrange)
    assert_zero(r - sp.Matrix([L.EQ_ALPHA, L.EQ_BETA]))
    # (4.21) is right: the beta equation is (m l / 2) times it
    assert sp.simplify(r[1] - L.m * L.l / 2 * L.BOOK_4_21) == 0
    # (4.20) is not: it differs exactly by its velocity-product terms, book - true =
    # -(m l / 2) cos(b) (a + (l/2) sin(b)) alpha' beta'; everything else in it agrees
    sb, cb = sp.sin(L.be), sp.cos(L.be)
    wrong = -L.m * L.l / 2 * cb * (L.a + L.l / 2 * sb) * L.A1 * L.B1
    assert sp.simplify(L.BOOK_4_20 - r[0]) != 0
    assert sp.simplify(L.BOOK_4_20 - r[0] - wrong) == 0


# ------------------------------------------------------------------------------ quaternions
def test_heavy_top_in_quaternions_is_eulers_equations():
    """Seed 3.2's top on a ball joint: with unit quaternions the traced equations reduce to
    Euler's equations about the pivot in body axes, ``J w' = (J w) x w + m g l (e3 x k)`` with
    ``k`` the upward vertical in body axes (third row of R(Q))."""
    m, l, I1, I3, g = sp.symbols("m l I1 I3 g", positive=True)
    eqs = mbcomp.equations(load_model("models/textbook/ex3_2_gyro_top.py").build(),
                           params={"top.m": m, "top.r_cm": (0, 0, l), "top.I": sp.diag(I1, I1, I3),
                                   "world.g": (0, 0, -g)})
    w, x, y, z = eqs.q
    assert [s.name for s in eqs.q] == ["ball.Q.w", "ball.Q.x", "ball.Q.y", "ball.Q.z"]
    W = sp.Matrix(eqs.u)
    J = sp.diag(I1 + m * l ** 2, I1 + m * l ** 2, I3)  # inertia about the pivot
    k = sp.Matrix([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x ** 2 + y ** 2)])
    euler = (J * W).cross(W) + (sp.Matrix([0, 0, l])).cross(-m * g * k)
    assert eqs.M == J
    assert_zero(eqs.f - euler)
    # quaternion kinematics dQ/dt = Q * (0, w) / 2
    Qw = sp.Matrix([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]]) * sp.Matrix([0, *W]) / 2
    assert_zero(eqs.qdot - Qw)


# ------------------------------------------------------------------------------ numeric identity
def _random_states(system, rng, n, unit=True):
    for _ in range(n):
        q = rng.normal(size=system.nq)
        yield rng.uniform(0, 3), (system.normalize(q) if unit else q), rng.normal(size=system.nu)


def _lambdified(eqs, *names):
    return {k: sp.lambdify([eqs.t, list(eqs.q), list(eqs.u)], getattr(eqs, k), "numpy", cse=True) for k in names}


@pytest.mark.parametrize("drive, unit", [(None, True), ("0.5*sin(3*t)", False)], ids=["free", "driven-nonunit"])
def test_spherical_model_symbolic_equals_numeric(drive, unit):
    """Slider + revolute + ball joint in 3-D (seed 4.3): quaternion coordinates, gravity, and
    optionally a prescribed rotation (time in the equations). With ``unit_quaternions=False``
    the trace keeps the numeric code's normalization, so it agrees even off the unit sphere."""
    model = EX43.build(drive_rotation=drive)
    system = mbcomp.assemble(model)
    eqs = mbcomp.equations(system, simplify=False, unit_quaternions=unit)
    assert len(eqs.q) == system.nq == len(eqs.u) + 1  # 4 quaternion coordinates, 3 speeds
    assert "ball.Q.w" in [s.name for s in eqs.q]
    assert (eqs.t in eqs.f.free_symbols) == (drive is not None)
    fn = _lambdified(eqs, "M", "f", "qdot")
    rng = np.random.default_rng(7)
    for t, q, u in _random_states(system, rng, 5, unit):
        ev = system.evaluate(t, q, u)
        M, f, qd = (np.array(fn[k](t, q, u), float) for k in ("M", "f", "qdot"))
        scale = max(1.0, np.abs(ev.M).max())
        np.testing.assert_allclose(M, ev.M, rtol=1e-12, atol=1e-12 * scale)
        np.testing.assert_allclose(f.ravel(), ev.f, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(ev.f).max()))
        np.testing.assert_allclose(qd.ravel(), system.q_rate(q, u), rtol=1e-12, atol=1e-12)


def test_slider_crank_symbolic_equals_numeric_with_constraints():
    system = mbcomp.assemble(CRANK.build())
    eqs = mbcomp.equations(system)  # simplified: simplification must keep the values
    # planar loop closed by a 3-D revolute: its out-of-plane rows vanish identically
    assert set(eqs.dropped) == {"rod_joint.z", "rod_joint.tilt_1", "rod_joint.tilt_2"}
    assert eqs.constraint_names == ("rod_joint.x", "rod_joint.y")
    assert eqs.C.shape == (2, 3) and len(eqs.lam) == 2
    rows = [system.constraint_names(all_rows=True).index(n) for n in eqs.constraint_names]
    fn = _lambdified(eqs, "M", "f", "Phi", "C", "cb")
    rng = np.random.default_rng(3)
    for t, q, u in _random_states(system, rng, 6):
        ev = system.evaluate(t, q, u, masked=False)
        got = {k: np.array(fn[k](t, q, u), float) for k in fn}
        np.testing.assert_allclose(got["M"], ev.M, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(got["f"].ravel(), ev.f, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(got["Phi"].ravel(), ev.Phi[rows], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(got["C"], ev.C[rows], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(got["cb"].ravel(), ev.cb[rows], rtol=1e-12, atol=1e-11)
        # the dropped rows are zero numerically too
        dropped = [system.constraint_names(all_rows=True).index(n) for n in eqs.dropped]
        assert np.abs(ev.C[dropped]).max() < 1e-15 and np.abs(ev.cb[dropped]).max() < 1e-15


# ------------------------------------------------------------------------------ errors
def test_untraceable_law_names_its_component():
    with pytest.raises(mbcomp.ModelError) as err:
        mbcomp.equations(EX63.build(tau2=lambda t, phi, w: math.sin(phi)), simplify=False)
    text = str(err.value)
    assert "motor2" in text and "math.sin" in text and "SymbolicScalar" in text


def test_unknown_parameter_is_named():
    with pytest.raises(mbcomp.ModelError) as err:
        mbcomp.equations(EX61.build(), params={"bob.mass": 1, "rodd.r": (0, 1, 0)})
    text = str(err.value)
    assert "bob.mass: no such parameter" in text and "rodd.r: no component 'rodd'" in text
