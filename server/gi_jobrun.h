/* gi_jobrun: the life of one job on a coordinator: plan, lease tasks, take
 * results, merge them in task-id order, retry failures, finish.
 *
 * It knows nothing about who runs tasks: `gi render` drives it with a local
 * pool, gi-farmd with remote workers. Results may arrive in any order and
 * more than once (a retried task whose first run was late); each task is
 * merged exactly once, in id order, so outputs are bit-identical however the
 * work was spread. */
#ifndef GI_JOBRUN_H
#define GI_JOBRUN_H

#include <stdint.h>

#include "gi_job.h"
#include "gi_progress.h"
#include "gi_task.h"

typedef enum {
    GI_TASK_PENDING,
    GI_TASK_LEASED,
    GI_TASK_DONE,   /* result held, waiting for its turn to merge */
    GI_TASK_MERGED
} gi_task_state;

typedef struct gi_jobrun_task {
    gi_task task; /* task.attempt numbers its runs: +1 on every failure or loss */
    gi_task_state state;
    /* While leased: what a check decoded (decoded set), else empty; once
     * done: what merges, the worker's result or what its check decoded. */
    gi_buf result;
    int decoded;
    size_t result_len; /* the worker's result's bytes (merged_bytes) */
    uint32_t failures; /* runs that failed (counted against max_attempts) */
    uint32_t losses;   /* runs lost with their host (against max_losses) */
    char *lost_on;     /* the hosts of those losses, ", "-separated (NULL: none) */
} gi_jobrun_task;

typedef struct gi_jobrun_finisher gi_jobrun_finisher;

/* How a run finishes (gi_jobrun_start_opts, gi_jobrun_restore_opts).
 * finish_threaded: method->finish runs on a thread of its own (gi-farmd's:
 * writing a 4 Mpx EXR takes a second its loop must not wait): when the last
 * task is merged, the run is "finishing" (gi_jobrun_finishing) until
 * gi_jobrun_finish_poll takes the finish's end in. Meanwhile the method's
 * state and job (its outputs, its published data) are the thread's: nothing
 * may read them, nor checkpoint the run. The thread writes 8 bytes to
 * finish_wake_fd (>= 0: an eventfd) when it ends. finish_gate: a test hook
 * (gi-farmd's GI_FAULT_FINISH_GATE), NULL or a path: the thread waits
 * before finish until that file exists and it removed it, so that tests
 * can act meanwhile. */
typedef struct gi_jobrun_opts {
    int finish_threaded;
    int finish_wake_fd;
    const char *finish_gate;
} gi_jobrun_opts;

typedef struct gi_jobrun {
    gi_job *job;
    /* The tasks with ids [task_base, task_count), task id at
     * tasks[id - task_base] (gi_jobrun_task_at): merged ones are dropped
     * from the front as merging goes on, so a long animation's coordinator
     * holds about one frame's tasks, not every task the job ever had. */
    gi_jobrun_task *tasks;
    uint64_t task_base, task_count, task_cap;
    uint64_t *pending; /* ids waiting for a lease; retries go first */
    uint64_t pending_head, pending_count, pending_cap;
    uint64_t leased;
    uint64_t held;       /* results waiting for their turn to merge (GI_TASK_DONE) */
    uint64_t merge_next; /* every id below this is merged */
    uint32_t max_attempts; /* failures of a task before the job fails */
    uint32_t max_losses;   /* losses of a task with its host before the job fails */
    int finished, failed;
    gi_error error;
    /* Progress and statistics. */
    double cost_total, cost_done;
    gi_progress_clock clock; /* frames and ETA (gi_jobrun_progress) */
    gi_task_stats stats; /* summed over merged tasks */
    uint64_t retries;
    uint64_t losses; /* runs lost with their host and requeued (not retries) */
    /* Results done, not merged yet: what they hold (a decoded form, when
     * their check kept one). */
    uint64_t held_results_bytes, held_results_peak;
    /* Coordinator time in method->merge (with the bytes merged) and in
     * method->finish, for throughput figures. */
    double merge_seconds, finish_seconds;
    uint64_t merged_bytes;
    gi_jobrun_opts opts;
    gi_jobrun_finisher *finisher; /* the finish on its thread, while it runs */
    /* The animation frame its checkpoint was at (gi_jobrun_restore), before
     * a finish the restore ran (a checkpoint with every task merged). */
    uint32_t restored_frame;
} gi_jobrun;

static inline int gi_jobrun_finishing(const gi_jobrun *jr) { return jr->finisher != NULL; }
/* Takes in the end of the finish running on its thread, waiting for it if
 * wait: merging goes on, and the run may be finished or failed now
 * (gi_jobrun_done), or have follow-up tasks. The finish's warnings are
 * passed to this thread's log hook (gi_log_hook_set), as if it had run
 * here. Returns 1 while the finish still runs (wait = 0), else 0. */
int gi_jobrun_finish_poll(gi_jobrun *jr, int wait);

/* Plans the job (method->plan); finishes in place. */
int gi_jobrun_start(gi_jobrun *jr, gi_job *job, gi_error *err);
/* The same, finishing as opts say (NULL: in place). */
int gi_jobrun_start_opts(gi_jobrun *jr, gi_job *job, const gi_jobrun_opts *opts,
                         gi_error *err);
/* Waits for a finish running on its thread first. */
void gi_jobrun_free(gi_jobrun *jr);

/* The next task to run (its state becomes LEASED), or NULL if none is
 * pending right now. */
const gi_task *gi_jobrun_lease(gi_jobrun *jr);
/* Like gi_jobrun_lease, for one particular taker: the first pending task
 * accept() agrees to (NULL: any). Tasks passed over stay pending, in their
 * order. *passed (optional) gets how many pending tasks were refused, so a
 * caller can tell "nothing for you" (> 0) from "nothing at all" (0). */
const gi_task *gi_jobrun_lease_if(gi_jobrun *jr, int (*accept)(void *ctx, const gi_task *t),
                                  void *ctx, uint64_t *passed);
/* The method's check of a result for run `attempt` of a leased task (0 if
 * it has none, or that run is not the one leased: gi_jobrun_complete
 * ignores such a result). On -1 the caller fails the task with err
 * (gi_jobrun_fail). A method with merge_decoded may keep what its check
 * decoded with the task, which the run's gi_jobrun_complete then merges
 * instead of the result (so the caller gives it the same result); the run
 * ending otherwise drops it. */
int gi_jobrun_check_result(gi_jobrun *jr, uint64_t task_id, uint32_t attempt,
                           const gi_buf *result, gi_error *err);
/* A result for a leased task: taken over (result is left empty). Stale or
 * duplicate results are ignored. Returns -1 if the job failed (merge or
 * finish error): see jr->error. */
int gi_jobrun_complete(gi_jobrun *jr, uint64_t task_id, uint32_t attempt, gi_buf *result,
                       const gi_task_stats *stats);
/* A leased task failed (error from the worker, or a crash). It is retried up
 * to max_attempts; bad input (GI_EINVAL) and this host's full disk
 * (GI_EHOST) fail the job at once. */
int gi_jobrun_fail(gi_jobrun *jr, uint64_t task_id, uint32_t attempt, const gi_error *why);
/* A leased task's host was lost (its connection, or its lease expired):
 * not the task's fault, so no attempt is counted. The task is requeued
 * first in line under a new attempt number (a late result of the lost run
 * is stale). Its losses are counted apart and bounded by max_losses, so a
 * task that takes down every host running it fails the job, naming it and
 * the hosts (host: the lost one's name, for that message). */
int gi_jobrun_lost(gi_jobrun *jr, uint64_t task_id, uint32_t attempt, const char *host,
                   const gi_error *why);
/* Task time limits. A task whose run lasts longer than its job's
 * task_timeout (or default_s, the coordinator's, when the job sets none;
 * 0: no limit) is stopped by its coordinator, which fails the run with
 * gi_jobrun_timeout_error: a hang is the task's doing, like a crash, so the
 * run counts as an attempt (gi_jobrun_fail). The run lasts from when a
 * pool process got the task: time queued before is not counted (gi_local.c,
 * gi_farm_sched.c). */
double gi_jobrun_task_timeout(const gi_jobrun *jr, double default_s);
/* The error of a run of task_id stopped after limit_s seconds on `where`
 * ("worker NAME", or the pool child). */
void gi_jobrun_timeout_error(gi_error *e, uint64_t task_id, double limit_s, const char *where);
/* A lease given back without running (worker shutting down). */
void gi_jobrun_requeue(gi_jobrun *jr, uint64_t task_id);

/* The job's fraction, ETA, frame and totals now (monotonic seconds). */
void gi_jobrun_progress(const gi_jobrun *jr, double now, gi_progress_at *out);

/* The task with this id, or NULL once it was merged and dropped (or if
 * there is no such id). */
static inline gi_jobrun_task *gi_jobrun_task_at(const gi_jobrun *jr, uint64_t id)
{
    return id >= jr->task_base && id < jr->task_count ? &jr->tasks[id - jr->task_base] : NULL;
}

static inline int gi_jobrun_done(const gi_jobrun *jr) { return jr->finished || jr->failed; }

/* The run failed only writing its outputs (GI_EIO, GI_EHOST: a full disk,
 * a path in the way) with every task merged, and the method can finish
 * again: a checkpoint of it now keeps the whole result, and a run resumed
 * from that writes the outputs without rendering anything again. */
int gi_jobrun_finish_retryable(const gi_jobrun *jr);
/* Calls finish again on such a run (the outputs may find room now): 0 if
 * it is finished (or finishing on its thread), -1 if it failed again (or
 * was not such a run). */
int gi_jobrun_finish_again(gi_jobrun *jr);
/* Tasks waiting for a lease: those not merged, less the leased and held
 * ones (kept as counts: a job's view is asked for many times a second). */
static inline uint64_t gi_jobrun_pending_count(const gi_jobrun *jr)
{
    return jr->task_count - jr->merge_next - jr->leased - jr->held;
}

/* What a job's results depend on: BLAKE2b-256 (hex) of its text and of the
 * name and hash of every file its scene read. Checkpoints carry it. */
void gi_jobrun_identity(const gi_job *job, char out[GI_HASH_HEX]);

/* Checkpoints. The checkpoint holds the merge position, every task not yet
 * merged (id, kind, attempt, failures, losses and their hosts, cost,
 * payload), the statistics, and the method's state (method->save).
 * Results received but not yet merged are not in it: their tasks run again
 * after a restore. Refused while the run is finishing on its thread. */
int gi_jobrun_checkpoint(const gi_jobrun *jr, gi_buf *out, gi_error *err);
/* Rebuilds the run of `job` (parsed and loaded again from the same text and
 * assets) from a checkpoint, in place of gi_jobrun_start. A checkpoint of
 * another job (another identity, version 5 on) is refused. */
int gi_jobrun_restore(gi_jobrun *jr, gi_job *job, const gi_buf *in, gi_error *err);
/* The same, finishing as opts say (NULL: in place): a run whose tasks were
 * all merged starts its finish on its thread before this returns. */
int gi_jobrun_restore_opts(gi_jobrun *jr, gi_job *job, const gi_buf *in,
                           const gi_jobrun_opts *opts, gi_error *err);
/* What the periodic checkpoints of a run have cost, for their spacing: each
 * one's time, serialized by the loop, then written by a thread. Zeroed: no
 * checkpoint yet. */
typedef struct gi_ckpt_pace {
    double last_s; /* the last one's (the one being written: so far) */
    double prev_s; /* the one before */
    unsigned count;
} gi_ckpt_pace;

/* A checkpoint was serialized in seconds (its write's time comes later). */
void gi_ckpt_pace_begun(gi_ckpt_pace *p, double seconds);
/* Its write took seconds more. */
void gi_ckpt_pace_written(gi_ckpt_pace *p, double seconds);
/* Seconds between periodic checkpoints: every_s, or 20 times as long as the
 * cheaper of the last two took if that was a quarter second or more. A big
 * image's sums on a slow disk thus take the loop and the disk at most a
 * twentieth of the time; shorter checkpoints never matter; and one slowed
 * by a passing hiccup of the disk does not put the next one off (the
 * cheaper of two: only a disk slow twice in a row spaces them). */
double gi_ckpt_pace_interval(const gi_ckpt_pace *p, double every_s);

#endif
