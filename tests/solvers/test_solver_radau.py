"""Radau5 (Radau IIA, order 5) for ``E dy/dt = fun(t, y)`` of index <= 3.

Checks, each of which can fail:

* the coefficients derived in the module are those of Radau IIA (order conditions, the
  eigenvalues of ``A^{-1}``, RADAU5's error weights);
* a stiff problem (Robertson, as an ODE with ``E = I`` and as an index-1 DAE) agrees with
  scipy's Radau at ``rtol=1e-10`` to within the requested tolerance, in a few hundred steps
  where any explicit Runge-Kutta method would need ~10^8;
* the Cartesian pendulum as an index-3, index-2 and index-1 DAE agrees with the angle ODE
  (DOP853, ``rtol=1e-12``) in position, velocity and constraint force, conserves energy and
  keeps its constraint;
* errors fall when the tolerance is tightened;
* the dense output is the collocation polynomial: it passes through the step ends, satisfies
  the ODE and the constraint at the collocation nodes and is accurate in between;
* failures (singular iteration matrix, rank-deficient constraints, non-finite ``fun``,
  blow-up) end in status ``"failed"`` with a message naming cause and time.
"""
import doctest
import functools
import re
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import solve_ivp, trapezoid

import mbcomp.solvers.radau as radau_mod
from mbcomp.solvers.radau import Radau5

G = 9.81
TH0 = 0.5  # initial angle from the downward vertical (rad)


def integrate(problem, y0, t_end, **kw):
    """Run Radau5 to ``t_end``; returns the solver, step-end times (m,), states (m, n), dense outputs."""
    s = Radau5(problem, 0.0, y0, t_end, **kw)
    ts, ys, dense = [s.t], [s.y.copy()], []
    while s.status == "running":
        msg = s.step()
        assert msg is None, msg
        ts.append(s.t)
        ys.append(s.y.copy())
        dense.append(s.dense_output())
    return s, np.array(ts), np.array(ys), dense


# ==========================================================================================
# coefficients
# ==========================================================================================
def test_coefficients_are_radau_iia():
    co = radau_mod._COEF
    c, A, b = co["c"], co["A"], co["b"]
    s6 = np.sqrt(6.0)
    A_book = np.array([[(88 - 7 * s6) / 360, (296 - 169 * s6) / 1800, (-2 + 3 * s6) / 225],
                       [(296 + 169 * s6) / 1800, (88 + 7 * s6) / 360, (-2 - 3 * s6) / 225],
                       [(16 - s6) / 36, (16 + s6) / 36, 1 / 9]])  # Hairer & Wanner II, Table IV.5.6
    np.testing.assert_allclose(A, A_book, rtol=0, atol=1e-14)
    for k in range(1, 6):  # B(5): order 5 quadrature
        assert abs(b @ c ** (k - 1) - 1 / k) < 1e-14
    for k in range(1, 4):  # C(3): stage order 3
        np.testing.assert_allclose(A @ c ** (k - 1), c ** k / k, atol=1e-14)
    # eigenvalues of A^{-1}: gamma = 3 + 3^(2/3) - 3^(1/3), alpha +- i beta
    assert abs(co["gamma"] - (3 + 3 ** (2 / 3) - 3 ** (1 / 3))) < 1e-12
    mu = 3 + 0.5 * (3 ** (1 / 3) - 3 ** (2 / 3)) + 0.5j * (3 ** (5 / 6) + 3 ** (7 / 6))
    assert abs(co["mu"] - mu) < 1e-12
    lam = co["TI"] @ np.linalg.inv(A) @ co["T"]
    np.testing.assert_allclose(lam, co["LAM"], atol=1e-12)
    assert abs(lam[1, 0]) + abs(lam[2, 0]) + abs(lam[0, 1]) + abs(lam[0, 2]) < 1e-12  # decoupled
    # RADAU5's error weights (d1, d2, d3) = (-13 - 7 sqrt6, -13 + 7 sqrt6, -1)/3
    np.testing.assert_allclose(co["d"], np.array([-13 - 7 * s6, -13 + 7 * s6, -1]) / 3, atol=1e-12)
    # the dense-output basis interpolates the stages
    Lc = np.column_stack([c, c ** 2, c ** 3]) @ co["P"].T
    np.testing.assert_allclose(Lc, np.eye(3), atol=1e-12)


def test_module_doctests_pass():
    runner = doctest.DocTestRunner(verbose=False)
    out = []
    for test in doctest.DocTestFinder().find(radau_mod, radau_mod.__name__):
        runner.run(test, out=out.append)
    res = runner.summarize(verbose=False)
    assert res.attempted >= 8 and res.failed == 0, "".join(out)


# ==========================================================================================
# stiff: Robertson
# ==========================================================================================
def rob_fun(t, y):
    return np.array([-0.04 * y[0] + 1e4 * y[1] * y[2],
                     0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2,
                     3e7 * y[1] ** 2])


def rob_jac(t, y):
    return np.array([[-0.04, 1e4 * y[2], 1e4 * y[1]],
                     [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]],
                     [0.0, 6e7 * y[1], 0.0]])


def rob_dae_fun(t, y):  # y3 from the conservation law: an index-1 DAE
    f = rob_fun(t, y)
    f[2] = y[0] + y[1] + y[2] - 1.0
    return f


T_ROB = 1e5


@functools.lru_cache(maxsize=None)
def robertson_reference():
    return solve_ivp(rob_fun, (0.0, T_ROB), [1.0, 0.0, 0.0], method="Radau", rtol=1e-10, atol=1e-12,
                     jac=rob_jac, dense_output=True)


@pytest.mark.parametrize("form", ["ode", "dae"])
def test_robertson_matches_scipy_in_few_steps(form):
    if form == "ode":  # E = I, analytic Jacobian
        prob = SimpleNamespace(n=3, mass=np.ones(3), index=np.ones(3, int), fun=rob_fun, jac=rob_jac)
    else:  # E = diag(1, 1, 0), finite-difference Jacobian (no jac attribute)
        prob = SimpleNamespace(n=3, mass=np.array([1.0, 1.0, 0.0]), index=np.ones(3, int), fun=rob_dae_fun)
    rtol, atol = 1e-6, 1e-10
    s, ts, ys, _ = integrate(prob, [1.0, 0.0, 0.0], T_ROB, rtol=rtol, atol=atol)
    ref = robertson_reference()
    yr = ref.sol(ts).T
    # global error within the requested tolerance (reference: rtol 1e-10)
    werr = np.abs(ys - yr) / (rtol * np.abs(yr) + atol)
    assert werr.max() < 1.0, werr.max()
    assert np.abs(ys[-1] - ref.y[:, -1]).max() < 1e-7
    if form == "dae":  # the algebraic equation holds at every step end
        assert np.abs(ys.sum(axis=1) - 1.0).max() < 1e-12
    # stiff: an explicit RK method needs h * rho(J) <= ~4 (its real stability interval), so at
    # least int rho(J(y(t))) / 4 dt steps along the solution
    tg = np.linspace(0.0, T_ROB, 2001)
    rho = [np.abs(np.linalg.eigvals(rob_jac(0.0, y))).max() for y in ref.sol(tg).T]
    n_explicit = trapezoid(rho, tg) / 4.0
    assert n_explicit > 1e8
    assert s.stats["nsteps"] < 400
    assert s.stats["nsteps"] < 1e-5 * n_explicit
    # comparable to scipy's Radau at the same tolerance (within a factor 2)
    sc = solve_ivp(rob_fun, (0.0, T_ROB), [1.0, 0.0, 0.0], method="Radau", rtol=rtol, atol=atol, jac=rob_jac)
    assert s.stats["nsteps"] < 2 * (len(sc.t) - 1)
    # Jacobians are reused across steps
    assert s.stats["njev"] < s.stats["nsteps"]


# ==========================================================================================
# pendulum, index 3, 2 and 1
# ==========================================================================================
class Pendulum:
    """Planar pendulum, m = l = 1, in Cartesian coordinates ``y = (x, y, vx, vy, lam)``.

    ``vx' = -lam x``, ``vy' = -lam y - g``; the algebraic row is the position constraint
    (index 3), the velocity constraint (index 2) or the acceleration-level equation solved
    for ``lam`` (index 1).
    """

    mass = np.array([1.0, 1.0, 1.0, 1.0, 0.0])

    def __init__(self, dae_index):
        self.n = 5
        self.dae_index = dae_index
        self.index = np.array({3: [1, 1, 2, 2, 3], 2: [1, 1, 1, 1, 2], 1: [1, 1, 1, 1, 1]}[dae_index])
        self.calls = 0

    def fun(self, t, y):
        self.calls += 1
        x, yy, vx, vy, lam = y
        if self.dae_index == 3:
            c = 0.5 * (x * x + yy * yy - 1.0)
        elif self.dae_index == 2:
            c = x * vx + yy * vy
        else:
            c = vx * vx + vy * vy - lam * (x * x + yy * yy) - G * yy
        return np.array([vx, vy, -lam * x, -lam * yy - G, c])

    def jac(self, t, y):
        return None  # finite differences


Y0_PEND = np.array([np.sin(TH0), -np.cos(TH0), 0.0, 0.0, G * np.cos(TH0)])  # at rest: lam = g cos(th0)


@functools.lru_cache(maxsize=None)
def angle_reference():
    return solve_ivp(lambda t, u: [u[1], -G * np.sin(u[0])], (0.0, 3.0), [TH0, 0.0], method="DOP853",
                     rtol=1e-12, atol=1e-12, dense_output=True)


def reference_state(t):
    """(x, y, vx, vy, lam) (5, m) from the angle ODE (lam = tension = thdot^2 + g cos th)."""
    th, om = angle_reference().sol(t)
    return np.array([np.sin(th), -np.cos(th), np.cos(th) * om, np.sin(th) * om, om ** 2 + G * np.cos(th)])


@functools.lru_cache(maxsize=None)
def pendulum_run(dae_index, rtol):
    prob = Pendulum(dae_index)
    s, ts, ys, dense = integrate(prob, Y0_PEND, 3.0, rtol=rtol, atol=rtol)
    return s, ts, ys, dense, prob.calls


def position_error(ts, ys):
    return np.abs(ys[:, :2] - reference_state(ts)[:2].T).max()


LAM_TOL = {3: 1e-2, 2: 1e-4, 1: 1e-7}  # the multiplier of an index-k formulation is less accurate


@pytest.mark.parametrize("dae_index", [3, 2, 1])
def test_pendulum_matches_angle_ode(dae_index):
    s, ts, ys, dense, calls = pendulum_run(dae_index, 1e-8)
    assert s.status == "finished" and ts[-1] == 3.0
    ref = reference_state(ts).T
    assert position_error(ts, ys) < 1e-6
    assert np.abs(ys[:, 2:4] - ref[:, 2:4]).max() < 1e-5
    assert np.abs(ys[:, 4] - ref[:, 4]).max() < LAM_TOL[dae_index]
    # at t = 1, 2, 3 s (dense output inside the step that contains them)
    for tq in (1.0, 2.0, 3.0):
        k = min(np.searchsorted(ts, tq, side="left"), len(dense)) - 1
        yq = dense[k](tq)
        assert np.abs(yq[:2] - reference_state(tq)[:2]).max() < 1e-6
    energy = 0.5 * (ys[:, 2] ** 2 + ys[:, 3] ** 2) + G * ys[:, 1]
    assert np.abs(energy - energy[0]).max() < 1e-6 * G
    assert np.abs(ys[:, 0] ** 2 + ys[:, 1] ** 2 - 1.0).max() < 1e-8
    if dae_index == 3:
        assert np.abs(ys[:, 0] ** 2 + ys[:, 1] ** 2 - 1.0).max() < 1e-10  # enforced directly
    # bookkeeping: every call of fun is counted; the pendulum swings ~2 periods in < 400 steps
    assert s.stats["nfev"] == calls
    assert 30 < s.stats["nsteps"] < 400
    assert s.stats["nlu"] >= 2 and s.stats["njev"] >= 1 and s.stats["nnewton"] >= s.stats["nsteps"]


@pytest.mark.parametrize("dae_index", [3, 2])
def test_tighter_tolerance_gives_smaller_error(dae_index):
    errs = [position_error(*pendulum_run(dae_index, rtol)[1:3]) for rtol in (1e-4, 1e-6, 1e-8)]
    steps = [pendulum_run(dae_index, rtol)[0].stats["nsteps"] for rtol in (1e-4, 1e-6, 1e-8)]
    # each factor 100 in rtol buys at least a factor 20 in error (order 5: h ~ tol^(1/4))
    assert errs[1] < errs[0] / 20 and errs[2] < errs[1] / 20, errs
    assert errs[0] < 1e-3 and errs[2] < 1e-8
    assert steps[0] < steps[1] < steps[2]


def test_index_aware_error_control_is_what_makes_index3_work():
    # Weighting lam (index 3) and the velocities (index 2) like differential variables
    # ignores that their error estimates are two resp. one powers of h larger than the
    # differential ones: the error test cannot be met and the step size collapses. With
    # Hairer's scaling (h and h**2) the same problem runs in ~100 steps.
    good, _, _, _, _ = pendulum_run(3, 1e-6)
    assert good.status == "finished" and good.stats["nsteps"] < 200
    naive = Pendulum(3)
    naive.index = np.ones(5, int)
    s = Radau5(naive, 0.0, Y0_PEND, 3.0, rtol=1e-6, atol=1e-6)
    msg = None
    while s.status == "running" and s.stats["nsteps"] < 20 * good.stats["nsteps"]:
        msg = s.step()
    assert s.status == "failed" or s.stats["nsteps"] >= 20 * good.stats["nsteps"]
    if s.status == "failed":
        assert msg.startswith("Radau5: ") and f"t={s.t:.17g}" in msg


# ==========================================================================================
# dense output
# ==========================================================================================
@pytest.mark.parametrize("dae_index", [3, 1])
def test_dense_output_is_the_collocation_polynomial(dae_index):
    s, ts, ys, dense, _ = pendulum_run(dae_index, 1e-8)
    end_err = position_error(ts, ys)
    tm = 0.5 * (ts[:-1] + ts[1:])
    ym = np.array([d(t) for d, t in zip(dense, tm)])
    mid_err = np.abs(ym[:, :2] - reference_state(tm)[:2].T).max()
    assert mid_err < 1e-7  # stage order 3 inside the step, order 5 at its ends
    assert mid_err < 100 * max(end_err, 1e-9)
    # vectorized evaluation agrees and has shape (n, m)
    d = dense[len(dense) // 2]
    tt = np.linspace(d.t_min, d.t_max, 7)
    np.testing.assert_allclose(d(tt), np.array([d(t) for t in tt]).T, rtol=0, atol=1e-14)
    c = radau_mod.C
    for k in range(len(dense)):
        d, h = dense[k], ts[k + 1] - ts[k]
        # passes through both step ends
        np.testing.assert_allclose(d(ts[k]), ys[k], rtol=0, atol=1e-14)
        np.testing.assert_allclose(d(ts[k + 1]), ys[k + 1], rtol=0, atol=1e-12 * (1 + np.abs(ys[k + 1])).max())
        # collocation: x' = vx, y' = vy at the nodes (central difference of the cubic)
        tc = ts[k] + c * h
        eps = 1e-4 * h
        du = (d(tc + eps) - d(tc - eps)) / (2 * eps)
        u = d(tc)
        assert np.abs(du[:2] - u[2:4]).max() < 1e-6
        # vx' = -lam x at the nodes
        assert np.abs(du[2] + u[4] * u[0]).max() < 1e-6 * G
        if dae_index == 3:  # the constraint holds at the stages, not in between
            assert np.abs(u[0] ** 2 + u[1] ** 2 - 1.0).max() < 1e-9



@pytest.mark.parametrize("dae_index", [3, 1])
def test_predicted_stages_are_the_dense_output_extrapolated(dae_index):
    # the next step's starting values (RadauDenseOutput.increments, the predictor) are the
    # collocation polynomial at the new step's nodes minus the step's start -- bit for bit
    # what calling the dense output gives, and the polynomial's passage through the stages
    s, ts, ys, dense, _ = pendulum_run(dae_index, 1e-8)
    c = radau_mod.C
    out = np.empty((3, ys.shape[1]))
    for k in range(len(dense) - 1):
        d, t, h = dense[k], ts[k + 1], ts[k + 2] - ts[k + 1]
        got = d.increments(t, h, ys[k + 1], out)
        assert got is out
        np.testing.assert_array_equal(out, (d(t + c * h) - ys[k + 1][:, None]).T)
    d = dense[0]  # inside its own step the increments are the stages Z_i = Y_i - y0
    own = d.increments(d.t_old, d.h, d.y_old, out) + d.y_old
    np.testing.assert_allclose(own[2], ys[1], rtol=0, atol=1e-12 * (1 + np.abs(ys[1])).max())

# ==========================================================================================
# failures
# ==========================================================================================
def run_to_failure(problem, y0, t_end, **kw):
    s = Radau5(problem, 0.0, y0, t_end, **kw)
    msgs = []
    while s.status == "running":
        msgs.append(s.step())  # must never raise
    assert s.status == "failed"
    assert all(m is None for m in msgs[:-1]) and isinstance(msgs[-1], str)
    return s, msgs[-1]


def test_variable_in_no_equation_is_a_singular_iteration_matrix():
    # the constraint force was forgotten in the dynamics: lam enters no equation
    def fun(t, y):
        x, yy, vx, vy, lam = y
        return np.array([vx, vy, 0.0, -G, 0.5 * (x * x + yy * yy - 1.0)])

    prob = SimpleNamespace(n=5, mass=Pendulum.mass, index=np.array([1, 1, 2, 2, 3]), fun=fun)
    s, msg = run_to_failure(prob, Y0_PEND, 1.0)
    assert msg.startswith("Radau5: the iteration matrix is singular at t=0 ")
    assert "variable 4 enters no equation" in msg and "index <= 3" in msg
    assert s.t == 0.0 and s.stats["nsteps"] == 0


def test_redundant_constraint_is_a_singular_iteration_matrix():
    # the constraint stated twice with two multipliers: the constraint Jacobian lost rank
    def fun(t, y):
        x, yy, vx, vy, l1, l2 = y
        c = 0.5 * (x * x + yy * yy - 1.0)
        return np.array([vx, vy, -(l1 + l2) * x, -(l1 + l2) * yy - G, c, 2.0 * c])

    prob = SimpleNamespace(n=6, mass=np.array([1.0, 1, 1, 1, 0, 0]), index=np.array([1, 1, 2, 2, 3, 3]),
                           fun=fun)
    y0 = np.r_[Y0_PEND[:4], Y0_PEND[4] / 2, Y0_PEND[4] / 2]
    s, msg = run_to_failure(prob, y0, 1.0)
    assert "iteration matrix is singular at t=0 " in msg and "rank" in msg


def test_non_finite_fun_is_reported_with_time():
    # the force law is undefined beyond t = 0.5 s
    prob = SimpleNamespace(n=1, fun=lambda t, y: np.array([np.nan if t > 0.5 else -y[0]]))
    s, msg = run_to_failure(prob, [1.0], 2.0)
    assert "non-finite" in msg
    t_msg = float(re.search(r"at t=([0-9.eE+-]+)", msg).group(1))
    assert abs(t_msg - 0.5) < 1e-9  # the message names where it happened
    assert 0.5 - 1e-9 < s.t <= 0.5
    assert abs(s.y[0] - np.exp(-s.t)) < 1e-5  # what was integrated is right


def test_blow_up_collapses_the_step_size_at_the_singularity():
    # y' = y^2, y(0) = 1: y = 1/(1 - t) blows up at t = 1
    prob = SimpleNamespace(n=1, fun=lambda t, y: y ** 2, jac=lambda t, y: np.array([[2.0 * y[0]]]))
    s, msg = run_to_failure(prob, [1.0], 2.0, rtol=1e-6, atol=1e-9)
    assert "step size collapsed" in msg and "t=1.0000000" in msg
    assert abs(s.t - 1.0) < 1e-6 and s.y[0] > 1e6
