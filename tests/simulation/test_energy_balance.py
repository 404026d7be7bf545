"""Force elements and actuators report what they do; the energy balance closes for driven
and damped mechanisms; the momenta are columns (issue 18, item 1)."""
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.library import (FixedTranslation, FreeMotion, PointMass, PrescribedMotion, Revolute, RigidBody,
                            RotationalDamper, RotationalSpringDamper, SpringDamper, Torque, World)

BACKENDS = ["numeric", "auto"]


def rotor(**elements):
    """A disk (I = 0.5 kg m^2) on a hinge about z, no gravity, with the given flange elements
    on its axis."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), w0=elements.pop("w0", 0.0)))
    disk = m.add("disk", RigidBody(m=1.0, I=np.diag([0.25, 0.25, 0.5])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, disk.frame_a)
    for name, comp in elements.items():
        m.add(name, comp)
        if "flange_a" in comp.ports():
            m.connect(j.support, comp.flange_a)
        m.connect(j.axis, comp.flange_b)
    return m


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_constant_torque_reports_its_torque_power_and_work(backend):
    tau0, I = 0.3, 0.5
    res = mbcomp.simulate(rotor(motor=Torque(tau=tau0)), t_end=2.0, n_out=201, backend=backend)
    t, w = res.time, res["j.w"]
    np.testing.assert_allclose(res["motor.tau"], tau0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(res["motor.power"], tau0 * w, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res["energy.work"], tau0 ** 2 * t ** 2 / (2 * I), rtol=1e-9, atol=1e-12)  # tau phi
    assert np.abs(res["energy.dissipated"]).max() == 0.0
    assert np.abs(res["energy.balance"]).max() < 1e-9


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_damper_dissipates_the_kinetic_energy_it_takes(backend):
    d, I, w0 = 0.2, 0.5, 3.0
    res = mbcomp.simulate(rotor(w0=w0, damper=RotationalDamper(d=d)), t_end=3.0, n_out=601, backend=backend)
    w_exact = w0 * np.exp(-d / I * res.time)
    np.testing.assert_allclose(res["j.w"], w_exact, rtol=1e-7)
    np.testing.assert_allclose(res["damper.tau"], d * res["j.w"], rtol=1e-12)   # torque opposing w > 0
    np.testing.assert_allclose(res["damper.power"], -d * res["j.w"] ** 2, rtol=1e-12)
    np.testing.assert_allclose(res["energy.dissipated"], 0.5 * I * (w0 ** 2 - w_exact ** 2), rtol=1e-6, atol=1e-9)
    assert np.abs(res["energy.work"]).max() == 0.0
    assert np.abs(res["energy.balance"]).max() < 1e-7 * 0.5 * I * w0 ** 2


def damped_driven_pendulum(c=3.0, d=0.4):
    """A 1 m, 1 kg pendulum driven by a torque 0.5 sin(2 t) (``motor``), with a rotational
    spring-damper ``sd`` (c in N m/rad, d in N m s/rad) on its hinge unless ``d`` is None."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=lambda t, phi, w: 0.5 * np.sin(2.0 * t)))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    if d is not None:
        sd = m.add("sd", RotationalSpringDamper(c=c, d=d))
        m.connect(j.support, sd.flange_a)
        m.connect(j.axis, sd.flange_b)
    return m


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_balance_of_a_damped_driven_pendulum_closes_and_splits_work_from_dissipation(backend):
    res = mbcomp.simulate(damped_driven_pendulum(), t_end=5.0, n_out=2001, rtol=1e-10, atol=1e-12, backend=backend)
    t, w, phi = res.time, res["j.w"], res["j.phi"]
    # the spring-damper's dissipation is the damper part alone: its spring's power is its potential's rate
    from scipy.integrate import cumulative_simpson
    # (the potential's rate is a central difference over 1e-6 s: rounding of eps V / 1e-6 s per point)
    floor = 1e-10 * np.abs(res["energy.total"]).max()
    np.testing.assert_allclose(res["energy.dissipated"], cumulative_simpson(0.4 * w ** 2, x=t, initial=0.0),
                               rtol=1e-9, atol=floor)
    np.testing.assert_allclose(res["energy.work"], cumulative_simpson(0.5 * np.sin(2 * t) * w, x=t, initial=0.0),
                               rtol=1e-9, atol=floor)
    np.testing.assert_allclose(res["sd.potential"], 0.5 * 3.0 * phi ** 2, rtol=1e-12)
    np.testing.assert_allclose(res["sd.phi_rel"], phi, rtol=0, atol=0)
    scale = np.abs(res["energy.total"]).max()
    assert np.abs(res["energy.balance"]).max() < 1e-8 * scale
    assert res["energy.dissipated"][-1] > 0.1 * scale        # the balance is not trivially small
    assert np.abs(res["energy.total"] - res["energy.total"][0]).max() > 0.1 * scale


@pytest.mark.parametrize("method, kwargs", [("dop853", {}), ("radau5", {"index": 3}), ("genalpha", {"h": 0.01}),
                                            ("dop853", {"formulation": "dalembert"})])
def test_a_drive_reports_its_power_and_the_balance_counts_its_work(method, kwargs):
    """Every motion prescribed (no state to integrate): each method gives the kinematics."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1)))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=2.0))
    drive = m.add("drive", PrescribedMotion(s="1.2*t"))  # constant speed: the drive lifts and lowers the bob
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, drive.flange_b)
    res = mbcomp.simulate(m, t_end=3.0, n_out=1501, method=method, **kwargs)
    assert res.status == "success" and len(res.time) == 1501
    phi = 1.2 * res.time
    # quasi-static at constant speed: the drive's torque balances gravity, m g l cos(phi)
    np.testing.assert_allclose(res["drive.tau"], 2.0 * 9.81 * np.cos(phi), rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(res["drive.power"], res["drive.tau"] * 1.2, rtol=1e-12)
    np.testing.assert_allclose(res["energy.work"], 2.0 * 9.81 * np.sin(phi), rtol=1e-8, atol=1e-8)  # = its potential
    assert np.abs(res["energy.balance"]).max() < 1e-8


def test_a_line_spring_reports_tension_length_and_power():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    free = m.add("free", FreeMotion(r0=(0.3, 0.1, -1.2), v0=(0.2, -0.5, 0.1)))
    ball = m.add("ball", RigidBody(m=0.7, I=np.diag([1e-3, 1e-3, 1e-3])))
    sd = m.add("sd", SpringDamper(c=40.0, d=0.3, s_unstretched=1.0))
    m.connect(w.frame_b, free.frame_a)
    m.connect(free.frame_b, ball.frame_a)
    m.connect(w.frame_b, sd.frame_a)
    m.connect(ball.frame_a, sd.frame_b)
    res = mbcomp.simulate(m, t_end=2.0, n_out=801, rtol=1e-10, atol=1e-12)
    r = np.stack([res[f"ball.r.{ax}"] for ax in "xyz"], -1)
    v = np.stack([res[f"ball.v.{ax}"] for ax in "xyz"], -1)
    L = np.linalg.norm(r, axis=1)
    Ldot = np.einsum("ij,ij->i", r, v) / L
    np.testing.assert_allclose(res["sd.length"], L, rtol=1e-12)
    np.testing.assert_allclose(res["sd.length_rate"], Ldot, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res["sd.f"], 40.0 * (L - 1.0) + 0.3 * Ldot, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res["sd.power"], -res["sd.f"] * Ldot, rtol=1e-9, atol=1e-12)
    assert [res.units[n] for n in ("sd.f", "sd.length", "sd.power", "energy.work", "momentum.x")] == \
        ["N", "m", "W", "J", "kg m/s"]
    assert np.abs(res["energy.balance"]).max() < 1e-8 * np.abs(res["energy.total"]).max()


def test_momenta_of_two_free_bodies_on_a_spring_are_constant_and_equal_the_start():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    fa = m.add("fa", FreeMotion(r0=(0, 0, 0), v0=(1.0, 0.5, 0), w0=(0, 0, 2.0)))
    fb = m.add("fb", FreeMotion(r0=(1.5, 0.2, 0.1), v0=(-0.2, 0.0, 0.3)))
    a = m.add("a", RigidBody(m=2.0, r_cm=(0.1, 0, 0), I=np.diag([0.1, 0.2, 0.3])))
    b = m.add("b", RigidBody(m=1.0, I=np.diag([0.05, 0.05, 0.05])))
    k = m.add("k", SpringDamper(c=30.0, d=0.5, s_unstretched=1.0))
    m.connect(w.frame_b, fa.frame_a)
    m.connect(fa.frame_b, a.frame_a)
    m.connect(w.frame_b, fb.frame_a)
    m.connect(fb.frame_b, b.frame_a)
    m.connect(a.frame_a, k.frame_a)
    m.connect(b.frame_a, k.frame_b)
    res = mbcomp.simulate(m, t_end=3.0, n_out=301, rtol=1e-10, atol=1e-12)
    # at the start: m v of each body's centre (a's centre moves with w x r_cm too)
    P0 = 2.0 * (np.array([1.0, 0.5, 0]) + np.cross([0, 0, 2.0], [0.1, 0, 0])) + 1.0 * np.array([-0.2, 0.0, 0.3])
    for j, ax in enumerate("xyz"):
        np.testing.assert_allclose(res[f"momentum.{ax}"], P0[j], rtol=0, atol=1e-9)
        L = res[f"angular_momentum.{ax}"]
        assert np.abs(L - L[0]).max() < 1e-9
    assert res["energy.dissipated"][-1] > 1e-3          # the damper worked, yet the momenta stayed


def test_per_body_momenta_on_request_sum_to_the_total():
    m = damped_driven_pendulum()
    res = mbcomp.simulate(m, t_end=1.0, n_out=11, body_momenta=True)
    np.testing.assert_allclose(res["bob.momentum.x"], res["momentum.x"], rtol=1e-15)
    np.testing.assert_allclose(res["bob.momentum.y"], 1.0 * res["bob.v.y"], rtol=1e-12)
    assert "momentum.x" in mbcomp.simulate(m, t_end=1.0, n_out=11) and \
        "bob.momentum.x" not in mbcomp.simulate(m, t_end=1.0, n_out=11)


def test_a_model_without_world_says_no_gravity_acts():
    m = mbcomp.Model()
    m.add("ball", RigidBody(m=1.0, I=np.diag([0.1, 0.1, 0.1])), free=True)
    res = mbcomp.simulate(m, t_end=1.0)
    assert "the model has no World, so there is no gravity" in res.message
    assert np.abs(res["ball.r.z"]).max() == 0.0       # and indeed nothing moves it


def test_a_loop_left_open_beyond_the_tolerance_is_a_warning_with_the_fix():
    m = mbcomp.load_model_file("models/slider_crank.py").build()
    with pytest.warns(RuntimeWarning, match="position constraints are open by") as rec:
        res = mbcomp.simulate(m, t_end=10.0, rtol=1e-6, atol=1e-8, stabilization="none")
    text = next(str(w.message) for w in rec if "position constraints are open by" in str(w.message))
    assert "stabilization='projection'" in text and text.split("mbcomp: ")[1] in res.message
    assert float(text.split("open by ")[1].split()[0]) == pytest.approx(res["residual.position"][-1], rel=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)   # closed loops: no warning
        mbcomp.simulate(m, t_end=10.0, rtol=1e-6, atol=1e-8, stabilization="projection")


def driven_pendulum():
    """Undamped: integration errors in its energy accumulate (nothing dissipates them)."""
    return damped_driven_pendulum(d=None)


def test_a_balance_off_by_more_than_the_tolerance_promises_raises_the_alarm():
    loose = mbcomp.simulate(driven_pendulum(), t_end=500.0, n_out=50001, rtol=1e-5, atol=1e-7, method="RK23")
    assert loose.status == "inaccurate" and "the energy balance is off by" in loose.message
    assert "rerun with rtol=1e-08" in loose.message
    tight = mbcomp.simulate(driven_pendulum(), t_end=500.0, n_out=50001, rtol=1e-10, atol=1e-12)
    assert tight.status == "success" and np.abs(tight["energy.balance"]).max() < 1e-6


def test_a_grid_that_cannot_resolve_the_power_raises_no_alarm():
    """61 points over 500 s of a 2 rad/s motion: the balance is off by the quadrature, not by
    the integration, and the run says nothing false."""
    coarse = mbcomp.simulate(driven_pendulum(), t_end=500.0, n_out=61, rtol=1e-10, atol=1e-12)
    assert np.abs(coarse["energy.balance"]).max() > 1.0 and coarse.status == "success"
    assert "cannot be judged on this output grid" in coarse.message and "n_out" in coarse.message


def test_a_world_force_reports_its_force_and_the_work_it_does():
    """A constant push F on a free body without gravity: its columns are F, its power F.v, the
    work F.(r - r0) = the kinetic energy gained."""
    from mbcomp.library import WorldForce

    m = mbcomp.Model()
    m.add("world", World(g=(0, 0, 0)))
    body = m.add("body", RigidBody(m=2.0, I=np.eye(3) * 0.1), free=True)
    push = m.add("push", WorldForce(f=(3.0, -1.0, 0.5)))
    m.connect(body.frame_a, push.frame_b)
    res = mbcomp.simulate(m, t_end=2.0, n_out=201, rtol=1e-10, atol=1e-12)
    F = np.array([3.0, -1.0, 0.5])
    assert [float(res[f"push.f.{a}"][-1]) for a in "xyz"] == F.tolist()
    assert res.units["push.f.x"] == "N"
    r = np.stack([res[f"body.r.{a}"] for a in "xyz"], -1)
    np.testing.assert_allclose(res["energy.work"], (r - r[0]) @ F, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res["energy.work"], res["energy.kinetic"], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("n_out", [11, 301])  # the numeric points and the C output program over the grid
def test_the_output_programs_momenta_equal_the_sums_over_the_bodies_columns(n_out):
    """The totals come from the output program (``MultibodySystem.momenta`` at each point);
    ``momentum_columns`` sums the same from the bodies' pose, twist and mass columns in
    numpy: two formulations of p = sum m v_c and h = sum (r_c x m v_c + R I R^T w)."""
    from mbcomp.simulation.balance import momentum_columns

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j1 = m.add("j1", Revolute(n=(0, 0, 1), phi0=0.4, w0=1.0))
    a = m.add("a", RigidBody(m=2.0, r_cm=(0.3, 0.05, 0.0), I=np.diag([0.1, 0.2, 0.3])))
    j2 = m.add("j2", Revolute(n=(0.3, 0.0, 1.0), phi0=-0.2, w0=2.0))
    rod = m.add("rod", FixedTranslation(r=(0.6, 0.0, 0.1)))
    b = m.add("b", RigidBody(m=1.5, r_cm=(0.0, 0.2, -0.1), I=np.diag([0.05, 0.08, 0.06])))
    m.connect(w.frame_b, j1.frame_a); m.connect(j1.frame_b, a.frame_a); m.connect(a.frame_a, rod.frame_a)
    m.connect(rod.frame_b, j2.frame_a); m.connect(j2.frame_b, b.frame_a)
    res = mbcomp.simulate(m, t_end=1.0, n_out=n_out)
    series = {k: res[k] for k in res.names if k.split(".")[0] in ("a", "b")}
    sums = momentum_columns(res.system, series)
    assert set(sums) == {f"{k}.{ax}" for k in ("momentum", "angular_momentum") for ax in "xyz"}
    scale = max(np.abs(res[k]).max() for k in sums)
    assert scale > 1.0  # the test has something to compare
    for k, v in sums.items():
        np.testing.assert_allclose(res[k], v, rtol=0, atol=1e-12 * scale)
