/* gi_farm_jobs: the coordinator's job records and their life:
 *
 *   submit -> CHECKING (forked scene check) -> RUNNING (gi_jobrun) -> DONE
 *                  \-> FAILED                     \-> FAILED / CANCELLED
 *
 * Every transition that must survive a crash is journaled before it is
 * acted on; running jobs are checkpointed periodically (gi_jobrun_checkpoint
 * into <state>/jobs/<id>/checkpoint, replaced atomically by a writer thread,
 * and journaled once it is in place). A restarted
 * coordinator replays the journal, checks every unfinished job's scene
 * again, and restores it from its checkpoint, so tasks merged before the
 * checkpoint are not run again.
 *
 * A job's method->finish (writing its outputs: a second for a 4 Mpx EXR)
 * runs on a thread of its own (gi_jobrun_opts); the job shows
 * as "finishing" meanwhile, and the tick takes the finish's end in: DONE
 * only once it returned with its outputs in place, and then END is
 * journaled. No checkpoint is taken while it runs; a stopping coordinator
 * waits for it (its thread works on the run's memory, and the work is then
 * kept: done, or checkpointed). A cancel does not wait on the loop: it
 * journals the job's END (cancelled) at once, so that a restart finds it
 * cancelled, and the tick ends the job cancelled, with no second END, once
 * the finish has returned (cancelling). A purge of such a job is refused
 * like that of any job not ended. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_farm_impl.h"
#include "gi_farm_published.h"
#include "gi_file_writer.h"
#include "gi_progress.h"
#include "gi_fs.h"
#include "gi_log.h"

#define COMPACT_AFTER_RECORDS 4096
#define MAX_MANIFEST_ENTRIES 10000

const char *gi_fj_state_name(gi_fj_state s)
{
    switch (s) {
    case GI_FJ_CHECKING: return "checking";
    case GI_FJ_RUNNING: return "running";
    case GI_FJ_DONE: return "done";
    case GI_FJ_FAILED: return "failed";
    case GI_FJ_CANCELLED: return "cancelled";
    }
    return "unknown";
}

int gi_farm_job_finishing(const gi_farm_job *j)
{
    return j->state == GI_FJ_RUNNING && j->loaded && gi_jobrun_finishing(&j->jr);
}

const char *gi_farm_job_state_name(const gi_farm_job *j)
{
    if (gi_farm_job_finishing(j))
        return j->cancelling ? "cancelling" : "finishing";
    return gi_fj_state_name(j->state);
}

static void start_checkers(gi_farm *f);
static void checkpoint_begin(gi_farm *f, gi_farm_job *j, int over);
static int checkpoint_finish(gi_farm *f, gi_farm_job *j, int wait);
static void published_load(gi_farm_job *j);
static void end_journaled(gi_farm *f, gi_farm_job *j);

static int terminal(const gi_farm_job *j)
{
    return j->state == GI_FJ_DONE || j->state == GI_FJ_FAILED || j->state == GI_FJ_CANCELLED;
}

/* ---- records ----------------------------------------------------------- */

static gi_farm_job *job_new(gi_farm *f, uint64_t id)
{
    gi_farm_job *j = gi_xcalloc(1, sizeof *j);
    j->id = id;
    j->state = GI_FJ_CHECKING;
    j->check_fd = -1;
    j->est_task_s = 1.0;
    gi_manifest_init(&j->manifest);
    gi_manifest_init(&j->published);
    gi_manifest_init(&j->ckpt_w_published);
    gi_buf_init(&j->check_msg);
    gi_buf_init(&j->log_pending);
    size_t n = strlen(f->jobs_dir) + 32;
    j->dir = gi_xmalloc(n);
    snprintf(j->dir, n, "%s/%llu", f->jobs_dir, (unsigned long long)id);
    if (f->job_count == f->job_cap) {
        f->job_cap = f->job_cap ? 2 * f->job_cap : 16;
        f->jobs = gi_xrealloc(f->jobs, f->job_cap * sizeof *f->jobs);
    }
    if (f->job_count && f->jobs[f->job_count - 1]->id > id)
        f->jobs_unsorted = 1;
    f->jobs[f->job_count++] = j;
    f->live_stale = 1;
    /* Never past GI_JOB_ID_MAX: at the last id, submissions are refused
     * (next_free_id) instead of wrapping to ids of jobs that exist. */
    if (id >= f->next_job_id)
        f->next_job_id = id < GI_JOB_ID_MAX ? id + 1 : GI_JOB_ID_MAX;
    return j;
}

static void run_free(gi_farm_job *j)
{
    if (!j->loaded)
        return;
    gi_jobrun_free(&j->jr);
    gi_job_free(&j->job);
    gi_affinity_free(&j->affinity);
    gi_affinity_free(&j->failed_on);
    j->loaded = 0;
}

static void job_free(gi_farm_job *j)
{
    gi_farm_check_kill(j);
    if (j->ckpt_w) /* only at exit, after gi_farm_jobs_checkpoint_all */
        gi_file_writer_finish(j->ckpt_w, NULL, NULL);
    run_free(j);
    free(j->excl);
    free(j->suspects);
    free(j->file);
    free(j->text);
    free(j->submit_key);
    free(j->name);
    free(j->method);
    for (int i = 0; i < j->output_count; i++)
        free(j->outputs[i]);
    free(j->outputs);
    for (int i = 0; i < j->declared_count; i++) {
        free(j->declared[i].kind);
        free(j->declared[i].file);
    }
    free(j->declared);
    free(j->dir);
    gi_manifest_free(&j->manifest);
    gi_manifest_free(&j->published);
    gi_manifest_free(&j->ckpt_w_published);
    gi_buf_free(&j->check_msg);
    gi_buf_free(&j->log_pending);
    for (int i = 0; i < j->log_count; i++)
        free(j->log[(j->log_start + i) % GI_FJ_LOG_KEEP]);
    free(j->errors);
    free(j);
}

/* Every result and lease looks its job up, among all the farm's jobs ever
 * submitted and not purged: ids rise in submission order, so a binary
 * search (a linear one if a damaged journal broke the order). */
gi_farm_job *gi_farm_job_find(gi_farm *f, uint64_t id)
{
    if (f->jobs_unsorted) {
        for (size_t i = 0; i < f->job_count; i++)
            if (f->jobs[i]->id == id)
                return f->jobs[i];
        return NULL;
    }
    size_t lo = 0, hi = f->job_count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (f->jobs[mid]->id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < f->job_count && f->jobs[lo]->id == id ? f->jobs[lo] : NULL;
}

gi_farm_job *gi_farm_job_by_key(gi_farm *f, const char *key)
{
    /* Newest first: a repeated submission follows its first closely. A
     * linear search: keys are only looked up for a submission that has
     * one, and each costs a journal append anyway. */
    for (size_t i = f->job_count; i-- > 0;)
        if (f->jobs[i]->submit_key && strcmp(f->jobs[i]->submit_key, key) == 0)
            return f->jobs[i];
    return NULL;
}

gi_farm_job **gi_farm_live_jobs(gi_farm *f, size_t *count)
{
    if (f->live_stale) {
        if (f->live_cap < f->job_count) {
            f->live_cap = f->job_count;
            f->live = gi_xrealloc(f->live, f->live_cap * sizeof *f->live);
        }
        f->live_count = 0;
        for (size_t i = 0; i < f->job_count; i++)
            if (!terminal(f->jobs[i]))
                f->live[f->live_count++] = f->jobs[i];
        f->live_stale = 0;
    }
    *count = f->live_count;
    return f->live;
}

static void push_log_line(gi_farm_job *j, char *line)
{
    if (j->log_count == GI_FJ_LOG_KEEP) {
        free(j->log[j->log_start]);
        j->log[j->log_start] = line;
        j->log_start = (j->log_start + 1) % GI_FJ_LOG_KEEP;
    } else {
        j->log[(j->log_start + j->log_count++) % GI_FJ_LOG_KEEP] = line;
    }
}

/* Appends the lines not yet in the job's log file, if its disk has room
 * (whole lines: a cut one is cut back off). gi-farmd's own log has them
 * meanwhile. */
static int log_flush(gi_farm_job *j)
{
    if (!j->log_pending.len && !j->log_dropped)
        return 0;
    if (j->log_dropped) {
        char note[128];
        int n = snprintf(note, sizeof note, "(%llu more lines lost here: the disk was full)\n",
                         (unsigned long long)j->log_dropped);
        gi_buf_put(&j->log_pending, note, (size_t)n);
        j->log_dropped = 0;
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/log", j->dir);
    if (gi_append_whole(path, j->log_pending.data, j->log_pending.len, NULL) == 0)
        j->log_pending.len = 0;
    return j->log_pending.len != 0;
}

/* echo: also to gi-farmd's own log (a line already there is not). */
static void job_log(gi_farm_job *j, int warn, int echo, const char *fmt, va_list ap)
{
    char msg[1200];
    vsnprintf(msg, sizeof msg, fmt, ap);
    char stamp[32];
    time_t t = (time_t)gi_farm_wallnow();
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &tm);
    char line[1300];
    snprintf(line, sizeof line, "%s %s", stamp, msg);
    push_log_line(j, gi_xstrdup(line));
    /* The echo must not come back through a hook routing warnings here. */
    gi_log_hook fn;
    void *ctx;
    gi_log_hook_get(&fn, &ctx);
    gi_log_hook_set(NULL, NULL);
    if (echo && warn)
        gi_warn("job %llu: %s", (unsigned long long)j->id, msg);
    else if (echo)
        gi_info("job %llu: %s", (unsigned long long)j->id, msg);
    gi_log_hook_set(fn, ctx);
    /* The log file outlives restarts; the in-memory ring is its tail. */
    if (j->log_pending.len + strlen(line) < GI_FJ_LOG_PENDING_MAX) {
        gi_buf_put(&j->log_pending, line, strlen(line));
        gi_buf_put(&j->log_pending, "\n", 1);
    } else {
        j->log_dropped++;
    }
    log_flush(j);
}

void gi_farm_job_log(gi_farm_job *j, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    job_log(j, 0, 1, fmt, ap);
    va_end(ap);
}

void gi_farm_job_warn(gi_farm_job *j, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    job_log(j, 1, 1, fmt, ap);
    va_end(ap);
}

static void job_log_line(gi_farm_job *j, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    job_log(j, 1, 0, fmt, ap);
    va_end(ap);
}

/* gi_log_hook: a warning of the code working on a job (its method, its
 * scene: a coarse bake, a mesh's broken normals) goes to the job's log,
 * where whoever submitted it looks, not only to gi-farmd's. */
static void to_job_log(void *ctx, gi_log_level level, const char *msg)
{
    job_log_line(ctx, "%s: %s", level == GI_LOG_ERROR ? "error" : "warning", msg);
}

void gi_farm_job_logging(gi_farm_job *j)
{
    gi_log_hook_set(j ? to_job_log : NULL, j);
}

void gi_farm_job_task_error(gi_farm_job *j, uint64_t task, uint32_t attempt,
                            const char *worker, const char *msg)
{
    gi_fj_task_error *e;
    if (!j->errors)
        j->errors = gi_xcalloc(GI_FJ_ERRORS_KEEP, sizeof *j->errors);
    if (j->err_count == GI_FJ_ERRORS_KEEP) {
        e = &j->errors[j->err_start];
        j->err_start = (j->err_start + 1) % GI_FJ_ERRORS_KEEP;
    } else {
        e = &j->errors[(j->err_start + j->err_count++) % GI_FJ_ERRORS_KEEP];
    }
    e->when = gi_farm_wallnow();
    e->task_id = task;
    e->attempt = attempt;
    snprintf(e->worker, sizeof e->worker, "%.255s", worker);
    snprintf(e->message, sizeof e->message, "%.500s", msg);
}

/* Reloads the tail of a job's log file into its ring (after a restart). */
static void load_log_tail(gi_farm_job *j)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/log", j->dir);
    int fd = gi_open_regular(path, O_RDONLY, NULL, NULL);
    FILE *fp = fd >= 0 ? fdopen(fd, "r") : NULL;
    if (!fp) {
        if (fd >= 0)
            close(fd);
        return;
    }
    char line[1400];
    while (fgets(line, sizeof line, fp)) {
        line[strcspn(line, "\n")] = '\0';
        push_log_line(j, gi_xstrdup(line));
    }
    fclose(fp);
}

/* Fills name, method and outputs from the job text (for listings). */
static int describe(gi_farm_job *j, gi_job *parsed)
{
    j->name = gi_xstrdup(parsed->name);
    j->method = gi_xstrdup(parsed->method->name);
    j->output_count = parsed->output_count;
    j->outputs = gi_xcalloc((size_t)parsed->output_count + 1, sizeof *j->outputs);
    j->keeps_batches = parsed->keeps_batches;
    j->declared_count = parsed->output_count;
    j->declared = gi_xcalloc((size_t)parsed->output_count + 1, sizeof *j->declared);
    for (int i = 0; i < parsed->output_count; i++) {
        j->outputs[i] = gi_xstrdup(parsed->outputs[i].file);
        j->declared[i].kind = gi_xstrdup(parsed->outputs[i].kind);
        j->declared[i].file = gi_xstrdup(parsed->outputs[i].file);
    }
    return 0;
}

static int cmp_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The outputs as written, from the job's out directory: a method may write
 * more than the job names (an animation writes NAME.0003.exr per frame).
 * Temporary files (gi_temp_path) and hidden names are not outputs; those
 * of a coordinator killed while writing are removed here, in the one read
 * of the directory (at start-up for done jobs, when a job is done).
 * Keeps the declared names if the directory holds nothing. */
static void list_written_outputs(gi_farm_job *j)
{
    char path[4300];
    snprintf(path, sizeof path, "%s/out", j->dir);
    DIR *d = opendir(path);
    if (!d)
        return;
    char **names = NULL;
    int n = 0, cap = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (gi_is_stale_temp_name(e->d_name)) { /* the coordinator was killed writing it */
            char *stale = gi_path_join(path, e->d_name);
            unlink(stale);
            free(stale);
        }
        if (e->d_name[0] == '.' || gi_is_temp_name(e->d_name))
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 16;
            names = gi_xrealloc(names, (size_t)cap * sizeof *names);
        }
        names[n++] = gi_xstrdup(e->d_name);
    }
    closedir(d);
    if (n == 0) {
        free(names);
        return;
    }
    qsort(names, (size_t)n, sizeof *names, cmp_name);
    for (int i = 0; i < j->output_count; i++)
        free(j->outputs[i]);
    free(j->outputs);
    j->outputs = names;
    j->output_count = n;
}

/* ---- journal ----------------------------------------------------------- */

static void submit_record(const gi_farm_job *j, gi_jrec *r)
{
    gi_jrec_init(r, GI_JREC_SUBMIT, j->id);
    r->priority = j->priority;
    r->submitted = j->submitted;
    r->file = j->file;
    r->text = j->text;
    r->key = j->submit_key;
    r->manifest = j->manifest; /* borrowed: not freed */
}

static void end_record(const gi_farm_job *j, gi_jrec *r)
{
    gi_jrec_init(r, GI_JREC_END, j->id);
    r->end = j->cancelling || j->state == GI_FJ_CANCELLED ? GI_JOB_END_CANCELLED
             : j->state == GI_FJ_DONE                     ? GI_JOB_END_DONE
                                                          : GI_JOB_END_FAILED;
    r->code = (uint32_t)j->error.code;
    r->message = (char *)j->error.msg;
    r->when = j->ended;
    if (j->final_progress.frames) { /* the run this process saw end */
        r->has_summary = 1;
        r->started = j->started;
        r->tasks = j->final_tasks;
        r->merged = j->final_merged;
        r->retries = j->final_retries;
        r->has_losses = 1;
        r->losses = j->final_losses;
        r->rays = j->final_stats.rays;
        r->samples = j->final_stats.samples;
        r->seconds = j->final_stats.seconds;
        r->fraction = j->final_progress.fraction;
        r->done = j->final_progress.done;
        r->total = j->final_progress.total;
        r->frame = j->final_progress.frame;
        r->frames = j->final_progress.frames;
    }
}

static void ckpt_record(const gi_farm_job *j, gi_jrec *r)
{
    gi_jrec_init(r, GI_JREC_CHECKPOINT, j->id);
    r->seq = j->ckpt_seq;
    r->merged = j->ckpt_merged;
    r->tasks = j->loaded ? j->jr.task_count : j->ckpt_merged;
}

static void fetched_record(const gi_farm_job *j, gi_jrec *r)
{
    gi_jrec_init(r, GI_JREC_FETCHED, j->id);
    r->when = j->fetched;
}

/* Rewrites the journal as the current state: per job one SUBMIT (with its
 * Idempotency-Key), the last CHECKPOINT of a job not done, the END of an
 * ended one and the FETCHED of a fetched one. */
static int compact(gi_farm *f, gi_error *err)
{
    size_t n = 0;
    gi_jrec *recs = gi_xcalloc(4 * f->job_count + 1, sizeof *recs);
    const gi_jrec **ptrs = gi_xcalloc(4 * f->job_count + 1, sizeof *ptrs);
    for (size_t i = 0; i < f->job_count; i++) {
        const gi_farm_job *j = f->jobs[i];
        submit_record(j, &recs[n++]);
        /* A failed or cancelled job's checkpoint may still be retried. */
        if (j->ckpt_seq && j->state != GI_FJ_DONE)
            ckpt_record(j, &recs[n++]);
        if (terminal(j))
            end_record(j, &recs[n++]);
        /* After its END: replay takes a FETCHED for a done job only. */
        if (j->state == GI_FJ_DONE && j->fetched > 0)
            fetched_record(j, &recs[n++]);
    }
    for (size_t i = 0; i < n; i++)
        ptrs[i] = &recs[i];
    int rc = gi_journal_rewrite(&f->journal, ptrs, n, err);
    free(ptrs);
    free(recs); /* every string was borrowed */
    for (size_t i = 0; rc == 0 && i < f->job_count; i++)
        if (f->jobs[i]->end_pending) /* its END is in the rewritten journal */
            end_journaled(f, f->jobs[i]);
    return rc;
}

/* A failed or cancelled job made unfinished again: it is checked and
 * loaded like a job of a restarted coordinator, from its checkpoint if it
 * has one. What its last run counted starts over. */
static void reopen(gi_farm *f, gi_farm_job *j)
{
    j->state = GI_FJ_CHECKING;
    f->live_stale = 1;
    j->ended = 0;
    j->fetched = 0; /* outputs to come are new */
    gi_error_clear(&j->error);
    j->final_tasks = j->final_merged = j->final_retries = j->final_losses = 0;
    memset(&j->final_stats, 0, sizeof j->final_stats);
    memset(&j->final_progress, 0, sizeof j->final_progress);
    j->resumed_merged = j->results_accepted = j->results_late = 0;
    j->leases = j->lease_expiries = j->result_bytes = j->merged_bytes = 0;
    j->host_disk_errors = j->task_timeouts = 0;
    j->excl_count = 0; /* a retried job gives every worker a new chance */
    j->suspect_count = 0;
    f->standing_dirty = 1;
    j->merge_s = j->finish_s = 0.0;
    j->outputs_retry_at = 0;
    j->disk_measured = 0;
    j->outputs_retrying = 0;
}

static int replay_one(void *ctx, const gi_jrec *r, gi_error *err)
{
    gi_farm *f = ctx;
    gi_farm_job *j = gi_farm_job_find(f, r->job_id);
    switch (r->type) {
    case GI_JREC_SUBMIT: {
        if (j)
            return gi_fail(err, GI_EPROTO, "job %llu is submitted twice",
                           (unsigned long long)r->job_id);
        j = job_new(f, r->job_id);
        j->priority = r->priority;
        j->submitted = r->submitted;
        j->file = gi_xstrdup(r->file);
        j->text = gi_xstrdup(r->text);
        j->text_len = strlen(j->text);
        j->submit_key = r->key ? gi_xstrdup(r->key) : NULL;
        for (size_t i = 0; i < r->manifest.count; i++)
            gi_manifest_put(&j->manifest, r->manifest.entries[i].name,
                            r->manifest.entries[i].hash, r->manifest.entries[i].size);
        return 0;
    }
    case GI_JREC_CHECKPOINT:
        if (j) {
            j->ckpt_seq = r->seq;
            j->ckpt_merged = r->merged;
        }
        return 0;
    case GI_JREC_END:
        if (j) {
            f->live_stale = 1;
            j->state = r->end == GI_JOB_END_DONE     ? GI_FJ_DONE
                       : r->end == GI_JOB_END_FAILED ? GI_FJ_FAILED
                                                     : GI_FJ_CANCELLED;
            j->error.code = (gi_errcode)r->code;
            snprintf(j->error.msg, sizeof j->error.msg, "%s", r->message ? r->message : "");
            j->ended = r->when;
            if (r->has_summary) {
                j->started = r->started;
                j->final_tasks = r->tasks;
                j->final_merged = r->merged;
                j->final_retries = r->retries;
                j->final_losses = r->losses;
                j->final_stats.rays = r->rays;
                j->final_stats.samples = r->samples;
                j->final_stats.seconds = r->seconds;
                memset(&j->final_progress, 0, sizeof j->final_progress);
                j->final_progress.fraction = r->fraction;
                j->final_progress.done = r->done;
                j->final_progress.total = r->total;
                j->final_progress.frame = r->frame;
                j->final_progress.frames = r->frames;
            }
        }
        return 0;
    case GI_JREC_RETRY:
        if (j && (j->state == GI_FJ_FAILED || j->state == GI_FJ_CANCELLED))
            reopen(f, j);
        return 0;
    case GI_JREC_FETCHED:
        if (j && j->state == GI_FJ_DONE && !j->fetched) /* the first fetch */
            j->fetched = r->when;
        return 0;
    case GI_JREC_PURGE:
        for (size_t i = 0; i < f->job_count; i++)
            if (f->jobs[i]->id == r->job_id) {
                job_free(f->jobs[i]);
                memmove(&f->jobs[i], &f->jobs[i + 1], (f->job_count - i - 1) * sizeof *f->jobs);
                f->job_count--;
                f->live_stale = 1;
                break;
            }
        return 0;
    }
    return 0;
}

/* A directory name that is a job id ("17"), or 0. */
static uint64_t dir_job_id(const char *name)
{
    uint64_t id = 0;
    if (name[0] < '1' || name[0] > '9' || strlen(name) > 16)
        return 0;
    for (const char *c = name; *c; c++) {
        if (*c < '0' || *c > '9')
            return 0;
        id = 10 * id + (uint64_t)(*c - '0');
    }
    return id <= GI_JOB_ID_MAX ? id : 0;
}

/* Job directories the journal does not know (it was lost, cut or damaged)
 * keep their ids: a new job given one would adopt the old job's checkpoint
 * and outputs. New ids start after the highest. */
static void skip_leftover_ids(gi_farm *f)
{
    DIR *d = opendir(f->jobs_dir);
    if (!d)
        return;
    uint64_t top = 0;
    size_t left = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        uint64_t id = dir_job_id(e->d_name);
        if (!id || gi_farm_job_find(f, id))
            continue;
        left++;
        if (id > top)
            top = id;
    }
    closedir(d);
    if (!left)
        return;
    if (top >= f->next_job_id)
        f->next_job_id = top < GI_JOB_ID_MAX ? top + 1 : GI_JOB_ID_MAX;
    gi_warn("%s: %zu job directories the journal does not know (up to %llu; a lost or damaged "
            "journal?): kept, not reused; new jobs start at id %llu",
            f->jobs_dir, left, (unsigned long long)top, (unsigned long long)f->next_job_id);
}

int gi_farm_jobs_replay(gi_farm *f, gi_error *err)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/journal", f->cfg.state_dir);
    int damaged;
    if (gi_journal_open(&f->journal, path, replay_one, f, &damaged, err))
        return -1;
    skip_leftover_ids(f);
    size_t unfinished = 0;
    for (size_t i = 0; i < f->job_count; i++) {
        gi_farm_job *j = f->jobs[i];
        gi_error perr;
        gi_job parsed;
        if (gi_job_parse(j->text, strlen(j->text), j->file, &parsed, &perr) == 0) {
            describe(j, &parsed);
        } else {
            /* Accepted once, refused now: a method or limit changed. */
            j->name = gi_xstrdup("?");
            j->method = gi_xstrdup("?");
            j->outputs = gi_xcalloc(1, sizeof *j->outputs);
        }
        gi_job_free(&parsed);
        if (j->state == GI_FJ_DONE)
            list_written_outputs(j);
        load_log_tail(j);
        published_load(j);
        if (!terminal(j))
            unfinished++;
    }
    if (f->job_count)
        gi_info("journal: %zu jobs, %zu unfinished", f->job_count, unfinished);
    /* Start from a compact journal (and without a damaged tail). */
    if (compact(f, err))
        return -1;
    for (size_t i = 0; i < f->job_count; i++) {
        gi_farm_job *j = f->jobs[i];
        if (terminal(j))
            continue;
        gi_farm_job_log(j, "coordinator restarted: resuming%s", j->ckpt_seq ? " from its checkpoint" : "");
    }
    start_checkers(f);
    return 0;
}

/* ---- submit / check / run ---------------------------------------------- */

/* Scene checkers run at most this many at once (a restart with many
 * unfinished jobs must not fork them all together); the others wait in
 * CHECKING, in submission order. */
#define MAX_CHECKERS 4

static void start_checkers(gi_farm *f)
{
    size_t n;
    gi_farm_job **live = gi_farm_live_jobs(f, &n);
    int running = 0;
    for (size_t i = 0; i < n; i++)
        running += live[i]->check_pid > 0;
    for (size_t i = 0; i < n && running < MAX_CHECKERS; i++) {
        gi_farm_job *j = live[i];
        if (j->state != GI_FJ_CHECKING || j->check_pid > 0)
            continue;
        gi_error err;
        if (gi_farm_check_start(f, j, &err))
            gi_farm_job_fail(f, j, &err);
        else
            running++;
    }
}

static size_t unfinished_jobs(const gi_farm *f)
{
    size_t n = 0;
    for (size_t i = 0; i < f->job_count; i++)
        n += !terminal(f->jobs[i]);
    return n;
}

/* A job's record, its text and its Idempotency-Key. */
static uint64_t job_memory(size_t text_len, const char *key)
{
    return sizeof(gi_farm_job) + text_len + (key ? strlen(key) + 1 : 0);
}

/* What the farm's jobs hold in memory for as long as they are kept (a
 * cancelled or failed job keeps its text for a retry, a done one until it
 * is purged): their records, texts and keys. */
static uint64_t jobs_memory(const gi_farm *f)
{
    uint64_t n = 0;
    for (size_t i = 0; i < f->job_count; i++)
        n += job_memory(f->jobs[i]->text_len, f->jobs[i]->submit_key);
    return n;
}

/* The id for a new job: next_job_id, or past it while that id is taken (by
 * a job, or by a directory left in jobs/ since start-up). 0 when none is
 * left. */
static uint64_t next_free_id(gi_farm *f)
{
    for (uint64_t id = f->next_job_id; id && id <= GI_JOB_ID_MAX; id++) {
        char path[4200];
        snprintf(path, sizeof path, "%s/%llu", f->jobs_dir, (unsigned long long)id);
        struct stat st;
        if (gi_farm_job_find(f, id))
            continue;
        if (lstat(path, &st) == 0) {
            gi_warn("%s is in the way of a new job: kept, the id is skipped", path);
            continue;
        }
        return id;
    }
    return 0;
}

gi_farm_job *gi_farm_job_submit(gi_farm *f, const char *file, char *text,
                                gi_manifest *manifest, uint32_t priority, const char *key,
                                gi_error *err)
{
    if (unfinished_jobs(f) >= f->cfg.max_jobs) {
        gi_fail(err, GI_ENOMEM, "the farm already has %u unfinished jobs (its limit)",
                f->cfg.max_jobs);
        return NULL;
    }
    /* Else submitting and cancelling jobs would fill the coordinator's
     * memory (and its journal) without bound. */
    uint64_t held = jobs_memory(f), more = job_memory(strlen(text), key);
    if (held + more > f->cfg.max_jobs_memory) {
        gi_fail(err, GI_ENOMEM,
                "the farm's %zu jobs hold %llu bytes, and this one's %llu more would pass "
                "--max-jobs-memory (%llu): `gi purge` ended jobs",
                f->job_count, (unsigned long long)held, (unsigned long long)more,
                (unsigned long long)f->cfg.max_jobs_memory);
        return NULL;
    }
    /* Everything that can be checked without loading the scene is checked
     * here, so a bad submission is refused at once with a 400. */
    gi_job parsed;
    if (gi_job_parse(text, strlen(text), file, &parsed, err)) {
        gi_job_free(&parsed);
        return NULL;
    }
    int rc = 0;
    uint64_t pixels = (uint64_t)parsed.width * (uint64_t)parsed.height;
    if (pixels > f->cfg.max_job_pixels)
        rc = gi_fail(err, GI_EINVAL, "%s: image: %d x %d pixels is over this farm's limit of %llu",
                     file, parsed.width, parsed.height, (unsigned long long)f->cfg.max_job_pixels);
    if (rc == 0 && manifest->count > MAX_MANIFEST_ENTRIES)
        rc = gi_fail(err, GI_EINVAL, "%s: %zu assets (limit %d)", file, manifest->count,
                     MAX_MANIFEST_ENTRIES);
    if (rc == 0 && !gi_manifest_find(manifest, parsed.scene_name))
        rc = gi_fail(err, GI_EINVAL,
                     "%s: scene: \"%s\" is not among the job's assets (upload it and list it "
                     "under \"assets\")",
                     file, parsed.scene_name);
    for (size_t i = 0; rc == 0 && i < manifest->count; i++) {
        gi_manifest_entry *e = &manifest->entries[i];
        uint64_t size;
        if (!gi_farm_store_has(f, e->hash, &size))
            rc = gi_fail(err, GI_EINVAL, "%s: assets: \"%s\": asset %.16s... was never uploaded",
                         file, e->name, e->hash);
        else
            e->size = size;
    }
    uint64_t id = rc ? 0 : next_free_id(f);
    if (rc == 0 && !id)
        rc = gi_fail(err, GI_ENOMEM, "the farm has no job id left (the last is %llu): "
                     "set up a new state directory", (unsigned long long)GI_JOB_ID_MAX);
    if (rc) {
        gi_job_free(&parsed);
        return NULL;
    }
    gi_farm_job *j = job_new(f, id);
    j->priority = priority;
    j->submitted = gi_farm_wallnow();
    j->file = gi_xstrdup(file);
    j->text = text;
    j->text_len = strlen(text);
    j->submit_key = key ? gi_xstrdup(key) : NULL; /* journaled with the job */
    j->manifest = *manifest;
    gi_manifest_init(manifest);
    describe(j, &parsed);
    gi_job_free(&parsed);
    char out[4300];
    snprintf(out, sizeof out, "%s/out", j->dir);
    gi_jrec r;
    submit_record(j, &r);
    if (gi_mkdirs(out, err) || gi_journal_append(&f->journal, &r, err)) {
        /* Not journaled: forget it (the id is not reused). */
        f->job_count--;
        f->live_stale = 1;
        j->text = NULL;
        job_free(j);
        return NULL;
    }
    f->m.jobs_submitted++;
    gi_farm_job_log(j, "submitted: %s, method %s, priority %u, %zu asset%s", j->file, j->method,
                    j->priority, j->manifest.count, j->manifest.count == 1 ? "" : "s");
    start_checkers(f);
    gi_error cerr;
    if (f->journal.records > COMPACT_AFTER_RECORDS && compact(f, &cerr))
        gi_warn("journal compaction: %s", cerr.msg);
    return j;
}

static char *affinity_path(const gi_farm_job *j)
{
    size_t n = strlen(j->dir) + 16;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/affinity", j->dir);
    return p;
}

static char *checkpoint_path(const gi_farm_job *j)
{
    size_t n = strlen(j->dir) + 16;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/checkpoint", j->dir);
    return p;
}

static char *published_path(const gi_farm_job *j)
{
    size_t n = strlen(j->dir) + 16;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/published", j->dir);
    return p;
}

/* <dir>/published (gi_farm_published.h): what the checkpoint on disk
 * needs from the asset store. */
static void published_load(gi_farm_job *j)
{
    char *path = published_path(j);
    gi_buf b;
    gi_buf_init(&b);
    if (gi_read_file(path, (size_t)1 << 24, &b, NULL) == 0) {
        size_t skipped = gi_published_parse((const char *)b.data, b.len, &j->published);
        if (skipped)
            gi_warn("%s: %zu damaged lines skipped", path, skipped);
    }
    gi_buf_free(&b);
    free(path);
}

static int published_save(const gi_farm_job *j, const gi_manifest *m, gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_published_format(m, &b);
    char *path = published_path(j);
    int rc = gi_write_file_atomic(path, b.data, b.len, err);
    free(path);
    gi_buf_free(&b);
    return rc;
}

/* The job's published data is no longer needed (it is done, or purged). */
static uint64_t published_release(gi_farm *f, gi_farm_job *j)
{
    gi_manifest old = j->published;
    gi_manifest_init(&j->published);
    char *path = published_path(j);
    unlink(path);
    free(path);
    uint64_t freed = gi_farm_store_release(f, &old, 0);
    gi_manifest_free(&old);
    return freed;
}

/* The job's END is in the journal: a done job's checkpoint and published
 * data are no longer needed (a failed or cancelled job's stay for a retry). */
static void end_journaled(gi_farm *f, gi_farm_job *j)
{
    j->end_pending = 0;
    if (j->state != GI_FJ_DONE)
        return;
    char *ck = checkpoint_path(j);
    unlink(ck); /* nothing left to resume */
    free(ck);
    published_release(f, j);
}

/* Appends the END of a job whose END could not be journaled when it ended:
 * 0 once it is there (or was), -1 while the journal still refuses it. */
static int end_flush(gi_farm *f, gi_farm_job *j)
{
    if (!j->end_pending)
        return 0;
    gi_jrec r;
    end_record(j, &r);
    gi_error err;
    if (gi_journal_append(&f->journal, &r, &err))
        return -1;
    gi_farm_job_log(j, "its end is journaled now");
    end_journaled(f, j);
    return 0;
}

/* The summary of the run as it ends, for the views and the END record. */
static void final_summary(gi_farm_job *j)
{
    if (!j->loaded)
        return;
    j->final_tasks = j->jr.task_count;
    j->final_merged = j->jr.merge_next;
    j->final_retries = j->jr.retries;
    j->final_losses = j->jr.losses;
    j->final_stats = j->jr.stats;
    gi_jobrun_progress(&j->jr, gi_now(), &j->final_progress);
}

/* Appends j's END; one the journal refuses is tried again at every tick. */
static void end_append(gi_farm *f, gi_farm_job *j)
{
    gi_jrec r;
    end_record(j, &r);
    gi_error err;
    if (gi_journal_append(&f->journal, &r, &err) == 0) {
        end_journaled(f, j);
        return;
    }
    j->end_pending = 1;
    gi_farm_job_warn(j, "its end cannot be journaled (%s): tried again every tick; until then "
                     "a restarted coordinator would run it again from its checkpoint, kept "
                     "for that", err.msg);
}

static void end_job(gi_farm *f, gi_farm_job *j, gi_fj_state state)
{
    /* A cancel of a finishing job journaled its END already (or left it
     * pending): it is not appended twice. */
    int journaled = j->cancelling;
    j->cancelling = 0;
    checkpoint_finish(f, j, 1); /* journaled before the END */
    j->state = state;
    f->live_stale = 1;
    f->ended_flush_due = 1; /* its END or log lines may have to wait for room */
    if (!journaled)
        j->ended = gi_farm_wallnow();
    j->disk_measured = 0;
    gi_farm_check_kill(j);
    gi_farm_sched_drop_job(f, j);
    final_summary(j);
    run_free(j);
    if (!journaled)
        end_append(f, j);
}

void gi_farm_job_fail(gi_farm *f, gi_farm_job *j, const gi_error *why)
{
    if (terminal(j) || j->cancelling)
        return;
    j->error = *why;
    gi_farm_job_log(j, "failed: %s", why->msg);
    f->m.jobs_failed++;
    end_job(f, j, GI_FJ_FAILED);
}

int gi_farm_job_cancel(gi_farm *f, gi_farm_job *j, const char *why)
{
    if (terminal(j) || j->cancelling)
        return -1;
    gi_fail(&j->error, GI_ECANCEL, "cancelled: %s", why);
    f->m.jobs_cancelled++;
    if (j->state != GI_FJ_RUNNING || !j->loaded || !gi_jobrun_finishing(&j->jr)) {
        gi_farm_job_log(j, "cancelled: %s", why);
        end_job(f, j, GI_FJ_CANCELLED);
        return 0;
    }
    /* Joining the finish's thread here would stall the loop for as long as
     * the outputs take; the END goes to the journal now, and finish_taken
     * ends the job once the thread has returned. */
    gi_farm_job_log(j, "cancelled: %s; the cancel waits for the outputs being written (the "
                    "job ends cancelled once they are, and they are not served)", why);
    checkpoint_finish(f, j, 1); /* journaled before the END */
    j->cancelling = 1;
    j->ended = gi_farm_wallnow();
    final_summary(j);
    end_append(f, j);
    return 0;
}

int gi_farm_job_retry(gi_farm *f, gi_farm_job *j, gi_error *err)
{
    if (j->state != GI_FJ_FAILED && j->state != GI_FJ_CANCELLED)
        return gi_fail(err, GI_EINVAL, "job %llu is %s: only a failed or cancelled job is retried",
                       (unsigned long long)j->id, gi_fj_state_name(j->state));
    if (unfinished_jobs(f) >= f->cfg.max_jobs)
        return gi_fail(err, GI_ENOMEM, "the farm already has %u unfinished jobs (its limit)",
                       f->cfg.max_jobs);
    /* A RETRY before the END it undoes would be undone by it on replay. */
    if (end_flush(f, j))
        return gi_fail(err, GI_EIO, "job %llu's end is not journaled yet (the coordinator's "
                       "disk is full?): try again later", (unsigned long long)j->id);
    gi_jrec r;
    gi_jrec_init(&r, GI_JREC_RETRY, j->id);
    r.when = gi_farm_wallnow();
    if (gi_journal_append(&f->journal, &r, err))
        return -1;
    char *ck = checkpoint_path(j);
    int has_ckpt = access(ck, F_OK) == 0;
    free(ck);
    gi_farm_job_log(j, "retried after it %s (%s): %s",
                    j->state == GI_FJ_FAILED ? "failed" : "was cancelled", j->error.msg,
                    has_ckpt ? "resuming from its last checkpoint" : "starting over");
    reopen(f, j);
    f->m.jobs_retried++;
    start_checkers(f);
    return 0;
}

/* Calls fn for every entry below path, then for path itself: children
 * first, as a removal needs them. Symbolic links are not followed. */
static void walk_tree(const char *path, void (*fn)(void *ctx, const char *p, int is_dir),
                      void *ctx)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            char p[4400];
            snprintf(p, sizeof p, "%s/%s", path, e->d_name);
            if (e->d_type == DT_DIR)
                walk_tree(p, fn, ctx);
            else
                fn(ctx, p, 0);
        }
        closedir(d);
    }
    fn(ctx, path, d != NULL);
}

static void remove_entry(void *ctx, const char *p, int is_dir)
{
    (void)ctx;
    if (is_dir)
        rmdir(p);
    else
        unlink(p);
}

static void remove_tree(const char *path)
{
    walk_tree(path, remove_entry, NULL);
}

void gi_farm_job_fetched(gi_farm *f, uint64_t id, const char *name, const char *peer)
{
    gi_farm_job *j = gi_farm_job_find(f, id);
    if (!j || j->state != GI_FJ_DONE || j->fetched > 0)
        return;
    /* A FETCHED before the END it follows would be dropped by replay: the
     * next download tries again, and retention meanwhile keeps the job as
     * unfetched (the safe side). So does a journal that refuses it. */
    gi_error err;
    gi_jrec r;
    double now = gi_farm_wallnow();
    gi_jrec_init(&r, GI_JREC_FETCHED, j->id);
    r.when = now;
    if (end_flush(f, j) || gi_journal_append(&f->journal, &r, &err)) {
        gi_warn("job %llu: its fetch of \"%s\" is not journaled (%s): it still counts as "
                "unfetched", (unsigned long long)j->id, name,
                j->end_pending ? "its end is not journaled yet" : err.msg);
        return;
    }
    j->fetched = now;
    gi_farm_job_log(j, "outputs fetched: \"%s\" sent whole to %s (the first download)", name,
                    peer);
}

int gi_farm_job_purge(gi_farm *f, gi_farm_job *j, gi_error *err)
{
    if (j->cancelling)
        return gi_fail(err, GI_EINVAL, "job %llu is cancelled, but its outputs are still being "
                       "written: purge it once it shows as cancelled", (unsigned long long)j->id);
    if (!terminal(j))
        return gi_fail(err, GI_EINVAL, "job %llu is %s: cancel it first",
                       (unsigned long long)j->id, gi_fj_state_name(j->state));
    gi_jrec r;
    gi_jrec_init(&r, GI_JREC_PURGE, j->id);
    if (gi_journal_append(&f->journal, &r, err))
        return -1;
    /* Its files in the asset store go with it, unless another job names
     * the same bytes: its published data first, while its own uploads
     * (which the published data may include) still count as named, so that
     * these go only with their grace period, below. */
    uint64_t freed = published_release(f, j);
    remove_tree(j->dir);
    if (j->keeps_batches)
        gi_farm_sched_job_over(f, j->id); /* a failed one's were kept for a retry */
    for (size_t i = 0; i < f->job_count; i++)
        if (f->jobs[i] == j) {
            memmove(&f->jobs[i], &f->jobs[i + 1], (f->job_count - i - 1) * sizeof *f->jobs);
            f->job_count--;
            f->live_stale = 1;
            break;
        }
    freed += gi_farm_store_release(f, &j->manifest, 1);
    gi_info("job %llu purged: %llu bytes of the asset store freed", (unsigned long long)j->id,
            (unsigned long long)freed);
    job_free(j);
    return 0;
}

/* Loads the job in the coordinator, outputs going to <dir>/out. */
static int load_for_run(gi_farm *f, gi_farm_job *j, gi_error *err)
{
    if (gi_farm_load_job(f, j, &j->job, err)) {
        gi_job_free(&j->job);
        return -1;
    }
    size_t n = strlen(j->dir) + 8;
    j->job.out_dir = gi_xmalloc(n);
    snprintf(j->job.out_dir, n, "%s/out", j->dir);
    return 0;
}

/* Every run's finish goes to a thread of its own, waking the loop. */
static gi_jobrun_opts run_opts(const gi_farm *f)
{
    return (gi_jobrun_opts){.finish_threaded = 1, .finish_wake_fd = f->finish_wake_fd,
                            .finish_gate = f->finish_gate};
}

/* The job failed writing its outputs, its whole result in its checkpoint. */
static void result_kept(const gi_farm_job *j, gi_error *e)
{
    gi_error was = *e;
    if (j->job.in_frame) /* an animation: the frames after go on */
        gi_fail(e, was.code, "%s; the frames rendered so far are kept in checkpoint %llu: a retry "
                "writes their outputs and goes on from there", was.msg,
                (unsigned long long)j->ckpt_seq);
    else
        gi_fail(e, was.code, "%s; the whole result is kept in checkpoint %llu: a retry only "
                "writes the outputs", was.msg, (unsigned long long)j->ckpt_seq);
}

/* The run failed writing its outputs with its whole result merged: the
 * result goes into a checkpoint now, so that `gi retry` renders nothing
 * again. 1 if it is in place. */
static int keep_result(gi_farm *f, gi_farm_job *j, gi_error *e)
{
    checkpoint_finish(f, j, 1);
    uint64_t seq = j->ckpt_seq;
    checkpoint_begin(f, j, 0);
    checkpoint_finish(f, j, 1);
    if (j->ckpt_seq == seq)
        return 0;
    result_kept(j, e); /* in place (even if its journal record failed) */
    return 1;
}

/* A result waiting in memory (no new checkpoint file fits: a full disk)
 * would be lost with the coordinator: it goes into the room of the
 * checkpoint before, so that a restart resumes from it whole. Says in
 * `out` where a restart would resume. */
static void keep_held_result(gi_farm *f, gi_farm_job *j, char *out, size_t len)
{
    checkpoint_finish(f, j, 1);
    uint64_t seq = j->ckpt_seq;
    checkpoint_begin(f, j, 1);
    checkpoint_finish(f, j, 1);
    char *ck = checkpoint_path(j);
    if (j->ckpt_seq != seq)
        snprintf(out, len, "the result is kept in checkpoint %llu, written in the room of the "
                 "one before: a restart resumes from it", (unsigned long long)j->ckpt_seq);
    else if (access(ck, F_OK) == 0) /* the one before stayed */
        snprintf(out, len, "a restart would run it again from checkpoint %llu",
                 (unsigned long long)j->ckpt_seq);
    else /* none, or the one before gave its room for nothing: the job stays running */
        snprintf(out, len, "a restart would run it again from the start");
    free(ck);
}

/* The run failed: the job fails, unless only its outputs could not be
 * written and no checkpoint can keep its result either (a full disk): then
 * the result waits in memory (and in the room of its checkpoint before, if
 * that is enough), and the tick tries the outputs again. */
static void run_failed(gi_farm *f, gi_farm_job *j)
{
    gi_error e = j->jr.error;
    if (gi_jobrun_finish_retryable(&j->jr) && !keep_result(f, j, &e)) {
        char kept[160];
        if (!j->outputs_retry_at) {
            keep_held_result(f, j, kept, sizeof kept);
            gi_farm_job_warn(j, "its outputs cannot be written (%s), nor a checkpoint of its "
                             "result in a new file: it waits in memory, and they are tried "
                             "again every %g s (`gi cancel` gives up); %s", e.msg,
                             f->cfg.checkpoint_s, kept);
        }
        j->outputs_retry_at = gi_now() + f->cfg.checkpoint_s;
        return;
    }
    j->outputs_retry_at = 0;
    gi_farm_job_fail(f, j, &e);
}

/* A job waiting for room to write its outputs tries again. */
static void outputs_retry(gi_farm *f, gi_farm_job *j, double now)
{
    if (j->state != GI_FJ_RUNNING || !j->outputs_retry_at || now < j->outputs_retry_at ||
        j->outputs_retrying)
        return;
    gi_farm_job_logging(j);
    int rc = gi_jobrun_finish_again(&j->jr);
    gi_farm_job_logging(NULL);
    if (rc) {
        run_failed(f, j);
        return;
    }
    if (gi_jobrun_finishing(&j->jr)) {
        j->outputs_retrying = 1; /* finish_taken goes on */
        return;
    }
    j->outputs_retry_at = 0;
    gi_farm_job_log(j, "its outputs are written now");
    gi_farm_job_settle(f, j);
}

/* Takes in the end of the job's finish on its thread, if it has ended
 * (waiting for it if wait): the job is done, fails, or has follow-up tasks. */
static void finish_taken(gi_farm *f, gi_farm_job *j, int wait)
{
    if (j->state != GI_FJ_RUNNING || !gi_jobrun_finishing(&j->jr))
        return;
    double f0 = j->jr.finish_seconds;
    gi_farm_job_logging(j); /* the finish's warnings */
    int running = gi_jobrun_finish_poll(&j->jr, wait);
    gi_farm_job_logging(NULL);
    if (running)
        return;
    j->finish_s += j->jr.finish_seconds - f0;
    f->m.finish_s += j->jr.finish_seconds - f0;
    if (j->cancelling) {
        j->outputs_retrying = 0;
        gi_farm_job_log(j, "cancelled: its finish has returned (%s%s)",
                        j->jr.failed ? "it failed: " : "its outputs are not served",
                        j->jr.failed ? j->jr.error.msg : "");
        end_job(f, j, GI_FJ_CANCELLED);
        return;
    }
    if (j->outputs_retrying) {
        j->outputs_retrying = 0;
        if (j->jr.failed) {
            run_failed(f, j); /* waits again, or fails the job */
            return;
        }
        j->outputs_retry_at = 0;
        gi_farm_job_log(j, "its outputs are written now");
    }
    gi_farm_job_settle(f, j);
}

/* Restores the run from the job's checkpoint file: 1 if restored (failed,
 * with err, if its outputs still cannot be written), 0 if there is none or
 * it is unusable (then the job is loaded afresh), -1 if the job cannot be
 * loaded again. */
static int restore(gi_farm *f, gi_farm_job *j, gi_error *err)
{
    char *ck = checkpoint_path(j);
    if (access(ck, F_OK) != 0) {
        free(ck);
        return 0;
    }
    gi_buf cp;
    gi_buf_init(&cp);
    int rc = gi_read_file(ck, (size_t)1 << 40, &cp, err);
    free(ck);
    if (rc == 0) {
        gi_jobrun_opts opts = run_opts(f);
        rc = gi_jobrun_restore_opts(&j->jr, &j->job, &cp, &opts, err);
    }
    gi_buf_free(&cp);
    if (rc == 0) {
        char *ap = affinity_path(j);
        gi_farm_affinity_load(f, j, ap);
        free(ap);
        return 1;
    }
    if (j->jr.failed && gi_jobrun_finish_retryable(&j->jr)) {
        /* A whole result, restored, whose outputs still cannot be written:
         * the run fails (jr.failed) and the checkpoint stays as it is. */
        result_kept(j, err);
        return 1;
    }
    /* A checkpoint that does not restore costs its work, not the job. The
     * method may have half-built its state: start from a fresh load. */
    gi_farm_job_warn(j, "checkpoint unusable, starting over: %s", err->msg);
    gi_jobrun_free(&j->jr);
    gi_job_free(&j->job);
    return load_for_run(f, j, err) ? -1 : 0;
}

/* The checkpoint file restored is not the one the journal last recorded
 * (the coordinator stopped between the file's rename and its record, or the
 * journal refused the record): it is journaled now, as the next in
 * sequence, so that its number is not given to another. */
static void checkpoint_adopted(gi_farm *f, gi_farm_job *j)
{
    j->ckpt_seq++;
    gi_jrec r;
    ckpt_record(j, &r);
    gi_error err;
    if (gi_journal_append(&f->journal, &r, &err))
        gi_warn("job %llu: %s", (unsigned long long)j->id, err.msg);
    gi_farm_job_log(j, "its checkpoint file is newer than the journal's record of it: taken as "
                    "checkpoint %llu", (unsigned long long)j->ckpt_seq);
}

void gi_farm_job_checked(gi_farm *f, gi_farm_job *j, const gi_error *why)
{
    if (j->state != GI_FJ_CHECKING)
        return;
    if (why) {
        gi_farm_job_fail(f, j, why);
        return;
    }
    gi_error err;
    gi_error_clear(&err);
    gi_farm_job_logging(j);
    gi_jobrun_opts opts = run_opts(f);
    int resumed = load_for_run(f, j, &err) ? -1 : restore(f, j, &err);
    int rc = resumed < 0  ? -1
             : resumed ? (j->jr.failed ? -1 : 0)
                       : gi_jobrun_start_opts(&j->jr, &j->job, &opts, &err);
    gi_farm_job_logging(NULL);
    if (resumed < 0) {
        gi_farm_job_fail(f, j, &err);
        return;
    }
    j->loaded = 1;
    if (rc) {
        gi_farm_job_fail(f, j, &err);
        return;
    }
    j->jr.max_attempts = f->cfg.max_attempts;
    j->jr.max_losses = f->cfg.max_task_losses;
    j->state = GI_FJ_RUNNING;
    if (!j->started)
        j->started = gi_farm_wallnow();
    j->run_t0 = gi_now();
    j->ckpt_last = j->run_t0;
    uint64_t journaled = j->ckpt_merged;
    j->ckpt_merged = j->jr.merge_next;
    j->ckpt_done_cost = j->jr.cost_done;
    if (resumed) {
        if (j->jr.merge_next != journaled)
            checkpoint_adopted(f, j);
        j->resumed_merged = j->jr.merge_next;
        gi_farm_job_log(j, "resumed from checkpoint %llu: %llu of %llu tasks already merged",
                        (unsigned long long)j->ckpt_seq, (unsigned long long)j->jr.merge_next,
                        (unsigned long long)j->jr.task_count);
    } else {
        gi_farm_job_log(j, "running: %llu tasks planned", (unsigned long long)j->jr.task_count);
    }
    gi_farm_sched_join(f, j);
    gi_farm_job_settle(f, j);
}

void gi_farm_job_settle(gi_farm *f, gi_farm_job *j)
{
    if (j->state != GI_FJ_RUNNING || !gi_jobrun_done(&j->jr))
        return;
    if (j->jr.failed) {
        if (!j->outputs_retry_at) /* else the tick tries its outputs again */
            run_failed(f, j);
        return;
    }
    list_written_outputs(j);
    char list[1024] = "";
    size_t k = 0;
    for (int i = 0; i < j->output_count && k + 16 < sizeof list; i++)
        k += (size_t)snprintf(list + k, sizeof list - k, "%s%s", i ? ", " : "", j->outputs[i]);
    gi_farm_job_log(j, "done: %llu tasks, %llu retries, %llu lost with their host, %llu results "
                    "this run; outputs: %s",
                    (unsigned long long)j->jr.task_count, (unsigned long long)j->jr.retries,
                    (unsigned long long)j->jr.losses, (unsigned long long)j->results_accepted,
                    list);
    f->m.jobs_done++;
    gi_error_clear(&j->error);
    end_job(f, j, GI_FJ_DONE);
}

/* ---- checkpoints ------------------------------------------------------- */

/* A checkpoint is taken in two steps, so that the loop does not wait for a
 * big image's sums to reach the disk (write, fsync, rename: half a second
 * for 271 MB): checkpoint_start serializes the run (the loop's own data)
 * and hands the bytes to a writer thread; checkpoint_finish, once the file
 * is in place, saves the affinity owners and journals the checkpoint. One
 * at a time per job. */
/* Serializes the run and starts writing its checkpoint. over: for a result
 * no new file has room for (a full disk), the checkpoint before gives up
 * its room first, if it takes at least as much as this one needs (else it
 * stays, and this one fails). */
static int checkpoint_start(gi_farm *f, gi_farm_job *j, int over, gi_error *err)
{
    /* Data the method published for its tasks must outlive a restart too:
     * into the store, where workers' requests find it by hash. */
    gi_manifest_free(&j->ckpt_w_published);
    gi_manifest_init(&j->ckpt_w_published);
    if (j->job.assets) {
        for (size_t i = 0; i < gi_asset_store_count(j->job.assets); i++) {
            char hash[GI_HASH_HEX];
            const gi_buf *b = gi_asset_store_at(j->job.assets, i, hash);
            if (gi_farm_store_put(f, hash, b->data, b->len, err))
                return -1;
            gi_manifest_put(&j->ckpt_w_published, hash, hash, b->len);
        }
    }
    gi_buf cp;
    gi_buf_init(&cp);
    if (gi_jobrun_checkpoint(&j->jr, &cp, err)) {
        gi_buf_free(&cp);
        return -1;
    }
    char *path = checkpoint_path(j);
    if (over) {
        struct stat st;
        int none = stat(path, &st) != 0;
        if (none || (uint64_t)st.st_blocks * 512 < cp.len) {
            gi_fail(err, GI_EIO, "%s: %s", path,
                    none ? "no checkpoint before to write over"
                         : "the checkpoint before takes less room than this one needs");
            free(path);
            gi_buf_free(&cp);
            return -1;
        }
        if (unlink(path) != 0) {
            gi_fail(err, GI_EIO, "%s: unlink: %s", path, strerror(errno));
            free(path);
            gi_buf_free(&cp);
            return -1;
        }
    }
    j->ckpt_w_merged = j->jr.merge_next;
    j->ckpt_w_done_cost = j->jr.cost_done;
    j->ckpt_w_bytes = cp.len;
    j->ckpt_w = gi_file_writer_start(path, &cp);
    free(path);
    return 0;
}

/* A checkpoint written (why NULL) or failed: failures go to the job's log
 * (once while the reason stays the same) and its view, so that whoever
 * watches the job sees its work is not being kept. */
static void checkpoint_outcome(gi_farm *f, gi_farm_job *j, const char *why)
{
    if (!why) {
        if (j->ckpt_error[0])
            gi_farm_job_log(j, "checkpoint %llu written: checkpoints work again",
                            (unsigned long long)j->ckpt_seq);
        j->ckpt_error[0] = '\0';
        return;
    }
    f->m.checkpoint_failures++;
    if (strncmp(j->ckpt_error, why, sizeof j->ckpt_error - 1) != 0)
        gi_farm_job_warn(j, "checkpoint failed (the job goes on): %s", why);
    snprintf(j->ckpt_error, sizeof j->ckpt_error, "%.511s", why);
}

/* The checkpoint being written is in place (written) or not: the data it
 * needs from the store becomes the job's published set, and what only the
 * checkpoint before needed goes; else what it alone stored goes. */
static int same_hashes(const gi_manifest *a, const gi_manifest *b)
{
    if (a->count != b->count)
        return 0;
    for (size_t i = 0; i < a->count; i++)
        if (!gi_manifest_has_hash(b, a->entries[i].hash))
            return 0;
    return 1;
}

static void checkpoint_published(gi_farm *f, gi_farm_job *j, int written)
{
    gi_manifest gone = j->ckpt_w_published;
    gi_manifest_init(&j->ckpt_w_published);
    if (written && same_hashes(&gone, &j->published)) {
        gi_manifest_free(&gone); /* most checkpoints: no file to sync, nothing to free */
        return;
    }
    gi_error err;
    if (written && published_save(j, &gone, &err) != 0) {
        gi_warn("job %llu: %s (the asset store keeps the data of older checkpoints)",
                (unsigned long long)j->id, err.msg);
        for (size_t i = 0; i < j->published.count; i++) /* keep both sets */
            gi_manifest_put(&gone, j->published.entries[i].hash, j->published.entries[i].hash,
                            j->published.entries[i].size);
        gi_manifest_free(&j->published);
        j->published = gone;
        return;
    }
    if (written) {
        gi_manifest old = j->published;
        j->published = gone;
        gone = old;
    }
    gi_farm_store_release(f, &gone, 0);
    gi_manifest_free(&gone);
}

/* Completes the checkpoint being written, if any, waiting for it if wait:
 * 1 when none is left, 0 while it is still being written. */
static int checkpoint_finish(gi_farm *f, gi_farm_job *j, int wait)
{
    if (!j->ckpt_w)
        return 1;
    if (!wait && !gi_file_writer_done(j->ckpt_w))
        return 0;
    gi_error err;
    double seconds;
    int rc = gi_file_writer_finish(j->ckpt_w, &seconds, &err);
    j->ckpt_w = NULL;
    gi_ckpt_pace_written(&j->ckpt_pace, seconds);
    checkpoint_published(f, j, rc == 0);
    if (rc == 0) {
        char *ap = affinity_path(j);
        gi_farm_affinity_save(j, ap);
        free(ap);
        j->ckpt_seq++;
        j->ckpt_merged = j->ckpt_w_merged;
        j->ckpt_done_cost = j->ckpt_w_done_cost;
        f->m.checkpoints++;
        f->m.checkpoint_bytes += j->ckpt_w_bytes;
        gi_jrec r;
        ckpt_record(j, &r);
        rc = gi_journal_append(&f->journal, &r, &err);
        gi_debug("job %llu: checkpoint %llu (%llu tasks merged, %zu bytes)",
                 (unsigned long long)j->id, (unsigned long long)j->ckpt_seq,
                 (unsigned long long)j->ckpt_merged, j->ckpt_w_bytes);
    }
    checkpoint_outcome(f, j, rc ? err.msg : NULL);
    return 1;
}

/* force: now, whatever the interval, and in place before returning (a
 * stopping coordinator). */
/* Starts a checkpoint; one that cannot start is a failed one: what it
 * stored goes, and the job's log and view say so. */
static void checkpoint_begin(gi_farm *f, gi_farm_job *j, int over)
{
    gi_error err;
    if (checkpoint_start(f, j, over, &err)) {
        checkpoint_published(f, j, 0);
        checkpoint_outcome(f, j, err.msg);
    }
}

static void checkpoint_if_due(gi_farm *f, gi_farm_job *j, double now, int force)
{
    if (!checkpoint_finish(f, j, force) || j->state != GI_FJ_RUNNING)
        return;
    if (gi_jobrun_finishing(&j->jr))
        return; /* its state is the finish's; the job ends or goes on once it returns */
    if (j->outputs_retry_at && !force)
        return; /* its outputs' retries try a checkpoint as well (keep_result) */
    double every = gi_ckpt_pace_interval(&j->ckpt_pace, f->cfg.checkpoint_s);
    if (!force && now - j->ckpt_last < every)
        return;
    j->ckpt_last = now;
    if (j->jr.merge_next == j->ckpt_merged && j->jr.cost_done == j->ckpt_done_cost)
        return; /* nothing merged since the last one */
    checkpoint_begin(f, j, 0);
    gi_ckpt_pace_begun(&j->ckpt_pace, gi_now() - now); /* the write's time comes later */
    if (force)
        checkpoint_finish(f, j, 1);
}

/* ---- retention ---------------------------------------------------------- */

/* Purges by retention per pass (one a second): each is a journal append and
 * its fdatasync, and the loop must not stall on a backlog (a farm started
 * with a retention shorter than its history, or after a long stop). */
#define RETENTION_PURGES_PER_PASS 100

static void add_entry_bytes(void *ctx, const char *p, int is_dir)
{
    struct stat st;
    (void)is_dir;
    if (lstat(p, &st) == 0)
        *(uint64_t *)ctx += (uint64_t)st.st_blocks * 512;
}

/* Bytes the files under path take on disk. */
static uint64_t tree_bytes(const char *path)
{
    uint64_t n = 0;
    walk_tree(path, add_entry_bytes, &n);
    return n;
}

double gi_farm_job_purge_at(const gi_farm *f, const gi_farm_job *j)
{
    if (!terminal(j) || f->cfg.keep_ended_s <= 0 || j->ended <= 0)
        return 0;
    return j->ended + f->cfg.keep_ended_s;
}

/* An ended job whose END is in the journal: what retention may purge. A
 * job not ended is never purged: running, checking, or waiting to write
 * its outputs again (outputs_retry_at: it is still running). */
static int retainable(const gi_farm_job *j)
{
    return terminal(j) && !j->end_pending && j->ended > 0;
}

/* A done job whose outputs were never downloaded whole: what a purge can
 * lose that nobody has. A failed or cancelled job has no outputs. */
static int unfetched(const gi_farm_job *j)
{
    return j->state == GI_FJ_DONE && j->fetched <= 0;
}

/* Exactly `gi purge`, logged with the reason; a warning for a job never
 * fetched. 1 if j is gone. */
static int retention_purge(gi_farm *f, gi_farm_job *j, const char *why)
{
    unsigned long long id = (unsigned long long)j->id;
    if (unfetched(j))
        gi_warn("job %llu (%s, %s): purged by retention: %s; its outputs were never fetched",
                id, j->name ? j->name : "?", gi_fj_state_name(j->state), why);
    else
        gi_info("job %llu (%s, %s): purged by retention: %s", id, j->name ? j->name : "?",
                gi_fj_state_name(j->state), why);
    gi_error err;
    if (gi_farm_job_purge(f, j, &err) == 0)
        return 1;
    /* A journal that refuses the PURGE (a full disk) refuses the next one
     * too: a warning a minute, not one a second. */
    gi_warn("job %llu: its purge by retention failed (%s): tried again in a minute", id, err.msg);
    f->retention_next = gi_now() + 60.0;
    return 0;
}

/* Retention's order: the jobs with nothing left to fetch (fetched, failed
 * or cancelled) before the done jobs never fetched; within each, the one
 * that ended first. */
static int by_retention(const void *a, const void *b)
{
    const gi_farm_job *x = *(gi_farm_job *const *)a, *y = *(gi_farm_job *const *)b;
    if (unfetched(x) != unfetched(y))
        return unfetched(x) - unfetched(y);
    if (x->ended != y->ended)
        return x->ended < y->ended ? -1 : 1;
    return x->id < y->id ? -1 : x->id > y->id;
}

/* --keep-ended-bytes: ended jobs go in retention's order while the ended
 * jobs' directories hold more. */
static void retention_by_size(gi_farm *f, int *budget)
{
    uint64_t total = 0;
    size_t n = 0;
    gi_farm_job **ended = gi_xmalloc((f->job_count + 1) * sizeof *ended);
    for (size_t i = 0; i < f->job_count; i++) {
        gi_farm_job *j = f->jobs[i];
        if (!retainable(j))
            continue;
        if (!j->disk_measured) {
            j->disk_bytes = tree_bytes(j->dir);
            j->disk_measured = 1;
        }
        total += j->disk_bytes;
        ended[n++] = j;
    }
    qsort(ended, n, sizeof *ended, by_retention);
    for (size_t i = 0; i < n && total > f->cfg.keep_ended_bytes && *budget > 0; i++, --*budget) {
        char why[300];
        uint64_t bytes = ended[i]->disk_bytes;
        snprintf(why, sizeof why, "the ended jobs' files hold %llu bytes, over --keep-ended-bytes "
                 "%llu, and it is the oldest %s", (unsigned long long)total,
                 (unsigned long long)f->cfg.keep_ended_bytes,
                 unfetched(ended[i]) ? "(no job fetched or without outputs is left)"
                                     : "fetched or without outputs");
        if (!retention_purge(f, ended[i], why))
            break;
        total -= bytes;
    }
    free(ended);
}

/* --keep-ended: the jobs due go, in retention's order (a backlog over the
 * budget of a pass sends those fetched first). */
static void retention_by_age(gi_farm *f, int *budget)
{
    double wall = gi_farm_wallnow();
    size_t n = 0;
    gi_farm_job **due = gi_xmalloc((f->job_count + 1) * sizeof *due);
    for (size_t i = 0; i < f->job_count; i++)
        if (retainable(f->jobs[i]) && wall >= gi_farm_job_purge_at(f, f->jobs[i]))
            due[n++] = f->jobs[i];
    qsort(due, n, sizeof *due, by_retention);
    for (size_t i = 0; i < n && *budget > 0; i++, --*budget) {
        char why[200], ago[32], keep[32];
        snprintf(why, sizeof why, "ended %s ago (--keep-ended %s)",
                 gi_duration(wall - due[i]->ended, ago, sizeof ago),
                 gi_duration(f->cfg.keep_ended_s, keep, sizeof keep));
        if (!retention_purge(f, due[i], why))
            break;
    }
    free(due);
}

/* Purges the ended jobs that retention no longer keeps. Once a second; the
 * ended time is journaled (END), so a job due while gi-farmd was stopped
 * goes at its first pass after a restart. */
static void retention(gi_farm *f)
{
    if (f->cfg.keep_ended_s <= 0 && !f->cfg.keep_ended_bytes)
        return;
    double now = gi_now();
    if (now < f->retention_next)
        return;
    f->retention_next = now + 1.0;
    int budget = RETENTION_PURGES_PER_PASS;
    if (f->cfg.keep_ended_s > 0)
        retention_by_age(f, &budget);
    if (f->cfg.keep_ended_bytes)
        retention_by_size(f, &budget);
}

void gi_farm_jobs_tick(gi_farm *f)
{
    start_checkers(f);
    double now = gi_now();
    size_t n;
    gi_farm_job **live = gi_farm_live_jobs(f, &n);
    for (size_t i = 0; i < n; i++) {
        gi_farm_job *j = live[i];
        if (j->state == GI_FJ_CHECKING)
            gi_farm_check_deadline(f, j, now);
        finish_taken(f, j, 0);
        checkpoint_if_due(f, j, now, 0);
        outputs_retry(f, j, now);
        log_flush(j);
    }
    /* Ended jobs are not live: their END records and log lines still
     * waiting for room are tried here, while there are any. */
    if (f->ended_flush_due) {
        f->ended_flush_due = 0;
        for (size_t i = 0; i < f->job_count; i++) {
            gi_farm_job *j = f->jobs[i];
            if (terminal(j) && ((end_flush(f, j) != 0) | log_flush(j)))
                f->ended_flush_due = 1;
        }
    }
    retention(f);
    if (f->journal.records > COMPACT_AFTER_RECORDS) {
        gi_error err;
        if (compact(f, &err))
            gi_warn("journal compaction: %s", err.msg);
    }
}

void gi_farm_jobs_checkpoint_all(gi_farm *f)
{
    double now = gi_now();
    for (size_t i = 0; i < f->job_count; i++) {
        /* A finish under way is waited for: its job is then done (outputs
         * in place, END journaled), or failed, or checkpointed below with
         * the follow-up tasks it planned. */
        finish_taken(f, f->jobs[i], 1);
        checkpoint_if_due(f, f->jobs[i], now, 1);
    }
}

void gi_farm_jobs_free(gi_farm *f)
{
    for (size_t i = 0; i < f->job_count; i++) {
        log_flush(f->jobs[i]); /* a last try */
        end_flush(f, f->jobs[i]);
        job_free(f->jobs[i]);
    }
    free(f->jobs);
    f->jobs = NULL;
    f->job_count = f->job_cap = 0;
    free(f->live);
    f->live = NULL;
    f->live_count = f->live_cap = 0;
    gi_journal_close(&f->journal);
}

/* ---- views ------------------------------------------------------------- */

char *gi_farm_job_output_path(const gi_farm_job *j, const char *name)
{
    for (int i = 0; i < j->output_count; i++)
        if (strcmp(j->outputs[i], name) == 0) {
            size_t n = strlen(j->dir) + strlen(name) + 8;
            char *p = gi_xmalloc(n);
            snprintf(p, n, "%s/out/%s", j->dir, name);
            return p;
        }
    return NULL;
}

void gi_farm_job_progress(const gi_farm_job *j, gi_progress_at *out)
{
    if (j->loaded) {
        gi_jobrun_progress(&j->jr, gi_now(), out);
    } else if (j->final_progress.frames) {
        *out = j->final_progress; /* as the run ended */
    } else {
        memset(out, 0, sizeof *out); /* not run by this process */
        out->frames = 1;
        out->total = 1;
        out->done = j->state == GI_FJ_DONE;
    }
    /* 1 means done: a job with every task merged that is still writing its
     * outputs, or that failed or was cancelled doing it, did not get there. */
    if (j->state == GI_FJ_DONE) {
        out->fraction = 1;
        out->eta_s = 0;
    } else {
        if (out->fraction > GI_FARM_PROGRESS_NOT_DONE)
            out->fraction = GI_FARM_PROGRESS_NOT_DONE;
        if (j->state != GI_FJ_RUNNING || j->cancelling)
            out->eta_s = -1;
    }
}
