/* gi_refusal_log: how gi-farmd logs refusals of peers that have not proved
 * who they are (API requests without the right token, worker connections
 * that fail or never finish their handshake). A scanner, or a host with a
 * wrong secret retrying as fast as it can, would otherwise write a log line
 * per attempt. API connections closed for their pace (gi_farm_api.c) are
 * logged this way too: anyone can open them, token or not.
 *
 * Per peer address (the port aside): its first refusal is logged in full
 * (the peer and the reason); the ones in the GI_REFUSAL_WINDOW_S after it
 * are only counted, and when that window is over one line says how many
 * there were and the last one's reason. A window without refusals forgets
 * the address, so its next refusal is logged in full again. Past
 * GI_REFUSAL_PEERS_MAX addresses at once, the others share one entry
 * ("other peers"): a scan from many addresses writes a bounded number of
 * lines too. The counters in /metrics count every refusal. A window of 0
 * logs every refusal in full (gi-farmd --refusal-log-window 0: for a log
 * reader such as fail2ban that counts lines). */
#ifndef GI_REFUSAL_LOG_H
#define GI_REFUSAL_LOG_H

#include <stddef.h>
#include <stdint.h>

#define GI_REFUSAL_WINDOW_S 10.0
#define GI_REFUSAL_PEERS_MAX 64

typedef struct gi_refusal_peer {
    char addr[64];      /* "" for the shared entry of other peers */
    double since;       /* start of its window (monotonic) */
    uint64_t suppressed;
    char last[400];     /* the last suppressed refusal's line */
} gi_refusal_peer;

typedef struct gi_refusal_log {
    double window_s;
    gi_refusal_peer peers[GI_REFUSAL_PEERS_MAX];
    size_t count;
    gi_refusal_peer others; /* used when others.since > 0 */
} gi_refusal_log;

void gi_refusal_log_init(gi_refusal_log *rl, double window_s);
/* A refusal of `peer` ("HOST:PORT", "[V6]:PORT" or just a host) at `now`
 * (monotonic seconds), described by the printf-style line (which names
 * the peer and the reason): logged as a warning now if it is the peer's
 * first in a window, else counted for the window's summary. Returns 1 if
 * it was logged. */
int gi_refusal_logf(gi_refusal_log *rl, double now, const char *peer, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* Logs the summaries of the windows that are over and forgets the peers
 * that were quiet for one (call it from the loop's timers). */
void gi_refusal_tick(gi_refusal_log *rl, double now);

#endif
