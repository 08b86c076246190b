/* rad_aca: adaptive cross approximation with partial pivoting. */
#include <cblas.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rad_lowrank.h"

int gi_rad_aca(gi_rad_vector_fn row, gi_rad_vector_fn col, void *user, uint32_t n, uint32_t k,
               double tol, gi_rad_lowrank *lr, gi_error *err)
{
    if (k == 0 || k > n)
        return gi_fail(err, GI_EINVAL, "ACA: rank %u out of [1, %u]", k, n);
    /* Crosses as columns: u_r in Us[r], v_r in Vs[r] (n each). */
    double *Us = gi_try_malloc((size_t)k * n * sizeof *Us, err, "ACA");
    double *Vs = gi_try_malloc((size_t)k * n * sizeof *Vs, err, "ACA");
    double *r = gi_try_malloc((size_t)n * sizeof *r, err, "ACA");
    uint8_t *used = gi_try_calloc(n, 1, err, "ACA"), *used_col = gi_try_calloc(n, 1, err, "ACA");
    int rc = -1;
    if (!Us || !Vs || !r || !used || !used_col)
        goto done;
    uint32_t rank = 0, i = 0, tried = 0;
    double norm2 = 0.0; /* ||sum u v^T||_F^2, updated per cross */
    while (rank < k && tried < n) {
        tried++;
        used[i] = 1;
        if (row(user, i, r, err)) /* residual row i: F(i, :) - sum u_l(i) v_l */
            goto done;
        for (uint32_t l = 0; l < rank; l++)
            cblas_daxpy((int)n, -Us[(size_t)l * n + i], Vs + (size_t)l * n, 1, r, 1);
        /* The pivot: the largest residual entry outside the pivot columns
         * so far (their residual columns vanish). */
        uint32_t j = UINT32_MAX;
        for (uint32_t q = 0; q < n; q++)
            if (!used_col[q] && (j == UINT32_MAX || fabs(r[q]) > fabs(r[j])))
                j = q;
        double *v = Vs + (size_t)rank * n, *u = Us + (size_t)rank * n;
        int degenerate = j == UINT32_MAX || fabs(r[j]) < 1e-300;
        if (!degenerate) {
            for (uint32_t q = 0; q < n; q++)
                v[q] = r[q] / r[j];
            if (col(user, j, u, err)) /* residual column j */
                goto done;
            for (uint32_t l = 0; l < rank; l++)
                cblas_daxpy((int)n, -Vs[(size_t)l * n + j], Us + (size_t)l * n, 1, u, 1);
            degenerate = cblas_dnrm2((int)n, u, 1) == 0.0;
        }
        if (degenerate) {
            /* Nothing left in this row (or its column): try another row. */
            uint32_t next = 0;
            while (next < n && used[next])
                next++;
            if (next == n)
                break;
            i = next;
            continue;
        }
        used_col[j] = 1;
        double nu = cblas_dnrm2((int)n, u, 1), nv = cblas_dnrm2((int)n, v, 1);
        for (uint32_t l = 0; l < rank; l++)
            norm2 += 2.0 * cblas_ddot((int)n, u, 1, Us + (size_t)l * n, 1) *
                     cblas_ddot((int)n, v, 1, Vs + (size_t)l * n, 1);
        norm2 += nu * nu * nv * nv;
        rank++;
        if (tol > 0.0 && nu * nv <= tol * sqrt(norm2 > 0.0 ? norm2 : 0.0))
            break;
        /* Next row: the largest entry of the new column among unused rows. */
        double best = -1.0;
        for (uint32_t q = 0; q < n; q++)
            if (!used[q] && fabs(u[q]) > best) {
                best = fabs(u[q]);
                i = q;
            }
        if (best < 0.0)
            break;
    }
    if (rank == 0) {
        gi_fail(err, GI_EINVAL, "ACA: the matrix is zero");
        goto done;
    }
    if (gi_rad_lowrank_alloc(lr, n, rank, 1, err))
        goto done;
    for (uint32_t e = 0; e < n; e++)
        for (uint32_t l = 0; l < rank; l++) {
            lr->U[(size_t)e * rank + l] = Us[(size_t)l * n + e];
            lr->V[(size_t)e * rank + l] = Vs[(size_t)l * n + e];
        }
    rc = 0;
done:
    free(Us), free(Vs), free(r), free(used), free(used_col);
    return rc;
}
