"""Tests of the C runtime ``mbcomp.codegen.runtime`` (linear algebra, DOPRI5, DOP853).

The runtime sources are compiled together with a small C file of test
right-hand sides into a shared library and called through ctypes; the same C
file has a ``main()`` (under ``MBRT_SELFTEST_MAIN``) used for the
AddressSanitizer/UBSan and valgrind runs at the end.
"""

import ctypes
import shutil
import subprocess

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mbcomp.codegen import c_compiler

from runtime_selftest import Stats, build, run_under_sanitizers

CC = c_compiler()
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler found")

TEST_C = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mbrt.h"

/* ctx of every rhs: a double array of parameters (may be NULL) */
int rhs_decay(void *ctx, double t, const double *y, double *dy)
{ (void)ctx; (void)t; dy[0] = -y[0]; return 0; }

/* a fall: y0' = y1, y1' = -g  (g = p[0]) */
int rhs_fall(void *ctx, double t, const double *y, double *dy)
{ (void)t; dy[0] = y[1]; dy[1] = -((const double *)ctx)[0]; return 0; }

/* y0' = y1, y1' = -w^2 y0  (w = p[0]) */
int rhs_osc(void *ctx, double t, const double *y, double *dy)
{ double w = ((const double *)ctx)[0]; (void)t; dy[0] = y[1]; dy[1] = -w * w * y[0]; return 0; }

/* Van der Pol, mu = p[0] */
int rhs_vdp(void *ctx, double t, const double *y, double *dy)
{ double mu = ((const double *)ctx)[0]; (void)t;
  dy[0] = y[1]; dy[1] = mu * (1.0 - y[0] * y[0]) * y[1] - y[0]; return 0; }

/* Arenstorf orbit (Hairer et al., Sec. II.0) */
int rhs_arenstorf(void *ctx, double t, const double *y, double *dy)
{ const double mu = 0.012277471, mp = 1.0 - mu; (void)ctx; (void)t;
  double d1 = pow((y[0] + mu) * (y[0] + mu) + y[1] * y[1], 1.5);
  double d2 = pow((y[0] - mp) * (y[0] - mp) + y[1] * y[1], 1.5);
  dy[0] = y[2]; dy[1] = y[3];
  dy[2] = y[0] + 2.0 * y[3] - mp * (y[0] + mu) / d1 - mu * (y[0] - mp) / d2;
  dy[3] = y[1] - 2.0 * y[2] - mp * y[1] / d1 - mu * y[1] / d2;
  return 0; }

/* y' = -y until t > p[0] or call number p[3] > 0, then returns code p[1]
 * (p[2] counts calls) */
int rhs_fail(void *ctx, double t, const double *y, double *dy)
{ double *p = (double *)ctx; p[2] += 1.0; dy[0] = -y[0];
  return (t > p[0] || (p[3] > 0.0 && p[2] >= p[3])) ? (int)p[1] : 0; }

/* y' = -y until t > p[0], then NaN */
int rhs_nan(void *ctx, double t, const double *y, double *dy)
{ double *p = (double *)ctx; dy[0] = t > p[0] ? NAN : -y[0]; return 0; }

/* outward spiral: rotation plus growth p[5] * y (ctx shared with step_project) */
int rhs_spiral(void *ctx, double t, const double *y, double *dy)
{ double g = ((const double *)ctx)[5]; (void)t;
  dy[0] = -y[1] + g * y[0]; dy[1] = y[0] + g * y[1]; return 0; }

/* step callback: p[0] counts calls, p[1] = 1 to project onto |y| = 1,
 * stop with code p[3] once t >= p[2] > 0, p[4] = max ||y|-1| before projecting */
int step_project(void *ctx, double t, double *y)
{ double *p = (double *)ctx; p[0] += 1.0;
  double r = sqrt(y[0] * y[0] + y[1] * y[1]);
  if (fabs(r - 1.0) > p[4]) p[4] = fabs(r - 1.0);
  if (p[1] != 0.0) { y[0] /= r; y[1] /= r; }
  if (p[2] > 0.0 && t >= p[2]) return (int)p[3];
  return 0; }

/* step callback that breaks the state */
int step_nan(void *ctx, double t, double *y)
{ (void)ctx; (void)t; y[0] = NAN; return 0; }

/* An evaluation program for the mechanics kernels: a point mass p[0] (kg) in the
 * vertical plane, coordinates q = (x, y) (m), speeds u = dq/dt, gravity p[1] (m/s^2)
 * along -y, on a rod of length p[2] (m) from the origin: Phi = (x^2 + y^2 - L^2) / 2,
 * C = [x, y], dPhi/dt = C u, c_b = |u|^2 (d/dt C times u).  Output layout:
 * M 0..3, f 4..5, Phi 6, dPhi/dt 7, C 8..9, c_b 10 (no nonholonomic rows); n_out 11.
 * A guard: x > 5 m fails (returns 1). */
int prog_pendulum(const double *q, const double *u, double t, const double *d, const double *h,
                  const double *p, double *w, double *out)
{ (void)t; (void)d; (void)h; (void)w;
  if (q[0] > 5.0) return 1;
  out[0] = p[0]; out[1] = 0.0; out[2] = 0.0; out[3] = p[0];
  out[4] = 0.0; out[5] = -p[0] * p[1];
  out[6] = 0.5 * (q[0] * q[0] + q[1] * q[1] - p[2] * p[2]);
  out[7] = q[0] * u[0] + q[1] * u[1];
  out[8] = q[0]; out[9] = q[1];
  out[10] = u[0] * u[0] + u[1] * u[1];
  return 0; }

/* dq/dt = u, as a program (the kernels' qrate) */
int prog_qrate(const double *q, const double *u, double t, const double *d, const double *h,
               const double *p, double *w, double *out)
{ (void)q; (void)t; (void)d; (void)h; (void)p; (void)w; out[0] = u[0]; out[1] = u[1]; return 0; }

/* A rigid body on a ball joint, q = unit quaternion (w, x, y, z), u = body angular velocity
 * (rad/s), whose x axis must stay horizontal: Phi = R20 = 2 (x z - w y), C = [0, -R22, R21]
 * (dPhi/dt = (R (u x e_x))_z), unit inertia and no forces; layout as prog_pendulum's with
 * nq = 4, nu = 3: M 0..8, f 9..11, Phi 12, dPhi/dt 13, C 14..16, c_b 17; n_out 18. */
int prog_ball(const double *q, const double *u, double t, const double *d, const double *h,
              const double *p, double *w, double *out)
{ (void)t; (void)d; (void)h; (void)p; (void)w;
  double R21 = 2.0 * (q[2] * q[3] + q[0] * q[1]), R22 = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]);
  for (int i = 0; i < 9; ++i) out[i] = (i % 4 == 0) ? 1.0 : 0.0;
  out[9] = out[10] = out[11] = 0.0;
  out[12] = 2.0 * (q[1] * q[3] - q[0] * q[2]);
  out[14] = 0.0; out[15] = -R22; out[16] = R21;
  out[13] = out[15] * u[1] + out[16] * u[2];
  out[17] = 0.0;
  return 0; }

/* dQ/dt = Q (0, u) / 2 */
int prog_ball_qrate(const double *q, const double *u, double t, const double *d, const double *h,
                    const double *p, double *w, double *out)
{ (void)t; (void)d; (void)h; (void)p; (void)w;
  out[0] = 0.5 * (-q[1] * u[0] - q[2] * u[1] - q[3] * u[2]);
  out[1] = 0.5 * (q[0] * u[0] + q[2] * u[2] - q[3] * u[1]);
  out[2] = 0.5 * (q[0] * u[1] - q[1] * u[2] + q[3] * u[0]);
  out[3] = 0.5 * (q[0] * u[2] + q[1] * u[1] - q[2] * u[0]);
  return 0; }

void mech_ball(mbrt_mech *P, const int *rows, const int *seg)
{ memset(P, 0, sizeof *P);
  P->eval = prog_ball; P->qrate = prog_ball_qrate;
  P->nq = 4; P->nu = 3; P->n_out = 18; P->mh = 1; P->mn = 0; P->nrows = 1; P->rows = rows;
  P->off_M = 0; P->off_f = 9; P->off_Phi = 12; P->off_Phid = 13; P->off_C = 14; P->off_cb = 17;
  P->off_B = 18; P->off_Bb = 18; P->off_Psi = 18; P->nseg = 1; P->seg = seg; }

/* The pendulum's layout in an mbrt_mech (p: m, g, L; rows: the one holonomic row). */
void mech_pendulum(mbrt_mech *P, const double *p, const int *rows, int qrate)
{ memset(P, 0, sizeof *P);
  P->eval = prog_pendulum; P->qrate = qrate ? prog_qrate : NULL; P->p = p;
  P->nq = 2; P->nu = 2; P->n_out = 11; P->mh = 1; P->mn = 0; P->nrows = 1; P->rows = rows;
  P->off_M = 0; P->off_f = 4; P->off_Phi = 6; P->off_Phid = 7; P->off_C = 8; P->off_cb = 10;
  P->off_B = 11; P->off_Bb = 11; P->off_Psi = 11; }

/* A mass on a vertical line over a floor at s = 0 (mbrt_impacts): the evaluation program of
 * q = s, u = ds/dt, mass p[0] (kg), gravity p[1] (m/s^2): M = [m], f = [-m g]; n_out 2. */
int prog_fall(const double *q, const double *u, double t, const double *d, const double *h,
              const double *p, double *w, double *out)
{ (void)q; (void)u; (void)t; (void)d; (void)h; (void)w; out[0] = p[0]; out[1] = -p[0] * p[1]; return 0; }

/* A stretch function over mbrt_dop853_events for the falling mass (ctx: an mbrt_events *,
 * gravity 9.81), with mbcomp_integrate's signature. */
static double g_fall = 9.81;
int stretch_fall(int order, void *ctx, double t0, const double *y0, double t_end, double rtol,
                 const double *atol, double h0, double hmax, long max_steps, const double *t_out,
                 int n_out, double *y_out, int *n_written, double *work, mbrt_stats *stats)
{ (void)order;
  return mbrt_dop853_events(rhs_fall, NULL, &g_fall, 2, t0, y0, t_end, rtol, atol, h0, hmax, max_steps, t_out,
                            n_out, y_out, n_written, work, stats, 0, (mbrt_events *)ctx); }

#ifdef MBRT_SELFTEST_MAIN
/* Standalone driver for sanitizer / valgrind runs: exercises every code path
 * with work buffers of exactly the advertised size (heap, so overruns show). */
typedef int (*integ_fn)(mbrt_rhs_fn, mbrt_step_fn, void *, int, double, const double *, double,
                        double, const double *, double, double, long, const double *, int,
                        double *, int *, double *, mbrt_stats *);
static int failures = 0;
#define CHECK(c) do { if (!(c)) { printf("FAILED: %s (line %d)\n", #c, __LINE__); failures++; } } while (0)

static int run(integ_fn F, size_t (*ws)(int), mbrt_rhs_fn f, mbrt_step_fn s, void *ctx, int n,
               const double *y0, double t1, double rtol, int nout, long max_steps, mbrt_stats *st,
               double *last)
{
    double *work = malloc(ws(n) * sizeof(double));
    double *tout = malloc((size_t)nout * sizeof(double));
    double *yout = malloc((size_t)nout * (size_t)n * sizeof(double));
    double *atol = malloc((size_t)n * sizeof(double));
    for (int i = 0; i < n; ++i) atol[i] = rtol;
    for (int i = 0; i < nout; ++i) tout[i] = t1 * i / (nout - 1);
    int nw = -1;
    int rc = F(f, s, ctx, n, 0.0, y0, t1, rtol, atol, 0.0, 0.0, max_steps, tout, nout, yout, &nw,
               work, st);
    CHECK(rc == st->status && nw >= 0 && nw <= nout);
    if (last && nw > 0) memcpy(last, yout + (size_t)(nw - 1) * n, (size_t)n * sizeof(double));
    free(work); free(tout); free(yout); free(atol);
    return rc;
}

/* the van der Pol Jacobian (rhs_vdp's, mu = p[0]) for mbrt_radau5 */
static int jac_vdp(void *ctx, double t, const double *y, const double *fy, double *J)
{ double mu = ((const double *)ctx)[0]; (void)t; (void)fy;
  J[0] = 0.0; J[1] = 1.0; J[2] = -2.0 * mu * y[0] * y[1] - 1.0; J[3] = mu * (1.0 - y[0] * y[0]); return 0; }

/* mbrt_radau5 (mbrt_radau5.c) with exact-size heap buffers: paused and resumed, the dense
 * output, exact and differenced Jacobians, a failing rhs, max_steps, a NaN rhs, bad input */
static void radau5_selftest(void)
{
    int n = 2, nw = 0;
    double *w = malloc(mbrt_radau5_work_size(n) * sizeof(double));
    int *iw = malloc(mbrt_radau5_iwork_size(n) * sizeof(int));
    double mu[1] = {1000.0}, y0[2] = {2.0, 0.0}, atol[2] = {1e-8, 1e-8}, yl[2], yd[2];
    double tout[3] = {1.0, 5.0, 3000.0}, yout[6]; /* a relaxation near t = 800 */
    mbrt_stats st;
    mbrt_radau5_info info;
    CHECK(mbrt_radau5(rhs_vdp, jac_vdp, mu, n, 0.0, y0, 3000.0, 5.0, 1e-6, atol, 0, 0, 0, tout, 3, yout, &nw, w, iw,
                      0, yl, &st, &info) == MBRT_RADAU5_PAUSED);
    CHECK(st.t >= 5.0 && nw >= 2 && info.ndiff == 0 && info.njev >= 1);
    mbrt_radau5_dense(w, n, st.t, yd);
    CHECK(fabs(yd[0] - yl[0]) < 1e-12 && fabs(yd[1] - yl[1]) < 1e-9);
    int done = nw;
    CHECK(mbrt_radau5(rhs_vdp, NULL, mu, n, st.t, yl, 3000.0, 0.0, 1e-6, atol, 0, 0, 0, tout + done, 3 - done,
                      yout + 2 * done, &nw, w, iw, 1, yl, &st, &info) == MBRT_OK);
    CHECK(st.t == 3000.0 && nw == 3 - done && yout[4] == yl[0] && info.ndiff == info.njev);
    double p[4] = {0.5, 7.0, 0.0, 0.0}, one[1] = {1.0}, a1[1] = {1e-8}, y1[1], o1[4], tf[4] = {0.25, 0.5, 0.75, 1.0};
    CHECK(mbrt_radau5(rhs_fail, NULL, p, 1, 0.0, one, 1.0, 0.0, 1e-6, a1, 0, 0, 0, tf, 4, o1, &nw, w, iw, 0, y1, &st,
                      &info) == MBRT_RHS_FAILED);
    CHECK(st.t <= 0.5 && nw >= 1 && isfinite(y1[0]));
    CHECK(mbrt_radau5(rhs_decay, NULL, NULL, 1, 0.0, one, 1.0, 0.0, 1e-6, a1, 0, 0, 3, tf, 4, o1, &nw, w, iw, 0, y1,
                      &st, &info) == MBRT_MAX_STEPS);
    double q[1] = {0.3};
    int rc = mbrt_radau5(rhs_nan, NULL, q, 1, 0.0, one, 1.0, 0.0, 1e-6, a1, 0, 0, 0, tf, 4, o1, &nw, w, iw, 0, y1, &st,
                         &info);
    CHECK((rc == MBRT_STEP_TOO_SMALL || rc == MBRT_NONFINITE) && isfinite(y1[0]) && st.t <= 0.3 + 1e-12);
    CHECK(mbrt_radau5(rhs_decay, NULL, NULL, 0, 0.0, one, 1.0, 0.0, 1e-6, a1, 0, 0, 0, tf, 4, o1, &nw, w, iw, 0, y1,
                      &st, &info) == MBRT_BAD_ARGUMENT);
    free(w);
    free(iw);
}

int main(void)
{
    /* linear algebra on a pseudo-random diagonally dominant matrix */
    enum { N = 7 };
    double A[N * N], LU[N * N], b[N], x[N], S[N * N];
    int piv[N];
    unsigned long seed = 12345;
    for (int i = 0; i < N * N; ++i) { seed = seed * 6364136223846793005UL + 1442695040888963407UL;
        A[i] = (double)(seed >> 11) / 9007199254740992.0 - 0.5; }
    for (int i = 0; i < N; ++i) { A[i * N + i] += 4.0; x[i] = i + 1.0; }
    for (int i = 0; i < N; ++i) { b[i] = 0; for (int j = 0; j < N; ++j) b[i] += A[i * N + j] * x[j]; }
    memcpy(LU, A, sizeof A);
    CHECK(mbrt_lu_factor(N, LU, piv) == 0);
    mbrt_lu_solve(N, LU, piv, b);
    for (int i = 0; i < N; ++i) CHECK(fabs(b[i] - x[i]) < 1e-12);
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) {
            double s = 0;
            for (int k = 0; k < N; ++k)
                s += A[i * N + k] * A[j * N + k];
            S[i * N + j] = s;
        }
    for (int i = 0; i < N; ++i) { b[i] = 0; for (int j = 0; j < N; ++j) b[i] += S[i * N + j] * x[j]; }
    CHECK(mbrt_chol_factor(N, S) == 0);
    mbrt_chol_solve(N, S, b);
    for (int i = 0; i < N; ++i) CHECK(fabs(b[i] - x[i]) < 1e-10);
    double Z[4] = {1, 2, 2, 4}; int pz[2];
    CHECK(mbrt_lu_factor(2, Z, pz) == 2);
    double Zc[4] = {1, 2, 2, 4};
    CHECK(mbrt_chol_factor(2, Zc) == 2);

    integ_fn meth[2] = {mbrt_dopri5, mbrt_dop853};
    size_t (*wsz[2])(int) = {mbrt_dopri5_work_size, mbrt_dop853_work_size};
    for (int m = 0; m < 2; ++m) {
        mbrt_stats st;
        double last[4];
        double w = 2.0, y2[2] = {1.0, 0.0};
        CHECK(run(meth[m], wsz[m], rhs_osc, NULL, &w, 2, y2, 10.0, 1e-8, 101, 0, &st, last) == 0);
        CHECK(fabs(last[0] - cos(20.0)) < 1e-6);
        double mu = 1.0, yv[2] = {2.0, 0.0};
        CHECK(run(meth[m], wsz[m], rhs_vdp, NULL, &mu, 2, yv, 20.0, 1e-9, 57, 0, &st, last) == 0);
        double ya[4] = {0.994, 0.0, 0.0, -2.00158510637908252240537862224};
        CHECK(run(meth[m], wsz[m], rhs_arenstorf, NULL, NULL, 4, ya, 17.0652165601579625588917206249,
                  1e-10, 33, 0, &st, last) == 0);
        CHECK(fabs(last[0] - 0.994) < 1e-5 && fabs(last[1]) < 1e-5);
        double y1[1] = {1.0}, pf[4] = {0.5, 7, 0, 0};
        CHECK(run(meth[m], wsz[m], rhs_fail, NULL, pf, 1, y1, 1.0, 1e-8, 11, 0, &st, last) == 1);
        double pf2[4] = {9.0, 5, 0, 20};  /* fails at the 20th call */
        CHECK(run(meth[m], wsz[m], rhs_fail, NULL, pf2, 1, y1, 1.0, 1e-8, 3, 0, &st, last) == 1);
        double pn[1] = {0.5};
        CHECK(run(meth[m], wsz[m], rhs_nan, NULL, pn, 1, y1, 1.0, 1e-8, 11, 0, &st, last) == 2);
        double ps[6] = {0, 1, 0, 0, 0, 0.1};
        CHECK(run(meth[m], wsz[m], rhs_spiral, step_project, ps, 2, y2, 10.0, 1e-6, 11, 0, &st, last) == 0);
        /* the sample at t_end is taken before the last projection: one step's growth */
        CHECK(fabs(hypot(last[0], last[1]) - 1.0) < 0.2 && ps[0] == st.naccept && ps[4] < 0.2);
        double ps2[6] = {0, 1, 3.0, 9, 0, 0.1};
        CHECK(run(meth[m], wsz[m], rhs_spiral, step_project, ps2, 2, y2, 10.0, 1e-6, 11, 0, &st, last) == 5);
        CHECK(run(meth[m], wsz[m], rhs_osc, NULL, &w, 2, y2, 10.0, 1e-8, 11, 5, &st, last) == 3);
        CHECK(run(meth[m], wsz[m], rhs_osc, step_nan, &w, 2, y2, 10.0, 1e-8, 11, 0, &st, last) == 4);
        double pn0[1] = {-1.0};
        CHECK(run(meth[m], wsz[m], rhs_nan, NULL, pn0, 1, y1, 1.0, 1e-8, 11, 0, &st, last) == 4);
        /* every output exactly at a step end, tiny fixed steps, no outputs at all */
        mbrt_stats st2;
        double *wk = malloc(wsz[m](1) * sizeof(double)), at[1] = {1e-3}, yo[3], to[3] = {0.0, 0.5, 1.0};
        int nw = -1;
        CHECK(meth[m](rhs_decay, NULL, NULL, 1, 0.0, y1, 1.0, 1e-6, at, 0.25, 0.25, 0, to, 3, yo, &nw,
                      wk, &st2) == 0 && nw == 3 && st2.naccept == 4);
        CHECK(meth[m](rhs_decay, NULL, NULL, 1, 0.0, y1, 1.0, 1e-6, at, 0.0, 0.0, 0, NULL, 0, NULL,
                      NULL, wk, NULL) == 0);
        double pf3[4] = {9.0, 5, 0, 50}, big[1] = {1e3}, to2[2] = {0.0, 0.9};
        /* fixed steps of 0.25: for DOP853 call 50 is a dense-output stage */
        CHECK(meth[m](rhs_fail, NULL, pf3, 1, 0.0, y1, 1.0, 0.1, big, 0.25, 0.25, 0, to2, 2, yo, &nw,
                      wk, &st2) == (m ? 1 : 0));
        CHECK(meth[m](NULL, NULL, NULL, 1, 0.0, y1, 1.0, 1e-6, at, 0.0, 0.0, 0, NULL, 0, NULL,
                      NULL, wk, &st2) == 6);
        free(wk);
        CHECK(run(meth[m], wsz[m], rhs_osc, NULL, &w, 0, y2, 10.0, 1e-8, 11, 0, &st, last) == 6);
        CHECK(run(meth[m], wsz[m], rhs_osc, NULL, &w, 2, y2, 10.0, -1.0, 11, 0, &st, last) == 6);
        printf("%s ok (last message: %s)\n", m ? "DOP853" : "DOPRI5", st.message);
    }

    /* events (mbrt_events.c) on exact-size heap buffers: the oscillator y0 = cos(2t) falling
     * through 0.5 (t = pi/6) and rising through -0.5 (t = pi/3), watched on both methods; a
     * mass thrown up from 0 returning inside one first step (fresh); bad descriptions */
    {
        typedef int (*ev_fn)(mbrt_rhs_fn, mbrt_step_fn, void *, int, double, const double *, double, double,
                             const double *, double, double, long, const double *, int, double *, int *,
                             double *, mbrt_stats *, int, mbrt_events *);
        ev_fn evm[2] = {mbrt_dopri5_events, mbrt_dop853_events};
        for (int m = 0; m < 2; ++m) {
            int idx[2] = {0, 0}, dir[2] = {-1, 1};
            double sg[2] = {1.0, -1.0}, at[2] = {0.5, -0.5}, w = 2.0, y2[2] = {1.0, 0.0}, atl[2] = {1e-12, 1e-12};
            mbrt_linear_events L = {2, idx, sg, at};
            mbrt_events E;
            memset(&E, 0, sizeof E);
            E.g = mbrt_linear_event_values; E.gctx = &L; E.n_ev = 2; E.direction = dir; E.tol = 1e-13; E.fresh = -1;
            E.work = malloc(mbrt_events_work_size(2, 2) * sizeof(double));
            E.y_event = malloc(2 * sizeof(double));
            double *wk = malloc(wsz[m](2) * sizeof(double)), to[4] = {0.1, 0.2, 0.6, 1.0}, yo[8];
            int nw = -1;
            mbrt_stats st;
            CHECK(evm[m](rhs_osc, NULL, &w, 2, 0.0, y2, 1.0, 1e-10, atl, 0.0, 0.0, 0, to, 4, yo, &nw, wk, &st, 0, &E)
                  == MBRT_EVENT && E.which == 0 && nw == 2);
            CHECK(fabs(E.t_event - acos(-1.0) / 6) < 1e-9 && fabs(E.y_event[0] - 0.5) < 1e-9 && st.t == E.t_event);
            /* on from there watching the second only (the first would be found again at its start) */
            double y3[2] = {E.y_event[0], E.y_event[1]};
            mbrt_linear_events L2 = {1, idx + 1, sg + 1, at + 1};
            mbrt_events E2 = E;
            E2.gctx = &L2; E2.n_ev = 1; E2.direction = dir + 1;
            CHECK(evm[m](rhs_osc, NULL, &w, 2, E.t_event, y3, 2.0, 1e-10, atl, 0.0, 0.0, 0, NULL, 0, NULL, &nw, wk,
                         &st, 0, &E2) == MBRT_EVENT && E2.which == 0 && fabs(E2.t_event - acos(-1.0) / 3) < 1e-9);
            /* thrown up at 1 m/s under g = 9.81 from y = 0 (rhs_osc with w = 0 and a constant pull) */
            double yt[2] = {0.0, 1.0}, g = 9.81;
            int i0[1] = {0}, d0[1] = {-1};
            double s0[1] = {1.0}, a0[1] = {0.0};
            mbrt_linear_events L1 = {1, i0, s0, a0};
            mbrt_events F = E;
            F.gctx = &L1; F.n_ev = 1; F.direction = d0; F.fresh = 0;
            CHECK(evm[m](rhs_fall, NULL, &g, 2, 0.0, yt, 1.0, 1e-9, atl, 1.0, 0.0, 0, NULL, 0, NULL, &nw, wk, &st, 0,
                         &F) == MBRT_EVENT && fabs(F.t_event - 2.0 / g) < 1e-12 && st.naccept == 1);
            F.fresh = 3;  /* beyond n_ev: refused */
            CHECK(evm[m](rhs_fall, NULL, &g, 2, 0.0, yt, 1.0, 1e-9, atl, 1.0, 0.0, 0, NULL, 0, NULL, &nw, wk, &st, 0,
                         &F) == MBRT_BAD_ARGUMENT);
            F.fresh = -1; F.tol = 0.0;
            CHECK(evm[m](rhs_fall, NULL, &g, 2, 0.0, yt, 1.0, 1e-9, atl, 1.0, 0.0, 0, NULL, 0, NULL, &nw, wk, &st, 0,
                         &F) == MBRT_BAD_ARGUMENT);
            free(wk); free(E.work); free(E.y_event);
            printf("%s events ok\n", m ? "DOP853" : "DOPRI5");
        }
    }

    /* impacts acted on between stretches (mbrt_impacts_integrate): a mass dropped from 1 m onto
     * the floor, e = 0.5: impacts at t1 = sqrt(2/g), then every 2 e^k sqrt(2 g) / g; a rebound
     * too low (rest) and bad descriptions are the caller's; exact-size heap buffers */
    {
        double par[2] = {2.0, 9.81};
        mbrt_mech P;
        memset(&P, 0, sizeof P);
        P.eval = prog_fall; P.p = par; P.nq = 1; P.nu = 1; P.n_out = 2; P.off_M = 0; P.off_f = 1;
        P.off_Phi = P.off_Phid = P.off_C = P.off_cb = P.off_B = P.off_Bb = P.off_Psi = 2;
        int idx[1] = {0}, dir[1] = {-1}, iu[1] = {0}, comp[1] = {0}, shr[1] = {0}, wh[8];
        double sg[1] = {1.0}, at[1] = {0.0}, e[1] = {0.5}, last[1] = {-INFINITY}, gap[1] = {-1.0};
        mbrt_linear_events L = {1, idx, sg, at};
        mbrt_events E;
        memset(&E, 0, sizeof E);
        E.g = mbrt_linear_event_values; E.gctx = &L; E.n_ev = 1; E.direction = dir; E.tol = 1e-13; E.fresh = -1;
        E.work = malloc(mbrt_events_work_size(2, 1) * sizeof(double));
        E.y_event = malloc(2 * sizeof(double));
        double *iw = malloc(mbrt_impacts_work_size(&P) * sizeof(double));
        double *lt = malloc(8 * sizeof(double)), *ly = malloc(8 * 4 * sizeof(double)), *ll = malloc(8 * sizeof(double));
        mbrt_impacts I = {1, iu, sg, e, comp, 1, last, gap, shr, 30, 1e-9, 0.0, &P, iw, 8, 0, lt, wh, ly, ll};
        double *wk = malloc(mbrt_dop853_work_size(2) * sizeof(double)), *ys = malloc(2 * sizeof(double));
        double to[4] = {0.25, 0.5, 1.0, 1.5}, yo[8], y0[2] = {1.0, 0.0}, atl[2] = {1e-12, 1e-12};
        int nw = -1;
        mbrt_stats st;
        /* stretches of 2 outputs, 4 after an impact (chunk 2, doubling, at most 4), h_last: none */
        mbrt_stretches R = {2, 4, 0, 1, 1e-13, 0.0, NULL, 0.0};
        int rc = mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                        yo, &nw, wk, &st, ys);
        /* Zeno at 3 t1 = 1.35 s: the log's 8 entries fill, the 9th impact is the caller's */
        double t1 = sqrt(2.0 / 9.81), v1 = sqrt(2.0 * 9.81), tk = t1;
        CHECK(rc == MBRT_EVENT && I.count == 8 && E.which == 0 && nw == 3 && shr[0] == 6 && R.t_end == 1.5);
        for (int k = 0; k < 8; ++k) {
            CHECK(fabs(lt[k] - tk) < 1e-9 && wh[k] == 0 && fabs(ly[4 * k + 3] - pow(0.5, k + 1) * v1) < 1e-8);
            CHECK(fabs(ll[k] - 0.5 * 2.0 * pow(0.25, k) * v1 * v1 * 0.75) < 1e-8);  /* (1 - e^2) of T- */
            tk += 2.0 * pow(0.5, k + 1) * v1 / 9.81;
        }
        CHECK(fabs(E.t_event - tk) < 1e-9 && st.naccept > 0);
        /* chattering: 3 shrinking intervals make it the caller's (the 5th impact) */
        I.count = 0; I.chatter = 3; last[0] = -INFINITY; gap[0] = -1.0; shr[0] = 0; E.fresh = -1; R.count = 0;
        rc = mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                    yo, &nw, wk, &st, ys);
        CHECK(rc == MBRT_EVENT && I.count == 4 && shr[0] == 2);
        I.chatter = 30;
        /* the resting height beyond the first rebound's: handed back at the first impact */
        I.count = 0; I.rest = 10.0; last[0] = -INFINITY; gap[0] = -1.0; shr[0] = 0; E.fresh = -1; R.count = 2;
        rc = mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                    yo, &nw, wk, &st, ys);
        CHECK(rc == MBRT_EVENT && I.count == 0 && E.which == 0 && fabs(E.t_event - t1) < 1e-9 && nw == 1 && R.count == 3);
        /* no impacts acted on (iu = -1), stretches of 1 output going on with the last step: all four in one call */
        double hl = 0.05;
        int iu_off[1] = {-1};
        mbrt_stretches R1 = {1, 1, 0, 10, 1e-13, 0.0, &hl, 0.0};
        double yu[2] = {0.0, 10.0};
        I.iu = iu_off; E.fresh = -1;
        rc = mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R1, 2, 0.0, yu, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                    yo, &nw, wk, &st, ys);
        CHECK(rc == MBRT_OK && nw == 4 && R1.count == 4 && R1.t_end == 1.5 && fabs(yo[7] - (10.0 - 9.81 * 1.5)) < 1e-9);
        I.iu = iu;
        e[0] = 1.5;  /* restitution outside [0, 1] */
        CHECK(mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                     yo, &nw, wk, &st, ys) == MBRT_BAD_ARGUMENT);
        e[0] = 0.5; P.nrows = 1;  /* rows: not a system the loop acts on */
        CHECK(mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                     yo, &nw, wk, &st, ys) == MBRT_BAD_ARGUMENT);
        P.nrows = 0;
        CHECK(mbrt_impacts_integrate(NULL, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                     yo, &nw, wk, &st, ys) == MBRT_BAD_ARGUMENT);
        R.chunk_max = 1;  /* below chunk */
        CHECK(mbrt_impacts_integrate(stretch_fall, 8, &E, &E, &I, &R, 2, 0.0, y0, to, 4, 1e-10, atl, 0.0, 0.0, 0,
                                     yo, &nw, wk, &st, ys) == MBRT_BAD_ARGUMENT);
        CHECK(mbrt_impacts_work_size(NULL) == 0 && mbrt_impacts_work_size(&P) == 5);
        free(E.work); free(E.y_event); free(iw); free(lt); free(ly); free(ll); free(wk); free(ys);
        printf("impacts ok\n");
    }

    /* the mechanics kernels on the Cartesian pendulum, exact-size heap scratch */
    {
        double par[3] = {2.0, 9.81, 1.5}, th = 0.4, wd = 1.3, L = 1.5;
        int rows[1] = {0}, dep[1] = {1}, ind[1] = {0};
        for (int qr = 0; qr < 2; ++qr) {
            mbrt_mech P;
            mech_pendulum(&P, par, rows, qr);
            size_t nw = mbrt_mech_work_size(&P);
            double *wk = malloc(nw * sizeof(double));
            int *iw = malloc(4 * sizeof(int));
            double y[3] = {L * sin(th), -L * cos(th), L * cos(th) * wd}, dy[3], g = -1, c = -1;
            CHECK(mbrt_dalembert_rhs(&P, 0.0, y, dep, ind, 1, dy, &g, &c, wk, iw) == MBRT_MECH_OK);
            double thdd = -9.81 / L * sin(th);
            CHECK(fabs(dy[2] - (L * cos(th) * thdd - L * sin(th) * wd * wd)) < 1e-12);
            CHECK(fabs(dy[1] - L * sin(th) * wd) < 1e-12 && fabs(g - tan(th)) < 1e-12 && c == 1.0);
            double yb[3] = {6.0, -1.0, 0.0};
            CHECK(mbrt_dalembert_rhs(&P, 0.0, yb, dep, ind, 1, dy, &g, &c, wk, iw) == MBRT_MECH_FALLBACK);
            double yz[3] = {1.0, 0.0, 0.0};  /* y = 0: the dependent block A_d = [y] is zero */
            CHECK(mbrt_dalembert_rhs(&P, 0.0, yz, dep, ind, 1, dy, &g, &c, wk, iw) == MBRT_MECH_SINGULAR);
            CHECK(mbrt_dalembert_rhs(&P, 0.0, y, dep, ind, 0, dy, &g, &c, wk, iw) == MBRT_MECH_BAD_ARGUMENT);
            int bad[1] = {0};
            CHECK(mbrt_dalembert_rhs(&P, 0.0, y, bad, ind, 1, dy, &g, &c, wk, iw) == MBRT_MECH_BAD_ARGUMENT);
            double zero[3] = {0.0, 9.81, 1.5};
            P.p = zero;
            CHECK(mbrt_dalembert_rhs(&P, 0.0, y, dep, ind, 1, dy, &g, &c, wk, iw) == MBRT_MECH_MASS_SINGULAR);
            P.p = par;
            double yp[4] = {1.01 * L * sin(th), -0.98 * L * cos(th), 0.3, 0.2}, nrm = -1;
            CHECK(mbrt_project(&P, 0.0, yp, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_OK);
            CHECK(fabs(hypot(yp[0], yp[1]) - L) < 1e-12 && fabs(yp[0] * yp[2] + yp[1] * yp[3]) < 1e-12);
            double y0[4] = {0.0, 0.0, 0.3, 0.2};
            CHECK(mbrt_project(&P, 0.0, y0, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_SINGULAR);
            double yf[4] = {2.0 * L, 0.0, 0.0, 0.0};
            CHECK(mbrt_project(&P, 0.0, yf, 1e-12, 0, 1e-9, &nrm, wk) == MBRT_MECH_NO_CONVERGENCE);
            CHECK(mbrt_project(&P, 0.0, yf, 1e-12, -1, 1e-9, &nrm, wk) == MBRT_MECH_BAD_ARGUMENT);
            {   /* the free directions only (fixed start values kept): x and vx fixed, y and vy move */
                unsigned char pfree[2] = {0, 1}, vfree[2] = {0, 1}, none[2] = {0, 0};
                double ys[4] = {0.5 * L, -0.9 * L, 0.3, 0.2};
                CHECK(mbrt_project_free(&P, 0.0, ys, pfree, vfree, 1e-12, 20, 1e-9, &nrm, wk) == MBRT_MECH_OK);
                CHECK(ys[0] == 0.5 * L && ys[2] == 0.3 && fabs(ys[1] + sqrt(0.75) * L) < 1e-12);
                CHECK(fabs(ys[0] * ys[2] + ys[1] * ys[3]) < 1e-12);
                double ya[4] = {0.5 * L, -0.9 * L, 0.3, 0.2}, yb[4] = {0.5 * L, -0.9 * L, 0.3, 0.2};
                CHECK(mbrt_project_free(&P, 0.0, ya, NULL, NULL, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_OK);
                CHECK(mbrt_project(&P, 0.0, yb, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_OK);
                CHECK(memcmp(ya, yb, sizeof ya) == 0);  /* NULL: every direction, mbrt_project's numbers */
                double yn[4] = {0.5 * L, -0.9 * L, 0.3, 0.2};  /* nothing free: the rows have no solution */
                CHECK(mbrt_project_free(&P, 0.0, yn, none, none, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_SINGULAR);
                double yo[4] = {2.0 * L, -0.1 * L, 0.0, 0.0};  /* x fixed beyond the circle: no closure */
                CHECK(mbrt_project_free(&P, 0.0, yo, pfree, vfree, 1e-12, 20, 1e-9, &nrm, wk) != MBRT_MECH_OK);
                CHECK(yo[0] == 2.0 * L && yo[1] == -0.1 * L);  /* y written only on success */
            }
            free(wk);
            free(iw);
        }
        {   /* the quaternion segment: a tilted ball joint brought back to a horizontal x axis */
            mbrt_mech B;
            int seg[4] = {MBRT_SEG_QUAT, 0, 0, 1}, bad[4] = {MBRT_SEG_QUAT, 1, 0, 1};
            mech_ball(&B, rows, seg);
            double *wk = malloc(mbrt_mech_work_size(&B) * sizeof(double)), nrm = -1;
            double yq[7] = {0.9, 0.1, 0.3, 0.2, 0.4, -0.3, 0.8};
            CHECK(mbrt_project(&B, 0.0, yq, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_OK);
            double nq = sqrt(yq[0] * yq[0] + yq[1] * yq[1] + yq[2] * yq[2] + yq[3] * yq[3]);
            double R21 = 2.0 * (yq[2] * yq[3] + yq[0] * yq[1]), R22 = 1.0 - 2.0 * (yq[1] * yq[1] + yq[2] * yq[2]);
            CHECK(fabs(nq - 1.0) < 1e-15 && nrm <= 1e-12 && fabs(2.0 * (yq[1] * yq[3] - yq[0] * yq[2])) < 1e-12);
            CHECK(fabs(-R22 * yq[5] + R21 * yq[6]) < 1e-12);
            B.seg = bad;  /* a segment reaching past q */
            CHECK(mbrt_project(&B, 0.0, yq, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_BAD_ARGUMENT);
            B.nseg = 0;   /* no map with nq != nu */
            CHECK(mbrt_project(&B, 0.0, yq, 1e-12, 8, 1e-9, &nrm, wk) == MBRT_MECH_BAD_ARGUMENT);
            free(wk);
        }
        {   /* the DAE forms' residual and Jacobian at the pendulum's consistent state */
            mbrt_mech P;
            mech_pendulum(&P, par, rows, 1);
            double x = L * sin(th), y = -L * cos(th), vx = L * cos(th) * wd, vy = L * sin(th) * wd;
            double thdd = -9.81 / L * sin(th);
            double ax = L * cos(th) * thdd - L * sin(th) * wd * wd, ay = L * sin(th) * thdd + L * cos(th) * wd * wd;
            double lam = -par[0] * ax / x;
            double ys[8] = {x, y, vx, vy, ax, ay, lam, 0.0};
            double g2[2] = {10.0, 10.0};
            for (int form = 1; form <= 3; ++form) {
                int n = mbrt_dae_size(&P, form), nf = -1;
                CHECK(n == (form == 2 ? 8 : 7));
                double *wk = malloc(mbrt_dae_work_size(&P, form) * sizeof(double));
                double *F = malloc((size_t)n * sizeof(double)), *J = malloc((size_t)n * n * sizeof(double));
                CHECK(mbrt_dae_fun(&P, form, 0.0, ys, form == 1 ? g2 : NULL, F, J, &nf, wk) == MBRT_MECH_OK);
                CHECK(nf == 1 + 4 + (form == 2));
                CHECK(fabs(F[0] - vx) < 1e-12 && fabs(F[3] - ay) < 1e-12);
                for (int i = 4; i < n; ++i)
                    CHECK(fabs(F[i]) < 1e-11);
                CHECK(J[4 * n + 4] == -par[0] && J[4 * n + 6] == -x && J[2 * n + 4] == 1.0);
                CHECK(mbrt_dae_fun(&P, 9, 0.0, ys, NULL, F, J, &nf, wk) == MBRT_MECH_BAD_ARGUMENT);
                double yb[8] = {6.0, -1.0, 0, 0, 0, 0, 0, 0};
                CHECK(mbrt_dae_fun(&P, form, 0.0, yb, NULL, F, NULL, &nf, wk) == MBRT_MECH_FALLBACK);
                free(wk); free(F); free(J);
            }
        }
        double R[9] = {1, 2, 3, 4, 5, 6, 7, 8, 10}, S[9], Z[4] = {1, 2, 2, 4}, S2[4];
        CHECK(fabs(mbrt_cond2(3, R, S) / 88.44 - 1.0) < 1e-3);  /* numpy: 88.4482799 */
        CHECK(isinf(mbrt_cond2(2, Z, S2)));
    }
    radau5_selftest();
    printf("%d failures\n", failures);
    return failures != 0;
}
#endif
"""


def _build(outdir, extra=(), exe=False):
    return build(outdir, TEST_C, "mbrt_selftest", "MBRT_SELFTEST_MAIN", extra, exe, ())


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    out, res = _build(tmp_path_factory.mktemp("mbrt"))
    assert res.returncode == 0, res.stderr
    assert "warning" not in res.stderr, res.stderr  # the runtime compiles cleanly with -Wall -Wextra -pedantic
    L = ctypes.CDLL(str(out))
    vp, i, d, lng = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_long
    L.mbrt_lu_factor.argtypes = [i, vp, vp]
    L.mbrt_lu_solve.argtypes = [i, vp, vp, vp]
    L.mbrt_chol_factor.argtypes = [i, vp]
    L.mbrt_chol_solve.argtypes = [i, vp, vp]
    L.mbrt_lu_solve.restype = L.mbrt_chol_solve.restype = None
    for m in ("dopri5", "dop853"):
        fn = getattr(L, f"mbrt_{m}")
        fn.argtypes = [vp, vp, vp, i, d, vp, d, d, vp, d, d, lng, vp, i, vp, vp, vp, ctypes.POINTER(Stats)]
        fn.restype = i
        getattr(L, f"mbrt_{m}_work_size").argtypes = [i]
        getattr(L, f"mbrt_{m}_work_size").restype = ctypes.c_size_t
    return L


def _ptr(a):
    return None if a is None else a.ctypes.data


def integrate(lib, method, rhs, y0, t_end, t_out, rtol=1e-6, atol=None, ctx=None, on_step=None,
              t0=0.0, h0=0.0, hmax=0.0, max_steps=0, n=None):
    """Call ``mbrt_<method>``; returns (status, y_out[:n_written], stats)."""
    y0 = np.ascontiguousarray(y0, dtype=float)
    n = len(y0) if n is None else n
    atol = np.full(max(len(y0), 1), rtol) if atol is None else np.ascontiguousarray(atol, dtype=float)
    t_out = np.ascontiguousarray(t_out, dtype=float)
    y_out = np.full((max(len(t_out), 1), max(len(y0), 1)), np.nan)
    work = np.zeros(max(getattr(lib, f"mbrt_{method}_work_size")(max(n, 1)), 1))
    nw, st = ctypes.c_int(-1), Stats()
    f = ctypes.cast(getattr(lib, rhs), ctypes.c_void_p)
    cb = ctypes.cast(getattr(lib, on_step), ctypes.c_void_p) if on_step else None
    status = getattr(lib, f"mbrt_{method}")(
        f, cb, _ptr(ctx), n, t0, _ptr(y0), t_end, rtol, _ptr(atol), h0, hmax, max_steps,
        _ptr(t_out), len(t_out), _ptr(y_out), ctypes.addressof(nw), work.ctypes.data, ctypes.byref(st))
    assert status == st.status
    return status, y_out[: nw.value], st


METHODS = ["dopri5", "dop853"]
ORDER = {"dopri5": 5, "dop853": 8}


# --------------------------------------------------------------------------- linear algebra
@pytest.mark.parametrize("n", [1, 2, 5, 17, 40])
def test_lu_solve_matches_numpy(lib, n):
    rng = np.random.default_rng(n)
    A = rng.standard_normal((n, n)) + n * np.eye(n) * 0.5
    b = rng.standard_normal(n)
    LU, piv, x = A.copy(), np.zeros(n, dtype=np.intc), b.copy()
    assert lib.mbrt_lu_factor(n, _ptr(LU), _ptr(piv)) == 0
    lib.mbrt_lu_solve(n, _ptr(LU), _ptr(piv), _ptr(x))
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-10, atol=1e-12)


def test_lu_pivots_on_zero_leading_entry(lib):
    A = np.array([[0.0, 1.0], [1.0, 0.0]])
    LU, piv, x = A.copy(), np.zeros(2, dtype=np.intc), np.array([3.0, 5.0])
    assert lib.mbrt_lu_factor(2, _ptr(LU), _ptr(piv)) == 0
    lib.mbrt_lu_solve(2, _ptr(LU), _ptr(piv), _ptr(x))
    np.testing.assert_allclose(x, [5.0, 3.0])


@pytest.mark.parametrize("A, code", [
    (np.array([[1.0, 2.0], [2.0, 4.0]]), 2),
    (np.zeros((3, 3)), 1),
    (np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, np.nan]]), 3),
    (np.array([[2.0, 1, 1], [4.0, 2, 2], [1.0, 5, 3]]), 3),
])
def test_lu_singular_codes(lib, A, code):
    n = A.shape[0]
    assert lib.mbrt_lu_factor(n, _ptr(A.copy()), _ptr(np.zeros(n, dtype=np.intc))) == code


@pytest.mark.parametrize("n", [1, 3, 10, 33])
def test_cholesky_matches_numpy(lib, n):
    rng = np.random.default_rng(100 + n)
    M = rng.standard_normal((n, n))
    A = M @ M.T + n * np.eye(n)
    b = rng.standard_normal(n)
    L = A.copy()
    L[np.triu_indices(n, 1)] = 7.0  # the upper triangle must not be read
    assert lib.mbrt_chol_factor(n, _ptr(L)) == 0
    np.testing.assert_allclose(L, np.linalg.cholesky(A), rtol=1e-12, atol=1e-12)
    x = b.copy()
    lib.mbrt_chol_solve(n, _ptr(L), _ptr(x))
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("A, code", [
    (np.array([[1.0, 2.0], [2.0, 4.0]]), 2),          # singular, pivot exactly 0
    (np.array([[-1.0, 0.0], [0.0, 1.0]]), 1),         # negative
    (np.array([[4.0, 2, 0], [2, 2, 3], [0, 3, 1.0]]), 3),  # indefinite
    (np.array([[1.0, 0.0], [0.0, np.nan]]), 2),
])
def test_cholesky_not_positive_codes(lib, A, code):
    assert lib.mbrt_chol_factor(A.shape[0], _ptr(A.copy())) == code


# --------------------------------------------------------------------------- integrators: accuracy
@pytest.mark.parametrize("method", METHODS)
def test_exponential_decay(lib, method):
    t = np.linspace(0.0, 5.0, 51)
    for rtol in (1e-6, 1e-10):
        status, Y, st = integrate(lib, method, "rhs_decay", [1.0], 5.0, t, rtol=rtol, atol=[rtol])
        assert status == 0 and st.t == 5.0 and len(Y) == len(t)
        assert Y[0, 0] == 1.0  # t_out[0] == t0 is y0 itself
        err = np.abs(Y[:, 0] - np.exp(-t)).max()
        assert err < 5 * rtol, (rtol, err)
        assert st.nstep == st.naccept + st.nreject
        assert b"reached t_end" in st.message


@pytest.mark.parametrize("method", METHODS)
def test_oscillator_dense_output_within_tolerance(lib, method):
    """y'' = -4 y on [0, 10] sampled on 1001 points (many per step): the dense
    output error stays a small multiple of the tolerance, and the global error
    follows the tolerance (Hairer's control is tolerance proportional)."""
    w = np.array([2.0])
    t = np.linspace(0.0, 10.0, 1001)
    errs = []
    for rtol in (1e-5, 1e-7, 1e-9):
        status, Y, st = integrate(lib, method, "rhs_osc", [1.0, 0.0], 10.0, t, rtol=rtol, ctx=w)
        assert status == 0 and len(Y) == len(t)
        exact = np.column_stack([np.cos(2 * t), -2 * np.sin(2 * t)])
        err = np.abs(Y - exact).max()
        assert err < 20 * rtol, (rtol, err)  # measured: ~5x (DOPRI5), ~3.5x (DOP853)
        assert st.naccept < len(t) / 2  # so most samples really come from the interpolant
        errs.append(err)
    slope = np.polyfit(np.log10([1e-5, 1e-7, 1e-9]), np.log10(errs), 1)[0]
    assert 0.85 < slope < 1.15, slope


@pytest.mark.parametrize("method", METHODS)
def test_convergence_order_fixed_steps(lib, method):
    """With h0 = hmax = T/N and a loose tolerance every step is accepted with the
    same h, so halving h must divide both the step-end and the dense-output
    (interior sample) errors by 2^p, p = 5 (DOPRI5) or 8 (DOP853)."""
    w = np.array([2.0])
    t = np.linspace(0.0, 10.0, 1001)
    exact = np.cos(2 * t)
    errs, errs_end = [], []
    for N in (20, 40, 80):
        h = 10.0 / N
        status, Y, st = integrate(lib, method, "rhs_osc", [1.0, 0.0], 10.0, t, rtol=1e-1,
                                  atol=[1e3, 1e3], ctx=w, h0=h, hmax=h)
        assert status == 0 and st.naccept == N and st.nreject == 0
        errs.append(np.abs(Y[:, 0] - exact).max())
        errs_end.append(np.abs(Y[::50, 0] - exact[::50]).max())  # t = 0, 0.5, ...: step ends
    p = ORDER[method]
    for e in (errs, errs_end):
        rates = np.log2(np.array(e[:-1]) / np.array(e[1:]))
        assert np.all(np.abs(rates - p) < 0.4), rates  # measured 5.10-5.20 / 7.93-8.08


def _vdp(t, y):
    return [y[1], (1 - y[0] ** 2) * y[1] - y[0]]


_MU = 0.012277471


def _arenstorf(t, y):
    mp = 1 - _MU
    d1 = ((y[0] + _MU) ** 2 + y[1] ** 2) ** 1.5
    d2 = ((y[0] - mp) ** 2 + y[1] ** 2) ** 1.5
    return [y[2], y[3], y[0] + 2 * y[3] - mp * (y[0] + _MU) / d1 - _MU * (y[0] - mp) / d2,
            y[1] - 2 * y[2] - mp * y[1] / d1 - _MU * y[1] / d2]


PROBLEMS = {
    "vdp": ("rhs_vdp", _vdp, [2.0, 0.0], 20.0, np.array([1.0])),
    "arenstorf": ("rhs_arenstorf", _arenstorf, [0.994, 0.0, 0.0, -2.00158510637908252240537862224],
                  17.0652165601579625588917206249, None),
}


@pytest.mark.parametrize("problem", sorted(PROBLEMS))
@pytest.mark.parametrize("method, scipy_method", [("dopri5", "RK45"), ("dop853", "DOP853")])
@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_against_scipy(lib, problem, method, scipy_method, rtol):
    """Accuracy against a tight scipy DOP853 reference and accepted-step counts
    within 20% of scipy's own RK45/DOP853 at the same tolerances."""
    rhs, pyrhs, y0, t1, ctx = PROBLEMS[problem]
    t = np.linspace(0.0, t1, 201)
    ref = solve_ivp(pyrhs, (0, t1), y0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=t)
    ours_status, Y, st = integrate(lib, method, rhs, y0, t1, t, rtol=rtol, ctx=ctx)
    assert ours_status == 0, st.message
    theirs = solve_ivp(pyrhs, (0, t1), y0, method=scipy_method, rtol=rtol, atol=rtol, t_eval=t)
    err, err_scipy = np.abs(Y - ref.y.T).max(), np.abs(theirs.y.T - ref.y.T).max()
    # the Arenstorf orbit amplifies errors ~1e4-fold; compare with scipy's result
    assert err < max(3 * err_scipy, 100 * rtol), (err, err_scipy)
    steps_scipy = len(solve_ivp(pyrhs, (0, t1), y0, method=scipy_method, rtol=rtol, atol=rtol).t) - 1
    assert abs(st.naccept / steps_scipy - 1) < 0.2, (st.naccept, steps_scipy)


@pytest.mark.parametrize("method", METHODS)
def test_nfev_counts_every_rhs_call(lib, method):
    p = np.array([1e9, 3.0, 0.0, 0.0])  # rhs_fail never fails, counts calls in p[2]
    t = np.linspace(0, 3, 7)
    status, Y, st = integrate(lib, method, "rhs_fail", [1.0], 3.0, t, rtol=1e-8, ctx=p)
    assert status == 0 and st.nfev == p[2]
    per_step = {"dopri5": 6, "dop853": 12}[method]
    assert st.nfev >= 2 + per_step * st.naccept


@pytest.mark.parametrize("method", METHODS)
def test_user_initial_step_and_hmax(lib, method):
    t = np.linspace(0, 2, 5)
    status, Y, st = integrate(lib, method, "rhs_decay", [1.0], 2.0, t, rtol=1e-8, h0=1e-3, hmax=0.05)
    assert status == 0 and st.naccept >= 40
    np.testing.assert_allclose(Y[:, 0], np.exp(-t), rtol=1e-7)


@pytest.mark.parametrize("method", METHODS)
def test_zero_length_interval(lib, method):
    status, Y, st = integrate(lib, method, "rhs_decay", [3.0], 1.5, [1.5], t0=1.5)
    assert status == 0 and Y.tolist() == [[3.0]] and st.nfev == 0


# --------------------------------------------------------------------------- integrators: failures
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("code", [1, 7, -3])
def test_rhs_failure_stops_and_keeps_outputs(lib, method, code):
    p = np.array([0.5, float(code), 0.0, 0.0])
    t = np.linspace(0, 1, 11)
    status, Y, st = integrate(lib, method, "rhs_fail", [1.0], 1.0, t, rtol=1e-8, ctx=p)
    assert status == 1
    assert f"returned {code} at t=".encode() in st.message
    assert 0.5 < float(st.message.split(b"t=")[1].split(b" ")[0]) <= 1.0  # the failing call
    assert st.t <= 0.5  # last accepted state: all its stages were at t <= 0.5
    assert 1 <= len(Y) <= 6 and t[len(Y) - 1] <= st.t < t[len(Y)]  # every sample up to st.t
    np.testing.assert_allclose(Y[:, 0], np.exp(-t[: len(Y)]), rtol=1e-7)


def test_rhs_failure_in_dop853_dense_output_stage(lib):
    """Fixed steps of 0.25: 1 call at t0 + 12 per accepted step, so calls 50-52 are
    the extra dense-output stages of the 4th step (the only one with a sample)."""
    p = np.array([9.0, 5.0, 0.0, 50.0])
    status, Y, st = integrate(lib, "dop853", "rhs_fail", [1.0], 1.0, [0.0, 0.9], rtol=1e-1,
                              atol=[1e3], ctx=p, h0=0.25, hmax=0.25)
    assert status == 1 and b"dense output of the step from t=0.75" in st.message
    assert st.t == 0.75 and len(Y) == 1 and st.nfev == 50 == p[2]


@pytest.mark.parametrize("method", METHODS)
def test_rhs_failure_at_start(lib, method):
    p = np.array([-1.0, 4.0, 0.0, 0.0])
    status, Y, st = integrate(lib, method, "rhs_fail", [1.0], 1.0, [0.0, 1.0], ctx=p)
    assert status == 1 and b"returned 4" in st.message and len(Y) == 1 and st.nfev == 1


@pytest.mark.parametrize("method", METHODS)
def test_nan_rhs_ends_with_step_too_small(lib, method):
    p = np.array([0.5])
    t = np.linspace(0, 1, 11)
    status, Y, st = integrate(lib, method, "rhs_nan", [1.0], 1.0, t, rtol=1e-8, ctx=p)
    assert status == 2, st.message
    assert b"too small" in st.message and b"non-finite" in st.message
    assert abs(st.t - 0.5) < 1e-10 and len(Y) in (5, 6)  # stuck just before t = 0.5
    np.testing.assert_allclose(Y[:, 0], np.exp(-t[: len(Y)]), rtol=1e-7)


@pytest.mark.parametrize("method", METHODS)
def test_max_steps(lib, method):
    w = np.array([2.0])
    t = np.linspace(0, 10, 101)
    status, Y, st = integrate(lib, method, "rhs_osc", [1.0, 0.0], 10.0, t, rtol=1e-10, ctx=w,
                              max_steps=7)
    assert status == 3 and st.nstep == 7 and b"max_steps=7" in st.message
    assert 0 < len(Y) < len(t) and st.t < 10.0
    np.testing.assert_allclose(Y[:, 0], np.cos(2 * t[: len(Y)]), atol=1e-8)


@pytest.mark.parametrize("method", METHODS)
def test_projection_callback_keeps_unit_circle(lib, method):
    """y' = R y + 0.1 y spirals outwards (|y| = e^{0.1 t}); projecting after each
    step keeps |y| = 1 up to one step's growth (outputs are interpolated before
    the projection), without it |y(10)| = e."""
    t = np.linspace(0, 10, 201)
    ctx = np.array([0.0, 1.0, 0.0, 0.0, 0.0, 0.1])  # calls, project, stop t, stop code, max dev, g
    status, Y, st = integrate(lib, method, "rhs_spiral", [1.0, 0.0], 10.0, t, rtol=1e-8, ctx=ctx,
                              on_step="step_project", hmax=0.05)
    assert status == 0 and ctx[0] == st.naccept  # called once per accepted step
    r = np.hypot(Y[:, 0], Y[:, 1])
    assert np.abs(r - 1).max() < np.expm1(0.1 * 0.05) * 1.01  # growth within one step only
    assert ctx[4] < np.expm1(0.1 * 0.05) * 1.01  # deviation seen by the callback before projecting
    # the rhs was re-evaluated after each projection (6/12 calls per step + 1 per projection)
    per_step = {"dopri5": 6, "dop853": 12}[method]
    assert st.nfev >= per_step * st.naccept + (st.naccept - 1)

    ctx = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.1])  # same, without projecting
    status, Y, st = integrate(lib, method, "rhs_spiral", [1.0, 0.0], 10.0, t, rtol=1e-8, ctx=ctx,
                              on_step="step_project", hmax=0.05)
    assert status == 0 and abs(np.hypot(*Y[-1]) - np.e) < 1e-6


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("code", [1, 9, -2])
def test_step_callback_stops(lib, method, code):
    t = np.linspace(0, 10, 101)
    ctx = np.array([0.0, 1.0, 3.0, float(code), 0.0, 0.1])
    status, Y, st = integrate(lib, method, "rhs_spiral", [1.0, 0.0], 10.0, t, rtol=1e-8, ctx=ctx,
                              on_step="step_project")
    assert status == 5 and f"callback returned {code}".encode() in st.message
    assert st.t >= 3.0 and ctx[0] == st.naccept
    assert t[len(Y) - 1] <= st.t < t[min(len(Y), len(t) - 1)]  # every sample up to st.t written


@pytest.mark.parametrize("method", METHODS)
def test_nonfinite_state_or_derivative(lib, method):
    w = np.array([2.0])
    status, Y, st = integrate(lib, method, "rhs_osc", [1.0, 0.0], 10.0, [0.0, 5.0], ctx=w,
                              on_step="step_nan")
    assert status == 4 and b"callback made the state non-finite" in st.message and st.naccept == 1
    status, Y, st = integrate(lib, method, "rhs_nan", [1.0], 1.0, [0.0, 1.0], ctx=np.array([-1.0]))
    assert status == 4 and b"non-finite value at t=0" in st.message and len(Y) == 1


BAD = {
    "n=0": dict(n=0),
    "rtol=0": dict(rtol=0.0),
    "rtol tiny": dict(rtol=1e-17),
    "rtol nan": dict(rtol=np.nan),
    "atol<0": dict(atol=[-1.0]),
    "atol nan": dict(atol=[np.nan]),
    "y0 nan": dict(y0=[np.nan]),
    "y0 inf": dict(y0=[np.inf]),
    "t_end<t0": dict(t_end=-1.0),
    "t_end nan": dict(t_end=np.nan),
    "t0 inf": dict(t0=-np.inf),
    "h0<0": dict(h0=-0.1),
    "hmax nan": dict(hmax=np.nan),
    "max_steps<0": dict(max_steps=-1),
    "t_out decreasing": dict(t_out=[0.5, 0.2]),
    "t_out repeated": dict(t_out=[0.5, 0.5]),
    "t_out before t0": dict(t_out=[-0.1, 0.5]),
    "t_out after t_end": dict(t_out=[0.5, 1.5]),
    "t_out nan": dict(t_out=[np.nan]),
}


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_arguments(lib, method, case):
    kw = dict(y0=[1.0], t_end=1.0, t_out=[0.0, 1.0], rtol=1e-6)
    kw.update(BAD[case])
    y0, t_end, t_out = kw.pop("y0"), kw.pop("t_end"), kw.pop("t_out")
    status, Y, st = integrate(lib, method, "rhs_decay", y0, t_end, t_out, **kw)
    assert status == 6 and len(Y) == 0 and st.nfev == 0
    assert len(st.message) > 20 and st.message.endswith(b".")


@pytest.mark.parametrize("method", METHODS)
def test_null_pointers_are_bad_arguments(lib, method):
    fn = getattr(lib, f"mbrt_{method}")
    st, y0, atol = Stats(), np.ones(1), np.ones(1)
    work = np.zeros(getattr(lib, f"mbrt_{method}_work_size")(1))
    f = ctypes.cast(lib.rhs_decay, ctypes.c_void_p)
    assert fn(None, None, None, 1, 0.0, y0.ctypes.data, 1.0, 1e-6, atol.ctypes.data, 0.0, 0.0, 0,
              None, 0, None, None, work.ctypes.data, ctypes.byref(st)) == 6
    assert fn(f, None, None, 1, 0.0, y0.ctypes.data, 1.0, 1e-6, atol.ctypes.data, 0.0, 0.0, 0,
              None, 0, None, None, None, ctypes.byref(st)) == 6
    assert fn(f, None, None, 1, 0.0, y0.ctypes.data, 1.0, 1e-6, atol.ctypes.data, 0.0, 0.0, 0,
              None, 3, None, None, work.ctypes.data, ctypes.byref(st)) == 6
    # no outputs, no n_written, no stats: still integrates
    assert fn(f, None, None, 1, 0.0, y0.ctypes.data, 1.0, 1e-6, atol.ctypes.data, 0.0, 0.0, 0,
              None, 0, None, None, work.ctypes.data, None) == 0
    assert getattr(lib, f"mbrt_{method}_work_size")(0) == 0


def test_work_sizes(lib):
    assert lib.mbrt_dopri5_work_size(3) == 16 * 3 and lib.mbrt_dop853_work_size(3) == 28 * 3


# --------------------------------------------------------------------------- mechanics kernels
def _pendulum(lib, par, qrate=True):
    """The C test program ``prog_pendulum`` (a point mass on a rod, Cartesian coordinates) as
    an ``mbrt_mech`` (the engine's ctypes layout, so the layout itself is checked too)."""
    from mbcomp.codegen.engine import _Mech

    P, rows = _Mech(), np.zeros(1, dtype=np.intc)
    lib.mech_pendulum.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int]
    lib.mech_pendulum(ctypes.addressof(P), par.ctypes.data, rows.ctypes.data, int(qrate))
    lib.mbrt_mech_work_size.argtypes = [ctypes.c_void_p]
    lib.mbrt_mech_work_size.restype = ctypes.c_size_t
    work = np.zeros(lib.mbrt_mech_work_size(ctypes.addressof(P)))
    return P, (rows, work, par)  # P points into rows and par: keep them alive


def _dalembert(lib, P, keep, t, y, dep, ind):
    dep, ind = np.asarray(dep, np.intc), np.asarray(ind, np.intc)
    dy, fig, iw = np.zeros(3), np.zeros(2), np.zeros(8, np.intc)
    lib.mbrt_dalembert_rhs.argtypes = [ctypes.c_void_p, ctypes.c_double] + [ctypes.c_void_p] * 3 + [ctypes.c_int] + \
        [ctypes.c_void_p] * 5
    rc = lib.mbrt_dalembert_rhs(ctypes.addressof(P), t, np.asarray(y, float).ctypes.data, dep.ctypes.data,
                                ind.ctypes.data, len(dep), dy.ctypes.data, fig.ctypes.data, fig[1:].ctypes.data,
                                keep[1].ctypes.data, iw.ctypes.data)
    return rc, dy, fig


@pytest.mark.parametrize("qrate", [True, False])
@pytest.mark.parametrize("th, wd", [(0.4, 1.3), (-1.1, -0.2), (2.5, 3.0)])
def test_dalembert_rhs_is_the_pendulum_equation(lib, th, wd, qrate):
    """A 1.5 m pendulum written in Cartesian coordinates with one loop row: D'Alembert's
    reduction onto either speed gives theta'' = -g/L sin(theta) back, whichever speed is
    independent; the growth figure is |A_d^-1 A_i| = |x/y| or |y/x|."""
    m, g, L = 2.0, 9.81, 1.5
    P, keep = _pendulum(lib, np.array([m, g, L]), qrate)
    x, y = L * np.sin(th), -L * np.cos(th)
    vx, vy = L * np.cos(th) * wd, L * np.sin(th) * wd
    thdd = -g / L * np.sin(th)
    ax = L * np.cos(th) * thdd - L * np.sin(th) * wd ** 2
    ay = L * np.sin(th) * thdd + L * np.cos(th) * wd ** 2
    for dep, ind, v, a, growth in (([1], [0], vx, ax, abs(x / y)), ([0], [1], vy, ay, abs(y / x))):
        rc, dy, fig = _dalembert(lib, P, keep, 0.0, [x, y, v], dep, ind)
        assert rc == 0
        np.testing.assert_allclose(dy, [vx, vy, a], rtol=1e-12, atol=1e-12)
        assert fig[0] == pytest.approx(growth, rel=1e-12) and fig[1] == 1.0


def test_project_equals_the_python_closure(lib):
    """``mbrt_project`` against :func:`close_positions` + :func:`solve_speeds` (the Python
    projection's own functions) on the Cartesian pendulum from perturbed states: the same
    point to rounding, on the circle, with no radial speed."""
    from mbcomp.assembly.manifold import close_positions, solve_speeds

    L = 1.5
    P, keep = _pendulum(lib, np.array([2.0, 9.81, L]))
    lib.mbrt_project.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_double, ctypes.c_int,
                                 ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p]
    rng = np.random.default_rng(3)
    for _ in range(20):
        th = rng.uniform(-3, 3)
        y = np.array([L * np.sin(th), -L * np.cos(th), *rng.normal(size=2)]) + np.r_[rng.normal(scale=1e-3, size=2), 0, 0]
        yc, norm = y.copy(), ctypes.c_double()
        assert lib.mbrt_project(ctypes.addressof(P), 0.0, yc.ctypes.data, 1e-12, 8, 1e-9, ctypes.addressof(norm),
                                keep[1].ctypes.data) == 0
        q, u = y[:2], y[2:]
        c = close_positions(lambda qq: (np.array([0.5 * (qq @ qq - L * L)]), qq[None, :], None), lambda a, b: a + b, q)
        ref = np.concatenate((c.q, solve_speeds(c.q[None, :], np.array([c.q @ u]), u)))
        np.testing.assert_allclose(yc, ref, rtol=0, atol=1e-14)
        assert abs(np.hypot(*yc[:2]) - L) < 1e-12 and abs(yc[:2] @ yc[2:]) < 1e-12
        # the converged residual is rounding noise (0 or a few ulp of L^2/2): numpy's dot and
        # the C loop may round it differently (numpy 2.4 with FMA: 2.2e-16 against 0.0)
        assert abs(norm.value - c.norm) <= 4 * np.finfo(float).eps * L * L


def test_project_turns_quaternions_as_the_python_closure(lib):
    """A ball joint whose body x axis must stay horizontal, from tilted, non-unit quaternions:
    ``mbrt_project`` normalizes, steps in the body's rotation vector with
    :func:`quat_increment` and corrects the speeds -- :func:`close_positions` with the same
    increment gives the same state to 1e-14; the quaternion is unit."""
    from mbcomp.assembly.manifold import close_positions, solve_speeds
    from mbcomp.codegen.engine import _Mech
    from mbcomp.modeling.free_joint import quat_increment

    P, rows, seg = _Mech(), np.zeros(1, dtype=np.intc), np.array([1, 0, 0, 1], dtype=np.intc)
    lib.mech_ball.argtypes = [ctypes.c_void_p] * 3
    lib.mech_ball(ctypes.addressof(P), rows.ctypes.data, seg.ctypes.data)
    lib.mbrt_mech_work_size.argtypes = [ctypes.c_void_p]
    lib.mbrt_mech_work_size.restype = ctypes.c_size_t
    work = np.zeros(lib.mbrt_mech_work_size(ctypes.addressof(P)))
    lib.mbrt_project.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_double, ctypes.c_int,
                                 ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p]

    def residual(Q):
        R21, R22 = 2 * (Q[2] * Q[3] + Q[0] * Q[1]), 1 - 2 * (Q[1] ** 2 + Q[2] ** 2)
        return np.array([2 * (Q[1] * Q[3] - Q[0] * Q[2])]), np.array([[0.0, -R22, R21]]), None

    rng = np.random.default_rng(9)
    for _ in range(20):
        y = np.concatenate((rng.normal(size=4) * [1, 0.2, 0.2, 1] + [1.5, 0, 0, 0], rng.normal(size=3)))
        yc = y.copy()
        assert lib.mbrt_project(ctypes.addressof(P), 0.0, yc.ctypes.data, 1e-12, 8, 1e-9, None,
                                work.ctypes.data) == 0
        q0 = quat_increment(y[:4], np.zeros(3))
        c = close_positions(residual, quat_increment, q0)
        r, C, _ = residual(c.q)
        ref = np.concatenate((c.q, solve_speeds(C, C @ y[4:], y[4:])))
        np.testing.assert_allclose(yc, ref, rtol=0, atol=1e-14)
        assert abs(np.linalg.norm(yc[:4]) - 1) < 1e-15 and abs(residual(yc[:4])[0][0]) < 1e-12


@pytest.mark.parametrize("form", [1, 2, 3])
def test_dae_residual_vanishes_on_the_pendulum_motion(lib, form):
    """The Cartesian pendulum at a point of its exact motion (theta, theta') with the exact
    accelerations and multiplier: the residual of Index1 (with Baumgarte), GGL (eta = 0)
    and Index3 is zero in its dynamic and constraint rows, and the Jacobian's exact blocks
    are -M, -C^T (and -C in Index1's acceleration rows)."""
    m, g, L = 2.0, 9.81, 1.5
    P, keep = _pendulum(lib, np.array([m, g, L]))
    for f in ("mbrt_dae_size", "mbrt_dae_work_size"):
        getattr(lib, f).argtypes = [ctypes.c_void_p, ctypes.c_int]
    lib.mbrt_dae_work_size.restype = ctypes.c_size_t
    lib.mbrt_dae_fun.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_double] + [ctypes.c_void_p] * 6
    n = lib.mbrt_dae_size(ctypes.addressof(P), form)
    work = np.zeros(lib.mbrt_dae_work_size(ctypes.addressof(P), form))
    for th, wd in ((0.4, 1.3), (-2.0, 0.5)):
        x, y = L * np.sin(th), -L * np.cos(th)
        thdd = -g / L * np.sin(th)
        a = np.array([L * np.cos(th) * thdd - L * np.sin(th) * wd ** 2, L * np.sin(th) * thdd + L * np.cos(th) * wd ** 2])
        lam = -m * a[0] / x
        yv = np.r_[x, y, L * np.cos(th) * wd, L * np.sin(th) * wd, a, lam, [0.0] * (n - 7)]
        F, J, nf, gains = np.zeros(n), np.zeros((n, n)), ctypes.c_int(), np.array([10.0, 10.0])
        assert lib.mbrt_dae_fun(ctypes.addressof(P), form, 0.0, yv.ctypes.data, gains.ctypes.data if form == 1 else None,
                                F.ctypes.data, J.ctypes.data, ctypes.addressof(nf), work.ctypes.data) == 0
        np.testing.assert_allclose(F[:4], yv[2:6], rtol=1e-14)
        np.testing.assert_allclose(F[4:], 0.0, atol=1e-11)
        np.testing.assert_array_equal(J[4:6, 4:6], -m * np.eye(2))
        np.testing.assert_array_equal(J[4:6, 6], [-x, -y])
        if form == 1:
            np.testing.assert_array_equal(J[6, 4:6], [-x, -y])


def test_cond2_matches_numpy(lib):
    """The one-sided Jacobi condition number against numpy's SVD (relative error ~1e-16 cond)."""
    lib.mbrt_cond2.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
    lib.mbrt_cond2.restype = ctypes.c_double
    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 6, 12):
        for c in (1.0, 1e3, 1e8, 1e10):
            U, _ = np.linalg.qr(rng.normal(size=(n, n)))
            V, _ = np.linalg.qr(rng.normal(size=(n, n)))
            A = np.ascontiguousarray(U @ np.diag(np.geomspace(1.0, 1.0 / c, n)) @ V.T)
            S = np.zeros(n * n)
            got = lib.mbrt_cond2(n, A.ctypes.data, S.ctypes.data)
            assert got == pytest.approx(np.linalg.cond(A), rel=1e-14 * c + 1e-12)
    S = np.zeros(4)
    assert np.isinf(lib.mbrt_cond2(2, np.array([1.0, 2.0, 2.0, 4.0]).ctypes.data, S.ctypes.data))


# --------------------------------------------------------------------------- memory checkers
def _runs_clean(cmd, **kw):
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120, **kw)
    return res


def test_selftest_under_asan_ubsan(tmp_path):
    """The C self-test driver (every status, exact-size heap work buffers) under
    AddressSanitizer + UndefinedBehaviorSanitizer."""
    run = run_under_sanitizers(tmp_path, _build)
    if run is None:
        pytest.skip("AddressSanitizer/UBSan not usable here")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 failures" in run.stdout and "runtime error" not in run.stderr


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not installed")
def test_selftest_under_valgrind(tmp_path):
    exe, res = _build(tmp_path, exe=True)
    assert res.returncode == 0, res.stderr
    run = _runs_clean(["valgrind", "--error-exitcode=99", "--leak-check=full", "-q", str(exe)])
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 failures" in run.stdout
