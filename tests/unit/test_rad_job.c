/* Unit tests: the radiosity method as a job - parameter validation, and
 * checkpoints (a run stopped anywhere and restored gives the same bits). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_jobrun.h"
#include "gi_test.h"
#include "gi_worker_ctx.h"
#include "test_drive.h"

static const char *job_text =
    "{\"scene\": \"%s/scenes/cornell-box/scene.json\", \"method\": \"radiosity\", \"seed\": 3,"
    " \"image\": {\"width\": 24, \"height\": 16},"
    " \"radiosity\": {%s},"
    " \"outputs\": {\"exr\": \"r.exr\", \"ply\": \"r.ply\", \"factorization\": \"r.fact\"}}";

#define PARAMS                                                                                     \
    "\"patches\": 40, \"levels\": 1, \"rays\": 64, \"task_elements\": 37, "                        \
    "\"tile\": 8, \"image_spp\": 2"

static int fetch_none(void *fctx, const char *hash, gi_error *err)
{
    return gi_fail(err, GI_EIO, "no asset %.12s in the test", hash);
}

static int load(const char *dir, const char *params, gi_job *job, gi_error *err)
{
    char text[2048], path[1024], *src = realpath(gi_test_srcdir(), NULL);
    snprintf(text, sizeof text, job_text, src, params);
    free(src);
    snprintf(path, sizeof path, "%s/job.json", dir);
    if (gi_write_file_atomic(path, text, strlen(text), err) || gi_job_load(path, job, err))
        return -1;
    job->out_dir = gi_xstrdup(dir);
    return 0;
}

static int read_all(const char *dir, const char *name, gi_buf *out, gi_error *err)
{
    char *path = gi_path_join(dir, name);
    gi_buf_init(out);
    int rc = gi_read_file(path, (size_t)1 << 30, out, err);
    free(path);
    return rc;
}

/* Loads the job into dir, a worker for it, and starts its run. */
static int start(const char *dir, gi_job *job, gi_worker_ctx *ctx, gi_jobrun *jr, gi_error *err)
{
    if (load(dir, PARAMS, job, err))
        return -1;
    if (gi_worker_ctx_load(ctx, 1, job->file, job->text, &job->manifest, fetch_none, NULL,
                           job->assets, err) == 0) {
        if (gi_jobrun_start(jr, job, err) == 0)
            return 0;
        gi_worker_ctx_free(ctx);
    }
    gi_job_free(job);
    return -1;
}

GI_TEST(test_rad_job_checkpoint_restore_gives_the_same_outputs)
{
    gi_error err;
    char ref[1024];
    snprintf(ref, sizeof ref, "%s/ref", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_mkdirs(ref, &err));
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(start(ref, &job, &ctx, &jr, &err));
    uint64_t ff_tasks = jr.task_count;
    GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
    GI_REQUIRE(jr.finished);
    uint64_t all_tasks = jr.task_count;
    GI_CHECK(all_tasks > ff_tasks); /* image tiles followed */
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);

    /* Stop in the form-factor phase, at its end, and among the tiles. */
    int stops[] = {2, (int)ff_tasks, (int)ff_tasks + 3};
    for (size_t s = 0; s < GI_ARRAY_LEN(stops); s++) {
        char dir[1024];
        snprintf(dir, sizeof dir, "%s/stop%zu", gi_test_tmpdir(), s);
        GI_REQUIRE_OK(gi_mkdirs(dir, &err));
        GI_REQUIRE_OK(load(dir, PARAMS, &job, &err));
        GI_REQUIRE_OK(gi_worker_ctx_load(&ctx, 1, job.file, job.text, &job.manifest, fetch_none,
                                         NULL, job.assets, &err));
        GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
        GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, (uint64_t)stops[s], &err));
        gi_jobrun_lease(&jr); /* leased, never answered: runs again after restore */
        gi_buf ck;
        gi_buf_init(&ck);
        GI_REQUIRE_OK(gi_jobrun_checkpoint(&jr, &ck, &err));
        gi_jobrun_free(&jr);
        gi_worker_ctx_free(&ctx);
        gi_job_free(&job);

        GI_REQUIRE_OK(load(dir, PARAMS, &job, &err));
        GI_REQUIRE_OK(gi_jobrun_restore(&jr, &job, &ck, &err));
        GI_REQUIRE_OK(gi_worker_ctx_load(&ctx, 1, job.file, job.text, &job.manifest, fetch_none,
                                         NULL, job.assets, &err));
        GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
        GI_CHECK_MSG(jr.finished && jr.task_count == all_tasks, "stop %d", stops[s]);
        static const char *const files[] = {"r.fact", "r.ply", "r.exr"};
        for (int f = 0; f < 3; f++) {
            gi_buf a, b;
            GI_REQUIRE_OK(read_all(ref, files[f], &a, &err));
            GI_REQUIRE_OK(read_all(dir, files[f], &b, &err));
            GI_CHECK_MSG(a.len == b.len && memcmp(a.data, b.data, a.len) == 0,
                         "stop %d: %s differs", stops[s], files[f]);
            gi_buf_free(&a);
            gi_buf_free(&b);
        }
        gi_buf_free(&ck);
        gi_jobrun_free(&jr);
        gi_worker_ctx_free(&ctx);
        gi_job_free(&job);
    }
}

GI_TEST(test_rad_job_parameters_are_validated)
{
    static const struct {
        const char *extra, *what;
    } cases[] = {
        {"\"rays\": 1000", "radiosity.rays"},
        {"\"rays\": 0", "radiosity.rays"},
        {"\"levels\": 11", "radiosity.levels"},
        {"\"levels\": 1, \"patch_level\": 2", "radiosity.patch_level"},
        {"\"max_level\": 1", "2mce"},
        {"\"factorization\": \"svd\"", "radiosity.factorization"},
        {"\"factorization\": \"2mce\", \"threshold\": 1, \"target_patches\": 5", "either"},
        {"\"factorization\": \"2mce\", \"patch_level\": 0", "only for"},
        {"\"solver\": \"jacobi\"", "radiosity.solver"},
        {"\"tolerance\": 0", "radiosity.tolerance"},
        {"\"colour\": true", "colour"},
        {"\"emissions\": []", "radiosity.emissions"},
        {"\"emissions\": [{\"name\": \"x\", \"materials\": {\"velvet\": [1, 1, 1]}}]", "velvet"},
        {"\"emissions\": [{\"name\": \"x\", \"objects\": {\"sofa\": [1, 1, 1]}}]", "sofa"},
        {"\"patches\": 4000, \"levels\": 2, \"patch_level\": 1", "patches at patch_level"},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(cases); i++) {
        gi_error err;
        gi_error_clear(&err);
        gi_job job;
        int rc = load(gi_test_tmpdir(), cases[i].extra, &job, &err);
        GI_CHECK_MSG(rc == -1 && err.code == GI_EINVAL && strstr(err.msg, cases[i].what) &&
                         strstr(err.msg, "job.json") && !strchr(err.msg, '\n'),
                     "case %zu: rc %d: %s", i, rc, err.msg);
        gi_job_free(&job);
    }
}

/* A form-factor result that does not decode (cut short, a row whose rays do
 * not add up, bytes past its rows), or an image tile of the wrong size, is
 * refused as it arrives, naming the task: its run fails and the task runs
 * again, and the job still ends well. */
GI_TEST(test_rad_job_malformed_form_factor_result_is_retried)
{
    gi_error err;
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/badff", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_mkdirs(dir, &err));
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(start(dir, &job, &ctx, &jr, &err));
    uint64_t ff_tasks = jr.task_count;
    GI_REQUIRE(ff_tasks >= 1);
    for (int spoil = 0; spoil < 3; spoil++) {
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t != NULL);
        gi_buf good, bad;
        gi_buf_init(&good);
        gi_buf_init(&bad);
        GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &good, &err));
        GI_REQUIRE(good.len > 20);
        GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &good, &err) == 0);
        gi_buf_put(&bad, good.data, good.len);
        if (spoil == 0)
            bad.len -= 3;
        else if (spoil == 1)
            bad.data[4]++; /* the first row's escaped rays: one too many */
        else
            gi_buf_put_u32(&bad, 0);
        char want[64];
        snprintf(want, sizeof want, "task %llu's result: radiosity", (unsigned long long)t->id);
        uint64_t retries = jr.retries;
        GI_CHECK_OK(gi_test_refuse(&jr, t, &bad, want, &err));
        GI_CHECK(jr.retries == retries + 1);
        gi_buf_free(&good);
        gi_buf_free(&bad);
    }
    /* The form factors, then an image tile one pixel short. */
    GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, ff_tasks, &err));
    GI_REQUIRE(jr.task_count > ff_tasks);
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t != NULL && t->id >= ff_tasks);
    gi_buf tile;
    gi_buf_init(&tile);
    GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &tile, &err));
    GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &tile, &err) == 0);
    tile.len -= 12;
    char want[64];
    snprintf(want, sizeof want, "task %llu's result: tile result has", (unsigned long long)t->id);
    GI_CHECK_OK(gi_test_refuse(&jr, t, &tile, want, &err));
    gi_buf_free(&tile);
    GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
    GI_CHECK(jr.finished && !jr.failed && jr.retries == 4);
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
}
