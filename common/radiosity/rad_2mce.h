/* rad_2mce: 2MCE, "two meshes with spatial coherence" (thesis 3.6.3,
 * Algorithms 1-2): patches adapt to where the coherence of form factors
 * breaks down (surface junctions), between level 0 and max_level.
 *
 * Coherence metric, broad and partial (eq. 3.61) with |m_scene| = n (every
 * element) and the |m_p| = 4 samples being the node's children, element
 * form factors approximated by each child's mean:
 *
 *   eval(p) = 1/n sum_e sqrt( 1/4 sum_{i=1..4} (F_ep / c_p - F_e,ch_i / c_ch)^2 )
 *
 * A node whose eval exceeds the threshold is split: its four children
 * become patches. HalloParches (Algorithm 2) walks each tree bottom-up;
 * the sibling rule keeps patches triangles (if one child is or contains a
 * patch, its siblings become patches). The thesis's pseudocode does not
 * mark a node whose children became patches in the threshold branch
 * (lines 11-13); it is marked here, as the text requires, so that its
 * parent cannot become a patch overlapping them.
 *
 * The thesis tuned the threshold until 2MCE had the k of 2MF; so does
 * gi_rad_2mce_tune for a target k. */
#ifndef GI_RAD_2MCE_H
#define GI_RAD_2MCE_H

#include <stdint.h>

#include "gi_error.h"
#include "rad_mesh.h"
#include "rad_patches.h"

typedef struct gi_rad_2mce {
    uint32_t max_level; /* maxnivel: the tracked level T */
    uint32_t roots;
    double *metric;         /* eval(p) per node at levels 0..T-1, level by level */
    uint32_t *level_offset; /* T + 1 entries */
} gi_rad_2mce;

/* Computes eval(p) for every node above max_level from the counts at
 * max_level (n x stride). */
int gi_rad_2mce_metrics(gi_rad_2mce *c, const gi_rad_mesh *m, const uint16_t *counts, size_t stride,
                        uint32_t max_level, uint32_t rays, gi_error *err);
void gi_rad_2mce_free(gi_rad_2mce *c);

/* HalloParches with a threshold (nodes with eval > threshold are split). */
int gi_rad_2mce_select(const gi_rad_2mce *c, const gi_rad_mesh *m, double threshold,
                       gi_rad_patches *out, gi_error *err);
/* The threshold whose patch count is closest to target (ties: fewer
 * patches), and its patches. */
int gi_rad_2mce_tune(const gi_rad_2mce *c, const gi_rad_mesh *m, uint32_t target, double *threshold,
                     gi_rad_patches *out, gi_error *err);

#endif
