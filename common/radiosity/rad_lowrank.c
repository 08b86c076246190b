/* rad_lowrank: dense low-rank factors and their colour solvers. */
#include "rad_lowrank.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int gi_rad_lowrank_alloc(gi_rad_lowrank *lr, uint32_t n, uint32_t k, int dense_v, gi_error *err)
{
    memset(lr, 0, sizeof *lr);
    lr->n = n;
    lr->k = k;
    lr->U = gi_try_calloc((size_t)n * k, sizeof *lr->U, err, "low-rank factor");
    if (dense_v)
        lr->V = gi_try_calloc((size_t)n * k, sizeof *lr->V, err, "low-rank factor");
    else
        lr->patch = gi_try_calloc(n, sizeof *lr->patch, err, "low-rank factor");
    if (!lr->U || (dense_v ? !lr->V : !lr->patch)) {
        gi_rad_lowrank_free(lr);
        return -1;
    }
    return 0;
}

void gi_rad_lowrank_free(gi_rad_lowrank *lr)
{
    free(lr->U);
    free(lr->V);
    free(lr->patch);
    memset(lr, 0, sizeof *lr);
}

int gi_rad_lowrank_from_factor(gi_rad_lowrank *lr, const gi_rad_factor *f, gi_error *err)
{
    if (gi_rad_lowrank_alloc(lr, f->n, f->k, 0, err))
        return -1;
    for (uint32_t e = 0; e < f->n; e++) {
        for (uint32_t p = 0; p < f->k; p++)
            lr->U[(size_t)e * f->k + p] =
                f->hits[(size_t)e * f->k_pad + p] * f->w[p]; /* eq. 3.53 */
        lr->patch[e] = f->patch[e];
    }
    return 0;
}

void gi_rad_lowrank_vt(const gi_rad_lowrank *lr, const double *X, uint32_t m, double *T)
{
    if (lr->V) {
        cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)lr->k, (int)m, (int)lr->n, 1.0,
                    lr->V, (int)lr->k, X, (int)m, 0.0, T, (int)m);
        return;
    }
    memset(T, 0, (size_t)lr->k * m * sizeof *T);
    for (uint32_t e = 0; e < lr->n; e++) /* per-patch sums */
        cblas_daxpy((int)m, 1.0, X + (size_t)e * m, 1, T + (size_t)lr->patch[e] * m, 1);
}

void gi_rad_lowrank_v(const gi_rad_lowrank *lr, const double *T, uint32_t m, double *X)
{
    if (lr->V) {
        cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)lr->n, (int)m, (int)lr->k, 1.0,
                    lr->V, (int)lr->k, T, (int)m, 0.0, X, (int)m);
        return;
    }
    for (uint32_t e = 0; e < lr->n; e++)
        memcpy(X + (size_t)e * m, T + (size_t)lr->patch[e] * m, m * sizeof *X);
}

int gi_rad_lowrank_smw(const gi_rad_lowrank *lr, const double *rho, const double *E, uint32_t m,
                       double *B, gi_error *err)
{
    uint32_t n = lr->n, k = lr->k;
    double *RU = gi_try_malloc((size_t)n * k * sizeof *RU, err, "SMW solve");
    double *A = gi_try_malloc((size_t)k * k * sizeof *A, err, "SMW solve");
    double *T = gi_try_malloc((size_t)k * m * sizeof *T, err, "SMW solve");
    lapack_int *ipiv = gi_try_malloc((size_t)k * sizeof *ipiv, err, "SMW solve");
    int rc = -1;
    if (!RU || !A || !T || !ipiv)
        goto done;
    for (uint32_t e = 0; e < n; e++)
        for (uint32_t p = 0; p < k; p++)
            RU[(size_t)e * k + p] = rho[e] * lr->U[(size_t)e * k + p];
    gi_rad_lowrank_vt(lr, RU, k, A); /* V^T R U */
    for (size_t i = 0; i < (size_t)k * k; i++)
        A[i] = -A[i];
    for (uint32_t p = 0; p < k; p++)
        A[(size_t)p * k + p] += 1.0; /* I_k - V^T R U */
    gi_rad_lowrank_vt(lr, E, m, T);
    lapack_int info = LAPACKE_dgesv(LAPACK_ROW_MAJOR, (lapack_int)k, (lapack_int)m, A,
                                    (lapack_int)k, ipiv, T, (lapack_int)m);
    if (info != 0) {
        gi_fail(err, info > 0 ? GI_EINVAL : GI_EINTERNAL,
                "SMW: I - V^T R U is singular (LAPACK info %d)", (int)info);
        goto done;
    }
    memcpy(B, E, (size_t)n * m * sizeof *B); /* eq. 3.32 */
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)m, (int)k, 1.0, RU, (int)k,
                T, (int)m, 1.0, B, (int)m);
    rc = 0;
done:
    free(RU);
    free(A);
    free(T);
    free(ipiv);
    return rc;
}

int gi_rad_lowrank_neumann(const gi_rad_lowrank *lr, const double *rho, const double *E, uint32_t m,
                           double tol, int max_iter, double *B, int *iterations, gi_error *err)
{
    uint32_t n = lr->n, k = lr->k;
    double *T = gi_try_malloc((size_t)k * m * sizeof *T, err, "Neumann iteration");
    double *Y = gi_try_malloc((size_t)n * m * sizeof *Y, err, "Neumann iteration");
    double *d2 = gi_try_malloc(2 * (size_t)m * sizeof *d2, err, "Neumann iteration");
    if (!T || !Y || !d2) {
        free(T), free(Y), free(d2);
        return -1;
    }
    memcpy(B, E, (size_t)n * m * sizeof *B);
    double res = INFINITY;
    int it = 0;
    while (it < max_iter && res > tol) {
        gi_rad_lowrank_vt(lr, B, m, T);
        cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)m, (int)k, 1.0, lr->U,
                    (int)k, T, (int)m, 0.0, Y, (int)m);
        memset(d2, 0, 2 * (size_t)m * sizeof *d2);
        for (uint32_t e = 0; e < n; e++)
            for (uint32_t j = 0; j < m; j++) {
                size_t i = (size_t)e * m + j;
                double next = E[i] + rho[e] * Y[i]; /* eq. 3.30 */
                d2[2 * j] += (next - B[i]) * (next - B[i]);
                d2[2 * j + 1] += next * next;
                B[i] = next;
            }
        res = 0.0;
        for (uint32_t j = 0; j < m; j++)
            if (d2[2 * j + 1] > 0.0 && sqrt(d2[2 * j] / d2[2 * j + 1]) > res)
                res = sqrt(d2[2 * j] / d2[2 * j + 1]);
        it++;
    }
    free(T), free(Y), free(d2);
    if (iterations)
        *iterations = it;
    if (res > tol)
        return gi_fail(err, GI_EINVAL, "Neumann iteration: residual %.3g after %d iterations", res,
                       it);
    return 0;
}

double gi_rad_lowrank_distance(const gi_rad_lowrank *lr, const double *F)
{
    uint32_t n = lr->n, k = lr->k, block = 64;
    double *P = gi_xmalloc((size_t)block * n * sizeof *P);
    double sum = 0.0;
    for (uint32_t r0 = 0; r0 < n; r0 += block) {
        uint32_t rows = n - r0 < block ? n - r0 : block;
        if (lr->V) {
            cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)rows, (int)n, (int)k, 1.0,
                        lr->U + (size_t)r0 * k, (int)k, lr->V, (int)k, 0.0, P, (int)n);
        } else {
            for (uint32_t r = 0; r < rows; r++)
                for (uint32_t j = 0; j < n; j++)
                    P[(size_t)r * n + j] = lr->U[(size_t)(r0 + r) * k + lr->patch[j]];
        }
        for (size_t i = 0; i < (size_t)rows * n; i++) {
            double d = F[(size_t)r0 * n + i] - P[i];
            sum += d * d;
        }
    }
    free(P);
    return sqrt(sum);
}

typedef struct ranked {
    double value;
    uint32_t index;
} ranked;

static int by_value_desc(const void *a, const void *b)
{
    const ranked *x = a, *y = b;
    if (x->value != y->value)
        return x->value > y->value ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

void gi_rad_top_k(const double *values, uint32_t n, uint32_t k, uint32_t *out)
{
    ranked *r = gi_xmalloc((size_t)n * sizeof *r);
    for (uint32_t i = 0; i < n; i++)
        r[i] = (ranked){values[i], i};
    qsort(r, n, sizeof *r, by_value_desc);
    for (uint32_t i = 0; i < k && i < n; i++)
        out[i] = r[i].index;
    free(r);
}

int gi_rad_dense_solve(const double *F, uint32_t n, const double *rho, const double *E, uint32_t m,
                       double *B, gi_error *err)
{
    double *A = gi_try_malloc((size_t)n * n * sizeof *A, err, "dense radiosity solve");
    lapack_int *ipiv = gi_try_malloc((size_t)n * sizeof *ipiv, err, "dense radiosity solve");
    if (!A || !ipiv) {
        free(A);
        free(ipiv);
        return -1;
    }
    for (uint32_t i = 0; i < n; i++) /* I - R F (eq. 2.33) */
        for (uint32_t j = 0; j < n; j++)
            A[(size_t)i * n + j] = (i == j ? 1.0 : 0.0) - rho[i] * F[(size_t)i * n + j];
    memcpy(B, E, (size_t)n * m * sizeof *B);
    lapack_int info = LAPACKE_dgesv(LAPACK_ROW_MAJOR, (lapack_int)n, (lapack_int)m, A,
                                    (lapack_int)n, ipiv, B, (lapack_int)m);
    free(A);
    free(ipiv);
    if (info != 0)
        return gi_fail(err, GI_EINVAL, "dense solve: I - R F is singular (LAPACK info %d)",
                       (int)info);
    return 0;
}
