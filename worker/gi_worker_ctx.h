/* gi_worker_ctx: what a method's run() sees in a worker process: the job as
 * parsed there, its scene and ray tracer, per-job method state, published
 * coordinator data, and the statistics of the task being run. */
#ifndef GI_WORKER_CTX_H
#define GI_WORKER_CTX_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_job.h"
#include "gi_rt.h"
#include "gi_task.h"

#define GI_WORKER_BLOBS_KEPT 8

struct gi_worker_ctx {
    uint64_t job_id;
    gi_job job;
    gi_rt rt;
    /* Method state kept across the job's tasks in this process (e.g. an
     * index over the scene), created by run() on first use. */
    void *method_state;
    void (*method_state_free)(void *state);
    /* Assets and published data: bytes by hash, fetched on demand. */
    gi_asset_store *store;
    gi_manifest_source source;
    /* The published blobs fetched last: an older one is dropped from store
     * when a new one comes (an animation publishes a frame's radiance each
     * frame; kept, they would add up for the life of the job). */
    char recent_blobs[GI_WORKER_BLOBS_KEPT][GI_HASH_HEX];
    unsigned recent_next;
    /* This job's directory on this host's disk for method caches, shared by
     * the host's pool children and removed by the host process when the job
     * ends (docs/farm.md, "Batch directories"); NULL when the host gives
     * none. Use gi_worker_batch_dir, which creates it. */
    char *batch_dir;
    /* Filled by run(): the method's work units; rays come from rt. */
    gi_task_stats stats;
};

/* Loads a job in this worker: parse, scene (assets fetched through fetch()),
 * Embree scene. On failure ctx is left freed. */
int gi_worker_ctx_load(gi_worker_ctx *ctx, uint64_t job_id, const char *file,
                       const char *text, const gi_manifest *manifest,
                       int (*fetch)(void *fctx, const char *hash, gi_error *err), void *fctx,
                       gi_asset_store *store, gi_error *err);
void gi_worker_ctx_free(gi_worker_ctx *ctx);

/* Bytes the coordinator published with gi_job_publish (fetched once). */
int gi_worker_blob(gi_worker_ctx *ctx, const char hash[GI_HASH_HEX], const gi_buf **out,
                   gi_error *err);

/* This job's batch directory, created (mkdir -p) on first use: *dir is
 * ctx->batch_dir. Files inside are the method's (write them to a temporary
 * name and rename: another child of the host may read them). GI_EIO when the
 * host gives no directory or it cannot be created. */
int gi_worker_batch_dir(gi_worker_ctx *ctx, const char **dir, gi_error *err);

/* Runs one task: stats are filled (rays, samples, seconds). */
int gi_worker_run_task(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result,
                       gi_error *err);

#endif
