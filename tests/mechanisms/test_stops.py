"""Joint stops (issue 22): rigid stops with Newton's restitution on revolute and prismatic
joints, against closed forms: impact times of a free rotor between stops, e^2 of the kinetic
energy kept per impact, energy balance through impacts, resting (Zeno) and chattering,
engaging at e = 0 and releasing when the stop would pull."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import (FixedTranslation, PointMass, PrescribedMotion, Prismatic, Revolute, RigidBody, Torque,
                            World)
from mbcomp.library.joints import StopModes

TOL = dict(rtol=1e-10, atol=1e-12)


def rotor(e, w0=1.0, lim=(-0.5, 0.5), J=2.0, tau=None, joint=Revolute):
    """A rotor (J about z) on a hinge between stops, no gravity."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("hinge", joint(n=(0, 0, 1), phi0=0.0, w0=w0, limits=lim, restitution=e))
    b = m.add("disk", RigidBody(m=1.0, I=np.diag([1.0, 1.0, J])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    if tau is not None:
        t = m.add("motor", Torque(tau=tau))
        m.connect(t.flange_b, j.axis)
    return m


def slider(e, v0=1.0, lim=(-0.5, 0.5), mass=3.0):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("slide", Prismatic(n=(1, 0, 0), s0=0.0, v0=v0, limits=lim, restitution=e))
    b = m.add("block", PointMass(m=mass))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def pendulum(e, lo, phi0=0.8, length=1.0):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("hinge", Revolute(phi0=phi0, w0=0.0, limits=(lo, 3.0), restitution=e))
    rod = m.add("rod", FixedTranslation(r=(0, -length, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def rattle_times(e, w0, lo, hi, n):
    """Impact times of a free coordinate from 0 at speed w0 > 0 between lo and hi."""
    t, speed, out = (hi - 0.0) / w0, w0, []
    for _ in range(n):
        out.append(t)
        speed *= e
        t += (hi - lo) / speed
    return np.array(out)


CASES = [("dop853", "lagrange", "c"), ("dop853", "lagrange", "numeric"), ("radau5", "lagrange", "numeric"),
         ("dop853", "dalembert", "numeric"), ("DOP853", "dalembert", "c")]


@pytest.mark.parametrize("method, formulation, backend", CASES)
def test_rotor_between_stops_impact_times_and_energy(method, formulation, backend):
    e = 0.8
    r = mbcomp.simulate(rotor(e), t_end=6.0, method=method, formulation=formulation, backend=backend, **TOL)
    impacts = [x for x in r.events if x.kind == "impact"]
    exact = rattle_times(e, 1.0, -0.5, 0.5, len(impacts))
    assert len(impacts) == 4 and r.status == "success"
    assert np.max(np.abs([x.time for x in impacts] - exact)) < 1e-9
    assert [x.name for x in impacts] == ["hi", "lo", "hi", "lo"]
    for x in impacts:   # e^2 of the kinetic energy kept: speed ratio -e, loss (1 - e^2) J w^2 / 2
        assert abs(x.detail["speed_after"] / x.detail["speed_before"] + e) < 1e-10
        w = x.detail["speed_before"]
        assert abs(x.detail["energy_loss"] - 0.5 * 2.0 * w**2 * (1 - e**2)) < 1e-10
    T = r["energy.kinetic"]
    assert abs(T[-1] / T[0] - e ** (2 * len(impacts))) < 1e-8
    assert np.ptp(T + r["energy.impacts"]) < 1e-9 * T[0]
    assert np.all(r["hinge.phi"] <= 0.5 + 1e-9) and np.all(r["hinge.phi"] >= -0.5 - 1e-9)   # no tunnelling


def test_prismatic_stops():
    e, mass = 0.5, 3.0
    r = mbcomp.simulate(slider(e, mass=mass), t_end=8.0, **TOL)
    impacts = [x for x in r.events if x.kind == "impact"]
    assert len(impacts) == 3
    assert np.max(np.abs([x.time for x in impacts] - rattle_times(e, 1.0, -0.5, 0.5, 3))) < 1e-9
    assert abs(r["energy.kinetic"][-1] - 0.5 * mass * e**6) < 1e-9
    assert impacts[0].component == "slide"


@pytest.mark.parametrize("method", ["dop853", "radau5"])
def test_pendulum_keeps_e_squared_of_its_kinetic_energy(method):
    e = 0.7
    r = mbcomp.simulate(pendulum(e, lo=0.0), t_end=5.0, method=method, **TOL)
    impacts = [x for x in r.events if x.kind == "impact"]
    assert len(impacts) == 5 and r.status == "success"
    E0 = 9.81 * (1 - np.cos(0.8))
    for k, x in enumerate(impacts):   # at phi = 0 all energy is kinetic: (w-)^2 / 2 = E0 e^(2k)
        assert abs(0.5 * x.detail["speed_before"] ** 2 - E0 * e ** (2 * k)) < 1e-8 * E0
        assert abs(x.detail["speed_after"] ** 2 / x.detail["speed_before"] ** 2 - e**2) < 1e-8
    # the first impact: the quarter period of the amplitude-0.8 pendulum, K(sin(0.4)) / sqrt(g/l)
    from scipy.special import ellipk
    assert abs(impacts[0].time - ellipk(np.sin(0.4) ** 2) / np.sqrt(9.81)) < 1e-9
    balance = r["energy.kinetic"] + r["energy.potential"] + r["energy.impacts"]
    assert np.ptp(balance) < 1e-8 * E0


def test_plastic_stop_engages_and_holds():
    # e = 0: the pendulum falls onto a stop at 0.3 rad (gravity presses it there) and stays
    r = mbcomp.simulate(pendulum(0.0, lo=0.3), t_end=2.0, **TOL)
    kinds = [x.kind for x in r.events]
    assert kinds == ["impact", "engage"] and r.status == "success"
    after = r.time > r.events[0].time
    assert np.max(np.abs(r["hinge.phi"][after] - 0.3)) < 1e-9 and np.max(np.abs(r["hinge.w"][after])) < 1e-9
    lost = r.events[0].detail["energy_loss"]
    assert abs(lost - 9.81 * (np.cos(0.3) - np.cos(0.8))) < 1e-9


@pytest.mark.parametrize("method, formulation", [("dop853", "lagrange"), ("radau5", "lagrange"),
                                                 ("dop853", "dalembert")])
def test_bouncing_on_a_stop_comes_to_rest(method, formulation):
    # e = 0.5, gravity pressing into the stop: impacts ever closer in time (Zeno) -> at rest there
    e = 0.5
    r = mbcomp.simulate(pendulum(e, lo=0.3), t_end=2.5, method=method, formulation=formulation, **TOL)
    assert r.status == "success" and r.events[-1].kind == "rest" and r.events[-1].component == "hinge"
    impacts = [x for x in r.events if x.kind == "impact"]
    d = np.diff([x.time for x in impacts])
    assert np.all(d[1:] < d[:-1])                       # ever closer
    # rests at the accumulation point of the geometric series of flight times
    assert np.all(np.abs(d[-6:] / d[-7:-1] - e) < 1e-3)     # small flights: ratio e (constant push)
    t_rest = impacts[-1].time
    t_star = impacts[-6].time + d[-5] / (1 - e)
    assert abs(t_rest - t_star) < 2 * d[-1]
    at_rest = r.time > t_rest
    assert np.max(np.abs(r["hinge.phi"][at_rest] - 0.3)) < 1e-9
    balance = r["energy.kinetic"] + r["energy.potential"] + r["energy.impacts"]
    assert np.ptp(balance) < 1e-8


def test_chattering_without_rest_mode_fails_naming_the_joint():
    class NoRest(StopModes):
        def rest(self, name, mode):
            return None

    class Bare(Revolute):
        def modes(self, p):
            return NoRest(*p.limits, p.restitution)

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("latch", Bare(phi0=0.8, w0=0.0, limits=(0.3, 3.0), restitution=0.9))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    r = mbcomp.simulate(m, t_end=30.0, **TOL)
    assert r.status == "failed" and r.message.startswith("chattering: latch hit 'lo'")
    assert r.time[-1] < 30.0 and len(r.events) > 30
    # the same joint with its resting mode settles instead
    r2 = mbcomp.simulate(pendulum(0.9, lo=0.3), t_end=30.0, **TOL)
    assert r2.status == "success" and r2.events[-1].kind == "rest"


def test_release_when_the_stop_would_pull():
    # torque -1 N m presses the rotor (J = 2) onto its stop at -0.5 (e = 0); at t = 2 s it turns
    # to +1 N m: the stop releases there and phi = -0.5 + (t - 2)^2 / (2 J)
    r = mbcomp.simulate(rotor(0.0, w0=0.0, tau=lambda t, phi, w: -1.0 if t < 2.0 else 1.0), t_end=3.0, **TOL)
    kinds = [(x.kind, x.name) for x in r.events]
    assert kinds == [("impact", "lo"), ("engage", "lo"), ("release", "lo")], kinds
    assert abs(r.events[0].time - np.sqrt(2 * 0.5 * 2.0)) < 1e-9       # 0.5 rad at alpha = 1/J
    assert abs(r.events[2].time - 2.0) < 1e-9
    late = r.time > 2.0
    assert np.max(np.abs(r["hinge.phi"][late] - (-0.5 + (r.time[late] - 2.0) ** 2 / 4.0))) < 1e-8


def test_a_stop_on_a_driven_joint_is_refused():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("hinge", Revolute(n=(0, 0, 1), limits=(-0.5, 0.5), restitution=0.5))
    b = m.add("disk", RigidBody(m=1.0, I=np.eye(3)))
    d = m.add("drive", PrescribedMotion(s=lambda t: t))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    m.connect(d.flange_b, j.axis)
    with pytest.raises(mbcomp.ModelError, match="hinge: a stop needs the joint's own coordinate, but hinge is driven"):
        mbcomp.simulate(m, t_end=1.0)
