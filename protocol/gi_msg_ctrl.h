/* gi_msg_ctrl: payloads of the control messages between a coordinator and a
 * remote worker: the handshake (HELLO, CHALLENGE, AUTH, WELCOME), HEARTBEAT,
 * CANCEL and DRAIN. (Jobs, tasks, results and assets are in gi_msg.h.)
 *
 * Handshake (docs/farm.md, "Protocol"):
 *   worker      -> HELLO     versions it speaks, its nonce, name, resources
 *   coordinator -> CHALLENGE the version chosen, its nonce
 *   worker      -> AUTH      MAC(secret; both nonces, HELLO)     (gi_auth.h)
 *   coordinator -> WELCOME   worker id, timings, MAC(secret; nonces, id)
 * Both sides prove they know the farm secret; neither sends it.
 *
 * Versioning: a message set version is negotiated in the handshake (HELLO
 * lists [proto_min, proto_max], CHALLENGE names the one chosen: the highest
 * both speak, gi_msg_proto_choose) and decides the payloads' forms for the
 * rest of the connection. Frames keep their own version (GI_FRAME_VERSION:
 * the header layout, which no message set version has changed), so the
 * HELLO frame of any worker can be read by any coordinator, which refuses
 * cleanly when they have no version in common. The versions:
 *   1  the first;
 *   2  a worker's HEARTBEAT says of each task it holds whether its pool runs
 *      it and for how long (gi_msg_taskref.running, run_ms): task time
 *      limits count from the run's start, not from the lease.
 * Every field is explicit; decoders check every length and refuse trailing
 * bytes. */
#ifndef GI_MSG_CTRL_H
#define GI_MSG_CTRL_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

#define GI_PROTO_MIN 1  /* the message set versions this build speaks */
#define GI_PROTO_MAX 2
#define GI_PROTO_RUNS 2 /* the first whose HEARTBEAT tells which held tasks run */

#define GI_MSG_NONCE_BYTES 32
#define GI_MSG_MAC_BYTES 32
#define GI_MSG_MAX_NAME 255      /* worker name */
#define GI_MSG_MAX_VERSION 64    /* software version string */
#define GI_MSG_MAX_TASKREFS 4096 /* task lists in HEARTBEAT and DRAIN */
#define GI_MSG_ALL_TASKS UINT64_MAX /* CANCEL: every task of the job */
/* CANCEL: every task of the job, which stopped but may be retried (it
 * failed): the worker keeps its batch directory. */
#define GI_MSG_JOB_STOPPED (UINT64_MAX - 1)

typedef struct gi_msg_hello {
    uint32_t proto_min, proto_max;
    uint8_t nonce[GI_MSG_NONCE_BYTES];
    char *name;    /* e.g. the host name; shown in `gi workers`, used for blocklisting */
    char *version; /* the worker's GI_VERSION */
    uint32_t procs; /* pool children */
    uint32_t slots; /* tasks it accepts at once (running + queued), >= procs */
    uint32_t cores; /* online CPUs */
    uint64_t memory; /* physical memory, bytes */
} gi_msg_hello;

void gi_msg_hello_encode(gi_buf *out, const gi_msg_hello *m);
int gi_msg_hello_decode(const gi_buf *in, gi_msg_hello *out, gi_error *err);
void gi_msg_hello_free(gi_msg_hello *m);

/* The version a coordinator picks for a worker speaking [min, max]: the
 * highest this build speaks too, or 0 when there is none. */
uint32_t gi_msg_proto_choose(uint32_t min, uint32_t max);

typedef struct gi_msg_challenge {
    uint32_t proto; /* the version chosen */
    uint8_t nonce[GI_MSG_NONCE_BYTES];
} gi_msg_challenge;

void gi_msg_challenge_encode(gi_buf *out, const gi_msg_challenge *m);
int gi_msg_challenge_decode(const gi_buf *in, gi_msg_challenge *out, gi_error *err);

/* AUTH is the worker's MAC alone. */
void gi_msg_auth_encode(gi_buf *out, const uint8_t mac[GI_MSG_MAC_BYTES]);
int gi_msg_auth_decode(const gi_buf *in, uint8_t mac[GI_MSG_MAC_BYTES], gi_error *err);

typedef struct gi_msg_welcome {
    uint64_t worker_id;
    uint32_t heartbeat_ms; /* send a HEARTBEAT at least this often */
    uint32_t lease_ms;     /* a task not renewed for this long is given to another worker */
    uint8_t mac[GI_MSG_MAC_BYTES];
} gi_msg_welcome;

void gi_msg_welcome_encode(gi_buf *out, const gi_msg_welcome *m);
int gi_msg_welcome_decode(const gi_buf *in, gi_msg_welcome *out, gi_error *err);

/* A task a worker holds. running and run_ms are on the wire only in a
 * list with runs (below); elsewhere they are 0. */
typedef struct gi_msg_taskref {
    uint64_t job_id, task_id;
    uint32_t attempt;
    uint8_t running; /* 1: a pool child runs it; 0: it waits in the worker's queue */
    uint32_t run_ms; /* running: for how long so far (saturated); queued: 0 */
} gi_msg_taskref;

/* HEARTBEAT: a sequence number and, from a worker, the tasks it holds
 * (running or queued): their leases are renewed. From a coordinator the
 * list is empty. DRAIN (worker -> coordinator): the worker is shutting
 * down; the listed tasks are handed back unrun, the rest will be finished.
 *
 * runs != 0 (a HEARTBEAT in protocol GI_PROTO_RUNS and later) adds to each
 * reference a u8 running flag (0 or 1) and a u32 run_ms (0 when queued);
 * DRAIN never has them (what it hands back never ran). */
typedef struct gi_msg_tasklist {
    uint64_t seq; /* HEARTBEAT: increasing; DRAIN: 0 */
    gi_msg_taskref *refs;
    uint32_t count;
} gi_msg_tasklist;

void gi_msg_tasklist_encode(gi_buf *out, uint64_t seq, const gi_msg_taskref *refs,
                            uint32_t count, int runs);
/* what names the message in errors ("HEARTBEAT message"). */
int gi_msg_tasklist_decode(const gi_buf *in, const char *what, int runs, gi_msg_tasklist *out,
                           gi_error *err);
void gi_msg_tasklist_free(gi_msg_tasklist *m);

/* CANCEL (coordinator -> worker): drop a task, or every task of a job
 * and the job itself (task_id GI_MSG_ALL_TASKS: the job is over, its batch
 * directory goes too; GI_MSG_JOB_STOPPED: the directory stays); running
 * ones are killed. */
typedef struct gi_msg_cancel {
    uint64_t job_id, task_id;
} gi_msg_cancel;

void gi_msg_cancel_encode(gi_buf *out, const gi_msg_cancel *m);
int gi_msg_cancel_decode(const gi_buf *in, gi_msg_cancel *out, gi_error *err);

#endif
