"""Rolling contact (library/contact.py) against analytic results of rolling-body dynamics.

Notation: ``r`` radius, ``m`` mass, ``I_a`` axial and ``I_d`` diametral moment of inertia of
the disk (thin uniform disk: ``I_a = m r^2/2``, ``I_d = m r^2/4``), ``g = 9.81 m/s^2``.
Everything the tests compare with is computed here from the result columns (centre,
quaternion, velocities) by formulas written out in this file, not by the library's helpers.

* no slip and energy: the material point of the wheel at the contact point (re-derived here
  from the centre and orientation) has zero velocity, lies on the plane, energy is conserved;
  a Chaplygin ball also conserves its angular momentum about the contact point;
* critical speed of the upright disk, linearized lean equation (frequency and growth rate);
* steady turning at constant lean: the exact relation between lean, heading rate and spin,
  and the contact forces of circular motion;
* a ball on an inclined plane (5/7 g sin a), a ball on a turntable (circle at 2/7 of the
  table's rate), ball and disk on an accelerating platform (2/7 A, A/3);
* the two formulations and projection agree; the summary and ``mbcomp info`` counts;
  clear errors.

Runs use the generated Python program (``backend="python"``), ~8x faster than the numeric
path on these models.
"""
import os

# The D'Alembert path solves 3x3 systems with scipy's LU; multi-threaded OpenBLAS on a shared
# machine made each solve cost ~1 ms (16 s instead of 0.9 s for a 1 s ball run). Effective when
# this file is the first to load numpy; bench/*.py do the same.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import subprocess  # noqa: E402
import sys  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.optimize import curve_fit  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.cli import main  # noqa: E402
from mbcomp.library import (DiskContact, FixedRotation, FreeMotion, PrescribedMotion, Prismatic,  # noqa: E402
                            Revolute, RigidBody, RollingDisk, RollingSphere, World)

G = 9.81
EZ = np.array([0.0, 0.0, 1.0])
TIGHT = dict(rtol=1e-10, atol=1e-12, backend="python")


# ---------------------------------------------------------------------------- helpers

def vec(res, name):
    """(n, 3) array of the columns ``name.x|y|z``."""
    return np.column_stack([res[f"{name}.{ax}"] for ax in "xyz"])


def rotation(res, body):
    """(n, 3, 3) orientation matrices (frame -> world) from the result quaternion (w, x, y, z)."""
    w, x, y, z = (res[f"{body}.Q.{c}"] for c in "wxyz")
    s = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / s, x / s, y / s, z / s
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return R.transpose(2, 0, 1)


def unit_rows(v):
    return v / np.linalg.norm(v, axis=1)[:, None]


def dot_rows(a, b):
    return np.einsum("ij,ij->i", a, b)


def disk_frames(res, body="disk.wheel"):
    """Spin axis ``a``, rolling direction ``l = unit(a x z)``, disk-plane "up" ``k = l x a``
    (from the contact point towards the centre) and lean ``asin(a_z)`` (> 0: axis tilted
    up, the centre displaced to ``-y`` of the rolling direction, i.e. to the right)."""
    a = rotation(res, body)[:, :, 1]
    l = unit_rows(np.cross(a, EZ))
    k = np.cross(l, a)
    return a, l, k, np.arcsin(a[:, 2])


def disk_model(**kw):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    d = m.add("disk", RollingDisk(**kw))
    m.connect(w.frame_b, d.plane)
    return m


def thin_disk(r, m):
    return m * r * r / 2, m * r * r / 4  # I_a, I_d


# ---------------------------------------------------------------------------- 1. no slip, energy

R1, M1 = 0.3, 2.0
TURNING = dict(r=R1, m=M1, lean0=0.2, spin_rate0=8.0, heading_rate0=1.0)


@pytest.fixture(scope="module")
def turning():
    """A leaning, turning disk (not a steady motion: lean and heading rate oscillate)."""
    res = mbcomp.simulate(disk_model(**TURNING), t_end=3.0, n_out=301, **TIGHT)
    assert res.success, res.message
    return res


def test_disk_contact_point_is_at_rest_on_the_plane_and_energy_is_conserved(turning):
    """The contact point is the rim point nearest the plane: with ``a`` the spin axis, the
    rim direction towards the plane is ``-k``, ``k = unit(z - (z.a) a)`` (z projected into
    the disk plane) = ``unit(a x (a x n))`` up to sign: ``P = c - r k``. No slip: the
    wheel's material velocity there ``v_c + w x (P - c)`` vanishes; friction and normal force
    do no work, so ``T + V`` is constant."""
    res = turning
    c, v, w = vec(res, "disk.wheel.r"), vec(res, "disk.wheel.v"), vec(res, "disk.wheel.w")
    a = rotation(res, "disk.wheel")[:, :, 1]
    down = unit_rows(np.cross(a, np.cross(a, EZ)))  # a x (a x z) = (a.z) a - z: points down
    assert np.all(down[:, 2] < 0)
    P = c + R1 * down
    slip = v + np.cross(w, P - c)
    assert np.abs(slip).max() < 1e-8
    assert np.abs(P[:, 2]).max() < 1e-10
    np.testing.assert_allclose(vec(res, "disk.contact.p"), P, atol=1e-12)  # the library's output
    lean = np.arcsin(a[:, 2])
    assert np.ptp(lean) > 0.1 and np.ptp(np.linalg.norm(w, axis=1)) > 0.1  # a non-trivial motion
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-9 * abs(E[0])
    assert res["residual.nonholonomic"].max() < 1e-8


@pytest.fixture(scope="module")
def chaplygin_ball():
    """A ball with unequal principal moments (centre of mass at the centre): Chaplygin's
    ball, whose rolling is non-trivial on a level plane."""
    r, m = 0.1, 0.5
    I = np.diag([0.3, 0.4, 0.5]) * m * r * r
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, -G)))
    b = mdl.add("ball", RollingSphere(r=r, m=m, I=I, v0=(0.4, 0.1), spin_rate0=6.0))
    mdl.connect(w.frame_b, b.plane)
    res = mbcomp.simulate(mdl, t_end=3.0, n_out=301, **TIGHT)
    assert res.success, res.message
    return res, r, m, I


def test_ball_contact_point_is_at_rest_and_angular_momentum_about_it_is_conserved(chaplygin_ball):
    """``P = c - r z``; ``v_c + w x (P - c) = 0``. Angular momentum about the contact point
    ``K = R I R^T w + m r^2 (w - w_z z)`` is conserved: gravity and the contact force have no
    moment about P, and P moves with the centre (``dK/dt = -v_P x m v_c = 0``)."""
    res, r, m, I = chaplygin_ball
    c, v, w = vec(res, "ball.ball.r"), vec(res, "ball.ball.v"), vec(res, "ball.ball.w")
    P = c - r * EZ
    assert np.abs(v + np.cross(w, P - c)).max() < 1e-8
    assert np.abs(P[:, 2]).max() < 1e-10
    R = rotation(res, "ball.ball")
    K = np.einsum("nij,jk,nlk,nl->ni", R, I, R, w) + m * r * r * (w - w[:, 2:3] * EZ)
    assert np.abs(K - K[0]).max() < 1e-9 * np.linalg.norm(K[0])
    assert np.ptp(w, axis=0).max() > 1.0  # the spin axis wanders: a non-trivial motion
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-9 * abs(E[0])


# ---------------------------------------------------------------------------- 2. critical speed

def lean_coefficients(r, m, spin):
    """Linearized about upright straight rolling at spin ``W`` (lean ``phi``, heading ``psi``):
    ``(I_d + m r^2) phi'' + (I_a + m r^2) W psi' - m g r phi = 0`` and ``I_d psi'' = I_a W phi'``;
    with ``psi'(0) = 0, phi(0) = 0``: ``I_d psi' = I_a W phi``, so
    ``(I_d + m r^2) phi'' + [(I_a + m r^2) I_a W^2 / I_d - m g r] phi = 0``.
    Returns (K, J) with ``J phi'' + K phi = 0``; thin disk: K = 0 at ``W^2 = g / (3 r)``."""
    Ia, Id = thin_disk(r, m)
    return (Ia + m * r * r) * Ia * spin ** 2 / Id - m * G * r, Id + m * r * r


LEAN_RATE0 = 0.05


@pytest.fixture(scope="module")
def above_critical():
    spin = np.sqrt(3.0 * G / (3 * R1))
    res = mbcomp.simulate(disk_model(r=R1, m=M1, spin_rate0=spin, lean_rate0=LEAN_RATE0), t_end=5.0,
                          n_out=1001, **TIGHT)
    assert res.success, res.message
    return res, spin


@pytest.fixture(scope="module")
def below_critical():
    spin = np.sqrt(0.5 * G / (3 * R1))
    res = mbcomp.simulate(disk_model(r=R1, m=M1, spin_rate0=spin, lean_rate0=LEAN_RATE0), t_end=1.5,
                          n_out=751, **TIGHT)
    assert res.success, res.message
    return res, spin


def test_above_the_critical_speed_the_lean_oscillates_at_the_linear_frequency(above_critical):
    """``phi = (phi'0 / w) sin(w t)``, ``w = sqrt(K / J)``; the frequency is measured from the
    zero crossings (linear interpolation) of the lean."""
    res, spin = above_critical
    # the derivation's critical speed is the textbook one, W^2 = g / (3 r) for a thin disk
    assert abs(lean_coefficients(R1, M1, np.sqrt(G / (3 * R1)))[0]) < 1e-12 * M1 * G * R1
    K, J = lean_coefficients(R1, M1, spin)
    omega = np.sqrt(K / J)
    _, _, _, lean = disk_frames(res)
    t = res.time
    amp = LEAN_RATE0 / omega
    assert np.abs(lean).max() < 1.01 * amp  # stays small: bounded by the linear amplitude
    assert np.abs(lean).max() > 0.99 * amp
    i = np.where(np.sign(lean[1:]) * np.sign(lean[:-1]) < 0)[0]
    tz = t[i] - lean[i] * (t[i + 1] - t[i]) / (lean[i + 1] - lean[i])
    assert len(tz) >= 10
    measured = np.pi * (len(tz) - 1) / (tz[-1] - tz[0])
    # measured 7.23357 vs 7.23326 rad/s (4e-5: the amplitude-squared shift of the nonlinear motion)
    assert abs(measured / omega - 1) < 1e-3, (measured, omega)


def test_below_the_critical_speed_the_lean_grows_at_the_linear_rate_and_the_disk_falls(below_critical):
    """``phi = (phi'0 / s) sinh(s t)``, ``s = sqrt(-K / J)``: ``log|phi|`` fitted with
    ``log A + log sinh(s t)`` while ``|phi| < 0.02`` (linear phase)."""
    res, spin = below_critical
    K, J = lean_coefficients(R1, M1, spin)
    assert K < 0
    rate = np.sqrt(-K / J)
    _, _, _, lean = disk_frames(res)
    t = res.time
    early = (t > 0) & (np.cumsum(np.abs(lean) >= 0.02) == 0)
    assert early.sum() > 50
    (A, s), _ = curve_fit(lambda tt, lnA, ss: lnA + np.log(np.sinh(ss * tt)), t[early],
                          np.log(np.abs(lean[early])), p0=(np.log(0.01), 1.0))
    # measured 3.61635 vs 3.61663 1/s (-8e-5)
    assert abs(s / rate - 1) < 3e-3, (s, rate)
    assert abs(np.exp(A) / (LEAN_RATE0 / rate) - 1) < 3e-3
    assert np.abs(lean).max() > 0.5  # it falls (and the run ends before it lies flat)
    assert res["residual.position"].max() < 1e-8


# ---------------------------------------------------------------------------- 3. steady turning

def steady_turning_spin(r, m, lean, heading_rate):
    """Steady motion: lean ``phi``, heading rate ``W`` about z, ``w = W z + s a``,
    ``a = cos(phi) e2 + sin(phi) z``, ``k = -sin(phi) e2 + cos(phi) z`` (contact -> centre),
    ``w_a = w.a = W sin(phi) + s``, ``w.k = W cos(phi)``. The centre moves with
    ``v = w x r k = r w_a e1`` on a circle: ``m a_c = m W V e2 = F - m g z``. Angular
    momentum about the centre ``H = I_a w_a a + I_d W cos(phi) k`` turns with ``W z``:
    ``dH/dt = W cos(phi) (I_d W sin(phi) - I_a w_a) e1`` = moment of F about the centre
    ``-r k x F = r (m g sin(phi) + m W V cos(phi)) e1``. Hence
    ``I_d W^2 sin cos - (I_a + m r^2) W w_a cos - m g r sin = 0``, solved for ``w_a``
    (with ``I_d -> 0``: ``tan(phi) = -(I_a + m r^2) W w_a / (m g r)``)."""
    Ia, Id = thin_disk(r, m)
    s, c = np.sin(lean), np.cos(lean)
    return (Id * heading_rate ** 2 * s * c - m * G * r * s) / ((Ia + m * r * r) * heading_rate * c)


PHI3, W3 = 0.3, -0.5  # leaning right (centre to -e2), turning right, rolling forward


@pytest.fixture(scope="module")
def steady_turn():
    wa = steady_turning_spin(R1, M1, PHI3, W3)
    res = mbcomp.simulate(disk_model(r=R1, m=M1, lean0=PHI3, heading_rate0=W3, spin_rate0=wa - W3 * np.sin(PHI3)),
                          t_end=4.0, n_out=401, **TIGHT)
    assert res.success, res.message
    return res, wa


def test_steady_turning_keeps_lean_and_heading_rate(steady_turn):
    res, wa = steady_turn
    # the exact relation reduces to the small-inertia one, tan(phi) = -(I_a + m r^2) W w_a / (m g r),
    # times 1 - I_d W^2 cos(phi) / (m g r)
    Ia, Id = thin_disk(R1, M1)
    approx = -np.tan(PHI3) * M1 * G * R1 / ((Ia + M1 * R1 ** 2) * W3)
    assert wa > 0 and wa / approx == pytest.approx(1 - Id * W3 ** 2 * np.cos(PHI3) / (M1 * G * R1), rel=1e-14)
    t = res.time
    a, l, k, lean = disk_frames(res)
    assert np.abs(lean - PHI3).max() < 1e-6
    heading = np.unwrap(np.arctan2(l[:, 1], l[:, 0]))
    assert np.abs(heading - W3 * t).max() < 1e-6
    w = vec(res, "disk.wheel.w")
    assert np.abs(dot_rows(w, k) / np.cos(lean) - W3).max() < 1e-6  # heading rate from w.k = W cos(phi)
    assert np.abs(dot_rows(w, l)).max() < 1e-6  # lean rate
    assert np.abs(dot_rows(w, a) - wa).max() < 1e-6 * wa


def test_steady_turning_centre_circles_and_contact_forces_match(steady_turn):
    """``N = m g``, ``F_long = 0``, ``F_lat = m W V`` along ``n x l = e2`` (``V = r w_a``);
    the centre moves at speed V on a circle of radius ``|V / W|`` about a fixed point on the
    side the disk leans to."""
    res, wa = steady_turn
    V = R1 * wa
    c, v = vec(res, "disk.wheel.r"), vec(res, "disk.wheel.v")
    assert np.abs(np.linalg.norm(v, axis=1) - V).max() < 1e-9 * V
    centre = c[:, :2] + np.column_stack((-v[:, 1], v[:, 0])) / W3  # c + z x v / W
    assert np.abs(centre - centre[0]).max() < 1e-8
    assert np.abs(np.linalg.norm(c[:, :2] - centre[0], axis=1) - abs(V / W3)).max() < 1e-8
    lean_dir = (c - vec(res, "disk.contact.p"))[:, :2]  # horizontal offset contact -> centre
    assert np.all(dot_rows(lean_dir, centre - c[:, :2]) > 0)  # leans into the turn
    np.testing.assert_allclose(res["disk.contact.N"], M1 * G, rtol=1e-9)
    assert np.abs(res["disk.contact.F_long"]).max() < 1e-9
    np.testing.assert_allclose(res["disk.contact.F_lat"], M1 * W3 * V, rtol=1e-9)


# ---------------------------------------------------------------------------- 4. inclined plane

ALPHA, R4, M4, V4 = 0.4, 0.1, 0.5, (0.3, 0.4)


def incline():
    c, s = np.cos(ALPHA), np.sin(ALPHA)
    Ry = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])  # plane x axis (c, 0, -s): downhill
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    tilt = m.add("tilt", FixedRotation(R=Ry))
    b = m.add("ball", RollingSphere(r=R4, m=M4, x0=0.2, y0=-0.1, v0=V4))
    m.connect(w.frame_b, tilt.frame_a)
    m.connect(tilt.frame_b, b.plane)
    return m, Ry


@pytest.mark.parametrize("formulation", ["lagrange", "dalembert"])
def test_ball_on_an_incline_accelerates_at_five_sevenths_g_sin_alpha(formulation):
    """Along the slope ``m x'' = m g sin(a) + F``, ``(2/5) m r^2 w' = -r F``, no slip
    ``x'' = r w'``: ``x'' = (5/7) g sin(a)``, ``F = -(2/7) m g sin(a)`` (uphill),
    ``N = m g cos(a)``; across the slope the ball rolls uniformly."""
    mdl, Ry = incline()
    res = mbcomp.simulate(mdl, t_end=1.0, n_out=101, formulation=formulation, **TIGHT)
    assert res.success, res.message
    t = res.time
    cp = vec(res, "ball.ball.r") @ Ry  # centre in plane coordinates
    assert np.abs(cp[:, 2] - R4).max() < 1e-10
    np.testing.assert_allclose(cp[:, 0], 0.2 + V4[0] * t + 5 / 14 * G * np.sin(ALPHA) * t ** 2, atol=1e-9)
    np.testing.assert_allclose(cp[:, 1], -0.1 + V4[1] * t, atol=1e-9)
    np.testing.assert_allclose(res["ball.contact.N"], M4 * G * np.cos(ALPHA), rtol=1e-9)
    np.testing.assert_allclose(res["ball.contact.F_1"], -2 / 7 * M4 * G * np.sin(ALPHA), rtol=1e-9)
    assert np.abs(res["ball.contact.F_2"]).max() < 1e-9
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-9 * res["energy.kinetic"].max()


# ---------------------------------------------------------------------------- 5. moving platforms

def test_ball_on_a_turntable_circles_at_two_sevenths_of_the_table_rate():
    """Table rate ``W``; ball centre ``x`` (horizontal), ``v``. No slip
    ``v + r z x w = W z x x``; ``m v' = F``, ``(2/5) m r^2 w' = -r z x F``. Differentiating
    the no-slip condition: ``v' (1 + m r^2 / I) = W z x v``, so ``v' = (2/7) W z x v``: the
    centre moves (ground frame) on a circle at rate ``k = 2 W / 7`` about ``x + z x v / k``."""
    W, r, m = 3.0, 0.1, 0.5
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, -G)))
    hinge = mdl.add("hinge", Revolute(n=(0, 0, 1)))
    drive = mdl.add("drive", PrescribedMotion(s=f"{W}*t"))
    table = mdl.add("table", RigidBody(m=5.0, I=np.diag([1.0, 1.0, 2.0])))
    ball = mdl.add("ball", RollingSphere(r=r, m=m, x0=0.5, y0=0.0, v0=(0.1, 0.2)))  # v0 relative to the table
    mdl.connect(w.frame_b, hinge.frame_a)
    mdl.connect(drive.flange_b, hinge.axis)
    mdl.connect(hinge.frame_b, table.frame_a)
    mdl.connect(hinge.frame_b, ball.plane)
    res = mbcomp.simulate(mdl, t_end=3.0, n_out=301, **TIGHT)
    assert res.success, res.message
    t = res.time
    np.testing.assert_allclose(res["hinge.phi"], W * t, atol=1e-12)
    c, v = vec(res, "ball.ball.r"), vec(res, "ball.ball.v")
    np.testing.assert_allclose(v[0], [0.1, 0.2 + W * 0.5, 0.0], atol=1e-12)  # relative + table velocity
    kappa = 2 * W / 7
    centre = c[:, :2] + np.column_stack((-v[:, 1], v[:, 0])) / kappa
    assert np.abs(centre - centre[0]).max() < 1e-8
    rho = np.linalg.norm(v[0]) / kappa
    d = c[:, :2] - centre[0]
    assert np.abs(np.linalg.norm(d, axis=1) - rho).max() < 1e-8
    angle = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    assert np.abs(angle - angle[0] - kappa * t).max() < 1e-8
    assert kappa * t[-1] > 2.5  # a good part of the circle
    assert np.abs(c[:, 2] - r).max() < 1e-10
    F = np.hypot(res["ball.contact.F_1"], res["ball.contact.F_2"])  # the friction is the only horizontal force
    np.testing.assert_allclose(F, m * kappa * np.linalg.norm(v[0]), rtol=1e-8)


def test_ball_and_disk_on_an_accelerating_platform():
    """Platform acceleration ``A`` (prescribed). In the platform frame the inertial force
    ``-m A`` acts at the centre: ball ``x_rel'' = -(5/7) A`` so ``x'' = (2/7) A``; upright
    disk rolling along ``A``: ``x_rel'' = -A m r^2 / (I_a + m r^2)`` so
    ``x'' = A I_a / (I_a + m r^2) = A / 3`` (thin disk). Friction forces ``m x''``; the
    drive's force ``(m_p + (2/7) m_b + (1/3) m_d) A``."""
    A, mp, (rb, mb), (rd, md), spin = 2.0, 5.0, (0.1, 0.5), (0.3, 2.0), 10.0
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, -G)))
    slide = mdl.add("slide", Prismatic(n=(1, 0, 0)))
    drive = mdl.add("drive", PrescribedMotion(s=f"0.5*{A}*t**2"))
    plat = mdl.add("platform", RigidBody(m=mp, I=np.diag([1.0, 1.0, 2.0])))
    ball = mdl.add("ball", RollingSphere(r=rb, m=mb, x0=0.0, y0=0.5, v0=(0.2, 0.3)))
    disk = mdl.add("disk", RollingDisk(r=rd, m=md, x0=0.0, y0=-0.5, spin_rate0=spin))
    mdl.connect(w.frame_b, slide.frame_a)
    mdl.connect(drive.flange_b, slide.axis)
    mdl.connect(slide.frame_b, plat.frame_a)
    mdl.connect(slide.frame_b, ball.plane)
    mdl.connect(slide.frame_b, disk.plane)
    res = mbcomp.simulate(mdl, t_end=1.5, n_out=151, **TIGHT)
    assert res.success, res.message
    t = res.time
    cb, cd = vec(res, "ball.ball.r"), vec(res, "disk.wheel.r")
    np.testing.assert_allclose(cb[:, 0], 0.2 * t + (2 / 7) * A * t ** 2 / 2, atol=1e-9)
    np.testing.assert_allclose(cb[:, 1], 0.5 + 0.3 * t, atol=1e-9)
    np.testing.assert_allclose(cd[:, 0], rd * spin * t + (A / 3) * t ** 2 / 2, atol=1e-9)
    np.testing.assert_allclose(cd[:, 1:], np.tile([-0.5, rd], (len(t), 1)), atol=1e-9)
    np.testing.assert_allclose(res["ball.contact.F_1"], mb * (2 / 7) * A, rtol=1e-8)
    assert np.abs(res["ball.contact.F_2"]).max() < 1e-9
    np.testing.assert_allclose(res["disk.contact.F_long"], md * A / 3, rtol=1e-8)
    np.testing.assert_allclose(res["disk.contact.N"], md * G, rtol=1e-9)
    np.testing.assert_allclose(res["drive.f"], (mp + 2 / 7 * mb + md / 3) * A, rtol=1e-8)


# ---------------------------------------------------------------------------- 6. formulations agree

@pytest.mark.parametrize("variant", [dict(formulation="dalembert"), dict(stabilization="projection")],
                         ids=["dalembert", "projection"])
def test_formulations_agree_on_the_turning_disk(turning, variant):
    """Same motion as the Lagrange/Baumgarte run of the leaning, turning disk (2 s)."""
    res = mbcomp.simulate(disk_model(**TURNING), t_end=2.0, n_out=201, **TIGHT, **variant)
    assert res.success, res.message
    ref = turning
    n = len(res.time)
    np.testing.assert_allclose(res.time, ref.time[:n], atol=1e-12)
    np.testing.assert_allclose(vec(res, "disk.wheel.r"), vec(ref, "disk.wheel.r")[:n], atol=1e-7)
    np.testing.assert_allclose(rotation(res, "disk.wheel"), rotation(ref, "disk.wheel")[:n], atol=1e-7)
    np.testing.assert_allclose(res["disk.contact.N"], ref["disk.contact.N"][:n], rtol=1e-6)


# ---------------------------------------------------------------------------- 7. summary, CLI

def sphere_model():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    b = m.add("ball", RollingSphere(r=0.1, m=0.5, v0=(1.0, 0.0)))
    m.connect(w.frame_b, b.plane)
    return m


@pytest.mark.parametrize("build", [lambda: disk_model(**TURNING), sphere_model], ids=["disk", "sphere"])
def test_summary_counts_rolling_contacts(build):
    """Free body (6) minus the holonomic normal row: 5 DOF; minus two no-slip rows: 3 motion DOF."""
    text = mbcomp.assemble(build()).summary()
    assert "degrees of freedom: 5 " in text
    assert "nonholonomic constraints (velocity level): 2; motion DOF 3" in text


MODEL_FILE = '''
import mbcomp
from mbcomp.library import World, RollingDisk

def build(r=0.3, lean0=0.2):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    d = m.add("disk", RollingDisk(r=r, m=2.0, lean0=lean0, spin_rate0=8.0))
    m.connect(w.frame_b, d.plane)
    return m
'''


def test_info_reports_rolling_disk_counts(tmp_path, capsys):
    path = tmp_path / "rolling_disk.py"
    path.write_text(MODEL_FILE)
    out = subprocess.run([sys.executable, "-m", "mbcomp.cli", "info", str(path), "-p", "lean0=0.4"],
                         capture_output=True, text=True, check=True).stdout
    assert "degrees of freedom: 5 " in out
    assert "nonholonomic constraints (velocity level): 2; motion DOF 3" in out
    assert "disk.contact (1 holonomic + 2 nonholonomic rows)" in out
    # a runtime parameter reaches the contact and its check
    assert main(["info", str(path), "-p", "disk.contact.r=-1"]) == 2
    err = capsys.readouterr().err
    assert "disk.contact.r" in err and "> 0" in err


# ---------------------------------------------------------------------------- 8. clear errors

def test_a_disk_started_flat_is_a_clear_error():
    with pytest.raises(mbcomp.SimulationError) as ei:
        mbcomp.simulate(disk_model(r=0.3, m=2.0, lean0=np.pi / 2), t_end=0.1)
    msg = str(ei.value)
    assert "disk.contact" in msg and "flat" in msg


def test_non_numeric_composite_parameter_names_it():
    with pytest.raises(ValueError, match=r"RollingDisk: parameter r='abc'"):
        RollingDisk(r="abc")
    with pytest.raises(ValueError, match=r"RollingSphere: parameter v0="):
        RollingSphere(v0=(1.0, 2.0, 3.0))


def test_negative_contact_radius_is_a_model_error():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    free = m.add("free", FreeMotion(r0=(0, 0, 0.3)))
    wheel = m.add("wheel", RigidBody(m=2.0, I=np.diag([0.045, 0.09, 0.045])))
    c = m.add("contact", DiskContact(r=-1))
    m.connect(w.frame_b, free.frame_a)
    m.connect(free.frame_b, wheel.frame_a)
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, wheel.frame_a)
    with pytest.raises(mbcomp.ModelError) as ei:
        m.validate()
    assert "contact.r" in str(ei.value) and "> 0" in str(ei.value)


@pytest.mark.parametrize("backend", ["numeric", "python"])
def test_a_disk_falling_flat_during_a_run_fails_naming_the_contact(backend):
    """A disk released at lean 1.2 rad without spin falls flat at t ~ 0.17 s, where the
    contact is undefined. The driver's watch (Joint.singularity on accepted steps, the minimum
    located along the dense output) must stop the run there and name the contact, on the
    numeric path and on the generated program alike; the results up to it are kept and the
    contact stays on the plane until then. (Before the watch knew joint singularities the
    integrator stepped over flat and the centre sank through the plane with status success.)"""
    res = mbcomp.simulate(disk_model(r=0.3, m=2.0, lean0=1.2), t_end=0.3, n_out=31, backend=backend)
    assert res.status == "failed"
    assert "disk.contact" in res.message and "flat" in res.message
    t_flat = float(res.message.split("at t=")[1].split()[0])
    assert 0.15 < t_flat < 0.2
    assert res.time[-1] <= t_flat and len(res.time) > 10
    assert res["residual.position"].max() < 1e-6 and res["disk.wheel.r.z"].min() > 0
