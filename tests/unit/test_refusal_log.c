/* gi_refusal_log: refusals of unauthenticated peers reach the log once per
 * peer and window, then as a count. */
#include <stdio.h>
#include <string.h>

#include "gi_log.h"
#include "gi_refusal_log.h"
#include "gi_test.h"

typedef struct lines {
    int n;
    char last[600];
    char first[600];
} lines;

static void catch_line(void *ctx, gi_log_level level, const char *msg)
{
    lines *l = ctx;
    if (level != GI_LOG_WARN)
        return;
    if (l->n++ == 0)
        snprintf(l->first, sizeof l->first, "%s", msg);
    snprintf(l->last, sizeof l->last, "%s", msg);
}

GI_TEST(test_refusal_log_per_peer)
{
    static gi_refusal_log rl;
    gi_refusal_log_init(&rl, GI_REFUSAL_WINDOW_S);
    lines l = {0};
    gi_log_hook_set(catch_line, &l);
    /* 1000 refusals of one host (other ports) within a window: one line. */
    for (int i = 0; i < 1000; i++)
        gi_refusal_logf(&rl, 100.0 + i * 0.001, "10.0.0.7:4000", "refused 10.0.0.7:%d: bad %d",
                        4000 + i, i);
    GI_CHECK(l.n == 1);
    GI_CHECK(strstr(l.first, "10.0.0.7:4000") && strstr(l.first, "bad 0"));
    /* Another host is logged in full at once. */
    GI_CHECK(gi_refusal_logf(&rl, 101.0, "[::1]:80", "refused [::1]:80: wrong token") == 1);
    GI_CHECK(l.n == 2 && strstr(l.last, "wrong token"));
    gi_refusal_tick(&rl, 105.0);
    GI_CHECK(l.n == 2); /* windows not over */
    gi_refusal_tick(&rl, 110.5);
    GI_CHECK(l.n == 3);
    GI_CHECK(strstr(l.last, "999 more refusals from 10.0.0.7 ") != NULL);
    GI_CHECK(strstr(l.last, "bad 999") != NULL);
    /* The next window is counted again; [::1] was quiet: forgotten. */
    GI_CHECK(gi_refusal_logf(&rl, 111.0, "10.0.0.7:1", "again") == 0);
    gi_refusal_tick(&rl, 111.5);
    GI_CHECK(l.n == 3 && rl.count == 1);
    GI_CHECK(gi_refusal_logf(&rl, 112.0, "[::1]:81", "refused [::1]:81 once more") == 1);
    gi_refusal_tick(&rl, 121.0);
    GI_CHECK(l.n == 5 && strstr(l.last, "1 more refusals from 10.0.0.7"));
    /* A quiet window forgets it: the next is in full. */
    gi_refusal_tick(&rl, 132.0);
    GI_CHECK(rl.count == 0 && l.n == 5);
    GI_CHECK(gi_refusal_logf(&rl, 133.0, "10.0.0.7:9", "full again") == 1);
    /* A window of 0: every refusal in full. */
    gi_refusal_log_init(&rl, 0);
    for (int i = 0; i < 5; i++)
        GI_CHECK(gi_refusal_logf(&rl, 140.0, "10.0.0.7:9", "each %d", i) == 1);
    GI_CHECK(l.n == 11 && strstr(l.last, "each 4"));
    gi_log_hook_set(NULL, NULL);
}

GI_TEST(test_refusal_log_many_peers)
{
    static gi_refusal_log rl;
    gi_refusal_log_init(&rl, GI_REFUSAL_WINDOW_S);
    lines l = {0};
    gi_log_hook_set(catch_line, &l);
    /* A scan from 10000 addresses: the first GI_REFUSAL_PEERS_MAX each get a
     * line, the others share one, and one summary per entry follows. */
    for (int i = 0; i < 10000; i++) {
        char peer[64];
        snprintf(peer, sizeof peer, "10.%d.%d.%d:1", i >> 16, (i >> 8) & 255, i & 255);
        gi_refusal_logf(&rl, 50.0, peer, "refused %s", peer);
        gi_refusal_logf(&rl, 50.0, peer, "refused %s again", peer);
    }
    GI_CHECK_MSG(l.n == GI_REFUSAL_PEERS_MAX + 1, "%d lines", l.n);
    gi_refusal_tick(&rl, 60.0);
    GI_CHECK_MSG(l.n == 2 * (GI_REFUSAL_PEERS_MAX + 1), "%d lines", l.n);
    GI_CHECK(strstr(l.last, "more refusals from other peers") != NULL);
    gi_log_hook_set(NULL, NULL);
}
