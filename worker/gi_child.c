/* gi_child: pool child task loop. */
#include "gi_child.h"

#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "gi_batch_dir.h"
#include "gi_frame.h"
#include "gi_log.h"
#include "gi_msg.h"
#include "gi_netio.h"
#include "gi_worker_ctx.h"

#define MAX_JOB_DEFS 8

typedef struct child {
    int fd;
    gi_frame_limits limits;
    gi_msg_job defs[MAX_JOB_DEFS]; /* known job definitions, oldest first */
    int def_count;
    gi_worker_ctx ctx;
    int loaded;
    gi_asset_store *store;
    const char *batch_root;
    gi_child_faults faults; /* read once, at the start */
} child;

static int send_msg(child *c, uint16_t type, const gi_buf *b, gi_error *err)
{
    return gi_frame_send(c->fd, type, b ? b->data : NULL, b ? b->len : 0,
                         GI_CHILD_LINK_COMPRESS, err);
}

/* Asks the parent for an asset and waits for it (the parent answers
 * ASSET_NEED before anything else it has for us). */
static int fetch_asset(void *fctx, const char *hash, gi_error *err)
{
    child *c = fctx;
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_asset_need_encode(&b, hash);
    int rc = send_msg(c, GI_MSG_ASSET_NEED, &b, err);
    gi_buf_free(&b);
    if (rc)
        return -1;
    for (;;) {
        gi_frame f;
        int got = gi_frame_recv(c->fd, &c->limits, "parent", &f, err);
        if (got <= 0)
            return got == 0 ? gi_fail(err, GI_EIO, "parent closed the connection") : -1;
        if (f.type == GI_MSG_ASSET_PUT) {
            char h[GI_HASH_HEX];
            const uint8_t *data;
            size_t len;
            rc = gi_msg_asset_put_decode(&f.payload, h, &data, &len, err);
            if (rc == 0 && strcmp(h, hash) != 0)
                rc = gi_fail(err, GI_EPROTO, "asked for asset %.12s, got %.12s", hash, h);
            if (rc == 0)
                gi_asset_store_put(c->store, h, data, len);
            gi_buf_free(&f.payload);
            return rc;
        }
        if (f.type == GI_MSG_ERROR) {
            gi_error e;
            rc = gi_msg_error_decode(&f.payload, &e, err);
            gi_buf_free(&f.payload);
            if (rc == 0) {
                if (err)
                    *err = e;
                rc = -1;
            }
            return rc;
        }
        uint16_t t = f.type;
        gi_buf_free(&f.payload);
        return gi_fail(err, GI_EPROTO, "expected ASSET_PUT, got %s", gi_msg_type_name(t));
    }
}

/* The same job: the same text, file name and asset bytes. */
static int same_def(const gi_msg_job *a, const gi_msg_job *b)
{
    if (strcmp(a->text, b->text) != 0 || strcmp(a->file, b->file) != 0 ||
        a->manifest.count != b->manifest.count)
        return 0;
    for (size_t i = 0; i < a->manifest.count; i++) {
        const gi_manifest_entry *e = gi_manifest_find(&b->manifest, a->manifest.entries[i].name);
        if (!e || memcmp(e->hash, a->manifest.entries[i].hash, GI_HASH_HEX) != 0)
            return 0;
    }
    return 1;
}

static void unload(child *c)
{
    gi_worker_ctx_free(&c->ctx);
    c->loaded = 0;
    /* Drop the job's asset bytes too. */
    gi_asset_store_free(c->store);
    c->store = gi_asset_store_new();
}

static void add_def(child *c, gi_msg_job *def)
{
    for (int i = 0; i < c->def_count; i++)
        if (c->defs[i].job_id == def->job_id) {
            /* An id given to another job: what was loaded for it is not it. */
            if (c->loaded && c->ctx.job_id == def->job_id && !same_def(&c->defs[i], def))
                unload(c);
            gi_msg_job_free(&c->defs[i]);
            c->defs[i] = *def;
            return;
        }
    if (c->def_count == MAX_JOB_DEFS) {
        gi_msg_job_free(&c->defs[0]);
        memmove(&c->defs[0], &c->defs[1], (MAX_JOB_DEFS - 1) * sizeof c->defs[0]);
        c->def_count--;
    }
    c->defs[c->def_count++] = *def;
}

static int ensure_job(child *c, uint64_t job_id, gi_error *err)
{
    if (c->loaded && c->ctx.job_id == job_id)
        return 0;
    const gi_msg_job *def = NULL;
    for (int i = 0; i < c->def_count; i++)
        if (c->defs[i].job_id == job_id)
            def = &c->defs[i];
    if (!def)
        return gi_fail(err, GI_EPROTO, "task for job %llu, whose JOB was never sent",
                       (unsigned long long)job_id);
    if (c->loaded)
        unload(c); /* a new job */
    if (gi_worker_ctx_load(&c->ctx, job_id, def->file, def->text, &def->manifest, fetch_asset,
                           c, c->store, err))
        return -1;
    if (c->batch_root)
        c->ctx.batch_dir = gi_batch_dir_path(c->batch_root, job_id, def->text);
    c->loaded = 1;
    return 0;
}

static int handle_task(child *c, const gi_buf *payload, gi_error *err)
{
    gi_msg_task m;
    if (gi_msg_task_decode(payload, &m, err))
        return -1; /* protocol error: the connection is broken */
    gi_error terr;
    gi_error_clear(&terr);
    gi_buf result;
    gi_buf_init(&result);
    int rc = ensure_job(c, m.job_id, &terr);
    if (rc == 0 && gi_fault_hits(&c->faults.kill_host, m.task.id, m.task.attempt)) {
        gi_warn("fault injection: task %llu kills this host's gi-worker (pid %ld)",
                (unsigned long long)m.task.id, (long)getppid());
        kill(getppid(), SIGKILL);
        kill(getpid(), SIGKILL);
    }
    if (rc == 0 && gi_fault_hits(&c->faults.stop_host, m.task.id, m.task.attempt)) {
        gi_warn("fault injection: task %llu stops this host's gi-worker (pid %ld)",
                (unsigned long long)m.task.id, (long)getppid());
        kill(getppid(), SIGSTOP);
    }
    if (rc == 0 && gi_fault_hits(&c->faults.hang, m.task.id, m.task.attempt)) {
        gi_warn("fault injection: task %llu hangs this child (pid %ld)",
                (unsigned long long)m.task.id, (long)getpid());
        for (;;)
            pause();
    }
    if (rc == 0 && gi_fault_hits(&c->faults.slow, m.task.id, m.task.attempt)) {
        double secs = c->faults.slow_s;
        gi_debug("fault injection: task %llu sleeps %.2f s first", (unsigned long long)m.task.id,
                 secs);
        if (secs > 0) {
            struct timespec ts = {(time_t)secs, (long)((secs - (double)(time_t)secs) * 1e9)};
            while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
                ;
        }
    }
    if (rc == 0)
        rc = gi_worker_run_task(&c->ctx, &m.task, &result, &terr);
    if (rc == 0 && gi_fault_hits(&c->faults.crash, m.task.id, m.task.attempt)) {
        gi_warn("fault injection: killing this child during task %llu",
                (unsigned long long)m.task.id);
        kill(getpid(), SIGKILL);
    }
    if (rc == 0 && result.len > 0 &&
        gi_fault_hits(&c->faults.bad_result, m.task.id, m.task.attempt))
        gi_fault_damage(&c->faults, &c->ctx.job, &m.task, &result);
    gi_buf out;
    gi_buf_init(&out);
    if (rc == 0)
        gi_msg_result_encode(&out, m.job_id, m.task.id, m.task.attempt, &c->ctx.stats,
                             result.data, result.len);
    else
        gi_msg_fail_encode(&out, m.job_id, m.task.id, m.task.attempt, &terr);
    rc = send_msg(c, rc == 0 ? GI_MSG_RESULT : GI_MSG_FAIL, &out, err);
    gi_buf_free(&out);
    gi_buf_free(&result);
    gi_task_free(&m.task);
    return rc;
}

int gi_child_main(int fd, const char *batch_root)
{
    child c;
    memset(&c, 0, sizeof c);
    c.fd = fd;
    c.batch_root = batch_root;
    c.limits = gi_frame_limits_default();
    c.store = gi_asset_store_new();
    gi_child_faults_read(&c.faults);
    signal(SIGPIPE, SIG_IGN);
    pid_t parent = getppid();
    int status = 0;
    for (;;) {
        gi_error err;
        gi_error_clear(&err);
        gi_frame f;
        int got = gi_frame_recv(fd, &c.limits, "parent", &f, &err);
        /* A parent that died (killed: its socket reset) is no error of ours. */
        if (got == 0 || (got < 0 && getppid() != parent))
            break;
        if (got < 0) {
            gi_error_log("%s", err.msg);
            status = 1;
            break;
        }
        int rc = 0, stop = 0;
        switch (f.type) {
        case GI_MSG_JOB: {
            gi_msg_job def;
            rc = gi_msg_job_decode(&f.payload, &def, &err);
            if (rc == 0)
                add_def(&c, &def);
            break;
        }
        case GI_MSG_TASK:
            rc = handle_task(&c, &f.payload, &err);
            break;
        case GI_MSG_HEARTBEAT:
        case GI_MSG_CANCEL:
            break;
        case GI_MSG_BYE:
            stop = 1;
            break;
        default:
            rc = gi_fail(&err, GI_EPROTO, "unexpected %s from parent", gi_msg_type_name(f.type));
        }
        gi_buf_free(&f.payload);
        if (rc) {
            gi_error_log("%s", err.msg);
            status = 1;
            break;
        }
        if (stop)
            break;
    }
    if (c.loaded)
        gi_worker_ctx_free(&c.ctx);
    for (int i = 0; i < c.def_count; i++)
        gi_msg_job_free(&c.defs[i]);
    gi_asset_store_free(c.store);
    gi_child_faults_free(&c.faults);
    close(fd);
    return status;
}
