/* detp_anim_update: the ray set update of thesis Fig. 4.2, and the mobile's
 * vertices from scratch (thesis 4.5).
 *
 * A segment stays valid unless the mobile was its hit at the old pose or
 * the mobile at the new pose lies before its hit; only then is the rest of
 * its path retraced against the whole scene. The second test is a
 * ray/bounding-sphere check first and a ray against the mobile alone
 * (a scene of a few hundred triangles) only if that passes, so most
 * segments cost a dot product or two and never touch the full scene. A hit
 * counts only if strictly closer than the stored one (thesis [IMPL NOTE]). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp_anim.h"
#include "detp_sphere.h"
#include "gi_clock.h"

gi_detp_mobile_pose gi_detp_object_sphere(const gi_scene *s, uint32_t object)
{
    const gi_object *o = &s->objects[object];
    const gi_vec3 *p = &s->positions[o->first_vertex];
    gi_vec3 lo = gi_v3(INFINITY, INFINITY, INFINITY), hi = gi_scale(lo, -1.0f);
    for (uint32_t i = 0; i < o->vertex_count; i++) {
        lo = gi_min_v3(lo, p[i]);
        hi = gi_max_v3(hi, p[i]);
    }
    gi_detp_mobile_pose m = {gi_scale(gi_add(lo, hi), 0.5f), 0.0f};
    if (o->vertex_count == 0)
        m.c = gi_v3(0, 0, 0);
    for (uint32_t i = 0; i < o->vertex_count; i++)
        m.r = gi_maxf(m.r, gi_length(gi_sub(p[i], m.c)));
    return m;
}

float gi_detp_object_disc_reach(const gi_scene *s, uint32_t object, gi_detp_mobile_pose b,
                                float radius)
{
    const gi_object *o = &s->objects[object];
    double reach2 = 0.0;
    for (uint32_t i = 0; i < o->vertex_count; i++) {
        /* The disc point farthest from b.c: out from the centre along the
         * in-plane part of (vertex - b.c). */
        gi_vec3 v = s->positions[o->first_vertex + i];
        gi_vec3 n = gi_normalize(s->normals[o->first_vertex + i]);
        double dx = (double)v.x - b.c.x, dy = (double)v.y - b.c.y, dz = (double)v.z - b.c.z;
        double dn = dx * n.x + dy * n.y + dz * n.z;
        double d2 = dx * dx + dy * dy + dz * dz;
        double dt = sqrt(fmax(d2 - dn * dn, 0.0)) + radius;
        reach2 = fmax(reach2, dn * dn + dt * dt);
    }
    /* A relative margin far above the disc test's rounding; never beyond
     * the plain bound. */
    return gi_minf((float)(sqrt(reach2) * 1.0001), b.r * 1.0001f + radius);
}

int gi_detp_ray_may_meet(gi_vec3 org, gi_vec3 dir, float t0, float t1, gi_detp_mobile_pose m)
{
    gi_vec3 oc = gi_sub(m.c, org);
    float t = gi_dot(oc, dir);
    t = t < t0 ? t0 : (t > t1 ? t1 : t);
    gi_vec3 q = gi_sub(oc, gi_scale(dir, t));
    float scale = fabsf(t) + fabsf(oc.x) + fabsf(oc.y) + fabsf(oc.z) + m.r + 1.0f;
    float r = m.r + 1e-4f * scale;
    return gi_dot(q, q) <= r * r;
}

int gi_detp_anim_may_retrace(const gi_detp_segment *g, uint32_t m0, uint32_t mn,
                             gi_detp_mobile_pose pose)
{
    return (g->hit_tri != GI_DETP_NO_HIT && g->hit_tri - m0 < mn) ||
           gi_detp_ray_may_meet(g->org, g->dir, 0.0f, g->t_hit, pose);
}

/* The mobile at its new pose, strictly before the stored hit: that hit is
 * then the one the whole scene gives. Nothing static lies before the
 * stored hit (the ray is the one traced when it was stored, and the static
 * objects have not moved), and the mobile's own scene is the one the whole
 * scene holds as an identity instance, so its hits are the same bits
 * (gi_rt.h). */
static int mobile_hit_before(const gi_detp_tracer *tr, RTCScene mobile,
                             const gi_detp_segment *g, gi_hit *h)
{
    float tfar = isfinite(g->t_hit) ? g->t_hit : FLT_MAX;
    return gi_rt_intersect_in(tr->rt, mobile, g->org, g->dir, 0.0f, tfar, h) && h->t < g->t_hit;
}

/* t_second of a segment that keeps its hit, exactly as the tracer
 * computes it (detp_photons.c). */
static float second_distance(const gi_detp_tracer *tr, const gi_detp_segment *g)
{
    return gi_detp_second_t(tr, g->org, g->dir, g->t_hit, g->hit_tri);
}

static void append(gi_detp_segments *s, const gi_detp_segment *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        *gi_detp_segments_push(s) = v[i];
}

/* Room for n more without a doubling realloc's copies (next ends up about
 * as long as prev). */
static void reserve(gi_detp_segments *s, size_t n)
{
    if (s->cap - s->count < n) {
        s->cap = s->count + n;
        s->v = gi_xrealloc(s->v, s->cap * sizeof *s->v);
    }
}

static int same_float(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

int gi_detp_anim_update_path(const gi_detp_anim_update_in *in, const gi_detp_segment *path,
                             size_t n, int keep_unchanged, gi_detp_segments *out,
                             gi_detp_segments *old_list, gi_detp_segments *new_list,
                             gi_detp_update_stats *st)
{
    const gi_detp_tracer *tr = in->tracer;
    uint32_t m0 = in->mobile_first_tri, mn = in->mobile_tri_count;
    int changed = 0;
    st->paths++;
    if (in->still) {
        /* The scene is the one the path was traced in: no hit can differ
         * (and retracing a hit on the mobile would only draw new random
         * numbers: a held shot would flicker). */
        st->segments += n;
        if (keep_unchanged)
            append(out, path, n);
        return 0;
    }
    for (size_t k = 0; k < n; k++) {
        const gi_detp_segment *g = &path[k];
        st->segments++;
        int retrace = 0, known = 0;
        gi_hit first;
        if (g->hit_tri != GI_DETP_NO_HIT && g->hit_tri - m0 < mn) {
            st->old_hits++;
            retrace = 1;
            /* Hit again at the new pose before the old hit: that is the
             * new first hit, without a ray through the whole scene. */
            st->mobile_tests++;
            known = mobile_hit_before(tr, in->mobile_scene, g, &first);
        } else if (gi_detp_ray_may_meet(g->org, g->dir, 0.0f, g->t_hit, in->new_pose)) {
            st->sphere_passes++;
            st->mobile_tests++;
            retrace = known = mobile_hit_before(tr, in->mobile_scene, g, &first);
            st->mobile_hits += (uint64_t)retrace;
        }
        if (retrace) {
            /* Fig. 4.2: the old suffix out, a new one from this segment. */
            double t0 = in->timed ? gi_now() : 0.0;
            if (!keep_unchanged && !changed)
                append(out, path, k); /* the unchanged prefix */
            append(old_list, &path[k], n - k);
            size_t s0 = new_list->count;
            gi_detp_trace_from_hit(tr, g->photon, g->bounce, g->org, g->dir, g->energy,
                                   known ? &first : NULL, new_list);
            gi_detp_segments added = {new_list->v + s0, new_list->count - s0, 0};
            gi_detp_set_extent(&added, in->artifact, in->eps);
            append(out, added.v, added.count);
            st->paths_retraced++;
            st->old_segments += n - k;
            st->new_segments += added.count;
            if (in->timed)
                st->seconds_retrace += gi_now() - t0;
            return 1;
        }
        /* Rule 1: the surface behind the hit may be the mobile's, at
         * either pose. */
        if (tr->second_hit && isfinite(g->t_hit) &&
            (gi_detp_ray_may_meet(g->org, g->dir, g->t_hit, g->t_second, in->old_pose) ||
             gi_detp_ray_may_meet(g->org, g->dir, g->t_hit, g->t_second, in->new_pose))) {
            double t0 = in->timed ? gi_now() : 0.0;
            st->second_tests++;
            float t2 = second_distance(tr, g);
            if (!same_float(t2, g->t_second)) {
                st->second_changed++;
                if (!keep_unchanged && !changed)
                    append(out, path, k);
                changed = 1;
                *gi_detp_segments_push(old_list) = *g;
                gi_detp_segment *kept = gi_detp_segments_push(out);
                *kept = *g;
                kept->t_second = t2;
                gi_detp_segments one = {kept, 1, 0};
                gi_detp_set_extent(&one, in->artifact, in->eps);
                *gi_detp_segments_push(new_list) = *kept;
                st->old_segments++;
                st->new_segments++;
                if (in->timed)
                    st->seconds_retrace += gi_now() - t0;
                continue;
            }
            if (in->timed)
                st->seconds_retrace += gi_now() - t0;
        }
        if (keep_unchanged || changed)
            *gi_detp_segments_push(out) = *g;
    }
    return changed;
}

int gi_detp_anim_update(const gi_detp_anim_update_in *in, gi_detp_segments *next,
                        gi_detp_segments *old_list, gi_detp_segments *new_list,
                        gi_detp_update_stats *st, gi_error *err)
{
    const gi_detp_segment *prev = in->prev;
    size_t n = in->prev_count;
    double t_start = in->timed ? gi_now() : 0.0, retrace0 = st->seconds_retrace;
    reserve(next, n);
    for (size_t i = 0; i < n;) {
        uint64_t photon = prev[i].photon;
        size_t j = i + 1;
        while (j < n && prev[j].photon == photon) {
            if (prev[j].bounce != prev[j - 1].bounce + 1)
                return gi_fail(err, GI_EINTERNAL, "animation update: segment %zu breaks its path", j);
            j++;
        }
        if (j < n && prev[j].photon < photon)
            return gi_fail(err, GI_EINTERNAL, "animation update: photons out of order at %zu", j);
        gi_detp_anim_update_path(in, &prev[i], j - i, 1, next, old_list, new_list, st);
        i = j;
    }
    if (in->timed)
        st->seconds_test += gi_now() - t_start - (st->seconds_retrace - retrace0);
    return 0;
}

/* The object's discs at its current pose: the same as
 * gi_detp_discs_from_scene's, for its vertex range. */
static int mobile_discs(const gi_scene *s, const gi_object *o, float radius, gi_detp_discs *d,
                        gi_error *err)
{
    uint32_t n = o->vertex_count;
    *d = (gi_detp_discs){n, NULL, radius, radius * radius};
    d->d = gi_try_calloc((size_t)n + 1, sizeof *d->d, err, "mobile discs");
    if (!d->d)
        return -1;
    for (uint32_t i = 0; i < n; i++) {
        d->d[i].c = s->positions[o->first_vertex + i];
        d->d[i].n = gi_normalize(s->normals[o->first_vertex + i]);
    }
    return 0;
}

int gi_detp_anim_mobile_order(const gi_scene *s, uint32_t object, gi_detp_mobile_estimator how,
                              const gi_detp_sc_params *sc, uint32_t **out, gi_error *err)
{
    *out = NULL;
    if (object >= s->object_count || (how == GI_DETP_MOBILE_SPHERE_CACHE && !sc))
        return gi_fail(err, GI_EINTERNAL, "mobile order: bad object or parameters");
    if (how == GI_DETP_MOBILE_EMBREE)
        return 0;
    gi_detp_discs d;
    if (mobile_discs(s, &s->objects[object], 0.0f, &d, err))
        return -1;
    gi_detp_order kind = how == GI_DETP_MOBILE_SPHERE_CACHE ? sc->order : GI_DETP_ORDER_HILBERT;
    *out = gi_detp_query_order(&d, kind, 0, err);
    free(d.d);
    return *out ? 0 : -1;
}

int gi_detp_anim_mobile_estimate(const gi_scene *s, uint32_t object, float radius,
                                 const gi_detp_segments *segs, gi_detp_mobile_estimator how,
                                 const gi_detp_sc_params *sc, const uint32_t *order,
                                 RTCDevice device, gi_detp_accum *acc, gi_detp_stats *st,
                                 gi_error *err)
{
    if (object >= s->object_count || !acc->fixed ||
        (how == GI_DETP_MOBILE_SPHERE_CACHE && !sc) || (how == GI_DETP_MOBILE_EMBREE && !device))
        return gi_fail(err, GI_EINTERNAL, "mobile estimate: bad object, accumulator or index");
    const gi_object *o = &s->objects[object];
    uint32_t n = o->vertex_count;
    if ((uint64_t)o->first_vertex + n > acc->count)
        return gi_fail(err, GI_EINTERNAL, "mobile estimate: accumulator too small");
    memset(acc->fixed + 3 * (size_t)o->first_vertex, 0, 3 * (size_t)n * sizeof *acc->fixed);
    memset(acc->hits + o->first_vertex, 0, (size_t)n * sizeof *acc->hits);
    if (n == 0)
        return 0;
    gi_detp_discs d;
    if (mobile_discs(s, o, radius, &d, err))
        return -1;
    /* The object's slice of the global accumulator. */
    gi_detp_accum view = *acc;
    view.count = n;
    view.energy = NULL;
    view.fixed = acc->fixed + 3 * (size_t)o->first_vertex;
    view.hits = acc->hits + o->first_vertex;
    view.sign = 1;
    int rc = 0;
    if (how == GI_DETP_MOBILE_SPHERE_CACHE) {
        gi_detp_mobile_pose b = gi_detp_object_sphere(s, object);
        float r0 = b.r * 1.0001f + radius;
        /* Only segments that meet the root can cross a disc (the cache
         * would drop the others at its first level anyway). */
        gi_detp_segments near;
        gi_detp_segments_init(&near);
        float rr = r0 + gi_detp_sphere_slack(r0);
        rr *= rr;
        for (size_t j = 0; j < segs->count; j++)
            if (gi_detp_segment_meets_sphere(&segs->v[j], b.c, rr))
                *gi_detp_segments_push(&near) = segs->v[j];
        uint32_t *own = order ? NULL : gi_detp_query_order(&d, sc->order, 0, err);
        const uint32_t *q = order ? order : own;
        rc = q ? gi_detp_sphere_cache_root(&d, q, &near, sc, b.c, r0, &view, st, err) : -1;
        free(own);
        gi_detp_segments_free(&near);
    } else if (how == GI_DETP_MOBILE_LANES) {
        gi_detp_lanes_estimate(&d, order, segs, &view, st);
    } else {
        gi_detp_embree_index *x = NULL;
        rc = gi_detp_embree_build(device, &d, &x, err);
        if (rc == 0)
            gi_detp_embree_estimate(x, segs, &view, st);
        gi_detp_embree_free(x);
    }
    free(d.d);
    return rc;
}
