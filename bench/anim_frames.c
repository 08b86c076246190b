/* anim_frames: full recompute vs incremental time per frame of a detp
 * animation (issue 7, thesis Table A.14), from the per-frame reports
 * NAME.0000.json ... that `gi render` wrote. Several runs of the same job
 * (rounds, alternated with other jobs by bench/detp_anim.sh) give medians.
 *
 *   anim_frames header | phase_header         a table's header
 *   anim_frames row LABEL C FRAMES PREFIX...    one row: full vs incremental
 *   anim_frames phases LABEL FRAMES PREFIX...   two rows: seconds per phase
 *   anim_frames image FRAMES PREFIX             an animation's image phase
 *
 * PREFIX is a run's NAME with its directory (PREFIX.0000.json is frame 0).
 * Times are the reports' "animation"."seconds": worker seconds summed over
 * the frame's batches (wall time inside the worker, phase by phase).
 *   full = frame 0's index_build + photon_tracing + density_estimation +
 *          mobile_vertices (store_write, writing the batch files, apart);
 *   incremental = the mean over frames 1..FRAMES-1 of all their phases
 *          (index_build, store_read, regenerate, test_and_retrace,
 *          static_update, mobile_vertices, store_write).
 * The row's times are medians over the runs; its ratio is the median of the
 * runs' ratios. C is the mobile's radius as a fraction of the scene width:
 * the row shows the thesis's Table A.14 (if C is one of its sizes) and the
 * theory A(C) = cbrt(1 + C^3) / (2 C^2 + 8.08 C^3) (eq. 4.24, with C read as
 * the digest's table reads it: the radius fraction; C = 0: no theory). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "bench_util.h"
#include "gi_fs.h"

#define MAX_RUNS 64

enum { P_BUILD, P_READ, P_REGEN, P_TRACE, P_STATIC, P_MOBILE, P_WRITE, NPHASE };
static const char *phase_key[2][NPHASE] = {
    {"index_build", "store_read", "regenerate", "photon_tracing", "density_estimation",
     "mobile_vertices", "store_write"},
    {"index_build", "store_read", "regenerate", "test_and_retrace", "static_update",
     "mobile_vertices", "store_write"}};

typedef struct {
    double sec[NPHASE];
    double paths, retraced, segments, seg_old, seg_new, wall;
    double image, wall_image; /* tiles' worker seconds, the image phase's wall time */
} frame_rec;

/* Thesis Table A.14: mobile size (%), whole scene (s), recompute (s). */
static const double thesis[][3] = {
    {1.25, 0.90, 0.03}, {2.5, 0.92, 0.03},  {5, 0.92, 0.06},   {7.5, 0.91, 0.09},
    {10, 1.00, 0.15},   {12.5, 1.04, 0.20}, {15, 1.08, 0.25},  {17.5, 1.09, 0.30},
    {20, 1.16, 0.39},   {25, 1.26, 0.56},   {50, 1.87, 1.63}};

static double num(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsNumber(v) ? v->valuedouble : 0.0;
}

static int load_frame(const char *prefix, int f, frame_rec *r)
{
    char path[4096];
    snprintf(path, sizeof path, "%s.%04d.json", prefix, f);
    gi_buf b;
    gi_error err;
    gi_buf_init(&b);
    if (gi_read_file(path, 64u << 20, &b, &err)) {
        fprintf(stderr, "anim_frames: %s\n", err.msg);
        return -1;
    }
    cJSON *root = cJSON_ParseWithLength((const char *)b.data, b.len);
    gi_buf_free(&b);
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(root, "animation");
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(a, "seconds");
    if (!cJSON_IsObject(s) || (int)num(a, "frame") != f) {
        fprintf(stderr, "anim_frames: %s: no animation report of frame %d\n", path, f);
        cJSON_Delete(root);
        return -1;
    }
    for (int i = 0; i < NPHASE; i++)
        r->sec[i] = num(s, phase_key[f > 0][i]);
    r->paths = num(a, "paths_tested");
    r->retraced = num(a, "paths_retraced");
    r->segments = num(a, "segments");
    r->seg_old = num(a, "segments_old");
    r->seg_new = num(a, "segments_new");
    const cJSON *js = cJSON_GetObjectItemCaseSensitive(root, "seconds");
    r->wall = num(js, "wall_bake");
    r->image = num(js, "image");
    r->wall_image = num(js, "wall_image");
    cJSON_Delete(root);
    return 0;
}

/* One run: frame 0 and the mean of frames 1..frames-1. */
typedef struct {
    frame_rec f0, inc;
    double full, incr;
} run_rec;

static int load_run(const char *prefix, int frames, run_rec *run)
{
    memset(run, 0, sizeof *run);
    if (load_frame(prefix, 0, &run->f0))
        return -1;
    for (int f = 1; f < frames; f++) {
        frame_rec r;
        if (load_frame(prefix, f, &r))
            return -1;
        for (int i = 0; i < NPHASE; i++)
            run->inc.sec[i] += r.sec[i] / (frames - 1);
        run->inc.paths += r.paths / (frames - 1);
        run->inc.retraced += r.retraced / (frames - 1);
        run->inc.segments += r.segments / (frames - 1);
        run->inc.seg_old += r.seg_old / (frames - 1);
        run->inc.seg_new += r.seg_new / (frames - 1);
        run->inc.wall += r.wall / (frames - 1);
        run->inc.image += r.image / (frames - 1);
        run->inc.wall_image += r.wall_image / (frames - 1);
    }
    const double *s = run->f0.sec;
    run->full = s[P_BUILD] + s[P_TRACE] + s[P_STATIC] + s[P_MOBILE];
    for (int i = 0; i < NPHASE; i++)
        run->incr += run->inc.sec[i];
    return 0;
}

static double theory(double c) { return cbrt(1 + c * c * c) / (2 * c * c + 8.08 * c * c * c); }

static int row(const char *label, double c, int frames, char **prefix, int n)
{
    static run_rec run[MAX_RUNS];
    double full[MAX_RUNS], incr[MAX_RUNS], ratio[MAX_RUNS], write0[MAX_RUNS];
    for (int i = 0; i < n; i++) {
        if (load_run(prefix[i], frames, &run[i]))
            return 1;
        full[i] = run[i].full;
        incr[i] = run[i].incr;
        ratio[i] = run[i].full / run[i].incr;
        write0[i] = run[i].f0.sec[P_WRITE];
    }
    char th[64] = "- | - | -";
    for (size_t i = 0; i < sizeof thesis / sizeof thesis[0]; i++)
        if (fabs(thesis[i][0] - 100 * c) < 1e-6)
            snprintf(th, sizeof th, "%.2f | %.2f | %.1f", thesis[i][1], thesis[i][2],
                     thesis[i][1] / thesis[i][2]);
    char theo[32] = "-";
    if (c > 0)
        snprintf(theo, sizeof theo, "%.1f", theory(c));
    const run_rec *r = &run[0];
    printf("| %s | %.0f | %.3f (+%.3f) | %.4f | **%.1f** | %.2f%% | %.1f%% | %s | %s |\n", label,
           r->f0.segments, gi_bench_median(full, n), gi_bench_median(write0, n),
           gi_bench_median(incr, n), gi_bench_median(ratio, n),
           100 * r->inc.retraced / r->inc.paths,
           100 * (r->inc.seg_old + r->inc.seg_new) / r->inc.segments, th, theo);
    return 0;
}

static int phases(const char *label, int frames, char **prefix, int n)
{
    static run_rec run[MAX_RUNS];
    double v[MAX_RUNS];
    for (int i = 0; i < n; i++)
        if (load_run(prefix[i], frames, &run[i]))
            return 1;
    for (int k = 0; k < 2; k++) {
        printf("| %s, %s |", label, k ? "incremental (mean of frames 1..)" : "frame 0 (full)");
        for (int p = 0; p < NPHASE; p++) {
            for (int i = 0; i < n; i++)
                v[i] = k ? run[i].inc.sec[p] : run[i].f0.sec[p];
            printf(" %.4f |", gi_bench_median(v, n));
        }
        for (int i = 0; i < n; i++)
            v[i] = k ? run[i].inc.wall : run[i].f0.wall;
        printf(" %.3f |\n", gi_bench_median(v, n));
    }
    return 0;
}

/* An animation with images: frame 0 and the mean of frames 1.. */
static int image(int frames, const char *prefix)
{
    run_rec run;
    if (load_run(prefix, frames, &run))
        return 1;
    printf("frame 0: wall_bake %.3f s, image %.3f worker s, wall_image %.3f s\n", run.f0.wall,
           run.f0.image, run.f0.wall_image);
    printf("frames 1..%d (mean): wall_bake %.3f s, image %.3f worker s, wall_image %.3f s\n",
           frames - 1, run.inc.wall, run.inc.image, run.inc.wall_image);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "header")) {
        printf("| mobile radius | segments | full: frame 0 s (+ store_write) | incremental s "
               "per frame | ratio | paths retraced | segments changed | thesis whole s | "
               "thesis recompute s | thesis ratio | theory A(C) |\n");
        printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
        return 0;
    }
    if (argc >= 6 && !strcmp(argv[1], "row") && argc - 5 <= MAX_RUNS && atoi(argv[4]) >= 2)
        return row(argv[2], atof(argv[3]), atoi(argv[4]), argv + 5, argc - 5);
    if (argc >= 2 && !strcmp(argv[1], "phase_header")) {
        printf("| run | index_build | store_read | regenerate | trace or test_and_retrace | "
               "density_estimation or static_update | mobile_vertices | store_write | "
               "wall_bake |\n|---|---|---|---|---|---|---|---|---|\n");
        return 0;
    }
    if (argc >= 5 && !strcmp(argv[1], "phases") && argc - 4 <= MAX_RUNS && atoi(argv[3]) >= 2)
        return phases(argv[2], atoi(argv[3]), argv + 4, argc - 4);
    if (argc == 4 && !strcmp(argv[1], "image") && atoi(argv[2]) >= 2)
        return image(atoi(argv[2]), argv[3]);
    fprintf(stderr, "usage: anim_frames header | phase_header\n"
                    "       anim_frames row LABEL C FRAMES PREFIX...\n"
                    "       anim_frames phases LABEL FRAMES PREFIX...\n"
                    "       anim_frames image FRAMES PREFIX\n");
    return 2;
}
