/* gi_frame: frame encoding and the incremental, limit-checking decoder.
 * Layout and limits are documented in gi_frame.h. */
#include "gi_frame.h"

#include <assert.h>
#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_log.h"
#include "gi_zstd.h"

static const uint8_t frame_magic[4] = {'G', 'I', 'F', '1'};

/* The first payload allocation; later ones double, capped at the declared
 * length, so memory follows the bytes actually received. */
#define PAYLOAD_GROW_MIN ((size_t)64 << 10)

enum { ST_HEADER, ST_PAYLOAD, ST_READY, ST_BROKEN };

static const char *const type_names[GI_MSG_TYPE_COUNT] = {
#define GI_MSG_NAME_(name, value, limit) [value] = #name,
    GI_MSG_TYPE_LIST(GI_MSG_NAME_)
#undef GI_MSG_NAME_
};

int gi_msg_type_known(uint16_t type)
{
    return type < GI_MSG_TYPE_COUNT && type_names[type] != NULL;
}

const char *gi_msg_type_name(uint16_t type)
{
    return gi_msg_type_known(type) ? type_names[type] : "unknown";
}

gi_frame_limits gi_frame_limits_default(void)
{
    gi_frame_limits lim;
    memset(&lim, 0, sizeof lim);
#define GI_MSG_LIMIT_(name, value, limit) lim.max_payload[value] = (limit);
    GI_MSG_TYPE_LIST(GI_MSG_LIMIT_)
#undef GI_MSG_LIMIT_
    lim.max_decompressed = GI_FRAME_LIMIT_BULK;
    return lim;
}

void gi_frame_free(gi_frame *f)
{
    gi_buf_free(&f->payload);
}

/* ---- encoding ---------------------------------------------------------- */

void gi_frame_header_write(uint8_t hdr[GI_FRAME_HEADER_SIZE], uint16_t type, uint32_t flags,
                           const void *wire, size_t wire_len)
{
    memcpy(hdr, frame_magic, 4);
    gi_le_put_u16(hdr + 4, GI_FRAME_VERSION);
    gi_le_put_u16(hdr + 6, type);
    gi_le_put_u32(hdr + 8, flags);
    gi_le_put_u64(hdr + 12, (uint64_t)wire_len);
    uint32_t crc = gi_crc32c(0, hdr, GI_FRAME_CRC_OFFSET);
    gi_le_put_u32(hdr + GI_FRAME_CRC_OFFSET, gi_crc32c(crc, wire, wire_len));
}

uint32_t gi_frame_wire_payload(gi_buf *scratch, const void *payload, size_t len, int compress,
                               const void **wire, size_t *wire_len)
{
    *wire = payload;
    *wire_len = len;
    if (!compress || len < GI_FRAME_COMPRESS_MIN)
        return 0;
    size_t start = scratch->len;
    gi_error err;
    if (gi_zstd_compress(scratch, payload, len, GI_ZSTD_LEVEL, &err) != 0) {
        /* Sending raw is always correct; compression is only an optimisation. */
        gi_warn("frame payload of %zu bytes sent uncompressed: %s", len, err.msg);
        scratch->len = start;
        return 0;
    }
    if (scratch->len - start >= len) { /* incompressible (already dense data) */
        scratch->len = start;
        return 0;
    }
    *wire = scratch->data + start;
    *wire_len = scratch->len - start;
    return GI_FRAME_ZSTD;
}

void gi_frame_encode(gi_buf *out, uint16_t type, const void *payload, size_t len, int compress)
{
    assert(gi_msg_type_known(type));
    size_t off = out->len;
    gi_buf_grow(out, GI_FRAME_HEADER_SIZE);
    /* Compress straight after the header; fall back to copying the raw bytes. */
    const void *wire;
    size_t wire_len;
    uint32_t flags = gi_frame_wire_payload(out, payload, len, compress, &wire, &wire_len);
    if (!flags)
        gi_buf_put(out, payload, len);
    uint8_t *hdr = out->data + off; /* only now: the buffer may have moved */
    gi_frame_header_write(hdr, type, flags, hdr + GI_FRAME_HEADER_SIZE,
                          out->len - off - GI_FRAME_HEADER_SIZE);
}

/* ---- decoding ---------------------------------------------------------- */

/* Latches the stream failure: the message names the peer and where in the
 * stream the offending frame starts. */
static void broken(gi_frame_decoder *d, gi_errcode code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void broken(gi_frame_decoder *d, gi_errcode code, const char *fmt, ...)
{
    char msg[sizeof d->err.msg];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    gi_fail(&d->err, code, "%s, frame at stream byte %llu: %s", d->peer,
            (unsigned long long)d->offset, msg);
    d->state = ST_BROKEN;
    /* A broken stream is never resumed: release what it was holding. */
    free(d->payload);
    d->payload = NULL;
    d->fill = d->cap = 0;
    gi_buf_free(&d->pending);
    d->pending_off = 0;
}

static void describe_magic(const uint8_t *m, char *out, size_t n)
{
    size_t k = 0;
    for (int i = 0; i < 4 && k + 5 < n; i++) {
        if (isprint(m[i]) && m[i] != '"' && m[i] != '\\')
            out[k++] = (char)m[i];
        else
            k += (size_t)snprintf(out + k, n - k, "\\x%02x", m[i]);
    }
    out[k] = '\0';
}

/* Validates a complete header; everything that can be refused without the
 * payload is refused here, before anything is allocated for it. */
static void header_done(gi_frame_decoder *d)
{
    const uint8_t *h = d->hdr;
    if (memcmp(h, frame_magic, 4) != 0) {
        char m[32];
        describe_magic(h, m, sizeof m);
        broken(d, GI_EPROTO, "bad magic \"%s\" (expected \"GIF1\")", m);
        return;
    }
    uint16_t version = gi_le_get_u16(h + 4);
    if (version != GI_FRAME_VERSION) {
        broken(d, GI_EPROTO, "frame version %u is not supported (this build frames version %u)",
               version, GI_FRAME_VERSION);
        return;
    }
    uint16_t type = gi_le_get_u16(h + 6);
    if (!gi_msg_type_known(type)) {
        broken(d, GI_EPROTO, "frame type %u is unknown", type);
        return;
    }
    uint32_t flags = gi_le_get_u32(h + 8);
    if (flags & ~GI_FRAME_FLAGS_KNOWN) {
        broken(d, GI_EPROTO, "%s frame has reserved flag bits 0x%08x set",
               gi_msg_type_name(type), flags & ~GI_FRAME_FLAGS_KNOWN);
        return;
    }
    uint64_t length = gi_le_get_u64(h + 12);
    uint64_t limit = d->lim.max_payload[type];
    if (length > 0 && limit == 0) {
        broken(d, GI_EPROTO, "%s frames are not accepted on this connection",
               gi_msg_type_name(type));
        return;
    }
    if (length > limit || length > SIZE_MAX) {
        broken(d, GI_EPROTO, "%s frame payload of %llu bytes exceeds the limit of %llu bytes",
               gi_msg_type_name(type), (unsigned long long)length, (unsigned long long)limit);
        return;
    }
    d->type = type;
    d->flags = flags;
    d->length = length;
    d->crc_expected = gi_le_get_u32(h + GI_FRAME_CRC_OFFSET);
    d->crc = gi_crc32c(0, h, GI_FRAME_CRC_OFFSET);
    d->state = length ? ST_PAYLOAD : ST_READY;
}

/* Makes room for at least one more payload byte. */
static int payload_grow(gi_frame_decoder *d)
{
    size_t left = (size_t)d->length - d->fill;
    size_t cap = d->cap < PAYLOAD_GROW_MIN ? PAYLOAD_GROW_MIN
                 : d->cap > SIZE_MAX / 2  ? SIZE_MAX
                                          : d->cap * 2;
    if (cap - d->fill > left) /* cap >= fill always; never beyond the declared end */
        cap = d->fill + left;
    uint8_t *p = realloc(d->payload, cap);
    if (!p) {
        broken(d, GI_ENOMEM, "cannot allocate %zu bytes for a %s payload of %llu bytes", cap,
               gi_msg_type_name(d->type), (unsigned long long)d->length);
        return -1;
    }
    d->payload = p;
    d->cap = cap;
    return 0;
}

/* space/commit without looking at the pending queue. */
static uint8_t *space_raw(gi_frame_decoder *d, size_t *n)
{
    switch (d->state) {
    case ST_HEADER:
        *n = GI_FRAME_HEADER_SIZE - d->hdr_fill;
        return d->hdr + d->hdr_fill;
    case ST_PAYLOAD:
        if (d->cap == d->fill && payload_grow(d) != 0)
            return NULL;
        *n = d->cap - d->fill;
        return d->payload + d->fill;
    default:
        *n = 0;
        return NULL;
    }
}

void gi_frame_decoder_commit(gi_frame_decoder *d, size_t n)
{
    if (d->state == ST_HEADER) {
        assert(n <= GI_FRAME_HEADER_SIZE - d->hdr_fill);
        d->hdr_fill += n;
        if (d->hdr_fill == GI_FRAME_HEADER_SIZE)
            header_done(d);
    } else if (d->state == ST_PAYLOAD) {
        assert(n <= d->cap - d->fill);
        /* Hashing as the bytes arrive keeps them in cache and spares a
         * second pass over a 1 GiB payload. */
        d->crc = gi_crc32c(d->crc, d->payload + d->fill, n);
        d->fill += n;
        if (d->fill == d->length)
            d->state = ST_READY;
    } else {
        assert(n == 0);
    }
}

/* Moves bytes into the frame in progress; returns how many it took. */
static size_t absorb(gi_frame_decoder *d, const uint8_t *p, size_t n)
{
    size_t used = 0;
    while (used < n) {
        size_t room;
        uint8_t *dst = space_raw(d, &room);
        if (!dst)
            break;
        size_t k = n - used < room ? n - used : room;
        memcpy(dst, p + used, k);
        gi_frame_decoder_commit(d, k);
        used += k;
    }
    return used;
}

static void drain_pending(gi_frame_decoder *d)
{
    gi_buf *q = &d->pending;
    if (d->pending_off == q->len)
        return;
    size_t used = absorb(d, q->data + d->pending_off, q->len - d->pending_off);
    if (d->state == ST_BROKEN)
        return; /* broken() emptied the queue */
    d->pending_off += used;
    if (d->pending_off == q->len) {
        /* Keep a small queue for the next burst; drop a large one. */
        if (q->cap > ((size_t)1 << 20))
            gi_buf_free(q);
        q->len = 0;
        d->pending_off = 0;
    }
}

void gi_frame_decoder_init(gi_frame_decoder *d, const gi_frame_limits *lim, const char *peer)
{
    memset(d, 0, sizeof *d);
    d->lim = lim ? *lim : gi_frame_limits_default();
    d->peer = gi_xstrdup(peer ? peer : "peer");
    d->state = ST_HEADER;
    gi_buf_init(&d->pending);
    gi_error_clear(&d->err);
}

void gi_frame_decoder_free(gi_frame_decoder *d)
{
    free(d->peer);
    free(d->payload);
    gi_buf_free(&d->pending);
    memset(d, 0, sizeof *d);
}

void gi_frame_decoder_set_limits(gi_frame_decoder *d, const gi_frame_limits *lim)
{
    d->lim = *lim;
}

void gi_frame_decoder_feed(gi_frame_decoder *d, const void *data, size_t len)
{
    if (d->state == ST_BROKEN || len == 0)
        return;
    const uint8_t *p = data;
    gi_buf *q = &d->pending;
    if (d->pending_off == q->len) {
        size_t used = absorb(d, p, len);
        p += used;
        len -= used;
        if (len == 0 || d->state == ST_BROKEN)
            return;
    }
    /* Compact when the consumed prefix dominates, so queueing stays linear. */
    if (d->pending_off > 0 && d->pending_off >= q->len / 2) {
        memmove(q->data, q->data + d->pending_off, q->len - d->pending_off);
        q->len -= d->pending_off;
        d->pending_off = 0;
    }
    gi_buf_put(q, p, len);
}

int gi_frame_decoder_mid_frame(const gi_frame_decoder *d)
{
    if (d->state == ST_BROKEN)
        return 0;
    return d->state != ST_HEADER || d->hdr_fill > 0 || d->pending_off != d->pending.len;
}

uint8_t *gi_frame_decoder_space(gi_frame_decoder *d, size_t *n)
{
    drain_pending(d);
    if (d->pending_off != d->pending.len) {
        *n = 0;
        return NULL;
    }
    return space_raw(d, n);
}

int gi_frame_decoder_next(gi_frame_decoder *d, gi_frame *out, gi_error *err)
{
    drain_pending(d);
    if (d->state == ST_BROKEN) {
        if (err)
            *err = d->err;
        return -1;
    }
    if (d->state != ST_READY)
        return 0;

    const char *name = gi_msg_type_name(d->type);
    if (d->crc != d->crc_expected) {
        broken(d, GI_EPROTO, "%s frame CRC32C mismatch (header says 0x%08x, bytes give 0x%08x)",
               name, d->crc_expected, d->crc);
        if (err)
            *err = d->err;
        return -1;
    }
    gi_buf payload;
    gi_buf_init(&payload);
    if (d->flags & GI_FRAME_ZSTD) {
        uint64_t max = d->lim.max_payload[d->type];
        if (max > d->lim.max_decompressed)
            max = d->lim.max_decompressed;
        gi_error zerr;
        char what[64];
        snprintf(what, sizeof what, "%s frame", name);
        if (gi_zstd_decompress(&payload, d->payload, d->fill, max, what, &zerr) != 0) {
            broken(d, zerr.code, "%s", zerr.msg);
            if (err)
                *err = d->err;
            return -1;
        }
        free(d->payload);
    } else {
        payload.data = d->payload; /* cap == length: growth never passes the end */
        payload.len = payload.cap = d->fill;
    }
    out->type = d->type;
    out->flags = d->flags;
    out->payload = payload;

    d->offset += GI_FRAME_HEADER_SIZE + d->length;
    d->payload = NULL;
    d->fill = d->cap = 0;
    d->hdr_fill = 0;
    d->state = ST_HEADER;
    return 1;
}
