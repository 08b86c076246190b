/* pt_method: the path tracer as a farm method. A task is an image tile and
 * a range of samples; its result is the tile's per-pixel sums; merge adds
 * them; finish divides by the sample count and writes the image.
 *
 * An animation (pt.animation: one mobile object keyframed, as detp's) is
 * its frames one after another: a frame's tasks carry its number, the
 * workers pose the mobile for it, and finish writes NAME.0003.exr and
 * plans the next frame. Every frame draws the same random numbers (keyed
 * by seed, pixel and sample, not frame), so a pixel whose paths never meet
 * the mobile has the same value in every frame, bit for bit: the still
 * parts of the picture do not flicker with noise, and a frame whose pose is
 * the very same as the frame before's is written again without tasks. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_anim_pose.h"
#include "gi_camera.h"
#include "gi_job.h"
#include "gi_log.h"
#include "gi_outputs.h"
#include "gi_tiles.h"
#include "gi_worker_ctx.h"
#include "pt.h"
#include "pt_task.h"

#define PT_MAX_SPP (1 << 24)

/* Per pixel in a result: R, G, B sums and the sum of squared luminance. */
#define PT_VALUES_PER_PIXEL 4

typedef struct pt_state {
    double *sum;    /* width * height * PT_VALUES_PER_PIXEL */
    uint32_t frame; /* an animation's frame being computed */
} pt_state;

void gi_pt_params_default(gi_pt_params *p)
{
    p->spp = 64;
    p->max_bounces = -1;
    p->rr_depth = 3;
    p->tile = 32;
    p->pass_spp = 16;
    p->strategy = GI_PT_MIS;
}

static int pt_parse(gi_job *job, const cJSON *params, gi_jv *v)
{
    gi_pt_job_params *jp = gi_xcalloc(1, sizeof *jp);
    gi_pt_params *p = &jp->pt;
    job->params = jp;
    gi_pt_params_default(p);
    snprintf(jp->anim.path, sizeof jp->anim.path, "pt.animation");
    if (!params)
        return 0;
    static const char *const keys[] = {"spp", "max_bounces", "rr_depth", "tile",
                                       "pass_spp", "strategy", "animation", NULL};
    static const char *const strategies[] = {"mis", "bsdf", "light", NULL};
    int64_t spp = p->spp, maxb = p->max_bounces, rr = p->rr_depth, tile = p->tile,
            pass = -1;
    int strategy = 0;
    const cJSON *anim;
    if (gi_jv_keys(v, params, "pt", keys) ||
        gi_jv_int(v, params, "pt", "spp", 0, 1, PT_MAX_SPP, &spp) ||
        gi_jv_int(v, params, "pt", "max_bounces", 0, -1, 100000, &maxb) ||
        gi_jv_int(v, params, "pt", "rr_depth", 0, 0, 100000, &rr) ||
        gi_jv_int(v, params, "pt", "tile", 0, 4, 4096, &tile) ||
        gi_jv_int(v, params, "pt", "pass_spp", 0, 1, PT_MAX_SPP, &pass) ||
        gi_jv_enum(v, params, "pt", "strategy", 0, strategies, &strategy) ||
        gi_jv_member_object(v, params, "pt", "animation", 0, &anim) ||
        gi_anim_parse(&jp->anim, anim, "pt.animation", NULL, GI_ANIM_CAMERA, v))
        return -1;
    p->spp = (int)spp;
    p->max_bounces = (int)maxb;
    p->rr_depth = (int)rr;
    p->tile = (int)tile;
    p->pass_spp = pass > 0 ? (int)pass : (p->spp < 16 ? p->spp : 16);
    if (p->pass_spp > p->spp)
        return gi_jv_fail(v, "pt.pass_spp", "%d is more than spp (%d)", p->pass_spp, p->spp);
    p->strategy = (gi_pt_strategy)strategy;
    int passes = (p->spp + p->pass_spp - 1) / p->pass_spp;
    /* A frame's tasks are planned when the frame before is written: the
     * most at once is one frame's. */
    return gi_job_check_tasks(v, "pt.tile",
                              gi_tiles_count(job->width, job->height, p->tile) * passes,
                              "%d x %d pixels in tiles of %d, %d passes of %d spp (raise pt.tile "
                              "or pt.pass_spp)",
                              job->width, job->height, p->tile, passes, p->pass_spp);
}

/* An animation's mobile, found in the scene wherever the scene is loaded
 * (coordinator and workers); its keys' warning is the coordinator's. */
static int pt_check_scene(gi_job *job, gi_error *err)
{
    gi_pt_job_params *jp = job->params;
    return gi_anim_check_scene(&jp->anim, job, err);
}

/* The tasks of the frame st->frame (a still's: its only ones). */
static void plan_frame(gi_job *job, const pt_state *st, gi_task_queue *q)
{
    const gi_pt_job_params *jp = job->params;
    const gi_pt_params *p = &jp->pt;
    /* Passes outermost: the first pass covers the whole image, so a
     * cancelled or previewed job has a complete (noisier) image early. */
    gi_buf extra;
    gi_buf_init(&extra);
    for (int s0 = 0; s0 < p->spp; s0 += p->pass_spp) {
        int s1 = s0 + p->pass_spp < p->spp ? s0 + p->pass_spp : p->spp;
        gi_buf_reset(&extra);
        gi_buf_put_u32(&extra, (uint32_t)s0);
        gi_buf_put_u32(&extra, (uint32_t)s1);
        if (jp->anim.enabled)
            gi_buf_put_u32(&extra, st->frame); /* the workers pose the mobile */
        gi_tiles_plan(q, PT_TASK_TILE, job->width, job->height, p->tile, s1 - s0, &extra);
    }
    gi_buf_free(&extra);
}

/* Values in the accumulator: PT_VALUES_PER_PIXEL per pixel. */
static size_t sum_count(const gi_job *job)
{
    return (size_t)job->width * (size_t)job->height * PT_VALUES_PER_PIXEL;
}

static pt_state *state_new(const gi_job *job, gi_error *err)
{
    pt_state *st = gi_xcalloc(1, sizeof *st);
    st->sum = gi_try_calloc(sum_count(job), sizeof(double), err, "pt accumulator");
    if (!st->sum) {
        free(st);
        return NULL;
    }
    return st;
}

static int pt_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    const gi_pt_job_params *jp = job->params;
    pt_state *st = state_new(job, err);
    if (!st)
        return -1;
    job->state = st;
    gi_anim_set_frame(&jp->anim, job, 0);
    plan_frame(job, st, q);
    return 0;
}

int gi_pt_task_decode(const gi_job *job, const gi_task *t, gi_pt_task *tl, gi_error *err)
{
    const gi_pt_job_params *jp = job->params;
    gi_reader r;
    gi_reader_init(&r, t->payload.data, t->payload.len, "pt task");
    if (gi_tile_read(&r, job->width, job->height, &tl->tile, err))
        return -1;
    tl->s0 = gi_get_u32(&r);
    tl->s1 = gi_get_u32(&r);
    tl->frame = jp->anim.enabled ? gi_get_u32(&r) : 0;
    if (gi_reader_finish(&r, err))
        return -1;
    if (jp->anim.enabled && tl->frame >= jp->anim.frames)
        return gi_fail(err, GI_EPROTO, "pt task %llu: frame %u past the animation's %u",
                       (unsigned long long)t->id, tl->frame, jp->anim.frames);
    if (tl->s0 >= tl->s1)
        return gi_fail(err, GI_EPROTO, "pt task %llu: empty sample range",
                       (unsigned long long)t->id);
    /* Up to 2^32 samples a pixel would hold the worker until the task's
     * timeout, and be merged into pixels the job never asked for. */
    if (tl->s1 > (uint32_t)jp->pt.spp)
        return gi_fail(err, GI_EPROTO, "pt task %llu: samples [%u, %u) past the job's %d",
                       (unsigned long long)t->id, tl->s0, tl->s1, jp->pt.spp);
    return 0;
}

/* Paths advanced together in pt_run (bounds the scratch memory). */
#define PT_WAVEFRONT 16384

/* A pool process's memory for its tasks' paths, kept across tasks (in
 * ctx->method_state): see gi_pt_wavefront. */
typedef struct pt_worker {
    gi_pt_path *paths; /* PT_WAVEFRONT */
    gi_pt_wavefront wf;
    gi_anim_poser poser; /* an animation's scene and ray tracer, posed */
} pt_worker;

static void pt_worker_free(void *state)
{
    pt_worker *w = state;
    free(w->paths);
    gi_pt_wavefront_free(&w->wf);
    gi_anim_poser_free(&w->poser);
    free(w);
}

static pt_worker *pt_worker_get(gi_worker_ctx *ctx)
{
    if (!ctx->method_state) {
        pt_worker *w = gi_xcalloc(1, sizeof *w);
        w->paths = gi_xmalloc(PT_WAVEFRONT * sizeof *w->paths);
        ctx->method_state = w;
        ctx->method_state_free = pt_worker_free;
    }
    return ctx->method_state;
}

static int pt_run(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    const gi_job *job = &ctx->job;
    const gi_pt_job_params *jp = job->params;
    const gi_pt_params *p = &jp->pt;
    gi_pt_task tl;
    if (gi_pt_task_decode(job, t, &tl, err))
        return -1;
    pt_worker *w = pt_worker_get(ctx);
    if (jp->anim.enabled &&
        gi_anim_poser_pose(&w->poser, &jp->anim, &ctx->job.scene, &ctx->rt, tl.frame, err))
        return -1;
    gi_camera frame_cam;
    gi_anim_camera(&jp->anim, gi_job_camera(job), tl.frame, &frame_cam);
    gi_camera_frame cam;
    gi_camera_frame_init(&cam, &frame_cam, job->width, job->height);
    gi_pt_tracer tr = {&ctx->rt, &job->scene, p, NULL};
    uint32_t tw = tl.tile.x1 - tl.tile.x0, ns = tl.s1 - tl.s0;
    size_t npix = (size_t)tw * (tl.tile.y1 - tl.tile.y0), total = npix * ns;
    double *acc = gi_xcalloc(npix * PT_VALUES_PER_PIXEL, sizeof *acc);
    gi_pt_path *paths = w->paths;
    /* Path j is sample s0 + j % ns of pixel j / ns: each pixel's samples are
     * added in sample order whatever the chunking. */
    for (size_t first = 0; first < total; first += PT_WAVEFRONT) {
        size_t n = total - first < PT_WAVEFRONT ? total - first : PT_WAVEFRONT;
        for (size_t j = 0; j < n; j++) {
            size_t k = (first + j) / ns;
            uint32_t s = tl.s0 + (uint32_t)((first + j) % ns);
            uint32_t x = tl.tile.x0 + (uint32_t)(k % tw), y = tl.tile.y0 + (uint32_t)(k / tw);
            gi_rng rng;
            gi_rng_init(&rng, job->seed, (uint64_t)y * (uint64_t)job->width + x, s);
            float jx = gi_rng_float(&rng), jy = gi_rng_float(&rng);
            gi_vec3 dir = gi_camera_dir(&cam, (float)x + jx, (float)y + jy);
            gi_pt_path_start(&paths[j], cam.origin, dir, &rng);
        }
        gi_pt_trace_paths(&tr, &w->wf, paths, n);
        for (size_t j = 0; j < n; j++) {
            double *a = &acc[PT_VALUES_PER_PIXEL * ((first + j) / ns)];
            gi_vec3 L = paths[j].L;
            a[0] += L.x;
            a[1] += L.y;
            a[2] += L.z;
            double lum = gi_luminance(L);
            a[3] += lum * lum;
        }
    }
    ctx->stats.samples = total;
    gi_buf_put_f64s(result, acc, npix * PT_VALUES_PER_PIXEL);
    free(acc);
    return 0;
}

static int pt_check_result(const gi_job *job, const gi_task *t, const gi_buf *result,
                           gi_buf *decoded, gi_error *err)
{
    (void)decoded; /* no merge_decoded */
    gi_pt_task tl;
    if (gi_pt_task_decode(job, t, &tl, err))
        return -1;
    uint32_t w = tl.tile.x1 - tl.tile.x0;
    size_t want = (size_t)w * (tl.tile.y1 - tl.tile.y0) * PT_VALUES_PER_PIXEL * 8;
    if (result->len != want) /* pt_merge takes nothing else */
        return gi_fail(err, GI_EPROTO, "result has %zu bytes, expected %zu", result->len, want);
    /* A sample's radiance is a float vector: ns of them sum to at most ns x
     * FLT_MAX a channel, and their squared luminances to ns x FLT_MAX^2;
     * the image's sums over all passes then stay finite, and so does their
     * mean as a float. */
    uint32_t ns = tl.s1 - tl.s0;
    double max = (double)ns * FLT_MAX, max2 = max * FLT_MAX;
    for (size_t i = 0; i + 8 <= result->len; i += 8) {
        double v;
        memcpy(&v, result->data + i, 8); /* little-endian hosts only (gi_buf.h) */
        static const char *const what[PT_VALUES_PER_PIXEL] = {
            "red sum", "green sum", "blue sum", "sum of squared luminances"};
        size_t pix = i / (8 * PT_VALUES_PER_PIXEL), c = i / 8 % PT_VALUES_PER_PIXEL;
        if (isfinite(v) && (c == 3 ? v >= 0 && v <= max2 : fabs(v) <= max))
            continue;
        uint32_t x = tl.tile.x0 + (uint32_t)(pix % w), y = tl.tile.y0 + (uint32_t)(pix / w);
        if (!isfinite(v))
            return gi_fail(err, GI_EPROTO, "pixel (%u, %u) is not finite (%g)", x, y, v);
        return gi_fail(err, GI_EPROTO, "pixel (%u, %u)'s %s is %g, out of range for %u samples",
                       x, y, what[c], v, ns);
    }
    return 0;
}

/* A NaN or an impossibly large sum in the first pixel's red channel. */
static int pt_damage_result(const gi_job *job, const gi_task *t, gi_buf *result, gi_damage how)
{
    (void)job;
    (void)t;
    if (result->len < 8)
        return 1;
    double v = how == GI_DAMAGE_NAN ? NAN : 1e300;
    memcpy(result->data, &v, 8);
    return 0;
}

static int pt_merge(gi_job *job, const gi_task *t, const gi_buf *result, gi_task_queue *fq,
                    gi_error *err)
{
    pt_state *st = job->state;
    gi_pt_task tl;
    if (gi_pt_task_decode(job, t, &tl, err))
        return -1;
    if (tl.frame != st->frame) /* planned for this frame; merged before it ends */
        return gi_fail(err, GI_EPROTO, "pt task %llu: a result of frame %u during frame %u",
                       (unsigned long long)t->id, tl.frame, st->frame);
    size_t npix = (size_t)(tl.tile.x1 - tl.tile.x0) * (tl.tile.y1 - tl.tile.y0);
    if (result->len != npix * PT_VALUES_PER_PIXEL * 8)
        return gi_fail(err, GI_EPROTO, "pt task %llu: result has %zu bytes, expected %zu",
                       (unsigned long long)t->id, result->len, npix * PT_VALUES_PER_PIXEL * 8);
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "pt result");
    size_t row_values = (size_t)(tl.tile.x1 - tl.tile.x0) * PT_VALUES_PER_PIXEL;
    double *in = gi_xmalloc(row_values * sizeof *in);
    for (uint32_t y = tl.tile.y0; y < tl.tile.y1 && !r.failed; y++) {
        double *row = st->sum + ((size_t)y * job->width + tl.tile.x0) * PT_VALUES_PER_PIXEL;
        gi_get_f64s(&r, in, row_values);
        for (size_t i = 0; i < row_values; i++)
            row[i] += in[i];
    }
    free(in);
    return gi_reader_finish(&r, err);
}

/* The image of the sums so far (a frame's, once all its tasks merged);
 * st: the pt_state. */
static int write_image(gi_job *job, void *state, gi_error *err)
{
    const pt_state *st = state;
    const gi_pt_job_params *jp = job->params;
    const gi_pt_params *p = &jp->pt;
    gi_image img;
    static const char *const names[] = {"R", "G", "B"};
    if (gi_image_init(&img, job->width, job->height, 3, names, err))
        return -1;
    double inv = 1.0 / p->spp, rel_err_sum = 0.0;
    size_t n = (size_t)job->width * job->height, counted = 0;
    for (size_t i = 0; i < n; i++) {
        const double *s = &st->sum[PT_VALUES_PER_PIXEL * i];
        for (int c = 0; c < 3; c++)
            img.pixels[3 * i + c] = (float)(s[c] * inv);
        /* Standard error of the pixel's luminance mean, for the report. */
        double mean = gi_luminance(gi_v3((float)(s[0] * inv), (float)(s[1] * inv),
                                         (float)(s[2] * inv)));
        double var = p->spp > 1 ? (s[3] * inv - mean * mean) / (p->spp - 1) : 0.0;
        if (mean > 0) {
            rel_err_sum += sqrt(var > 0 ? var : 0) / mean;
            counted++;
        }
    }
    if (jp->anim.enabled)
        gi_info("%s: frame %u: mean relative standard error per pixel %.4f", job->name,
                st->frame, counted ? rel_err_sum / counted : 0.0);
    else
        gi_info("%s: mean relative standard error per pixel %.4f", job->name,
                counted ? rel_err_sum / counted : 0.0);
    int rc = gi_write_image_outputs(job, &img, err);
    gi_image_free(&img);
    return rc;
}

/* Writes the frame's image, then plans the next frame that moves; the
 * frames between whose pose is the frame before's are the same image,
 * written again. A failed write leaves the frame and its sums as they
 * were, for finish again. */
static int pt_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    const gi_pt_job_params *jp = job->params;
    pt_state *st = job->state;
    int rc = gi_anim_write_frames(&jp->anim, job, &st->frame, write_image, st, err);
    if (rc <= 0)
        return rc;
    memset(st->sum, 0, sum_count(job) * sizeof *st->sum);
    plan_frame(job, st, fq);
    return 0;
}

static int pt_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    const gi_pt_job_params *jp = job->params;
    const pt_state *st = job->state;
    if (jp->anim.enabled)
        gi_buf_put_u32(out, st->frame);
    gi_buf_put_f64s(out, st->sum, sum_count(job));
    return 0;
}

static int pt_load(gi_job *job, gi_reader *in, gi_error *err)
{
    const gi_pt_job_params *jp = job->params;
    pt_state *st = state_new(job, err);
    if (!st)
        return -1;
    job->state = st;
    if (jp->anim.enabled) {
        st->frame = gi_get_u32(in);
        if (!in->failed && st->frame >= jp->anim.frames)
            return gi_fail(err, GI_EPROTO, "pt checkpoint: frame %u past the animation's %u",
                           st->frame, jp->anim.frames);
    }
    if (gi_get_f64s(in, st->sum, sum_count(job)))
        return gi_fail(err, GI_EPROTO, "pt checkpoint: truncated accumulator");
    gi_anim_set_frame(&jp->anim, job, st->frame);
    return 0;
}

/* finish only reads the sums (and moves to the next frame only once the
 * frame is written): it can always write the image again. */
static int pt_can_finish_again(const gi_job *job)
{
    (void)job;
    return 1;
}

/* An animation's frame. Its frames count alike (a held frame, which costs
 * nothing, too). */
static void pt_progress(const gi_job *job, gi_job_progress *out)
{
    const gi_pt_job_params *jp = job->params;
    const pt_state *st = job->state;
    out->frame = jp->anim.enabled ? st->frame : 0;
    out->frames = jp->anim.enabled ? jp->anim.frames : 1;
}

static void pt_release(gi_job *job)
{
    pt_state *st = job->state;
    if (st) {
        free(st->sum);
        free(st);
    }
    free(job->params);
    job->state = job->params = NULL;
}

static const char *const pt_outputs[] = {"exr", "png", NULL};

const gi_method gi_method_pt = {
    .name = "pt",
    .summary = "reference path tracer (next-event estimation + MIS, Russian roulette)",
    .unit = "samples",
    .output_kinds = pt_outputs,
    .default_outputs = pt_outputs,
    .parse = pt_parse,
    .check_scene = pt_check_scene,
    .plan = pt_plan,
    .run = pt_run,
    .check_result = pt_check_result,
    .damage_result = pt_damage_result,
    .merge = pt_merge,
    .finish = pt_finish,
    .save = pt_save,
    .load = pt_load,
    .can_finish_again = pt_can_finish_again,
    .progress = pt_progress,
    .release = pt_release,
};
