/* detp_photons: photon paths (thesis 1.1, Fig. 4.1).
 *
 * Emission. Photon p picks an emissive triangle with probability
 * proportional to its power (the scene's light CDF), at a van der Corput
 * point u_p = frac(phi_2(p) + shift): any run of consecutive photon indices
 * (a batch) is spread over the emitters in proportion to their power, as
 * thesis 1.1 allocates photons per light. The point is uniform on the
 * triangle, the direction cosine-distributed about its emitting face (a
 * two-sided emitter picks a face with probability 1/2). Every photon leaves
 * with the same power in luminance, Phi_T / N (thesis 3.3: "all photons
 * have the same power"), and RGB power Le * Phi_T / (lum(Le) N): the
 * emitter's colour.
 *
 * Reflection: absorb or reflect the whole photon (thesis 3.3; the survival
 * probability is not in the thesis). We survive with probability
 * q = lum(Phi * rho) / lum(Phi) and scale the RGB power by rho / q, so the
 * expected power after the bounce is Phi * rho in every channel (unbiased
 * per channel) and the photon's luminance never changes: equal-power
 * photons, whose colour drifts towards the surfaces they visit. For grey
 * surfaces this is plain absorb-or-reflect with q = rho. The new direction
 * is cosine-distributed about the shading normal on the side the photon
 * came from (diffuse BRDF sampling).
 *
 * Each segment also records the distance to the next intersection beyond
 * its hit along the same line (one more ray), for artifact control rule 1. */
#include <float.h>
#include <math.h>

#include "detp.h"
#include "gi_light.h"
#include "gi_rng.h"
#include "gi_sampling.h"

/* Bits of the index reversed: the base-2 radical inverse, in [0, 1). */
static double radical_inverse2(uint64_t i)
{
    i = (i << 32) | (i >> 32);
    i = ((i & 0x0000FFFF0000FFFFull) << 16) | ((i >> 16) & 0x0000FFFF0000FFFFull);
    i = ((i & 0x00FF00FF00FF00FFull) << 8) | ((i >> 8) & 0x00FF00FF00FF00FFull);
    i = ((i & 0x0F0F0F0F0F0F0F0Full) << 4) | ((i >> 4) & 0x0F0F0F0F0F0F0F0Full);
    i = ((i & 0x3333333333333333ull) << 2) | ((i >> 2) & 0x3333333333333333ull);
    i = ((i & 0x5555555555555555ull) << 1) | ((i >> 1) & 0x5555555555555555ull);
    return (double)(i >> 11) * (1.0 / 9007199254740992.0);
}

void gi_detp_tracer_init(gi_detp_tracer *tr, gi_rt *rt, const gi_scene *scene, uint64_t seed,
                         uint64_t photons_total, int max_bounces, int second_hit)
{
    tr->rt = rt;
    tr->scene = scene;
    tr->seed = seed;
    tr->photons_total = photons_total ? photons_total : 1;
    tr->max_bounces = max_bounces;
    tr->second_hit = second_hit;
    gi_rng r;
    gi_rng_init(&r, seed, GI_DETP_STREAM_PHOTON - 1, 0);
    tr->select_shift = gi_rng_double(&r);
    tr->frame = 0;
    tr->mobile_alone = NULL;
    tr->mobile_first = tr->mobile_count = 0;
}

void gi_detp_trace_photon(const gi_detp_tracer *tr, uint64_t photon, gi_detp_segments *out)
{
    const gi_scene *s = tr->scene;
    if (s->light_count == 0 || !(s->total_power > 0.0))
        return;
    gi_rng rng;
    gi_rng_init(&rng, tr->seed, GI_DETP_STREAM_PHOTON + photon, 0);
    double u = radical_inverse2(photon) + tr->select_shift;
    if (u >= 1.0)
        u -= 1.0;
    float u1 = gi_rng_float(&rng), u2 = gi_rng_float(&rng);
    gi_light_sample ls;
    gi_light_sample_point(s, u, u1, u2, &ls);
    const gi_material *m = gi_scene_tri_material(s, ls.tri);
    gi_vec3 n = ls.n;
    float side = gi_rng_float(&rng);
    if (m->two_sided && side < 0.5f)
        n = gi_neg(n);
    float d1 = gi_rng_float(&rng), d2 = gi_rng_float(&rng);
    gi_vec3 dir = gi_sample_cosine(n, d1, d2);
    float scale = (float)(s->total_power /
                          ((double)gi_luminance(m->emission) * (double)tr->photons_total));
    gi_vec3 power = gi_scale(m->emission, scale);
    gi_detp_trace_from(tr, photon, 0, gi_rt_offset(ls.p, n, dir), dir, power, out);
}

void gi_detp_trace_from(const gi_detp_tracer *tr, uint64_t photon, uint32_t bounce,
                        gi_vec3 org, gi_vec3 dir, gi_vec3 energy, gi_detp_segments *out)
{
    gi_detp_trace_from_hit(tr, photon, bounce, org, dir, energy, NULL, out);
}

/* The closest hit behind a hit on triangle hit_tri. On the mobile with no
 * other object near it, the mobile's own BVH first: what it hits is the
 * whole scene's hit (gi_detp_tracer.mobile_alone); only rays through the
 * whole scene are counted. */
static int hit_behind(const gi_detp_tracer *tr, uint32_t hit_tri, gi_vec3 org, gi_vec3 dir,
                      float tnear, gi_hit *h)
{
    if (tr->mobile_alone && hit_tri - tr->mobile_first < tr->mobile_count &&
        gi_rt_intersect_in(tr->rt, tr->mobile_alone, org, dir, tnear, FLT_MAX, h))
        return 1;
    return gi_rt_intersect(tr->rt, org, dir, tnear, FLT_MAX, h);
}

float gi_detp_second_t(const gi_detp_tracer *tr, gi_vec3 org, gi_vec3 dir, float t_hit,
                       uint32_t hit_tri)
{
    const gi_scene *s = tr->scene;
    gi_vec3 p = gi_madd(org, dir, t_hit);
    gi_vec3 ng = s->tri_normal[hit_tri];
    float c = fabsf(gi_dot(ng, dir));
    gi_hit h2;
    if (c >= 0.05f) {
        /* The segment's own line, from just behind its hit: where it next
         * meets a surface, exactly. (A ray started off the surface along
         * its normal runs beside the line, by an offset that grows with
         * the distance from the origin, and can pass a surface the line
         * crosses: a floor behind a thin wall then took light from the
         * wall's other side.) */
        float tnear = t_hit + gi_rt_offset_scale(p) / c;
        return hit_behind(tr, hit_tri, org, dir, tnear, &h2) ? h2.t : INFINITY;
    }
    /* Grazing: behind the surface along its normal, as the reflections
     * start, and the line's crossing of the plane met, when nearer. */
    gi_vec3 o2 = gi_rt_offset(p, gi_dot(ng, dir) < 0.0f ? ng : gi_neg(ng), dir);
    if (!hit_behind(tr, hit_tri, o2, dir, 0.0f, &h2))
        return INFINITY;
    float t = gi_dot(gi_sub(o2, org), dir) + h2.t;
    gi_vec3 q2 = gi_madd(o2, dir, h2.t), n2 = s->tri_normal[h2.tri];
    float den = gi_dot(dir, n2);
    if (fabsf(den) > 1e-3f) {
        float tp = gi_dot(gi_sub(q2, org), n2) / den;
        float reach = 4.0f * gi_maxf(gi_rt_offset_scale(o2), gi_rt_offset_scale(q2)) / fabsf(den);
        if (tp < t && t - tp <= reach)
            t = tp;
    }
    return t;
}

void gi_detp_trace_from_hit(const gi_detp_tracer *tr, uint64_t photon, uint32_t bounce,
                            gi_vec3 org, gi_vec3 dir, gi_vec3 energy, const gi_hit *first,
                            gi_detp_segments *out)
{
    const gi_scene *s = tr->scene;
    for (;;) {
        gi_detp_segment *g = gi_detp_segments_push(out);
        g->org = org;
        g->dir = dir;
        g->energy = energy;
        g->photon = photon;
        g->bounce = bounce;
        g->t_hit = g->t_second = g->t_end = INFINITY;
        g->hit_tri = GI_DETP_NO_HIT;
        gi_hit h;
        if (first) {
            h = *first;
            first = NULL;
        } else if (!gi_rt_intersect(tr->rt, org, dir, 0.0f, FLT_MAX, &h)) {
            return;
        }
        g->t_hit = g->t_end = h.t;
        g->hit_tri = h.tri;
        gi_vec3 p = gi_madd(org, dir, h.t);
        gi_vec3 ng = s->tri_normal[h.tri];
        gi_vec3 ng_f = gi_dot(ng, dir) < 0.0f ? ng : gi_neg(ng);
        if (tr->second_hit)
            g->t_second = gi_detp_second_t(tr, org, dir, h.t, h.tri);
        if ((tr->max_bounces >= 0 && (int64_t)bounce >= tr->max_bounces) ||
            bounce + 1 >= GI_DETP_MAX_PATH)
            return;
        const gi_material *m = gi_scene_tri_material(s, h.tri);
        float lum = gi_luminance(energy);
        gi_vec3 reflected = gi_mul(energy, m->diffuse);
        float q = lum > 0.0f ? gi_luminance(reflected) / lum : 0.0f;
        gi_rng rng;
        gi_rng_init(&rng, tr->seed, GI_DETP_STREAM_PHOTON + photon,
                    (tr->frame << 13) | (bounce + 1));
        if (!(gi_rng_float(&rng) < q))
            return; /* absorbed */
        energy = gi_scale(reflected, 1.0f / q);
        gi_vec3 ns = gi_scene_shading_normal(s, h.tri, h.u, h.v, ng_f);
        float d1 = gi_rng_float(&rng), d2 = gi_rng_float(&rng);
        gi_vec3 wi = gi_sample_cosine(ns, d1, d2);
        if (!(gi_dot(wi, ng_f) > 0.0f))
            return; /* below the geometric surface (shading normal near a silhouette) */
        org = gi_rt_offset(p, ng_f, wi);
        dir = wi;
        bounce++;
    }
}
