/* gi_farm_conn: worker connections on the coordinator's side.
 *
 * Each connection is a non-blocking socket with an incremental frame
 * decoder and an output queue. Until the worker has authenticated, the
 * decoder accepts only HELLO, AUTH, ERROR and BYE frames of control size:
 * an unauthenticated peer cannot make the coordinator hold more than 64 KiB,
 * and has `handshake_s` to finish. Afterwards it accepts what a worker
 * sends (RESULT up to max_result_bytes, FAIL, HEARTBEAT, ASSET_NEED, DRAIN,
 * BYE, ERROR) and nothing else: a frame of any other type is refused from
 * its header. Every refusal is logged with the reason (a peer's refusals
 * before it authenticated: once per peer and 10 s, gi_refusal_log), counted
 * in the metrics, answered with ERROR when the socket still works, and ends only
 * that connection. */
#include <errno.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "gi_farm_impl.h"
#include "gi_progress.h"
#include "gi_log.h"
#include "gi_msg.h"
#include "gi_net.h"
#include "gi_netio.h"
#include "gi_version.h"

/* Asset answers wait while this much output is queued (memory bound). */
#define ASSET_OUT_HIGH ((size_t)64 << 20)
/* Assets above this are sent uncompressed: zstd on the loop's thread would
 * stall every other connection for seconds. */
#define ASSET_COMPRESS_MAX ((size_t)64 << 20)
/* Bytes read from one connection per poll round, so one fast sender does
 * not starve the others. */
#define READ_BUDGET ((size_t)8 << 20)
#define CLOSE_GRACE_S 2.0
/* Connections authenticating at once. */
#define HANDSHAKES_MAX 64

static gi_frame_limits handshake_limits(void)
{
    gi_frame_limits lim = gi_frame_limits_default();
    for (int t = 0; t < GI_MSG_TYPE_COUNT; t++)
        lim.max_payload[t] = 0;
    lim.max_payload[GI_MSG_HELLO] = GI_FRAME_LIMIT_CONTROL;
    lim.max_payload[GI_MSG_AUTH] = GI_FRAME_LIMIT_CONTROL;
    lim.max_payload[GI_MSG_ERROR] = GI_FRAME_LIMIT_CONTROL;
    lim.max_payload[GI_MSG_BYE] = GI_FRAME_LIMIT_CONTROL;
    return lim;
}

static gi_frame_limits worker_limits(const gi_farm *f)
{
    gi_frame_limits lim = gi_frame_limits_default();
    static const uint16_t accepted[] = {GI_MSG_RESULT, GI_MSG_FAIL,  GI_MSG_HEARTBEAT,
                                        GI_MSG_ASSET_NEED, GI_MSG_DRAIN, GI_MSG_BYE,
                                        GI_MSG_ERROR};
    gi_frame_limits out = lim;
    for (int t = 0; t < GI_MSG_TYPE_COUNT; t++)
        out.max_payload[t] = 0;
    for (size_t i = 0; i < GI_ARRAY_LEN(accepted); i++)
        out.max_payload[accepted[i]] = lim.max_payload[accepted[i]];
    if (out.max_payload[GI_MSG_RESULT] > f->cfg.max_result_bytes)
        out.max_payload[GI_MSG_RESULT] = f->cfg.max_result_bytes;
    out.max_decompressed = out.max_payload[GI_MSG_RESULT];
    return out;
}

static const char *who(const gi_farm_conn *c)
{
    return c->have_hello ? c->hello.name : "unauthenticated peer";
}

int gi_farm_conn_wants_write(const gi_farm_conn *c)
{
    return c->fd >= 0 && gi_outq_pending(&c->out) > 0;
}

void gi_farm_conn_send(gi_farm_conn *c, uint16_t type, const gi_buf *payload, int compress)
{
    if (c->fd < 0 || c->state == GI_FC_CLOSING)
        return;
    gi_outq_push(&c->out, type, payload, compress);
}

/* Open connections (closed ones wait for the loop to reap them). */
static size_t open_connections(const gi_farm *f)
{
    size_t n = 0;
    for (size_t i = 0; i < f->conn_count; i++)
        n += f->conns[i]->fd >= 0;
    return n;
}

/* When HANDSHAKES_MAX connections have not authenticated yet, the oldest
 * of them (a worker's handshake takes a round trip) makes way for the new
 * one. Otherwise a peer without the secret, opening that many connections
 * again as each timed out, would keep every worker from joining. */
static void make_room_for_a_handshake(gi_farm *f)
{
    size_t n = 0;
    gi_farm_conn *oldest = NULL;
    for (size_t i = 0; i < f->conn_count; i++) {
        gi_farm_conn *c = f->conns[i];
        if (c->fd < 0 || (c->state != GI_FC_HELLO && c->state != GI_FC_AUTH))
            continue;
        n++;
        if (!oldest || c->connected < oldest->connected)
            oldest = c;
    }
    if (n < HANDSHAKES_MAX)
        return;
    /* Closed at once, and logged once per peer and 10 s (gi_refusal_log): a
     * peer reconnecting as fast as it can would otherwise write a line per
     * connection. */
    double now = gi_now();
    f->m.workers_refused++;
    f->m.handshakes_displaced++;
    gi_refusal_logf(&f->refusals, now, oldest->peer,
                    "refused unauthenticated peer (%s): no handshake after %.1f s, and a newer "
                    "connection needed its place (%d handshakes at most)",
                    oldest->peer, now - oldest->connected, HANDSHAKES_MAX);
    close(oldest->fd);
    oldest->fd = -1;
}

int gi_farm_conn_accept(gi_farm *f)
{
    for (;;) {
        int fd = accept4(f->worker_fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            if (errno == EINTR)
                continue;
            if (errno != EAGAIN && errno != EWOULDBLOCK)
                gi_warn("accepting a worker connection: %s", strerror(errno));
            return 0;
        }
        char peer[80];
        gi_net_peer(fd, peer, sizeof peer);
        make_room_for_a_handshake(f);
        /* Room for every allowed worker, the handshakes in progress and
         * connections flushing their last frames. */
        size_t open = open_connections(f);
        if (open >= (size_t)f->cfg.max_workers + 2 * HANDSHAKES_MAX) {
            gi_refusal_logf(&f->refusals, gi_now(), peer,
                            "refused worker connection from %s: %zu connections open (limit %u "
                            "workers)", peer, open, f->cfg.max_workers);
            f->m.workers_refused++;
            close(fd);
            continue;
        }
        gi_net_tune(fd);
        gi_farm_conn *c = gi_xcalloc(1, sizeof *c);
        c->id = ++f->next_conn_id;
        c->fd = fd;
        snprintf(c->peer, sizeof c->peer, "%s", peer);
        c->state = GI_FC_HELLO;
        gi_frame_limits lim = handshake_limits();
        char name[120];
        snprintf(name, sizeof name, "worker connection %s", peer);
        gi_frame_decoder_init(&c->dec, &lim, name);
        c->connected = c->last_heard = gi_now();
        gi_outq_init(&c->out);
        gi_buf_init(&c->hello_raw);
        if (f->conn_count == f->conn_cap) {
            f->conn_cap = f->conn_cap ? 2 * f->conn_cap : 16;
            f->conns = gi_xrealloc(f->conns, f->conn_cap * sizeof *f->conns);
        }
        f->conns[f->conn_count++] = c;
        gi_debug("connection from %s", peer);
    }
}

void gi_farm_conn_close(gi_farm *f, gi_farm_conn *c, gi_errcode code, const char *fmt, ...)
{
    if (c->fd < 0 || c->state == GI_FC_CLOSING)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->close_reason, sizeof c->close_reason, fmt, ap);
    va_end(ap);
    int was_worker = c->state == GI_FC_ACTIVE || c->state == GI_FC_DRAINING;
    if (code == GI_OK)
        gi_info("worker %s (%s) left: %s", who(c), c->peer, c->close_reason);
    else if (!was_worker) /* not authenticated: a scanner, a wrong secret */
        gi_refusal_logf(&f->refusals, gi_now(), c->peer, "refused %s (%s): %s", who(c), c->peer,
                        c->close_reason);
    else
        gi_warn("dropped worker %s (%s): %s", who(c), c->peer, c->close_reason);
    if (code != GI_OK && code != GI_EIO) {
        /* Tell the peer why; it may no longer be listening. */
        gi_error e;
        gi_fail(&e, code, "%s", c->close_reason);
        gi_buf b;
        gi_buf_init(&b);
        gi_msg_error_encode(&b, &e);
        gi_farm_conn_send(c, GI_MSG_ERROR, &b, 0);
        gi_buf_free(&b);
    }
    c->state = GI_FC_CLOSING;
    c->last_heard = gi_now(); /* the grace period for flushing starts now */
    gi_farm_sched_release(f, c, code != GI_OK, c->close_reason);
    if (!gi_farm_conn_wants_write(c)) {
        close(c->fd);
        c->fd = -1;
    }
}

/* ---- handshake ----------------------------------------------------------- */

static void on_hello(gi_farm *f, gi_farm_conn *c, const gi_frame *fr)
{
    gi_error err;
    if (gi_msg_hello_decode(&fr->payload, &c->hello, &err)) {
        f->m.workers_refused++;
        gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
        return;
    }
    c->have_hello = 1;
    c->proto = gi_msg_proto_choose(c->hello.proto_min, c->hello.proto_max);
    if (!c->proto) {
        f->m.workers_refused++;
        gi_farm_conn_close(f, c, GI_EPROTO,
                           "worker speaks protocol versions %u-%u; this coordinator speaks %u-%u",
                           c->hello.proto_min, c->hello.proto_max, GI_PROTO_MIN, GI_PROTO_MAX);
        return;
    }
    gi_buf_put(&c->hello_raw, fr->payload.data, fr->payload.len);
    gi_auth_random(c->nonce, sizeof c->nonce);
    gi_msg_challenge ch = {.proto = c->proto};
    memcpy(ch.nonce, c->nonce, sizeof c->nonce);
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_challenge_encode(&b, &ch);
    gi_farm_conn_send(c, GI_MSG_CHALLENGE, &b, 0);
    gi_buf_free(&b);
    c->state = GI_FC_AUTH;
}

static size_t active_workers(const gi_farm *f)
{
    size_t n = 0;
    for (size_t i = 0; i < f->conn_count; i++)
        n += f->conns[i]->state == GI_FC_ACTIVE || f->conns[i]->state == GI_FC_DRAINING;
    return n;
}

/* Blocklisting and batch affinity go by name: two live workers sharing one
 * (two gi-worker on a host, both without --name) are taken for one host.
 * A worker reconnecting after a lost link has the same name too, but its
 * old connection has gone silent. */
static void warn_same_name(const gi_farm *f, const gi_farm_conn *c)
{
    double now = gi_now();
    for (size_t i = 0; i < f->conn_count; i++) {
        const gi_farm_conn *o = f->conns[i];
        if (o != c && o->state == GI_FC_ACTIVE && o->have_hello &&
            strcmp(o->hello.name, c->hello.name) == 0 &&
            now - o->last_heard < 2 * f->cfg.heartbeat_s) {
            gi_warn("worker %s (%s) joined while another worker of that name (%s) is active: "
                    "they count as one host for blocklisting and batch affinity; give each "
                    "gi-worker its own --name",
                    c->hello.name, c->peer, o->peer);
            return;
        }
    }
}

static void on_auth(gi_farm *f, gi_farm_conn *c, const gi_frame *fr)
{
    uint8_t mac[GI_MSG_MAC_BYTES], want[GI_MSG_MAC_BYTES];
    gi_error err;
    if (gi_msg_auth_decode(&fr->payload, mac, &err)) {
        f->m.workers_refused++;
        gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
        return;
    }
    gi_auth_worker_mac(f->key, c->nonce, c->hello.nonce, c->hello_raw.data, c->hello_raw.len,
                       want);
    if (!gi_auth_mac_equal(mac, want)) {
        f->m.workers_refused++;
        gi_farm_conn_close(f, c, GI_EPROTO,
                           "authentication failed: the worker does not know the farm secret");
        return;
    }
    if (active_workers(f) >= f->cfg.max_workers) {
        f->m.workers_refused++;
        gi_farm_conn_close(f, c, GI_ENOMEM, "the farm has its limit of %u workers",
                           f->cfg.max_workers);
        return;
    }
    gi_msg_welcome w;
    w.worker_id = c->id;
    w.heartbeat_ms = (uint32_t)(f->cfg.heartbeat_s * 1000.0 + 0.5);
    w.lease_ms = (uint32_t)(f->cfg.lease_s * 1000.0 + 0.5);
    gi_auth_coord_mac(f->key, c->hello.nonce, c->nonce, c->id, w.mac);
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_welcome_encode(&b, &w);
    gi_farm_conn_send(c, GI_MSG_WELCOME, &b, 0);
    gi_buf_free(&b);
    gi_buf_free(&c->hello_raw);
    gi_frame_limits lim = worker_limits(f);
    gi_frame_decoder_set_limits(&c->dec, &lim);
    c->state = GI_FC_ACTIVE;
    warn_same_name(f, c);
    c->host = gi_farm_host_get(f, c->hello.name);
    c->next_heartbeat = gi_now() + f->cfg.heartbeat_s;
    f->m.workers_accepted++;
    gi_farm_sched_welcome(f, c);
    gi_info("worker %s (%s) joined: %u process%s, %u slots, %u cores, %.1f GiB, protocol %u, "
            "version %s%s",
            c->hello.name, c->peer, c->hello.procs, c->hello.procs == 1 ? "" : "es",
            c->hello.slots, c->hello.cores,
            (double)c->hello.memory / (1u << 30), c->proto, c->hello.version,
            strcmp(c->hello.version, GI_VERSION) ? " (differs from the coordinator's)" : "");
}

/* ---- assets ---------------------------------------------------------------- */

static void serve_assets(gi_farm *f, gi_farm_conn *c)
{
    while (c->asset_q_count && gi_outq_pending(&c->out) < ASSET_OUT_HIGH &&
           c->state != GI_FC_CLOSING) {
        char *hash = c->asset_q[c->asset_q_head];
        gi_buf bytes, b;
        gi_buf_init(&bytes);
        gi_buf_init(&b);
        gi_error err;
        /* Every host asks for a job's assets: read, checked and compressed
         * once (gi_frame_cache), not once a host. */
        const gi_buf *frame = gi_frame_cache_get(&f->asset_frames, hash);
        if (frame) {
            gi_outq_push_frame(&c->out, frame);
            f->m.assets_served++;
        } else if (gi_farm_asset_bytes(f, hash, &bytes, &err) == 0) {
            gi_msg_asset_put_encode(&b, hash, bytes.data, bytes.len);
            gi_buf fr;
            gi_buf_init(&fr);
            gi_frame_encode(&fr, GI_MSG_ASSET_PUT, b.data, b.len, bytes.len <= ASSET_COMPRESS_MAX);
            gi_outq_push_frame(&c->out, &fr);
            gi_frame_cache_put(&f->asset_frames, hash, &fr);
            gi_buf_free(&fr);
            f->m.assets_served++;
        } else {
            gi_warn("worker %s asked for asset %.12s: %s", who(c), hash, err.msg);
            gi_msg_error_encode(&b, &err);
            gi_farm_conn_send(c, GI_MSG_ERROR, &b, 0);
        }
        gi_buf_free(&bytes);
        gi_buf_free(&b);
        c->asset_q_head++;
        c->asset_q_count--;
        if (c->asset_q_count == 0)
            c->asset_q_head = 0;
    }
}

static void on_asset_need(gi_farm *f, gi_farm_conn *c, const gi_frame *fr)
{
    char hash[GI_HASH_HEX];
    gi_error err;
    if (gi_msg_asset_need_decode(&fr->payload, hash, &err)) {
        gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
        return;
    }
    /* A worker asks once per asset it lacks; a queue of this length is a
     * peer misbehaving. */
    if (c->asset_q_count >= 4096) {
        gi_farm_conn_close(f, c, GI_EPROTO, "more than 4096 asset requests outstanding");
        return;
    }
    if (c->asset_q_head + c->asset_q_count == c->asset_q_cap) {
        if (c->asset_q_head > 0) {
            memmove(c->asset_q, c->asset_q + c->asset_q_head, c->asset_q_count * sizeof *c->asset_q);
            c->asset_q_head = 0;
        } else {
            c->asset_q_cap = c->asset_q_cap ? 2 * c->asset_q_cap : 16;
            c->asset_q = gi_xrealloc(c->asset_q, c->asset_q_cap * sizeof *c->asset_q);
        }
    }
    memcpy(c->asset_q[c->asset_q_head + c->asset_q_count++], hash, GI_HASH_HEX);
    serve_assets(f, c);
}

/* ---- frames ---------------------------------------------------------------- */

static void on_frame(gi_farm *f, gi_farm_conn *c, const gi_frame *fr)
{
    gi_error err;
    const char *name = gi_msg_type_name(fr->type);
    if (fr->type == GI_MSG_ERROR) {
        gi_error e;
        if (gi_msg_error_decode(&fr->payload, &e, &err))
            gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
        else
            gi_farm_conn_close(f, c, GI_EIO, "the worker reported: %s", e.msg);
        return;
    }
    if (c->state == GI_FC_HELLO) {
        if (fr->type == GI_MSG_HELLO)
            on_hello(f, c, fr);
        else
            gi_farm_conn_close(f, c, GI_EPROTO, "expected HELLO, got %s", name);
        return;
    }
    if (c->state == GI_FC_AUTH) {
        if (fr->type == GI_MSG_AUTH)
            on_auth(f, c, fr);
        else
            gi_farm_conn_close(f, c, GI_EPROTO, "expected AUTH, got %s", name);
        return;
    }
    switch (fr->type) {
    case GI_MSG_RESULT:
        gi_farm_sched_result(f, c, &fr->payload);
        break;
    case GI_MSG_FAIL:
        gi_farm_sched_fail(f, c, &fr->payload);
        break;
    case GI_MSG_HEARTBEAT:
    case GI_MSG_DRAIN: {
        gi_msg_tasklist tl;
        int hb = fr->type == GI_MSG_HEARTBEAT;
        if (gi_msg_tasklist_decode(&fr->payload, hb ? "HEARTBEAT message" : "DRAIN message",
                                   hb && c->proto >= GI_PROTO_RUNS, &tl, &err)) {
            gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
            return;
        }
        if (fr->type == GI_MSG_DRAIN)
            gi_farm_sched_drain(f, c, &tl);
        else
            gi_farm_sched_heartbeat(f, c, &tl);
        gi_msg_tasklist_free(&tl);
        break;
    }
    case GI_MSG_ASSET_NEED:
        on_asset_need(f, c, fr);
        break;
    case GI_MSG_BYE:
        if (fr->payload.len)
            gi_farm_conn_close(f, c, GI_EPROTO, "BYE message with a payload");
        else
            gi_farm_conn_close(f, c, GI_OK, "said goodbye");
        break;
    default:
        gi_farm_conn_close(f, c, GI_EPROTO, "unexpected %s from a worker", name);
    }
}

void gi_farm_conn_readable(gi_farm *f, gi_farm_conn *c)
{
    size_t budget = READ_BUDGET;
    while (c->fd >= 0 && c->state != GI_FC_CLOSING) {
        ssize_t n = gi_frame_decoder_recv(&c->dec, c->fd, budget);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK)) {
            gi_farm_conn_close(f, c, GI_EIO, n == 0 ? "connection closed by the worker%s"
                                                    : "connection error%s",
                               gi_frame_decoder_mid_frame(&c->dec) ? " in the middle of a frame" : "");
            return;
        }
        if (n > 0) {
            budget -= (size_t)n;
            c->last_heard = gi_now();
        }
        for (;;) {
            gi_frame fr;
            gi_error err;
            int got = gi_frame_decoder_next(&c->dec, &fr, &err);
            if (got == 0)
                break;
            if (got < 0) {
                f->m.frames_refused++;
                if (c->state == GI_FC_HELLO || c->state == GI_FC_AUTH)
                    f->m.workers_refused++;
                gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
                return;
            }
            on_frame(f, c, &fr);
            gi_frame_free(&fr);
            if (c->fd < 0 || c->state == GI_FC_CLOSING)
                return;
        }
        if (n < 0 || budget == 0)
            return; /* drained, or this connection's share of the round is used */
    }
}

void gi_farm_conn_writable(gi_farm *f, gi_farm_conn *c)
{
    if (c->fd < 0)
        return;
    if (gi_outq_flush(&c->out, c->fd) != 0) {
        if (c->state == GI_FC_CLOSING) {
            close(c->fd);
            c->fd = -1;
            return;
        }
        gi_farm_conn_close(f, c, GI_EIO, "send failed: %s", strerror(errno));
        return;
    }
    if (c->state == GI_FC_CLOSING && gi_outq_pending(&c->out) == 0) {
        shutdown(c->fd, SHUT_WR);
        close(c->fd);
        c->fd = -1;
        return;
    }
    serve_assets(f, c);
}

void gi_farm_conns_tick(gi_farm *f)
{
    double now = gi_now();
    for (size_t i = 0; i < f->conn_count; i++) {
        gi_farm_conn *c = f->conns[i];
        if (c->fd < 0)
            continue;
        switch (c->state) {
        case GI_FC_HELLO:
        case GI_FC_AUTH:
            if (now - c->connected > f->cfg.handshake_s) {
                f->m.workers_refused++;
                gi_farm_conn_close(f, c, GI_EPROTO, "no handshake within %.0f s",
                                   f->cfg.handshake_s);
            }
            break;
        case GI_FC_ACTIVE:
        case GI_FC_DRAINING:
            if (now - c->last_heard > f->cfg.dead_s) {
                gi_farm_conn_close(f, c, GI_EIO, "silent for %.1f s", now - c->last_heard);
                break;
            }
            if (now >= c->next_heartbeat) {
                gi_buf b;
                gi_buf_init(&b);
                gi_msg_tasklist_encode(&b, (uint64_t)(now * 1000.0), NULL, 0,
                                       c->proto >= GI_PROTO_RUNS);
                gi_farm_conn_send(c, GI_MSG_HEARTBEAT, &b, 0);
                gi_buf_free(&b);
                c->next_heartbeat = now + f->cfg.heartbeat_s;
            }
            break;
        case GI_FC_CLOSING:
            if (now - c->last_heard > CLOSE_GRACE_S) {
                close(c->fd);
                c->fd = -1;
            }
            break;
        }
    }
    gi_farm_sched_expire(f, now);
}

void gi_farm_conns_reap(gi_farm *f)
{
    size_t k = 0;
    for (size_t i = 0; i < f->conn_count; i++) {
        gi_farm_conn *c = f->conns[i];
        if (c->fd >= 0) {
            f->conns[k++] = c;
            continue;
        }
        gi_farm_sched_release(f, c, 1, "connection closed");
        gi_frame_decoder_free(&c->dec);
        gi_outq_free(&c->out);
        gi_buf_free(&c->hello_raw);
        gi_msg_hello_free(&c->hello);
        free(c->leases);
        free(c->jobs_sent);
        free(c->asset_q);
        free(c);
    }
    f->conn_count = k;
}

void gi_farm_conns_goodbye(gi_farm *f, double wait_s)
{
    struct pollfd *fds = gi_xcalloc(f->conn_count ? f->conn_count : 1, sizeof *fds);
    size_t n = 0;
    for (size_t i = 0; i < f->conn_count; i++) {
        gi_farm_conn *c = f->conns[i];
        if (c->fd < 0)
            continue;
        if (c->state == GI_FC_ACTIVE || c->state == GI_FC_DRAINING)
            gi_outq_push(&c->out, GI_MSG_BYE, NULL, 0);
        gi_outq_flush(&c->out, c->fd);
        shutdown(c->fd, SHUT_WR);
        fds[n++] = (struct pollfd){.fd = c->fd, .events = POLLIN};
        c->fd = -1;
    }
    /* Closing with their frames unread would reset the connections: read
     * and drop until each worker hangs up. */
    double end = gi_now() + wait_s;
    size_t open_count = n;
    while (open_count > 0) {
        double left = end - gi_now();
        if (left <= 0 || poll(fds, n, (int)(left * 1000) + 1) <= 0)
            break;
        for (size_t i = 0; i < n; i++) {
            if (fds[i].fd < 0 || !fds[i].revents)
                continue;
            char sink[4096];
            ssize_t got = recv(fds[i].fd, sink, sizeof sink, MSG_DONTWAIT);
            if (got > 0 || (got < 0 && (errno == EINTR || errno == EAGAIN)))
                continue;
            close(fds[i].fd);
            fds[i].fd = -1;
            open_count--;
        }
    }
    for (size_t i = 0; i < n; i++)
        if (fds[i].fd >= 0)
            close(fds[i].fd);
    free(fds);
}
