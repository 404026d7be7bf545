"""Seed Example 6.4: spinning pendulum with constant prescribed spin (models/textbook/ex6_4_spinning_pendulum.py).

Checks: an independent Lagrange derivation in sympy (rotation matrices, rod inertia about its
centre, spin angle Omega t substituted) gives the book's (6.63) with ``I = m l^2/3``; the model's
bar angle follows (6.63) integrated with scipy at tight tolerance; the Jacobi integral
``h = E - Omega H_Z`` (energy in the rotating frame, with ``H_Z`` the angular momentum about the
spin axis computed from the bodies' positions, velocities and orientations) is conserved while
the energy itself is not; the drive torque equals ``dH_Z/dt`` and its power ``tau Omega`` equals
``dE/dt``.

Misprint: (6.57) prints ``T = 1/2 I_Z w^2 + 1/2 (beta'^2 + w^2 sin^2 beta)``; the second term
lacks the factor ``I`` (the bar's inertia about the hinge), as (6.59)-(6.61) and the matrix
form (6.56) show. (6.63) itself is right.
"""
import functools
import types

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import cumulative_simpson, solve_ivp

import mbcomp
from conftest import load_model

MOD = load_model("models/textbook/ex6_4_spinning_pendulum.py")
M, L, OMEGA, M1, I_Z, G = 1.0, 0.6, 6.0, 0.5, 0.02, 9.81
B0, BD0 = 0.2, 0.0
T_END = 5.0

# ------------------------------------------------------------- independent Lagrange derivation
@functools.cache
def derivation():
    """The symbolic derivation (sympy) as a namespace of its names (``S.EQ``, ...), made once on
    first use: not at import, which pytest does in every worker while it collects."""
    t = sp.Symbol("t", real=True)
    m, l, g, Om, IZ = sp.symbols("m l g Omega I_Z", positive=True)
    be = sp.Function("beta")(t)
    B, BD, BDD = sp.symbols("beta beta_d beta_dd")

    def _rz(q):
        return sp.Matrix([[sp.cos(q), -sp.sin(q), 0], [sp.sin(q), sp.cos(q), 0], [0, 0, 1]])

    def _rx(q):
        return sp.Matrix([[1, 0, 0], [0, sp.cos(q), -sp.sin(q)], [0, sp.sin(q), sp.cos(q)]])

    def _omega(R):
        W = sp.simplify(R.T * R.diff(t))
        return sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])  # body components

    R1 = _rz(Om * t)
    R2 = R1 * _rx(be)
    r_G = R2 * sp.Matrix([0, 0, -l / 2])
    v_G = r_G.diff(t)
    w1, w2 = _omega(R1), _omega(R2)
    I_G = sp.diag(m * l ** 2 / 12, m * l ** 2 / 12, 0)
    T_kin = sp.simplify((IZ * w1[2] ** 2 + m * v_G.dot(v_G) + (w2.T * I_G * w2)[0]) / 2)
    V_pot = m * g * r_G[2]
    Lag = T_kin - V_pot

    def _plain(expr):
        return expr.subs({be.diff(t, 2): BDD}).subs({be.diff(t): BD}).subs({be: B})

    EQ = sp.expand(_plain(sp.diff(Lag.diff(be.diff(t)), t) - Lag.diff(be)))
    I_A = m * l ** 2 / 3  # the book's I: bar about hinge A, transverse axis
    BOOK_6_63 = I_A * BDD - I_A * Om ** 2 * sp.sin(B) * sp.cos(B) + m * g * l / 2 * sp.sin(B)
    # angular momentum about Z (world), all bodies, about the origin (A is on the axis)
    H_world = sp.simplify((m * r_G.cross(v_G) + R2 * I_G * w2)[2] + IZ * w1[2])
    _vals = {m: M, l: L, g: G, Om: OMEGA, IZ: I_Z}
    _H = sp.lambdify((B, BD), _plain(H_world).subs(_vals), "numpy")
    _dH = sp.lambdify((B, BD, BDD), _plain(H_world.diff(t)).subs(_vals), "numpy")
    _E = sp.lambdify((B, BD), _plain(T_kin + V_pot).subs(_vals), "numpy")
    return types.SimpleNamespace(**locals())


def eq_6_63(_, y):
    b, bd = y
    I = M * L ** 2 / 3
    return [bd, (I * OMEGA ** 2 * np.sin(b) * np.cos(b) - M * G * L / 2 * np.sin(b)) / I]


def _quat_matrix(q):
    """Rotation matrices (n, 3, 3) from unit quaternions (n, 4), scalar first."""
    w, x, y, z = q.T
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def _body_Hz(res, name, mass, r_cm, I_cm):
    """Angular momentum about the world Z axis through the origin, from the body outputs."""
    comp = lambda v: np.stack([res[f"{name}.{v}.{a}"] for a in "xyz"], -1)  # noqa: E731
    R = _quat_matrix(np.stack([res[f"{name}.Q.{a}"] for a in "wxyz"], -1))
    d = R @ np.asarray(r_cm)
    w = comp("w")
    r_c, v_c = comp("r") + d, comp("v") + np.cross(w, d)
    spin = np.einsum("nij,jk,nlk,nl->ni", R, I_cm, R, w)
    return (mass * np.cross(r_c, v_c) + spin)[:, 2]


@pytest.fixture(scope="module")
def result():
    res = mbcomp.simulate(MOD.build(m=M, l=L, Omega=OMEGA, m1=M1, I_Z=I_Z, beta0=B0, beta_dot0=BD0, g=G),
                          t_end=T_END, rtol=1e-11, atol=1e-12, n_out=1001, method="DOP853")
    assert res.success, res.message
    return res


def test_lagrange_derivation_gives_eq_6_63():
    S = derivation()
    assert sp.simplify(S.EQ - S.BOOK_6_63) == 0
    # the kinetic energy (6.57) with the factor I restored: T = I_Z W^2/2 + I (beta'^2 + W^2 sin^2 beta)/2
    book_T = (S.IZ * S.Om ** 2 + S.I_A * (S.BD ** 2 + S.Om ** 2 * sp.sin(S.B) ** 2)) / 2
    assert sp.simplify(S._plain(S.T_kin) - book_T) == 0


def test_summary_one_dof_spin_prescribed():
    text = mbcomp.assemble(MOD.build()).summary()
    assert "degrees of freedom: 1 " in text  # book: 6*2 - (5 + 5) - 1 = 1
    assert "prescribed (eliminated, rheonomic): spin by spin_drive" in text


def test_spin_is_the_prescribed_constant_rate(result):
    np.testing.assert_allclose(result["spin_angle"], OMEGA * result.time, rtol=0, atol=1e-13)
    np.testing.assert_allclose(result["link1.w.z"], OMEGA, rtol=0, atol=1e-13)


def test_beta_matches_eq_6_63(result):
    sol = solve_ivp(eq_6_63, (0.0, T_END), [B0, BD0], method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=result.time)
    assert sol.success
    b, bd = sol.y
    # Omega^2 = 36 > 3g/(2l) = 24.5: the bar leaves the unstable hanging position and swings
    # about cos(beta*) = 3g/(2 l Omega^2) (beta* = 0.82 rad) with a large amplitude
    assert b.max() > 1.1 and b.min() < 0.25
    np.testing.assert_allclose(result["beta"], b, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["beta_dot"], bd, rtol=0, atol=1e-7)


def test_model_acceleration_satisfies_eq_6_63(result):
    S = derivation()
    f = sp.lambdify((S.B, S.BD, S.BDD), S.BOOK_6_63.subs(S._vals), "numpy")
    np.testing.assert_allclose(f(result["beta"], result["beta_dot"], result["hinge_A.w.der"]), 0.0, atol=1e-10)


def test_jacobi_integral_is_conserved_energy_is_not(result):
    S = derivation()
    E = result["energy.total"]
    np.testing.assert_allclose(E, S._E(result["beta"], result["beta_dot"]), rtol=0, atol=1e-12)
    Hz = (_body_Hz(result, "bar", M, (0, 0, -L / 2), np.diag([M * L ** 2 / 12] * 2 + [0.0]))
          + _body_Hz(result, "link1", M1, (0, 0, 0), np.diag([I_Z / 2, I_Z / 2, I_Z])))
    np.testing.assert_allclose(Hz, S._H(result["beta"], result["beta_dot"]), rtol=0, atol=1e-12)
    h = E - OMEGA * Hz
    assert np.ptp(E) > 1.0  # the drive pumps energy in and out
    assert np.abs(h - h[0]).max() < 1e-9 * np.ptp(E)
    # the book's form: I beta'^2/2 - I Omega^2 sin^2(beta)/2 - m g l/2 cos(beta) + const
    I = M * L ** 2 / 3
    b, bd = result["beta"], result["beta_dot"]
    h_book = I * bd ** 2 / 2 - I * OMEGA ** 2 * np.sin(b) ** 2 / 2 - M * G * L / 2 * np.cos(b)
    np.testing.assert_allclose(h - h_book, -I_Z * OMEGA ** 2 / 2, rtol=0, atol=1e-9)


def test_drive_torque_is_rate_of_angular_momentum_and_its_power_is_dE_dt(result):
    S = derivation()
    tau = result["drive_torque"]
    dH = S._dH(result["beta"], result["beta_dot"], result["hinge_A.w.der"])
    b, bd = result["beta"], result["beta_dot"]
    np.testing.assert_allclose(dH, 2 * M * L ** 2 / 3 * OMEGA * np.sin(b) * np.cos(b) * bd, rtol=0, atol=1e-10)
    assert np.abs(tau).max() > 1.0
    np.testing.assert_allclose(tau, dH, rtol=0, atol=1e-9)
    E = result["energy.total"]
    work = cumulative_simpson(tau * OMEGA, x=result.time, initial=0.0)
    np.testing.assert_allclose(E - E[0], work, rtol=0, atol=1e-6 * np.ptp(E))
