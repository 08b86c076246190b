/* detp_method: photon paths + DETP as a farm method (coordinator side).
 *
 * plan: photon batches (a batch is a range of photon indices: the same
 * range always gives the same paths), plus, if asked, tasks that measure
 * the discs' visible area (artifact control rule 2) and tasks that
 * path-trace the irradiance at some vertices for comparison. run
 * (detp_worker.c) traces a batch and density-estimates it against the
 * discs, returning the irradiance contribution per vertex. merge adds, in
 * task order. finish turns irradiance into radiance (L = rho E / pi,
 * eq. 4.2), publishes it and plans image tiles; when those are merged it
 * writes the image, the PLY, the binary float file and the report. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp_method.h"
#include "gi_clock.h"
#include "gi_log.h"
#include "gi_outputs.h"
#include "gi_published.h"
#include "gi_tiles.h"
#include "gi_worker_ctx.h"
#include "pt/pt.h"

static int wants_image(const gi_job *job)
{
    return gi_job_output(job, "exr") || gi_job_output(job, "png");
}

/* A camera path with nothing moving: the lighting is baked once (a still
 * bake) and seen from each frame's camera. */
static int camera_only(const gi_detp_params *p)
{
    return p->anim.enabled && !gi_anim_moves_object(&p->anim);
}

static int detp_parse(gi_job *job, const cJSON *params, gi_jv *v)
{
    gi_detp_params *p = gi_xcalloc(1, sizeof *p);
    job->params = p;
    if (gi_detp_parse_params(p, params, v))
        return -1;
    if (p->anim.camera_count && !wants_image(job))
        return gi_jv_fail(v, "detp.animation.camera",
                          "a camera path needs an image output (\"exr\" or \"png\")");
    job->keeps_batches = gi_anim_moves_object(&p->anim);
    /* "auto" photons: their batches are counted once the scene says how many. */
    double batches = p->photons > 0 ? ceil((double)p->photons / (double)p->batch) : 0;
    return gi_job_check_tasks(v, "detp.batch", batches, "%lld photons in batches of %lld",
                              (long long)p->photons, (long long)p->batch) ||
           gi_job_check_tasks(v, "detp.tile", gi_tiles_count(job->width, job->height, p->tile),
                              "%d x %d pixels in tiles of %d", job->width, job->height, p->tile);
}

/* Runs on the coordinator and in every worker, so both see the same
 * refined mesh and derived parameters; warnings are the coordinator's (and
 * gi validate's, gi submit's). */
static int detp_check_scene(gi_job *job, gi_error *err)
{
    gi_detp_params *p = job->params;
    if (gi_detp_resolve_params(p, &job->scene, job->file, err))
        return -1;
    if (p->anim.enabled)
        job->frame_count = p->anim.frames; /* gi validate says how many */
    if (job->on_worker)
        return 0;
    gi_anim_warn_keys(&p->anim, &job->scene, job->file);
    /* "auto" discs are the mesh's own spacing: on an unsubdivided scene of
     * big faces that is a blurred, dark-edged bake, and nothing else says so.
     * Said at load, so that gi validate and gi submit say it before a run. */
    if (p->radius.kind == GI_DETP_LEN_AUTO && p->disc_radius > 0.05 * p->scene_size)
        gi_warn("%s: detp: the discs' radius is %.3g (%.0f%% of the scene's size, the mesh's mean "
                "edge with %u vertices): a coarse bake; set detp.subdivide (\"2%%\", say) for "
                "finer lighting",
                job->name, (double)p->disc_radius, 100.0 * p->disc_radius / p->scene_size,
                job->scene.vertex_count);
    return 0;
}

static uint32_t reference_count(const gi_job *job)
{
    const gi_detp_params *p = job->params;
    if (!p->reference_spp)
        return 0;
    return p->reference_vertices < job->scene.vertex_count ? p->reference_vertices
                                                           : job->scene.vertex_count;
}

static void state_free(gi_job *job, detp_state *st)
{
    if (!st)
        return;
    gi_error ignored;
    gi_image_writer_finish(job, &st->writer, NULL, &ignored);
    gi_image_free(&st->unwritten);
    free(st->irr);
    free(st->hits);
    free(st->visible);
    free(st->ref);
    gi_image_free(&st->img);
    detp_anim_free(st->anim);
    free(st);
}

static int state_new(gi_job *job, detp_state **out, gi_error *err)
{
    const gi_detp_params *p = job->params;
    detp_state *st = gi_xcalloc(1, sizeof *st);
    st->nv = job->scene.vertex_count;
    st->nref = reference_count(job);
    st->irr = gi_try_calloc((size_t)st->nv * 3 + 1, sizeof *st->irr, err, "detp irradiance");
    st->hits = gi_try_calloc((size_t)st->nv + 1, sizeof *st->hits, err, "detp hits");
    if (p->artifact == GI_DETP_AC_VISIBLE_AREA)
        st->visible = gi_try_calloc((size_t)st->nv + 1, sizeof *st->visible, err,
                                    "detp visible areas");
    st->ref = gi_try_calloc((size_t)st->nref * 4 + 1, sizeof *st->ref, err, "detp reference");
    if (!st->irr || !st->hits || !st->ref ||
        (p->artifact == GI_DETP_AC_VISIBLE_AREA && !st->visible)) {
        state_free(job, st);
        return -1;
    }
    st->wall_start = gi_now();
    *out = st;
    return 0;
}

static int detp_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    const gi_detp_params *p = job->params;
    detp_state *st;
    if (state_new(job, &st, err))
        return -1;
    job->state = st;
    if (gi_anim_moves_object(&p->anim))
        return detp_anim_plan(job, st, q, err);
    gi_anim_set_frame(&p->anim, job, 0); /* a camera path's: its outputs name the frame */
    for (uint64_t p0 = 0; p0 < p->photon_count; p0 += (uint64_t)p->batch) {
        uint64_t p1 = p0 + (uint64_t)p->batch;
        if (p1 > p->photon_count)
            p1 = p->photon_count;
        gi_task *t = gi_task_queue_add(q, DETP_TASK_BATCH, (double)(p1 - p0));
        detp_task_encode(t->kind, &(detp_task_in){.p0 = p0, .p1 = p1}, &t->payload);
    }
    if (st->visible)
        for (uint32_t v0 = 0; v0 < st->nv; v0 += DETP_VIS_PER_TASK) {
            uint32_t v1 = st->nv - v0 < DETP_VIS_PER_TASK ? st->nv : v0 + DETP_VIS_PER_TASK;
            gi_task *t = gi_task_queue_add(q, DETP_TASK_VISIBILITY, (double)(v1 - v0));
            detp_task_encode(t->kind, &(detp_task_in){.a = v0, .b = v1}, &t->payload);
        }
    for (uint32_t j0 = 0; j0 < st->nref; j0 += DETP_REF_PER_TASK) {
        uint32_t j1 = st->nref - j0 < DETP_REF_PER_TASK ? st->nref : j0 + DETP_REF_PER_TASK;
        gi_task *t = gi_task_queue_add(q, DETP_TASK_REFERENCE,
                                       (double)(j1 - j0) * p->reference_spp);
        detp_task_encode(t->kind, &(detp_task_in){.a = j0, .b = j1}, &t->payload);
    }
    return 0;
}

/* The fixed part of the visibility / reference / tile results. */
static void read_timing(gi_reader *r, double *seconds, uint64_t *rays)
{
    *seconds += gi_get_f64(r);
    *rays += gi_get_u64(r);
}

/* An image tile's task and result: its tile, its timing (into *seconds and
 * *rays) and its pixels, which point into result. */
static int tile_result(const gi_job *job, const gi_task *t, const gi_buf *result, gi_tile *tile,
                       double *seconds, uint64_t *rays, gi_buf *px, gi_error *err)
{
    detp_task_in in;
    if (detp_task_decode(job, t, 0, &in, err))
        return -1;
    *tile = in.tile;
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp tile result");
    read_timing(&r, seconds, rays);
    if (r.failed)
        return gi_fail(err, GI_EPROTO, "detp tile %llu: truncated result",
                       (unsigned long long)t->id);
    *px = (gi_buf){(uint8_t *)r.p, r.left, r.left};
    return 0;
}

/* A visibility (one f32 in [0, 1] per vertex, into vis) or reference
 * (`reference`: four finite f64s per sample, added into ref) task's result,
 * after its timing (added into *seconds and *rays). vis and ref NULL: only
 * checks it (detp_check_result), by the same rules as the merge. */
static int range_result(const gi_job *job, const gi_task *t, const gi_buf *result, uint32_t lim,
                        int reference, float *vis, double *ref, double *seconds, uint64_t *rays,
                        gi_error *err)
{
    detp_task_in in;
    if (detp_task_decode(job, t, lim, &in, err))
        return -1;
    uint32_t a = in.a, b = in.b;
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp result");
    read_timing(&r, seconds, rays);
    int per = reference ? 4 : 1;
    for (uint32_t i = a; i < b && !r.failed; i++) {
        for (int c = 0; c < per; c++) {
            double v = reference ? gi_get_f64(&r) : gi_get_f32(&r);
            if (r.failed) /* cut short: gi_reader_finish says so */
                break;
            /* A visible fraction divides irradiance: 0, or at least one ray's. */
            if (!gi_result_summable(v) ||
                (!reference && !(v == 0.0 || (v >= 1.0 / GI_DETP_VIS_RAYS && v <= 1.0))))
                return gi_fail(err, GI_EPROTO, "detp: value %u of the result out of range",
                               i - a);
            if (vis)
                vis[i] = (float)v;
            if (ref)
                ref[4 * (size_t)i + c] += v;
        }
    }
    return gi_reader_finish(&r, err);
}

/* The most a still's photon batch may add to a vertex's energy, in
 * magnitude. The B batches' energies are summed (f64), divided by the
 * vertex's visible fraction when rule 2 is on (0, or at least 1 /
 * GI_DETP_VIS_RAYS: the visibility check refuses others), and written as
 * float irradiance (PLY, bin) and, times rho / pi (rho <= 1), as the
 * reflected radiance published for the tiles, which the workers take up to
 * GI_PUBLISHED_VALUE_MAX (FLT_MAX / 4). Each batch within that bound x the
 * least visible fraction / B keeps every sum within it (B < 2^20 floats'
 * f64 rounding is far below the factor rho / pi leaves): a result beyond
 * it is refused and retried, instead of failing the job at publish. A
 * detp animation bounds its exact sums the same way (INT64_MAX / B). */
static double batch_energy_max(const gi_job *job, const detp_state *st)
{
    const gi_detp_params *p = job->params;
    uint64_t b = (p->photon_count + (uint64_t)p->batch - 1) / (uint64_t)p->batch;
    double f_min = st->visible ? 1.0 / GI_DETP_VIS_RAYS : 1.0;
    return GI_PUBLISHED_VALUE_MAX * f_min / (double)(b ? b : 1);
}

static int detp_merge(gi_job *job, const gi_task *t, const gi_buf *result, gi_task_queue *fq,
                      gi_error *err)
{
    detp_state *st = job->state;
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp result");
    switch (t->kind) {
    case DETP_TASK_BATCH: {
        detp_batch_result h;
        if (detp_decode_batch(&r, st->nv, batch_energy_max(job, st), &h, st->irr, st->hits,
                              err))
            return -1;
        st->batches++;
        st->photons += h.photons;
        st->segments += h.segments;
        st->rays_trace += h.rays;
        st->sec_trace += h.trace_seconds;
        st->sec_build += h.build_seconds;
        st->sec_estimate += h.estimate_seconds;
        gi_detp_stats_add(&st->stats, &h.stats);
        return 0;
    }
    case DETP_TASK_VISIBILITY:
        if (!st->visible)
            return gi_fail(err, GI_EPROTO, "unexpected visibility result");
        return range_result(job, t, result, st->nv, 0, st->visible, NULL, &st->sec_visibility,
                            &st->rays_visibility, err);
    case DETP_TASK_REFERENCE:
        return range_result(job, t, result, st->nref, 1, NULL, st->ref, &st->sec_reference,
                            &st->rays_reference, err);
    case DETP_TASK_ANIM_BATCH:
    case DETP_TASK_ANIM_UPDATE:
        if (!st->anim)
            return gi_fail(err, GI_EPROTO, "unexpected detp animation result");
        return detp_anim_merge(job, t, result, err);
    case DETP_TASK_TILE:
    case DETP_TASK_ANIM_TILE: {
        gi_tile tile;
        gi_buf px;
        if (tile_result(job, t, result, &tile, &st->sec_image, &st->rays_image, &px, err))
            return -1;
        return gi_tile_merge(&st->img, &tile, &px, err);
    }
    }
    return gi_fail(err, GI_EPROTO, "detp: unknown task kind %u", t->kind);
}

int detp_vertex_data_compute(const gi_job *job, const detp_state *st, detp_vertex_data *v,
                             gi_error *err)
{
    size_t n = (size_t)st->nv * 3 + 1;
    memset(v, 0, sizeof *v);
    v->irradiance = gi_try_malloc(n * sizeof(float), err, "detp vertex data");
    v->reflected = gi_try_malloc(n * sizeof(float), err, "detp vertex data");
    v->radiance = gi_try_malloc(n * sizeof(float), err, "detp vertex data");
    float *rho = gi_try_malloc(n * sizeof(float), err, "detp vertex data");
    float *le = gi_try_malloc(n * sizeof(float), err, "detp vertex data");
    if (!v->irradiance || !v->reflected || !v->radiance || !rho || !le) {
        free(rho);
        free(le);
        detp_vertex_data_free(v);
        return -1;
    }
    gi_detp_vertex_materials(&job->scene, rho, le);
    for (uint32_t i = 0; i < st->nv; i++) {
        /* Rule 2: the energy was spread over the visible part only. */
        double f = st->visible ? st->visible[i] : 1.0;
        for (int c = 0; c < 3; c++) {
            size_t k = 3 * (size_t)i + c;
            double E = f > 0.0 ? st->irr[k] / f : 0.0;
            v->irradiance[k] = (float)E;
            v->reflected[k] = (float)(rho[k] * E * GI_INV_PI); /* eq. 4.2 */
            v->radiance[k] = v->reflected[k] + le[k];
        }
    }
    free(rho);
    free(le);
    return 0;
}

void detp_vertex_data_free(detp_vertex_data *v)
{
    free(v->irradiance);
    free(v->reflected);
    free(v->radiance);
    memset(v, 0, sizeof *v);
}

/* The frame's reflected radiance per vertex for its tiles; the frame
 * before's is dropped (its tiles are all merged by now). What the workers
 * would refuse (detp_radiance_decode: a vertex's radiance beyond what the
 * shader can interpolate) fails the job here, naming the vertex, instead of
 * failing every tile on every attempt. */
static int publish_radiance(gi_job *job, detp_state *st, const detp_vertex_data *v,
                            gi_error *err)
{
    char before[GI_HASH_HEX], hash[GI_HASH_HEX];
    memcpy(before, st->hash, sizeof before);
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_f32s(&b, v->reflected, (size_t)st->nv * 3);
    gi_hash_hex(b.data, b.len, hash);
    float *checked = detp_radiance_decode(&b, hash, st->nv, err);
    if (checked)
        gi_job_publish(job, b.data, b.len, st->hash);
    gi_buf_free(&b);
    if (!checked)
        return gi_error_prefix(err, "%s", job->file);
    free(checked);
    if (before[0] && strcmp(before, st->hash) != 0)
        gi_job_unpublish(job, before);
    return 0;
}

static void plan_tiles(gi_job *job, detp_state *st, gi_task_queue *fq)
{
    const gi_detp_params *p = job->params;
    gi_buf extra;
    gi_buf_init(&extra);
    gi_buf_put_str(&extra, st->hash);
    if (p->anim.enabled) /* the workers pose the mobile, and take the frame's camera */
        gi_buf_put_u32(&extra, job->frame);
    gi_tiles_plan(fq, p->anim.enabled ? DETP_TASK_ANIM_TILE : DETP_TASK_TILE, job->width,
                  job->height, p->tile, p->image_spp, &extra);
    gi_buf_free(&extra);
}

/* After a frame's outputs: for animations the next frame is planned. */
static void frame_written(gi_job *job, detp_state *st, gi_task_queue *fq)
{
    if (st->anim && detp_anim_next_frame(job, st, fq)) {
        job->frame = detp_anim_frame(st);
        st->phase = DETP_PHASE_BAKE;
        return;
    }
    job->in_frame = 0;
    st->phase = DETP_PHASE_DONE;
}

/* A camera path's frame (camera_only): its image and report, and with
 * frame 0 the vertex outputs, once and under their own names (NAME.ply, no
 * frame number: the light is the same in every frame); then the frames
 * after it whose camera holds, written again; then the next frame whose
 * camera moves gets its tiles, from the same radiance. A failed write keeps
 * the frame, its image and the phase, to be written again. */
typedef struct camera_frame {
    const detp_state *st;
    const detp_vertex_data *v;
} camera_frame;

static int write_camera_frame(gi_job *job, void *ctx, gi_error *err)
{
    const camera_frame *c = ctx;
    if (gi_write_image_outputs(job, &c->st->img, err))
        return -1;
    if (job->frame == 0) {
        job->in_frame = 0;
        int rc = detp_write_vertex_outputs(job, c->st, c->v, err);
        job->in_frame = 1;
        if (rc)
            return -1;
    }
    return detp_write_report(job, c->st, c->v, err);
}

static int write_camera_frames(gi_job *job, detp_state *st, const detp_vertex_data *v,
                               gi_task_queue *fq, gi_error *err)
{
    const gi_detp_params *p = job->params;
    uint32_t frame = job->frame;
    camera_frame c = {st, v};
    int rc = gi_anim_write_frames(&p->anim, job, &frame, write_camera_frame, &c, err);
    if (rc <= 0) {
        if (rc == 0)
            st->phase = DETP_PHASE_DONE;
        return rc;
    }
    st->sec_image = 0; /* each frame's report has its own image's */
    st->rays_image = 0;
    plan_tiles(job, st, fq);
    st->wall_start = gi_now();
    return 0;
}

/* A frame's vertex outputs (and report), then the next frame. */
static int write_frame(gi_job *job, detp_state *st, const detp_vertex_data *v,
                       gi_task_queue *fq, gi_error *err)
{
    if (detp_write_outputs(job, st, v, err))
        return -1;
    frame_written(job, st, fq);
    return 0;
}

/* The frame before's image outputs are written by now: those its writer
 * wrote, or, if that failed, the image kept from it (or from a
 * checkpoint), written again here. A failure keeps it for the next try. */
static int write_earlier_frame(gi_job *job, detp_state *st, gi_error *err)
{
    if (gi_image_writer_finish(job, &st->writer, &st->unwritten, err))
        return -1;
    if (!st->unwritten.pixels)
        return 0;
    uint32_t frame = job->frame;
    job->frame = st->earlier_frame;
    int rc = gi_write_image_outputs(job, &st->unwritten, err);
    job->frame = frame;
    if (rc == 0)
        gi_image_free(&st->unwritten);
    return rc;
}

/* Whatever detp_merge would refuse for what a result holds is refused as it
 * arrives: its run then fails and the task runs again, instead of the job
 * failing at merge. Image tiles also need finite pixels. */
static int detp_check_result(const gi_job *job, const gi_task *t, const gi_buf *result,
                             gi_buf *decoded, gi_error *err)
{
    const detp_state *st = job->state;
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp result");
    detp_batch_result h;
    double seconds = 0; /* timings: read, not kept */
    uint64_t rays = 0;
    switch (t->kind) {
    case DETP_TASK_BATCH:
        return detp_decode_batch(&r, st->nv, batch_energy_max(job, st), &h, NULL, NULL, err);
    case DETP_TASK_VISIBILITY:
        return st->visible ? range_result(job, t, result, st->nv, 0, NULL, NULL, &seconds, &rays,
                                          err)
                           : 0;
    case DETP_TASK_REFERENCE:
        return range_result(job, t, result, st->nref, 1, NULL, NULL, &seconds, &rays, err);
    case DETP_TASK_ANIM_BATCH:
    case DETP_TASK_ANIM_UPDATE:
        return st->anim ? detp_anim_check(job, t, result, decoded, err) : 0;
    }
    if (t->kind != DETP_TASK_TILE && t->kind != DETP_TASK_ANIM_TILE)
        return 0;
    gi_tile tile;
    gi_buf px;
    if (tile_result(job, t, result, &tile, &seconds, &rays, &px, err))
        return -1;
    return gi_tile_check_result(&tile, px.data, px.len, err);
}

/* Tests only (gi_method.h). Tiles', visibility's and reference values come
 * after the timing (f64 seconds, u64 rays); only reference values and
 * animation sums are summed. */
static int detp_damage_result(const gi_job *job, const gi_task *t, gi_buf *result,
                              gi_damage how)
{
    (void)job;
    if (t->kind == DETP_TASK_BATCH)
        return detp_batch_damage(result, how == GI_DAMAGE_NAN ? NAN : FLT_MAX);
    if (t->kind == DETP_TASK_ANIM_BATCH || t->kind == DETP_TASK_ANIM_UPDATE)
        return how == GI_DAMAGE_HUGE ? detp_anim_damage(result) : 1;
    if (t->kind == DETP_TASK_REFERENCE && result->len >= 24) {
        double v = how == GI_DAMAGE_NAN ? NAN : 1e300;
        memcpy(result->data + 16, &v, 8);
        return 0;
    }
    if (how == GI_DAMAGE_HUGE || result->len < 20)
        return 1;
    float v = NAN;
    memcpy(result->data + 16, &v, 4);
    return 0;
}

/* What detp_check_result decoded: animation batches' entries. (A still's
 * photon batches are merged from the worker's bytes: their results are
 * mostly dense floats, cheap to read twice, and a decoded copy of them
 * cost the check more than it saved the merge: see bench/BENCHMARKS.md.) */
static int detp_merge_decoded(gi_job *job, const gi_task *t, const gi_buf *decoded,
                              gi_task_queue *fq, gi_error *err)
{
    (void)fq;
    const detp_state *st = job->state;
    if ((t->kind == DETP_TASK_ANIM_BATCH || t->kind == DETP_TASK_ANIM_UPDATE) && st->anim)
        return detp_anim_merge_decoded(job, t, decoded, err);
    return gi_fail(err, GI_EINTERNAL, "detp task %llu: no decoded form for its kind %u",
                   (unsigned long long)t->id, t->kind);
}

static int detp_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    const gi_detp_params *p = job->params;
    detp_state *st = job->state;
    if (st->phase == DETP_PHASE_DONE)
        return 0;
    if (st->anim) {
        if (detp_anim_fill(job, st, err))
            return -1;
        job->in_frame = 1;
        job->frame = detp_anim_frame(st);
        job->frame_count = p->anim.frames;
    }
    detp_vertex_data v;
    if (detp_vertex_data_compute(job, st, &v, err))
        return -1;
    int rc = 0;
    if (st->phase == DETP_PHASE_BAKE) {
        st->wall_bake = gi_now() - st->wall_start;
        if (wants_image(job)) {
            static const char *const names[] = {"R", "G", "B"};
            gi_image_free(&st->img);
            rc = gi_image_init(&st->img, job->width, job->height, 3, names, err);
            if (rc == 0)
                rc = publish_radiance(job, st, &v, err);
            if (rc == 0) {
                plan_tiles(job, st, fq);
                st->phase = DETP_PHASE_IMAGE;
                st->wall_start = gi_now();
            }
            detp_vertex_data_free(&v);
            return rc;
        }
    } else {
        st->wall_image = gi_now() - st->wall_start;
        if (camera_only(p)) {
            rc = write_camera_frames(job, st, &v, fq, err);
            detp_vertex_data_free(&v);
            return rc;
        }
        rc = write_earlier_frame(job, st, err);
        if (rc == 0 && st->anim && detp_anim_frame(st) + 1 < p->anim.frames) {
            /* This frame's images are written while the next frame runs;
             * its vertex outputs first, so that if they fail the frame is
             * still whole (its image not handed over) for finish again. */
            rc = detp_write_outputs(job, st, &v, err);
            if (rc == 0) {
                st->earlier_frame = job->frame;
                st->writer = gi_image_writer_start(job, &st->img);
                frame_written(job, st, fq);
            }
            detp_vertex_data_free(&v);
            return rc;
        }
        if (rc == 0)
            rc = gi_write_image_outputs(job, &st->img, err);
    }
    if (rc == 0)
        rc = write_frame(job, st, &v, fq, err);
    detp_vertex_data_free(&v);
    return rc;
}

/* A failed write leaves the phase, the frame and its image as they were
 * (an earlier frame's image whose write failed is kept beside them), and
 * finish writes them again: a still's outputs, or an animation's from the
 * first frame not on disk on. */
static int detp_can_finish_again(const gi_job *job)
{
    const detp_state *st = job->state;
    return st->phase != DETP_PHASE_DONE && !st->writer;
}

/* A frame after 0 over frame 0, in bake time: k * (frame 0's share of
 * segments from the mobile) + c. Fitted to the Cornell box with a sphere
 * of radius 1.25%, 2.5%, 10% and 20% of its width (bench/detp_anim.sh;
 * within 10% at each): the update retraces those suffixes and estimates
 * them twice (old out, new in), plus a fixed part (opening the store,
 * the mobile's own vertices). */
#define LATER_PER_SHARE 1.4
#define LATER_FIXED 0.0025

/* An animation's frame, and a bake's image tiles still to plan. */
static void detp_progress(const gi_job *job, gi_job_progress *out)
{
    const gi_detp_params *p = job->params;
    const detp_state *st = job->state;
    double tiles = wants_image(job) ? gi_tiles_cost(job->width, job->height, p->image_spp) : 0;
    out->frame = st->anim ? detp_anim_frame(st) : job->frame; /* a camera path's, or 0 */
    out->frames = p->anim.enabled ? p->anim.frames : 1;
    out->cost_unplanned = st->phase == DETP_PHASE_BAKE ? tiles : 0;
    if (camera_only(p)) { /* one bake, then tiles each frame */
        out->first_frame_cost = (double)p->photon_count + tiles;
        out->later_frame_cost = tiles;
    }
    double share = st->anim ? detp_anim_from_mobile_share(st) : -1;
    if (share >= 0 && p->anim_update != GI_DETP_UPDATE_FULL) {
        double bake = (double)p->photon_count;
        out->first_frame_cost = bake + tiles;
        out->later_frame_cost = bake * (LATER_PER_SHARE * share + LATER_FIXED) + tiles;
    }
}

#define STATE_MAGIC 0x53505444u /* "DTPS" */
/* 2: animations; 3: frame 0's share of segments from the mobile; 4: an
 * animation's earlier frame image not written; 5: a camera path's frame. */
#define STATE_VERSION 5u

static int detp_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    const gi_detp_params *p = job->params;
    const detp_state *st = job->state;
    (void)err;
    /* A checkpoint past a frame holds its outputs on disk, or the image of
     * one whose write failed, to be written again. */
    const gi_image *unwritten =
        st->unwritten.pixels ? &st->unwritten : gi_image_writer_failed(st->writer);
    gi_buf_put_u32(out, STATE_MAGIC);
    gi_buf_put_u32(out, STATE_VERSION);
    gi_buf_put_u32(out, (uint32_t)st->phase);
    gi_buf_put_u32(out, st->nv);
    gi_buf_put_u32(out, st->nref);
    gi_buf_put_u8(out, st->visible != NULL);
    gi_buf_put_u64(out, st->batches);
    gi_buf_put_u64(out, st->photons);
    gi_buf_put_u64(out, st->segments);
    gi_buf_put_u64(out, st->rays_trace);
    gi_buf_put_u64(out, st->rays_visibility);
    gi_buf_put_u64(out, st->rays_reference);
    gi_buf_put_u64(out, st->rays_image);
    gi_buf_put_f64(out, st->sec_trace);
    gi_buf_put_f64(out, st->sec_build);
    gi_buf_put_f64(out, st->sec_estimate);
    gi_buf_put_f64(out, st->sec_visibility);
    gi_buf_put_f64(out, st->sec_reference);
    gi_buf_put_f64(out, st->sec_image);
    gi_detp_stats_encode(&st->stats, out);
    gi_buf_put_f64s(out, st->irr, (size_t)st->nv * 3);
    for (uint32_t i = 0; i < st->nv; i++)
        gi_buf_put_u64(out, st->hits[i]);
    if (st->visible)
        gi_buf_put_f32s(out, st->visible, st->nv);
    gi_buf_put_f64s(out, st->ref, (size_t)st->nref * 4);
    if (st->phase == DETP_PHASE_IMAGE) {
        gi_buf_put_str(out, st->hash);
        gi_buf_put_f32s(out, st->img.pixels, (size_t)job->width * job->height * 3);
    }
    if (camera_only(p))
        gi_buf_put_u32(out, job->frame);
    if (st->anim) {
        detp_anim_save(st, out);
        gi_buf_put_u8(out, unwritten != NULL);
        if (unwritten) {
            gi_buf_put_u32(out, st->earlier_frame);
            gi_buf_put_f32s(out, unwritten->pixels, (size_t)job->width * job->height * 3);
        }
    }
    return 0;
}

/* The animation's earlier frame image not written (version 4 on). */
static int load_unwritten(gi_job *job, detp_state *st, gi_reader *in, gi_error *err)
{
    uint8_t has = gi_get_u8(in);
    if (in->failed || has > 1)
        return gi_fail(err, GI_EPROTO, "%s: truncated detp checkpoint", job->file);
    if (!has)
        return 0;
    st->earlier_frame = gi_get_u32(in);
    if (in->failed || st->earlier_frame >= detp_anim_frame(st))
        return gi_fail(err, GI_EPROTO, "%s: not a checkpoint of this detp animation", job->file);
    static const char *const names[] = {"R", "G", "B"};
    if (gi_image_init(&st->unwritten, job->width, job->height, 3, names, err))
        return -1;
    if (gi_get_f32s(in, st->unwritten.pixels, (size_t)job->width * job->height * 3))
        return gi_fail(err, GI_EPROTO, "%s: truncated detp checkpoint", job->file);
    return 0;
}

static int detp_load(gi_job *job, gi_reader *in, gi_error *err)
{
    const gi_detp_params *p = job->params;
    detp_state *st;
    if (state_new(job, &st, err))
        return -1;
    job->state = st;
    uint32_t magic = gi_get_u32(in), version = gi_get_u32(in), phase = gi_get_u32(in);
    uint32_t nv = gi_get_u32(in), nref = gi_get_u32(in);
    uint8_t has_vis = gi_get_u8(in);
    if (in->failed || magic != STATE_MAGIC || version < 2 || version > STATE_VERSION ||
        phase > DETP_PHASE_DONE || nv != st->nv || nref != st->nref ||
        has_vis != (p->artifact == GI_DETP_AC_VISIBLE_AREA))
        return gi_fail(err, GI_EPROTO, "%s: not a checkpoint of this detp job", job->file);
    st->phase = (int)phase;
    st->batches = gi_get_u64(in);
    st->photons = gi_get_u64(in);
    st->segments = gi_get_u64(in);
    st->rays_trace = gi_get_u64(in);
    st->rays_visibility = gi_get_u64(in);
    st->rays_reference = gi_get_u64(in);
    st->rays_image = gi_get_u64(in);
    st->sec_trace = gi_get_f64(in);
    st->sec_build = gi_get_f64(in);
    st->sec_estimate = gi_get_f64(in);
    st->sec_visibility = gi_get_f64(in);
    st->sec_reference = gi_get_f64(in);
    st->sec_image = gi_get_f64(in);
    gi_detp_stats_decode(in, &st->stats);
    gi_get_f64s(in, st->irr, (size_t)nv * 3);
    for (uint32_t i = 0; i < nv; i++)
        st->hits[i] = gi_get_u64(in);
    if (st->visible)
        gi_get_f32s(in, st->visible, nv);
    gi_get_f64s(in, st->ref, (size_t)nref * 4);
    if (in->failed)
        return gi_fail(err, GI_EPROTO, "%s: truncated detp checkpoint", job->file);
    char *hash = NULL;
    int rc = 0;
    if (st->phase == DETP_PHASE_IMAGE) {
        hash = gi_get_str(in, GI_HASH_HEX - 1);
        static const char *const names[] = {"R", "G", "B"};
        rc = !hash ? gi_fail(err, GI_EPROTO, "%s: truncated detp checkpoint", job->file)
                   : gi_image_init(&st->img, job->width, job->height, 3, names, err);
        if (rc == 0 && gi_get_f32s(in, st->img.pixels, (size_t)job->width * job->height * 3))
            rc = gi_fail(err, GI_EPROTO, "%s: truncated detp checkpoint", job->file);
    }
    if (rc == 0 && camera_only(p)) {
        uint32_t frame = gi_get_u32(in);
        if (version < 5 || in->failed || frame >= p->anim.frames)
            rc = gi_fail(err, GI_EPROTO, "%s: not a checkpoint of this detp job", job->file);
        else
            gi_anim_set_frame(&p->anim, job, frame);
    }
    if (rc == 0 && gi_anim_moves_object(&p->anim)) {
        rc = detp_anim_load(job, st, in, version, err);
        if (rc == 0 && version >= 4)
            rc = load_unwritten(job, st, in, err);
        if (rc == 0) {
            job->in_frame = 1;
            job->frame = detp_anim_frame(st);
            job->frame_count = p->anim.frames;
        }
    }
    if (rc == 0 && hash) {
        /* The tiles still to run fetch the radiance by hash: publish it
         * again (the same bits, so the same hash). */
        detp_vertex_data v;
        rc = detp_vertex_data_compute(job, st, &v, err);
        if (rc == 0) {
            rc = publish_radiance(job, st, &v, err);
            detp_vertex_data_free(&v);
            if (rc == 0 && strcmp(st->hash, hash) != 0)
                rc = gi_fail(err, GI_EPROTO, "%s: detp checkpoint does not match its radiance",
                             job->file);
        }
    }
    free(hash);
    return rc;
}

static void detp_release(gi_job *job)
{
    state_free(job, job->state);
    free(job->params);
    job->state = job->params = NULL;
}

static const char *const detp_outputs[] = {"exr", "png", "ply", "glb", "bin", "json", NULL};

const gi_method gi_method_detp = {
    .name = "detp",
    .summary = "photon paths + density estimation on the tangent plane: per-vertex radiance",
    .unit = "photons",
    .output_kinds = detp_outputs,
    .default_outputs = detp_outputs,
    .parse = detp_parse,
    .check_scene = detp_check_scene,
    .plan = detp_plan,
    .run = detp_run,
    .check_result = detp_check_result,
    .damage_result = detp_damage_result,
    .merge_decoded = detp_merge_decoded,
    .merge = detp_merge,
    .finish = detp_finish,
    .save = detp_save,
    .load = detp_load,
    .progress = detp_progress,
    .can_finish_again = detp_can_finish_again,
    .release = detp_release,
};
