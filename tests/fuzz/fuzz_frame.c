/* fuzz_frame: libFuzzer target for the incremental frame decoder.
 *
 * Input layout:
 *   byte 0      options: bit 0 receive through space/commit instead of feed,
 *               bit 1 tight limits (256-byte payloads, 1 KiB decompressed),
 *               bit 2 repair CRCs before decoding, so mutated payloads get
 *               past the checksum to the zstd decoder and beyond,
 *               bit 3 lazy reader: take at most one frame after each chunk,
 *               so fed bytes queue up behind complete frames
 *   bytes 1..8  chunk sizes: chunk i is input[1 + i % 8] + 1 bytes long
 *   bytes 9..   the byte stream, delivered in those chunks; after each chunk
 *               frames are drained until the decoder wants more or fails.
 * Every frame it produces must satisfy the decoder's promises (known type,
 * no reserved flags, payload within the limit) and must survive a
 * re-encode/decode round trip unchanged.
 *
 * Build (see the Makefile's fuzzers target):
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -I. -Icommon -Iprotocol \
 *     tests/fuzz/fuzz_frame.c protocol/gi_frame.c protocol/gi_crc32c.c \
 *     protocol/gi_zstd.c common/gi_buf.c common/gi_error.c common/gi_log.c -lzstd
 * The seed corpus in tests/fuzz/corpus/frame/ is written by this file built
 * without libFuzzer:
 *   cc -DGI_FUZZ_FRAME_WRITE_CORPUS ... tests/fuzz/fuzz_frame.c ... -o w &&
 *   ./w tests/fuzz/corpus/frame */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"

#define PREFIX 9

/* Rewrites the CRC of every complete frame in s[0..n) (lengths as read). */
static void repair_crcs(uint8_t *s, size_t n)
{
    size_t o = 0;
    while (n - o >= GI_FRAME_HEADER_SIZE) {
        uint64_t len = gi_le_get_u64(s + o + 12);
        if (len > n - o - GI_FRAME_HEADER_SIZE)
            return;
        uint32_t crc = gi_crc32c(0, s + o, GI_FRAME_CRC_OFFSET);
        crc = gi_crc32c(crc, s + o + GI_FRAME_HEADER_SIZE, (size_t)len);
        gi_le_put_u32(s + o + GI_FRAME_CRC_OFFSET, crc);
        o += GI_FRAME_HEADER_SIZE + (size_t)len;
    }
}

static gi_frame_limits fuzz_limits(int tight)
{
    gi_frame_limits lim = gi_frame_limits_default();
    if (tight) {
        for (int t = 0; t < GI_MSG_TYPE_COUNT; t++)
            lim.max_payload[t] = 256;
        lim.max_decompressed = 1024;
    }
    return lim;
}

static void check_frame(const gi_frame *f, const gi_frame_limits *lim)
{
    if (!gi_msg_type_known(f->type) || (f->flags & ~GI_FRAME_FLAGS_KNOWN) ||
        f->payload.len > lim->max_payload[f->type])
        abort();
    /* Round trip: what was accepted re-encodes to something accepted again. */
    if (f->payload.len > (64 << 10))
        return;
    gi_buf b;
    gi_buf_init(&b);
    gi_frame_encode(&b, f->type, f->payload.data, f->payload.len, 1);
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, NULL, "fuzz round trip");
    gi_frame_decoder_feed(&d, b.data, b.len);
    gi_frame g;
    gi_error err;
    if (gi_frame_decoder_next(&d, &g, &err) != 1)
        abort();
    if (g.type != f->type || g.payload.len != f->payload.len ||
        (g.payload.len && memcmp(g.payload.data, f->payload.data, g.payload.len) != 0))
        abort();
    gi_frame_free(&g);
    gi_frame_decoder_free(&d);
    gi_buf_free(&b);
}

/* Takes up to max frames; returns -1 once the stream is broken. */
static int drain(gi_frame_decoder *d, const gi_frame_limits *lim, size_t max)
{
    for (size_t taken = 0; taken < max; taken++) {
        gi_frame f;
        gi_error err;
        int r = gi_frame_decoder_next(d, &f, &err);
        if (r == 0)
            return 0;
        if (r < 0) {
            /* One line, naming the peer; and the failure sticks. */
            if (strchr(err.msg, '\n') || strncmp(err.msg, "fuzz peer", 9) != 0)
                abort();
            gi_error again;
            if (gi_frame_decoder_next(d, &f, &again) != -1 || strcmp(again.msg, err.msg) != 0)
                abort();
            return -1;
        }
        check_frame(&f, lim);
        gi_frame_free(&f);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < PREFIX)
        return 0;
    int zero_copy = data[0] & 1;
    size_t per_chunk = (data[0] & 8) ? 1 : SIZE_MAX;
    gi_frame_limits lim = fuzz_limits(data[0] & 2);
    const uint8_t *sizes = data + 1;
    size_t n = size - PREFIX;
    uint8_t *copy = NULL;
    const uint8_t *p = data + PREFIX;
    if (data[0] & 4) {
        copy = malloc(n ? n : 1);
        if (!copy)
            return 0;
        memcpy(copy, p, n);
        repair_crcs(copy, n);
        p = copy;
    }

    gi_frame_decoder d;
    gi_frame_decoder_init(&d, &lim, "fuzz peer");
    size_t pos = 0;
    for (size_t i = 0; pos < n; i++) {
        size_t chunk = (size_t)sizes[i % 8] + 1;
        if (chunk > n - pos)
            chunk = n - pos;
        if (!zero_copy) {
            gi_frame_decoder_feed(&d, p + pos, chunk);
            pos += chunk;
        } else {
            size_t end = pos + chunk;
            while (pos < end) {
                size_t room;
                uint8_t *dst = gi_frame_decoder_space(&d, &room);
                if (!dst) {
                    if (drain(&d, &lim, per_chunk) < 0)
                        break;
                    continue;
                }
                if (room == 0)
                    abort();
                size_t k = end - pos < room ? end - pos : room;
                memcpy(dst, p + pos, k);
                gi_frame_decoder_commit(&d, k);
                pos += k;
            }
        }
        if (drain(&d, &lim, per_chunk) < 0)
            break;
    }
    drain(&d, &lim, SIZE_MAX);
    gi_frame_decoder_free(&d);
    free(copy);
    return 0;
}

#ifdef GI_FUZZ_FRAME_WRITE_CORPUS
/* Seed corpus: valid streams (compressed and not, one and many frames, both
 * receive paths), and a few that must be refused, so the fuzzer starts from
 * inputs that reach every stage of the decoder. */
static void write_seed(const char *dir, const char *name, uint8_t options,
                       const uint8_t sizes[8], const gi_buf *stream)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        exit(1);
    }
    fputc(options, f);
    fwrite(sizes, 1, 8, f);
    fwrite(stream->data, 1, stream->len, f);
    if (fclose(f) != 0) {
        perror(path);
        exit(1);
    }
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s CORPUS_DIR\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1];
    static const uint8_t whole[8] = {255, 255, 255, 255, 255, 255, 255, 255};
    static const uint8_t ragged[8] = {0, 1, 6, 22, 23, 100, 2, 255};
    uint8_t text[6000];
    for (size_t i = 0; i < sizeof text; i++)
        text[i] = (uint8_t)("radiance photon disc "[(i * 7 + i / 13) % 21]);
    gi_buf s;
    gi_buf_init(&s);

    gi_frame_encode(&s, GI_MSG_HELLO, "gi-worker 1 cores=8", 19, 0);
    write_seed(dir, "hello", 0, whole, &s);

    gi_buf_reset(&s);
    gi_frame_encode(&s, GI_MSG_RESULT, text, sizeof text, 1);
    write_seed(dir, "result-zstd", 0, whole, &s);
    write_seed(dir, "result-zstd-zero-copy", 1, ragged, &s);
    write_seed(dir, "result-zstd-repair-crc", 4, whole, &s);

    gi_buf_reset(&s);
    gi_frame_encode(&s, GI_MSG_HEARTBEAT, NULL, 0, 0);
    gi_frame_encode(&s, GI_MSG_TASK, text, 300, 0);
    gi_frame_encode(&s, GI_MSG_ASSET_PUT, text, 5000, 1);
    gi_frame_encode(&s, GI_MSG_PROGRESS, "\x01\x00\x00\x00", 4, 0);
    gi_frame_encode(&s, GI_MSG_BYE, NULL, 0, 0);
    write_seed(dir, "mixed-ragged", 0, ragged, &s);
    write_seed(dir, "mixed-tight-limits", 2, ragged, &s);
    write_seed(dir, "mixed-repair-crc", 4 | 1, ragged, &s);
    write_seed(dir, "mixed-lazy", 8, ragged, &s);

    gi_buf_reset(&s);
    gi_frame_encode(&s, GI_MSG_ERROR, "boom", 4, 0);
    s.data[s.len - 1] ^= 1; /* CRC mismatch */
    write_seed(dir, "bad-crc", 0, whole, &s);

    gi_buf_reset(&s);
    gi_frame_encode(&s, GI_MSG_CANCEL, "x", 1, 0);
    s.data[6] = 77; /* unknown type */
    write_seed(dir, "bad-type", 1, whole, &s);
    gi_buf_free(&s);
    return 0;
}
#endif
