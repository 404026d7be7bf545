/*
 * mbrt_radau5_internal.h -- the pieces of mbrt_radau5 (mbrt_radau5.c: the driver;
 * mbrt_radau5_step.c: Jacobian, Newton, predictor, error estimate; mbrt_radau5_linalg.c: the
 * iteration matrices).  Not part of the public API; everything public is in mbrt.h.
 */
#ifndef MBRT_RADAU5_INTERNAL_H
#define MBRT_RADAU5_INTERNAL_H

#include "mbrt.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define NIT 7              /* Newton iterations at most (RADAU5's NIT)               */
#define THETA_JAC 0.03     /* keep the Jacobian below this contraction rate          */
#define SAFETY 0.9
#define FAC_MAX 8.0        /* largest step increase                                  */
#define FAC_MIN 0.2        /* largest decrease after an error-test rejection         */
#define QUOT_LO 1.0        /* keep h (and the factors) when h_new / h is in here     */
#define QUOT_HI 1.2
#define MAX_SINGULAR 5     /* consecutive singular matrices before giving up         */
#define MAX_FAILURES 60    /* consecutive failed attempts in one step                */
#define H_START 1e-6       /* shortest automatic first step                          */
#define PIVOT_TOL (50.0 * DBL_EPSILON)
#define DEFAULT_MAX_STEPS 100000L
#define HDR 16             /* doubles of the resumable header                        */

/* the Python stepper's coefficients (mbcomp.solvers.radau: C, T, TI, LAM, GAMMA, MU, D_ERR, P_DENSE) */
static const double C_[3] = {0x1.3d8b64657caeap-3, 0x1.4a36c0803a6dfp-1, 1.0};
static const double T_[9] = {0x1.82d23845d6779p-4, 0x1.0715053fb4eadp-3, 0x1.bf6cccc37fe73p-6,
                             0x1.0037de70aa1fap-2, -0x1.7c2eb3951e591p-3, -0x1.649b5c5d01267p-2,
                             1.0, -0x1.d19d567e523e0p-1, -0.0};
static const double TI_[9] = {0x1.0b70201a79c3fp+2, 0x1.4f8c15da84ea0p-2, 0x1.0bf7ff59d56f0p-1,
                              0x1.2614a65cf8d5dp+2, 0x1.70f99ce1aad9fp-2, -0x1.0c57949a59de5p-1,
                              0x1.1b1ed9d7c3a5ep-1, -0x1.6a00b9a724fa4p+1, 0x1.4f92ea3ad9822p-1};
static const double LAM_[9] = {0x1.d1a48d83e7320p+1, 0.0, 0.0, 0.0, 0x1.572db93e0c667p+1, -0x1.86747f2c3fcbdp+1,
                               0.0, 0x1.86747f2c3fcb3p+1, 0x1.572db93e0c675p+1};
static const double GAMMA_ = 0x1.d1a48d83e731bp+1;
static const double MU_RE = 0x1.572db93e0c667p+1, MU_IM = 0x1.86747f2c3fcbdp+1;
static const double D_[3] = {-0x1.418fd8baffe06p+3, 0x1.61d41b2d54583p+0, -0x1.5555555555533p-2};
static const double P_[9] = {0x1.418fd8baffe07p+3, -0x1.9a12ce7b30917p+4, 0x1.f295c43b61426p+3,
                             -0x1.61d41b2d54586p+0, 0x1.497af24bb6781p+3, -0x1.1d406ee60bed0p+3,
                             0x1.5555555555555p-2, -0x1.5555555555554p+1, 0x1.aaaaaaaaaaaaap+1};

/* The resumable header: what a call leaves for the next (resume != 0). */
enum { H_VALID, H_T, H_H, H_HACC, H_ERRACC, H_FACCON, H_FIRST, H_HAVE_J, H_JCUR, H_LU_H, H_DENSE,
       H_DT0, H_DH, H_N };

typedef struct {
    mbrt_rhs_fn f;
    mbrt_jac_fn jac;
    void *ctx;
    int n;
    double rtol, newton_tol;
    const double *atol;
    double *hdr;
    double *y, *fy, *ynew, *J, *E1, *E2, *r1, *s1, *r2, *s2;
    double *Z, *W, *F, *R, *dW, *yold, *Q, *scale, *ev, *tmp, *cz;
    int *p1, *p2;
    long nfev;
    mbrt_radau5_info *info;
    double t_fail;      /* time of an rhs call that returned nonzero */
    int rhs_rc;         /* its code                                   */
} R5;

/* 1 when every v[0..n-1] is finite */
int mbrt_r5_finite(int n, const double *v);
/* sqrt(mean((x / sc)^2)) */
double mbrt_r5_rms(int n, const double *x, const double *sc);
/* f(t, y) into out, counted; 1 (t_fail, rhs_rc set) when f returned nonzero */
int mbrt_r5_rhs(R5 *S, double t, const double *y, double *out);
/* S->J at (t, S->y): 0, 1 (the rhs failed) or -1 (a non-finite difference) */
int mbrt_r5_jacobian(R5 *S, double t);
/* the factors of (gamma/h) I - J and (mu/h) I - J: 0, or 1 with msg (*structural) */
int mbrt_r5_factorize(R5 *S, double h, char *msg, size_t len, int *structural);
/* b = ((gamma/h) I - J)^-1 b */
void mbrt_r5_solve_real(const R5 *S, double *b);
/* x + i y = ((mu/h) I - J)^-1 (x + i y); cz: 2 n scratch */
void mbrt_r5_solve_complex(const R5 *S, double *x, double *y, double *cz);
/* the simplified Newton iteration from S->Z: 1 converged, 0 failed (fac, msg), -1 rhs failed */
int mbrt_r5_newton(R5 *S, double t, double h, double *theta_out, int *iters, double *fac, char *msg, size_t len);
/* S->Z predicted from the last step's collocation polynomial */
void mbrt_r5_predict(R5 *S, double t, double h);
/* the scaled local error (>= 1e-10, INFINITY if not finite), -1 when the rhs failed */
double mbrt_r5_error(R5 *S, double t, double h, int refilter, const double *absy);
/* the work buffer's arrays (iwork may be NULL) */
void mbrt_r5_layout(R5 *S, double *work, int *iwork);

#endif /* MBRT_RADAU5_INTERNAL_H */
