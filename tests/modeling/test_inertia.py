"""Inertia of standard shapes, parallel axes, rotation, composition (seed chapter 2).

Every closed form is checked against something independent of the formula that produced
it: the parallel-axis theorem, composition of halves/octants, limits of one shape into
another, quadrature of the defining integral ``I = int (|x|^2 E - x x^T) dm``, and a
compound pendulum simulated with a composed part against the exact period.
"""
import dataclasses

import numpy as np
import pytest
from scipy.special import ellipk

import mbcomp
from mbcomp.inertia import MassProperties, box, combine, cylinder, disk, point_mass, rod, sphere, steiner
from mbcomp.kinematics import rot_axis
from mbcomp.library import Revolute, RigidBody, World


def quadrature_inertia(points, weights):
    """I about the origin of a mass distribution sampled at ``points`` with ``weights`` (kg)."""
    x = np.asarray(points)
    w = np.asarray(weights)
    r2 = np.einsum("ni,ni->n", x, x)
    return np.einsum("n,ij->ij", w * r2, np.eye(3)) - np.einsum("n,ni,nj->ij", w, x, x)


def gauss(n, a, b):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


# ---------------------------------------------------------------- closed forms

def test_rod_about_its_end_is_ml2_over_3():
    m, l = 1.7, 0.9
    r = rod(m, l, axis="x")
    np.testing.assert_allclose(np.diag(r.I), [0.0, m * l ** 2 / 12, m * l ** 2 / 12], rtol=1e-15)
    # the end of the rod is at x = -l/2 in the rod's frame: Steiner adds m (l/2)^2
    I_end = r.about((-l / 2, 0, 0))
    np.testing.assert_allclose(np.diag(I_end), [0.0, m * l ** 2 / 3, m * l ** 2 / 3], rtol=1e-14)
    # the same rod placed with its end at frame_a's origin
    np.testing.assert_allclose(r.placed(r=(l / 2, 0, 0)).about(), I_end, rtol=1e-14)
    # going back to the centre subtracts the Steiner term (the sign matters)
    back = MassProperties.from_inertia_about(m, (l / 2, 0, 0), I_end)
    np.testing.assert_allclose(back.I, r.I, atol=1e-15)
    # an oblique rod: m l^2/12 (E - n n^T)
    n = np.array([1.0, -2.0, 2.0]) / 3.0
    np.testing.assert_allclose(rod(m, l, axis=3 * n).I, m * l ** 2 / 12 * (np.eye(3) - np.outer(n, n)), atol=1e-15)


def test_steiner_adds_about_any_point_and_is_zero_at_the_centre():
    mp = box(2.0, 0.3, 0.2, 0.1).placed(r=(0.4, -0.1, 0.25), R=rot_axis([1, 1, 0], 0.7))
    np.testing.assert_allclose(mp.about(mp.r_cm), mp.I, atol=1e-16)
    P = np.array([-0.2, 0.3, 0.05])
    I_P = mp.about(P)
    # I_P - I_cm is positive semi-definite with eigenvalues 0, m d^2, m d^2
    ev = np.linalg.eigvalsh(I_P - mp.I)
    d2 = np.sum((mp.r_cm - P) ** 2)
    np.testing.assert_allclose(ev, [0.0, 2.0 * d2, 2.0 * d2], atol=1e-14)
    np.testing.assert_allclose(steiner(2.0, mp.r_cm - P), steiner(2.0, P - mp.r_cm))


def test_box_against_quadrature():
    m, a, b, c = 3.0, 0.4, 0.25, 0.1
    xs, wx = gauss(4, -a / 2, a / 2)
    ys, wy = gauss(4, -b / 2, b / 2)
    zs, wz = gauss(4, -c / 2, c / 2)
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    W = np.einsum("i,j,k->ijk", wx, wy, wz) * m / (a * b * c)
    I = quadrature_inertia(np.column_stack([X.ravel(), Y.ravel(), Z.ravel()]), W.ravel())
    np.testing.assert_allclose(box(m, a, b, c).I, I, rtol=1e-13, atol=1e-16)


def test_hollow_cylinder_against_quadrature():
    m, R, ri, L = 2.5, 0.12, 0.05, 0.3
    rr, wr = gauss(6, ri, R)
    th = np.linspace(0, 2 * np.pi, 16, endpoint=False)  # exact for the trigonometric degree here
    zz, wz = gauss(4, -L / 2, L / 2)
    Rg, Tg, Zg = np.meshgrid(rr, th, zz, indexing="ij")
    W = np.einsum("i,j,k->ijk", wr * rr, np.full(th.size, 2 * np.pi / th.size), wz)
    W *= m / (np.pi * (R ** 2 - ri ** 2) * L)
    pts = np.column_stack([(Rg * np.cos(Tg)).ravel(), (Rg * np.sin(Tg)).ravel(), Zg.ravel()])
    I = quadrature_inertia(pts, W.ravel())
    np.testing.assert_allclose(cylinder(m, R, L, axis="z", inner_radius=ri).I, I, rtol=1e-13, atol=1e-16)


def test_solid_sphere_against_radial_integral_and_shell_limit():
    m, R = 4.0, 0.2
    # int r^2 sin^2(polar) dm over the ball: (8 pi / 15) rho R^5 = 2/5 m R^2
    r, w = gauss(8, 0.0, R)
    rho = m / (4 / 3 * np.pi * R ** 3)
    # int rho r^4 dr * int_0^pi sin^3(polar) d(polar) * int_0^2pi d(azimuth)
    I_axis = np.sum(w * rho * r ** 4) * (4 / 3) * (2 * np.pi)
    assert sphere(m, R).I[0, 0] == pytest.approx(I_axis, rel=1e-14)
    np.testing.assert_allclose(sphere(m, R).I, 0.4 * m * R ** 2 * np.eye(3), rtol=1e-15)
    # a thin shell is a ball minus a slightly smaller ball (masses in proportion to volume)
    eps = 1e-5
    ri = R * (1 - eps)
    m_in = m * (ri / R) ** 3
    shell = sphere(m, R) - sphere(m_in, ri)
    hollow = sphere(m - m_in, R, hollow=True)
    np.testing.assert_allclose(shell.I, hollow.I, rtol=3 * eps)
    assert shell.m == pytest.approx(m - m_in, rel=1e-14)
    np.testing.assert_allclose(hollow.I, 2 / 3 * (m - m_in) * R ** 2 * np.eye(3), rtol=1e-15)


def test_cylinder_limits_are_disk_and_rod():
    m, R, L = 1.3, 0.25, 0.8
    np.testing.assert_allclose(cylinder(m, R, 1e-9, axis="x").I, disk(m, R, axis="x").I, rtol=1e-15, atol=1e-18)
    thin = cylinder(m, 1e-9, L, axis="y").I
    np.testing.assert_allclose(thin, rod(m, L, axis="y").I, rtol=1e-15, atol=1e-18)
    # a tube is a solid cylinder with the bore removed
    ri = 0.1
    tube = cylinder(m, R, L, inner_radius=ri)
    m_bore = m * ri ** 2 / (R ** 2 - ri ** 2)
    assert (cylinder(m + m_bore, R, L) - cylinder(m_bore, ri, L)).allclose(tube, rtol=1e-13, atol=1e-16)


def test_box_composed_of_halves_and_octants_equals_the_whole():
    m, a, b, c = 2.4, 0.3, 0.2, 0.1
    whole = box(m, a, b, c)
    for k, half_dims in enumerate([(a / 2, b, c), (a, b / 2, c), (a, b, c / 2)]):
        e = np.eye(3)[k] * [a, b, c][k] / 4
        left = box(m / 2, *half_dims).placed(r=-e)
        right = box(m / 2, *half_dims).placed(r=e)
        assert (left + right).allclose(whole, rtol=1e-13, atol=1e-16)
        assert combine(left, right).allclose(whole, rtol=1e-13, atol=1e-16)
        # each half alone is not the whole (the test has teeth)
        assert not (left + left).allclose(whole, rtol=1e-6)
    octants = [box(m / 8, a / 2, b / 2, c / 2).placed(r=np.array(s) * [a, b, c] / 4)
               for s in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3)]
    assert sum(octants).allclose(whole, rtol=1e-13, atol=1e-16)
    # removing a half leaves the other half
    right = box(m / 2, a / 2, b, c).placed(r=(a / 4, 0, 0))
    assert (whole - box(m / 2, a / 2, b, c).placed(r=(-a / 4, 0, 0))).allclose(right, rtol=1e-12, atol=1e-16)


def test_combined_centre_of_mass_and_inertia_of_two_particles():
    a = point_mass(1.0, (0.0, 0.0, 0.0))
    b = point_mass(3.0, (0.4, 0.0, 0.0))
    ab = a + b
    assert ab.m == 4.0
    np.testing.assert_allclose(ab.r_cm, [0.3, 0, 0], atol=1e-16)
    # reduced mass mu = 3/4, distance 0.4: I = mu d^2 about the transverse axes
    np.testing.assert_allclose(np.diag(ab.I), [0.0, 0.75 * 0.16, 0.75 * 0.16], rtol=1e-14, atol=1e-17)


def test_rotation_direction_and_principal_axes_of_a_rotated_box():
    # R maps the part's own coordinates into the new frame: a rod along x, turned +90 deg
    # about z, lies along y
    turned = rod(1.0, 1.0, axis="x").rotated(rot_axis([0, 0, 1], np.pi / 2))
    np.testing.assert_allclose(np.diag(turned.I), [1 / 12, 0.0, 1 / 12], atol=1e-16)
    m, a, b, c = 1.5, 0.5, 0.3, 0.1
    R = rot_axis([0.3, -1.0, 0.7], 1.2)
    own = box(m, a, b, c)
    mp = own.placed(r=(0.2, 0.1, -0.3), R=R)
    assert np.abs(mp.I - np.diag(np.diag(mp.I))).max() > 1e-3  # really not diagonal
    moments, axes = mp.principal()
    # ascending: the longest edge (x, a) has the smallest moment
    np.testing.assert_allclose(moments, np.sort(np.diag(own.I)), rtol=1e-13)
    np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, mp.I, atol=1e-15)
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-14)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-14)
    order = np.argsort(np.diag(own.I))  # which box edge each principal axis is
    for k in range(3):
        assert abs(axes[:, k] @ R[:, order[k]]) == pytest.approx(1.0, abs=1e-12)


def test_values_are_immutable():
    mp = box(1.0, 0.1, 0.2, 0.3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        mp.m = 2.0
    with pytest.raises(ValueError):
        mp.I[0, 0] = 1.0
    with pytest.raises(ValueError):
        mp.r_cm[0] = 1.0


@pytest.mark.parametrize("make, where, words", [
    (lambda: box(-1.0, 0.1, 0.1, 0.1), "box.m", "negative"),
    (lambda: box(1.0, 0.1, 0.0, 0.1), "box.b", "edge length along y"),
    (lambda: rod(1.0, -2.0), "rod.length", "> 0"),
    (lambda: cylinder(1.0, 0.1, 0.2, inner_radius=0.1), "cylinder.inner_radius", "smaller than the outer"),
    (lambda: cylinder(1.0, 0.1, 0.2, axis="w"), "cylinder.axis", "'x', 'y' or 'z'"),
    (lambda: sphere(1.0, 0.0), "sphere.radius", "> 0"),
    (lambda: MassProperties(1.0, (0, 0, 0), np.diag([0.1, 0.1, 0.3])), "MassProperties.I", "triangle inequality"),
    (lambda: MassProperties(1.0, (0, 0, 0), np.diag([0.1, -0.1, 0.1])), "MassProperties.I", "negative"),
    (lambda: MassProperties(1.0, (0, 0, 0), [[0.1, 0.01, 0], [0, 0.1, 0], [0, 0, 0.1]]), "MassProperties.I",
     "not symmetric"),
    (lambda: MassProperties(-1.0), "MassProperties.m", "negative"),
    (lambda: box(1.0, 0.1, 0.1, 0.1).placed(R=np.diag([1.0, 1.0, -1.0])), "placed.R", "rotation"),
    (lambda: box(1.0, 0.1, 0.1, 0.1) - box(2.0, 0.1, 0.1, 0.1), "__sub__", "exceeds"),
])
def test_bad_values_name_the_parameter_and_the_fix(make, where, words):
    with pytest.raises(mbcomp.ModelError) as err:
        make()
    msg = str(err.value)
    assert where in msg and words in msg and "fix:" in msg


def test_rigid_body_accepts_mass_properties():
    mp = box(2.0, 0.3, 0.2, 0.1).placed(r=(0.15, 0.1, 0.0), R=rot_axis([0, 0, 1], 0.3))
    body = RigidBody.from_mass_properties(mp)
    assert body.p.m == mp.m
    np.testing.assert_array_equal(body.p.r_cm, mp.r_cm)
    np.testing.assert_array_equal(body.p.I, mp.I)
    assert body.problems() == []
    with pytest.raises(TypeError, match="not a MassProperties"):
        RigidBody.from_mass_properties((2.0, (0, 0, 0), np.eye(3)))


# ------------------------------------------------- a composed part in a simulation

M_ROD, L_ROD, M_DISK, R_DISK, G = 0.6, 0.8, 1.1, 0.12, 9.81


def clock_pendulum_parts():
    """A rod hanging from the hinge (frame_a origin) along -y with a disk (normal z) at its tip."""
    stick = rod(M_ROD, L_ROD, axis="y").placed(r=(0, -L_ROD / 2, 0))
    bob = disk(M_DISK, R_DISK, axis="z").placed(r=(0, -L_ROD, 0))
    return stick + bob


def by_hand():
    """The same body's mass properties written out by hand (m, d below the hinge, I_cm, I_O)."""
    m = M_ROD + M_DISK
    d = (M_ROD * L_ROD / 2 + M_DISK * L_ROD) / m
    rod_t = M_ROD * L_ROD ** 2 / 12 + M_ROD * (L_ROD / 2 - d) ** 2
    disk_off = M_DISK * (L_ROD - d) ** 2
    I = np.diag([rod_t + M_DISK * R_DISK ** 2 / 4 + disk_off,
                 M_DISK * R_DISK ** 2 / 4,
                 rod_t + M_DISK * R_DISK ** 2 / 2 + disk_off])
    I_O = M_ROD * L_ROD ** 2 / 3 + M_DISK * R_DISK ** 2 / 2 + M_DISK * L_ROD ** 2
    return m, d, I, I_O


def pendulum(body, theta0):
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0, -G, 0)))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0, w0=0.0))
    b = mdl.add("body", body)
    mdl.connect(world.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, b.frame_a)
    return mdl


def first_maximum_time(res):
    w, t = res["hinge.w"], res.time
    idx = np.where((w[:-1] > 0) & (w[1:] <= 0))[0][0]
    return t[idx] - w[idx] * (t[idx + 1] - t[idx]) / (w[idx + 1] - w[idx])


def test_composed_part_equals_the_hand_written_body():
    m, d, I, I_O = by_hand()
    mp = clock_pendulum_parts()
    assert mp.m == pytest.approx(m, rel=1e-15)
    np.testing.assert_allclose(mp.r_cm, [0, -d, 0], atol=1e-15)
    np.testing.assert_allclose(mp.I, I, rtol=1e-13, atol=1e-16)
    assert mp.about()[2, 2] == pytest.approx(I_O, rel=1e-14)


def test_compound_pendulum_period_from_a_composed_part():
    """Exact period of a compound pendulum released from rest at theta0:
    T = 4 sqrt(I_O / (m g d)) K(sin^2(theta0/2)); the body built from parts and the body with
    the tensor typed by hand follow the same trajectory."""
    m, d, I, I_O = by_hand()
    th0 = 0.9
    T_exact = 4 * np.sqrt(I_O / (m * G * d)) * ellipk(np.sin(th0 / 2) ** 2)
    kw = dict(t_end=1.05 * T_exact, rtol=1e-11, atol=1e-12, n_out=2001)
    composed = mbcomp.simulate(pendulum(RigidBody.from_mass_properties(clock_pendulum_parts()), th0), **kw)
    hand = mbcomp.simulate(pendulum(RigidBody(m=m, r_cm=(0, -d, 0), I=I), th0), **kw)
    assert composed.success and hand.success
    assert abs(first_maximum_time(composed) - T_exact) < 1e-7 * T_exact
    np.testing.assert_allclose(composed["hinge.phi"], hand["hinge.phi"], rtol=0, atol=1e-10)
    # the centroidal inertia alone (forgetting Steiner) would give a clearly different period
    T_wrong = 4 * np.sqrt(I[2, 2] / (m * G * d)) * ellipk(np.sin(th0 / 2) ** 2)
    assert abs(T_wrong - T_exact) > 0.3 * T_exact
