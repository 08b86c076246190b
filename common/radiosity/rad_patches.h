/* rad_patches: coarse meshes (the k patches) as sets of tree nodes, and the
 * factor built from form-factor counts over them.
 *
 * Form factors are counted at one tracked level T of the forest: counts
 * (n x stride, row-major) holds hits(e, j) for the nodes j at level T. A
 * patch is a node at a level l <= T; its descendants at level T are the
 * contiguous columns [first, first + 4^(T-l)), so its counts are their sum
 * (eq. 3.50, additivity). Any set of patches that covers every tree exactly
 * once is a coarse mesh compatible with the elements.
 *
 *   2MF  (thesis 3.6.1, "two fixed meshes"): every node at one level.
 *   2MCE (thesis 3.6.3): adaptive, see rad_2mce.h. */
#ifndef GI_RAD_PATCHES_H
#define GI_RAD_PATCHES_H

#include <stdint.h>

#include "gi_error.h"
#include "rad_factor.h"
#include "rad_mesh.h"

typedef struct gi_rad_patch {
    uint32_t level, node;  /* the tree node */
    uint32_t first, count; /* its columns at the tracked level */
} gi_rad_patch;

typedef struct gi_rad_patches {
    uint32_t tracked_level; /* T */
    uint32_t k;
    gi_rad_patch *p; /* sorted by first: they partition [0, nodes at T) */
} gi_rad_patches;

void gi_rad_patches_free(gi_rad_patches *pt);
/* Appends the patch (level, node) (used by the selections). */
void gi_rad_patches_add(gi_rad_patches *pt, uint32_t level, uint32_t node);
/* Sorts the patches and checks that they cover the tracked level exactly
 * once (GI_EINTERNAL otherwise). */
int gi_rad_patches_finish(gi_rad_patches *pt, const gi_rad_mesh *m, gi_error *err);

/* 2MF: the nodes of `level` (tracked level = level). */
void gi_rad_2mf_patches(const gi_rad_mesh *m, uint32_t level, gi_rad_patches *pt);

/* The factor over these patches: hits(e, p) = sum of counts over p's
 * columns (eq. 3.53), P(e) from e's ancestor (eq. 3.54); reflectances are
 * left for the caller. */
int gi_rad_factor_from_counts(gi_rad_factor *f, const gi_rad_mesh *m, const uint16_t *counts,
                              size_t stride, uint32_t rays, const gi_rad_patches *pt,
                              gi_error *err);

#endif
