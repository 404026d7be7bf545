"""No false alarm (issue 30, item 4): a right answer never ends "inaccurate" or warns.

Each case is a correct run that used to ring an alarm, checked against its closed form (or an
invariant), on both formulations and two integrators, next to the real situation the alarm is
for, which must still ring.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import PointMass, PrescribedMotion, Prismatic, World
from mbcomp.library.friction import SlidingFriction
from mbcomp.simulation.accuracy import between_events

G = 9.81
TOL = dict(rtol=1e-10, atol=1e-12)
#: (formulation, method): both formulations, a compiled explicit method and a second integrator
RUNS = [("lagrange", "dop853"), ("lagrange", "radau5"), ("dalembert", "dop853"), ("dalembert", "DOP853")]


# --- a drive carrying a joint with Coulomb friction ---------------------------------------------
M_BLOCK, M_CART, MU_S, MU_K = 2.0, 1.0, 0.3, 0.25


def cart_and_block(law, block_joint):
    """A cart (``M_CART``) on a prismatic joint along x driven at ``s = law`` carrying a block
    (``M_BLOCK``) on ``block_joint`` (a prismatic joint along the same axis); gravity -z."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    a = m.add("a", Prismatic(n=(1, 0, 0)))
    cart = m.add("cart", PointMass(m=M_CART))
    s = m.add("s", block_joint)
    b = m.add("b", PointMass(m=M_BLOCK))
    d = m.add("drive", PrescribedMotion(s=law))
    m.connect(w.frame_b, a.frame_a)
    m.connect(a.axis, d.flange_b)
    m.connect(a.frame_b, cart.frame_a)
    m.connect(a.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def carried_block(law="t**3"):
    """The cart driven at ``s = t^3`` (so ``a = 6 t``) carrying the block on a joint with
    Coulomb friction (normal force ``M_BLOCK g``)."""
    return cart_and_block(law, Prismatic(n=(1, 0, 0), friction=SlidingFriction(MU_S, MU_K, normal=M_BLOCK * G)))


@pytest.mark.parametrize("formulation,method", RUNS)
def test_a_drive_carries_the_friction_of_the_joint_it_moves(formulation, method):
    """The block rides stuck until the cart's acceleration 6 t needs more than the static
    friction (t_b = mu_s g / 6), then slides back on the cart: the drive's force is
    (M_cart + M_block) 6 t before, M_cart 6 t + mu_k M_block g after (it was 0 for a massless
    cart: the friction was in no reaction), and the drive's work balances the energy."""
    r = mbcomp.simulate(carried_block(), t_end=1.0, n_out=201, formulation=formulation, method=method, **TOL)
    assert r.status == "success", r.message
    t_b = MU_S * G / 6.0
    assert [e.name for e in r.events] == ["break-"]
    assert abs(r.events[0].time - t_b) < 1e-8
    t, f = r.time, r["drive.f"]
    stuck, sliding = t < t_b - 1e-6, t > t_b + 1e-6
    assert np.max(np.abs(f[stuck] - (M_CART + M_BLOCK) * 6.0 * t[stuck])) < 1e-7
    assert np.max(np.abs(f[sliding] - (M_CART * 6.0 * t[sliding] + MU_K * M_BLOCK * G))) < 1e-7
    # the drive's work, int f v dt with v = 3 t^2, feeds the kinetic energy and the friction
    c = MU_K * M_BLOCK * G
    work = 13.5 * t_b ** 4 + 4.5 * (1.0 - t_b ** 4) + c * (1.0 - t_b ** 3)
    # (the output grid's quadrature across the break, a power jump of c v(t_b) = 3.5 W in a 5 ms
    # interval, is the only error: below 3.5 W x 5 ms)
    assert abs(r["energy.work"][-1] - work) < 3.5 * 5e-3
    assert np.max(np.abs(between_events(r["energy.balance"], r.time, [t_b]))) < 1e-6 * work


# --- a driven mechanism hitting a joint stop ----------------------------------------------------
A_CART, E_STOP, LO = 4.0, 0.5, -0.1


def cart_with_stop():
    """The cart (``M_CART``) driven at ``s = A t^2 / 2`` carrying a block (``M_BLOCK``) free on a
    prismatic joint along the drive, between stops at +-0.1 m with restitution ``E_STOP``."""
    return cart_and_block(f"{A_CART / 2}*t**2", Prismatic(n=(1, 0, 0), limits=(LO, -LO), restitution=E_STOP))


@pytest.mark.parametrize("formulation,method", RUNS)
def test_impacts_on_a_driven_mechanism_close_the_energy_balance(formulation, method):
    """The block falls back on the cart (relative acceleration -A) onto the stop at
    t1 = sqrt(2 |lo| / A) and bounces as a ball on a floor (impacts at t1 + 2 e t1 (1 - e^k)
    / (1 - e), settling at t1 (1 + e) / (1 - e)). The impact takes M v^2 (1 - e^2) / 2 of the
    relative speed v, and the drive, which keeps the cart's speed A t through it, does the
    work A t M (1 + e) v with its impulse: counted, the balance closes and the run is a success
    (the drive's impulses were counted as balance error, with the advice rtol=1e-13)."""
    r = mbcomp.simulate(cart_with_stop(), t_end=1.0, n_out=201, formulation=formulation, method=method, **TOL)
    assert r.status == "success", r.message
    t1 = np.sqrt(2.0 * abs(LO) / A_CART)
    impacts = [e for e in r.events if e.kind == "impact"]
    k = np.arange(3)
    assert np.allclose([e.time for e in impacts[:3]], t1 + 2 * t1 * E_STOP * (1 - E_STOP ** k) / (1 - E_STOP), atol=1e-8)
    v = A_CART * t1 * E_STOP ** k                    # the relative speeds at the first impacts
    assert np.allclose([e.detail["energy_loss"] for e in impacts[:3]], 0.5 * M_BLOCK * v ** 2 * (1 - E_STOP ** 2),
                       rtol=1e-7)
    t_k = np.array([e.time for e in impacts[:3]])
    assert np.allclose([e.detail["drive_work"] for e in impacts[:3]], A_CART * t_k * M_BLOCK * (1 + E_STOP) * v,
                       rtol=1e-7)
    # it settles once a rebound would rise less than the tolerance: just before the accumulation
    assert r.events[-1].kind == "rest" and 0.0 < t1 * (1 + E_STOP) / (1 - E_STOP) - r.events[-1].time < 1e-4
    judged = between_events(r["energy.balance"], r.time, [e.time for e in r.events])
    assert np.max(np.abs(judged)) < 1e-6 * r["energy.work"][-1]


def torqued_into_a_stop(e):
    """A 1 kg point mass on a 1 m arm (J = 1 kg m^2, no gravity) turned from rest by a constant
    1 N m torque into a stop at 0.5 rad with restitution ``e``."""
    from mbcomp.library import FixedTranslation, Revolute, Torque

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("j", Revolute(phi0=0.0, w0=0.0, limits=(-0.5, 0.5), restitution=e))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=lambda t, phi, w: 1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    return m


@pytest.mark.parametrize("e", [0.5, 0.0])
@pytest.mark.parametrize("formulation,method", RUNS)
def test_a_torque_driving_into_a_stop_closes_the_energy_balance(formulation, method, e):
    """phi = t^2 / 2 reaches the stop at t = 1 s with 1 rad/s; each rebound e w returns after
    2 e w s, so the impacts fall at 1, 1 + 2e, 1 + 2e + 2e^2, ... and settle at (1 + e) / (1 - e)
    s, the torque's work 0.5 J all taken by the impacts. The balance (impacts counted) closes
    between the events: success (the grid's quadrature of the power jumping at each impact
    was judged as drift, 0.49 J, with the advice rtol=1e-13)."""
    r = mbcomp.simulate(torqued_into_a_stop(e), t_end=4.0, n_out=401, formulation=formulation, method=method,
                        **TOL)
    assert r.status == "success", r.message
    impacts = [ev.time for ev in r.events if ev.kind == "impact"]
    k = np.arange(min(3, len(impacts)))
    assert np.allclose(impacts[:len(k)], 1 + 2 * e * (1 - e ** k) / (1 - e), atol=1e-8)
    assert r.events[-1].kind in ("rest", "engage") and abs(r.events[-1].time - (1 + e) / (1 - e)) < 1e-3
    assert r["energy.impacts"][-1] == pytest.approx(0.5, rel=1e-6)
    assert abs(r["j.phi"][-1] - 0.5) < 1e-9 and abs(r["j.w"][-1]) < 1e-9
    # the work column is the output grid's quadrature of the power, which jumps at each impact:
    # off there by the jump times an interval, and exact between the events
    judged = between_events(r["energy.balance"], r.time, [ev.time for ev in r.events])
    assert np.max(np.abs(judged)) < 1e-6 * 0.5


# --- a nearly motionless mechanism ------------------------------------------------------------
def pendulum(phi0, L=1.0):
    """A point mass (1 kg) on a massless rod of length ``L`` on a hinge, gravity -y."""
    from mbcomp.library import FixedTranslation, Revolute

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=phi0))
    rod = m.add("rod", FixedTranslation(r=(0, -L, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def resting_ball(m=0.5, r=0.3, z0=0.1 + 0.2):
    """A ball (a point mass with a contact radius ``r``) resting on a floor: the unilateral
    contact closed from the start, its centre at ``z0`` (0.30000000000000004: a sum's rounding,
    moved onto the floor at the start)."""
    from mbcomp.library import PlaneContact
    from mbcomp.modeling.free_joint import FreeTranslation

    model = mbcomp.Model()
    w = model.add("world", World(g=(0, 0, -G)))
    free = model.add("free", FreeTranslation(r0=(0.0, 0.0, z0), v0=(0.0, 0.0, 0.0)))
    ball = model.add("ball", PointMass(m=m))
    floor = model.add("floor", PlaneContact(r=r, unilateral=True, restitution=0.5))
    model.connect(w.frame_b, free.frame_a)
    model.connect(free.frame_b, ball.frame_a)
    model.connect(w.frame_b, floor.frame_a)
    model.connect(floor.frame_b, ball.frame_a)
    return model


@pytest.mark.parametrize("formulation,method", RUNS)
def test_a_nearly_still_pendulum_is_no_false_alarm(formulation, method):
    """A pendulum swinging 1e-7 rad exchanges 1e-13 J of its 9.81 J of potential energy: the
    energy's own rounding (2e-15 J) was 2 % of it, and the run ended "inaccurate". The motion is
    the small-angle closed form phi0 cos(sqrt(g/L) t)."""
    phi0 = 1e-7
    r = mbcomp.simulate(pendulum(phi0), t_end=10.0, n_out=201, formulation=formulation, method=method, **TOL)
    assert r.status == "success", r.message
    assert np.max(np.abs(r["j.phi"] - phi0 * np.cos(np.sqrt(G) * r.time))) < 1e-3 * phi0


@pytest.mark.parametrize("formulation,method", RUNS)
def test_a_ball_at_rest_on_a_floor_is_no_false_alarm(formulation, method):
    """A ball resting on a floor exchanges no energy; its height wanders within the tolerance,
    m g (atol + rtol z) = 1.5e-10 J of energy at rtol 1e-10 (5e-11 J on Lagrange's dop853):
    that was 40 % of the "energy the motion exchanges" and rang the alarm. It stays at z = r,
    pressed with m g."""
    r = mbcomp.simulate(resting_ball(), t_end=2.0, formulation=formulation, method=method, **TOL)
    assert r.status == "success", r.message
    assert np.max(np.abs(r["ball.r.z"] - 0.3)) < 1e-9 and np.max(np.abs(r["floor.N"] - 0.5 * G)) < 1e-6


@pytest.mark.parametrize("formulation", ["lagrange", "dalembert"])
def test_a_small_motion_integrated_badly_still_rings(formulation):
    """The same scaling must not hide a real error: a pendulum swinging 1e-6 rad integrated by
    RK23 at rtol 1e-4 for 200 s loses 5 % of the 1e-11 J it exchanges, far above the rounding
    and what the tolerances leave open: "inaccurate"."""
    r = mbcomp.simulate(pendulum(1e-6), t_end=200.0, formulation=formulation, method="RK23", rtol=1e-4, atol=1e-14)
    assert r.status == "inaccurate" and "total energy drifted" in r.message


# --- a stiff mass ratio is no massless motion ------------------------------------------------
def sliders(m_heavy, m_light, x=10.0):
    """A slider along x (``m_heavy``) 10 m from the origin carrying a slider along y
    (``m_light``), gravity -y: the light one falls freely, the heavy one stays."""
    from mbcomp.library import FixedTranslation

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    off = m.add("off", FixedTranslation(r=(x, 0, 0)))
    j1 = m.add("j1", Prismatic(n=(1, 0, 0)))
    b1 = m.add("b1", PointMass(m=m_heavy))
    j2 = m.add("j2", Prismatic(n=(0, 1, 0)))
    b2 = m.add("b2", PointMass(m=m_light))
    m.connect(w.frame_b, off.frame_a)
    m.connect(off.frame_b, j1.frame_a)
    m.connect(j1.frame_b, b1.frame_a)
    m.connect(j1.frame_b, j2.frame_a)
    m.connect(j2.frame_b, b2.frame_a)
    return m


@pytest.mark.parametrize("formulation,method", RUNS)
def test_a_1e10_mass_ratio_is_called_ill_conditioned_not_massless(formulation, method):
    """1e10 kg and 1 kg 10 m from the origin: the roundoff scale took the heavy body's m |r|^2
    (1e12) although nothing turns, and the 1 kg motion was "massless". It is a stiff mass ratio:
    a warning saying so, and the run gives the free fall y = -g t^2 / 2."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = mbcomp.simulate(sliders(1e10, 1.0), t_end=1.0, formulation=formulation, method=method, **TOL)
    texts = [str(w.message) for w in caught]
    assert any("ill-conditioned" in x and "mass ratio 1e+10" in x for x in texts), texts
    assert not any("massless" in x for x in texts + [r.message])
    assert r.status == "success", r.message
    assert np.max(np.abs(r["j2.s"] + 0.5 * G * r.time ** 2)) < 1e-6 and np.max(np.abs(r["j1.s"])) < 1e-9


def test_a_truly_massless_motion_is_still_an_error():
    """The same sliders with the light one massless: its motion has no inertia at all."""
    from mbcomp.errors import InitializationError

    with pytest.raises(InitializationError, match=r"massless(.|\n)*j2\.v: this motion carries no mass"):
        mbcomp.simulate(sliders(1e10, 0.0), t_end=0.1)


# --- warnings on correct runs ----------------------------------------------------------------
@pytest.mark.parametrize("formulation", ["lagrange", "dalembert"])
@pytest.mark.parametrize("method", ["RK23", "RK45"])
def test_a_plain_pendulum_at_a_tight_tolerance_is_no_law_with_a_kink(formulation, method):
    """RK23 at rtol 1e-9 steps a pendulum at h |lambda| = 2e-3: what a third-order method needs
    for a smooth motion at that tolerance (rtol^(1/4) = 5.6e-3), not a creep. It was told "a
    law with a kink or a discontinuity makes the integrator creep" (there is no law)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        r = mbcomp.simulate(pendulum(1.0), t_end=30.0, formulation=formulation, method=method, rtol=1e-9,
                            atol=1e-11, max_steps=3000)
    assert r.status in ("budget", "success") and "kink" not in r.message
    # the motion is right where it got: the energy of the swing is kept to 100 rtol of its 5.3 J
    assert np.max(np.abs(r["energy.total"] - r["energy.total"][0])) < 100 * 1e-9 * 5.3


def square_wave_torque():
    """The pendulum with a torque switching between 0 and 0.5 N m every 2.5 ms (a law in t
    with a jump every 2.5 ms: the integrator steps onto each)."""
    from mbcomp.library import Torque

    m = pendulum(1.0)
    tq = m.add("tq", Torque(tau=lambda t, phi, w: 0.5 * (np.floor(400.0 * t) % 2.0)))
    m.connect(m["j"].axis, tq.flange_b)
    return m


@pytest.mark.parametrize("formulation", ["lagrange", "dalembert"])
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_a_law_with_jumps_in_time_still_gets_the_creep_hint(formulation, method):
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = mbcomp.simulate(square_wave_torque(), t_end=30.0, formulation=formulation, method=method, rtol=1e-9,
                            atol=1e-11, max_steps=1000)  # the hint rings from ~600 steps on
    assert r.status == "budget" and "a law with a kink or a discontinuity" in r.stats["stiffness_hint"]
    assert "laws in tq" in r.stats["stiffness_hint"] and any("kink" in str(w.message) for w in caught)


@pytest.mark.parametrize("formulation,method", [("lagrange", "dop853"), ("dalembert", "DOP853")])
def test_an_open_contact_is_not_called_redundant_rows(formulation, method):
    """A ball starting in the air (its floor contact open, models/bouncing_ball.py) has the
    free point's 3 DOF against Gruebler's 6 - 3 - 1 = 2: the excess is the open contact's row,
    not in force -- the summary said "1 constraint rows are redundant, e.g. a planar loop".
    A planar four-bar closed by a spatial joint still has its 3 redundant rows said."""
    r = mbcomp.simulate(mbcomp.load_model_file("models/bouncing_ball.py").build(), t_end=0.5,
                        formulation=formulation, method=method)
    line = next(x for x in r.summary.splitlines() if "Gruebler" in x)
    assert "degrees of freedom: 3 " in line and "redundant" not in line
    assert "1 constraint row of contacts starting open is not in force" in line
    four_bar = mbcomp.simulate(mbcomp.load_model_file("models/four_bar.py").build(), t_end=0.1,
                               formulation=formulation, method=method)
    assert "mobility exceeds it by 3 because 3 constraint rows are redundant" in four_bar.summary


def test_fallbacks_of_a_model_without_laws_blame_no_law():
    """Guards of the generated program failing on nearly singular matrices (a four-bar run on
    past its flat positions: 1655 of 2435 evaluations) were blamed on "a law's branch" of a
    model without laws; the note now names what it was. A model with a law keeps the advice
    (tests/simulation/test_budgets_and_requests.py: a Python branch on w)."""
    from types import SimpleNamespace

    from mbcomp.simulation.driver import why_slow

    run = SimpleNamespace(form=SimpleNamespace(system=mbcomp.assemble(pendulum(1.0))), t_out=np.array([0.0, 1.0]),
                          t=1.0, stepper=SimpleNamespace(t_bound=1.0))
    notes = why_slow(run, None, "success", dict(fallbacks=1655, nfev=2435, steps=300))
    assert len(notes) == 1 and "1655 of 2435 evaluations left the generated program" in notes[0]
    assert "no laws" in notes[0] and "law's branch" not in notes[0] and "singular" in notes[0]


@pytest.mark.parametrize("formulation", ["lagrange", "dalembert"])
@pytest.mark.parametrize("method", ["DOP853", "dop853"])
def test_a_ball_bouncing_on_a_floor_runs_on_scipy_and_compiled_dop853(formulation, method):
    """models/bouncing_ball.py on scipy's DOP853 and the compiled dop853 (a 'mass matrix is
    singular ... carries no inertia' failure was reported on DOP853): the bounce times are
    t0 + 2 t0 e (1 - e^k) / (1 - e), t0 = sqrt(2 h0 / g), and the impacts take the energy
    (1 - e^2) of each landing."""
    h0, e, m = 1.0, 0.8, 0.5
    r = mbcomp.simulate(mbcomp.load_model_file("models/bouncing_ball.py").build(), t_end=2.5, formulation=formulation,
                        method=method, **TOL)
    assert r.status == "success", r.message
    t0 = np.sqrt(2 * h0 / G)
    k = np.arange(4)
    impacts = [x for x in r.events if x.kind == "impact"][:4]
    assert np.allclose([x.time for x in impacts], t0 + 2 * t0 * e * (1 - e ** k) / (1 - e), atol=1e-8)
    assert np.allclose([x.detail["energy_loss"] for x in impacts], m * G * h0 * e ** (2 * k) * (1 - e ** 2),
                       rtol=1e-7)
