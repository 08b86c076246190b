/* gi_msg_ctrl: explicit encoding of the handshake, heartbeat, cancel and
 * drain messages. */
#include "gi_msg_ctrl.h"

#include <stdlib.h>
#include <string.h>

void gi_msg_hello_encode(gi_buf *out, const gi_msg_hello *m)
{
    gi_buf_put_u32(out, m->proto_min);
    gi_buf_put_u32(out, m->proto_max);
    gi_buf_put(out, m->nonce, GI_MSG_NONCE_BYTES);
    gi_buf_put_str(out, m->name);
    gi_buf_put_str(out, m->version);
    gi_buf_put_u32(out, m->procs);
    gi_buf_put_u32(out, m->slots);
    gi_buf_put_u32(out, m->cores);
    gi_buf_put_u64(out, m->memory);
}

/* Names are shown in logs and JSON: printable ASCII only, no quotes. */
static int printable(const char *s)
{
    for (; *s; s++)
        if (*s < 0x20 || *s > 0x7e || *s == '"' || *s == '\\')
            return 0;
    return 1;
}

int gi_msg_hello_decode(const gi_buf *in, gi_msg_hello *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "HELLO message");
    out->proto_min = gi_get_u32(&r);
    out->proto_max = gi_get_u32(&r);
    gi_get(&r, out->nonce, GI_MSG_NONCE_BYTES);
    out->name = gi_get_str(&r, GI_MSG_MAX_NAME);
    out->version = gi_get_str(&r, GI_MSG_MAX_VERSION);
    out->procs = gi_get_u32(&r);
    out->slots = gi_get_u32(&r);
    out->cores = gi_get_u32(&r);
    out->memory = gi_get_u64(&r);
    int rc = gi_reader_finish(&r, err);
    if (rc == 0 && (!out->name[0] || !printable(out->name) || !printable(out->version)))
        rc = gi_fail(err, GI_EPROTO, "HELLO message: name or version is empty or not printable");
    if (rc == 0 && (out->proto_min > out->proto_max))
        rc = gi_fail(err, GI_EPROTO, "HELLO message: protocol range %u-%u is empty",
                     out->proto_min, out->proto_max);
    if (rc == 0 && (out->procs < 1 || out->procs > 1024 || out->slots < out->procs ||
                    out->slots > 4 * out->procs + 16))
        rc = gi_fail(err, GI_EPROTO,
                     "HELLO message: %u processes and %u slots (need 1-1024 processes, "
                     "slots from processes to 4 x processes + 16)",
                     out->procs, out->slots);
    if (rc)
        gi_msg_hello_free(out);
    return rc;
}

void gi_msg_hello_free(gi_msg_hello *m)
{
    free(m->name);
    free(m->version);
    m->name = m->version = NULL;
}

uint32_t gi_msg_proto_choose(uint32_t min, uint32_t max)
{
    uint32_t v = max < GI_PROTO_MAX ? max : GI_PROTO_MAX;
    return v >= min && v >= GI_PROTO_MIN ? v : 0;
}

void gi_msg_challenge_encode(gi_buf *out, const gi_msg_challenge *m)
{
    gi_buf_put_u32(out, m->proto);
    gi_buf_put(out, m->nonce, GI_MSG_NONCE_BYTES);
}

int gi_msg_challenge_decode(const gi_buf *in, gi_msg_challenge *out, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "CHALLENGE message");
    out->proto = gi_get_u32(&r);
    gi_get(&r, out->nonce, GI_MSG_NONCE_BYTES);
    return gi_reader_finish(&r, err);
}

void gi_msg_auth_encode(gi_buf *out, const uint8_t mac[GI_MSG_MAC_BYTES])
{
    gi_buf_put(out, mac, GI_MSG_MAC_BYTES);
}

int gi_msg_auth_decode(const gi_buf *in, uint8_t mac[GI_MSG_MAC_BYTES], gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "AUTH message");
    gi_get(&r, mac, GI_MSG_MAC_BYTES);
    return gi_reader_finish(&r, err);
}

void gi_msg_welcome_encode(gi_buf *out, const gi_msg_welcome *m)
{
    gi_buf_put_u64(out, m->worker_id);
    gi_buf_put_u32(out, m->heartbeat_ms);
    gi_buf_put_u32(out, m->lease_ms);
    gi_buf_put(out, m->mac, GI_MSG_MAC_BYTES);
}

int gi_msg_welcome_decode(const gi_buf *in, gi_msg_welcome *out, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "WELCOME message");
    out->worker_id = gi_get_u64(&r);
    out->heartbeat_ms = gi_get_u32(&r);
    out->lease_ms = gi_get_u32(&r);
    gi_get(&r, out->mac, GI_MSG_MAC_BYTES);
    if (gi_reader_finish(&r, err))
        return -1;
    /* A heartbeat must fit in a lease at least twice, or leases expire on
     * healthy workers. */
    if (out->heartbeat_ms < 10 || out->lease_ms < 2 * out->heartbeat_ms)
        return gi_fail(err, GI_EPROTO,
                       "WELCOME message: heartbeat %u ms and lease %u ms (need heartbeat >= "
                       "10 ms and lease >= 2 x heartbeat)",
                       out->heartbeat_ms, out->lease_ms);
    return 0;
}

void gi_msg_tasklist_encode(gi_buf *out, uint64_t seq, const gi_msg_taskref *refs,
                            uint32_t count, int runs)
{
    gi_buf_put_u64(out, seq);
    gi_buf_put_u32(out, count);
    for (uint32_t i = 0; i < count; i++) {
        gi_buf_put_u64(out, refs[i].job_id);
        gi_buf_put_u64(out, refs[i].task_id);
        gi_buf_put_u32(out, refs[i].attempt);
        if (runs) {
            gi_buf_put_u8(out, refs[i].running);
            gi_buf_put_u32(out, refs[i].running ? refs[i].run_ms : 0);
        }
    }
}

int gi_msg_tasklist_decode(const gi_buf *in, const char *what, int runs, gi_msg_tasklist *out,
                           gi_error *err)
{
    memset(out, 0, sizeof *out);
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, what);
    out->seq = gi_get_u64(&r);
    uint32_t n = gi_get_u32(&r);
    if (r.failed)
        return gi_reader_finish(&r, err);
    /* Bounded, and checked against the bytes present before allocating. */
    size_t size = runs ? 25 : 20;
    if (n > GI_MSG_MAX_TASKREFS || n > r.left / size)
        return gi_fail(err, GI_EPROTO, "%s: %u task references (limit %u, %zu bytes left)",
                       what, n, GI_MSG_MAX_TASKREFS, r.left);
    out->refs = gi_xcalloc(n ? n : 1, sizeof *out->refs);
    out->count = n;
    int bad = -1;
    for (uint32_t i = 0; i < n; i++) {
        gi_msg_taskref *t = &out->refs[i];
        t->job_id = gi_get_u64(&r);
        t->task_id = gi_get_u64(&r);
        t->attempt = gi_get_u32(&r);
        if (!runs)
            continue;
        t->running = gi_get_u8(&r);
        t->run_ms = gi_get_u32(&r);
        if (bad < 0 && (t->running > 1 || (!t->running && t->run_ms)))
            bad = (int)i;
    }
    int rc = gi_reader_finish(&r, err);
    if (rc == 0 && bad >= 0)
        rc = gi_fail(err, GI_EPROTO,
                     "%s: task reference %d: running %u, run_ms %u (running is 0 or 1; a "
                     "queued task has run 0 ms)",
                     what, bad, out->refs[bad].running, out->refs[bad].run_ms);
    if (rc) {
        gi_msg_tasklist_free(out);
        return -1;
    }
    return 0;
}

void gi_msg_tasklist_free(gi_msg_tasklist *m)
{
    free(m->refs);
    m->refs = NULL;
    m->count = 0;
}

void gi_msg_cancel_encode(gi_buf *out, const gi_msg_cancel *m)
{
    gi_buf_put_u64(out, m->job_id);
    gi_buf_put_u64(out, m->task_id);
}

int gi_msg_cancel_decode(const gi_buf *in, gi_msg_cancel *out, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, in->data, in->len, "CANCEL message");
    out->job_id = gi_get_u64(&r);
    out->task_id = gi_get_u64(&r);
    return gi_reader_finish(&r, err);
}
