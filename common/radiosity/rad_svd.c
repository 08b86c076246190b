/* rad_svd: truncated SVD of F (thesis 3.2.2, validation). */
#include <lapacke.h>
#include <stdlib.h>
#include <string.h>

#include "rad_lowrank.h"

int gi_rad_svd_compute(gi_rad_svd *s, const double *F, uint32_t n, gi_error *err)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    double *A = gi_try_malloc((size_t)n * n * sizeof *A, err, "SVD");
    s->U = gi_try_malloc((size_t)n * n * sizeof *s->U, err, "SVD");
    s->VT = gi_try_malloc((size_t)n * n * sizeof *s->VT, err, "SVD");
    s->S = gi_try_malloc((size_t)n * sizeof *s->S, err, "SVD");
    if (!A || !s->U || !s->VT || !s->S) {
        free(A);
        gi_rad_svd_free(s);
        return -1;
    }
    memcpy(A, F, (size_t)n * n * sizeof *A);
    lapack_int info =
        LAPACKE_dgesdd(LAPACK_ROW_MAJOR, 'S', (lapack_int)n, (lapack_int)n, A, (lapack_int)n, s->S,
                       s->U, (lapack_int)n, s->VT, (lapack_int)n);
    free(A);
    if (info != 0) {
        gi_rad_svd_free(s);
        return gi_fail(err, GI_EINTERNAL, "SVD did not converge (LAPACK info %d)", (int)info);
    }
    return 0;
}

int gi_rad_svd_truncate(const gi_rad_svd *s, uint32_t k, gi_rad_lowrank *lr, gi_error *err)
{
    uint32_t n = s->n;
    if (k == 0 || k > n)
        return gi_fail(err, GI_EINVAL, "SVD: rank %u out of [1, %u]", k, n);
    if (gi_rad_lowrank_alloc(lr, n, k, 1, err))
        return -1;
    for (uint32_t e = 0; e < n; e++)
        for (uint32_t i = 0; i < k; i++) {
            lr->U[(size_t)e * k + i] = s->U[(size_t)e * n + i] * s->S[i]; /* U_k S_k */
            lr->V[(size_t)e * k + i] = s->VT[(size_t)i * n + e];
        }
    return 0;
}

void gi_rad_svd_free(gi_rad_svd *s)
{
    free(s->U);
    free(s->S);
    free(s->VT);
    memset(s, 0, sizeof *s);
}
