"""Surfaces of library/surfaces.py: the distance, normal and curvature each gives, and the
jets a ball on them gets (``surface_rows``), against finite differences along exact motions.

* ``HeightJet`` against hand derivatives and central differences;
* ``distance``: ``n`` is the gradient of ``G`` and ``K`` its Hessian (central differences
  of ``G`` and ``n``), ``K n = 0``, ``K`` symmetric; the centre minus ``G n`` lies on the
  surface (checked with the surface's own implicit equation, written here);
* the spherical cap as a ``HeightField`` gives ``SphereSurface``'s ``G``, ``n``, ``K``;
* the contact's rows: ``dot``, ``bias`` and ``jac`` of the normal row, and the velocity rows'
  ``jac`` and ``bias``, against finite differences for two independently moving frames;
* ``Plane`` gives the same rows as the contact without a surface; clear errors.
"""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbcomp
from mbcomp.jets import FrameJet
from mbcomp.library import FreeMotion, RigidBody, SphereContact, World
from mbcomp.library.surfaces import (CylinderSurface, HeightField, HeightJet, Plane, SphereSurface, TorusSurface,
                                     surface_rows)
from conftest import moving_frame


def cap(R):
    """The bowl of radius R with its bottom at the origin, as a height field."""
    return lambda x, y: R - np.sqrt(R * R - x * x - y * y)


def wavy(x, y):
    return 0.3 * (x * x - 0.5 * y * y) + 0.05 * np.sin(2.0 * x) * np.cos(y) + 0.02 * np.exp(0.3 * y)


# (surface, point near it in frame_a coordinates, implicit equation F(point on surface) = 0)
CASES = {
    "plane": (Plane(n=(0.2, -0.3, 1.0), origin=(0.1, 0, 0)), np.array([0.3, 0.2, 0.4]),
              lambda p: p @ (np.array([0.2, -0.3, 1.0]) / np.linalg.norm([0.2, -0.3, 1.0])) - 0.1 * 0.2 / np.linalg.norm([0.2, -0.3, 1.0])),
    "bowl": (SphereSurface(R=1.2, center=(0.1, 0, 1.0)), np.array([0.4, 0.3, 0.3]),
             lambda p: np.linalg.norm(p - (0.1, 0, 1.0)) - 1.2),
    "dome": (SphereSurface(R=0.8, inside=False), np.array([0.3, -0.2, 1.0]), lambda p: np.linalg.norm(p) - 0.8),
    "pipe": (CylinderSurface(R=1.0, axis=(1, 0.2, 0), center=(0, 0, 1.0)), np.array([0.5, 0.2, 0.25]),
             lambda p: np.linalg.norm(np.cross(p - (0, 0, 1.0), np.array([1, 0.2, 0]) / np.hypot(1, 0.2))) - 1.0),
    "rod": (CylinderSurface(R=0.3, axis=(0, 0, 1), inside=False), np.array([0.5, 0.2, 0.3]),
            lambda p: np.hypot(p[0], p[1]) - 0.3),
    "tube": (TorusSurface(R=2.0, a=0.5, inside=True), np.array([1.7, 0.8, -0.2]),
             lambda p: np.hypot(np.hypot(p[0], p[1]) - 2.0, p[2]) - 0.5),
    "ring": (TorusSurface(R=2.0, a=0.5, axis=(0, 0.3, 1), inside=False), np.array([1.9, 0.7, 0.8]),
             lambda p: torus_f(p, np.array([0, 0.3, 1]) / np.hypot(0.3, 1), 2.0, 0.5)),
    "cap": (HeightField(cap(1.5)), np.array([0.4, -0.3, 0.3]), lambda p: p[2] - cap(1.5)(p[0], p[1])),
    "wavy": (HeightField(wavy), np.array([0.5, 0.4, 0.4]), lambda p: p[2] - wavy(p[0], p[1])),
}


def torus_f(p, k, R, a):
    z = p @ k
    return np.hypot(np.linalg.norm(p - z * k) - R, z) - a


def test_height_jet_derivatives():
    """h = x^2 y + sqrt(1 + x y) / (2 - y) + tanh(x) y^3: gradient and Hessian by hand."""
    x0, y0 = 0.4, -0.7
    X, Y = HeightJet.variables(x0, y0)
    z = X ** 2 * Y + np.sqrt(1.0 + X * Y) / (2.0 - Y) + np.tanh(X) * Y ** 3
    f = lambda x, y: x * x * y + np.sqrt(1 + x * y) / (2 - y) + np.tanh(x) * y ** 3
    h = 1e-4
    gx = (f(x0 + h, y0) - f(x0 - h, y0)) / (2 * h)
    gy = (f(x0, y0 + h) - f(x0, y0 - h)) / (2 * h)
    hxx = (f(x0 + h, y0) - 2 * f(x0, y0) + f(x0 - h, y0)) / h ** 2
    hyy = (f(x0, y0 + h) - 2 * f(x0, y0) + f(x0, y0 - h)) / h ** 2
    hxy = (f(x0 + h, y0 + h) - f(x0 + h, y0 - h) - f(x0 - h, y0 + h) + f(x0 - h, y0 - h)) / (4 * h * h)
    assert abs(z.val - f(x0, y0)) < 1e-15
    np.testing.assert_allclose(z.g, [gx, gy], atol=1e-8)
    np.testing.assert_allclose(z.H, [hxx, hxy, hyy], atol=2e-6)
    # exact values for a polynomial: h = x^2 y -> (2xy, x^2), (2y, 2x, 0)
    p = X * X * Y
    np.testing.assert_allclose(p.g, [2 * x0 * y0, x0 * x0], atol=1e-15)
    np.testing.assert_allclose(p.H, [2 * y0, 2 * x0, 0.0], atol=1e-15)


@pytest.mark.parametrize("name", list(CASES))
def test_distance_gradient_and_curvature(name):
    """``n = grad G``, ``K = grad n`` (central differences), ``K`` symmetric with ``K n = 0``,
    ``|n| = 1``; the foot point ``x - G n`` satisfies the surface's implicit equation."""
    surf, x, F = CASES[name]
    G, n, K, err = surf.distance(x)
    assert abs(np.linalg.norm(n) - 1) < 1e-14 and err < 1e-12
    h = 1e-6
    E = np.eye(3)
    dG = np.array([(surf.distance(x + h * e)[0] - surf.distance(x - h * e)[0]) / (2 * h) for e in E])
    dn = np.column_stack([(surf.distance(x + h * e)[1] - surf.distance(x - h * e)[1]) / (2 * h) for e in E])
    np.testing.assert_allclose(dG, n, atol=1e-9)
    np.testing.assert_allclose(dn, K, atol=1e-8)
    np.testing.assert_allclose(K, K.T, atol=1e-12)
    np.testing.assert_allclose(K @ n, 0.0, atol=1e-12)
    assert abs(F(x - G * n)) < 1e-12
    assert abs(G) > 0.05  # a point off the surface, so the test means something


def test_cap_height_field_is_the_sphere():
    """The spherical cap as a height field: ``G``, ``n``, ``K`` equal the sphere's to 1e-12
    over points up to 40 degrees up the bowl wall, 0.02 to 0.3 m from the surface."""
    R = 1.0
    field, sphere = HeightField(cap(R)), SphereSurface(R=R, center=(0, 0, R))
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(50):
        th, ph, s = rng.uniform(0, 0.7), rng.uniform(0, 2 * np.pi), rng.uniform(0.02, 0.3)
        x = np.array([0, 0, R]) + (R - s) * np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), -np.cos(th)])
        a, b = field.distance(x), sphere.distance(x)
        worst = max(worst, abs(a[0] - b[0]), np.abs(a[1] - b[1]).max(), np.abs(a[2] - b[2]).max())
    assert worst < 1e-12, worst


def test_newton_step_count_sets_the_accuracy():
    """One Newton step from the point below the centre is not exact on a steep wall; the error
    falls quadratically with the steps (each step's error about the square of the last's)."""
    R = 1.0
    sphere = SphereSurface(R=R, center=(0, 0, R))
    x = np.array([0, 0, R]) + 0.8 * np.array([np.sin(0.6), 0.0, -np.cos(0.6)])
    exact = sphere.distance(x)[0]
    errs = [abs(HeightField(cap(R), newton_steps=k).distance(x)[0] - exact) for k in (1, 2, 3)]
    assert errs[0] > 1e-5 and errs[1] < errs[0] ** 1.5 and errs[2] < 1e-14


# --------------------------------------------------------------------------- jets of the rows


@pytest.mark.parametrize("name", list(CASES))
def test_row_jets_match_finite_differences(name):
    """frame_a (carrying the surface) and the ball's centre move independently (rows violated,
    not too far from the surface): the normal row's ``dot`` and ``bias`` are its first and
    second time derivatives, its ``jac`` column k the rate for a unit local twist; the velocity
    rows are ``jac . twist`` and their ``bias`` is their time derivative."""
    surf, x, _ = CASES[name]
    rng = np.random.default_rng(len(name))
    r = 0.2 * abs(surf.distance(x)[0])
    Ra = Rotation.from_quat(rng.normal(size=4)).as_matrix()
    ra = rng.normal(size=3)
    Rb = Rotation.from_quat(rng.normal(size=4)).as_matrix()
    rb = ra + Ra @ x
    sc = 0.3
    ta = moving_frame(Ra, ra, *(sc * rng.normal(size=(4, 3))))
    tb = moving_frame(Rb, rb, *(sc * rng.normal(size=(4, 3))))

    def rows(t, ta=ta, tb=tb):
        hol, vel, _ = surface_rows(surf, ta(t), tb(t), r)
        return hol[0][1], [c for _, c in vel]

    c0, v0 = rows(0.0)
    h = 1e-5
    val = lambda t, **kw: rows(t, **kw)[0].val
    assert abs(c0.dot - (val(h) - val(-h)) / (2 * h)) < 1e-8
    assert abs(c0.bias - (rows(h)[0].dot - rows(-h)[0].dot) / (2 * h)) < 1e-7
    assert abs(c0.bias - (val(2e-4) - 2 * c0.val + val(-2e-4)) / 4e-8) < 1e-4
    tw = np.concatenate((ta(0).v, ta(0).w, tb(0).v, tb(0).w))
    assert abs(c0.jac @ tw - c0.dot) < 1e-13
    vval = lambda t, **kw: np.array([c.val for c in rows(t, **kw)[1]])
    np.testing.assert_allclose([c.jac @ tw for c in v0], vval(0.0), atol=1e-13)
    np.testing.assert_allclose([c.bias for c in v0], (vval(h) - vval(-h)) / (2 * h), atol=1e-7)
    assert np.abs(vval(0.0)).max() > 1e-3
    z = np.zeros(3)
    for k in range(12):
        e = np.zeros(12)
        e[k] = 1.0
        sa, sb = moving_frame(Ra, ra, e[3:6], e[0:3], z, z), moving_frame(Rb, rb, e[9:12], e[6:9], z, z)
        fd = (val(h, ta=sa, tb=sb) - val(-h, ta=sa, tb=sb)) / (2 * h)
        assert abs(c0.jac[k] - fd) < 1e-8, k
        np.testing.assert_allclose([c.jac[k] for c in v0], vval(0.0, ta=sa, tb=sb), atol=1e-13)


def test_plane_surface_equals_the_contact_without_surface():
    """``Plane(n)`` through the generic surface rows gives the plane contact's own rows."""
    rng = np.random.default_rng(11)
    n = np.array([0.3, -0.4, 1.0])
    plain, generic = SphereContact(r=0.2, n=n), SphereContact(r=0.2, surface=Plane(n=n))
    ta = moving_frame(Rotation.from_quat(rng.normal(size=4)).as_matrix(), rng.normal(size=3), *rng.normal(size=(4, 3)))
    tb = moving_frame(Rotation.from_quat(rng.normal(size=4)).as_matrix(), rng.normal(size=3), *rng.normal(size=(4, 3)))
    a, b = ta(0.0), tb(0.0)
    for method in ("constraints", "velocity_constraints"):
        for (n1, c1), (n2, c2) in zip(getattr(plain, method)(a, b, plain.p), getattr(generic, method)(a, b, generic.p)):
            assert n1 == n2
            for f in ("val", "jac", "bias"):
                np.testing.assert_allclose(getattr(c2, f), getattr(c1, f), atol=1e-12, err_msg=f"{n1}.{f}")


# --------------------------------------------------------------------------- errors

def ball_in(surface, r=0.1, r0=(0, 0, 0.1)):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    free = m.add("free", FreeMotion(r0=r0))
    ball = m.add("ball", RigidBody(m=1.0, I=0.004 * np.eye(3)))
    c = m.add("bowl", SphereContact(r=r, surface=surface))
    m.connect(w.frame_b, free.frame_a)
    m.connect(free.frame_b, ball.frame_a)
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, ball.frame_a)
    return m


def test_errors_name_the_contact_and_the_fix():
    with pytest.raises(mbcomp.ModelError, match=r"bowl\.surface.*does not fit inside.*smaller ball"):
        ball_in(SphereSurface(R=0.05, center=(0, 0, 0.05))).validate()
    with pytest.raises(mbcomp.ModelError, match=r"bowl\.surface.*is not a surface.*SphereSurface"):
        ball_in("bowl").validate()
    with pytest.raises(ValueError, match="TorusSurface: tube radius"):
        TorusSurface(R=1.0, a=2.0)
    with pytest.raises(ValueError, match="HeightField: h="):
        HeightField(3.0)
    with pytest.raises(TypeError, match=r"HeightField: h=.*np.sqrt, not math.sqrt"):
        HeightField(lambda x, y: math.sqrt(1.0 + x * x)).distance(np.array([0.1, 0.2, 0.3]))
    with pytest.raises(ValueError, match="CylinderSurface: axis"):
        CylinderSurface(axis=(0, 0, 0))
    # a single Newton step on a steep wall: the numeric evaluation refuses an unconverged foot point
    R = 1.0
    x = np.array([0, 0, R]) + 0.8 * np.array([np.sin(0.6), 0.0, -np.cos(0.6)])
    a = FrameJet.ground(nu=0)
    b = FrameJet.ground(nu=0, r=x)
    with pytest.raises(mbcomp.SimulationError, match=r"cup: the foot point .* did not converge in 1 Newton steps"):
        surface_rows(HeightField(cap(R), newton_steps=1), a, b, 0.2, "cup")


def test_surfaces_compare_by_geometry():
    """Equal surfaces are equal and hash alike (a generated program is reused for them)."""
    assert SphereSurface(R=1.0) == SphereSurface(R=1.0, center=(0, 0, 0)) != SphereSurface(R=1.0, inside=False)
    assert hash(TorusSurface(R=2, a=0.5)) == hash(TorusSurface(R=2.0, a=0.5))
    assert HeightField(wavy) == HeightField(wavy) != HeightField(wavy, newton_steps=3)
