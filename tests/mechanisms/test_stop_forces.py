"""An engaged rigid stop's force in the result (issue 22): the stop's column, the hinge's
reaction and the energy balance at output times where the stop holds the joint.

A rod (mass m, centre at l from a horizontal hinge, axis z; gravity -y) falls from
phi0 onto its lower stop at phi = a with e = 0 and rests there: the stop must hold the
gravity torque m g l cos(a), the hinge carries the weight.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import Prismatic, PointMass, Revolute, RigidBody, RotationalDamper, World

M, L, G, A = 2.0, 0.7, 9.81, 0.3


def _pendulum(damping=0.0):
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, -G, 0)))
    hinge = model.add("hinge", Revolute(n=(0, 0, 1), phi0=A + 0.6, w0=0.0, limits=(A, 2.5), restitution=0.0))
    rod = model.add("rod", RigidBody(m=M, r_cm=(L, 0.0, 0.0), I=np.diag([0.01, 0.1, 0.1])))
    model.connect(world.frame_b, hinge.frame_a)
    model.connect(hinge.frame_b, rod.frame_a)
    if damping:  # a damper makes the run keep an energy balance (energy.balance)
        d = model.add("damper", RotationalDamper(d=damping))
        model.connect(d.flange_a, hinge.support)
        model.connect(d.flange_b, hinge.axis)
    return model


@pytest.fixture(scope="module")
def resting():
    res = mbcomp.simulate(_pendulum(0.05), t_end=2.0, n_out=401, rtol=1e-10, atol=1e-12)
    assert res.status == "success", res.message
    impact = [e.time for e in res.events if e.kind == "impact"][0]
    return res, impact


def test_stop_torque_is_the_gravity_torque_while_engaged(resting):
    res, t_hit = resting
    after, before = res.time > t_hit + 1e-9, res.time < t_hit - 1e-9
    assert after.sum() > 100 and before.sum() > 10
    np.testing.assert_allclose(res["hinge.phi"][after], A, atol=1e-9)
    np.testing.assert_allclose(res["hinge.stop"][after], M * G * L * np.cos(A), rtol=0, atol=1e-9)
    assert np.all(res["hinge.stop"][before] == 0.0)
    assert res.units["hinge.stop"] == "N m"
    # the torque through the hinge about its axis is the stop's; the rod does not accelerate
    np.testing.assert_allclose(res["hinge.tau.z"][after], M * G * L * np.cos(A), atol=1e-9)
    np.testing.assert_allclose(res["hinge.w.der"][after], 0.0, atol=1e-9)


def test_hinge_carries_the_weight_while_engaged(resting):
    res, t_hit = resting
    after = res.time > t_hit + 1e-9
    phi = res["hinge.phi"][after]
    fb = np.stack([res[f"hinge.f.{ax}"][after] for ax in "xyz"], -1)   # frame_b coordinates
    c, s = np.cos(phi), np.sin(phi)
    f_world = np.stack([c * fb[:, 0] - s * fb[:, 1], s * fb[:, 0] + c * fb[:, 1], fb[:, 2]], -1)
    np.testing.assert_allclose(f_world, np.tile([0.0, M * G, 0.0], (after.sum(), 1)), atol=1e-9)


def test_energy_balance_through_the_engaged_phase(resting):
    """Resting on the stop nothing does work: the balance stays where the impact left it
    (its step there, 2e-4 J, is the damper power's Simpson quadrature across the jump of w
    at the impact, which energy.impacts does not hold; 1e-9 J before it)."""
    res, t_hit = resting
    before = res.time < t_hit - 1e-9
    settled = np.flatnonzero(res.time > t_hit)[2:]   # past the quadrature stencil over the impact
    assert np.max(np.abs(res["energy.balance"][before])) < 1e-8
    assert np.ptp(res["energy.balance"][settled]) < 1e-9
    assert np.max(np.abs(res["energy.balance"])) < 1e-4 * res["energy.impacts"][-1]


def test_upper_stop_pushes_back_and_slider_stop_is_a_force():
    """A slider falling onto its upper stop (s <= hi, gravity along +s): the push is
    positive (away from the limit), m g, in N."""
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, -G, 0)))
    s = model.add("s", Prismatic(n=(0, -1, 0), s0=0.0, v0=0.0, limits=(-1.0, 0.2), restitution=0.0))
    b = model.add("b", PointMass(m=M))
    model.connect(world.frame_b, s.frame_a)
    model.connect(s.frame_b, b.frame_a)
    res = mbcomp.simulate(model, t_end=1.0, n_out=101, rtol=1e-10, atol=1e-12)
    t_hit = np.sqrt(2 * 0.2 / G)
    after, before = res.time > t_hit + 1e-6, res.time < t_hit - 1e-6
    np.testing.assert_allclose(res["s.stop"][after], M * G, atol=1e-9)
    assert np.all(res["s.stop"][before] == 0.0) and res.units["s.stop"] == "N"
    np.testing.assert_allclose(res["s.f.y"][after], M * G, atol=1e-9)   # frame_b is not rotated


def test_the_engaged_columns_take_the_base_evaluation_inside_the_modes():
    """The columns of an engaged output read the assembled system's evaluation from inside the
    mode's (``evaluation_within``: the held row appended, a mode force added, each wrapping
    the same evaluator): the same numbers as evaluating the assembled system again, and the
    mode's own row and force on top of them; a system that does not wrap it gives None."""
    from mbcomp.hybrid.active import ForceEvaluator, evaluation_within, mode_system

    system = mbcomp.assemble(_pendulum(0.05))
    held = mode_system(system, {"hinge": "lo"})
    pushed = held.with_evaluator(lambda new: ForceEvaluator(held.evaluator, [(0, 1.5)]))
    q, u = np.array([A + 1e-3]), np.array([-0.4])
    plain = system.evaluate(0.0, q, u)
    for sysm in (held, pushed):
        ev = sysm.evaluate(0.0, q, u)
        inner = evaluation_within(sysm, ev, system)
        for name in ("M", "f", "Phi", "C"):
            np.testing.assert_array_equal(getattr(inner, name), getattr(plain, name))
        assert ev.Phi.tolist() == [float(q[0] - A)]  # the stop's row, phi - lo, after the system's (none)
    assert pushed.evaluate(0.0, q, u).f[0] == plain.f[0] + 1.5  # the mode force on the joint's speed
    assert evaluation_within(system.with_evaluator(None), plain, system) is None
