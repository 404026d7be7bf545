"""The rolling disk driven over a bump lifts off where the normal force reaches zero (issue 22).

A thin disk (radius r, rolling upright along x) runs over a Gaussian bump z = A exp(-(x - x_b)^2
/ w^2) on a height field. Its centre follows the bump's offset curve; where the centripetal
acceleration that curve asks for exceeds what gravity can give, the normal force of the
bilateral contact turns negative. With the contact unilateral the disk leaves the ground at
that instant: the unilateral run's lift-off ("release") equals the time the bilateral run's N
crosses zero, the two runs agree up to it, and after it the disk flies (its centre on a
parabola, its spin constant) until it touches down again with an impact.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import DiskContact, RigidBody, World
from mbcomp.library.surfaces import HeightField

G, R_DISK, MASS = 9.81, 0.3, 2.0
A, W, X_BUMP = 0.05, 0.3, 1.0
TOL = dict(rtol=1e-10, atol=1e-12)


def bump(x, y):
    return A * np.exp(-((x - X_BUMP) / W) ** 2)


def disk_over_bump(v, unilateral):
    m = mbcomp.Model()
    m.add("world", World(g=(0, 0, -G)))
    I = MASS * R_DISK ** 2 * np.diag([0.25, 0.5, 0.25])      # spin axis y
    m.add("disk", RigidBody(m=MASS, I=I), free=True)
    c = m.add("contact", DiskContact(r=R_DISK, n=(0, 0, 1), axis=(0, 1, 0), surface=HeightField(bump),
                                     unilateral=unilateral, restitution=0.0))
    m.connect(m["world"].frame_b, c.frame_a)
    m.connect(c.frame_b, m["disk"].frame_a)
    params = {"disk.free.r0": (-0.5, 0.0, R_DISK + bump(-0.5, 0.0)), "disk.free.v0": (v, 0.0, 0.0),
              "disk.free.w0": (0.0, v / R_DISK, 0.0)}
    return m, params


@pytest.fixture(scope="module")
def runs():
    out = {}
    for unilateral, n_out in ((False, 8001), (True, 801)):  # the bilateral N is read off a fine grid
        m, params = disk_over_bump(5.0, unilateral)
        out[unilateral] = mbcomp.simulate(m, t_end=0.8, params=params, n_out=n_out, **TOL)
    return out


def test_lift_off_is_where_the_bilateral_normal_force_reaches_zero(runs):
    bil, uni = runs[False], runs[True]
    N = bil["contact.N"]
    k = int(np.flatnonzero((N[:-1] > 0) & (N[1:] <= 0))[0])   # the bilateral N crosses zero in [t_k, t_k+1]
    t_zero = bil.time[k] - N[k] * (bil.time[k + 1] - bil.time[k]) / (N[k + 1] - N[k])
    lift = [e for e in uni.events if e.component == "contact" and e.kind == "release"]
    assert lift, [(e.time, e.kind) for e in uni.events]
    # the zero of N found by linear interpolation on the 1e-4 s grid is off by about |N''| dt^2 / (8 |N'|):
    # measured 7.6e-9 s (1.3e-6 on a 1e-3 s grid, 3.4e-10 on 1e-5 s: it converges to the event's time)
    assert abs(lift[0].time - t_zero) < 2e-8
    before = uni.time < lift[0].time
    assert np.allclose(uni["disk.r.x"][before], np.interp(uni.time[before], bil.time, bil["disk.r.x"]), atol=1e-7)
    assert np.all(N[:k] > 0)


def test_in_flight_the_disk_follows_a_parabola_and_keeps_its_spin(runs):
    uni = runs[True]
    lift = next(e for e in uni.events if e.component == "contact" and e.kind == "release")
    land = next((e for e in uni.events if e.component == "contact" and e.kind in ("impact", "engage")
                 and e.time > lift.time), None)
    end = land.time if land is not None else uni.time[-1]
    fly = (uni.time > lift.time + 1e-6) & (uni.time < end - 1e-6)
    assert fly.sum() > 5
    t, z, vz = uni.time[fly], uni["disk.r.z"][fly], uni["disk.v.z"][fly]
    assert np.allclose(np.diff(vz) / np.diff(t), -G, rtol=1e-6)            # free fall
    assert np.ptp(uni["disk.v.x"][fly]) < 1e-9                              # no horizontal force
    assert np.ptp(uni["disk.w.y"][fly]) < 1e-9                              # the spin is kept
    assert np.all(uni["contact.N"][fly] == 0.0)
    assert z[0] > R_DISK  # off the ground
