/* pt_integrator: the path tracing estimator (see pt.h). */
#include <float.h>

#include "gi_bsdf.h"
#include "gi_light.h"
#include "pt.h"

/* Next-event estimation: radiance from a sampled emitter point, weighted.
 * Written for few divisions and square roots: this runs once per vertex. */
static gi_vec3 sample_light(const gi_pt_tracer *tr, gi_vec3 p, gi_vec3 ng_f,
                            const gi_bsdf *bsdf, gi_rng *rng)
{
    const gi_scene *s = tr->scene;
    double us = gi_rng_double(rng);
    float u1 = gi_rng_float(rng), u2 = gi_rng_float(rng);
    gi_light_sample ls;
    gi_light_sample_point(s, us, u1, u2, &ls);
    gi_vec3 d = gi_sub(ls.p, p);
    float dist2 = gi_dot(d, d);
    if (!(dist2 > 0.0f))
        return gi_v3(0, 0, 0);
    float dist = sqrtf(dist2), inv_dist = 1.0f / dist;
    gi_vec3 wi = gi_scale(d, inv_dist);
    float cos_s = gi_dot(bsdf->n, wi);
    if (cos_s <= 0.0f || gi_dot(ng_f, wi) <= 0.0f)
        return gi_v3(0, 0, 0);
    const gi_material *lm = gi_scene_tri_material(s, ls.tri);
    float cos_l = -gi_dot(ls.n, wi);
    if (cos_l == 0.0f || (cos_l < 0.0f && !lm->two_sided))
        return gi_v3(0, 0, 0);
    float inv_cos_l = 1.0f / fabsf(cos_l);
    float pdf_light = ls.pdf_area * dist2 * inv_cos_l; /* per solid angle */
    gi_vec3 org;
    float tfar;
    if (!gi_rt_shadow_segment(p, ng_f, ls.p, dist, inv_cos_l, &org, &tfar))
        return gi_v3(0, 0, 0);
    if (tr->log)
        tr->log->ray(tr->log->user, org, wi, 0.0f, tfar, 1);
    if (gi_rt_occluded(tr->rt, org, wi, 0.0f, tfar))
        return gi_v3(0, 0, 0);
    gi_vec3 fl = gi_mul(gi_bsdf_eval(bsdf, wi), lm->emission);
    if (tr->params->strategy != GI_PT_MIS)
        return gi_scale(fl, cos_s / pdf_light);
    /* Power heuristic folded in: f Le cos / p_l * p_l^2 / (p_l^2 + p_b^2). */
    float pdf_bsdf = gi_bsdf_pdf(bsdf, wi);
    return gi_scale(fl, cos_s * pdf_light / (pdf_light * pdf_light + pdf_bsdf * pdf_bsdf));
}

gi_vec3 gi_pt_radiance(const gi_pt_tracer *tr, gi_vec3 org, gi_vec3 dir, gi_rng *rng)
{
    const gi_scene *s = tr->scene;
    const gi_pt_params *prm = tr->params;
    gi_vec3 L = gi_v3(0, 0, 0), beta = gi_v3(1, 1, 1);
    float prev_pdf = 0.0f;
    for (int bounce = 0;; bounce++) {
        gi_hit h;
        if (tr->log)
            tr->log->ray(tr->log->user, org, dir, 0.0f, FLT_MAX, 0);
        if (!gi_rt_intersect(tr->rt, org, dir, 0.0f, FLT_MAX, &h))
            break;
        const gi_material *m = gi_scene_tri_material(s, h.tri);
        gi_vec3 ng = s->tri_normal[h.tri];
        /* org + t dir is off the plane by ~1e-7 t: far below the 2e-5
         * relative offset every new ray starts with. */
        gi_vec3 p = gi_madd(org, dir, h.t);
        gi_vec3 wo = gi_neg(dir);
        float cos_o = gi_dot(ng, wo);
        gi_vec3 ng_f = cos_o >= 0.0f ? ng : gi_neg(ng);

        if (!gi_is_black(m->emission)) {
            gi_vec3 le = gi_light_emitted(m, ng, wo);
            if (!gi_is_black(le)) {
                if (bounce == 0 || prm->strategy == GI_PT_BSDF) {
                    L = gi_add(L, gi_mul(beta, le));
                } else if (prm->strategy == GI_PT_MIS && cos_o != 0.0f) {
                    /* Power heuristic against light sampling, whose density
                     * here is pdf_area t^2 / |cos_o|, times cos_o^2 above
                     * and below. */
                    float a = prev_pdf * cos_o, b = gi_light_pdf_area(s, m) * h.t * h.t;
                    L = gi_add(L, gi_scale(gi_mul(beta, le), a * a / (a * a + b * b)));
                }
            }
        }
        if (prm->max_bounces >= 0 && bounce >= prm->max_bounces)
            break;
        if (gi_is_black(m->diffuse))
            break;
        gi_bsdf bsdf = gi_bsdf_at(m, gi_bsdf_shading_normal(s, h.tri, h.u, h.v, ng_f));

        if (prm->strategy != GI_PT_BSDF)
            L = gi_add(L, gi_mul(beta, sample_light(tr, p, ng_f, &bsdf, rng)));

        gi_vec3 wi;
        float pdf;
        float u1 = gi_rng_float(rng), u2 = gi_rng_float(rng);
        gi_vec3 weight = gi_bsdf_sample(&bsdf, u1, u2, &wi, &pdf);
        if (!(pdf > 0.0f) || gi_dot(wi, ng_f) <= 0.0f)
            break;
        beta = gi_mul(beta, weight);
        if (bounce + 1 >= prm->rr_depth) {
            float q = gi_minf(0.95f, gi_max3(beta));
            if (!(gi_rng_float(rng) < q))
                break;
            beta = gi_scale(beta, 1.0f / q);
        }
        prev_pdf = pdf;
        org = gi_rt_offset(p, ng_f, wi);
        dir = wi;
    }
    return L;
}
