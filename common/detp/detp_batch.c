/* detp_batch: an animation batch on disk as a base plus per-frame deltas
 * (see detp_batch.h). */
#include "detp_batch.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

enum { FILE_BASE, FILE_DELTA, FILE_GRID };

static char *file_name(const char *dir, uint32_t batch, uint32_t frame, int kind)
{
    static const char *const ext[] = {"base", "delta", "grid"};
    size_t n = strlen(dir) + 64;
    char *p = gi_xmalloc(n);
    snprintf(p, n, "%s/b%u.f%u.%s", dir, batch, frame, ext[kind]);
    return p;
}

static int exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

/* Maps one file of the batch, checking that it is the one asked for. */
static int map_file(const char *dir, const detp_batch *b, uint32_t frame, int delta,
                    gi_detp_store_mapping *m, gi_error *err)
{
    char *path = file_name(dir, b->batch, frame, delta ? FILE_DELTA : FILE_BASE);
    int rc = gi_detp_store_map(path, m, err);
    if (rc == 1) {
        const gi_detp_store_header *h = &m->header;
        if (h->p0 != b->p0 || h->p1 != b->p1 || h->frame != frame ||
            h->kind != (uint32_t)(delta ? GI_DETP_STORE_DELTA : GI_DETP_STORE_BASE)) {
            gi_detp_store_unmap(m);
            gi_fail(err, GI_EPROTO, "%s: not this batch's file", path);
            rc = 0;
        }
    }
    free(path);
    return rc;
}

/* A delta's runs in photon order, as a cursor of the merge below. */
typedef struct delta_cursor {
    const gi_detp_segment *seg;
    size_t i, n;  /* the next run starts at seg[i] */
    uint32_t age; /* 0: the newest delta */
} delta_cursor;

static int cursor_before(const delta_cursor *x, const delta_cursor *y)
{
    uint64_t px = x->seg[x->i].photon, py = y->seg[y->i].photon;
    return px != py ? px < py : x->age < y->age;
}

static void sift_down(delta_cursor *h, size_t n, size_t k)
{
    for (;;) {
        size_t c = 2 * k + 1;
        if (c >= n)
            return;
        if (c + 1 < n && cursor_before(&h[c + 1], &h[c]))
            c++;
        if (!cursor_before(&h[c], &h[k]))
            return;
        delta_cursor t = h[k];
        h[k] = h[c];
        h[c] = t;
        k = c;
    }
}

/* The newest run of each path the deltas hold, by photon: a merge of the
 * deltas (each photon-ordered), the newest first among equal photons. */
static void build_overrides(detp_batch *b)
{
    size_t total = 0, n = 0;
    delta_cursor *h = gi_xmalloc((b->delta_count + 1) * sizeof *h);
    for (uint32_t d = 0; d < b->delta_count; d++) {
        total += b->deltas[d].count; /* an upper bound on the runs */
        if (b->deltas[d].count)
            h[n++] = (delta_cursor){b->deltas[d].seg, 0, b->deltas[d].count,
                                    b->delta_count - 1 - d};
    }
    for (size_t k = n / 2; k-- > 0;)
        sift_down(h, n, k);
    b->over = gi_xmalloc((total + 1) * sizeof *b->over);
    b->over_count = 0;
    while (n) {
        delta_cursor *c = &h[0];
        size_t j = c->i + 1;
        while (j < c->n && c->seg[j].photon == c->seg[c->i].photon)
            j++;
        uint64_t photon = c->seg[c->i].photon;
        if (b->over_count == 0 || b->over[b->over_count - 1].photon != photon)
            b->over[b->over_count++] = (detp_path){photon, &c->seg[c->i], (uint32_t)(j - c->i)};
        c->i = j;
        if (j == c->n)
            h[0] = h[--n];
        sift_down(h, n, 0);
    }
    free(h);
}

/* The overrides after one more delta d (the newest): a merge of two
 * photon-ordered lists, d's run winning. */
static void merge_delta(detp_batch *b, const gi_detp_store_mapping *d)
{
    detp_path *out = gi_xmalloc((b->over_count + d->count + 1) * sizeof *out);
    size_t n = 0, o = 0, i = 0;
    while (i < d->count) {
        uint64_t photon = d->seg[i].photon;
        size_t j = i + 1;
        while (j < d->count && d->seg[j].photon == photon)
            j++;
        while (o < b->over_count && b->over[o].photon < photon)
            out[n++] = b->over[o++];
        if (o < b->over_count && b->over[o].photon == photon)
            o++;
        out[n++] = (detp_path){photon, &d->seg[i], (uint32_t)(j - i)};
        i = j;
    }
    while (o < b->over_count)
        out[n++] = b->over[o++];
    free(b->over);
    b->over = out;
    b->over_count = n;
}

/* The base's grid, rebuilt if it is missing or stale. */
static int map_grid(const char *dir, const detp_grid_spec *spec, detp_batch *b, gi_error *err)
{
    char *path = file_name(dir, b->batch, b->base_frame, FILE_GRID);
    uint32_t crc = b->base.header.records_crc;
    int rc = detp_grid_map(path, spec, b->p0, b->p1, b->base_frame, b->base.count, crc, &b->grid,
                           err);
    if (rc == 0) {
        gi_detp_segments view = gi_detp_store_view(&b->base);
        rc = detp_grid_write(path, spec, b->p0, b->p1, b->base_frame, &view, crc, err);
        if (rc == 0)
            rc = detp_grid_map(path, spec, b->p0, b->p1, b->base_frame, b->base.count, crc,
                               &b->grid, err);
        if (rc == 0)
            rc = gi_fail(err, GI_EIO, "%s: rewritten but unreadable", path);
    }
    free(path);
    return rc;
}

int detp_batch_open(const char *dir, const detp_grid_spec *spec, uint32_t batch, uint64_t p0,
                    uint64_t p1, uint32_t frame, detp_batch *b, gi_error *err)
{
    memset(b, 0, sizeof *b);
    b->batch = batch;
    b->frame = frame;
    b->p0 = p0;
    b->p1 = p1;
    /* The newest base at or before the frame. */
    uint32_t g = frame;
    for (;;) {
        char *path = file_name(dir, batch, g, FILE_BASE);
        int found = exists(path);
        free(path);
        if (found)
            break;
        char *dpath = file_name(dir, batch, g, FILE_DELTA);
        int has_delta = exists(dpath);
        free(dpath);
        if (!has_delta || g == 0) {
            gi_fail(err, GI_EIO, "batch %u: no stored state for frame %u", batch, g);
            return 0;
        }
        g--;
    }
    b->base_frame = g;
    int rc = map_file(dir, b, g, 0, &b->base, err);
    if (rc != 1)
        return rc;
    rc = map_grid(dir, spec, b, err);
    if (rc != 1) {
        detp_batch_close(b);
        return rc;
    }
    b->deltas = gi_xcalloc((size_t)(frame - g) + 1, sizeof *b->deltas);
    for (uint32_t f = g + 1; f <= frame; f++) {
        rc = map_file(dir, b, f, 1, &b->deltas[b->delta_count], err);
        if (rc != 1) {
            detp_batch_close(b);
            return rc;
        }
        b->delta_segments += b->deltas[b->delta_count].count;
        b->delta_count++;
    }
    build_overrides(b);
    return 1;
}

int detp_batch_advance(const char *dir, const detp_grid_spec *spec, detp_batch *b,
                       uint32_t frame, int as_base, gi_error *err)
{
    if (as_base || frame != b->frame + 1) {
        uint32_t batch = b->batch;
        uint64_t p0 = b->p0, p1 = b->p1;
        detp_batch_close(b);
        return detp_batch_open(dir, spec, batch, p0, p1, frame, b, err);
    }
    detp_batch_forget_crossings(b); /* they were the previous delta's */
    b->deltas = gi_xrealloc(b->deltas, ((size_t)b->delta_count + 1) * sizeof *b->deltas);
    gi_detp_store_mapping *d = &b->deltas[b->delta_count];
    int rc = map_file(dir, b, frame, 1, d, err);
    if (rc != 1) {
        detp_batch_close(b);
        return rc;
    }
    b->delta_count++;
    b->delta_segments += d->count;
    b->frame = frame;
    merge_delta(b, d);
    return 1;
}

/* The file at the path is still the one mapped. */
static int still_there(const char *dir, const detp_batch *b, uint32_t frame, int kind,
                       const gi_detp_store_mapping *m)
{
    char *path = file_name(dir, b->batch, frame, kind);
    struct stat sb;
    int ok = stat(path, &sb) == 0 && (uint64_t)sb.st_dev == m->dev &&
             (uint64_t)sb.st_ino == m->ino;
    free(path);
    return ok;
}

int detp_batch_files_present(const char *dir, const detp_batch *b)
{
    if (!still_there(dir, b, b->base_frame, FILE_BASE, &b->base))
        return 0;
    return b->delta_count == 0 ||
           still_there(dir, b, b->frame, FILE_DELTA, &b->deltas[b->delta_count - 1]);
}

void detp_batch_release_pages(const detp_batch *b)
{
    /* Read-only file mappings: the pages stay in the page cache, only this
     * process's references to them go. */
    if (b->base.base)
        madvise(b->base.base, b->base.len, MADV_DONTNEED);
    if (b->grid.map)
        madvise(b->grid.map, b->grid.len, MADV_DONTNEED);
}

void detp_batch_close(detp_batch *b)
{
    gi_detp_store_unmap(&b->base);
    detp_grid_unmap(&b->grid);
    for (uint32_t d = 0; d < b->delta_count; d++)
        gi_detp_store_unmap(&b->deltas[d]);
    free(b->deltas);
    free(b->over);
    detp_batch_forget_crossings(b);
    memset(b, 0, sizeof *b);
}

void detp_batch_forget_crossings(detp_batch *b)
{
    free(b->cross_off);
    free(b->cross_ids);
    free(b->cross_known);
    b->cross_off = b->cross_ids = NULL;
    b->cross_known = NULL;
}

int detp_batch_next(detp_batch_iter *it, detp_path *run)
{
    const detp_batch *b = it->b;
    const gi_detp_segment *seg = b->base.seg;
    size_t n = b->base.count;
    if (it->i >= n)
        return 0;
    uint64_t photon = seg[it->i].photon;
    size_t j = it->i + 1;
    while (j < n && seg[j].photon == photon)
        j++;
    while (it->o < b->over_count && b->over[it->o].photon < photon)
        it->o++; /* cannot happen for files we wrote: every path is in the base */
    if (it->o < b->over_count && b->over[it->o].photon == photon)
        *run = b->over[it->o++];
    else
        *run = (detp_path){photon, &seg[it->i], (uint32_t)(j - it->i)};
    it->i = j;
    return 1;
}

void detp_batch_materialize(const detp_batch *prev, const gi_detp_segments *changed,
                            gi_detp_segments *out)
{
    out->count = 0;
    detp_batch_iter it;
    detp_batch_iter_init(&it, prev);
    detp_path r;
    size_t c = 0;
    while (detp_batch_next(&it, &r)) {
        while (c < changed->count && changed->v[c].photon < r.photon)
            c++;
        if (c < changed->count && changed->v[c].photon == r.photon) {
            while (c < changed->count && changed->v[c].photon == r.photon)
                *gi_detp_segments_push(out) = changed->v[c++];
        } else {
            for (uint32_t k = 0; k < r.count; k++)
                *gi_detp_segments_push(out) = r.seg[k];
        }
    }
}

/* Some segment of the run comes within the sphere over the part the grid
 * would list (detp_grid_reach). */
static int run_near(const detp_path *run, gi_detp_mobile_pose s)
{
    for (uint32_t k = 0; k < run->count; k++) {
        const gi_detp_segment *g = &run->seg[k];
        if (gi_detp_ray_may_meet(g->org, g->dir, 0.0f, detp_grid_reach(g), s))
            return 1;
    }
    return 0;
}

void detp_batch_mark_near(const detp_batch *b, gi_detp_mobile_pose s0, gi_detp_mobile_pose s1,
                          uint8_t *mark)
{
    detp_grid_mark(&b->grid, s0.c, s0.r, mark);
    detp_grid_mark(&b->grid, s1.c, s1.r, mark);
    /* A path a delta changed is as near as its newest run is (the grid
     * knows its base run only): tested here, segment by segment. */
    for (size_t i = 0; i < b->over_count; i++)
        mark[b->over[i].photon - b->p0] = run_near(&b->over[i], s0) || run_near(&b->over[i], s1);
}

/* A marked path of the base, its run not yet looked up (no path is that
 * long: GI_DETP_MAX_PATH). */
#define BASE_RUN UINT32_MAX

size_t detp_batch_marked(const detp_batch *b, const uint8_t *mark, detp_path **runs,
                         size_t *cap)
{
    size_t n = 0, o = 0, np = (size_t)(b->p1 - b->p0);
    for (size_t i = 0; i < np; i++) {
        /* A few paths in a hundred are marked: eight unmarked at once. */
        uint64_t eight;
        if ((i & 7) == 0 && i + 8 <= np && (memcpy(&eight, mark + i, 8), eight == 0)) {
            i += 7;
            continue;
        }
        if (!mark[i])
            continue;
        if (n == *cap) {
            *cap = *cap ? 2 * *cap : 1024;
            *runs = gi_xrealloc(*runs, *cap * sizeof **runs);
        }
        /* Both in photon order: a cursor, not a search, finds the override.
         * A base path's run is filled in below. */
        uint64_t photon = b->p0 + i;
        while (o < b->over_count && b->over[o].photon < photon)
            o++;
        if (o < b->over_count && b->over[o].photon == photon)
            (*runs)[n++] = b->over[o];
        else
            (*runs)[n++] = (detp_path){photon, NULL, BASE_RUN};
    }
    /* The marked paths lie scattered over the base and its grid: each is
     * a cache miss or two. Asked for well ahead of use they overlap; the
     * frame's test then finds the paths' segments in cache. */
    const uint32_t *ps = b->grid.path_start;
    enum { AHEAD = 16 };
    for (size_t k = 0; k < n + AHEAD; k++) {
        if (k + AHEAD < n && (*runs)[k + AHEAD].count == BASE_RUN)
            __builtin_prefetch(&ps[(*runs)[k + AHEAD].photon - b->p0]);
        if (k < n) {
            detp_path *r = &(*runs)[k];
            if (r->count == BASE_RUN) {
                size_t i = (size_t)(r->photon - b->p0);
                r->seg = b->base.seg + ps[i];
                r->count = ps[i + 1] - ps[i];
            }
            __builtin_prefetch(r->seg);
            __builtin_prefetch(r->seg + 1);
        }
    }
    return n;
}

uint64_t detp_batch_count(const detp_batch *b)
{
    uint64_t n = b->base.count;
    for (size_t k = 0; k < b->over_count; k++) {
        uint32_t i = (uint32_t)(b->over[k].photon - b->p0);
        n = n - (b->grid.path_start[i + 1] - b->grid.path_start[i]) + b->over[k].count;
    }
    return n;
}

static int write_file(const char *dir, const detp_grid_spec *spec, uint32_t batch, uint64_t p0,
                      uint64_t p1, uint32_t frame, int delta, uint32_t prev_base,
                      const gi_detp_segments *s, gi_error *err)
{
    gi_detp_store_header h;
    memset(&h, 0, sizeof h);
    h.p0 = p0;
    h.p1 = p1;
    h.frame = frame;
    h.kind = delta ? GI_DETP_STORE_DELTA : GI_DETP_STORE_BASE;
    h.prev_base = prev_base;
    char *path = file_name(dir, batch, frame, delta ? FILE_DELTA : FILE_BASE);
    int rc = gi_detp_store_write(path, &h, s, err);
    free(path);
    if (rc == 0 && !delta) {
        char *gpath = file_name(dir, batch, frame, FILE_GRID);
        rc = detp_grid_write(gpath, spec, p0, p1, frame, s, gi_detp_store_records_crc(s), err);
        free(gpath);
    }
    return rc;
}

int detp_batch_write_base(const char *dir, const detp_grid_spec *spec, uint32_t batch,
                          uint64_t p0, uint64_t p1, uint32_t frame, const gi_detp_segments *s,
                          gi_error *err)
{
    return write_file(dir, spec, batch, p0, p1, frame, 0, GI_DETP_STORE_NO_BASE, s, err);
}

static void remove_file(const char *dir, uint32_t batch, uint32_t frame, int kind)
{
    char *path = file_name(dir, batch, frame, kind);
    unlink(path);
    free(path);
}

int detp_batch_write_frame(const char *dir, const detp_grid_spec *spec, const detp_batch *prev,
                           uint32_t frame, const gi_detp_segments *changed, gi_error *err)
{
    int rc, base = 0;
    /* A base is rewritten once its deltas would hold more segments than it
     * does, or number more than DETP_BATCH_MAX_DELTAS. Rewriting sooner
     * costs more than it saves: with a quarter of the base as the limit,
     * the 10% sphere of bench/detp_anim.sh (24 frames) spent 0.13 s of its
     * 0.40 s per frame on rewrites; with the whole base, 0.03 s of 0.31 s
     * (reading the longer deltas costs 0.01 s more). The count bounds the
     * files a frame opens when the mobile is small. */
    if (prev->delta_segments + changed->count > prev->base.count ||
        prev->delta_count + 1 > DETP_BATCH_MAX_DELTAS) {
        /* A new base: the batch at this frame, whole. */
        gi_detp_segments all;
        gi_detp_segments_init(&all);
        detp_batch_materialize(prev, changed, &all);
        rc = write_file(dir, spec, prev->batch, prev->p0, prev->p1, frame, 0,
                        prev->base_frame, &all, err);
        gi_detp_segments_free(&all);
        base = 1;
    } else {
        rc = write_file(dir, spec, prev->batch, prev->p0, prev->p1, frame, 1, 0, changed, err);
    }
    /* prev stands on a base only: the base before it and the deltas up to
     * it are no longer needed, even by a retry of this frame. */
    if (rc == 0 && prev->delta_count == 0 &&
        prev->base.header.prev_base != GI_DETP_STORE_NO_BASE) {
        uint32_t k = prev->base.header.prev_base;
        remove_file(dir, prev->batch, k, FILE_BASE);
        remove_file(dir, prev->batch, k, FILE_GRID);
        for (uint32_t f = k + 1; f <= prev->base_frame; f++)
            remove_file(dir, prev->batch, f, FILE_DELTA);
    }
    return rc ? rc : base;
}

void detp_batch_remove(const char *dir, uint32_t batch)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    char prefix[32];
    int n = snprintf(prefix, sizeof prefix, "b%u.", batch);
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strncmp(e->d_name, prefix, (size_t)n) == 0) {
            size_t len = strlen(dir) + strlen(e->d_name) + 2;
            char *p = gi_xmalloc(len);
            snprintf(p, len, "%s/%s", dir, e->d_name);
            unlink(p);
            free(p);
        }
    closedir(d);
}
