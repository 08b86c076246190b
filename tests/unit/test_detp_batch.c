/* The animation batch on disk (detp_batch.c): a base plus per-frame deltas
 * reads back as the batch it stands for, frame after frame, through
 * rewrites of the base; old files go; a missing or foreign file reads as
 * missing. Synthetic paths: the store does not care where they came from. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "detp/detp_batch.h"
#include "gi_rng.h"
#include "gi_test.h"

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

GI_TEST(test_detp_batch_base_and_deltas_over_many_frames)
{
    char dir[512];
    snprintf(dir, sizeof dir, "%s/batches", gi_test_tmpdir());
    mkdir(dir, 0755);
    gi_error err;
    uint32_t version[PATHS] = {0};
    gi_detp_segments expect, got, changed;
    gi_detp_segments_init(&expect);
    gi_detp_segments_init(&got);
    gi_detp_segments_init(&changed);
    whole(version, &expect);
    GI_REQUIRE_OK(detp_batch_write_base(dir, 7, P0, P0 + PATHS, 0, &expect, &err));
    int max_files = 0;
    for (uint32_t f = 1; f <= 40; f++) {
        detp_batch prev;
        GI_REQUIRE(detp_batch_open(dir, 7, P0, P0 + PATHS, f - 1, &prev, &err) == 1);
        detp_batch_materialize(&prev, &changed, &got); /* changed is empty here */
        changed.count = 0;
        GI_CHECK_MSG(same_segments(&got, &expect), "frame %u reads back wrong", f - 1);
        /* This frame changes a few paths (more in some frames: the base is
         * rewritten now and then). */
        gi_rng r;
        gi_rng_init(&r, 99, f, 0);
        uint32_t k = f % 9 == 0 ? 60 : 5;
        for (uint32_t i = 0; i < PATHS; i++)
            if (gi_rng_u32(&r) % PATHS < k) {
                version[i] = f;
                make_run(P0 + i, f, &changed);
            }
        GI_REQUIRE_OK(detp_batch_write_frame(dir, &prev, f, &changed, &err));
        detp_batch_close(&prev);
        whole(version, &expect);
        int n = files_in(dir);
        max_files = n > max_files ? n : max_files;
    }
    detp_batch last;
    GI_REQUIRE(detp_batch_open(dir, 7, P0, P0 + PATHS, 40, &last, &err) == 1);
    gi_detp_segments none = {NULL, 0, 0};
    detp_batch_materialize(&last, &none, &got);
    GI_CHECK(same_segments(&got, &expect));
    GI_CHECK_MSG(last.base_frame > 0, "the base was never rewritten");
    detp_batch_close(&last);
    /* Old bases and deltas go: far fewer files than frames. */
    GI_CHECK_MSG(max_files < 20, "%d files at once", max_files);

    /* A missing delta: frame 40 cannot be read (regenerate). */
    char path[600];
    snprintf(path, sizeof path, "%s/b7.f40.delta", dir);
    if (remove(path) == 0)
        GI_CHECK(detp_batch_open(dir, 7, P0, P0 + PATHS, 40, &last, &err) == 0);
    /* Another batch's range under this batch's name is not this batch. */
    GI_CHECK(detp_batch_open(dir, 7, P0, P0 + PATHS + 1, 39, &last, &err) == 0);
    detp_batch_remove(dir, 7);
    GI_CHECK(files_in(dir) == 0);
    gi_detp_segments_free(&expect);
    gi_detp_segments_free(&got);
    gi_detp_segments_free(&changed);
}
