/* gi_farm_api: the HTTP/JSON API (docs/farm.md, "API") on libmicrohttpd.
 *
 * Threading: MHD runs without threads of its own (MHD_USE_EPOLL, no internal
 * polling thread). Its epoll descriptor is one more entry in the
 * coordinator's poll set and MHD_run is called from the loop, so handlers
 * run on the loop's thread and read and change the coordinator's state
 * directly. Handlers never block: request bodies arrive in pieces (assets
 * stream to a temporary file while being hashed), outputs are sent from
 * their file descriptor by MHD.
 *
 * Every endpoint but the static dashboard page needs
 * "Authorization: Bearer <token>"; the comparison hashes both sides and
 * compares the digests in constant time. Refusals (no token, wrong token,
 * bodies over their limit, invalid jobs) are logged with the peer and the
 * reason, never with the token; those of a missing or wrong token, which
 * anyone can send, once per peer and 10 s (gi_refusal_log), as are the
 * connections closed for their pace (a request's head or whole request not
 * in time, gi_api_conn) and MHD's own messages. */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/tcp.h> /* struct tcp_info with its byte counts (glibc's has none) */
#include <math.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_clock.h"
#include "gi_farm_impl.h"
#include "gi_farm_route.h"
#include "gi_farm_submit.h"
#include "gi_fs.h"
#include "gi_log.h"
#include "gi_net.h"

typedef struct api_req {
    gi_route rt;
    int responded;     /* a response is queued: ignore the rest of the body */
    int status;        /* for a body-phase failure */
    char err[1100];
    char peer[80];
    gi_buf body;
    gi_farm_upload *up;
    int fetching; /* an output's bytes are being sent (GET): its job's fetch once sent whole */
    uint64_t received, limit;
} api_req;

/* A request target for logs: printable ASCII only, cut short. */
static void log_safe(const char *in, char *out, size_t n)
{
    size_t k = 0;
    for (; *in && k + 5 < n; in++)
        if (isprint((unsigned char)*in))
            out[k++] = *in;
        else
            k += (size_t)snprintf(out + k, n - k, "\\x%02x", (unsigned char)*in);
    out[k] = '\0';
}

/* A TCP connection of the API. A client gets --api-head-seconds to send a
 * request's head, from its connection or from the end of its last request;
 * then it is shut down. MHD's own timeout counts idle time only, so a
 * client trickling a header line every few seconds would hold its
 * connection (and, 64 of them, every other client from its address) for
 * ever.
 *
 * Once the head is in, the request (its body in, its answer out) keeps a
 * pace, as a credit of time: it starts with --api-request-seconds (S), is
 * spent a second a second and earns a second for every --api-min-rate (B)
 * bytes moved, but never holds more than S; once it is spent, the request
 * is shut down. So every stretch of T seconds of a request must move
 * (T - S) x B bytes: one moving B bytes a second or more is never cut,
 * however long it takes; one that stops (an upload no longer sent, an
 * answer no longer read) is cut S seconds after it stopped, however much
 * it moved before; one slower than B once it is S seconds' worth of bytes
 * behind since it last kept up. Averaged since the head instead, a request
 * that moved 100 MiB fast would have had 6400 s in hand, to stall in (until
 * MHD's 60 s without a byte) or trickle a byte every 50 s in.
 *
 * Bytes moved are the kernel's count of bytes received and of bytes the
 * client acknowledged (TCP_INFO), so that an answer counts as the client
 * takes it, not as MHD hands it to the socket; a body MHD reads only to
 * discard it counts as well. An answer MHD has handed whole to the kernel
 * (one smaller than the socket's send buffer) ends the request, read or
 * not: its connection then waits for a head (--api-head-seconds).
 * Without a pace, a token holder sending a submission a byte a second
 * (never idle for MHD) holds its slot for ever, and 64 of them every other
 * client of its address.
 *
 * No request waits on the server by design: every answer is queued as soon
 * as its head, or its body, is in (no long poll: `gi wait` asks again).
 * The coordinator's loop can be away, though (a merge, a checkpoint
 * written): while it is, MHD neither reads nor writes, so the time between
 * two turns of the API past API_AWAY_S is not spent (api_away).
 *
 * A kernel whose TCP_INFO has no byte counts (they came with Linux 4.1)
 * keeps no pace: a request is then closed only after MHD's 60 s without a
 * byte, and never shed for its pace (heads are still timed: that needs no
 * counts). gi-farmd says so once, when the first request comes. */
typedef struct gi_api_conn {
    int fd;
    struct sockaddr_storage addr; /* the client's; port ignored */
    char peer[80];
    double since;   /* when it began to wait for a request's head */
    int in_request; /* a head has come, the answer has not gone */
    int cut;        /* shut down already */
    char what[120]; /* the request under way, for logs: "POST /api/v1/jobs" */
    double head_at; /* when its head came */
    uint64_t moved_at_head; /* bytes moved (received + acknowledged) by then */
    /* The request's credit as of looked_at and moved_at_look, the bytes
     * moved then; INFINITY: no pace kept. */
    double credit, looked_at;
    uint64_t moved_at_look;
    double full_at; /* its credit was last whole (for logs: since when it is behind) */
    uint64_t moved_at_full;
    double deadline; /* looked_at + credit: when it is spent if no byte moves */
    double peer_checked_at; /* when wake_if_peer_closed last looked */
    struct gi_api_conn *prev, *next;
} gi_api_conn;

/* API connections in all and from one address (keep_a_slot_free). */
#define API_CONNS_MAX 256u
#define API_CONNS_PER_ADDRESS 64u
/* MHD's limits are higher by this much, for connections cut but not closed yet. */
#define API_CONNS_CUT_ROOM 64u
/* A connection's first second idle, or a request's first second: the time a
 * client needs to get going (its head read, its body flowing), during which
 * keep_a_slot_free spares it if it can. */
#define API_SETTLE_S 1.0
/* A request's credit is brought up to date this often at least, so that
 * bytes moved and then a stall are told apart to this much. */
#define API_LOOK_S 0.25
/* The loop turns every 50 ms (gi_farm.c); two turns of the API further apart
 * than this, the loop was away: the time over it is not spent. */
#define API_AWAY_S 1.0

static gi_api_conn *api_conn_of(struct MHD_Connection *conn)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci ? ci->socket_context : NULL;
}

static void cut(gi_api_conn *c, uint64_t *counter)
{
    shutdown(c->fd, SHUT_RDWR);
    c->cut = 1;
    (*counter)++;
}

static void remember_address(gi_api_conn *c, const struct sockaddr *sa)
{
    if (sa->sa_family == AF_INET)
        memcpy(&c->addr, sa, sizeof(struct sockaddr_in));
    else if (sa->sa_family == AF_INET6)
        memcpy(&c->addr, sa, sizeof(struct sockaddr_in6));
}

/* The same client host (the port aside), as MHD's limit per address counts. */
static int same_host(const struct sockaddr_storage *a, const struct sockaddr_storage *b)
{
    if (a->ss_family != b->ss_family)
        return 0;
    if (a->ss_family == AF_INET)
        return memcmp(&((const struct sockaddr_in *)a)->sin_addr,
                      &((const struct sockaddr_in *)b)->sin_addr, sizeof(struct in_addr)) == 0;
    if (a->ss_family == AF_INET6)
        return memcmp(&((const struct sockaddr_in6 *)a)->sin6_addr,
                      &((const struct sockaddr_in6 *)b)->sin6_addr,
                      sizeof(struct in6_addr)) == 0;
    return 1;
}

/* Bytes the connection has received and had acknowledged, from the
 * kernel: 0; -1 when it cannot say (then no pace is kept), with *no_counts
 * set if that is for want of the counts in TCP_INFO. */
static int bytes_moved(int fd, uint64_t *out, int *no_counts)
{
    struct tcp_info ti;
    socklen_t n = sizeof ti;
    memset(&ti, 0, sizeof ti);
    *no_counts = 0;
    if (fd < 0 || getsockopt(fd, IPPROTO_TCP, TCP_INFO, &ti, &n) != 0)
        return -1;
    if (n < offsetof(struct tcp_info, tcpi_bytes_received) + sizeof ti.tcpi_bytes_received) {
        *no_counts = 1;
        return -1;
    }
    *out = ti.tcpi_bytes_acked + ti.tcpi_bytes_received;
    return 0;
}

static void request_began(gi_farm *f, gi_api_conn *c, const char *method, const char *url)
{
    char u[100];
    log_safe(url, u, sizeof u);
    snprintf(c->what, sizeof c->what, "%.10s %s", method, u);
    c->in_request = 1;
    c->head_at = c->looked_at = c->full_at = gi_now();
    c->credit = f->cfg.api_request_s;
    int no_counts = 0;
    if (f->cfg.api_min_rate == 0 || bytes_moved(c->fd, &c->moved_at_head, &no_counts)) {
        c->credit = INFINITY;
        if (f->cfg.api_min_rate && no_counts && !f->api_pace_unknown)
            gi_warn("api: this kernel's TCP_INFO has no byte counts (Linux 4.1 has them): "
                    "--api-request-seconds and --api-min-rate are not kept; a request is "
                    "closed after 60 s without a byte only");
        f->api_pace_unknown |= no_counts;
    }
    c->moved_at_look = c->moved_at_full = c->moved_at_head;
    c->deadline = c->looked_at + c->credit;
}

/* Brings the request's credit up to now: spent for the time since it was
 * last looked at, earned for the bytes moved meanwhile, S at most (the
 * comment above gi_api_conn). Returns 1 if it is spent. */
static int pace_look(const gi_farm *f, gi_api_conn *c, double now)
{
    uint64_t total;
    int no_counts;
    if (c->credit == INFINITY || bytes_moved(c->fd, &total, &no_counts))
        return 0;
    c->credit += (double)(total - c->moved_at_look) / (double)f->cfg.api_min_rate -
                 (now - c->looked_at);
    c->looked_at = now;
    c->moved_at_look = total;
    if (c->credit >= f->cfg.api_request_s) {
        c->credit = f->cfg.api_request_s;
        c->full_at = now;
        c->moved_at_full = total;
    }
    c->deadline = now + c->credit;
    return c->credit < 0;
}

/* How far behind --api-min-rate a request under way is, in seconds of its
 * credit spent: 0 if less than API_SETTLE_S, so that one just begun, or
 * one keeping the pace with a hiccup, is spared. */
static double request_behind(const gi_farm *f, gi_api_conn *c, double now)
{
    if (c->credit == INFINITY)
        return 0;
    pace_look(f, c, now);
    double spent = f->cfg.api_request_s - c->credit;
    return spent >= API_SETTLE_S ? spent : 0;
}

/* The loop was away from the API (api_ran_at): the time over API_AWAY_S
 * is given back to the requests under way, which could not move. */
static void api_away(gi_farm *f, double now)
{
    double away = f->api_ran_at > 0 ? now - f->api_ran_at - API_AWAY_S : 0;
    if (away <= 0)
        return;
    for (gi_api_conn *c = f->api_conns; c; c = c->next)
        if (c->in_request && c->credit != INFINITY) {
            c->looked_at += away;
            c->deadline += away;
        }
}

/* A connection shut down for its pace: a line per peer and
 * --refusal-log-window, as anyone can open connections. */
static void log_slow(gi_farm *f, gi_api_conn *c, double now, const char *why)
{
    gi_refusal_logf(&f->refusals, now, c->peer, "api: closed the connection of %s: %s", c->peer,
                    why);
}

/* The longest idle connection if it was idle for API_SETTLE_S, else the
 * request furthest behind, else the idle one all the same (one just opened,
 * its head not read yet: a client's next request; or a flood of idle
 * connections), else the new one if it is over the limit. */
static gi_api_conn *shed_first(gi_api_conn *idle, gi_api_conn *behind, double now, int over,
                               gi_api_conn *fresh)
{
    if (idle && now - idle->since >= API_SETTLE_S)
        return idle;
    return behind ? behind : idle ? idle : over ? fresh : NULL;
}

/* When the new connection fills its address's slots or all of them, the
 * connection waiting longest for a request head (idle: nothing sent yet, or
 * between two requests) gives its slot up, so that the next client gets in;
 * with none idle (for a second: shed_first), the request furthest behind
 * --api-min-rate (request_behind); with none of those either, the new one
 * over the limit is closed. Otherwise a client opening idle connections
 * again as each was cut after --api-head-seconds, or trickling requests'
 * bodies, would hold every slot of its address (on loopback: every local
 * client's) or, from a few addresses, all of them. MHD's own limits are
 * higher: the connections cut here are only closed when MHD next runs.
 *
 * Four addresses or more can fill the 256 slots (64 each) with no limit
 * per address reached; the next connection, from any address, then sheds
 * one of theirs as above. So a slot is held past its first second only by
 * a request keeping --api-min-rate, which costs its client that bandwidth
 * (256 x 16 KiB/s), not by one waiting for its deadline: a request that
 * moved fast and then stopped is behind a second after it stopped (its
 * credit holds --api-request-seconds at most), not only once its deadline
 * averaged over the bytes it moved (as it was) came. What this does not
 * stop is a flood (more than 256 connections a second, each shed within
 * its first second): a matter for a firewall's limit on new connections. */
static void keep_a_slot_free(gi_farm *f, gi_api_conn *fresh)
{
    unsigned all = 0, here = 0;
    gi_api_conn *oldest = NULL, *oldest_here = NULL, *slowest = NULL, *slowest_here = NULL;
    double behind_most = 0, behind_most_here = 0, now = gi_now();
    for (gi_api_conn *c = f->api_conns; c; c = c->next) {
        if (c->cut)
            continue;
        int mine = same_host(&c->addr, &fresh->addr);
        all++;
        here += mine;
        if (c == fresh || c->fd < 0)
            continue;
        if (c->in_request) {
            double b = request_behind(f, c, now);
            if (b > behind_most)
                behind_most = b, slowest = c;
            if (mine && b > behind_most_here)
                behind_most_here = b, slowest_here = c;
            continue;
        }
        if (!oldest || c->since < oldest->since)
            oldest = c;
        if (mine && (!oldest_here || c->since < oldest_here->since))
            oldest_here = c;
    }
    gi_api_conn *shed = NULL;
    if (here >= API_CONNS_PER_ADDRESS)
        shed = shed_first(oldest_here, slowest_here, now, here > API_CONNS_PER_ADDRESS, fresh);
    else if (all >= API_CONNS_MAX)
        shed = shed_first(oldest, slowest, now, all > API_CONNS_MAX, fresh);
    if (!shed || shed->fd < 0)
        return;
    if (shed->in_request) {
        char why[300];
        snprintf(why, sizeof why,
                 "its request (%s) is behind --api-min-rate (%llu bytes/s) and its slot was "
                 "needed",
                 shed->what, (unsigned long long)f->cfg.api_min_rate);
        log_slow(f, shed, now, why);
    }
    cut(shed, &f->m.api_conns_shed);
}

static void on_connection(void *cls, struct MHD_Connection *conn, void **socket_context,
                          enum MHD_ConnectionNotificationCode toe)
{
    gi_farm *f = cls;
    gi_api_conn *c = *socket_context;
    if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
        c = gi_xcalloc(1, sizeof *c);
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
        c->fd = ci ? ci->connect_fd : -1;
        ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
        if (ci && ci->client_addr) {
            remember_address(c, ci->client_addr);
            gi_net_sockaddr_name(ci->client_addr, c->peer, sizeof c->peer);
        } else {
            snprintf(c->peer, sizeof c->peer, "?");
        }
        c->since = gi_now();
        c->next = f->api_conns;
        if (c->next)
            c->next->prev = c;
        f->api_conns = c;
        *socket_context = c;
        keep_a_slot_free(f, c);
    } else if (c) {
        if (c->prev)
            c->prev->next = c->next;
        else
            f->api_conns = c->next;
        if (c->next)
            c->next->prev = c->prev;
        free(c);
        *socket_context = NULL;
    }
}

/* The kernel's TCP state "close wait" (include/net/tcp_states.h: not in
 * the headers a program includes): the client sent its FIN. */
#define API_TCP_CLOSE_WAIT 8

/* MHD reads its sockets edge-triggered and, when a read returns less than
 * it asked for, takes the socket for drained without reading again. A
 * client's FIN that came with its last bytes (a request head sent and the
 * client gone at once: killed, or a script that closes after writing) is
 * then never read: the connection sat in close-wait holding its slot until
 * its deadline. Every API_LOOK_S, a connection whose client closed is shut
 * for reading (again: a wake before MHD's last read is spent), which wakes
 * MHD up on it: it reads the end and closes the connection, or, if the
 * request is complete, sends its answer first as it would have. */
static void wake_if_peer_closed(gi_api_conn *c, double now)
{
    if (now - c->peer_checked_at < API_LOOK_S)
        return;
    c->peer_checked_at = now;
    struct tcp_info ti;
    socklen_t n = sizeof ti;
    memset(&ti, 0, sizeof ti);
    if (getsockopt(c->fd, IPPROTO_TCP, TCP_INFO, &ti, &n) == 0 &&
        ti.tcpi_state == API_TCP_CLOSE_WAIT)
        shutdown(c->fd, SHUT_RD);
}

/* Shuts down the connections past their time for a request head, or
 * their request's deadline (MHD closes them when it next runs), and wakes
 * MHD up on those whose client left (wake_if_peer_closed). */
static void cut_slow_connections(gi_farm *f)
{
    double now = gi_now();
    for (gi_api_conn *c = f->api_conns; c; c = c->next) {
        if (c->cut || c->fd < 0)
            continue;
        wake_if_peer_closed(c, now);
        char why[400];
        if (!c->in_request && now - c->since > f->cfg.api_head_s) {
            snprintf(why, sizeof why, "no request head within --api-head-seconds (%g s)",
                     f->cfg.api_head_s);
            log_slow(f, c, now, why);
            cut(c, &f->m.api_slow_closed);
        } else if (c->in_request && (now > c->deadline || now - c->looked_at >= API_LOOK_S) &&
                   pace_look(f, c, now)) {
            snprintf(why, sizeof why,
                     "its request (%s) fell --api-request-seconds (%g s) behind --api-min-rate "
                     "(%llu bytes/s): %llu bytes moved in the last %.1f s, %llu in %.1f s in all",
                     c->what, f->cfg.api_request_s, (unsigned long long)f->cfg.api_min_rate,
                     (unsigned long long)(c->moved_at_look - c->moved_at_full), now - c->full_at,
                     (unsigned long long)(c->moved_at_look - c->moved_at_head), now - c->head_at);
            log_slow(f, c, now, why);
            cut(c, &f->m.api_slow_requests);
        }
    }
}

/* ---- helpers ------------------------------------------------------------- */

/* body is malloc'ed (freed by MHD) unless persistent. */
static enum MHD_Result send_body_allow(struct MHD_Connection *conn, unsigned status, char *body,
                                       size_t len, const char *type, int persistent,
                                       const char *allow)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(
        len, body, persistent ? MHD_RESPMEM_PERSISTENT : MHD_RESPMEM_MUST_FREE);
    if (!r) {
        if (!persistent)
            free(body);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", type);
    MHD_add_response_header(r, "Cache-Control", "no-store");
    if (status == MHD_HTTP_UNAUTHORIZED)
        MHD_add_response_header(r, "WWW-Authenticate", "Bearer realm=\"gi-farm\"");
    if (allow)
        MHD_add_response_header(r, "Allow", allow);
    enum MHD_Result rc = MHD_queue_response(conn, status, r);
    MHD_destroy_response(r);
    return rc;
}

static enum MHD_Result send_body(struct MHD_Connection *conn, unsigned status, char *body,
                                 size_t len, const char *type, int persistent)
{
    return send_body_allow(conn, status, body, len, type, persistent, NULL);
}

static enum MHD_Result send_response(struct MHD_Connection *conn, unsigned status, char *body,
                                     size_t len, const char *type)
{
    return send_body(conn, status, body, len, type, body == NULL);
}

static enum MHD_Result send_json_allow(struct MHD_Connection *conn, unsigned status, char *json,
                                       const char *allow)
{
    size_t n = strlen(json);
    /* Newline-terminated: nicer with curl. */
    json = gi_xrealloc(json, n + 2);
    json[n] = '\n';
    json[n + 1] = '\0';
    return send_body_allow(conn, status, json, n + 1, "application/json", 0, allow);
}

static enum MHD_Result send_json(struct MHD_Connection *conn, unsigned status, char *json)
{
    return send_json_allow(conn, status, json, NULL);
}

static char *json_error(const char *msg)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "error", msg);
    char *s = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    return s;
}

/* Answers an error, logging it as a refusal for 4xx statuses. */
static enum MHD_Result refuse(gi_farm *f, struct MHD_Connection *conn, api_req *r,
                              const char *method, const char *url, unsigned status,
                              const char *fmt, ...) __attribute__((format(printf, 7, 8)));

static enum MHD_Result refuse(gi_farm *f, struct MHD_Connection *conn, api_req *r,
                              const char *method, const char *url, unsigned status,
                              const char *fmt, ...)
{
    char msg[1200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    char u[300];
    log_safe(url, u, sizeof u);
    if (status == MHD_HTTP_UNAUTHORIZED)
        f->m.api_refused_auth++;
    else if (status >= 400 && status < 500 && status != MHD_HTTP_NOT_FOUND)
        f->m.api_refused_input++;
    if (status == MHD_HTTP_UNAUTHORIZED) /* anyone can send these: a line per peer and 10 s */
        gi_refusal_logf(&f->refusals, gi_now(), r->peer, "api: refused %s %s from %s: %s",
                        method, u, r->peer, msg);
    else if (status != MHD_HTTP_NOT_FOUND)
        gi_warn("api: refused %s %s from %s: %s", method, u, r->peer, msg);
    r->responded = 1;
    return send_json_allow(conn, status, json_error(msg),
                           status == MHD_HTTP_METHOD_NOT_ALLOWED ? r->rt.allow : NULL);
}

static int authorized(gi_farm *f, struct MHD_Connection *conn, const char **why)
{
    const char *h = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION);
    if (!h) {
        *why = "missing bearer token (send \"Authorization: Bearer <token>\")";
        return 0;
    }
    if (strncasecmp(h, "Bearer ", 7) != 0) {
        *why = "the Authorization header is not a bearer token";
        return 0;
    }
    const char *t = h + 7;
    while (*t == ' ')
        t++;
    if (!gi_token_equal(&f->cfg.token, t, strlen(t))) {
        *why = "wrong bearer token";
        return 0;
    }
    return 1;
}

/* ---- endpoints ------------------------------------------------------------- */

static enum MHD_Result do_submit(gi_farm *f, struct MHD_Connection *conn, api_req *r,
                                 const char *method, const char *url)
{
    gi_farm_submission s;
    gi_error err;
    if (gi_farm_submission_parse((const char *)r->body.data, r->body.len, &s, &err))
        return refuse(f, conn, r, method, url, MHD_HTTP_BAD_REQUEST, "%s", err.msg);
    /* A submission repeated with its Idempotency-Key (its client lost the
     * first answer: a connection reset under load, a gi-farmd restart) gets
     * the job the first one made, instead of a second one. The key is
     * journaled with the job (SUBMIT) and lives as long as it. */
    const char *key = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Idempotency-Key");
    int status = MHD_HTTP_CREATED;
    gi_farm_job *j = NULL;
    if (key && !gi_submit_key_valid(key)) {
        gi_farm_submission_free(&s);
        return refuse(f, conn, r, method, url, MHD_HTTP_BAD_REQUEST,
                      "Idempotency-Key: 16 to 64 characters of A-Z, a-z, 0-9, '-' and '_'");
    }
    if (key && (j = gi_farm_job_by_key(f, key)) != NULL) {
        int same = strcmp(j->text, s.text) == 0 && strcmp(j->file, s.file) == 0 &&
                   j->priority == s.priority;
        gi_farm_submission_free(&s);
        if (!same)
            return refuse(f, conn, r, method, url, MHD_HTTP_CONFLICT,
                          "Idempotency-Key %s was given to job %llu, another submission", key,
                          (unsigned long long)j->id);
        gi_info("job %llu: its submission came again with its Idempotency-Key (from %s): "
                "answered with the job, not submitted twice", (unsigned long long)j->id, r->peer);
        status = MHD_HTTP_OK;
    } else {
        j = gi_farm_job_submit(f, s.file, s.text, &s.manifest, s.priority, key, &err);
    }
    if (!j) {
        gi_farm_submission_free(&s);
        return refuse(f, conn, r, method, url,
                      err.code == GI_EINVAL   ? MHD_HTTP_BAD_REQUEST
                      : err.code == GI_ENOMEM ? MHD_HTTP_SERVICE_UNAVAILABLE
                                              : MHD_HTTP_INTERNAL_SERVER_ERROR,
                      "%s", err.msg);
    }
    if (status == MHD_HTTP_CREATED) {
        s.text = NULL; /* the job owns it */
        gi_farm_submission_free(&s);
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", (double)j->id);
    cJSON_AddStringToObject(o, "state", gi_farm_job_state_name(j));
    char *json = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    return send_json(conn, (unsigned)status, json);
}

static const char *content_type(const char *name)
{
    const char *dot = strrchr(name, '.');
    if (dot && strcmp(dot, ".png") == 0)
        return "image/png";
    if (dot && strcmp(dot, ".exr") == 0)
        return "image/x-exr";
    if (dot && strcmp(dot, ".json") == 0)
        return "application/json";
    return "application/octet-stream";
}

static enum MHD_Result do_output(gi_farm *f, struct MHD_Connection *conn, api_req *r,
                                 gi_farm_job *j, const char *method, const char *url)
{
    if (j->state != GI_FJ_DONE)
        return refuse(f, conn, r, method, url, MHD_HTTP_CONFLICT, "job %llu is %s, not done",
                      (unsigned long long)j->id, gi_farm_job_state_name(j));
    char *path = gi_farm_job_output_path(j, r->rt.name);
    if (!path)
        return refuse(f, conn, r, method, url, MHD_HTTP_NOT_FOUND, "job %llu has no output \"%s\"",
                      (unsigned long long)j->id, r->rt.name);
    struct stat st;
    int fd = gi_open_regular(path, O_RDONLY, &st, NULL);
    free(path);
    if (fd < 0) {
        return refuse(f, conn, r, method, url, MHD_HTTP_NOT_FOUND,
                      "output \"%s\" of job %llu was not written", r->rt.name,
                      (unsigned long long)j->id);
    }
    struct MHD_Response *resp = MHD_create_response_from_fd64((uint64_t)st.st_size, fd);
    if (!resp) {
        close(fd);
        return MHD_NO;
    }
    MHD_add_response_header(resp, "Content-Type", content_type(r->rt.name));
    char disp[300];
    snprintf(disp, sizeof disp, "attachment; filename=\"%s\"", r->rt.name);
    MHD_add_response_header(resp, "Content-Disposition", disp);
    enum MHD_Result rc = MHD_queue_response(conn, MHD_HTTP_OK, resp);
    MHD_destroy_response(resp);
    r->fetching = rc == MHD_YES && strcmp(method, "GET") == 0;
    return rc;
}

static enum MHD_Result dispatch(gi_farm *f, struct MHD_Connection *conn, api_req *r,
                                const char *method, const char *url)
{
    gi_farm_job *j = NULL;
    gi_route_id route = r->rt.id;
    if (route == GI_ROUTE_JOB_GET || route == GI_ROUTE_JOB_DELETE ||
        route == GI_ROUTE_JOB_RETRY || route == GI_ROUTE_JOB_OUTPUT) {
        j = gi_farm_job_find(f, r->rt.job_id);
        if (!j)
            return refuse(f, conn, r, method, url, MHD_HTTP_NOT_FOUND, "no job %llu",
                          (unsigned long long)r->rt.job_id);
    }
    gi_error err;
    switch (r->rt.id) {
    case GI_ROUTE_DASHBOARD:
        return send_body(conn, MHD_HTTP_OK, (char *)gi_farm_dashboard_html,
                         strlen(gi_farm_dashboard_html), "text/html; charset=utf-8", 1);
    case GI_ROUTE_METRICS: {
        char *m = gi_farm_view_metrics(f);
        return send_response(conn, MHD_HTTP_OK, m, strlen(m), "text/plain; version=0.0.4");
    }
    case GI_ROUTE_JOBS_LIST:
        return send_json(conn, MHD_HTTP_OK, gi_farm_view_jobs(f));
    case GI_ROUTE_WORKERS:
        return send_json(conn, MHD_HTTP_OK, gi_farm_view_workers(f));
    case GI_ROUTE_JOB_GET:
        return send_json(conn, MHD_HTTP_OK, gi_farm_view_job(f, j));
    case GI_ROUTE_JOB_DELETE: {
        /* Cancelling twice (a reply lost, a script run again) must not
         * remove the job and its outputs: that takes ?purge=1. */
        const char *purge = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "purge");
        int purging = purge && strcmp(purge, "1") == 0;
        if (purge && !purging)
            return refuse(f, conn, r, method, url, MHD_HTTP_BAD_REQUEST,
                          "purge=%.40s: expected purge=1", purge);
        if (!purging && gi_farm_job_cancel(f, j, "requested through the API") == 0)
            return send_json(conn, MHD_HTTP_OK, gi_farm_view_job(f, j));
        if (!purging && j->cancelling)
            return refuse(f, conn, r, method, url, MHD_HTTP_CONFLICT,
                          "job %llu is cancelled already: it ends once its outputs being "
                          "written are", (unsigned long long)j->id);
        if (!purging)
            return refuse(f, conn, r, method, url, MHD_HTTP_CONFLICT,
                          "job %llu has ended (%s): `gi purge %llu` (DELETE "
                          "/api/v1/jobs/%llu?purge=1) removes it and its files",
                          (unsigned long long)j->id, gi_farm_job_state_name(j),
                          (unsigned long long)j->id, (unsigned long long)j->id);
        {
            uint64_t id = j->id;
            if (gi_farm_job_purge(f, j, &err))
                return refuse(f, conn, r, method, url,
                              err.code == GI_EINVAL ? MHD_HTTP_CONFLICT
                                                    : MHD_HTTP_INTERNAL_SERVER_ERROR,
                              "%s", err.msg);
            char body[64];
            snprintf(body, sizeof body, "{\"id\":%llu,\"purged\":true}", (unsigned long long)id);
            return send_json(conn, MHD_HTTP_OK, gi_xstrdup(body));
        }
    }
    case GI_ROUTE_JOB_RETRY:
        if (gi_farm_job_retry(f, j, &err))
            return refuse(f, conn, r, method, url,
                          err.code == GI_EINVAL    ? MHD_HTTP_CONFLICT
                          : err.code == GI_ENOMEM ? MHD_HTTP_SERVICE_UNAVAILABLE
                                                  : MHD_HTTP_INTERNAL_SERVER_ERROR,
                          "%s", err.msg);
        return send_json(conn, MHD_HTTP_OK, gi_farm_view_job(f, j));
    case GI_ROUTE_JOB_OUTPUT:
        return do_output(f, conn, r, j, method, url);
    case GI_ROUTE_ASSET_HEAD: {
        uint64_t size;
        int have = gi_farm_store_has(f, r->rt.name, &size);
        if (have) /* the client will not upload it: its job is coming */
            gi_farm_store_touch(f, r->rt.name);
        return send_response(conn, have ? MHD_HTTP_OK : MHD_HTTP_NOT_FOUND, NULL, 0,
                             "application/octet-stream");
    }
    case GI_ROUTE_ASSET_PUT: {
        gi_farm_upload *u = r->up;
        r->up = NULL;
        uint64_t bytes = r->received;
        if (gi_farm_upload_finish(f, u, &err))
            return refuse(f, conn, r, method, url,
                          err.code == GI_EINVAL ? MHD_HTTP_BAD_REQUEST : MHD_HTTP_INTERNAL_SERVER_ERROR,
                          "%s", err.msg);
        char body[400];
        snprintf(body, sizeof body, "{\"hash\":\"%s\",\"bytes\":%llu}", r->rt.name,
                 (unsigned long long)bytes);
        return send_json(conn, MHD_HTTP_CREATED, gi_xstrdup(body));
    }
    case GI_ROUTE_JOBS_SUBMIT:
        return do_submit(f, conn, r, method, url);
    case GI_ROUTE_NONE:
        break;
    }
    return refuse(f, conn, r, method, url, MHD_HTTP_NOT_FOUND, "no such endpoint");
}

/* Submission bodies are held in memory until they are complete: those
 * under way at once hold at most this much (else 256 connections of 32 MiB
 * each: 8 GiB). Four of the largest; a job is usually a few KiB. */
#define SUBMIT_BUFFERED_MAX ((uint64_t)128 << 20)

static int submissions_have_room(const gi_farm *f, uint64_t more, api_req *r)
{
    if (f->submit_buffered + more <= SUBMIT_BUFFERED_MAX)
        return 1;
    r->status = MHD_HTTP_SERVICE_UNAVAILABLE;
    snprintf(r->err, sizeof r->err,
             "submissions under way hold %llu bytes, and this one's %llu more would pass the "
             "limit of %llu: try again when they are in",
             (unsigned long long)f->submit_buffered, (unsigned long long)more,
             (unsigned long long)SUBMIT_BUFFERED_MAX);
    return 0;
}

/* The memory a submission's body held is free again. */
static void body_release(gi_farm *f, api_req *r)
{
    f->submit_buffered -= r->body.len;
    gi_buf_free(&r->body);
}

/* First call of a request: route, authenticate, prepare for its body. */
static enum MHD_Result begin(gi_farm *f, struct MHD_Connection *conn, api_req *r,
                             const char *method, const char *url)
{
    unsigned status = gi_route_find(method, url, &r->rt);
    /* Authentication first, so that without the token every path looks
     * the same (no probing for endpoints or job ids). */
    const char *why;
    if (r->rt.id != GI_ROUTE_DASHBOARD && !authorized(f, conn, &why))
        return refuse(f, conn, r, method, url, MHD_HTTP_UNAUTHORIZED, "%s", why);
    if (status == MHD_HTTP_NOT_FOUND)
        return refuse(f, conn, r, method, url, status, "no such endpoint: %s %s", method, url);
    if (status == MHD_HTTP_METHOD_NOT_ALLOWED)
        return refuse(f, conn, r, method, url, status, "%s is not allowed on %s", method, url);
    if (r->rt.id == GI_ROUTE_JOBS_SUBMIT)
        r->limit = GI_FARM_SUBMIT_MAX_BYTES;
    else if (r->rt.id == GI_ROUTE_ASSET_PUT)
        r->limit = f->cfg.max_asset_bytes;
    else
        r->limit = 0;
    const char *cl = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Content-Length");
    if (cl) {
        unsigned long long n = strtoull(cl, NULL, 10);
        if (n > 0 && r->limit == 0)
            return refuse(f, conn, r, method, url, MHD_HTTP_BAD_REQUEST,
                          "%s %s takes no request body", method, url);
        if (n > r->limit)
            return refuse(f, conn, r, method, url, MHD_HTTP_CONTENT_TOO_LARGE,
                          "request body of %llu bytes is over the limit of %llu", n,
                          (unsigned long long)r->limit);
        gi_error err;
        if (r->rt.id == GI_ROUTE_ASSET_PUT && gi_farm_store_room(f, n, &err))
            return refuse(f, conn, r, method, url, MHD_HTTP_INSUFFICIENT_STORAGE, "%s",
                          err.msg);
        if (r->rt.id == GI_ROUTE_JOBS_SUBMIT && !submissions_have_room(f, n, r))
            return refuse(f, conn, r, method, url, (unsigned)r->status, "%s", r->err);
    }
    if (r->rt.id == GI_ROUTE_ASSET_PUT) {
        gi_error err;
        r->up = gi_farm_upload_begin(f, r->rt.name, &err);
        if (!r->up)
            return refuse(f, conn, r, method, url,
                          err.code == GI_EINVAL ? MHD_HTTP_BAD_REQUEST : MHD_HTTP_INTERNAL_SERVER_ERROR,
                          "%s", err.msg);
    }
    return MHD_YES;
}

/* How far past its limit, or its refusal, a body is read (and discarded)
 * to answer. */
#define DISCARD_MAX ((uint64_t)64 << 20)

/* A piece of a request body. */
static void body_piece(gi_farm *f, api_req *r, const char *data, size_t n)
{
    r->received += n;
    if (r->status)
        return; /* already failed: the rest is discarded */
    if (r->received > r->limit) {
        gi_farm_upload_abort(r->up);
        r->up = NULL;
        body_release(f, r);
        r->status = MHD_HTTP_CONTENT_TOO_LARGE;
        snprintf(r->err, sizeof r->err, "request body is over the limit of %llu bytes",
                 (unsigned long long)r->limit);
        return;
    }
    if (r->up) {
        gi_error err;
        if (gi_farm_upload_write(r->up, data, n, &err)) {
            gi_farm_upload_abort(r->up);
            r->up = NULL;
            r->status = err.code == GI_ENOMEM ? MHD_HTTP_INSUFFICIENT_STORAGE
                                              : MHD_HTTP_INTERNAL_SERVER_ERROR;
            snprintf(r->err, sizeof r->err, "%s", err.msg);
        }
    } else if (r->rt.id == GI_ROUTE_JOBS_SUBMIT) {
        if (submissions_have_room(f, n, r)) {
            gi_buf_put(&r->body, data, n);
            f->submit_buffered += n;
        } else {
            body_release(f, r);
        }
    } else {
        r->status = MHD_HTTP_BAD_REQUEST;
        snprintf(r->err, sizeof r->err, "this endpoint takes no request body");
    }
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    gi_farm *f = cls;
    api_req *r = *con_cls;
    if (!r) {
        gi_api_conn *c = api_conn_of(conn);
        if (c)
            request_began(f, c, method, url);
        r = gi_xcalloc(1, sizeof *r);
        gi_buf_init(&r->body);
        *con_cls = r;
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
        if (ci && ci->client_addr)
            gi_net_sockaddr_name(ci->client_addr, r->peer, sizeof r->peer);
        else
            snprintf(r->peer, sizeof r->peer, "?");
        f->m.api_requests++;
        return begin(f, conn, r, method, url);
    }
    if (r->responded) {
        *upload_data_size = 0; /* discarded */
        return MHD_YES;
    }
    if (*upload_data_size) {
        body_piece(f, r, upload_data, *upload_data_size);
        *upload_data_size = 0;
        /* A body over the limit (sent chunked, or longer than it said) is
         * read to its end and answered then: MHD cannot answer in the middle
         * of a body. One far over it is cut off without an answer. */
        if (r->status && r->received > r->limit + DISCARD_MAX) {
            gi_warn("api: %s from %s: closed after %llu bytes of a body refused (%s)", method,
                    r->peer, (unsigned long long)r->received, r->err);
            return MHD_NO;
        }
        return MHD_YES;
    }
    if (r->status) {
        gi_farm_upload_abort(r->up);
        r->up = NULL;
        return refuse(f, conn, r, method, url, (unsigned)r->status, "%s", r->err);
    }
    r->responded = 1;
    (void)version;
    return dispatch(f, conn, r, method, url);
}

static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    gi_api_conn *c = api_conn_of(conn);
    if (c) { /* the next request's head is awaited from now */
        c->in_request = 0;
        c->since = gi_now();
    }
    api_req *r = *con_cls;
    if (!r)
        return;
    /* Only an output sent to its end counts as fetched: one cut off (the
     * client gone, a timeout) leaves the job unfetched for retention. */
    if (r->fetching && toe == MHD_REQUEST_TERMINATED_COMPLETED_OK)
        gi_farm_job_fetched(cls, r->rt.job_id, r->rt.name, r->peer);
    gi_farm_upload_abort(r->up); /* a client that went away mid-upload */
    body_release(cls, r);
    free(r);
    *con_cls = NULL;
    (void)conn;
}

/* MHD's messages are about one connection each ("closed by remote side",
 * the ones cut here for their pace...) and say not which: a client opening
 * connections by the hundred would write as many lines. The first in a
 * --refusal-log-window is logged, the others counted and summed up when it
 * is over (mhd_log_tick), with the last one. */
static void on_mhd_log(void *cls, const char *fmt, va_list ap)
{
    gi_farm *f = cls;
    char msg[sizeof f->mhd_log_last];
    vsnprintf(msg, sizeof msg, fmt, ap);
    msg[strcspn(msg, "\n")] = '\0';
    double now = gi_now();
    if (f->cfg.refusal_window_s > 0 && f->mhd_log_since > 0 &&
        now - f->mhd_log_since < f->cfg.refusal_window_s) {
        f->mhd_log_suppressed++;
        memcpy(f->mhd_log_last, msg, sizeof msg);
        return;
    }
    f->mhd_log_since = now;
    gi_info("api: %s", msg);
}

static void mhd_log_tick(gi_farm *f, double now)
{
    if (f->mhd_log_since <= 0 || now - f->mhd_log_since < f->cfg.refusal_window_s)
        return;
    if (f->mhd_log_suppressed)
        gi_info("api: %llu more libmicrohttpd messages in the last %.0f s (the last: %s)",
                (unsigned long long)f->mhd_log_suppressed, now - f->mhd_log_since,
                f->mhd_log_last);
    f->mhd_log_suppressed = 0;
    f->mhd_log_since = 0;
}

static size_t unescape(void *cls, struct MHD_Connection *conn, char *s)
{
    (void)cls;
    (void)conn;
    return gi_url_unescape(s);
}

int gi_farm_api_start(gi_farm *f, gi_error *err)
{
    f->api_fd = gi_net_listen(f->cfg.listen_api, f->api_addr, sizeof f->api_addr, err);
    if (f->api_fd < 0)
        return gi_error_prefix(err, "--listen-api");
    f->mhd = MHD_start_daemon(
        MHD_USE_EPOLL | MHD_USE_ERROR_LOG, 0, NULL, NULL, on_request, f,
        MHD_OPTION_EXTERNAL_LOGGER, on_mhd_log, f, MHD_OPTION_LISTEN_SOCKET, f->api_fd,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, f, MHD_OPTION_NOTIFY_CONNECTION,
        on_connection, f, MHD_OPTION_CONNECTION_LIMIT, API_CONNS_MAX + API_CONNS_CUT_ROOM,
        MHD_OPTION_PER_IP_CONNECTION_LIMIT, API_CONNS_PER_ADDRESS + API_CONNS_CUT_ROOM,
        MHD_OPTION_CONNECTION_TIMEOUT, 60u, MHD_OPTION_CONNECTION_MEMORY_LIMIT,
        (size_t)(256u << 10), MHD_OPTION_UNESCAPE_CALLBACK, unescape, NULL,
        MHD_OPTION_END);
    if (!f->mhd) {
        close(f->api_fd);
        f->api_fd = -1;
        return gi_fail(err, GI_EIO, "cannot start the HTTP API on %s", f->cfg.listen_api);
    }
    return 0;
}

int gi_farm_api_fd(gi_farm *f)
{
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(f->mhd, MHD_DAEMON_INFO_EPOLL_FD);
    return info ? info->epoll_fd : -1;
}

int gi_farm_api_timeout_ms(gi_farm *f)
{
    MHD_UNSIGNED_LONG_LONG t;
    if (MHD_get_timeout(f->mhd, &t) != MHD_YES)
        return -1;
    return t > 1000 ? 1000 : (int)t;
}

void gi_farm_api_run(gi_farm *f)
{
    api_away(f, gi_now());
    MHD_run(f->mhd);
    cut_slow_connections(f);
    f->api_ran_at = gi_now();
    mhd_log_tick(f, f->api_ran_at);
}

void gi_farm_api_stop(gi_farm *f)
{
    if (f->mhd)
        MHD_stop_daemon(f->mhd);
    f->mhd = NULL;
    if (f->api_fd >= 0)
        close(f->api_fd);
    f->api_fd = -1;
}
