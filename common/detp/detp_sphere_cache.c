/* detp_sphere_cache: the Sphere Cache of [Lastra 02c] (thesis 1.6).
 *
 * A stack of nested spheres S_0 > S_1 > ... > S_k, radius r_i = r_0 Q^i,
 * each holding the segments that meet it, found by testing its parent's.
 * A disc entirely inside the innermost sphere is tested against that
 * sphere's segments only. Otherwise (a cache miss) spheres are popped until
 * one contains the disc (and so do all above it: a sphere centred near its
 * parent's edge reaches outside it, where it has no segments), and new ones centred on the disc are built below it
 * while the next radius still holds the disc (r Q >= d), the parent has at
 * least r_min segments and the level is below max_levels. S_0 encloses
 * everything and is never rebuilt; the first query builds the stack.
 *
 * Lists keep the segment order, so each disc's sum is added in segment
 * order, as in basic DETP: the two give identical energies. */
#include <math.h>
#include <stdlib.h>

#include "detp.h"
#include "detp_sphere.h"

typedef struct level {
    gi_vec3 c;
    float r;
    uint32_t *rays; /* unused at level 0: it holds every segment */
    size_t n, cap;
} level;

int gi_detp_sphere_cache(const gi_detp_discs *d, const uint32_t *order,
                         const gi_detp_segments *s, const gi_detp_sc_params *p, gi_vec3 lo,
                         gi_vec3 hi, gi_detp_accum *acc, gi_detp_stats *st, gi_error *err)
{
    gi_vec3 c;
    float r;
    gi_detp_sphere_root(lo, hi, d->radius, &c, &r);
    return gi_detp_sphere_cache_root(d, order, s, p, c, r, acc, st, err);
}

int gi_detp_sphere_cache_root(const gi_detp_discs *d, const uint32_t *order,
                              const gi_detp_segments *s, const gi_detp_sc_params *p,
                              gi_vec3 c0, float r0, gi_detp_accum *acc, gi_detp_stats *st,
                              gi_error *err)
{
    uint32_t max_levels = p->max_levels < GI_DETP_MAX_LEVELS - 1 ? p->max_levels
                                                                  : GI_DETP_MAX_LEVELS - 1;
    level lv[GI_DETP_MAX_LEVELS] = {{{0, 0, 0}, 0, NULL, 0, 0}};
    lv[0].c = c0;
    lv[0].r = r0;
    lv[0].n = s->count;
    float slack = gi_detp_sphere_slack(lv[0].r);
    uint32_t top = 0;
    int rc = 0, built = 0;
    for (uint32_t q = 0; q < d->count && rc == 0; q++) {
        uint32_t i = order ? order[q] : q;
        const gi_detp_disc *D = &d->d[i];
        /* The deepest sphere such that it and every sphere above it hold
         * the disc: a child centred near its parent's edge pokes out of
         * it, and its list only has segments that meet the parent. */
        uint32_t k = 0;
        while (k < top && gi_detp_sphere_holds(lv[k + 1].c, lv[k + 1].r, D->c, d->radius))
            k++;
        st->queries++;
        if (k < top || !built) {
            /* Miss: rebuild below S_k, centred on this disc. */
            built = 1;
            st->faults++;
            while (k < max_levels) {
                float r = lv[k].r * (float)p->q;
                if (r < d->radius || lv[k].n < p->r_min)
                    break;
                level *c = &lv[k + 1];
                if (c->cap < lv[k].n) {
                    uint32_t *nr = realloc(c->rays, lv[k].n * sizeof *nr);
                    if (!nr) {
                        rc = gi_fail(err, GI_ENOMEM, "sphere cache: out of memory at level %u",
                                     k + 1);
                        break;
                    }
                    c->rays = nr;
                    c->cap = lv[k].n;
                }
                c->c = D->c;
                c->r = r;
                c->n = 0;
                float rr = (r + slack) * (r + slack);
                if (k == 0) {
                    for (size_t j = 0; j < s->count; j++)
                        if (gi_detp_segment_meets_sphere(&s->v[j], c->c, rr))
                            c->rays[c->n++] = (uint32_t)j;
                } else {
                    for (size_t j = 0; j < lv[k].n; j++) {
                        uint32_t g = lv[k].rays[j];
                        if (gi_detp_segment_meets_sphere(&s->v[g], c->c, rr))
                            c->rays[c->n++] = g;
                    }
                }
                st->sphere_tests += lv[k].n;
                st->spheres_built++;
                k++;
                st->level_faults[k]++;
                st->level_rays[k] += c->n;
            }
            top = k;
            if (top > st->max_level)
                st->max_level = top;
            if (top + 1 > st->max_spheres)
                st->max_spheres = top + 1;
        }
        /* The disc against the innermost sphere's segments. */
        const level *in = &lv[top];
        st->inner_rays += in->n;
        st->disc_tests += in->n;
        if (top == 0) {
            for (size_t j = 0; j < s->count; j++)
                if (gi_detp_crosses(D, d->r2, &s->v[j])) {
                    gi_detp_accum_add(acc, i, &s->v[j]);
                    st->crossings++;
                }
        } else {
            for (size_t j = 0; j < in->n; j++) {
                const gi_detp_segment *g = &s->v[in->rays[j]];
                if (gi_detp_crosses(D, d->r2, g)) {
                    gi_detp_accum_add(acc, i, g);
                    st->crossings++;
                }
            }
        }
    }
    for (int k = 0; k < GI_DETP_MAX_LEVELS; k++)
        free(lv[k].rays);
    return rc;
}
