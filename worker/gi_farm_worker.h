/* gi_farm_worker: gi-worker, a render host of the farm (docs/farm.md).
 *
 * A TCP connection to the coordinator plus a gi_pool of forked children (the
 * same children `gi render` uses). The worker:
 *   - connects and authenticates (HELLO / CHALLENGE / AUTH / WELCOME, both
 *     sides proving the farm secret), advertising its processes, task slots,
 *     cores, memory and version; reconnects with exponential backoff and
 *     jitter when the connection fails or is lost;
 *   - queues the TASKs it is sent (up to its slots) and hands them to idle
 *     children with the job's definition (JOB); relays each child's RESULT
 *     or FAIL, and reports a crashed child as a failure of its task;
 *   - serves the children's ASSET_NEED from its disk cache, fetching what
 *     it lacks from the coordinator (one request per hash, however many
 *     children wait for it);
 *   - sends HEARTBEATs listing the tasks it holds (renewing their leases),
 *     each running one with how long it has run (protocol 2: time limits
 *     count from a run's start), and gives up on a coordinator silent for
 *     4 leases;
 *   - gives each job a batch directory (gi_batch_dir.h) that its children
 *     share; removes it when the coordinator says the job is over (CANCEL
 *     of all its tasks), and sweeps directories idle for
 *     GI_BATCH_DIR_MAX_AGE_S at start-up and hourly;
 *   - on SIGTERM drains: hands its queued tasks back (DRAIN), finishes the
 *     running ones (killing them after drain_s), says BYE and exits; a second
 *     SIGTERM stops at once.
 * Event loop: poll() over the coordinator socket and the children's sockets,
 * one thread. */
#ifndef GI_FARM_WORKER_H
#define GI_FARM_WORKER_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

typedef struct gi_worker_opts {
    const char *connect;   /* coordinator HOST:PORT */
    const char *name;      /* NULL: the host name */
    const char *cache_dir;
    uint64_t cache_max;    /* bytes; 0 = unbounded */
    const char *batch_dir; /* root of per-job batch directories; NULL: <cache_dir>/batches */
    int procs;             /* pool children */
    int queue;             /* extra tasks queued beyond procs */
    double drain_s;        /* time allowed to finish running tasks on SIGTERM */
    double backoff_max_s;  /* longest wait between connection attempts */
    int once;              /* exit instead of reconnecting (tests) */
    gi_buf secret;
} gi_worker_opts;

/* Tests of a farm with older workers: GI_FAULT_PROTO_MAX=N (N from
 * GI_PROTO_MIN to below GI_PROTO_MAX) makes the worker offer protocol
 * versions up to N only, as a build of that version would. */
#define GI_FAULT_PROTO_MAX_ENV "GI_FAULT_PROTO_MAX"

/* Runs until drained (SIGTERM) or, with once, until the first session ends.
 * Returns 0 after a clean drain. */
int gi_farm_worker_run(gi_worker_opts *o, gi_error *err);

/* Signal handlers call this (async-signal-safe): the first call drains, the
 * second stops at once. */
void gi_farm_worker_signal(void);

#endif
