/* gi_worker_ctx: loading a job in a worker process and running its tasks. */
#include "gi_worker_ctx.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gi_fs.h"

int gi_worker_ctx_load(gi_worker_ctx *ctx, uint64_t job_id, const char *file,
                       const char *text, const gi_manifest *manifest,
                       int (*fetch)(void *fctx, const char *hash, gi_error *err), void *fctx,
                       gi_asset_store *store, gi_error *err)
{
    memset(ctx, 0, sizeof *ctx);
    ctx->job_id = job_id;
    ctx->store = store;
    if (gi_job_parse(text, strlen(text), file, &ctx->job, err))
        goto fail;
    for (size_t i = 0; i < manifest->count; i++)
        gi_manifest_put(&ctx->job.manifest, manifest->entries[i].name,
                        manifest->entries[i].hash, manifest->entries[i].size);
    ctx->source.manifest = &ctx->job.manifest;
    ctx->source.store = store;
    ctx->source.fetch = fetch;
    ctx->source.fetch_ctx = fctx;
    gi_asset_source src = gi_manifest_source_as_source(&ctx->source);
    ctx->job.on_worker = 1;
    if (gi_job_load_scene(&ctx->job, &src, err))
        goto fail;
    if (gi_rt_create(&ctx->rt, &ctx->job.scene, err))
        goto fail;
    return 0;
fail:
    gi_worker_ctx_free(ctx);
    return -1;
}

void gi_worker_ctx_free(gi_worker_ctx *ctx)
{
    if (ctx->method_state && ctx->method_state_free)
        ctx->method_state_free(ctx->method_state);
    gi_rt_free(&ctx->rt);
    gi_job_free(&ctx->job);
    free(ctx->batch_dir);
    memset(ctx, 0, sizeof *ctx);
}

int gi_worker_blob(gi_worker_ctx *ctx, const char hash[GI_HASH_HEX], const gi_buf **out,
                   gi_error *err)
{
    *out = gi_asset_store_get(ctx->store, hash);
    if (*out)
        return 0;
    if (!ctx->source.fetch)
        return gi_fail(err, GI_EIO, "published data %.12s is not available", hash);
    if (ctx->source.fetch(ctx->source.fetch_ctx, hash, err))
        return gi_error_prefix(err, "published data %.12s", hash);
    char *oldest = ctx->recent_blobs[ctx->recent_next];
    if (oldest[0] && !gi_manifest_has_hash(&ctx->job.manifest, oldest))
        gi_asset_store_remove(ctx->store, oldest);
    memcpy(oldest, hash, GI_HASH_HEX);
    ctx->recent_next = (ctx->recent_next + 1) % GI_WORKER_BLOBS_KEPT;
    *out = gi_asset_store_get(ctx->store, hash);
    return *out ? 0 : gi_fail(err, GI_EIO, "published data %.12s was not delivered", hash);
}

int gi_worker_batch_dir(gi_worker_ctx *ctx, const char **dir, gi_error *err)
{
    *dir = NULL;
    if (!ctx->batch_dir)
        return gi_fail(err, GI_EIO, "job %llu: this host has no batch directory",
                       (unsigned long long)ctx->job_id);
    /* Children race to create it: mkdir -p takes EEXIST as success. Every
     * time: the host removes it when the job ends, and the same job may
     * come back (a retry, an id the coordinator gave again). */
    if (gi_mkdirs(ctx->batch_dir, err)) /* GI_EHOST on a full disk: the host's */
        return gi_error_prefix(err, "batch directory");
    *dir = ctx->batch_dir;
    return 0;
}

int gi_worker_run_task(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result,
                       gi_error *err)
{
    memset(&ctx->stats, 0, sizeof ctx->stats);
    uint64_t rays0 = ctx->rt.rays;
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    int rc = ctx->job.method->run(ctx, task, result, err);
    clock_gettime(CLOCK_MONOTONIC, &b);
    ctx->stats.rays = ctx->rt.rays - rays0;
    ctx->stats.seconds = (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
    if (ctx->rt.failed && rc == 0)
        rc = gi_fail(err, GI_EINTERNAL, "%s", ctx->rt.error);
    return rc;
}
