/* rad_ff: ray-cast form factors, one row block at a time (the farm's task).
 *
 * For each element e of a block, its rays (rad_rays.h) are cast; a ray that
 * lands on the front face of element e' credits the ancestor of e' at the
 * tracked level (thesis eq. 3.50: F_e,node is the sum of F_e,e' over the
 * node's elements, so a hit on e' counts for every ancestor of e' at once).
 * Then F_e,node = hits / rays. Rays that leave the scene or land on a back
 * face carry energy out of the system (elements are one-sided).
 *
 * Error estimate: each row also carries d2 = sum over nodes of
 * (hits on even rays - hits on odd rays)^2. The halves are two independent
 * estimates, so |h_even - h_odd| / rays estimates the standard error of
 * hits / rays, and sqrt(sum d2 / sum h^2) the relative Frobenius error of
 * the sampled matrix. (Each half is less stratified than the whole, so this
 * errs on the high side.)
 *
 * A row block travels as, per element: u32 nnz, u32 escaped, u32 backface,
 * u64 d2, then nnz pairs (u32 node, u32 hits) in increasing node order. */
#ifndef GI_RAD_FF_H
#define GI_RAD_FF_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "gi_rt.h"
#include "rad_mesh.h"
#include "rad_rays.h"

typedef struct gi_rad_ff_opts {
    uint64_t seed;
    uint32_t level; /* tracked level, 0..L (L: element-to-element rows) */
} gi_rad_ff_opts;

/* Worker side: appends the rows of elements [e0, e1) to out. */
int gi_rad_ff_rows(gi_rt *rt, const gi_scene *s, const gi_rad_mesh *m, const gi_rad_strata *st,
                   const gi_rad_ff_opts *o, uint32_t e0, uint32_t e1, gi_buf *out, gi_error *err);

typedef struct gi_rad_ff_stats {
    uint64_t escaped, backface; /* rays lost */
    uint64_t d2, h2;            /* error estimate: sums of (h_even - h_odd)^2 and h^2 */
} gi_rad_ff_stats;

/* Receives decoded rows. */
typedef void (*gi_rad_ff_hit_fn)(void *user, uint32_t e, uint32_t node, uint32_t hits);

/* Coordinator side: checks and decodes the rows of [e0, e1) (nodes: the
 * tracked level's node count), calling hit() for every nonzero and adding
 * to *stats. Malformed input fails with GI_EPROTO. */
int gi_rad_ff_decode(const uint8_t *data, size_t len, uint32_t e0, uint32_t e1, uint32_t nodes,
                     uint32_t rays, gi_rad_ff_hit_fn hit, void *user, gi_rad_ff_stats *stats,
                     gi_error *err);

/* qsort comparison of uint32_t values. */
int gi_rad_cmp_u32(const void *a, const void *b);

/* In one process: the rows of every element as a dense count matrix
 * (counts[e * stride + node], zeroed first), for tests and benchmarks. */
int gi_rad_ff_dense(gi_rt *rt, const gi_scene *s, const gi_rad_mesh *m, const gi_rad_strata *st,
                    const gi_rad_ff_opts *o, uint16_t *counts, size_t stride,
                    gi_rad_ff_stats *stats, gi_error *err);

#endif
