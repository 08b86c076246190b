/* gi_pool: forked task-running children, parent side. */
#include "gi_pool.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "gi_child.h"
#include "gi_clock.h"
#include "gi_log.h"
#include "gi_netio.h"

int gi_pool_start(gi_pool *p, int count, const char *batch_root, gi_error *err)
{
    memset(p, 0, sizeof *p);
    p->batch_root = batch_root;
    if (count < 1 || count > 1024)
        return gi_fail(err, GI_EINVAL, "pool size %d is out of range [1, 1024]", count);
    p->count = count;
    p->limits = gi_frame_limits_default();
    p->kids = gi_xcalloc((size_t)count, sizeof *p->kids);
    for (int i = 0; i < count; i++)
        p->kids[i].fd = -1;
    signal(SIGPIPE, SIG_IGN);
    for (int i = 0; i < count; i++)
        if (gi_pool_spawn(p, i, err)) {
            gi_pool_stop(p);
            return -1;
        }
    return 0;
}

int gi_pool_spawn(gi_pool *p, int i, gi_error *err)
{
    gi_pool_child *k = &p->kids[i];
    if (k->pid)
        gi_pool_kill(p, i);
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        return gi_fail(err, GI_EIO, "socketpair: %s", strerror(errno));
    fflush(NULL); /* no duplicated stdio buffers in the child */
    pid_t pid = fork();
    if (pid < 0) {
        close(sv[0]);
        close(sv[1]);
        return gi_fail(err, GI_EIO, "fork: %s", strerror(errno));
    }
    if (pid == 0) {
        /* Child: drop every descriptor that belongs to the parent's side. */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        close(sv[0]);
        for (int j = 0; j < p->count; j++)
            if (p->kids[j].fd >= 0)
                close(p->kids[j].fd);
        for (int j = 0; j < p->extra_fd_count; j++)
            close(p->extra_fds[j]);
        /* A terminal's Ctrl-C reaches the whole process group: the parent
         * decides what stops (it kills children itself), so a child does
         * not die of it mid-task. */
        signal(SIGINT, SIG_IGN);
        signal(SIGTERM, SIG_DFL);
        _exit(gi_child_main(sv[1], p->batch_root));
    }
    close(sv[1]);
    k->pid = pid;
    k->fd = sv[0];
    k->busy = 0;
    k->jobs_sent_count = 0;
    gi_frame_decoder_init(&k->dec, &p->limits, "pool child");
    p->spawned++;
    return 0;
}

/* Reaps child i (which is exiting or killed); describes how it ended. */
static void reap(gi_pool *p, int i, char *why, size_t n)
{
    gi_pool_child *k = &p->kids[i];
    if (k->fd >= 0)
        close(k->fd);
    k->fd = -1;
    int status = 0;
    if (k->pid) {
        /* Its socket is closed: give it a moment to exit, then insist. */
        int waited = 0;
        for (int tries = 0; tries < 200; tries++) {
            if (waitpid(k->pid, &status, WNOHANG) == k->pid) {
                waited = 1;
                break;
            }
            struct timespec ts = {0, 5 * 1000 * 1000};
            nanosleep(&ts, NULL);
        }
        if (!waited) {
            kill(k->pid, SIGKILL);
            waitpid(k->pid, &status, 0);
        }
        if (why) {
            if (WIFSIGNALED(status))
                snprintf(why, n, "pool child %d (pid %ld) was killed by signal %d", i,
                         (long)k->pid, WTERMSIG(status));
            else
                snprintf(why, n, "pool child %d (pid %ld) exited with status %d", i,
                         (long)k->pid, WEXITSTATUS(status));
        }
    }
    gi_frame_decoder_free(&k->dec);
    k->pid = 0;
    k->busy = 0;
}

void gi_pool_kill(gi_pool *p, int i)
{
    gi_pool_child *k = &p->kids[i];
    if (k->pid)
        kill(k->pid, SIGKILL);
    reap(p, i, NULL, 0);
}

void gi_pool_stop(gi_pool *p)
{
    if (!p->kids)
        return;
    for (int i = 0; i < p->count; i++)
        if (p->kids[i].fd >= 0 && !p->kids[i].busy)
            gi_frame_send(p->kids[i].fd, GI_MSG_BYE, NULL, 0, 0, NULL);
    for (int i = 0; i < p->count; i++) {
        if (!p->kids[i].pid)
            continue;
        if (p->kids[i].busy)
            kill(p->kids[i].pid, SIGKILL);
        reap(p, i, NULL, 0);
    }
    free(p->kids);
    p->kids = NULL;
    p->count = 0;
}

int gi_pool_alive(const gi_pool *p, int i) { return p->kids[i].pid != 0; }

int gi_pool_idle_child(const gi_pool *p)
{
    for (int i = 0; i < p->count; i++)
        if (p->kids[i].pid && !p->kids[i].busy)
            return i;
    return -1;
}

static int child_has_job(const gi_pool_child *k, uint64_t job_id)
{
    for (int j = 0; j < k->jobs_sent_count; j++)
        if (k->jobs_sent[j] == job_id)
            return 1;
    return 0;
}

void gi_pool_forget_job(gi_pool *p, uint64_t job_id)
{
    for (int i = 0; i < p->count; i++) {
        gi_pool_child *k = &p->kids[i];
        for (int j = 0; j < k->jobs_sent_count;)
            if (k->jobs_sent[j] == job_id) {
                memmove(&k->jobs_sent[j], &k->jobs_sent[j + 1],
                        (size_t)(k->jobs_sent_count - j - 1) * sizeof k->jobs_sent[0]);
                k->jobs_sent_count--;
            } else {
                j++;
            }
    }
}

int gi_pool_assign(gi_pool *p, int i, uint64_t job_id, const char *job_file,
                   const char *job_text, const gi_manifest *manifest, const gi_task *task,
                   gi_error *err)
{
    gi_pool_child *k = &p->kids[i];
    gi_buf b;
    gi_buf_init(&b);
    int rc = 0;
    if (!child_has_job(k, job_id)) {
        gi_msg_job_encode(&b, job_id, job_file, job_text, manifest);
        rc = gi_frame_send(k->fd, GI_MSG_JOB, b.data, b.len, GI_CHILD_LINK_COMPRESS, err);
        if (rc == 0) {
            if (k->jobs_sent_count == (int)GI_ARRAY_LEN(k->jobs_sent)) {
                memmove(k->jobs_sent, k->jobs_sent + 1, sizeof k->jobs_sent - sizeof k->jobs_sent[0]);
                k->jobs_sent_count--;
            }
            k->jobs_sent[k->jobs_sent_count++] = job_id;
        }
    }
    if (rc == 0) {
        gi_buf_reset(&b);
        gi_msg_task_encode(&b, job_id, task);
        rc = gi_frame_send(k->fd, GI_MSG_TASK, b.data, b.len, GI_CHILD_LINK_COMPRESS, err);
    }
    gi_buf_free(&b);
    /* Busy even if the send failed: the child's death is then reported with
     * this task, which the owner retries. */
    k->busy = 1;
    k->job_id = job_id;
    k->task_id = task->id;
    k->attempt = task->attempt;
    k->started = gi_now();
    return rc;
}

int gi_pool_pollfds(gi_pool *p, struct pollfd *fds, int *child_of)
{
    int n = 0;
    for (int i = 0; i < p->count; i++)
        if (p->kids[i].fd >= 0) {
            p->kids[i].polled_pid = p->kids[i].pid;
            fds[n].fd = p->kids[i].fd;
            fds[n].events = POLLIN;
            fds[n].revents = 0;
            child_of[n] = i;
            n++;
        }
    return n;
}

static void child_lost(gi_pool *p, int i, const char *reason, const gi_pool_events *ev)
{
    gi_pool_child *k = &p->kids[i];
    int busy = k->busy;
    uint64_t job = k->job_id, task = k->task_id;
    uint32_t attempt = k->attempt;
    char why[512];
    if (reason && k->pid)
        kill(k->pid, SIGKILL);
    reap(p, i, why, sizeof why);
    if (reason) {
        char full[700];
        snprintf(full, sizeof full, "%s (%s)", why, reason);
        gi_warn("%s", full);
        if (busy && ev->crash)
            ev->crash(ev->user, i, job, task, attempt, full);
        return;
    }
    gi_warn("%s", why);
    if (busy && ev->crash)
        ev->crash(ev->user, i, job, task, attempt, why);
}

static int send_asset(int fd, const char *hash, const gi_buf *bytes, const gi_error *why,
                      gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    int rc;
    if (bytes) {
        gi_msg_asset_put_encode(&b, hash, bytes->data, bytes->len);
        rc = gi_frame_send(fd, GI_MSG_ASSET_PUT, b.data, b.len, GI_CHILD_LINK_COMPRESS, err);
    } else {
        gi_msg_error_encode(&b, why);
        rc = gi_frame_send(fd, GI_MSG_ERROR, b.data, b.len, 0, err);
    }
    gi_buf_free(&b);
    return rc;
}

void gi_pool_reply_asset(gi_pool *p, int i, const char *hash, const gi_buf *bytes,
                         const gi_error *why)
{
    gi_pool_child *k = &p->kids[i];
    if (k->fd < 0)
        return;
    gi_error err;
    if (send_asset(k->fd, hash, bytes, why, &err))
        gi_debug("answering pool child %d's asset request: %s", i, err.msg);
}

static int handle_frame(gi_pool *p, int i, gi_frame *f, const gi_pool_events *ev,
                        gi_error *err)
{
    gi_pool_child *k = &p->kids[i];
    switch (f->type) {
    case GI_MSG_RESULT: {
        gi_msg_result r;
        if (gi_msg_result_decode(&f->payload, &r, err))
            return -1;
        if (!k->busy || r.task_id != k->task_id || r.job_id != k->job_id) {
            gi_buf_free(&r.data);
            return gi_fail(err, GI_EPROTO, "RESULT for task %llu, which this child does not hold",
                           (unsigned long long)r.task_id);
        }
        k->busy = 0;
        if (ev->result)
            ev->result(ev->user, i, &r);
        gi_buf_free(&r.data);
        return 0;
    }
    case GI_MSG_FAIL: {
        gi_msg_fail fl;
        if (gi_msg_fail_decode(&f->payload, &fl, err))
            return -1;
        if (!k->busy || fl.task_id != k->task_id)
            return gi_fail(err, GI_EPROTO, "FAIL for task %llu, which this child does not hold",
                           (unsigned long long)fl.task_id);
        k->busy = 0;
        if (ev->fail)
            ev->fail(ev->user, i, &fl);
        return 0;
    }
    case GI_MSG_ASSET_NEED: {
        char hash[GI_HASH_HEX];
        if (gi_msg_asset_need_decode(&f->payload, hash, err))
            return -1;
        if (ev->asset_async) {
            ev->asset_async(ev->user, i, hash);
            return 0;
        }
        const gi_buf *bytes = ev->asset ? ev->asset(ev->user, hash) : NULL;
        gi_error unknown;
        if (!bytes)
            gi_fail(&unknown, GI_EINVAL, "asset %.12s is unknown to the coordinator", hash);
        return send_asset(k->fd, hash, bytes, &unknown, err);
    }
    case GI_MSG_HEARTBEAT:
    case GI_MSG_PROGRESS:
        return 0;
    default:
        return gi_fail(err, GI_EPROTO, "unexpected %s from a pool child",
                       gi_msg_type_name(f->type));
    }
}

static void child_readable(gi_pool *p, int i, const gi_pool_events *ev)
{
    gi_pool_child *k = &p->kids[i];
    uint8_t buf[65536];
    /* Never blocks: a stale readiness report must not stall the loop. */
    ssize_t n = recv(k->fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n < 0 && (errno == EINTR || errno == EAGAIN))
        return;
    if (n <= 0) {
        child_lost(p, i, NULL, ev);
        return;
    }
    gi_frame_decoder_feed(&k->dec, buf, (size_t)n);
    for (;;) {
        gi_frame f;
        gi_error err;
        gi_error_clear(&err);
        int got = gi_frame_decoder_next(&k->dec, &f, &err);
        if (got == 0)
            return;
        if (got < 0) {
            child_lost(p, i, err.msg, ev);
            return;
        }
        int rc = handle_frame(p, i, &f, ev, &err);
        gi_buf_free(&f.payload);
        if (rc) {
            child_lost(p, i, err.msg, ev);
            return;
        }
    }
}

void gi_pool_dispatch(gi_pool *p, const struct pollfd *fds, const int *child_of, int n,
                      const gi_pool_events *ev)
{
    for (int j = 0; j < n; j++) {
        int i = child_of[j];
        const gi_pool_child *k = &p->kids[i];
        if (!fds[j].revents || k->fd != fds[j].fd || k->pid != k->polled_pid)
            continue;
        child_readable(p, i, ev);
    }
}

int gi_pool_poll(gi_pool *p, int timeout_ms, const gi_pool_events *ev)
{
    struct pollfd *fds = gi_xcalloc((size_t)p->count, sizeof *fds);
    int *child_of = gi_xcalloc((size_t)p->count, sizeof *child_of);
    int n = gi_pool_pollfds(p, fds, child_of);
    int rc = poll(fds, (nfds_t)n, timeout_ms);
    if (rc > 0)
        gi_pool_dispatch(p, fds, child_of, n, ev);
    free(fds);
    free(child_of);
    return rc;
}
