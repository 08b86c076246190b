/* rad_dynamic: Algorithm 6 and the double SMW update. */
#include "rad_dynamic.h"
#include "rad_ff.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void gi_rad_sparse_free(gi_rad_sparse *s)
{
    free(s->row_ptr);
    free(s->col);
    free(s->val);
    memset(s, 0, sizeof *s);
}

int gi_rad_alg6(const gi_rad_sparse *dF, uint32_t k_delta, gi_rad_lowrank *delta,
                gi_rad_alg6_stats *stats, gi_error *err)
{
    uint32_t n = dF->n, kd = k_delta < n ? k_delta : n;
    if (kd == 0)
        return gi_fail(err, GI_EINVAL, "Algorithm 6: k_delta must be positive");
    if (gi_rad_lowrank_alloc(delta, n, 2 * kd, 1, err))
        return -1;
    uint32_t K = 2 * kd;
    double *norm2 = gi_xcalloc(n, sizeof *norm2);
    uint32_t *pick = gi_xmalloc(kd * sizeof *pick);
    int32_t *slot = gi_xmalloc((size_t)n * sizeof *slot); /* column -> selected position */
    memset(stats, 0, sizeof *stats);
    stats->nnz = dF->nnz;
    /* Lines 1-6: the k_delta columns of largest norm, whole. */
    for (uint64_t i = 0; i < dF->nnz; i++)
        norm2[dF->col[i]] += dF->val[i] * dF->val[i];
    gi_rad_top_k(norm2, n, kd, pick);
    for (uint32_t j = 0; j < n; j++)
        slot[j] = -1;
    for (uint32_t i = 0; i < kd; i++) {
        slot[pick[i]] = (int32_t)i;
        delta->V[(size_t)pick[i] * K + i] = 1.0; /* V_dc(I(i), i) = 1 */
    }
    memset(norm2, 0, (size_t)n * sizeof *norm2);
    for (uint32_t e = 0; e < n; e++)
        for (uint64_t i = dF->row_ptr[e]; i < dF->row_ptr[e + 1]; i++) {
            int32_t s = slot[dF->col[i]];
            if (s >= 0) {
                delta->U[(size_t)e * K + (uint32_t)s] = dF->val[i]; /* U_dc = dF(:, I) */
                stats->captured++;
            } else {
                norm2[e] += dF->val[i] * dF->val[i]; /* line 7: the residual's rows */
            }
        }
    /* Lines 8-13: the k_delta rows of largest norm of the residual. */
    gi_rad_top_k(norm2, n, kd, pick);
    for (uint32_t i = 0; i < kd; i++) {
        uint32_t e = pick[i];
        delta->U[(size_t)e * K + kd + i] = 1.0; /* U_dr(I(i), i) = 1 */
        for (uint64_t q = dF->row_ptr[e]; q < dF->row_ptr[e + 1]; q++)
            if (slot[dF->col[q]] < 0) {
                delta->V[(size_t)dF->col[q] * K + kd + i] = dF->val[q]; /* V_dr = dF(I, :)^T */
                stats->captured++;
            }
    }
    free(norm2);
    free(pick);
    free(slot);
    return 0;
}

int gi_rad_delta_coarse(const gi_rad_sparse *dF, const uint32_t *patch, const uint32_t *patch_count,
                        uint32_t k, gi_rad_sparse *out, gi_error *err)
{
    uint32_t n = dF->n;
    memset(out, 0, sizeof *out);
    out->n = n;
    /* The elements of each patch, in order (columns of a row stay sorted). */
    uint32_t *first = gi_xcalloc((size_t)k + 1, sizeof *first);
    uint32_t *members = gi_try_malloc((size_t)n * sizeof *members, err, "coarse change");
    double *du = gi_try_calloc(k, sizeof *du, err, "coarse change");
    uint8_t *seen = gi_try_calloc(k, 1, err, "coarse change");
    uint32_t *touched = gi_try_malloc((size_t)k * sizeof *touched, err, "coarse change");
    out->row_ptr = gi_try_calloc((size_t)n + 1, sizeof *out->row_ptr, err, "coarse change");
    int rc = -1;
    if (!members || !du || !seen || !touched || !out->row_ptr)
        goto done;
    for (uint32_t e = 0; e < n; e++)
        first[patch[e] + 1]++;
    for (uint32_t p = 0; p < k; p++)
        first[p + 1] += first[p];
    uint32_t *fill = gi_xmalloc((size_t)k * sizeof *fill);
    memcpy(fill, first, (size_t)k * sizeof *fill);
    for (uint32_t e = 0; e < n; e++)
        members[fill[patch[e]]++] = e;
    free(fill);
    uint64_t cap = 1024;
    out->col = gi_xmalloc(cap * sizeof *out->col);
    out->val = gi_xmalloc(cap * sizeof *out->val);
    for (uint32_t e = 0; e < n; e++) {
        uint32_t nt = 0;
        for (uint64_t q = dF->row_ptr[e]; q < dF->row_ptr[e + 1]; q++) {
            uint32_t p = patch[dF->col[q]];
            if (!seen[p]) {
                seen[p] = 1;
                touched[nt++] = p;
            }
            du[p] += dF->val[q] / patch_count[p];
        }
        qsort(touched, nt, sizeof *touched, gi_rad_cmp_u32);
        for (uint32_t t = 0; t < nt; t++) {
            uint32_t p = touched[t];
            if (du[p] != 0.0)
                for (uint32_t i = first[p]; i < first[p + 1]; i++) {
                    if (out->nnz == cap) {
                        cap *= 2;
                        out->col = gi_xrealloc(out->col, cap * sizeof *out->col);
                        out->val = gi_xrealloc(out->val, cap * sizeof *out->val);
                    }
                    out->col[out->nnz] = members[i];
                    out->val[out->nnz++] = du[p];
                }
            du[p] = 0.0;
            seen[p] = 0;
        }
        out->row_ptr[e + 1] = out->nnz;
    }
    rc = 0;
done:
    free(first), free(members), free(du), free(seen), free(touched);
    if (rc)
        gi_rad_sparse_free(out);
    return rc;
}

/* out = inverse of (I - A) for a k x k A, in place of A. */
static int inverse_of_identity_minus(double *A, uint32_t k, gi_error *err)
{
    for (size_t i = 0; i < (size_t)k * k; i++)
        A[i] = -A[i];
    for (uint32_t i = 0; i < k; i++)
        A[(size_t)i * k + i] += 1.0;
    lapack_int *ipiv = gi_xmalloc((size_t)k * sizeof *ipiv);
    lapack_int info =
        LAPACKE_dgetrf(LAPACK_ROW_MAJOR, (lapack_int)k, (lapack_int)k, A, (lapack_int)k, ipiv);
    if (info == 0)
        info = LAPACKE_dgetri(LAPACK_ROW_MAJOR, (lapack_int)k, A, (lapack_int)k, ipiv);
    free(ipiv);
    if (info != 0)
        return gi_fail(err, GI_EINVAL, "update: singular SMW matrix (LAPACK info %d)", (int)info);
    return 0;
}

int gi_rad_update_solve(const gi_rad_lowrank *init, const gi_rad_lowrank *delta, const double *rho,
                        const double *E, uint32_t m, double *B, gi_error *err)
{
    uint32_t n = init->n, k = init->k, kd = delta->k;
    if (delta->n != n || !delta->V)
        return gi_fail(err, GI_EINVAL, "update: factor sizes differ");
    double *RUi = gi_try_malloc((size_t)n * k * sizeof *RUi, err, "moving-object update");
    double *RUd = gi_try_malloc((size_t)n * kd * sizeof *RUd, err, "moving-object update");
    double *Y = gi_try_malloc((size_t)n * k * sizeof *Y, err, "moving-object update");
    double *A = gi_try_malloc((size_t)k * k * sizeof *A, err, "moving-object update");
    double *YtVd = gi_try_malloc((size_t)k * kd * sizeof *YtVd, err, "moving-object update");
    double *W = gi_try_malloc((size_t)n * kd * sizeof *W, err, "moving-object update");
    double *P = gi_try_malloc((size_t)k * kd * sizeof *P, err, "moving-object update");
    double *Q = gi_try_malloc((size_t)n * kd * sizeof *Q, err, "moving-object update");
    double *A2 = gi_try_malloc((size_t)kd * kd * sizeof *A2, err, "moving-object update");
    double *Z = gi_try_malloc((size_t)n * kd * sizeof *Z, err, "moving-object update");
    double *T1 = gi_try_malloc((size_t)k * m * sizeof *T1, err, "moving-object update");
    double *T2 = gi_try_malloc((size_t)kd * m * sizeof *T2, err, "moving-object update");
    int rc = -1;
    if (!RUi || !RUd || !Y || !A || !YtVd || !W || !P || !Q || !A2 || !Z || !T1 || !T2)
        goto done;
    for (uint32_t e = 0; e < n; e++) { /* R folded into both U factors */
        for (uint32_t p = 0; p < k; p++)
            RUi[(size_t)e * k + p] = rho[e] * init->U[(size_t)e * k + p];
        for (uint32_t p = 0; p < kd; p++)
            RUd[(size_t)e * kd + p] = rho[e] * delta->U[(size_t)e * kd + p];
    }
    /* Y = -U_I (I_k - V_I^T U_I)^-1                       (eq. 3.39) */
    gi_rad_lowrank_vt(init, RUi, k, A);
    if (inverse_of_identity_minus(A, k, err))
        goto done;
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)k, (int)k, -1.0, RUi,
                (int)k, A, (int)k, 0.0, Y, (int)k);
    /* W = V_d - V_I (Y^T V_d)                              (eq. 3.40) */
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)k, (int)kd, (int)n, 1.0, Y, (int)k,
                delta->V, (int)kd, 0.0, YtVd, (int)kd);
    gi_rad_lowrank_v(init, YtVd, kd, W);
    for (size_t i = 0; i < (size_t)n * kd; i++)
        W[i] = delta->V[i] - W[i];
    /* Z = -(U_d - Y (V_I^T U_d)) (I - W^T U_d)^-1          (eq. 3.41) */
    gi_rad_lowrank_vt(init, RUd, kd, P);
    memcpy(Q, RUd, (size_t)n * kd * sizeof *Q);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)kd, (int)k, -1.0, Y, (int)k,
                P, (int)kd, 1.0, Q, (int)kd);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)kd, (int)kd, (int)n, 1.0, W, (int)kd,
                RUd, (int)kd, 0.0, A2, (int)kd);
    if (inverse_of_identity_minus(A2, kd, err))
        goto done;
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)kd, (int)kd, -1.0, Q,
                (int)kd, A2, (int)kd, 0.0, Z, (int)kd);
    /* B = E - Y (V_I^T E) - Z (W^T E)                     (eq. 3.42) */
    gi_rad_lowrank_vt(init, E, m, T1);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)kd, (int)m, (int)n, 1.0, W, (int)kd,
                E, (int)m, 0.0, T2, (int)m);
    memcpy(B, E, (size_t)n * m * sizeof *B);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)m, (int)k, -1.0, Y, (int)k,
                T1, (int)m, 1.0, B, (int)m);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)m, (int)kd, -1.0, Z,
                (int)kd, T2, (int)m, 1.0, B, (int)m);
    rc = 0;
done:
    free(RUi), free(RUd), free(Y), free(A), free(YtVd), free(W), free(P), free(Q), free(A2),
        free(Z), free(T1), free(T2);
    return rc;
}
