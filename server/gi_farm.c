/* gi_farm: the coordinator's context and its single poll() loop.
 *
 * Each round: poll the worker listener, every worker connection, MHD's
 * epoll descriptor and the checkers' pipes (timeout: the next timer, at
 * most TICK_MS); dispatch what is ready; run the timers (handshakes,
 * heartbeats, leases, checker deadlines, checkpoints, finishes that ended
 * on their threads); hand pending tasks to workers with free slots; drop
 * closed connections. How long each round keeps the loop from poll() is
 * kept per second (gi_farm_loop_stall, GET /metrics): a round that takes
 * long delays every merge, lease and answer behind it. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_farm_impl.h"
#include "gi_progress.h"
#include "gi_fs.h"
#include "gi_log.h"
#include "gi_net.h"

#define TICK_MS 50
/* Bytes of ASSET_PUT frames kept for the next host that asks. */
#define ASSET_FRAMES_MAX ((size_t)256 << 20)

double gi_farm_wallnow(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void gi_farm_config_default(gi_farm_config *c)
{
    memset(c, 0, sizeof *c);
    c->listen_workers = "127.0.0.1:7071";
    c->listen_api = "127.0.0.1:7070";
    c->heartbeat_s = 2.0;
    c->lease_s = 30.0;
    c->api_head_s = 10.0;
    c->api_request_s = 10.0;
    c->api_min_rate = 16 << 10;
    c->dead_s = 120.0;
    c->handshake_s = 10.0;
    c->checkpoint_s = 30.0;
    c->refusal_window_s = GI_REFUSAL_WINDOW_S;
    c->max_attempts = 4;
    c->max_task_losses = 8; /* why 8: gi_jobrun.c, DEFAULT_MAX_LOSSES */
    c->blocklist_failures = 5;
    c->blocklist_losses = 3; /* why 3: gi_farm_sched.c, Blocklisting */
    c->blocklist_s = 600.0;
    c->max_asset_bytes = (uint64_t)1 << 30;
    c->max_store_bytes = (uint64_t)64 << 30;
    c->max_result_bytes = (uint64_t)1 << 30;
    c->max_job_pixels = (uint64_t)64 << 20;
    c->max_jobs = 1000;
    c->max_jobs_memory = (uint64_t)1 << 30;
    c->max_workers = 1024;
    c->check_timeout_s = 300.0;
    c->check_memory = (uint64_t)16 << 30;
    gi_buf_init(&c->secret);
    gi_buf_init(&c->token);
}

static int open_state(gi_farm *f, gi_error *err)
{
    const char *dir = f->cfg.state_dir;
    if (mkdir(dir, 0700) != 0 && errno != EEXIST)
        return gi_fail(err, GI_EIO, "--state %s: %s", dir, strerror(errno));
    char p[4200];
    snprintf(p, sizeof p, "%s/lock", dir);
    f->lock_fd = open(p, O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (f->lock_fd < 0)
        return gi_fail(err, GI_EIO, "%s: %s", p, strerror(errno));
    if (flock(f->lock_fd, LOCK_EX | LOCK_NB) != 0)
        return gi_fail(err, GI_EIO, "--state %s is in use by another gi-farmd", dir);
    size_t n = strlen(dir) + 16;
    f->assets_dir = gi_xmalloc(n);
    snprintf(f->assets_dir, n, "%s/assets", dir);
    f->jobs_dir = gi_xmalloc(n);
    snprintf(f->jobs_dir, n, "%s/jobs", dir);
    if (gi_mkdirs(f->assets_dir, err) || gi_mkdirs(f->jobs_dir, err))
        return -1;
    return gi_farm_store_scan(f, err);
}

/* <state>/addresses: where the listeners really are (ports chosen by the
 * kernel when 0 was asked for), for scripts and tests. */
static int write_addresses(gi_farm *f, gi_error *err)
{
    char path[4200], text[256];
    snprintf(path, sizeof path, "%s/addresses", f->cfg.state_dir);
    int n = snprintf(text, sizeof text, "workers %s\napi %s\n", f->worker_addr, f->api_addr);
    return gi_write_file_atomic(path, text, (size_t)n, err);
}

int gi_farm_open(gi_farm **out, gi_farm_config *cfg, gi_error *err)
{
    gi_farm *f = gi_xcalloc(1, sizeof *f);
    *out = f;
    f->cfg = *cfg;
    gi_buf_init(&cfg->secret);
    gi_buf_init(&cfg->token);
    f->lock_fd = f->worker_fd = f->api_fd = -1;
    f->journal.fd = -1;
    f->finish_wake_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (f->finish_wake_fd < 0)
        return gi_fail(err, GI_EIO, "eventfd: %s", strerror(errno));
    f->finish_gate = getenv(GI_FAULT_FINISH_GATE_ENV);
    f->started = gi_now();
    f->started_wall = gi_farm_wallnow();
    f->next_job_id = 1;
    gi_refusal_log_init(&f->refusals, f->cfg.refusal_window_s);
    gi_frame_cache_init(&f->asset_frames, ASSET_FRAMES_MAX);
    gi_auth_key(&f->cfg.secret, f->key);
    /* Clients hold the token, workers the secret: one value for both would
     * let every client join as a worker, which is trusted with results and
     * with every asset. */
    if (gi_token_equal(&f->cfg.token, (const char *)f->cfg.secret.data, f->cfg.secret.len))
        return gi_fail(err, GI_EINVAL,
                       "the API token and the farm secret are the same: every client holding "
                       "the token could join as a worker; give each a value of its own");
    signal(SIGPIPE, SIG_IGN);
    if (open_state(f, err))
        return -1;
    f->worker_fd = gi_net_listen(f->cfg.listen_workers, f->worker_addr, sizeof f->worker_addr, err);
    if (f->worker_fd < 0)
        return gi_error_prefix(err, "--listen-workers");
    if (gi_farm_api_start(f, err))
        return -1;
    if (gi_farm_jobs_replay(f, err))
        return -1;
    gi_farm_standing_load(f);
    if (write_addresses(f, err))
        return -1;
    gi_info("state in %s; workers connect to %s; API on http://%s/", f->cfg.state_dir,
            f->worker_addr, f->api_addr);
    return 0;
}

void gi_farm_stop(gi_farm *f)
{
    f->stop = 1;
}

/* One poll round's descriptors and what each belongs to. */
typedef struct slot {
    int kind; /* 0 listener, 1 api, 2 conn, 3 checker, 4 a finish thread's wake-up */
    void *ptr;
} slot;

static void stall_note(gi_farm *f, double now, double busy)
{
    int64_t sec = (int64_t)now;
    int k = (int)(sec % GI_FARM_STALL_WINDOW);
    if (f->stall_sec[k] != sec) {
        f->stall_sec[k] = sec;
        f->stall_max[k] = 0;
    }
    if (busy > f->stall_max[k])
        f->stall_max[k] = busy;
    if (busy > f->stall_max_ever)
        f->stall_max_ever = busy;
}

double gi_farm_loop_stall(const gi_farm *f, double now)
{
    double worst = 0;
    for (int k = 0; k < GI_FARM_STALL_WINDOW; k++)
        if ((int64_t)now - f->stall_sec[k] < GI_FARM_STALL_WINDOW && f->stall_max[k] > worst)
            worst = f->stall_max[k];
    return worst;
}

int gi_farm_run(gi_farm *f, gi_error *err)
{
    size_t cap = 0;
    struct pollfd *fds = NULL;
    slot *slots = NULL;
    int api_fd = gi_farm_api_fd(f);
    double busy_since = 0; /* when the round began: poll's return */
    while (!f->stop) {
        size_t live_count;
        gi_farm_job **live = gi_farm_live_jobs(f, &live_count);
        size_t need = 3 + f->conn_count + live_count;
        if (need > cap) {
            cap = 2 * need;
            fds = gi_xrealloc(fds, cap * sizeof *fds);
            slots = gi_xrealloc(slots, cap * sizeof *slots);
        }
        size_t n = 0;
        fds[n] = (struct pollfd){.fd = f->worker_fd, .events = POLLIN};
        slots[n++] = (slot){0, NULL};
        if (api_fd >= 0) {
            fds[n] = (struct pollfd){.fd = api_fd, .events = POLLIN};
            slots[n++] = (slot){1, NULL};
        }
        fds[n] = (struct pollfd){.fd = f->finish_wake_fd, .events = POLLIN};
        slots[n++] = (slot){4, NULL};
        for (size_t i = 0; i < f->conn_count; i++) {
            gi_farm_conn *c = f->conns[i];
            if (c->fd < 0)
                continue;
            short ev = c->state == GI_FC_CLOSING ? 0 : POLLIN;
            if (gi_farm_conn_wants_write(c))
                ev |= POLLOUT;
            fds[n] = (struct pollfd){.fd = c->fd, .events = ev};
            slots[n++] = (slot){2, c};
        }
        for (size_t i = 0; i < live_count; i++)
            if (live[i]->check_fd >= 0) {
                fds[n] = (struct pollfd){.fd = live[i]->check_fd, .events = POLLIN};
                slots[n++] = (slot){3, live[i]};
            }
        int timeout = TICK_MS;
        int at = gi_farm_api_timeout_ms(f);
        if (at >= 0 && at < timeout)
            timeout = at;
        if (busy_since > 0)
            stall_note(f, gi_now(), gi_now() - busy_since);
        int rc = poll(fds, (nfds_t)n, timeout);
        busy_since = gi_now();
        if (rc < 0 && errno != EINTR) {
            gi_fail(err, GI_EIO, "poll: %s", strerror(errno));
            break;
        }
        for (size_t i = 0; rc > 0 && i < n; i++) {
            if (!fds[i].revents)
                continue;
            switch (slots[i].kind) {
            case 0:
                gi_farm_conn_accept(f);
                break;
            case 2: {
                gi_farm_conn *c = slots[i].ptr;
                if (c->fd >= 0 && (fds[i].revents & POLLOUT))
                    gi_farm_conn_writable(f, c);
                if (c->fd >= 0 && (fds[i].revents & (POLLIN | POLLHUP | POLLERR)))
                    gi_farm_conn_readable(f, c);
                break;
            }
            case 3: {
                gi_farm_job *j = slots[i].ptr;
                if (j->check_fd == fds[i].fd)
                    gi_farm_check_readable(f, j);
                break;
            }
            case 4: { /* the tick below takes the finish in */
                uint64_t count;
                ssize_t got = read(f->finish_wake_fd, &count, sizeof count);
                (void)got;
                break;
            }
            default:
                break;
            }
        }
        /* Always: MHD also has timeouts of its own to run. */
        gi_farm_api_run(f);
        gi_farm_conns_tick(f);
        gi_refusal_tick(&f->refusals, gi_now());
        gi_farm_jobs_tick(f);
        gi_farm_standing_tick(f);
        gi_farm_schedule(f);
        gi_farm_conns_reap(f);
    }
    free(fds);
    free(slots);
    if (!f->stop)
        return -1;
    gi_info("stopping: checkpointing running jobs");
    gi_farm_jobs_checkpoint_all(f);
    gi_farm_standing_save(f);
    return 0;
}

void gi_farm_close(gi_farm *f)
{
    if (!f)
        return;
    gi_farm_api_stop(f);
    /* Jobs first: the connections' leases then belong to no job, and
     * hanging up fails no task (the checkpoints already hold the state). */
    gi_farm_jobs_free(f);
    gi_farm_conns_goodbye(f, 1.0);
    gi_farm_conns_reap(f);
    free(f->conns);
    for (size_t i = 0; i < f->host_count; i++)
        free(f->hosts[i]);
    free(f->hosts);
    if (f->worker_fd >= 0)
        close(f->worker_fd);
    if (f->lock_fd >= 0)
        close(f->lock_fd);
    if (f->finish_wake_fd >= 0)
        close(f->finish_wake_fd);
    free(f->assets_dir);
    free(f->jobs_dir);
    gi_frame_cache_free(&f->asset_frames);
    gi_secret_free(&f->cfg.secret);
    gi_secret_free(&f->cfg.token);
    memset(f->key, 0, sizeof f->key);
    free(f);
}
