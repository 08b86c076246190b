/* result_check: what the coordinator's check of a worker result costs
 * beside its merge. gi-farmd and `gi render` check every result before they
 * merge it (gi_jobrun_check_result: a result that cannot be merged fails
 * only its task's run), and for detp and quadrature the check decodes what
 * the merge decodes again; both run on the coordinator's one loop.
 *
 *   result_check JOB.json [OUT_DIR]
 *
 * Runs the job in this process, one task at a time (its worker side too,
 * untimed), and times, in this thread's CPU time, the check and the merge
 * (gi_jobrun_complete) of every result; the merge of the task that ends the
 * job (it runs the finish: the outputs) is left out. Prints one line: tasks,
 * result bytes a task, check and merge microseconds a task, check / merge;
 * then the same for each kind of task the job has (a method's numbering). */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "gi_fs.h"
#include "gi_job.h"
#include "gi_jobrun.h"
#include "gi_worker_ctx.h"

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int fail(const gi_error *err)
{
    fprintf(stderr, "result_check: %s\n", err->msg);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: result_check JOB.json [OUT_DIR]\n");
        return 2;
    }
    const char *out = argc > 2 ? argv[2] : "out/result_check";
    gi_error err;
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    if (gi_job_load(argv[1], &job, &err))
        return fail(&err);
    job.out_dir = gi_path_join(out, "outputs");
    if (gi_mkdirs(job.out_dir, &err) ||
        gi_worker_ctx_load(&ctx, 1, job.file, job.text, &job.manifest, NULL, NULL, job.assets,
                           &err))
        return fail(&err);
    ctx.batch_dir = gi_path_join(out, "batches");
    if (gi_jobrun_start(&jr, &job, &err))
        return fail(&err);
    double check_s = 0, merge_s = 0;
    size_t tasks = 0, bytes = 0;
    enum { KINDS = 16 };
    struct {
        double check_s, merge_s;
        size_t tasks, bytes;
    } kind[KINDS] = {{0}};
    while (!gi_jobrun_done(&jr)) {
        const gi_task *t = gi_jobrun_lease(&jr);
        if (!t) {
            fprintf(stderr, "result_check: nothing to lease before the job is done\n");
            return 1;
        }
        uint64_t id = t->id;
        uint32_t k = t->kind < KINDS ? t->kind : KINDS - 1;
        gi_buf res;
        gi_buf_init(&res);
        if (gi_worker_run_task(&ctx, t, &res, &err))
            return fail(&err);
        size_t len = res.len;
        double t0 = cpu_now();
        if (gi_jobrun_check_result(&jr, id, t->attempt, &res, &err))
            return fail(&err);
        double t1 = cpu_now();
        gi_jobrun_complete(&jr, id, t->attempt, &res, &ctx.stats);
        double t2 = cpu_now();
        gi_buf_free(&res);
        if (jr.failed)
            return fail(&jr.error);
        if (gi_jobrun_done(&jr))
            break;
        check_s += t1 - t0;
        merge_s += t2 - t1;
        bytes += len;
        tasks++;
        kind[k].check_s += t1 - t0;
        kind[k].merge_s += t2 - t1;
        kind[k].bytes += len;
        kind[k].tasks++;
    }
    if (!tasks) {
        fprintf(stderr, "result_check: the job has one task; nothing to time\n");
        return 1;
    }
    printf("%s: %zu tasks, %.1f KB a result, check %.1f us, merge %.1f us a task, "
           "check/merge %.3f\n",
           job.method->name, tasks, (double)bytes / (double)tasks / 1024.0,
           1e6 * check_s / (double)tasks, 1e6 * merge_s / (double)tasks, check_s / merge_s);
    for (int k = 0; k < KINDS; k++)
        if (kind[k].tasks)
            printf("  kind %d: %zu tasks, %.1f KB a result, check %.1f us, merge %.1f us a task\n",
                   k, kind[k].tasks, (double)kind[k].bytes / (double)kind[k].tasks / 1024.0,
                   1e6 * kind[k].check_s / (double)kind[k].tasks,
                   1e6 * kind[k].merge_s / (double)kind[k].tasks);
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
    return 0;
}
