/* detp_anim_job: a detp animation on the coordinator (thesis ch. 4 as a
 * batch job).
 *
 * Frame 0 is a bake whose batches the workers also keep on disk. Every
 * later frame sends one update task per batch: the worker moves its stored
 * segments from the frame before to this one (only the paths the mobile
 * touches are retraced) and returns, for the static vertices, the change of
 * their sums (new segments added, old ones subtracted: eq. 4.4) and, for
 * the mobile's vertices, their sums from scratch (thesis 1.12.4). The sums
 * are integers (fixed point), so frame t's result equals a full recompute
 * over frame t's segments bit for bit, whatever the split or the order.
 * A frame's image tiles and outputs (NAME.0003.exr ...) follow its bake;
 * then the next frame is planned. */
#include <stdlib.h>
#include <string.h>

#include "detp_anim.h"
#include "detp_method.h"
#include "gi_clock.h"

typedef struct detp_anim_state {
    uint32_t frame;   /* the frame being computed */
    int64_t *sum;     /* 3 per vertex: exact sums in fixed-point units */
    int64_t *hits;    /* crossings per vertex */
    /* No sum or hit count has a larger magnitude (detp_anim_decode): kept
     * by the merges, reset from the totals when a checkpoint is loaded. */
    uint64_t bound;
    detp_anim_result tot; /* this frame's batches, summed */
    gi_vec3 *base_pos, *base_nrm; /* the mobile as loaded: the PLY shows it posed */
    /* Segments from the mobile over all segments, in the first batch of
     * frame 0 merged: about the share a later frame replaces (< 0: not
     * known yet, or restored from a checkpoint that did not keep it). */
    double from_mobile_share;
    double wall_frame;    /* coordinator clock at the frame's start (not saved) */
} detp_anim_state;

void detp_anim_free(detp_anim_state *a)
{
    if (!a)
        return;
    free(a->sum);
    free(a->hits);
    free(a->base_pos);
    free(a->base_nrm);
    free(a);
}

uint32_t detp_anim_frame(const detp_state *st) { return st->anim->frame; }

static int anim_new(gi_job *job, detp_state *st, gi_error *err)
{
    detp_anim_state *a = gi_xcalloc(1, sizeof *a);
    a->sum = gi_try_calloc((size_t)job->scene.vertex_count * 3 + 1, sizeof *a->sum, err,
                           "detp animation sums");
    a->hits = gi_try_calloc((size_t)job->scene.vertex_count + 1, sizeof *a->hits, err,
                            "detp animation hits");
    if (!a->sum || !a->hits) {
        detp_anim_free(a);
        return -1;
    }
    const gi_detp_params *p = job->params;
    const gi_object *o = &job->scene.objects[p->anim.object_index];
    a->base_pos = gi_xmalloc(((size_t)o->vertex_count + 1) * sizeof *a->base_pos);
    a->base_nrm = gi_xmalloc(((size_t)o->vertex_count + 1) * sizeof *a->base_nrm);
    memcpy(a->base_pos, &job->scene.positions[o->first_vertex],
           o->vertex_count * sizeof *a->base_pos);
    memcpy(a->base_nrm, &job->scene.normals[o->first_vertex],
           o->vertex_count * sizeof *a->base_nrm);
    a->from_mobile_share = -1;
    st->anim = a;
    return 0;
}

/* One task per batch for frame `frame`; a batch sticks to the worker host
 * that holds its segments (affinity). */
static void plan_frame(gi_job *job, uint32_t frame, gi_task_queue *q)
{
    const gi_detp_params *p = job->params;
    uint32_t b = 0;
    for (uint64_t p0 = 0; p0 < p->photon_count; p0 += (uint64_t)p->batch, b++) {
        uint64_t p1 = p0 + (uint64_t)p->batch;
        if (p1 > p->photon_count)
            p1 = p->photon_count;
        gi_task *t = gi_task_queue_add(q, frame ? DETP_TASK_ANIM_UPDATE : DETP_TASK_ANIM_BATCH,
                                       (double)(p1 - p0));
        t->affinity = (uint64_t)b + 1;
        detp_task_encode(t->kind, &(detp_task_in){.p0 = p0, .p1 = p1, .frame = frame, .batch = b},
                         &t->payload);
    }
}

static void reset_frame_counters(detp_state *st)
{
    memset(&st->anim->tot, 0, sizeof st->anim->tot);
    st->batches = st->photons = st->segments = 0;
    st->rays_trace = st->rays_image = 0;
    st->sec_trace = st->sec_build = st->sec_estimate = st->sec_image = 0;
    memset(&st->stats, 0, sizeof st->stats);
    st->anim->wall_frame = gi_now();
    st->wall_start = st->anim->wall_frame;
}

int detp_anim_plan(gi_job *job, detp_state *st, gi_task_queue *q, gi_error *err)
{
    if (anim_new(job, st, err))
        return -1;
    reset_frame_counters(st);
    plan_frame(job, 0, q);
    return 0;
}

/* Decodes a batch's result into h, checked against the frame's running
 * totals (detp_anim_decode), its entries appended to entries (or NULL). */
static int decode_result(const gi_job *job, const gi_task *t, const gi_buf *result,
                         detp_anim_result *h, gi_buf *entries, gi_error *err)
{
    const detp_state *st = job->state;
    const detp_anim_state *a = st->anim;
    detp_task_in in;
    if (detp_task_decode(job, t, 0, &in, err))
        return -1;
    uint32_t frame = in.frame, batch = in.batch;
    if (frame != a->frame)
        return gi_fail(err, GI_EPROTO, "a task of frame %u while at frame %u", frame,
                       a->frame);
    gi_reader r;
    gi_reader_init(&r, result->data, result->len, "detp animation result");
    /* Whose result it is, before anything is added. */
    gi_reader head = r;
    if (detp_anim_header_get(&head, h, 1) == 0 && (h->frame != frame || h->batch != batch))
        return gi_fail(err, GI_EPROTO, "result of frame %u batch %u", h->frame, h->batch);
    /* Frame 0's totals start at zero: B batches each within INT64_MAX / B
     * cannot overflow them. */
    const gi_detp_params *p = job->params;
    uint64_t batches = (p->photon_count + (uint64_t)p->batch - 1) / (uint64_t)p->batch;
    int64_t max = INT64_MAX / (int64_t)(batches ? batches : 1);
    if (detp_anim_decode(&r, st->nv, max, h, a->sum, a->hits, a->bound, entries, err))
        return gi_error_prefix(err, "frame %u, batch %u", frame, batch);
    return 0;
}

/* The totals it reads are written only by merges, which run on the thread
 * that checks, and by the frame's finish (on a thread of its own in
 * gi-farmd), which starts once all the frame's tasks are merged: none is
 * leased then, so none is checked. decoded: the header, then the entries
 * (detp_anim_entry; the header's size keeps them aligned). */
int detp_anim_check(const gi_job *job, const gi_task *t, const gi_buf *result,
                    gi_buf *decoded, gi_error *err)
{
    detp_anim_result h;
    if (!decoded)
        return decode_result(job, t, result, &h, NULL, err);
    _Static_assert(sizeof h % _Alignof(detp_anim_entry) == 0, "entries after the header");
    gi_buf_reset(decoded);
    gi_buf_grow(decoded, sizeof h);
    if (decode_result(job, t, result, &h, decoded, err))
        return -1;
    memcpy(decoded->data, &h, sizeof h);
    return 0;
}

int detp_anim_merge(gi_job *job, const gi_task *t, const gi_buf *result, gi_error *err)
{
    gi_buf d;
    gi_buf_init(&d);
    int rc = detp_anim_check(job, t, result, &d, err);
    if (rc)
        gi_error_prefix(err, "detp task %llu", (unsigned long long)t->id);
    else
        rc = detp_anim_merge_decoded(job, t, &d, err);
    gi_buf_free(&d);
    return rc;
}

int detp_anim_merge_decoded(gi_job *job, const gi_task *t, const gi_buf *decoded,
                            gi_error *err)
{
    detp_state *st = job->state;
    detp_anim_state *a = st->anim;
    detp_anim_result h;
    if (decoded->len < sizeof h || (decoded->len - sizeof h) % sizeof(detp_anim_entry))
        return gi_fail(err, GI_EINTERNAL, "detp task %llu: decoded result of %zu bytes",
                       (unsigned long long)t->id, decoded->len);
    memcpy(&h, decoded->data, sizeof h);
    if (h.frame != a->frame) /* checked for this frame; merged before it ends */
        return gi_fail(err, GI_EINTERNAL, "detp task %llu: result of frame %u at frame %u",
                       (unsigned long long)t->id, h.frame, a->frame);
    /* Against the totals as they now stand: results merged since its
     * check may have brought them close to the limit. */
    const detp_anim_entry *e = (const detp_anim_entry *)(decoded->data + sizeof h);
    if (detp_anim_add(e, (decoded->len - sizeof h) / sizeof *e, a->sum, a->hits, &a->bound,
                      "detp animation result", err))
        return gi_error_prefix(err, "detp task %llu: frame %u, batch %u",
                               (unsigned long long)t->id, h.frame, h.batch);
    uint32_t frame = h.frame;
    detp_anim_result *s = &a->tot;
    s->photons += h.photons;
    s->paths_examined += h.paths_examined;
    s->segments += h.segments;
    s->segments_old += h.segments_old;
    s->segments_new += h.segments_new;
    s->paths_retraced += h.paths_retraced;
    s->segments_repaired += h.segments_repaired;
    s->bv_passes += h.bv_passes;
    s->rays += h.rays;
    s->regenerated_frames += h.regenerated_frames;
    s->segments_from_mobile += h.segments_from_mobile;
    /* The first batch merged says it for the job, so that the weights of
     * its frames (detp_progress) stay put: the fraction never goes back. */
    if (frame == 0 && a->from_mobile_share < 0 && h.segments)
        a->from_mobile_share = (double)h.segments_from_mobile / (double)h.segments;
    s->sec_build += h.sec_build;
    s->sec_load += h.sec_load;
    s->sec_regenerate += h.sec_regenerate;
    s->sec_trace += h.sec_trace;
    s->sec_static += h.sec_static;
    s->sec_mobile += h.sec_mobile;
    s->sec_store += h.sec_store;
    gi_detp_stats_add(&s->stats, &h.stats);
    return 0;
}

int detp_anim_fill(gi_job *job, detp_state *st, gi_error *err)
{
    const gi_detp_params *p = job->params;
    const detp_anim_state *a = st->anim;
    /* The mobile where this frame has it, for the PLY. */
    gi_mat4 m;
    gi_anim_pose(&p->anim, a->frame, &m);
    if (gi_scene_pose_object(&job->scene, p->anim.object_index, a->base_pos, a->base_nrm, &m,
                             err))
        return -1;
    /* Fixed point -> energy -> irradiance (over the disc area). */
    double k = gi_detp_fixed_unit(job->scene.total_power, p->photon_count) /
               (GI_PI * (double)p->disc_radius * (double)p->disc_radius);
    for (size_t i = 0; i < (size_t)st->nv * 3; i++)
        st->irr[i] = (double)a->sum[i] * k;
    for (uint32_t i = 0; i < st->nv; i++)
        st->hits[i] = a->hits[i] > 0 ? (uint64_t)a->hits[i] : 0;
    const detp_anim_result *s = &a->tot;
    st->batches = (uint64_t)((p->photon_count + (uint64_t)p->batch - 1) / (uint64_t)p->batch);
    st->photons = s->photons;
    st->segments = s->segments;
    st->rays_trace = s->rays;
    st->sec_build = s->sec_build;
    st->sec_trace = s->sec_trace + s->sec_regenerate;
    st->sec_estimate = s->sec_static + s->sec_mobile;
    st->stats = s->stats;
    return 0;
}

int detp_anim_next_frame(gi_job *job, detp_state *st, gi_task_queue *q)
{
    const gi_detp_params *p = job->params;
    detp_anim_state *a = st->anim;
    if (a->frame + 1 >= p->anim.frames)
        return 0;
    a->frame++;
    /* The mobile's vertices are recomputed from scratch each frame (all of
     * them with "update": "full"). */
    const gi_object *o = &job->scene.objects[p->anim.object_index];
    uint32_t v0 = o->first_vertex, nv = o->vertex_count;
    if (p->anim_update == GI_DETP_UPDATE_FULL) {
        v0 = 0;
        nv = st->nv;
    }
    memset(&a->sum[3 * (size_t)v0], 0, 3 * (size_t)nv * sizeof *a->sum);
    memset(&a->hits[v0], 0, (size_t)nv * sizeof *a->hits);
    reset_frame_counters(st);
    plan_frame(job, a->frame, q);
    return 1;
}

static void add_num(cJSON *o, const char *k, double v) { cJSON_AddNumberToObject(o, k, v); }

cJSON *detp_anim_report(const gi_job *job, const detp_state *st)
{
    const gi_detp_params *p = job->params;
    const detp_anim_state *a = st->anim;
    const detp_anim_result *s = &a->tot;
    cJSON *o = cJSON_CreateObject();
    add_num(o, "frame", a->frame);
    add_num(o, "frames", p->anim.frames);
    cJSON_AddStringToObject(o, "object", p->anim.object);
    /* The mobile's pose: rows of the 3x4 matrix applied to its vertices
     * as loaded. */
    cJSON_AddItemToObject(o, "pose", gi_anim_pose_json(&p->anim, a->frame));
    gi_anim_report_camera(&p->anim, gi_job_camera(job), a->frame, o);
    add_num(o, "paths_tested", (double)s->photons);
    add_num(o, "paths_examined", (double)s->paths_examined);
    add_num(o, "paths_retraced", (double)s->paths_retraced);
    add_num(o, "segments", (double)s->segments);
    add_num(o, "segments_old", (double)s->segments_old);
    add_num(o, "segments_new", (double)s->segments_new);
    add_num(o, "segments_second_hit_repaired", (double)s->segments_repaired);
    add_num(o, "segments_past_bounding_pretest", (double)s->bv_passes);
    add_num(o, "rays", (double)s->rays);
    add_num(o, "frames_regenerated", (double)s->regenerated_frames);
    if (a->frame == 0)
        add_num(o, "segments_from_mobile", (double)s->segments_from_mobile);
    cJSON *sec = cJSON_AddObjectToObject(o, "seconds");
    add_num(sec, "index_build", s->sec_build);
    add_num(sec, "store_read", s->sec_load);
    add_num(sec, "regenerate", s->sec_regenerate);
    add_num(sec, a->frame ? "test_and_retrace" : "photon_tracing", s->sec_trace);
    add_num(sec, a->frame ? "static_update" : "density_estimation", s->sec_static);
    add_num(sec, "mobile_vertices", s->sec_mobile);
    add_num(sec, "store_write", s->sec_store);
    return o;
}

double detp_anim_from_mobile_share(const detp_state *st) { return st->anim->from_mobile_share; }

void detp_anim_save(const detp_state *st, gi_buf *out)
{
    const detp_anim_state *a = st->anim;
    gi_buf_put_u32(out, a->frame);
    detp_anim_header_put(&a->tot, out);
    gi_buf_put_f64(out, a->from_mobile_share);
    for (size_t i = 0; i < (size_t)st->nv * 3; i++)
        gi_buf_put_u64(out, (uint64_t)a->sum[i]);
    for (uint32_t i = 0; i < st->nv; i++)
        gi_buf_put_u64(out, (uint64_t)a->hits[i]);
}

int detp_anim_load(gi_job *job, detp_state *st, gi_reader *in, uint32_t version, gi_error *err)
{
    const gi_detp_params *p = job->params;
    if (anim_new(job, st, err))
        return -1;
    detp_anim_state *a = st->anim;
    a->frame = gi_get_u32(in);
    if (detp_anim_header_get(in, &a->tot, version >= 3) || a->frame >= p->anim.frames)
        return gi_fail(err, GI_EPROTO, "%s: not a checkpoint of this detp animation", job->file);
    if (version >= 3) {
        a->from_mobile_share = gi_get_f64(in);
        if (!(a->from_mobile_share >= -1 && a->from_mobile_share <= 1))
            return gi_fail(err, GI_EPROTO, "%s: not a checkpoint of this detp animation",
                           job->file);
    }
    for (size_t i = 0; i < (size_t)st->nv * 3; i++)
        a->sum[i] = (int64_t)gi_get_u64(in);
    for (uint32_t i = 0; i < st->nv; i++)
        a->hits[i] = (int64_t)gi_get_u64(in);
    if (in->failed)
        return gi_fail(err, GI_EPROTO, "%s: truncated detp checkpoint", job->file);
    a->bound = detp_anim_bound(a->sum, a->hits, st->nv);
    a->wall_frame = gi_now();
    return 0;
}
