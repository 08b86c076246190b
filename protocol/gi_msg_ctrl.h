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
 * lists [proto_min, proto_max], CHALLENGE names the one chosen) and every
 * later frame carries it in its header. The HELLO frame itself is always in
 * version-1 framing so that any coordinator can read it and refuse cleanly.
 * Every field is explicit; decoders check every length and refuse trailing
 * bytes. */
#ifndef GI_MSG_CTRL_H
#define GI_MSG_CTRL_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

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

/* A task a worker holds. */
typedef struct gi_msg_taskref {
    uint64_t job_id, task_id;
    uint32_t attempt;
} gi_msg_taskref;

/* HEARTBEAT: a sequence number and, from a worker, the tasks it holds
 * (running or queued): their leases are renewed. From a coordinator the
 * list is empty. DRAIN (worker -> coordinator): the worker is shutting
 * down; the listed tasks are handed back unrun, the rest will be finished. */
typedef struct gi_msg_tasklist {
    uint64_t seq; /* HEARTBEAT: increasing; DRAIN: 0 */
    gi_msg_taskref *refs;
    uint32_t count;
} gi_msg_tasklist;

void gi_msg_tasklist_encode(gi_buf *out, uint64_t seq, const gi_msg_taskref *refs,
                            uint32_t count);
/* what names the message in errors ("HEARTBEAT message"). */
int gi_msg_tasklist_decode(const gi_buf *in, const char *what, gi_msg_tasklist *out,
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
