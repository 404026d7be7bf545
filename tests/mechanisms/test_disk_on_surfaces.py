"""A thin disk rolling without slip on curved surfaces (DiskContact(surface=...)) against closed forms.

Notation: disk radius ``r``, mass ``m``, uniform (``I_axis = m r^2/2``, ``I_diam = m r^2/4``),
``g = 9.81 m/s^2``.

**A coin in a pipe.** A disk rolls inside a horizontal cylinder of radius ``R`` in a plane
normal to the cylinder's axis (or inside a spherical bowl of radius ``R`` in a vertical plane
through its centre, along a great circle). Its centre moves on the circle of radius
``L = R - r`` about the axis; with ``theta`` the centre's angle from the bottom, the centre's
speed is ``L theta'`` and the contact point (on the same radius, ``R`` from the axis) is at
rest, so the disk turns at ``L theta' / r`` about its axis (rolling on the inside of the
circle). Then ``T = 1/2 m L^2 theta'^2 + 1/2 (m r^2 / 2)(L theta' / r)^2 = 3/4 m L^2 theta'^2``
and ``V = -m g L cos(theta)``; Lagrange's equation is ``theta'' = -(2 g / (3 L)) sin(theta)``:

    omega^2 = 2 g / (3 (R - r))       (small oscillations)

At amplitude ``theta0`` the exact period is ``4 K(sin^2(theta0/2)) / omega`` (``K`` the complete
elliptic integral) ``= 2 pi / omega (1 + theta0^2/16 + ...)``: 6.25e-6 above the
small-oscillation period at 0.01 rad, well inside the 1e-4 the period is checked to against
``omega`` (and the run is checked against the elliptic period to 1e-8).

**On top of a dome** (a sphere of radius ``R``, the disk outside, in a vertical plane through
the centre) the same Lagrangian with ``L = R + r`` and ``V = +m g L cos(theta)`` gives the
inverted pendulum ``theta'' = (2 g / (3 L)) sin(theta)``: from rest at ``theta0`` the disk leaves
the top as ``theta0 cosh(lambda t)``, ``lambda^2 = 2 g / (3 (R + r))``, to relative order
``theta^2`` (checked to 1e-4 while ``theta < 5e-3``).

**General rolling** (the disk leaning and turning off any symmetry plane, on a bowl, a pipe
and a height field): energy is conserved, the contact point reported lies on the surface (its
implicit equation, written here), on the rim, where the surface normal is perpendicular to the
rim tangent, and the disk's material point there is at rest.

The contact's jets against finite differences for every surface, the rim point against a
dense search of the rim and the Newton iteration's quadratic convergence are in the first
section; the plane through the surface machinery reproduces the plane contact's rows.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402
from scipy.special import ellipk  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.codegen import c_compiler  # noqa: E402
from mbcomp.jets import FrameJet  # noqa: E402
from mbcomp.kinematics import rot_axis  # noqa: E402
from mbcomp.library import DiskContact, FreeMotion, RigidBody, World  # noqa: E402
from mbcomp.library.contact import rim_point  # noqa: E402
from mbcomp.library.surfaces import CylinderSurface, HeightField, Plane, SphereSurface, TorusSurface  # noqa: E402
from conftest import moving_frame  # noqa: E402

G = 9.81
TIGHT = dict(rtol=1e-10, atol=1e-12, backend="python")
R_DISK, MASS, TH0 = 0.1, 0.5, 0.01


def wavy(x, y):
    return 0.3 * (x * x - 0.5 * y * y) + 0.05 * np.sin(2.0 * x) * np.cos(y) + 0.02 * np.exp(0.3 * y)


def basin(x, y):
    return 0.3 * (x * x + 0.5 * y * y) + 0.05 * np.sin(2.0 * x)


# (surface, a point near it in frame_a coordinates, disk radius)
CASES = {
    "plane": (Plane(n=(0.2, -0.3, 1.0), origin=(0.1, 0, 0)), np.array([0.3, 0.2, 0.4]), 0.3),
    "bowl": (SphereSurface(R=1.2, center=(0.1, 0, 1.0)), np.array([0.4, 0.3, 0.3]), 0.3),
    "dome": (SphereSurface(R=0.8, inside=False), np.array([0.3, -0.2, 1.0]), 0.3),
    "pipe": (CylinderSurface(R=1.0, axis=(1, 0.2, 0), center=(0, 0, 1.0)), np.array([0.5, 0.2, 0.25]), 0.3),
    "rod": (CylinderSurface(R=0.3, axis=(0, 0, 1), inside=False), np.array([0.5, 0.2, 0.3]), 0.2),
    "tube": (TorusSurface(R=2.0, a=0.5), np.array([1.7, 0.8, -0.2]), 0.15),
    "ring": (TorusSurface(R=2.0, a=0.5, axis=(0, 0.3, 1), inside=False), np.array([1.9, 0.7, 0.8]), 0.2),
    "wavy": (HeightField(wavy), np.array([0.5, 0.4, 0.4]), 0.25),
}



def ring(c, ax, r, k=400001):
    """Points of the rim circle (centre c, unit axis ax, radius r), densely."""
    e1 = np.cross(ax, [0.3, -0.5, 0.8])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(ax, e1)
    t = np.linspace(0, 2 * np.pi, k)
    return c + r * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2)


# --------------------------------------------------------------------------- the rim point and the jets

@pytest.mark.parametrize("name", list(CASES))
def test_rim_point_is_the_deepest_point_of_the_rim(name):
    """The rim point found is where the surface's signed distance is least over the rim (a
    dense search of 400001 rim points, not the contact's code) and the Newton step left is at
    machine precision."""
    surf, x, r = CASES[name]
    rng = np.random.default_rng(len(name) + 7)
    ax = rng.normal(size=3)
    ax /= np.linalg.norm(ax)
    u, delta = rim_point(surf, x, ax, r, steps=6)
    pts = ring(x, ax, r)
    dist = np.array([surf.distance(p)[0] for p in pts[::400]])  # coarse, then fine near the least
    k = int(np.argmin(dist)) * 400
    fine = pts[max(k - 800, 0):k + 800]
    G_fine = np.array([surf.distance(p)[0] for p in fine])
    gap = G_fine.min() - surf.distance(x + r * u)[0]  # no sample deeper; as deep as the sampling resolves
    assert -1e-15 < gap < 1e-10
    assert np.linalg.norm(x + r * u - fine[np.argmin(G_fine)]) < 2e-5  # the sampling's step is 1.6e-6 r
    assert abs(delta) < 1e-14 and abs(u @ ax) < 1e-14 and abs(np.linalg.norm(u) - 1) < 1e-14


@pytest.mark.parametrize("name", ["bowl", "dome", "pipe", "tube", "wavy"])
def test_rim_newton_converges_quadratically(name):
    """From the normal at the centre's foot point the error (angle from the converged rim
    direction) falls as the square of the last one (Newton), to 1e-7 rad in 4 steps. On a
    sphere the start is the answer (the deepest rim point lies on the centre's normal line)."""
    surf, x, r = CASES[name]
    ax = np.array([0.6, 0.3, 0.5])
    ax /= np.linalg.norm(ax)
    exact = rim_point(surf, x, ax, r, steps=12)[0]
    errs = [np.arccos(np.clip(rim_point(surf, x, ax, r, steps=k)[0] @ exact, -1, 1)) for k in range(5)]
    if isinstance(surf, SphereSurface):
        assert max(errs) < 1e-7  # arccos near 1 resolves 1e-8
        return
    assert errs[0] > 1e-3  # the start is not the answer
    for e0, e1 in zip(errs[:2], errs[1:3]):
        assert e1 < 2.0 * e0 ** 2, errs
    assert errs[4] < 1e-7, errs


@pytest.mark.parametrize("name", list(CASES))
def test_disk_contact_jets_match_finite_differences(name):
    """frame_a (carrying the surface) and the disk move independently (rows violated): the
    normal row's ``dot`` and ``bias`` are its first and second time derivatives, its ``jac``
    column k the rate for a unit local twist; the velocity rows are ``jac . twist`` and their
    ``bias`` is their time derivative."""
    surf, x, r = CASES[name]
    rng = np.random.default_rng(len(name))
    joint = DiskContact(r=r, surface=surf, axis=rng.normal(size=3))
    p = joint.p
    Ra, ra = Rotation.from_quat(rng.normal(size=4)).as_matrix(), rng.normal(size=3)
    Rb, rb = Rotation.from_quat(rng.normal(size=4)).as_matrix(), None
    rb = ra + Ra @ x
    ta = moving_frame(Ra, ra, *(0.3 * rng.normal(size=(4, 3))))
    tb = moving_frame(Rb, rb, *(0.3 * rng.normal(size=(4, 3))))

    def rows(t, ta=ta, tb=tb):
        a, b = ta(t), tb(t)
        return joint.constraints(a, b, p)[0][1], [c for _, c in joint.velocity_constraints(a, b, p)]

    c0, v0 = rows(0.0)
    h = 1e-5
    val = lambda t, **kw: rows(t, **kw)[0].val  # noqa: E731
    vval = lambda t, **kw: np.array([c.val for c in rows(t, **kw)[1]])  # noqa: E731
    assert abs(c0.val) > 0.05 and np.abs(vval(0.0)).max() > 1e-2  # violated: every term counts
    assert abs(c0.dot - (val(h) - val(-h)) / (2 * h)) < 1e-8
    assert abs(c0.bias - (rows(h)[0].dot - rows(-h)[0].dot) / (2 * h)) < 1e-7
    assert abs(c0.bias - (val(2e-4) - 2 * c0.val + val(-2e-4)) / 4e-8) < 1e-5
    tw = np.concatenate((ta(0).v, ta(0).w, tb(0).v, tb(0).w))
    assert abs(c0.jac @ tw - c0.dot) < 1e-13
    np.testing.assert_allclose([c.jac @ tw for c in v0], vval(0.0), atol=1e-13)
    np.testing.assert_allclose([c.bias for c in v0], (vval(h) - vval(-h)) / (2 * h), atol=1e-7)
    z = np.zeros(3)
    for k in range(12):
        e = np.zeros(12)
        e[k] = 1.0
        sa, sb = moving_frame(Ra, ra, e[3:6], e[0:3], z, z), moving_frame(Rb, rb, e[9:12], e[6:9], z, z)
        assert abs(c0.jac[k] - (val(h, ta=sa, tb=sb) - val(-h, ta=sa, tb=sb)) / (2 * h)) < 1e-8, k
        np.testing.assert_allclose([c.jac[k] for c in v0], vval(0.0, ta=sa, tb=sb), atol=1e-13)


def test_plane_surface_equals_the_disk_contact_without_surface():
    """``Plane(n)`` through the rim machinery gives the plane contact's own rows (value,
    gradient, rate, bias) for random moving frames, to 1e-12 (measured 1e-13)."""
    rng = np.random.default_rng(11)
    n, ax = np.array([0.3, -0.4, 1.0]), np.array([0.2, 1.0, -0.3])
    plain, generic = DiskContact(r=0.4, n=n, axis=ax), DiskContact(r=0.4, surface=Plane(n=n), axis=ax)
    for _ in range(10):
        ta = moving_frame(Rotation.from_quat(rng.normal(size=4)).as_matrix(), rng.normal(size=3), *rng.normal(size=(4, 3)))
        tb = moving_frame(Rotation.from_quat(rng.normal(size=4)).as_matrix(), rng.normal(size=3), *rng.normal(size=(4, 3)))
        a, b = ta(0.0), tb(0.0)
        for method, fields in (("constraints", ("val", "jac", "dot", "bias")), ("velocity_constraints", ("val", "jac", "bias"))):
            for (n1, c1), (n2, c2) in zip(getattr(plain, method)(a, b, plain.p), getattr(generic, method)(a, b, generic.p)):
                assert n1 == n2
                for f in fields:
                    np.testing.assert_allclose(getattr(c2, f), getattr(c1, f), atol=1e-12, err_msg=f"{n1}.{f}")
        assert abs(plain.singularity(a, b, plain.p) - generic.singularity(a, b, generic.p)) < 1e-13


# --------------------------------------------------------------------------- runs

def vec(res, name):
    return np.column_stack([res[f"{name}.{ax}"] for ax in "xyz"])


def disk_on(surface, c0, R0=np.eye(3), v0=(0, 0, 0), w0=(0, 0, 0), axis=(1, 0, 0), r=R_DISK, m=MASS, **contact):
    """A uniform thin disk (FreeMotion from the world; spin axis ``axis`` in its frame) on
    ``surface`` fixed in the world."""
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, 0, -G)))
    free = mdl.add("free", FreeMotion(r0=c0, R0=R0, v0=v0, w0=w0))
    ax = np.asarray(axis, float)
    inertia = m * r * r * (0.25 * np.eye(3) + 0.25 * np.outer(ax, ax))
    disk = mdl.add("disk", RigidBody(m=m, I=inertia))
    c = mdl.add("contact", DiskContact(r=r, surface=surface, axis=axis, **contact))
    mdl.connect(w.frame_b, free.frame_a)
    mdl.connect(free.frame_b, disk.frame_a)
    mdl.connect(w.frame_b, c.frame_a)
    mdl.connect(c.frame_b, disk.frame_a)
    return mdl


def crossings(t, y):
    i = np.nonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)[0]
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


def period(t, y):
    tc = crossings(t, y)
    assert len(tc) >= 5, "too few oscillations"
    return 2.0 * (tc[-1] - tc[0]) / (len(tc) - 1)


def coin_periods(L, theta0):
    """(small-oscillation, exact) periods of ``theta'' = -(2 g / 3 L) sin(theta)``."""
    w = np.sqrt(2.0 * G / (3.0 * L))
    return 2 * np.pi / w, 4.0 * ellipk(np.sin(theta0 / 2) ** 2) / w


R_PIPE = 0.5
PIPE = CylinderSurface(R=R_PIPE, axis=(1, 0, 0), center=(0, 0, R_PIPE))


def pipe_start(R=R_PIPE, th0=TH0):
    return np.array([0.0, 0.0, R]) + (R - R_DISK) * np.array([0.0, np.sin(th0), -np.cos(th0)])


@pytest.fixture(scope="module")
def coin():
    res = mbcomp.simulate(disk_on(PIPE, pipe_start()), t_end=10.0, n_out=4001, **TIGHT)  # 6.4 periods
    assert res.success, res.message
    return res


def test_coin_in_a_pipe_small_oscillation_period(coin):
    """The period of the centre's swing against ``omega^2 = 2 g / (3 (R - r))`` to 1e-4 and
    the elliptic period to 1e-8; the disk stays in its plane; energy and no slip hold."""
    c = vec(coin, "disk.r")
    theta = np.arctan2(c[:, 1], R_PIPE - c[:, 2])
    T = period(coin.time, theta)
    T_lin, T_exact = coin_periods(R_PIPE - R_DISK, TH0)
    assert abs(T / T_lin - 1) < 1e-4 and abs(T / T_exact - 1) < 1e-8
    assert abs(T / (1.0001 * T_lin) - 1) > 5e-5  # a 1e-4 error would be seen
    assert abs(T / T_lin * np.sqrt(14 / 15) - 1) > 0.03  # not a ball's period (5/7 for 2/3): 3.5 % off
    assert np.abs(c[:, 0]).max() < 1e-12 and np.abs(vec(coin, "disk.w")[:, 1:]).max() < 1e-12
    np.testing.assert_allclose(np.hypot(c[:, 1], R_PIPE - c[:, 2]), R_PIPE - R_DISK, atol=1e-10)
    E = coin["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-8 * MASS * G * R_DISK
    assert coin["residual.nonholonomic"].max() < 1e-9
    np.testing.assert_allclose(coin["contact.N"], MASS * G, rtol=1e-3)  # weight, plus 1e-4 centripetal


@pytest.mark.skipif(c_compiler() is None, reason="no C compiler")
def test_c_program_rolls_the_coin_as_the_numeric_path(coin):
    """The numeric evaluation and the C program give the same motion (1e-8 m) as the Python
    program, over the coin's first 2.5 s (1.6 swings, the same output times; they agree to
    3e-14 and 1.3e-12 m, over 10 s to 4e-15 and 3e-12: the numeric path's 10 s took 8 s)."""
    n = 1001
    for backend in ("numeric", "c"):
        res = mbcomp.simulate(disk_on(PIPE, pipe_start()), t_end=2.5, n_out=n, rtol=1e-10, atol=1e-12,
                              backend=backend)
        assert res.success and res.stats["backend"] == backend, res.message
        np.testing.assert_array_equal(res.time, coin.time[:n])
        np.testing.assert_allclose(vec(res, "disk.r"), vec(coin, "disk.r")[:n], atol=1e-8)


def test_disk_in_a_bowl_along_a_great_circle():
    """Inside a spherical bowl of radius 1 m, in the vertical plane through its centre: the
    same period with ``R`` the bowl's radius."""
    R = 1.0
    bowl = SphereSurface(R=R, center=(0, 0, R))
    res = mbcomp.simulate(disk_on(bowl, pipe_start(R)), t_end=10.0, n_out=4001, **TIGHT)
    assert res.success, res.message
    c = vec(res, "disk.r")
    T = period(res.time, np.arctan2(c[:, 1], R - c[:, 2]))
    T_lin, T_exact = coin_periods(R - R_DISK, TH0)
    assert abs(T / T_lin - 1) < 1e-4 and abs(T / T_exact - 1) < 1e-8
    np.testing.assert_allclose(np.linalg.norm(c - (0, 0, R), axis=1), R - R_DISK, atol=1e-10)


def test_disk_leaves_the_top_of_a_dome_at_the_closed_form_rate():
    """On top of a sphere of radius 1 m: ``theta = theta0 cosh(lambda t)`` with
    ``lambda^2 = 2 g / (3 (R + r))`` while the angle is small (and not the ball's 5/7)."""
    R, th0 = 1.0, 1e-6
    L = R + R_DISK
    c0 = L * np.array([0.0, np.sin(th0), np.cos(th0)])
    res = mbcomp.simulate(disk_on(SphereSurface(R=R, inside=False), c0), t_end=4.0, n_out=4001, **TIGHT)
    assert res.success, res.message
    c = vec(res, "disk.r")
    theta = np.arctan2(c[:, 1], c[:, 2])
    lam = np.sqrt(2 * G / (3 * L))
    small = theta < 5e-3
    assert small.sum() > 3000 and theta.max() > 5e-3
    np.testing.assert_allclose(theta[small], th0 * np.cosh(lam * res.time[small]), rtol=1e-4)
    ball = th0 * np.cosh(np.sqrt(5 * G / (7 * L)) * res.time[small])
    assert np.abs(theta[small] / ball - 1).max() > 1e-2


def place(surface, c, R0, axis, r=R_DISK):
    """The centre moved along the normal until the rim touches ``surface``; the rim direction."""
    ax = R0 @ np.asarray(axis, float)
    for _ in range(40):
        u = rim_point(surface, c, ax, r, 8)[0]
        Gs, n, _, _ = surface.distance(c + r * u)
        c = c - Gs * n
    return c, u


GENERAL = {  # surface, implicit equation F(point on the surface) = 0, start near the surface, (lean, yaw, spin, t_end)
    "bowl": (SphereSurface(R=1.0, center=(0, 0, 1.0)), lambda p: np.linalg.norm(p - (0, 0, 1.0), axis=1) - 1.0,
             (0.1, 0.05, 0.12), (0.05, 0.5, 12.0, 0.5)),
    "pipe": (PIPE, lambda p: np.hypot(p[:, 1], p[:, 2] - R_PIPE) - R_PIPE, (0.0, 0.05, 0.12), (0.05, 0.5, 10.0, 1.5)),
    "basin": (HeightField(basin), lambda p: p[:, 2] - basin(p[:, 0], p[:, 1]), (0.05, 0.05, 0.2), (0.1, 0.3, 10.0, 1.5)),
}


@pytest.mark.parametrize("name", list(GENERAL))
def test_leaning_disk_rolls_on_the_surface_without_slip_and_conserves_energy(name):
    """A disk leaning 0.05 to 0.1 rad, its plane turned off any symmetry plane, rolling at 1 to
    1.2 m/s (it wobbles, turns and leans up to 70 degrees while pressing on the surface): the
    contact point lies on the surface, on the rim, where the surface normal is perpendicular to
    the rim tangent; the disk's material point there is at rest; energy is conserved to 1e-8
    of m g r (measured 1e-10)."""
    surf, F, c0, (lean, yaw, spin, t_end) = GENERAL[name]
    R0 = rot_axis([0, 0, 1], yaw) @ rot_axis([1, 0, 0], lean)
    axis = np.array([0.0, 1.0, 0.0])
    c0, u = place(surf, np.array(c0), R0, axis)
    w0 = spin * axis
    res = mbcomp.simulate(disk_on(surf, c0, R0=R0, v0=-np.cross(R0 @ w0, R_DISK * u), w0=w0, axis=axis),
                          t_end=t_end, n_out=601, **TIGHT)
    assert res.success, res.message
    c, v, w, P = vec(res, "disk.r"), vec(res, "disk.v"), vec(res, "disk.w"), vec(res, "contact.p")
    Q = np.column_stack([res[f"free.Q.{k}"] for k in "xyzw"])
    ax = Rotation.from_quat(Q).apply(axis)
    assert np.abs(ax[:, 2]).max() > 0.15 and np.ptp(np.arctan2(ax[:, 1], ax[:, 0])) > 0.1  # leans and turns
    assert np.abs(F(P)).max() < 1e-10
    np.testing.assert_allclose(np.linalg.norm(P - c, axis=1), R_DISK, atol=1e-12)
    assert np.abs(np.einsum("ij,ij->i", P - c, ax)).max() < 1e-12
    h = 1e-6  # the surface normal by central differences of the implicit equation
    grad = np.column_stack([(F(P + h * e) - F(P - h * e)) / (2 * h) for e in np.eye(3)])
    tangent = np.cross(ax, P - c)
    assert np.abs(np.einsum("ij,ij->i", grad, tangent)).max() < 1e-8
    assert np.abs(v + np.cross(w, P - c)).max() < 1e-9
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-8 * MASS * G * R_DISK
    assert res["contact.N"].min() > 0.0


# --------------------------------------------------------------------------- errors

def test_errors_name_the_contact_and_the_fix():
    with pytest.raises(mbcomp.ModelError, match=r"contact\.surface.*disk \(r = 0\.1 m\) does not fit inside"):
        disk_on(CylinderSurface(R=0.05), (0, 0, 0)).validate()
    with pytest.raises(mbcomp.ModelError, match=r"contact\.surface.*is not a surface.*CylinderSurface"):
        disk_on("pipe", (0, 0, 0)).validate()
    with pytest.raises(mbcomp.ModelError, match=r"contact\.rim_steps.*whole number"):
        disk_on(PIPE, pipe_start(), rim_steps=2.5).validate()
    # one Newton step from a poor start (a disk leaning far over in a pipe) is refused
    a = FrameJet.ground(nu=0)
    lean = rot_axis([0, 1, 0], 1.2)
    b = FrameJet.ground(nu=0, R=lean, r=place(PIPE, np.array([0.0, 0.3, 0.1]), lean, (1, 0, 0))[0])
    c = DiskContact(r=R_DISK, surface=PIPE, axis=(1, 0, 0), rim_steps=1)
    with pytest.raises(mbcomp.SimulationError, match=r"rim point on CylinderSurface.*not found in 1 Newton steps"):
        c.constraints(a, b, c.p)
    good = DiskContact(r=R_DISK, surface=PIPE, axis=(1, 0, 0))
    assert abs(good.constraints(a, b, good.p)[0][1].val) < 1e-12
