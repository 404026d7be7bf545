"""The evaluation's derivative programs (mbcomp.codegen.eval_tangent) against central
differences of the jet recursion (Taylor tests): along a random direction the difference
quotient's error falls as h^2 over three decades, to the exact program's value. Models: the
Whipple bicycle (quaternion free joint, rolling contacts: holonomic and nonholonomic rows),
the slider-crank (a loop) and the bead on a spinning ring (a prescribed motion evaluated per
call)."""
import numpy as np
import pytest

import mbcomp
from conftest import load_model
from mbcomp.assembly.kkt import accelerations
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen.eval_tangent import eval_tangent
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Revolute, World

BICYCLE = load_model("models/bicycle.py")
SLIDER_CRANK = load_model("models/slider_crank.py")


def bead():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    spin = m.add("spin", Revolute(n=(0, 1, 0)))
    drive = m.add("drive", PrescribedMotion(s=lambda t: 3.0 * t + 0.4 * t * t))
    hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.3, w0=0.2))
    rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0)))
    b = m.add("bead", PointMass(m=0.1))
    m.connect(w.frame_b, spin.frame_a)
    m.connect(drive.flange_b, spin.axis)
    m.connect(spin.frame_b, hinge.frame_a)
    m.connect(hinge.frame_b, rod.frame_a)
    m.connect(rod.frame_b, b.frame_a)
    return m


def groups(system, t, q, u, a, lam):
    """``R1, R2, G`` of the module docstring from the jet recursion (every holonomic row)."""
    ev = system.evaluate_numeric(t, q, u, masked=False)
    A = np.vstack((ev.C, ev.B))
    R1 = ev.f - ev.M @ a - A.T @ lam
    R2 = -np.concatenate((ev.cb, ev.Bb)) - A @ a
    return np.concatenate((R1, R2, ev.Phid, ev.Psi))


@pytest.mark.parametrize("name, build, t", [("bicycle", lambda: BICYCLE.build(v=4.0, roll_rate0=0.3), 0.0),
                                            ("slider-crank", lambda: SLIDER_CRANK.build(), 0.2),
                                            ("bead", bead, 0.7)])
def test_derivatives_pass_the_taylor_test(name, build, t):
    system = mbcomp.assemble(build())
    init = initialize(system, t)
    q, u = init.q, init.u
    rng = np.random.default_rng(7)
    ev = system.evaluate(t, q, u)
    ud, lam_kept = accelerations(ev)
    mask = system.row_mask
    m_all = len(mask) if mask is not None else ev.C.shape[0]
    lam = np.zeros(m_all + ev.B.shape[0])
    lam[np.concatenate((np.flatnonzero(mask) if mask is not None else np.arange(m_all),
                        m_all + np.arange(ev.B.shape[0])))] = lam_kept
    a = ud + rng.normal(size=ud.size)  # any a, lam: the program takes them as inputs
    lam = lam + rng.normal(size=lam.size)
    dev = eval_tangent(system)
    Q = dev.Q(q)
    delta, du = rng.normal(size=system.nu), rng.normal(size=system.nu)
    dq = Q @ delta  # along the coordinates' own motion (quaternions stay unit to first order)
    exact = np.concatenate(dev.jvp(t, q, u, a, lam, dq, du))
    scale = np.abs(exact).max()
    errs = []
    for h in (1e-2, 1e-3, 1e-4):
        fd = (groups(system, t, system.increment(q, h * delta), u + h * du, a, lam)
              - groups(system, t, system.increment(q, -h * delta), u - h * du, a, lam)) / (2 * h)
        errs.append(np.abs(fd - exact).max() / scale)
    # the second-order error falls 100x per decade (rounding stays below it at these h);
    # measured: bicycle 2.2e-4, 2.2e-6, 2.2e-8; slider-crank 1.4e-5 .. 1.4e-9; bead 4.1e-6 .. 4.1e-10
    assert errs[0] > 1e-8, errs  # the test sees the truncation error at all
    assert errs[1] < errs[0] / 50 and errs[2] < errs[1] / 50, errs


def test_q_is_the_coordinates_motion_along_the_speeds():
    """``Q(q) u`` is ``dq/dt``: the bicycle's quaternion kinematics, exactly (linear in u)."""
    system = mbcomp.assemble(BICYCLE.build(v=4.0, roll_rate0=0.3))
    init = initialize(system)
    Q = eval_tangent(system).Q(init.q)
    np.testing.assert_allclose(Q @ init.u, system.q_rate_numeric(init.q, init.u), rtol=0, atol=1e-15)
