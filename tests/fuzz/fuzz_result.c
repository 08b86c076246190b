/* fuzz_result: libFuzzer target for a worker's result as the coordinator
 * takes it, for every method and task kind, through the method interface
 * the way gi-farmd and `gi render` drive it (gi_jobrun_check_result, then
 * gi_jobrun_complete: merge, and finish after the last task): pt tiles,
 * detp photon batches and image tiles, an animation's batches and frame
 * tiles, radiosity form-factor blocks and tiles, quadrature rounds. The
 * decoders alone are fuzzed by fuzz_detp_result, fuzz_rad_ff and fuzz_quad;
 * here what a check lets through meets the merge and the finish.
 *
 * The first byte picks the job (% JOBS), the second a point in its run
 * (% the points recorded): the run is restored from the checkpoint taken
 * there when the target started, its next task leased, and the rest of the
 * input given as that task's result.
 *
 * Properties: a result the check refuses is refused with GI_EPROTO and a
 * one-line message; one it takes merges (and finishes, for the last task)
 * without failing the job: a result that would fail the job must be refused
 * by the check, so that the task is retried elsewhere instead. Never crash,
 * leak or hang.
 *
 * With GI_FUZZ_RESULT_SEEDS=DIR in the environment it writes the seed
 * corpus instead (the real result of the task leased at each point, as an
 * in-process worker computed it) and exits. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_job.h"
#include "gi_jobrun.h"
#include "gi_log.h"
#include "gi_worker_ctx.h"
#include "small_jobs.h"

static const char *const job_texts[] = {
    SMALL_JOB_TEXTS,
    "{\"scene\": \"scene.json\", \"method\": \"quadrature\", \"seed\": 3,"
    " \"image\": {\"width\": 8, \"height\": 6},"
    " \"quadrature\": {\"rule\": \"genz-malik\", \"max_evals\": 20000, \"round_tasks\": 2,"
    "  \"task_regions\": 2, \"task_splits\": 4, \"threshold\": 1e-6},"
    " \"outputs\": {\"exr\": \"e.exr\"}}",
    SMALL_JOB_DETP_CAMERA,
    SMALL_JOB_RAD_CAMERA,
};
#define JOBS (SMALL_JOBS + 3)
#define MAX_POINTS 64

/* A point in a job's run: the checkpoint taken there, and the result the
 * task leased next really had (for the seeds). */
typedef struct point {
    gi_buf checkpoint, result;
} point;

static char job_path[JOBS][SMALL_JOB_PATH_MAX];
static point points[JOBS][MAX_POINTS];
static size_t point_count[JOBS];

/* Runs job `which` to its end with an in-process worker, recording a point
 * before each of its first MAX_POINTS tasks. */
static int record_points(int which, gi_error *err)
{
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    if (small_jobs_start(job_path[which], &job, &ctx, &jr, err))
        return -1;
    int rc = 0;
    while (rc == 0 && !gi_jobrun_done(&jr)) {
        point *p = point_count[which] < MAX_POINTS ? &points[which][point_count[which]] : NULL;
        if (p) {
            gi_buf_init(&p->checkpoint);
            gi_buf_init(&p->result);
            rc = gi_jobrun_checkpoint(&jr, &p->checkpoint, err);
        }
        const gi_task *t = gi_jobrun_lease(&jr);
        if (rc == 0 && !t)
            rc = gi_fail(err, GI_EINTERNAL, "nothing to lease");
        gi_buf res;
        gi_buf_init(&res);
        if (rc == 0)
            rc = gi_worker_run_task(&ctx, t, &res, err);
        if (rc == 0 && p) {
            gi_buf_put(&p->result, res.data, res.len);
            point_count[which]++;
        }
        if (rc == 0)
            rc = gi_jobrun_check_result(&jr, t->id, t->attempt, &res, err);
        if (rc == 0 && gi_jobrun_complete(&jr, t->id, t->attempt, &res, &ctx.stats))
            rc = gi_fail(err, GI_EINTERNAL, "%s", jr.error.msg);
        gi_buf_free(&res);
    }
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
    return rc;
}

static int write_seeds(const char *seeds, gi_error *err)
{
    for (int j = 0; j < JOBS; j++)
        for (size_t i = 0; i < point_count[j]; i++) {
            gi_buf s;
            gi_buf_init(&s);
            gi_buf_put_u8(&s, (uint8_t)j);
            gi_buf_put_u8(&s, (uint8_t)i);
            gi_buf_put(&s, points[j][i].result.data, points[j][i].result.len);
            char path[600];
            snprintf(path, sizeof path, "%s/job%d-task%zu", seeds, j, i);
            int rc = gi_write_file_atomic(path, s.data, s.len, err);
            gi_buf_free(&s);
            if (rc)
                return -1;
        }
    return 0;
}

static void cleanup(void)
{
    for (int j = 0; j < JOBS; j++)
        for (size_t i = 0; i < point_count[j]; i++) {
            gi_buf_free(&points[j][i].checkpoint);
            gi_buf_free(&points[j][i].result);
        }
    small_jobs_remove();
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    gi_log_set_level(GI_LOG_ERROR); /* refusals and finishes are logged */
    small_jobs_write("result", job_texts, JOBS, job_path);
    atexit(cleanup);
    gi_error err;
    for (int i = 0; i < JOBS; i++) {
        if (record_points(i, &err)) {
            fprintf(stderr, "fuzz_result: job %d: %s\n", i, err.msg);
            abort();
        }
    }
    const char *seeds = getenv("GI_FUZZ_RESULT_SEEDS");
    if (seeds) {
        if (write_seeds(seeds, &err)) {
            fprintf(stderr, "fuzz_result: %s\n", err.msg);
            exit(1);
        }
        exit(0);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2)
        return 0;
    int which = data[0] % JOBS;
    const point *p = &points[which][data[1] % point_count[which]];
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    if (small_jobs_load(job_path[which], &job, &err) ||
        gi_jobrun_restore(&jr, &job, &p->checkpoint, &err))
        abort(); /* recorded from this very job: it restores */
    const gi_task *t = gi_jobrun_lease(&jr);
    if (!t)
        abort();
    uint64_t id = t->id;
    uint32_t attempt = t->attempt;
    gi_buf res;
    gi_buf_init(&res);
    gi_buf_put(&res, data + 2, size - 2);
    gi_task_stats stats = {0};
    gi_error_clear(&err);
    if (gi_jobrun_check_result(&jr, id, attempt, &res, &err)) {
        if (err.code != GI_EPROTO || !err.msg[0] || strchr(err.msg, '\n'))
            abort();
    } else if (gi_jobrun_complete(&jr, id, attempt, &res, &stats)) {
        fprintf(stderr, "fuzz_result: job %d, task %llu: a result its check took failed the "
                "job: %s\n", which, (unsigned long long)id, jr.error.msg);
        abort();
    }
    gi_buf_free(&res);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    return 0;
}
