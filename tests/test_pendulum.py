"""Seed Example 6.5: the pendulum's rod tension from the Lagrange multiplier / reaction.

(6.79): lambda = m l thetadot^2 + m g cos(theta) along the whole trajectory.
"""
import numpy as np

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World


def pendulum(m=1.3, l=0.8, theta0=1.2):
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, -9.81, 0)))
    j = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0, w0=0.0))
    rod = mdl.add("rod", FixedTranslation(r=(0, -l, 0)))
    bob = mdl.add("bob", PointMass(m=m))
    mdl.connect(w.frame_b, j.frame_a)
    mdl.connect(j.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, bob.frame_a)
    return mdl


def test_rod_tension_equals_eq_6_79():
    m, l, g = 1.3, 0.8, 9.81
    r = mbcomp.simulate(pendulum(m, l), t_end=3.0, rtol=1e-10, atol=1e-12)
    assert r.success
    th, w = r["hinge.phi"], r["hinge.w"]
    tension = m * l * w ** 2 + m * g * np.cos(th)
    # The reaction on frame_b (which rotates with the pendulum) along +y_b points from the
    # bob to the hinge: it is the rod tension.
    np.testing.assert_allclose(r["hinge.f.y"], tension, rtol=1e-8, atol=1e-8)
    # a free hinge transmits no torque about its axis
    assert np.abs(r["hinge.tau.z"]).max() < 1e-9


def test_period_matches_exact_elliptic_integral():
    from scipy.special import ellipk

    l, g, th0 = 0.8, 9.81, 1.2
    r = mbcomp.simulate(pendulum(l=l, theta0=th0), t_end=4.0, rtol=1e-11, atol=1e-12, n_out=4001)
    th = r["hinge.phi"]
    T_exact = 4 * np.sqrt(l / g) * ellipk(np.sin(th0 / 2) ** 2)
    # first return to theta0 (maximum) after t=0: interpolate the zero crossing of w
    w = r["hinge.w"]
    t = r.time
    # zero crossings of w from + to - mark maxima of theta
    idx = np.where((w[:-1] > 0) & (w[1:] <= 0))[0][0]
    t_max = t[idx] - w[idx] * (t[idx + 1] - t[idx]) / (w[idx + 1] - w[idx])
    assert abs(t_max - T_exact) < 1e-6
