"""Tests of the runtime's singular passages (``mbrt_pass.c``, ``mbrt_pass.h``) on a model in C.

The runtime's sources are compiled with a small C model into a shared library (called through
ctypes) and, with its ``main()`` (``MBRT_PASS_SELFTEST_MAIN``), into a program run under
AddressSanitizer/UBSan and valgrind with work buffers of exactly the advertised size.

The model: coordinates ``q = (a, b, c)``, unit masses (``M = I``), forces ``f = -g (cos a,
cos b, 0)``, rows ``sin a - sin b = 0`` and ``c - a = 0``. On the branch ``b = c = a`` it moves
as one coordinate with ``3 a'' = -2 g cos a`` (kinetic energy ``3 a'^2 / 2``, potential
``2 g sin a``), and at ``cos a = 0`` the first row's Jacobian ``(cos a, -cos b, 0)`` vanishes:
a singular position (the branches ``b = a`` and ``b = pi - a`` cross), passed straight through
on ``b = a`` when the multipliers leave out the lost direction. The model's "Lagrange program"
solves the saddle point directly and fails its guard where ``C C^T`` loses rank, as mbcomp's
generated one does.
"""
import ctypes
import shutil
import subprocess

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mbcomp.codegen import c_compiler

from runtime_selftest import Stats, build, run_under_sanitizers
from mbcomp.formulations.passing import MbrtPass

CC = c_compiler()
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler found")
G = 1.0  # m/s^2
W0 = 2.0  # rad/s: circulates (W0^2 / 2 > 4 g / 3), through cos a = 0 twice a turn

TEST_C = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mbrt.h"
#include "mbrt_pass.h"

/* the evaluation program: M 0..8, f 9..11, Phi 12..13, dPhi/dt 14..15, C 16..21, c_b 22..23 */
int prog_eval(const double *q, const double *u, double t, const double *d, const double *h,
              const double *p, double *w, double *out)
{ (void)t; (void)d; (void)h; (void)w;
  for (int i = 0; i < 9; ++i) out[i] = (i % 4 == 0) ? 1.0 : 0.0;
  out[9] = -p[0] * cos(q[0]); out[10] = -p[0] * cos(q[1]); out[11] = 0.0;
  out[12] = sin(q[0]) - sin(q[1]); out[13] = q[2] - q[0];
  out[16] = cos(q[0]); out[17] = -cos(q[1]); out[18] = 0.0;
  out[19] = -1.0; out[20] = 0.0; out[21] = 1.0;
  out[14] = out[16] * u[0] + out[17] * u[1]; out[15] = u[2] - u[0];
  out[22] = -sin(q[0]) * u[0] * u[0] + sin(q[1]) * u[1] * u[1]; out[23] = 0.0;
  return 0; }

/* the "Lagrange program": the saddle point with M = I by the 2 x 2 range space, its guard
 * failing where det(C C^T) falls below 1e-6 (dq/dt = u); d = (alpha, beta) unused (0) */
int prog_fun(const double *q, const double *u, double t, const double *d, const double *h,
             const double *p, double *w, double *out)
{ double e[24];
  (void)d;
  prog_eval(q, u, t, NULL, h, p, w, e);
  const double *C = e + 16, *f = e + 9;
  double G00 = 0, G01 = 0, G11 = 0, r0 = e[22], r1 = e[23];
  for (int j = 0; j < 3; ++j) {
      G00 += C[j] * C[j]; G01 += C[j] * C[3 + j]; G11 += C[3 + j] * C[3 + j];
      r0 += C[j] * f[j]; r1 += C[3 + j] * f[j]; }
  const double det = G00 * G11 - G01 * G01;
  if (!(det > 1e-6)) return 1;
  const double l0 = (G11 * r0 - G01 * r1) / det, l1 = (G00 * r1 - G01 * r0) / det;
  for (int j = 0; j < 3; ++j) { out[j] = u[j]; out[3 + j] = f[j] - C[j] * l0 - C[3 + j] * l1; }
  return 0; }

static const int ROWS[2] = {0, 1};
static const double GAINS[2] = {0.0, 0.0};

void model_mech(mbrt_mech *P, const double *p)
{ memset(P, 0, sizeof *P);
  P->eval = prog_eval; P->p = p; P->nq = 3; P->nu = 3; P->n_out = 24; P->mh = 2; P->mn = 0;
  P->nrows = 2; P->rows = ROWS;
  P->off_M = 0; P->off_f = 9; P->off_Phi = 12; P->off_Phid = 14; P->off_C = 16; P->off_cb = 22;
  P->off_B = 24; P->off_Bb = 24; P->off_Psi = 24; }

/* an mbrt_pass over the model (buffers from the caller: work, mech_work, log_t, log_y, y_last,
 * y_from) */
void model_pass(mbrt_pass *S, const mbrt_mech *P, int cap, double *work, double *mech_work, double *log_t,
                double *log_y, double *y_last, double *y_from)
{ memset(S, 0, sizeof *S);
  S->fun = prog_fun; S->d = GAINS; S->h = NULL; S->p = P->p; S->w = NULL; S->mech = P;
  S->mech_work = mech_work; S->pass_rank = 1e-8; S->project = 1; S->proj_tol = 1e-12; S->proj_accept = 1e-9;
  S->proj_iter = 8; S->delta = 1e-7; S->cap = cap; S->log_t = log_t; S->log_y = log_y; S->work = work;
  S->y_last = y_last; S->y_from = y_from; S->t_min = -INFINITY; S->t_rolled = -INFINITY;
  S->t_hidden = -INFINITY; }

size_t model_sizes(int which)
{ mbrt_mech P; double p[1] = {1.0};
  model_mech(&P, p);
  return which == 0 ? sizeof(mbrt_pass) : which == 1 ? mbrt_mech_work_size(&P) : mbrt_pass_work_size(&P, 64); }

#ifdef MBRT_PASS_SELFTEST_MAIN
static int failures = 0;
#define CHECK(c) do { if (!(c)) { failures++; printf("FAILED %s:%d: %s\n", __FILE__, __LINE__, #c); } } while (0)

int main(void)
{
    double p[1] = {1.0};
    mbrt_mech P;
    model_mech(&P, p);
    const int n = 6, cap = 64;
    double *work = malloc(mbrt_pass_work_size(&P, cap) * sizeof(double));
    double *mw = malloc(mbrt_mech_work_size(&P) * sizeof(double));
    double *lt = malloc(cap * sizeof(double)), *ly = malloc((size_t)cap * n * sizeof(double));
    double *yl = malloc(n * sizeof(double)), *yf = malloc(n * sizeof(double));
    double *rk = malloc(mbrt_dop853_work_size(n) * sizeof(double));
    double *rk5 = malloc(mbrt_dopri5_work_size(n) * sizeof(double));
    double y0[6] = {0, 0, 0, 2, 2, 2}, atol[6] = {1e-10, 1e-10, 1e-10, 1e-10, 1e-10, 1e-10};
    double t_out[40], *Y = malloc(40 * (size_t)n * sizeof(double));
    for (int i = 0; i < 40; ++i) t_out[i] = 0.25 * (i + 1);
    mbrt_pass S;
    mbrt_stats st;
    int nw = -1, total = 0;
    for (int order = 5; order <= 8; order += 3) {  /* the whole run in one call, then in stretches */
        model_pass(&S, &P, cap, work, mw, lt, ly, yl, yf);
        CHECK(mbrt_pass_integrate(&S, order, 0.0, y0, 10.0, 10.0, 1e-8, atol, 0.0, 0.0, 0, t_out, 40, Y, &nw,
                                  order == 8 ? rk : rk5, &st) == MBRT_OK);
        CHECK(nw == 40 && S.count >= 4 && S.nretaken >= S.count);
        model_pass(&S, &P, cap, work, mw, lt, ly, yl, yf);
        double t = 0.0, y[6], h = 0.0;
        memcpy(y, y0, sizeof y);
        total = 0;
        for (int c = 0; c < 4; ++c) {
            const double *to = t_out + 10 * c;
            int rc = mbrt_pass_integrate(&S, order, t, y, to[9], to[9] + 2.5, 1e-8, atol, h, 0.0, 0, to, 10,
                                         Y + (size_t)10 * c * n, &nw, order == 8 ? rk : rk5, &st);
            CHECK(rc == MBRT_OK && nw == 10 && S.t_last >= to[9]);
            total += S.count;
            t = S.t_from;  /* the step across the stretch's end, taken again */
            memcpy(y, S.y_from, sizeof y);
            h = S.h_last;
        }
        CHECK(total >= 4);
    }
    /* the range-space right-hand side next to the singular position, and bad descriptions */
    double ys[6] = {M_PI / 2 - 1e-9, M_PI / 2 - 1e-9, M_PI / 2 - 1e-9, 1.5, 1.5, 1.5}, dy[6];
    model_pass(&S, &P, cap, work, mw, lt, ly, yl, yf);
    CHECK(mbrt_pass_rhs(&S, 0.0, ys, dy) == MBRT_MECH_OK && isfinite(dy[3]) && fabs(dy[3] - dy[4]) < 1e-9);
    S.pass_rank = 0.0;
    CHECK(mbrt_pass_integrate(&S, 8, 0.0, y0, 1.0, 1.0, 1e-8, atol, 0.0, 0.0, 0, t_out, 1, Y, &nw, rk, &st) ==
          MBRT_BAD_ARGUMENT && nw == 0);
    model_pass(&S, &P, cap, work, mw, lt, ly, yl, yf);
    CHECK(mbrt_pass_integrate(&S, 7, 0.0, y0, 1.0, 1.0, 1e-8, atol, 0.0, 0.0, 0, t_out, 1, Y, &nw, rk, &st) ==
          MBRT_BAD_ARGUMENT);
    CHECK(mbrt_pass_integrate(&S, 8, 0.0, y0, 2.0, 1.0, 1e-8, atol, 0.0, 0.0, 0, t_out, 1, Y, &nw, rk, &st) ==
          MBRT_BAD_ARGUMENT);
    model_pass(&S, &P, 0, work, mw, lt, ly, yl, yf);  /* no room for a minimum: stopped at the first */
    CHECK(mbrt_pass_integrate(&S, 8, 0.0, y0, 10.0, 10.0, 1e-8, atol, 0.0, 0.0, 0, t_out, 40, Y, &nw, rk, &st) ==
          MBRT_STOPPED && S.t_last < 10.0 && nw < 40);
    free(work); free(mw); free(lt); free(ly); free(yl); free(yf); free(rk); free(rk5); free(Y);
    printf("%d failures\n", failures);
    return failures != 0;
}
#endif
"""


def _build(outdir, extra=(), exe=False):
    return build(outdir, TEST_C, "pass_selftest", "MBRT_PASS_SELFTEST_MAIN", extra, exe, ("-D_DEFAULT_SOURCE",))


class Model:
    """The C model's ``mbrt_mech`` and ``mbrt_pass`` with their buffers, from Python."""

    def __init__(self, lib, cap=64):
        self.lib, self.cap, n = lib, cap, 6
        size_pass, size_mech, _ = (lib.model_sizes(i) for i in range(3))
        assert size_pass == ctypes.sizeof(MbrtPass)  # the Python mirror of the struct has its layout
        self.p = np.array([G])
        self.mech = (ctypes.c_char * 512)()
        lib.model_mech(ctypes.addressof(self.mech), self.p.ctypes.data)
        self.work = np.zeros(int(lib.mbrt_pass_work_size(ctypes.addressof(self.mech), cap)))
        self.mw = np.zeros(size_mech)
        self.log_t, self.log_y = np.zeros(cap), np.zeros((cap, n))
        self.y_last, self.y_from = np.zeros(n), np.zeros(n)
        self.rk = np.zeros(int(lib.mbrt_dop853_work_size(n)))
        self.S = MbrtPass()
        lib.model_pass(ctypes.addressof(self.S), ctypes.addressof(self.mech), cap,
                       *(a.ctypes.data for a in (self.work, self.mw, self.log_t, self.log_y, self.y_last, self.y_from)))

    def integrate(self, t0, y0, t_out, t_end=None, h0=0.0, rtol=1e-8):
        t_out = np.ascontiguousarray(t_out, float)
        Y, nw, st = np.zeros((len(t_out), 6)), ctypes.c_int(0), Stats()
        y0 = np.ascontiguousarray(y0, float)
        rc = self.lib.mbrt_pass_integrate(ctypes.addressof(self.S), 8, t0, y0.ctypes.data, t_out[-1],
                                          t_out[-1] if t_end is None else t_end, rtol, np.full(6, 1e-10).ctypes.data,
                                          h0, 0.0, 0, t_out.ctypes.data, len(t_out), Y.ctypes.data,
                                          ctypes.addressof(nw), self.rk.ctypes.data, ctypes.addressof(st))
        return rc, Y[: nw.value], list(self.log_t[: self.S.count])


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    out, res = _build(tmp_path_factory.mktemp("mbrt_pass"))
    assert res.returncode == 0, res.stderr
    assert "warning" not in res.stderr, res.stderr
    L = ctypes.CDLL(str(out))
    vp, i, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    L.model_sizes.restype = ctypes.c_size_t
    L.model_sizes.argtypes = [i]
    L.model_mech.argtypes = [vp, vp]
    L.model_pass.argtypes = [vp, vp, i] + [vp] * 6
    L.mbrt_pass_work_size.restype = ctypes.c_size_t
    L.mbrt_pass_work_size.argtypes = [vp, i]
    L.mbrt_dop853_work_size.restype = ctypes.c_size_t
    L.mbrt_dop853_work_size.argtypes = [i]
    L.mbrt_pass_rhs.argtypes = [vp, d, vp, vp]
    L.mbrt_pass_integrate.argtypes = [vp, i, d, vp, d, d, d, vp, d, d, ctypes.c_long, vp, i, vp, vp, vp, vp]
    return L


def exact(ts):
    """a at ``ts`` and the singular instants (cos a = 0) of ``3 a'' = -2 g cos a``, a(0) = 0, a'(0) = W0."""
    sol = solve_ivp(lambda t, y: [y[1], -2.0 * G * np.cos(y[0]) / 3.0], (0.0, ts[-1]), [0.0, W0], t_eval=ts,
                    events=lambda t, y: np.cos(y[0]), rtol=1e-13, atol=1e-13, method="DOP853")
    return sol.y[0], sol.t_events[0]


def test_range_space_solve_is_the_saddle_point_away_from_and_at_the_singular_position(lib):
    m = Model(lib)
    for a, off, v in ((0.4, (1e-3, -2e-3), (1.0, 1.3, 0.7)), (np.pi / 2 - 1e-7, (0.0, 0.0), (1.5, 1.5, 1.5))):
        y = np.array([a, a + off[0], a + off[1], *v])
        dy = np.zeros(6)
        assert lib.mbrt_pass_rhs(ctypes.addressof(m.S), 0.0, y.ctypes.data, dy.ctypes.data) == 0
        q, u = y[:3], y[3:]
        C = np.array([[np.cos(q[0]), -np.cos(q[1]), 0.0], [-1.0, 0.0, 1.0]])
        f = -G * np.array([np.cos(q[0]), np.cos(q[1]), 0.0])
        cb = np.array([-np.sin(q[0]) * u[0] ** 2 + np.sin(q[1]) * u[1] ** 2, 0.0])
        g, V = np.linalg.eigh(C @ C.T)
        keep = g > 1e-8 * g[-1]
        lam = V[:, keep] @ ((V[:, keep].T @ (C @ f + cb)) / g[keep])
        np.testing.assert_allclose(dy[3:], f - C.T @ lam, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(dy[:3], u)
        assert keep.all() == (a < 1.5)  # the lost direction left out only next to cos a = 0


def test_passes_every_singular_position_on_the_exact_motion(lib):
    ts = np.linspace(0.25, 10.0, 40)
    rc, Y, minima = Model(lib).integrate(0.0, [0, 0, 0, W0, W0, W0], ts)
    assert rc == 0
    a, flats = exact(np.concatenate(([0.0], ts)))
    assert len(flats) >= 4
    np.testing.assert_allclose(minima, flats, atol=1e-8)  # located on the motion's own dense output
    np.testing.assert_allclose(Y[:, 0], a[1:], rtol=1e-6)  # rtol 1e-8 steps, 4 turns: 1.5e-7 measured
    np.testing.assert_allclose(Y[:, 1], Y[:, 0], atol=1e-7)  # still on the branch b = a
    E = 1.5 * Y[:, 3] ** 2 + 2.0 * G * np.sin(Y[:, 0])
    assert np.max(np.abs(E - E[0])) < 1e-6


def test_stretches_going_on_from_the_step_across_their_end_are_one_integration(lib):
    ts = np.linspace(0.25, 10.0, 40)
    whole, Yw, mw = Model(lib).integrate(0.0, [0, 0, 0, W0, W0, W0], ts)
    m = Model(lib)
    t, y, h, Ys, ms = 0.0, np.array([0, 0, 0, W0, W0, W0], float), 0.0, [], []
    for c in range(4):
        rc, Y, mins = m.integrate(t, y, ts[10 * c: 10 * c + 10], t_end=ts[10 * c + 9] + 2.5, h0=h)
        assert rc == 0 and m.S.t_last >= ts[10 * c + 9]
        Ys.append(Y)
        ms += mins
        t, y, h = m.S.t_from, m.y_from.copy(), m.S.h_last
    np.testing.assert_allclose(np.vstack(Ys), Yw, atol=1e-9)
    np.testing.assert_allclose(ms, mw, atol=1e-10)


def test_a_full_log_stops_at_the_last_step_before_the_minimum(lib):
    ts = np.linspace(0.25, 10.0, 40)
    m = Model(lib, cap=0)
    rc, Y, minima = m.integrate(0.0, [0, 0, 0, W0, W0, W0], ts)
    _, flats = exact(ts)
    assert rc == 5 and not minima and m.S.t_last < flats[0]  # status 5: stopped, the caller goes on
    assert len(Y) == np.searchsorted(ts, m.S.t_last, side="right")


# --------------------------------------------------------------------------- memory checkers
def test_selftest_under_asan_ubsan(tmp_path):
    """The C driver (one call, stretches, DOPRI5 and DOP853, the bad descriptions, a full log)
    with exact-size heap buffers under AddressSanitizer + UndefinedBehaviorSanitizer."""
    run = run_under_sanitizers(tmp_path, _build)
    if run is None:
        pytest.skip("AddressSanitizer/UBSan not usable here")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 failures" in run.stdout and "runtime error" not in run.stderr


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not installed")
def test_selftest_under_valgrind(tmp_path):
    exe, res = _build(tmp_path, exe=True)
    assert res.returncode == 0, res.stderr
    run = subprocess.run(["valgrind", "--error-exitcode=99", "--leak-check=full", "-q", str(exe)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 failures" in run.stdout
