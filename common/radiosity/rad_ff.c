/* rad_ff: form-factor rows by ray casting. */
#include "rad_ff.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

int gi_rad_cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

int gi_rad_ff_rows(gi_rt *rt, const gi_scene *s, const gi_rad_mesh *m, const gi_rad_strata *st,
                   const gi_rad_ff_opts *o, uint32_t e0, uint32_t e1, gi_buf *out, gi_error *err)
{
    if (e0 > e1 || e1 > m->element_count || o->level > m->levels)
        return gi_fail(err, GI_EPROTO, "radiosity: element block [%u, %u) out of range", e0, e1);
    uint32_t nodes = gi_rad_mesh_nodes(m, o->level), shift = 2 * (m->levels - o->level);
    /* Per node: hits on even and odd rays; `touched` lists the nonzeros. */
    uint32_t *half = gi_try_calloc((size_t)nodes * 2, sizeof *half, err, "form-factor row");
    uint32_t *touched = gi_try_malloc((size_t)st->rays * sizeof *touched, err, "form-factor row");
    uint32_t *perm = gi_try_malloc((size_t)st->rays * sizeof *perm, err, "form-factor row");
    if (!half || !touched || !perm) {
        free(half);
        free(touched);
        free(perm);
        return -1;
    }
    for (uint32_t e = e0; e < e1; e++) {
        gi_rad_element_rays er;
        gi_rad_element_rays_init(&er, st, m, s, o->seed, e, perm);
        uint32_t nnz = 0, escaped = 0, backface = 0;
        for (uint32_t j = 0; j < st->rays; j++) {
            gi_vec3 org, dir;
            gi_rad_element_ray(&er, j, &org, &dir);
            gi_hit h;
            if (!gi_rt_intersect(rt, org, dir, 0.0f, FLT_MAX, &h)) {
                escaped++;
                continue;
            }
            if (gi_dot(dir, s->tri_normal[h.tri]) >= 0.0f) {
                backface++;
                continue;
            }
            uint32_t hit = gi_rad_mesh_locate(m, h.tri, h.u, h.v, NULL);
            if (hit == UINT32_MAX) {
                escaped++; /* a degenerate triangle: no element to receive it */
                continue;
            }
            uint32_t node = hit >> shift;
            if (half[2 * node] + half[2 * node + 1] == 0)
                touched[nnz++] = node;
            half[2 * node + (j & 1)]++;
        }
        /* Increasing node order: a scan of the counts when the row is
         * dense, else a sort of the nodes touched. */
        if ((uint64_t)nnz * 16 > nodes) {
            nnz = 0;
            for (uint32_t q = 0; q < nodes; q++)
                if (half[2 * q] + half[2 * q + 1])
                    touched[nnz++] = q;
        } else {
            qsort(touched, nnz, sizeof *touched, gi_rad_cmp_u32);
        }
        uint64_t d2 = 0;
        for (uint32_t i = 0; i < nnz; i++) {
            int64_t d = (int64_t)half[2 * touched[i]] - half[2 * touched[i] + 1];
            d2 += (uint64_t)(d * d);
        }
        uint8_t *p = gi_buf_grow(out, 20 + 8 * (size_t)nnz);
        gi_le_put_u32(p, nnz);
        gi_le_put_u32(p + 4, escaped);
        gi_le_put_u32(p + 8, backface);
        gi_le_put_u64(p + 12, d2);
        p += 20;
        for (uint32_t i = 0; i < nnz; i++, p += 8) {
            uint32_t node = touched[i];
            gi_le_put_u32(p, node);
            gi_le_put_u32(p + 4, half[2 * node] + half[2 * node + 1]);
            half[2 * node] = half[2 * node + 1] = 0;
        }
    }
    free(half);
    free(touched);
    free(perm);
    return 0;
}

int gi_rad_ff_decode(const uint8_t *data, size_t len, uint32_t e0, uint32_t e1, uint32_t nodes,
                     uint32_t rays, gi_rad_ff_hit_fn hit, void *user, gi_rad_ff_stats *stats,
                     gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, data, len, "radiosity form-factor rows");
    for (uint32_t e = e0; e < e1; e++) {
        uint32_t nnz = gi_get_u32(&r), escaped = gi_get_u32(&r), backface = gi_get_u32(&r);
        uint64_t d2 = gi_get_u64(&r);
        if (r.failed || nnz > rays || nnz > nodes || (uint64_t)nnz * 8 > r.left)
            return gi_fail(err, GI_EPROTO, "radiosity: row of element %u is malformed", e);
        uint64_t total = (uint64_t)escaped + backface, h2 = 0;
        uint32_t prev = 0;
        for (uint32_t i = 0; i < nnz; i++) {
            uint32_t node = gi_get_u32(&r), h = gi_get_u32(&r);
            if (node >= nodes || (i > 0 && node <= prev) || h == 0 || h > rays)
                return gi_fail(err, GI_EPROTO, "radiosity: row of element %u is malformed", e);
            prev = node;
            total += h;
            h2 += (uint64_t)h * h;
            hit(user, e, node, h);
        }
        if (total != rays)
            return gi_fail(err, GI_EPROTO,
                           "radiosity: row of element %u accounts for %llu rays, not %u", e,
                           (unsigned long long)total, rays);
        /* |h_even - h_odd| <= h for every node: a larger d2 is not one, and
         * could overflow the job's sum of them. */
        if (d2 > h2)
            return gi_fail(err, GI_EPROTO,
                           "radiosity: row of element %u has d2 %llu, above its sum of "
                           "squared hits %llu", e, (unsigned long long)d2,
                           (unsigned long long)h2);
        stats->escaped += escaped;
        stats->backface += backface;
        stats->d2 += d2;
        stats->h2 += h2;
    }
    return gi_reader_finish(&r, err);
}

typedef struct dense_sink {
    uint16_t *counts;
    size_t stride;
} dense_sink;

static void dense_put(void *user, uint32_t e, uint32_t node, uint32_t hits)
{
    dense_sink *d = user;
    d->counts[(size_t)e * d->stride + node] = (uint16_t)hits;
}

int gi_rad_ff_dense(gi_rt *rt, const gi_scene *s, const gi_rad_mesh *m, const gi_rad_strata *st,
                    const gi_rad_ff_opts *o, uint16_t *counts, size_t stride,
                    gi_rad_ff_stats *stats, gi_error *err)
{
    uint32_t nodes = gi_rad_mesh_nodes(m, o->level), block = 256;
    dense_sink d = {counts, stride};
    memset(counts, 0, (size_t)m->element_count * stride * sizeof *counts);
    memset(stats, 0, sizeof *stats);
    gi_buf b;
    gi_buf_init(&b);
    int rc = 0;
    for (uint32_t e0 = 0; e0 < m->element_count && rc == 0; e0 += block) {
        uint32_t e1 = m->element_count - e0 < block ? m->element_count : e0 + block;
        gi_buf_reset(&b);
        rc = gi_rad_ff_rows(rt, s, m, st, o, e0, e1, &b, err);
        if (rc == 0)
            rc =
                gi_rad_ff_decode(b.data, b.len, e0, e1, nodes, st->rays, dense_put, &d, stats, err);
    }
    gi_buf_free(&b);
    return rc;
}
