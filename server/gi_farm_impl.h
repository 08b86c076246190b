/* gi_farm_impl: the coordinator's structures, shared by its subsystems
 * (one file each, like a Redis server.h):
 *   gi_farm.c        the context and the poll loop, timers, signals
 *   gi_farm_conn.c   worker connections: accept, handshake, frames in/out
 *   gi_farm_sched.c  leases, results, failures, fair sharing, blocklisting
 *   gi_farm_jobs.c   job records: submit, check, run, checkpoint, end, replay
 *   gi_farm_check.c  the forked scene checker
 *   gi_farm_store.c  the content-addressed asset store on disk
 *   gi_farm_standing.c  the workers' standing kept across restarts
 *   gi_farm_api.c    the HTTP API (libmicrohttpd), gi_farm_views.c its JSON
 * Everything runs on the loop's thread, but for writes handed to threads
 * of their own: checkpoints (gi_file_writer) and a job's finish, its
 * outputs (gi_jobrun_opts.finish_threaded), whose job the loop leaves alone
 * meanwhile. */
#ifndef GI_FARM_IMPL_H
#define GI_FARM_IMPL_H

#include <stdint.h>
#include <sys/types.h>

#include "gi_affinity.h"
#include "gi_auth.h"
#include "gi_farm.h"
#include "gi_frame.h"
#include "gi_frame_cache.h"
#include "gi_job.h"
#include "gi_jobrun.h"
#include "gi_journal.h"
#include "gi_msg_ctrl.h"
#include "gi_netio.h"
#include "gi_refusal_log.h"

struct MHD_Daemon;

/* ---- jobs -------------------------------------------------------------- */

typedef enum {
    GI_FJ_CHECKING, /* waiting for (or in) the scene checker */
    GI_FJ_RUNNING,  /* its gi_jobrun is live */
    GI_FJ_DONE,
    GI_FJ_FAILED,
    GI_FJ_CANCELLED
} gi_fj_state;

const char *gi_fj_state_name(gi_fj_state s);
/* What a job's views call its state: gi_fj_state_name, except "finishing"
 * for a running job whose method->finish (its outputs) runs on its thread,
 * and "cancelling" for one cancelled meanwhile (it ends cancelled once the
 * finish has returned: it must not look as if it were about to be done). */
typedef struct gi_farm_job gi_farm_job;
const char *gi_farm_job_state_name(const gi_farm_job *j);
/* A running job whose finish runs on its thread ("finishing" or
 * "cancelling"). */
int gi_farm_job_finishing(const gi_farm_job *j);

#define GI_FJ_LOG_KEEP 64    /* log lines kept in memory per job */
#define GI_FJ_ERRORS_KEEP 32 /* task errors kept per job */
#define GI_FJ_LOG_PENDING_MAX (256 * 1024)

typedef struct gi_fj_task_error {
    double when;
    uint64_t task_id;
    uint32_t attempt;
    char worker[GI_MSG_MAX_NAME + 1];
    char message[512];
} gi_fj_task_error;

/* A worker's standing with one job (gi_farm_sched.c, Exclusions), kept
 * across restarts with the blocklist (gi_farm_standing.c). */
typedef struct gi_fj_exclusion {
    struct gi_farm_host *host;
    uint32_t streak;       /* its failures of this job's tasks since its last result of them */
    uint32_t times;        /* how often it was excluded from the job */
    double until;          /* monotonic: excluded until then; 0: never was */
    /* host->results when it first failed one of the job's tasks (an entry
     * exists once it has): more since, and the job fails on a host that
     * works (gi_farm_sched.c, Blame). */
    uint64_t results_at_failure;
    /* Monotonic: its latest failure of the job's tasks (-INFINITY: before
     * a restart that did not know it). Only failures this recent count as
     * the job failing elsewhere (gi_farm_sched.c, Blame). */
    double last_failed;
    char last_error[256];
} gi_fj_exclusion;

/* A failure of one of the job's tasks on a host, not judged yet: the host's
 * fault or the job's (gi_farm_sched.c, Blame). */
typedef struct gi_fj_suspect {
    uint64_t task_id;
    struct gi_farm_host *host;
    uint64_t results_at; /* host->results then: more since, its streak has ended */
    double failed_at;    /* monotonic */
} gi_fj_suspect;

struct gi_farm_job {
    uint64_t id;
    gi_fj_state state;
    uint32_t priority;
    double submitted, started, ended; /* wall clock (epoch seconds); 0 = not yet */
    /* When an output of the done job was first sent whole through the API
     * (journaled: FETCHED); 0 = never. Retention purges fetched jobs first. */
    double fetched;
    char *file, *text;
    /* The submission's Idempotency-Key (NULL: none), journaled with the
     * job's SUBMIT: a client's retry after a restart gets this job again.
     * It lives as long as the job (until purged), like the job's text. */
    char *submit_key;
    size_t text_len; /* strlen(text): counted against --max-jobs-memory at every submission */
    gi_manifest manifest;
    /* Data the job published that its last checkpoint needs from the asset
     * store (named by hash; <dir>/published), kept there until the job
     * no longer needs it (gi_farm_store_release). */
    gi_manifest published;
    char *name, *method; /* from parsing the text, for listings */
    char **outputs;      /* output file names */
    int output_count;
    gi_output_spec *declared; /* the job's outputs block: what each kind is called */
    int declared_count;
    int keeps_batches;        /* gi_job.keeps_batches */
    char *dir; /* <state>/jobs/<id> */
    gi_error error; /* why it failed */
    /* Ended, but its END record is not in the journal yet (a full disk):
     * appended again at every tick; until then its checkpoint stays, for a
     * restart would run it again. */
    int end_pending;
    /* Monotonic time to try writing the outputs again; 0: not waiting. Its
     * run failed only writing them, and no checkpoint could keep its
     * result either (the same full disk): the result waits in memory. */
    double outputs_retry_at;
    /* Bytes of <dir> once it ended (--keep-ended-bytes), measured by the
     * first retention pass that needs them; disk_measured 0: not yet. */
    uint64_t disk_bytes;
    int disk_measured;
    /* Such a retry's finish runs on its thread (gi_jobrun_finishing). */
    int outputs_retrying;
    /* Cancelled while its finish ran on its thread: its END (cancelled) is
     * journaled (or end_pending), and the job ends cancelled once the
     * finish has returned; until then it is still RUNNING ("cancelling"). */
    int cancelling;

    /* Checker. */
    pid_t check_pid;
    int check_fd;
    double check_deadline; /* monotonic */
    gi_buf check_msg;

    /* Running. */
    int loaded;
    gi_job job;
    gi_jobrun jr;
    double pass;        /* stride scheduling: worker-seconds / priority */
    double est_task_s;  /* mean worker-seconds of its tasks so far */
    uint64_t est_n;
    double run_t0;          /* monotonic start of this process's run */
    uint64_t resumed_merged; /* tasks merged before a restart (from a checkpoint) */
    uint64_t results_accepted, results_late, leases, lease_expiries;
    uint64_t host_disk_errors; /* tasks a host's full disk sent elsewhere */
    uint64_t task_timeouts;    /* runs stopped for their time limit (gi_farm_sched.c) */
    double merge_s, finish_s; /* coordinator time in method merge / finish */
    uint64_t result_bytes;    /* result data accepted */
    uint64_t merged_bytes;    /* result data merged (in task order) */
    /* Task counts and statistics as they stood when the run ended. */
    uint64_t final_tasks, final_merged, final_retries, final_losses;
    gi_task_stats final_stats;
    gi_progress_at final_progress;
    /* Affinity key -> gi_farm_host owning it (gi_farm_sched.c). Kept with
     * the job's checkpoint (<dir>/affinity, by host name) so a restarted
     * coordinator sends a key's tasks to the same host again. */
    gi_affinity affinity;
    uint64_t affinity_moves; /* keys that changed owner */
    /* Task id + 1 -> the host its last attempt failed on: its retry goes to
     * another host when one can take it (a full disk, a broken GPU driver:
     * host trouble follows the host, not the task). */
    gi_affinity failed_on;
    /* Workers whose failures of this job's tasks excluded them from it, or
     * that have a streak of them (gi_farm_sched.c, Exclusions). */
    gi_fj_exclusion *excl;
    size_t excl_count, excl_cap;
    /* Its task failures waiting for a verdict (gi_farm_sched.c, Blame). */
    gi_fj_suspect *suspects;
    size_t suspect_count, suspect_cap;
    uint64_t ckpt_seq, ckpt_merged;
    char ckpt_error[512]; /* why the last checkpoint failed; "" if it did not */
    double ckpt_done_cost;
    double ckpt_last;   /* monotonic */
    gi_ckpt_pace ckpt_pace;
    /* The checkpoint being written (gi_farm_jobs.c), and what it holds. */
    struct gi_file_writer *ckpt_w;
    gi_manifest ckpt_w_published; /* the data it needs from the store */
    uint64_t ckpt_w_merged;
    double ckpt_w_done_cost;
    size_t ckpt_w_bytes;

    char *log[GI_FJ_LOG_KEEP];
    int log_start, log_count;
    /* Lines not yet in <dir>/log (its disk was full), appended with the
     * next line or tick that finds room; beyond GI_FJ_LOG_PENDING_MAX bytes,
     * lines are only counted, and the file says how many it lacks. */
    gi_buf log_pending;
    uint64_t log_dropped;
    /* GI_FJ_ERRORS_KEEP of them, allocated at the first: 25 KB a job, most
     * of a farm's history of ended jobs would otherwise be empty rings. */
    gi_fj_task_error *errors;
    int err_start, err_count;
};

/* ---- workers ----------------------------------------------------------- */

typedef enum {
    GI_FC_HELLO,    /* waiting for HELLO */
    GI_FC_AUTH,     /* CHALLENGE sent, waiting for AUTH */
    GI_FC_ACTIVE,   /* authenticated, takes tasks */
    GI_FC_DRAINING, /* finishing its tasks, takes no more */
    GI_FC_CLOSING   /* flushing its last frames, then closed */
} gi_fc_state;

typedef struct gi_farm_lease {
    uint64_t job_id, task_id;
    uint32_t attempt;
    double deadline; /* monotonic */
    double est_s;    /* worker-seconds charged to the job's pass when leased */
    double leased;   /* monotonic: when it was sent */
    /* Monotonic: when the worker's pool began running it, as its HEARTBEAT
     * said (protocol GI_PROTO_RUNS); 0 while it is queued or unreported.
     * Task time limits count from it (from `leased` for older workers). */
    double started;
} gi_farm_lease;

/* A worker by name: what outlives its connections (blocklisting). */
typedef struct gi_farm_host {
    char name[GI_MSG_MAX_NAME + 1];
    /* Its failures judged its own (gi_farm_sched.c, Blame) since its last
     * result: the streak that blocklists it. */
    uint32_t consecutive_failures;
    /* The job of the streak's first failure; wide: the streak has failures
     * of another job too, or of the host's own disk (GI_EHOST), so it may
     * blocklist the host (gi_farm_sched.c, Blocklisting). */
    uint64_t streak_job;
    int streak_wide;
    uint64_t failures; /* its task failures that count (not bad input, not timeouts) */
    uint64_t own_failures; /* those judged its own */
    uint64_t results;   /* results accepted from it */
    /* Losses with tasks held (gi_farm_sched.c, Blocklisting); consecutive:
     * since its last result. */
    uint32_t consecutive_losses;
    uint64_t losses;
    double blocked_until; /* monotonic; 0 = not blocklisted */
    /* Set by each scheduling round: an authenticated, active connection of
     * this host can take work now or when a slot frees (affinity owners). */
    int present;
    char last_error[512];
    int seen; /* has had an active connection since this coordinator started */
} gi_farm_host;

typedef struct gi_farm_conn {
    uint64_t id; /* worker id once authenticated, else a connection number */
    int fd;
    char peer[80];
    gi_fc_state state;
    gi_frame_decoder dec;
    double connected, last_heard; /* monotonic */
    double next_heartbeat;
    gi_msg_hello hello;
    int have_hello;
    uint32_t proto; /* the message set version chosen for it (gi_msg_ctrl.h) */
    gi_buf hello_raw;
    uint8_t nonce[GI_MSG_NONCE_BYTES];
    gi_farm_host *host;
    gi_outq out; /* frames not yet written */
    /* Leases held. */
    gi_farm_lease *leases;
    size_t lease_count, lease_cap;
    /* Jobs whose JOB frame this connection has had. */
    uint64_t *jobs_sent;
    size_t jobs_sent_count, jobs_sent_cap;
    /* ASSET_NEEDs waiting for room in the output queue (answered in order). */
    char (*asset_q)[GI_HASH_HEX];
    size_t asset_q_head, asset_q_count, asset_q_cap;
    uint64_t tasks_done, tasks_failed, result_bytes;
    double lost_at; /* monotonic: when a loss of its host was last counted for it; 0: never */
    char close_reason[256];
} gi_farm_conn;

/* ---- counters (GET /metrics) ------------------------------------------- */

typedef struct gi_farm_metrics {
    uint64_t jobs_submitted, jobs_done, jobs_failed, jobs_cancelled, jobs_retried;
    uint64_t tasks_leased, task_results, task_failures, late_results, lease_expiries;
    uint64_t requeued;
    uint64_t tasks_lost; /* runs lost with their host: requeued, not counted as attempts */
    uint64_t host_losses; /* hosts lost with tasks held, once per loss (blocklisting) */
    uint64_t task_timeouts; /* runs stopped for their time limit: failed (attempts) */
    uint64_t job_exclusions; /* a worker excluded from one job (gi_farm_sched.c, Exclusions) */
    /* Task failures judged the host's, or the job's (gi_farm_sched.c, Blame). */
    uint64_t failures_host, failures_job;
    uint64_t result_bytes, merged_bytes;
    double merge_s, finish_s;
    uint64_t checkpoints, checkpoint_bytes, checkpoint_failures;
    uint64_t workers_accepted, workers_refused, frames_refused;
    uint64_t handshakes_displaced; /* closed unauthenticated for a newer connection */
    uint64_t api_requests, api_refused_auth, api_refused_input;
    uint64_t api_slow_closed; /* connections cut for a request head not sent in time */
    /* cut to keep a slot free (the longest idle, a request behind --api-min-rate, or one over) */
    uint64_t api_conns_shed;
    uint64_t api_slow_requests; /* requests cut out of time in hand (--api-min-rate) */
    uint64_t assets_uploaded, asset_bytes_uploaded, assets_served;
} gi_farm_metrics;

/* ---- the context ------------------------------------------------------- */

#define GI_FARM_STALL_WINDOW 60

struct gi_farm {
    gi_farm_config cfg;
    uint8_t key[GI_AUTH_KEY_BYTES];
    volatile int stop;
    int lock_fd;
    char *assets_dir, *jobs_dir;
    gi_journal journal;
    double started; /* monotonic */
    double started_wall;

    gi_farm_job **jobs; /* by submission order */
    size_t job_count, job_cap;
    int jobs_unsorted;  /* some job's id is below an earlier one's (a damaged journal) */
    /* The jobs not ended (checking or running), in submission order: what
     * the loop's poll set, timers and scheduler go through, so that a
     * farm's history of ended jobs costs them nothing (gi_farm_live_jobs). */
    gi_farm_job **live;
    size_t live_count, live_cap;
    int live_stale; /* a job was added, ended, reopened or purged since */
    int ended_flush_due; /* an ended job may have its END or log lines to write */
    uint64_t next_job_id;
    double retention_next; /* monotonic: the next retention pass (gi_farm_jobs.c) */
    uint64_t store_bytes;  /* bytes in the asset store */
    uint64_t upload_bytes; /* bytes in assets/tmp: uploads under way */

    int worker_fd;
    char worker_addr[80];
    gi_farm_conn **conns;
    size_t conn_count, conn_cap;
    uint64_t next_conn_id;
    gi_farm_host **hosts;
    size_t host_count, host_cap;
    /* The hosts' standing changed since <state>/standing was written, and
     * when it may be written next (monotonic; gi_farm_standing.c). */
    int standing_dirty;
    double standing_next;
    int standing_unsaved; /* the last write failed (said once until one works) */
    /* Refusals of peers not authenticated (worker handshakes, API tokens):
     * a line per peer and 10 s at most. */
    gi_refusal_log refusals;

    int api_fd;
    char api_addr[80];
    struct MHD_Daemon *mhd;
    struct gi_api_conn *api_conns; /* the API's TCP connections (gi_farm_api.c) */
    double api_ran_at;        /* the end of the API's last turn in the loop */
    int api_pace_unknown;     /* the kernel gave no TCP byte counts: said once */
    uint64_t submit_buffered; /* bytes of submission bodies held while they arrive */
    /* libmicrohttpd's messages: a line per --refusal-log-window, then a count. */
    double mhd_log_since;
    uint64_t mhd_log_suppressed;
    char mhd_log_last[300];

    /* ASSET_PUT frames served lately: each host asks for the same bytes. */
    gi_frame_cache asset_frames;

    gi_farm_metrics m;

    /* Written by a job's finish thread when it ends (gi_jobrun_opts):
     * an eventfd in the poll set, so that the loop takes the end in at once. */
    int finish_wake_fd;
    const char *finish_gate; /* GI_FAULT_FINISH_GATE_ENV, or NULL */
    /* The loop's longest iteration (time out of poll) in each of the last
     * GI_FARM_STALL_WINDOW seconds, by second, and since it started. */
    double stall_max[GI_FARM_STALL_WINDOW];
    int64_t stall_sec[GI_FARM_STALL_WINDOW];
    double stall_max_ever;
};

/* The loop's longest iteration within the last GI_FARM_STALL_WINDOW
 * seconds (GET /metrics). */
double gi_farm_loop_stall(const gi_farm *f, double now);

double gi_farm_wallnow(void); /* epoch seconds (monotonic time is gi_now) */

/* gi_farm_jobs.c */
int gi_farm_jobs_replay(gi_farm *f, gi_error *err);
/* A validated submission: takes over text (malloc'ed) and manifest. Returns
 * the new job, or NULL with err (GI_EINVAL: bad job; GI_ENOMEM: full). */
gi_farm_job *gi_farm_job_submit(gi_farm *f, const char *file, char *text,
                                gi_manifest *manifest, uint32_t priority, const char *key,
                                gi_error *err);
gi_farm_job *gi_farm_job_find(gi_farm *f, uint64_t id);
/* The job submitted with this Idempotency-Key (key: NULL if none), or NULL. */
gi_farm_job *gi_farm_job_by_key(gi_farm *f, const char *key);
/* Output `name` of job `id` was sent whole to peer: the first time, the
 * job is fetched (journaled, logged). A job purged or retried meanwhile
 * is left alone. */
void gi_farm_job_fetched(gi_farm *f, uint64_t id, const char *name, const char *peer);
/* The jobs not ended, in submission order (rebuilt here after a change).
 * Valid until the next call: a job that ends meanwhile stays in it. */
gi_farm_job **gi_farm_live_jobs(gi_farm *f, size_t *count);
int gi_farm_job_cancel(gi_farm *f, gi_farm_job *j, const char *why);
int gi_farm_job_purge(gi_farm *f, gi_farm_job *j, gi_error *err);
/* Runs a failed or cancelled job again, from its last checkpoint if it has
 * one (journaled first). GI_EINVAL: the job is not failed or cancelled;
 * GI_ENOMEM: the farm is at its limit of unfinished jobs. */
int gi_farm_job_retry(gi_farm *f, gi_farm_job *j, gi_error *err);
/* Called after merges: ends the job if its run is done (outputs written or failed). */
void gi_farm_job_settle(gi_farm *f, gi_farm_job *j);
void gi_farm_job_fail(gi_farm *f, gi_farm_job *j, const gi_error *why);
void gi_farm_job_log(gi_farm_job *j, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The same for what an operator must see: logged as a warning. */
void gi_farm_job_warn(gi_farm_job *j, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Routes this thread's warnings to j's log as well (NULL: stop). */
void gi_farm_job_logging(gi_farm_job *j);
void gi_farm_job_task_error(gi_farm_job *j, uint64_t task, uint32_t attempt,
                            const char *worker, const char *msg);
/* Timers: checker deadlines and periodic checkpoints. */
void gi_farm_jobs_tick(gi_farm *f);
/* Checkpoints every running job now (shutdown). */
void gi_farm_jobs_checkpoint_all(gi_farm *f);
void gi_farm_jobs_free(gi_farm *f);
/* When retention (--keep-ended) purges job j (epoch seconds), or 0 if it
 * does not: not ended, or no --keep-ended. */
double gi_farm_job_purge_at(const gi_farm *f, const gi_farm_job *j);
/* Output file path of a finished job, or NULL if the job has no such output. */
char *gi_farm_job_output_path(const gi_farm_job *j, const char *name);
/* Fraction, ETA (< 0: unknown or not running), frames and work of a job.
 * The fraction is 1 only once it is done: at most GI_FARM_PROGRESS_NOT_DONE
 * before (99.9% in the views), its outputs being the last of its work. */
#define GI_FARM_PROGRESS_NOT_DONE 0.999
void gi_farm_job_progress(const gi_farm_job *j, gi_progress_at *out);

/* The checker's verdict (NULL: the scene loads): loads and starts the job,
 * or fails it. */
void gi_farm_job_checked(gi_farm *f, gi_farm_job *j, const gi_error *why);

/* gi_farm_check.c. Test hook: with GI_FAULT_CHECK_CRASH set in gi-farmd's
 * environment, every checker crashes (SIGSEGV) as a hostile mesh might make
 * it. */
#define GI_FAULT_CHECK_CRASH_ENV "GI_FAULT_CHECK_CRASH"
/* Test hook: with GI_FAULT_FINISH_GATE=PATH in gi-farmd's environment, every
 * job's finish waits on its thread, before it writes the outputs, until a
 * file PATH exists (and removes it: one file lets one finish through), so
 * that tests can look at, cancel or stop a finishing job whatever the
 * machine's load. */
#define GI_FAULT_FINISH_GATE_ENV "GI_FAULT_FINISH_GATE"
int gi_farm_check_start(gi_farm *f, gi_farm_job *j, gi_error *err);
/* Reads what the checker wrote; at its end, calls gi_farm_job_checked. */
void gi_farm_check_readable(gi_farm *f, gi_farm_job *j);
void gi_farm_check_deadline(gi_farm *f, gi_farm_job *j, double now);
void gi_farm_check_kill(gi_farm_job *j);
/* Parses the job text and loads its scene from the store through the
 * manifest (the checker child and then the coordinator itself). */
int gi_farm_load_job(const gi_farm *f, const gi_farm_job *j, gi_job *job, gi_error *err);

/* gi_farm_store.c: content-addressed bytes in <state>/assets. */
char *gi_farm_store_path(const gi_farm *f, const char *hash);
int gi_farm_store_has(const gi_farm *f, const char *hash, uint64_t *size);
int gi_farm_store_read(const gi_farm *f, const char *hash, gi_buf *out, gi_error *err);
int gi_farm_store_put(gi_farm *f, const char *hash, const void *data, size_t len, gi_error *err);
/* -1 with err (GI_ENOMEM, "the asset store is full...") if `more` bytes
 * do not fit beside the store's and the uploads' under way. */
int gi_farm_store_room(const gi_farm *f, uint64_t more, gi_error *err);
/* Streaming upload: bytes go to a temporary file while being hashed; the
 * bytes written count against --max-store-bytes as they arrive
 * (GI_ENOMEM once they do not fit). */
typedef struct gi_farm_upload gi_farm_upload;
gi_farm_upload *gi_farm_upload_begin(gi_farm *f, const char *hash, gi_error *err);
int gi_farm_upload_write(gi_farm_upload *u, const void *data, size_t len, gi_error *err);
/* Verifies the hash and moves the file into place; frees u. */
int gi_farm_upload_finish(gi_farm *f, gi_farm_upload *u, gi_error *err);
void gi_farm_upload_abort(gi_farm_upload *u);
int gi_farm_store_scan(gi_farm *f, gi_error *err);
/* Touched: a client was told the store has it (a job about to name it). */
void gi_farm_store_touch(const gi_farm *f, const char *hash);
/* Removes the files of m (hashes) that no job of the farm names in its
 * manifest or published data: files of a manifest only once untouched for
 * GI_FARM_STORE_GRACE_S (an upload's job may not be submitted yet).
 * Returns the bytes freed. */
#define GI_FARM_STORE_GRACE_S 600.0
uint64_t gi_farm_store_release(gi_farm *f, const gi_manifest *m, int uploaded);
/* Bytes of hash for a worker: a live job's published data, else the store. */
int gi_farm_asset_bytes(gi_farm *f, const char *hash, gi_buf *out, gi_error *err);

/* gi_farm_conn.c */
int gi_farm_conn_accept(gi_farm *f);
void gi_farm_conn_readable(gi_farm *f, gi_farm_conn *c);
void gi_farm_conn_writable(gi_farm *f, gi_farm_conn *c);
void gi_farm_conn_send(gi_farm_conn *c, uint16_t type, const gi_buf *payload, int compress);
/* Refuses or ends a connection: logs the reason, sends ERROR when it can,
 * hands its leases back. */
void gi_farm_conn_close(gi_farm *f, gi_farm_conn *c, gi_errcode code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
void gi_farm_conns_tick(gi_farm *f);
/* Removes connections marked closed (after the loop dispatched events). */
void gi_farm_conns_reap(gi_farm *f);
/* A stopping coordinator's goodbye: BYE to every worker and what was
 * queued flushed (best effort), then up to wait_s for them to hang up,
 * so that they hear it rather than a reset connection. Closes them all. */
void gi_farm_conns_goodbye(gi_farm *f, double wait_s);
int gi_farm_conn_wants_write(const gi_farm_conn *c);
/* Sends the job's JOB frame once per connection. */
void gi_farm_conn_send_job(gi_farm_conn *c, const gi_farm_job *j);

/* gi_farm_sched.c */
void gi_farm_schedule(gi_farm *f);
void gi_farm_sched_result(gi_farm *f, gi_farm_conn *c, const gi_buf *payload);
void gi_farm_sched_fail(gi_farm *f, gi_farm_conn *c, const gi_buf *payload);
void gi_farm_sched_heartbeat(gi_farm *f, gi_farm_conn *c, const gi_msg_tasklist *hb);
void gi_farm_sched_drain(gi_farm *f, gi_farm_conn *c, const gi_msg_tasklist *back);
/* A connection is going away: its leases fail (crash = 1: the worker was
 * lost) or go back to their queues unrun (crash = 0: it said goodbye). */
void gi_farm_sched_release(gi_farm *f, gi_farm_conn *c, int crash, const char *why);
void gi_farm_sched_expire(gi_farm *f, double now);
/* Forgets every lease of a job (cancelled / failed / done) and tells every
 * worker: the job is over, or (a failed job that kept batches) stopped. */
void gi_farm_sched_drop_job(gi_farm *f, gi_farm_job *j);
/* Tells every worker that job `id` is over (it was purged). */
void gi_farm_sched_job_over(gi_farm *f, uint64_t id);
/* A worker that just joined hears of every job that kept batches on its
 * hosts and ended within GI_BATCH_DIR_MAX_AGE_S: it may hold their
 * directories from before it was away (or restarted) when they ended. */
void gi_farm_sched_welcome(gi_farm *f, gi_farm_conn *c);
gi_farm_host *gi_farm_host_get(gi_farm *f, const char *name);
int gi_farm_host_blocked(const gi_farm_host *h, double now);
/* j's entry for h (made if it has none): its standing with the job. */
gi_fj_exclusion *gi_farm_job_exclusion(gi_farm_job *j, gi_farm_host *h);
/* Is h excluded from job j now (gi_farm_sched.c, Exclusions)? */
int gi_farm_job_excludes(const gi_farm_job *j, const gi_farm_host *h, double now);
/* Can some connected worker take j's tasks now, slots or not (active, not
 * blocklisted, not excluded from j)? */
int gi_farm_job_has_host(const gi_farm *f, const gi_farm_job *j, double now);
/* Makes a job that just became runnable start at the current fair share. */
void gi_farm_sched_join(gi_farm *f, gi_farm_job *j);
/* The job's affinity owners, by host name, in a file beside its checkpoint
 * (written atomically; a hint: failures are logged, never fatal). */
void gi_farm_affinity_save(const gi_farm_job *j, const char *path);
void gi_farm_affinity_load(gi_farm *f, gi_farm_job *j, const char *path);

/* gi_farm_standing.c: the hosts' standing in <state>/standing. Changes
 * set f->standing_dirty; the tick writes them at most once a second, save
 * at once (gi-farmd stopping); load once the journal is replayed. */
void gi_farm_standing_tick(gi_farm *f);
void gi_farm_standing_save(gi_farm *f);
void gi_farm_standing_load(gi_farm *f);

/* gi_farm_api.c */
int gi_farm_api_start(gi_farm *f, gi_error *err);
int gi_farm_api_fd(gi_farm *f);      /* MHD's epoll descriptor */
int gi_farm_api_timeout_ms(gi_farm *f);
void gi_farm_api_run(gi_farm *f);
void gi_farm_api_stop(gi_farm *f);

/* gi_farm_views.c: JSON documents and metrics (strings are malloc'ed). */
char *gi_farm_view_job(gi_farm *f, const gi_farm_job *j);
char *gi_farm_view_jobs(gi_farm *f);
char *gi_farm_view_workers(gi_farm *f);
char *gi_farm_view_metrics(gi_farm *f);
extern const char gi_farm_dashboard_html[];

#endif
