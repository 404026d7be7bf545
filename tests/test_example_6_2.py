"""Seed Example 6.2: a cart on a spring carrying a pendulum (two degrees of freedom).

The cart (mass m1) slides along the world x axis on a Prismatic joint and is tied to the
ground by a linear spring of rate k (a TranslationalSpringDamper between the slider's
support and axis flanges). A point mass m2 hangs from the cart at distance L on a Revolute
about z. Gravity acts along -y; the book's theta is measured from the downward vertical,
which is the revolute angle here (the rod points along -y at phi = 0 and phi > 0 swings the
bob towards +x). The book's equations of motion are

    (m1 + m2) x'' + m2 L th'' cos th - m2 L th'^2 sin th + k x = 0        (6.36)
    m2 L^2 th'' + m2 L x'' cos th + m2 g L sin th = 0                      (6.37)

and the energy (6.24) + (6.25) is conserved.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, TranslationalSpringDamper, World

M1, M2, L, K, G = 2.0, 0.7, 0.9, 35.0, 9.81
X0, XD0, TH0, THD0 = 0.15, -0.3, 1.1, 0.8
T_END = 5.0


def cart_pendulum(m1=M1, m2=M2, L=L, k=K, x0=X0, xd0=XD0, th0=TH0, thd0=THD0):
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0, -G, 0)))
    slider = mdl.add("slider", Prismatic(n=(1, 0, 0), s0=x0, v0=xd0))
    spring = mdl.add("spring", TranslationalSpringDamper(c=k))
    cart = mdl.add("cart", PointMass(m=m1))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=th0, w0=thd0))
    rod = mdl.add("rod", FixedTranslation(r=(0, -L, 0)))
    bob = mdl.add("bob", PointMass(m=m2))
    mdl.connect(world.frame_b, slider.frame_a)
    mdl.connect(slider.frame_b, cart.frame_a)
    mdl.connect(slider.support, spring.flange_a)
    mdl.connect(slider.axis, spring.flange_b)
    mdl.connect(slider.frame_b, hinge.frame_a)
    mdl.connect(hinge.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, bob.frame_a)
    return mdl


def book_rhs(t, y, m1=M1, m2=M2, L=L, k=K, g=G):
    """(6.36)-(6.37) solved for x'' and th'' (a 2x2 linear system)."""
    x, th, xd, thd = y
    c, s = np.cos(th), np.sin(th)
    A = np.array([[m1 + m2, m2 * L * c], [m2 * L * c, m2 * L ** 2]])
    b = np.array([m2 * L * thd ** 2 * s - k * x, -m2 * g * L * s])
    xdd, thdd = np.linalg.solve(A, b)
    return [xd, thd, xdd, thdd]


def book_energy(x, th, xd, thd, m1=M1, m2=M2, L=L, k=K, g=G):
    T = 0.5 * (m1 + m2) * xd ** 2 + m2 * L * xd * thd * np.cos(th) + 0.5 * m2 * L ** 2 * thd ** 2  # (6.24)
    V = 0.5 * k * x ** 2 - m2 * g * L * np.cos(th)  # (6.25)
    return T + V


@pytest.fixture(scope="module")
def result():
    r = mbcomp.simulate(cart_pendulum(), t_end=T_END, rtol=1e-11, atol=1e-12, n_out=501)
    assert r.success, r.message
    return r


@pytest.fixture(scope="module")
def reference(result):
    sol = solve_ivp(book_rhs, (0.0, T_END), [X0, TH0, XD0, THD0], method="DOP853",
                    rtol=1e-13, atol=1e-13, t_eval=result.time)
    assert sol.success
    return sol.y


def test_start_values_are_the_fixed_ones(result):
    assert result["slider.s"][0] == pytest.approx(X0, abs=1e-14)
    assert result["slider.v"][0] == pytest.approx(XD0, abs=1e-14)
    assert result["hinge.phi"][0] == pytest.approx(TH0, abs=1e-14)
    assert result["hinge.w"][0] == pytest.approx(THD0, abs=1e-14)


def test_trajectory_matches_eqs_6_36_6_37(result, reference):
    x, th, xd, thd = reference
    # the motion is genuinely coupled and large: the pendulum swings well past 1 rad
    assert np.ptp(th) > 1.5 and np.ptp(x) > 0.2
    np.testing.assert_allclose(result["slider.s"], x, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["hinge.phi"], th, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["slider.v"], xd, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result["hinge.w"], thd, rtol=0, atol=1e-7)


def test_bob_position_is_cart_plus_pendulum(result):
    x, th = result["slider.s"], result["hinge.phi"]
    np.testing.assert_allclose(result["bob.r.x"], x + L * np.sin(th), atol=1e-12)
    np.testing.assert_allclose(result["bob.r.y"], -L * np.cos(th), atol=1e-12)
    np.testing.assert_allclose(result["cart.r.x"], x, atol=1e-12)


def test_energy_is_conserved_and_equals_book_energy(result):
    E = result["energy.total"]
    E_book = book_energy(result["slider.s"], result["hinge.phi"], result["slider.v"], result["hinge.w"])
    # mbcomp's potential has the datum at the world origin, like (6.25): same value, not just a constant offset
    np.testing.assert_allclose(E, E_book, rtol=0, atol=1e-9)
    scale = np.abs(result["energy.kinetic"]).max()
    assert np.abs(E - E[0]).max() < 1e-8 * scale
