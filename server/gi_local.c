/* gi_local: the embedded coordinator behind `gi render`.
 *
 * Batch directories: the children's per-job cache directory (gi_batch_dir.h)
 * lies under a private temporary directory, $TMPDIR/gi-render-XXXXXX
 * (/var/tmp when TMPDIR is unset: batches can be large and /tmp is often
 * in memory), created before the pool starts and removed when the render
 * ends, unless it was stopped from outside with work to resume (below).
 * A render touches its batch root every minute; when the next one starts
 * it removes this user's roots that cannot be resumed and those left
 * untouched for GI_BATCH_DIR_MAX_AGE_S (gi_batch_root.h). Affinity keys are
 * ignored here: one host, one disk.
 *
 * Task time limits (the job's task_timeout, else --task-timeout): a pool
 * child whose task ran longer is killed and replaced, and the run fails as
 * an attempt (stop_overdue). The clock starts when the task is sent to the
 * child, which starts it at once (a child holds one task at a time); a
 * task waiting for a free child is off the clock. The farm follows the
 * same rule: its workers report when their pool starts each task
 * (gi_farm_sched.c, "Time limits").
 *
 * Checkpoints (gi_local_checkpoint.h) are written every few seconds (on a
 * thread of their own: the loop only encodes them) and when the render is
 * stopped, so that `gi render --resume` continues it.
 * Each names the batch root; a render stopped by a signal keeps it (when it
 * holds anything), and so does a killed one, so that the resumed render
 * reads an animation's photon batches as stored instead of tracing them
 * again (a batch whose files are gone or torn is regenerated from its
 * seeds, as anywhere). A render that replaces a checkpoint instead of
 * resuming it removes the batch root it names. */
#include "gi_local.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_batch_dir.h"
#include "gi_batch_root.h"
#include "gi_cores.h"
#include "gi_file_writer.h"
#include "gi_fs.h"
#include "gi_local_checkpoint.h"
#include "gi_log.h"
#include "gi_pool.h"

#define LOCAL_JOB_ID 1

volatile int gi_local_interrupted;

typedef struct local_run {
    gi_job *job;
    gi_jobrun jr;
    gi_pool pool;
    char *batch_root; /* private temporary directory */
    uint64_t crashes, timeouts;
    unsigned respawn_budget;
    int ckpt_ours; /* the checkpoint file holds this run's work (resumed or written) */
    gi_file_writer *ckpt_w; /* a periodic checkpoint being written */
    gi_ckpt_pace ckpt_pace;
} local_run;

static void on_result(void *user, int child, gi_msg_result *r)
{
    local_run *lr = user;
    gi_error e;
    if (gi_jobrun_check_result(&lr->jr, r->task_id, r->attempt, &r->data, &e))
        gi_jobrun_fail(&lr->jr, r->task_id, r->attempt, &e);
    else
        gi_jobrun_complete(&lr->jr, r->task_id, r->attempt, &r->data, &r->stats);
}

static void on_fail(void *user, int child, gi_msg_fail *f)
{
    local_run *lr = user;
    gi_warn("task %llu failed: %s", (unsigned long long)f->task_id, f->error.msg);
    gi_jobrun_fail(&lr->jr, f->task_id, f->attempt, &f->error);
}

static void on_crash(void *user, int child, uint64_t job_id, uint64_t task_id,
                     uint32_t attempt, const char *why)
{
    local_run *lr = user;
    lr->crashes++;
    gi_error e;
    gi_fail(&e, GI_ECRASH, "%s", why);
    gi_jobrun_fail(&lr->jr, task_id, attempt, &e);
}

/* Kills the children whose task ran longer than limit_s (gi_jobrun.h:
 * task time limits) and fails those runs; their replacements are forked
 * here, outside the respawn budget, which bounds crashes: each timeout is
 * an attempt of its task, bounded by max_attempts. */
static int stop_overdue(local_run *lr, double limit_s, double now, gi_error *err)
{
    for (int i = 0; i < lr->pool.count; i++) {
        const gi_pool_child *k = &lr->pool.kids[i];
        if (!k->pid || !k->busy || now - k->started < limit_s)
            continue;
        uint64_t task = k->task_id;
        uint32_t attempt = k->attempt;
        char where[64];
        snprintf(where, sizeof where, "pool child %d (pid %ld)", i, (long)k->pid);
        gi_pool_kill(&lr->pool, i);
        lr->timeouts++;
        gi_error e;
        gi_jobrun_timeout_error(&e, task, limit_s, where);
        gi_warn("%s", e.msg);
        gi_jobrun_fail(&lr->jr, task, attempt, &e);
        if (gi_pool_spawn(&lr->pool, i, err))
            return -1;
    }
    return 0;
}

static const gi_buf *on_asset(void *user, const char *hash)
{
    local_run *lr = user;
    return lr->job->assets ? gi_asset_store_get(lr->job->assets, hash) : NULL;
}

/* Creates the render's private batch root (an absolute path: a checkpoint
 * names it, and --resume may run from another directory), after removing
 * the roots of earlier renders that are of no use (gi_batch_root.h). */
static int batch_root_make(local_run *lr, const char *ckpt, gi_error *err)
{
    const char *tmp = getenv("TMPDIR");
    if (!tmp || !tmp[0])
        tmp = "/var/tmp";
    int swept = gi_batch_root_sweep(tmp, GI_BATCH_DIR_MAX_AGE_S);
    if (swept)
        gi_info("removed %d batch director%s of earlier renders that cannot be resumed from %s",
                swept, swept == 1 ? "y" : "ies", tmp);
    lr->batch_root = gi_batch_root_make(tmp, ckpt, err);
    return lr->batch_root ? 0 : -1;
}

static void batch_root_remove(local_run *lr)
{
    if (!lr->batch_root)
        return;
    gi_error err;
    if (gi_batch_dir_remove(lr->batch_root, &err))
        gi_warn("%s", err.msg);
    free(lr->batch_root);
    lr->batch_root = NULL;
}

/* 1 if dir holds a job's batch directory (not only its owner record,
 * .owner: nothing else there starts with a dot). */
static int dir_has_entries(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    struct dirent *e;
    int any = 0;
    while (!any && (e = readdir(d)) != NULL)
        any = e->d_name[0] != '.';
    closedir(d);
    return any;
}

/* Lets go of the batch root: kept on disk if asked (the callers ask only
 * for one that holds something), removed otherwise. */
static void batch_root_end(local_run *lr, int keep)
{
    if (keep && lr->batch_root) {
        gi_batch_dir_touch(lr->batch_root); /* kept GI_BATCH_DIR_MAX_AGE_S from now */
        free(lr->batch_root);
        lr->batch_root = NULL;
        return;
    }
    batch_root_remove(lr);
}

/* The batch root a render stopped before this one kept beside ckpt, if it
 * is one of ours: removed, since this render starts over. */
static void remove_kept_batch_root(const char *ckpt)
{
    char *root = gi_local_checkpoint_batch_root(ckpt);
    if (root && gi_local_batch_root_ours(root)) {
        gi_error err;
        if (gi_batch_dir_remove(root, &err))
            gi_warn("%s", err.msg);
    }
    free(root);
}

/* A resumed animation writes only the frames from its checkpoint's (`at`)
 * on: says so if outputs of the frames before it are gone (deleted since
 * the stop), since nothing will write them again. Not the frames a finish
 * on restore wrote since: their images may still be being written. */
static void warn_missing_frames(gi_job *job, uint32_t at)
{
    if (!job->in_frame || at == 0)
        return;
    uint32_t now = job->frame, missing = 0;
    char *first = NULL;
    for (uint32_t f = 0; f < at; f++) {
        job->frame = f;
        for (int i = 0; i < job->output_count; i++) {
            char *path = gi_job_output_path(job, job->outputs[i].file);
            if (access(path, F_OK) != 0 && missing++ == 0) {
                first = path;
                path = NULL;
            }
            free(path);
        }
    }
    job->frame = now;
    if (missing)
        gi_warn("%s: %u output%s of the frames before frame %u %s missing (%s%s); they were "
                "written before the stop and are not written again: render without --resume "
                "to make every frame",
                job->name, missing, missing == 1 ? "" : "s", at, missing == 1 ? "is" : "are",
                first, missing > 1 ? ", ..." : "");
    free(first);
}

/* The periodic checkpoint being written (on a thread of its own, so that
 * results are merged meanwhile), if any, completed, waiting for it if
 * wait: 1 when none is left, 0 while it is still being written. */
static int periodic_finish(local_run *lr, int wait)
{
    if (!lr->ckpt_w)
        return 1;
    if (!wait && !gi_file_writer_done(lr->ckpt_w))
        return 0;
    gi_error e;
    double seconds;
    int rc = gi_file_writer_finish(lr->ckpt_w, &seconds, &e);
    gi_ckpt_pace_written(&lr->ckpt_pace, seconds);
    if (rc)
        gi_warn("checkpoint not written: %s", e.msg);
    else
        lr->ckpt_ours = 1;
    lr->ckpt_w = NULL;
    return 1;
}

static int default_workers(void) { return gi_cores_usable(); }

/* The end of a render (its pool stopped, if it had one): a finished job's
 * checkpoint removed; one stopped from outside (interrupted, its pool
 * failing), or failed writing its outputs with its whole result merged,
 * checkpointed so that --resume continues it, its batch root kept for it if
 * that holds anything; one failed on another write left with its last
 * checkpoint and the batch root that names. Frees the run and ckpt. */
static int local_end(local_run *lr, char *ckpt, int checkpoints, double t0,
                     gi_local_summary *summary, int rc, gi_error *err)
{
    gi_job *job = lr->job;
    int keep_batches = 0, saved = 0;
    if (err && lr->jr.failed && lr->jr.error.code == GI_EHOST && lr->batch_root &&
        strstr(err->msg, lr->batch_root)) {
        gi_error e = *err;
        char *tmp = gi_dirname(lr->batch_root);
        gi_fail(err, e.code, "%s; the photon batches are written under $TMPDIR (%s): free space "
                "there or set TMPDIR to a larger disk", e.msg, tmp);
        free(tmp);
    }
    if (!checkpoints) {
        /* none */
    } else if (rc == 0) {
        unlink(ckpt);
    } else if ((!lr->jr.failed || gi_jobrun_finish_retryable(&lr->jr)) && job->method->save) {
        gi_error cerr;
        keep_batches = lr->batch_root && dir_has_entries(lr->batch_root);
        const char *root = keep_batches ? lr->batch_root : NULL;
        saved = gi_local_checkpoint_write(&lr->jr, root, ckpt, &cerr) == 0;
        if (saved) {
            if (err) {
                gi_progress_at at;
                gi_jobrun_progress(&lr->jr, gi_now(), &at);
                char where[64] = "";
                if (at.frames > 1)
                    snprintf(where, sizeof where, ", frame %u of %u", at.frame, at.frames);
                gi_error e = *err;
                gi_fail(err, e.code, "%s; the work done (%.0f%%%s) is kept in %s%s%s: "
                        "`gi render %s --out %s --resume` continues", e.msg, 100.0 * at.fraction,
                        where, ckpt, root ? " and its photon batches in " : "", root ? root : "",
                        job->file, job->out_dir);
            }
        } else {
            keep_batches = 0;
            if (err)
                gi_warn("%s", cerr.msg);
        }
    }
    if (checkpoints && rc != 0 && !saved && lr->jr.failed &&
        (lr->jr.error.code == GI_EIO || lr->jr.error.code == GI_EHOST) && lr->ckpt_ours) {
        /* A write failed (a full disk, a path in the way): the last
         * checkpoint, taken with every output before it on disk, still
         * holds the work up to it, and with it the batches it names. */
        char *named = gi_local_checkpoint_batch_root(ckpt);
        keep_batches = named && lr->batch_root && strcmp(named, lr->batch_root) == 0 &&
                       dir_has_entries(lr->batch_root);
        free(named);
        if (err) {
            gi_error e = *err;
            gi_fail(err, e.code, "%s; the work checkpointed before it is kept in %s: once that is "
                    "fixed, `gi render %s --out %s --resume` continues", e.msg, ckpt, job->file,
                    job->out_dir);
        }
    }
    batch_root_end(lr, keep_batches);
    summary->seconds = gi_now() - t0;
    summary->tasks = lr->jr.task_count;
    summary->retries = lr->jr.retries;
    summary->crashes = lr->crashes;
    summary->timeouts = lr->timeouts;
    summary->stats = lr->jr.stats;
    gi_jobrun_free(&lr->jr);
    free(ckpt);
    return rc;
}

int gi_render_local(gi_job *job, const gi_local_opts *opts, gi_local_summary *summary,
                    gi_error *err)
{
    local_run lr;
    memset(&lr, 0, sizeof lr);
    memset(summary, 0, sizeof *summary);
    lr.job = job;
    double t0 = gi_now();
    char *ckpt = gi_local_checkpoint_path(job);
    int resumed = 0, checkpoints = opts->checkpoint_s >= 0;
    if (opts->resume && checkpoints) {
        char *root = NULL;
        resumed = gi_local_checkpoint_restore(&lr.jr, job, ckpt, &root, err);
        if (resumed > 0) {
            lr.ckpt_ours = 1;
            gi_progress_at at;
            gi_jobrun_progress(&lr.jr, gi_now(), &at);
            char where[64] = "";
            if (at.frames > 1)
                snprintf(where, sizeof where, ", at frame %u of %u", at.frame, at.frames);
            gi_say("%s: resuming from %s (%.0f%% done%s)", job->name, ckpt, 100.0 * at.fraction,
                   where);
            summary->resumed = 1;
            summary->fraction_before = at.fraction;
            summary->stats_before = lr.jr.stats;
            warn_missing_frames(job, lr.jr.restored_frame);
            if (root && gi_local_batch_root_ours(root)) {
                lr.batch_root = root; /* the stopped render's batches, read again */
                root = NULL;
                gi_batch_root_claim(lr.batch_root, ckpt);
                if (dir_has_entries(lr.batch_root))
                    gi_say("%s: reading the photon batches kept in %s", job->name,
                           lr.batch_root);
            }
            free(root);
        } else if (resumed == 0) {
            gi_say("%s: no checkpoint in %s; starting from the beginning", job->name,
                   job->out_dir);
        }
    } else if (checkpoints && access(ckpt, F_OK) == 0) {
        gi_warn("%s holds an earlier run that was stopped; this run starts over and replaces "
                "it (--resume continues it)",
                ckpt);
        remove_kept_batch_root(ckpt);
    }
    if (resumed < 0 || (resumed == 0 && gi_jobrun_start(&lr.jr, job, err))) {
        gi_jobrun_free(&lr.jr);
        free(ckpt);
        return -1;
    }
    if (lr.jr.finished) /* resumed from a checkpoint taken at the very end */
        return local_end(&lr, ckpt, checkpoints, t0, summary, 0, err);
    /* Not capped by the tasks planned so far: a method's later phases (a detp
     * job's image after one photon batch) plan many more. */
    int workers = opts->workers > 0 ? opts->workers : default_workers();
    summary->workers = workers;
    if (!lr.batch_root && batch_root_make(&lr, checkpoints ? ckpt : NULL, err)) {
        gi_jobrun_free(&lr.jr);
        free(ckpt);
        return -1;
    }
    if (gi_pool_start(&lr.pool, workers, lr.batch_root, err)) {
        /* The checkpoint may name it still. */
        batch_root_end(&lr, resumed > 0 && dir_has_entries(lr.batch_root));
        gi_jobrun_free(&lr.jr);
        free(ckpt);
        return -1;
    }
    /* Crashes are retried on fresh children, but a job whose tasks kill every
     * child is failing, not unlucky: bound the respawns. */
    lr.respawn_budget = 4u * (unsigned)workers + 16u;

    gi_progress prog;
    gi_progress_init(&prog, opts->progress, stderr, job->name, job->method->unit);
    gi_pool_events ev = {&lr, on_result, on_fail, on_crash, on_asset, NULL};
    double limit_s = gi_jobrun_task_timeout(&lr.jr, opts->task_timeout_s);
    int rc = 0;
    double last_ckpt = gi_now(), last_touch = last_ckpt;
    uint64_t ckpt_merged = lr.jr.merge_next;
    while (!gi_jobrun_done(&lr.jr)) {
        if (gi_local_interrupted) {
            rc = gi_fail(err, GI_ECANCEL, "%s: interrupted", job->file);
            break;
        }
        for (int i = 0; i < lr.pool.count; i++) {
            if (gi_pool_alive(&lr.pool, i))
                continue;
            if (lr.respawn_budget == 0) {
                rc = gi_fail(err, GI_ECRASH, "%s: pool children keep dying (%llu crashes); giving up",
                             job->file, (unsigned long long)lr.crashes);
                break;
            }
            lr.respawn_budget--;
            if (gi_pool_spawn(&lr.pool, i, err)) {
                rc = -1;
                break;
            }
        }
        if (rc)
            break;
        int idle;
        while ((idle = gi_pool_idle_child(&lr.pool)) >= 0) {
            const gi_task *t = gi_jobrun_lease(&lr.jr);
            if (!t)
                break;
            gi_error serr;
            if (gi_pool_assign(&lr.pool, idle, LOCAL_JOB_ID, job->file, job->text,
                               &job->manifest, t, &serr))
                gi_debug("sending a task to child %d failed: %s", idle, serr.msg);
        }
        gi_pool_poll(&lr.pool, 200, &ev);
        double now = gi_now();
        if (limit_s > 0 && stop_overdue(&lr, limit_s, now, err)) {
            rc = -1;
            break;
        }
        int writer_idle = periodic_finish(&lr, 0); /* first: it adds the write's time */
        double every = gi_ckpt_pace_interval(&lr.ckpt_pace, opts->checkpoint_s);
        if (writer_idle && checkpoints && opts->checkpoint_s > 0 &&
            now - last_ckpt >= every && lr.jr.merge_next != ckpt_merged &&
            !gi_jobrun_done(&lr.jr) && job->method->save) {
            gi_buf b;
            gi_buf_init(&b);
            gi_error cerr;
            if (gi_local_checkpoint_encode(&lr.jr, lr.batch_root, &b, &cerr))
                gi_warn("checkpoint %s: %s", ckpt, cerr.msg);
            else
                lr.ckpt_w = gi_file_writer_start(ckpt, &b);
            gi_buf_free(&b);
            last_ckpt = now;
            gi_ckpt_pace_begun(&lr.ckpt_pace, gi_now() - now);
            ckpt_merged = lr.jr.merge_next;
        }
        if (now - last_touch >= 60.0) { /* alive: not for the sweep */
            gi_batch_dir_touch(lr.batch_root);
            last_touch = now;
        }
        gi_progress_at at;
        gi_jobrun_progress(&lr.jr, now, &at);
        gi_progress_update(&prog, &at, 0);
    }
    periodic_finish(&lr, 1); /* in place (or failed) before the end decides */
    if (rc == 0 && lr.jr.failed) {
        if (err)
            *err = lr.jr.error;
        rc = -1;
    }
    if (rc == 0) {
        gi_progress_at at;
        gi_jobrun_progress(&lr.jr, gi_now(), &at);
        gi_progress_update(&prog, &at, 1);
    }
    gi_progress_end(&prog);
    gi_pool_stop(&lr.pool); /* children gone: nothing writes below batch_root now */
    gi_debug("%s: peak bytes of results held for in-order merging: %llu", job->name,
             (unsigned long long)lr.jr.held_results_peak);
    return local_end(&lr, ckpt, checkpoints, t0, summary, rc, err);
}
