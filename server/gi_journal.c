/* gi_journal: record encoding, replay with torn-tail detection, durable
 * appends and compaction. */
#include "gi_journal.h"

#include <errno.h>
#include <fcntl.h>
#include <ctype.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gi_crc32c.h"
#include "gi_fs.h"
#include "gi_job.h"
#include "gi_log.h"

#define JOURNAL_MAGIC "GIJ1"
/* 2: RETRY records; 3: ENDs carry the run's summary (a build before it
 * would take such an END for damage, so it refuses the version instead);
 * 4: the summary ends with the run's tasks lost with their host (absent
 * from a version 3 END, read as 0); 5: a SUBMIT ends with its Idempotency-Key
 * (none before: a restart forgot the keys, and a client's retry made a
 * second job), and FETCHED records. */
#define JOURNAL_VERSION 5u
#define HEADER_BYTES 8
#define RECORD_OVERHEAD 12 /* type, length, crc */
#define MAX_FILE_NAME 4096
#define MAX_MESSAGE 4096

int gi_submit_key_valid(const char *k)
{
    size_t n = strlen(k);
    if (n < GI_SUBMIT_KEY_MIN || n > GI_SUBMIT_KEY_MAX)
        return 0;
    for (size_t i = 0; i < n; i++)
        if (!isalnum((unsigned char)k[i]) && k[i] != '-' && k[i] != '_')
            return 0;
    return 1;
}

void gi_jrec_init(gi_jrec *r, gi_jrec_type type, uint64_t job_id)
{
    memset(r, 0, sizeof *r);
    r->type = type;
    r->job_id = job_id;
    gi_manifest_init(&r->manifest);
}

void gi_jrec_free(gi_jrec *r)
{
    free(r->file);
    free(r->text);
    free(r->message);
    free(r->key);
    gi_manifest_free(&r->manifest);
    r->file = r->text = r->message = r->key = NULL;
}

static void encode_payload(const gi_jrec *r, gi_buf *out)
{
    gi_buf_put_u64(out, r->job_id);
    switch (r->type) {
    case GI_JREC_SUBMIT:
        gi_buf_put_u32(out, r->priority);
        gi_buf_put_f64(out, r->submitted);
        gi_buf_put_str(out, r->file);
        gi_buf_put_str(out, r->text);
        gi_manifest_encode(&r->manifest, out);
        if (r->key)
            gi_buf_put_str(out, r->key);
        break;
    case GI_JREC_CHECKPOINT:
        gi_buf_put_u64(out, r->seq);
        gi_buf_put_u64(out, r->merged);
        gi_buf_put_u64(out, r->tasks);
        break;
    case GI_JREC_END:
        gi_buf_put_u32(out, r->end);
        gi_buf_put_u32(out, r->code);
        gi_buf_put_str(out, r->message);
        gi_buf_put_f64(out, r->when);
        if (r->has_summary) {
            gi_buf_put_f64(out, r->started);
            gi_buf_put_u64(out, r->tasks);
            gi_buf_put_u64(out, r->merged);
            gi_buf_put_u64(out, r->retries);
            gi_buf_put_u64(out, r->rays);
            gi_buf_put_u64(out, r->samples);
            gi_buf_put_f64(out, r->seconds);
            gi_buf_put_f64(out, r->fraction);
            gi_buf_put_f64(out, r->done);
            gi_buf_put_f64(out, r->total);
            gi_buf_put_u32(out, r->frame);
            gi_buf_put_u32(out, r->frames);
            if (r->has_losses)
                gi_buf_put_u64(out, r->losses);
        }
        break;
    case GI_JREC_PURGE:
        break;
    case GI_JREC_RETRY:
    case GI_JREC_FETCHED:
        gi_buf_put_f64(out, r->when);
        break;
    }
}

void gi_jrec_encode(const gi_jrec *r, gi_buf *out)
{
    size_t start = out->len;
    gi_buf_put_u32(out, (uint32_t)r->type);
    gi_buf_put_u32(out, 0); /* length, patched below */
    size_t body = out->len;
    encode_payload(r, out);
    gi_le_put_u32(out->data + start + 4, (uint32_t)(out->len - body));
    gi_buf_put_u32(out, gi_crc32c(0, out->data + start, out->len - start));
}

static int decode_payload(uint32_t type, const uint8_t *p, size_t n, gi_jrec *r,
                          gi_error *err)
{
    gi_reader rd;
    gi_reader_init(&rd, p, n, "journal record");
    gi_jrec_init(r, (gi_jrec_type)type, gi_get_u64(&rd));
    /* Ids are JSON numbers in the API, and the next id is one more. */
    if (!rd.failed && (r->job_id < 1 || r->job_id > GI_JOB_ID_MAX))
        return gi_fail(err, GI_EPROTO, "journal record: job id %llu out of range",
                       (unsigned long long)r->job_id);
    switch (type) {
    case GI_JREC_SUBMIT:
        r->priority = gi_get_u32(&rd);
        r->submitted = gi_get_f64(&rd);
        r->file = gi_get_str(&rd, MAX_FILE_NAME);
        r->text = gi_get_str(&rd, GI_JOB_MAX_BYTES);
        if (!rd.failed && gi_manifest_decode(&rd, &r->manifest, err))
            return -1;
        if (!rd.failed && rd.left) { /* version 5 */
            r->key = gi_get_str(&rd, GI_SUBMIT_KEY_MAX);
            if (!rd.failed && !gi_submit_key_valid(r->key))
                return gi_fail(err, GI_EPROTO, "journal SUBMIT: not an Idempotency-Key");
        }
        break;
    case GI_JREC_CHECKPOINT:
        r->seq = gi_get_u64(&rd);
        r->merged = gi_get_u64(&rd);
        r->tasks = gi_get_u64(&rd);
        if (!rd.failed && r->merged > r->tasks)
            return gi_fail(err, GI_EPROTO, "journal CHECKPOINT: %llu of %llu tasks merged",
                           (unsigned long long)r->merged, (unsigned long long)r->tasks);
        break;
    case GI_JREC_END:
        r->end = gi_get_u32(&rd);
        r->code = gi_get_u32(&rd);
        r->message = gi_get_str(&rd, MAX_MESSAGE);
        r->when = gi_get_f64(&rd);
        if (!rd.failed && (r->end < GI_JOB_END_DONE || r->end > GI_JOB_END_CANCELLED ||
                           r->code > GI_EHOST))
            return gi_fail(err, GI_EPROTO, "journal END: state %u, code %u out of range",
                           r->end, r->code);
        if (!rd.failed && rd.left) {
            r->has_summary = 1;
            r->started = gi_get_f64(&rd);
            r->tasks = gi_get_u64(&rd);
            r->merged = gi_get_u64(&rd);
            r->retries = gi_get_u64(&rd);
            r->rays = gi_get_u64(&rd);
            r->samples = gi_get_u64(&rd);
            r->seconds = gi_get_f64(&rd);
            r->fraction = gi_get_f64(&rd);
            r->done = gi_get_f64(&rd);
            r->total = gi_get_f64(&rd);
            r->frame = gi_get_u32(&rd);
            r->frames = gi_get_u32(&rd);
            if (!rd.failed && rd.left) { /* version 4 */
                r->has_losses = 1;
                r->losses = gi_get_u64(&rd);
            }
            if (!rd.failed && (r->merged > r->tasks || !(r->fraction >= 0 && r->fraction <= 1) ||
                               !isfinite(r->started) || !isfinite(r->seconds) ||
                               !isfinite(r->done) || !isfinite(r->total) || r->frame >= r->frames))
                return gi_fail(err, GI_EPROTO, "journal END: a summary out of range");
        }
        break;
    case GI_JREC_PURGE:
        break;
    case GI_JREC_RETRY:
        r->when = gi_get_f64(&rd);
        break;
    case GI_JREC_FETCHED:
        r->when = gi_get_f64(&rd);
        if (!rd.failed && !(isfinite(r->when) && r->when > 0))
            return gi_fail(err, GI_EPROTO, "journal FETCHED: time out of range");
        break;
    default:
        return gi_fail(err, GI_EPROTO, "journal record type %u is unknown", type);
    }
    return gi_reader_finish(&rd, err);
}

static const char *type_name(uint32_t type)
{
    switch (type) {
    case GI_JREC_SUBMIT: return "SUBMIT";
    case GI_JREC_CHECKPOINT: return "CHECKPOINT";
    case GI_JREC_END: return "END";
    case GI_JREC_PURGE: return "PURGE";
    case GI_JREC_RETRY: return "RETRY";
    case GI_JREC_FETCHED: return "FETCHED";
    }
    return "unknown";
}

/* The record at off. 0: intact, decoded into r (to be freed), *size its
 * bytes. 1: torn (cut short, or a length past the end). 2: damaged (its CRC
 * or payload is wrong) though its length fits: *size is what it claims. */
static int read_record(const uint8_t *data, size_t len, size_t off, gi_jrec *r, size_t *size,
                       gi_error *err)
{
    gi_jrec_init(r, 0, 0);
    size_t left = len - off;
    if (left < RECORD_OVERHEAD) {
        gi_fail(err, GI_EPROTO, "record at byte %zu is torn (%zu bytes)", off, left);
        return 1;
    }
    uint32_t type = gi_le_get_u32(data + off);
    uint32_t n = gi_le_get_u32(data + off + 4);
    if (n > GI_JOURNAL_MAX_RECORD || n > left - RECORD_OVERHEAD) {
        gi_fail(err, GI_EPROTO, "record at byte %zu is torn or damaged (length %u, %zu bytes left)",
                off, n, left);
        return 1;
    }
    *size = RECORD_OVERHEAD + (size_t)n;
    uint32_t crc = gi_le_get_u32(data + off + 8 + n);
    if (crc != gi_crc32c(0, data + off, 8 + (size_t)n)) {
        gi_fail(err, GI_EPROTO, "record at byte %zu (type %u, %s) fails its CRC", off, type,
                type_name(type));
        return 2;
    }
    if (decode_payload(type, data + off + 8, n, r, err)) {
        gi_jrec_free(r);
        gi_error_prefix(err, "record at byte %zu (type %u, %s)", off, type, type_name(type));
        return 2;
    }
    r->at = off;
    return 0;
}

int gi_journal_parse(const uint8_t *data, size_t len,
                     int (*fn)(void *ctx, const gi_jrec *r, gi_error *err), void *ctx,
                     size_t *valid, size_t *skipped, gi_error *err)
{
    *valid = 0;
    *skipped = 0;
    if (len < HEADER_BYTES || memcmp(data, JOURNAL_MAGIC, 4) != 0)
        return gi_fail(err, GI_EPROTO, "not a gi-farm journal (bad header)");
    uint32_t version = gi_le_get_u32(data + 4);
    if (version < 1 || version > JOURNAL_VERSION)
        return gi_fail(err, GI_EPROTO, "journal version %u is not supported (this build: %u)",
                       version, JOURNAL_VERSION);
    size_t off = HEADER_BYTES;
    *valid = off;
    while (off < len) {
        gi_jrec r;
        size_t size = 0;
        gi_error e;
        int rc = read_record(data, len, off, &r, &size, &e);
        if (rc == 2 && off + size < len) {
            /* A crash tears only the last record: one in the middle that an
             * intact record follows is bit rot, and only it is lost. */
            gi_jrec next;
            size_t next_size;
            gi_error nerr;
            if (read_record(data, len, off + size, &next, &next_size, &nerr) == 0) {
                gi_jrec_free(&next);
                gi_warn("journal: %s: skipped (the records after it are kept)", e.msg);
                ++*skipped;
                off += size;
                continue;
            }
        }
        if (rc) {
            if (err)
                *err = e;
            return 1;
        }
        rc = fn(ctx, &r, err);
        gi_jrec_free(&r);
        if (rc)
            return -1;
        off += size;
        *valid = off;
    }
    return 0;
}

static int write_all_fd(int fd, const void *p, size_t n, const char *path, gi_error *err)
{
    const uint8_t *b = p;
    while (n) {
        ssize_t w = write(fd, b, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0)
            return gi_fail(err, GI_EIO, "%s: write: %s", path, strerror(errno));
        b += w;
        n -= (size_t)w;
    }
    return 0;
}

static void header(gi_buf *b)
{
    gi_buf_put(b, JOURNAL_MAGIC, 4);
    gi_buf_put_u32(b, JOURNAL_VERSION);
}

int gi_journal_open(gi_journal *j, const char *path,
                    int (*fn)(void *ctx, const gi_jrec *r, gi_error *err), void *ctx,
                    int *damaged, gi_error *err)
{
    memset(j, 0, sizeof *j);
    j->fd = -1;
    *damaged = 0;
    j->path = gi_xstrdup(path);
    gi_buf data;
    gi_buf_init(&data);
    struct stat st;
    if (stat(path, &st) == 0) {
        if (gi_read_file(path, (size_t)1 << 34, &data, err))
            goto fail;
    } else if (errno != ENOENT) {
        gi_fail(err, GI_EIO, "%s: %s", path, strerror(errno));
        goto fail;
    }
    if (data.len == 0) {
        header(&data);
        if (gi_write_file_atomic(path, data.data, data.len, err))
            goto fail;
    } else {
        size_t valid, skipped;
        gi_error perr;
        int rc = gi_journal_parse(data.data, data.len, fn, ctx, &valid, &skipped, &perr);
        if (rc < 0) {
            if (err)
                *err = perr;
            gi_error_prefix(err, "%s", path);
            goto fail;
        }
        if (rc > 0 || skipped) {
            char keep[4200];
            long long now = (long long)time(NULL);
            snprintf(keep, sizeof keep, "%s.damaged-%lld", path, now);
            /* Two damaged starts in a second must not lose the first copy. */
            for (int k = 2; access(keep, F_OK) == 0 && k < 1000; k++)
                snprintf(keep, sizeof keep, "%s.damaged-%lld.%d", path, now, k);
            if (rc > 0)
                gi_warn("%s: %s; the %zu bytes from there on are ignored (the file is kept as %s)",
                        path, perr.msg, data.len - valid, keep);
            if (skipped)
                gi_warn("%s: %zu damaged records skipped (the file is kept as %s)", path, skipped,
                        keep);
            gi_error werr;
            if (gi_write_file_atomic(keep, data.data, data.len, &werr))
                gi_warn("%s", werr.msg);
            *damaged = 1;
            /* Keep only the intact prefix; the caller compacts anyway. */
            if (truncate(path, (off_t)valid) != 0) {
                gi_fail(err, GI_EIO, "%s: truncate: %s", path, strerror(errno));
                goto fail;
            }
            data.len = valid;
        }
    }
    j->fd = open(path, O_WRONLY | O_APPEND | O_CLOEXEC);
    if (j->fd < 0) {
        gi_fail(err, GI_EIO, "%s: %s", path, strerror(errno));
        goto fail;
    }
    j->size = data.len;
    gi_buf_free(&data);
    return 0;
fail:
    gi_buf_free(&data);
    gi_journal_close(j);
    return -1;
}

int gi_journal_append(gi_journal *j, const gi_jrec *r, gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_jrec_encode(r, &b);
    int rc = write_all_fd(j->fd, b.data, b.len, j->path, err);
    if (rc == 0 && fdatasync(j->fd) != 0)
        rc = gi_fail(err, GI_EIO, "%s: fdatasync: %s", j->path, strerror(errno));
    if (rc == 0) {
        j->size += b.len;
        j->records++;
    } else if (ftruncate(j->fd, (off_t)j->size) != 0) {
        /* A half-written record is cut off by the next replay anyway. */
        gi_warn("%s: ftruncate after a failed append: %s", j->path, strerror(errno));
    }
    gi_buf_free(&b);
    return rc;
}

int gi_journal_rewrite(gi_journal *j, const gi_jrec *const *recs, size_t n, gi_error *err)
{
    gi_buf b;
    gi_buf_init(&b);
    header(&b);
    for (size_t i = 0; i < n; i++)
        gi_jrec_encode(recs[i], &b);
    int rc = gi_write_file_atomic(j->path, b.data, b.len, err);
    if (rc == 0) {
        int fd = open(j->path, O_WRONLY | O_APPEND | O_CLOEXEC);
        if (fd < 0) {
            rc = gi_fail(err, GI_EIO, "%s: %s", j->path, strerror(errno));
        } else {
            if (j->fd >= 0)
                close(j->fd);
            j->fd = fd;
            j->size = b.len;
            j->records = 0;
        }
    }
    gi_buf_free(&b);
    return rc;
}

void gi_journal_close(gi_journal *j)
{
    if (j->fd >= 0)
        close(j->fd);
    free(j->path);
    j->fd = -1;
    j->path = NULL;
}
