/* gi_standing: the workers' standing file round-trips, reads version 1
 * files (written before exclusions kept their last failure), and refuses a
 * newer version by name. */
#include <string.h>

#include "gi_standing.h"
#include "gi_test.h"

typedef struct got {
    gi_standing_host host;
    gi_standing_excl excl[2];
    size_t hosts, excls;
} got;

static void got_host(void *ctx, const gi_standing_host *h)
{
    got *g = ctx;
    g->host = *h;
    g->hosts++;
}

static void got_excl(void *ctx, const gi_standing_excl *x)
{
    got *g = ctx;
    if (g->excls < 2)
        g->excl[g->excls] = *x;
    g->excls++;
}

GI_TEST(test_standing_versions)
{
    gi_standing_host h = {.name = "w1", .failures = 7, .own_failures = 3,
                          .consecutive_failures = 2, .streak_job = 4, .streak_wide = 1,
                          .blocked_until = 1.8e9, .last_error = "pool child crashed"};
    gi_standing_excl x[2] = {
        {.job_id = 4, .host = "w1", .streak = 2, .times = 1, .until = 1.8e9,
         .last_failed = 1.79e9, .last_error = "boom"},
        {.job_id = 5, .host = "w2", .streak = 1, .last_failed = 1.7e9},
    };
    gi_buf b;
    gi_buf_init(&b);
    gi_standing_encode(&h, 1, x, 2, &b);
    got g = {0};
    gi_standing_sink sink = {got_host, got_excl, &g};
    gi_error err;
    GI_CHECK(gi_standing_decode(b.data, b.len, "standing", &sink, &err) == 0);
    GI_CHECK(g.hosts == 1 && g.excls == 2);
    GI_CHECK(!strcmp(g.host.name, "w1") && g.host.own_failures == 3 && g.host.streak_wide == 1);
    GI_CHECK(g.excl[0].last_failed == 1.79e9 && g.excl[0].until == 1.8e9 &&
             !strcmp(g.excl[0].last_error, "boom"));
    GI_CHECK(g.excl[1].last_failed == 1.7e9 && !strcmp(g.excl[1].host, "w2"));

    /* Version 1: the same without the exclusions' last_failed (8 bytes
     * before each exclusion's last_error), read as 0. */
    gi_buf v1;
    gi_buf_init(&v1);
    gi_standing_encode(&h, 1, x, 0, &v1);
    ((unsigned char *)v1.data)[4] = 1;
    v1.len -= 8; /* the exclusion count: written again below */
    gi_buf_put_u64(&v1, 2);
    for (int i = 0; i < 2; i++) {
        gi_buf_put_u64(&v1, x[i].job_id);
        gi_buf_put_str(&v1, x[i].host);
        gi_buf_put_u32(&v1, x[i].streak);
        gi_buf_put_u32(&v1, x[i].times);
        gi_buf_put_f64(&v1, x[i].until);
        gi_buf_put_str(&v1, x[i].last_error);
    }
    memset(&g, 0, sizeof g);
    GI_CHECK(gi_standing_decode(v1.data, v1.len, "standing", &sink, &err) == 0);
    GI_CHECK(g.excls == 2 && g.excl[0].last_failed == 0 && g.excl[0].until == 1.8e9 &&
             !strcmp(g.excl[0].last_error, "boom") && !strcmp(g.excl[1].host, "w2"));

    /* A newer version is refused as such, before anything is read. */
    ((unsigned char *)b.data)[4] = 3;
    memset(&g, 0, sizeof g);
    GI_CHECK(gi_standing_decode(b.data, b.len, "DIR/standing", &sink, &err) == -1);
    GI_CHECK(g.hosts == 0 && strstr(err.msg, "DIR/standing: version 3, newer"));
    /* A last failure that is no date is damage, named. */
    ((unsigned char *)b.data)[4] = 2;
    gi_buf c;
    gi_buf_init(&c);
    x[1].last_failed = -1;
    gi_standing_encode(&h, 1, x, 2, &c);
    memset(&g, 0, sizeof g);
    GI_CHECK(gi_standing_decode(c.data, c.len, "standing", &sink, &err) == 1);
    GI_CHECK(g.excls == 1 && strstr(err.msg, "exclusion 1 is out of range"));
    gi_buf_free(&b);
    gi_buf_free(&v1);
    gi_buf_free(&c);
}
