/* pt_integrator: the path tracing estimator (see pt.h). */
#include <float.h>
#include <stdlib.h>

#include "gi_bsdf.h"
#include "gi_light.h"
#include "pt.h"

/* Next-event estimation: a point on an emitter, and the shadow ray that
 * decides whether its (weighted) radiance counts. Written for few divisions
 * and square roots: this runs once per vertex. Returns 0 if the sample
 * cannot contribute. */
static int sample_light(const gi_pt_tracer *tr, gi_vec3 p, gi_vec3 ng_f, const gi_bsdf *bsdf,
                        gi_rng *rng, gi_pt_shadow *sh)
{
    const gi_scene *s = tr->scene;
    double us = gi_rng_double(rng);
    float u1 = gi_rng_float(rng), u2 = gi_rng_float(rng);
    gi_light_sample ls;
    gi_light_sample_point(s, us, u1, u2, &ls);
    gi_vec3 d = gi_sub(ls.p, p);
    float dist2 = gi_dot(d, d);
    if (!(dist2 > 0.0f))
        return 0;
    float dist = sqrtf(dist2), inv_dist = 1.0f / dist;
    gi_vec3 wi = gi_scale(d, inv_dist);
    float cos_s = gi_dot(bsdf->n, wi);
    if (cos_s <= 0.0f || gi_dot(ng_f, wi) <= 0.0f)
        return 0;
    const gi_material *lm = gi_scene_tri_material(s, ls.tri);
    float cos_l = -gi_dot(ls.n, wi);
    if (cos_l == 0.0f || (cos_l < 0.0f && !lm->two_sided))
        return 0;
    float inv_cos_l = 1.0f / fabsf(cos_l);
    float pdf_light = ls.pdf_area * dist2 * inv_cos_l; /* per solid angle */
    if (!gi_rt_shadow_segment(p, ng_f, ls.p, dist, inv_cos_l, &sh->org, &sh->tfar))
        return 0;
    sh->dir = wi;
    gi_vec3 fl = gi_mul(gi_bsdf_eval(bsdf, wi), lm->emission);
    if (tr->params->strategy != GI_PT_MIS) {
        sh->contrib = gi_scale(fl, cos_s / pdf_light);
    } else {
        /* Power heuristic folded in: f Le cos / p_l * p_l^2 / (p_l^2 + p_b^2). */
        float pdf_bsdf = gi_bsdf_pdf(bsdf, wi);
        sh->contrib =
            gi_scale(fl, cos_s * pdf_light / (pdf_light * pdf_light + pdf_bsdf * pdf_bsdf));
    }
    return 1;
}

void gi_pt_path_start(gi_pt_path *P, gi_vec3 org, gi_vec3 dir, const gi_rng *rng)
{
    P->org = org;
    P->dir = dir;
    P->beta = gi_v3(1, 1, 1);
    P->L = gi_v3(0, 0, 0);
    P->prev_pdf = 0.0f;
    P->bounce = 0;
    P->rng = *rng;
}

int gi_pt_vertex(const gi_pt_tracer *tr, gi_pt_path *P, const gi_hit *h, gi_pt_shadow *sh)
{
    const gi_scene *s = tr->scene;
    const gi_pt_params *prm = tr->params;
    const gi_material *m = gi_scene_tri_material(s, h->tri);
    gi_vec3 ng = s->tri_normal[h->tri];
    /* org + t dir is off the plane by ~1e-7 t: far below the 2e-5 relative
     * offset every new ray starts with. */
    gi_vec3 p = gi_madd(P->org, P->dir, h->t);
    gi_vec3 wo = gi_neg(P->dir);
    float cos_o = gi_dot(ng, wo);
    gi_vec3 ng_f = cos_o >= 0.0f ? ng : gi_neg(ng);
    int flags = 0;

    if (!gi_is_black(m->emission)) {
        gi_vec3 le = gi_light_emitted(m, ng, wo);
        if (!gi_is_black(le)) {
            if (P->bounce == 0 || prm->strategy == GI_PT_BSDF) {
                P->L = gi_add(P->L, gi_mul(P->beta, le));
            } else if (prm->strategy == GI_PT_MIS && cos_o != 0.0f) {
                /* Power heuristic against light sampling, whose density here
                 * is pdf_area t^2 / |cos_o|, times cos_o^2 above and below. */
                float a = P->prev_pdf * cos_o, b = gi_light_pdf_area(s, m) * h->t * h->t;
                P->L = gi_add(P->L, gi_scale(gi_mul(P->beta, le), a * a / (a * a + b * b)));
            }
        }
    }
    if ((prm->max_bounces >= 0 && P->bounce >= prm->max_bounces) || gi_is_black(m->diffuse))
        return 0;
    gi_bsdf bsdf = gi_bsdf_at(m, gi_scene_shading_normal(s, h->tri, h->u, h->v, ng_f));

    if (prm->strategy != GI_PT_BSDF && sample_light(tr, p, ng_f, &bsdf, &P->rng, sh)) {
        sh->contrib = gi_mul(P->beta, sh->contrib);
        flags |= GI_PT_SHADOW;
    }

    gi_vec3 wi;
    float pdf;
    float u1 = gi_rng_float(&P->rng), u2 = gi_rng_float(&P->rng);
    gi_vec3 weight = gi_bsdf_sample(&bsdf, u1, u2, &wi, &pdf);
    if (!(pdf > 0.0f) || gi_dot(wi, ng_f) <= 0.0f)
        return flags;
    P->beta = gi_mul(P->beta, weight);
    if (P->bounce + 1 >= prm->rr_depth) {
        float q = gi_minf(0.95f, gi_max3(P->beta));
        if (!(gi_rng_float(&P->rng) < q))
            return flags;
        P->beta = gi_scale(P->beta, 1.0f / q);
    }
    P->prev_pdf = pdf;
    P->org = gi_rt_offset(p, ng_f, wi);
    P->dir = wi;
    P->bounce++;
    return flags | GI_PT_CONTINUE;
}

static inline int trace(const gi_pt_tracer *tr, const gi_pt_path *P, gi_hit *h)
{
    if (tr->log)
        tr->log->ray(tr->log->user, P->org, P->dir, 0.0f, FLT_MAX, 0);
    return gi_rt_intersect(tr->rt, P->org, P->dir, 0.0f, FLT_MAX, h);
}

static inline int blocked(const gi_pt_tracer *tr, const gi_pt_shadow *sh)
{
    if (tr->log)
        tr->log->ray(tr->log->user, sh->org, sh->dir, 0.0f, sh->tfar, 1);
    return gi_rt_occluded(tr->rt, sh->org, sh->dir, 0.0f, sh->tfar);
}

/* Follows one path to its end, shadow rays tested as they come. */
static void run_path(const gi_pt_tracer *tr, gi_pt_path *P)
{
    gi_hit h;
    while (trace(tr, P, &h)) {
        gi_pt_shadow sh;
        int flags = gi_pt_vertex(tr, P, &h, &sh);
        if ((flags & GI_PT_SHADOW) && !blocked(tr, &sh))
            P->L = gi_add(P->L, sh.contrib);
        if (!(flags & GI_PT_CONTINUE))
            break;
    }
}

gi_vec3 gi_pt_radiance(const gi_pt_tracer *tr, gi_vec3 org, gi_vec3 dir, gi_rng *rng)
{
    gi_pt_path P;
    gi_pt_path_start(&P, org, dir, rng);
    run_path(tr, &P);
    *rng = P.rng;
    return P.L;
}

gi_vec3 gi_pt_irradiance(const gi_pt_tracer *tr, gi_vec3 p, gi_vec3 n, gi_rng *rng)
{
    /* E = pi L_o of a white (rho = 1) Lambertian surface at p: the same
     * light sampling and BSDF sampling (MIS) as at any path vertex, p being
     * the path's first scattering vertex. */
    gi_bsdf white = {gi_v3(1, 1, 1), n};
    gi_vec3 L = gi_v3(0, 0, 0);
    if (tr->params->max_bounces == 0)
        return L;
    gi_pt_shadow sh;
    if (tr->params->strategy != GI_PT_BSDF && sample_light(tr, p, n, &white, rng, &sh) &&
        !blocked(tr, &sh))
        L = sh.contrib;
    float u1 = gi_rng_float(rng), u2 = gi_rng_float(rng), pdf;
    gi_vec3 wi;
    gi_bsdf_sample(&white, u1, u2, &wi, &pdf);
    if (pdf > 0.0f) {
        gi_pt_path P;
        gi_pt_path_start(&P, gi_rt_offset(p, n, wi), wi, rng);
        P.bounce = 1;
        P.prev_pdf = pdf;
        run_path(tr, &P);
        *rng = P.rng;
        L = gi_add(L, P.L);
    }
    return gi_scale(L, (float)GI_PI);
}

void gi_pt_trace_paths(const gi_pt_tracer *tr, gi_pt_path *paths, size_t n)
{
    uint32_t *live = gi_xmalloc(n * sizeof *live), *owner = gi_xmalloc(n * sizeof *owner);
    gi_hit *hits = gi_xmalloc(n * sizeof *hits);
    uint8_t *hit_ok = gi_xmalloc(n);
    gi_pt_shadow *sh = gi_xmalloc(n * sizeof *sh);
    size_t nlive = n;
    for (size_t i = 0; i < n; i++)
        live[i] = (uint32_t)i;
    while (nlive) {
        for (size_t k = 0; k < nlive; k++)
            hit_ok[k] = (uint8_t)trace(tr, &paths[live[k]], &hits[k]);
        size_t nsh = 0, next = 0;
        for (size_t k = 0; k < nlive; k++) {
            if (!hit_ok[k])
                continue;
            uint32_t i = live[k];
            int flags = gi_pt_vertex(tr, &paths[i], &hits[k], &sh[nsh]);
            if (flags & GI_PT_SHADOW)
                owner[nsh++] = i;
            if (flags & GI_PT_CONTINUE)
                live[next++] = i;
        }
        /* A path's shadow ray of this bounce is settled before its next
         * emission is added: the same order of additions as one at a time. */
        for (size_t j = 0; j < nsh; j++)
            if (!blocked(tr, &sh[j]))
                paths[owner[j]].L = gi_add(paths[owner[j]].L, sh[j].contrib);
        nlive = next;
    }
    free(live);
    free(owner);
    free(hits);
    free(hit_ok);
    free(sh);
}
