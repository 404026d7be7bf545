"""Which mechanisms conserve their momenta (``assembly/conservation.py``): a sensor fixed to
the world applies no load, so a free-floating body it watches keeps its momentum check; a
real load to the world beside the sensor still ends it."""
import numpy as np
import pytest

import mbcomp
import mbcomp.simulation.postprocess as postprocess
from mbcomp.assembly.conservation import momenta, momentum_conserved
from mbcomp.library import AbsoluteSensor, FreeMotion, RelativeSensor, RigidBody, Spring, World


def floating(sensor=None, spring=False):
    """A body tumbling freely without gravity (an asymmetric inertia, spun near its middle
    axis), watched by a sensor from the world (``"relative"``) or on itself (``"absolute"``);
    ``spring``: also a spring from the world to it."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0.0, 0.0, 0.0)))
    f = m.add("f", FreeMotion(r0=(1.0, 0.2, 0.0), v0=(0.3, 0.2, -0.1), w0=(0.05, 4.0, 0.05)))
    b = m.add("b", RigidBody(m=1.5, r_cm=(0.1, 0.0, 0.05), I=np.diag([0.1, 0.2, 0.3])))
    m.connect(w.frame_b, f.frame_a); m.connect(f.frame_b, b.frame_a)
    if sensor == "relative":
        s = m.add("s", RelativeSensor())
        m.connect(w.frame_b, s.frame_a); m.connect(b.frame_a, s.frame_b)
    elif sensor == "absolute":
        s = m.add("s", AbsoluteSensor())
        m.connect(b.frame_a, s.frame_a)
    if spring:
        k = m.add("k", Spring(c=2.0, s_unstretched=0.5))
        m.connect(w.frame_b, k.frame_a); m.connect(b.frame_a, k.frame_b)
    return m


@pytest.mark.parametrize("sensor", [None, "relative", "absolute"])
def test_a_sensor_loads_nothing_so_the_momenta_stay_watched(sensor):
    assert momentum_conserved(mbcomp.assemble(floating(sensor)))
    assert not momentum_conserved(mbcomp.assemble(floating(sensor, spring=True)))  # the spring does load it


def test_the_run_of_a_watched_floating_body_checks_and_keeps_its_momenta(monkeypatch):
    seen = []

    def spy(P, L, *args):
        seen.append((np.asarray(P), np.asarray(L)))
        return original(P, L, *args)

    original = postprocess.momentum_alarm
    monkeypatch.setattr(postprocess, "momentum_alarm", spy)
    m = floating("relative")
    res = mbcomp.simulate(m, t_end=10.0, n_out=201)
    assert res.success, res.message
    assert len(seen) == 1  # the run's momentum alarm looked at the momenta
    P, L = seen[0]
    assert len(P) > 100
    # what it looked at is constant (no load from the sensor) and is the body's momentum
    assert np.abs(P - P[0]).max() < 1e-6 and np.abs(L - L[0]).max() < 1e-6  # rtol 1e-8 over 10 s
    np.testing.assert_allclose(P[0], 1.5 * (np.array([0.3, 0.2, -0.1]) + np.cross([0.05, 4.0, 0.05], [0.1, 0.0, 0.05])),
                               rtol=1e-12)
    # the sensor measured the body it does not load
    np.testing.assert_allclose(res["s.r_rel.x"], res["b.r.x"], atol=1e-12)


def test_without_drives_the_impulse_work_is_zero_as_evaluated():
    """``impulse_work`` answers 0 without evaluating when nothing is driven; what it skips,
    ``T(u+) - T(u-) + loss`` from the bodies' and rotors' velocities with the loss of ``M``,
    is 0 to roundoff for any speeds (``T(u) = u^T M u / 2``)."""
    from mbcomp.assembly.conservation import impulse_work
    from mbcomp.library import FixedTranslation, Inertia, PointMass, Revolute

    m = mbcomp.Model()
    w = m.add("world", World(g=(0.0, 0.0, -9.81)))
    f = m.add("f", FreeMotion(r0=(1.0, 0.2, 0.0)))
    b = m.add("b", RigidBody(m=1.5, r_cm=(0.1, 0.0, 0.05), I=np.diag([0.1, 0.2, 0.3])))
    j = m.add("j", Revolute(n=(1.0, 0.0, 0.0), phi0=0.4))
    rod = m.add("rod", FixedTranslation(r=(0.0, -0.7, 0.2)))
    bob = m.add("bob", PointMass(m=0.8))
    rotor = m.add("rotor", Inertia(J=0.3))
    m.connect(w.frame_b, f.frame_a); m.connect(f.frame_b, b.frame_a)
    m.connect(b.frame_a, j.frame_a); m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a); m.connect(rotor.flange, j.axis)
    s = mbcomp.assemble(m)
    assert not s.topology.drives and s.nq != s.nu
    rng = np.random.default_rng(3)
    q = s.default_q()
    for _ in range(5):
        u_minus, u_plus = rng.normal(size=s.nu), rng.normal(size=s.nu)
        M = s.evaluate(0.0, q, u_minus).M
        loss = 0.5 * (u_minus @ M @ u_minus - u_plus @ M @ u_plus)
        T_minus = s.energies(s.evaluate(0.0, q, u_minus))[0]
        T_plus = s.energies(s.evaluate(0.0, q, u_plus))[0]
        assert abs(T_plus - T_minus + loss) <= 1e-14 * (T_minus + T_plus)
        assert impulse_work(s, 0.0, q, u_minus, u_plus, loss) == 0.0
