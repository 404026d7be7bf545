/*
 * mbrt_linalg.c -- dense LU (partial pivoting) and Cholesky factorisations on
 * row-major double arrays, in place, without allocation.
 *
 * Both follow the textbook algorithms (Golub & Van Loan, "Matrix
 * Computations", 4th ed., Alg. 3.4.1 and 4.2.1); they are meant for the small
 * systems (n up to a few hundred) of a multibody model's mass matrix and
 * constraint Jacobian, where a straightforward O(n^3) loop is fastest.
 */
#include "mbrt.h"

#include <math.h>

/* Right-looking LU: for each column k pick the row with the largest |a_ik|
 * (i >= k), swap it into place, store the multipliers l_ik = a_ik / a_kk
 * below the diagonal and update the trailing submatrix. */
int mbrt_lu_factor(int n, double *A, int *piv)
{
    if (n < 0 || (n > 0 && (A == NULL || piv == NULL)))
        return -1;
    for (int k = 0; k < n; ++k) {
        /* pivot search in column k */
        int p = k;
        double amax = fabs(A[(size_t)k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            double a = fabs(A[(size_t)i * n + k]);
            if (a > amax || isnan(a)) { /* a NaN is picked so it is reported */
                amax = a;
                p = i;
                if (isnan(a))
                    break;
            }
        }
        piv[k] = p;
        if (p != k) {
            double *rk = A + (size_t)k * n, *rp = A + (size_t)p * n;
            for (int j = 0; j < n; ++j) {
                double tmp = rk[j];
                rk[j] = rp[j];
                rp[j] = tmp;
            }
        }
        const double *rk = A + (size_t)k * n;
        double pivot = rk[k];
        if (pivot == 0.0 || !isfinite(pivot))
            return k + 1;
        /* multipliers and rank-1 update of the trailing block */
        for (int i = k + 1; i < n; ++i) {
            double *ri = A + (size_t)i * n;
            double l = ri[k] / pivot;
            ri[k] = l;
            if (l != 0.0)
                for (int j = k + 1; j < n; ++j)
                    ri[j] -= l * rk[j];
        }
    }
    return 0;
}

/* P A = L U  =>  A x = b  <=>  L (U x) = P b: permute b with the recorded
 * swaps (in the order they were made), then forward substitution with the
 * unit lower triangle and back substitution with U. */
void mbrt_lu_solve(int n, const double *LU, const int *piv, double *b)
{
    if (n <= 0 || LU == NULL || piv == NULL || b == NULL)
        return;
    for (int k = 0; k < n; ++k) {
        int p = piv[k];
        if (p != k && p >= 0 && p < n) {
            double tmp = b[k];
            b[k] = b[p];
            b[p] = tmp;
        }
    }
    for (int i = 1; i < n; ++i) {
        const double *ri = LU + (size_t)i * n;
        double s = b[i];
        for (int j = 0; j < i; ++j)
            s -= ri[j] * b[j];
        b[i] = s;
    }
    for (int i = n - 1; i >= 0; --i) {
        const double *ri = LU + (size_t)i * n;
        double s = b[i];
        for (int j = i + 1; j < n; ++j)
            s -= ri[j] * b[j];
        b[i] = s / ri[i];
    }
}

/* Row-by-row (Cholesky-Banachiewicz) factorisation: with rows 0..i-1 of L
 * known, l_ij = (a_ij - sum_{k<j} l_ik l_jk) / l_jj for j < i and
 * l_ii = sqrt(a_ii - sum_{k<i} l_ik^2).  Row-major storage makes both sums
 * contiguous dot products. */
int mbrt_chol_factor(int n, double *A)
{
    if (n < 0 || (n > 0 && A == NULL))
        return -1;
    for (int i = 0; i < n; ++i) {
        double *ri = A + (size_t)i * n;
        for (int j = 0; j < i; ++j) {
            const double *rj = A + (size_t)j * n;
            double s = ri[j];
            for (int k = 0; k < j; ++k)
                s -= ri[k] * rj[k];
            ri[j] = s / rj[j];
        }
        double d = ri[i];
        for (int k = 0; k < i; ++k)
            d -= ri[k] * ri[k];
        if (!(d > 0.0) || !isfinite(d)) /* also catches NaN */
            return i + 1;
        ri[i] = sqrt(d);
        for (int j = i + 1; j < n; ++j)
            ri[j] = 0.0;
    }
    return 0;
}

/* L L^T x = b: forward substitution with L, then back substitution with L^T
 * (column access of L, i.e. a strided walk down row-major storage). */
void mbrt_chol_solve(int n, const double *L, double *b)
{
    if (n <= 0 || L == NULL || b == NULL)
        return;
    for (int i = 0; i < n; ++i) {
        const double *ri = L + (size_t)i * n;
        double s = b[i];
        for (int k = 0; k < i; ++k)
            s -= ri[k] * b[k];
        b[i] = s / ri[i];
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < n; ++k)
            s -= L[(size_t)k * n + i] * b[k];
        b[i] = s / L[(size_t)i * n + i];
    }
}
