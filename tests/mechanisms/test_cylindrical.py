"""Cylindrical joint: analytic free fall along a spinning axis, and the same motion as a
Prismatic + Revolute composition (a cross-check between two assemblies) - also as a cut
joint closing a loop."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import (Cylindrical, FixedTranslation, Prismatic, Revolute, RigidBody,
                            Spherical, World)

I_BODY = np.array([[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.04]])


def _body():
    return RigidBody(m=1.5, r_cm=(0.1, 0.05, 0.02), I=I_BODY)


def cylindrical_model(n=(0.0, 0.0, 1.0), g=(0.0, 0.0, -9.81), **start):
    m = mbcomp.Model()
    w = m.add("world", World(g=g))
    j = m.add("joint", Cylindrical(n=n, **start))
    b = m.add("body", _body())
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def test_free_fall_along_a_vertical_spinning_axis():
    """Axis along gravity: s(t) = s0 + v0 t - g t^2 / 2 whatever the spin; the axial
    angular momentum is conserved, so w stays constant (no torque about the axis)."""
    res = mbcomp.simulate(cylindrical_model(s0=0.2, v0=1.0, phi0=0.3, w0=5.0), t_end=1.0,
                          rtol=1e-10, atol=1e-12, method="DOP853")
    t = res.time
    assert np.allclose(res["joint.s"], 0.2 + t - 0.5 * 9.81 * t ** 2, atol=1e-8)
    assert np.allclose(res["joint.w"], 5.0, atol=1e-8)
    assert np.allclose(res["joint.phi"], 0.3 + 5.0 * t, atol=1e-8)
    # the reaction along the free directions vanishes; the transverse one holds the
    # centrifugal force of the off-axis centre of mass: |f_perp| = m w^2 rho
    assert np.max(np.abs(res["joint.f.z"])) < 1e-9
    assert np.max(np.abs(res["joint.tau.z"])) < 1e-9
    fperp = np.hypot(res["joint.f.x"], res["joint.f.y"])
    assert np.allclose(fperp, 1.5 * 25.0 * np.hypot(0.1, 0.05), rtol=1e-8)


def composed_model(n, g, **start):
    m = mbcomp.Model()
    w = m.add("world", World(g=g))
    s = m.add("slide", Prismatic(n=n, s0=start["s0"], v0=start["v0"]))
    r = m.add("turn", Revolute(n=n, phi0=start["phi0"], w0=start["w0"]))
    b = m.add("body", _body())
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, r.frame_a)
    m.connect(r.frame_b, b.frame_a)
    return m


def test_tilted_axis_matches_prismatic_plus_revolute():
    """A tilted axis with gravity across it couples sliding and turning; the joint must
    move exactly as a slider and a hinge on the same axis (zero-mass middle frame)."""
    n, g = (0.3, -0.2, 1.0), (0.0, -9.81, -2.0)
    start = dict(s0=0.1, v0=-0.4, phi0=0.7, w0=2.0)
    kw = dict(t_end=2.0, rtol=1e-10, atol=1e-12, method="DOP853")
    a = mbcomp.simulate(cylindrical_model(n=n, g=g, **start), **kw)
    b = mbcomp.simulate(composed_model(n, g, **start), **kw)
    assert np.allclose(a["joint.s"], b["slide.s"], atol=1e-8)
    assert np.allclose(a["joint.phi"], b["turn.phi"], atol=1e-8)
    # the sum of the two single-axis joints' reactions on the body equals the cylinder's
    for c in "xyz":
        assert np.allclose(a[f"body.r.{c}"], b[f"body.r.{c}"], atol=1e-8)
        assert np.allclose(a[f"joint.f.{c}"], b[f"turn.f.{c}"], atol=1e-6)
    # energy conserved (no dissipation)
    E = a["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-7 * max(1.0, np.max(np.abs(a["energy.kinetic"])))


def test_cylindrical_collar_in_a_slider_crank_loop():
    """Slider-crank whose slider is a collar on a Cylindrical rail, joined to the rod by a
    ball joint on the rail axis: the ball's force passes through the axis, so the collar's
    spin about the rail is conserved while the crank drives it along; energy is conserved
    and the loop stays closed."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0.0, -9.81, 0.0)))
    crank_j = m.add("crank_joint", Revolute(n=(0, 0, 1), phi0=0.3, w0=6.0))
    crank = m.add("crank", RigidBody(m=1.0, r_cm=(0.1, 0, 0), I=np.diag([1e-4, 3.4e-3, 3.4e-3])))
    crank_tip = m.add("crank_tip", FixedTranslation(r=(0.2, 0, 0)))
    pin = m.add("pin", Spherical(w0=mbcomp.Guess((0.0, 0.0, 0.0))))
    rod = m.add("rod", RigidBody(m=2.0, r_cm=(0.3, 0, 0), I=np.diag([2e-3, 0.06, 0.06])))
    rod_tip = m.add("rod_tip", FixedTranslation(r=(0.6, 0, 0)))
    ball = m.add("ball", Spherical(w0=mbcomp.Guess((0.0, 0.0, 0.0))))
    rail = m.add("rail", Cylindrical(n=(1, 0, 0), s0=mbcomp.Guess(0.8), phi0=0.0, w0=3.0))
    collar = m.add("collar", RigidBody(m=0.5, I=np.diag([4e-3, 2e-3, 2e-3])))
    m.connect(w.frame_b, crank_j.frame_a)
    m.connect(crank_j.frame_b, crank.frame_a)
    m.connect(crank.frame_a, crank_tip.frame_a)
    m.connect(crank_tip.frame_b, pin.frame_a)
    m.connect(pin.frame_b, rod.frame_a)
    m.connect(rod.frame_a, rod_tip.frame_a)
    m.connect(rod_tip.frame_b, ball.frame_a)
    m.connect(w.frame_b, rail.frame_a)
    m.connect(rail.frame_b, collar.frame_a)
    m.connect(collar.frame_a, ball.frame_b)
    res = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12, method="DOP853", stabilization="projection")
    assert res.success, res.message
    assert np.max(res["residual.position"]) < 1e-9
    assert np.allclose(res["collar.w.x"], 3.0, atol=1e-7)  # world x = rail axis
    E = res["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-7
    # the collar stays on the rail: y = z = 0
    assert np.max(np.abs(res["collar.r.y"])) < 1e-9 and np.max(np.abs(res["collar.r.z"])) < 1e-9
