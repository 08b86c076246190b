/* rad_delta: the change of the form factors when one object moves, by
 * re-casting only the rays that can see it (rad_dynamic.h). */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "rad_dynamic.h"
#include "rad_ff.h"

typedef struct box {
    gi_vec3 lo, hi;
} box;

static box object_box(const gi_scene *s, uint32_t object)
{
    const gi_object *o = &s->objects[object];
    box b = {{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}};
    for (uint32_t v = o->first_vertex; v < o->first_vertex + o->vertex_count; v++) {
        b.lo = gi_min_v3(b.lo, s->positions[v]);
        b.hi = gi_max_v3(b.hi, s->positions[v]);
    }
    /* A margin: ray origins are offset off surfaces, and the boxes of flat
     * objects have no thickness. */
    gi_vec3 d = gi_sub(b.hi, b.lo);
    float pad = 1e-4f * gi_maxf(1.0f, gi_max3(d)) +
                1e-4f * gi_max3(gi_max_v3(gi_v3(fabsf(b.lo.x), fabsf(b.lo.y), fabsf(b.lo.z)),
                                          gi_v3(fabsf(b.hi.x), fabsf(b.hi.y), fabsf(b.hi.z))));
    b.lo = gi_sub(b.lo, gi_v3(pad, pad, pad));
    b.hi = gi_add(b.hi, gi_v3(pad, pad, pad));
    return b;
}

/* Slab test for the ray org + t dir, t >= 0. */
static int ray_hits_box(const box *b, gi_vec3 org, gi_vec3 dir)
{
    float t0 = 0.0f, t1 = FLT_MAX;
    for (int a = 0; a < 3; a++) {
        float o = gi_v3_get(org, a), d = gi_v3_get(dir, a);
        float lo = gi_v3_get(b->lo, a), hi = gi_v3_get(b->hi, a);
        if (d == 0.0f) {
            if (o < lo || o > hi)
                return 0;
            continue;
        }
        float ta = (lo - o) / d, tb = (hi - o) / d;
        if (ta > tb) {
            float t = ta;
            ta = tb;
            tb = t;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
        if (t0 > t1)
            return 0;
    }
    return 1;
}

/* The element a ray lands on (front face), or UINT32_MAX. */
static uint32_t cast(gi_rt *rt, const gi_scene *s, const gi_rad_mesh *m, gi_vec3 org, gi_vec3 dir)
{
    gi_hit h;
    if (!gi_rt_intersect(rt, org, dir, 0.0f, FLT_MAX, &h) ||
        gi_dot(dir, s->tri_normal[h.tri]) >= 0.0f)
        return UINT32_MAX;
    return gi_rad_mesh_locate(m, h.tri, h.u, h.v, NULL);
}

int gi_rad_delta(gi_rt *rt_i, const gi_scene *s_i, gi_rt *rt_f, const gi_scene *s_f,
                 const gi_rad_mesh *m, const gi_rad_strata *st, uint64_t seed, uint32_t object,
                 gi_rad_sparse *dF, gi_rad_delta_stats *stats, gi_error *err)
{
    memset(dF, 0, sizeof *dF);
    memset(stats, 0, sizeof *stats);
    if (object >= s_i->object_count || s_i->object_count != s_f->object_count ||
        s_i->triangle_count != s_f->triangle_count)
        return gi_fail(err, GI_EINVAL, "delta: the two states are not the same scene");
    uint32_t n = m->element_count;
    const gi_object *ob = &s_i->objects[object];
    box bi = object_box(s_i, object), bf = object_box(s_f, object);
    int32_t *count = gi_try_calloc(n, sizeof *count, err, "delta");
    uint32_t *touched = gi_try_malloc(2 * (size_t)st->rays * sizeof *touched, err, "delta");
    uint32_t *perm_i = gi_try_malloc((size_t)st->rays * sizeof *perm_i, err, "delta");
    uint32_t *perm_f = gi_try_malloc((size_t)st->rays * sizeof *perm_f, err, "delta");
    dF->n = n;
    dF->row_ptr = gi_try_calloc((size_t)n + 1, sizeof *dF->row_ptr, err, "delta");
    uint64_t cap = 1024;
    dF->col = gi_xmalloc(cap * sizeof *dF->col);
    dF->val = gi_xmalloc(cap * sizeof *dF->val);
    if (!count || !touched || !perm_i || !perm_f || !dF->row_ptr) {
        free(count), free(touched), free(perm_i), free(perm_f);
        gi_rad_sparse_free(dF);
        return -1;
    }
    for (uint32_t e = 0; e < n; e++) {
        uint32_t t = gi_rad_mesh_element_tri(m, e), nt = 0;
        int moving = t >= ob->first_triangle && t < ob->first_triangle + ob->triangle_count;
        gi_rad_element_rays ri, rf;
        gi_rad_element_rays_init(&ri, st, m, s_i, seed, e, perm_i);
        if (moving)
            gi_rad_element_rays_init(&rf, st, m, s_f, seed, e, perm_f);
        for (uint32_t j = 0; j < st->rays; j++) {
            gi_vec3 oi, di;
            gi_rad_element_ray(&ri, j, &oi, &di);
            gi_vec3 of = oi, df = di;
            if (moving)
                gi_rad_element_ray(&rf, j, &of, &df);
            else if (!ray_hits_box(&bi, oi, di) && !ray_hits_box(&bf, oi, di))
                continue; /* the same ray misses the object in both states */
            stats->recast++;
            uint32_t hi = cast(rt_i, s_i, m, oi, di), hf = cast(rt_f, s_f, m, of, df);
            if (hi == hf)
                continue;
            stats->changed++;
            if (hi != UINT32_MAX) {
                if (count[hi] == 0)
                    touched[nt++] = hi;
                count[hi]--;
            }
            if (hf != UINT32_MAX) {
                if (count[hf] == 0)
                    touched[nt++] = hf;
                count[hf]++;
            }
        }
        stats->rays += st->rays;
        /* Row e: the nonzero changes, in column order. */
        qsort(touched, nt, sizeof *touched, gi_rad_cmp_u32);
        for (uint32_t a = 0; a < nt; a++) {
            uint32_t c = touched[a];
            if (a > 0 && c == touched[a - 1])
                continue; /* listed twice: went to zero and back */
            if (count[c] != 0) {
                if (dF->nnz == cap) {
                    cap *= 2;
                    dF->col = gi_xrealloc(dF->col, cap * sizeof *dF->col);
                    dF->val = gi_xrealloc(dF->val, cap * sizeof *dF->val);
                }
                dF->col[dF->nnz] = c;
                dF->val[dF->nnz++] = (double)count[c] / st->rays;
            }
            count[c] = 0;
        }
        dF->row_ptr[e + 1] = dF->nnz;
    }
    free(count), free(touched), free(perm_i), free(perm_f);
    return 0;
}
