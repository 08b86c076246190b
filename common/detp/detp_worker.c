/* detp_worker: what a worker process does for a detp job. The discs, the
 * query order and the disc index are built once per job per process (on
 * the first task that needs them, timed and reported with it) and kept in
 * ctx->method_state; a batch is traced into memory, density-estimated and
 * dropped, so a worker holds one batch at a time. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp_method.h"
#include "gi_clock.h"
#include "gi_light.h"
#include "gi_published.h"
#include "gi_rng.h"
#include "gi_tiles.h"
#include "gi_worker_ctx.h"
#include "pt/pt.h"

static void worker_free(void *p)
{
    detp_worker *w = p;
    gi_detp_discs_free(&w->discs);
    free(w->order);
    gi_detp_octree_free(w->octree);
    gi_detp_embree_free(w->embree);
    gi_detp_accum_free(&w->acc);
    gi_detp_segments_free(&w->segs);
    free(w->inward);
    free(w->radiance);
    detp_anim_worker_free(w->anim);
    free(w);
}

detp_worker *detp_worker_state(gi_worker_ctx *ctx)
{
    if (!ctx->method_state) {
        ctx->method_state = gi_xcalloc(1, sizeof(detp_worker));
        ctx->method_state_free = worker_free;
    }
    return ctx->method_state;
}

int detp_worker_discs(gi_worker_ctx *ctx, detp_worker *w, gi_error *err)
{
    if (w->discs_ready)
        return 0;
    const gi_detp_params *p = ctx->job.params;
    if (gi_detp_discs_from_scene(&ctx->job.scene, p->disc_radius, &w->discs, err))
        return -1;
    /* Animations sum exactly, in fixed point (detp_anim_job.c). */
    int rc = gi_anim_moves_object(&p->anim)
                 ? gi_detp_accum_init_fixed(&w->acc, w->discs.count,
                                            gi_detp_fixed_unit(ctx->job.scene.total_power,
                                                               p->photon_count),
                                            err)
                 : gi_detp_accum_init(&w->acc, w->discs.count, err);
    if (rc) {
        gi_detp_discs_free(&w->discs);
        return -1;
    }
    w->discs_ready = 1;
    return 0;
}

static void need_inward(gi_worker_ctx *ctx, detp_worker *w)
{
    if (w->inward)
        return;
    w->inward = gi_xmalloc(((size_t)ctx->job.scene.vertex_count + 1) * sizeof *w->inward);
    gi_detp_inward_dirs(&ctx->job.scene, w->inward);
}

/* The per-job structures of the estimator. */
int detp_worker_index(gi_worker_ctx *ctx, detp_worker *w, gi_error *err)
{
    if (w->index_ready)
        return 0;
    const gi_detp_params *p = ctx->job.params;
    switch (p->estimator) {
    case GI_DETP_EST_SPHERE_CACHE:
    case GI_DETP_EST_MULTILIST:
        w->order = gi_detp_query_order(&w->discs, p->sc.order, ctx->job.seed, err);
        if (!w->order)
            return -1;
        break;
    case GI_DETP_EST_OCTREE:
        if (gi_detp_octree_build(&w->discs, &p->octree, &w->octree, err))
            return -1;
        break;
    case GI_DETP_EST_EMBREE:
        if (gi_detp_embree_build(ctx->rt.device, &w->discs, &w->embree, err))
            return -1;
        break;
    default:
        break;
    }
    w->index_ready = 1;
    return 0;
}

int detp_worker_estimate(gi_worker_ctx *ctx, detp_worker *w, gi_detp_stats *st, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    const gi_scene *s = &ctx->job.scene;
    switch (p->estimator) {
    case GI_DETP_EST_IMPACT_COUNT:
        return gi_detp_impact_count(s, &w->segs, &w->acc, st, err);
    case GI_DETP_EST_PHOTON_MAP:
        return gi_detp_photon_map(&w->discs, &w->segs, p->pm_k, p->pm_k_minus_one, &w->acc, st,
                                  err);
    case GI_DETP_EST_BASIC:
        gi_detp_basic(&w->discs, &w->segs, &w->acc, st);
        return 0;
    case GI_DETP_EST_SPHERE_CACHE:
        return gi_detp_sphere_cache(&w->discs, w->order, &w->segs, &p->sc, s->bbox_min,
                                    s->bbox_max, &w->acc, st, err);
    case GI_DETP_EST_MULTILIST:
        return gi_detp_multilist(&w->discs, w->order, &w->segs, &p->sc, s->bbox_min,
                                 s->bbox_max, &w->acc, st, err);
    case GI_DETP_EST_OCTREE:
        gi_detp_octree_estimate(w->octree, &w->segs, &w->acc, st);
        return 0;
    case GI_DETP_EST_EMBREE:
        gi_detp_embree_estimate(w->embree, &w->segs, &w->acc, st);
        return 0;
    }
    return gi_fail(err, GI_EINTERNAL, "detp: unknown estimator %d", (int)p->estimator);
}

static int run_batch(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    const gi_job *job = &ctx->job;
    const gi_detp_params *p = job->params;
    detp_task_in in;
    if (detp_task_decode(job, t, 0, &in, err))
        return -1;
    uint64_t p0 = in.p0, p1 = in.p1;
    detp_worker *w = detp_worker_state(ctx);
    detp_batch_result h;
    memset(&h, 0, sizeof h);
    double t0 = gi_now();
    if (detp_worker_discs(ctx, w, err) || detp_worker_index(ctx, w, err))
        return -1;
    double t1 = gi_now();
    gi_detp_tracer tr;
    gi_detp_tracer_init(&tr, &ctx->rt, &job->scene, job->seed, p->photon_count, p->max_bounces,
                        p->artifact == GI_DETP_AC_SECOND_HIT);
    uint64_t rays0 = ctx->rt.rays;
    w->segs.count = 0;
    for (uint64_t ph = p0; ph < p1; ph++) {
        gi_detp_trace_photon(&tr, ph, &w->segs);
        if (w->segs.count > 0xFFFFFFF0u)
            return gi_fail(err, GI_EINVAL, "detp: a batch of %llu photons made more than 2^32 "
                                           "segments; use a smaller detp.batch",
                           (unsigned long long)(p1 - p0));
    }
    gi_detp_set_extent(&w->segs, p->artifact, p->extent_eps);
    double t2 = gi_now();
    gi_detp_accum_clear(&w->acc);
    if (detp_worker_estimate(ctx, w, &h.stats, err))
        return -1;
    double t3 = gi_now();
    h.photons = p1 - p0;
    h.segments = w->segs.count;
    h.rays = ctx->rt.rays - rays0;
    h.build_seconds = t1 - t0;
    h.trace_seconds = t2 - t1;
    h.estimate_seconds = t3 - t2;
    /* The discs' energies become irradiance (over the disc area); the
     * impact count and the photon map produce irradiance already. */
    double scale = 1.0;
    if (p->estimator != GI_DETP_EST_IMPACT_COUNT && p->estimator != GI_DETP_EST_PHOTON_MAP)
        scale = 1.0 / (GI_PI * (double)w->discs.radius * (double)w->discs.radius);
    detp_encode_batch(&h, &w->acc, scale, result);
    /* The summary counts photons (the method's unit): batches are the only
     * tasks that add to it, not tiles' or the reference's samples. */
    ctx->stats.samples = h.photons;
    /* Give back the batch's memory if it was unusually large. */
    if (w->segs.cap > 4 * (w->segs.count + 1024)) {
        gi_detp_segments_free(&w->segs);
        gi_detp_segments_init(&w->segs);
    }
    return 0;
}

static int run_visibility(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    detp_worker *w = detp_worker_state(ctx);
    detp_task_in in;
    if (detp_worker_discs(ctx, w, err) ||
        detp_task_decode(&ctx->job, t, w->discs.count, &in, err))
        return -1;
    uint32_t v0 = in.a, v1 = in.b;
    need_inward(ctx, w);
    double t0 = gi_now();
    uint64_t rays0 = ctx->rt.rays;
    gi_buf body;
    gi_buf_init(&body);
    for (uint32_t i = v0; i < v1; i++)
        gi_buf_put_f32(&body, gi_detp_visible_fraction(&ctx->rt, &w->discs.d[i],
                                                       w->discs.radius, w->inward[i]));
    gi_buf_put_f64(result, gi_now() - t0);
    gi_buf_put_u64(result, ctx->rt.rays - rays0);
    gi_buf_put(result, body.data, body.len);
    gi_buf_free(&body);
    return 0;
}

static int run_reference(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    const gi_job *job = &ctx->job;
    const gi_detp_params *p = job->params;
    const gi_scene *s = &job->scene;
    uint32_t m = p->reference_vertices < s->vertex_count ? p->reference_vertices
                                                         : s->vertex_count;
    detp_task_in in;
    if (detp_task_decode(job, t, m, &in, err))
        return -1;
    uint32_t j0 = in.a, j1 = in.b;
    gi_pt_params pp;
    gi_pt_params_default(&pp);
    /* The photons' direct light is bounce 0; the path tracer counts the
     * irradiance point as its first bounce. */
    pp.max_bounces = p->max_bounces < 0 ? -1 : p->max_bounces + 1;
    gi_pt_tracer tr = {&ctx->rt, s, &pp, NULL};
    detp_worker *w = detp_worker_state(ctx);
    need_inward(ctx, w);
    /* A vertex on an edge where another surface meets its own (a wall's
     * top edge on the ceiling) is evaluated a hair inside its own
     * triangles: the limit of the irradiance from its own side. */
    float nudge = (float)(1e-4 * p->scene_size);
    double t0 = gi_now();
    uint64_t rays0 = ctx->rt.rays;
    gi_buf body;
    gi_buf_init(&body);
    for (uint32_t j = j0; j < j1; j++) {
        uint32_t v = detp_reference_vertex(j, m, s->vertex_count);
        gi_vec3 n = gi_normalize(s->normals[v]);
        double sum[3] = {0, 0, 0}, lum2 = 0;
        for (uint32_t k = 0; k < p->reference_spp; k++) {
            gi_rng rng;
            gi_rng_init(&rng, job->seed, DETP_STREAM_REFERENCE + v, k);
            gi_vec3 E = gi_pt_irradiance(&tr, gi_madd(s->positions[v], w->inward[v], nudge), n,
                                         &rng);
            sum[0] += E.x;
            sum[1] += E.y;
            sum[2] += E.z;
            double l = gi_luminance(E);
            lum2 += l * l;
        }
        gi_buf_put_f64s(&body, sum, 3);
        gi_buf_put_f64(&body, lum2);
    }
    gi_buf_put_f64(result, gi_now() - t0);
    gi_buf_put_u64(result, ctx->rt.rays - rays0);
    gi_buf_put(result, body.data, body.len);
    gi_buf_free(&body);
    return 0;
}

/* Image tiles: per-vertex radiance interpolated on the visible triangle
 * (eq. 3.8's barycentric interpolation), emission added. */
typedef struct shade_ctx {
    const gi_scene *scene;
    const float *radiance;
} shade_ctx;

static gi_vec3 shade(void *user, const gi_hit *h, gi_vec3 p, gi_vec3 wo)
{
    const shade_ctx *c = user;
    const uint32_t *ix = &c->scene->indices[3 * (size_t)h->tri];
    float w[3] = {1.0f - h->u - h->v, h->u, h->v};
    gi_vec3 L = gi_v3(0, 0, 0);
    for (int k = 0; k < 3; k++) {
        const float *r = &c->radiance[3 * (size_t)ix[k]];
        L = gi_add(L, gi_scale(gi_v3(r[0], r[1], r[2]), w[k]));
    }
    const gi_material *m = gi_scene_tri_material(c->scene, h->tri);
    return gi_add(L, gi_light_emitted(m, c->scene->tri_normal[h->tri], wo));
}

float *detp_radiance_decode(const gi_buf *blob, const char *hash, uint32_t nv, gi_error *err)
{
    gi_published_layout l = {"detp: published radiance", "vertex", "vertices", nv, 3};
    return gi_published_floats(blob, hash, &l, err);
}

static int run_tile(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    const gi_job *job = &ctx->job;
    const gi_detp_params *p = job->params;
    detp_task_in in;
    if (detp_task_decode(job, t, 0, &in, err))
        return -1;
    const char *hash = in.hash;
    detp_worker *w = detp_worker_state(ctx);
    if (strcmp(w->hash, hash) != 0) {
        const gi_buf *blob;
        if (gi_worker_blob(ctx, hash, &blob, err))
            return -1;
        float *rad = detp_radiance_decode(blob, hash, job->scene.vertex_count, err);
        if (!rad)
            return -1;
        free(w->radiance);
        w->radiance = rad;
        memcpy(w->hash, hash, GI_HASH_HEX);
    }
    double t0 = gi_now();
    uint64_t rays0 = ctx->rt.rays;
    gi_buf px;
    gi_buf_init(&px);
    shade_ctx sc = {&job->scene, w->radiance};
    gi_camera cam; /* the frame's (a still's: the job's) */
    gi_anim_camera(&p->anim, gi_job_camera(job), in.frame, &cam);
    int rc = t->kind == DETP_TASK_ANIM_TILE && gi_anim_moves_object(&p->anim)
                 ? detp_anim_render_tile(ctx, w, &in.tile, in.frame, &cam, shade, &sc, &px, err)
                 : gi_tile_render(&ctx->rt, job, &cam, &in.tile, p->image_spp, shade, &sc, &px,
                                  err);
    if (rc == 0) {
        gi_buf_put_f64(result, gi_now() - t0);
        gi_buf_put_u64(result, ctx->rt.rays - rays0);
        gi_buf_put(result, px.data, px.len);
    }
    gi_buf_free(&px);
    return rc;
}

int detp_run(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err)
{
    switch (task->kind) {
    case DETP_TASK_BATCH:
        return run_batch(ctx, task, result, err);
    case DETP_TASK_VISIBILITY:
        return run_visibility(ctx, task, result, err);
    case DETP_TASK_REFERENCE:
        return run_reference(ctx, task, result, err);
    case DETP_TASK_TILE:
    case DETP_TASK_ANIM_TILE:
        return run_tile(ctx, task, result, err);
    case DETP_TASK_ANIM_BATCH:
    case DETP_TASK_ANIM_UPDATE:
        return detp_anim_run(ctx, task, result, err);
    }
    return gi_fail(err, GI_EPROTO, "detp: unknown task kind %u", task->kind);
}
