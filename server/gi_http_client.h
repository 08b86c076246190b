/* gi_http_client: the small HTTP/1.1 client `gi` uses to talk to a farm's
 * API. None of the project's dependencies is an HTTP client (libmicrohttpd
 * only serves), and the API needs little: one request per connection
 * ("Connection: close"), a body from memory, a response into memory or a
 * file, Content-Length or chunked bodies, limits and timeouts everywhere.
 * Plain http:// only; put a TLS-terminating proxy in front of gi-farmd for
 * traffic that leaves a trusted network (docs/farm.md, "Security"). */
#ifndef GI_HTTP_CLIENT_H
#define GI_HTTP_CLIENT_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"

#define GI_HTTP_MAX_HEAD 65536

typedef struct gi_http_url {
    char *hostport; /* "host:port" for connecting and the Host header */
    char *prefix;   /* path prefix without a trailing slash ("" for none) */
} gi_http_url;

/* "http://HOST[:PORT][/PREFIX]" (port 80 by default). */
int gi_http_url_parse(const char *url, gi_http_url *out, gi_error *err);
void gi_http_url_free(gi_http_url *u);

/* A parsed response head. */
typedef struct gi_http_head {
    int status;
    int chunked;
    int64_t content_length; /* -1 when absent */
} gi_http_head;

/* Parses the status line and headers in data[0..len). Returns 1 with
 * *head_len = bytes of the head (through the blank line), 0 if the head is
 * not complete yet, -1 if it is malformed or longer than GI_HTTP_MAX_HEAD. */
int gi_http_parse_head(const char *data, size_t len, gi_http_head *out, size_t *head_len,
                       gi_error *err);
/* Decodes a complete chunked body in place (in->len shrinks to the data).
 * -1 if it is malformed or truncated. */
int gi_http_dechunk(gi_buf *in, gi_error *err);

typedef struct gi_http_request {
    const char *method, *path; /* path below the URL's prefix, e.g. "/api/v1/jobs" */
    const char *token;         /* bearer token, or NULL */
    const void *body;
    size_t body_len;
    const char *content_type;
    double timeout_s;          /* for connecting and between reads */
    /* Sent as "Idempotency-Key" when not NULL: gi-farmd answers a job
     * submission repeated with the same key with the job it made the first
     * time, so that a POST whose answer was lost can be sent again. */
    const char *idempotency_key;
} gi_http_request;

/* gi_http_do's transport failures: after the whole request was sent (the
 * server may have acted on it), and before (no connection, or it broke
 * while sending: a server acts on a whole request only). */
#define GI_HTTP_FAILED -1
#define GI_HTTP_UNSENT -2

/* Sends the request and reads the response. With to_file NULL the body goes
 * into *body (at most max_body bytes); otherwise, for a 2xx status, into
 * to_file (temporary name + rename), and the body of any other status into
 * *body. Returns the HTTP status, or GI_HTTP_FAILED / GI_HTTP_UNSENT with
 * err on a transport failure. */
int gi_http_do(const gi_http_url *u, const gi_http_request *rq, gi_buf *body, uint64_t max_body,
               const char *to_file, gi_error *err);

#endif
