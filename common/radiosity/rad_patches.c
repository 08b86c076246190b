/* rad_patches: coarse meshes as node sets; factors from counts. */
#include "rad_patches.h"

#include <stdlib.h>
#include <string.h>

#include "rad_kernel.h"

void gi_rad_patches_free(gi_rad_patches *pt)
{
    free(pt->p);
    memset(pt, 0, sizeof *pt);
}

void gi_rad_patches_add(gi_rad_patches *pt, uint32_t level, uint32_t node)
{
    /* Grow in powers of two: k is at most the tracked level's node count. */
    if ((pt->k & (pt->k - 1)) == 0)
        pt->p = gi_xrealloc(pt->p, (pt->k ? 2 * (size_t)pt->k : 1) * sizeof *pt->p);
    uint32_t span = 1u << (2 * (pt->tracked_level - level));
    pt->p[pt->k++] = (gi_rad_patch){level, node, node * span, span};
}

static int by_first(const void *a, const void *b)
{
    uint32_t x = ((const gi_rad_patch *)a)->first, y = ((const gi_rad_patch *)b)->first;
    return x < y ? -1 : x > y;
}

int gi_rad_patches_finish(gi_rad_patches *pt, const gi_rad_mesh *m, gi_error *err)
{
    qsort(pt->p, pt->k, sizeof *pt->p, by_first);
    uint32_t next = 0;
    for (uint32_t i = 0; i < pt->k; i++) {
        if (pt->p[i].first != next)
            return gi_fail(err, GI_EINTERNAL,
                           "radiosity: patches overlap or leave a gap at node %u", next);
        next += pt->p[i].count;
    }
    if (next != gi_rad_mesh_nodes(m, pt->tracked_level))
        return gi_fail(err, GI_EINTERNAL, "radiosity: patches do not cover the mesh");
    return 0;
}

void gi_rad_2mf_patches(const gi_rad_mesh *m, uint32_t level, gi_rad_patches *pt)
{
    memset(pt, 0, sizeof *pt);
    pt->tracked_level = level;
    uint32_t nodes = gi_rad_mesh_nodes(m, level);
    pt->p = gi_xmalloc((size_t)nodes * sizeof *pt->p);
    for (uint32_t q = 0; q < nodes; q++)
        pt->p[q] = (gi_rad_patch){level, q, q, 1};
    pt->k = nodes;
}

int gi_rad_factor_from_counts(gi_rad_factor *f, const gi_rad_mesh *m, const uint16_t *counts,
                              size_t stride, uint32_t rays, const gi_rad_patches *pt, gi_error *err)
{
    uint32_t n = m->element_count, T = pt->tracked_level;
    if (gi_rad_factor_alloc(f, n, pt->k, rays, err))
        return -1;
    uint32_t nodes = gi_rad_mesh_nodes(m, T);
    uint32_t *owner = gi_try_malloc((size_t)nodes * sizeof *owner, err, "radiosity patches");
    if (!owner) {
        gi_rad_factor_free(f);
        return -1;
    }
    for (uint32_t p = 0; p < pt->k; p++)
        for (uint32_t j = 0; j < pt->p[p].count; j++)
            owner[pt->p[p].first + j] = p;
    for (uint32_t e = 0; e < n; e++) {
        const uint16_t *c = counts + (size_t)e * stride;
        uint16_t *h = f->hits + (size_t)e * f->k_pad;
        for (uint32_t p = 0; p < pt->k; p++) {
            uint32_t sum = 0; /* at most rays: a ray credits one node per level */
            for (uint32_t j = 0; j < pt->p[p].count; j++)
                sum += c[pt->p[p].first + j];
            h[p] = (uint16_t)sum;
        }
        f->patch[e] = owner[gi_rad_mesh_ancestor(m, e, T)];
    }
    free(owner);
    if (gi_rad_factor_finish(f, err)) {
        gi_rad_factor_free(f);
        return -1;
    }
    return 0;
}
