"""ElasticStop (issue 22): a compliant stop on a joint axis against closed forms.

A rotor of inertia J (no gravity) turning at w0 into the stop at ``hi``:

* undamped, it is a half oscillation of ``J x'' = -c x`` (x = phi - hi): contact for exactly
  ``pi sqrt(J/c)``, leaving at ``-w0``;
* damped, the law (damping limited by the spring torque and never pulling) has three pieces,
  each linear: (A) while ``d w > c x`` the torque is ``2 c x`` (``J x'' = -2 c x``, from
  ``x = 0, w = w0``, until ``tan(W t) = d W / c`` with ``W = sqrt(2 c / J)``); (B) then
  ``J x'' = -c x - d w`` until the torque ``c x + d w`` falls to zero on the way out; (C) no
  torque: the rotor leaves at the speed it had then. The coefficient of restitution is
  ``e = -w_C / w0``, a function of ``zeta = d / (2 sqrt(c J))`` alone (every piece is linear
  and homogeneous), computed here from the exact solutions of the pieces (a sine, a matrix
  exponential) and one scalar root (the end of B);
* as c grows, the compliant rotor's contacts approach the rigid stop's impacts
  (``Revolute(limits=..., restitution=e)``): the lag is the contacts' summed duration,
  which shrinks like ``1 / sqrt(c)``.
"""
import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

import mbcomp
from mbcomp.library import ElasticStop, Revolute, RigidBody, World

TOL = dict(rtol=1e-11, atol=1e-13)
J = 2.0
#: an explicit method stepping across the contact's corners (no events mark them) can lose
#: ~3e-7 in the exit speed (DOP853, c = 1e2, steps longer than the contact); scipy's Radau
#: keeps 1e-11 here, so the closed-form checks below use it (DOP853 where it is checked too)
STIFF = dict(method="Radau", **TOL)


def rotor(w0=1.0, lo=-0.5, hi=0.5, c=None, d=0.0, restitution=None):
    """A rotor (J about z) on a hinge, no gravity: with an ElasticStop (c given) or the
    joint's rigid stops (restitution given)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    limits = dict(limits=(lo, hi), restitution=restitution) if restitution is not None else {}
    j = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=w0, **limits))
    b = m.add("disk", RigidBody(m=1.0, I=np.diag([1.0, 1.0, J])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    if c is not None:
        s = m.add("stop", ElasticStop(lo=lo, hi=hi, c=c, d=d))
        m.connect(s.flange_a, j.support)
        m.connect(s.flange_b, j.axis)
    return m


def crossing(level, direction):
    """A user event: the hinge angle (y[0], rad) crossing ``level`` in ``direction``."""
    def f(t, y):
        return y[0] - level
    f.direction = direction
    f.__name__ = f"at_{level:g}_{direction:+d}"
    return f


def restitution_closed_form(c, d, J):
    """``(e, T)``: the damped half oscillation's coefficient of restitution and the time from
    entering the stop to leaving it (A, B, then C's drift back out at the speed it left with)."""
    if d == 0.0:
        return 1.0, np.pi * np.sqrt(J / c)
    W = np.sqrt(2.0 * c / J)
    t1 = np.arctan(d * W / c) / W                     # end of A: d w = c x (w0 = 1: linear)
    x1, v1 = np.sin(W * t1) / W, np.cos(W * t1)
    A = np.array([[0.0, 1.0], [-c / J, -d / J]])

    def force(t):                                     # c x + d w along B's exact solution
        x, v = expm(A * t) @ [x1, v1]
        return c * x + d * v

    T, dt = 0.0, 0.01 * np.sqrt(J / c)
    while force(T + dt) > 0.0:                        # bracket B's end (the force is > 0 before it)
        T += dt
    t2 = brentq(force, T, T + dt, xtol=1e-15, rtol=1e-15)
    x2, v2 = expm(A * t2) @ [x1, v1]
    return -v2, t1 + t2 + x2 / -v2


def test_closed_form_helper_limits():
    # undamped: e = 1 in half a period; light damping: e ~ exp(-pi zeta) of the linear oscillator,
    # somewhat above it (the limited damper does less on the way in, nothing on the way out)
    e, T = restitution_closed_form(1e4, 0.0, J)
    assert e == 1.0 and T == np.pi * np.sqrt(J / 1e4)
    zeta = 0.01
    e, _ = restitution_closed_form(1e4, 2 * zeta * np.sqrt(1e4 * J), J)
    assert np.exp(-np.pi * zeta) < e < 1.0 and abs(e - np.exp(-np.pi * zeta)) < 0.5 * np.pi * zeta


@pytest.mark.parametrize("method", ["dop853", "Radau"])
def test_undamped_contact_lasts_half_a_period_and_returns_the_speed(method):
    c, w0 = 1e4, 1.0
    r = mbcomp.simulate(rotor(w0, lo=-10.0, c=c), t_end=0.7, method=method,
                        events=[crossing(0.5, +1), crossing(0.5, -1)], n_out=701, **TOL)
    assert r.status == "success", r.message
    t_in, t_out = [x.time for x in r.events]
    assert abs(t_in - 0.5 / w0) < 1e-12                              # free flight to the stop
    assert abs((t_out - t_in) - np.pi * np.sqrt(J / c)) < 1e-8       # half the contact's period
    assert abs(r["hinge.w"][-1] + w0) < 1e-8                         # back at the same speed
    om, tt = np.sqrt(c / J), r.time - 0.5 / w0                      # in contact: x = w0 / om sin(om t)
    exact = np.where((tt > 0) & (tt < np.pi / om), w0 / om * np.sin(om * tt), 0.0)
    assert np.max(np.abs(r["stop.penetration"] - exact)) < 1e-9
    assert np.ptp(r["energy.total"]) < 1e-9                           # conservative: T + V constant


@pytest.mark.parametrize("zeta", [0.05, 0.2, 0.5, 1.0, 2.0])
def test_damped_rebound_matches_the_closed_form(zeta):
    c = 1e4
    d = 2 * zeta * np.sqrt(c * J)
    e, T = restitution_closed_form(c, d, J)
    for w0 in (1.0, 3.0):                            # e does not depend on the speed
        r = mbcomp.simulate(rotor(w0, lo=-10.0, c=c, d=d), t_end=0.5 / w0 + T + 1e-3, n_out=3, **STIFF)
        assert r.status in ("success", "inaccurate"), r.message   # the balance's grid is coarse here
        assert r["stop.tau"][-1] == 0.0              # the stop lets go (C: no torque, even if still in)
        assert abs(-r["hinge.w"][-1] / w0 - e) < 1e-9, (zeta, w0)


def test_restitution_falls_with_damping_and_the_energy_balance_closes():
    c = 1e4
    es = []
    for zeta in (0.0, 0.1, 0.3, 1.0, 3.0):
        d = 2 * zeta * np.sqrt(c * J)
        _, T = restitution_closed_form(c, d, J)       # the run ends as the rotor leaves the stop
        r = mbcomp.simulate(rotor(1.0, lo=-10.0, c=c, d=d), t_end=0.5 + T, n_out=20001, **STIFF)
        es.append(-r["hinge.w"][-1])
        lost = 0.5 * J * (1.0 - es[-1] ** 2)
        assert abs(r["energy.kinetic"][-1] - 0.5 * J * es[-1] ** 2) < 1e-9
        if d:   # what the rotor lost is what the element dissipated (its power beyond dV/dt,
            # integrated by the trapezoid rule on the output grid: measured ~1e-6 of J/2)
            assert abs(r["energy.dissipated"][-1] - lost) < 1e-5 * 0.5 * J
            assert np.ptp(r["energy.balance"]) < 1e-5 * 0.5 * J
            assert np.all(r["stop.tau"] >= 0.0)                    # never pulls into the stop
    assert es[0] == pytest.approx(1.0, abs=1e-8)
    assert np.all(np.diff(es) < 0.0), es


@pytest.mark.parametrize("zeta", [0.0, 0.1])
def test_stiffening_compliant_stop_approaches_the_rigid_stop(zeta):
    # rigid: impacts at the limits with restitution e(zeta); compliant: the contacts start
    # later by the earlier contacts' summed duration, T ~ sqrt(J/c): the lag shrinks like 1/sqrt(c)
    t_end, lags = 4.0, []
    e, _ = restitution_closed_form(1.0, 2 * zeta * np.sqrt(J), J)     # depends on zeta only
    rigid = mbcomp.simulate(rotor(restitution=e), t_end=t_end, **STIFF)
    t_rigid = np.array([x.time for x in rigid.events if x.kind == "impact"])
    assert len(t_rigid) >= 3
    for c in (1e2, 1e4, 1e6):
        d = 2 * zeta * np.sqrt(c * J)
        _, T = restitution_closed_form(c, d, J)
        r = mbcomp.simulate(rotor(c=c, d=d), t_end=t_end + 2.0, events=[crossing(0.5, +1), crossing(-0.5, -1)],
                            **STIFF)
        t_in = np.array([x.time for x in r.events])[: len(t_rigid)]
        k = np.arange(len(t_in))
        # the k-th contact starts after k earlier ones, each lasting T (whatever the speed)
        np.testing.assert_allclose(t_in - t_rigid[: len(t_in)], k * T, atol=1e-8)
        lags.append(np.max(np.abs(t_in - t_rigid[: len(t_in)])))
    ratios = np.array(lags[:-1]) / np.array(lags[1:])
    np.testing.assert_allclose(ratios, 10.0, rtol=1e-6)              # 100 x c -> lag / 10

