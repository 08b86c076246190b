/* fuzz_checkpoint: libFuzzer target for job checkpoints, which gi-farmd
 * reads back when it restarts (gi_jobrun_restore and the methods' load):
 * a damaged one must be refused with a message (the job then starts over),
 * never crash, leak or hang the coordinator. The first byte picks one of
 * six small jobs (detp, a detp animation, pt, radiosity, detp and
 * radiosity camera paths; quadrature's checkpoints are in fuzz_quad); the
 * rest is the checkpoint. With the byte's high bit set, the rest is a `gi
 * render` checkpoint file instead (gi_local_checkpoint.h: its header, the
 * job's identity and batch root, then the same state), read back as `gi
 * render --resume` does.
 *
 * With GI_FUZZ_CHECKPOINT_SEEDS=DIR in the environment it writes the seed
 * corpus instead: each job run in this process (an in-process worker) and
 * checkpointed after several numbers of merged tasks (the next task lost
 * with its host once), then it exits. The corpus keeps older versions'
 * seeds too (the v6- ones are version 6's). */
#define _XOPEN_SOURCE 700 /* nftw */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_job.h"
#include "gi_jobrun.h"
#include "gi_limits.h"
#include "gi_local_checkpoint.h"
#include "gi_log.h"
#include "gi_worker_ctx.h"
#include "small_jobs.h"

static const char *const job_texts[] = {SMALL_JOB_TEXTS, SMALL_JOB_DETP_CAMERA,
                                        SMALL_JOB_RAD_CAMERA};
#define JOBS (SMALL_JOBS + 2)

static char job_path[JOBS][SMALL_JOB_PATH_MAX], local_path[300];

/* A seed: the selector byte, then the bytes of the file at path. */
static int write_local_seed(const char *seeds, int which, uint64_t done, const char *path,
                            gi_error *err)
{
    gi_buf file, ck;
    gi_buf_init(&file);
    gi_buf_init(&ck);
    int rc = gi_read_file(path, (size_t)1 << 30, &file, err);
    gi_buf_put_u8(&ck, (uint8_t)(which | 0x80));
    gi_buf_put(&ck, file.data, file.len);
    char seed[600];
    snprintf(seed, sizeof seed, "%s/local%d-after-%llu", seeds, which, (unsigned long long)done);
    if (rc == 0)
        rc = gi_write_file_atomic(seed, ck.data, ck.len, err);
    gi_buf_free(&file);
    gi_buf_free(&ck);
    return rc;
}

/* Runs job `which` in this process, writing a checkpoint after each of
 * `stops` merged tasks as SEEDS/job<which>-after-<stop>, and the same as a
 * `gi render` checkpoint as SEEDS/local<which>-after-<stop>. */
static int write_seeds(const char *seeds, int which, gi_error *err)
{
    static const uint64_t stops[] = {1, 2, 4, 7, 11, 16, 30, 60, 100};
    gi_job job;
    gi_worker_ctx ctx;
    gi_jobrun jr;
    if (small_jobs_start(job_path[which], &job, &ctx, &jr, err))
        return -1;
    uint64_t done = 0;
    size_t next = 0;
    int rc = 0;
    while (rc == 0 && !gi_jobrun_done(&jr)) {
        const gi_task *t = gi_jobrun_lease(&jr);
        if (!t)
            return gi_fail(err, GI_EINTERNAL, "nothing to lease");
        gi_buf res;
        gi_buf_init(&res);
        rc = gi_worker_run_task(&ctx, t, &res, err);
        if (rc == 0 && gi_jobrun_complete(&jr, t->id, t->attempt, &res, &ctx.stats))
            rc = gi_fail(err, GI_EINTERNAL, "%s", jr.error.msg);
        gi_buf_free(&res);
        if (rc || next == sizeof stops / sizeof stops[0] || ++done != stops[next])
            continue;
        next++;
        /* The next task lost with its host once, so that its losses and
         * their host are in the checkpoint (version 6). */
        const gi_task *next_task = gi_jobrun_lease(&jr);
        gi_error lost;
        gi_fail(&lost, GI_ECRASH, "seed: host lost");
        if (next_task)
            gi_jobrun_lost(&jr, next_task->id, next_task->attempt, "seed-host", &lost);
        gi_buf ck;
        gi_buf_init(&ck);
        gi_buf_put_u8(&ck, (uint8_t)which);
        rc = gi_jobrun_checkpoint(&jr, &ck, err);
        char path[600];
        snprintf(path, sizeof path, "%s/job%d-after-%llu", seeds, which,
                 (unsigned long long)done);
        if (rc == 0)
            rc = gi_write_file_atomic(path, ck.data, ck.len, err);
        gi_buf_free(&ck);
        char *local = gi_path_join(small_jobs_dir, "local.checkpoint");
        if (rc == 0)
            rc = gi_local_checkpoint_write(&jr, "/var/tmp/gi-render-Seed01", local, err);
        if (rc == 0)
            rc = write_local_seed(seeds, which, done, local, err);
        free(local);
    }
    gi_jobrun_free(&jr);
    gi_worker_ctx_free(&ctx);
    gi_job_free(&job);
    return rc;
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    gi_log_set_level(GI_LOG_ERROR); /* restores and refusals are logged */
    small_jobs_write("checkpoint", job_texts, JOBS, job_path);
    atexit(small_jobs_remove);
    snprintf(local_path, sizeof local_path, "%s/fuzzed.checkpoint", small_jobs_dir);
    const char *seeds = getenv("GI_FUZZ_CHECKPOINT_SEEDS");
    if (seeds) {
        gi_error err;
        for (int i = 0; i < JOBS; i++)
            if (write_seeds(seeds, i, &err)) {
                fprintf(stderr, "job %d: %s\n", i, err.msg);
                exit(1);
            }
        exit(0);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    gi_job job;
    gi_error err;
    if (small_jobs_load(job_path[(data[0] & 0x7f) % JOBS], &job, &err))
        abort(); /* the jobs are fixed: they load */
    gi_jobrun jr;
    gi_error_clear(&err);
    if (data[0] & 0x80) {
        memset(&jr, 0, sizeof jr); /* freed whatever the restore did, as gi_local does */
        /* Plainly written: gi_write_file_atomic's fsync, once an input, stalled a
         * run past the timeout on a busy disk. */
        FILE *f = fopen(local_path, "wb");
        if (!f || (size > 1 && fwrite(data + 1, 1, size - 1, f) != size - 1) || fclose(f) != 0)
            abort();
        char *root = gi_local_checkpoint_batch_root(local_path), *restored_root = NULL;
        int rc = gi_local_checkpoint_restore(&jr, &job, local_path, &restored_root, &err);
        if (rc < 0 && (!err.msg[0] || strchr(err.msg, '\n')))
            abort();
        /* The header alone and the whole restore agree on the root. */
        if (rc > 0 && (!root != !restored_root || (root && strcmp(root, restored_root) != 0)))
            abort();
        gi_jobrun_free(&jr);
        free(root);
        free(restored_root);
        gi_job_free(&job);
        return 0;
    }
    gi_buf ck;
    gi_buf_init(&ck);
    gi_buf_put(&ck, data + 1, size - 1);
    if (gi_jobrun_restore(&jr, &job, &ck, &err) != 0 && (!err.msg[0] || strchr(err.msg, '\n')))
        abort();
    gi_jobrun_free(&jr);
    gi_buf_free(&ck);
    gi_job_free(&job);
    return 0;
}
