"""Physics of the scaling-benchmark models (models/n_link_pendulum.py, models/chain_3d.py).

* N = 1: the compound pendulum ``(m L^2 / 3) phi'' = -m g (L/2) sin(phi)`` integrated
  independently with scipy;
* N = 2: the classic double compound pendulum (two uniform rods) in absolute angles,
  derived by hand from its Lagrangian (``theta_1 = phi_1``, ``theta_2 = phi_1 + phi_2``)::

      (4/3) m L^2 th1'' + (1/2) m L^2 cos(th1 - th2) th2'' + (1/2) m L^2 sin(th1 - th2) th2'^2
          + (3/2) m g L sin(th1) = 0
      (1/2) m L^2 cos(th1 - th2) th1'' + (1/3) m L^2 th2'' - (1/2) m L^2 sin(th1 - th2) th1'^2
          + (1/2) m g L sin(th2) = 0

* N = 5: the total energy is conserved;
* the 3-D chain: energy and the vertical angular momentum about the pivot, computed here
  from the bodies' outputs (``L = sum m r_c x v_c + R I R^T w``), are conserved, and the
  motion leaves every plane through the vertical.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.kinematics import quat_to_matrix

from conftest import load_model

PEND = load_model("models/n_link_pendulum.py")
CHAIN = load_model("models/chain_3d.py")
G, L, M = 9.81, 0.5, 1.0
TOL = dict(rtol=1e-10, atol=1e-12)


def test_one_link_is_the_compound_pendulum():
    r = mbcomp.simulate(PEND.build(N=1, L=L, m=M, phi0=1.0, w0=0.5), t_end=2.0, n_out=201, **TOL)
    assert r.success, r.message

    def rhs(t, y):
        return [y[1], -1.5 * G / L * np.sin(y[0])]

    ref = solve_ivp(rhs, (0, 2.0), [1.0, 0.5], t_eval=r.time, **TOL)
    np.testing.assert_allclose(r["phi1"], ref.y[0], atol=1e-8)
    np.testing.assert_allclose(r["joint1.w"], ref.y[1], atol=1e-8)
    assert np.ptp(r["phi1"]) > 1.5  # it really swings


def test_two_links_are_the_double_compound_pendulum():
    r = mbcomp.simulate(PEND.build(N=2, L=L, m=M, phi0=(0.9, -0.4), w0=(0.0, 1.0)), t_end=2.0, n_out=201, **TOL)
    assert r.success, r.message
    mL2 = M * L ** 2

    def rhs(t, y):
        t1, t2, w1, w2 = y
        c, s = np.cos(t1 - t2), np.sin(t1 - t2)
        A = np.array([[4 / 3 * mL2, 0.5 * mL2 * c], [0.5 * mL2 * c, mL2 / 3]])
        b = -np.array([0.5 * mL2 * s * w2 ** 2 + 1.5 * M * G * L * np.sin(t1),
                       -0.5 * mL2 * s * w1 ** 2 + 0.5 * M * G * L * np.sin(t2)])
        return [w1, w2, *np.linalg.solve(A, b)]

    ref = solve_ivp(rhs, (0, 2.0), [0.9, 0.5, 0.0, 1.0], t_eval=r.time, **TOL)
    np.testing.assert_allclose(r["phi1"], ref.y[0], atol=1e-7)
    np.testing.assert_allclose(r["phi1"] + r["phi2"], ref.y[1], atol=1e-7)
    np.testing.assert_allclose(r["joint1.w"], ref.y[2], atol=1e-6)
    # the check has teeth: the second link moves relative to the first
    assert np.ptp(r["phi2"]) > 0.5


def test_five_links_conserve_energy():
    r = mbcomp.simulate(PEND.build(N=5), t_end=1.0, rtol=1e-9, atol=1e-11)
    assert r.success, r.message
    E = r["energy.total"]
    scale = np.abs(r["energy.kinetic"]).max()
    assert scale > 1.0  # the chain falls and swings
    assert np.ptp(E) < 1e-6 * scale
    # the links stay in the plane and keep their length (hinge k+1 at the end of link k)
    for k in range(1, 5):
        d = np.column_stack([r[f"link{k + 1}.r.{a}"] - r[f"link{k}.r.{a}"] for a in "xyz"])
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), L, rtol=1e-12)
        assert np.abs(r[f"link{k}.r.z"]).max() < 1e-14


def _chain_invariants(r, N, m=1.0, a=0.02, length=0.5):
    I = CHAIN.cylinder_inertia(m, length, a)
    c_body = np.array([0.0, -length / 2, 0.0])
    E = np.zeros(len(r.time))
    Lv = np.zeros((len(r.time), 3))
    for k in range(1, N + 1):
        Q = np.column_stack([r[f"link{k}.Q.{x}"] for x in "wxyz"])
        R = np.array([quat_to_matrix(x) for x in Q])
        w = np.column_stack([r[f"link{k}.w.{x}"] for x in "xyz"])
        c = R @ c_body
        rc = np.column_stack([r[f"link{k}.r.{x}"] for x in "xyz"]) + c
        vc = np.column_stack([r[f"link{k}.v.{x}"] for x in "xyz"]) + np.cross(w, c)
        Iw = np.einsum("nij,nj->ni", R @ I @ R.transpose(0, 2, 1), w)
        Lv += m * np.cross(rc, vc) + Iw
        E += 0.5 * m * np.einsum("ni,ni->n", vc, vc) + 0.5 * np.einsum("ni,ni->n", w, Iw) + m * G * rc[:, 1]
    return E, Lv


def test_chain_3d_conserves_energy_and_vertical_angular_momentum():
    N = 4
    r = mbcomp.simulate(CHAIN.build(N=N), t_end=1.5, n_out=151, rtol=1e-9, atol=1e-11)
    assert r.success, r.message
    E, Lv = _chain_invariants(r, N)
    np.testing.assert_allclose(r["energy.total"], E, rtol=1e-10, atol=1e-10)  # independent energy
    scale_E = np.abs(r["energy.kinetic"]).max()
    assert np.ptp(E) < 1e-6 * scale_E
    scale_L = np.abs(Lv).max()
    assert abs(Lv[0, 1]) > 0.05 * scale_L  # the start spin gives a non-trivial conserved value
    assert np.ptp(Lv[:, 1]) < 1e-6 * scale_L
    assert np.ptp(Lv[:, 0]) > 0.01 * scale_L  # gravity torques the horizontal components: teeth
    # genuinely 3-D: the tip leaves the start plane and moves around the vertical
    tip = np.column_stack([r[f"link{N}.r.{x}"] for x in "xyz"])
    assert np.ptp(tip[:, 0]) > 0.05 and np.ptp(tip[:, 2]) > 0.05


@pytest.mark.parametrize("N", [0, -2])
def test_bad_size_is_refused(N):
    with pytest.raises(ValueError, match="N >= 1"):
        PEND.build(N=N)
    with pytest.raises(ValueError, match="N >= 1"):
        CHAIN.build(N=N)
