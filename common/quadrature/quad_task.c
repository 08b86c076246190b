/* quad_task: task payloads and results on the wire, and what a worker does
 * with a task (see quad_farm.h and quadrature.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_anim_pose.h"
#include "gi_job.h"
#include "gi_worker_ctx.h"
#include "quad_farm.h"
#include "quad_hybrid.h"
#include "quad_path.h"
#include "quad_refine.h"
#include "quad_splat.h"

int gi_quad_job_rule(const gi_quad_params *p, gi_quad_rule *rule, gi_error *err)
{
    return gi_quad_rule_init(rule, p->rule, p->dims, GI_QUAD_CHANNELS, err);
}

void gi_quad_task_encode(gi_buf *b, const gi_quad_task_in *t, const gi_quad_rule *rule)
{
    if (t->kind == GI_QUAD_TASK_REFINE) {
        gi_buf_put_u32(b, t->round);
        gi_buf_put_f64(b, t->threshold);
        gi_buf_put_u64(b, t->max_splits);
    }
    gi_buf_put_u32(b, t->count);
    for (uint32_t i = 0; i < t->count; i++) {
        if (t->kind == GI_QUAD_TASK_REFINE)
            gi_buf_put_u8(b, t->is_new[i]);
        gi_quad_summary_put(b, &t->regions[i], rule);
    }
    if (t->animated)
        gi_buf_put_u32(b, t->frame);
}

void gi_quad_task_in_free(gi_quad_task_in *t)
{
    free(t->is_new);
    free(t->regions);
    memset(t, 0, sizeof *t);
}

int gi_quad_task_decode(const gi_task *t, const gi_quad_rule *rule, uint32_t frames,
                        gi_quad_task_in *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    if (t->kind != GI_QUAD_TASK_REFINE && t->kind != GI_QUAD_TASK_MC)
        return gi_fail(err, GI_EPROTO, "quadrature task %llu: unknown kind %u",
                       (unsigned long long)t->id, t->kind);
    gi_reader r;
    gi_reader_init(&r, t->payload.data, t->payload.len, "quadrature task");
    out->kind = t->kind;
    if (t->kind == GI_QUAD_TASK_REFINE) {
        out->round = gi_get_u32(&r);
        out->threshold = gi_get_f64(&r);
        out->max_splits = gi_get_u64(&r);
    }
    out->count = gi_get_u32(&r);
    size_t each = gi_quad_summary_bytes(rule) + (t->kind == GI_QUAD_TASK_REFINE);
    if (r.failed || !(out->threshold >= 0.0) || (uint64_t)out->count * each > r.left)
        return gi_fail(err, GI_EPROTO, "quadrature task %llu: bad header",
                       (unsigned long long)t->id);
    out->is_new = gi_xcalloc(out->count ? out->count : 1, 1);
    out->regions = gi_try_calloc(out->count ? out->count : 1, sizeof *out->regions, err,
                                 "quadrature task regions");
    if (!out->regions) {
        gi_quad_task_in_free(out);
        return -1;
    }
    for (uint32_t i = 0; i < out->count; i++) {
        if (t->kind == GI_QUAD_TASK_REFINE)
            out->is_new[i] = gi_get_u8(&r);
        if (out->is_new[i] > 1 || gi_quad_summary_get(&r, rule, &out->regions[i], err)) {
            gi_quad_task_in_free(out);
            return gi_fail(err, GI_EPROTO, "quadrature task %llu: bad region %u",
                           (unsigned long long)t->id, i);
        }
    }
    out->animated = frames > 0;
    if (out->animated)
        out->frame = gi_get_u32(&r);
    if (gi_reader_finish(&r, err)) {
        gi_quad_task_in_free(out);
        return -1;
    }
    if (out->animated && out->frame >= frames) {
        gi_quad_task_in_free(out);
        return gi_fail(err, GI_EPROTO, "quadrature task %llu: frame %u past the animation's %u",
                       (unsigned long long)t->id, out->frame, frames);
    }
    return 0;
}

int gi_quad_result_decode_head(const gi_buf *b, const gi_quad_rule *rule, gi_quad_result *out,
                               gi_reader *rest, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_reader r;
    gi_reader_init(&r, b->data, b->len, "quadrature result");
    out->evals = gi_get_u64(&r);
    out->reevals = gi_get_u64(&r);
    out->splits = gi_get_u64(&r);
    out->closed = gi_get_u64(&r);
    out->mc_samples = gi_get_u64(&r);
    out->nonfinite = gi_get_u64(&r);
    out->closed_err = gi_get_f64(&r);
    gi_get_f64s(&r, out->dtotal, GI_QUAD_CHANNELS);
    gi_get_f64s(&r, out->mc_total, GI_QUAD_CHANNELS);
    /* Summed into the job's totals: within the bound that keeps them finite. */
    const double *sums[] = {&out->closed_err, &out->dtotal[0], &out->dtotal[1],
                            &out->dtotal[2], &out->mc_total[0], &out->mc_total[1],
                            &out->mc_total[2]};
    static const char *const names[] = {"closed regions' error", "red estimate change",
                                        "green estimate change", "blue estimate change",
                                        "red Monte Carlo total", "green Monte Carlo total",
                                        "blue Monte Carlo total"};
    _Static_assert(GI_QUAD_CHANNELS == 3, "one name per channel");
    for (size_t i = 0; i < sizeof sums / sizeof *sums && !r.failed; i++)
        if (!gi_result_summable(*sums[i]) || (i == 0 && *sums[i] < 0))
            return gi_fail(err, GI_EPROTO, "quadrature result: the %s is %g, not within %s%g",
                           names[i], *sums[i], i == 0 ? "0.." : "+-", GI_RESULT_SUM_MAX);
    int ok = !r.failed && out->reevals <= out->evals;
    /* The delta: skipped here (u32 count, then count x (u32 + C f64)). */
    out->delta = r;
    uint32_t pixels = gi_get_u32(&r);
    size_t each = 4 + 8 * GI_QUAD_CHANNELS;
    if (!ok || r.failed || (uint64_t)pixels * each > r.left)
        return gi_fail(err, GI_EPROTO, "quadrature result: bad header");
    r.p += (size_t)pixels * each;
    r.left -= (size_t)pixels * each;
    out->open_count = gi_get_u32(&r);
    if (r.failed || (uint64_t)out->open_count * gi_quad_summary_bytes(rule) > r.left)
        return gi_fail(err, GI_EPROTO, "quadrature result: bad region count");
    *rest = r;
    return 0;
}

int gi_quad_result_decode_open(gi_reader *rest, const gi_quad_rule *rule, uint32_t count,
                               gi_quad_summary *open, gi_error *err)
{
    for (uint32_t i = 0; i < count; i++)
        if (gi_quad_summary_get(rest, rule, &open[i], err))
            return -1;
    return gi_reader_finish(rest, err);
}

/* ---- worker side ---- */

/* Kept across the tasks of a job in one worker process. */
typedef struct quad_worker {
    gi_quad_rule rule;
    gi_quad_path path;
    gi_quad_engine engine;
    gi_quad_accum acc;
    gi_qheap *heap;
    /* Per engine slot: the task summary a region came from (its splat is
     * the one in the image), or NULL for regions made here. */
    const gi_quad_summary **root;
    size_t root_cap;
    gi_anim_poser poser; /* an animation's scene and ray tracer, posed */
} quad_worker;

static void worker_free(void *state)
{
    quad_worker *w = state;
    if (!w)
        return;
    gi_qheap_free(w->heap);
    gi_quad_accum_free(&w->acc);
    gi_quad_engine_free(&w->engine);
    gi_quad_path_free(&w->path);
    gi_quad_rule_free(&w->rule);
    free(w->root);
    gi_anim_poser_free(&w->poser);
    free(w);
}

static quad_worker *worker_get(gi_worker_ctx *ctx, gi_error *err)
{
    if (ctx->method_state)
        return ctx->method_state;
    const gi_job *job = &ctx->job;
    const gi_quad_params *p = job->params;
    quad_worker *w = gi_xcalloc(1, sizeof *w);
    gi_quad_integrand fn = {gi_quad_path_eval, &w->path};
    gi_quad_image im = {job->width, job->height};
    if (gi_quad_job_rule(p, &w->rule, err) ||
        gi_quad_path_init(&w->path, &ctx->rt, &job->scene, gi_job_camera(job), job->width,
                          job->height, p->dims, p->max_bounces, p->rr_depth, err) ||
        gi_quad_engine_init(&w->engine, &w->rule, p->axis_rule, &im, &fn, err) ||
        gi_quad_accum_init(&w->acc, job->width, job->height, GI_QUAD_CHANNELS, err)) {
        worker_free(w);
        return NULL;
    }
    w->heap = gi_qheap_create(p->heap);
    ctx->method_state = w;
    ctx->method_state_free = worker_free;
    return w;
}

static void mc_eval(void *user, const double *u, gi_rng *rng, double *out)
{
    gi_quad_path_eval_mc(user, u, rng, out);
}

typedef struct refine_ctx {
    quad_worker *w;
    const gi_quad_params *p;
    uint64_t seed;
    double dtotal[GI_QUAD_CHANNELS];
    double mc_total[GI_QUAD_CHANNELS];
    double closed_err;
    uint64_t closed, mc_samples;
} refine_ctx;

static void clear_root(quad_worker *w, uint32_t slot)
{
    if (slot < w->root_cap)
        w->root[slot] = NULL;
}

static const gi_quad_summary *region_summary(const refine_ctx *c, const gi_quad_region *r)
{
    const gi_quad_summary *s = r->slot < c->w->root_cap ? c->w->root[r->slot] : NULL;
    return s ? s : &r->s;
}

static void on_split(void *user, const gi_quad_region *parent, gi_quad_region *const child[2])
{
    refine_ctx *c = user;
    const gi_quad_summary *ps = region_summary(c, parent);
    /* The children replace the parent in the image. */
    gi_quad_splat(&ps->interp, ps->lo, ps->hi, -1.0, &c->w->acc);
    for (int k = 0; k < 2; k++)
        gi_quad_splat(&child[k]->s.interp, child[k]->s.lo, child[k]->s.hi, 1.0, &c->w->acc);
    for (int ch = 0; ch < GI_QUAD_CHANNELS; ch++)
        c->dtotal[ch] += child[0]->s.est[ch] + child[1]->s.est[ch] - ps->est[ch];
    clear_root(c->w, parent->slot);
}

static void on_close(void *user, gi_quad_region *r)
{
    refine_ctx *c = user;
    const gi_quad_summary *s = region_summary(c, r);
    c->closed++;
    c->closed_err += s->err_raw;
    if (c->p->hybrid)
        c->mc_samples += gi_quad_hybrid_region(mc_eval, &c->w->path, c->seed, s, c->p->dims,
                                               c->p->mc_spp, &c->w->acc, c->mc_total);
    clear_root(c->w, r->slot);
}

static void put_header(gi_buf *out, uint64_t evals, uint64_t reevals, uint64_t splits,
                       const refine_ctx *c, uint64_t nonfinite)
{
    gi_buf_put_u64(out, evals);
    gi_buf_put_u64(out, reevals);
    gi_buf_put_u64(out, splits);
    gi_buf_put_u64(out, c->closed);
    gi_buf_put_u64(out, c->mc_samples);
    gi_buf_put_u64(out, nonfinite);
    gi_buf_put_f64(out, c->closed_err);
    gi_buf_put_f64s(out, c->dtotal, GI_QUAD_CHANNELS);
    gi_buf_put_f64s(out, c->mc_total, GI_QUAD_CHANNELS);
}

static int run_refine(gi_worker_ctx *ctx, quad_worker *w, const gi_quad_task_in *t,
                      gi_buf *result, gi_error *err)
{
    const gi_quad_params *p = ctx->job.params;
    gi_quad_engine *e = &w->engine;
    refine_ctx c;
    memset(&c, 0, sizeof c);
    c.w = w;
    c.p = p;
    c.seed = ctx->job.seed;
    gi_quad_refine_cb cb = {on_split, on_close, NULL, &c};
    uint64_t evals0 = e->evals, nonfinite0 = w->path.nonfinite, splits = 0;
    int rc = 0;
    for (uint32_t i = 0; i < t->count && rc == 0; i++) {
        const gi_quad_summary *s = &t->regions[i];
        gi_quad_region *r = gi_quad_region_new(e, s->lo, s->hi, err);
        if (!r) {
            rc = -1;
            break;
        }
        if (r->slot >= w->root_cap) {
            size_t cap = w->root_cap ? 2 * w->root_cap : 256;
            while (cap <= r->slot)
                cap *= 2;
            w->root = gi_xrealloc(w->root, cap * sizeof *w->root);
            memset(w->root + w->root_cap, 0, (cap - w->root_cap) * sizeof *w->root);
            w->root_cap = cap;
        }
        if (t->is_new[i]) {
            /* Round 0: the region enters the image now. */
            gi_quad_splat(&r->s.interp, r->s.lo, r->s.hi, 1.0, &w->acc);
            for (int ch = 0; ch < GI_QUAD_CHANNELS; ch++)
                c.dtotal[ch] += r->s.est[ch];
        } else {
            w->root[r->slot] = s;
        }
        gi_quad_refine_offer(e, w->heap, r, t->threshold, &cb);
    }
    /* Re-evaluations: the samples of regions the coordinator sent back. */
    uint64_t reevals = 0;
    for (uint32_t i = 0; i < t->count; i++)
        reevals += t->is_new[i] ? 0 : w->rule.points;
    if (rc == 0)
        rc = gi_quad_refine(e, w->heap, t->threshold, t->max_splits, &cb, &splits, err);
    if (rc == 0) {
        put_header(result, e->evals - evals0, reevals, splits, &c, w->path.nonfinite - nonfinite0);
        gi_quad_accum_emit(&w->acc, result);
        gi_buf_put_u32(result, (uint32_t)gi_qheap_size(w->heap));
    }
    /* What is left is open: its summaries go back to the global heap, in
     * heap order. */
    double key;
    uint64_t tie;
    uint32_t slot;
    while (gi_qheap_pop(w->heap, &key, &tie, &slot)) {
        gi_quad_region *r = gi_quad_region_at(e, slot);
        if (rc == 0)
            gi_quad_summary_put(result, region_summary(&c, r), &w->rule);
        clear_root(w, slot);
        gi_quad_region_release(e, r);
    }
    if (rc != 0) {
        /* Leave the accumulator clean for the next task. */
        gi_buf scratch;
        gi_buf_init(&scratch);
        gi_quad_accum_emit(&w->acc, &scratch);
        gi_buf_free(&scratch);
    }
    ctx->stats.samples = e->evals - evals0 + c.mc_samples;
    return rc;
}

static int run_mc(gi_worker_ctx *ctx, quad_worker *w, const gi_quad_task_in *t, gi_buf *result)
{
    const gi_quad_params *p = ctx->job.params;
    refine_ctx c;
    memset(&c, 0, sizeof c);
    uint64_t nonfinite0 = w->path.nonfinite;
    for (uint32_t i = 0; i < t->count; i++)
        c.mc_samples += gi_quad_hybrid_region(mc_eval, &w->path, ctx->job.seed, &t->regions[i],
                                              p->dims, p->mc_spp, &w->acc, c.mc_total);
    put_header(result, 0, 0, 0, &c, w->path.nonfinite - nonfinite0);
    gi_quad_accum_emit(&w->acc, result);
    gi_buf_put_u32(result, 0);
    ctx->stats.samples = c.mc_samples;
    return 0;
}

int gi_quad_run(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err)
{
    quad_worker *w = worker_get(ctx, err);
    if (!w)
        return -1;
    const gi_quad_params *p = ctx->job.params;
    gi_quad_task_in t;
    if (gi_quad_task_decode(task, &w->rule, p->anim.enabled ? p->anim.frames : 0, &t, err))
        return -1;
    if (t.animated &&
        gi_anim_poser_pose(&w->poser, &p->anim, &ctx->job.scene, &ctx->rt, t.frame, err)) {
        gi_quad_task_in_free(&t);
        return -1;
    }
    if (t.animated) {
        /* The frame's camera (its path's, or the job's in every frame), and
         * no camera vertex kept from a task of another frame. */
        gi_camera cam;
        gi_anim_camera(&p->anim, gi_job_camera(&ctx->job), t.frame, &cam);
        gi_camera_frame_init(&w->path.cam, &cam, ctx->job.width, ctx->job.height);
        w->path.cache_valid = 0;
    }
    int rc = t.kind == GI_QUAD_TASK_REFINE ? run_refine(ctx, w, &t, result, err)
                                           : run_mc(ctx, w, &t, result);
    gi_quad_task_in_free(&t);
    return rc;
}

/* Tests only (gi_method.h). A NaN: the red estimate change, after six u64
 * counts and the closed error (13 eight-byte values in all). Huge: the
 * first pixel's red value of the image delta (after its u32 count and u32
 * index), 1e100: finite in f64 and far within GI_RESULT_SUM_MAX, but beyond
 * FLT_MAX, the float the image is written in; a result without pixels gets
 * 1e300 as its red estimate change instead. */
int gi_quad_damage_result(const gi_job *job, const gi_task *task, gi_buf *result,
                          gi_damage how)
{
    (void)job;
    (void)task;
    if (result->len < 108)
        return 1;
    double v = how == GI_DAMAGE_NAN ? NAN : 1e300;
    size_t at = 56;
    if (how == GI_DAMAGE_HUGE && gi_le_get_u32(result->data + 104) > 0 && result->len >= 120) {
        v = 1e100;
        at = 112;
    }
    memcpy(result->data + at, &v, 8);
    return 0;
}
