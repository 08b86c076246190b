/* gi_netio: blocking frame I/O on sockets, socketpairs and pipes.
 *
 * For the simple sides of the protocol (a pool child, the handshake, tools,
 * tests): these block until done. If handed a non-blocking descriptor they
 * wait for it with poll() rather than failing with EAGAIN. Event loops use
 * gi_frame_decoder directly. */
#ifndef GI_NETIO_H
#define GI_NETIO_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "gi_error.h"
#include "gi_frame.h"

/* Writes all n bytes, retrying on EINTR and partial writes. On sockets it
 * uses MSG_NOSIGNAL, so a closed peer is an EPIPE error (GI_EIO), not a
 * SIGPIPE; on pipes the process must ignore SIGPIPE for the same effect. */
int gi_write_all(int fd, const void *p, size_t n, gi_error *err);

/* Encodes and writes one frame (see gi_frame_encode for compress). The
 * payload is not copied: header and payload go out with one sendmsg. */
int gi_frame_send(int fd, uint16_t type, const void *payload, size_t len, int compress,
                  gi_error *err);

/* Reads exactly one frame, never a byte more (so it can be mixed with other
 * readers of fd). lim NULL means the defaults; peer names fd in messages.
 * Returns 1 with *out filled (caller frees out->payload), 0 on a clean end
 * of stream before the first byte of a frame, -1 on an error (GI_EIO for
 * I/O and truncation, GI_EPROTO / GI_ENOMEM as gi_frame_decoder_next). */
int gi_frame_recv(int fd, const gi_frame_limits *lim, const char *peer, gi_frame *out,
                  gi_error *err);

/* For event loops: reads what a non-blocking socket has (at most max bytes)
 * straight into the decoder's buffer. Returns the bytes read (> 0), 0 at
 * the end of the stream, or -1 with errno (EAGAIN: nothing now). While the
 * decoder holds a complete frame (or is broken) it reads nothing and
 * returns -1 with errno EAGAIN: take the frames with
 * gi_frame_decoder_next first. */
ssize_t gi_frame_decoder_recv(gi_frame_decoder *d, int fd, size_t max);

/* Frames waiting to be written to a non-blocking socket (event loops). */
typedef struct gi_outq {
    gi_buf buf;
    size_t off; /* bytes of buf already sent */
} gi_outq;

void gi_outq_init(gi_outq *q);
void gi_outq_free(gi_outq *q);
/* Encodes one frame at the end of the queue (see gi_frame_encode). */
void gi_outq_push(gi_outq *q, uint16_t type, const gi_buf *payload, int compress);
/* Queues a frame gi_frame_encode made earlier (sent to many peers). */
void gi_outq_push_frame(gi_outq *q, const gi_buf *frame);
static inline size_t gi_outq_pending(const gi_outq *q) { return q->buf.len - q->off; }
/* Sends what the socket takes now (MSG_NOSIGNAL). Returns 0, with or
 * without bytes left, or -1 with errno when the socket failed. */
int gi_outq_flush(gi_outq *q, int fd);

int gi_set_nonblocking(int fd, gi_error *err);

#endif
