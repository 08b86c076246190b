/* detp_segments: the segment record (container, disc extent),
 * per-disc accumulators and estimator statistics. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp.h"

void gi_detp_segments_init(gi_detp_segments *s) { memset(s, 0, sizeof *s); }

void gi_detp_segments_free(gi_detp_segments *s)
{
    free(s->v);
    memset(s, 0, sizeof *s);
}

gi_detp_segment *gi_detp_segments_push(gi_detp_segments *s)
{
    if (s->count == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 1024;
        s->v = gi_xrealloc(s->v, s->cap * sizeof *s->v);
    }
    gi_detp_segment *g = &s->v[s->count++];
    memset(g, 0, sizeof *g);
    return g;
}

void gi_detp_set_extent(gi_detp_segments *s, gi_detp_artifact ac, float eps)
{
    for (size_t i = 0; i < s->count; i++) {
        gi_detp_segment *g = &s->v[i];
        g->t_end = g->t_hit + eps;
        /* Strictly before the surface behind (but never short of the
         * surface hit, should the two be closer than eps). */
        if (ac == GI_DETP_AC_SECOND_HIT && g->t_second - eps > g->t_end)
            g->t_end = g->t_second - eps;
    }
}

void gi_detp_discs_free(gi_detp_discs *d)
{
    free(d->d);
    memset(d, 0, sizeof *d);
}

int gi_detp_accum_init(gi_detp_accum *a, uint32_t count, gi_error *err)
{
    memset(a, 0, sizeof *a);
    a->energy = gi_try_calloc((size_t)count * 3 + 1, sizeof *a->energy, err, "disc energies");
    a->hits = gi_try_calloc((size_t)count + 1, sizeof *a->hits, err, "disc hit counts");
    if (!a->energy || !a->hits) {
        gi_detp_accum_free(a);
        return -1;
    }
    a->count = count;
    return 0;
}

int gi_detp_accum_init_fixed(gi_detp_accum *a, uint32_t count, double unit, gi_error *err)
{
    memset(a, 0, sizeof *a);
    if (!(unit > 0.0) || !isfinite(unit))
        return gi_fail(err, GI_EINVAL, "fixed-point accumulator: bad unit %g", unit);
    a->fixed = gi_try_calloc((size_t)count * 3 + 1, sizeof *a->fixed, err, "disc sums");
    a->hits = gi_try_calloc((size_t)count + 1, sizeof *a->hits, err, "disc hit counts");
    if (!a->fixed || !a->hits) {
        gi_detp_accum_free(a);
        return -1;
    }
    a->count = count;
    a->inv_unit = 1.0 / unit;
    a->sign = 1;
    return 0;
}

double gi_detp_fixed_unit(double total_power, uint64_t photons_total)
{
    return ldexp(total_power / (double)(photons_total ? photons_total : 1), -32);
}

void gi_detp_accum_clear(gi_detp_accum *a)
{
    if (a->energy)
        memset(a->energy, 0, (size_t)a->count * 3 * sizeof *a->energy);
    if (a->fixed)
        memset(a->fixed, 0, (size_t)a->count * 3 * sizeof *a->fixed);
    if (a->hits)
        memset(a->hits, 0, (size_t)a->count * sizeof *a->hits);
}

void gi_detp_accum_free(gi_detp_accum *a)
{
    free(a->energy);
    free(a->fixed);
    free(a->hits);
    memset(a, 0, sizeof *a);
}

/* The counters in a fixed order, for add / encode / decode. */
#define STATS_SCALARS(X)                                                                    \
    X(disc_tests) X(crossings) X(sphere_tests) X(queries) X(faults) X(spheres_built)        \
    X(inner_rays) X(evictions) X(node_visits) X(candidates) X(photons_found)

void gi_detp_stats_add(gi_detp_stats *into, const gi_detp_stats *s)
{
#define ADD(f) into->f += s->f;
    STATS_SCALARS(ADD)
#undef ADD
    if (s->max_level > into->max_level)
        into->max_level = s->max_level;
    if (s->max_spheres > into->max_spheres)
        into->max_spheres = s->max_spheres;
    for (int i = 0; i < GI_DETP_MAX_LEVELS; i++) {
        into->level_faults[i] += s->level_faults[i];
        into->level_rays[i] += s->level_rays[i];
    }
}

void gi_detp_stats_encode(const gi_detp_stats *s, gi_buf *out)
{
#define PUT(f) gi_buf_put_u64(out, s->f);
    STATS_SCALARS(PUT)
#undef PUT
    gi_buf_put_u64(out, s->max_level);
    gi_buf_put_u64(out, s->max_spheres);
    for (int i = 0; i < GI_DETP_MAX_LEVELS; i++) {
        gi_buf_put_u64(out, s->level_faults[i]);
        gi_buf_put_u64(out, s->level_rays[i]);
    }
}

void gi_detp_stats_decode(gi_reader *r, gi_detp_stats *s)
{
#define GET(f) s->f = gi_get_u64(r);
    STATS_SCALARS(GET)
#undef GET
    s->max_level = gi_get_u64(r);
    s->max_spheres = gi_get_u64(r);
    for (int i = 0; i < GI_DETP_MAX_LEVELS; i++) {
        s->level_faults[i] = gi_get_u64(r);
        s->level_rays[i] = gi_get_u64(r);
    }
}
