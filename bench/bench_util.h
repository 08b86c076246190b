/* bench_util: what the benchmark drivers share: a monotonic clock and
 * medians (drivers alternate the runs they compare and report medians). */
#ifndef GI_BENCH_UTIL_H
#define GI_BENCH_UTIL_H

#include <stdlib.h>
#include <time.h>

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

#endif
