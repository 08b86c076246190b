/* Unit tests: the quadrature method through the job state machine in one
 * process (coordinator and a worker context side by side): checkpoints
 * taken between rounds (and frames) resume to the same bits, damaged
 * results and tasks are refused, and the parameter block is validated. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_image.h"
#include "gi_jobrun.h"
#include "gi_test.h"
#include "gi_worker_ctx.h"
#include "quadrature/quad_farm.h"
#include "test_drive.h"

/* The test job: mode 0 refinement only, 1 hybrid, 2 refinement over the
 * 3 frames of an animation (outputs img.0000.exr ...). */
static const char *job_text(int mode)
{
    static char buf[2048];
    char src[1024];
    if (!realpath(gi_test_srcdir(), src))
        snprintf(src, sizeof src, "%s", gi_test_srcdir());
    snprintf(buf, sizeof buf,
             "{\"scene\": \"%s/scenes/cornell-box/%s\", \"method\": \"quadrature\","
             " \"seed\": 3, \"image\": {\"width\": 24, \"height\": 20},"
             " \"quadrature\": {\"rule\": \"genz-malik\", \"max_evals\": 30000, \"round_tasks\": 3,"
             " \"task_regions\": 2, \"task_splits\": 8, \"threshold\": 1e-6%s},"
             " \"outputs\": {\"exr\": \"img.exr\"}}",
             src, mode == 2 ? "scene-mobile.json" : "scene.json",
             mode == 1   ? ", \"hybrid\": true, \"mc_spp\": 1"
             : mode == 2 ? ", \"animation\": {\"object\": \"mobile\", \"frames\": 3, \"keyframes\":"
                           " [{\"frame\": 0, \"translate\": [340, -338.9, -90]},"
                           " {\"frame\": 2, \"translate\": [200, -338.9, 35]}]}"
                         : "");
    return buf;
}

/* Loads the job (coordinator side) from a file written in the test's
 * scratch directory, with outputs going to out. */
static int load_job(gi_job *job, int hybrid, const char *out, gi_error *err)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/quad-job.json", gi_test_tmpdir());
    FILE *f = fopen(path, "w");
    if (!f)
        return gi_fail(err, GI_EIO, "cannot write %s", path);
    fputs(job_text(hybrid), f);
    fclose(f);
    if (gi_job_load(path, job, err))
        return -1;
    snprintf(path, sizeof path, "%s/%s", gi_test_tmpdir(), out);
    job->out_dir = gi_xstrdup(path);
    return gi_mkdirs(path, err);
}

/* load_job, its worker context and its run started. */
static int start_job(gi_job *job, gi_worker_ctx *ctx, gi_jobrun *jr, int hybrid,
                     const char *out, gi_error *err)
{
    if (load_job(job, hybrid, out, err))
        return -1;
    if (gi_worker_ctx_load(ctx, 1, job->file, job->text, &job->manifest, NULL, NULL,
                           job->assets, err)) {
        gi_job_free(job);
        return -1;
    }
    if (gi_jobrun_start(jr, job, err)) {
        gi_worker_ctx_free(ctx);
        gi_job_free(job);
        return -1;
    }
    return 0;
}

static int read_file(const char *dir, const char *name, gi_buf *out)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s/%s", gi_test_tmpdir(), dir, name);
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    char b[4096];
    size_t n;
    while ((n = fread(b, 1, sizeof b, f)) > 0)
        gi_buf_put(out, b, n);
    fclose(f);
    return 0;
}

GI_TEST(test_quad_checkpoint_restore_gives_the_same_image)
{
    static const char *const frame_names[] = {"img.0000.exr", "img.0001.exr", "img.0002.exr"};
    static const char *const still_name[] = {"img.exr"};
    for (int hybrid = 0; hybrid < 3; hybrid++) {
        const char *const *names = hybrid == 2 ? frame_names : still_name;
        int nfiles = hybrid == 2 ? 3 : 1;
        gi_error err;
        gi_job job;
        GI_REQUIRE_OK(load_job(&job, hybrid, "ref", &err));
        gi_worker_ctx ctx;
        GI_REQUIRE_OK(gi_worker_ctx_load(&ctx, 1, job.file, job.text, &job.manifest, NULL, NULL,
                                         job.assets, &err));
        gi_jobrun jr;
        GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
        GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
        GI_REQUIRE(jr.finished);
        uint64_t tasks = jr.task_count;
        GI_CHECK_MSG(tasks > 12, "only %llu tasks", (unsigned long long)tasks);
        gi_jobrun_free(&jr);
        gi_job_free(&job);
        gi_buf ref[3];
        for (int k = 0; k < nfiles; k++) {
            gi_buf_init(&ref[k]);
            GI_REQUIRE(read_file("ref", names[k], &ref[k]) == 0);
        }

        /* Stop after k tasks (inside round 0, between rounds, in the Monte
         * Carlo round), checkpoint, drop everything, restore, finish. */
        int stops[] = {1, 4, 9, (int)tasks / 2, (int)tasks - 1};
        for (size_t s = 0; s < sizeof stops / sizeof stops[0]; s++) {
            char out[64];
            snprintf(out, sizeof out, "ck%d-%zu", hybrid, s);
            GI_REQUIRE_OK(load_job(&job, hybrid, out, &err));
            GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
            GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, (uint64_t)stops[s], &err));
            gi_buf ck;
            gi_buf_init(&ck);
            GI_REQUIRE_OK(gi_jobrun_checkpoint(&jr, &ck, &err));
            gi_jobrun_free(&jr);
            gi_job_free(&job);

            GI_REQUIRE_OK(load_job(&job, hybrid, out, &err));
            GI_REQUIRE_OK(gi_jobrun_restore(&jr, &job, &ck, &err));
            GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
            GI_CHECK(jr.finished && jr.task_count == tasks);
            gi_jobrun_free(&jr);
            gi_job_free(&job);
            for (int k = 0; k < nfiles; k++) {
                gi_buf img;
                gi_buf_init(&img);
                GI_REQUIRE(read_file(out, names[k], &img) == 0);
                GI_CHECK_MSG(img.len == ref[k].len &&
                                 memcmp(img.data, ref[k].data, ref[k].len) == 0,
                             "mode %d: stop after %d tasks: %s differs", hybrid, stops[s],
                             names[k]);
                gi_buf_free(&img);
            }
            gi_buf_free(&ck);
        }
        for (int k = 0; k < nfiles; k++)
            gi_buf_free(&ref[k]);
        gi_worker_ctx_free(&ctx);
    }
}

GI_TEST(test_quad_damaged_results_and_tasks_are_refused)
{
    gi_error err;
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(start_job(&job, &ctx, &jr, 0, "damaged", &err));
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t != NULL);
    gi_buf res;
    gi_buf_init(&res);
    GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &res, &err));
    /* Every truncation, and a flipped byte in the header, fails cleanly. */
    gi_task_queue fq;
    gi_task_queue_init(&fq, 1000);
    for (size_t cut = 0; cut < res.len; cut += 1 + res.len / 97) {
        gi_buf part;
        gi_buf_init(&part);
        gi_buf_put(&part, res.data, cut);
        GI_CHECK(job.method->merge(&job, t, &part, &fq, &err) == -1 && err.code == GI_EPROTO);
        gi_buf_free(&part);
    }
    gi_buf bad;
    gi_buf_init(&bad);
    gi_buf_put(&bad, res.data, res.len);
    gi_buf_put_u8(&bad, 0);
    GI_CHECK(job.method->merge(&job, t, &bad, &fq, &err) == -1);
    gi_buf_reset(&bad);
    gi_buf_put(&bad, res.data, res.len);
    bad.data[8 * 7 + 3] ^= 0x7f; /* the change of estimates becomes huge or NaN */
    memset(bad.data + 8 * 6, 0xff, 8); /* closed error: NaN */
    GI_CHECK(job.method->merge(&job, t, &bad, &fq, &err) == -1);
    GI_CHECK(fq.count == 0);
    /* A task payload cut short is refused by the worker. */
    gi_task cut = *t;
    gi_buf_init(&cut.payload);
    gi_buf_put(&cut.payload, t->payload.data, t->payload.len - 5);
    gi_buf out;
    gi_buf_init(&out);
    GI_CHECK(gi_worker_run_task(&ctx, &cut, &out, &err) == -1 && err.code == GI_EPROTO);
    gi_buf_free(&cut.payload);
    gi_buf_free(&out);
    gi_buf_free(&bad);
    gi_buf_free(&res);
    gi_task_queue_free(&fq);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_worker_ctx_free(&ctx);
}

/* The same damage reaching the coordinator as a worker's answer is refused
 * as it arrives (gi_jobrun_check_result), naming the task: the run fails,
 * the task runs again, and the job ends well. */
GI_TEST(test_quad_damaged_results_are_retried)
{
    gi_error err;
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(start_job(&job, &ctx, &jr, 0, "retried", &err));
    enum { CUT, TRAILING, NAN_HEADER, PIXEL_OUT_OF_RANGE, SPOILS };
    for (int spoil = 0; spoil < SPOILS; spoil++) {
        if (spoil == PIXEL_OUT_OF_RANGE) /* task 0 ran well: one failure short of its last */
            GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, 1, &err));
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t != NULL);
        gi_buf bad;
        gi_buf_init(&bad);
        GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &bad, &err));
        GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &bad, &err) == 0);
        /* 13 eight-byte header values, then the delta: u32 count, u32 pixel. */
        GI_REQUIRE(bad.len > 112 && gi_le_get_u32(bad.data + 104) > 0);
        const char *want = "quadrature result";
        if (spoil == CUT) {
            bad.len /= 2;
        } else if (spoil == TRAILING) {
            gi_buf_put_u8(&bad, 0);
        } else if (spoil == NAN_HEADER) {
            memset(bad.data + 8 * 6, 0xff, 8); /* closed error: NaN */
        } else {
            gi_le_put_u32(bad.data + 108, (uint32_t)(job.width * job.height));
            want = "quadrature result: bad pixel index";
        }
        char msg[128];
        snprintf(msg, sizeof msg, "task %llu's result: %s", (unsigned long long)t->id, want);
        uint64_t retries = jr.retries;
        GI_CHECK_MSG(gi_test_refuse(&jr, t, &bad, msg, &err) == 0, "spoil %d: %s", spoil,
                     err.msg);
        GI_CHECK(jr.retries == retries + 1);
        gi_buf_free(&bad);
    }
    GI_REQUIRE_OK(gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
    GI_CHECK(jr.finished && !jr.failed);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_worker_ctx_free(&ctx);
}

/* Sets every value of a result's image delta (13 eight-byte header values,
 * then u32 count, then per pixel u32 index and three f64s) to v, or only
 * the first if `first`; returns the pixel count. */
static uint32_t set_delta(gi_buf *res, double v, int first)
{
    uint32_t n = gi_le_get_u32(res->data + 104);
    for (uint32_t i = 0; i < n; i++)
        for (int c = 0; c < 3 && (!first || (i == 0 && c == 0)); c++)
            memcpy(res->data + 108 + (size_t)i * 28 + 4 + 8 * (size_t)c, &v, 8);
    return n;
}

/* The image is the sum of every task's delta, written as floats: a delta
 * value beyond what task i may add (gi_quad_pixel_delta_max(i); beyond
 * FLT_MAX, or just beyond the bound) is refused and retried, while a job
 * whose every result adds exactly its bound to every pixel it touches is
 * accepted whole, and its image is finite, some pixels beyond FLT_MAX / 4. */
GI_TEST(test_quad_pixel_values_beyond_what_a_float_holds_are_refused)
{
    gi_error err;
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    GI_REQUIRE_OK(start_job(&job, &ctx, &jr, 1, "bounded", &err));
    uint64_t refused = 0, tasks = 0;
    const gi_task *t;
    while (!gi_jobrun_done(&jr) && (t = gi_jobrun_lease(&jr)) != NULL) {
        uint64_t id = t->id;
        uint32_t attempt = t->attempt;
        double bound = gi_quad_pixel_delta_max(id);
        gi_buf res;
        gi_buf_init(&res);
        GI_REQUIRE_OK(gi_worker_run_task(&ctx, t, &res, &err));
        /* Twice beyond: 1e39 (past FLT_MAX, far within 1e280) for task 0,
         * the next double past the bound for the others. */
        double over = id == 0 ? 1e39 : nextafter(bound, INFINITY);
        if (attempt == 0 && set_delta(&res, over, 1) > 0) {
            char want[160];
            snprintf(want, sizeof want, "task %llu's result: quadrature result: pixel ",
                     (unsigned long long)id);
            GI_CHECK_MSG(gi_test_refuse(&jr, t, &res, want, &err) == 0, "task %llu: %s",
                         (unsigned long long)id, err.msg);
            GI_CHECK_MSG(strstr(err.msg, "not within +-") != NULL, "%s", err.msg);
            refused++;
            gi_buf_free(&res);
            continue;
        }
        set_delta(&res, bound, 0);
        GI_CHECK_MSG(gi_jobrun_check_result(&jr, id, attempt, &res, &err) == 0, "task %llu: %s",
                     (unsigned long long)id, err.msg);
        gi_task_stats stats;
        memset(&stats, 0, sizeof stats);
        gi_jobrun_complete(&jr, id, attempt, &res, &stats);
        gi_buf_free(&res);
        tasks++;
    }
    GI_CHECK_MSG(jr.finished && !jr.failed, "%s", jr.error.msg);
    GI_CHECK(refused > 10 && jr.retries == refused && tasks == jr.task_count);
    char path[1024];
    snprintf(path, sizeof path, "%s/bounded/img.exr", gi_test_tmpdir());
    gi_image img;
    GI_REQUIRE_OK(gi_exr_read(path, &img, &err));
    size_t big = 0;
    for (size_t i = 0; i < (size_t)img.width * img.height * 3; i++) {
        GI_REQUIRE(isfinite(img.pixels[i]));
        big += img.pixels[i] > FLT_MAX / 4;
    }
    GI_CHECK(big > 0);
    gi_image_free(&img);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_worker_ctx_free(&ctx);
}

/* What a check decoded and kept (merged by merge_decoded, results given
 * out of order) makes the same image and report as merging the worker's
 * bytes. */
GI_TEST(test_quad_outputs_are_the_same_merged_from_the_checks_decoding)
{
    for (int hybrid = 0; hybrid < 2; hybrid++) {
        gi_buf img[2];
        for (int checked = 0; checked < 2; checked++) {
            gi_error err;
            gi_job job;
            char out[32];
            snprintf(out, sizeof out, "decoded%d-%d", hybrid, checked);
            gi_worker_ctx ctx;
            gi_jobrun jr;
            GI_REQUIRE_OK(start_job(&job, &ctx, &jr, hybrid, out, &err));
            GI_REQUIRE_OK(checked ? gi_test_drive_checked(&jr, &ctx, 5, &err)
                                  : gi_test_drive(&jr, &ctx, UINT64_MAX, &err));
            GI_CHECK(jr.finished && !jr.failed);
            gi_jobrun_free(&jr);
            gi_job_free(&job);
            gi_worker_ctx_free(&ctx);
            gi_buf_init(&img[checked]);
            GI_REQUIRE(read_file(out, "img.exr", &img[checked]) == 0);
        }
        GI_CHECK_MSG(img[0].len == img[1].len && memcmp(img[0].data, img[1].data, img[0].len) == 0,
                     "hybrid %d: the images differ", hybrid);
        gi_buf_free(&img[0]);
        gi_buf_free(&img[1]);
    }
}

static int parse_block(const char *block, gi_error *err)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{\"scene\": \"s.json\", \"method\": \"quadrature\", \"quadrature\": %s}", block);
    gi_job job;
    int rc = gi_job_parse(text, strlen(text), "q.json", &job, err);
    gi_job_free(&job);
    return rc;
}

/* With no "outputs" block every kind is written, named after the job; the
 * report, which is JSON, as NAME-report.json (NAME.json is the job file). */
GI_TEST(test_quad_default_outputs_are_named_by_kind)
{
    const char *text = "{\"scene\": \"s.json\", \"method\": \"quadrature\"}";
    gi_job job;
    gi_error err;
    GI_REQUIRE(gi_job_parse(text, strlen(text), "hall.json", &job, &err) == 0);
    const char *want[][2] = {
        {"exr", "hall.exr"}, {"png", "hall.png"}, {"report", "hall-report.json"}};
    GI_CHECK(job.output_count == 3);
    for (int i = 0; i < job.output_count && i < 3; i++) {
        GI_CHECK_MSG(strcmp(job.outputs[i].kind, want[i][0]) == 0, "kind %s", job.outputs[i].kind);
        GI_CHECK_MSG(strcmp(job.outputs[i].file, want[i][1]) == 0, "file %s", job.outputs[i].file);
    }
    gi_job_free(&job);
}

GI_TEST(test_quad_parameters_are_validated)
{
    gi_error err;
    GI_CHECK_OK(parse_block("{}", &err));
    GI_CHECK_OK(parse_block("{\"dims\": 6, \"rule\": \"genz-malik\", \"heap\": \"pairing\","
                            " \"initial\": [8, 2], \"initial_path\": 2, \"hybrid\": true,"
                            " \"mc_spp\": 4, \"max_bounces\": 3, \"rr_depth\": 1,"
                            " \"axis\": \"centre\", \"tolerance\": 1e-3, \"threshold\": 1e-7}",
                            &err));
    const char *bad[][2] = {
        {"{\"dims\": 5}", "quadrature.dims: 5 is odd"},
        {"{\"dims\": 2}", "quadrature.dims: 2 is out of range"},
        {"{\"dims\": 8}", "too many for the Boole rule"},
        {"{\"rule\": \"gauss\"}", "quadrature.rule"},
        {"{\"initial\": [3, 4]}", "quadrature.initial[0]: 3 is not a power of two"},
        {"{\"initial\": [4]}", "quadrature.initial: expected [x, y]"},
        {"{\"initial_path\": 16, \"dims\": 8, \"rule\": \"genz-malik\"}", "initial regions"},
        {"{\"mc_spp\": 4}", "quadrature.mc_spp: only with \"hybrid\": true"},
        {"{\"threshold\": -1}", "quadrature.threshold"},
        {"{\"speed\": 1}", "speed: unknown key"},
        {"{\"max_evals\": 0}", "quadrature.max_evals"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        GI_CHECK_MSG(parse_block(bad[i][0], &err) == -1 && err.code == GI_EINVAL &&
                         strstr(err.msg, bad[i][1]) && strstr(err.msg, "q.json"),
                     "%s: \"%s\" does not say \"%s\"", bad[i][0], err.msg, bad[i][1]);
    }
}
