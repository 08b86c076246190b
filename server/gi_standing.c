/* gi_standing: the workers' standing file (gi_standing.h). */
#include "gi_standing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_journal.h"

#define STANDING_MAGIC 0x54534947u /* "GIST" */
#define STANDING_VERSION 2u

void gi_standing_encode(const gi_standing_host *hosts, size_t host_count,
                        const gi_standing_excl *excl, size_t excl_count, gi_buf *out)
{
    gi_buf_put_u32(out, STANDING_MAGIC);
    gi_buf_put_u32(out, STANDING_VERSION);
    gi_buf_put_u64(out, host_count);
    for (size_t i = 0; i < host_count; i++) {
        const gi_standing_host *h = &hosts[i];
        gi_buf_put_str(out, h->name);
        gi_buf_put_u64(out, h->failures);
        gi_buf_put_u64(out, h->own_failures);
        gi_buf_put_u32(out, h->consecutive_failures);
        gi_buf_put_u64(out, h->streak_job);
        gi_buf_put_u8(out, h->streak_wide ? 1 : 0);
        gi_buf_put_u64(out, h->losses);
        gi_buf_put_u32(out, h->consecutive_losses);
        gi_buf_put_f64(out, h->blocked_until);
        gi_buf_put_str(out, h->last_error);
    }
    gi_buf_put_u64(out, excl_count);
    for (size_t i = 0; i < excl_count; i++) {
        const gi_standing_excl *x = &excl[i];
        gi_buf_put_u64(out, x->job_id);
        gi_buf_put_str(out, x->host);
        gi_buf_put_u32(out, x->streak);
        gi_buf_put_u32(out, x->times);
        gi_buf_put_f64(out, x->until);
        gi_buf_put_f64(out, x->last_failed);
        gi_buf_put_str(out, x->last_error);
    }
}

/* A string field into dst (of cap bytes): 0, or -1 (r failed) when it is
 * missing, too long, or empty and must not be. */
static int get_text(gi_reader *r, char *dst, size_t cap, int nonempty)
{
    char *s = gi_get_str(r, cap - 1);
    if (!s || (nonempty && !s[0])) {
        r->failed = 1;
        free(s);
        return -1;
    }
    memcpy(dst, s, strlen(s) + 1);
    free(s);
    return 0;
}

static int time_ok(double t)
{
    return isfinite(t) && t >= 0;
}

/* An entry's bytes read, but its values wrong: damage, named. */
static void bad_entry(gi_reader *r, gi_error *err, const char *what, const char *which,
                      uint64_t i)
{
    r->failed = 1;
    gi_fail(err, GI_EPROTO, "%s: %s %llu is out of range", what, which,
                   (unsigned long long)i);
}

static int read_host(gi_reader *r, gi_standing_host *h)
{
    memset(h, 0, sizeof *h);
    if (get_text(r, h->name, sizeof h->name, 1))
        return -1;
    h->failures = gi_get_u64(r);
    h->own_failures = gi_get_u64(r);
    h->consecutive_failures = gi_get_u32(r);
    h->streak_job = gi_get_u64(r);
    uint8_t wide = gi_get_u8(r);
    h->losses = gi_get_u64(r);
    h->consecutive_losses = gi_get_u32(r);
    h->blocked_until = gi_get_f64(r);
    if (get_text(r, h->last_error, sizeof h->last_error, 0) || r->failed)
        return -1;
    h->streak_wide = wide;
    return wide <= 1 && time_ok(h->blocked_until) && h->streak_job <= GI_JOB_ID_MAX ? 0 : 1;
}

static int read_excl(gi_reader *r, uint32_t version, gi_standing_excl *x)
{
    memset(x, 0, sizeof *x);
    x->job_id = gi_get_u64(r);
    if (get_text(r, x->host, sizeof x->host, 1))
        return -1;
    x->streak = gi_get_u32(r);
    x->times = gi_get_u32(r);
    x->until = gi_get_f64(r);
    if (version >= 2)
        x->last_failed = gi_get_f64(r);
    if (get_text(r, x->last_error, sizeof x->last_error, 0) || r->failed)
        return -1;
    return x->job_id >= 1 && x->job_id <= GI_JOB_ID_MAX && time_ok(x->until) &&
                   time_ok(x->last_failed) ? 0 : 1;
}

int gi_standing_decode(const void *data, size_t len, const char *what,
                       const gi_standing_sink *sink, gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, data, len, what);
    uint32_t magic = gi_get_u32(&r), version = gi_get_u32(&r);
    uint64_t n = gi_get_u64(&r);
    /* A host takes 58 bytes at least: a count beyond that is damage. */
    if (!r.failed && magic == STANDING_MAGIC && version > STANDING_VERSION)
        return gi_fail(err, GI_EPROTO, "%s: version %u, newer than this gi-farmd reads (%u)",
                       what, version, STANDING_VERSION);
    if (r.failed || magic != STANDING_MAGIC || version < 1 || n > r.left / 58)
        return gi_fail(err, GI_EPROTO, "%s: not a standing file", what);
    gi_standing_host h;
    for (uint64_t i = 0; i < n; i++) {
        int rc = read_host(&r, &h);
        if (rc < 0) {
            gi_reader_finish(&r, err);
            return 1;
        }
        if (rc > 0) {
            bad_entry(&r, err, what, "host", i);
            return 1;
        }
        sink->host(sink->ctx, &h);
    }
    n = gi_get_u64(&r);
    /* An exclusion takes 33 bytes at least (41 from version 2): a count
     * beyond that is damage. */
    if (!r.failed && n > r.left / (version >= 2 ? 41 : 33)) {
        gi_fail(err, GI_EPROTO, "%s: %llu exclusions in %zu bytes", what, (unsigned long long)n,
                r.left);
        return 1;
    }
    gi_standing_excl x;
    for (uint64_t i = 0; i < n && !r.failed; i++) {
        int rc = read_excl(&r, version, &x);
        if (rc < 0)
            break;
        if (rc > 0) {
            bad_entry(&r, err, what, "exclusion", i);
            return 1;
        }
        sink->excl(sink->ctx, &x);
    }
    return gi_reader_finish(&r, err) ? 1 : 0;
}
