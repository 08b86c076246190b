/* quad_region: region records and the engine (see quad_region.h). */
#include "quad_region.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_method.h"
#include "gi_rng.h"
#include "quad_splat.h"

int gi_quad_engine_init(gi_quad_engine *e, const gi_quad_rule *rule, gi_quad_axis_rule axis_rule,
                        const gi_quad_image *image, const gi_quad_integrand *fn, gi_error *err)
{
    memset(e, 0, sizeof *e);
    e->rule = rule;
    e->axis_rule = axis_rule;
    e->image = *image;
    e->fn = *fn;
    size_t p = rule->points;
    e->pts = gi_try_malloc(p * rule->dims * sizeof(double), err, "quadrature points");
    e->vals = gi_try_malloc(p * rule->channels * sizeof(double), err, "quadrature values");
    e->idx = gi_try_malloc(p * sizeof(size_t), err, "quadrature points");
    if (!e->pts || !e->vals || !e->idx ||
        (image->width > 0 &&
         gi_quad_accum_init(&e->scratch, image->width, image->height, rule->channels, err))) {
        gi_quad_engine_free(e);
        return -1;
    }
    return 0;
}

void gi_quad_engine_free(gi_quad_engine *e)
{
    for (uint32_t i = 0; i < e->nchunks; i++) {
        free(e->chunks[i]);
        free(e->chunk_samples[i]);
    }
    free(e->chunks);
    free(e->chunk_samples);
    free(e->free_slots);
    free(e->pts);
    free(e->vals);
    free(e->idx);
    gi_quad_accum_free(&e->scratch);
    memset(e, 0, sizeof *e);
}

static gi_quad_region *alloc_region(gi_quad_engine *e, gi_error *err)
{
    uint32_t slot;
    if (e->nfree > 0) {
        slot = e->free_slots[--e->nfree];
    } else {
        if (e->used == e->nchunks * GI_QUAD_CHUNK) {
            size_t per = e->rule->points * (size_t)e->rule->channels;
            gi_quad_region *c = gi_try_calloc(GI_QUAD_CHUNK, sizeof *c, err, "regions");
            double *f = gi_try_malloc(GI_QUAD_CHUNK * per * sizeof(double), err,
                                      "region samples");
            if (!c || !f || e->nchunks == UINT32_MAX / GI_QUAD_CHUNK) {
                free(c);
                free(f);
                return NULL;
            }
            e->chunks = gi_xrealloc(e->chunks, (e->nchunks + 1) * sizeof *e->chunks);
            e->chunk_samples =
                gi_xrealloc(e->chunk_samples, (e->nchunks + 1) * sizeof *e->chunk_samples);
            e->free_slots =
                gi_xrealloc(e->free_slots, (size_t)(e->nchunks + 1) * GI_QUAD_CHUNK * sizeof(uint32_t));
            for (uint32_t i = 0; i < GI_QUAD_CHUNK; i++) {
                c[i].f = f + i * per;
                c[i].slot = e->nchunks * GI_QUAD_CHUNK + i;
            }
            e->chunks[e->nchunks] = c;
            e->chunk_samples[e->nchunks] = f;
            e->nchunks++;
        }
        slot = e->used++;
    }
    e->live++;
    gi_quad_region *r = gi_quad_region_at(e, slot);
    r->live = 1;
    return r;
}

void gi_quad_region_release(gi_quad_engine *e, gi_quad_region *r)
{
    r->live = 0;
    e->free_slots[e->nfree++] = r->slot;
    e->live--;
}

uint64_t gi_quad_box_id(const double *lo, const double *hi, int dims)
{
    uint64_t h = 0x51ED270B27A1F3C5ull;
    for (int d = 0; d < dims; d++) {
        uint64_t a, b;
        memcpy(&a, &lo[d], 8);
        memcpy(&b, &hi[d], 8);
        h = gi_mix64(h ^ a);
        h = gi_mix64(h + b);
    }
    return h;
}

/* Estimate, errors, axis and interpolant from the samples. */
static void analyse(gi_quad_engine *e, gi_quad_region *r)
{
    const gi_quad_rule *rule = e->rule;
    gi_quad_summary *s = &r->s;
    gi_quad_analysis a;
    gi_quad_rule_analyse(rule, e->axis_rule, r->f, s->lo, s->hi, &a);
    memcpy(s->est, a.est, sizeof(double) * rule->channels);
    s->axis = gi_quad_split_axis(&e->image, rule->dims, &a, s->lo, s->hi);
    s->id = gi_quad_box_id(s->lo, s->hi, rule->dims);
    gi_quad_interp_build(rule, &a, s->lo, s->hi, &s->interp);
    s->err_raw = a.err_raw;
    int px, py;
    gi_quad_pixel_span(&e->image, s->lo, s->hi, &px, &py);
    if (e->image.width > 0 && px * py > 1) {
        /* The reconstruction error (quad_region.h). */
        gi_quad_interp d;
        gi_quad_interp_coarse_diff(&s->interp, s->lo, s->hi, &d);
        gi_quad_splat(&d, s->lo, s->hi, 1.0, &e->scratch);
        s->err_raw += gi_quad_accum_take_l1(&e->scratch) /
                      ((double)e->image.width * (double)e->image.height);
    }
    s->err = gi_quad_region_error(&e->image, s->err_raw, s->lo, s->hi);
}

gi_quad_region *gi_quad_region_new(gi_quad_engine *e, const double *lo, const double *hi,
                                   gi_error *err)
{
    gi_quad_region *r = alloc_region(e, err);
    if (!r)
        return NULL;
    const gi_quad_rule *rule = e->rule;
    memset(&r->s, 0, sizeof r->s);
    memcpy(r->s.lo, lo, sizeof(double) * rule->dims);
    memcpy(r->s.hi, hi, sizeof(double) * rule->dims);
    gi_quad_rule_points(rule, lo, hi, e->pts);
    e->fn.eval(e->fn.user, rule->points, e->pts, r->f);
    e->evals += rule->points;
    analyse(e, r);
    return r;
}

int gi_quad_region_split(gi_quad_engine *e, const gi_quad_region *r, gi_quad_region *child[2],
                         gi_error *err)
{
    const gi_quad_rule *rule = e->rule;
    int axis = r->s.axis, nc = rule->channels;
    if (axis < 0)
        return gi_fail(err, GI_EINTERNAL, "region cannot be split");
    child[0] = child[1] = NULL;
    for (int side = 0; side < 2; side++) {
        gi_quad_region *c = alloc_region(e, err);
        if (!c) {
            if (side == 1)
                gi_quad_region_release(e, child[0]);
            return -1;
        }
        memset(&c->s, 0, sizeof c->s);
        memcpy(c->s.lo, r->s.lo, sizeof(double) * rule->dims);
        memcpy(c->s.hi, r->s.hi, sizeof(double) * rule->dims);
        double mid = 0.5 * (r->s.lo[axis] + r->s.hi[axis]);
        if (side == 0)
            c->s.hi[axis] = mid;
        else
            c->s.lo[axis] = mid;
        size_t n = gi_quad_rule_child(rule, r->f, axis, side, c->s.lo, c->s.hi, c->f, e->pts,
                                      e->idx);
        e->fn.eval(e->fn.user, n, e->pts, e->vals);
        e->evals += n;
        for (size_t i = 0; i < n; i++)
            memcpy(c->f + e->idx[i] * nc, e->vals + i * nc, sizeof(double) * nc);
        analyse(e, c);
        child[side] = c;
    }
    return 0;
}

size_t gi_quad_summary_bytes(const gi_quad_rule *rule)
{
    size_t nodes = (size_t)rule->nodes * rule->nodes;
    return 8 + 8 + 8 + 4 + 16 * (size_t)rule->dims + 8 * (size_t)rule->channels * (1 + nodes);
}

void gi_quad_summary_put(gi_buf *b, const gi_quad_summary *s, const gi_quad_rule *rule)
{
    gi_buf_put_u64(b, s->id);
    gi_buf_put_f64(b, s->err);
    gi_buf_put_f64(b, s->err_raw);
    gi_buf_put_u32(b, (uint32_t)s->axis);
    gi_buf_put_f64s(b, s->lo, (size_t)rule->dims);
    gi_buf_put_f64s(b, s->hi, (size_t)rule->dims);
    gi_buf_put_f64s(b, s->est, (size_t)rule->channels);
    gi_buf_put_f64s(b, s->interp.v, (size_t)rule->nodes * rule->nodes * rule->channels);
}

int gi_quad_summary_get(gi_reader *r, const gi_quad_rule *rule, gi_quad_summary *s,
                        gi_error *err)
{
    memset(s, 0, sizeof *s);
    int n = rule->dims, nc = rule->channels;
    size_t nv = (size_t)rule->nodes * rule->nodes * nc;
    s->id = gi_get_u64(r);
    s->err = gi_get_f64(r);
    s->err_raw = gi_get_f64(r);
    s->axis = (int32_t)gi_get_u32(r);
    gi_get_f64s(r, s->lo, (size_t)n);
    gi_get_f64s(r, s->hi, (size_t)n);
    gi_get_f64s(r, s->est, (size_t)nc);
    gi_get_f64s(r, s->interp.v, nv);
    s->interp.n = rule->nodes;
    s->interp.channels = nc;
    if (r->failed)
        return gi_fail(err, GI_EPROTO, "%s: truncated region", r->what);
    /* Estimates and errors are summed (splats, totals): within the bound
     * that keeps the sums finite (gi_method.h). */
    int ok = s->axis >= -1 && s->axis < n && gi_result_summable(s->err_raw) &&
             s->err_raw >= 0 && gi_result_summable(s->err) && s->err >= 0;
    for (int d = 0; d < n && ok; d++)
        ok = s->lo[d] >= 0.0 && s->hi[d] <= 1.0 && s->lo[d] < s->hi[d];
    for (int c = 0; c < nc && ok; c++)
        ok = gi_result_summable(s->est[c]);
    for (size_t i = 0; i < nv && ok; i++)
        ok = gi_result_summable(s->interp.v[i]);
    if (!ok || s->id != gi_quad_box_id(s->lo, s->hi, n))
        return gi_fail(err, GI_EPROTO, "%s: invalid region", r->what);
    return 0;
}
