/* bench_util: what the benchmark drivers share: a monotonic clock,
 * medians (drivers alternate the runs they compare and report medians) and
 * loading a scene. */
#ifndef GI_BENCH_UTIL_H
#define GI_BENCH_UTIL_H

#include <stdlib.h>
#include <time.h>

#include "gi_assets.h"
#include "gi_scene.h"

static inline double gi_bench_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline int gi_bench_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Median of v[0..n) (v is sorted). */
static inline double gi_bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, gi_bench_cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Loads the scene file at `path` (relative to the working directory). */
static inline int gi_bench_load_scene(const char *path, gi_scene *s, gi_error *err)
{
    gi_dir_source ds;
    gi_dir_source_init(&ds, ".");
    gi_asset_source src = gi_dir_source_as_source(&ds);
    int rc = gi_scene_load(&src, path, s, err);
    gi_dir_source_free(&ds);
    return rc;
}

#endif
