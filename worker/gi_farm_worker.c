/* gi_farm_worker: the worker host's connection, relay and drain logic. */
#include "gi_farm_worker.h"

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "gi_asset_cache.h"
#include "gi_auth.h"
#include "gi_batch_dir.h"
#include "gi_clock.h"
#include "gi_cores.h"
#include "gi_frame.h"
#include "gi_fs.h"
#include "gi_log.h"
#include "gi_msg.h"
#include "gi_msg_ctrl.h"
#include "gi_net.h"
#include "gi_netio.h"
#include "gi_pool.h"
#include "gi_version.h"

#define HANDSHAKE_S 10.0
#define MAX_DEFS 1024
#define READ_BUDGET ((size_t)8 << 20)
#define SWEEP_EVERY_S 3600.0

static volatile sig_atomic_t signals_seen;

void gi_farm_worker_signal(void)
{
    signals_seen++;
}

typedef struct job_def {
    uint64_t id;
    char *file, *text;
    gi_manifest manifest;
} job_def;

typedef struct queued_task {
    uint64_t job_id;
    gi_task task;
} queued_task;

/* A child waiting for an asset's bytes (pid: the answer must not go to a
 * child forked later in the same slot). */
typedef struct asset_wait {
    char hash[GI_HASH_HEX];
    int child;
    pid_t pid;
} asset_wait;

enum { SESSION_LOST, SESSION_STOP };

typedef struct worker {
    gi_worker_opts *o;
    uint8_t key[GI_AUTH_KEY_BYTES];
    gi_asset_cache cache;
    gi_pool pool;
    double tokens, tokens_at; /* respawn budget (token bucket) */
    char name[GI_MSG_MAX_NAME + 1];
    char *batch_root; /* per-job batch directories */
    double next_sweep;

    /* The session. */
    int fd;
    int established;
    int heard; /* bytes came from the coordinator on this connection */
    gi_frame_decoder dec;
    gi_outq out;
    double last_heard, next_hb;
    uint64_t hb_seq;
    double heartbeat_s, lease_s;
    uint32_t proto; /* the message set version the coordinator chose */
    job_def *defs;
    size_t def_count;
    queued_task *q;
    size_t q_count, q_cap;
    asset_wait *waits;
    size_t wait_count, wait_cap;
    char (*reqs)[GI_HASH_HEX]; /* ASSET_NEEDs sent, answered in order */
    size_t req_count, req_cap;
    int draining;
    double drain_deadline;
    int lost;
    char lost_why[600];
    /* The coordinator is on this host (a loopback address): results go
     * uncompressed, since zstd would only take CPU from the pool (a 1080p
     * frame's tiles: ~30 ms of it for 25 -> 11.5 MB that cost nothing to
     * send here). */
    int loopback;
} worker;

static void lose(worker *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void lose(worker *w, const char *fmt, ...)
{
    if (w->lost)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w->lost_why, sizeof w->lost_why, fmt, ap);
    va_end(ap);
    w->lost = 1;
}

static void send_frame(worker *w, uint16_t type, const gi_buf *b, int compress)
{
    if (w->fd < 0)
        return;
    gi_outq_push(&w->out, type, b, compress);
}

/* ---- job definitions and the task queue ----------------------------------- */

static job_def *def_find(worker *w, uint64_t id)
{
    for (size_t i = 0; i < w->def_count; i++)
        if (w->defs[i].id == id)
            return &w->defs[i];
    return NULL;
}

static void def_free(job_def *d)
{
    free(d->file);
    free(d->text);
    gi_manifest_free(&d->manifest);
}

static void def_drop(worker *w, uint64_t id)
{
    for (size_t i = 0; i < w->def_count; i++)
        if (w->defs[i].id == id) {
            def_free(&w->defs[i]);
            w->defs[i] = w->defs[--w->def_count];
            return;
        }
}

/* The job's batch directory (malloc'ed). */
static char *def_batch_dir(const worker *w, const job_def *d)
{
    return gi_batch_dir_path(w->batch_root, d->id, d->text);
}

/* Removes the batch directories idle for long, except those of the jobs
 * this worker has now. */
static void sweep_batches(worker *w)
{
    char **keep = gi_xcalloc(w->def_count + 1, sizeof *keep);
    for (size_t i = 0; i < w->def_count; i++)
        keep[i] = def_batch_dir(w, &w->defs[i]);
    int n = gi_batch_dir_sweep(w->batch_root, GI_BATCH_DIR_MAX_AGE_S, (const char *const *)keep);
    if (n)
        gi_info("removed %d batch directories idle for more than %.0f days", n,
                GI_BATCH_DIR_MAX_AGE_S / 86400.0);
    for (size_t i = 0; i < w->def_count; i++)
        free(keep[i]);
    free(keep);
}

static void def_add(worker *w, gi_msg_job *m)
{
    def_drop(w, m->job_id);
    /* The children get it again with their next task of it: the same id may
     * be a new job (the coordinator's state was wiped), and a child must not
     * run it as the old one. */
    gi_pool_forget_job(&w->pool, m->job_id);
    /* The coordinator sends a job's JOB once per connection and CANCELs it
     * when the job ends, so definitions are never evicted here (a TASK
     * would then arrive without one); a coordinator that keeps more jobs
     * than this on one worker is refused instead. */
    if (w->def_count == MAX_DEFS) {
        lose(w, "the coordinator sent more than %d jobs at once", MAX_DEFS);
        gi_msg_job_free(m);
        return;
    }
    if (!w->defs)
        w->defs = gi_xcalloc(MAX_DEFS, sizeof *w->defs);
    job_def *d = &w->defs[w->def_count++];
    d->id = m->job_id;
    d->file = m->file;
    d->text = m->text;
    d->manifest = m->manifest;
    m->file = m->text = NULL;
    gi_manifest_init(&m->manifest);
    /* The coordinator still runs this job: what its directory holds (from
     * before a reconnection or a restart of this worker) is worth keeping. */
    char *dir = def_batch_dir(w, d);
    gi_batch_dir_touch(dir);
    free(dir);
}

static gi_msg_taskref ref_of(uint64_t job, const gi_task *t)
{
    gi_msg_taskref r = {job, t->id, t->attempt, 0, 0};
    return r;
}

/* Tells the coordinator these tasks go back unrun. */
static void hand_back(worker *w, const gi_msg_taskref *refs, uint32_t n)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_tasklist_encode(&b, 0, refs, n, 0);
    send_frame(w, GI_MSG_DRAIN, &b, 0);
    gi_buf_free(&b);
}

static void queue_clear(worker *w)
{
    for (size_t i = 0; i < w->q_count; i++)
        gi_task_free(&w->q[i].task);
    w->q_count = 0;
}

/* DRAIN with every queued task; the queue is emptied. */
static void hand_back_queue(worker *w)
{
    gi_msg_taskref *refs = gi_xcalloc(w->q_count + 1, sizeof *refs);
    for (size_t i = 0; i < w->q_count; i++)
        refs[i] = ref_of(w->q[i].job_id, &w->q[i].task);
    hand_back(w, refs, (uint32_t)w->q_count);
    free(refs);
    queue_clear(w);
}

/* ---- assets ---------------------------------------------------------------- */

static void wait_drop_child(worker *w, int child)
{
    for (size_t i = 0; i < w->wait_count;)
        if (w->waits[i].child == child)
            w->waits[i] = w->waits[--w->wait_count];
        else
            i++;
}

/* Answers every child waiting for hash (bytes NULL: with the error why). */
static void answer_waiters(worker *w, const char *hash, const gi_buf *bytes, const gi_error *why)
{
    for (size_t i = 0; i < w->wait_count;) {
        asset_wait *a = &w->waits[i];
        if (strcmp(a->hash, hash) != 0) {
            i++;
            continue;
        }
        if (w->pool.kids[a->child].pid == a->pid)
            gi_pool_reply_asset(&w->pool, a->child, hash, bytes, why);
        *a = w->waits[--w->wait_count];
    }
}

static void on_asset_async(void *user, int child, const char *hash)
{
    worker *w = user;
    gi_buf b;
    gi_buf_init(&b);
    gi_error err;
    int got = gi_asset_cache_get(&w->cache, hash, &b, &err);
    if (got < 0)
        gi_warn("%s", err.msg);
    if (got > 0) {
        gi_pool_reply_asset(&w->pool, child, hash, &b, NULL);
        gi_buf_free(&b);
        return;
    }
    gi_buf_free(&b);
    if (w->fd < 0) {
        gi_error e;
        gi_fail(&e, GI_EIO, "asset %.12s: no connection to the coordinator", hash);
        gi_pool_reply_asset(&w->pool, child, hash, NULL, &e);
        return;
    }
    if (w->wait_count == w->wait_cap) {
        w->wait_cap = w->wait_cap ? 2 * w->wait_cap : 8;
        w->waits = gi_xrealloc(w->waits, w->wait_cap * sizeof *w->waits);
    }
    asset_wait *a = &w->waits[w->wait_count++];
    memcpy(a->hash, hash, GI_HASH_HEX);
    a->child = child;
    a->pid = w->pool.kids[child].pid;
    for (size_t i = 0; i < w->req_count; i++)
        if (strcmp(w->reqs[i], hash) == 0)
            return; /* already asked */
    if (w->req_count == w->req_cap) {
        w->req_cap = w->req_cap ? 2 * w->req_cap : 8;
        w->reqs = gi_xrealloc(w->reqs, w->req_cap * sizeof *w->reqs);
    }
    memcpy(w->reqs[w->req_count++], hash, GI_HASH_HEX);
    gi_buf need;
    gi_buf_init(&need);
    gi_msg_asset_need_encode(&need, hash);
    send_frame(w, GI_MSG_ASSET_NEED, &need, 0);
    gi_buf_free(&need);
}

static void req_remove(worker *w, const char *hash)
{
    for (size_t i = 0; i < w->req_count; i++)
        if (strcmp(w->reqs[i], hash) == 0) {
            memmove(&w->reqs[i], &w->reqs[i + 1], (w->req_count - i - 1) * sizeof *w->reqs);
            w->req_count--;
            return;
        }
}

static void on_asset_put(worker *w, const gi_frame *fr)
{
    char hash[GI_HASH_HEX];
    const uint8_t *data;
    size_t len;
    gi_error err;
    if (gi_msg_asset_put_decode(&fr->payload, hash, &data, &len, &err)) {
        lose(w, "%s", err.msg);
        return;
    }
    if (gi_asset_cache_put(&w->cache, hash, data, len, &err))
        gi_warn("%s (serving the asset from memory)", err.msg);
    gi_buf b = {(uint8_t *)data, len, len}; /* borrowed view for the replies */
    answer_waiters(w, hash, &b, NULL);
    req_remove(w, hash);
}

/* ---- pool events ------------------------------------------------------------- */

static void on_result(void *user, int child, gi_msg_result *r)
{
    worker *w = user;
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_result_encode(&b, r->job_id, r->task_id, r->attempt, &r->stats, r->data.data,
                         r->data.len);
    send_frame(w, GI_MSG_RESULT, &b, !w->loopback);
    gi_buf_free(&b);
}

static void send_fail(worker *w, uint64_t job, uint64_t task, uint32_t attempt, const gi_error *e)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_fail_encode(&b, job, task, attempt, e);
    send_frame(w, GI_MSG_FAIL, &b, 0);
    gi_buf_free(&b);
}

static void on_fail(void *user, int child, gi_msg_fail *f)
{
    worker *w = user;
    gi_warn("task %llu of job %llu failed: %s", (unsigned long long)f->task_id,
            (unsigned long long)f->job_id, f->error.msg);
    send_fail(w, f->job_id, f->task_id, f->attempt, &f->error);
}

static void on_crash(void *user, int child, uint64_t job, uint64_t task, uint32_t attempt,
                     const char *why)
{
    worker *w = user;
    wait_drop_child(w, child);
    gi_error e;
    gi_fail(&e, GI_ECRASH, "%s: %s", w->name, why);
    send_fail(w, job, task, attempt, &e);
}

/* Kills child i (its task is abandoned) and forks a fresh one. */
static void replace_child(worker *w, int i)
{
    wait_drop_child(w, i);
    gi_pool_kill(&w->pool, i);
    gi_error err;
    if (gi_pool_spawn(&w->pool, i, &err))
        gi_warn("respawning pool child %d: %s", i, err.msg);
}

/* Crashed children come back, but at most one per process every 2 s on
 * average (after a burst of 2 x procs + 4): a host whose children keep
 * dying slows down instead of forking in a loop. */
static void respawn(worker *w, double now)
{
    double rate = w->pool.count / 2.0, burst = 2.0 * w->pool.count + 4;
    w->tokens += (now - w->tokens_at) * rate;
    if (w->tokens > burst)
        w->tokens = burst;
    w->tokens_at = now;
    for (int i = 0; i < w->pool.count; i++) {
        if (gi_pool_alive(&w->pool, i) || w->tokens < 1.0)
            continue;
        gi_error err;
        if (gi_pool_spawn(&w->pool, i, &err) == 0)
            w->tokens -= 1.0;
        else
            gi_warn("respawning pool child %d: %s", i, err.msg);
    }
}

static void assign(worker *w)
{
    int i;
    while (w->q_count && (i = gi_pool_idle_child(&w->pool)) >= 0) {
        queued_task qt = w->q[0];
        memmove(&w->q[0], &w->q[1], (w->q_count - 1) * sizeof *w->q);
        w->q_count--;
        job_def *d = def_find(w, qt.job_id);
        gi_error err;
        if (!d) {
            gi_fail(&err, GI_EPROTO, "%s: task %llu of job %llu came without its JOB", w->name,
                    (unsigned long long)qt.task.id, (unsigned long long)qt.job_id);
            send_fail(w, qt.job_id, qt.task.id, qt.task.attempt, &err);
        } else if (gi_pool_assign(&w->pool, i, qt.job_id, d->file, d->text, &d->manifest,
                                  &qt.task, &err)) {
            /* The child's death reports the task (as a crash). */
            gi_debug("sending a task to pool child %d: %s", i, err.msg);
        }
        gi_task_free(&qt.task);
    }
}

/* ---- coordinator frames ------------------------------------------------------- */

static void on_task(worker *w, const gi_frame *fr)
{
    gi_msg_task m;
    gi_error err;
    if (gi_msg_task_decode(&fr->payload, &m, &err)) {
        lose(w, "%s", err.msg);
        return;
    }
    if (w->draining) {
        gi_msg_taskref r = ref_of(m.job_id, &m.task);
        hand_back(w, &r, 1);
        gi_task_free(&m.task);
        return;
    }
    if (w->q_count == w->q_cap) {
        w->q_cap = w->q_cap ? 2 * w->q_cap : 16;
        w->q = gi_xrealloc(w->q, w->q_cap * sizeof *w->q);
    }
    w->q[w->q_count].job_id = m.job_id;
    w->q[w->q_count].task = m.task;
    w->q_count++;
}

static void on_cancel(worker *w, const gi_frame *fr)
{
    gi_msg_cancel m;
    gi_error err;
    if (gi_msg_cancel_decode(&fr->payload, &m, &err)) {
        lose(w, "%s", err.msg);
        return;
    }
    int stopped = m.task_id == GI_MSG_JOB_STOPPED;
    int all = m.task_id == GI_MSG_ALL_TASKS || stopped;
    unsigned queued = 0, running = 0;
    for (size_t i = 0; i < w->q_count;) {
        if (w->q[i].job_id == m.job_id && (all || w->q[i].task.id == m.task_id)) {
            gi_task_free(&w->q[i].task);
            memmove(&w->q[i], &w->q[i + 1], (w->q_count - i - 1) * sizeof *w->q);
            w->q_count--;
            queued++;
        } else {
            i++;
        }
    }
    for (int i = 0; i < w->pool.count; i++) {
        const gi_pool_child *k = &w->pool.kids[i];
        if (k->pid && k->busy && k->job_id == m.job_id && (all || k->task_id == m.task_id)) {
            replace_child(w, i); /* the task is abandoned with its process */
            running++;
        }
    }
    if (all) {
        /* The job is over on the coordinator, which tells every worker: its
         * batch files are useless, this run's and any an earlier run of this
         * worker kept (it restarted since; its directory bears the id).
         * Unless it only stopped: a retry will want them (the 3-day sweep
         * bounds them). */
        int had = def_find(w, m.job_id) != NULL;
        int removed = stopped ? 0 : gi_batch_dir_remove_job(w->batch_root, m.job_id);
        def_drop(w, m.job_id);
        if (!had && !queued && !running) {
            if (removed)
                gi_info("job %llu is over: removed the batch files an earlier run of this "
                        "worker kept",
                        (unsigned long long)m.job_id);
            return; /* not this run's job */
        }
    }
    gi_info("job %llu %s: %u queued and %u running tasks dropped", (unsigned long long)m.job_id,
            stopped ? "stopped (batch files kept)" : all ? "is over" : "task cancelled", queued,
            running);
}

static void on_coord_frame(worker *w, const gi_frame *fr)
{
    gi_error err;
    switch (fr->type) {
    case GI_MSG_JOB: {
        gi_msg_job m;
        if (gi_msg_job_decode(&fr->payload, &m, &err)) {
            lose(w, "%s", err.msg);
            return;
        }
        def_add(w, &m);
        gi_msg_job_free(&m);
        break;
    }
    case GI_MSG_TASK:
        on_task(w, fr);
        break;
    case GI_MSG_ASSET_PUT:
        on_asset_put(w, fr);
        break;
    case GI_MSG_CANCEL:
        on_cancel(w, fr);
        break;
    case GI_MSG_HEARTBEAT: {
        gi_msg_tasklist tl;
        if (gi_msg_tasklist_decode(&fr->payload, "HEARTBEAT message", w->proto >= GI_PROTO_RUNS,
                                   &tl, &err))
            lose(w, "%s", err.msg);
        gi_msg_tasklist_free(&tl);
        break;
    }
    case GI_MSG_ERROR: {
        gi_error e;
        if (gi_msg_error_decode(&fr->payload, &e, &err)) {
            lose(w, "%s", err.msg);
            return;
        }
        if (w->req_count) {
            /* The coordinator answers ASSET_NEEDs in order. */
            char hash[GI_HASH_HEX];
            memcpy(hash, w->reqs[0], GI_HASH_HEX);
            req_remove(w, hash);
            answer_waiters(w, hash, NULL, &e);
            break;
        }
        lose(w, "the coordinator says: %s", e.msg);
        break;
    }
    case GI_MSG_BYE:
        lose(w, "the coordinator said goodbye");
        break;
    default:
        lose(w, "unexpected %s from the coordinator", gi_msg_type_name(fr->type));
    }
}

/* Handles every complete frame the decoder holds. */
static void drain_frames(worker *w)
{
    while (!w->lost) {
        gi_frame fr;
        gi_error err;
        int got = gi_frame_decoder_next(&w->dec, &fr, &err);
        if (got == 0)
            return;
        if (got < 0) {
            lose(w, "%s", err.msg);
            return;
        }
        on_coord_frame(w, &fr);
        gi_frame_free(&fr);
    }
}

static void coord_readable(worker *w)
{
    size_t budget = READ_BUDGET;
    while (!w->lost) {
        ssize_t n = gi_frame_decoder_recv(&w->dec, w->fd, budget);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK)) {
            lose(w, n == 0 ? "the coordinator closed the connection" : "connection error: %s",
                 strerror(errno));
            return;
        }
        if (n > 0) {
            budget -= (size_t)n;
            w->last_heard = gi_now();
        }
        drain_frames(w);
        if (n < 0 || budget == 0)
            return;
    }
}

static void coord_writable(worker *w)
{
    if (gi_outq_flush(&w->out, w->fd) != 0)
        lose(w, "send: %s", strerror(errno));
}

/* Blocking flush with a time limit (before hanging up). */
static void flush(worker *w, double seconds)
{
    double end = gi_now() + seconds;
    while (!w->lost && gi_outq_pending(&w->out) && gi_now() < end) {
        struct pollfd p = {.fd = w->fd, .events = POLLOUT};
        if (poll(&p, 1, 100) > 0)
            coord_writable(w);
    }
}

/* ---- handshake ---------------------------------------------------------------- */

/* A handshake that heard nothing, or HTTP: the usual cause is a --connect
 * naming the API port (HTTP waits for a request, says nothing, and closes
 * when its --api-head-seconds run out; or it takes the HELLO for a
 * malformed request and answers 400). */
static int silent_peer(const char *what, gi_error *err)
{
    return gi_fail(err, GI_EIO,
                   "%s: is that gi-farmd's worker port (its --listen-workers, 7071 by default), "
                   "not its API port (--listen-api, 7070)?", what);
}

/* Reads one frame within the deadline. */
static int recv_frame(worker *w, double deadline, gi_frame *fr, gi_error *err)
{
    char what[160];
    for (;;) {
        int got = gi_frame_decoder_next(&w->dec, fr, err);
        if (got)
            return got < 0 ? -1 : 0;
        double left = deadline - gi_now();
        if (left <= 0) {
            snprintf(what, sizeof what, "no answer from the coordinator at %s within %.0f s",
                     w->o->connect, HANDSHAKE_S);
            return silent_peer(what, err);
        }
        struct pollfd p = {.fd = w->fd, .events = POLLIN};
        int r = poll(&p, 1, (int)(left * 1000) + 1);
        if (r < 0 && errno != EINTR)
            return gi_fail(err, GI_EIO, "poll: %s", strerror(errno));
        if (r <= 0)
            continue;
        uint8_t buf[4096];
        ssize_t n = recv(w->fd, buf, sizeof buf, 0);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0 && !w->heard) {
            snprintf(what, sizeof what, "the coordinator at %s closed the connection during the "
                     "handshake without a word", w->o->connect);
            return silent_peer(what, err);
        }
        if (n <= 0)
            return gi_fail(err, GI_EIO, "the coordinator closed the connection during the handshake");
        if (!w->heard && n >= 5 && memcmp(buf, "HTTP/", 5) == 0) {
            snprintf(what, sizeof what, "the coordinator at %s answered in HTTP", w->o->connect);
            return silent_peer(what, err);
        }
        w->heard = 1;
        gi_frame_decoder_feed(&w->dec, buf, (size_t)n);
    }
}

/* Reads the next handshake frame, which must be of `type`; an ERROR is the
 * coordinator's refusal and becomes err. The caller frees fr's payload. */
static int expect(worker *w, double deadline, uint16_t type, gi_frame *fr, gi_error *err)
{
    if (recv_frame(w, deadline, fr, err))
        return -1;
    if (fr->type == type)
        return 0;
    gi_error e, derr;
    if (fr->type != GI_MSG_ERROR)
        gi_fail(err, GI_EPROTO, "expected %s, got %s", gi_msg_type_name(type),
                gi_msg_type_name(fr->type));
    else if (gi_msg_error_decode(&fr->payload, &e, &derr))
        gi_fail(err, GI_EPROTO, "%s", derr.msg);
    else
        gi_fail(err, e.code == GI_OK ? GI_EPROTO : e.code, "the coordinator refused: %s", e.msg);
    gi_frame_free(fr);
    return -1;
}

static int handshake(worker *w, gi_error *err)
{
    double deadline = gi_now() + HANDSHAKE_S;
    gi_msg_hello h;
    memset(&h, 0, sizeof h);
    h.proto_min = GI_PROTO_MIN;
    h.proto_max = GI_PROTO_MAX;
    /* For tests of a mixed farm: this worker speaks as an older build. */
    const char *older_env = getenv(GI_FAULT_PROTO_MAX_ENV);
    int older = older_env ? atoi(older_env) : 0;
    if (older >= GI_PROTO_MIN && older < GI_PROTO_MAX)
        h.proto_max = (uint32_t)older;
    gi_auth_random(h.nonce, sizeof h.nonce);
    h.name = w->name;
    h.version = (char *)GI_VERSION;
    h.procs = (uint32_t)w->pool.count;
    h.slots = (uint32_t)(w->pool.count + w->o->queue);
    h.cores = (uint32_t)gi_cores_usable();
    long pages = sysconf(_SC_PHYS_PAGES), psize = sysconf(_SC_PAGESIZE);
    h.memory = pages > 0 && psize > 0 ? (uint64_t)pages * (uint64_t)psize : 0;
    gi_buf hello;
    gi_buf_init(&hello);
    gi_msg_hello_encode(&hello, &h);
    int rc = gi_frame_send(w->fd, GI_MSG_HELLO, hello.data, hello.len, 0, err);
    gi_frame fr;
    gi_msg_challenge ch;
    if (rc == 0 && (rc = expect(w, deadline, GI_MSG_CHALLENGE, &fr, err)) == 0) {
        rc = gi_msg_challenge_decode(&fr.payload, &ch, err);
        gi_frame_free(&fr);
    }
    if (rc == 0 && (ch.proto < h.proto_min || ch.proto > h.proto_max))
        rc = gi_fail(err, GI_EPROTO, "the coordinator chose protocol version %u (this worker "
                     "speaks %u-%u)", ch.proto, h.proto_min, h.proto_max);
    if (rc == 0) {
        uint8_t mac[GI_MSG_MAC_BYTES];
        gi_auth_worker_mac(w->key, ch.nonce, h.nonce, hello.data, hello.len, mac);
        gi_buf b;
        gi_buf_init(&b);
        gi_msg_auth_encode(&b, mac);
        rc = gi_frame_send(w->fd, GI_MSG_AUTH, b.data, b.len, 0, err);
        gi_buf_free(&b);
    }
    gi_msg_welcome wm;
    if (rc == 0 && (rc = expect(w, deadline, GI_MSG_WELCOME, &fr, err)) == 0) {
        rc = gi_msg_welcome_decode(&fr.payload, &wm, err);
        gi_frame_free(&fr);
    }
    if (rc == 0) {
        uint8_t want[GI_MSG_MAC_BYTES];
        gi_auth_coord_mac(w->key, h.nonce, ch.nonce, wm.worker_id, want);
        if (!gi_auth_mac_equal(want, wm.mac))
            rc = gi_fail(err, GI_EPROTO,
                         "the coordinator could not prove it knows the farm secret; not "
                         "working for it");
    }
    gi_buf_free(&hello);
    if (rc)
        return -1;
    w->heartbeat_s = wm.heartbeat_ms / 1000.0;
    w->lease_s = wm.lease_ms / 1000.0;
    w->proto = ch.proto;
    gi_info("connected to %s as worker %llu (heartbeat %.2f s, lease %.1f s)", w->o->connect,
            (unsigned long long)wm.worker_id, w->heartbeat_s, w->lease_s);
    return 0;
}

/* ---- the session --------------------------------------------------------------- */

static void heartbeat(worker *w)
{
    size_t n = 0;
    gi_msg_taskref *refs = gi_xcalloc(w->q_count + (size_t)w->pool.count + 1, sizeof *refs);
    /* The running ones first (never cut by the list's limit), saying for
     * how long: the coordinator counts their time limits from there (a
     * queued task waits off the clock). */
    double now = gi_now();
    for (int i = 0; i < w->pool.count; i++) {
        const gi_pool_child *k = &w->pool.kids[i];
        if (!k->pid || !k->busy)
            continue;
        double ms = (now - k->started) * 1000.0;
        uint32_t run_ms = ms <= 0 ? 0 : ms >= (double)UINT32_MAX ? UINT32_MAX : (uint32_t)ms;
        refs[n++] = (gi_msg_taskref){k->job_id, k->task_id, k->attempt, 1, run_ms};
    }
    for (size_t i = 0; i < w->q_count; i++)
        refs[n++] = ref_of(w->q[i].job_id, &w->q[i].task);
    if (n > GI_MSG_MAX_TASKREFS)
        n = GI_MSG_MAX_TASKREFS;
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_tasklist_encode(&b, ++w->hb_seq, refs, (uint32_t)n, w->proto >= GI_PROTO_RUNS);
    send_frame(w, GI_MSG_HEARTBEAT, &b, 0);
    gi_buf_free(&b);
    free(refs);
}

static int busy_children(const worker *w)
{
    int n = 0;
    for (int i = 0; i < w->pool.count; i++)
        n += w->pool.kids[i].pid && w->pool.kids[i].busy;
    return n;
}

/* Ends the session: abandons what the coordinator has already reassigned
 * (or will, once it notices). */
static void end_session(worker *w)
{
    for (int i = 0; i < w->pool.count; i++)
        if (w->pool.kids[i].pid && w->pool.kids[i].busy)
            replace_child(w, i);
    queue_clear(w);
    for (size_t i = 0; i < w->def_count; i++)
        def_free(&w->defs[i]);
    w->def_count = 0;
    w->wait_count = 0;
    w->req_count = 0;
    if (w->fd >= 0)
        close(w->fd);
    w->fd = -1;
    w->pool.extra_fd_count = 0;
    gi_frame_decoder_free(&w->dec);
    gi_outq_free(&w->out);
}

/* Stops: hands back what has not run (and, at once, what is running), says
 * goodbye. */
static int stop_now(worker *w, int kill_running)
{
    hand_back_queue(w);
    if (kill_running) {
        gi_msg_taskref refs[1024];
        uint32_t n = 0;
        for (int i = 0; i < w->pool.count && n < GI_ARRAY_LEN(refs); i++) {
            const gi_pool_child *k = &w->pool.kids[i];
            if (k->pid && k->busy) {
                refs[n++] = (gi_msg_taskref){k->job_id, k->task_id, k->attempt, 0, 0};
                replace_child(w, i);
            }
        }
        if (n)
            hand_back(w, refs, n);
    }
    send_frame(w, GI_MSG_BYE, NULL, 0);
    flush(w, 5.0);
    return SESSION_STOP;
}

static int session(worker *w, gi_error *err)
{
    w->heard = 0;
    w->fd = gi_net_connect(w->o->connect, HANDSHAKE_S, err);
    if (w->fd < 0)
        return SESSION_LOST;
    w->loopback = gi_net_peer_is_loopback(w->fd);
    w->pool.extra_fds[0] = w->fd;
    w->pool.extra_fd_count = 1;
    char peer[120];
    snprintf(peer, sizeof peer, "coordinator %s", w->o->connect);
    gi_frame_decoder_init(&w->dec, NULL, peer);
    gi_outq_init(&w->out);
    w->lost = 0;
    w->draining = 0;
    if (handshake(w, err)) {
        end_session(w);
        return SESSION_LOST;
    }
    w->established = 1;
    double now = gi_now();
    w->last_heard = now;
    w->next_hb = now;
    double dead_s = 4.0 * w->lease_s > 10.0 ? 4.0 * w->lease_s : 10.0;
    struct pollfd *fds = gi_xcalloc((size_t)w->pool.count + 1, sizeof *fds);
    int *child_of = gi_xcalloc((size_t)w->pool.count + 1, sizeof *child_of);
    gi_pool_events ev = {w, on_result, on_fail, on_crash, NULL, on_asset_async};
    int result = SESSION_LOST;
    while (!w->lost) {
        now = gi_now();
        if (signals_seen >= 2) {
            gi_warn("second signal: stopping now, handing every task back");
            result = stop_now(w, 1);
            break;
        }
        if (signals_seen == 1 && !w->draining) {
            gi_warn("draining: %zu queued tasks handed back, finishing %d running ones "
                    "(at most %.0f s)",
                    w->q_count, busy_children(w), w->o->drain_s);
            hand_back_queue(w);
            w->draining = 1;
            w->drain_deadline = now + w->o->drain_s;
        }
        if (w->draining && busy_children(w) == 0) {
            result = stop_now(w, 0);
            break;
        }
        if (w->draining && now > w->drain_deadline) {
            gi_warn("drain time is up: abandoning the running tasks");
            result = stop_now(w, 1);
            break;
        }
        drain_frames(w); /* frames that arrived with the handshake's last one */
        if (now >= w->next_sweep) {
            sweep_batches(w);
            w->next_sweep = now + SWEEP_EVERY_S;
        }
        respawn(w, now);
        assign(w);
        if (now >= w->next_hb) {
            heartbeat(w);
            w->next_hb = now + w->heartbeat_s;
        }
        if (now - w->last_heard > dead_s) {
            lose(w, "the coordinator has been silent for %.0f s", now - w->last_heard);
            break;
        }
        fds[0] = (struct pollfd){.fd = w->fd, .events = POLLIN};
        if (gi_outq_pending(&w->out))
            fds[0].events |= POLLOUT;
        int n = gi_pool_pollfds(&w->pool, fds + 1, child_of + 1);
        int rc = poll(fds, (nfds_t)n + 1, 100);
        if (rc < 0 && errno != EINTR) {
            lose(w, "poll: %s", strerror(errno));
            break;
        }
        if (rc <= 0)
            continue;
        if (fds[0].revents & POLLOUT)
            coord_writable(w);
        if (fds[0].revents & (POLLIN | POLLHUP | POLLERR))
            coord_readable(w);
        gi_pool_dispatch(&w->pool, fds + 1, child_of + 1, n, &ev);
        if (gi_outq_pending(&w->out))
            coord_writable(w); /* send results without waiting a round */
    }
    free(fds);
    free(child_of);
    if (w->lost && result == SESSION_LOST)
        gi_fail(err, GI_EIO, "%s", w->lost_why);
    end_session(w);
    return result;
}

/* Sleeps up to s seconds; returns early on a signal. */
static void nap(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

int gi_farm_worker_run(gi_worker_opts *o, gi_error *err)
{
    worker w;
    memset(&w, 0, sizeof w);
    w.o = o;
    w.fd = -1;
    gi_auth_key(&o->secret, w.key);
    if (o->name) {
        snprintf(w.name, sizeof w.name, "%s", o->name);
    } else if (gethostname(w.name, sizeof w.name - 1) != 0 || !w.name[0]) {
        snprintf(w.name, sizeof w.name, "worker-%ld", (long)getpid());
    }
    if (gi_asset_cache_open(&w.cache, o->cache_dir, o->cache_max, err))
        return -1;
    w.batch_root = o->batch_dir ? gi_xstrdup(o->batch_dir) : gi_path_join(o->cache_dir, "batches");
    /* Proved writable now: found at the first task, it would fail every
     * task sent here and get the host blocklisted with no word to a user. */
    if (gi_output_dir_ready(w.batch_root, err)) {
        gi_error_prefix(err, "batch directory");
        gi_asset_cache_close(&w.cache);
        free(w.batch_root);
        return -1;
    }
    /* Left by an earlier run of this worker: kept while recent (the
     * coordinator may send the same jobs again), swept when idle for long. */
    sweep_batches(&w);
    w.next_sweep = gi_now() + SWEEP_EVERY_S;
    if (gi_pool_start(&w.pool, o->procs, w.batch_root, err)) {
        gi_asset_cache_close(&w.cache);
        free(w.batch_root);
        return -1;
    }
    w.tokens = 2.0 * o->procs + 4;
    w.tokens_at = gi_now();
    double backoff = 0.25;
    int rc = -1, said_refused = 0, ever = 0; /* ever: a session was established */
    gi_error serr;
    for (;;) {
        if (signals_seen) {
            rc = 0; /* nothing held while disconnected: nothing to drain */
            break;
        }
        w.established = 0;
        gi_error_clear(&serr);
        int s = session(&w, &serr);
        if (s == SESSION_STOP) {
            rc = 0;
            break;
        }
        if (serr.code == GI_OK)
            gi_fail(&serr, GI_EIO, "the session ended");
        /* Once: a worker started before its coordinator, or pointed at
         * the wrong address, must not look like a worker that is fine. */
        ever |= w.established;
        if (!ever && !said_refused && !o->once && serr.sys_errno == ECONNREFUSED) {
            gi_warn("%s (no gi-farmd listening for workers there yet: is it running, with "
                    "--listen-workers %s? asking again, at most --backoff-max %.0f s apart)",
                    serr.msg, o->connect, o->backoff_max_s);
            said_refused = 1;
        } else {
            gi_warn("%s", serr.msg);
        }
        if (o->once) {
            if (err)
                *err = serr;
            rc = -1;
            break;
        }
        if (w.established)
            backoff = 0.25;
        /* Jitter, so a restarted coordinator is not hit by every worker at
         * once; --backoff-max bounds the wait itself. */
        double wait = backoff * (0.5 + (double)(rand() % 1000) / 1000.0);
        if (wait > o->backoff_max_s)
            wait = o->backoff_max_s;
        gi_info("reconnecting in %.1f s", wait);
        nap(wait);
        backoff = backoff * 2 > o->backoff_max_s ? o->backoff_max_s : backoff * 2;
    }
    gi_pool_stop(&w.pool);
    gi_asset_cache_close(&w.cache);
    free(w.batch_root);
    free(w.defs);
    free(w.q);
    free(w.waits);
    free(w.reqs);
    memset(w.key, 0, sizeof w.key);
    return rc;
}
