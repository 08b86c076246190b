/* gi_http_client: one HTTP/1.1 request per connection. */
#include "gi_http_client.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <unistd.h>

#include "gi_fs.h"
#include "gi_net.h"
#include "gi_netio.h"

int gi_http_url_parse(const char *url, gi_http_url *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    if (strncmp(url, "http://", 7) != 0)
        return gi_fail(err, GI_EINVAL, "farm URL \"%s\": expected http://HOST[:PORT][/PATH]", url);
    const char *h = url + 7;
    const char *slash = strchr(h, '/');
    size_t n = slash ? (size_t)(slash - h) : strlen(h);
    if (n == 0 || n > 255)
        return gi_fail(err, GI_EINVAL, "farm URL \"%s\": no host", url);
    out->hostport = gi_xmalloc(n + 4);
    memcpy(out->hostport, h, n);
    out->hostport[n] = '\0';
    /* A port is needed to connect: add :80 unless one is given. */
    const char *colon = strrchr(out->hostport, ':');
    const char *bracket = strrchr(out->hostport, ']');
    if (!colon || (bracket && colon < bracket))
        strcat(out->hostport, ":80");
    const char *p = slash ? slash : "";
    size_t pl = strlen(p);
    while (pl && p[pl - 1] == '/')
        pl--;
    out->prefix = gi_xmalloc(pl + 1);
    memcpy(out->prefix, p, pl);
    out->prefix[pl] = '\0';
    return 0;
}

void gi_http_url_free(gi_http_url *u)
{
    free(u->hostport);
    free(u->prefix);
    u->hostport = u->prefix = NULL;
}

/* ---- parsing ------------------------------------------------------------- */

static const char *find_crlf(const char *p, const char *end)
{
    for (; p + 1 < end; p++)
        if (p[0] == '\r' && p[1] == '\n')
            return p;
    return NULL;
}

int gi_http_parse_head(const char *data, size_t len, gi_http_head *out, size_t *head_len,
                       gi_error *err)
{
    out->status = 0;
    out->chunked = 0;
    out->content_length = -1;
    size_t scan = len < GI_HTTP_MAX_HEAD ? len : GI_HTTP_MAX_HEAD;
    const char *end = NULL;
    for (size_t i = 0; i + 3 < scan; i++)
        if (memcmp(data + i, "\r\n\r\n", 4) == 0) {
            end = data + i + 4;
            break;
        }
    if (!end) {
        if (len >= GI_HTTP_MAX_HEAD)
            return gi_fail(err, GI_EPROTO, "HTTP response head is longer than %d bytes",
                           GI_HTTP_MAX_HEAD);
        return 0;
    }
    *head_len = (size_t)(end - data);
    const char *line = data, *eol = find_crlf(line, end);
    /* "HTTP/1.x NNN reason" */
    if (eol - line < 12 || strncmp(line, "HTTP/1.", 7) != 0 || !isdigit((unsigned char)line[7]) ||
        line[8] != ' ' || !isdigit((unsigned char)line[9]) ||
        !isdigit((unsigned char)line[10]) || !isdigit((unsigned char)line[11]))
        return gi_fail(err, GI_EPROTO, "malformed HTTP status line");
    out->status = (line[9] - '0') * 100 + (line[10] - '0') * 10 + (line[11] - '0');
    if (out->status < 100)
        return gi_fail(err, GI_EPROTO, "malformed HTTP status %d", out->status);
    for (line = eol + 2; line < end - 2; line = eol + 2) {
        eol = find_crlf(line, end);
        const char *colon = memchr(line, ':', (size_t)(eol - line));
        if (!colon)
            return gi_fail(err, GI_EPROTO, "malformed HTTP header line");
        size_t kn = (size_t)(colon - line);
        const char *v = colon + 1;
        while (v < eol && (*v == ' ' || *v == '\t'))
            v++;
        size_t vn = (size_t)(eol - v);
        if (kn == 14 && strncasecmp(line, "Content-Length", 14) == 0) {
            int64_t n = 0;
            if (vn == 0 || vn > 18)
                return gi_fail(err, GI_EPROTO, "malformed Content-Length");
            for (size_t i = 0; i < vn; i++) {
                if (!isdigit((unsigned char)v[i]))
                    return gi_fail(err, GI_EPROTO, "malformed Content-Length");
                n = n * 10 + (v[i] - '0');
            }
            out->content_length = n;
        } else if (kn == 17 && strncasecmp(line, "Transfer-Encoding", 17) == 0) {
            if (vn == 7 && strncasecmp(v, "chunked", 7) == 0)
                out->chunked = 1;
            else if (!(vn == 8 && strncasecmp(v, "identity", 8) == 0))
                return gi_fail(err, GI_EPROTO, "unsupported Transfer-Encoding");
        }
    }
    return 1;
}

/* A chunk's size line [p, eol) (hex digits, then maybe ";extensions"). */
static int chunk_size(const char *p, const char *eol, uint64_t *out, gi_error *err)
{
    uint64_t n = 0;
    const char *q = p;
    int digits = 0;
    for (; q < eol && isxdigit((unsigned char)*q); q++, digits++) {
        if (digits == 15)
            return gi_fail(err, GI_EPROTO, "chunk size too large");
        n = n * 16 + (uint64_t)(isdigit((unsigned char)*q) ? *q - '0' : (tolower(*q) - 'a' + 10));
    }
    if (digits == 0 || (q < eol && *q != ';'))
        return gi_fail(err, GI_EPROTO, "malformed chunk size");
    *out = n;
    return 0;
}

int gi_http_dechunk(gi_buf *in, gi_error *err)
{
    if (in->len == 0)
        return gi_fail(err, GI_EPROTO, "empty chunked body");
    const char *p = (const char *)in->data, *end = p + in->len;
    size_t w = 0;
    for (;;) {
        const char *eol = find_crlf(p, end);
        if (!eol)
            return gi_fail(err, GI_EPROTO, "truncated chunked body");
        uint64_t n;
        if (chunk_size(p, eol, &n, err))
            return -1;
        p = eol + 2;
        if (n == 0)
            break; /* trailers, if any, are ignored */
        if ((uint64_t)(end - p) < n + 2 || p[n] != '\r' || p[n + 1] != '\n')
            return gi_fail(err, GI_EPROTO, "truncated chunk");
        memmove(in->data + w, p, (size_t)n);
        w += (size_t)n;
        p += n + 2;
    }
    in->len = w;
    return 0;
}

/* ---- transport ----------------------------------------------------------- */

static int wait_readable(int fd, double timeout_s, gi_error *err)
{
    struct pollfd p = {.fd = fd, .events = POLLIN};
    for (;;) {
        int r = poll(&p, 1, (int)(timeout_s * 1000));
        if (r > 0)
            return 0;
        if (r == 0)
            return gi_fail(err, GI_EIO, "the farm did not answer within %.0f s", timeout_s);
        if (errno != EINTR)
            return gi_fail(err, GI_EIO, "poll: %s", strerror(errno));
    }
}

/* Reads what is available (at most n) after waiting; 0 at end of stream. */
static ssize_t read_some(int fd, void *p, size_t n, double timeout_s, gi_error *err)
{
    if (wait_readable(fd, timeout_s, err))
        return -1;
    for (;;) {
        ssize_t r = recv(fd, p, n, 0);
        if (r >= 0)
            return r;
        if (errno != EINTR)
            return gi_fail(err, GI_EIO, "reading the response: %s", strerror(errno));
    }
}

static int send_request(int fd, const gi_http_url *u, const gi_http_request *rq, gi_error *err)
{
    gi_buf h;
    gi_buf_init(&h);
    char line[8192];
    int n = snprintf(line, sizeof line,
                     "%s %s%s HTTP/1.1\r\nHost: %s\r\nConnection: close\r\nUser-Agent: gi\r\n",
                     rq->method, u->prefix, rq->path, u->hostport);
    gi_buf_put(&h, line, (size_t)n);
    if (rq->idempotency_key) {
        n = snprintf(line, sizeof line, "Idempotency-Key: %s\r\n", rq->idempotency_key);
        gi_buf_put(&h, line, (size_t)n);
    }
    if (rq->token) {
        gi_buf_put(&h, "Authorization: Bearer ", 22);
        gi_buf_put(&h, rq->token, strlen(rq->token));
        gi_buf_put(&h, "\r\n", 2);
    }
    if (rq->body || strcmp(rq->method, "POST") == 0 || strcmp(rq->method, "PUT") == 0) {
        n = snprintf(line, sizeof line, "Content-Type: %s\r\nContent-Length: %zu\r\n",
                     rq->content_type ? rq->content_type : "application/octet-stream",
                     rq->body_len);
        gi_buf_put(&h, line, (size_t)n);
    }
    gi_buf_put(&h, "\r\n", 2);
    int rc = gi_write_all(fd, h.data, h.len, err);
    if (h.data)
        memset(h.data, 0, h.len); /* it held the token */
    gi_buf_free(&h);
    if (rc == 0 && rq->body_len)
        rc = gi_write_all(fd, rq->body, rq->body_len, err);
    return rc ? gi_error_prefix(err, "sending the request") : 0;
}

/* Streams `left` body bytes (or up to the end when left < 0) into fd_out. */
static int body_to_fd(int fd, int out, const gi_buf *already, int64_t left, double timeout_s,
                      const char *path, gi_error *err)
{
    /* Bytes past the body that came with the head are not the file's. */
    size_t have = left >= 0 && (uint64_t)left < already->len ? (size_t)left : already->len;
    if (have && gi_write_all(out, already->data, have, err))
        return gi_error_prefix(err, "%s", path);
    if (left >= 0)
        left -= (int64_t)have;
    uint8_t buf[65536];
    while (left != 0) {
        size_t want = left > 0 && (uint64_t)left < sizeof buf ? (size_t)left : sizeof buf;
        ssize_t r = read_some(fd, buf, want, timeout_s, err);
        if (r < 0)
            return -1;
        if (r == 0) {
            if (left > 0)
                return gi_fail(err, GI_EIO, "the connection closed %lld bytes before the end of %s",
                               (long long)left, path);
            break;
        }
        if (gi_write_all(out, buf, (size_t)r, err))
            return gi_error_prefix(err, "%s", path);
        if (left > 0)
            left -= r;
    }
    return 0;
}

/* Streams a chunked body into fd_out: the bytes in `pend` first, then the
 * connection's, to the last chunk (trailers are not read). */
static int chunked_to_fd(int fd, int out, gi_buf *pend, double timeout_s, const char *path,
                         gi_error *err)
{
    enum { SIZE, DATA, DATA_END } state = SIZE;
    uint64_t left = 0; /* of the chunk's data */
    for (;;) {
        size_t off = 0;
        for (;;) {
            const char *p = (const char *)pend->data + off;
            const char *end = (const char *)pend->data + pend->len;
            if (state == SIZE) {
                const char *eol = find_crlf(p, end);
                if (!eol) {
                    if (end - p > 4096)
                        return gi_fail(err, GI_EPROTO, "%s: malformed chunk size", path);
                    break;
                }
                if (chunk_size(p, eol, &left, err))
                    return gi_error_prefix(err, "%s", path);
                if (left == 0)
                    return 0;
                off += (size_t)(eol + 2 - p);
                state = DATA;
            } else if (state == DATA) {
                size_t k = (size_t)(end - p) < left ? (size_t)(end - p) : (size_t)left;
                if (k == 0)
                    break;
                if (gi_write_all(out, p, k, err))
                    return gi_error_prefix(err, "%s", path);
                off += k;
                left -= k;
                if (left == 0)
                    state = DATA_END;
            } else {
                if (end - p < 2)
                    break;
                if (p[0] != '\r' || p[1] != '\n')
                    return gi_fail(err, GI_EPROTO, "%s: malformed chunk", path);
                off += 2;
                state = SIZE;
            }
        }
        memmove(pend->data, pend->data + off, pend->len - off);
        pend->len -= off;
        gi_buf_reserve(pend, 65536);
        ssize_t r = read_some(fd, pend->data + pend->len, pend->cap - pend->len, timeout_s, err);
        if (r < 0)
            return -1;
        if (r == 0)
            return gi_fail(err, GI_EIO, "the connection closed before the end of %s", path);
        pend->len += (size_t)r;
    }
}

int gi_http_do(const gi_http_url *u, const gi_http_request *rq, gi_buf *body, uint64_t max_body,
               const char *to_file, gi_error *err)
{
    double timeout = rq->timeout_s > 0 ? rq->timeout_s : 60.0;
    int fd = gi_net_connect(u->hostport, timeout, err);
    if (fd < 0)
        return GI_HTTP_UNSENT;
    int status = GI_HTTP_FAILED;
    gi_buf in;
    gi_buf_init(&in);
    gi_buf_reset(body);
    if (send_request(fd, u, rq, err)) {
        status = GI_HTTP_UNSENT;
        goto out;
    }
    gi_http_head head;
    size_t head_len = 0;
    for (;;) {
        gi_buf_reserve(&in, 16384);
        ssize_t r = read_some(fd, in.data + in.len, in.cap - in.len, timeout, err);
        if (r < 0)
            goto out;
        if (r == 0) {
            gi_fail(err, GI_EIO, "the farm closed the connection before answering");
            goto out;
        }
        in.len += (size_t)r;
        int got = gi_http_parse_head((const char *)in.data, in.len, &head, &head_len, err);
        if (got < 0)
            goto out;
        if (got)
            break;
    }
    memmove(in.data, in.data + head_len, in.len - head_len);
    in.len -= head_len;
    if (to_file && head.status / 100 == 2) {
        char *tmp = gi_temp_path(to_file);
        int out = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        int rc = out < 0      ? gi_fail(err, GI_EIO, "%s: %s", tmp, strerror(errno))
                 : head.chunked ? chunked_to_fd(fd, out, &in, timeout, to_file, err)
                              : body_to_fd(fd, out, &in, head.content_length, timeout, to_file, err);
        if (out >= 0 && close(out) != 0 && rc == 0)
            rc = gi_fail(err, GI_EIO, "%s: close: %s", tmp, strerror(errno));
        if (rc == 0)
            rc = gi_commit_file(tmp, to_file, err);
        else
            unlink(tmp);
        free(tmp);
        if (rc == 0)
            status = head.status;
        goto out;
    }
    /* Into memory, bounded. */
    uint64_t limit = max_body;
    if (!head.chunked && head.content_length > (int64_t)limit) {
        gi_fail(err, GI_EPROTO, "response body of %lld bytes is over the limit of %llu",
                (long long)head.content_length, (unsigned long long)limit);
        goto out;
    }
    for (;;) {
        if (!head.chunked && head.content_length >= 0 && (int64_t)in.len >= head.content_length)
            break;
        if (in.len > limit + (head.chunked ? 65536u : 0u)) {
            gi_fail(err, GI_EPROTO, "response body is over the limit of %llu bytes",
                    (unsigned long long)limit);
            goto out;
        }
        gi_buf_reserve(&in, 65536);
        ssize_t r = read_some(fd, in.data + in.len, in.cap - in.len, timeout, err);
        if (r < 0)
            goto out;
        if (r == 0)
            break;
        in.len += (size_t)r;
    }
    if (head.chunked && gi_http_dechunk(&in, err))
        goto out;
    if (!head.chunked && head.content_length >= 0) {
        if ((int64_t)in.len < head.content_length) {
            gi_fail(err, GI_EIO, "response body cut short");
            goto out;
        }
        in.len = (size_t)head.content_length;
    }
    gi_buf_move(body, &in);
    status = head.status;
out:
    close(fd);
    gi_buf_free(&in);
    return status;
}
