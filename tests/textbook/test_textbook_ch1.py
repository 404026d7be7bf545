"""Seed book, chapter 1 (kinematics): Examples 1.1-1.4 and the coordinate transformations of
sections 1.6-1.8, reproduced symbolically with mbcomp.rotations and mbcomp.relative_motion.

Each example is computed twice: with the book's method (angular velocity, moving-frame terms)
through the mbcomp modules, and independently by writing the position vector in the inertial
frame as a product of elementary rotations and differentiating it with sympy. Both are
compared with the book's printed answers where these are right; where the print is wrong
the test says what is wrong and checks the corrected result.

Findings (details at each test):
* Example 1.1 (jet plane): book right; its omega = phi' e_y + psi' e_z holds at the wings-level
  instant if psi is the yaw about the vertical (in general the body components are
  (-psi' sin phi, phi', psi' cos phi)).
* Example 1.2 (satellite panel): book's eq. 1.21 right; the exercise it leaves (components in
  [e_r, e_theta, e_2]) is solved here.
* Example 1.3 (ventilator): final angular velocity right; an intermediate line carries a
  spurious factor Omega, the rotor transformation prints alpha*t for Omega*t; the velocity of G
  (left as omega~ [0 L mu]^T) is expanded here.
* Example 1.4 (submarine): eq. 1.45-1.46 right (and exact, no small-angle neglect needed);
  eq. 1.44 misprints an entry of 1.40; theta(t) violates theta(0) = 0; eq. 1.47 has the wrong
  sign of the e_y component and, through theta(t), the wrong argument of the cosine.
"""
import sympy as sp

from mbcomp.relative_motion import compose, homogeneous, point_acceleration, point_velocity
from mbcomp.rotations import C1, C2, C3, euler_rate_matrix, euler_to_matrix, tilde, vee

t = sp.symbols("t", real=True)
s_, c_ = sp.sin, sp.cos


def _trig_canon(M):
    """Canonical polynomial form of a matrix built from sin and cos: functions of time and
    their derivatives become plain symbols, every sin(x), cos(x) (after expand_trig) a
    polynomial variable, and each entry is reduced modulo sin(x)^2 + cos(x)^2 - 1."""
    M = M.applyfunc(sp.expand_trig)
    undef = sorted(M.atoms(sp.Derivative), key=lambda d: -d.derivative_count) + list(
        M.atoms(sp.core.function.AppliedUndef))
    M = M.xreplace({f: sp.Dummy() for f in undef})
    rep, gens, G = {}, [], []
    for x in {a.args[0] for a in M.atoms(sp.sin, sp.cos)}:
        sx, cx = sp.Dummy(), sp.Dummy()
        rep[sp.sin(x)], rep[sp.cos(x)] = sx, cx
        gens += [sx, cx]
        G.append(sx**2 + cx**2 - 1)

    def one(e):
        e = sp.expand(e.xreplace(rep))
        return e if e == 0 or not G else sp.reduced(e, G, *gens)[1]

    return M.applyfunc(one)


def zero(M):
    """Exact identity test: the expression or matrix vanishes identically (a canonical
    trigonometric polynomial form first, ``simplify`` only when that is not conclusive)."""
    M = M if isinstance(M, sp.MatrixBase) else sp.Matrix([M])
    Z = sp.zeros(*M.shape)
    return _trig_canon(M) == Z or sp.simplify(M) == Z


def angular_velocity_body(R):
    """Body components of the angular velocity by definition, tilde(omega) = R^T dR/dt."""
    return vee(R.T * R.diff(t))


def velocity_body(R, r_body):
    """Independent derivation: differentiate the inertial position R r_body of a body-fixed
    point and resolve the result in the body frame."""
    return R.T * (R * sp.Matrix(r_body)).diff(t)


# ==================================================================== sections 1.6 and 1.8
def test_book_coordinate_transformations_are_the_elementary_rotations():
    """Eqs. 1.29-1.31 (precession-nutation-spin), 1.33-1.35 (yaw-pitch-roll) and 1.55-1.57
    (finite rotations) as printed, against C1, C2, C3 (rotations about x, y, z mapping
    rotated-frame components to reference components, the same sense as the book's C)."""
    a = sp.symbols("a", real=True)
    about_z = sp.Matrix([[c_(a), -s_(a), 0], [s_(a), c_(a), 0], [0, 0, 1]])   # 1.29, 1.31, 1.33, 1.55
    about_x = sp.Matrix([[1, 0, 0], [0, c_(a), -s_(a)], [0, s_(a), c_(a)]])   # 1.30, 1.35, 1.57
    about_y = sp.Matrix([[c_(a), 0, s_(a)], [0, 1, 0], [-s_(a), 0, c_(a)]])   # 1.34, 1.56
    assert C3(a) == about_z and C1(a) == about_x and C2(a) == about_y
    phi, theta, psi = sp.symbols("phi theta psi", real=True)
    book_C1, book_C2, book_C3 = about_z.subs(a, phi), about_x.subs(a, theta), about_z.subs(a, psi)
    assert euler_to_matrix("313", (phi, theta, psi)) == book_C1 * book_C2 * book_C3           # eq. 1.32
    R_psi, R_theta, R_phi = about_z.subs(a, psi), about_y.subs(a, theta), about_x.subs(a, phi)
    assert euler_to_matrix("321", (psi, theta, phi)) == R_psi * R_theta * R_phi              # eq. 1.36


def test_infinitesimal_rotation_eq_1_60():
    """Eqs. 1.58-1.60: T1 T2 T3 over dt with phi = w_z dt, theta = w_y dt, psi = w_x dt gives
    r(t + dt) = (I + w~ dt) r(t) to first order, in any order of the factors."""
    w = sp.symbols("w_x w_y w_z", real=True)
    dt = sp.symbols("dt", positive=True)
    for T in (C3(w[2] * dt) * C2(w[1] * dt) * C1(w[0] * dt), C1(w[0] * dt) * C3(w[2] * dt) * C2(w[1] * dt)):
        assert T.diff(dt).subs(dt, 0) == tilde(w)


def test_general_finite_motion_eq_1_65():
    """Section 1.8.2: T = [[A, u], [0, 1]] with T = T1 T2 (translation after rotation)."""
    th, ux, uy, uz, px, py, pz = sp.symbols("theta u_x u_y u_z rho_x rho_y rho_z", real=True)
    A = C3(th)  # eq. 1.64: rotation about z
    T = homogeneous(A, [ux, uy, uz])
    assert T == compose(homogeneous(r=[ux, uy, uz]), homogeneous(A))
    r = T * sp.Matrix([px, py, pz, 1])
    assert zero(r[:3, 0] - (sp.Matrix([ux, uy, uz]) + A * sp.Matrix([px, py, pz])))       # eq. 1.64


# ==================================================================== Example 1.1
def test_example_1_1_jet_plane():
    """Roll rate phi' about the longitudinal body axis e_y, yaw rate psi' about e_z; C at
    (b, a, 0) in body axes. Book: omega~ as printed and v_C(rel) = [-a psi', b psi', -b phi']^T."""
    a, b = sp.symbols("a b", real=True)
    phid, psid = sp.symbols("phidot psidot", real=True)
    omega = [0, phid, psid]
    book_omega_tilde = sp.Matrix([[0, -psid, phid], [psid, 0, 0], [-phid, 0, 0]])
    assert tilde(omega) == book_omega_tilde
    v = point_velocity([0, 0, 0], omega, [b, a, 0]).total
    book = sp.Matrix([-a * psid, b * psid, -b * phid])
    assert zero(v - book)

    # independent derivation: yaw psi(t) about the vertical, then roll phi(t) about the body's
    # longitudinal axis y: R = C3(psi) C2(phi). The body components of omega are
    # (-psi' sin phi, phi', psi' cos phi); the book's omega = phi' e_y + psi' e_z is their value
    # at the wings-level instant phi = 0 (or exact if psi' is a yaw rate about body z).
    phi, psi = sp.Function("phi", real=True)(t), sp.Function("psi", real=True)(t)
    R = C3(psi) * C2(phi)
    w_body = angular_velocity_body(R)
    assert zero(w_body - sp.Matrix([-psi.diff(t) * s_(phi), phi.diff(t), psi.diff(t) * c_(phi)]))
    assert zero(w_body - euler_rate_matrix("321", (psi, phi, 0)) * sp.Matrix([psi.diff(t), 0, 0])
                - sp.Matrix([0, phi.diff(t), 0]))
    v_direct = velocity_body(R, [b, a, 0])
    at_level = {phi.diff(t): phid, psi.diff(t): psid}
    assert zero(v_direct.subs(at_level).subs(phi, 0) - book)
    assert zero(v_direct - point_velocity([0, 0, 0], w_body, [b, a, 0]).total)


# ==================================================================== Example 1.2
def test_example_1_2_satellite_panel_acceleration():
    """Satellite spinning steadily at Omega about e_3 (inertially fixed); the panel arm hinged
    at R = b e_1 turns about e_2 at a constant rate theta'; P slides out along e_r at
    s' = alpha (s'' = 0), at distance s(t) + c from the hinge.

    The book's eq. 1.21 (terms of eq. 1.20 in [e1 e2 e3] components) is right. Written out, in
    [e1, e2, e3] with rho = s + c:
        a_P = [-b W^2 - (W^2 + theta'^2) rho sin th + 2 alpha theta' cos th,
               2 W (alpha sin th + rho theta' cos th),
               -theta'^2 rho cos th - 2 alpha theta' sin th]
    and, the exercise the book leaves to the reader, in [e_r, e_theta, e_2]:
        a_P = [-b W^2 sin th - W^2 rho sin^2 th - rho theta'^2,
               -b W^2 cos th - W^2 rho sin th cos th + 2 alpha theta',
               2 W (alpha sin th + rho theta' cos th)].
    """
    b, c, W, alpha, thd = sp.symbols("b c Omega alpha thetadot", real=True)
    th, s = sp.symbols("theta s", real=True)
    rho = s + c
    e_r = sp.Matrix([s_(th), 0, c_(th)])       # e_r = cos th e3 + sin th e1 (Fig. 1.10)
    e_th = sp.Matrix([c_(th), 0, -s_(th)])     # e_theta = cos th e1 - sin th e3
    e_2 = sp.Matrix([0, 1, 0])
    # the book's ingredients in [e1 e2 e3] components
    omega = sp.Matrix([0, thd, W])
    omega_dot = sp.Matrix([-W * thd, 0, 0])   # d/dt (W e3 + theta' e2) = theta' W e3 x e2
    assert omega_dot == sp.Matrix([0, 0, W]).cross(omega)
    R_ddot = sp.Matrix([-b * W**2, 0, 0])
    book_omega_tilde = sp.Matrix([[0, -W, thd], [W, 0, 0], [-thd, 0, 0]])
    book_omega_dot_tilde = sp.Matrix([[0, 0, 0], [0, 0, W * thd], [0, -W * thd, 0]])
    assert tilde(omega) == book_omega_tilde and tilde(omega_dot) == book_omega_dot_tilde
    # the book's 2-D transformation [u_r, u_th] = [[cos, sin], [-sin, cos]] [u3, u1]
    basis = sp.Matrix.hstack(e_r, e_th, e_2)   # [e_r e_th e_2] components -> [e1 e2 e3] components
    assert zero(basis.T[:2, [2, 0]] - sp.Matrix([[c_(th), s_(th)], [-s_(th), c_(th)]]))
    assert zero(basis.T * basis - sp.eye(3)) and sp.simplify(basis.det()) == 1

    acc = point_acceleration(R_ddot, omega, omega_dot, rho * e_r, alpha * e_r, [0, 0, 0])
    book_1_21 = (R_ddot + rho * book_omega_tilde * book_omega_tilde * e_r
                 + rho * book_omega_dot_tilde * e_r + 2 * alpha * book_omega_tilde * e_r)
    assert zero(acc.total - book_1_21)
    assert zero(acc.centripetal - rho * book_omega_tilde**2 * e_r)
    assert zero(acc.euler - rho * book_omega_dot_tilde * e_r)
    assert zero(acc.coriolis - 2 * alpha * book_omega_tilde * e_r)

    # independent: inertial position of P, differentiated twice, resolved in [e1 e2 e3]
    thf, sf = sp.Function("theta", real=True)(t), sp.Function("s", real=True)(t)
    e_r_t = e_r.subs(th, thf)
    r_P = C3(W * t) * (sp.Matrix([b, 0, 0]) + (sf + c) * e_r_t)
    a_direct = C3(W * t).T * r_P.diff(t, 2)
    a_direct = a_direct.subs({thf.diff(t, 2): 0, sf.diff(t, 2): 0}).subs(
        {thf.diff(t): thd, sf.diff(t): alpha}).subs({thf: th, sf: s})
    assert zero(a_direct - book_1_21)
    written_out = sp.Matrix([-b * W**2 - (W**2 + thd**2) * rho * s_(th) + 2 * alpha * thd * c_(th),
                             2 * W * (alpha * s_(th) + rho * thd * c_(th)),
                             -thd**2 * rho * c_(th) - 2 * alpha * thd * s_(th)])
    assert zero(a_direct - written_out)

    # the exercise: everything resolved in the rotating [e_r e_th e_2] frame of the arm
    to_arm = basis.T
    acc_arm = point_acceleration(to_arm * R_ddot, to_arm * omega, to_arm * omega_dot,
                                 [rho, 0, 0], [alpha, 0, 0], [0, 0, 0])
    assert zero(to_arm * omega - sp.Matrix([W * c_(th), -W * s_(th), thd]))
    exercise = sp.Matrix([-b * W**2 * s_(th) - W**2 * rho * s_(th)**2 - rho * thd**2,
                          -b * W**2 * c_(th) - W**2 * rho * s_(th) * c_(th) + 2 * alpha * thd,
                          2 * W * (alpha * s_(th) + rho * thd * c_(th))])
    assert zero(acc_arm.total - exercise)
    assert zero(basis * exercise - a_direct)


# ==================================================================== Example 1.3
def test_example_1_3_ventilator():
    """Base oscillating about Z with alpha = alpha0 sin(w t); rotor axis y2 tilted by beta about
    x1; rotor spinning at constant Omega about y2; G at L e_y2 + mu e_z from the (fixed) pivot.
    Rotor frame: R = C3(alpha) C1(beta) C2(Omega t) (rotor components -> inertial).

    Book: omega = -alpha' cos(beta) sin(Omega t) e_x + (Omega + alpha' sin(beta)) e_y
    + alpha' cos(beta) cos(Omega t) e_z: right. Misprints on the way:
    * the transformation [x; z] = [[cos at, -sin at], [sin at, cos at]] [x2; z2] prints alpha*t
      where the rotor angle is Omega*t (Fig. 1.12 labels it Omega t; alpha is the base angle);
    * the fourth line of the omega derivation reads (alpha' sin(beta) + Omega) Omega e_y: the
      trailing factor Omega is spurious (it is dimensionally rad^2/s^2) and disappears again in
      the next line.
    The velocity of G, left by the book as omega~ [0 L mu]^T (correct, since the pivot is fixed
    and L e_y2 turns with the rotor frame up to the spin about e_y2 itself), is
        v_G = [mu (Omega + alpha' sin b) - L alpha' cos b cos(Omega t),
               mu alpha' cos b sin(Omega t),
               -L alpha' cos b sin(Omega t)]   (rotor components).
    """
    a0, wb, beta, W, L, mu = sp.symbols("alpha_0 omega beta Omega L mu", real=True)
    alpha = sp.Function("alpha", real=True)(t)   # any base motion; the book's is alpha0 sin(w t)
    ad = alpha.diff(t)
    # the book's 2-D component transformations, as C1^T and C2^T blocks
    book_y2z2 = sp.Matrix([[c_(beta), s_(beta)], [-s_(beta), c_(beta)]])
    assert C1(beta).T[1:, 1:] == book_y2z2
    book_xz = sp.Matrix([[c_(W * t), -s_(W * t)], [s_(W * t), c_(W * t)]])  # printed with alpha*t
    assert C2(W * t).T[[0, 2], [0, 2]] == book_xz

    # book's method: omega = alpha' e_z1 + Omega e_y2, resolved in the rotor frame
    R2 = C3(alpha) * C1(beta)            # frame 2 (x2 y2 z2) -> inertial
    Rr = R2 * C2(W * t)                  # rotor (x y z) -> inertial
    omega = Rr.T * sp.Matrix([0, 0, ad]) + C2(W * t).T * sp.Matrix([0, W, 0])
    book_omega = sp.Matrix([-ad * c_(beta) * s_(W * t), W + ad * s_(beta), ad * c_(beta) * c_(W * t)])
    assert zero(omega - book_omega)
    # the intermediate line in frame-2 components, correct and as printed
    omega_2 = C2(W * t) * omega
    assert zero(omega_2 - sp.Matrix([0, ad * s_(beta) + W, ad * c_(beta)]))
    assert not zero(omega_2[1] - (ad * s_(beta) + W) * W)   # book's extra factor Omega
    # independent: omega by definition from the rotor's rotation matrix
    assert zero(angular_velocity_body(Rr) - book_omega)

    # velocity of G: book's omega~ r_G, the moving-frame formula, and direct differentiation
    r_G = [0, L, mu]
    v = point_velocity([0, 0, 0], book_omega, r_G).total
    assert zero(v - tilde(book_omega) * sp.Matrix(r_G))
    assert zero(v - velocity_body(Rr, r_G))
    v_expanded = sp.Matrix([mu * (W + ad * s_(beta)) - L * ad * c_(beta) * c_(W * t),
                            mu * ad * c_(beta) * s_(W * t),
                            -L * ad * c_(beta) * s_(W * t)])
    assert zero(v - v_expanded)
    book_alpha = a0 * s_(wb * t)
    v_book_base = v_expanded.subs(ad, book_alpha.diff(t))
    assert zero(velocity_body(Rr.subs(alpha, book_alpha), r_G).doit() - v_book_base)


# ==================================================================== Example 1.4
def test_example_1_4_submarine_bow():
    """Yaw rate psi' = A cos(Omega t), pitch rate theta' = B sin(Omega t), no roll; the bow at
    L e_x. R = C3(psi) C2(theta) (yaw-pitch-roll with phi = 0).

    Book right: eq. 1.45 omega = -psi' sin th e_x + theta' e_y + psi' cos th e_z, eq. 1.46
    v = L psi' cos th e_y - L theta' e_z. Both are exact for phi = 0; the remark "neglecting the
    higher order terms" is not needed.
    Book wrong:
    * eq. 1.44 (a copy of 1.40) prints the (2, 3) entry as cos th sin th instead of
      cos th sin phi; as printed it would add psi' cos th sin th to omega_y (it is 0 for phi = 0);
    * "if psi(0) = theta(0) = 0 then theta(t) = -(B/Omega) cos(Omega t)": that theta has
      theta(0) = -B/Omega; the integral of B sin(Omega t) from 0 is (B/Omega)(1 - cos(Omega t));
    * eq. 1.47 prints v = -A L cos(Omega t) cos((B/Omega) cos(Omega t)) e_y - L B sin(Omega t) e_z:
      the e_y component has the wrong sign (1.46 gives +L psi' cos th with psi' = A cos(Omega t))
      and, from the theta(t) error, the wrong cosine argument; correct:
      v = A L cos(Omega t) cos((B/Omega)(1 - cos(Omega t))) e_y - L B sin(Omega t) e_z.
      So for small B/Omega and A = B the bow velocity is A L (cos(Omega t) e_y - sin(Omega t) e_z):
      a circle of radius A L as the book says, but traversed in the opposite sense
      (about -e_x, not +e_x).
    """
    A, B, W, L = sp.symbols("A B Omega L", positive=True)
    psi, theta = sp.Function("psi", real=True)(t), sp.Function("theta", real=True)(t)
    psid, thd = psi.diff(t), theta.diff(t)
    rates = sp.Matrix([psid, thd, 0])                     # (yaw, pitch, roll) rates
    omega = euler_rate_matrix("321", (psi, theta, 0)) * rates
    book_1_45 = sp.Matrix([-psid * s_(theta), thd, psid * c_(theta)])
    assert zero(omega - book_1_45)
    R = C3(psi) * C2(theta)
    assert zero(angular_velocity_body(R) - book_1_45)    # by definition, no approximation
    # eq. 1.44 as printed (columns roll, pitch, yaw rates; phi = 0)
    phi = 0
    book_1_44 = sp.Matrix([[1, 0, -s_(theta)], [0, c_(phi), c_(theta) * s_(theta)], [0, -s_(phi), c_(theta) * c_(phi)]])
    printed = book_1_44 * sp.Matrix([0, thd, psid])
    assert zero(printed - book_1_45 - sp.Matrix([0, psid * c_(theta) * s_(theta), 0]))  # the misprint
    corrected = book_1_44.copy()
    corrected[1, 2] = c_(theta) * s_(phi)
    assert zero(corrected * sp.Matrix([0, thd, psid]) - book_1_45)

    v = point_velocity([0, 0, 0], omega, [L, 0, 0]).total
    book_1_46 = sp.Matrix([0, L * psid * c_(theta), -L * thd])
    assert zero(v - book_1_46)
    assert zero(velocity_body(R, [L, 0, 0]) - book_1_46)

    # integrate the rates with psi(0) = theta(0) = 0
    tau = sp.symbols("tau", real=True)
    psi_t = sp.integrate(A * c_(W * tau), (tau, 0, t))
    theta_t = sp.integrate(B * s_(W * tau), (tau, 0, t))
    assert sp.simplify(psi_t - A / W * s_(W * t)) == 0                  # book right
    book_theta = -B / W * c_(W * t)
    assert book_theta.subs(t, 0) != 0                                   # book's theta(0) = -B/Omega
    assert sp.simplify(theta_t - B / W * (1 - c_(W * t))) == 0
    on_path = {psid: A * c_(W * t), thd: B * s_(W * t)}
    v_t = v.subs(on_path).subs({theta: theta_t, psi: psi_t})
    correct_1_47 = sp.Matrix([0, A * L * c_(W * t) * c_(B / W * (1 - c_(W * t))), -L * B * s_(W * t)])
    assert zero(v_t - correct_1_47)
    # independent: differentiate the bow's inertial position along the integrated angles
    R_t = C3(psi_t) * C2(theta_t)
    assert zero(R_t.T * (R_t * sp.Matrix([L, 0, 0])).diff(t) - correct_1_47)
    book_1_47 = sp.Matrix([0, -A * L * c_(W * t) * c_(B / W * c_(W * t)), -L * B * s_(W * t)])
    assert book_1_47[2] == correct_1_47[2]
    at = {A: 1, B: sp.Rational(1, 2), W: 2, L: 3, t: sp.Rational(1, 5)}
    assert abs(float((book_1_47[1] - correct_1_47[1]).subs(at))) > 1.0      # sign (and argument) wrong
    # small B/Omega, A = B: v / (A L) -> (0, cos, -sin): a circle of radius A L turning about -e_x
    eps = sp.symbols("epsilon", positive=True)
    direction = (correct_1_47.subs(B, A) / (A * L)).subs(A, eps * W).subs(eps, 0)
    assert zero(direction - sp.Matrix([0, c_(W * t), -s_(W * t)]))
    assert zero(direction.cross(direction.diff(t)) - sp.Matrix([-W, 0, 0]))
    book_direction = sp.Matrix([0, -c_(W * t), -s_(W * t)])             # book: -A L (cos e_y + sin e_z)
    assert zero(book_direction.cross(book_direction.diff(t)) - sp.Matrix([W, 0, 0]))
