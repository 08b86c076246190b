/* gi_farm_standing: the workers' standing kept across gi-farmd restarts
 * (docs/farm.md, "Blocklisting"): each host's failure and loss counts, its
 * streaks and blocklisting, and every job's exclusions, in
 * <state>/standing (gi_standing.h). It is written atomically from the
 * loop's tick, at most once a second while it changes, and when gi-farmd
 * stops; read once the journal is replayed (exclusions of jobs it no
 * longer knows are dropped). A coordinator killed outright loses a second
 * of changes at most. Failures not yet judged (gi_farm_sched.c, Blame) are
 * not kept: a restart judges them nobody's. A file that cannot be written
 * or read is a warning, never fatal: like a job's affinity file, it is a
 * hint, and a farm without it starts its workers afresh, as it did. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_farm_impl.h"
#include "gi_fs.h"
#include "gi_log.h"
#include "gi_standing.h"

#define STANDING_SAVE_EVERY_S 1.0

static char *standing_path(const gi_farm *f)
{
    size_t n = strlen(f->cfg.state_dir) + 16;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/standing", f->cfg.state_dir);
    return p;
}

/* Monotonic t (0: none) as epoch seconds, and back. */
static double to_wall(double t, double now, double wall)
{
    return t > 0 ? wall + (t - now) : 0;
}

static double to_mono(double t, double now, double wall)
{
    return t > 0 ? now + (t - wall) : 0;
}

static int host_worth_keeping(const gi_farm_host *h)
{
    return h->failures || h->losses || h->blocked_until > 0;
}

void gi_farm_standing_save(gi_farm *f)
{
    double now = gi_now(), wall = gi_farm_wallnow();
    f->standing_next = now + STANDING_SAVE_EVERY_S;
    if (!f->standing_dirty)
        return;
    gi_standing_host *hs = gi_xcalloc(f->host_count + 1, sizeof *hs);
    size_t nh = 0, nx = 0, xcap = 0;
    for (size_t i = 0; i < f->host_count; i++) {
        const gi_farm_host *h = f->hosts[i];
        if (!host_worth_keeping(h))
            continue;
        gi_standing_host *o = &hs[nh++];
        snprintf(o->name, sizeof o->name, "%s", h->name);
        o->failures = h->failures;
        o->own_failures = h->own_failures;
        o->consecutive_failures = h->consecutive_failures;
        o->streak_job = h->streak_job;
        o->streak_wide = h->streak_wide;
        o->losses = h->losses;
        o->consecutive_losses = h->consecutive_losses;
        o->blocked_until = h->blocked_until > now ? to_wall(h->blocked_until, now, wall) : 0;
        snprintf(o->last_error, sizeof o->last_error, "%s", h->last_error);
    }
    gi_standing_excl *xs = NULL;
    for (size_t i = 0; i < f->job_count; i++) {
        const gi_farm_job *j = f->jobs[i];
        for (size_t k = 0; k < j->excl_count; k++) {
            const gi_fj_exclusion *x = &j->excl[k];
            if (nx == xcap) {
                xcap = xcap ? 2 * xcap : 16;
                xs = gi_xrealloc(xs, xcap * sizeof *xs);
            }
            gi_standing_excl *o = &xs[nx++];
            memset(o, 0, sizeof *o);
            o->job_id = j->id;
            snprintf(o->host, sizeof o->host, "%s", x->host->name);
            o->streak = x->streak;
            o->times = x->times;
            o->until = to_wall(x->until, now, wall);
            /* Any monotonic time, even one before this boot, is a date. */
            o->last_failed = isfinite(x->last_failed) ? wall + (x->last_failed - now) : 0;
            snprintf(o->last_error, sizeof o->last_error, "%s", x->last_error);
        }
    }
    gi_buf b;
    gi_buf_init(&b);
    gi_standing_encode(hs, nh, xs, nx, &b);
    free(hs);
    free(xs);
    char *path = standing_path(f);
    gi_error err;
    if (gi_write_file_atomic(path, b.data, b.len, &err)) {
        if (!f->standing_unsaved) /* a full disk would say it every second */
            gi_warn("the workers' standing was not saved (tried again every %.0f s, said once): "
                    "%s", STANDING_SAVE_EVERY_S, err.msg);
        f->standing_unsaved = 1;
    } else {
        if (f->standing_unsaved)
            gi_info("the workers' standing is saved again");
        f->standing_unsaved = 0;
        f->standing_dirty = 0;
    }
    free(path);
    gi_buf_free(&b);
}

void gi_farm_standing_tick(gi_farm *f)
{
    if (f->standing_dirty && gi_now() >= f->standing_next)
        gi_farm_standing_save(f);
}

typedef struct loader {
    gi_farm *f;
    double now, wall;
    size_t hosts, excl;
} loader;

static void host_loaded(void *ctx, const gi_standing_host *s)
{
    loader *l = ctx;
    gi_farm_host *h = gi_farm_host_get(l->f, s->name);
    h->failures = s->failures;
    h->own_failures = s->own_failures;
    h->consecutive_failures = s->consecutive_failures;
    h->streak_job = s->streak_job;
    h->streak_wide = s->streak_wide;
    h->losses = s->losses;
    h->consecutive_losses = s->consecutive_losses;
    h->blocked_until = s->blocked_until > l->wall ? to_mono(s->blocked_until, l->now, l->wall) : 0;
    snprintf(h->last_error, sizeof h->last_error, "%s", s->last_error);
    l->hosts++;
}

static void excl_loaded(void *ctx, const gi_standing_excl *s)
{
    loader *l = ctx;
    gi_farm_job *j = gi_farm_job_find(l->f, s->job_id);
    if (!j)
        return; /* purged since */
    gi_fj_exclusion *x = gi_farm_job_exclusion(j, gi_farm_host_get(l->f, s->host));
    x->streak = s->streak;
    x->times = s->times;
    x->until = to_mono(s->until, l->now, l->wall);
    x->last_failed = s->last_failed > 0 ? l->now + (s->last_failed - l->wall) : -INFINITY;
    snprintf(x->last_error, sizeof x->last_error, "%.250s", s->last_error);
    l->excl++;
}

void gi_farm_standing_load(gi_farm *f)
{
    char *path = standing_path(f);
    f->standing_next = gi_now() + STANDING_SAVE_EVERY_S;
    if (access(path, F_OK) != 0) {
        free(path);
        return;
    }
    gi_buf b;
    gi_buf_init(&b);
    gi_error err;
    loader l = {f, gi_now(), gi_farm_wallnow(), 0, 0};
    gi_standing_sink sink = {host_loaded, excl_loaded, &l};
    int rc = gi_read_file(path, (size_t)64 << 20, &b, &err) ? -1
             : gi_standing_decode(b.data, b.len, path, &sink, &err);
    if (rc && !l.hosts && !l.excl)
        gi_warn("the workers' standing was not restored: %s", err.msg);
    else if (rc)
        gi_warn("the workers' standing was partly restored (%zu hosts, %zu exclusions): %s",
                l.hosts, l.excl, err.msg);
    else
        gi_info("the workers' standing restored: %zu hosts, %zu exclusions", l.hosts, l.excl);
    gi_buf_free(&b);
    free(path);
}
