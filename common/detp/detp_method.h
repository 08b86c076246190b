/* detp_method: the detp method's internals shared by its coordinator side
 * (detp_method.c, detp_outputs.c) and its worker side (detp_worker.c):
 * task kinds and payloads, result encodings, the coordinator's state. */
#ifndef GI_DETP_METHOD_H
#define GI_DETP_METHOD_H

#include <stdint.h>

#include "detp.h"
#include "detp_params.h"
#include "gi_assets.h"
#include "gi_image.h"
#include "gi_job.h"
#include "gi_method.h"
#include "gi_tiles.h"

/* Task kinds and their payloads. */
enum {
    DETP_TASK_BATCH = 1,      /* u64 first photon, u64 end photon */
    DETP_TASK_VISIBILITY = 2, /* u32 first vertex, u32 end vertex */
    DETP_TASK_REFERENCE = 3,  /* u32 first, u32 end reference index */
    DETP_TASK_TILE = 4,       /* gi_tile, str hash of the published radiance */
    /* Animations (detp_anim_*.c): u32 frame, u32 batch, u64 first, u64 end
     * photon. Frame 0 traces the batch and stores it; a later frame updates
     * the stored batch from the frame before. */
    DETP_TASK_ANIM_BATCH = 5,
    DETP_TASK_ANIM_UPDATE = 6,
    /* gi_tile, str hash, u32 frame: an animation frame's tile, the mobile
     * posed and seen from the frame's camera (a camera path alone: a still
     * bake's radiance seen from it). */
    DETP_TASK_ANIM_TILE = 7
};

/* A task's payload, by kind: the fields its kind has (the others 0). */
typedef struct detp_task_in {
    uint64_t p0, p1;        /* batches: photons [p0, p1) */
    uint32_t a, b;          /* visibility, reference: vertices or reference indices [a, b) */
    uint32_t frame, batch;  /* animation batches (frame, batch) and tiles (frame) */
    gi_tile tile;           /* tiles */
    char hash[GI_HASH_HEX]; /* tiles: the published radiance */
} detp_task_in;

/* Appends the payload of a task of this kind (detp_task.c). */
void detp_task_encode(uint32_t kind, const detp_task_in *in, gi_buf *out);
/* Reads task t's payload, checked against the job: photon ranges, frames,
 * tiles, and for visibility and reference tasks [a, b) within [0, lim).
 * Bad bytes: GI_EPROTO naming the task. */
int detp_task_decode(const gi_job *job, const gi_task *t, uint32_t lim, detp_task_in *in,
                     gi_error *err);

#define DETP_VIS_PER_TASK 2048
#define DETP_REF_PER_TASK 16
/* Streams of gi_rng besides the photons' (detp.h): disjoint ranges. */
#define DETP_STREAM_REFERENCE (3ull << 61)

/* A batch's result: timings and statistics, then per vertex the irradiance
 * contribution (RGB; for DETP the disc energy over the disc area) and the
 * number of crossings, dense or sparse (index deltas as varints), whichever
 * is smaller. The frame layer zstd-compresses it. */
typedef struct detp_batch_result {
    uint64_t photons, segments, rays;
    double trace_seconds, build_seconds, estimate_seconds;
    gi_detp_stats stats;
} detp_batch_result;

void detp_encode_batch(const detp_batch_result *h, const gi_detp_accum *acc, double scale,
                       gi_buf *out);
/* Adds the result's per-vertex values into irr (3 per vertex) and hits;
 * with irr and hits NULL, only checks the result. An energy beyond max in
 * magnitude (or not finite) is refused (detp_method.c, batch_energy_max). */
int detp_decode_batch(gi_reader *r, uint32_t vertex_count, double max, detp_batch_result *h,
                      double *irr, uint64_t *hits, gi_error *err);
/* Tests only (gi_method.h, damage_result): value for the first energy of a
 * batch's result; an INT64_MAX for the first sum of an animation batch's.
 * 1 if it has no entry. */
int detp_batch_damage(gi_buf *result, float value);
int detp_anim_damage(gi_buf *result);

/* An animation frame's batch result: what the worker did, then per vertex
 * exact integer sums (fixed point, detp_anim.h): for frame 0 every vertex's
 * sums; for a later frame the static vertices' changes (new segments added,
 * old ones subtracted) and the mobile's vertices from scratch. */
typedef struct detp_anim_result {
    uint32_t frame, batch;
    uint64_t photons;           /* paths tested */
    uint64_t paths_examined;    /* paths read: those the grid puts near the mobile */
    uint64_t segments;          /* in the batch after the frame */
    uint64_t segments_old;      /* removed (O^t) */
    uint64_t segments_new;      /* added (N^t) */
    uint64_t paths_retraced;    /* paths with a retraced suffix */
    uint64_t segments_repaired; /* second-hit distance changed only */
    uint64_t bv_passes;         /* segments that passed the bounding pre-test */
    uint64_t rays;
    uint64_t regenerated_frames; /* frames replayed because the store had no file */
    /* Frame 0: segments from each path's first hit on the mobile on, which
     * a small move of the mobile replaces: what a later frame will cost. */
    uint64_t segments_from_mobile;
    double sec_build, sec_load, sec_regenerate, sec_trace, sec_static, sec_mobile, sec_store;
    gi_detp_stats stats;
} detp_anim_result;

/* The fixed part alone (checkpoints keep a frame's totals in this form). */
void detp_anim_header_put(const detp_anim_result *h, gi_buf *out);
/* with_from_mobile: the header has segments_from_mobile (results, and
 * checkpoints from version 3 on). */
int detp_anim_header_get(gi_reader *r, detp_anim_result *h, int with_from_mobile);
void detp_encode_anim(const detp_anim_result *h, const int64_t *sum, const int64_t *hits,
                      uint32_t nv, gi_buf *out);
/* Reads an animation batch's result into h; fails on a malformed one, and
 * on a value beyond +-max (naming the vertex: the frame's batches, each
 * within INT64_MAX / batches, cannot overflow totals that start at zero).
 * sum (3 per vertex) and hits: the running totals it goes into (NULL: the
 * result's form alone is checked); it also fails, naming the vertex, if
 * adding it would overflow one of them. apply: adds it (else they are only
 * read); one that fails leaves them as they were. Each vertex comes at most
 * once in a result, so a pass without apply says exactly whether one with
 * it succeeds. */
int detp_decode_anim(gi_reader *r, uint32_t nv, int64_t max, detp_anim_result *h, int64_t *sum,
                     int64_t *hits, int apply, gi_error *err);
/* One vertex's entry of an animation batch's result, decoded: its red,
 * green and blue sums, then its hit count. */
typedef struct detp_anim_entry {
    uint64_t vertex;
    int64_t v[4];
} detp_anim_entry;
/* The reading half of detp_decode_anim (without apply), which also appends
 * the result's entries to entries (NULL: not kept) for detp_anim_add: the
 * coordinator's check reads a result once, its merge adds what it read.
 * bound: no total's magnitude is above it (INT64_MAX: not known); a value
 * that cannot take such a total out of range is not checked against its
 * total, which then is not read (the same refusals, fewer cache misses). */
int detp_anim_decode(gi_reader *r, uint32_t nv, int64_t max, detp_anim_result *h,
                     const int64_t *sum, const int64_t *hits, uint64_t bound, gi_buf *entries,
                     gi_error *err);
/* Adds n entries into the totals; if one would overflow, fails naming it
 * (after `what`) and leaves the totals as they were. *bound (bound NULL:
 * none kept) is raised to the largest magnitude of a total it wrote. */
int detp_anim_add(const detp_anim_entry *e, size_t n, int64_t *sum, int64_t *hits,
                  uint64_t *bound, const char *what, gi_error *err);
/* The largest magnitude of the nv vertices' totals: their bound. */
uint64_t detp_anim_bound(const int64_t *sum, const int64_t *hits, uint32_t nv);

/* The vertex of reference sample j (of m, over n vertices): evenly spread. */
static inline uint32_t detp_reference_vertex(uint32_t j, uint32_t m, uint32_t n)
{
    return (uint32_t)(((uint64_t)2 * j + 1) * n / (2 * (uint64_t)m));
}

enum { DETP_PHASE_BAKE, DETP_PHASE_IMAGE, DETP_PHASE_DONE };

typedef struct detp_state {
    int phase;
    uint32_t nv;
    double *irr;     /* 3 per vertex: summed irradiance contributions */
    uint64_t *hits;  /* crossings per vertex */
    float *visible;  /* per vertex, artifact control rule 2 (else NULL) */
    uint32_t nref;   /* reference vertices */
    double *ref;     /* 4 per reference vertex: R, G, B sums and luminance^2 sum */
    uint64_t batches, photons, segments;
    uint64_t rays_trace, rays_visibility, rays_reference, rays_image;
    double sec_trace, sec_build, sec_estimate, sec_visibility, sec_reference, sec_image;
    gi_detp_stats stats;
    double wall_start, wall_bake, wall_image; /* coordinator clock, not checkpointed */
    char hash[GI_HASH_HEX];                   /* published radiance (image phase) */
    gi_image img;
    struct detp_anim_state *anim; /* animations only (detp_anim_job.c) */
    /* An animation frame's image outputs, still being written while the
     * next frame runs (or NULL). */
    struct gi_image_writer *writer;
    /* The image of an earlier frame whose outputs could not be written (a
     * full disk, a path in the way): kept, in checkpoints too, and written
     * again before the next frame's outputs (pixels NULL: none). */
    gi_image unwritten;
    uint32_t earlier_frame; /* the frame of writer or unwritten */
} detp_state;

/* Per-vertex results computed from the state (finish). */
typedef struct detp_vertex_data {
    float *irradiance; /* E, 3 per vertex */
    float *reflected;  /* rho E / pi */
    float *radiance;   /* reflected + emission */
} detp_vertex_data;

int detp_vertex_data_compute(const gi_job *job, const detp_state *st, detp_vertex_data *out,
                             gi_error *err);
void detp_vertex_data_free(detp_vertex_data *v);

/* Outputs (detp_outputs.c): the per-vertex ones (PLY, glTF, the binary
 * float file), then the report; or each part alone. */
int detp_write_outputs(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                       gi_error *err);
int detp_write_vertex_outputs(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                              gi_error *err);
int detp_write_report(gi_job *job, const detp_state *st, const detp_vertex_data *v,
                      gi_error *err);

/* Animations, coordinator side (detp_anim_job.c). The frame's state lives
 * in st->anim; st's per-frame counters and irr/hits are filled from it. */
int detp_anim_plan(gi_job *job, detp_state *st, gi_task_queue *q, gi_error *err);
/* Refuses a batch's result that detp_anim_merge would refuse, as it
 * arrives: its run fails and the task runs again. That includes sums that
 * overflow the frame's running totals as merged so far; an overflow that
 * needs results which arrived before it but are not merged yet (merges go
 * in task order) is found only by the merge, which then fails the job.
 * (Conversely, a total within one result of the limit that those results
 * would bring back down could refuse it wrongly; it runs again, and fails
 * the job only if refused on every attempt. Real sums stay many powers of
 * two below the limit: a vertex gets a small share of a job's photons, each
 * worth about 2^32 units.) decoded (or NULL): where it leaves the result
 * decoded, for detp_anim_merge_decoded. */
int detp_anim_check(const gi_job *job, const gi_task *t, const gi_buf *result,
                    gi_buf *decoded, gi_error *err);
/* Adds a batch's result; a malformed one, or one whose sums overflow the
 * totals, fails the job (EPROTO: its message names the task, frame, batch,
 * vertex and why) and leaves the totals as they were. */
int detp_anim_merge(gi_job *job, const gi_task *t, const gi_buf *result, gi_error *err);
/* The same for what detp_anim_check left in decoded (it keeps the
 * result's entries there, decoded: see detp_anim_decode). */
int detp_anim_merge_decoded(gi_job *job, const gi_task *t, const gi_buf *decoded,
                            gi_error *err);
/* Before a frame's outputs: irr and hits from the exact sums, and the
 * coordinator's scene posed for the frame. */
int detp_anim_fill(gi_job *job, detp_state *st, gi_error *err);
/* After a frame's outputs: plans the next frame; 0 if there is none. */
int detp_anim_next_frame(gi_job *job, detp_state *st, gi_task_queue *q);
/* The frame's part of the report. */
cJSON *detp_anim_report(const gi_job *job, const detp_state *st);
/* Frame 0's segments from the mobile over all its segments, in its first
 * batch merged; < 0 if not known. */
double detp_anim_from_mobile_share(const detp_state *st);
void detp_anim_save(const detp_state *st, gi_buf *out);
/* version: detp's checkpoint state version (2 lacks frame 0's share). */
int detp_anim_load(gi_job *job, detp_state *st, gi_reader *in, uint32_t version, gi_error *err);
void detp_anim_free(struct detp_anim_state *a);
uint32_t detp_anim_frame(const detp_state *st);

/* Worker side (detp_worker.c). The discs, the query order and the disc
 * index are built once per job per process, on the first task that needs
 * them, and kept in ctx->method_state. */
typedef struct detp_worker {
    gi_detp_discs discs;
    int discs_ready;
    uint32_t *order;
    gi_detp_octree *octree;
    gi_detp_embree_index *embree;
    int index_ready;
    gi_detp_accum acc; /* over discs (fixed point for animations) */
    gi_detp_segments segs;
    gi_vec3 *inward;
    /* The radiance the coordinator published for image tiles. */
    char hash[GI_HASH_HEX];
    float *radiance;
    struct detp_anim_worker *anim; /* animations (detp_anim_worker.c) */
} detp_worker;

detp_worker *detp_worker_state(gi_worker_ctx *ctx);
/* The radiance published for image tiles (nv x RGB floats), read and
 * checked (gi_published.h): malloc'ed, or NULL with GI_EPROTO naming the
 * blob and what is wrong. Exposed for fuzz_published. */
float *detp_radiance_decode(const gi_buf *blob, const char *hash, uint32_t nv, gi_error *err);
int detp_worker_discs(gi_worker_ctx *ctx, detp_worker *w, gi_error *err);
int detp_worker_index(gi_worker_ctx *ctx, detp_worker *w, gi_error *err);
/* The job's estimator over w->segs into w->acc. */
int detp_worker_estimate(gi_worker_ctx *ctx, detp_worker *w, gi_detp_stats *st,
                         gi_error *err);

/* Animations, worker side (detp_anim_worker.c): frame-0 batches, updates,
 * and a frame's image tiles seen from cam, the frame's camera (the mobile
 * posed and traced alone, the rest's hits kept in the batch directory:
 * gi_tile_render_split). */
int detp_anim_run(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err);
int detp_anim_render_tile(gi_worker_ctx *ctx, detp_worker *w, const gi_tile *tile,
                          uint32_t frame, const gi_camera *cam, gi_surface_shader shade,
                          void *user, gi_buf *px, gi_error *err);
void detp_anim_worker_free(struct detp_anim_worker *a);
int detp_run(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err);


#endif
