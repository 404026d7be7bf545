"""Coulomb friction with exact stick/slip switching (issue 22, item 4) against closed forms.

A block on an incline sticks for tan(alpha) <= mu_s (the friction force then equals the
slope's pull m g sin(alpha)) and otherwise slides with a = g (sin(alpha) - mu_k cos(alpha));
a block pushed along a floor sticks at t = v0 / (mu_k g) and stays; a pull k t breaks it away
at t = mu_s m g / k; a rotor with a Coulomb bearing spins down linearly and sticks at
w0 J / torque_c. Event times to 1e-8 s at rtol 1e-10 on dop853 and radau5; the energy
balance (kinetic + potential + dissipated) closes.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import Force, Inertia, PointMass, Prismatic, Revolute, World
from mbcomp.library.friction import CoulombBearing, SlidingFriction

G, M = 9.81, 2.0
TOL = dict(rtol=1e-10, atol=1e-12)
METHODS = ["dop853", "radau5"]


def block(n, mu_s, mu_k, normal, v0=0.0, pull=None):
    """A point mass on a Prismatic along ``n`` (world), gravity -z, friction on the axis."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=n, s0=0.0, v0=v0, friction=SlidingFriction(mu_s, mu_k, normal=normal)))
    b = m.add("b", PointMass(m=M))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    if pull is not None:
        f = m.add("pull", Force(f=pull))
        m.connect(s.axis, f.flange_b)
    return m


def incline(alpha, mu_s=0.5, mu_k=0.4, v0=0.0):
    """s runs down the slope (n points downhill)."""
    return block((np.cos(alpha), 0.0, -np.sin(alpha)), mu_s, mu_k, M * G * np.cos(alpha), v0)


@pytest.mark.parametrize("method", METHODS)
def test_incline_sticks_below_the_friction_angle(method):
    alpha = 0.4  # tan = 0.423 < mu_s = 0.5
    r = mbcomp.simulate(incline(alpha), t_end=2.0, method=method, **TOL)
    assert r.status == "success" and r.events == []
    assert np.max(np.abs(r["s.s"])) < 1e-12 and np.all(r["s.sticking"] == 1.0)
    # the friction holds the slope's pull: m g sin(alpha) uphill (the axis points downhill)
    assert np.max(np.abs(r["s.friction"] + M * G * np.sin(alpha))) < 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_incline_slides_above_the_friction_angle(method):
    alpha, mu_k = 0.6, 0.4  # tan = 0.684 > mu_s = 0.5: breaks away at the start
    r = mbcomp.simulate(incline(alpha, mu_k=mu_k), t_end=1.5, method=method, **TOL)
    assert [(e.time, e.name, e.detail["mode"]) for e in r.events] == [(0.0, "break+", "slip+")]
    a = G * (np.sin(alpha) - mu_k * np.cos(alpha))
    assert np.max(np.abs(r["s.s"] - 0.5 * a * r.time ** 2)) < 1e-9
    assert np.max(np.abs(r["s.friction"][1:] + mu_k * M * G * np.cos(alpha))) < 1e-12
    # kinetic + potential + dissipated = E0: the friction's work mu_k N s, exactly
    assert np.max(np.abs(r["energy.balance"])) < 1e-9 * r["energy.dissipated"][-1]
    assert r["energy.dissipated"][-1] == pytest.approx(mu_k * M * G * np.cos(alpha) * r["s.s"][-1], rel=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_a_pushed_block_sticks_and_stays(method):
    v0, mu_k = 3.0, 0.4
    r = mbcomp.simulate(block((1, 0, 0), 0.5, mu_k, M * G, v0=v0), t_end=2.0, n_out=401, method=method, **TOL)
    t_stick = v0 / (mu_k * G)
    assert [e.name for e in r.events] == ["stick"]  # no chattering: it stays stuck
    assert abs(r.events[0].time - t_stick) < 1e-8
    s_stick = v0 ** 2 / (2 * mu_k * G)
    s_exact = np.where(r.time < t_stick, v0 * r.time - 0.5 * mu_k * G * r.time ** 2, s_stick)
    assert np.max(np.abs(r["s.s"] - s_exact)) < 1e-9
    after = r.time > t_stick
    assert np.all(r["s.v"][after] == 0.0) and np.all(r["s.sticking"][after] == 1.0)
    assert np.max(np.abs(r["s.friction"][after])) < 1e-12  # nothing pulls: the stuck friction holds nothing
    # all the kinetic energy went into the friction
    assert r["energy.dissipated"][-1] == pytest.approx(0.5 * M * v0 ** 2, rel=1e-12)
    assert np.max(np.abs(r["energy.balance"])) < 1e-12 * 0.5 * M * v0 ** 2 * 100


@pytest.mark.parametrize("method", METHODS)
def test_a_pull_ramp_breaks_it_away(method):
    k, mu_s, mu_k = 10.0, 0.5, 0.4
    r = mbcomp.simulate(block((1, 0, 0), mu_s, mu_k, M * G, pull=lambda t, s, v: k * t), t_end=2.0,
                        method=method, **TOL)
    t_b = mu_s * M * G / k
    assert [e.name for e in r.events] == ["break+"] and abs(r.events[0].time - t_b) < 1e-8
    t = r.time
    held = t < t_b
    assert np.max(np.abs(r["s.s"][held])) < 1e-12
    assert np.max(np.abs(r["s.friction"][held] + k * t[held])) < 1e-9  # the friction holds the pull
    # after: m a = k t - mu_k m g, from rest at t_b
    d = t[~held] - t_b
    s_exact = k * (d ** 3 / 6 + t_b * d ** 2 / 2) / M - mu_k * G * d ** 2 / 2
    assert np.max(np.abs(r["s.s"][~held] - s_exact)) < 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_a_rotor_spins_down_linearly_and_sticks(method):
    J, w0, tau_max, tau_c = 0.5, 10.0, 2.0, 1.5
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.0, w0=w0, friction=CoulombBearing(tau_max, tau_c)))
    rotor = m.add("rotor", Inertia(J=J))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.axis, rotor.flange)
    r = mbcomp.simulate(m, t_end=5.0, method=method, **TOL)
    t_stick = w0 * J / tau_c
    assert [e.name for e in r.events] == ["stick"] and abs(r.events[0].time - t_stick) < 1e-8
    assert np.max(np.abs(r["j.w"] - np.maximum(w0 - tau_c / J * r.time, 0.0))) < 1e-9
    assert np.all(r["j.w"][r.time > t_stick] == 0.0)
    assert r["energy.dissipated"][-1] == pytest.approx(0.5 * J * w0 ** 2, rel=1e-12)


def test_a_stuck_block_slips_back_when_the_load_reverses():
    """Sticking needs more than mu_s N where the slip ends: it slips on the other way at once."""
    mu_s, k = 0.3, 20.0  # a spring pull -k s: at the turning point k s_max > mu_s m g
    r = mbcomp.simulate(block((1, 0, 0), mu_s, mu_s, M * G, v0=2.0, pull=lambda t, s, v: -k * s), t_end=1.0, **TOL)
    names = [(e.name, e.detail["mode"]) for e in r.events]
    assert names[:2] == [("stick", "stick"), ("break-", "slip-")]
    assert r.events[0].time == r.events[1].time
    # first half cycle: s'' = -om^2 s - mu g from s = 0, v = 2: s = c (cos om t - 1) + 2/om sin om t
    om = np.sqrt(k / M)
    c = mu_s * G / om ** 2
    t_turn = np.arctan2(2.0, c * om) / om
    s_turn = c * (np.cos(om * t_turn) - 1) + 2.0 / om * np.sin(om * t_turn)
    assert k * s_turn > mu_s * M * G  # the spring beats the static friction there
    assert abs(r.events[0].time - t_turn) < 1e-8


def test_friction_parameters_are_checked():
    with pytest.raises(ValueError, match="kinetic friction"):
        SlidingFriction(mu_s=0.3, mu_k=0.5, normal=1.0)
    with pytest.raises((mbcomp.ModelError, mbcomp.SimulationError), match="CoulombBearing"):
        m = mbcomp.Model()
        w = m.add("world", World())
        j = m.add("j", Revolute(friction=SlidingFriction(0.5, 0.4, 1.0)))
        rotor = m.add("rotor", Inertia(J=1.0))
        m.connect(w.frame_b, j.frame_a)
        m.connect(j.axis, rotor.flange)
        mbcomp.simulate(m, t_end=0.1)
