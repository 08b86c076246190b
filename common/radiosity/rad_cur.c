/* rad_cur: maximal-volume row selection and CUR (thesis 3.2.3). */
#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rad_lowrank.h"

int gi_rad_maxvol(const double *A, uint32_t n, uint32_t k, double tol, int max_swaps,
                  uint32_t *rows, gi_error *err)
{
    if (k == 0 || k > n)
        return gi_fail(err, GI_EINVAL, "maxvol: %u rows of %u", k, n);
    double *LU = gi_try_malloc((size_t)n * k * sizeof *LU, err, "maxvol");
    double *B = gi_try_malloc((size_t)n * k * sizeof *B, err, "maxvol");
    double *W = gi_try_malloc((size_t)k * k * sizeof *W, err, "maxvol");
    double *row = gi_try_malloc((size_t)k * sizeof *row, err, "maxvol");
    double *col = gi_try_malloc((size_t)n * sizeof *col, err, "maxvol");
    lapack_int *ipiv = gi_try_malloc((size_t)k * sizeof *ipiv, err, "maxvol");
    uint32_t *perm = gi_try_malloc((size_t)n * sizeof *perm, err, "maxvol");
    int rc = -1;
    if (!LU || !B || !W || !row || !col || !ipiv || !perm)
        goto done;
    /* Start: the pivot rows of LU with partial pivoting. */
    memcpy(LU, A, (size_t)n * k * sizeof *LU);
    lapack_int info =
        LAPACKE_dgetrf(LAPACK_ROW_MAJOR, (lapack_int)n, (lapack_int)k, LU, (lapack_int)k, ipiv);
    if (info != 0) {
        gi_fail(err, GI_EINVAL, "maxvol: the %u x %u matrix has rank < %u", n, k, k);
        goto done;
    }
    for (uint32_t i = 0; i < n; i++)
        perm[i] = i;
    for (uint32_t i = 0; i < k; i++) {
        uint32_t j = (uint32_t)ipiv[i] - 1, t = perm[i];
        perm[i] = perm[j];
        perm[j] = t;
    }
    memcpy(rows, perm, k * sizeof *rows);
    /* B = A A(I,:)^-1: the coefficients of every row in the chosen rows. */
    for (uint32_t i = 0; i < k; i++)
        memcpy(W + (size_t)i * k, A + (size_t)rows[i] * k, k * sizeof *W);
    if (LAPACKE_dgetrf(LAPACK_ROW_MAJOR, (lapack_int)k, (lapack_int)k, W, (lapack_int)k, ipiv) ||
        LAPACKE_dgetri(LAPACK_ROW_MAJOR, (lapack_int)k, W, (lapack_int)k, ipiv)) {
        gi_fail(err, GI_EINVAL, "maxvol: singular starting submatrix");
        goto done;
    }
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)k, (int)k, 1.0, A, (int)k,
                W, (int)k, 0.0, B, (int)k);
    for (int swap = 0; swap < max_swaps; swap++) {
        size_t best = (size_t)cblas_idamax((int)((size_t)n * k), B, 1);
        uint32_t i = (uint32_t)(best / k), j = (uint32_t)(best % k);
        double b = B[best];
        if (fabs(b) <= 1.0 + tol)
            break;
        /* Row i replaces rows[j]; |det| grows by |b|. Sherman-Morrison:
         * B -= B(:, j) (B(i, :) - e_j^T) / b. */
        memcpy(row, B + (size_t)i * k, k * sizeof *row);
        row[j] -= 1.0;
        cblas_dcopy((int)n, B + j, (int)k, col, 1);
        cblas_dger(CblasRowMajor, (int)n, (int)k, -1.0 / b, col, 1, row, 1, B, (int)k);
        rows[j] = i;
    }
    rc = 0;
done:
    free(LU), free(B), free(W), free(row), free(col), free(ipiv), free(perm);
    return rc;
}

/* pinv of a k x k matrix via SVD, singular values below 1e-12 sigma_max
 * dropped. */
static int pinv(const double *W, uint32_t k, double *out, gi_error *err)
{
    double *A = gi_xmalloc((size_t)k * k * sizeof *A), *U = gi_xmalloc((size_t)k * k * sizeof *U);
    double *VT = gi_xmalloc((size_t)k * k * sizeof *VT), *S = gi_xmalloc((size_t)k * sizeof *S);
    memcpy(A, W, (size_t)k * k * sizeof *A);
    lapack_int info = LAPACKE_dgesdd(LAPACK_ROW_MAJOR, 'S', (lapack_int)k, (lapack_int)k, A,
                                     (lapack_int)k, S, U, (lapack_int)k, VT, (lapack_int)k);
    if (info == 0) {
        /* pinv = V S^+ U^T: scale U's columns, then VT^T (U S^+)^T. */
        for (uint32_t i = 0; i < k; i++)
            for (uint32_t j = 0; j < k; j++)
                U[(size_t)i * k + j] *= S[j] > 1e-12 * S[0] ? 1.0 / S[j] : 0.0;
        cblas_dgemm(CblasRowMajor, CblasTrans, CblasTrans, (int)k, (int)k, (int)k, 1.0, VT, (int)k,
                    U, (int)k, 0.0, out, (int)k);
    }
    free(A), free(U), free(VT), free(S);
    if (info != 0)
        return gi_fail(err, GI_EINTERNAL, "CUR: SVD of W did not converge");
    return 0;
}

int gi_rad_cur(const double *F, uint32_t n, uint32_t k, int sweeps, gi_rad_lowrank *lr,
               gi_error *err)
{
    if (k == 0 || k > n)
        return gi_fail(err, GI_EINVAL, "CUR: rank %u out of [1, %u]", k, n);
    uint32_t *Ir = gi_xmalloc(k * sizeof *Ir), *Jc = gi_xmalloc(k * sizeof *Jc);
    double *C = gi_try_malloc((size_t)n * k * sizeof *C, err, "CUR");
    double *RT = gi_try_malloc((size_t)n * k * sizeof *RT, err, "CUR");
    double *W = gi_xmalloc((size_t)k * k * sizeof *W), *Wp = gi_xmalloc((size_t)k * k * sizeof *Wp);
    double *norms = gi_try_malloc((size_t)n * sizeof *norms, err, "CUR");
    int rc = -1;
    if (!C || !RT || !norms)
        goto done;
    /* Start from the k columns of largest norm. */
    for (uint32_t j = 0; j < n; j++)
        norms[j] = cblas_dnrm2((int)n, F + j, (int)n);
    gi_rad_top_k(norms, n, k, Jc);
    for (int s = 0; s <= sweeps; s++) {
        for (uint32_t e = 0; e < n; e++) /* C = F(:, Jc) */
            for (uint32_t i = 0; i < k; i++)
                C[(size_t)e * k + i] = F[(size_t)e * n + Jc[i]];
        if (gi_rad_maxvol(C, n, k, 1e-2, 100 * (int)k, Ir, err))
            goto done;
        for (uint32_t e = 0; e < n; e++) /* R^T = F(Ir, :)^T */
            for (uint32_t i = 0; i < k; i++)
                RT[(size_t)e * k + i] = F[(size_t)Ir[i] * n + e];
        if (s == sweeps)
            break;
        if (gi_rad_maxvol(RT, n, k, 1e-2, 100 * (int)k, Jc, err))
            goto done;
    }
    for (uint32_t a = 0; a < k; a++) /* W = F(Ir, Jc) */
        for (uint32_t b = 0; b < k; b++)
            W[(size_t)a * k + b] = F[(size_t)Ir[a] * n + Jc[b]];
    if (pinv(W, k, Wp, err) || gi_rad_lowrank_alloc(lr, n, k, 1, err))
        goto done;
    /* U_k = C pinv(W), V_k = R^T. */
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)k, (int)k, 1.0, C, (int)k,
                Wp, (int)k, 0.0, lr->U, (int)k);
    memcpy(lr->V, RT, (size_t)n * k * sizeof *RT);
    rc = 0;
done:
    free(Ir), free(Jc), free(C), free(RT), free(W), free(Wp), free(norms);
    return rc;
}
