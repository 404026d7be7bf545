"""GeneralizedAlpha (Arnold & Brüls 2007 index-3 generalized-alpha) on small mechanical DAEs.

The problems are defined here, independently of the multibody machinery:

* the planar pendulum in Cartesian coordinates (m = 1 kg, l = 1 m, g = 9.81 m/s^2,
  ``Phi = (x^2 + y^2 - 1)/2``), started at rest 0.5 rad from the bottom, whose exact motion is
  the angle ODE ``theta'' = -g sin(theta)``;
* the same pendulum in its angle coordinate (no constraint);
* a two-mass chain: mass 1 on a rigid rod (constraint), mass 2 hung from it by a stiff
  spring (k = 1e6 N/m, omega ~ 1000 rad/s, so omega h ~ 10 for h = 10 ms);
* a coordinate fixed by a linear constraint (the algebraic modes of the scheme alone);
* a torque-free rigid body in unit quaternions (nq = 4, nu = 3), moved by rotation vectors.
"""
import doctest

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp.solvers.genalpha as genalpha_module
from conftest import step_through
from mbcomp.solvers.base import StepFailure
from mbcomp.solvers.genalpha import GeneralizedAlpha

G = 9.81
TH0 = 0.5


class Pendulum:
    """Cartesian pendulum; ``twice=True`` states the rod constraint twice (rank-deficient C)."""

    nq = nu = 2

    def __init__(self, twice=False):
        self.twice = twice
        self.m = 2 if twice else 1

    def dynamics(self, t, q, u):
        phi = np.array([(q @ q - 1.0) / 2.0])
        C = q[None, :].copy()
        if self.twice:
            phi, C = np.r_[phi, phi], np.vstack((C, C))
        return np.eye(2), np.array([0.0, -G]), phi, C

    def increment(self, q, dq):
        return q + dq

    def q_rate(self, q, u):
        return u


class AnglePendulum:
    """The same pendulum in its angle (no constraint, m = 0)."""

    nq = nu = 1
    m = 0

    def dynamics(self, t, q, u):
        return np.eye(1), -G * np.sin(q), np.zeros(0), np.zeros((0, 1))

    def increment(self, q, dq):
        return q + dq

    def q_rate(self, q, u):
        return u


class SpringChain:
    """Mass 1 on a unit rod about the origin, mass 2 tied to it by a spring (rest length 1)."""

    nq = nu = 4
    m = 1

    def __init__(self, k=1e6):
        self.k = k

    def dynamics(self, t, q, u):
        p1, p2 = q[:2], q[2:]
        d = p2 - p1
        L = np.linalg.norm(d)
        F = self.k * (L - 1.0) * d / L  # force on mass 1 (N), opposite on mass 2
        f = np.r_[F + [0.0, -G], -F + [0.0, -G]]
        return np.eye(4), f, np.array([(p1 @ p1 - 1.0) / 2.0]), np.r_[p1, 0.0, 0.0][None, :]

    def increment(self, q, dq):
        return q + dq

    def q_rate(self, q, u):
        return u


class FixedPoint:
    """``M = 1``, ``f = 0``, ``Phi = q``: the coordinate is pinned; only algebraic modes remain."""

    nq = nu = m = 1

    def dynamics(self, t, q, u):
        return np.eye(1), np.zeros(1), q.copy(), np.eye(1)

    def increment(self, q, dq):
        return q + dq

    def q_rate(self, q, u):
        return u


class FreeBody:
    """Torque-free rigid body: unit quaternion q (nq = 4), body angular velocity u (nu = 3);
    ``increment`` is the body-frame rotation-vector update (a Lie-group step)."""

    nq, nu, m = 4, 3, 0
    J = np.diag([1.0, 2.0, 3.0])  # kg m^2

    @staticmethod
    def qmul(a, b):
        return np.r_[a[0] * b[0] - a[1:] @ b[1:], a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])]

    def dynamics(self, t, q, u):
        return self.J, -np.cross(u, self.J @ u), np.zeros(0), np.zeros((0, 3))

    def increment(self, q, dq):
        th = np.linalg.norm(dq)
        half = np.r_[np.cos(th / 2), np.sin(th / 2) * dq / th] if th > 0 else np.r_[1.0, 0.0, 0.0, 0.0]
        return self.qmul(q, half)

    def q_rate(self, q, u):
        return 0.5 * self.qmul(q, np.r_[0.0, u])


def consistent_start(problem, q, u):
    """``[q, u, udot, a = udot, lam]`` from ``M udot + C^T lam = f``, ``C udot = -(d/dt C) u``."""
    M, f, _, C = problem.dynamics(0.0, q, u)
    m = C.shape[0]
    # for the constraints used here (|p|^2/2 of the first point) d(C u)/dt = |u_p1|^2
    A = np.block([[M, C.T], [C, np.zeros((m, m))]])
    sol = np.linalg.solve(A, np.r_[f, -np.full(m, u[:2] @ u[:2])])
    udot, lam = sol[: problem.nu], sol[problem.nu:]
    return np.r_[q, u, udot, udot, lam]


def pendulum_start():
    return consistent_start(Pendulum(), np.array([np.sin(TH0), -np.cos(TH0)]), np.zeros(2))


def run(problem, y0, t_end, h, **kw):
    """Step to ``t_end``; returns times (k,), states (k, n) including the start, and the solver."""
    s = GeneralizedAlpha(problem, 0.0, y0, t_end, first_step=h, **kw)
    return (*step_through(s), s)


def pendulum_energy(Y):
    return 0.5 * (Y[:, 2] ** 2 + Y[:, 3] ** 2) + G * Y[:, 1]


@pytest.fixture(scope="module")
def reference():
    """theta(t) of the exact pendulum (DOP853, rtol 1e-12), as a dense solution."""
    sol = solve_ivp(lambda t, z: [z[1], -G * np.sin(z[0])], (0.0, 1.0), [TH0, 0.0], method="DOP853",
                    rtol=1e-12, atol=1e-12, dense_output=True)
    return sol.sol


@pytest.fixture(scope="module")
def pendulum_runs():
    """rho_inf = 0.9, T = 1 s, h = 4, 2, 1 ms, tight Newton tolerance."""
    return {h: run(Pendulum(), pendulum_start(), 1.0, h, rho_inf=0.9, rtol=1e-10, atol=1e-12)
            for h in (4e-3, 2e-3, 1e-3)}


def test_second_order_convergence_in_q_and_u(pendulum_runs, reference):
    th, om = reference(1.0)
    x_ref, ux_ref = np.sin(th), np.cos(th) * om
    err_x, err_u = [], []
    for h in (4e-3, 2e-3, 1e-3):
        ts, Y, s = pendulum_runs[h]
        assert ts[-1] == 1.0 and s.stats["nsteps"] == round(1.0 / h)
        err_x.append(abs(Y[-1, 0] - x_ref))
        err_u.append(abs(Y[-1, 2] - ux_ref))
    # the method is consistent: errors are small and shrink with h ...
    assert err_x[0] < 1e-5 and err_u[0] < 5e-4
    # ... at the rate h^2 (Arnold & Bruels 2007), not h or h^3
    for err in (err_x, err_u):
        orders = np.log2(np.array(err[:-1]) / np.array(err[1:]))
        assert np.all((orders > 1.8) & (orders < 2.3)), orders


def test_position_constraint_holds_at_every_step(pendulum_runs):
    for h, (ts, Y, s) in pendulum_runs.items():
        phi = (Y[:, 0] ** 2 + Y[:, 1] ** 2 - 1.0) / 2.0
        assert np.max(np.abs(phi)) < 1e-10, h
        assert s.stats["nfev"] > s.stats["nsteps"] and s.stats["nlu"] == s.stats["njev"] >= 1


def test_dense_output_interpolates_the_step(pendulum_runs, reference):
    ts, Y, s = pendulum_runs[4e-3]
    sol = s.dense_output()
    assert np.allclose(sol(s.t_old), Y[-2], rtol=0, atol=1e-14)
    assert np.allclose(sol(s.t), Y[-1], rtol=0, atol=1e-14)
    tm = 0.5 * (s.t_old + s.t)
    th, om = reference(tm)
    ym = sol(tm)
    assert ym.shape == Y[-1].shape and sol(np.array([s.t_old, tm, s.t])).shape == (Y.shape[1], 3)
    assert abs(ym[0] - np.sin(th)) < 5e-6 and abs(ym[2] - np.cos(th) * om) < 5e-4
    # u is the cubic Hermite interpolant with udot as slopes: its derivative at the ends is udot
    eps = 1e-7 * (s.t - s.t_old)
    assert np.allclose((sol(s.t_old + eps)[2:4] - sol(s.t_old)[2:4]) / eps, Y[-2, 4:6], rtol=1e-4, atol=1e-4)


def test_rho_inf_1_conserves_energy_without_drift_unconstrained():
    # rho_inf = 1 is the average-acceleration (trapezoidal) rule: no numerical dissipation.
    y0 = [TH0, 0.0, -G * np.sin(TH0), -G * np.sin(TH0)]
    errs = []
    for h in (0.04, 0.02):
        _, Y, _ = run(AnglePendulum(), y0, 20.0, h, rho_inf=1.0)
        e = np.abs(0.5 * Y[:, 1] ** 2 - G * np.cos(Y[:, 0]) + G * np.cos(TH0))
        n = len(e) // 4
        assert e[-n:].max() < 1.1 * e[:n].max()  # bounded oscillation, no secular drift
        errs.append(e.max())
    assert errs[1] < 1e-4  # J/kg, for |E| = 8.6 J/kg
    assert 3.5 < errs[0] / errs[1] < 4.5  # the bound scales as h^2


def test_energy_bounded_and_no_constraint_drift_with_constraint_rho_0_9():
    # default Newton tolerances, 20 s: the energy error stays an O(h^2) oscillation, and
    # Phi = 0 (solved at each step: index 3) does not drift off either
    errs = []
    for h in (0.04, 0.02):
        _, Y, _ = run(Pendulum(), pendulum_start(), 20.0, h, rho_inf=0.9)
        e = np.abs(pendulum_energy(Y) - pendulum_energy(Y[:1]))
        phi = np.abs(Y[:, 0] ** 2 + Y[:, 1] ** 2 - 1.0) / 2.0
        n = len(e) // 4
        assert e[-n:].max() < 1.2 * e[:n].max()
        assert phi.max() < 1e-8 and phi[-n:].max() < 2.0 * phi[:n].max() + 1e-12
        errs.append(e.max())
    assert errs[1] < 1e-3
    assert 3.0 < errs[0] / errs[1] < 5.0


def test_algebraic_modes_damped_for_rho_below_1_but_not_for_rho_1():
    # A pinned coordinate started with an inconsistent speed: the scheme's algebraic
    # (constraint-direction) modes alone. For rho_inf < 1 they decay geometrically; for
    # rho_inf = 1 the eigenvalue -1 is defective and the response grows linearly in n --
    # the weak instability of the trapezoidal rule on index-3 DAEs.
    y0 = [0.0, 1e-2, 0.0, 0.0, 0.0]
    amp = {}
    for rho in (0.5, 1.0):
        _, Y, _ = run(FixedPoint(), y0, 1.0, 0.01, rho_inf=rho, rtol=1e-10, atol=1e-14)
        amp[rho] = np.abs(Y[:, 1:]).max(axis=1)  # u, udot, a, lam
    assert amp[0.5][-1] < 1e-10 * amp[0.5].max()
    n = len(amp[1.0]) - 1
    assert amp[1.0][-1] > 0.5 * n * amp[1.0][1]  # linear growth, not decay


def test_spectral_radius_stiff_spring_decays_for_rho_0_not_for_rho_1():
    problem = SpringChain(k=1e6)  # omega ~ 1000 rad/s, h = 10 ms: omega h ~ 10
    e = np.array([np.sin(TH0), -np.cos(TH0)])
    y0 = consistent_start(problem, np.r_[e, 2.01 * e], np.zeros(4))  # spring stretched 1 cm

    def hf_amplitude(Y):  # spring stretch minus its smooth trend (second difference)
        s = np.linalg.norm(Y[:, 2:4] - Y[:, 0:2], axis=1) - 1.0
        return np.abs(s[1:-1] - 0.5 * (s[:-2] + s[2:]))

    A = {}
    for rho in (0.0, 1.0):
        _, Y, _ = run(problem, y0, 0.5, 0.01, rho_inf=rho)
        A[rho] = hf_amplitude(Y)
    # rho_inf = 0 annihilates the unresolved oscillation within a few steps ...
    assert A[0.0][-10:].max() < 1e-4 * A[0.0][:3].max()
    # ... rho_inf = 1 keeps its amplitude (no algorithmic damping), without blowing up
    assert 0.5 * A[1.0][:3].max() < A[1.0][-10:].max() < 2.0 * A[1.0][:3].max()


def test_first_step_is_required():
    with pytest.raises(ValueError, match="first_step"):
        GeneralizedAlpha(Pendulum(), 0.0, pendulum_start(), 1.0)
    with pytest.raises(ValueError, match="rho_inf"):
        GeneralizedAlpha(Pendulum(), 0.0, pendulum_start(), 1.0, first_step=0.01, rho_inf=1.5)
    assert GeneralizedAlpha.capabilities() == dict(implicit=True, adaptive=False, one_step=True, max_index=3,
                                                   problem="mechanical")


def test_span_not_a_multiple_of_h_is_cut_into_equal_steps():
    ts, _, s = run(Pendulum(), pendulum_start(), 0.1, 0.03)
    assert s.stats["nsteps"] == 4 and ts[-1] == 0.1 and np.allclose(np.diff(ts), 0.025)


def test_redundant_constraint_makes_the_iteration_matrix_singular():
    y = pendulum_start()
    y0 = np.r_[y[:-1], y[-1] / 2.0, y[-1] / 2.0]  # the force split over the two equal rows
    s = GeneralizedAlpha(Pendulum(twice=True), 0.0, y0, 1.0, first_step=0.01)
    msg = s.step()
    assert s.status == "failed"
    assert "singular" in msg and "t=0.01" in msg
    assert issubclass(StepFailure, RuntimeError)


def test_docstring_examples():
    result = doctest.testmod(genalpha_module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 5 and result.failed == 0


def test_lie_group_increment_keeps_unit_quaternion_and_conserves_momentum_to_order_2():
    body = FreeBody()
    w0 = np.array([2.0, 0.3, 0.2])
    wd = np.linalg.solve(body.J, -np.cross(w0, body.J @ w0))
    y0 = np.r_[1.0, 0.0, 0.0, 0.0, w0, wd, wd]

    def rot(q):
        w, x, y, z = q
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])

    errs = []
    for h in (0.02, 0.01):
        _, Y, _ = run(body, y0, 2.0, h)
        assert np.max(np.abs(np.linalg.norm(Y[:, :4], axis=1) - 1.0)) < 1e-12  # stays on the group
        q, w = Y[-1, :4], Y[-1, 4:7]
        errs.append(np.linalg.norm(rot(q) @ body.J @ w - body.J @ w0))  # spatial angular momentum
    assert errs[0] < 1e-3
    assert 3.5 < errs[0] / errs[1] < 4.5


def test_non_finite_force_fails_with_a_message_naming_t():
    class Broken(Pendulum):
        def dynamics(self, t, q, u):
            M, f, phi, C = super().dynamics(t, q, u)
            return M, (f * np.nan if t > 0.035 else f), phi, C

    s = GeneralizedAlpha(Broken(), 0.0, pendulum_start(), 1.0, first_step=0.01)
    msgs = [s.step() for _ in range(4)]
    assert msgs[:3] == [None, None, None] and s.status == "failed"
    assert "non-finite" in msgs[3] and "t=0.04" in msgs[3] and "first_step" in msgs[3]
