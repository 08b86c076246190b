/* gi_journal: the coordinator's append-only record of job state, in the
 * state directory, so a restarted gi-farmd knows every job it had.
 *
 * File layout (little-endian; docs/farm.md, "Journal"):
 *   header   "GIJ1" | u32 version (5; versions 1 to 4, without RETRY, END
 *            summaries, their losses, SUBMIT keys or FETCHED, are read too)
 *   record   u32 type | u32 length | payload | u32 crc32c(type, length, payload)
 * Records:
 *   SUBMIT      job id, priority, submit time, job file name, job text, manifest,
 *               and the submission's Idempotency-Key if it had one (version 5)
 *   CHECKPOINT  job id, sequence, tasks merged, tasks planned (the checkpoint
 *               itself is a file next to the job; the record is its history)
 *   END         job id, final state (done / failed / cancelled), error code
 *               and message, time
 *   PURGE       job id: forget the job (its files are removed)
 *   RETRY       job id, time: a failed or cancelled job runs again, from its
 *               last checkpoint if it has one
 *   FETCHED     job id, time: an output of the done job was first downloaded
 *               whole through the API (retention purges such jobs first)
 * Each append is written with one write() and fdatasync'ed before the
 * coordinator acts on it. A crash can only tear the last record; replay
 * stops at a last record that is short or fails its CRC (a damaged record
 * followed by an intact one is skipped alone: bit rot) and the journal is
 * then rewritten without it (compaction: one SUBMIT, the last CHECKPOINT,
 * the END and the FETCHED of every job; a retried job is unfinished again,
 * so no RETRY survives it). */
#ifndef GI_JOURNAL_H
#define GI_JOURNAL_H

#include <stddef.h>
#include <stdint.h>

#include "gi_assets.h"
#include "gi_buf.h"
#include "gi_error.h"

#define GI_JOURNAL_MAX_RECORD (64u << 20) /* a SUBMIT holds a job (<= 16 MiB) and its manifest */
/* Job ids are in [1, GI_JOB_ID_MAX]: the API's JSON numbers are exact up
 * to 2^53. A record with another id is damage. */
#define GI_JOB_ID_MAX ((UINT64_C(1) << 53) - 1)

typedef enum gi_jrec_type {
    GI_JREC_SUBMIT = 1,
    GI_JREC_CHECKPOINT = 2,
    GI_JREC_END = 3,
    GI_JREC_PURGE = 4,
    GI_JREC_RETRY = 5,
    GI_JREC_FETCHED = 6
} gi_jrec_type;

/* A submission's Idempotency-Key: 16 to 64 of A-Z a-z 0-9 - _ (a client's
 * random token, kept with its job; docs/farm.md, "API"). */
#define GI_SUBMIT_KEY_MIN 16
#define GI_SUBMIT_KEY_MAX 64
int gi_submit_key_valid(const char *key);

/* Final job states in END records. */
typedef enum gi_job_end {
    GI_JOB_END_DONE = 1,
    GI_JOB_END_FAILED = 2,
    GI_JOB_END_CANCELLED = 3
} gi_job_end;

typedef struct gi_jrec {
    gi_jrec_type type;
    uint64_t job_id;
    size_t at; /* replay: where the record starts in the journal */
    /* SUBMIT */
    uint32_t priority;
    double submitted; /* seconds since the epoch */
    char *file;
    char *text;
    gi_manifest manifest;
    char *key; /* version 5 on: the Idempotency-Key, NULL if none */
    /* CHECKPOINT */
    uint64_t seq, merged, tasks;
    /* END */
    uint32_t end;  /* gi_job_end */
    uint32_t code; /* gi_errcode */
    char *message;
    double when; /* END, RETRY, FETCHED */
    /* END's summary of the run, so that a restarted coordinator still shows
     * it (journals before it lack it: has_summary 0). Also uses tasks and
     * merged. */
    int has_summary;
    double started, seconds, fraction, done, total;
    uint64_t retries, rays, samples;
    uint32_t frame, frames;
    int has_losses;  /* version 4 on: the summary ends with losses */
    uint64_t losses; /* tasks lost with their host and requeued */
} gi_jrec;

void gi_jrec_init(gi_jrec *r, gi_jrec_type type, uint64_t job_id);
void gi_jrec_free(gi_jrec *r);
/* Appends the record (header, payload, CRC) to out. Strings are borrowed. */
void gi_jrec_encode(const gi_jrec *r, gi_buf *out);

/* Parses journal bytes (header included): calls fn for every intact record
 * in order (the record is freed after fn returns; fn returns 0 to go on).
 * A damaged record (bad CRC or payload, plausible length) that an intact
 * record follows is bit rot, not a torn tail: it is skipped with a warning
 * naming its offset and type, and counted in *skipped. *valid gets the end
 * of the last intact record. Returns 0 when the data ends with an intact
 * record, 1 when it ends in a torn or damaged one (msg says where and why;
 * what follows it is ignored), -1 when fn failed or the header is not a
 * journal's. */
int gi_journal_parse(const uint8_t *data, size_t len,
                     int (*fn)(void *ctx, const gi_jrec *r, gi_error *err), void *ctx,
                     size_t *valid, size_t *skipped, gi_error *err);

typedef struct gi_journal {
    int fd;
    char *path;
    uint64_t size;    /* bytes in the file */
    uint64_t records; /* appended since open or rewrite */
} gi_journal;

/* Opens (creating if needed) the journal at path and replays it through fn.
 * A torn or damaged tail, or damaged records skipped, are reported with
 * gi_warn; the damaged file is kept as <path>.damaged-<unix time> and the
 * caller is expected to rewrite. Sets *damaged to 1 in that case. */
int gi_journal_open(gi_journal *j, const char *path,
                    int (*fn)(void *ctx, const gi_jrec *r, gi_error *err), void *ctx,
                    int *damaged, gi_error *err);
/* Appends one record durably (write + fdatasync). */
int gi_journal_append(gi_journal *j, const gi_jrec *r, gi_error *err);
/* Replaces the journal with exactly these records (temp file + fsync +
 * rename), then appends go to the new file. */
int gi_journal_rewrite(gi_journal *j, const gi_jrec *const *recs, size_t n, gi_error *err);
void gi_journal_close(gi_journal *j);

#endif
