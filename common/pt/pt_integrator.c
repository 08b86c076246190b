/* pt_integrator: the path tracing estimator (see pt.h). */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "gi_bsdf.h"
#include "gi_light.h"
#include "pt.h"

/* A vertex of a path between the stages of its shading: what the first
 * stage (vertex_open) found and drew, the square roots and divisions
 * (vertex_roots), and what the last stage (vertex_close) needs of them.
 * Split so that a batch of paths runs each stage in turn: the long
 * latencies of independent vertices then overlap in the CPU. Every vertex
 * goes through the same three functions, so the arithmetic is the same
 * whether one path or many advance. */
typedef struct pt_shade {
    gi_vec3 p, ng_f;
    gi_bsdf bsdf;
    int has_light;        /* a point on an emitter was drawn (next-event estimation) */
    double light_pick;    /* the light sample's numbers (if has_light) */
    float light_u1, light_u2;
    gi_light_sample ls;   /* and the point they pick */
    gi_vec3 to_light;     /* ls.p - p */
    float dist2, dist, inv_dist; /* of to_light (if has_light) */
    float u1, u2;         /* the BSDF sample's numbers */
    gi_vec3 bsdf_wi, bsdf_weight; /* the BSDF sample */
    float bsdf_pdf;
} pt_shade;

/* The small steps below are inlined into each stage's loop: a call per
 * vertex and step cost ~3% of the tracer's time. */
#define PT_INLINE static inline __attribute__((always_inline))

/* Draws the numbers of the vertex's light sample (next-event estimation,
 * unless the strategy is BSDF sampling alone), then of its BSDF sample: a
 * path's order of random numbers is fixed. */
PT_INLINE void vertex_draw(const gi_pt_tracer *tr, gi_rng *rng, pt_shade *v)
{
    v->has_light = tr->params->strategy != GI_PT_BSDF;
    if (v->has_light) {
        v->light_pick = gi_rng_double(rng);
        v->light_u1 = gi_rng_float(rng);
        v->light_u2 = gi_rng_float(rng);
    }
    v->u1 = gi_rng_float(rng);
    v->u2 = gi_rng_float(rng);
}

/* The light sample's point and distance, and the BSDF sample. */
PT_INLINE void vertex_roots(const gi_pt_tracer *tr, pt_shade *v)
{
    if (v->has_light) {
        gi_light_sample_point(tr->scene, v->light_pick, v->light_u1, v->light_u2, &v->ls);
        v->to_light = gi_sub(v->ls.p, v->p);
        v->dist2 = gi_dot(v->to_light, v->to_light);
        v->dist = sqrtf(v->dist2);
        v->inv_dist = 1.0f / v->dist;
    }
    v->bsdf_weight = gi_bsdf_sample_mapped(&v->bsdf, gi_bsdf_map(v->u1, v->u2), &v->bsdf_wi,
                                           &v->bsdf_pdf);
}

/* Next-event estimation, second half: the shadow ray that decides whether
 * the emitter point's radiance counts, and *contrib, what it adds (MIS
 * weighted, before the path's throughput). Written for few divisions: this
 * runs once per vertex. Returns 0 if the sample cannot contribute. */
PT_INLINE int light_shadow(const gi_pt_tracer *tr, const pt_shade *v, gi_pt_shadow *sh,
                           gi_vec3 *contrib)
{
    const gi_light_sample *ls = &v->ls;
    if (!(v->dist2 > 0.0f))
        return 0;
    gi_vec3 wi = gi_scale(v->to_light, v->inv_dist);
    float cos_s = gi_dot(v->bsdf.n, wi);
    if (cos_s <= 0.0f || gi_dot(v->ng_f, wi) <= 0.0f)
        return 0;
    const gi_material *lm = gi_scene_tri_material(tr->scene, ls->tri);
    float cos_l = -gi_dot(ls->n, wi);
    if (cos_l == 0.0f || (cos_l < 0.0f && !lm->two_sided))
        return 0;
    float inv_cos_l = 1.0f / fabsf(cos_l);
    float pdf_light = ls->pdf_area * v->dist2 * inv_cos_l; /* per solid angle */
    if (!gi_rt_shadow_segment(v->p, v->ng_f, ls->p, v->dist, inv_cos_l, &sh->org, &sh->tfar))
        return 0;
    sh->dir = wi;
    gi_vec3 fl = gi_mul(gi_bsdf_eval(&v->bsdf, wi), lm->emission);
    if (tr->params->strategy != GI_PT_MIS) {
        *contrib = gi_scale(fl, cos_s / pdf_light);
    } else {
        /* Power heuristic folded in: f Le cos / p_l * p_l^2 / (p_l^2 + p_b^2). */
        float pdf_bsdf = gi_bsdf_pdf(&v->bsdf, wi);
        *contrib =
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

/* The vertex where the path's ray hit (h): emission gathered, and, unless
 * the path ends here (returns 0), the random numbers of its light and BSDF
 * samples drawn into *v. */
static int vertex_open(const gi_pt_tracer *tr, gi_pt_path *P, const gi_hit *h, pt_shade *v)
{
    const gi_scene *s = tr->scene;
    const gi_pt_params *prm = tr->params;
    const gi_material *m = gi_scene_tri_material(s, h->tri);
    gi_vec3 ng = s->tri_normal[h->tri];
    /* org + t dir is off the plane by ~1e-7 t: far below the 2e-5 relative
     * offset every new ray starts with. */
    v->p = gi_madd(P->org, P->dir, h->t);
    gi_vec3 wo = gi_neg(P->dir);
    float cos_o = gi_dot(ng, wo);
    v->ng_f = cos_o >= 0.0f ? ng : gi_neg(ng);

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
    v->bsdf = gi_bsdf_at(m, gi_scene_shading_normal(s, h->tri, h->u, h->v, v->ng_f));
    vertex_draw(tr, &P->rng, v);
    return 1;
}

/* The rest of an opened vertex: the shadow ray of next-event estimation
 * and the next ray. Returns GI_PT_SHADOW | GI_PT_CONTINUE flags. */
static int vertex_close(const gi_pt_tracer *tr, gi_pt_path *P, const pt_shade *v,
                        gi_pt_shadow *sh)
{
    const gi_pt_params *prm = tr->params;
    int flags = 0;
    gi_vec3 contrib;
    if (v->has_light && light_shadow(tr, v, sh, &contrib)) {
        sh->contrib = gi_mul(P->beta, contrib);
        flags |= GI_PT_SHADOW;
    }
    gi_vec3 wi = v->bsdf_wi;
    float pdf = v->bsdf_pdf;
    if (!(pdf > 0.0f) || gi_dot(wi, v->ng_f) <= 0.0f)
        return flags;
    P->beta = gi_mul(P->beta, v->bsdf_weight);
    /* Russian roulette without a branch on its coin (a branch would be
     * mispredicted at every other toss): a path that stops still gets the
     * next ray's fields (and beta may become inf for q = 0), but only its
     * L is read after it ends. */
    int go_on = 1;
    if (P->bounce + 1 >= prm->rr_depth) {
        float q = gi_rr_survival(P->beta);
        go_on = gi_rng_float(&P->rng) < q && (prm->max_bounces >= 0 ||
                                               P->bounce + 1 < GI_RR_MAX_PATH);
        P->beta = gi_scale(P->beta, 1.0f / q);
    }
    P->prev_pdf = pdf;
    P->org = gi_rt_offset(v->p, v->ng_f, wi);
    P->dir = wi;
    P->bounce++;
    return flags | (go_on ? GI_PT_CONTINUE : 0);
}

int gi_pt_vertex(const gi_pt_tracer *tr, gi_pt_path *P, const gi_hit *h, gi_pt_shadow *sh)
{
    pt_shade v;
    if (!vertex_open(tr, P, h, &v))
        return 0;
    vertex_roots(tr, &v);
    return vertex_close(tr, P, &v, sh);
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
    pt_shade v = {.p = p, .ng_f = n, .bsdf = white};
    vertex_draw(tr, rng, &v);
    vertex_roots(tr, &v);
    gi_pt_shadow sh;
    gi_vec3 contrib;
    if (v.has_light && light_shadow(tr, &v, &sh, &contrib) && !blocked(tr, &sh))
        L = contrib;
    gi_vec3 wi = v.bsdf_wi;
    float pdf = v.bsdf_pdf;
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

/* Vertices shaded together: enough independent work to fill the CPU's
 * window, little enough to stay in the first-level cache. */
#define PT_SHADE_BATCH 32

/* Grows wf to hold n paths' scratch (the old contents need not survive). */
static void wavefront_reserve(gi_pt_wavefront *wf, size_t n)
{
    if (n <= wf->cap)
        return;
    gi_pt_wavefront_free(wf);
    wf->live = gi_xmalloc(n * sizeof *wf->live);
    wf->owner = gi_xmalloc(n * sizeof *wf->owner);
    wf->hits = gi_xmalloc(n * sizeof *wf->hits);
    wf->hit_ok = gi_xmalloc(n);
    wf->sh = gi_xmalloc(n * sizeof *wf->sh);
    wf->cap = n;
}

void gi_pt_wavefront_free(gi_pt_wavefront *wf)
{
    free(wf->live);
    free(wf->owner);
    free(wf->hits);
    free(wf->hit_ok);
    free(wf->sh);
    memset(wf, 0, sizeof *wf);
}

void gi_pt_trace_paths(const gi_pt_tracer *tr, gi_pt_wavefront *wf, gi_pt_path *paths,
                       size_t n)
{
    wavefront_reserve(wf, n);
    uint32_t *live = wf->live, *owner = wf->owner;
    gi_hit *hits = wf->hits;
    uint8_t *hit_ok = wf->hit_ok;
    gi_pt_shadow *sh = wf->sh;
    pt_shade shade[PT_SHADE_BATCH];
    uint32_t opened[PT_SHADE_BATCH];
    size_t nlive = n;
    for (size_t i = 0; i < n; i++)
        live[i] = (uint32_t)i;
    while (nlive) {
        for (size_t k = 0; k < nlive; k++)
            hit_ok[k] = (uint8_t)trace(tr, &paths[live[k]], &hits[k]);
        size_t nsh = 0, next = 0;
        /* Shading, a batch of vertices at a time, each stage over the whole
         * batch. live[] is rewritten behind the batch being read. */
        for (size_t k0 = 0; k0 < nlive; k0 += PT_SHADE_BATCH) {
            size_t k1 = k0 + PT_SHADE_BATCH < nlive ? k0 + PT_SHADE_BATCH : nlive, m = 0;
            for (size_t k = k0; k < k1; k++)
                if (hit_ok[k] && vertex_open(tr, &paths[live[k]], &hits[k], &shade[m]))
                    opened[m++] = live[k];
            for (size_t j = 0; j < m; j++)
                vertex_roots(tr, &shade[j]);
            for (size_t j = 0; j < m; j++) {
                uint32_t i = opened[j];
                int flags = vertex_close(tr, &paths[i], &shade[j], &sh[nsh]);
                /* Branch-free appends: these flags are coin tosses. */
                owner[nsh] = i;
                nsh += (flags & GI_PT_SHADOW) != 0;
                live[next] = i;
                next += (flags & GI_PT_CONTINUE) != 0;
            }
        }
        /* A path's shadow ray of this bounce is settled before its next
         * emission is added: the same order of additions as one at a time. */
        for (size_t j = 0; j < nsh; j++) {
            /* L + 0 is L (L >= 0): no branch on the ray's outcome. */
            gi_vec3 add = blocked(tr, &sh[j]) ? gi_v3(0, 0, 0) : sh[j].contrib;
            paths[owner[j]].L = gi_add(paths[owner[j]].L, add);
        }
        nlive = next;
    }
}
