/* gi_msg: explicit encoding of job, task, result and asset messages. */
#include "gi_msg.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void gi_msg_job_encode(gi_buf *out, uint64_t job_id, const char *file, const char *text,
                       const gi_manifest *manifest)
{
    gi_buf_put_u64(out, job_id);
    gi_buf_put_str(out, file);
    gi_buf_put_str(out, text);
    gi_manifest_encode(manifest, out);
}

int gi_msg_job_decode(const gi_buf *in, gi_msg_job *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_manifest_init(&out->manifest);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "JOB message");
    out->job_id = gi_get_u64(&r);
    out->file = gi_get_str(&r, 4096);
    out->text = gi_get_str(&r, GI_MSG_MAX_TEXT);
    if (!r.failed && gi_manifest_decode(&r, &out->manifest, err)) {
        gi_msg_job_free(out);
        return -1;
    }
    if (gi_reader_finish(&r, err)) {
        gi_msg_job_free(out);
        return -1;
    }
    return 0;
}

void gi_msg_job_free(gi_msg_job *m)
{
    free(m->file);
    free(m->text);
    gi_manifest_free(&m->manifest);
    m->file = m->text = NULL;
}

void gi_msg_task_encode(gi_buf *out, uint64_t job_id, const gi_task *t)
{
    gi_buf_put_u64(out, job_id);
    gi_buf_put_u64(out, t->id);
    gi_buf_put_u32(out, t->kind);
    gi_buf_put_u32(out, t->attempt);
    gi_buf_put_f64(out, t->cost);
    gi_buf_put_blob(out, t->payload.data, t->payload.len);
    /* Optional trailing field: a task without affinity encodes as before. */
    if (t->affinity)
        gi_buf_put_u64(out, t->affinity);
}

int gi_msg_task_decode(const gi_buf *in, gi_msg_task *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "TASK message");
    out->job_id = gi_get_u64(&r);
    out->task.id = gi_get_u64(&r);
    out->task.kind = gi_get_u32(&r);
    out->task.attempt = gi_get_u32(&r);
    out->task.cost = gi_get_f64(&r);
    size_t len;
    const uint8_t *p = gi_get_blob(&r, GI_MSG_MAX_TASK, &len);
    if (!r.failed && r.left > 0) {
        out->task.affinity = gi_get_u64(&r);
        if (out->task.affinity == 0) /* never written: absent means 0 */
            return gi_fail(err, GI_EPROTO, "TASK message: explicit affinity 0");
    }
    if (gi_reader_finish(&r, err))
        return -1;
    gi_buf_init(&out->task.payload);
    gi_buf_put(&out->task.payload, p, len);
    return 0;
}

void gi_msg_result_encode(gi_buf *out, uint64_t job_id, uint64_t task_id, uint32_t attempt,
                          const gi_task_stats *s, const void *data, size_t len)
{
    gi_buf_put_u64(out, job_id);
    gi_buf_put_u64(out, task_id);
    gi_buf_put_u32(out, attempt);
    gi_buf_put_u64(out, s->rays);
    gi_buf_put_u64(out, s->samples);
    gi_buf_put_f64(out, s->seconds);
    gi_buf_put_blob(out, data, len);
}

int gi_msg_result_decode(const gi_buf *in, gi_msg_result *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "RESULT message");
    out->job_id = gi_get_u64(&r);
    out->task_id = gi_get_u64(&r);
    out->attempt = gi_get_u32(&r);
    out->stats.rays = gi_get_u64(&r);
    out->stats.samples = gi_get_u64(&r);
    out->stats.seconds = gi_get_f64(&r);
    size_t len;
    const uint8_t *p = gi_get_blob(&r, GI_MSG_MAX_RESULT, &len);
    if (gi_reader_finish(&r, err))
        return -1;
    gi_buf_init(&out->data);
    gi_buf_put(&out->data, p, len);
    return 0;
}

void gi_msg_fail_encode(gi_buf *out, uint64_t job_id, uint64_t task_id, uint32_t attempt,
                        const gi_error *e)
{
    gi_buf_put_u64(out, job_id);
    gi_buf_put_u64(out, task_id);
    gi_buf_put_u32(out, attempt);
    gi_buf_put_u32(out, (uint32_t)e->code);
    gi_buf_put_str(out, e->msg);
}

static int decode_error_fields(gi_reader *r, gi_error *e)
{
    uint32_t code = gi_get_u32(r);
    char *msg = gi_get_str(r, GI_MSG_MAX_ERROR);
    if (r->failed || !msg) {
        free(msg);
        return -1;
    }
    e->code = code <= GI_EHOST ? (gi_errcode)code : GI_EINTERNAL;
    snprintf(e->msg, sizeof e->msg, "%s", msg);
    free(msg);
    return 0;
}

int gi_msg_fail_decode(const gi_buf *in, gi_msg_fail *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "FAIL message");
    out->job_id = gi_get_u64(&r);
    out->task_id = gi_get_u64(&r);
    out->attempt = gi_get_u32(&r);
    decode_error_fields(&r, &out->error);
    return gi_reader_finish(&r, err);
}

void gi_msg_asset_need_encode(gi_buf *out, const char hash[GI_HASH_HEX])
{
    gi_buf_put(out, hash, 64);
}

static int get_hash(gi_reader *r, char hash[GI_HASH_HEX], gi_error *err)
{
    gi_get(r, hash, 64);
    hash[64] = '\0';
    if (!r->failed && !gi_hash_is_valid(hash))
        return gi_fail(err, GI_EPROTO, "%s: malformed asset hash", r->what);
    return 0;
}

int gi_msg_asset_need_decode(const gi_buf *in, char hash[GI_HASH_HEX], gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "ASSET_NEED message");
    if (get_hash(&r, hash, err))
        return -1;
    return gi_reader_finish(&r, err);
}

void gi_msg_asset_put_encode(gi_buf *out, const char hash[GI_HASH_HEX], const void *data,
                             size_t len)
{
    gi_buf_put(out, hash, 64);
    gi_buf_put_blob(out, data, len);
}

int gi_msg_asset_put_decode(const gi_buf *in, char hash[GI_HASH_HEX], const uint8_t **data,
                            size_t *len, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "ASSET_PUT message");
    if (get_hash(&r, hash, err))
        return -1;
    *data = gi_get_blob(&r, GI_ASSET_MAX_BYTES, len);
    if (gi_reader_finish(&r, err))
        return -1;
    char actual[GI_HASH_HEX];
    gi_hash_hex(*data, *len, actual);
    if (strcmp(actual, hash) != 0)
        return gi_fail(err, GI_EPROTO, "ASSET_PUT message: bytes do not match hash %.12s",
                       hash);
    return 0;
}

void gi_msg_error_encode(gi_buf *out, const gi_error *e)
{
    gi_buf_put_u32(out, (uint32_t)e->code);
    gi_buf_put_str(out, e->msg);
}

int gi_msg_error_decode(const gi_buf *in, gi_error *out, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "ERROR message");
    decode_error_fields(&r, out);
    return gi_reader_finish(&r, err);
}
