/* Tests for the frame layer: CRC32C, encoding, the incremental decoder and
 * every refusal it makes, and blocking send/receive over socketpairs. */
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zstd.h>

#include "gi_buf.h"
#include "gi_crc32c.h"
#include "gi_frame.h"
#include "gi_netio.h"
#include "gi_test.h"
#include "gi_zstd.h"

/* ---- helpers ----------------------------------------------------------- */

/* xorshift64*: deterministic bytes for payloads. */
static uint64_t rng_next(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * UINT64_C(2685821657736338717);
}

static void fill_random(uint8_t *p, size_t n, uint64_t seed)
{
    uint64_t s = seed * 0x9E3779B97F4A7C15u + 1;
    for (size_t i = 0; i < n; i++)
        p[i] = (uint8_t)(rng_next(&s) >> 56);
}

/* Compressible but not trivial: short words from a small alphabet. */
static void fill_text(uint8_t *p, size_t n, uint64_t seed)
{
    uint64_t s = seed * 0x9E3779B97F4A7C15u + 7;
    for (size_t i = 0; i < n; i++)
        p[i] = (uint8_t)("abcdefgh     \n"[rng_next(&s) % 14]);
}

/* A frame with every header field chosen by the caller; the CRC is correct
 * for whatever was chosen unless crc_xor is non-zero. */
static void raw_frame(gi_buf *out, const char *magic, uint16_t version, uint16_t type,
                      uint32_t flags, uint64_t length, const void *payload, size_t n,
                      uint32_t crc_xor)
{
    uint8_t *h = gi_buf_grow(out, GI_FRAME_HEADER_SIZE);
    size_t off = (size_t)(h - out->data);
    memcpy(h, magic, 4);
    gi_le_put_u16(h + 4, version);
    gi_le_put_u16(h + 6, type);
    gi_le_put_u32(h + 8, flags);
    gi_le_put_u64(h + 12, length);
    gi_buf_put(out, payload, n);
    h = out->data + off;
    uint32_t crc = gi_crc32c(gi_crc32c(0, h, 20), h + GI_FRAME_HEADER_SIZE, n);
    gi_le_put_u32(h + 20, crc ^ crc_xor);
}

/* Feeds everything and returns the decoder's verdict on the first frame. */
static int decode_one(const gi_frame_limits *lim, const void *data, size_t n, gi_frame *f,
                      gi_error *err)
{
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, lim, "test-peer");
    gi_frame_decoder_feed(&d, data, n);
    int r = gi_frame_decoder_next(&d, f, err);
    gi_frame_decoder_free(&d);
    return r;
}

/* Expects the bytes to be refused with a message containing `want`
 * (and the peer name). */
static void expect_refused(const gi_frame_limits *lim, const gi_buf *b, const char *want,
                           int line)
{
    gi_frame f;
    gi_error err;
    gi_error_clear(&err);
    int r = decode_one(lim, b->data, b->len, &f, &err);
    GI_CHECK_MSG(r == -1, "line %d: decoder returned %d, expected -1", line, r);
    if (r == 1)
        gi_frame_free(&f);
    GI_CHECK_MSG(strstr(err.msg, want) != NULL, "line %d: message \"%s\" lacks \"%s\"", line,
                 err.msg, want);
    GI_CHECK_MSG(strstr(err.msg, "test-peer") != NULL, "line %d: message \"%s\" lacks the peer",
                 line, err.msg);
}

/* A zstd frame built by hand from RLE blocks: declares `declared` bytes of
 * content and holds `blocks` RLE blocks of 128 KiB of 'A'. Format: RFC 8878
 * sections 3.1.1 (frame header) and 3.1.1.2 (blocks). */
static void zstd_rle_frame(gi_buf *out, uint64_t declared, size_t blocks)
{
    gi_buf_put_u32(out, ZSTD_MAGICNUMBER);
    gi_buf_put_u8(out, 0xE0); /* FCS field 8 bytes, single segment, no checksum */
    gi_buf_put_u64(out, declared);
    const uint32_t block = 128 << 10;
    for (size_t i = 0; i < blocks; i++) {
        uint32_t last = i + 1 == blocks;
        uint32_t bh = last | (1u << 1) /* RLE */ | (block << 3);
        gi_buf_put_u8(out, (uint8_t)bh);
        gi_buf_put_u8(out, (uint8_t)(bh >> 8));
        gi_buf_put_u8(out, (uint8_t)(bh >> 16));
        gi_buf_put_u8(out, 'A');
    }
}

/* ---- CRC32C ------------------------------------------------------------ */

GI_TEST(frame_crc32c_check_values)
{
    const char *check = "123456789";
    GI_CHECK(gi_crc32c_sw(0, check, 9) == 0xE3069283u);
    GI_CHECK(gi_crc32c(0, check, 9) == 0xE3069283u);
    GI_CHECK(gi_crc32c_sw(0, "", 0) == 0);
    /* RFC 3720 appendix B.4 test vectors. */
    uint8_t v[32];
    memset(v, 0, sizeof v);
    GI_CHECK(gi_crc32c_sw(0, v, 32) == 0x8A9136AAu);
    memset(v, 0xff, sizeof v);
    GI_CHECK(gi_crc32c_sw(0, v, 32) == 0x62A8AB43u);
    for (int i = 0; i < 32; i++)
        v[i] = (uint8_t)i;
    GI_CHECK(gi_crc32c_sw(0, v, 32) == 0x46DD794Eu);
    for (int i = 0; i < 32; i++)
        v[i] = (uint8_t)(31 - i);
    GI_CHECK(gi_crc32c_sw(0, v, 32) == 0x113FDB5Cu);
#ifdef GI_CRC32C_HAVE_HW
    if (gi_crc32c_hw_available()) {
        GI_CHECK(gi_crc32c_hw(0, check, 9) == 0xE3069283u);
        GI_CHECK(gi_crc32c_hw(0, v, 32) == 0x113FDB5Cu);
    } else {
        printf("  (this CPU has no SSE4.2: only the table version was checked)\n");
    }
#endif
}

GI_TEST(frame_crc32c_paths_agree)
{
    enum { N = 4096 };
    uint8_t *data = gi_xmalloc(N + 8);
    fill_random(data, N + 8, 1);
    /* Every length up to 300 at every alignment, then larger ones. */
    for (size_t align = 0; align < 8; align++) {
        for (size_t n = 0; n <= N; n += n < 300 ? 1 : 97) {
            uint32_t sw = gi_crc32c_sw(0, data + align, n);
            /* Chaining: any split point gives the same CRC. */
            size_t cut = n / 3;
            uint32_t chained = gi_crc32c_sw(gi_crc32c_sw(0, data + align, cut),
                                            data + align + cut, n - cut);
            GI_CHECK_MSG(chained == sw, "chained sw CRC differs at n=%zu", n);
            GI_CHECK_MSG(gi_crc32c(0, data + align, n) == sw, "dispatch differs at n=%zu", n);
#ifdef GI_CRC32C_HAVE_HW
            if (gi_crc32c_hw_available()) {
                GI_CHECK_MSG(gi_crc32c_hw(0, data + align, n) == sw,
                             "hw and sw differ at n=%zu align=%zu", n, align);
                GI_CHECK(gi_crc32c_hw(gi_crc32c_hw(0, data + align, cut), data + align + cut,
                                      n - cut) == sw);
            }
#endif
        }
    }
    free(data);
}

/* ---- types, limits, encoding ------------------------------------------- */

GI_TEST(frame_msg_types)
{
    GI_CHECK(GI_MSG_TYPE_COUNT == 17);
    GI_CHECK(strcmp(gi_msg_type_name(GI_MSG_HELLO), "HELLO") == 0);
    GI_CHECK(strcmp(gi_msg_type_name(GI_MSG_ASSET_PUT), "ASSET_PUT") == 0);
    GI_CHECK(strcmp(gi_msg_type_name(GI_MSG_PROGRESS), "PROGRESS") == 0);
    GI_CHECK(GI_MSG_RESULT == 9 && GI_MSG_BYE == 14 && GI_MSG_ERROR == 15);
    GI_CHECK(!gi_msg_type_known(0) && !gi_msg_type_known(17) && !gi_msg_type_known(77) &&
             !gi_msg_type_known(65535));
    GI_CHECK(strcmp(gi_msg_type_name(77), "unknown") == 0);
    gi_frame_limits lim = gi_frame_limits_default();
    for (uint16_t t = 1; t < GI_MSG_TYPE_COUNT; t++) {
        GI_CHECK(gi_msg_type_known(t));
        GI_CHECK(lim.max_payload[t] >= 64 << 10);
        GI_CHECK(lim.max_payload[t] <= lim.max_decompressed);
    }
    GI_CHECK(lim.max_payload[GI_MSG_HEARTBEAT] == 64 << 10);
    GI_CHECK(lim.max_payload[GI_MSG_TASK] == 256 << 20);
    GI_CHECK(lim.max_payload[GI_MSG_RESULT] == 1 << 30);
}

GI_TEST(frame_encode_layout)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_frame_encode(&b, GI_MSG_TASK, "abc", 3, 1); /* too small to compress */
    GI_REQUIRE(b.len == GI_FRAME_HEADER_SIZE + 3);
    GI_CHECK(memcmp(b.data, "GIF1", 4) == 0);
    GI_CHECK(gi_le_get_u16(b.data + 4) == 1);
    GI_CHECK(gi_le_get_u16(b.data + 6) == GI_MSG_TASK);
    GI_CHECK(gi_le_get_u32(b.data + 8) == 0);
    GI_CHECK(gi_le_get_u64(b.data + 12) == 3);
    uint32_t crc = gi_crc32c_sw(gi_crc32c_sw(0, b.data, 20), "abc", 3);
    GI_CHECK(gi_le_get_u32(b.data + 20) == crc);
    GI_CHECK(memcmp(b.data + 24, "abc", 3) == 0);

    /* Compressible and large enough: zstd; incompressible: raw. */
    uint8_t *p = gi_xmalloc(20000);
    fill_text(p, 20000, 3);
    gi_buf_reset(&b);
    gi_frame_encode(&b, GI_MSG_RESULT, p, 20000, 1);
    GI_CHECK(gi_le_get_u32(b.data + 8) == GI_FRAME_ZSTD);
    GI_CHECK(b.len < 20000 && gi_le_get_u64(b.data + 12) == b.len - 24);
    GI_CHECK(ZSTD_getFrameContentSize(b.data + 24, b.len - 24) == 20000);
    gi_buf_reset(&b);
    gi_frame_encode(&b, GI_MSG_RESULT, p, 20000, 0);
    GI_CHECK(gi_le_get_u32(b.data + 8) == 0 && b.len == 20024);
    fill_random(p, 20000, 4);
    gi_buf_reset(&b);
    gi_frame_encode(&b, GI_MSG_RESULT, p, 20000, 1);
    GI_CHECK(gi_le_get_u32(b.data + 8) == 0 && b.len == 20024);
    free(p);
    gi_buf_free(&b);
}

/* ---- decoding ---------------------------------------------------------- */

GI_TEST(frame_roundtrip_every_type)
{
    enum { N = 6000 };
    uint8_t *text = gi_xmalloc(N), *noise = gi_xmalloc(N);
    fill_text(text, N, 5);
    fill_random(noise, N, 6);
    struct {
        const uint8_t *p;
        size_t n;
        int compress;
        uint32_t flags;
    } cases[] = {{text, 0, 0, 0},     {text, 0, 1, 0},     {text, 17, 1, 0},
                 {text, N, 0, 0},     {text, N, 1, GI_FRAME_ZSTD},
                 {noise, N, 1, 0},    {noise, 4095, 1, 0}, {text, 4096, 1, GI_FRAME_ZSTD}};
    for (uint16_t t = 1; t < GI_MSG_TYPE_COUNT; t++) {
        for (size_t c = 0; c < GI_ARRAY_LEN(cases); c++) {
            gi_buf b;
            gi_buf_init(&b);
            gi_frame_encode(&b, t, cases[c].p, cases[c].n, cases[c].compress);
            gi_frame f;
            gi_error err;
            int r = decode_one(NULL, b.data, b.len, &f, &err);
            GI_CHECK_MSG(r == 1, "type %s case %zu: %d %s", gi_msg_type_name(t), c, r,
                         r < 0 ? err.msg : "");
            if (r == 1) {
                GI_CHECK(f.type == t);
                GI_CHECK_MSG(f.flags == cases[c].flags, "type %u case %zu: flags %u", t, c,
                             f.flags);
                GI_CHECK(f.payload.len == cases[c].n);
                GI_CHECK(cases[c].n == 0 || memcmp(f.payload.data, cases[c].p, cases[c].n) == 0);
                gi_frame_free(&f);
            }
            gi_buf_free(&b);
        }
    }
    free(text);
    free(noise);
}

/* A stream of mixed frames used by the splitting tests. */
typedef struct {
    uint16_t type;
    size_t len;
    int compress;
    uint64_t seed;
} frame_spec;

static const frame_spec mixed[] = {
    {GI_MSG_HELLO, 40, 0, 1},     {GI_MSG_HEARTBEAT, 0, 0, 2}, {GI_MSG_RESULT, 9000, 1, 3},
    {GI_MSG_TASK, 300, 1, 4},     {GI_MSG_ASSET_PUT, 5000, 0, 5}, {GI_MSG_BYE, 1, 0, 6},
};

static void payload_for(const frame_spec *s, uint8_t *p)
{
    if (s->compress)
        fill_text(p, s->len, s->seed);
    else
        fill_random(p, s->len, s->seed);
}

static void encode_mixed(gi_buf *b)
{
    uint8_t *p = gi_xmalloc(10000);
    for (size_t i = 0; i < GI_ARRAY_LEN(mixed); i++) {
        payload_for(&mixed[i], p);
        gi_frame_encode(b, mixed[i].type, p, mixed[i].len, mixed[i].compress);
    }
    free(p);
}

/* Drains the decoder, checking frames against mixed[*next...]. */
static int drain_mixed(gi_frame_decoder *d, size_t *next, uint8_t *scratch)
{
    for (;;) {
        gi_frame f;
        gi_error err;
        int r = gi_frame_decoder_next(d, &f, &err);
        if (r == 0)
            return 0;
        if (r < 0) {
            gi_test_failed(__FILE__, __LINE__, "decoder failed: %s", err.msg);
            return -1;
        }
        if (*next >= GI_ARRAY_LEN(mixed)) {
            gi_test_failed(__FILE__, __LINE__, "more frames than were sent");
            gi_frame_free(&f);
            return -1;
        }
        const frame_spec *s = &mixed[(*next)++];
        payload_for(s, scratch);
        GI_CHECK(f.type == s->type && f.payload.len == s->len);
        GI_CHECK(f.payload.len != s->len || s->len == 0 ||
                 memcmp(f.payload.data, scratch, s->len) == 0);
        gi_frame_free(&f);
    }
}

GI_TEST(frame_split_at_every_byte)
{
    gi_buf b;
    gi_buf_init(&b);
    encode_mixed(&b);
    uint8_t *scratch = gi_xmalloc(10000);
    /* Two feeds split at every position. */
    for (size_t cut = 0; cut <= b.len; cut++) {
        gi_frame_decoder d;
        gi_frame_decoder_init(&d, NULL, "test-peer");
        size_t next = 0;
        gi_frame_decoder_feed(&d, b.data, cut);
        int r = drain_mixed(&d, &next, scratch);
        gi_frame_decoder_feed(&d, b.data + cut, b.len - cut);
        if (r == 0)
            r = drain_mixed(&d, &next, scratch);
        GI_CHECK_MSG(r == 0 && next == GI_ARRAY_LEN(mixed), "cut %zu: %zu frames", cut, next);
        gi_frame_decoder_free(&d);
        if (r != 0)
            break;
    }
    /* One byte at a time; mid_frame tells a clean end of stream from a cut. */
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, NULL, "test-peer");
    size_t next = 0, ends = 0;
    GI_CHECK(!gi_frame_decoder_mid_frame(&d));
    for (size_t i = 0; i < b.len; i++) {
        gi_frame_decoder_feed(&d, b.data + i, 1);
        GI_REQUIRE(drain_mixed(&d, &next, scratch) == 0);
        ends += !gi_frame_decoder_mid_frame(&d);
    }
    GI_CHECK(ends == GI_ARRAY_LEN(mixed)); /* exactly at each frame's end */
    GI_CHECK(next == GI_ARRAY_LEN(mixed));
    GI_CHECK(d.pending.cap == 0); /* nothing was queued: bytes went straight in */
    gi_frame_decoder_free(&d);
    free(scratch);
    gi_buf_free(&b);
}

GI_TEST(frame_zero_copy_space_commit)
{
    gi_buf b;
    gi_buf_init(&b);
    encode_mixed(&b);
    uint8_t *scratch = gi_xmalloc(10000);
    for (uint64_t seed = 1; seed <= 20; seed++) {
        uint64_t s = seed;
        gi_frame_decoder d;
        gi_frame_decoder_init(&d, NULL, "test-peer");
        size_t pos = 0, next = 0;
        while (pos < b.len) {
            size_t room;
            uint8_t *p = gi_frame_decoder_space(&d, &room);
            if (!p) {
                GI_REQUIRE(drain_mixed(&d, &next, scratch) == 0);
                continue;
            }
            /* Never asks for more than the current header or payload. */
            GI_CHECK(room >= 1);
            size_t k = 1 + rng_next(&s) % 700;
            if (k > room)
                k = room;
            if (k > b.len - pos)
                k = b.len - pos;
            memcpy(p, b.data + pos, k);
            gi_frame_decoder_commit(&d, k);
            pos += k;
        }
        GI_REQUIRE(drain_mixed(&d, &next, scratch) == 0);
        GI_CHECK(next == GI_ARRAY_LEN(mixed));
        gi_frame_decoder_free(&d);
    }
    free(scratch);
    gi_buf_free(&b);
}

GI_TEST(frame_many_frames_in_one_feed)
{
    enum { COUNT = 2000 };
    gi_buf b;
    gi_buf_init(&b);
    for (uint32_t i = 0; i < COUNT; i++) {
        uint8_t p[8];
        gi_le_put_u32(p, i);
        gi_le_put_u32(p + 4, ~i);
        gi_frame_encode(&b, (uint16_t)(1 + i % (GI_MSG_TYPE_COUNT - 1)), p, i % 9, 0);
    }
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, NULL, "test-peer");
    gi_frame_decoder_feed(&d, b.data, b.len);
    uint32_t got = 0;
    gi_frame f;
    gi_error err;
    int r;
    while ((r = gi_frame_decoder_next(&d, &f, &err)) == 1) {
        GI_CHECK(f.type == 1 + got % (GI_MSG_TYPE_COUNT - 1));
        GI_CHECK(f.payload.len == got % 9);
        if (f.payload.len >= 4)
            GI_CHECK(gi_le_get_u32(f.payload.data) == got);
        gi_frame_free(&f);
        got++;
    }
    GI_CHECK(r == 0);
    GI_CHECK(got == COUNT);
    /* And again, fed in two halves while frames are still pending. */
    gi_frame_decoder_feed(&d, b.data, b.len / 2);
    gi_frame_decoder_feed(&d, b.data + b.len / 2, b.len - b.len / 2);
    got = 0;
    while (gi_frame_decoder_next(&d, &f, &err) == 1) {
        gi_frame_free(&f);
        got++;
    }
    GI_CHECK(got == COUNT);
    /* A lazy reader: small feeds, at most 20 frames taken per feed, so bytes
     * queue behind complete frames and the queue is consumed from the front. */
    got = 0;
    for (size_t pos = 0; pos < b.len; pos += 700) {
        gi_frame_decoder_feed(&d, b.data + pos, b.len - pos < 700 ? b.len - pos : 700);
        for (int k = 0; k < 20 && gi_frame_decoder_next(&d, &f, &err) == 1; k++) {
            GI_CHECK(f.payload.len == got % 9);
            gi_frame_free(&f);
            got++;
        }
    }
    while (gi_frame_decoder_next(&d, &f, &err) == 1) {
        GI_CHECK(f.payload.len == got % 9);
        gi_frame_free(&f);
        got++;
    }
    GI_CHECK(got == COUNT);
    gi_frame_decoder_free(&d);
    gi_buf_free(&b);
}

/* ---- refusals ---------------------------------------------------------- */

GI_TEST(frame_refuses_bad_header_fields)
{
    gi_buf b;
    gi_buf_init(&b);
    raw_frame(&b, "GIF2", 1, GI_MSG_HELLO, 0, 2, "hi", 2, 0);
    expect_refused(NULL, &b, "bad magic \"GIF2\"", __LINE__);
    gi_buf_reset(&b);
    raw_frame(&b, "\x00\xffGI", 1, GI_MSG_HELLO, 0, 2, "hi", 2, 0);
    expect_refused(NULL, &b, "bad magic \"\\x00\\xffGI\"", __LINE__);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 2, GI_MSG_HELLO, 0, 2, "hi", 2, 0);
    expect_refused(NULL, &b, "frame version 2 is not supported (this build frames version 1)",
                   __LINE__);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, 0, 0, 2, "hi", 2, 0);
    expect_refused(NULL, &b, "frame type 0 is unknown", __LINE__);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, 77, 0, 2, "hi", 2, 0);
    expect_refused(NULL, &b, "frame type 77 is unknown", __LINE__);
    for (int bit = 1; bit < 32; bit++) {
        gi_buf_reset(&b);
        raw_frame(&b, "GIF1", 1, GI_MSG_TASK, 1u << bit, 2, "hi", 2, 0);
        expect_refused(NULL, &b, "TASK frame has reserved flag bits", __LINE__);
    }
    gi_buf_free(&b);
}

GI_TEST(frame_refuses_oversize_from_header_alone)
{
    gi_buf b;
    gi_buf_init(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, 0, UINT64_C(1) << 60, NULL, 0, 0);
    GI_REQUIRE(b.len == GI_FRAME_HEADER_SIZE); /* the header is all there is */
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, NULL, "test-peer");
    gi_frame_decoder_feed(&d, b.data, b.len);
    gi_frame f;
    gi_error err;
    GI_CHECK(gi_frame_decoder_next(&d, &f, &err) == -1);
    GI_CHECK(err.code == GI_EPROTO);
    GI_CHECK_MSG(strstr(err.msg,
                        "RESULT frame payload of 1152921504606846976 bytes exceeds the limit of "
                        "1073741824 bytes") != NULL,
                 "%s", err.msg);
    GI_CHECK(d.payload == NULL && d.cap == 0);
    /* Bytes after the refusal are dropped, not queued; the failure sticks. */
    uint8_t junk[4096] = {0};
    gi_frame_decoder_feed(&d, junk, sizeof junk);
    GI_CHECK(d.pending.cap == 0);
    gi_error err2;
    GI_CHECK(gi_frame_decoder_next(&d, &f, &err2) == -1);
    GI_CHECK(strcmp(err.msg, err2.msg) == 0);
    gi_frame_decoder_free(&d);

    /* Per-type limits: a HEARTBEAT may not be 64 KiB + 1. */
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_HEARTBEAT, 0, (64 << 10) + 1, NULL, 0, 0);
    expect_refused(NULL, &b, "HEARTBEAT frame payload of 65537 bytes exceeds the limit of 65536",
                   __LINE__);

    /* Even with no limit at all, memory follows the bytes received rather
     * than the length a peer declares. */
    gi_frame_limits lim = gi_frame_limits_default();
    lim.max_payload[GI_MSG_RESULT] = UINT64_MAX;
    gi_frame_decoder_init(&d, &lim, "test-peer");
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, 0, UINT64_C(1) << 60, NULL, 0, 0);
    gi_frame_decoder_feed(&d, b.data, b.len);
    gi_frame_decoder_feed(&d, junk, 1000);
    GI_CHECK(gi_frame_decoder_next(&d, &f, &err) == 0);
    GI_CHECK(d.fill == 1000 && d.cap <= (64 << 10));
    gi_frame_decoder_free(&d);
    gi_buf_free(&b);
}

GI_TEST(frame_refuses_every_corrupted_byte)
{
    gi_buf good;
    gi_buf_init(&good);
    gi_frame_encode(&good, GI_MSG_PROGRESS, "0123456789", 10, 0);
    for (size_t i = 0; i < good.len; i++) {
        for (int bit = 0; bit < 8; bit++) {
            gi_buf b;
            gi_buf_init(&b);
            gi_buf_put(&b, good.data, good.len);
            b.data[i] ^= (uint8_t)(1u << bit);
            /* Bytes after it (a valid frame, then zeros up to the PROGRESS
             * limit) complete the frame if the flip lengthened the payload:
             * either way the corrupted frame must not pass. */
            gi_buf_put(&b, good.data, good.len);
            memset(gi_buf_grow(&b, 64 << 10), 0, 64 << 10);
            gi_frame f;
            gi_error err;
            int r = decode_one(NULL, b.data, b.len, &f, &err);
            GI_CHECK_MSG(r == -1, "byte %zu bit %d: decoder returned %d", i, bit, r);
            if (r == 1)
                gi_frame_free(&f);
            /* Outside magic/version/type/flags/length only the CRC can object. */
            int only_crc = i >= 20 || (i >= 6 && i < 8 && gi_msg_type_known(
                                                             gi_le_get_u16(b.data + 6)));
            if (r == -1 && only_crc)
                GI_CHECK_MSG(strstr(err.msg, "frame CRC32C mismatch") != NULL,
                             "byte %zu bit %d: %s", i, bit, err.msg);
            gi_buf_free(&b);
        }
    }
    gi_buf_free(&good);
}

GI_TEST(frame_refuses_zstd_bombs_and_bad_zstd)
{
    gi_buf z, b;
    gi_buf_init(&z);
    gi_buf_init(&b);

    /* First prove the hand-made RLE frame is valid zstd: 2 MiB of 'A'. */
    zstd_rle_frame(&z, 16 << 17, 16);
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    gi_frame f;
    gi_error err;
    int r = decode_one(NULL, b.data, b.len, &f, &err);
    GI_CHECK_MSG(r == 1, "valid RLE frame refused: %s", r < 0 ? err.msg : "");
    if (r == 1) {
        GI_CHECK(f.payload.len == (16 << 17));
        GI_CHECK(f.payload.data[0] == 'A' && f.payload.data[f.payload.len - 1] == 'A');
        gi_frame_free(&f);
    }

    /* A real bomb: 320 KiB of RLE blocks that expand to 10 GiB. */
    gi_buf_reset(&z);
    gi_buf_reset(&b);
    zstd_rle_frame(&z, UINT64_C(10) << 30, (size_t)((UINT64_C(10) << 30) >> 17));
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b,
                   "RESULT frame: zstd frame declares 10737418240 decompressed bytes, over the "
                   "limit 1073741824",
                   __LINE__);

    /* A small frame declaring 10 GiB. */
    gi_buf_reset(&z);
    gi_buf_reset(&b);
    zstd_rle_frame(&z, UINT64_C(10) << 30, 1);
    raw_frame(&b, "GIF1", 1, GI_MSG_ASSET_PUT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "declares 10737418240 decompressed bytes", __LINE__);

    /* Declared size and content disagree. */
    gi_buf_reset(&z);
    gi_buf_reset(&b);
    zstd_rle_frame(&z, (16 << 17) + 1, 16);
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "RESULT frame: zstd", __LINE__);

    /* The per-type limit applies to the decompressed size too. */
    uint8_t *zeros = gi_xcalloc(1, 100 << 10);
    gi_buf_reset(&z);
    gi_buf_reset(&b);
    gi_error zerr;
    GI_REQUIRE(gi_zstd_compress(&z, zeros, 100 << 10, 3, &zerr) == 0);
    GI_CHECK(z.len < 1000);
    raw_frame(&b, "GIF1", 1, GI_MSG_HEARTBEAT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "over the limit 65536", __LINE__);

    /* max_decompressed caps every type. */
    gi_frame_limits small = gi_frame_limits_default();
    small.max_decompressed = 1000;
    gi_buf_reset(&z);
    gi_buf_reset(&b);
    GI_REQUIRE(gi_zstd_compress(&z, zeros, 5000, 3, &zerr) == 0);
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(&small, &b, "declares 5000 decompressed bytes, over the limit 1000", __LINE__);

    /* Unknown content size. */
    ZSTD_CCtx *cctx = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_contentSizeFlag, 0);
    gi_buf_reset(&z);
    gi_buf_reserve(&z, ZSTD_compressBound(10000));
    size_t zn = ZSTD_compress2(cctx, z.data, z.cap, zeros, 10000);
    ZSTD_freeCCtx(cctx);
    GI_REQUIRE(!ZSTD_isError(zn));
    z.len = zn;
    GI_CHECK(ZSTD_getFrameContentSize(z.data, z.len) == ZSTD_CONTENTSIZE_UNKNOWN);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_TASK, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "TASK frame: zstd frame does not declare its content size",
                   __LINE__);

    /* Two frames back to back, trailing garbage, a skippable frame, not zstd,
     * an empty payload, a corrupted block (with a correct frame CRC). */
    gi_buf_reset(&z);
    GI_REQUIRE(gi_zstd_compress(&z, zeros, 5000, 3, &zerr) == 0);
    size_t one = z.len;
    GI_REQUIRE(gi_zstd_compress(&z, zeros, 5000, 3, &zerr) == 0);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_TASK, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "bytes follow the zstd frame", __LINE__);
    z.len = one + 1;
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_TASK, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "1 bytes follow the zstd frame", __LINE__);

    uint8_t skippable[12] = {0x50, 0x2A, 0x4D, 0x18, 4, 0, 0, 0, 1, 2, 3, 4};
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_TASK, GI_FRAME_ZSTD, 12, skippable, 12, 0);
    expect_refused(NULL, &b, "payload is not a zstd frame", __LINE__);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_TASK, GI_FRAME_ZSTD, 5, "hello", 5, 0);
    expect_refused(NULL, &b, "payload is not a zstd frame", __LINE__);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_TASK, GI_FRAME_ZSTD, 0, NULL, 0, 0);
    expect_refused(NULL, &b, "payload is not a zstd frame", __LINE__);

    gi_buf_reset(&z);
    uint8_t *text = gi_xmalloc(50000);
    fill_text(text, 50000, 9);
    GI_REQUIRE(gi_zstd_compress(&z, text, 50000, 3, &zerr) == 0);
    z.data[z.len / 2] ^= 0x55;
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, GI_MSG_RESULT, GI_FRAME_ZSTD, z.len, z.data, z.len, 0);
    expect_refused(NULL, &b, "RESULT frame: zstd", __LINE__);
    free(text);
    free(zeros);
    gi_buf_free(&z);
    gi_buf_free(&b);
}

/* ---- blocking I/O ------------------------------------------------------ */

enum { BIG = 100 * 1000 * 1000 };

/* Writer side of the socketpair test, in a child process. */
static int socket_writer(int fd)
{
    gi_error err;
    uint8_t *big = malloc(BIG);
    if (!big)
        return 10;
    fill_random(big, BIG, 42);
    uint8_t *text = gi_xmalloc(8 << 20);
    fill_text(text, 8 << 20, 43);
    if (gi_set_nonblocking(fd, &err) != 0 ||
        gi_frame_send(fd, GI_MSG_HELLO, "worker-1", 8, 0, &err) != 0 ||
        gi_frame_send(fd, GI_MSG_HEARTBEAT, NULL, 0, 1, &err) != 0 ||
        gi_frame_send(fd, GI_MSG_RESULT, big, BIG, 0, &err) != 0 ||
        gi_frame_send(fd, GI_MSG_RESULT, text, 8 << 20, 1, &err) != 0) {
        fprintf(stderr, "writer: %s\n", err.msg);
        return 1;
    }
    free(big);
    free(text);
    return 0;
}

GI_TEST(frame_socketpair_send_recv)
{
    int sv[2];
    GI_REQUIRE(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
    pid_t pid = fork();
    GI_REQUIRE(pid >= 0);
    if (pid == 0) {
        close(sv[0]);
        int rc = socket_writer(sv[1]);
        close(sv[1]);
        _exit(rc);
    }
    close(sv[1]);
    gi_error err;
    GI_REQUIRE_OK(gi_set_nonblocking(sv[0], &err)); /* exercises the poll() path */
    gi_frame f;
    GI_REQUIRE(gi_frame_recv(sv[0], NULL, "writer", &f, &err) == 1);
    GI_CHECK(f.type == GI_MSG_HELLO && f.payload.len == 8 &&
             memcmp(f.payload.data, "worker-1", 8) == 0);
    gi_frame_free(&f);
    GI_REQUIRE(gi_frame_recv(sv[0], NULL, "writer", &f, &err) == 1);
    GI_CHECK(f.type == GI_MSG_HEARTBEAT && f.payload.len == 0);
    gi_frame_free(&f);

    int r = gi_frame_recv(sv[0], NULL, "writer", &f, &err);
    GI_CHECK_MSG(r == 1, "100 MB frame: %s", err.msg);
    if (r == 1) {
        uint8_t *want = gi_xmalloc(BIG);
        fill_random(want, BIG, 42);
        GI_CHECK(f.type == GI_MSG_RESULT && f.flags == 0 && f.payload.len == BIG);
        GI_CHECK(f.payload.len == BIG && memcmp(f.payload.data, want, BIG) == 0);
        free(want);
        gi_frame_free(&f);
    }
    r = gi_frame_recv(sv[0], NULL, "writer", &f, &err);
    GI_CHECK_MSG(r == 1, "compressed frame: %s", err.msg);
    if (r == 1) {
        uint8_t *want = gi_xmalloc(8 << 20);
        fill_text(want, 8 << 20, 43);
        GI_CHECK(f.flags == GI_FRAME_ZSTD && f.payload.len == (8 << 20));
        GI_CHECK(f.payload.len == (8 << 20) && memcmp(f.payload.data, want, 8 << 20) == 0);
        free(want);
        gi_frame_free(&f);
    }
    /* The writer closed its end: a clean end of stream. */
    GI_CHECK(gi_frame_recv(sv[0], NULL, "writer", &f, &err) == 0);
    GI_CHECK(gi_frame_recv(sv[0], NULL, "writer", &f, &err) == 0);
    int status;
    GI_CHECK(waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0);
    close(sv[0]);
}

GI_TEST(frame_recv_reads_exactly_one_frame)
{
    int sv[2];
    GI_REQUIRE(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
    gi_buf two;
    gi_buf_init(&two);
    gi_frame_encode(&two, GI_MSG_TASK, "first", 5, 0);
    size_t first = two.len;
    gi_frame_encode(&two, GI_MSG_TASK, "second", 6, 0);
    gi_error err;
    GI_REQUIRE_OK(gi_write_all(sv[1], two.data, two.len, &err));
    gi_frame f;
    GI_REQUIRE(gi_frame_recv(sv[0], NULL, "peer", &f, &err) == 1);
    GI_CHECK(f.payload.len == 5 && memcmp(f.payload.data, "first", 5) == 0);
    gi_frame_free(&f);
    /* The second frame is still in the socket, byte for byte. */
    uint8_t rest[256];
    ssize_t n = read(sv[0], rest, sizeof rest);
    GI_CHECK(n == (ssize_t)(two.len - first));
    GI_CHECK(n > 0 && memcmp(rest, two.data + first, (size_t)n) == 0);
    gi_buf_free(&two);
    close(sv[0]);
    close(sv[1]);
}

GI_TEST(frame_recv_truncated_and_refused)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_frame_encode(&b, GI_MSG_RESULT, "0123456789abcdef", 16, 0);
    gi_error err;
    gi_frame f;
    /* Closed inside the payload, and inside the header. */
    size_t cuts[] = {b.len - 3, 10};
    for (size_t i = 0; i < GI_ARRAY_LEN(cuts); i++) {
        int sv[2];
        GI_REQUIRE(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
        GI_REQUIRE_OK(gi_write_all(sv[1], b.data, cuts[i], &err));
        close(sv[1]);
        GI_CHECK(gi_frame_recv(sv[0], NULL, "pool child 3", &f, &err) == -1);
        GI_CHECK(err.code == GI_EIO);
        GI_CHECK_MSG(strstr(err.msg, "pool child 3: connection closed") != NULL, "%s", err.msg);
        close(sv[0]);
    }
    /* A refused header over a pipe (gi_write_all's writev path). */
    int pfd[2];
    GI_REQUIRE(pipe(pfd) == 0);
    gi_buf_reset(&b);
    raw_frame(&b, "GIF1", 1, 77, 0, 0, NULL, 0, 0);
    GI_REQUIRE_OK(gi_write_all(pfd[1], b.data, b.len, &err));
    GI_REQUIRE_OK(gi_frame_send(pfd[1], GI_MSG_BYE, "ok", 2, 0, &err));
    GI_CHECK(gi_frame_recv(pfd[0], NULL, "pipe", &f, &err) == -1);
    GI_CHECK(err.code == GI_EPROTO && strstr(err.msg, "frame type 77 is unknown") != NULL);
    GI_CHECK(gi_frame_recv(pfd[0], NULL, "pipe", &f, &err) == 1);
    GI_CHECK(f.type == GI_MSG_BYE);
    gi_frame_free(&f);
    close(pfd[1]);
    GI_CHECK(gi_frame_recv(pfd[0], NULL, "pipe", &f, &err) == 0);
    close(pfd[0]);
    gi_buf_free(&b);
}

GI_TEST(frame_send_to_closed_peer_is_an_error)
{
    /* MSG_NOSIGNAL: EPIPE comes back as an error instead of killing us. */
    int sv[2];
    GI_REQUIRE(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
    close(sv[0]);
    gi_error err;
    GI_CHECK(gi_frame_send(sv[1], GI_MSG_BYE, NULL, 0, 0, &err) == -1);
    GI_CHECK(err.code == GI_EIO && strstr(err.msg, "sending a BYE frame") != NULL);
    close(sv[1]);
}

GI_TEST(frame_failure_is_sticky_with_queued_bytes)
{
    /* good | bad type | good, in one feed: one frame, then the failure,
     * every time it is asked, and nothing after it. */
    gi_buf b;
    gi_buf_init(&b);
    gi_frame_encode(&b, GI_MSG_HELLO, "a", 1, 0);
    raw_frame(&b, "GIF1", 1, 77, 0, 1, "b", 1, 0);
    gi_frame_encode(&b, GI_MSG_HELLO, "c", 1, 0);
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, NULL, "test-peer");
    gi_frame_decoder_feed(&d, b.data, b.len);
    gi_frame f;
    gi_error err;
    GI_REQUIRE(gi_frame_decoder_next(&d, &f, &err) == 1);
    GI_CHECK(f.payload.len == 1 && f.payload.data[0] == 'a');
    gi_frame_free(&f);
    for (int i = 0; i < 3; i++) {
        GI_CHECK(gi_frame_decoder_next(&d, &f, &err) == -1);
        GI_CHECK_MSG(strstr(err.msg, "test-peer, frame at stream byte 25: frame type 77") != NULL,
                     "%s", err.msg);
        size_t room;
        GI_CHECK(gi_frame_decoder_space(&d, &room) == NULL);
        gi_frame_decoder_feed(&d, b.data, b.len);
    }
    GI_CHECK(d.pending.cap == 0);
    gi_frame_decoder_free(&d);
    gi_buf_free(&b);
}
