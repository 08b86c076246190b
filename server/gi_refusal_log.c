/* gi_refusal_log: a log line per peer and window for refusals. */
#include "gi_refusal_log.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gi_log.h"

/* The address without its port: "10.0.0.7:5123" -> "10.0.0.7",
 * "[::1]:80" -> "[::1]"; a string without a port stays whole. */
static void host_of(const char *peer, char *out, size_t n)
{
    const char *colon = strrchr(peer, ':');
    size_t len = strlen(peer);
    if (colon && (peer[0] == '[' ? colon > strchr(peer, ']') : strchr(peer, ':') == colon))
        len = (size_t)(colon - peer);
    if (len >= n)
        len = n - 1;
    memcpy(out, peer, len);
    out[len] = '\0';
}

void gi_refusal_log_init(gi_refusal_log *rl, double window_s)
{
    memset(rl, 0, sizeof *rl);
    rl->window_s = window_s;
}

static gi_refusal_peer *find(gi_refusal_log *rl, const char *addr)
{
    for (size_t i = 0; i < rl->count; i++)
        if (strcmp(rl->peers[i].addr, addr) == 0)
            return &rl->peers[i];
    return NULL;
}

int gi_refusal_logf(gi_refusal_log *rl, double now, const char *peer, const char *fmt, ...)
{
    char line[sizeof rl->others.last];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (rl->window_s <= 0) {
        gi_warn("%s", line);
        return 1;
    }
    char addr[sizeof rl->others.addr];
    host_of(peer, addr, sizeof addr);
    gi_refusal_peer *p = find(rl, addr);
    if (!p && rl->count < GI_REFUSAL_PEERS_MAX) {
        p = &rl->peers[rl->count++];
        memset(p, 0, sizeof *p);
        snprintf(p->addr, sizeof p->addr, "%s", addr);
        p->since = now;
        gi_warn("%s", line);
        return 1;
    }
    if (!p) { /* every entry is taken: the others share one */
        p = &rl->others;
        if (p->since <= 0) {
            p->since = now > 0 ? now : 1e-9;
            gi_warn("%s", line);
            return 1;
        }
    }
    p->suppressed++;
    memcpy(p->last, line, sizeof p->last);
    return 0;
}

/* 1 if the peer's window is over and it is to be forgotten. */
static int window_over(const gi_refusal_log *rl, gi_refusal_peer *p, double now)
{
    if (now - p->since < rl->window_s)
        return 0;
    if (!p->suppressed)
        return 1;
    gi_warn("%llu more refusals from %s in the last %.0f s (the last: %s)",
            (unsigned long long)p->suppressed, p->addr[0] ? p->addr : "other peers",
            now - p->since, p->last);
    p->suppressed = 0;
    p->since = now;
    return 0;
}

void gi_refusal_tick(gi_refusal_log *rl, double now)
{
    for (size_t i = 0; i < rl->count;) {
        if (window_over(rl, &rl->peers[i], now))
            rl->peers[i] = rl->peers[--rl->count];
        else
            i++;
    }
    if (rl->others.since > 0 && window_over(rl, &rl->others, now))
        rl->others.since = 0;
}
