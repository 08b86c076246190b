/* gi_pool: a pool of forked child processes that run tasks.
 *
 * The parent side: it forks children (each runs gi_child_main on its end of
 * a socketpair), sends them JOB and TASK frames, answers their ASSET_NEED,
 * and reports results, failures and crashes through callbacks. A child that
 * dies (crash, kill -9, protocol error) is reaped and reported with the task
 * it held; the owner decides whether to respawn it. Used by `gi render`
 * (embedded coordinator) and by gi-worker (remote hosts). */
#ifndef GI_POOL_H
#define GI_POOL_H

#include <poll.h>
#include <stdint.h>
#include <sys/types.h>

#include "gi_assets.h"
#include "gi_frame.h"
#include "gi_msg.h"
#include "gi_task.h"

typedef struct gi_pool_child {
    pid_t pid; /* 0 when not running */
    int fd;    /* -1 when not running */
    gi_frame_decoder dec;
    int busy;
    uint64_t job_id, task_id;
    uint32_t attempt;
    double started; /* monotonic (gi_now): when its task was sent (task time limits) */
    uint64_t jobs_sent[8]; /* recent jobs whose JOB this child has */
    int jobs_sent_count;
    /* The process whose descriptor the last gi_pool_pollfds listed: a child
     * replaced since (same slot, same fd number) must not get its events. */
    pid_t polled_pid;
} gi_pool_child;

typedef struct gi_pool_events {
    void *user;
    void (*result)(void *user, int child, gi_msg_result *r);
    void (*fail)(void *user, int child, gi_msg_fail *f);
    /* The child died or broke the protocol while holding a task. */
    void (*crash)(void *user, int child, uint64_t job_id, uint64_t task_id, uint32_t attempt,
                  const char *why);
    /* Bytes for an asset hash a child asks for, or NULL if unknown. */
    const gi_buf *(*asset)(void *user, const char *hash);
    /* Instead of `asset`, for owners that fetch bytes asynchronously (a
     * worker asking its coordinator): the owner answers later with
     * gi_pool_reply_asset; the child waits. */
    void (*asset_async)(void *user, int child, const char *hash);
} gi_pool_events;

typedef struct gi_pool {
    gi_pool_child *kids;
    int count;
    gi_frame_limits limits;
    int extra_fds[8]; /* closed in children after fork (e.g. a coordinator socket) */
    int extra_fd_count;
    unsigned spawned; /* children forked so far */
    /* Root of the host's per-job batch directories, passed to every child
     * (NULL: none; the string must outlive the pool). */
    const char *batch_root;
} gi_pool;

/* batch_root: see gi_pool.batch_root (NULL: none). */
int gi_pool_start(gi_pool *p, int count, const char *batch_root, gi_error *err);
/* (Re)forks child i. */
int gi_pool_spawn(gi_pool *p, int i, gi_error *err);
/* Asks children to exit (BYE), then reaps them (SIGKILL after a grace time). */
void gi_pool_stop(gi_pool *p);
/* Kills child i at once (SIGKILL) and reaps it; no crash callback. */
void gi_pool_kill(gi_pool *p, int i);

int gi_pool_alive(const gi_pool *p, int i);
/* Index of an idle living child, or -1. */
int gi_pool_idle_child(const gi_pool *p);

/* Forgets that the children have job_id's JOB: the next task of that id
 * sends it again (a coordinator may give an id a new job: its state was
 * wiped). */
void gi_pool_forget_job(gi_pool *p, uint64_t job_id);
/* Sends the JOB (once per child) and the TASK to child i, which must be idle. */
int gi_pool_assign(gi_pool *p, int i, uint64_t job_id, const char *job_file,
                   const char *job_text, const gi_manifest *manifest, const gi_task *task,
                   gi_error *err);

/* Answers child i's ASSET_NEED for `hash`: ASSET_PUT with the bytes, or
 * ERROR `why` when bytes is NULL (its code decides what the child's task
 * failure means: GI_EINVAL fails the job, others are retried). A send
 * failure is left for the child's socket to report. */
void gi_pool_reply_asset(gi_pool *p, int i, const char *hash, const gi_buf *bytes,
                         const gi_error *why);

/* For event loops that also watch other descriptors: fills pollfds for the
 * living children (returns how many, at most p->count), then dispatches what
 * poll() reported. */
int gi_pool_pollfds(gi_pool *p, struct pollfd *fds, int *child_of);
void gi_pool_dispatch(gi_pool *p, const struct pollfd *fds, const int *child_of, int n,
                      const gi_pool_events *ev);
/* poll() on the children alone, then dispatch. Returns poll's result. */
int gi_pool_poll(gi_pool *p, int timeout_ms, const gi_pool_events *ev);

#endif
