/* gi_jobrun: task bookkeeping and in-order merging for one job. */
#include "gi_jobrun.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_crc32c.h"
#include "gi_log.h"
#include "gi_progress.h"
#include "gi_thread_call.h"

#define DEFAULT_MAX_ATTEMPTS 4
/* Losses are not the task's fault as a rule (spot hosts reclaimed, laptops
 * closed, kill -9): a chaos run of 4 allowed attempts failed one job in
 * ~220 only because a task had sat on 4 killed hosts. If each loss is
 * independent bad luck, 8 makes that some 220 times rarer (p^8 = (p^4)^2),
 * while a task that really takes its host down costs at most 8 host
 * restarts before its job fails saying so. */
#define DEFAULT_MAX_LOSSES 8
/* Bytes of host names a task keeps for its losses' message; past it, ", ...". */
#define LOST_ON_MAX 240

/* A warning the finish logged, passed on to the caller's log hook. */
typedef struct finish_line {
    gi_log_level level;
    char *msg;
} finish_line;

struct gi_jobrun_finisher {
    gi_thread_call *call;
    gi_job *job;
    gi_task_queue q; /* its follow-up tasks */
    const char *gate;
    int rc;
    gi_error err;
    double seconds;
    finish_line *lines;
    size_t line_count;
};

static void pending_push(gi_jobrun *jr, uint64_t id, int front)
{
    if (jr->pending_head > 0 && jr->pending_head == jr->pending_count) {
        jr->pending_head = jr->pending_count = 0;
    }
    if (front && jr->pending_head > 0) {
        jr->pending[--jr->pending_head] = id;
        return;
    }
    if (jr->pending_count == jr->pending_cap) {
        jr->pending_cap = jr->pending_cap ? 2 * jr->pending_cap : 256;
        jr->pending = gi_xrealloc(jr->pending, jr->pending_cap * sizeof *jr->pending);
    }
    if (front) {
        memmove(jr->pending + jr->pending_head + 1, jr->pending + jr->pending_head,
                (jr->pending_count - jr->pending_head) * sizeof *jr->pending);
        jr->pending[jr->pending_head] = id;
        jr->pending_count++;
    } else {
        jr->pending[jr->pending_count++] = id;
    }
}

/* Tells the progress clock where the method stands, before the tasks it
 * just planned count in cost_total. */
static void note_progress(gi_jobrun *jr)
{
    gi_job_progress at = {.frames = 1};
    if (jr->job->method->progress)
        jr->job->method->progress(jr->job, &at);
    gi_progress_clock_note(&jr->clock, &at, jr->cost_total, jr->cost_done, gi_now());
}

void gi_jobrun_progress(const gi_jobrun *jr, double now, gi_progress_at *out)
{
    gi_progress_clock_read(&jr->clock, jr->cost_total, jr->cost_done, now, out);
    if (jr->finished) {
        out->fraction = 1;
        out->eta_s = 0;
    }
    out->samples = (double)jr->stats.samples;
    out->rays = (double)jr->stats.rays;
}

/* Takes the queue's tasks (ids are consecutive from task_count). */
static int absorb(gi_jobrun *jr, gi_task_queue *q, gi_error *err)
{
    note_progress(jr);
    /* Methods refuse parameters that plan more (gi_job_check_tasks); this
     * catches what only the scene decides. */
    if (jr->task_count - jr->merge_next + q->count > GI_JOB_MAX_TASKS)
        return gi_fail(err, GI_EINVAL, "%s: the job would hold %llu tasks at once; at most %u",
                       jr->job->file,
                       (unsigned long long)(jr->task_count - jr->merge_next + q->count),
                       GI_JOB_MAX_TASKS);
    for (size_t i = 0; i < q->count; i++) {
        gi_task *t = &q->tasks[i];
        if (t->id != jr->task_count)
            return gi_fail(err, GI_EINTERNAL, "task id %llu out of sequence (expected %llu)",
                           (unsigned long long)t->id, (unsigned long long)jr->task_count);
        if (jr->task_count - jr->task_base == jr->task_cap) {
            jr->task_cap = jr->task_cap ? 2 * jr->task_cap : 256;
            jr->tasks = gi_xrealloc(jr->tasks, jr->task_cap * sizeof *jr->tasks);
        }
        gi_jobrun_task *jt = &jr->tasks[jr->task_count++ - jr->task_base];
        memset(jt, 0, sizeof *jt);
        jt->task = *t;
        gi_buf_init(&t->payload); /* moved */
        jt->state = GI_TASK_PENDING;
        gi_buf_init(&jt->result);
        jr->cost_total += t->cost;
        pending_push(jr, t->id, 0);
    }
    q->count = 0;
    return 0;
}

static int job_fail(gi_jobrun *jr, const gi_error *e)
{
    if (!jr->failed) {
        jr->failed = 1;
        jr->error = *e;
    }
    return -1;
}

/* Clears the run for start or restore. */
static void run_init(gi_jobrun *jr, gi_job *job, const gi_jobrun_opts *opts)
{
    memset(jr, 0, sizeof *jr);
    jr->job = job;
    jr->opts.finish_wake_fd = -1;
    if (opts)
        jr->opts = *opts;
}

int gi_jobrun_start(gi_jobrun *jr, gi_job *job, gi_error *err)
{
    return gi_jobrun_start_opts(jr, job, NULL, err);
}

int gi_jobrun_start_opts(gi_jobrun *jr, gi_job *job, const gi_jobrun_opts *opts,
                         gi_error *err)
{
    run_init(jr, job, opts);
    jr->max_attempts = DEFAULT_MAX_ATTEMPTS;
    jr->max_losses = DEFAULT_MAX_LOSSES;
    gi_task_queue q;
    gi_task_queue_init(&q, 0);
    int rc = job->method->plan(job, &q, err);
    if (rc == 0)
        rc = absorb(jr, &q, err);
    gi_task_queue_free(&q);
    if (rc == 0 && jr->task_count == 0)
        rc = gi_fail(err, GI_EINTERNAL, "%s: the plan has no tasks", job->file);
    return rc;
}

static void finisher_free(gi_jobrun_finisher *fz);

void gi_jobrun_free(gi_jobrun *jr)
{
    if (jr->finisher) {
        gi_thread_call_join(jr->finisher->call);
        finisher_free(jr->finisher);
    }
    for (uint64_t i = 0; i < jr->task_count - jr->task_base; i++) {
        gi_task_free(&jr->tasks[i].task);
        gi_buf_free(&jr->tasks[i].result);
        free(jr->tasks[i].lost_on);
    }
    free(jr->tasks);
    free(jr->pending);
    memset(jr, 0, sizeof *jr);
}

/* A pending entry whose task is still waiting for a lease (entries of tasks
 * leased again, or merged since, are stale). */
static int is_pending(const gi_jobrun *jr, uint64_t id)
{
    const gi_jobrun_task *jt = gi_jobrun_task_at(jr, id);
    return jt && jt->state == GI_TASK_PENDING;
}

const gi_task *gi_jobrun_lease(gi_jobrun *jr) { return gi_jobrun_lease_if(jr, NULL, NULL, NULL); }

const gi_task *gi_jobrun_lease_if(gi_jobrun *jr, int (*accept)(void *ctx, const gi_task *t),
                                  void *ctx, uint64_t *passed)
{
    if (passed)
        *passed = 0;
    if (gi_jobrun_done(jr))
        return NULL;
    /* Entries of tasks no longer pending (leased again after a requeue put
     * a second entry in front) are dropped as they are met. */
    while (jr->pending_head < jr->pending_count && !is_pending(jr, jr->pending[jr->pending_head]))
        jr->pending_head++;
    for (uint64_t i = jr->pending_head; i < jr->pending_count; i++) {
        gi_jobrun_task *jt = gi_jobrun_task_at(jr, jr->pending[i]);
        if (!jt || jt->state != GI_TASK_PENDING)
            continue;
        if (accept && !accept(ctx, &jt->task)) {
            if (passed)
                ++*passed;
            continue;
        }
        /* Close the gap, keeping the order of the entries passed over. */
        memmove(jr->pending + jr->pending_head + 1, jr->pending + jr->pending_head,
                (i - jr->pending_head) * sizeof *jr->pending);
        jr->pending_head++;
        jt->state = GI_TASK_LEASED;
        jr->leased++;
        if (!jr->clock.working)
            gi_progress_clock_working(&jr->clock, jr->cost_done, gi_now());
        return &jt->task;
    }
    return NULL;
}

/* Drops the merged tasks from the front of the array once they are at
 * least half of it (and 256), so moving the rest costs O(1) a task. */
static void drop_merged(gi_jobrun *jr)
{
    uint64_t merged = jr->merge_next - jr->task_base, held = jr->task_count - jr->task_base;
    if (merged < 256 || 2 * merged < held)
        return;
    memmove(jr->tasks, jr->tasks + merged, (held - merged) * sizeof *jr->tasks);
    jr->task_base = jr->merge_next;
}

static void finisher_start(gi_jobrun *jr);

/* A finish has returned rc, with its follow-up tasks in q: -1 if the run
 * failed, 1 if it is finished, 0 if follow-up tasks were planned. */
static int finish_end(gi_jobrun *jr, gi_task_queue *q, int rc, gi_error *err, double seconds)
{
    jr->finish_seconds += seconds;
    if (rc == 0)
        rc = absorb(jr, q, err);
    if (rc)
        return job_fail(jr, err);
    if (jr->merge_next < jr->task_count)
        return 0;
    jr->finished = 1;
    return 1;
}

/* What a task holds to merge: after its merge, or, while it is leased,
 * what a check decoded for a run that ended otherwise (or that a second
 * result for the same run replaces). */
static void drop_decoded(gi_jobrun_task *jt)
{
    gi_buf_free(&jt->result);
    jt->decoded = 0;
}

/* Merges every result whose turn has come; calls finish when all is merged
 * (or starts it on its thread). */
static int advance(gi_jobrun *jr)
{
    gi_job *job = jr->job;
    gi_error err;
    gi_error_clear(&err);
    for (;;) {
        while (jr->merge_next < jr->task_count &&
               gi_jobrun_task_at(jr, jr->merge_next)->state == GI_TASK_DONE) {
            gi_jobrun_task *jt = gi_jobrun_task_at(jr, jr->merge_next);
            gi_task_queue q;
            gi_task_queue_init(&q, jr->task_count);
            double t0 = gi_now();
            const gi_method *m = job->method;
            int rc = jt->decoded ? m->merge_decoded(job, &jt->task, &jt->result, &q, &err)
                                 : m->merge(job, &jt->task, &jt->result, &q, &err);
            jr->merge_seconds += gi_now() - t0;
            jr->merged_bytes += jt->result_len;
            if (rc == 0)
                rc = absorb(jr, &q, &err);
            gi_task_queue_free(&q);
            jt = gi_jobrun_task_at(jr, jr->merge_next); /* absorb may have moved the array */
            if (rc)
                return job_fail(jr, &err);
            jr->held--;
            jr->held_results_bytes -= jt->result.len;
            drop_decoded(jt);
            gi_task_free(&jt->task);
            free(jt->lost_on);
            jt->lost_on = NULL;
            jt->state = GI_TASK_MERGED;
            jr->merge_next++;
        }
        drop_merged(jr);
        if (jr->merge_next < jr->task_count)
            return 0;
        if (jr->opts.finish_threaded) {
            finisher_start(jr);
            return 0;
        }
        gi_task_queue q;
        gi_task_queue_init(&q, jr->task_count);
        double t0 = gi_now();
        int rc = job->method->finish(job, &q, &err);
        rc = finish_end(jr, &q, rc, &err, gi_now() - t0);
        gi_task_queue_free(&q);
        if (rc)
            return rc < 0 ? -1 : 0;
    }
}

/* ---- finishing on a thread (gi_jobrun_opts.finish_threaded) ------------ */

static void finisher_free(gi_jobrun_finisher *fz)
{
    for (size_t i = 0; i < fz->line_count; i++)
        free(fz->lines[i].msg);
    free(fz->lines);
    gi_task_queue_free(&fz->q);
    free(fz);
}

/* gi_log_hook on the finish's thread: kept for the caller's thread, whose
 * hook (a farm job's log) is not this thread's to call. At most 64 lines. */
static void finisher_keep_line(void *ctx, gi_log_level level, const char *msg)
{
    gi_jobrun_finisher *fz = ctx;
    if (fz->line_count == 64)
        return;
    fz->lines = gi_xrealloc(fz->lines, (fz->line_count + 1) * sizeof *fz->lines);
    fz->lines[fz->line_count++] = (finish_line){level, gi_xstrdup(msg)};
}

/* The test hook's wait: whichever finish removes the file goes on (one file,
 * one finish). Ten minutes at most, so that a test that forgets the file
 * does not leave gi-farmd unable to stop. */
static void finisher_gate(const char *path)
{
    for (int i = 0; path && i < 60000; i++) {
        if (unlink(path) == 0)
            return;
        usleep(10000);
    }
}

static void finisher_main(void *arg)
{
    gi_jobrun_finisher *fz = arg;
    gi_log_hook_set(finisher_keep_line, fz);
    finisher_gate(fz->gate);
    double t0 = gi_now();
    fz->rc = fz->job->method->finish(fz->job, &fz->q, &fz->err);
    fz->seconds = gi_now() - t0;
    gi_log_hook_set(NULL, NULL);
}

static void finisher_start(gi_jobrun *jr)
{
    gi_jobrun_finisher *fz = gi_xcalloc(1, sizeof *fz);
    fz->job = jr->job;
    fz->gate = jr->opts.finish_gate;
    gi_task_queue_init(&fz->q, jr->task_count);
    gi_error_clear(&fz->err);
    jr->finisher = fz;
    fz->call = gi_thread_call_start(finisher_main, fz, jr->opts.finish_wake_fd);
}

int gi_jobrun_finish_poll(gi_jobrun *jr, int wait)
{
    gi_jobrun_finisher *fz = jr->finisher;
    if (!fz)
        return 0;
    if (!wait && !gi_thread_call_done(fz->call))
        return 1;
    gi_thread_call_join(fz->call);
    jr->finisher = NULL;
    gi_log_hook hook;
    void *ctx;
    gi_log_hook_get(&hook, &ctx);
    for (size_t i = 0; hook && i < fz->line_count; i++)
        hook(ctx, fz->lines[i].level, fz->lines[i].msg);
    /* Follow-up tasks are pending now: nothing to merge before they run. */
    finish_end(jr, &fz->q, fz->rc, &fz->err, fz->seconds);
    finisher_free(fz);
    return 0;
}

int gi_jobrun_finish_retryable(const gi_jobrun *jr)
{
    const gi_method *m = jr->job->method;
    return jr->failed && (jr->error.code == GI_EIO || jr->error.code == GI_EHOST) &&
           jr->merge_next == jr->task_count && m->save && m->can_finish_again &&
           m->can_finish_again(jr->job);
}

int gi_jobrun_finish_again(gi_jobrun *jr)
{
    if (!gi_jobrun_finish_retryable(jr))
        return -1;
    jr->failed = 0;
    gi_error_clear(&jr->error);
    return advance(jr);
}

int gi_jobrun_check_result(gi_jobrun *jr, uint64_t task_id, uint32_t attempt,
                           const gi_buf *result, gi_error *err)
{
    gi_jobrun_task *jt = gi_jobrun_task_at(jr, task_id);
    const gi_method *m = jr->job->method;
    if (!jt || jt->state != GI_TASK_LEASED || jt->task.attempt != attempt || !m->check_result)
        return 0;
    drop_decoded(jt);
    if (m->check_result(jr->job, &jt->task, result, m->merge_decoded ? &jt->result : NULL,
                        err) == 0) {
        jt->decoded = jt->result.len > 0;
        return 0;
    }
    drop_decoded(jt); /* whatever a refusing check left */
    return gi_error_prefix(err, "task %llu's result", (unsigned long long)task_id);
}

int gi_jobrun_complete(gi_jobrun *jr, uint64_t task_id, uint32_t attempt, gi_buf *result,
                       const gi_task_stats *stats)
{
    if (gi_jobrun_done(jr))
        return jr->failed ? -1 : 0;
    gi_jobrun_task *jt = gi_jobrun_task_at(jr, task_id);
    if (!jt || jt->state != GI_TASK_LEASED || jt->task.attempt != attempt) {
        gi_debug("ignoring a stale result for task %llu (attempt %u)",
                 (unsigned long long)task_id, attempt);
        return 0;
    }
    jt->result_len = result->len;
    if (jt->decoded)
        gi_buf_free(result); /* its check kept what merges */
    else
        gi_buf_move(&jt->result, result);
    jt->state = GI_TASK_DONE;
    jr->leased--;
    jr->held++;
    jr->cost_done += jt->task.cost;
    jr->stats.rays += stats->rays;
    jr->stats.samples += stats->samples;
    jr->stats.seconds += stats->seconds;
    jr->held_results_bytes += jt->result.len;
    if (jr->held_results_bytes > jr->held_results_peak)
        jr->held_results_peak = jr->held_results_bytes;
    return advance(jr);
}

/* Ends run `attempt` of a leased task that failed or was lost: the task,
 * pending again under the next attempt number (so that anything the ended
 * run still sends is stale), or NULL if that run is not the one leased. */
static gi_jobrun_task *end_run(gi_jobrun *jr, uint64_t task_id, uint32_t attempt)
{
    gi_jobrun_task *jt = gi_jobrun_task_at(jr, task_id);
    if (!jt || jt->state != GI_TASK_LEASED || jt->task.attempt != attempt)
        return NULL;
    drop_decoded(jt);
    jr->leased--;
    jt->task.attempt++;
    jt->state = GI_TASK_PENDING;
    return jt;
}

int gi_jobrun_fail(gi_jobrun *jr, uint64_t task_id, uint32_t attempt, const gi_error *why)
{
    if (gi_jobrun_done(jr))
        return jr->failed ? -1 : 0;
    gi_jobrun_task *jt = end_run(jr, task_id, attempt);
    if (!jt)
        return 0;
    jt->failures++;
    /* Bad input fails the same way every time, and so does a full disk
     * here (the farm gives such a task to another host, gi_farm_sched.c). */
    if (why->code == GI_EINVAL || why->code == GI_EHOST || jt->failures >= jr->max_attempts) {
        gi_error e;
        if (why->code == GI_EINVAL || why->code == GI_EHOST)
            gi_fail(&e, why->code, "%s", why->msg);
        else
            gi_fail(&e, why->code, "task %llu failed %u times; last error: %s",
                    (unsigned long long)task_id, jt->failures, why->msg);
        return job_fail(jr, &e);
    }
    gi_info("retrying task %llu (attempt %u): %s", (unsigned long long)task_id,
            jt->task.attempt, why->msg);
    jr->retries++;
    pending_push(jr, task_id, 1);
    return 0;
}

double gi_jobrun_task_timeout(const gi_jobrun *jr, double default_s)
{
    return jr->job && jr->job->task_timeout > 0 ? jr->job->task_timeout : default_s;
}

void gi_jobrun_timeout_error(gi_error *e, uint64_t task_id, double limit_s, const char *where)
{
    /* GI_ECRASH: retried like a crashed run, never taken for bad input. */
    gi_fail(e, GI_ECRASH, "task %llu ran longer than its task_timeout of %g s on %s: stopped",
            (unsigned long long)task_id, limit_s, where);
}

/* Adds host to the task's list of hosts it was lost with, once. */
static void note_lost_on(gi_jobrun_task *jt, const char *host)
{
    if (!host || !*host)
        return;
    size_t have = jt->lost_on ? strlen(jt->lost_on) : 0, n = strlen(host);
    for (const char *p = jt->lost_on; p && *p;) {
        const char *end = strstr(p, ", ");
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len == n && memcmp(p, host, n) == 0)
            return;
        p = end ? end + 2 : p + len;
    }
    if (have >= 3 && strcmp(jt->lost_on + have - 3, "...") == 0)
        return; /* full */
    const char *add = have + 2 + n <= LOST_ON_MAX ? host : "...";
    jt->lost_on = gi_xrealloc(jt->lost_on, have + 2 + strlen(add) + 1);
    snprintf(jt->lost_on + have, 2 + strlen(add) + 1, "%s%s", have ? ", " : "", add);
}

int gi_jobrun_lost(gi_jobrun *jr, uint64_t task_id, uint32_t attempt, const char *host,
                   const gi_error *why)
{
    if (gi_jobrun_done(jr))
        return jr->failed ? -1 : 0;
    gi_jobrun_task *jt = end_run(jr, task_id, attempt);
    if (!jt)
        return 0;
    jt->losses++;
    note_lost_on(jt, host);
    if (jt->losses >= jr->max_losses) {
        gi_error e;
        gi_fail(&e, GI_ECRASH, "task %llu was lost with its host %u times (hosts %s): it may be "
                "taking its host down; last: %s", (unsigned long long)task_id, jt->losses,
                jt->lost_on ? jt->lost_on : "unnamed", why->msg);
        return job_fail(jr, &e);
    }
    gi_info("requeueing task %llu (attempt %u), lost with its host (loss %u of %u): %s",
            (unsigned long long)task_id, jt->task.attempt, jt->losses, jr->max_losses, why->msg);
    jr->losses++;
    pending_push(jr, task_id, 1);
    return 0;
}

void gi_jobrun_requeue(gi_jobrun *jr, uint64_t task_id)
{
    gi_jobrun_task *jt = gi_jobrun_task_at(jr, task_id);
    if (!jt || jt->state != GI_TASK_LEASED)
        return;
    drop_decoded(jt);
    jt->state = GI_TASK_PENDING;
    jr->leased--;
    pending_push(jr, task_id, 1);
}

#define CHECKPOINT_MAGIC 0x4B434947u /* "GICK" */
/* 2: tasks carry their affinity; 3: the current frame's start (its
 * progress survives a restart); 4: a CRC-32C of everything before it at the
 * end (a damaged checkpoint used to resume into wrong outputs); 5: the
 * job's identity after the method's name (a farm that lost its journal gave
 * a new job the id, and so the checkpoint, of an old one); 6: the job's
 * losses after its retries, and each task's failures, losses and the hosts
 * of those (the attempt numbers its runs, which a loss advances too; before
 * it, the attempt was the failures). Older versions are still read. */
#define CHECKPOINT_VERSION 6u

void gi_jobrun_identity(const gi_job *job, char out[GI_HASH_HEX])
{
    gi_buf b;
    gi_buf_init(&b);
    gi_buf_put_str(&b, job->text);
    for (size_t i = 0; i < job->manifest.count; i++) {
        gi_buf_put_str(&b, job->manifest.entries[i].name);
        gi_buf_put_str(&b, job->manifest.entries[i].hash);
    }
    gi_hash_hex(b.data, b.len, out);
    gi_buf_free(&b);
}

void gi_ckpt_pace_begun(gi_ckpt_pace *p, double seconds)
{
    p->prev_s = p->last_s;
    p->last_s = seconds;
    p->count++;
}

void gi_ckpt_pace_written(gi_ckpt_pace *p, double seconds)
{
    p->last_s += seconds;
}

double gi_ckpt_pace_interval(const gi_ckpt_pace *p, double every_s)
{
    double cost = p->count >= 2 && p->prev_s < p->last_s ? p->prev_s : p->last_s;
    double spaced = 20.0 * cost;
    return cost >= 0.25 && spaced > every_s ? spaced : every_s;
}

int gi_jobrun_checkpoint(const gi_jobrun *jr, gi_buf *out, gi_error *err)
{
    const gi_job *job = jr->job;
    if (!job->method->save)
        return gi_fail(err, GI_EINTERNAL, "method %s cannot checkpoint", job->method->name);
    if (jr->finisher) /* its state is the finish's thread's */
        return gi_fail(err, GI_EINTERNAL, "%s: no checkpoint while it finishes", job->file);
    size_t start = out->len;
    gi_buf_put_u32(out, CHECKPOINT_MAGIC);
    gi_buf_put_u32(out, CHECKPOINT_VERSION);
    gi_buf_put_str(out, job->method->name);
    char id[GI_HASH_HEX];
    gi_jobrun_identity(job, id);
    gi_buf_put_str(out, id);
    gi_buf_put_u64(out, jr->task_count);
    gi_buf_put_u64(out, jr->merge_next);
    gi_buf_put_u64(out, jr->retries);
    gi_buf_put_u64(out, jr->losses);
    gi_buf_put_u64(out, jr->stats.rays);
    gi_buf_put_u64(out, jr->stats.samples);
    gi_buf_put_f64(out, jr->stats.seconds);
    gi_buf_put_f64(out, jr->cost_total);
    gi_buf_put_f64(out, jr->clock.frame_base);
    for (uint64_t i = jr->merge_next; i < jr->task_count; i++) {
        const gi_jobrun_task *jt = gi_jobrun_task_at(jr, i);
        const gi_task *t = &jt->task;
        gi_buf_put_u32(out, t->kind);
        gi_buf_put_u32(out, t->attempt);
        gi_buf_put_u32(out, jt->failures);
        gi_buf_put_u32(out, jt->losses);
        gi_buf_put_f64(out, t->cost);
        gi_buf_put_u64(out, t->affinity);
        gi_buf_put_blob(out, t->payload.data, t->payload.len);
        gi_buf_put_str(out, jt->lost_on ? jt->lost_on : "");
    }
    /* The method's state goes straight into out as a blob, its length
     * patched after: a big image's sums are copied once, not twice. */
    size_t at = out->len;
    gi_buf_put_u64(out, 0);
    int rc = job->method->save(job, out, err);
    if (rc == 0) {
        gi_le_put_u64(out->data + at, (uint64_t)(out->len - at - 8));
        gi_buf_put_u32(out, gi_crc32c(0, out->data + start, out->len - start));
    }
    return rc;
}

int gi_jobrun_restore(gi_jobrun *jr, gi_job *job, const gi_buf *in, gi_error *err)
{
    return gi_jobrun_restore_opts(jr, job, in, NULL, err);
}

int gi_jobrun_restore_opts(gi_jobrun *jr, gi_job *job, const gi_buf *in,
                           const gi_jobrun_opts *opts, gi_error *err)
{
    run_init(jr, job, opts);
    jr->max_attempts = DEFAULT_MAX_ATTEMPTS;
    jr->max_losses = DEFAULT_MAX_LOSSES;
    if (!job->method->load)
        return gi_fail(err, GI_EINTERNAL, "method %s cannot restore", job->method->name);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "checkpoint");
    uint32_t magic = gi_get_u32(&r), version = gi_get_u32(&r);
    if (!r.failed && magic == CHECKPOINT_MAGIC && version >= 4) {
        /* Everything but the trailer, and only if its bytes are as written. */
        if (in->len < 12 ||
            gi_le_get_u32(in->data + in->len - 4) != gi_crc32c(0, in->data, in->len - 4))
            return gi_fail(err, GI_EPROTO, "%s: checkpoint damaged (its checksum does not match)",
                           job->file);
        gi_reader_init(&r, in->data, in->len - 4, "checkpoint");
        gi_get_u32(&r);
        gi_get_u32(&r);
    }
    char *method = gi_get_str(&r, 64);
    if (r.failed || magic != CHECKPOINT_MAGIC || version < 1 || version > CHECKPOINT_VERSION ||
        !method ||
        strcmp(method, job->method->name) != 0) {
        free(method);
        return gi_fail(err, GI_EPROTO, "%s: not a checkpoint of a %s job (version %u)",
                       job->file, job->method->name, CHECKPOINT_VERSION);
    }
    free(method);
    if (version >= 5) {
        char want[GI_HASH_HEX];
        gi_jobrun_identity(job, want);
        char *id = gi_get_str(&r, GI_HASH_HEX);
        int other = !id || strcmp(id, want) != 0;
        free(id);
        if (other)
            return gi_fail(err, GI_EPROTO, "%s: a checkpoint of another job (its text or the "
                           "files its scene reads differ)", job->file);
    }
    uint64_t count = gi_get_u64(&r), merged = gi_get_u64(&r);
    jr->retries = gi_get_u64(&r);
    jr->losses = version >= 6 ? gi_get_u64(&r) : 0;
    jr->stats.rays = gi_get_u64(&r);
    jr->stats.samples = gi_get_u64(&r);
    jr->stats.seconds = gi_get_f64(&r);
    jr->cost_total = gi_get_f64(&r);
    jr->clock.restored_base = version >= 3 ? gi_get_f64(&r) : -1;
    if (!(jr->clock.restored_base <= jr->cost_total)) /* NaN too */
        jr->clock.restored_base = -1;
    if (r.failed || merged > count || count - merged > r.left / 24)
        return gi_fail(err, GI_EPROTO, "%s: checkpoint: bad task counts", job->file);
    /* Only the tasks not merged are held; the count check above keeps them
     * within what the checkpoint's bytes can describe. */
    jr->task_base = merged;
    jr->task_cap = count - merged ? count - merged : 1;
    jr->tasks = gi_xcalloc(jr->task_cap, sizeof *jr->tasks);
    jr->task_count = count;
    jr->merge_next = merged;
    double unmerged_cost = 0;
    for (uint64_t i = merged; i < count; i++) {
        gi_jobrun_task *jt = gi_jobrun_task_at(jr, i);
        jt->task.id = i;
        gi_buf_init(&jt->task.payload);
        gi_buf_init(&jt->result);
        jt->task.kind = gi_get_u32(&r);
        jt->task.attempt = gi_get_u32(&r);
        jt->failures = version >= 6 ? gi_get_u32(&r) : jt->task.attempt;
        jt->losses = version >= 6 ? gi_get_u32(&r) : 0;
        jt->task.cost = gi_get_f64(&r);
        if (version >= 2)
            jt->task.affinity = gi_get_u64(&r);
        size_t len;
        const uint8_t *p = gi_get_blob(&r, (size_t)1 << 30, &len);
        char *lost_on = version >= 6 ? gi_get_str(&r, LOST_ON_MAX + 8) : NULL;
        if (r.failed)
            return gi_fail(err, GI_EPROTO, "%s: checkpoint: truncated task %llu", job->file,
                           (unsigned long long)i);
        if (lost_on && *lost_on)
            jt->lost_on = lost_on;
        else
            free(lost_on);
        gi_buf_put(&jt->task.payload, p, len);
        jt->state = GI_TASK_PENDING;
        unmerged_cost += jt->task.cost;
        pending_push(jr, i, 0);
    }
    jr->cost_done = jr->cost_total - unmerged_cost;
    size_t len;
    const uint8_t *p = gi_get_blob(&r, (size_t)1 << 40, &len);
    if (gi_reader_finish(&r, err))
        return gi_error_prefix(err, "%s", job->file);
    gi_reader sr;
    gi_reader_init(&sr, p, len, "checkpoint method state");
    if (job->method->load(job, &sr, err))
        return -1;
    if (gi_reader_finish(&sr, err))
        return gi_error_prefix(err, "%s", job->file);
    note_progress(jr);
    jr->restored_frame = job->frame;
    /* Everything was merged when the checkpoint was taken: only finish is left. */
    if (jr->merge_next == jr->task_count && advance(jr)) {
        if (err)
            *err = jr->error;
        return -1;
    }
    return 0;
}
