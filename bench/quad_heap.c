/* quad_heap: the three region heaps (bucketed as in the thesis, binary,
 * pairing) on the refinement's access pattern, and inside a whole adaptive
 * integration.
 *
 *   quad_heap [ITERATIONS] [ROUNDS]
 *
 * Trace: 1024 initial regions, then ITERATIONS times (default 2e6): take
 * the largest error, put back two children whose errors are the parent's
 * times a factor in [0.05, 0.6] (how errors fall under bisection), so the
 * heap grows to ~ITERATIONS elements. Integration: gi_quad_integrate of
 * Genz's discontinuous family in d = 2 (Genz-Malik, 2e6 evaluations: about
 * 9,000 regions, the heap a visible share of the time). The kinds are run
 * in turn, ROUNDS times (default 9), and the median time per kind is
 * printed (the machine is shared: alternating keeps drift out of the
 * comparison). */
#include <stdio.h>
#include <stdlib.h>

#include "bench/bench_util.h"
#include "bench/genz.h"
#include "gi_rng.h"
#include "quadrature/quad_heap.h"
#include "quadrature/quad_integrate.h"

/* Returns the time; *buckets gets the final bucket count. */
static double trace(gi_qheap_kind kind, long iterations, size_t *buckets, double *checksum)
{
    gi_qheap *h = gi_qheap_create(kind);
    gi_rng rng;
    gi_rng_init(&rng, 42, 0, 0);
    uint32_t next = 0;
    double t0 = gi_bench_now();
    for (int i = 0; i < 1024; i++, next++)
        gi_qheap_push(h, gi_rng_double(&rng), gi_mix64(next), next);
    double sum = 0;
    for (long it = 0; it < iterations; it++) {
        double key;
        uint64_t tie;
        uint32_t item;
        gi_qheap_pop(h, &key, &tie, &item);
        sum += key;
        for (int c = 0; c < 2; c++, next++)
            gi_qheap_push(h, key * (0.05 + 0.55 * gi_rng_double(&rng)), gi_mix64(next), next);
    }
    double t = gi_bench_now() - t0;
    *buckets = gi_qheap_buckets(h);
    *checksum = sum;
    gi_qheap_free(h);
    return t;
}

static void genz_fn(void *user, size_t n, const double *pts, double *out)
{
    const gi_genz *g = user;
    for (size_t i = 0; i < n; i++)
        out[i] = gi_genz_eval(g, pts + i * g->d);
}

static double integrate(gi_qheap_kind kind, uint64_t *regions)
{
    gi_genz g;
    gi_genz_pick(&g, GI_GENZ_DISCONTINUOUS, 2, 3);
    gi_quad_integrand fn = {genz_fn, &g};
    gi_quad_opts o = {GI_QUAD_GM, GI_QUAD_AXIS_MARGINAL, kind, 1e-15, 0, 2000000};
    gi_quad_result r;
    gi_error err;
    double t0 = gi_bench_now();
    if (gi_quad_integrate(2, 1, &fn, &o, &r, &err)) {
        fprintf(stderr, "quad_heap: %s\n", err.msg);
        exit(1);
    }
    *regions = r.regions;
    return gi_bench_now() - t0;
}

int main(int argc, char **argv)
{
    long iterations = argc > 1 ? atol(argv[1]) : 2000000;
    int rounds = argc > 2 ? atoi(argv[2]) : 9;
    if (iterations < 1 || rounds < 1 || rounds > 99) {
        fprintf(stderr, "usage: quad_heap [ITERATIONS] [ROUNDS <= 99]\n");
        return 2;
    }
    static const char *const names[3] = {"bucketed", "binary", "pairing"};
    double tt[3][99], ti[3][99], sums[3];
    size_t buckets[3];
    uint64_t regions[3];
    for (int r = 0; r < rounds; r++)
        for (int k = 0; k < 3; k++) {
            tt[k][r] = trace((gi_qheap_kind)k, iterations, &buckets[k], &sums[k]);
            ti[k][r] = integrate((gi_qheap_kind)k, &regions[k]);
        }
    printf("trace: %ld pops and %ld pushes; integration: %llu regions; median of %d rounds\n",
           iterations, 2 * iterations + 1024, (unsigned long long)regions[0], rounds);
    printf("| heap | trace | per operation | buckets at the end | integration |\n"
           "|---|---|---|---|---|\n");
    for (int k = 0; k < 3; k++) {
        double t = gi_bench_median(tt[k], rounds), ti_k = gi_bench_median(ti[k], rounds);
        printf("| %s | %.3f s | %.0f ns | %zu | %.3f s |\n", names[k], t,
               1e9 * t / (3.0 * iterations + 1024), buckets[k], ti_k);
        if (sums[k] != sums[0] || regions[k] != regions[0]) {
            fprintf(stderr, "quad_heap: %s popped a different sequence\n", names[k]);
            return 1;
        }
    }
    return 0;
}
