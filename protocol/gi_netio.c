/* gi_netio: blocking writes and frame send/receive over file descriptors. */
#include "gi_netio.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

/* One syscall moves at most this much, well under SSIZE_MAX and Linux's
 * own ~2 GiB per-call cap. */
#define IO_CHUNK ((size_t)1 << 30)

/* Waits until fd is ready for `events` (used only on EAGAIN, i.e. when a
 * non-blocking descriptor was handed to a blocking helper). */
static int wait_fd(int fd, short events, const char *what, gi_error *err)
{
    struct pollfd pfd = {.fd = fd, .events = events};
    for (;;) {
        int r = poll(&pfd, 1, -1);
        if (r > 0)
            return 0;
        if (r < 0 && errno != EINTR)
            return gi_fail(err, GI_EIO, "%s: poll on fd %d failed: %s", what, fd,
                           strerror(errno));
    }
}

/* Writes every byte of iov[0..cnt), advancing through partial writes
 * (iov is modified). */
static int writev_all(int fd, struct iovec *iov, int cnt, gi_error *err)
{
    int is_socket = 1;
    for (;;) {
        while (cnt > 0 && iov->iov_len == 0) {
            iov++;
            cnt--;
        }
        if (cnt == 0)
            return 0;
        /* One call carries at most IO_CHUNK bytes in total. */
        struct iovec v[4];
        int nv = 0;
        size_t total = 0;
        for (int i = 0; i < cnt && nv < (int)GI_ARRAY_LEN(v) && total < IO_CHUNK; i++) {
            v[nv] = iov[i];
            if (v[nv].iov_len > IO_CHUNK - total)
                v[nv].iov_len = IO_CHUNK - total;
            total += v[nv++].iov_len;
        }
        ssize_t w;
        if (is_socket) {
            struct msghdr mh = {.msg_iov = v, .msg_iovlen = (size_t)nv};
            w = sendmsg(fd, &mh, MSG_NOSIGNAL);
            if (w < 0 && errno == ENOTSOCK) { /* a pipe or file: plain writev */
                is_socket = 0;
                continue;
            }
        } else {
            w = writev(fd, v, nv);
        }
        if (w < 0) {
            if (errno == EINTR)
                continue;
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                if (wait_fd(fd, POLLOUT, "write", err) != 0)
                    return -1;
                continue;
            }
            return gi_fail(err, GI_EIO, "write to fd %d failed: %s", fd, strerror(errno));
        }
        for (size_t done = (size_t)w; done > 0;) {
            size_t k = done < iov->iov_len ? done : iov->iov_len;
            iov->iov_base = (uint8_t *)iov->iov_base + k;
            iov->iov_len -= k;
            done -= k;
            if (iov->iov_len == 0) {
                iov++;
                cnt--;
            }
        }
    }
}

int gi_write_all(int fd, const void *p, size_t n, gi_error *err)
{
    struct iovec iov = {.iov_base = (void *)p, .iov_len = n};
    return writev_all(fd, &iov, 1, err);
}

int gi_frame_send(int fd, uint16_t type, const void *payload, size_t len, int compress,
                  gi_error *err)
{
    gi_buf scratch;
    gi_buf_init(&scratch);
    const void *wire;
    size_t wire_len;
    uint32_t flags = gi_frame_wire_payload(&scratch, payload, len, compress, &wire, &wire_len);
    uint8_t hdr[GI_FRAME_HEADER_SIZE];
    gi_frame_header_write(hdr, type, flags, wire, wire_len);
    struct iovec iov[2] = {{.iov_base = hdr, .iov_len = sizeof hdr},
                           {.iov_base = (void *)wire, .iov_len = wire_len}};
    int rc = writev_all(fd, iov, 2, err);
    gi_buf_free(&scratch);
    if (rc != 0)
        gi_error_prefix(err, "sending a %s frame of %zu bytes", gi_msg_type_name(type), len);
    return rc;
}

int gi_frame_recv(int fd, const gi_frame_limits *lim, const char *peer, gi_frame *out,
                  gi_error *err)
{
    if (!peer)
        peer = "peer";
    gi_frame_decoder d;
    gi_frame_decoder_init(&d, lim, peer);
    uint64_t got = 0;
    int rc = -1;
    for (;;) {
        size_t n;
        uint8_t *p = gi_frame_decoder_space(&d, &n);
        if (!p)
            break;
        ssize_t r = read(fd, p, n < IO_CHUNK ? n : IO_CHUNK);
        if (r < 0) {
            if (errno == EINTR)
                continue;
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                if (wait_fd(fd, POLLIN, peer, err) != 0)
                    goto out;
                continue;
            }
            gi_fail(err, GI_EIO, "%s: read failed: %s", peer, strerror(errno));
            goto out;
        }
        if (r == 0) {
            if (got == 0) {
                rc = 0; /* clean end of stream between frames */
                goto out;
            }
            gi_fail(err, GI_EIO, "%s: connection closed %llu bytes into a frame%s", peer,
                    (unsigned long long)got,
                    got < GI_FRAME_HEADER_SIZE ? " (inside the header)" : "");
            goto out;
        }
        gi_frame_decoder_commit(&d, (size_t)r);
        got += (uint64_t)r;
    }
    rc = gi_frame_decoder_next(&d, out, err);
out:
    gi_frame_decoder_free(&d);
    return rc;
}

ssize_t gi_frame_decoder_recv(gi_frame_decoder *d, int fd, size_t max)
{
    size_t room;
    uint8_t *p = gi_frame_decoder_space(d, &room);
    if (!p) {
        errno = EAGAIN;
        return -1;
    }
    ssize_t n;
    do
        n = recv(fd, p, room < max ? room : max, MSG_DONTWAIT);
    while (n < 0 && errno == EINTR);
    if (n > 0)
        gi_frame_decoder_commit(d, (size_t)n);
    return n;
}

void gi_outq_init(gi_outq *q)
{
    gi_buf_init(&q->buf);
    q->off = 0;
}

void gi_outq_free(gi_outq *q)
{
    gi_buf_free(&q->buf);
    q->off = 0;
}

void gi_outq_push(gi_outq *q, uint16_t type, const gi_buf *payload, int compress)
{
    gi_frame_encode(&q->buf, type, payload ? payload->data : NULL, payload ? payload->len : 0,
                    compress);
}

void gi_outq_push_frame(gi_outq *q, const gi_buf *frame)
{
    gi_buf_put(&q->buf, frame->data, frame->len);
}

int gi_outq_flush(gi_outq *q, int fd)
{
    while (q->off < q->buf.len) {
        ssize_t n = send(fd, q->buf.data + q->off, q->buf.len - q->off, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            break;
        if (n < 0)
            return -1;
        q->off += (size_t)n;
    }
    if (q->off == q->buf.len) {
        q->buf.len = q->off = 0;
        if (q->buf.cap > ((size_t)4 << 20))
            gi_buf_free(&q->buf); /* an idle peer keeps no large buffer */
    } else if (q->off > q->buf.len / 2) {
        /* Compact when the sent prefix dominates, so queueing stays linear. */
        memmove(q->buf.data, q->buf.data + q->off, q->buf.len - q->off);
        q->buf.len -= q->off;
        q->off = 0;
    }
    return 0;
}

int gi_set_nonblocking(int fd, gi_error *err)
{
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0)
        return gi_fail(err, GI_EIO, "cannot make fd %d non-blocking: %s", fd, strerror(errno));
    return 0;
}
