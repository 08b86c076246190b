/* detp_anim_worker: a detp animation in a worker process.
 *
 * Frame 0 of a batch traces its photons with the mobile at pose 0, stores
 * them (detp_batch.c) and estimates every vertex. Frame f > 0 opens the
 * batch as stored at f-1, updates it path by path (thesis Fig. 4.2,
 * detp_anim_update.c), subtracts the old segments' contributions from the
 * static vertices and adds the new ones' (Embree Disc Indexing over the
 * static discs: the thesis's choice for them), estimates the mobile's own
 * vertices from scratch, and stores the frame as a delta. A batch the
 * store does not have (another host ran it, the disk lost it) is
 * regenerated: traced at frame 0 and updated through frames 1..f-1, which
 * gives the very same segments (random numbers keyed by frame). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp_anim.h"
#include "detp_batch.h"
#include "detp_batch_shelf.h"
#include "detp_method.h"
#include "detp_sphere.h"
#include "gi_clock.h"
#include "gi_tile_hits.h"
#include "gi_worker_ctx.h"

/* The segments that may cross one of the mobile's discs: those that come
 * within the reach of its discs (gi_detp_object_disc_reach). */
typedef struct near_test {
    gi_vec3 c;
    float rr;
} near_test;

/* The mobile's bounding sphere and its discs' reach at a frame. They
 * depend on the frame alone: each frame's are computed once, for all the
 * batches of the frame and as the old pose of the next one, not by
 * posing the scene again per batch. */
typedef struct mobile_frame {
    uint32_t frame;
    int valid;
    gi_detp_mobile_pose sphere;
    near_test near;
    int clear; /* nothing but the mobile comes within its sphere (grown) */
} mobile_frame;

/* An old segment's static crossings: listed with the batch (ids), or
 * searched this frame (ids NULL: the unlisted_x entry `at`). */
typedef struct old_crossings {
    const uint32_t *ids;
    uint32_t n, at;
} old_crossings;

typedef struct detp_anim_worker {
    uint32_t object;
    gi_vec3 *base_pos, *base_nrm; /* the mobile's vertices as loaded */
    uint32_t *mobile_order; /* its discs' order for its estimate, from pose 0 */
    int scene_posed, rt_posed;
    uint32_t scene_frame, rt_frame;
    /* The static discs alone (the mobile's vertex range left out: its
     * discs would only slow the static update down), their index and
     * fixed-point sums. */
    gi_detp_discs static_discs;
    gi_detp_embree_index *static_index;
    gi_detp_accum static_acc;
    gi_detp_segments old_list, new_list, changed, near, regen[2];
    gi_detp_segments unlisted; /* old segments whose crossings are not known */
    gi_detp_crossings unlisted_x; /* their crossings, searched this frame */
    old_crossings *old_x;      /* per old segment: its crossings */
    size_t old_x_cap;
    gi_detp_crossings listed;  /* the new segments' static crossings */
    int64_t *sum, *hits; /* the result, per vertex */
    detp_grid_spec grid;  /* of the stored batches: the box the mobile can reach */
    uint8_t *mark;        /* per path of a batch: may come near the mobile */
    size_t mark_cap;
    detp_path *runs;      /* the marked paths' runs */
    size_t runs_cap;
    detp_batch_shelf shelf; /* batches kept open for their next frame */
    mobile_frame at[2]; /* the mobile's spheres at the last two frames asked */
} detp_anim_worker;

/* Mapped batch files a process keeps open between frames (the shelf's
 * budget): the four 30 MB batches of a million photons fit; pages of them
 * count in the process's RSS only once read, and are the kernel's to
 * reclaim. */
#define SHELF_BYTES ((size_t)256 << 20)

void detp_anim_worker_free(detp_anim_worker *a)
{
    if (!a)
        return;
    free(a->base_pos);
    free(a->base_nrm);
    free(a->mobile_order);
    gi_detp_embree_free(a->static_index);
    gi_detp_discs_free(&a->static_discs);
    gi_detp_accum_free(&a->static_acc);
    gi_detp_segments_free(&a->old_list);
    gi_detp_segments_free(&a->unlisted);
    gi_detp_crossings_free(&a->listed);
    gi_detp_crossings_free(&a->unlisted_x);
    free(a->old_x);
    gi_detp_segments_free(&a->new_list);
    gi_detp_segments_free(&a->changed);
    gi_detp_segments_free(&a->near);
    gi_detp_segments_free(&a->regen[0]);
    gi_detp_segments_free(&a->regen[1]);
    free(a->sum);
    free(a->hits);
    free(a->mark);
    free(a->runs);
    detp_batch_shelf_free(&a->shelf);
    free(a);
}

/* The grid of the stored batches (detp_grid.h): over the box that holds
 * the mobile's bounding sphere at every frame, grown by the disc radius and
 * margins, in cells of half the mobile's bounding radius: a frame reads
 * the paths listed in the cells its two spheres overlap, and halving the
 * cells from the whole radius cut those paths at the 2.5% sphere from 21k
 * to 16k a frame (a quarter: 15k, for longer lists). The same on every
 * host. */
static void grid_spec(const gi_detp_params *p, gi_detp_mobile_pose as_loaded, float radius,
                      detp_grid_spec *out)
{
    gi_vec3 lo = gi_v3(INFINITY, INFINITY, INFINITY), hi = gi_scale(lo, -1.0f);
    for (uint32_t f = 0; f < p->anim.frames; f++) {
        gi_mat4 m;
        gi_anim_pose(&p->anim, f, &m);
        double scale = sqrt(m.m[0][0] * m.m[0][0] + m.m[1][0] * m.m[1][0] +
                            m.m[2][0] * m.m[2][0]);
        float r = (float)(as_loaded.r * scale * 1.02) + radius + 1e-3f * (float)p->scene_size;
        gi_vec3 c = gi_mat4_point(&m, as_loaded.c), e = gi_v3(r, r, r);
        lo = gi_min_v3(lo, gi_sub(c, e));
        hi = gi_max_v3(hi, gi_add(c, e));
    }
    detp_grid_spec_make(lo, hi, 0.5f * as_loaded.r, out);
}

static int pose_scene(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t frame, gi_error *err);

/* The per-process animation state, created before the mobile first moves
 * (its vertices as loaded are the poses' reference). */
static int anim_state(gi_worker_ctx *ctx, detp_worker *w, detp_anim_worker **out,
                      gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    if (!gi_anim_moves_object(&p->anim))
        return gi_fail(err, GI_EPROTO, "detp: animation task for a job with no moving object");
    if (w->anim) {
        *out = w->anim;
        return 0;
    }
    const gi_scene *s = &ctx->job.scene;
    const gi_object *o = &s->objects[p->anim.object_index];
    detp_anim_worker *a = gi_xcalloc(1, sizeof *a);
    a->object = p->anim.object_index;
    size_t n = (size_t)o->vertex_count + 1;
    a->base_pos = gi_xmalloc(n * sizeof *a->base_pos);
    a->base_nrm = gi_xmalloc(n * sizeof *a->base_nrm);
    memcpy(a->base_pos, &s->positions[o->first_vertex], o->vertex_count * sizeof *a->base_pos);
    memcpy(a->base_nrm, &s->normals[o->first_vertex], o->vertex_count * sizeof *a->base_nrm);
    grid_spec(p, gi_detp_object_sphere(s, a->object), p->disc_radius, &a->grid);
    a->shelf.budget = SHELF_BYTES;
    a->sum = gi_try_calloc((size_t)s->vertex_count * 3 + 1, sizeof *a->sum, err, "detp sums");
    a->hits = gi_try_calloc((size_t)s->vertex_count + 1, sizeof *a->hits, err, "detp hits");
    w->anim = a;
    if (!a->sum || !a->hits)
        return -1;
    /* The discs (and any index over them) at pose 0, where frame 0's
     * estimate needs the mobile's; later frames recompute the mobile's
     * vertices on their own and use only the static discs' entries. */
    if (pose_scene(ctx, a, 0, err) || detp_worker_discs(ctx, w, err) ||
        gi_detp_anim_mobile_order(s, a->object, p->mobile_estimator, &p->sc,
                                  &a->mobile_order, err))
        return -1;
    gi_detp_discs *sd = &a->static_discs;
    sd->count = w->discs.count - o->vertex_count;
    sd->radius = w->discs.radius;
    sd->r2 = w->discs.r2;
    sd->d = gi_try_malloc(((size_t)sd->count + 1) * sizeof *sd->d, err, "static discs");
    if (!sd->d)
        return -1;
    memcpy(sd->d, w->discs.d, o->first_vertex * sizeof *sd->d);
    memcpy(sd->d + o->first_vertex, w->discs.d + o->first_vertex + o->vertex_count,
           (sd->count - o->first_vertex) * sizeof *sd->d);
    if (gi_detp_accum_init_fixed(&a->static_acc, sd->count,
                                 gi_detp_fixed_unit(s->total_power, p->photon_count), err) ||
        gi_detp_embree_build(ctx->rt.device, sd, &a->static_index, err))
        return -1;
    *out = a;
    return 0;
}

/* The static crossings of old segment o as listed with prev's newest
 * file, if o is one of its records: runs (the frame's marked paths) and
 * o are in photon order, *r is a cursor over runs. */
static int listed_crossings(const detp_batch *prev, const detp_path *runs, size_t nrun,
                            size_t *r, const gi_detp_segment *o, const uint32_t **ids,
                            uint32_t *n)
{
    if (!prev->cross_off)
        return 0;
    while (*r < nrun && runs[*r].photon < o->photon)
        ++*r;
    if (*r == nrun || runs[*r].photon != o->photon || o->bounce >= runs[*r].count)
        return 0;
    const gi_detp_store_mapping *d = detp_batch_newest(prev);
    const gi_detp_segment *at = &runs[*r].seg[o->bounce];
    if (at < d->seg || at >= d->seg + d->count)
        return 0;
    size_t i = (size_t)(at - d->seg);
    if (!prev->cross_known[i] || memcmp(at, o, sizeof *o) != 0)
        return 0;
    *ids = prev->cross_ids + prev->cross_off[i];
    *n = prev->cross_off[i + 1] - prev->cross_off[i];
    return 1;
}

/* Eq. 4.4 for the static vertices: the sums of the new segments minus
 * those of the old, into the global accumulator (the mobile's range is
 * left for mobile_vertices). An old segment that the frame before added
 * (most are: what met the mobile at its last pose) takes back the
 * crossings listed then, without a search; the others are searched. A new
 * segment on the line of the old one it replaces (a retraced suffix's
 * first segment, a repaired one) takes that one's crossings and searches
 * only beyond its end, if at all; the others are searched. The new
 * segments' crossings are listed for the next frame. */
static void static_update(gi_worker_ctx *ctx, detp_worker *w, detp_anim_worker *a,
                          const detp_batch *prev, size_t nrun, gi_detp_stats *st)
{
    const gi_object *o = &ctx->job.scene.objects[a->object];
    const gi_detp_segments *old = &a->old_list, *nl = &a->new_list;
    gi_detp_accum *sa = &a->static_acc;
    gi_detp_accum_clear(sa);
    sa->sign = -1;
    a->unlisted.count = 0;
    if (a->old_x_cap < old->count) {
        a->old_x_cap = 2 * old->count;
        free(a->old_x);
        a->old_x = gi_xmalloc(a->old_x_cap * sizeof *a->old_x);
    }
    size_t r = 0;
    for (size_t k = 0; k < old->count; k++) {
        const gi_detp_segment *g = &old->v[k];
        old_crossings *x = &a->old_x[k];
        if (listed_crossings(prev, a->runs, nrun, &r, g, &x->ids, &x->n)) {
            gi_detp_crossings_apply(g, x->ids, x->n, sa, st);
        } else {
            x->ids = NULL;
            x->at = (uint32_t)a->unlisted.count;
            *gi_detp_segments_push(&a->unlisted) = *g;
        }
    }
    gi_detp_embree_estimate_listed(a->static_index, &a->unlisted, sa, st, &a->unlisted_x);
    sa->sign = 1;
    gi_detp_crossings_reset(&a->listed);
    /* Both lists are in (photon, bounce) order: a cursor finds the twin. */
    size_t k = 0;
    for (size_t j = 0; j < nl->count; j++) {
        const gi_detp_segment *g = &nl->v[j];
        while (k < old->count && (old->v[k].photon < g->photon ||
                                  (old->v[k].photon == g->photon && old->v[k].bounce < g->bounce)))
            k++;
        const gi_detp_segment *t = k < old->count ? &old->v[k] : NULL;
        if (t && t->photon == g->photon && t->bounce == g->bounce &&
            memcmp(&t->org, &g->org, sizeof g->org) == 0 &&
            memcmp(&t->dir, &g->dir, sizeof g->dir) == 0) {
            const old_crossings *x = &a->old_x[k];
            const gi_detp_crossings *u = &a->unlisted_x;
            uint32_t n = x->ids ? x->n : u->off[x->at + 1] - u->off[x->at];
            const uint32_t *ids = x->ids ? x->ids : n ? u->ids + u->off[x->at] : NULL;
            gi_detp_embree_estimate_twin(a->static_index, g, t, ids, n, sa, st, &a->listed);
        } else {
            gi_detp_embree_estimate_one(a->static_index, g, sa, st, &a->listed);
        }
    }
    /* Static disc i is vertex i below the mobile's range, i + n above. */
    size_t v0 = o->first_vertex, n = o->vertex_count;
    memcpy(w->acc.fixed, sa->fixed, 3 * v0 * sizeof *sa->fixed);
    memcpy(w->acc.hits, sa->hits, v0 * sizeof *sa->hits);
    memcpy(w->acc.fixed + 3 * (v0 + n), sa->fixed + 3 * v0,
           3 * (sa->count - v0) * sizeof *sa->fixed);
    memcpy(w->acc.hits + v0 + n, sa->hits + v0, (sa->count - v0) * sizeof *sa->hits);
}

/* Gives b the static crossings of its newest file's records (`records`,
 * as written), listed in `l` for `listed`: a subsequence of records (the
 * same bits, photon order; a path's segments differ in bounce). */
static void attach_crossings(detp_batch *b, const gi_detp_segments *records,
                             const gi_detp_segments *listed, const gi_detp_crossings *l)
{
    const gi_detp_segments *c = records, *nl = listed;
    if (detp_batch_newest(b)->count != c->count || l->segments != nl->count)
        return;
    detp_batch_forget_crossings(b);
    b->cross_off = gi_xmalloc((c->count + 1) * sizeof *b->cross_off);
    b->cross_known = gi_xcalloc(c->count + 1, 1);
    b->cross_ids = gi_xmalloc((l->pairs + 1) * sizeof *b->cross_ids);
    size_t j = 0, pairs = 0;
    for (size_t i = 0; i < c->count; i++) {
        b->cross_off[i] = (uint32_t)pairs;
        if (j < nl->count && nl->v[j].photon == c->v[i].photon &&
            nl->v[j].bounce == c->v[i].bounce) {
            uint32_t n = l->off[j + 1] - l->off[j];
            if (n)
                memcpy(b->cross_ids + pairs, l->ids + l->off[j], n * sizeof *l->ids);
            pairs += n;
            b->cross_known[i] = 1;
            j++;
        }
    }
    b->cross_off[c->count] = (uint32_t)pairs;
    if (j != nl->count) /* not a subsequence after all: list nothing */
        detp_batch_forget_crossings(b);
}

/* The scene's mobile at `frame` (vertices, normals, bounds), without the
 * ray tracer: what the bounding spheres need. */
static int pose_scene(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t frame, gi_error *err)
{
    if (a->scene_posed && a->scene_frame == frame)
        return 0;
    const gi_detp_params *p = ctx->job.params;
    gi_mat4 m;
    gi_anim_pose(&p->anim, frame, &m);
    if (gi_scene_pose_object(&ctx->job.scene, a->object, a->base_pos, a->base_nrm, &m, err))
        return -1;
    a->scene_posed = 1;
    a->scene_frame = frame;
    return 0;
}

/* The scene and the ray tracer at `frame`. */
static int pose(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t frame, gi_error *err)
{
    if (pose_scene(ctx, a, frame, err))
        return -1;
    if (a->rt_posed && a->rt_frame == frame)
        return 0;
    if (gi_rt_update_object(&ctx->rt, a->object, err))
        return -1;
    a->rt_posed = 1;
    a->rt_frame = frame;
    return 0;
}

static int mobile_at(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t frame,
                     mobile_frame *out, gi_error *err);

/* The most disk a job's tile hits may take on a host (16 bytes per pixel
 * and sample: 4K at 16 samples is 2.1 GB, 8K at 16 would be 8.5). */
#define TILE_HITS_MAX_BYTES ((uint64_t)4 << 30)

int detp_anim_render_tile(gi_worker_ctx *ctx, detp_worker *w, const gi_tile *tile,
                          uint32_t frame, const gi_camera *cam, gi_surface_shader shade,
                          void *user, gi_buf *px, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    detp_anim_worker *a;
    mobile_frame m;
    const char *dir;
    if (anim_state(ctx, w, &a, err))
        return -1;
    if (frame >= p->anim.frames)
        return gi_fail(err, GI_EPROTO, "detp: frame %u of %u", frame, p->anim.frames);
    if (pose(ctx, a, frame, err) || mobile_at(ctx, a, frame, &m, err) ||
        gi_worker_batch_dir(ctx, &dir, err))
        return -1;
    size_t n = (size_t)(tile->x1 - tile->x0) * (tile->y1 - tile->y0) * (size_t)p->image_spp;
    gi_tile_hit *rest = gi_try_malloc(n * sizeof *rest, err, "detp tile hits");
    if (!rest)
        return -1;
    /* All but the mobile stands still: its hits are traced once per host
     * and tile (gi_tile_hits.h), the mobile's every frame; unless the
     * whole image's would take more disk than TILE_HITS_MAX_BYTES, or the
     * camera moves along a path, then every frame traces them again. */
    int keep = p->anim.camera_count == 0 &&
               (uint64_t)ctx->job.width * (uint64_t)ctx->job.height * (uint64_t)p->image_spp *
                       sizeof *rest <=
                   TILE_HITS_MAX_BYTES;
    gi_error miss;
    gi_error_clear(&miss);
    int known = keep ? gi_tile_hits_read(dir, tile, p->image_spp,
                                         ctx->job.scene.triangle_count, rest, &miss)
                     : 0;
    int rc = known < 0 ? gi_fail(err, miss.code, "%s", miss.msg) : 0;
    if (rc == 0)
        rc = gi_tile_render_split(&ctx->rt, &ctx->job, cam, tile, p->image_spp, a->object,
                                  m.sphere.c, m.sphere.r, rest, known, shade, user, px, err);
    if (rc == 0 && keep && !known)
        rc = gi_tile_hits_write(dir, tile, p->image_spp, rest, err);
    free(rest);
    return rc;
}

/* The tracer at `frame` (the ray tracer must be posed there to trace),
 * with the mobile alone for rule 1's rays behind it when nothing else
 * comes near it. */
static int tracer_at(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t frame,
                     gi_detp_tracer *tr, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    gi_detp_tracer_init(tr, &ctx->rt, &ctx->job.scene, ctx->job.seed, p->photon_count,
                        p->max_bounces, p->artifact == GI_DETP_AC_SECOND_HIT);
    tr->frame = frame;
    mobile_frame m;
    if (mobile_at(ctx, a, frame, &m, err))
        return -1;
    if (m.clear) {
        const gi_object *o = &ctx->job.scene.objects[a->object];
        tr->mobile_alone = gi_rt_object_scene(&ctx->rt, a->object, err);
        tr->mobile_first = o->first_triangle;
        tr->mobile_count = o->triangle_count;
        if (!tr->mobile_alone)
            return -1;
    }
    return 0;
}

/* The batch's paths at frame 0 (the mobile at pose 0). */
static int trace_frame0(gi_worker_ctx *ctx, detp_anim_worker *a, uint64_t p0, uint64_t p1,
                        gi_detp_segments *out, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    if (pose(ctx, a, 0, err))
        return -1;
    gi_detp_tracer tr;
    if (tracer_at(ctx, a, 0, &tr, err))
        return -1;
    out->count = 0;
    for (uint64_t ph = p0; ph < p1; ph++)
        gi_detp_trace_photon(&tr, ph, out);
    gi_detp_set_extent(out, p->artifact, p->extent_eps);
    return 0;
}

static int mobile_at(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t frame,
                     mobile_frame *out, gi_error *err)
{
    for (int i = 0; i < 2; i++)
        if (a->at[i].valid && a->at[i].frame == frame) {
            *out = a->at[i];
            return 0;
        }
    if (pose_scene(ctx, a, frame, err))
        return -1;
    const gi_scene *s = &ctx->job.scene;
    const gi_detp_params *p = ctx->job.params;
    mobile_frame m = {frame, 1, gi_detp_object_sphere(s, a->object), {{0, 0, 0}, 0.0f}, 0};
    float r0 = gi_detp_object_disc_reach(s, a->object, m.sphere, p->disc_radius);
    float rr = r0 + gi_detp_sphere_slack(r0);
    m.near = (near_test){m.sphere.c, rr * rr};
    /* Grown by far more than rounding and the offset of a ray's origin
     * off the surface (gi_rt_offset). */
    float grown = m.sphere.r * 1.01f + 1e-3f * (float)p->scene_size;
    m.clear = !gi_rt_others_near(&ctx->rt, a->object, m.sphere.c, grown);
    /* Replace the older of the two. */
    int i = a->at[0].valid && (!a->at[1].valid || a->at[1].frame < a->at[0].frame);
    a->at[i] = m;
    *out = m;
    return 0;
}

/* The update's fixed inputs for frame f (scene and tracer posed at f). */
static int update_in(gi_worker_ctx *ctx, detp_anim_worker *a, uint32_t f,
                     const gi_detp_tracer *tr, gi_detp_anim_update_in *in, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    const gi_object *o = &ctx->job.scene.objects[a->object];
    memset(in, 0, sizeof *in);
    mobile_frame was, now;
    if (mobile_at(ctx, a, f - 1, &was, err) || pose(ctx, a, f, err) ||
        mobile_at(ctx, a, f, &now, err))
        return -1;
    in->old_pose = was.sphere;
    in->new_pose = now.sphere;
    in->tracer = tr;
    in->mobile_first_tri = o->first_triangle;
    in->mobile_tri_count = o->triangle_count;
    in->mobile_scene = gi_rt_object_scene(&ctx->rt, a->object, err);
    in->artifact = p->artifact;
    in->eps = p->extent_eps;
    in->still = gi_anim_still(&p->anim, f);
    return in->mobile_scene ? 0 : -1;
}

/* A batch the store lacks: frame 0 traced again and updated through
 * frames 1..f, stored as a base at f. */
static int regenerate(gi_worker_ctx *ctx, detp_anim_worker *a, const char *dir, uint32_t batch,
                      uint64_t p0, uint64_t p1, uint32_t f, detp_anim_result *h, gi_error *err)
{
    gi_detp_segments *cur = &a->regen[0], *nxt = &a->regen[1];
    if (trace_frame0(ctx, a, p0, p1, cur, err))
        return -1;
    for (uint32_t g = 1; g <= f; g++) {
        gi_detp_tracer tr;
        gi_detp_anim_update_in in;
        if (tracer_at(ctx, a, g, &tr, err) || update_in(ctx, a, g, &tr, &in, err))
            return -1;
        in.prev = cur->v;
        in.prev_count = cur->count;
        gi_detp_update_stats us;
        memset(&us, 0, sizeof us);
        nxt->count = a->old_list.count = a->new_list.count = 0;
        if (gi_detp_anim_update(&in, nxt, &a->old_list, &a->new_list, &us, err))
            return -1;
        gi_detp_segments *t = cur;
        cur = nxt;
        nxt = t;
    }
    h->regenerated_frames += (uint64_t)f + 1;
    int rc = detp_batch_write_base(dir, &a->grid, batch, p0, p1, f, cur, err);
    /* Give the memory back: regeneration is the exception. */
    gi_detp_segments_free(&a->regen[0]);
    gi_detp_segments_free(&a->regen[1]);
    return rc;
}

/* Collects the segments that may cross one of the mobile's discs, for
 * the mobile's estimate. */
static void collect_near(detp_anim_worker *a, near_test nt, const gi_detp_segment *seg,
                         size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (gi_detp_segment_meets_sphere(&seg[i], nt.c, nt.rr))
            *gi_detp_segments_push(&a->near) = seg[i];
}

/* The mobile's vertices from scratch (thesis 1.12.4) over segs (a->near,
 * or every segment of the frame). */
static int mobile_vertices(gi_worker_ctx *ctx, detp_worker *w, detp_anim_worker *a,
                           const gi_detp_segments *segs, gi_detp_stats *st, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    return gi_detp_anim_mobile_estimate(&ctx->job.scene, a->object, w->discs.radius, segs,
                                        p->mobile_estimator, &p->sc, a->mobile_order,
                                        ctx->rt.device, &w->acc, st, err);
}

/* The result: the accumulator as signed per-vertex sums. */
static void encode_result(const detp_worker *w, detp_anim_worker *a, const detp_anim_result *h,
                          gi_buf *result)
{
    for (size_t i = 0; i < (size_t)w->acc.count * 3; i++)
        a->sum[i] = w->acc.fixed[i];
    /* Removals count down modulo 2^32 (detp.h): back to signed. */
    for (uint32_t i = 0; i < w->acc.count; i++)
        a->hits[i] = (int32_t)w->acc.hits[i];
    detp_encode_anim(h, a->sum, a->hits, w->acc.count, result);
}

/* Keeps the batch open for frame 1, with the static crossings of the
 * segments frame 1 may drop (a path's from its first segment that hit the
 * mobile at pose 0 or may meet it at pose 1 on): frame 1 then takes them
 * back from the list instead of searching, as later frames do. The lists
 * cost frame 0 a search of those few segments (its sums are not touched);
 * if anything fails, frame 1 opens the batch from its files and searches. */
static void keep_for_frame1(gi_worker_ctx *ctx, detp_anim_worker *a, const char *dir,
                            uint32_t batch, uint64_t p0, uint64_t p1,
                            const gi_detp_segments *segs)
{
    const gi_detp_params *p = ctx->job.params;
    mobile_frame next;
    gi_error ignored;
    if (p->anim.frames < 2 || p->anim_update == GI_DETP_UPDATE_FULL ||
        mobile_at(ctx, a, 1, &next, &ignored))
        return;
    /* A shelf already full of batches in use would not keep this one:
     * then there is nothing to list for. */
    detp_batch b;
    if (detp_batch_open(dir, &a->grid, batch, p0, p1, 0, &b, &ignored) != 1)
        return;
    if (!detp_batch_shelf_fits(&a->shelf, &b)) {
        detp_batch_close(&b);
        return;
    }
    const gi_object *o = &ctx->job.scene.objects[a->object];
    gi_detp_segments *may = &a->unlisted;
    may->count = 0;
    for (size_t i = 0; i < segs->count;) {
        size_t j = i;
        while (j < segs->count && segs->v[j].photon == segs->v[i].photon)
            j++;
        size_t k = i;
        while (k < j && !gi_detp_anim_may_retrace(&segs->v[k], o->first_triangle,
                                                  o->triangle_count, next.sphere))
            k++;
        for (; k < j; k++)
            *gi_detp_segments_push(may) = segs->v[k];
        i = j;
    }
    gi_detp_stats scratch = {0};
    gi_detp_accum_clear(&a->static_acc);
    a->static_acc.sign = 1;
    gi_detp_embree_estimate_listed(a->static_index, may, &a->static_acc, &scratch, &a->listed);
    attach_crossings(&b, segs, may, &a->listed);
    detp_batch_shelf_put(&a->shelf, &b);
}

/* Segments from each path's first hit on triangles [m0, m0 + mn) on
 * (segs path-ordered, each path's in bounce order). */
static uint64_t count_from_mobile(const gi_detp_segment *segs, size_t n, uint32_t m0, uint32_t mn)
{
    uint64_t count = 0;
    int hit = 0;
    for (size_t i = 0; i < n; i++) {
        if (i == 0 || segs[i].photon != segs[i - 1].photon)
            hit = 0;
        hit = hit || segs[i].hit_tri - m0 < mn;
        count += (uint64_t)hit;
    }
    return count;
}

static int run_frame0(gi_worker_ctx *ctx, detp_worker *w, detp_anim_worker *a, const char *dir,
                      detp_anim_result *h, uint64_t p0, uint64_t p1, gi_error *err)
{
    double t0 = gi_now();
    if (detp_worker_index(ctx, w, err) || trace_frame0(ctx, a, p0, p1, &w->segs, err))
        return -1;
    double t1 = gi_now();
    if (detp_batch_write_base(dir, &a->grid, h->batch, p0, p1, 0, &w->segs, err))
        return -1;
    double t2 = gi_now();
    gi_detp_accum_clear(&w->acc);
    w->acc.sign = 1;
    if (detp_worker_estimate(ctx, w, &h->stats, err))
        return -1;
    double t3 = gi_now();
    mobile_frame m;
    if (mobile_at(ctx, a, 0, &m, err))
        return -1;
    a->near.count = 0;
    collect_near(a, m.near, w->segs.v, w->segs.count);
    if (mobile_vertices(ctx, w, a, &a->near, &h->stats, err))
        return -1;
    double t4 = gi_now();
    keep_for_frame1(ctx, a, dir, h->batch, p0, p1, &w->segs);
    h->sec_trace = t1 - t0;
    h->sec_store = (t2 - t1) + (gi_now() - t4);
    h->sec_static = t3 - t2;
    h->sec_mobile = t4 - t3;
    h->segments = h->segments_new = w->segs.count;
    const gi_object *o = &ctx->job.scene.objects[a->object];
    h->segments_from_mobile =
        count_from_mobile(w->segs.v, w->segs.count, o->first_triangle, o->triangle_count);
    return 0;
}

/* How many marked paths ahead of the one tested their runs are asked for
 * (4, 8 and 16 tried: 16 by a nose). */
#define RUN_AHEAD 16

static int run_update(gi_worker_ctx *ctx, detp_worker *w, detp_anim_worker *a, const char *dir,
                      detp_anim_result *h, uint64_t p0, uint64_t p1, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    uint32_t f = h->frame;
    double t0 = gi_now();
    detp_batch prev;
    gi_error miss;
    gi_error_clear(&miss);
    int found = detp_batch_shelf_take(&a->shelf, dir, h->batch, p0, p1, f - 1, &prev);
    if (!found)
        found = detp_batch_open(dir, &a->grid, h->batch, p0, p1, f - 1, &prev, &miss);
    if (found < 0)
        return gi_fail(err, miss.code, "%s", miss.msg);
    if (!found) {
        double tr0 = gi_now();
        if (regenerate(ctx, a, dir, h->batch, p0, p1, f - 1, h, err))
            return -1;
        h->sec_regenerate = gi_now() - tr0;
        found = detp_batch_open(dir, &a->grid, h->batch, p0, p1, f - 1, &prev, err);
        if (found != 1)
            return found < 0 ? -1 : gi_fail(err, GI_EIO, "detp batch %u: stored state lost",
                                            h->batch);
    }
    double t1 = gi_now();
    gi_detp_tracer tr;
    gi_detp_anim_update_in in;
    if (tracer_at(ctx, a, f, &tr, err) || update_in(ctx, a, f, &tr, &in, err)) {
        detp_batch_close(&prev);
        return -1;
    }
    mobile_frame now;
    if (mobile_at(ctx, a, f, &now, err)) { /* cannot fail: update_in computed it */
        detp_batch_close(&prev);
        return -1;
    }
    near_test nt = now.near;
    gi_detp_update_stats us;
    memset(&us, 0, sizeof us);
    a->changed.count = a->old_list.count = a->new_list.count = a->near.count = 0;
    /* Only the paths that may come near the mobile at either pose (the
     * base's grid, and those the deltas changed) can change or feed its
     * vertices; the others are not read at all. */
    size_t np = (size_t)(p1 - p0);
    if (a->mark_cap < np) {
        free(a->mark);
        a->mark = gi_xmalloc(np);
        a->mark_cap = np;
    }
    memset(a->mark, 0, np);
    /* The update tests segments against the mobile at both poses; the
     * mobile's estimate needs those that reach its discs at the new one. */
    float margin = 1e-3f * (float)p->scene_size;
    float ro = in.old_pose.r * 1.01f + margin;
    float rn = gi_maxf(in.new_pose.r * 1.01f, sqrtf(nt.rr)) + margin;
    detp_batch_mark_near(&prev, (gi_detp_mobile_pose){in.old_pose.c, ro},
                         (gi_detp_mobile_pose){in.new_pose.c, rn}, a->mark);
    uint64_t segments = detp_batch_count(&prev);
    size_t nrun = detp_batch_marked(&prev, a->mark, &a->runs, &a->runs_cap);
    for (size_t k = 0; k < nrun; k++) {
        detp_path run = a->runs[k];
        size_t c0 = a->changed.count;
        /* The runs a few paths ahead, into cache while this one is
         * tested (most paths are one to three segments long): a tenth off
         * the test at the 2.5% sphere, whose paths lie scattered over the
         * batch. */
        if (k + RUN_AHEAD < nrun) {
            const detp_path *ahead = &a->runs[k + RUN_AHEAD];
            for (uint32_t i = 0; i < ahead->count && i < 3; i++)
                __builtin_prefetch(ahead->seg + i);
        }
        if (gi_detp_anim_update_path(&in, run.seg, run.count, 0, &a->changed, &a->old_list,
                                     &a->new_list, &us)) {
            collect_near(a, nt, a->changed.v + c0, a->changed.count - c0);
            segments = segments - run.count + (a->changed.count - c0);
        } else {
            collect_near(a, nt, run.seg, run.count);
        }
    }
    double t2 = gi_now();
    gi_detp_accum_clear(&w->acc);
    int rc = 0;
    int full = p->anim_update == GI_DETP_UPDATE_FULL;
    if (full) {
        /* Every vertex from scratch over the frame's segments, the
         * mobile's too (the check of the incremental result, the grid's
         * marks included, and its benchmark). */
        detp_batch_materialize(&prev, &a->changed, &w->segs);
        w->acc.sign = 1;
        rc = detp_worker_estimate(ctx, w, &h->stats, err);
    } else {
        static_update(ctx, w, a, &prev, nrun, &h->stats);
    }
    double t3 = gi_now();
    if (rc == 0)
        rc = mobile_vertices(ctx, w, a, full ? &w->segs : &a->near, &h->stats, err);
    double t4 = gi_now();
    if (rc == 0)
        rc = detp_batch_write_frame(dir, &a->grid, &prev, f, &a->changed, err);
    h->segments = segments;
    if (rc >= 0) {
        /* Keep the batch open at this frame for the next; if that fails,
         * the next frame opens it from the files. */
        gi_error ignored;
        int as_base = rc;
        if (detp_batch_advance(dir, &a->grid, &prev, f, as_base, &ignored) == 1) {
            if (!as_base && !full)
                attach_crossings(&prev, &a->changed, &a->new_list, &a->listed);
            detp_batch_shelf_put(&a->shelf, &prev);
        }
        rc = 0;
    }
    detp_batch_close(&prev);
    h->segments_old = us.old_segments;
    h->segments_new = us.new_segments;
    h->paths_retraced = us.paths_retraced;
    h->segments_repaired = us.second_changed;
    h->bv_passes = us.sphere_passes;
    h->paths_examined = us.paths;
    h->sec_load = t1 - t0 - h->sec_regenerate;
    h->sec_trace = t2 - t1;
    h->sec_static = t3 - t2;
    h->sec_mobile = t4 - t3;
    h->sec_store = gi_now() - t4;
    return rc;
}

int detp_anim_run(gi_worker_ctx *ctx, const gi_task *t, gi_buf *result, gi_error *err)
{
    const gi_detp_params *p = ctx->job.params;
    detp_task_in in;
    if (detp_task_decode(&ctx->job, t, 0, &in, err))
        return -1;
    detp_anim_result h;
    memset(&h, 0, sizeof h);
    h.frame = in.frame;
    h.batch = in.batch;
    uint64_t p0 = in.p0, p1 = in.p1;
    detp_worker *w = detp_worker_state(ctx);
    detp_anim_worker *a;
    const char *dir;
    double t0 = gi_now();
    if (anim_state(ctx, w, &a, err) || gi_worker_batch_dir(ctx, &dir, err))
        return -1;
    h.sec_build = gi_now() - t0;
    h.photons = p1 - p0;
    uint64_t rays0 = ctx->rt.rays;
    int rc = h.frame == 0 ? run_frame0(ctx, w, a, dir, &h, p0, p1, err)
                          : run_update(ctx, w, a, dir, &h, p0, p1, err);
    if (rc)
        return -1;
    h.rays = ctx->rt.rays - rays0;
    /* The batch's last frame: its files are of no more use. */
    if (h.frame + 1 == p->anim.frames) {
        detp_batch_shelf_drop(&a->shelf, h.batch);
        detp_batch_remove(dir, h.batch);
    }
    encode_result(w, a, &h, result);
    /* Photons traced: all of them at frame 0 (or when the batch was
     * regenerated), then only the paths retraced: the rates in a render's
     * summary are of work done, not of photons merely tested. */
    ctx->stats.samples =
        h.frame == 0 || h.regenerated_frames ? h.photons + h.paths_retraced : h.paths_retraced;
    return 0;
}
