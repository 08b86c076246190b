/* gi_frame: the frame layer of the wire protocol (DESIGN.md "Wire protocol").
 *
 * Every message between the coordinator and a remote worker (TCP) and between
 * a worker and its pool children (socketpairs) is one frame:
 *
 *   offset  size  field
 *        0     4  magic "GIF1"
 *        4     2  version (u16 LE) = GI_FRAME_VERSION
 *        6     2  type (u16 LE), a gi_msg_type
 *        8     4  flags (u32 LE): bit 0 GI_FRAME_ZSTD, all others zero
 *       12     8  length (u64 LE) of the payload as sent
 *       20     4  crc32c (u32 LE) over bytes 0..19 and the payload as sent
 *       24     -  payload (a single zstd frame when GI_FRAME_ZSTD is set)
 *
 * The decoder is incremental, for non-blocking event loops: it validates a
 * header as soon as its 24 bytes are in, so an oversized or malformed frame
 * is refused before any payload is buffered, and the payload buffer grows
 * with the bytes actually received (never to the declared length up front),
 * so a peer that lies about a length costs nothing. */
#ifndef GI_FRAME_H
#define GI_FRAME_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_crc32c.h"
#include "gi_error.h"

/* The framing's version: the layout above. The message set's version is
 * another matter, negotiated in the handshake (gi_msg_ctrl.h: GI_PROTO_*);
 * its versions so far change payloads only, so every frame keeps this one. */
#define GI_FRAME_VERSION 1
#define GI_FRAME_HEADER_SIZE 24
#define GI_FRAME_CRC_OFFSET 20 /* the CRC covers the header bytes before it */

#define GI_FRAME_ZSTD 0x1u /* payload is one zstd frame declaring its content size */
#define GI_FRAME_FLAGS_KNOWN GI_FRAME_ZSTD

/* Below this, zstd's ~10-byte frame overhead and the per-call context setup
 * outweigh what a control message could save. */
#define GI_FRAME_COMPRESS_MIN 4096

/* Default payload limits (bytes). They bound the memory one connection can
 * make its reader hold, so each is the largest legitimate message of its
 * kind with headroom, not more:
 *   CONTROL  handshake, heartbeats, errors, progress: a few hundred bytes;
 *            64 KiB leaves room for long error messages and worker info.
 *   LIST     ASSET_NEED carries asset digests: 1 MiB is 32768 SHA-256 names.
 *   WORK     JOB (job + scene description) and TASK (e.g. a block of
 *            low-rank radiosity basis columns, k x n floats): 256 MiB.
 *   BULK     RESULT (per-vertex or per-pixel float arrays; an 8192 x 8192
 *            RGB float image is 768 MiB) and ASSET_PUT (meshes, textures; a
 *            20 M-triangle indexed mesh is ~0.6 GiB): 1 GiB.
 * Decompressed payloads are held to the same per-type limit and to
 * max_decompressed (default 1 GiB). */
#define GI_FRAME_LIMIT_CONTROL (UINT64_C(64) << 10)
#define GI_FRAME_LIMIT_LIST (UINT64_C(1) << 20)
#define GI_FRAME_LIMIT_WORK (UINT64_C(256) << 20)
#define GI_FRAME_LIMIT_BULK (UINT64_C(1) << 30)

/* The message types: X(NAME, value, default limit). Values must stay
 * contiguous from 1; adding a type is adding a line here (and handling it
 * where messages are dispatched). */
#define GI_MSG_TYPE_LIST(X)                                                              \
    X(HELLO, 1, GI_FRAME_LIMIT_CONTROL)                                                  \
    X(CHALLENGE, 2, GI_FRAME_LIMIT_CONTROL)                                              \
    X(AUTH, 3, GI_FRAME_LIMIT_CONTROL)                                                   \
    X(WELCOME, 4, GI_FRAME_LIMIT_CONTROL)                                                \
    X(JOB, 5, GI_FRAME_LIMIT_WORK)                                                       \
    X(ASSET_NEED, 6, GI_FRAME_LIMIT_LIST)                                                \
    X(ASSET_PUT, 7, GI_FRAME_LIMIT_BULK)                                                 \
    X(TASK, 8, GI_FRAME_LIMIT_WORK)                                                      \
    X(RESULT, 9, GI_FRAME_LIMIT_BULK)                                                    \
    X(FAIL, 10, GI_FRAME_LIMIT_CONTROL)                                                  \
    X(HEARTBEAT, 11, GI_FRAME_LIMIT_CONTROL)                                             \
    X(CANCEL, 12, GI_FRAME_LIMIT_CONTROL)                                                \
    X(DRAIN, 13, GI_FRAME_LIMIT_CONTROL)                                                 \
    X(BYE, 14, GI_FRAME_LIMIT_CONTROL)                                                   \
    X(ERROR, 15, GI_FRAME_LIMIT_CONTROL)                                                 \
    X(PROGRESS, 16, GI_FRAME_LIMIT_CONTROL)

typedef enum gi_msg_type {
#define GI_MSG_ENUM_(name, value, limit) GI_MSG_##name = value,
    GI_MSG_TYPE_LIST(GI_MSG_ENUM_)
#undef GI_MSG_ENUM_
    GI_MSG_TYPE_COUNT /* one past the largest type; arrays are indexed by type */
} gi_msg_type;

/* "HELLO", ..., or "unknown" for a type not in the list. */
const char *gi_msg_type_name(uint16_t type);
/* 1 if the decoder accepts frames of this type. */
int gi_msg_type_known(uint16_t type);

typedef struct gi_frame_limits {
    /* By type, bytes on the wire and decompressed. 0 refuses frames of that
     * type with a payload (a connection that must never carry them). */
    uint64_t max_payload[GI_MSG_TYPE_COUNT];
    uint64_t max_decompressed;               /* cap on any zstd content size */
} gi_frame_limits;

gi_frame_limits gi_frame_limits_default(void);

/* A decoded frame. flags are as received (GI_FRAME_ZSTD tells it was
 * compressed); payload is always the decompressed bytes. */
typedef struct gi_frame {
    uint16_t type;
    uint32_t flags;
    gi_buf payload;
} gi_frame;

void gi_frame_free(gi_frame *f); /* frees the payload */

/* Writes the 24-byte header for a payload already in its wire form
 * (compressed if flags has GI_FRAME_ZSTD), CRC included. */
void gi_frame_header_write(uint8_t hdr[GI_FRAME_HEADER_SIZE], uint16_t type, uint32_t flags,
                           const void *wire, size_t wire_len);

/* Chooses the wire form of a payload: when compress != 0, len >=
 * GI_FRAME_COMPRESS_MIN and zstd (level 3) makes it smaller, the compressed
 * bytes go into scratch (appended) and GI_FRAME_ZSTD is returned; otherwise
 * the payload is sent as is and 0 is returned. *wire / *wire_len point at
 * what to send (valid until scratch changes). */
uint32_t gi_frame_wire_payload(gi_buf *scratch, const void *payload, size_t len, int compress,
                               const void **wire, size_t *wire_len);

/* Appends one frame (header + payload) to out. type must be a known type. */
void gi_frame_encode(gi_buf *out, uint16_t type, const void *payload, size_t len,
                     int compress);

/* Incremental decoder. The fields are private; they are visible so a
 * decoder can live inside a connection struct without an allocation. */
typedef struct gi_frame_decoder {
    gi_frame_limits lim;
    char *peer;                       /* names the other end in messages */
    int state;                        /* header / payload / ready / broken */
    uint8_t hdr[GI_FRAME_HEADER_SIZE];
    size_t hdr_fill;
    uint16_t type;                    /* of the frame being received */
    uint32_t flags, crc_expected;
    uint64_t length;
    uint8_t *payload;                 /* wire payload, grown as bytes arrive */
    size_t fill, cap;
    uint32_t crc;                     /* running CRC32C of header[0..20) + payload[0..fill) */
    uint64_t offset;                  /* stream offset of the current frame */
    gi_buf pending;                   /* fed bytes beyond a complete frame */
    size_t pending_off;
    gi_error err;                     /* the failure, once the stream is broken */
} gi_frame_decoder;

/* lim NULL means gi_frame_limits_default(); it is copied. peer (copied)
 * prefixes every message, e.g. "worker 10.0.0.7:51234" or "pool child 3". */
void gi_frame_decoder_init(gi_frame_decoder *d, const gi_frame_limits *lim, const char *peer);
void gi_frame_decoder_free(gi_frame_decoder *d);
/* Replaces the limits for frames whose header is not yet complete (e.g.
 * raised once a peer has authenticated). */
void gi_frame_decoder_set_limits(gi_frame_decoder *d, const gi_frame_limits *lim);

/* Appends received bytes. Bytes that belong to the frame in progress go
 * straight into its header or payload buffer; only bytes past a complete,
 * not yet taken frame are queued. After a failure, bytes are dropped. */
void gi_frame_decoder_feed(gi_frame_decoder *d, const void *data, size_t len);

/* 1: a frame was produced into *out (overwritten; the caller frees
 *    out->payload with gi_buf_free or gi_frame_free);
 * 0: more bytes needed;
 * -1: the stream is broken (bad magic, version, type, flags, length over
 *    limit, CRC mismatch, bad zstd: GI_EPROTO; allocation failure:
 *    GI_ENOMEM) - err says which, naming the peer and the stream offset.
 *    The failure is sticky: later calls return -1 with the same message. */
int gi_frame_decoder_next(gi_frame_decoder *d, gi_frame *out, gi_error *err);

/* 1 if the decoder holds bytes of a frame not yet returned by next() (so an
 * end of stream now would cut a frame short), else 0. */
int gi_frame_decoder_mid_frame(const gi_frame_decoder *d);

/* Zero-copy receiving: where the next bytes read from the peer should go,
 * and how many the decoder takes there (*n >= 1, never past the end of the
 * current header or payload, so a reader using it never reads beyond one
 * frame). NULL when a frame is complete or the stream is broken: call
 * gi_frame_decoder_next. After reading k <= *n bytes into it, call
 * gi_frame_decoder_commit(d, k). */
uint8_t *gi_frame_decoder_space(gi_frame_decoder *d, size_t *n);
void gi_frame_decoder_commit(gi_frame_decoder *d, size_t n);

#endif
