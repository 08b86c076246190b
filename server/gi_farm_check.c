/* gi_farm_check: loading a job's scene in a forked, resource-limited child
 * before the coordinator loads it itself.
 *
 * Why: loading a scene parses mesh files with assimp, a large body of C++
 * that trusts what it reads. A job's files come from whoever holds the API
 * token, so the first parse of them happens in a child with limits on CPU
 * time, address space and core dumps, that reports back through a pipe and
 * exits. If it crashes, hangs or runs out of memory the job fails with that
 * reason and gi-farmd keeps serving. The coordinator then loads the same
 * bytes (content-addressed, so the same code sees the same input) knowing
 * they parse. The cost is parsing every scene twice; scenes load in a
 * fraction of the time their jobs take to render.
 *
 * The child uses only the store on disk and the job text: no sockets, no
 * HTTP, and it leaves with _exit (no atexit handlers, no stdio flush of the
 * parent's buffers). */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gi_farm_impl.h"
#include "gi_progress.h"
#include "gi_limits.h"
#include "gi_log.h"

typedef struct store_fetch_ctx {
    const gi_farm *f;
    gi_asset_store *store;
} store_fetch_ctx;

static int store_fetch(void *ctx, const char *hash, gi_error *err)
{
    store_fetch_ctx *c = ctx;
    gi_buf b;
    gi_buf_init(&b);
    int rc = gi_farm_store_read(c->f, hash, &b, err);
    if (rc == 0)
        gi_asset_store_put(c->store, hash, b.data, b.len);
    gi_buf_free(&b);
    return rc;
}

/* Parses a job's text and loads its scene from the store, resolving every
 * file name through the job's manifest only: a name the manifest does not
 * list is an error, whatever exists on this host's disk. */
int gi_farm_load_job(const gi_farm *f, const gi_farm_job *j, gi_job *job, gi_error *err)
{
    if (gi_job_parse(j->text, strlen(j->text), j->file, job, err))
        return -1;
    for (size_t i = 0; i < j->manifest.count; i++)
        gi_manifest_put(&job->manifest, j->manifest.entries[i].name, j->manifest.entries[i].hash,
                        j->manifest.entries[i].size);
    gi_asset_store *bytes = gi_asset_store_new();
    store_fetch_ctx fc = {f, bytes};
    gi_manifest_source ms = {&job->manifest, bytes, store_fetch, &fc};
    gi_asset_source src = gi_manifest_source_as_source(&ms);
    int rc = gi_job_load_scene(job, &src, err);
    /* The scene is built; the file bytes stay in the store, not in memory.
     * job->assets is left for what the method publishes. */
    gi_asset_store_free(bytes);
    return rc;
}

static void child_main(const gi_farm *f, const gi_farm_job *j, int fd)
{
    /* Drop every descriptor but stdio and the pipe: a worker connection or
     * a listener held here would stay open after the parent closed it. */
    if (fd > 3)
        close_range(3, (unsigned)fd - 1, 0);
    close_range((unsigned)fd + 1, ~0u, 0);
    struct rlimit rl;
    rl.rlim_cur = rl.rlim_max = 0;
    setrlimit(RLIMIT_CORE, &rl);
    rlim_t cpu = (rlim_t)(f->cfg.check_timeout_s + 1.0);
    rl.rlim_cur = rl.rlim_max = cpu;
    setrlimit(RLIMIT_CPU, &rl);
#if !defined(__SANITIZE_ADDRESS__)
    /* (AddressSanitizer reserves terabytes of address space up front.) */
    if (f->cfg.check_memory) {
        rl.rlim_cur = rl.rlim_max = (rlim_t)f->cfg.check_memory;
        setrlimit(RLIMIT_AS, &rl);
    }
#endif
    signal(SIGPIPE, SIG_IGN);
    signal(SIGTERM, SIG_DFL);
    signal(SIGINT, SIG_DFL);
    if (getenv(GI_FAULT_CHECK_CRASH_ENV)) { /* tests: a mesh that crashes its parser */
        signal(SIGSEGV, SIG_DFL);           /* (past a sanitizer's handler) */
        raise(SIGSEGV);
    }
    gi_error err;
    gi_error_clear(&err);
    gi_job job;
    int rc = gi_farm_load_job(f, j, &job, &err);
    gi_job_free(&job);
    char out[sizeof err.msg + 2];
    int n = snprintf(out, sizeof out, "%c%s", rc == 0 ? '0' : '0' + (int)err.code,
                     rc == 0 ? "" : err.msg);
    if (write(fd, out, (size_t)n) < 0)
        _exit(3);
    _exit(0);
}

int gi_farm_check_start(gi_farm *f, gi_farm_job *j, gi_error *err)
{
    int p[2];
    if (pipe2(p, O_CLOEXEC) != 0)
        return gi_fail(err, GI_EIO, "pipe: %s", strerror(errno));
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        close(p[0]);
        close(p[1]);
        return gi_fail(err, GI_EIO, "fork: %s", strerror(errno));
    }
    if (pid == 0) {
        close(p[0]);
        child_main(f, j, p[1]);
    }
    close(p[1]);
    fcntl(p[0], F_SETFL, fcntl(p[0], F_GETFL) | O_NONBLOCK);
    j->check_pid = pid;
    j->check_fd = p[0];
    j->check_deadline = gi_now() + f->cfg.check_timeout_s;
    gi_buf_reset(&j->check_msg);
    gi_farm_job_log(j, "checking the scene (process %ld)", (long)pid);
    return 0;
}

void gi_farm_check_kill(gi_farm_job *j)
{
    if (j->check_pid > 0) {
        kill(j->check_pid, SIGKILL);
        waitpid(j->check_pid, NULL, 0);
    }
    if (j->check_fd >= 0)
        close(j->check_fd);
    j->check_pid = 0;
    j->check_fd = -1;
}

void gi_farm_check_readable(gi_farm *f, gi_farm_job *j)
{
    for (;;) {
        char buf[512];
        ssize_t n = read(j->check_fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0 && errno == EAGAIN)
            return;
        if (n > 0) {
            if (j->check_msg.len < 4096)
                gi_buf_put(&j->check_msg, buf, (size_t)n);
            continue;
        }
        break; /* end of file (or an error): the child is done */
    }
    int status = 0;
    waitpid(j->check_pid, &status, 0);
    close(j->check_fd);
    j->check_fd = -1;
    j->check_pid = 0;
    gi_error why;
    gi_error_clear(&why);
    const gi_buf *m = &j->check_msg;
    if (WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        gi_fail(&why, GI_EINVAL,
                "%s: loading the scene %s (signal %d): a scene or mesh file is malformed or "
                "too large",
                j->file, sig == SIGXCPU || sig == SIGKILL ? "took too long" : "crashed", sig);
    } else if (m->len == 0 || WEXITSTATUS(status) != 0) {
        gi_fail(&why, GI_EINTERNAL, "%s: the scene checker exited with status %d", j->file,
                WEXITSTATUS(status));
    } else if (m->data[0] != '0') {
        int code = m->data[0] - '0';
        gi_fail(&why, code > GI_OK && code <= GI_EINTERNAL ? (gi_errcode)code : GI_EINTERNAL,
                "%.*s", (int)(m->len - 1), (const char *)m->data + 1);
    }
    gi_farm_job_checked(f, j, why.code == GI_OK ? NULL : &why);
}

/* Called from the loop's timer: a checker past its deadline is killed. */
void gi_farm_check_deadline(gi_farm *f, gi_farm_job *j, double now)
{
    if (j->check_pid <= 0 || now < j->check_deadline)
        return;
    gi_farm_check_kill(j);
    gi_error why;
    gi_fail(&why, GI_EINVAL, "%s: loading the scene took longer than %.0f s", j->file,
            f->cfg.check_timeout_s);
    gi_farm_job_checked(f, j, &why);
}
