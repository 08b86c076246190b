/* rad_2mce: the coherence metric and HalloParches. */
#include "rad_2mce.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int gi_rad_2mce_metrics(gi_rad_2mce *c, const gi_rad_mesh *m, const uint16_t *counts, size_t stride,
                        uint32_t max_level, uint32_t rays, gi_error *err)
{
    memset(c, 0, sizeof *c);
    if (max_level > m->levels)
        return gi_fail(err, GI_EINVAL, "2mce: max_level %u is below the elements (levels %u)",
                       max_level, m->levels);
    uint32_t T = max_level;
    c->max_level = T;
    c->roots = m->root_count;
    c->level_offset = gi_xcalloc(T + 1, sizeof *c->level_offset);
    for (uint32_t l = 0; l < T; l++)
        c->level_offset[l + 1] = c->level_offset[l] + gi_rad_mesh_nodes(m, l);
    size_t total = c->level_offset[T];
    c->metric = gi_try_calloc(total ? total : 1, sizeof *c->metric, err, "2mce metric");
    /* Per row: the counts of every level (level T first, then sums). */
    double *h = gi_try_malloc((total + gi_rad_mesh_nodes(m, T)) * sizeof *h, err, "2mce metric");
    if (!c->metric || !h) {
        free(h);
        gi_rad_2mce_free(c);
        return -1;
    }
    double *hT = h + total; /* level T; level l at h + level_offset[l] */
    uint32_t nT = gi_rad_mesh_nodes(m, T);
    for (uint32_t e = 0; e < m->element_count; e++) {
        const uint16_t *row = counts + (size_t)e * stride;
        for (uint32_t j = 0; j < nT; j++)
            hT[j] = row[j];
        for (uint32_t l = T; l-- > 0;) {
            const double *child = l + 1 == T ? hT : h + c->level_offset[l + 1];
            double *parent = h + c->level_offset[l];
            /* c_p / c_ch = 4, and the 1 / (n rays c_ch) factor comes after. */
            double scale =
                1.0 / ((double)m->element_count * rays * (double)(1u << (2 * (m->levels - l - 1))));
            for (uint32_t q = 0; q < gi_rad_mesh_nodes(m, l); q++) {
                const double *ch = child + 4 * (size_t)q;
                double hp = ch[0] + ch[1] + ch[2] + ch[3], sq = 0.0;
                parent[q] = hp;
                for (int i = 0; i < 4; i++) {
                    double d = 0.25 * hp - ch[i];
                    sq += d * d;
                }
                if (sq > 0.0)
                    c->metric[c->level_offset[l] + q] += sqrt(0.25 * sq) * scale; /* eq. 3.61 */
            }
        }
    }
    free(h);
    return 0;
}

void gi_rad_2mce_free(gi_rad_2mce *c)
{
    free(c->metric);
    free(c->level_offset);
    memset(c, 0, sizeof *c);
}

/* HalloParches(node): 1 if the node is or contains a patch (tieneparches). */
static int hallo(const gi_rad_2mce *c, uint32_t level, uint32_t q, double threshold,
                 gi_rad_patches *out)
{
    if (level == c->max_level)
        return 0; /* lines 19-21: a node at maxnivel has no patches below it */
    int has[4], any = 0;
    for (int i = 0; i < 4; i++)
        any |= has[i] = hallo(c, level + 1, 4 * q + (uint32_t)i, threshold, out);
    if (any) { /* lines 7-10: the siblings of a patch become patches */
        for (int i = 0; i < 4; i++)
            if (!has[i])
                gi_rad_patches_add(out, level + 1, 4 * q + (uint32_t)i);
        return 1;
    }
    if (c->metric[c->level_offset[level] + q] > threshold) { /* lines 11-13 */
        for (int i = 0; i < 4; i++)
            gi_rad_patches_add(out, level + 1, 4 * q + (uint32_t)i);
        return 1; /* the fix: this node now contains patches */
    }
    return 0;
}

int gi_rad_2mce_select(const gi_rad_2mce *c, const gi_rad_mesh *m, double threshold,
                       gi_rad_patches *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    out->tracked_level = c->max_level;
    for (uint32_t r = 0; r < c->roots; r++)
        if (!hallo(c, 0, r, threshold, out))
            gi_rad_patches_add(out, 0, r); /* lines 15-16: a coherent tree is one patch */
    if (gi_rad_patches_finish(out, m, err)) {
        gi_rad_patches_free(out);
        return -1;
    }
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int gi_rad_2mce_tune(const gi_rad_2mce *c, const gi_rad_mesh *m, uint32_t target, double *threshold,
                     gi_rad_patches *out, gi_error *err)
{
    /* Candidate thresholds: -1 (split every node above max_level) and each
     * distinct metric value (split the nodes above it). The patch count
     * does not grow with the threshold, so bisect for the target. */
    size_t total = c->level_offset[c->max_level];
    double *v = gi_xmalloc((total + 1) * sizeof *v);
    memcpy(v + 1, c->metric, total * sizeof *v);
    qsort(v + 1, total, sizeof *v, cmp_double);
    v[0] = -1.0;
    size_t lo = 0, hi = total; /* k(v[lo]) > target >= k(v[hi]), if possible */
    gi_rad_patches p;
    if (gi_rad_2mce_select(c, m, v[hi], &p, err)) {
        free(v);
        return -1;
    }
    uint32_t k_hi = p.k;
    gi_rad_patches_free(&p);
    if (k_hi >= target) { /* even the coarsest mesh has enough patches */
        lo = hi;
    } else {
        while (hi - lo > 1) {
            size_t mid = lo + (hi - lo) / 2;
            if (gi_rad_2mce_select(c, m, v[mid], &p, err)) {
                free(v);
                return -1;
            }
            if (p.k > target)
                lo = mid;
            else
                hi = mid;
            gi_rad_patches_free(&p);
        }
    }
    /* The better of v[lo] (above target) and v[hi] (at or below). */
    gi_rad_patches a, b;
    if (gi_rad_2mce_select(c, m, v[lo], &a, err)) {
        free(v);
        return -1;
    }
    if (gi_rad_2mce_select(c, m, v[hi], &b, err)) {
        gi_rad_patches_free(&a);
        free(v);
        return -1;
    }
    int64_t da = (int64_t)a.k - target, db = (int64_t)target - b.k;
    if (da < 0)
        da = -da;
    if (db < 0)
        db = -db;
    if (da < db) {
        *out = a;
        *threshold = v[lo];
        gi_rad_patches_free(&b);
    } else {
        *out = b;
        *threshold = v[hi];
        gi_rad_patches_free(&a);
    }
    free(v);
    return 0;
}
