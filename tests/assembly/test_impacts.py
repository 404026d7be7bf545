"""Rigid impacts (mbcomp.assembly.impacts): closed forms of textbook impacts, the loop kept
through an impact, energy never gained on single impacts, pulling impulses dropped."""
import numpy as np
import pytest
import scipy.linalg as sla
from conftest import load_model

import mbcomp
from mbcomp.assembly.impacts import impact_energy_loss, impulse, post_impact_state, single_row_loss
from mbcomp.assembly.initialization import initialize
from mbcomp.errors import SimulationError


@pytest.mark.parametrize("e", [0.0, 0.3, 0.75, 1.0])
def test_point_mass_on_the_ground_reverses_its_normal_speed_times_e(e):
    m, v = 0.7, np.array([1.2, -0.4, -3.0])  # kg, m/s; ground normal z
    u_plus, Lam = impulse(m * np.eye(3), [[0.0, 0.0, 1.0]], v, [0], e)
    assert np.allclose(u_plus, [1.2, -0.4, 3.0 * e], rtol=0, atol=1e-15)  # tangential speeds untouched
    assert Lam[0] == pytest.approx(m * (1 + e) * 3.0, rel=1e-15)


def _planar_rod(m, L):
    """Planar rod, speeds (vx, vy, w) of its centre: M, and the row of the velocity of the point
    at distance ``s`` along the rod (angle ``th``) in direction ``n``."""
    M = np.diag([m, m, m * L ** 2 / 12])

    def row(s, th, n):
        r = s * np.array([np.cos(th), np.sin(th)])
        return np.array([n[0], n[1], n[0] * -r[1] + n[1] * r[0]])
    return M, row


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_pendulum_hits_a_stop_at_its_tip_hinge_holds(e):
    # a free planar rod held by a hinge at one end (2 kept rows), stop under its tip (normal +y)
    m, L, th, w = 2.0, 1.5, 0.3, -4.0
    M, row = _planar_rod(m, L)
    t = np.array([-np.sin(th), np.cos(th)])  # the tip's direction of motion for w > 0
    C = np.array([row(-L / 2, th, (1, 0)), row(-L / 2, th, (0, 1)), row(L / 2, th, t)])
    u = np.concatenate((w * L / 2 * t, [w]))  # turning about the hinge
    assert np.abs(C[:2] @ u).max() < 1e-15
    up, Lam = impulse(M, C, u, [2], e, keep_rows=[0, 1])
    assert up[2] == pytest.approx(-e * w, abs=1e-14)
    assert np.abs(C[:2] @ up).max() < 1e-14
    P = (1 + e) * (m * L ** 2 / 3) * abs(w) / L  # tip impulse: I_hinge dw / L
    assert Lam[2] == pytest.approx(P, rel=1e-13)
    # a blow at the tip (beyond the centre of percussion at 2L/3) is helped by the hinge: P/2 along t
    assert np.allclose(Lam[0] * np.array([1, 0]) + Lam[1] * np.array([0, 1]), P / 2 * t, rtol=0, atol=1e-13)


def test_free_rod_hits_the_ground_at_one_end_textbook_result():
    """Uniform rod (m, L) at angle th to the ground, centre speed (vx, vy), angular speed w,
    lower end (-L/2 along the rod) hits the ground with restitution e. The end's normal speed is
    v_n = vy - w L/2 cos th; with the impulse P at the end, m dvy = P, (m L^2/12) dw = -P L/2 cos th
    and dv_n = -(1 + e) v_n:  dvy = -(1 + e) v_n / (1 + 3 cos^2 th), dw = -6 cos th dvy / L, dvx = 0.
    Flat and plastic (th = 0, e = 0, vy = -v, w = 0): vy+ = -3v/4, w+ = -3v/(2L) (end stopped)."""
    rng = np.random.default_rng(3)
    m, L = 1.3, 0.9
    M, row = _planar_rod(m, L)
    worst = 0.0
    for _ in range(200):
        th, e = rng.uniform(0, np.pi / 2 - 0.05), rng.uniform(0, 1)
        u = np.array([rng.normal(), -abs(rng.normal()) - 0.1, rng.normal()])
        c = row(-L / 2, th, (0, 1))
        vn = u[1] - u[2] * L / 2 * np.cos(th)
        if vn >= 0:
            continue
        dvy = -(1 + e) * vn / (1 + 3 * np.cos(th) ** 2)
        expect = u + [0.0, dvy, -6 * np.cos(th) * dvy / L]
        up, _ = impulse(M, [c], u, [0], e)
        worst = max(worst, np.abs(up - expect).max())
    assert worst < 1e-13
    up, _ = impulse(M, [row(-L / 2, 0.0, (0, 1))], np.array([0.0, -2.0, 0.0]), [0], 0.0)
    assert np.allclose(up, [0.0, -1.5, -3 * 2.0 / (2 * L)], rtol=0, atol=1e-14)


def test_two_equal_balls_exchange_speeds_with_e_one():
    m, v = 0.2, 1.7
    C = [[-1.0, 1.0]]  # gap rate x2' - x1' (ball 1 left of ball 2)
    up, Lam = impulse(m * np.eye(2), C, np.array([v, 0.0]), [0], 1.0)
    assert np.allclose(up, [0.0, v], rtol=0, atol=1e-15) and Lam[0] == pytest.approx(m * v, rel=1e-15)


def _ball_pair(ny):
    """Two equal point masses in the plane (speeds x1, y1, x2, y2), ball 2 resting on the ground
    (its row closed, speed 0), ball 1 hitting it along the unit line of centres n = (nx, ny)."""
    n = np.array([np.sqrt(1 - ny ** 2), ny])
    C = np.array([[-n[0], -n[1], n[0], n[1]],  # contact 1-2: n . (v2 - v1)
                  [0.0, 0.0, 0.0, 1.0]])  # ground under ball 2
    return n, C


@pytest.mark.parametrize("e", [0.0, 0.6, 1.0])
def test_ground_row_that_would_pull_is_dropped(e):
    # ball 1 hits ball 2 from below-left: holding ball 2 on the ground would need a pulling impulse
    m, v = 1.0, 2.0
    n, C = _ball_pair(0.6)
    u = np.array([*(v * n), 0.0, 0.0])
    r = impulse(m * np.eye(4), C, u, [0, 1], e, full=True)
    assert r.dropped.tolist() == [1] and r.Lambda[1] == 0.0 and r.pivots == 1
    # then a single central impact of equal masses: normal speeds share as (1 -+ e)/2
    assert np.allclose(r.u_plus, [*((1 - e) / 2 * v * n), *((1 + e) / 2 * v * n)], rtol=0, atol=1e-14)
    assert C[1] @ r.u_plus > 0  # ball 2 lifts off


@pytest.mark.parametrize("e", [0.0, 0.6, 1.0])
def test_ground_row_that_pushes_stays_with_closed_form(e):
    # ball 1 hits from above-left: the ground holds ball 2 (x-motion only); impulse P along n on
    # ball 2, ground R = -P ny; n.(v2 - v1)+ = -e n.(v2 - v1)-  =>  P = m (1 + e) (n.v1) / (1 + nx^2)
    m, v = 1.5, 2.0
    n, C = _ball_pair(-0.6)
    u = np.array([*(v * n), 0.0, 0.0])
    up, Lam = impulse(m * np.eye(4), C, u, [0, 1], e)
    P = m * (1 + e) * v / (1 + n[0] ** 2)
    assert Lam[0] == pytest.approx(P, rel=1e-14) and Lam[1] == pytest.approx(-P * n[1], rel=1e-14)
    assert np.allclose(up, [*(v * n - P * n / m), P * n[0] / m, 0.0], rtol=0, atol=1e-14)


def test_three_ball_cradle_simultaneous_newton_is_not_sequential():
    # documented limitation: ball 1 at v hits balls 2, 3 at rest in contact, e = 1 on both rows
    up, Lam = impulse(np.eye(3), [[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]], np.array([1.0, 0.0, 0.0]), [0, 1], 1.0)
    assert np.allclose(up, [-1 / 3, 2 / 3, 2 / 3], rtol=0, atol=1e-15)  # not the observed (0, 0, 1)
    assert impact_energy_loss(np.eye(3), [1.0, 0, 0], up) == pytest.approx(0.0, abs=1e-15)
    assert np.all(Lam > 0)


@pytest.fixture(scope="module")
def four_bar():
    system = mbcomp.assemble(load_model("models/four_bar.py").build(gap=0.1, g=0.0))
    init = initialize(system)
    return system, init


@pytest.mark.parametrize("e", [0.0, 0.4, 1.0])
def test_four_bar_stop_keeps_the_loop_and_loses_the_single_row_energy(four_bar, e):
    system, init = four_bar
    q, u = init.q, init.u
    ev = system.evaluate_numeric(0.0, q, u, masked=False)
    assert ev.C.shape[0] == 5 and np.linalg.matrix_rank(ev.C) == 2  # 3 redundant loop rows
    c = np.zeros(system.nu)
    c[system.u_names.index("crank_joint.w")] = -1.0  # a stop ahead of the crank turning at +8 rad/s
    after = post_impact_state(system, 0.0, q, u, c[None, :], e)
    assert np.abs(ev.C @ after.u).max() < 1e-12 * np.abs(u).max()  # all five loop rows, incl. redundant
    assert c @ after.u == pytest.approx(-e * (c @ u), abs=1e-12)
    assert len(after.notes) == 3 and after.dropped == []
    # the energy loss by the mechanism's one speed direction: N spans the loop's null space
    N = sla.null_space(ev.C)
    S = float(c @ N @ np.linalg.solve(N.T @ ev.M @ N, N.T @ c))
    closed = 0.5 * (1 - e ** 2) * (c @ u) ** 2 / S
    assert after.loss == pytest.approx(closed, rel=1e-12)
    assert after.loss == pytest.approx(single_row_loss(ev.M, c, u, e, ev.C), rel=1e-12)
    plastic = post_impact_state(system, 0.0, q, u, c[None, :], 0.0)
    assert after.loss == pytest.approx((1 - e ** 2) * plastic.loss, rel=1e-12)


def test_four_bar_rows_by_name_and_unknown_names(four_bar):
    system, init = four_bar
    # the loop's x row as the "impacting" row with e = 0 and the rest kept: nothing moves (C u- = 0)
    after = post_impact_state(system, 0.0, init.q, init.u, ["rocker_joint.x"], 0.0)
    assert np.allclose(after.u, init.u, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="rocker_joint.nope.*not constraint rows"):
        post_impact_state(system, 0.0, init.q, init.u, ["rocker_joint.nope"], 0.0)


def _random_case(rng):
    """Random SPD M (n <= 6), one impacting row, 0..n-2 kept rows (sometimes with a redundant
    copy), u- on the kept rows and approaching on the impacting one."""
    n = int(rng.integers(1, 7))
    A = rng.normal(size=(n, n))
    M = A @ A.T + 0.05 * np.eye(n) * rng.uniform(0.01, 10)
    k = int(rng.integers(0, max(n - 1, 1)))
    Ck = rng.normal(size=(k, n))
    if k and rng.uniform() < 0.3:
        Ck = np.vstack((Ck, rng.normal(size=k) @ Ck))  # redundant kept row
    c = rng.normal(size=n)
    u = rng.normal(size=n)
    if Ck.size:
        N = sla.null_space(Ck)
        u = N @ (N.T @ u)
    if c @ u > 0:
        c = -c
    return M, np.vstack((Ck, c)), u


def test_energy_never_rises_over_1000_random_single_impacts():
    rng = np.random.default_rng(22)
    worst_rise, worst_formula, worst_law = 0.0, 0.0, 0.0
    for _ in range(1000):
        M, C, u = _random_case(rng)
        e = rng.uniform(0, 1)
        i = C.shape[0] - 1
        up, Lam = impulse(M, C, u, [i], e, keep_rows=range(i))
        T = 0.5 * u @ M @ u
        loss = impact_energy_loss(M, u, up)
        worst_rise = max(worst_rise, -loss / T)
        closed = single_row_loss(M, C[i], u, e, C[:i])
        worst_formula = max(worst_formula, abs(loss - closed) / T)
        worst_law = max(worst_law, abs(C[i] @ up + e * (C[i] @ u)) / np.abs(C[i] @ u))
        assert Lam[i] >= 0
    print(f"rise {worst_rise:.2e}, formula {worst_formula:.2e}, Newton's law {worst_law:.2e}")
    assert worst_rise < 1e-12 and worst_formula < 1e-9 and worst_law < 1e-9


def test_simultaneous_impacts_solve_the_complementarity_and_mixed_e_can_gain_energy():
    rng = np.random.default_rng(5)
    rises_common, rises_mixed, worst = 0, 0, 0.0
    for _ in range(1000):
        n = int(rng.integers(2, 6))
        A = rng.normal(size=(n, n))
        M = A @ A.T + 0.1 * np.eye(n)
        k = int(rng.integers(2, n + 1))
        C, u = rng.normal(size=(k, n)), rng.normal(size=n)
        for mixed in (False, True):
            e = rng.uniform(0, 1, size=k) if mixed else np.full(k, rng.uniform(0, 1))
            r = impulse(M, C, u, range(k), e, full=True)
            w, wp = C @ u, C @ r.u_plus
            scale = np.abs(w).max()
            # complementarity: Lambda >= 0, C u+ >= -e C u-, and one of them holds with equality
            worst = max(worst, -r.Lambda.min() / max(np.abs(r.Lambda).max(), 1e-300),
                        (-(wp + e * w)).max() / scale,
                        np.abs(np.minimum(r.Lambda / max(np.abs(r.Lambda).max(), 1e-300), (wp + e * w) / scale)).max())
            gained = impact_energy_loss(M, u, r.u_plus) < -1e-12 * (u @ M @ u)
            rises_common += gained and not mixed
            rises_mixed += gained and mixed
    print(f"complementarity {worst:.2e}; energy gained: common e {rises_common}/1000, mixed e {rises_mixed}/1000")
    assert worst < 1e-9
    assert rises_common == 0  # documented: one common e never gains energy, whatever the active set


def test_inputs_are_checked_with_named_parameters():
    with pytest.raises(ValueError, match="restitution .* must lie in"):
        impulse(np.eye(1), [[1.0]], [-1.0], [0], 1.5)
    with pytest.raises(ValueError, match="both impacting and kept"):
        impulse(np.eye(1), [[1.0]], [-1.0], [0], 0.5, keep_rows=[0])
    with pytest.raises(SimulationError, match="not positive definite"):
        impulse(np.diag([1.0, 0.0]), [[1.0, 0.0]], [-1.0, 0.0], [0], 0.5)
