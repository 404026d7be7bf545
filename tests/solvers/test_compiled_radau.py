"""The C RADAU5 (runtime ``mbrt_radau5``) against closed forms, the Python Radau5 and scipy's
Radau, and radau5 through ``simulate`` over a compiled program (``solvers/compiled_radau.py``).

The runtime's sources are compiled with a few test right-hand sides (C, below) into a
library called through ctypes, as ``tests/codegen/test_runtime_c.py`` does.
"""
import ctypes
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.codegen.runtime import RUNTIME_DIR, SOURCES
from mbcomp.solvers import compiled_radau
from mbcomp.solvers.compiled_radau import RadauInfo
from mbcomp.solvers.radau import Radau5

CC = c_compiler()
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler found")
ROOT = Path(__file__).resolve().parents[2]

TEST_C = r"""
#include <math.h>
#include "mbrt.h"
/* ctx: n, then A (n x n): y' = A y */
int rhs_lin(void *c, double t, const double *y, double *dy)
{ const double *p = c; int n = (int)p[0]; (void)t;
  for (int i = 0; i < n; ++i) { dy[i] = 0.0; for (int j = 0; j < n; ++j) dy[i] += p[1 + i * n + j] * y[j]; }
  return 0; }
int jac_lin(void *c, double t, const double *y, const double *fy, double *J)
{ const double *p = c; int n = (int)p[0]; (void)t; (void)y; (void)fy;
  for (int k = 0; k < n * n; ++k) J[k] = p[1 + k];
  return 0; }
/* a Jacobian that is never there: the integrator differences */
int jac_nan(void *c, double t, const double *y, const double *fy, double *J)
{ (void)c; (void)t; (void)y; (void)fy; J[0] = NAN; return 0; }
/* van der Pol, mu = ctx[0]: y0' = y1, y1' = mu ((1 - y0^2) y1 - y0) */
int rhs_vdp(void *c, double t, const double *y, double *dy)
{ double mu = ((const double *)c)[0]; (void)t; dy[0] = y[1]; dy[1] = mu * ((1 - y[0] * y[0]) * y[1] - y[0]); return 0; }
int jac_vdp(void *c, double t, const double *y, const double *fy, double *J)
{ double mu = ((const double *)c)[0]; (void)t; (void)fy;
  J[0] = 0; J[1] = 1; J[2] = mu * (-2 * y[0] * y[1] - 1); J[3] = mu * (1 - y[0] * y[0]); return 0; }
/* y' = y^2 from y(0) = 1: y = 1 / (1 - t), blows up at t = 1 */
int rhs_blow(void *c, double t, const double *y, double *dy) { (void)c; (void)t; dy[0] = y[0] * y[0]; return 0; }
/* y' = -y until t > ctx[0], then the code 3 */
int rhs_guard(void *c, double t, const double *y, double *dy)
{ dy[0] = -y[0]; return t > ((const double *)c)[0] ? 3 : 0; }
"""


class Stats(ctypes.Structure):
    _fields_ = [("nfev", ctypes.c_long), ("nstep", ctypes.c_long), ("naccept", ctypes.c_long),
                ("nreject", ctypes.c_long), ("status", ctypes.c_int), ("t", ctypes.c_double),
                ("message", ctypes.c_char * 200)]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    d = tmp_path_factory.mktemp("radau5")
    (d / "t.c").write_text(TEST_C)
    out = d / "libr5.so"
    res = subprocess.run([CC, "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-shared", "-fPIC", "-I",
                          str(RUNTIME_DIR), *map(str, SOURCES), str(d / "t.c"), "-o", str(out), "-lm"],
                         capture_output=True, text=True)
    assert res.returncode == 0 and "warning" not in res.stderr, res.stderr
    L = ctypes.CDLL(str(out))
    vp, i, dd = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    L.mbrt_radau5.argtypes = [vp, vp, vp, i, dd, vp, dd, dd, dd, vp, dd, dd, ctypes.c_long, vp, i, vp, vp, vp, vp,
                              i, vp, vp, vp]
    L.mbrt_radau5.restype = i
    L.mbrt_radau5_work_size.argtypes = L.mbrt_radau5_iwork_size.argtypes = [i]
    L.mbrt_radau5_work_size.restype = L.mbrt_radau5_iwork_size.restype = ctypes.c_size_t
    L.mbrt_radau5_coefficients.argtypes = [vp]
    return L


class Call:
    """One integration's buffers, so that a later call can resume it."""

    def __init__(self, lib, rhs, jac, ctx, n):
        self.lib, self.n = lib, n
        self.f = ctypes.cast(getattr(lib, rhs), ctypes.c_void_p)
        self.j = ctypes.cast(getattr(lib, jac), ctypes.c_void_p) if jac else None
        self.ctx = np.ascontiguousarray(ctx, float)
        self.work = np.zeros(lib.mbrt_radau5_work_size(n))
        self.iwork = np.zeros(lib.mbrt_radau5_iwork_size(n), np.intc)

    def __call__(self, t0, y0, t_end, t_out, rtol, atol, resume=False, h0=0.0, max_steps=0, t_pause=0.0):
        y0, t_out = np.ascontiguousarray(y0, float), np.ascontiguousarray(t_out, float)
        atol = np.full(self.n, atol, float)
        Y = np.full((len(t_out), self.n), np.nan)
        y_last, nw, st, info = np.zeros(self.n), ctypes.c_int(-1), Stats(), RadauInfo()
        status = self.lib.mbrt_radau5(self.f, self.j, self.ctx.ctypes.data, self.n, t0, y0.ctypes.data, t_end, t_pause,
                                      rtol,
                                      atol.ctypes.data, h0, 0.0, max_steps, t_out.ctypes.data, len(t_out),
                                      Y.ctypes.data, ctypes.byref(nw), self.work.ctypes.data, self.iwork.ctypes.data,
                                      int(resume), y_last.ctypes.data, ctypes.byref(st), ctypes.byref(info))
        assert status == st.status
        return SimpleNamespace(status=status, Y=Y[: nw.value], y_last=y_last, st=st, info=info,
                               message=st.message.decode())


def _stiff_matrix():
    """A (4 x 4) with eigenvalues -1, -1e4 and -50 +- 200 i, in a non-orthogonal basis."""
    rng = np.random.default_rng(3)
    V = np.eye(4) + 0.3 * rng.standard_normal((4, 4))
    D = np.array([[-1.0, 0, 0, 0], [0, -1e4, 0, 0], [0, 0, -50.0, 200.0], [0, 0, -200.0, -50.0]])
    return V @ D @ np.linalg.inv(V)


@pytest.mark.parametrize("jac", ["jac_lin", None, "jac_nan"])
def test_linear_stiff_ode_matches_the_matrix_exponential(lib, jac):
    """y' = A y, y = expm(A t) y0: the outputs within the tolerance's reach of the closed form,
    with the exact Jacobian and with the differenced one (none given, or a non-finite one)."""
    A = _stiff_matrix()
    y0 = np.array([1.0, -0.5, 0.25, 2.0])
    t_out = np.linspace(0.0, 2.0, 21)
    r = Call(lib, "rhs_lin", jac, np.r_[4.0, A.ravel()], 4)(0.0, y0, 2.0, t_out, 1e-8, 1e-10)
    assert r.status == 0, r.message
    exact = np.array([expm(A * t) @ y0 for t in t_out])
    assert np.max(np.abs(r.Y - exact)) < 2e-7  # local tolerance 1e-8 relative, 21 outputs over ~100 steps
    assert np.array_equal(r.Y[-1], r.y_last)
    assert r.info.njev >= 1 and (r.info.ndiff == (0 if jac == "jac_lin" else r.info.njev))
    if jac != "jac_lin":  # each difference Jacobian costs n evaluations
        assert r.st.nfev >= 4 * r.info.ndiff


def test_the_c_steps_are_the_python_steps(lib):
    """The same algorithm as the Python Radau5 (E = I), its linear algebra the runtime's own
    (LAPACK's there): on the stiff linear ODE the same work to round-off's influence on the
    reuse decisions (within 1 %), the results equal far below the tolerance."""
    A = _stiff_matrix()
    y0 = np.array([1.0, -0.5, 0.25, 2.0])
    r = Call(lib, "rhs_lin", "jac_lin", np.r_[4.0, A.ravel()], 4)(0.0, y0, 2.0, [2.0], 1e-8, 1e-10)
    prob = SimpleNamespace(n=4, fun=lambda t, y: A @ y, jac=lambda t, y: A)
    s = Radau5(prob, 0.0, y0, 2.0, rtol=1e-8, atol=1e-10)
    while s.status == "running":
        s.step()
    assert abs(r.st.naccept - s.stats["nsteps"]) <= 0.01 * s.stats["nsteps"]
    assert r.st.nreject == s.stats["nreject"] and r.info.njev == s.stats["njev"]
    assert abs(r.info.nnewton - s.stats["nnewton"]) <= 0.01 * s.stats["nnewton"]
    assert np.max(np.abs(r.y_last - s.y)) < 1e-11


def test_van_der_pol_agrees_with_scipy_radau(lib):
    """Hairer's stiff van der Pol (VDPOL: eps = 1e-6, two relaxations over 2 time units) at
    rtol 1e-7 against scipy's Radau at 1e-12 (the reference): within the error that
    accumulates over the fast transitions (1e-4 here); and stiff work, not explicit work."""
    mu, t_out = 1e6, np.linspace(0.0, 2.0, 11)
    r = Call(lib, "rhs_vdp", "jac_vdp", [mu], 2)(0.0, [2.0, -0.66], 2.0, t_out, 1e-7, 1e-7)
    assert r.status == 0, r.message
    ref = solve_ivp(lambda t, y: [y[1], mu * ((1 - y[0] ** 2) * y[1] - y[0])], (0, 2), [2.0, -0.66], method="Radau",
                    rtol=1e-12, atol=1e-12, t_eval=t_out, jac=lambda t, y: [[0, 1], [mu * (-2 * y[0] * y[1] - 1),
                                                                             mu * (1 - y[0] ** 2)]])
    assert np.max(np.abs(r.Y[:, 0] - ref.y[0])) < 1e-4
    assert r.st.naccept < 2000  # an explicit method would take ~1e7 steps (|lambda| ~ 3e6)


def test_paused_calls_that_resume_take_the_steps_of_one_call(lib):
    """A run in three calls, each paused after the step past its last output and resumed by
    the next, is the run of one call bit for bit (the Jacobian, factors, predictor and
    controller live in the work buffer); a call that does not resume starts afresh."""
    A = _stiff_matrix()
    y0 = np.array([1.0, -0.5, 0.25, 2.0])
    t_out = np.linspace(0.0, 2.0, 21)[1:]
    ctx = np.r_[4.0, A.ravel()]
    one = Call(lib, "rhs_lin", "jac_lin", ctx, 4)(0.0, y0, 2.0, t_out, 1e-6, 1e-8)
    part = Call(lib, "rhs_lin", "jac_lin", ctx, 4)
    t, y, rows, steps, k = 0.0, y0, [], 0, 0
    for stop in (t_out[2], t_out[9], 0.0):
        r = part(t, y, 2.0, t_out[k:], 1e-6, 1e-8, resume=t > 0.0, t_pause=stop)
        assert r.status == (21 if stop else 0), r.message
        assert stop == 0.0 or r.st.t >= stop and len(r.Y) >= 1
        rows.append(r.Y)
        steps += r.st.naccept
        k += len(r.Y)
        t, y = r.st.t, r.y_last
    assert np.array_equal(np.vstack(rows), one.Y) and steps == one.st.naccept
    fresh = Call(lib, "rhs_lin", "jac_lin", ctx, 4)(t_out[2], one.Y[2], 2.0, t_out[3:], 1e-6, 1e-8)
    assert not np.array_equal(fresh.Y, one.Y[3:])  # not resumed: a new start (first step, Jacobian)


def test_a_blow_up_is_a_failure_with_a_message_not_nan(lib):
    """y' = y^2 leaves every finite value at t = 1: the integration stops before it with a
    status and a sentence naming the time; every output written is finite, y_last too."""
    t_out = np.linspace(0.0, 2.0, 41)
    r = Call(lib, "rhs_blow", None, [0.0], 1)(0.0, [1.0], 2.0, t_out, 1e-8, 1e-10)
    assert r.status in (2, 4), r.message  # step size collapsed, or not finite
    assert "RADAU5" in r.message and "t=" in r.message
    assert abs(r.st.t - 1.0) < 1e-6  # (an implicit step may land just past the pole, y finite there)
    assert np.isfinite(r.Y).all() and np.isfinite(r.y_last).all()
    before = t_out[: len(r.Y)] < 0.99
    assert before.sum() >= 19 and np.allclose(r.Y[before, 0], 1.0 / (1.0 - t_out[: len(r.Y)][before]), rtol=1e-6)


def test_a_failing_rhs_stops_at_the_last_accepted_step(lib):
    r = Call(lib, "rhs_guard", None, [0.5], 1)(0.0, [1.0], 1.0, np.linspace(0, 1, 11), 1e-8, 1e-10)
    assert r.status == 1 and "returned 3" in r.message
    assert r.st.t <= 0.5 + 1e-12 and abs(r.y_last[0] - np.exp(-r.st.t)) < 1e-8
    assert len(r.Y) == int(np.floor(r.st.t * 10 + 1e-9)) + 1


@pytest.mark.parametrize("case, what", [(dict(rtol=1e-20), "rtol"), (dict(atol=-1.0), "atol"),
                                        (dict(t_end=-1.0), "t_end"), (dict(y0=[np.nan]), "y0")])
def test_bad_arguments_are_named(lib, case, what):
    a = dict(t0=0.0, y0=[1.0], t_end=1.0, t_out=[1.0], rtol=1e-6, atol=1e-8)
    a.update(case)
    if what == "t_end":
        a["t_out"] = []
    r = Call(lib, "rhs_blow", None, [0.0], 1)(**a)
    assert r.status == 6 and what in r.message


def test_coefficients_are_radau_iia(lib):
    """The constants in C: TI = T^-1, TI A^-1 T = LAM with A Radau IIA's (3 stages), the
    complex eigenvalue in LAM's 2 x 2 block, the nodes, the dense output's basis."""
    out = np.zeros(45)
    lib.mbrt_radau5_coefficients(out.ctypes.data)
    c, T, TI, LAM = out[:3], out[3:12].reshape(3, 3), out[12:21].reshape(3, 3), out[21:30].reshape(3, 3)
    gamma, mu, P = out[30], complex(out[31], out[32]), out[36:45].reshape(3, 3)
    s6 = np.sqrt(6.0)
    assert np.allclose(c, [(4 - s6) / 10, (4 + s6) / 10, 1.0], atol=1e-16)
    A = np.array([[(88 - 7 * s6) / 360, (296 - 169 * s6) / 1800, (-2 + 3 * s6) / 225],
                  [(296 + 169 * s6) / 1800, (88 + 7 * s6) / 360, (-2 - 3 * s6) / 225],
                  [(16 - s6) / 36, (16 + s6) / 36, 1 / 9]])
    assert np.allclose(TI @ T, np.eye(3), atol=1e-14)
    assert np.allclose(TI @ np.linalg.inv(A) @ T, LAM, atol=1e-12)
    ev = np.linalg.eigvals(np.linalg.inv(A))
    assert np.isclose(min(abs(ev - gamma)), 0, atol=1e-12) and np.isclose(min(abs(ev - mu.conjugate())), 0, atol=1e-12)
    assert np.allclose(P @ np.column_stack([c, c**2, c**3]).T, np.eye(3), atol=1e-13)  # L_i(c_j) = delta_ij


# ------------------------------------------------------------------ through simulate
def _chain():
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        from peers import stiff_chain
    finally:
        sys.path.remove(str(ROOT / "bench"))
    return stiff_chain


def test_a_failed_guard_hands_the_run_to_the_python_stepper():
    """A torque law with a branch on the speed (traced on the start's branch): the C loop
    stops where the pendulum's speed passes -0.5 rad/s (a Newton iterate there), the Python
    Radau5 goes on from the last accepted step; the motion is the numeric path's (scipy's
    Radau on the dense path) within the tolerance's reach."""
    from conftest import torque_pendulum

    law = lambda t, phi, w: -0.3 if w > -0.5 else 0.3  # noqa: E731 - a torque switching on the speed
    kw = dict(t_end=2.0, rtol=1e-9, atol=1e-11, n_out=41)
    fast = mbcomp.simulate(torque_pendulum(law), method="radau5", backend="c", **kw)
    ref = mbcomp.simulate(torque_pendulum(law), method="Radau", backend="numeric", **kw)
    assert fast.success, fast.message
    assert fast.stats["stretches"] >= 1 and 0 < fast.stats["python_steps"] < fast.stats["steps"]  # C, then Python
    np.testing.assert_allclose(fast["hinge.phi"], ref["hinge.phi"], atol=1e-6)


def test_simulate_runs_radau5_in_c_and_agrees_with_the_python_stepper(monkeypatch):
    """The damped stiff spring chain (N = 2): radau5 in C stretches, the Python Radau5 (engine
    taken away) and scipy's Radau at 1e-12 agree within a few tolerances on 101 outputs."""
    chain = _chain()
    names = chain.state_names(2)
    opts = dict(t_end=0.5, rtol=1e-8, atol=1e-8, n_out=101)
    c = mbcomp.simulate(chain.build_model(), method="radau5", **opts)
    assert c.status == "success" and c.stats["stretches"] >= 3 and c.stats["python_steps"] == 0
    monkeypatch.setattr(compiled_radau, "engine_of", lambda problem: None)
    p = mbcomp.simulate(chain.build_model(), method="radau5", **opts)
    assert p.status == "success" and p.stats["stretches"] == 0
    monkeypatch.undo()
    ref = mbcomp.simulate(chain.build_model(), method="Radau", t_end=0.5, rtol=1e-12, atol=1e-13, n_out=101)
    Yc, Yp, Yr = (np.column_stack([r[n] for n in names]) for r in (c, p, ref))
    assert np.max(np.abs(Yc - Yr)) < 2e-7 and np.max(np.abs(Yp - Yr)) < 2e-7
    assert abs(c.stats["steps"] - p.stats["steps"]) <= 0.05 * p.stats["steps"]


def test_the_c_constants_are_the_python_steppers(lib):
    """The two steppers are one algorithm: the C's control constants are radau.py's, and its
    coefficients the numbers radau.py derives (were they to move -- another LAPACK's
    eigenvectors -- the hexadecimal floats in mbrt_radau5_internal.h are to be printed again)."""
    from mbcomp.solvers import radau

    text = (RUNTIME_DIR / "mbrt_radau5_internal.h").read_text()
    defs = {k: float(v) for k, v in re.findall(r"#define (\w+) +([0-9][0-9.e+-]*)L?\s", text)}
    assert (defs["NIT"], defs["THETA_JAC"], defs["SAFETY"], defs["FAC_MAX"], defs["FAC_MIN"]) == \
        (radau.NEWTON_MAXITER, radau.THETA_JAC, radau.SAFETY, radau.FAC_MAX, radau.FAC_MIN)
    assert (defs["QUOT_LO"], defs["QUOT_HI"]) == radau.QUOT_KEEP
    assert (defs["MAX_SINGULAR"], defs["MAX_FAILURES"], defs["H_START"]) == \
        (radau.MAX_SINGULAR, radau.MAX_FAILURES, radau.H_START)
    out = np.zeros(45)
    lib.mbrt_radau5_coefficients(out.ctypes.data)
    mine = np.r_[radau.C, radau.T.ravel(), radau.TI.ravel(), radau.LAM.ravel(), radau.GAMMA, radau.MU.real,
                 radau.MU.imag, radau.D_ERR, radau.P_DENSE.ravel()]
    assert np.array_equal(out, mine)
