"""A ball rolling without slip on curved surfaces (SphereContact(surface=...)) against closed forms.

Notation: ball radius ``r``, mass ``m``, uniform (``I = 2/5 m r^2``), ``g = 9.81 m/s^2``.

**Rolling in a circular cross-section.** A ball whose centre moves on a circle of radius
``L`` in a vertical plane (inside a spherical bowl of radius ``R``, ``L = R - r``; across a
horizontal pipe; around the cross-section of a torus tube of radius ``a``, ``L = a - r``)
with angle ``theta`` from the bottom rolls with angular velocity ``L theta' / r`` about the
plane's normal, so ``T = 1/2 m L^2 theta'^2 + 1/2 (2/5 m r^2)(L theta' / r)^2
= 7/10 m L^2 theta'^2`` and ``V = -m g L cos(theta)``: Lagrange's equation is the pendulum
``theta'' = -(5 g / (7 L)) sin(theta)``, so

    omega^2 = 5 g / (7 (R - r))      (small oscillations)

and at amplitude ``theta0`` the exact period is ``4 K(sin^2(theta0/2)) / omega`` (``K`` the
complete elliptic integral), ``2 pi / omega (1 + theta0^2/16 + ...)``: 6.25e-6 above the
small-oscillation period at 0.01 rad.

**Half-pipe with axial motion** (axis x, ``n`` rotating about x at the rate ``theta'``):
write ``w = w_x x + w_b b + w_n n`` with ``b = x X n``. No slip gives ``s' = -r w_b`` (axial
speed) and ``L theta' = r w_x``; the contact force has no moment about ``n``, so
``w_n' = w . n' = -theta' s' / r``; the axial force ``F_x = m s''`` and its moment give
``(7/2) s'' = r theta' w_n``. Eliminating time, ``d^2 s'/d theta^2 = -(2/7) s'``:

    s' = v cos(sqrt(2/7) (theta - theta0)),   w . n = -(v/r) sqrt(7/2) sin(sqrt(2/7) (theta - theta0))

(free uniform motion along the axis to first order, a second-order exchange with the spin
about the normal), and ``7/10 m (s'^2 + 2/7 r^2 w_n^2)`` is conserved by itself, so the
motion across the pipe is the pendulum above whatever the axial speed.

**Steady circling in a torus tube** (core radius ``R``, tube ``a``, axis z): the ball at a
constant angle ``beta`` up the outer wall, centre on the circle ``rho = R + (a - r) sin(beta)``
at speed ``v``, ``w = (v/r) n X e_phi`` (no spin about ``n``). ``w`` turns with
``Omega = v / rho`` about z, so ``I Omega z X w = (-r n) X F`` with ``F = m (g z - v^2/rho e_rho)``:
``(2/5)(v/rho) v cos(beta) = g sin(beta) - (v^2/rho) cos(beta)``, i.e.

    tan(beta) = (7/5) v^2 / (g rho)      (a sliding point mass: v^2 / (g rho))

**Moving bowl.** Translating at constant velocity: the same motion relative to the bowl
(Galilean invariance). Accelerating at ``A`` along x: in the bowl's frame gravity is
``g_eff = sqrt(g^2 + A^2)`` tilted by ``theta_e = atan(A / g)``; starting at rest at the
bottom the ball swings between 0 and ``2 theta_e`` with ``omega^2 = 5 g_eff / (7 (R - r))``.

Runs use the generated Python program; one run checks the C program gives the same motion.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.special import ellipk  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.codegen import c_compiler  # noqa: E402
from mbcomp.library import FreeMotion, PrescribedMotion, Prismatic, RigidBody, SphereContact, World  # noqa: E402
from mbcomp.library.surfaces import CylinderSurface, HeightField, SphereSurface, TorusSurface  # noqa: E402

G = 9.81
TIGHT = dict(rtol=1e-10, atol=1e-12, backend="python")
R_BOWL, R_BALL, MASS, TH0 = 1.0, 0.1, 0.5, 0.01


def vec(res, name):
    return np.column_stack([res[f"{name}.{ax}"] for ax in "xyz"])


def ball_on(surface, c0, v0=(0, 0, 0), w0=(0, 0, 0), carrier=None, r=R_BALL, m=MASS):
    """A uniform ball (FreeMotion from the world) on ``surface`` fixed in the world, or in
    ``carrier(model, world) -> frame`` (a moving body's frame)."""
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, -G)))
    free = mdl.add("free", FreeMotion(r0=c0, v0=v0, w0=w0))
    ball = mdl.add("ball", RigidBody(m=m, I=0.4 * m * r * r * np.eye(3)))
    c = mdl.add("contact", SphereContact(r=r, surface=surface))
    mdl.connect(w.frame_b, free.frame_a)
    mdl.connect(free.frame_b, ball.frame_a)
    mdl.connect(carrier(mdl, w) if carrier else w.frame_b, c.frame_a)
    mdl.connect(c.frame_b, ball.frame_a)
    return mdl


def crossings(t, y, level=0.0):
    """Times where ``y`` crosses ``level`` (linear interpolation between output points)."""
    y = y - level
    i = np.nonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)[0]
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


def period(t, y, level=0.0):
    """The mean full period over all crossings of ``level`` (every other one is a period)."""
    tc = crossings(t, y, level)
    assert len(tc) >= 5, "too few oscillations"
    return 2.0 * (tc[-1] - tc[0]) / (len(tc) - 1)


def pendulum_periods(L, theta0, g=G):
    """(small-oscillation, exact) periods of ``theta'' = -(5 g / 7 L) sin(theta)`` at amplitude theta0."""
    w = np.sqrt(5.0 * g / (7.0 * L))
    return 2 * np.pi / w, 4.0 * ellipk(np.sin(theta0 / 2) ** 2) / w


def bowl_start(th0=TH0):
    return np.array([0.0, 0.0, R_BOWL]) + (R_BOWL - R_BALL) * np.array([np.sin(th0), 0.0, -np.cos(th0)])


def cap(R):
    return lambda x, y: R - np.sqrt(R * R - x * x - y * y)


BOWL = SphereSurface(R=R_BOWL, center=(0, 0, R_BOWL))
T_END = 10.0  # 4.4 periods


@pytest.fixture(scope="module")
def bowl():
    res = mbcomp.simulate(ball_on(BOWL, bowl_start()), t_end=T_END, n_out=4001, **TIGHT)
    assert res.success, res.message
    return res


@pytest.fixture(scope="module")
def cap_bowl():
    res = mbcomp.simulate(ball_on(HeightField(cap(R_BOWL)), bowl_start()), t_end=T_END, n_out=4001, **TIGHT)
    assert res.success, res.message
    return res


# --------------------------------------------------------------------------- the spherical bowl

def test_ball_in_bowl_small_oscillation_period(bowl):
    """The measured period against ``omega^2 = 5 g / (7 (R - r))`` to 1e-4 (the amplitude
    correction at 0.01 rad is 6.25e-6) and against the exact elliptic period to 1e-8."""
    T = period(bowl.time, bowl["ball.r.x"])
    T_lin, T_exact = pendulum_periods(R_BOWL - R_BALL, TH0)
    assert abs(T / T_lin - 1) < 1e-4
    assert abs(T_exact / T_lin - 1) < 1e-5  # the amplitude correction is below the tolerance
    assert abs(T / T_exact - 1) < 1e-8
    assert abs(T / (1.0001 * T_lin) - 1) > 5e-5  # the test resolves a 1e-4 error


def test_ball_in_bowl_rolls_without_slip_on_the_sphere_and_conserves_energy(bowl):
    """The centre stays at ``R - r`` from the bowl's centre; the contact point
    ``P = C + R (c - C)/|c - C|`` (re-derived here) is where the library says, and the ball's
    material velocity there vanishes; energy is conserved."""
    c, v, w = vec(bowl, "ball.r"), vec(bowl, "ball.v"), vec(bowl, "ball.w")
    C = np.array([0, 0, R_BOWL])
    d = np.linalg.norm(c - C, axis=1)
    assert np.abs(d - (R_BOWL - R_BALL)).max() < 1e-10
    P = C + R_BOWL * (c - C) / d[:, None]
    np.testing.assert_allclose(vec(bowl, "contact.p"), P, atol=1e-12)
    assert np.abs(v + np.cross(w, P - c)).max() < 1e-10
    E = bowl["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-8 * MASS * G * R_BALL
    assert bowl["residual.nonholonomic"].max() < 1e-9
    N = bowl["contact.N"]  # weight plus centripetal at small amplitude: about m g
    assert np.abs(N / (MASS * G) - 1).max() < 1e-3


def test_height_field_bowl_reproduces_the_sphere(bowl, cap_bowl):
    """The spherical cap ``h = R - sqrt(R^2 - x^2 - y^2)`` as a HeightField: the same motion
    to 1e-10 (measured 1e-14; the foot point by Newton, the curvature by the implicit function theorem)."""
    np.testing.assert_allclose(vec(cap_bowl, "ball.r"), vec(bowl, "ball.r"), atol=1e-11)  # measured 1e-14
    np.testing.assert_allclose(vec(cap_bowl, "ball.w"), vec(bowl, "ball.w"), atol=1e-10)
    T = period(cap_bowl.time, cap_bowl["ball.r.x"])
    assert abs(T / pendulum_periods(R_BOWL - R_BALL, TH0)[0] - 1) < 1e-4


@pytest.mark.skipif(c_compiler() is None, reason="no C compiler")
def test_c_program_rolls_the_ball_as_the_python_one(bowl):
    """The surface is a constant of the generated program: the C program gives the same motion."""
    res = mbcomp.simulate(ball_on(BOWL, bowl_start()), t_end=T_END, n_out=4001, rtol=1e-10, atol=1e-12, backend="c")
    assert res.success and res.stats["backend"] == "c", res.message
    np.testing.assert_allclose(vec(res, "ball.r"), vec(bowl, "ball.r"), atol=1e-8)


# --------------------------------------------------------------------------- the half-pipe

def test_ball_in_half_pipe_swings_across_and_rolls_along():
    """Axis x, radius 0.6 m; start 0.01 rad up the wall, axial speed 0.4 m/s: the swing across
    has the pendulum's period, the axial speed and the spin about the normal follow the
    closed forms of the module's text."""
    Rp, v = 0.6, 0.4
    L = Rp - R_BALL
    pipe = CylinderSurface(R=Rp, axis=(1, 0, 0), center=(0, 0, Rp))
    c0 = np.array([0, 0, Rp]) + L * np.array([0.0, np.sin(TH0), -np.cos(TH0)])
    n0 = np.array([0.0, -np.sin(TH0), np.cos(TH0)])
    v0 = np.array([v, 0, 0])
    res = mbcomp.simulate(ball_on(pipe, c0, v0=v0, w0=np.cross(n0, v0) / R_BALL), t_end=8.0, n_out=4001, **TIGHT)
    assert res.success, res.message
    c, vel, w = vec(res, "ball.r"), vec(res, "ball.v"), vec(res, "ball.w")
    theta = np.arctan2(c[:, 1], Rp - c[:, 2])
    T_lin, T_exact = pendulum_periods(L, TH0)
    T = period(res.time, theta)
    assert abs(T / T_lin - 1) < 1e-4 and abs(T / T_exact - 1) < 1e-8
    k = np.sqrt(2.0 / 7.0)
    np.testing.assert_allclose(vel[:, 0], v * np.cos(k * (theta - TH0)), atol=1e-10)
    n = np.column_stack([np.zeros_like(theta), -np.sin(theta), np.cos(theta)])
    wn = np.einsum("ij,ij->i", w, n)
    np.testing.assert_allclose(np.abs(wn), v / R_BALL * np.sqrt(3.5) * np.abs(np.sin(k * (theta - TH0))), atol=1e-9)
    assert np.ptp(vel[:, 0]) > 1e-6  # the second-order exchange is there and resolved
    assert np.abs(vel[:, 0] / v - 1).max() < (2 * TH0) ** 2 / 7 * 1.01  # uniform to first order
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-8 * MASS * G * R_BALL


# --------------------------------------------------------------------------- the torus

def test_ball_swinging_across_a_torus_tube_has_the_pipe_period():
    """Inside a torus tube (core 1.5 m, tube 0.4 m), started at rest 0.01 rad outward at the
    bottom: the motion stays in the meridian plane, so it is the same pendulum of length
    ``a - r`` as in a straight pipe, for any core radius."""
    Rc, a = 1.5, 0.4
    L = a - R_BALL
    c0 = np.array([Rc + L * np.sin(TH0), 0.0, -L * np.cos(TH0)])
    res = mbcomp.simulate(ball_on(TorusSurface(R=Rc, a=a), c0), t_end=6.0, n_out=3001, **TIGHT)
    assert res.success, res.message
    c = vec(res, "ball.r")
    assert np.abs(c[:, 1]).max() < 1e-12
    T = period(res.time, c[:, 0] - Rc)
    T_lin, T_exact = pendulum_periods(L, TH0)
    assert abs(T / T_lin - 1) < 1e-4 and abs(T / T_exact - 1) < 1e-8


@pytest.mark.parametrize("factor, steady", [(7.0 / 5.0, True), (1.0, False)])
def test_ball_circling_in_a_torus_groove(factor, steady):
    """Core 1.5 m, tube 0.4 m, ``beta = 0.3 rad`` up the outer wall: at the speed of
    ``tan(beta) = (7/5) v^2 / (g rho)`` the ball circles steadily (its angle and height stay
    put over two laps); at the sliding point mass's speed (factor 1) it does not."""
    Rc, a, beta = 1.5, 0.4, 0.3
    L = a - R_BALL
    rho = Rc + L * np.sin(beta)
    v = np.sqrt(G * rho * np.tan(beta) / factor)
    c0 = np.array([rho, 0.0, -L * np.cos(beta)])
    n0 = np.array([-np.sin(beta), 0.0, np.cos(beta)])
    v0 = np.array([0.0, v, 0.0])
    t_end = 2 * (2 * np.pi * rho / v)
    res = mbcomp.simulate(ball_on(TorusSurface(R=Rc, a=a), c0, v0=v0, w0=np.cross(n0, v0) / R_BALL),
                          t_end=t_end, n_out=801, **TIGHT)
    assert res.success, res.message
    c = vec(res, "ball.r")
    dev = max(np.abs(np.hypot(c[:, 0], c[:, 1]) - rho).max(), np.abs(c[:, 2] - c0[2]).max())
    if steady:
        assert dev < 1e-8
        phi = np.unwrap(np.arctan2(c[:, 1], c[:, 0]))
        np.testing.assert_allclose(phi, v / rho * res.time, atol=1e-8)  # at constant speed
        assert res["residual.nonholonomic"].max() < 1e-9
    else:
        assert dev > 1e-3


# --------------------------------------------------------------------------- a moving bowl

def moving_bowl(law):
    """The bowl on a platform sliding along x with the prescribed position ``law``."""
    def carrier(mdl, w):
        slide = mdl.add("slide", Prismatic(n=(1, 0, 0)))
        drive = mdl.add("drive", PrescribedMotion(s=law))
        plat = mdl.add("platform", RigidBody(m=3.0, I=np.eye(3)))
        mdl.connect(w.frame_b, slide.frame_a)
        mdl.connect(drive.flange_b, slide.axis)
        mdl.connect(slide.frame_b, plat.frame_a)
        return slide.frame_b
    return carrier


def test_bowl_translating_at_constant_velocity_gives_the_same_motion(bowl):
    """Galilean invariance: the bowl and the ball moving at 1.5 m/s along x, the ball's
    motion relative to the bowl is the fixed bowl's to 1e-10 m (measured 4e-12), the period
    to 1e-8 (measured 4e-13)."""
    V = 1.5
    res = mbcomp.simulate(ball_on(BOWL, bowl_start(), v0=(V, 0, 0), carrier=moving_bowl(f"{V}*t")),
                          t_end=T_END, n_out=4001, **TIGHT)
    assert res.success, res.message
    rel = vec(res, "ball.r") - np.outer(V * res.time, [1, 0, 0])
    np.testing.assert_allclose(rel, vec(bowl, "ball.r"), atol=1e-10)
    T, T0 = period(res.time, rel[:, 0]), period(bowl.time, bowl["ball.r.x"])
    assert abs(T / T0 - 1) < 1e-8


def test_accelerating_bowl_swings_about_the_tilted_gravity():
    """The bowl accelerating at 0.1 m/s^2 along x, the ball at rest at its bottom at t = 0:
    it swings between 0 and ``2 theta_e`` (``theta_e = atan(A/g)``, backwards, -x) with the
    period of ``omega^2 = 5 sqrt(g^2 + A^2) / (7 (R - r))`` at amplitude ``theta_e``."""
    A = 0.1
    res = mbcomp.simulate(ball_on(BOWL, bowl_start(0.0), carrier=moving_bowl(f"0.5*{A}*t**2")),
                          t_end=T_END, n_out=4001, **TIGHT)
    assert res.success, res.message
    c = vec(res, "ball.r")
    rel_x = c[:, 0] - 0.5 * A * res.time ** 2
    theta = np.arctan2(rel_x, R_BOWL - c[:, 2])
    th_e = -np.arctan(A / G)
    assert abs(theta.min() - 2 * th_e) < 1e-8 and abs(theta.max()) < 1e-8
    g_eff = np.hypot(G, A)
    T_lin, T_exact = pendulum_periods(R_BOWL - R_BALL, th_e, g=g_eff)
    T = period(res.time, theta, level=th_e)
    assert abs(T / T_exact - 1) < 1e-8 and abs(T / T_lin - 1) < 1e-4
    assert abs(T / pendulum_periods(R_BOWL - R_BALL, th_e)[1] - 1) > 2e-5  # the plain g would fail
