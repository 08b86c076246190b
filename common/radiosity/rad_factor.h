/* rad_factor: the two-mesh factorization F ~ U_k V_k^T (2MF / 2MCE, thesis
 * 3.5-3.6) and its colour solvers, ready for relighting.
 *
 *   U(e, p) = F_ep / c_p = hits(e, p) / (rays c_p)       (eq. 3.53)
 *   V(e, P(e)) = 1, zero elsewhere                         (eq. 3.54)
 *
 * F is factorized, not RF: the reflectances R_c stay diagonal, one per
 * colour (thesis 3.4.4, "factorize F when using colour"). Per colour the
 * k x k matrix M_c = (I_k - V^T R_c U)^-1 is precomputed (eq. 3.33), so a
 * relight is
 *
 *   B_c = E_c + R_c (U (M_c (V^T E_c)))                    (eq. 3.33)
 *
 * where V^T E_c is a per-patch sum (V is never stored dense), M_c a k x k
 * product, and U s_c is one pass over U for all three colours
 * (rad_kernel.h). The Neumann iteration (eq. 3.30) uses the same pieces.
 *
 * Single precision in the relight path, as in the thesis's timings; the
 * k x k inverses are computed in double (LAPACK) and then rounded. */
#ifndef GI_RAD_FACTOR_H
#define GI_RAD_FACTOR_H

#include <stdint.h>

#include "gi_error.h"

#define GI_RAD_MAX_PATCHES 4096u

typedef struct gi_rad_factor {
    uint32_t n, k, k_pad, rays;
    uint16_t *hits;        /* n x k_pad, row-major, zero padding */
    double *w;             /* k: 1 / (rays c_p) */
    uint32_t *patch;       /* n: P(e) */
    uint32_t *patch_count; /* k: c_p, elements per patch */
    float *rho;            /* n x 3: reflectance per element and colour */
    float *M;              /* 3 x k x k, row-major: M_c (eq. 3.33); NULL until prepared */
    /* The same counts packed for relighting (gi_rad_factor_pack): 8 bits,
     * 255 where larger, the excess in per-row lists. NULL if not packed. */
    uint8_t *hits8;
    uint32_t *over_row, *over_col;
    uint16_t *over_val;
    uint32_t over_count;
} gi_rad_factor;

/* Allocates a factor with zeroed hits (the caller fills hits, patch, rho;
 * then gi_rad_factor_finish computes patch_count and w). */
int gi_rad_factor_alloc(gi_rad_factor *f, uint32_t n, uint32_t k, uint32_t rays, gi_error *err);
/* Checks patch[] (every patch non-empty), sets patch_count and w. */
int gi_rad_factor_finish(gi_rad_factor *f, gi_error *err);
void gi_rad_factor_free(gi_rad_factor *f);

/* Packs the counts into 8 bits (halving what a relight reads) unless more
 * than 1/64 of them exceed 255; repacks after the counts change. */
int gi_rad_factor_pack(gi_rad_factor *f, gi_error *err);
/* The counts as the kernel reads them (packed if packed). */
struct gi_rad_counts;
void gi_rad_factor_counts(const gi_rad_factor *f, struct gi_rad_counts *u);

/* M_c = (I_k - V^T R_c U)^-1 for the three colours (LAPACK dgetrf/dgetri
 * in double), then packs the counts. Fails (GI_EINVAL) if some
 * I_k - V^T R_c U is singular. */
int gi_rad_factor_prepare(gi_rad_factor *f, gi_error *err);

/* Eq. 3.33 for `count` emissions at once: E and B are count x n x 3
 * (element-major RGB). B may not alias E. For count > 1 the products with
 * U are one matrix product (rows converted to float in blocks, then
 * cblas_sgemm); for count == 1 the fused kernel. `threads` >= 1. */
int gi_rad_factor_relight(const gi_rad_factor *f, const float *E, float *B, uint32_t count,
                          int threads, gi_error *err);

/* Eq. 3.30: B_{m+1} = E + R (U (V^T B_m)), B_0 = E, until the residual
 * ||B_{m+1} - B_m|| / ||B_{m+1}|| <= tol (the residual of the low-rank
 * system at B_m is exactly B_{m+1} - B_m). Fails if max_iter is reached. */
int gi_rad_factor_neumann(const gi_rad_factor *f, const float *E, float *B, double tol,
                          int max_iter, int threads, int *iterations, double *residual,
                          gi_error *err);

/* V^T x for 3 colours: t (3 planar k_pad vectors, zero padding) from x
 * (n x 3), summed in double. */
void gi_rad_factor_vt(const gi_rad_factor *f, const float *x, double *t);

#endif
