"""Seed Example 3.1: a uniform rod hinged to a massless cart whose position is prescribed.

The cart is the frame_b of a Prismatic joint along world x whose coordinate is imposed by a
PrescribedMotion drive, u(t) = A sin(Omega t); it carries no body. The rod (mass m, length L,
inertia Ic = m L^2 / 12 about its CG) hangs from a Revolute about z. Gravity along -y.

Book equation (3.18):  (Ic + m L^2/4) th'' + m g L/2 sin th = m L/2 u'' cos th.

Sign convention: the revolute angle phi is counter-clockwise about +z, so phi > 0 swings the
rod towards +x (rod direction (sin phi, -cos phi)). The printed (3.18) is the equation of
motion for theta = -phi (theta positive towards -x): a cart accelerating to +x must push the
pendulum back towards -x. (With the unit vectors of (3.16), theta would be positive towards
+x and the right-hand side of (3.18) would need a minus sign; the Lagrange equation derived
in ``test_lagrange_equation_in_phi`` settles it.)

The drive force is the horizontal force the rod needs (the cart is massless):
f = m x_cm'' with x_cm = u + (L/2) sin phi.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.library import PrescribedMotion, Prismatic, Revolute, RigidBody, World

M, L, G = 1.4, 0.8, 9.81
IC = M * L ** 2 / 12.0
A, OMEGA = 0.2, 6.0
PHI0, W0 = 0.3, -0.5
T_END = 5.0


def u(t):
    return A * np.sin(OMEGA * t)


def udd(t):
    return -A * OMEGA ** 2 * np.sin(OMEGA * t)


def cart_pendulum(cart_body=False):
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0, -G, 0)))
    slider = mdl.add("slider", Prismatic(n=(1, 0, 0)))
    drive = mdl.add("drive", PrescribedMotion(s=f"{A}*sin({OMEGA}*t)"))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=PHI0, w0=W0))
    rod = mdl.add("rod", RigidBody(m=M, r_cm=(0, -L / 2, 0), I=np.diag([IC, 0.0, IC])))
    mdl.connect(world.frame_b, slider.frame_a)
    mdl.connect(drive.flange_b, slider.axis)
    mdl.connect(slider.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, rod.frame_a)
    if cart_body:
        cart = mdl.add("cart", RigidBody(m=0.0))
        mdl.connect(slider.frame_b, cart.frame_a)
    return mdl


def eq_3_18(t, y):
    """Book (3.18) for theta = -phi."""
    th, thd = y
    thdd = (M * L / 2 * udd(t) * np.cos(th) - M * G * L / 2 * np.sin(th)) / (IC + M * L ** 2 / 4)
    return [thd, thdd]


def phidd(t, phi, phid):
    """Lagrange equation in phi: (Ic + m L^2/4) phi'' = -m L/2 u'' cos phi - m g L/2 sin phi."""
    return -(M * L / 2 * udd(t) * np.cos(phi) + M * G * L / 2 * np.sin(phi)) / (IC + M * L ** 2 / 4)


@pytest.fixture(scope="module", params=[False, True], ids=["no_cart_body", "massless_cart_body"])
def result(request):
    r = mbcomp.simulate(cart_pendulum(request.param), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=501)
    assert r.success, r.message
    return r


def test_summary_reports_prescribed_joint_eliminated():
    text = mbcomp.assemble(cart_pendulum()).summary()
    assert "degrees of freedom: 1 " in text
    assert "prescribed (eliminated, rheonomic): slider by drive" in text
    assert "tree joints (minimal coordinates): hinge" in text
    system = mbcomp.assemble(cart_pendulum())
    assert system.nu == 1 and list(system.q_names) == ["hinge.phi"]


def test_cart_follows_prescribed_motion(result):
    t = result.time
    np.testing.assert_allclose(result["slider.s"], u(t), rtol=0, atol=1e-14)
    np.testing.assert_allclose(result["slider.v"], A * OMEGA * np.cos(OMEGA * t), rtol=0, atol=1e-13)


def test_theta_matches_eq_3_18(result):
    sol = solve_ivp(eq_3_18, (0.0, T_END), [-PHI0, -W0], method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=result.time)
    assert sol.success
    th, thd = sol.y
    assert np.ptp(th) > 0.5  # a large, driven swing
    np.testing.assert_allclose(-result["hinge.phi"], th, rtol=0, atol=1e-7)
    np.testing.assert_allclose(-result["hinge.w"], thd, rtol=0, atol=1e-7)


def test_lagrange_equation_in_phi(result):
    """The same motion from the Lagrangian in the model's own angle (independent of the
    book's sign convention): mbcomp's accelerations satisfy it at every output point."""
    t, phi, w = result.time, result["hinge.phi"], result["hinge.w"]
    np.testing.assert_allclose(result["hinge.w.der"], phidd(t, phi, w), rtol=0, atol=1e-8)


def test_drive_force_is_what_the_rod_needs(result):
    t, phi, w = result.time, result["hinge.phi"], result["hinge.w"]
    a = phidd(t, phi, w)
    # Newton for the rod: the massless cart passes the hinge force on to the slider
    xcm_dd = udd(t) + L / 2 * (a * np.cos(phi) - w ** 2 * np.sin(phi))
    ycm_dd = L / 2 * (a * np.sin(phi) + w ** 2 * np.cos(phi))
    F_x = M * xcm_dd
    F_y = M * (ycm_dd + G)
    scale = np.abs(F_x).max()
    assert scale > 1.0
    np.testing.assert_allclose(result["drive.f"], F_x, rtol=0, atol=1e-8 * scale)
    # the slider's frame_b does not rotate, so its reaction resolved in frame_b is in world axes
    np.testing.assert_allclose(result["slider.f.x"], F_x, rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(result["slider.f.y"], F_y, rtol=0, atol=1e-8 * scale)


def test_energy_balance_with_drive_power(result):
    """The energy is that of the rod on the moving cart, and it changes by the drive's work:
    E(t) - E(0) = int f u' dt (Simpson's rule on the output grid)."""
    from scipy.integrate import cumulative_simpson

    t, phi, w, ud = result.time, result["hinge.phi"], result["hinge.w"], result["slider.v"]
    T = 0.5 * M * (ud ** 2 + L * ud * w * np.cos(phi) + L ** 2 / 4 * w ** 2) + 0.5 * IC * w ** 2
    V = -M * G * L / 2 * np.cos(phi)
    E = result["energy.total"]
    np.testing.assert_allclose(E, T + V, rtol=0, atol=1e-10)
    work = cumulative_simpson(result["drive.f"] * ud, x=t, initial=0.0)
    assert np.ptp(E) > 1.0  # the drive pumps energy in and out
    np.testing.assert_allclose(E - E[0], work, rtol=0, atol=2e-4)
