/* The animation batch on disk (detp_batch.c): a base plus per-frame deltas
 * reads back as the batch it stands for, frame after frame, through
 * rewrites of the base; old files go; a missing or foreign file reads as
 * missing. Synthetic paths: the store does not care where they came from. */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "detp/detp_batch.h"
#include "detp/detp_batch_shelf.h"
#include "detp/detp_sphere.h"
#include "gi_checked_files.h"
#include "gi_rng.h"
#include "gi_test.h"
#include "test_helpers.h"

#define P0 1000u
#define PATHS 300u

/* Path `photon`'s run as of `version` (1 to 4 segments). */
static void make_run(uint64_t photon, uint32_t version, gi_detp_segments *out)
{
    gi_rng r;
    gi_rng_init(&r, version, photon, 0);
    uint32_t n = 1 + gi_rng_u32(&r) % 4;
    for (uint32_t b = 0; b < n; b++) {
        gi_detp_segment *g = gi_detp_segments_push(out);
        memset(g, 0, sizeof *g);
        g->org = gi_v3((float)photon, (float)version, (float)b);
        g->dir = gi_v3(0, 0, 1);
        g->t_hit = g->t_second = g->t_end = 1.0f + (float)b;
        g->energy = gi_v3(1, 2, 3);
        g->hit_tri = version;
        g->bounce = b;
        g->photon = photon;
    }
}

static void whole(const uint32_t *version, gi_detp_segments *out)
{
    out->count = 0;
    for (uint32_t i = 0; i < PATHS; i++)
        make_run(P0 + i, version[i], out);
}

static int same_segments(const gi_detp_segments *a, const gi_detp_segments *b)
{
    return a->count == b->count && memcmp(a->v, b->v, a->count * sizeof *a->v) == 0;
}

static int files_in(const char *dir)
{
    int n = 0;
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        n += e->d_name[0] != '.';
    if (d)
        closedir(d);
    return n;
}

/* A fresh directory for batch files under the test's temporary one, and
 * the grid spec the tests store with. */
static void batch_dir(const char *name, char *dir, size_t len, detp_grid_spec *spec)
{
    snprintf(dir, len, "%s/%s", gi_test_tmpdir(), name);
    mkdir(dir, 0755);
    detp_grid_spec_make(gi_v3(990, -10, -10), gi_v3(1310, 50, 20), 10.0f, spec);
}

/* detp_batch_mark_near on b (the batch as `paths`, path-ordered): every
 * path with a segment that enters either sphere is marked; a path a delta
 * changed is marked only if its newest run comes near (counted into
 * *changed_unmarked when it does not). */
static void check_marks(const detp_batch *b, const gi_detp_segments *paths, uint32_t f,
                        uint32_t *changed_unmarked)
{
    gi_rng r;
    gi_rng_init(&r, 7, f, 1);
    uint8_t mark[PATHS];
    for (int q = 0; q < 20; q++) {
        gi_detp_mobile_pose s[2];
        for (int k = 0; k < 2; k++) {
            s[k].c = gi_v3(1000 + 300 * gi_rng_float(&r), 40 * gi_rng_float(&r),
                           5 * gi_rng_float(&r));
            s[k].r = 1 + 9 * gi_rng_float(&r);
        }
        memset(mark, 0, sizeof mark);
        detp_batch_mark_near(b, (gi_detp_mobile_pose){s[0].c, s[0].r + 0.05f},
                             (gi_detp_mobile_pose){s[1].c, s[1].r + 0.05f}, mark);
        uint8_t near[PATHS] = {0};
        for (size_t k = 0; k < paths->count; k++)
            for (int j = 0; j < 2; j++)
                near[paths->v[k].photon - P0] |=
                    gi_detp_segment_meets_sphere(&paths->v[k], s[j].c, s[j].r * s[j].r);
        for (size_t o = 0; o < b->over_count; o++) {
            uint64_t i = b->over[o].photon - P0;
            *changed_unmarked += !near[i] && !mark[i];
        }
        for (uint32_t i = 0; i < PATHS; i++)
            GI_CHECK_MSG(!near[i] || mark[i], "frame %u: path %u near a sphere, not marked", f,
                         P0 + i);
    }
}

GI_TEST(test_detp_batch_base_and_deltas_over_many_frames)
{
    char dir[512];
    detp_grid_spec spec;
    batch_dir("batches", dir, sizeof dir, &spec);
    gi_error err;
    uint32_t version[PATHS] = {0};
    gi_detp_segments expect, got, changed;
    gi_detp_segments_init(&expect);
    gi_detp_segments_init(&got);
    gi_detp_segments_init(&changed);
    whole(version, &expect);
    GI_REQUIRE_OK(detp_batch_write_base(dir, &spec, 7, P0, P0 + PATHS, 0, &expect, &err));
    /* Frames 1-100 change one path each: the deltas stay far smaller than
     * the base, and their count makes the rewrites. Frames 101-130 change
     * a third of the paths each: their size does. */
    int max_files = 0;
    uint32_t base_at_100 = 0, late_bases = 0, advanced_bases = 0, near_changed_unmarked = 0;
    /* `kept` is opened once and then only advanced frame to frame
     * (detp_batch_advance); it must read like the batch opened afresh. */
    detp_batch kept;
    GI_REQUIRE(detp_batch_open(dir, &spec, 7, P0, P0 + PATHS, 0, &kept, &err) == 1);
    for (uint32_t f = 1; f <= 130; f++) {
        detp_batch prev;
        GI_REQUIRE(detp_batch_open(dir, &spec, 7, P0, P0 + PATHS, f - 1, &prev, &err) == 1);
        detp_batch_materialize(&prev, &changed, &got); /* changed is empty here */
        GI_CHECK_MSG(same_segments(&got, &expect), "frame %u reads back wrong", f - 1);
        GI_CHECK(detp_batch_count(&prev) == expect.count);
        detp_batch_materialize(&kept, &changed, &got);
        GI_CHECK_MSG(same_segments(&got, &expect) && kept.frame == f - 1 &&
                         kept.base_frame == prev.base_frame &&
                         kept.over_count == prev.over_count &&
                         detp_batch_count(&kept) == expect.count,
                     "frame %u: the batch kept open reads back wrong", f - 1);
        changed.count = 0;
        if (f % 10 == 0)
            check_marks(&kept, &expect, f, &near_changed_unmarked);
        GI_CHECK_MSG(prev.delta_count <= DETP_BATCH_MAX_DELTAS, "frame %u: %u deltas", f - 1,
                     prev.delta_count);
        if (f - 1 == 100)
            base_at_100 = prev.base_frame;
        late_bases += f - 1 > 100 && prev.base_frame == f - 1;
        gi_rng r;
        gi_rng_init(&r, 99, f, 0);
        uint32_t k = f <= 100 ? 1 : PATHS / 3;
        for (uint32_t i = 0; i < PATHS; i++)
            if (gi_rng_u32(&r) % PATHS < k) {
                version[i] = f;
                make_run(P0 + i, f, &changed);
            }
        int as_base = detp_batch_write_frame(dir, &spec, &prev, f, &changed, &err);
        GI_REQUIRE(as_base == 0 || as_base == 1);
        advanced_bases += (uint32_t)as_base;
        GI_REQUIRE(detp_batch_advance(dir, &spec, &kept, f, as_base, &err) == 1);
        detp_batch_close(&prev);
        whole(version, &expect);
        int n = files_in(dir);
        max_files = n > max_files ? n : max_files;
    }
    detp_batch last;
    GI_REQUIRE(detp_batch_open(dir, &spec, 7, P0, P0 + PATHS, 130, &last, &err) == 1);
    gi_detp_segments none = {NULL, 0, 0};
    detp_batch_materialize(&last, &none, &got);
    GI_CHECK(same_segments(&got, &expect));
    GI_CHECK_MSG(base_at_100 > 0, "many small deltas never made a new base");
    GI_CHECK(advanced_bases >= 5 && kept.frame == 130);
    detp_batch_close(&kept);
    /* ~250 segments a frame against a base of ~750: a new base every few. */
    GI_CHECK_MSG(late_bases >= 5, "large deltas made %u new bases in 30 frames", late_bases);
    GI_CHECK_MSG(near_changed_unmarked > 0, "every changed path was marked, near or not");
    const char *newest = last.base_frame == 130 ? "base" : "delta";
    detp_batch_close(&last);
    /* Old bases and deltas go: at most two bases' worth of files. */
    GI_CHECK_MSG(max_files <= 2 * (DETP_BATCH_MAX_DELTAS + 2), "%d files at once", max_files);

    /* A missing file (frame 130's delta or base): frame 130 cannot be read
     * (regenerate). */
    char path[600];
    snprintf(path, sizeof path, "%s/b7.f130.%s", dir, newest);
    GI_CHECK(remove(path) == 0);
    GI_CHECK(detp_batch_open(dir, &spec, 7, P0, P0 + PATHS, 130, &last, &err) == 0);
    /* Another batch's range under this batch's name is not this batch. */
    GI_CHECK(detp_batch_open(dir, &spec, 7, P0, P0 + PATHS + 1, 129, &last, &err) == 0);
    detp_batch_remove(dir, 7);
    GI_CHECK(files_in(dir) == 0);
    gi_detp_segments_free(&expect);
    gi_detp_segments_free(&got);
    gi_detp_segments_free(&changed);
}

/* The shelf hands a batch back only at the frame it was kept at and while
 * its files are the ones mapped, keeps one entry per batch, and past its
 * budget keeps the batches still in use. */
GI_TEST(test_detp_batch_shelf_takes_puts_and_evicts)
{
    char dir[512];
    detp_grid_spec spec;
    batch_dir("shelf", dir, sizeof dir, &spec);
    gi_error err;
    uint32_t version[PATHS] = {0};
    gi_detp_segments segs;
    gi_detp_segments_init(&segs);
    whole(version, &segs);
    for (uint32_t batch = 0; batch < 3; batch++)
        GI_REQUIRE_OK(detp_batch_write_base(dir, &spec, batch, P0, P0 + PATHS, 4, &segs, &err));
    detp_batch_shelf shelf = {NULL, 0, 0, 0, (size_t)1 << 30};
    detp_batch b;
    for (uint32_t batch = 0; batch < 3; batch++) {
        GI_REQUIRE(detp_batch_open(dir, &spec, batch, P0, P0 + PATHS, 4, &b, &err) == 1);
        detp_batch_shelf_put(&shelf, &b);
        GI_CHECK(b.base.seg == NULL); /* the shelf owns it now */
    }
    GI_CHECK(shelf.count == 3);
    /* Another frame or photon range: not handed out, and closed. */
    GI_CHECK(detp_batch_shelf_take(&shelf, dir, 1, P0, P0 + PATHS, 5, &b) == 0 && shelf.count == 2);
    GI_CHECK(detp_batch_shelf_take(&shelf, dir, 2, P0, P0 + PATHS + 1, 4, &b) == 0 &&
             shelf.count == 1);
    GI_REQUIRE(detp_batch_shelf_take(&shelf, dir, 0, P0, P0 + PATHS, 4, &b) == 1);
    GI_CHECK(shelf.count == 0 && shelf.bytes == 0 && b.batch == 0 && b.frame == 4 &&
             detp_batch_count(&b) == segs.count);
    /* Put twice: one entry. Then a budget of one batch: a batch still in
     * use stays and the newcomer is closed; one that missed a frame makes
     * room. */
    detp_batch again;
    GI_REQUIRE(detp_batch_open(dir, &spec, 0, P0, P0 + PATHS, 4, &again, &err) == 1);
    detp_batch_shelf_put(&shelf, &b);
    detp_batch_shelf_put(&shelf, &again);
    GI_CHECK(shelf.count == 1);
    shelf.budget = shelf.bytes;
    GI_REQUIRE(detp_batch_open(dir, &spec, 1, P0, P0 + PATHS, 4, &b, &err) == 1);
    GI_CHECK(!detp_batch_shelf_fits(&shelf, &b));
    detp_batch_shelf_put(&shelf, &b);
    GI_CHECK(shelf.count == 1 && shelf.b[0].batch == 0 && b.base.seg == NULL);
    GI_REQUIRE_OK(detp_batch_write_base(dir, &spec, 1, P0, P0 + PATHS, 6, &segs, &err));
    GI_REQUIRE(detp_batch_open(dir, &spec, 1, P0, P0 + PATHS, 6, &b, &err) == 1);
    GI_CHECK(detp_batch_shelf_fits(&shelf, &b));
    detp_batch_shelf_put(&shelf, &b); /* batch 0, kept at 4, missed frame 5 */
    GI_CHECK(shelf.count == 1 && shelf.b[0].batch == 1 && shelf.b[0].frame == 6);
    detp_batch_shelf_drop(&shelf, 1);
    GI_CHECK(shelf.count == 0 && shelf.bytes == 0);
    /* A batch whose base was rewritten (a new inode) or removed since it
     * was put is not handed out. */
    GI_REQUIRE(detp_batch_open(dir, &spec, 2, P0, P0 + PATHS, 4, &b, &err) == 1);
    detp_batch_shelf_put(&shelf, &b);
    GI_REQUIRE_OK(detp_batch_write_base(dir, &spec, 2, P0, P0 + PATHS, 4, &segs, &err));
    GI_CHECK(detp_batch_shelf_take(&shelf, dir, 2, P0, P0 + PATHS, 4, &b) == 0);
    GI_REQUIRE(detp_batch_open(dir, &spec, 2, P0, P0 + PATHS, 4, &b, &err) == 1);
    detp_batch_shelf_put(&shelf, &b);
    GI_CHECK(detp_batch_shelf_take(&shelf, dir, 2, P0, P0 + PATHS, 4, &b) == 1);
    detp_batch_shelf_put(&shelf, &b);
    detp_batch_remove(dir, 2);
    GI_CHECK(detp_batch_shelf_take(&shelf, dir, 2, P0, P0 + PATHS, 4, &b) == 0);
    GI_CHECK(shelf.count == 0);
    detp_batch_shelf_free(&shelf);
    for (uint32_t batch = 0; batch < 3; batch++)
        detp_batch_remove(dir, batch);
    gi_detp_segments_free(&segs);
}

/* The grid lists, for a sphere, every path with a segment that enters it
 * (over its extent: up to t_second, or to the grid's edge if it escapes or
 * nothing lies behind its hit). */
GI_TEST(test_detp_grid_lists_every_path_near_a_sphere)
{
    char path[512];
    snprintf(path, sizeof path, "%s/g.grid", gi_test_tmpdir());
    gi_detp_segments s;
    gi_detp_segments_init(&s);
    gi_rng r;
    gi_rng_init(&r, 5, 0, 0);
    const uint64_t p0 = 50, n = 2000;
    for (uint64_t ph = p0; ph < p0 + n; ph++) {
        uint32_t k = 1 + gi_rng_u32(&r) % 3;
        for (uint32_t b = 0; b < k; b++) {
            gi_detp_segment *g = gi_detp_segments_push(&s);
            memset(g, 0, sizeof *g);
            g->org = gi_v3(gi_rng_float(&r) * 100, gi_rng_float(&r) * 100, gi_rng_float(&r) * 100);
            g->dir = gi_test_random_dir(&r);
            float u = gi_rng_float(&r);
            g->t_hit = u < 0.1f ? INFINITY : 5 + 80 * u;
            g->t_second = u < 0.1f ? INFINITY : g->t_hit + 30 * gi_rng_float(&r);
            if (u > 0.85f) { /* a hit with nothing behind: rule 1 extends it without end */
                g->t_hit = 2 + 10 * gi_rng_float(&r);
                g->t_second = INFINITY;
            }
            g->t_end = g->t_second;
            g->bounce = b;
            g->photon = ph;
        }
    }
    detp_grid_spec spec;
    detp_grid_spec_make(gi_v3(20, 20, 20), gi_v3(80, 80, 80), 7.0f, &spec);
    gi_error err;
    GI_REQUIRE_OK(detp_grid_write(path, &spec, p0, p0 + n, 3, &s, 77, &err));
    detp_grid g;
    GI_REQUIRE(detp_grid_map(path, &spec, p0, p0 + n, 3, s.count, 77, &g, &err) == 1);
    GI_CHECK(detp_grid_map(path, &spec, p0, p0 + n, 4, s.count, 77, &g, &err) == 0 ||
             (detp_grid_unmap(&g), 0));
    GI_CHECK(detp_grid_map(path, &spec, p0, p0 + n, 3, s.count, 78, &g, &err) == 0 ||
             (detp_grid_unmap(&g), 0));
    GI_REQUIRE(detp_grid_map(path, &spec, p0, p0 + n, 3, s.count, 77, &g, &err) == 1);
    uint8_t *mark = calloc(n, 1);
    for (int q = 0; q < 400; q++) {
        /* Spheres inside the grid's box, as the mobile's always are. */
        gi_vec3 c = gi_v3(32 + 36 * gi_rng_float(&r), 32 + 36 * gi_rng_float(&r),
                          32 + 36 * gi_rng_float(&r));
        float rad = 1 + 8 * gi_rng_float(&r);
        memset(mark, 0, n);
        /* With a margin, as the worker queries (rounding at cell
         * boundaries stays far below it). */
        float m = rad + 0.05f;
        detp_grid_mark(&g, c, m, mark);
        uint32_t listed = 0, near = 0;
        for (uint64_t i = 0; i < n; i++)
            listed += mark[i];
        for (size_t k = 0; k < s.count; k++) {
            gi_detp_segment x = s.v[k];
            x.t_end = isfinite(x.t_second) ? x.t_second : INFINITY;
            if (gi_detp_segment_meets_sphere(&x, c, rad * rad)) {
                near++;
                GI_CHECK_MSG(mark[x.photon - p0], "query %d: photon %llu near but not listed", q,
                             (unsigned long long)x.photon);
            }
        }
        /* A superset, but a useful one: far from every path. */
        GI_CHECK_MSG(listed < n / 2, "query %d lists %u of %llu paths", q, listed,
                     (unsigned long long)n);
        (void)near;
    }
    free(mark);
    detp_grid_unmap(&g);
    gi_detp_segments_free(&s);
}

/* The files a process has checked (gi_checked_files.c): all of them are
 * remembered, however many (a frame opens a base, a grid and up to 64
 * deltas per batch); a change of size, time or header CRC, or a new file
 * on a reused inode, is not taken for the checked one. */
GI_TEST(test_detp_checked_files_remember_many_and_see_changes)
{
    enum { N = 3000 };
    static struct stat st[N];
    gi_file_forget_checked();
    for (uint32_t i = 0; i < N; i++) {
        memset(&st[i], 0, sizeof st[i]);
        st[i].st_dev = 3 + i % 2;
        st[i].st_ino = 1000 + 7 * (ino_t)i;
        st[i].st_size = 64 + i;
        st[i].st_mtim.tv_sec = 1700000000 + i;
        st[i].st_mtim.tv_nsec = i;
        gi_file_note_checked(&st[i], i);
    }
    uint32_t missed = 0;
    for (uint32_t i = 0; i < N; i++)
        missed += !gi_file_was_checked(&st[i], i);
    GI_CHECK_MSG(missed == 0, "%u of %u checked files forgotten", missed, N);
    struct stat s = st[5];
    s.st_size++;
    GI_CHECK(!gi_file_was_checked(&s, 5));
    s = st[5];
    s.st_mtim.tv_nsec++;
    GI_CHECK(!gi_file_was_checked(&s, 5));
    GI_CHECK(!gi_file_was_checked(&st[5], 6));
    s = st[5];
    s.st_dev = 9;
    GI_CHECK(!gi_file_was_checked(&s, 5));
    /* Inode 5 reused by another file. */
    s = st[5];
    s.st_size = 12345;
    gi_file_note_checked(&s, 77);
    GI_CHECK(gi_file_was_checked(&s, 77));
    GI_CHECK(!gi_file_was_checked(&st[5], 5));
    GI_CHECK(gi_file_was_checked(&st[6], 6));
    gi_file_forget_checked();
    GI_CHECK(!gi_file_was_checked(&st[6], 6));
}
