/* gi_farm: gi-farmd, the farm coordinator (docs/farm.md).
 *
 * One process, one thread, one poll() loop (gi_farm.c) serving:
 *   - the worker port: TCP connections speaking the frame protocol
 *     (gi_farm_conn.c), authenticated by the farm secret;
 *   - the HTTP/JSON API (gi_farm_api.c): libmicrohttpd without threads of
 *     its own; its epoll descriptor sits in the same poll set and MHD_run is
 *     called from the loop, so request handlers touch the coordinator's
 *     state directly and nothing needs a lock;
 *   - job checkers (gi_farm_check.c): forked processes that load a job's
 *     scene before the coordinator does, so a hostile mesh crashes a
 *     throw-away child, not the daemon.
 * Jobs (gi_farm_jobs.c) each drive one gi_jobrun, the same state machine
 * `gi render` uses; the scheduler (gi_farm_sched.c) hands their tasks to
 * workers under leases and shares workers between jobs by priority. State
 * survives restarts through the journal and checkpoints in --state DIR. */
#ifndef GI_FARM_H
#define GI_FARM_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

typedef struct gi_farm_config {
    const char *state_dir;
    const char *listen_workers; /* ADDR:PORT; port 0 picks a free one */
    const char *listen_api;
    double heartbeat_s;  /* workers send a heartbeat this often */
    double lease_s;      /* a lease not renewed for this long expires */
    double dead_s;       /* a connection silent this long is closed */
    double handshake_s;  /* time allowed for HELLO .. AUTH */
    double api_head_s;   /* time allowed an API client for a request's head */
    /* A request must be over by api_request_s after its head, plus a second
     * for every api_min_rate bytes it moved (0: no such limit). */
    double api_request_s;
    uint64_t api_min_rate;
    double checkpoint_s; /* checkpoint running jobs this often */
    double refusal_window_s; /* an unauthenticated peer's refusals: a log line per window */
    /* Retention: an ended job is purged this long after it ended (0: kept
     * until `gi purge`), and the oldest ended ones while their directories
     * hold more than keep_ended_bytes (0: no limit). */
    double keep_ended_s;
    uint64_t keep_ended_bytes;
    uint32_t max_attempts;       /* failed runs of a task before its job fails */
    uint32_t max_task_losses;    /* runs of a task lost with their host, likewise */
    /* A task running longer than this (from the start of its run on the
     * worker's pool) is stopped and its run failed, unless its job sets its
     * own task_timeout; 0: no limit. */
    double task_timeout_s;
    uint32_t blocklist_failures; /* consecutive task failures that blocklist a worker */
    uint32_t blocklist_losses;   /* losses of a host in a row (no result between), likewise */
    double blocklist_s;          /* for how long */
    uint64_t max_asset_bytes;    /* one uploaded asset */
    uint64_t max_store_bytes;    /* all uploaded assets together */
    uint64_t max_result_bytes;   /* one RESULT frame */
    uint64_t max_job_pixels;     /* image width x height */
    uint32_t max_jobs;           /* jobs not yet finished */
    uint64_t max_jobs_memory;    /* the records and texts of all jobs kept, ended ones too */
    uint32_t max_workers;        /* worker connections */
    double check_timeout_s;      /* scene check of one job */
    uint64_t check_memory;       /* address-space limit of a checker, 0 = none */
    gi_buf secret;               /* farm secret (workers) */
    gi_buf token;                /* API bearer token */
} gi_farm_config;

void gi_farm_config_default(gi_farm_config *c);

typedef struct gi_farm gi_farm;

/* Opens the state directory (replaying the journal), binds both listeners.
 * Takes over the secrets in cfg (cfg's buffers are left empty). */
int gi_farm_open(gi_farm **out, gi_farm_config *cfg, gi_error *err);
/* Serves until gi_farm_stop; returns 0 on a clean stop. */
int gi_farm_run(gi_farm *f, gi_error *err);
/* Async-signal-safe: asks the loop to stop (SIGINT / SIGTERM). */
void gi_farm_stop(gi_farm *f);
void gi_farm_close(gi_farm *f);

#endif
