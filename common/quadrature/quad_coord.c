/* quad_coord: the coordinator side of the quadrature method - the global
 * heap of open regions, the image accumulator, the rounds (plan, merge,
 * finish), checkpoints, and the report. Never calls Embree.
 *
 * An animation (quadrature.animation) renders its frames one after
 * another, each a whole adaptive run from round 0 with a state of its own:
 * its tasks carry the frame (the workers pose the mobile), finish writes
 * NAME.0003.exr and the frame's report, then plans the next frame that
 * moves (a held frame is the same image, written again). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_job.h"
#include "gi_clock.h"
#include "gi_log.h"
#include "gi_outputs.h"
#include "quad_accum.h"
#include "quad_farm.h"
#include "quad_hybrid.h"

enum { PHASE_REFINE, PHASE_MC, PHASE_DONE };

/* Regions per task at most (round 0 and Monte Carlo tasks): keeps a task
 * payload far below the protocol's 256 MiB. */
#define MAX_TASK_REGIONS 65536u

typedef struct quad_state {
    gi_quad_rule rule;
    double *image; /* width x height x 3: the current estimate, pixel values */
    /* Open regions: summaries in a slab, their slots in the heap. */
    gi_quad_summary *leaf;
    uint32_t nleaf, leaf_cap;
    uint32_t *leaf_free;
    uint32_t nfree;
    uint8_t *leaf_live;
    gi_qheap *heap;
    /* Sums over every region (open and closed). */
    double total[GI_QUAD_CHANNELS];    /* estimates */
    double mc_total[GI_QUAD_CHANNELS]; /* Monte Carlo residuals added to the image */
    double closed_err;              /* error estimates of the closed ones */
    uint64_t evals, reevals, splits, closed, mc_samples, nonfinite;
    uint64_t open_final; /* regions open when the refinement stopped */
    double err_final;    /* and the sum of every region's error estimate then */
    uint32_t frame;  /* an animation's frame being computed (0 for a still) */
    uint32_t round;  /* the round whose tasks are out (0: the initial regions) */
    int phase;
    double threshold_abs;
    /* Evaluations merged when the current round was planned plus that
     * round's task costs: what max_evals has left (progress; not saved). */
    double budget_planned;
    double splat_rel; /* |sum of pixels x area - sum of estimates| / sum, before Monte Carlo */
    double seconds;   /* coordinator wall time before this process took over */
    double t0;
} quad_state;

static quad_state *state_new(gi_job *job, gi_error *err)
{
    const gi_quad_params *p = job->params;
    quad_state *st = gi_xcalloc(1, sizeof *st);
    job->state = st;
    if (gi_quad_job_rule(p, &st->rule, err))
        return NULL;
    st->image = gi_try_calloc((size_t)job->width * (size_t)job->height,
                              GI_QUAD_CHANNELS * sizeof(double), err, "quadrature image");
    if (!st->image)
        return NULL;
    st->heap = gi_qheap_create(p->heap);
    st->t0 = gi_now();
    return st;
}

static void add_leaf(quad_state *st, const gi_quad_summary *s)
{
    uint32_t slot;
    if (st->nfree > 0) {
        slot = st->leaf_free[--st->nfree];
    } else {
        if (st->nleaf == st->leaf_cap) {
            st->leaf_cap = st->leaf_cap ? 2 * st->leaf_cap : 256;
            st->leaf = gi_xrealloc(st->leaf, st->leaf_cap * sizeof *st->leaf);
            st->leaf_live = gi_xrealloc(st->leaf_live, st->leaf_cap);
            st->leaf_free = gi_xrealloc(st->leaf_free, st->leaf_cap * sizeof *st->leaf_free);
        }
        slot = st->nleaf++;
    }
    st->leaf[slot] = *s;
    st->leaf_live[slot] = 1;
    gi_qheap_push(st->heap, s->err, s->id, slot);
}

/* Takes the first region out of the heap into *out. */
static int pop_leaf(quad_state *st, gi_quad_summary *out)
{
    double key;
    uint64_t tie;
    uint32_t slot;
    if (!gi_qheap_pop(st->heap, &key, &tie, &slot))
        return 0;
    *out = st->leaf[slot];
    st->leaf_live[slot] = 0;
    st->leaf_free[st->nfree++] = slot;
    return 1;
}

static double l1(const double *v)
{
    return fabs(v[0]) + fabs(v[1]) + fabs(v[2]);
}

/* Sum of the error estimates of every region. */
static double total_error(const quad_state *st)
{
    double e = st->closed_err;
    for (uint32_t i = 0; i < st->nleaf; i++)
        if (st->leaf_live[i])
            e += st->leaf[i].err_raw;
    return e;
}

static void add_task(gi_task_queue *q, const gi_job *job, quad_state *st,
                     const gi_quad_task_in *t, double cost)
{
    const gi_quad_params *p = job->params;
    gi_quad_task_in framed = *t;
    framed.animated = p->anim.enabled;
    framed.frame = st->frame;
    gi_task *task = gi_task_queue_add(q, t->kind, cost);
    gi_quad_task_encode(&task->payload, &framed, &st->rule);
    st->budget_planned += cost;
}

/* Round 0 of `frame` (a still's: 0), in a new state: the initial regions
 * (initial[0] x initial[1] image tiles, each path axis cut in
 * initial_path), dealt out in order. */
static int plan_frame(gi_job *job, uint32_t frame, gi_task_queue *q, gi_error *err)
{
    const gi_quad_params *p = job->params;
    quad_state *st = state_new(job, err);
    if (!st)
        return -1;
    st->frame = frame;
    gi_anim_set_frame(&p->anim, job, frame);
    int n = p->dims;
    uint64_t splits[GI_QUAD_MAX_DIMS], count = 1;
    for (int d = 0; d < n; d++) {
        splits[d] = d < 2 ? (uint64_t)p->initial[d] : (uint64_t)p->initial_path;
        count *= splits[d];
    }
    uint64_t per = (count + p->round_tasks - 1) / p->round_tasks;
    if (per > MAX_TASK_REGIONS)
        per = MAX_TASK_REGIONS;
    gi_quad_task_in t = {.kind = GI_QUAD_TASK_REFINE};
    t.is_new = gi_xcalloc(per, 1);
    t.regions = gi_xcalloc(per, sizeof *t.regions);
    memset(t.is_new, 1, per);
    for (uint64_t i = 0; i < count; i++) {
        gi_quad_summary *s = &t.regions[t.count++];
        memset(s, 0, sizeof *s);
        uint64_t rest = i;
        for (int d = n - 1; d >= 0; d--) {
            uint64_t k = rest % splits[d];
            rest /= splits[d];
            s->lo[d] = (double)k / (double)splits[d];
            s->hi[d] = (double)(k + 1) / (double)splits[d];
        }
        s->id = gi_quad_box_id(s->lo, s->hi, n);
        s->axis = -1;
        if (t.count == per || i + 1 == count) {
            add_task(q, job, st, &t, (double)t.count * (double)st->rule.points);
            t.count = 0;
        }
    }
    gi_quad_task_in_free(&t);
    return 0;
}

int gi_quad_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    return plan_frame(job, 0, q, err);
}

/* The next refinement round: the regions with the largest errors (above
 * the threshold), dealt out round-robin by rank to round_tasks tasks, each
 * with a bisection budget cut to what is left of max_evals. Returns the
 * number of tasks added (0: the budget cannot pay for one bisection). */
static int plan_refine_round(gi_job *job, quad_state *st, gi_task_queue *q)
{
    const gi_quad_params *p = job->params;
    uint64_t left = st->evals < p->max_evals ? p->max_evals - st->evals : 0;
    st->budget_planned = (double)st->evals;
    uint64_t want = (uint64_t)p->round_tasks * (uint64_t)p->task_regions;
    uint64_t pts = st->rule.points, split_cost = 2 * st->rule.child_new;
    gi_quad_summary *picked = gi_xcalloc(want, sizeof *picked);
    uint64_t k = 0;
    double key;
    uint64_t tie;
    uint32_t slot;
    while (k < want && gi_qheap_peek(st->heap, &key, &tie, &slot) && key >= st->threshold_abs)
        pop_leaf(st, &picked[k++]);
    uint64_t ntasks = k < (uint64_t)p->round_tasks ? k : (uint64_t)p->round_tasks;
    uint64_t per_task = ntasks ? left / ntasks : 0;
    gi_quad_task_in t = {
        .kind = GI_QUAD_TASK_REFINE, .round = st->round, .threshold = st->threshold_abs};
    t.is_new = gi_xcalloc(p->task_regions, 1);
    t.regions = gi_xcalloc(p->task_regions, sizeof *t.regions);
    int added = 0;
    for (uint64_t j = 0; j < ntasks; j++) {
        uint64_t regions = (k - j + ntasks - 1) / ntasks;
        uint64_t reeval = regions * pts;
        uint64_t budget = per_task > reeval ? (per_task - reeval) / split_cost : 0;
        if (budget > (uint64_t)p->task_splits)
            budget = (uint64_t)p->task_splits;
        t.count = 0;
        for (uint64_t r = j; r < k; r += ntasks) {
            if (budget == 0) {
                add_leaf(st, &picked[r]); /* not this round: back to the heap */
                continue;
            }
            t.regions[t.count++] = picked[r];
        }
        if (budget == 0)
            continue;
        t.max_splits = budget;
        add_task(q, job, st, &t, (double)(reeval + budget * split_cost));
        added++;
    }
    gi_quad_task_in_free(&t);
    free(picked);
    return added;
}

/* The Monte Carlo round: every region still open, about the same number of
 * samples per task. */
static int plan_mc_round(gi_job *job, quad_state *st, gi_task_queue *q)
{
    const gi_quad_params *p = job->params;
    size_t n = gi_qheap_size(st->heap);
    gi_quad_summary *all = gi_xcalloc(n ? n : 1, sizeof *all);
    uint64_t samples = 0;
    for (size_t i = 0; i < n; i++) {
        pop_leaf(st, &all[i]);
        samples += gi_quad_hybrid_samples(&all[i], job->width, job->height, p->mc_spp);
    }
    uint64_t per = samples / (uint64_t)p->round_tasks + 1, acc = 0;
    gi_quad_task_in t = {.kind = GI_QUAD_TASK_MC, .regions = all};
    size_t first = 0;
    int added = 0;
    for (size_t i = 0; i < n; i++) {
        acc += gi_quad_hybrid_samples(&all[i], job->width, job->height, p->mc_spp);
        if (acc >= per || i + 1 - first == MAX_TASK_REGIONS || i + 1 == n) {
            t.regions = all + first;
            t.count = (uint32_t)(i + 1 - first);
            add_task(q, job, st, &t, (double)acc);
            added++;
            first = i + 1;
            acc = 0;
        }
    }
    free(all);
    return added;
}

/* What a check decoded (gi_method.h, check_result's decoded): this head,
 * then the delta as the worker sent it (u32 count, count x (u32 index, C
 * f64), checked), then the open regions' summaries, decoded, at a multiple
 * of 8 bytes. One buffer, offsets and no pointers: gi_jobrun owns and
 * frees it as any gi_buf, and may move it. */
typedef struct quad_decoded {
    uint64_t evals, reevals, splits, closed, mc_samples, nonfinite;
    double closed_err;
    double dtotal[GI_QUAD_CHANNELS];
    double mc_total[GI_QUAD_CHANNELS];
    uint32_t pixels, open_count;
} quad_decoded;

/* A delta of that many pixels, in bytes. */
static size_t delta_bytes(uint32_t pixels)
{
    return 4 + (size_t)pixels * (4 + 8 * GI_QUAD_CHANNELS);
}

/* Where the open summaries of a decoded result of that many pixels start. */
static size_t open_at(uint32_t pixels)
{
    return (sizeof(quad_decoded) + delta_bytes(pixels) + 7) & ~(size_t)7;
}

/* Decodes and checks a result (task's bound on its delta) into out (reset
 * first): what the merge adds, without the worker's bytes. The summaries
 * are decoded straight into out, the delta's bytes copied as they are. */
static int quad_decode(const gi_job *job, const gi_task *task, const gi_buf *result,
                       gi_buf *out, gi_error *err)
{
    const quad_state *st = job->state;
    gi_quad_result r;
    gi_reader rest;
    if (gi_quad_result_decode_head(result, &st->rule, &r, &rest, err) ||
        gi_quad_accum_check(&r.delta, job->width, job->height, GI_QUAD_CHANNELS,
                            gi_quad_pixel_delta_max(task->id), err))
        return -1;
    gi_reader count = r.delta;
    uint32_t pixels = gi_get_u32(&count); /* checked: the bytes hold them */
    quad_decoded h = {.evals = r.evals, .reevals = r.reevals, .splits = r.splits,
                      .closed = r.closed, .mc_samples = r.mc_samples,
                      .nonfinite = r.nonfinite, .closed_err = r.closed_err,
                      .pixels = pixels, .open_count = r.open_count};
    memcpy(h.dtotal, r.dtotal, sizeof h.dtotal);
    memcpy(h.mc_total, r.mc_total, sizeof h.mc_total);
    gi_buf_reset(out);
    uint8_t *d = gi_buf_grow(out, open_at(pixels) + (size_t)r.open_count * sizeof(gi_quad_summary));
    memcpy(d, &h, sizeof h);
    memcpy(d + sizeof h, r.delta.p, delta_bytes(pixels));
    return gi_quad_result_decode_open(&rest, &st->rule, r.open_count,
                                      (gi_quad_summary *)(d + open_at(pixels)), err);
}

/* Whatever gi_quad_merge would refuse is refused as the result arrives:
 * its run then fails and the task runs again, instead of the job failing
 * at merge. What it decoded goes to decoded, for gi_quad_merge_decoded. */
int gi_quad_check_result(const gi_job *job, const gi_task *task, const gi_buf *result,
                         gi_buf *decoded, gi_error *err)
{
    gi_buf scratch;
    gi_buf_init(&scratch);
    int rc = quad_decode(job, task, result, decoded ? decoded : &scratch, err);
    gi_buf_free(&scratch);
    if (rc && decoded)
        gi_buf_free(decoded);
    return rc;
}

int gi_quad_merge(gi_job *job, const gi_task *task, const gi_buf *result, gi_task_queue *fq,
                  gi_error *err)
{
    gi_buf d;
    gi_buf_init(&d);
    int rc = quad_decode(job, task, result, &d, err);
    if (rc)
        rc = gi_error_prefix(err, "task %llu", (unsigned long long)task->id);
    else
        rc = gi_quad_merge_decoded(job, task, &d, fq, err);
    gi_buf_free(&d);
    return rc;
}

/* Nothing in a decoded result is refused once its size is right (its check
 * refused what the merge would), so nothing added is ever taken back. */
int gi_quad_merge_decoded(gi_job *job, const gi_task *task, const gi_buf *decoded,
                          gi_task_queue *fq, gi_error *err)
{
    (void)fq;
    quad_state *st = job->state;
    quad_decoded h;
    if (decoded->len < sizeof h)
        return gi_fail(err, GI_EINTERNAL, "quadrature task %llu: no decoded result",
                       (unsigned long long)task->id);
    memcpy(&h, decoded->data, sizeof h);
    if (decoded->len != open_at(h.pixels) + (size_t)h.open_count * sizeof(gi_quad_summary))
        return gi_fail(err, GI_EINTERNAL, "quadrature task %llu: decoded result of %zu bytes",
                       (unsigned long long)task->id, decoded->len);
    gi_reader delta;
    gi_reader_init(&delta, decoded->data + sizeof h, delta_bytes(h.pixels), "quadrature result");
    gi_quad_accum_add_delta(&delta, GI_QUAD_CHANNELS, st->image);
    st->evals += h.evals;
    st->reevals += h.reevals;
    st->splits += h.splits;
    st->closed += h.closed;
    st->mc_samples += h.mc_samples;
    st->nonfinite += h.nonfinite;
    st->closed_err += h.closed_err;
    for (int c = 0; c < GI_QUAD_CHANNELS; c++) {
        st->total[c] += h.dtotal[c];
        st->mc_total[c] += h.mc_total[c];
    }
    const gi_quad_summary *open = (const gi_quad_summary *)(decoded->data + open_at(h.pixels));
    for (uint32_t i = 0; i < h.open_count; i++)
        add_leaf(st, &open[i]);
    return 0;
}

/* Sum of pixel values x pixel area, less the Monte Carlo residuals, against
 * the sum of region estimates. */
static double splat_check(const gi_job *job, const quad_state *st)
{
    size_t n = (size_t)job->width * job->height;
    double sum[GI_QUAD_CHANNELS] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < GI_QUAD_CHANNELS; c++)
            sum[c] += st->image[GI_QUAD_CHANNELS * i + c];
    double area = 1.0 / (double)n, diff = 0;
    for (int c = 0; c < GI_QUAD_CHANNELS; c++)
        diff += fabs(sum[c] * area - st->mc_total[c] - st->total[c]);
    double t = l1(st->total);
    return t > 0 ? diff / t : diff;
}

/* The image and the report of the state (a frame's); st: the quad_state. */
static int write_outputs(gi_job *job, void *state, gi_error *err)
{
    const gi_quad_params *p = job->params;
    const quad_state *st = state;
    gi_image img;
    static const char *const names[] = {"R", "G", "B"};
    if (gi_image_init(&img, job->width, job->height, 3, names, err))
        return -1;
    size_t n = (size_t)job->width * job->height * GI_QUAD_CHANNELS;
    for (size_t i = 0; i < n; i++)
        img.pixels[i] = (float)st->image[i];
    int rc = gi_write_image_outputs(job, &img, err);
    gi_image_free(&img);
    if (rc)
        return -1;
    double seconds = st->seconds + (gi_now() - st->t0), err_est = st->err_final;
    uint64_t open = st->open_final;
    gi_info("%s: %llu evaluations (%llu re-evaluated), %llu regions, error estimate %.3g "
            "(relative %.3g), %.2f s",
            job->name, (unsigned long long)st->evals, (unsigned long long)st->reevals,
            (unsigned long long)(open + st->closed), err_est,
            l1(st->total) > 0 ? err_est / l1(st->total) : 0.0, seconds);
    cJSON *doc = cJSON_CreateObject();
    static const char *const rules[] = {"boole", "genz-malik"};
    static const char *const heaps[] = {"bucketed", "binary", "pairing"};
    cJSON_AddStringToObject(doc, "method", "quadrature");
    cJSON_AddNumberToObject(doc, "dims", p->dims);
    cJSON_AddStringToObject(doc, "rule", rules[p->rule]);
    cJSON_AddStringToObject(doc, "heap", heaps[p->heap]);
    cJSON_AddNumberToObject(doc, "evaluations", (double)st->evals);
    cJSON_AddNumberToObject(doc, "reevaluations", (double)st->reevals);
    cJSON_AddNumberToObject(doc, "bisections", (double)st->splits);
    cJSON_AddNumberToObject(doc, "regions", (double)(open + st->closed));
    cJSON_AddNumberToObject(doc, "regions_open", (double)open);
    cJSON_AddNumberToObject(doc, "regions_closed", (double)st->closed);
    cJSON_AddNumberToObject(doc, "rounds", st->round + 1);
    cJSON_AddNumberToObject(doc, "threshold", st->threshold_abs);
    cJSON_AddNumberToObject(doc, "error_estimate", err_est);
    cJSON_AddNumberToObject(doc, "relative_error_estimate",
                            l1(st->total) > 0 ? err_est / l1(st->total) : 0.0);
    cJSON *est = cJSON_AddArrayToObject(doc, "integral");
    for (int c = 0; c < GI_QUAD_CHANNELS; c++)
        cJSON_AddItemToArray(est, cJSON_CreateNumber(st->total[c]));
    cJSON_AddNumberToObject(doc, "splat_conservation", st->splat_rel);
    cJSON_AddNumberToObject(doc, "mc_samples", (double)st->mc_samples);
    cJSON_AddNumberToObject(doc, "nonfinite_samples", (double)st->nonfinite);
    cJSON_AddNumberToObject(doc, "seconds", seconds);
    if (p->anim.enabled) {
        /* The frame, and the mobile's pose: rows of the 3 x 4 matrix applied
         * to its vertices as loaded. */
        cJSON *a = cJSON_AddObjectToObject(doc, "animation");
        cJSON_AddNumberToObject(a, "frame", st->frame);
        cJSON_AddNumberToObject(a, "frames", p->anim.frames);
        cJSON_AddStringToObject(a, "object", p->anim.object);
        cJSON_AddItemToObject(a, "pose", gi_anim_pose_json(&p->anim, st->frame));
        gi_anim_report_camera(&p->anim, gi_job_camera(job), st->frame, a);
    }
    rc = gi_write_json_output(job, "report", doc, err);
    cJSON_Delete(doc);
    return rc;
}

static void state_free(quad_state *st)
{
    if (!st)
        return;
    gi_quad_rule_free(&st->rule);
    free(st->image);
    free(st->leaf);
    free(st->leaf_free);
    free(st->leaf_live);
    gi_qheap_free(st->heap);
    free(st);
}

/* The frame's outputs (a still's), then an animation's next frame that
 * moves, in a state of its own; the frames between, whose pose is the frame
 * before's, are the same image and report, written again. A failed write
 * leaves the frame's state DONE as it was, for finish again. */
static int write_frames(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    const gi_quad_params *p = job->params;
    quad_state *st = job->state;
    int rc = gi_anim_write_frames(&p->anim, job, &st->frame, write_outputs, st, err);
    if (rc <= 0)
        return rc;
    uint32_t next = st->frame;
    state_free(st);
    job->state = NULL;
    return plan_frame(job, next, fq, err);
}

int gi_quad_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    const gi_quad_params *p = job->params;
    quad_state *st = job->state;
    if (st->phase == PHASE_REFINE) {
        if (st->round == 0)
            /* Thesis Algorithm 1's THRESHOLD, relative to the image
             * integral the initial regions estimate. */
            st->threshold_abs = p->threshold * l1(st->total);
        double key;
        uint64_t tie;
        uint32_t slot;
        int go = gi_qheap_peek(st->heap, &key, &tie, &slot) && key >= st->threshold_abs &&
                 st->evals < p->max_evals &&
                 !(p->tolerance > 0 && total_error(st) <= p->tolerance * l1(st->total));
        if (go) {
            st->round++;
            if (plan_refine_round(job, st, fq) > 0)
                return 0;
            st->round--;
        }
        st->splat_rel = splat_check(job, st);
        st->open_final = gi_qheap_size(st->heap);
        st->err_final = total_error(st);
        st->phase = PHASE_DONE;
        if (p->hybrid && gi_qheap_size(st->heap) > 0) {
            st->phase = PHASE_MC;
            plan_mc_round(job, st, fq);
            return 0;
        }
    } else if (st->phase == PHASE_MC) {
        st->phase = PHASE_DONE;
    }
    return write_frames(job, fq, err);
}

/* The outputs are written once the phase is DONE, from the image and the
 * counts a checkpoint holds: a failed write can be made again. */
int gi_quad_can_finish_again(const gi_job *job)
{
    const quad_state *st = job->state;
    return st->phase == PHASE_DONE;
}

/* The refinement's rounds still to plan, as what max_evals has left. */
void gi_quad_progress(const gi_job *job, gi_job_progress *out)
{
    const gi_quad_params *p = job->params;
    const quad_state *st = job->state;
    double left = (double)p->max_evals - st->budget_planned;
    out->cost_unplanned = st->phase == PHASE_REFINE && left > 0 ? left : 0;
    out->frame = p->anim.enabled ? st->frame : 0;
    out->frames = p->anim.enabled ? p->anim.frames : 1;
}

/* ---- checkpoints ---- */

/* 2: the frame being computed (1: a still's, frame 0). */
#define QUAD_STATE_VERSION 2u

int gi_quad_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    const quad_state *st = job->state;
    gi_buf_put_u32(out, QUAD_STATE_VERSION);
    gi_buf_put_u32(out, st->frame);
    gi_buf_put_u32(out, st->round);
    gi_buf_put_u32(out, (uint32_t)st->phase);
    gi_buf_put_f64(out, st->threshold_abs);
    gi_buf_put_f64(out, st->splat_rel);
    gi_buf_put_f64(out, st->seconds + (gi_now() - st->t0));
    gi_buf_put_f64s(out, st->total, GI_QUAD_CHANNELS);
    gi_buf_put_f64s(out, st->mc_total, GI_QUAD_CHANNELS);
    gi_buf_put_f64(out, st->closed_err);
    gi_buf_put_u64(out, st->open_final);
    gi_buf_put_f64(out, st->err_final);
    gi_buf_put_u64(out, st->evals);
    gi_buf_put_u64(out, st->reevals);
    gi_buf_put_u64(out, st->splits);
    gi_buf_put_u64(out, st->closed);
    gi_buf_put_u64(out, st->mc_samples);
    gi_buf_put_u64(out, st->nonfinite);
    gi_buf_put_f64s(out, st->image, (size_t)job->width * job->height * GI_QUAD_CHANNELS);
    /* Open regions in slot order; the heap's total order makes the restored
     * heap pop them in the same sequence. */
    gi_buf_put_u32(out, (uint32_t)gi_qheap_size(st->heap));
    for (uint32_t i = 0; i < st->nleaf; i++)
        if (st->leaf_live[i])
            gi_quad_summary_put(out, &st->leaf[i], &st->rule);
    return 0;
}

int gi_quad_load(gi_job *job, gi_reader *in, gi_error *err)
{
    const gi_quad_params *p = job->params;
    quad_state *st = state_new(job, err);
    if (!st)
        return -1;
    uint32_t version = gi_get_u32(in);
    st->frame = version >= 2 ? gi_get_u32(in) : 0;
    st->round = gi_get_u32(in);
    st->phase = (int)gi_get_u32(in);
    st->threshold_abs = gi_get_f64(in);
    st->splat_rel = gi_get_f64(in);
    st->seconds = gi_get_f64(in);
    gi_get_f64s(in, st->total, GI_QUAD_CHANNELS);
    gi_get_f64s(in, st->mc_total, GI_QUAD_CHANNELS);
    st->closed_err = gi_get_f64(in);
    st->open_final = gi_get_u64(in);
    st->err_final = gi_get_f64(in);
    st->evals = gi_get_u64(in);
    st->budget_planned = (double)st->evals; /* the round out is not known */
    st->reevals = gi_get_u64(in);
    st->splits = gi_get_u64(in);
    st->closed = gi_get_u64(in);
    st->mc_samples = gi_get_u64(in);
    st->nonfinite = gi_get_u64(in);
    if (in->failed || version < 1 || version > QUAD_STATE_VERSION || st->phase < PHASE_REFINE ||
        st->phase > PHASE_DONE || !(st->threshold_abs >= 0) ||
        st->frame >= (p->anim.enabled ? p->anim.frames : 1))
        return gi_fail(err, GI_EPROTO, "quadrature checkpoint: bad header");
    gi_anim_set_frame(&p->anim, job, st->frame);
    if (gi_get_f64s(in, st->image, (size_t)job->width * job->height * GI_QUAD_CHANNELS))
        return gi_fail(err, GI_EPROTO, "quadrature checkpoint: truncated image");
    uint32_t n = gi_get_u32(in);
    if (in->failed || (uint64_t)n * gi_quad_summary_bytes(&st->rule) > in->left)
        return gi_fail(err, GI_EPROTO, "quadrature checkpoint: bad region count");
    for (uint32_t i = 0; i < n; i++) {
        gi_quad_summary s;
        if (gi_quad_summary_get(in, &st->rule, &s, err))
            return gi_error_prefix(err, "quadrature checkpoint");
        add_leaf(st, &s);
    }
    return 0;
}

void gi_quad_release(gi_job *job)
{
    state_free(job->state);
    free(job->params);
    job->state = job->params = NULL;
}
