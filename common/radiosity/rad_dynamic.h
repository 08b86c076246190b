/* rad_dynamic: scenes with a moving object (thesis 3.4.5 and 4.5).
 *
 * The change of the form factors between state I and state F,
 * dF = F_F - F_I, is found by re-casting only the rays that can see the
 * object's old or new position (rad_delta.c): rays are keyed by (seed,
 * element, ray), so a ray of a static element is the same ray in both
 * states, and its hit can only change if it crosses the object's bounding
 * box at either position; the moving object's own elements cast all their
 * rays in both states. (The thesis assumes dF given.)
 *
 * Algorithm 6 approximates dF by k_delta whole columns, then k_delta whole
 * rows of what is left (column/row selection by 2-norm):
 *   dF ~ U_dc V_dc^T + U_dr V_dr^T = U_d V_d^T      (eq. 4.5; 2 k_delta columns)
 * with the pseudocode's transposed indices fixed (V_dc(I(i), i) = 1,
 * U_dr(I(i), i) = 1). The update solves with SMW twice (eqs. 3.38-3.43):
 *   Y = -U_I (I_k - V_I^T U_I)^-1
 *   W = V_d - V_I (Y^T V_d)
 *   Z = -(U_d - Y (V_I^T U_d)) (I - W^T U_d)^-1
 *   B = E - Y (V_I^T E) - Z (W^T E)
 * in colour, with R_c folded into U_I and U_d per colour (the thesis writes
 * the update with F factors; the system needs R F). */
#ifndef GI_RAD_DYNAMIC_H
#define GI_RAD_DYNAMIC_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_rt.h"
#include "rad_lowrank.h"
#include "rad_mesh.h"
#include "rad_rays.h"

/* A sparse n x n matrix, rows compressed (CSR). */
typedef struct gi_rad_sparse {
    uint32_t n;
    uint64_t nnz;
    uint64_t *row_ptr; /* n + 1 */
    uint32_t *col;
    double *val;
} gi_rad_sparse;

void gi_rad_sparse_free(gi_rad_sparse *s);

typedef struct gi_rad_delta_stats {
    uint64_t rays;    /* rays of all elements */
    uint64_t recast;  /* rays cast again in both states */
    uint64_t changed; /* rays whose hit changed */
} gi_rad_delta_stats;

/* dF at element level between the scene in state I (rt_i over s_i) and in
 * state F (rt_f over s_f), where only `object` differs. The mesh is the
 * same in both (its topology; positions come from each scene). */
int gi_rad_delta(gi_rt *rt_i, const gi_scene *s_i, gi_rt *rt_f, const gi_scene *s_f,
                 const gi_rad_mesh *m, const gi_rad_strata *st, uint64_t seed, uint32_t object,
                 gi_rad_sparse *dF, gi_rad_delta_stats *stats, gi_error *err);

/* The change at the coarse mesh's resolution: the 2MF/2MCE factor of F_F
 * minus that of F_I (same patches), dU(e, p) = sum over e' in p of
 * dF(e, e') / c_p, as the n x n matrix dU V^T (every column of a patch
 * equal). This is the thesis's Delta F~ from two 2MF factorizations
 * (Figs. 4.10-4.11), where changes concentrate in few rows and columns;
 * element-level dF from sampled rays is spread thin (every changed ray
 * moves 1/rays between two single elements). */
int gi_rad_delta_coarse(const gi_rad_sparse *dF, const uint32_t *patch, const uint32_t *patch_count,
                        uint32_t k, gi_rad_sparse *out, gi_error *err);

typedef struct gi_rad_alg6_stats {
    uint64_t nnz;      /* of dF */
    uint64_t captured; /* nonzeros inside the selected columns and rows */
} gi_rad_alg6_stats;

/* Algorithm 6: delta gets U_d, V_d (n x 2 k_delta, dense). */
int gi_rad_alg6(const gi_rad_sparse *dF, uint32_t k_delta, gi_rad_lowrank *delta,
                gi_rad_alg6_stats *stats, gi_error *err);

/* Eqs. 3.38-3.42 for one colour and m emission vectors (E, B: n x m). */
int gi_rad_update_solve(const gi_rad_lowrank *init, const gi_rad_lowrank *delta, const double *rho,
                        const double *E, uint32_t m, double *B, gi_error *err);

#endif
