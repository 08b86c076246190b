/* Unit tests: the detp method end to end in one process (plan, tasks run
 * by an in-process worker, ordered merge, finish, outputs): every DETP
 * estimator gives the same bytes, a checkpoint taken anywhere resumes to
 * the same bytes, and batch results survive their encoding. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "detp/detp_method.h"
#include "gi_clock.h"
#include "gi_fs.h"
#include "gi_jobrun.h"
#include "gi_published.h"
#include "gi_test.h"
#include "gi_worker_ctx.h"
#include "test_drive.h"

static char *write_job(const char *name, const char *estimator, const char *extra)
{
    char text[2048], path[600];
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/scenes/cornell-box/scene.json\", \"method\": \"detp\","
             " \"seed\": 5, \"image\": {\"width\": 24, \"height\": 20},"
             " \"detp\": {\"photons\": 12000, \"batch\": 2500, \"subdivide\": \"14%%\","
             "  \"radius\": \"9%%\", \"estimator\": \"%s\"%s, \"tile\": 8, \"image_spp\": 2},"
             " \"outputs\": {\"exr\": \"img.exr\", \"ply\": \"v.ply\", \"bin\": \"v.bin\","
             "  \"json\": \"report.json\"}}",
             gi_test_srcdir(), estimator, extra);
    snprintf(path, sizeof path, "%s/%s", gi_test_tmpdir(), name);
    gi_error err;
    if (gi_write_file_atomic(path, text, strlen(text), &err))
        return NULL;
    return gi_xstrdup(path);
}

/* An animation of the Cornell box's mobile over `frames` frames, two
 * photon batches a frame. */
static char *write_anim_job(const char *name, int frames)
{
    char text[2048], path[600];
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/scenes/cornell-box/scene-mobile.json\", \"method\": \"detp\","
             " \"seed\": 5, \"image\": {\"width\": 16, \"height\": 12},"
             " \"detp\": {\"photons\": 6000, \"batch\": 3000, \"subdivide\": \"14%%\","
             "  \"tile\": 8, \"image_spp\": 1,"
             "  \"animation\": {\"object\": \"mobile\", \"frames\": %d,"
             "   \"keyframes\": [{\"frame\": 0, \"translate\": [340, -338.9, -90]},"
             "                   {\"frame\": %d, \"translate\": [248, -338.9, -0.4]}]}},"
             " \"outputs\": {\"exr\": \"a.exr\"}}",
             gi_test_srcdir(), frames, frames - 1);
    snprintf(path, sizeof path, "%s/%s", gi_test_tmpdir(), name);
    gi_error err;
    if (gi_write_file_atomic(path, text, strlen(text), &err))
        return NULL;
    return gi_xstrdup(path);
}

static int load(const char *path, const char *out, gi_job *job, gi_worker_ctx *ctx,
                gi_error *err)
{
    if (gi_job_load(path, job, err))
        return -1;
    job->out_dir = gi_path_join(gi_test_tmpdir(), out);
    if (gi_mkdirs(job->out_dir, err))
        return -1;
    return gi_worker_ctx_load(ctx, 1, job->file, job->text, &job->manifest, NULL, NULL,
                              job->assets, err);
}

/* Runs the job; after `stop_after` merged tasks (0: never) the run is
 * checkpointed, everything is thrown away, and a fresh coordinator and
 * worker resume from the checkpoint. */
static int run(const char *path, const char *out, uint64_t stop_after, gi_error *err)
{
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    if (load(path, out, &job, &ctx, err) || gi_jobrun_start(&jr, &job, err))
        return -1;
    int rc = stop_after ? gi_test_drive(&jr, &ctx, stop_after, err) : 0;
    if (rc == 0 && stop_after && !gi_jobrun_done(&jr)) {
        gi_buf ck;
        gi_buf_init(&ck);
        rc = gi_jobrun_checkpoint(&jr, &ck, err);
        gi_jobrun_free(&jr);
        gi_worker_ctx_free(&ctx);
        gi_job_free(&job);
        if (rc == 0)
            rc = load(path, out, &job, &ctx, err);
        if (rc == 0)
            rc = gi_jobrun_restore(&jr, &job, &ck, err);
        gi_buf_free(&ck);
    }
    if (rc == 0)
        rc = gi_test_drive(&jr, &ctx, UINT64_MAX, err);
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
    return rc;
}

static int same_file(const char *dir_a, const char *dir_b, const char *name)
{
    char pa[700], pb[700];
    snprintf(pa, sizeof pa, "%s/%s/%s", gi_test_tmpdir(), dir_a, name);
    snprintf(pb, sizeof pb, "%s/%s/%s", gi_test_tmpdir(), dir_b, name);
    gi_buf a, b;
    gi_buf_init(&a);
    gi_buf_init(&b);
    gi_error err;
    int same = gi_read_file(pa, 1 << 26, &a, &err) == 0 && gi_read_file(pb, 1 << 26, &b, &err) == 0 &&
               a.len == b.len && a.len > 0 && memcmp(a.data, b.data, a.len) == 0;
    gi_buf_free(&a);
    gi_buf_free(&b);
    return same;
}

GI_TEST(test_detp_job_same_bytes_for_every_detp_estimator_and_after_restore)
{
    gi_error err;
    const char *est[] = {"embree", "basic", "octree", "sphere_cache", "multilist"};
    char *paths[5];
    for (int i = 0; i < 5; i++) {
        char name[64], out[64];
        snprintf(name, sizeof name, "job-%s.json", est[i]);
        snprintf(out, sizeof out, "out-%s", est[i]);
        paths[i] = write_job(name, est[i], "");
        GI_REQUIRE(paths[i]);
        GI_REQUIRE_OK(run(paths[i], out, 0, &err));
        if (i > 0) {
            GI_CHECK_MSG(same_file("out-embree", out, "v.bin"), "%s: other vertex values", est[i]);
            GI_CHECK_MSG(same_file("out-embree", out, "img.exr"), "%s: other image", est[i]);
        }
    }
    /* Checkpoints: in the middle of the bake (5 batches), and among the
     * image tiles (after 5 + 4 tasks). */
    uint64_t stops[2] = {3, 8};
    for (int k = 0; k < 2; k++) {
        char out[64];
        snprintf(out, sizeof out, "out-restored-%d", k);
        GI_REQUIRE_OK(run(paths[0], out, stops[k], &err));
        GI_CHECK_MSG(same_file("out-embree", out, "v.bin") && same_file("out-embree", out, "v.ply") &&
                         same_file("out-embree", out, "img.exr"),
                     "restored after task %llu: outputs differ", (unsigned long long)stops[k]);
    }
    /* The report says what happened. */
    char rp[700];
    snprintf(rp, sizeof rp, "%s/out-sphere_cache/report.json", gi_test_tmpdir());
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(rp, 1 << 24, &b, &err));
    cJSON *doc = cJSON_ParseWithLength((const char *)b.data, b.len);
    GI_REQUIRE(doc);
    GI_CHECK(cJSON_GetObjectItem(doc, "photons")->valuedouble == 12000);
    GI_CHECK(cJSON_GetObjectItem(doc, "batches")->valuedouble == 5);
    const cJSON *st = cJSON_GetObjectItem(doc, "estimator_stats");
    GI_CHECK(cJSON_GetObjectItem(st, "cache_faults")->valuedouble > 0);
    GI_CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(st, "levels")) > 0);
    const cJSON *pred = cJSON_GetObjectItem(doc, "predicted_relative_error");
    GI_CHECK(cJSON_GetObjectItem(pred, "n_R_photons")->valuedouble > 0.01);
    cJSON_Delete(doc);
    gi_buf_free(&b);
    for (int i = 0; i < 5; i++)
        free(paths[i]);
}

GI_TEST(test_detp_batch_results_dense_and_sparse)
{
    gi_error err;
    for (int sparse = 0; sparse < 2; sparse++) {
        const uint32_t n = 1000;
        gi_detp_accum acc;
        GI_REQUIRE_OK(gi_detp_accum_init(&acc, n, &err));
        for (uint32_t i = 0; i < n; i++)
            if (!sparse || i % 97 == 3) {
                acc.energy[3 * i] = 0.5 * i;
                acc.energy[3 * i + 2] = 1.0 / (i + 1);
                acc.hits[i] = sparse ? i % 7 : 100000 + i; /* varints as long as u32s */
            }
        detp_batch_result h;
        memset(&h, 0, sizeof h);
        h.photons = 123;
        h.stats.faults = 9;
        gi_buf b;
        gi_buf_init(&b);
        detp_encode_batch(&h, &acc, 2.0, &b);
        GI_CHECK(sparse ? b.len < 2000 : b.len > (size_t)n * 16);
        double *irr = gi_xcalloc(3 * n, sizeof *irr);
        uint64_t *hits = gi_xcalloc(n, sizeof *hits);
        gi_reader r;
        gi_reader_init(&r, b.data, b.len, "batch result");
        detp_batch_result back;
        GI_REQUIRE_OK(detp_decode_batch(&r, n, FLT_MAX, &back, irr, hits, &err));
        GI_CHECK(back.photons == 123 && back.stats.faults == 9);
        int bad = 0;
        for (uint32_t i = 0; i < n; i++)
            bad += irr[3 * i] != (float)(acc.energy[3 * i] * 2.0) ||
                   irr[3 * i + 2] != (float)(acc.energy[3 * i + 2] * 2.0) || hits[i] != acc.hits[i];
        GI_CHECK(bad == 0);
        /* Wrong vertex count and truncation are refused. */
        gi_reader_init(&r, b.data, b.len, "batch result");
        GI_CHECK(detp_decode_batch(&r, n + 1, FLT_MAX, &back, irr, hits, &err) == -1);
        gi_reader_init(&r, b.data, b.len - 1, "batch result");
        GI_CHECK(detp_decode_batch(&r, n, FLT_MAX, &back, irr, hits, &err) == -1);
        free(irr);
        free(hits);
        gi_buf_free(&b);
        gi_detp_accum_free(&acc);
    }
}

GI_TEST(test_detp_automatic_radius_and_photon_count)
{
    /* Thesis 1.13: the radius is the mean sample spacing, the photon count
     * the one eq. 3.46 needs for the requested relative error. */
    gi_error err;
    char text[1024], p2[600];
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/scenes/cornell-box/scene.json\", \"method\": \"detp\","
             " \"detp\": {\"photons\": \"auto\", \"relative_error\": 0.05,"
             " \"radius\": \"auto\", \"subdivide\": 100}}",
             gi_test_srcdir());
    snprintf(p2, sizeof p2, "%s/auto.json", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_write_file_atomic(p2, text, strlen(text), &err));
    gi_job job;
    GI_REQUIRE_OK(gi_job_load(p2, &job, &err));
    const gi_detp_params *p = job.params;
    double spacing = gi_detp_mean_edge(&job.scene);
    GI_CHECK_NEAR(p->disc_radius, spacing, 1e-4 * spacing);
    double ad = GI_PI * (double)p->disc_radius * p->disc_radius;
    GI_CHECK(p->photon_count == gi_detp_rays_for_error(p->hull_area, ad, 0.05));
    GI_CHECK_NEAR(gi_detp_predicted_error(p->hull_area, ad, (double)p->photon_count), 0.05, 1e-4);
    /* The Cornell box's bounding box: 556 x 548.8 x 559.2 (A_0 = 1.85e6 mm^2). */
    GI_CHECK_REL(p->hull_area, 2.0 * (556.0 * 548.8 + 548.8 * 559.2 + 559.2 * 556.0), 1e-4);
    GI_CHECK((uint64_t)p->batch <= p->photon_count);
    gi_job_free(&job);
}

/* A worker's fetch: the bytes from the coordinator's store into its own. */
typedef struct fetch_link {
    const gi_asset_store *from;
    gi_asset_store *to;
} fetch_link;

static int copy_from_coordinator(void *fctx, const char *hash, gi_error *err)
{
    const fetch_link *l = fctx;
    const gi_buf *b = gi_asset_store_get(l->from, hash);
    if (!b)
        return gi_fail(err, GI_EIO, "%.12s is not published", hash);
    gi_asset_store_put(l->to, hash, b->data, b->len);
    return 0;
}

/* An animation publishes each frame's radiance for its tiles: the coordinator
 * drops the frame before's, and a worker keeps only its last few, so neither
 * holds every frame's for the life of the job. */
GI_TEST(test_detp_animation_keeps_only_recent_published_radiance)
{
    char *path = write_anim_job("anim-blobs.json", GI_WORKER_BLOBS_KEPT + 4);
    GI_REQUIRE(path != NULL);
    gi_error err;
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(load(path, "out-anim-blobs", &job, &ctx, &err));
    free(path);
    /* A worker with a store of its own, as in a pool child. */
    gi_asset_store *worker_store = gi_asset_store_new();
    for (size_t i = 0; i < gi_asset_store_count(job.assets); i++) {
        char hash[GI_HASH_HEX];
        const gi_buf *b = gi_asset_store_at(job.assets, i, hash);
        gi_asset_store_put(worker_store, hash, b->data, b->len);
    }
    fetch_link link = {job.assets, worker_store};
    ctx.store = ctx.source.store = worker_store;
    ctx.source.fetch = copy_from_coordinator;
    ctx.source.fetch_ctx = &link;
    ctx.batch_dir = gi_path_join(gi_test_tmpdir(), "anim-blobs-batches");
    size_t files = gi_asset_store_count(job.assets);
    GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
    size_t most_coordinator = 0, most_worker = 0;
    double last_fraction = 0, frame1_fraction = -1;
    while (!gi_jobrun_done(&jr)) {
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t);
        gi_buf res;
        gi_buf_init(&res);
        GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &res, &err));
        gi_jobrun_complete(&jr, t->id, t->attempt, &res, &ctx.stats);
        gi_buf_free(&res);
        /* Progress: once a batch of frame 0 is merged, the method weighs
         * frame 0 (the bake) above the frames after it (updates), and the
         * fraction never goes back. */
        gi_job_progress est = {.frames = 1};
        job.method->progress(&job, &est);
        GI_CHECK(est.later_frame_cost > 0 && est.later_frame_cost < est.first_frame_cost);
        gi_progress_at at;
        gi_jobrun_progress(&jr, gi_now(), &at);
        GI_CHECK_MSG(at.fraction >= last_fraction - 1e-12, "%.6f after %.6f", at.fraction,
                     last_fraction);
        last_fraction = at.fraction;
        if (at.frame == 1 && frame1_fraction < 0)
            frame1_fraction = at.fraction;
        size_t c = gi_asset_store_count(job.assets), w = gi_asset_store_count(worker_store);
        most_coordinator = c > most_coordinator ? c : most_coordinator;
        most_worker = w > most_worker ? w : most_worker;
    }
    GI_CHECK_MSG(jr.finished, "%s", jr.error.msg);
    GI_CHECK_MSG(frame1_fraction > 2.0 / (GI_WORKER_BLOBS_KEPT + 4), "frame 0 is %.4f of the job",
                 frame1_fraction);
    GI_CHECK_MSG(most_coordinator <= files + 1, "the coordinator held %zu blobs at once",
                 most_coordinator - files);
    GI_CHECK_MSG(most_worker <= files + GI_WORKER_BLOBS_KEPT, "the worker held %zu blobs",
                 most_worker - files);
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_asset_store_free(worker_store);
    gi_job_free(&job);
}

/* Runs the job at path into out dir `out`, its results checked as they
 * arrive and merged from what the check decoded (checked), or merged as the
 * worker sent them. */
static int run_checked_or_not(const char *path, const char *out, int checked, gi_error *err)
{
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    if (load(path, out, &job, &ctx, err))
        return -1;
    ctx.batch_dir = gi_path_join(job.out_dir, "batches");
    int rc = gi_jobrun_start(&jr, &job, err);
    if (rc == 0)
        rc = checked ? gi_test_drive_checked(&jr, &ctx, 3, err)
                     : gi_test_drive(&jr, &ctx, UINT64_MAX, err);
    if (rc == 0 && !jr.finished)
        rc = gi_fail(err, GI_EINTERNAL, "%s: not finished", out);
    if (rc == 0)
        gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
    return rc;
}

static int same_outputs(const char *a, const char *b, const char *name, gi_error *err)
{
    char *pa = gi_path_join(a, name), *pb = gi_path_join(b, name);
    gi_buf x, y;
    gi_buf_init(&x);
    gi_buf_init(&y);
    int rc = gi_read_file(pa, 1 << 28, &x, err) || gi_read_file(pb, 1 << 28, &y, err) ? -1 : 0;
    if (rc == 0 && (x.len != y.len || memcmp(x.data, y.data, x.len) != 0))
        rc = gi_fail(err, GI_EINTERNAL, "%s differs from %s", pa, pb);
    gi_buf_free(&x);
    gi_buf_free(&y);
    free(pa);
    free(pb);
    return rc;
}

/* The coordinator merges a checked animation batch from what its check
 * decoded (gi_method.merge_decoded): the animation's outputs are
 * bit-identical to those merged from the worker's bytes, results arriving
 * out of order included; so are a still's, whose checks keep nothing. */
GI_TEST(test_detp_outputs_are_the_same_merged_from_the_checks_decoding)
{
    gi_error err;
    char *still = write_job("decoded-still.json", "impact_count", "");
    char *anim = write_anim_job("decoded-anim.json", 3);
    GI_REQUIRE(still && anim);
    const char *out[2][2] = {{"out-decoded-still-raw", "out-decoded-still-checked"},
                             {"out-decoded-anim-raw", "out-decoded-anim-checked"}};
    for (int k = 0; k < 2; k++)
        for (int checked = 0; checked < 2; checked++)
            GI_CHECK_OK(run_checked_or_not(k ? anim : still, out[k][checked], checked, &err));
    char *a[2], *b[2];
    for (int k = 0; k < 2; k++) {
        a[k] = gi_path_join(gi_test_tmpdir(), out[k][0]);
        b[k] = gi_path_join(gi_test_tmpdir(), out[k][1]);
    }
    const char *still_files[] = {"img.exr", "v.ply", "v.bin"};
    for (int i = 0; i < 3; i++)
        GI_CHECK_OK(same_outputs(a[0], b[0], still_files[i], &err));
    for (unsigned f = 0; f < 3; f++) {
        char name[32];
        snprintf(name, sizeof name, "a.%04u.exr", f);
        GI_CHECK_OK(same_outputs(a[1], b[1], name, &err));
    }
    for (int k = 0; k < 2; k++) {
        free(a[k]);
        free(b[k]);
    }
    free(still);
    free(anim);
}

/* Spoils the result of leased task t in the way `spoil` says and gives it
 * to jr as a worker's answer: it must be refused naming the task, and the
 * task retried, the job not failed. */
enum { SPOIL_CUT, SPOIL_TRAILING, SPOIL_MAGIC, SPOIL_ANIM_BATCH, SPOIL_VISIBLE_SLIVER };
static int refuse_spoiled(gi_jobrun *jr, gi_worker_ctx *ctx, int spoil, const char *want,
                          gi_error *err)
{
    const gi_task *t = gi_jobrun_lease(jr);
    if (!t)
        return gi_fail(err, GI_EINTERNAL, "nothing to lease");
    gi_buf res;
    gi_buf_init(&res);
    int rc = gi_worker_run_task(ctx, t, &res, err);
    if (rc == 0 && gi_jobrun_check_result(jr, t->id, t->attempt, &res, err))
        rc = gi_error_prefix(err, "the result as sent");
    if (rc == 0 && res.len < 16)
        rc = gi_fail(err, GI_EINTERNAL, "a result of %zu bytes", res.len);
    if (rc == 0) {
        if (spoil == SPOIL_CUT)
            res.len /= 2;
        else if (spoil == SPOIL_TRAILING)
            gi_buf_put_u8(&res, 0);
        else if (spoil == SPOIL_MAGIC)
            res.data[0] ^= 1;
        else if (spoil == SPOIL_VISIBLE_SLIVER) /* less than one ray's fraction */
            gi_le_put_u32(res.data + 16, 0x3a83126fu); /* 1e-3f, after the timing */
        else
            gi_le_put_u32(res.data + 8, gi_le_get_u32(res.data + 8) + 1);
        char msg[128];
        snprintf(msg, sizeof msg, "task %llu's result: %s", (unsigned long long)t->id, want);
        uint64_t retries = jr->retries;
        rc = gi_test_refuse(jr, t, &res, msg, err);
        if (rc == 0 && jr->retries != retries + 1)
            rc = gi_fail(err, GI_EINTERNAL, "the task was not retried");
    }
    gi_buf_free(&res);
    return rc;
}

/* A photon batch's (still or animation), visibility or reference result
 * that merge could not take is refused as it arrives: its run fails, the
 * task runs again, and the job ends well. */
GI_TEST(test_detp_malformed_batch_results_are_retried)
{
    gi_error err;
    char *path = write_job("badres.json", "impact_count",
                           ", \"artifact_control\": \"visible_area\","
                           " \"reference\": {\"spp\": 2, \"vertices\": 6}");
    GI_REQUIRE(path != NULL);
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(load(path, "out-badres", &job, &ctx, &err));
    free(path);
    GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
    GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_CUT, "detp result", &err));
    GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_TRAILING, "detp result", &err));
    GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_MAGIC, "detp result: not a detp batch result", &err));
    /* The visibility and reference tasks after the batches. */
    uint32_t kinds[] = {DETP_TASK_VISIBILITY, DETP_TASK_REFERENCE};
    for (int k = 0; k < 2; k++) {
        while (gi_jobrun_task_at(&jr, jr.pending[jr.pending_head])->task.kind != kinds[k])
            GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, 1, &err));
        GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_CUT, "detp result", &err));
        GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_TRAILING, "detp result", &err));
        /* A visible fraction divides irradiance: above 0, at least 1/64. */
        if (kinds[k] == DETP_TASK_VISIBILITY)
            GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_VISIBLE_SLIVER,
                                       "detp: value 0 of the result out of range", &err));
    }
    GI_CHECK_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
    GI_CHECK(jr.finished && !jr.failed);
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);

    char *anim_path = write_anim_job("badres-anim.json", 2);
    GI_REQUIRE(anim_path != NULL);
    GI_REQUIRE_OK(load(anim_path, "out-badres-anim", &job, &ctx, &err));
    free(anim_path);
    ctx.batch_dir = gi_path_join(gi_test_tmpdir(), "badres-anim-batches");
    GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
    GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_CUT,
                               "frame 0, batch 0: detp animation result", &err));
    GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_ANIM_BATCH,
                               "result of frame 0 batch 1", &err));
    GI_CHECK_OK(refuse_spoiled(&jr, &ctx, SPOIL_TRAILING,
                               "frame 0, batch 0: detp animation result", &err));
    GI_CHECK_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
    GI_CHECK(jr.finished && !jr.failed);
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
}

/* The animation batch result `in` (of a job with nv vertices) with vertex
 * v's red sum set to red, into out. */
static int set_red_sum(const gi_buf *in, uint32_t nv, uint32_t v, int64_t red, gi_buf *out,
                       gi_error *err)
{
    int64_t *sum = gi_xcalloc((size_t)nv * 3, sizeof *sum);
    int64_t *hits = gi_xcalloc(nv, sizeof *hits);
    detp_anim_result h;
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "test result");
    int rc = detp_decode_anim(&r, nv, INT64_MAX, &h, sum, hits, 1, err);
    if (rc == 0) {
        sum[3 * (size_t)v] = red;
        gi_buf_init(out);
        detp_encode_anim(&h, sum, hits, nv, out);
    }
    free(sum);
    free(hits);
    return rc;
}

/* Runs leased task t on ctx into res, then sets vertex v's red sum to red. */
static int run_with_red_sum(gi_worker_ctx *ctx, const gi_job *job, const gi_task *t,
                            uint32_t v, int64_t red, gi_buf *res, gi_error *err)
{
    gi_buf plain;
    gi_buf_init(&plain);
    int rc = gi_worker_run_task(ctx, t, &plain, err);
    if (rc == 0)
        rc = set_red_sum(&plain, job->scene.vertex_count, v, red, res, err);
    gi_buf_free(&plain);
    return rc;
}

/* An animation batch's sum beyond INT64_MAX / (the frame's batches) is
 * refused as it arrives, naming the frame, batch, vertex and bound: frame
 * 0's batches within it cannot overflow its totals, which start at zero,
 * whatever order they merge in. A later frame's changes go into the totals
 * it carries, which they can still overflow: one that overflows the total
 * merged so far is refused as it arrives, naming the frame, batch, vertex
 * and why, and the task runs again; one that only overflows with a result
 * that arrived before it but merges before it (merges go in task order) is
 * found by the merge, which fails the job saying the same. */
GI_TEST(test_detp_animation_sums_overflowing_the_total_are_refused)
{
    char *path = write_anim_job("overflow-anim.json", 2);
    GI_REQUIRE(path != NULL);
    gi_error err;
    const uint32_t v = 7;
    const int64_t max = INT64_MAX / 2; /* 2 batches a frame */
    for (int at_merge = 0; at_merge < 2; at_merge++) {
        gi_job job;
        gi_worker_ctx ctx;
        gi_jobrun jr;
        GI_REQUIRE_OK(load(path, at_merge ? "out-overflow-merge" : "out-overflow", &job, &ctx,
                           &err));
        ctx.batch_dir = gi_path_join(gi_test_tmpdir(), at_merge ? "overflow-merge-batches"
                                                                : "overflow-batches");
        GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
        const gi_task *t0 = gi_jobrun_lease(&jr), *t1 = gi_jobrun_lease(&jr);
        GI_REQUIRE(t0 && t1 && t0->id == 0 && t1->id == 1);
        gi_buf r0, r1;
        GI_REQUIRE_OK(run_with_red_sum(&ctx, &job, t0, v, max + 1, &r0, &err));
        char want[256];
        snprintf(want, sizeof want,
                 "task 0's result: frame 0, batch 0: detp animation result: vertex %u's red "
                 "sum is %lld, beyond +-%lld",
                 v, (long long)max + 1, (long long)max);
        GI_CHECK_OK(gi_test_refuse(&jr, t0, &r0, want, &err));
        gi_buf_free(&r0);
        /* Frame 0's totals at INT64_MAX - 11 for vertex v: max, max - 10. */
        t0 = gi_jobrun_lease(&jr);
        GI_REQUIRE(t0 && t0->id == 0);
        GI_REQUIRE_OK(run_with_red_sum(&ctx, &job, t0, v, max, &r0, &err));
        GI_REQUIRE_OK(run_with_red_sum(&ctx, &job, t1, v, max - 10, &r1, &err));
        gi_task_stats stats = {0};
        GI_CHECK_OK(gi_jobrun_check_result(&jr, 0, 1, &r0, &err));
        GI_CHECK_OK(gi_jobrun_complete(&jr, 0, 1, &r0, &stats)); /* its second run */
        GI_CHECK_OK(gi_jobrun_check_result(&jr, 1, 0, &r1, &err));
        GI_CHECK_OK(gi_jobrun_complete(&jr, 1, 0, &r1, &stats));
        gi_buf_free(&r0);
        gi_buf_free(&r1);
        GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, 4, &err)); /* frame 0's tiles */
        /* Frame 1's changes: +6 each, which only together overflow. */
        const gi_task *t6 = gi_jobrun_lease(&jr), *t7 = gi_jobrun_lease(&jr);
        GI_REQUIRE(t6 && t7 && t6->id == 6 && t7->id == 7);
        GI_REQUIRE_OK(run_with_red_sum(&ctx, &job, t6, v, 6, &r0, &err));
        GI_REQUIRE_OK(run_with_red_sum(&ctx, &job, t7, v, 6, &r1, &err));
        long long before = (long long)(2 * max - 10);
        if (!at_merge) {
            /* Batch 0 merged first: batch 1's sum overflows its total. */
            GI_CHECK_OK(gi_jobrun_check_result(&jr, 6, 0, &r0, &err));
            GI_CHECK_OK(gi_jobrun_complete(&jr, 6, 0, &r0, &stats));
            snprintf(want, sizeof want,
                     "task 7's result: frame 1, batch 1: detp animation result: vertex %u's "
                     "red sum overflows: %lld + 6 is out of range",
                     v, before + 6);
            /* (The merge of task 6 may have moved the tasks: t7 is stale.) */
            GI_CHECK_OK(gi_test_refuse(&jr, &gi_jobrun_task_at(&jr, 7)->task, &r1, want, &err));
            GI_CHECK(jr.retries == 2);
            GI_CHECK_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
            GI_CHECK_MSG(jr.finished && !jr.failed, "%s", jr.error.msg);
        } else {
            /* Batch 1 arrives first and waits for batch 0: each passes its
             * check against the frame's totals, their merges overflow. */
            GI_CHECK_OK(gi_jobrun_check_result(&jr, 7, 0, &r1, &err));
            GI_CHECK_OK(gi_jobrun_complete(&jr, 7, 0, &r1, &stats));
            GI_CHECK_OK(gi_jobrun_check_result(&jr, 6, 0, &r0, &err));
            GI_CHECK(gi_jobrun_complete(&jr, 6, 0, &r0, &stats) != 0);
            snprintf(want, sizeof want,
                     "detp task 7: frame 1, batch 1: detp animation result: vertex %u's "
                     "red sum overflows: %lld + 6 is out of range",
                     v, before + 6);
            GI_CHECK(jr.failed && jr.error.code == GI_EPROTO);
            GI_CHECK_MSG(strcmp(jr.error.msg, want) == 0, "%s", jr.error.msg);
        }
        gi_buf_free(&r0);
        gi_buf_free(&r1);
        gi_jobrun_free(&jr);
        gi_worker_ctx_free(&ctx);
        gi_job_free(&job);
    }
    free(path);
}

/* The batch result `in` (of a job with nv vertices) with vertex v's red
 * energy set to red, into out. */
static int set_red_energy(const gi_buf *in, uint32_t nv, uint32_t v, double red, gi_buf *out,
                          gi_error *err)
{
    double *irr = gi_xcalloc((size_t)nv * 3, sizeof *irr);
    uint64_t *hits = gi_xcalloc(nv, sizeof *hits);
    uint32_t *hits32 = gi_xcalloc(nv, sizeof *hits32);
    detp_batch_result h;
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "test result");
    int rc = detp_decode_batch(&r, nv, FLT_MAX, &h, irr, hits, err);
    if (rc == 0) {
        irr[3 * (size_t)v] = red;
        for (uint32_t i = 0; i < nv; i++)
            hits32[i] = (uint32_t)hits[i];
        gi_detp_accum acc = {.count = nv, .energy = irr, .hits = hits32};
        gi_buf_init(out);
        detp_encode_batch(&h, &acc, 1.0, out);
    }
    free(irr);
    free(hits);
    free(hits32);
    return rc;
}

/* A still's photon batches are summed, divided by the visible fraction
 * (rule 2), and published as float radiance the workers take up to
 * GI_PUBLISHED_VALUE_MAX. A batch whose energy is finite but beyond its
 * share of that (FLT_MAX here: five such batches made the job fail at
 * publish, naming the vertex, before the check bounded them) is refused as
 * it arrives, naming the vertex and the bound, and retried; batches at the
 * bound, all five into the same vertex, are accepted and the job ends well,
 * publishing a finite radiance. */
GI_TEST(test_detp_still_batch_beyond_its_share_is_refused_and_retried)
{
    for (int visible = 0; visible < 2; visible++) {
        gi_error err;
        char *path = write_job("overflow-radiance.json", "basic",
                               visible ? ", \"artifact_control\": \"visible_area\"" : "");
        GI_REQUIRE(path != NULL);
        gi_job job;
        gi_worker_ctx ctx;
        gi_jobrun jr;
        GI_REQUIRE_OK(load(path, visible ? "out-share-vis" : "out-share", &job, &ctx, &err));
        free(path);
        GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
        const uint32_t v = 7;
        gi_task_stats stats = {0};
        /* 12,000 photons in batches of 2,500: five; rule 2 divides by down
         * to one visibility ray's fraction. */
        const double share = GI_PUBLISHED_VALUE_MAX * (visible ? 1.0 / GI_DETP_VIS_RAYS : 1.0) / 5;
        double bound = 0; /* as the refusals say it */
        int refused = 0, at_bound = 0;
        const gi_task *t;
        while (!gi_jobrun_done(&jr) && (t = gi_jobrun_lease(&jr)) != NULL) {
            uint64_t id = t->id;
            uint32_t attempt = t->attempt;
            gi_buf plain, res;
            gi_buf_init(&plain);
            gi_buf_init(&res);
            GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &plain, &err));
            if (t->kind == DETP_TASK_BATCH && attempt == 0) {
                GI_REQUIRE_OK(set_red_energy(&plain, job.scene.vertex_count, v, FLT_MAX, &res,
                                             &err));
                char want[160];
                snprintf(want, sizeof want,
                         "task %llu's result: detp result: vertex 7's energy is 3.40282e+38, "
                         "beyond +-",
                         (unsigned long long)id);
                GI_CHECK_MSG(gi_test_refuse(&jr, t, &res, want, &err) == 0, "%s", err.msg);
                const char *b = strstr(err.msg, "beyond +-");
                GI_REQUIRE(b != NULL);
                bound = strtod(b + 9, NULL);
                refused++;
            } else {
                if (t->kind == DETP_TASK_BATCH) {
                    float red = (float)share; /* at the bound, not above it */
                    if ((double)red > share)
                        red = nextafterf(red, 0.0f);
                    GI_REQUIRE_OK(set_red_energy(&plain, job.scene.vertex_count, v, red, &res,
                                                 &err));
                    at_bound++;
                } else {
                    gi_buf_move(&res, &plain);
                }
                GI_CHECK_MSG(gi_jobrun_check_result(&jr, id, attempt, &res, &err) == 0,
                             "task %llu: %s", (unsigned long long)id, err.msg);
                gi_jobrun_complete(&jr, id, attempt, &res, &stats);
            }
            gi_buf_free(&plain);
            gi_buf_free(&res);
        }
        GI_CHECK_MSG(fabs(bound - share) <= 1e-5 * share, "bound %g, not %g", bound, share);
        GI_CHECK(refused == 5 && at_bound == 5 && jr.retries == 5);
        GI_CHECK_MSG(jr.finished && !jr.failed, "%s", jr.error.msg);
        gi_jobrun_free(&jr);
        gi_worker_ctx_free(&ctx);
        gi_job_free(&job);
    }
}
