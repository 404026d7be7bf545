"""Properties of mbcomp.rotations and mbcomp.relative_motion (seed book ch. 1, numeric and sympy).

* elementary rotations are proper orthogonal, fix their own axis and agree with the Rodrigues
  formula of mbcomp.kinematics (so they follow mbcomp's x_ref = R x_moving convention);
* Euler 3-1-3 and 3-2-1: matrix <-> angles <-> quaternion round trips for random angles and at
  and near gimbal lock, and agreement with scipy's intrinsic "ZXZ" / "ZYX" sequences;
* the Euler-rate matrices E (omega = E rates) are *derived* here from the definition of the
  angular velocity, tilde(omega_body) = R^T dR/dt and tilde(omega_space) = dR/dt R^T, by sympy
  differentiation, and compared with the book's eqs. 1.38 and 1.40 (see the misprint notes);
* homogeneous transforms, the screw of a finite motion, and the moving-frame velocity and
  acceleration formulas against the second time derivative of an explicit trajectory.
"""
import functools
import math

import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

from mbcomp.kinematics import matrix_to_quat, quat_to_matrix, rot_axis
from mbcomp.relative_motion import (compose, homogeneous, homogeneous_inverse, point_acceleration,
                                    point_velocity, screw_motion, transform_points)
from mbcomp.rotations import (C1, C2, C3, euler_rate_matrix, euler_rates, euler_to_matrix,
                              euler_to_quat, matrix_to_euler, quat_to_euler, tilde, vee)

RNG = np.random.default_rng(20240601)
SEQS = ["313", "321"]
SCIPY_SEQ = {"313": "ZXZ", "321": "ZYX"}  # uppercase = intrinsic (rotating axes) in scipy
t = sp.symbols("t", real=True)


def random_angles(seq, n, rng=RNG):
    """Random angles inside the canonical ranges returned by matrix_to_euler."""
    a1 = rng.uniform(-np.pi, np.pi, n)
    a3 = rng.uniform(-np.pi, np.pi, n)
    a2 = rng.uniform(0.0, np.pi, n) if seq == "313" else rng.uniform(-np.pi / 2, np.pi / 2, n)
    return np.column_stack((a1, a2, a3))


def is_zero(expr):
    return sp.simplify(expr) == sp.zeros(*expr.shape) if isinstance(expr, sp.MatrixBase) else sp.simplify(expr) == 0


def trig_canon(expr, angles):
    """Canonical form of a polynomial in sin and cos of ``angles`` (other symbols are
    coefficients): sin, cos become polynomial variables and the result is reduced modulo
    sin^2 + cos^2 - 1 (a Groebner basis, so the remainder is unique: zero iff the identity
    holds). Much faster than ``simplify`` and exact."""
    s = sp.symbols(f"s0:{len(angles)}")
    c = sp.symbols(f"c0:{len(angles)}")
    rep = {}
    for a, si, ci in zip(angles, s, c):
        rep[sp.sin(a)], rep[sp.cos(a)] = si, ci
    G = [si**2 + ci**2 - 1 for si, ci in zip(s, c)]
    back = {v: k for k, v in rep.items()}

    def one(e):
        e = sp.expand(sp.expand_trig(e).xreplace(rep))
        assert not e.has(sp.sin, sp.cos), f"not a polynomial in sin/cos of {angles}: {e}"
        return e if e == 0 else sp.reduced(e, G, *s, *c)[1].xreplace(back)

    return expr.applyfunc(one) if isinstance(expr, sp.MatrixBase) else one(expr)


def trig_zero(expr, angles):
    out = trig_canon(sp.Matrix(expr), angles)
    return out == sp.zeros(*out.shape)


# ================================================================================ elementary
@pytest.mark.parametrize("k, Ck", [(0, C1), (1, C2), (2, C3)])
def test_elementary_rotation_is_rodrigues_about_its_axis(k, Ck):
    for a in RNG.uniform(-7, 7, 5):
        R = Ck(a)
        e = np.eye(3)[k]
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
        assert abs(np.linalg.det(R) - 1.0) < 1e-14
        np.testing.assert_allclose(R @ e, e, atol=1e-15)
        np.testing.assert_allclose(R, rot_axis(e, a), atol=1e-14)  # x_ref = R x_moving
    # symbolic path: same matrix, exact orthogonality
    x = sp.symbols("x", real=True)
    S = Ck(x)
    assert isinstance(S, sp.MatrixBase)
    assert trig_zero(S * S.T - sp.eye(3), [x])
    np.testing.assert_allclose(np.array(S.subs(x, 0.37), dtype=float), Ck(0.37), atol=1e-15)


def test_tilde_and_vee():
    a, b = RNG.normal(size=(2, 3))
    np.testing.assert_allclose(tilde(a) @ b, np.cross(a, b), atol=1e-14)
    np.testing.assert_allclose(vee(tilde(a)), a, atol=1e-15)
    s = sp.Matrix(sp.symbols("a1:4")), sp.Matrix(sp.symbols("b1:4"))
    assert sp.expand(tilde(s[0]) * s[1] - s[0].cross(s[1])) == sp.zeros(3, 1)
    assert vee(tilde(s[0])) == s[0]


# ================================================================================ Euler angles
@pytest.mark.parametrize("seq", SEQS)
def test_euler_matrix_is_the_product_of_elementary_rotations_and_matches_scipy(seq):
    for ang in random_angles(seq, 20):
        R = euler_to_matrix(seq, ang)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
        assert abs(np.linalg.det(R) - 1.0) < 1e-13
        np.testing.assert_allclose(R, Rotation.from_euler(SCIPY_SEQ[seq], ang).as_matrix(), atol=1e-14)
    a = sp.symbols("a b c", real=True)
    expected = C3(a[0]) * C1(a[1]) * C3(a[2]) if seq == "313" else C3(a[0]) * C2(a[1]) * C1(a[2])
    assert euler_to_matrix(seq, a) == expected


@pytest.mark.parametrize("seq", SEQS)
def test_matrix_euler_quaternion_round_trips(seq):
    for ang in random_angles(seq, 200):
        R = euler_to_matrix(seq, ang)
        back = matrix_to_euler(seq, R)
        np.testing.assert_allclose(back, ang, atol=1e-9)  # unique inside the canonical ranges
        np.testing.assert_allclose(euler_to_matrix(seq, back), R, atol=2e-15)
        Q = euler_to_quat(seq, ang)
        assert abs(np.linalg.norm(Q) - 1.0) < 1e-14 and Q[0] >= 0
        np.testing.assert_allclose(Q, matrix_to_quat(R), atol=1e-14)
        np.testing.assert_allclose(quat_to_matrix(Q), R, atol=1e-14)
        np.testing.assert_allclose(quat_to_euler(seq, Q), ang, atol=1e-9)
    # a random quaternion -> angles -> quaternion (same rotation: equal up to sign)
    for _ in range(50):
        Q = RNG.normal(size=4)
        Q /= np.linalg.norm(Q)
        Q2 = euler_to_quat(seq, quat_to_euler(seq, Q))
        assert min(np.linalg.norm(Q2 - Q), np.linalg.norm(Q2 + Q)) < 1e-14


@pytest.mark.parametrize("seq", SEQS)
def test_gimbal_lock_matrix_to_euler_reproduces_the_matrix(seq):
    """At gimbal lock only the sum or difference of the outer angles is defined; the returned
    triple must reproduce the matrix to round-off, also just next to the singularity."""
    locks = [0.0, np.pi] if seq == "313" else [np.pi / 2, -np.pi / 2]
    for lock in locks:
        for eps in (0.0, 1e-15, 1e-12, 1e-9, 1e-6):
            mid = lock + eps if (lock == 0.0 or lock == -np.pi / 2) else lock - eps
            for a1, a3 in RNG.uniform(-np.pi, np.pi, (5, 2)):
                R = euler_to_matrix(seq, (a1, mid, a3))
                back = matrix_to_euler(seq, R)
                np.testing.assert_allclose(euler_to_matrix(seq, back), R, atol=4e-15)
                if eps == 0.0:
                    assert back[2] == 0.0  # documented: third angle 0 at exact lock
    np.testing.assert_allclose(matrix_to_euler("313", C3(0.7) @ C1(np.pi)), [0.7, np.pi, 0.0], atol=1e-15)
    np.testing.assert_allclose(matrix_to_euler("321", C3(0.7) @ C2(np.pi / 2)), [0.7, np.pi / 2, 0.0],
                               atol=1e-8)


@pytest.mark.parametrize("seq", SEQS)
def test_symbolic_conversions(seq):
    """Exact sympy numbers in, sympy out; symbolic quaternion -> matrix via Q (0, e) Q*."""
    ang = [sp.pi / 3, sp.pi / 5, -sp.pi / 7]
    R = euler_to_matrix(seq, ang)
    back = matrix_to_euler(seq, R)
    assert isinstance(back, sp.MatrixBase)
    np.testing.assert_allclose(np.array(back.evalf(), dtype=float).ravel(), [float(a) for a in ang], atol=1e-14)
    Q = euler_to_quat(seq, ang)
    Qn = euler_to_quat(seq, [float(a) for a in ang])
    Qe = np.array(Q.evalf(), dtype=float).ravel()
    assert min(np.linalg.norm(Qe - Qn), np.linalg.norm(Qe + Qn)) < 1e-14
    np.testing.assert_allclose(np.array(quat_to_euler(seq, Q).evalf(), dtype=float).ravel(),
                               [float(a) for a in ang], atol=1e-14)
    # fully symbolic: R(Q(angles)) == R(angles) exactly
    a = sp.symbols("a b c", real=True)
    h = sp.symbols("h1:4", real=True)  # half angles: quaternion entries are trig of a / 2
    Qs = euler_to_quat(seq, a).subs(dict(zip(a, [2 * x for x in h])))
    w, x, y, z = Qs
    RQ = sp.Matrix([[1 - 2 * (y**2 + z**2), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                    [2 * (x * y + w * z), 1 - 2 * (x**2 + z**2), 2 * (y * z - w * x)],
                    [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x**2 + y**2)]])
    assert trig_zero(RQ - euler_to_matrix(seq, [2 * x for x in h]), h)


def test_unknown_sequence_and_frame_are_rejected():
    with pytest.raises(ValueError, match="unknown Euler sequence"):
        euler_to_matrix("123", (0, 0, 0))
    with pytest.raises(ValueError, match="frame must be"):
        euler_rate_matrix("313", (0, 1, 0), frame="world")


# ================================================================================ rates
@functools.lru_cache(maxsize=None)
def _derived_rate_matrices(seq):
    """E_body and E_space derived from the definition of angular velocity:
    tilde(omega_body) = R^T dR/dt, tilde(omega_space) = dR/dt R^T, with R(t) the product of the
    elementary rotations of the angles a_k(t); omega is linear in the rates a_k', and
    E[:, k] = d omega / d a_k'. Returned in the plain angle symbols p1, p2, p3."""
    f = [sp.Function(n, real=True)(t) for n in ("a1", "a2", "a3")]
    plain = sp.symbols("p1:4", real=True)
    rates = sp.symbols("r1:4", real=True)
    R = euler_to_matrix(seq, f)
    Rdot = R.diff(t)

    def plainify(M):
        return M.xreplace({fi.diff(t): ri for fi, ri in zip(f, rates)}).xreplace(dict(zip(f, plain)))

    W_body = trig_canon(plainify(R.T * Rdot), plain)
    W_space = trig_canon(plainify(Rdot * R.T), plain)
    assert W_body + W_body.T == sp.zeros(3, 3) and W_space + W_space.T == sp.zeros(3, 3)  # R orthogonal
    w_body, w_space = vee(W_body), vee(W_space)
    E_body = w_body.jacobian(rates)
    E_space = w_space.jacobian(rates)
    assert sp.expand(E_body * sp.Matrix(rates) - w_body) == sp.zeros(3, 1)  # omega linear in rates
    return E_body, E_space, plain


@pytest.mark.parametrize("seq", SEQS)
def test_rate_matrices_are_derived_from_the_definition_of_angular_velocity(seq):
    E_body, E_space, ang = _derived_rate_matrices(seq)
    assert trig_zero(euler_rate_matrix(seq, ang, "body") - E_body, ang)
    assert trig_zero(euler_rate_matrix(seq, ang, "space") - E_space, ang)
    assert trig_zero(euler_to_matrix(seq, ang) * E_body - E_space, ang)
    # numeric path = symbolic path
    for a in random_angles(seq, 5):
        for frame, E in (("body", E_body), ("space", E_space)):
            En = np.array(E.subs(dict(zip(ang, a))), dtype=float)
            np.testing.assert_allclose(euler_rate_matrix(seq, a, frame), En, atol=1e-14)


@pytest.mark.parametrize("seq", SEQS)
def test_rate_matrices_against_finite_differences(seq):
    """Independent of sympy: omega from central differences of R(t) along angles + rates t."""
    h = 1e-6
    for a, rates in zip(random_angles(seq, 5), RNG.normal(size=(5, 3))):
        R = euler_to_matrix(seq, a)
        Rdot = (euler_to_matrix(seq, a + h * rates) - euler_to_matrix(seq, a - h * rates)) / (2 * h)
        np.testing.assert_allclose(euler_rate_matrix(seq, a, "body") @ rates, vee(R.T @ Rdot), atol=1e-8)
        np.testing.assert_allclose(euler_rate_matrix(seq, a, "space") @ rates, vee(Rdot @ R.T), atol=1e-8)


def test_book_equations_1_38_and_1_40_as_printed():
    """The seed book's eqs. 1.38 and 1.40 (body components) against the derivation above.

    Misprints (seed book p. 23):
    * eq. 1.38 (3-1-3, rates (phi', theta', psi')) prints the (2, 2) entry as -sin(phi); the
      derivation gives -sin(psi): the line of nodes e_x' resolved in the body frame is
      C3(psi)^T e_1 = (cos psi, -sin psi, 0), and the precession angle phi cannot enter the
      body components of omega at all (rotating the whole motion about the fixed Z axis does
      not change them). All other entries of 1.38 are right.
    * eq. 1.40 (3-2-1) is right as printed once one notes that its rate vector is ordered
      (phi', theta', psi') = (roll, pitch, yaw), the reverse of the rotation order
      yaw-pitch-roll that mbcomp uses for the angles and rates. Its copy in Example 1.4,
      eq. 1.44, is misprinted: its (2, 3) entry reads cos(theta) sin(theta) instead of
      cos(theta) sin(phi) (see tests/textbook/test_textbook_ch1.py). In eqs. 1.37 and 1.39 the
      intermediate axes e_x' (line of nodes) and e_y' carry primes that the text extraction of
      the seed drops; they are not the body axes e_x, e_y.
    """
    E313, _, (phi, theta, psi) = _derived_rate_matrices("313")
    s, c = sp.sin, sp.cos
    book_1_38 = sp.Matrix([[s(theta) * s(psi), c(psi), 0],
                           [s(theta) * c(psi), -s(phi), 0],
                           [c(theta), 0, 1]])
    diff = trig_canon(book_1_38 - E313, (phi, theta, psi))
    assert diff == sp.Matrix([[0, 0, 0], [0, s(psi) - s(phi), 0], [0, 0, 0]])  # only entry (2, 2)
    corrected = book_1_38.copy()
    corrected[1, 1] = -s(psi)
    assert trig_zero(corrected - E313, (phi, theta, psi))

    E321, _, (psi, theta, phi) = _derived_rate_matrices("321")  # angles in rotation order
    book_1_40 = sp.Matrix([[1, 0, -s(theta)],
                           [0, c(phi), c(theta) * s(phi)],
                           [0, -s(phi), c(theta) * c(phi)]])  # columns: roll, pitch, yaw rates
    assert trig_zero(book_1_40 - E321[:, [2, 1, 0]], (psi, theta, phi))


@pytest.mark.parametrize("frame", ["body", "space"])
@pytest.mark.parametrize("seq", SEQS)
def test_rates_from_angular_velocity_invert_E(seq, frame):
    for a, rates in zip(random_angles(seq, 20), RNG.normal(size=(20, 3))):
        w = euler_rate_matrix(seq, a, frame) @ rates
        np.testing.assert_allclose(euler_rates(seq, a, w, frame), rates, atol=1e-9)
    ang = sp.symbols("p1:4", real=True)
    r = sp.Matrix(sp.symbols("r1:4", real=True))
    back = euler_rates(seq, ang, euler_rate_matrix(seq, ang, frame) * r, frame)
    d = sp.sin(ang[1]) if seq == "313" else sp.cos(ang[1])
    assert trig_zero(sp.expand(d * (back - r)), ang)  # cleared of the divisor sin or cos(theta)


@pytest.mark.parametrize("seq, lock", [("313", 0.0), ("313", np.pi), ("321", np.pi / 2), ("321", -np.pi / 2)])
def test_rates_at_gimbal_lock_raise_a_named_error(seq, lock):
    with pytest.raises(ValueError, match="gimbal lock") as err:
        euler_rates(seq, (0.3, lock, -0.2), [1.0, 2.0, 3.0])
    assert ("sin(theta) = 0" if seq == "313" else "cos(theta) = 0") in str(err.value)
    sym_lock = {0.0: 0, np.pi: sp.pi, np.pi / 2: sp.pi / 2, -np.pi / 2: -sp.pi / 2}[lock]
    with pytest.raises(ValueError, match="gimbal lock"):
        euler_rates(seq, (sp.Symbol("a"), sym_lock, sp.Symbol("b")), sp.symbols("w1:4"))
    # next to the lock the rates are large but exact
    a = np.array([0.3, lock + 1e-6 if lock <= 0 else lock - 1e-6, -0.2])
    rates = np.array([1.0, 2.0, 3.0])
    w = euler_rate_matrix(seq, a) @ rates
    np.testing.assert_allclose(euler_rates(seq, a, w), rates, rtol=1e-6)


# ================================================================================ transforms
def test_homogeneous_transforms_compose_invert_and_apply():
    R1, R2 = euler_to_matrix("313", RNG.normal(size=3)), euler_to_matrix("321", RNG.normal(size=3))
    r1, r2 = RNG.normal(size=(2, 3))
    T1, T2 = homogeneous(R1, r1), homogeneous(R2, r2)
    np.testing.assert_allclose(homogeneous_inverse(T1) @ T1, np.eye(4), atol=1e-14)
    np.testing.assert_allclose(homogeneous_inverse(T1), np.linalg.inv(T1), atol=1e-13)
    T12 = compose(T1, T2)
    np.testing.assert_allclose(T12, homogeneous(R1 @ R2, R1 @ r2 + r1), atol=1e-14)
    pts = RNG.normal(size=(6, 3))
    np.testing.assert_allclose(transform_points(T12, pts), transform_points(T1, transform_points(T2, pts)),
                               atol=1e-14)
    np.testing.assert_allclose(transform_points(T1, pts[0]), R1 @ pts[0] + r1, atol=1e-14)
    # distances are preserved (rigid motion)
    q = transform_points(T12, pts)
    np.testing.assert_allclose(np.linalg.norm(q[1:] - q[0], axis=1), np.linalg.norm(pts[1:] - pts[0], axis=1),
                               atol=1e-13)
    # symbolic path
    a, x, y = sp.symbols("a x y", real=True)
    T = homogeneous(C3(a), [x, y, 0])
    assert is_zero(homogeneous_inverse(T) * T - sp.eye(4))
    assert is_zero(transform_points(T, [1, 0, 0]) - sp.Matrix([sp.cos(a) + x, sp.sin(a) + y, 0]))


def test_screw_motion_reproduces_the_motion():
    cases = [(euler_to_matrix("313", RNG.normal(size=3)), RNG.normal(size=3)) for _ in range(10)]
    cases += [(rot_axis([1, 2, 3], np.pi), np.array([0.3, -0.2, 0.5])),          # half turn
              (rot_axis([1, -1, 0], np.pi - 1e-9), np.array([1.0, 0.0, 0.0])),   # nearly a half turn
              (rot_axis([0, 1, 0], 1e-3), np.array([0.0, 2.0, 1.0])),            # small rotation
              (np.eye(3), np.array([0.0, 0.0, 2.0]))]                            # translation
    for R, r in cases:
        s = screw_motion(homogeneous(R, r))
        assert abs(np.linalg.norm(s.axis) - 1.0) < 1e-14 and 0.0 <= s.angle <= np.pi
        np.testing.assert_allclose(rot_axis(s.axis, s.angle) if s.angle else np.eye(3), R, atol=1e-12)
        for x in RNG.normal(size=(3, 3)):
            np.testing.assert_allclose(R @ (x - s.point) + s.point + s.translation * s.axis, R @ x + r, atol=1e-9)
        assert abs(s.point @ s.axis) < 1e-9  # closest point of the axis to the origin


# ================================================================================ moving frame
@pytest.mark.parametrize("seq", SEQS)
def test_moving_frame_velocity_and_acceleration_against_differentiation(seq):
    """P(t) = r_O(t) + R(t) rho(t) with the origin r_O, the Euler angles of R and the frame
    coordinates rho of P arbitrary functions of time: the term-by-term formulas (omega from
    the rate matrix, alpha its derivative) equal the first and second derivatives of P
    (identity evaluated at random values of the functions and their derivatives)."""
    fs = [sp.Function(f"f{i}")(t) for i in range(9)]
    rO, rho, ang = sp.Matrix(fs[0:3]), sp.Matrix(fs[3:6]), fs[6:9]
    R = euler_to_matrix(seq, ang)
    P = rO + R * rho
    rates = sp.Matrix([a.diff(t) for a in ang])
    w = R * euler_rate_matrix(seq, ang, "body") * rates  # world components
    vel = point_velocity(rO.diff(t), w, R * rho, R * rho.diff(t))
    acc = point_acceleration(rO.diff(t, 2), w, w.diff(t), R * rho, R * rho.diff(t), R * rho.diff(t, 2))
    # every vector resolved in the moving frame; alpha = derivative of omega's body components
    # (valid in the frame that turns with omega)
    wb = euler_rate_matrix(seq, ang, "body") * rates
    accb = point_acceleration(R.T * rO.diff(t, 2), wb, wb.diff(t), rho, rho.diff(t), rho.diff(t, 2))
    x = sp.symbols("x0:27")
    rep = {}
    for i, f in enumerate(fs):  # xreplace matches whole derivative nodes first
        rep.update({f.diff(t, 2): x[3 * i + 2], f.diff(t): x[3 * i + 1], f: x[3 * i]})
    exprs = [vel.total, P.diff(t), acc.total, P.diff(t, 2), R * accb.total, acc.coriolis, acc.euler]
    fn = sp.lambdify(x, [list(e.xreplace(rep)) for e in exprs], "math")
    for vals in RNG.normal(size=(5, 27)):
        v, dP, a, ddP, ab, cor, eul = (np.array(e) for e in fn(*vals))
        np.testing.assert_allclose(v, dP, atol=1e-13)
        np.testing.assert_allclose(a, ddP, atol=1e-12)
        np.testing.assert_allclose(ab, ddP, atol=1e-12)
        assert np.linalg.norm(cor) > 1e-3 and np.linalg.norm(eul) > 1e-3  # all terms at work


def test_moving_frame_terms_numeric_uniform_rotation():
    """A point sliding outward at speed u along a spoke of a disk turning at W about z:
    centripetal -W^2 r e_r, Coriolis 2 W u e_theta, Euler 0; numeric = symbolic path."""
    W, u, r0 = 3.0, 0.5, 0.2
    acc = point_acceleration([0, 0, 0], [0, 0, W], [0, 0, 0], [r0, 0, 0], [u, 0, 0])
    np.testing.assert_allclose(acc.centripetal, [-W**2 * r0, 0, 0])
    np.testing.assert_allclose(acc.coriolis, [0, 2 * W * u, 0])
    np.testing.assert_allclose(acc.euler, 0.0)
    vel = point_velocity([1.0, 0, 0], [0, 0, W], [r0, 0, 0], [u, 0, 0])
    np.testing.assert_allclose(vel.total, [1.0 + u, W * r0, 0])
    np.testing.assert_allclose(vel.transport, [1.0, W * r0, 0])
    Ws = sp.Rational(3)
    accs = point_acceleration([0, 0, 0], [0, 0, Ws], [0, 0, 0], [sp.Rational(1, 5), 0, 0], [sp.Rational(1, 2), 0, 0])
    np.testing.assert_allclose(np.array(accs.total, dtype=float).ravel(), acc.total, atol=1e-15)
    assert math.isclose(float(accs.total[0]), -1.8)
