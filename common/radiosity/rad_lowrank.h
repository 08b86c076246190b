/* rad_lowrank: dense double-precision low-rank factors F ~ U V^T, their
 * colour solvers, and the validation factorizations of thesis 3.2 and 4.3
 * (truncated SVD, CUR with maximal volume) plus ACA (beyond the thesis).
 * Jobs use rad_factor (16-bit, single precision); this is the reference
 * side: benchmarks against the dense solve, tests, moving objects.
 *
 * V is either dense (SVD, CUR, ACA, Algorithm 6) or the 2MF/2MCE selector
 * V(e, patch[e]) = 1, applied as a per-patch sum / gather. Matrices are
 * row-major. Products use OpenBLAS (threads as the caller set them). */
#ifndef GI_RAD_LOWRANK_H
#define GI_RAD_LOWRANK_H

#include <stdint.h>

#include "gi_error.h"
#include "rad_factor.h"

typedef struct gi_rad_lowrank {
    uint32_t n, k;
    double *U;       /* n x k */
    double *V;       /* n x k, or NULL when patch[] is the selector */
    uint32_t *patch; /* n, when V is NULL */
} gi_rad_lowrank;

int gi_rad_lowrank_alloc(gi_rad_lowrank *lr, uint32_t n, uint32_t k, int dense_v, gi_error *err);
void gi_rad_lowrank_free(gi_rad_lowrank *lr);
/* The 2MF/2MCE factor in double: U = hits w, V the selector. */
int gi_rad_lowrank_from_factor(gi_rad_lowrank *lr, const gi_rad_factor *f, gi_error *err);

/* T = V^T X (X: n x m, T: k x m). */
void gi_rad_lowrank_vt(const gi_rad_lowrank *lr, const double *X, uint32_t m, double *T);
/* X = V T (T: k x m, X: n x m). */
void gi_rad_lowrank_v(const gi_rad_lowrank *lr, const double *T, uint32_t m, double *X);

/* One colour, m emission vectors (E, B: n x m; rho: n reflectances):
 *   B = E + R U (I_k - V^T R U)^-1 V^T E          (eq. 3.32)
 * Fails (GI_EINVAL) if I_k - V^T R U is singular. */
int gi_rad_lowrank_smw(const gi_rad_lowrank *lr, const double *rho, const double *E, uint32_t m,
                       double *B, gi_error *err);
/* B_{i+1} = E + R U (V^T B_i), B_0 = E (eq. 3.30), until the largest
 * relative residual over the m columns is <= tol. */
int gi_rad_lowrank_neumann(const gi_rad_lowrank *lr, const double *rho, const double *E, uint32_t m,
                           double tol, int max_iter, double *B, int *iterations, gi_error *err);
/* ||F - U V^T||_F for a dense n x n F (thesis Table 4.3). */
double gi_rad_lowrank_distance(const gi_rad_lowrank *lr, const double *F);

/* Indices of the k largest of values[0..n) in decreasing order (ties: the
 * smaller index first). */
void gi_rad_top_k(const double *values, uint32_t n, uint32_t k, uint32_t *out);

/* The dense reference: (I - R F) B = E for m right-hand sides (LAPACK
 * dgesv, O(n^3): for n up to a few thousand). */
int gi_rad_dense_solve(const double *F, uint32_t n, const double *rho, const double *E, uint32_t m,
                       double *B, gi_error *err);

/* Truncated SVD (thesis 3.2.2; LAPACK dgesdd): F = U S V^T once, then
 * F_k = (U_k S_k) V_k^T for any k (the thesis's Usvdk * Vsvdk'). */
typedef struct gi_rad_svd {
    uint32_t n;
    double *U, *S, *VT; /* n x n, n, n x n */
} gi_rad_svd;
int gi_rad_svd_compute(gi_rad_svd *s, const double *F, uint32_t n, gi_error *err);
int gi_rad_svd_truncate(const gi_rad_svd *s, uint32_t k, gi_rad_lowrank *lr, gi_error *err);
void gi_rad_svd_free(gi_rad_svd *s);

/* Maximal volume (Goreinov, Tyrtyshnikov et al.): k rows of the n x k
 * matrix A whose k x k submatrix has (locally) maximal |det|: start from
 * LU's pivots, then swap in any row whose coefficient in A A(I,:)^-1
 * exceeds 1 + tol in magnitude, until none does. */
int gi_rad_maxvol(const double *A, uint32_t n, uint32_t k, double tol, int max_swaps,
                  uint32_t *rows, gi_error *err);
/* CUR / pseudo-skeleton (thesis 3.2.3): columns J and rows I by
 * alternating maxvol (`sweeps` times, starting from the k columns of
 * largest norm), C = F(:, J), R = F(I, :), W = F(I, J);
 * U_k = C pinv(W), V_k = R^T (middle factor option 1 of the thesis). */
int gi_rad_cur(const double *F, uint32_t n, uint32_t k, int sweeps, gi_rad_lowrank *lr,
               gi_error *err);

/* Adaptive cross approximation with partial pivoting (Bebendorf 2000):
 * needs only rows and columns of F, one of each per rank, so it works
 * matrix-free from ray-cast rows (a column of F is a row scaled by areas,
 * by reciprocity). Stops at rank k or when the new cross's norm falls below
 * tol times the approximation's. */
typedef int (*gi_rad_vector_fn)(void *user, uint32_t index, double *out, gi_error *err);
int gi_rad_aca(gi_rad_vector_fn row, gi_rad_vector_fn col, void *user, uint32_t n, uint32_t k,
               double tol, gi_rad_lowrank *lr, gi_error *err);

#endif
