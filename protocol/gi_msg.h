/* gi_msg: payloads of the protocol messages that carry jobs, tasks and
 * results (the same between a worker and its pool children as between the
 * coordinator and remote workers). Every field is written explicitly; every
 * decoder checks lengths against limits and rejects trailing bytes. */
#ifndef GI_MSG_H
#define GI_MSG_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_buf.h"
#include "gi_error.h"
#include "gi_task.h"

#define GI_MSG_MAX_TEXT (16u << 20)     /* job text */
#define GI_MSG_MAX_TASK ((256ull << 20) - 4096) /* task payload (under the frame limit) */
#define GI_MSG_MAX_RESULT ((1ull << 30) - 4096) /* result payload (under the frame limit) */
#define GI_MSG_MAX_ERROR 4096           /* error message */

/* JOB: the job's text and the assets its scene reads. */
typedef struct gi_msg_job {
    uint64_t job_id;
    char *file; /* the job's name for messages */
    char *text;
    gi_manifest manifest;
} gi_msg_job;

void gi_msg_job_encode(gi_buf *out, uint64_t job_id, const char *file, const char *text,
                       const gi_manifest *manifest);
int gi_msg_job_decode(const gi_buf *in, gi_msg_job *out, gi_error *err);
void gi_msg_job_free(gi_msg_job *m);

/* TASK: one task of a job. The decoded payload points into `in`. A
 * non-zero affinity follows the payload as an optional u64 (absent when 0,
 * so tasks without one encode as in earlier versions). */
typedef struct gi_msg_task {
    uint64_t job_id;
    gi_task task; /* payload is a copy */
} gi_msg_task;

void gi_msg_task_encode(gi_buf *out, uint64_t job_id, const gi_task *task);
int gi_msg_task_decode(const gi_buf *in, gi_msg_task *out, gi_error *err);

/* RESULT: a finished task's result and statistics. */
typedef struct gi_msg_result {
    uint64_t job_id, task_id;
    uint32_t attempt;
    gi_task_stats stats;
    gi_buf data;
} gi_msg_result;

void gi_msg_result_encode(gi_buf *out, uint64_t job_id, uint64_t task_id, uint32_t attempt,
                          const gi_task_stats *stats, const void *data, size_t len);
int gi_msg_result_decode(const gi_buf *in, gi_msg_result *out, gi_error *err);

/* FAIL: a task that could not be run (with the gi_errcode and message). */
typedef struct gi_msg_fail {
    uint64_t job_id, task_id;
    uint32_t attempt;
    gi_error error;
} gi_msg_fail;

void gi_msg_fail_encode(gi_buf *out, uint64_t job_id, uint64_t task_id, uint32_t attempt,
                        const gi_error *error);
int gi_msg_fail_decode(const gi_buf *in, gi_msg_fail *out, gi_error *err);

/* ASSET_NEED: a hash. ASSET_PUT: a hash and the bytes (checked against it). */
void gi_msg_asset_need_encode(gi_buf *out, const char hash[GI_HASH_HEX]);
int gi_msg_asset_need_decode(const gi_buf *in, char hash[GI_HASH_HEX], gi_error *err);
void gi_msg_asset_put_encode(gi_buf *out, const char hash[GI_HASH_HEX], const void *data,
                             size_t len);
/* *data points into `in`; fails if the bytes do not hash to `hash`. */
int gi_msg_asset_put_decode(const gi_buf *in, char hash[GI_HASH_HEX], const uint8_t **data,
                            size_t *len, gi_error *err);

/* ERROR: a refusal with a code and message. */
void gi_msg_error_encode(gi_buf *out, const gi_error *error);
int gi_msg_error_decode(const gi_buf *in, gi_error *out, gi_error *err);

#endif
