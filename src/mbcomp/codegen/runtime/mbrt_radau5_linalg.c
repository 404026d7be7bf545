/*
 * mbrt_radau5_linalg.c -- RADAU5's iteration matrices (gamma/h) I - J and (mu/h) I - J, mu
 * complex: row and column equilibration (the largest magnitude of every row and column 1,
 * so that a pivot below 50 eps means "rank deficient" whatever the units), LU with partial
 * pivoting (whole rows swapped, LAPACK's convention: the solves apply every interchange
 * before the substitutions), the complex matrix in interleaved (re, im) storage pivoted by
 * |re| + |im|.
 */
#include "mbrt_radau5_internal.h"

#include <stdio.h>

/* ------------------------------------------------------------------ factors */
/* LU with partial pivoting of the n x n row-major real A in place; |pivot| below tol or
 * not finite: returns 1 + its index. */
static int lu_real(int n, double *A, int *piv, double *pmin)
{
    double smallest = INFINITY;
    for (int k = 0; k < n; ++k) {
        int p = k;
        double big = fabs(A[(size_t)k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            double v = fabs(A[(size_t)i * n + k]);
            if (v > big) {
                big = v;
                p = i;
            }
        }
        piv[k] = p;
        if (p != k)
            for (int j = 0; j < n; ++j) {
                double tmp = A[(size_t)k * n + j];
                A[(size_t)k * n + j] = A[(size_t)p * n + j];
                A[(size_t)p * n + j] = tmp;
            }
        double d = A[(size_t)k * n + k];
        smallest = fmin(smallest, fabs(d));
        if (!(fabs(d) > PIVOT_TOL) || !isfinite(d)) {
            *pmin = fabs(d);
            return k + 1;
        }
        for (int i = k + 1; i < n; ++i) {
            double l = A[(size_t)i * n + k] / d;
            A[(size_t)i * n + k] = l;
            if (l != 0.0)
                for (int j = k + 1; j < n; ++j)
                    A[(size_t)i * n + j] -= l * A[(size_t)k * n + j];
        }
    }
    *pmin = smallest;
    return 0;
}

/* The same for the complex A (interleaved re, im); pivots by |re| + |im| as LAPACK. */
static int lu_complex(int n, double *A, int *piv, double *pmin)
{
    double smallest = INFINITY;
    for (int k = 0; k < n; ++k) {
        int p = k;
        double big = -1.0;
        for (int i = k; i < n; ++i) {
            const double *a = A + 2 * ((size_t)i * n + k);
            double v = fabs(a[0]) + fabs(a[1]);
            if (v > big) {
                big = v;
                p = i;
            }
        }
        piv[k] = p;
        if (p != k)
            for (int j = 0; j < 2 * n; ++j) {
                double tmp = A[2 * (size_t)k * n + j];
                A[2 * (size_t)k * n + j] = A[2 * (size_t)p * n + j];
                A[2 * (size_t)p * n + j] = tmp;
            }
        double dre = A[2 * ((size_t)k * n + k)], dim = A[2 * ((size_t)k * n + k) + 1];
        double mod = hypot(dre, dim);
        smallest = fmin(smallest, mod);
        if (!(mod > PIVOT_TOL) || !isfinite(mod)) {
            *pmin = mod;
            return k + 1;
        }
        double den = dre * dre + dim * dim, ire = dre / den, iim = -dim / den; /* 1 / pivot */
        for (int i = k + 1; i < n; ++i) {
            double *a = A + 2 * ((size_t)i * n + k);
            double lre = a[0] * ire - a[1] * iim, lim = a[0] * iim + a[1] * ire;
            a[0] = lre;
            a[1] = lim;
            if (lre == 0.0 && lim == 0.0)
                continue;
            const double *u = A + 2 * (size_t)k * n;
            double *row = A + 2 * (size_t)i * n;
            for (int j = k + 1; j < n; ++j) {
                double ure = u[2 * j], uim = u[2 * j + 1];
                row[2 * j] -= lre * ure - lim * uim;
                row[2 * j + 1] -= lre * uim + lim * ure;
            }
        }
    }
    *pmin = smallest;
    return 0;
}

/* Factors (gamma/h) I - J and (mu/h) I - J after equilibration.  Returns 0, or 1 with the
 * reason in msg (structural: *structural = 1). */
int mbrt_r5_factorize(R5 *S, double h, char *msg, size_t len, int *structural)
{
    int n = S->n;
    const double *J = S->J;
    double g = GAMMA_ / h, cre = MU_RE / h, cim = MU_IM / h;
    double *E1 = S->E1, *E2 = S->E2, *r1 = S->r1, *s1 = S->s1, *r2 = S->r2, *s2 = S->s2;
    *structural = 0;
    /* the matrices, and the row maxima of their magnitudes */
    for (int i = 0; i < n; ++i) {
        double m1 = 0.0, m2 = 0.0;
        for (int j = 0; j < n; ++j) {
            size_t ij = (size_t)i * n + j;
            double a = -J[ij];
            if (i == j) {
                double dre = cre + a, dim = cim;
                E1[ij] = a + g;
                E2[2 * ij] = dre;
                E2[2 * ij + 1] = dim;
                m1 = fmax(m1, fabs(E1[ij]));
                m2 = fmax(m2, hypot(dre, dim));
            } else {
                E1[ij] = a;
                E2[2 * ij] = a;
                E2[2 * ij + 1] = 0.0;
                m1 = fmax(m1, fabs(a));
                m2 = fmax(m2, fabs(a));
            }
        }
        if (!(m1 > 0.0) || !(m2 > 0.0)) {
            snprintf(msg, len, "equation %d involves no variable (row %d is zero)", i, i);
            *structural = 1;
            return 1;
        }
        r1[i] = 1.0 / m1;
        r2[i] = 1.0 / m2;
    }
    for (int j = 0; j < n; ++j) {
        double m1 = 0.0, m2 = 0.0;
        for (int i = 0; i < n; ++i) {
            size_t ij = (size_t)i * n + j;
            m1 = fmax(m1, fabs(E1[ij]) * r1[i]);
            m2 = fmax(m2, hypot(E2[2 * ij], E2[2 * ij + 1]) * r2[i]);
        }
        if (!(m1 > 0.0) || !(m2 > 0.0)) {
            snprintf(msg, len, "variable %d enters no equation (column %d is zero)", j, j);
            *structural = 1;
            return 1;
        }
        s1[j] = 1.0 / m1;
        s2[j] = 1.0 / m2;
    }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            size_t ij = (size_t)i * n + j;
            E1[ij] = E1[ij] * r1[i] * s1[j];
            E2[2 * ij] = E2[2 * ij] * r2[i] * s2[j];
            E2[2 * ij + 1] = E2[2 * ij + 1] * r2[i] * s2[j];
        }
    S->info->nlu += 2;
    double pmin;
    int k = lu_real(n, E1, S->p1, &pmin);
    if (k == 0)
        k = lu_complex(n, E2, S->p2, &pmin);
    if (k != 0) {
        snprintf(msg, len, "pivot %d of the equilibrated matrix is %.3g (rank deficient)", k - 1, pmin);
        return 1;
    }
    S->hdr[H_LU_H] = h;
    return 0;
}

/* x = ((gamma/h) I - J)^-1 b (b overwritten by x). */
void mbrt_r5_solve_real(const R5 *S, double *b)
{
    int n = S->n;
    const double *A = S->E1;
    for (int i = 0; i < n; ++i)
        b[i] *= S->r1[i];
    for (int k = 0; k < n; ++k) { /* the rows' interchanges first (L's rows were swapped too) */
        int p = S->p1[k];
        double t = b[k];
        b[k] = b[p];
        b[p] = t;
    }
    for (int k = 0; k < n; ++k)
        for (int i = k + 1; i < n; ++i)
            b[i] -= A[(size_t)i * n + k] * b[k];
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int j = i + 1; j < n; ++j)
            s -= A[(size_t)i * n + j] * b[j];
        b[i] = s / A[(size_t)i * n + i];
    }
    for (int i = 0; i < n; ++i)
        b[i] *= S->s1[i];
}

/* x + i y = ((mu/h) I - J)^-1 (x + i y), in place; cz: 2n scratch. */
void mbrt_r5_solve_complex(const R5 *S, double *x, double *y, double *cz)
{
    int n = S->n;
    const double *A = S->E2;
    for (int i = 0; i < n; ++i) {
        cz[2 * i] = x[i] * S->r2[i];
        cz[2 * i + 1] = y[i] * S->r2[i];
    }
    for (int k = 0; k < n; ++k) { /* the rows' interchanges first */
        int p = S->p2[k];
        double a = cz[2 * k], b = cz[2 * k + 1];
        cz[2 * k] = cz[2 * p];
        cz[2 * k + 1] = cz[2 * p + 1];
        cz[2 * p] = a;
        cz[2 * p + 1] = b;
    }
    for (int k = 0; k < n; ++k) {
        double bre = cz[2 * k], bim = cz[2 * k + 1];
        for (int i = k + 1; i < n; ++i) {
            const double *l = A + 2 * ((size_t)i * n + k);
            cz[2 * i] -= l[0] * bre - l[1] * bim;
            cz[2 * i + 1] -= l[0] * bim + l[1] * bre;
        }
    }
    for (int i = n - 1; i >= 0; --i) {
        double sre = cz[2 * i], sim = cz[2 * i + 1];
        const double *row = A + 2 * (size_t)i * n;
        for (int j = i + 1; j < n; ++j) {
            sre -= row[2 * j] * cz[2 * j] - row[2 * j + 1] * cz[2 * j + 1];
            sim -= row[2 * j] * cz[2 * j + 1] + row[2 * j + 1] * cz[2 * j];
        }
        double dre = row[2 * i], dim = row[2 * i + 1], den = dre * dre + dim * dim;
        cz[2 * i] = (sre * dre + sim * dim) / den;
        cz[2 * i + 1] = (sim * dre - sre * dim) / den;
    }
    for (int i = 0; i < n; ++i) {
        x[i] = cz[2 * i] * S->s2[i];
        y[i] = cz[2 * i + 1] * S->s2[i];
    }
}
