/* detp_tree: the thesis's Table A.2-A.4 experiment (App. A.1) - density
 * estimation time on the Tree Scene for disc radii of 1%, 2% and 4% and
 * 100 ... 409,600 photons - for our Sphere Cache (Hilbert order), octree
 * Disc Indexing and Embree Disc Indexing, with the time of every phase.
 *
 *   detp_tree SCENE.json [MAX_PHOTONS] [ROUNDS] [MIN_PHOTONS] [RADII]
 *
 * SCENE is the tree scene from `gi_scenegen tree DIR`. For each photon
 * count (100, 200, 400, ... up to MAX_PHOTONS, default 409600) the photons
 * are traced once (timed; artifact control rule 1, as the thesis's default)
 * and the same segments go to every estimator, as one batch on one core.
 * Each round runs the three estimators in a rotating order (this machine's
 * speed drifts: alternating keeps the comparison fair) and the median of
 * ROUNDS (default 3) is printed. MIN_PHOTONS (default 100) starts the
 * doubling elsewhere; RADII (default "1,2,4") lists radii in percent. Build = Hilbert sort for the Sphere Cache,
 * tree / BVH construction for Disc Indexing; estimate = the density
 * estimation proper (the thesis's tables give this phase). The three must
 * agree on every disc's energy; the run stops if they do not. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "detp/detp.h"
#include "gi_rt.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

enum { SC, OCT, EMB, NEST };
static const char *const names[NEST] = {"sphere cache", "octree DI", "Embree DI"};

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: detp_tree SCENE.json [MAX_PHOTONS] [ROUNDS] [MIN_PHOTONS] [RADII]\n");
        return 2;
    }
    uint64_t max_photons = argc > 2 ? strtoull(argv[2], NULL, 10) : 409600;
    int rounds = argc > 3 ? atoi(argv[3]) : 3;
    if (rounds < 1 || rounds > 99)
        rounds = 3;
    uint64_t min_photons = argc > 4 ? strtoull(argv[4], NULL, 10) : 100;
    if (min_photons < 1)
        min_photons = 1;
    double radii[8];
    int nradii = 0;
    const char *rl = argc > 5 ? argv[5] : "1,2,4";
    for (char *e; *rl && nradii < 8; rl = *e ? e + 1 : e) {
        radii[nradii++] = 0.01 * strtod(rl, &e);
        if (e == rl)
            break;
    }
    gi_error err;
    gi_scene scene;
    if (gi_bench_load_scene(argv[1], &scene, &err)) {
        fprintf(stderr, "detp_tree: %s\n", err.msg);
        return 1;
    }
    gi_rt rt;
    if (gi_rt_create(&rt, &scene, &err)) {
        fprintf(stderr, "detp_tree: %s\n", err.msg);
        return 1;
    }
    double size = gi_detp_scene_size(&scene);
    printf("# %s: %u triangles, %u vertices (discs), scene size %.4g, mean edge %.4g\n",
           argv[1], scene.triangle_count, scene.vertex_count, size, gi_detp_mean_edge(&scene));
    printf("# median of %d rounds, one core; seconds\n", rounds);
    printf("%-8s %-8s %-7s %-4s | %-8s %-8s | %-8s %-8s | %-8s %-8s | %s\n", "photons", "segments",
           "trace", "r%", "SC sort", "SC est", "oct bld", "oct est", "emb bld", "emb est",
           "SC/Embree est");
    gi_detp_sc_params scp = {2.0 / 3.0, 100, 60, GI_DETP_ORDER_HILBERT, 1, 0};
    gi_detp_octree_params op = {0, 20};
    gi_detp_segments segs;
    gi_detp_segments_init(&segs);
    for (uint64_t n = min_photons; n <= max_photons; n *= 2) {
        gi_detp_tracer tr;
        gi_detp_tracer_init(&tr, &rt, &scene, 1, n, -1, 1);
        segs.count = 0;
        double t0 = now();
        for (uint64_t p = 0; p < n; p++)
            gi_detp_trace_photon(&tr, p, &segs);
        double trace = now() - t0;
        gi_detp_set_extent(&segs, GI_DETP_AC_SECOND_HIT, (float)(1e-5 * size));
        for (int ri = 0; ri < nradii; ri++) {
            gi_detp_discs d;
            if (gi_detp_discs_from_scene(&scene, (float)(radii[ri] * size), &d, &err))
                return 1;
            double build[NEST][99], est[NEST][99];
            gi_detp_accum acc[NEST];
            for (int e = 0; e < NEST; e++)
                if (gi_detp_accum_init(&acc[e], d.count, &err))
                    return 1;
            for (int r = 0; r < rounds; r++)
                for (int k = 0; k < NEST; k++) {
                    int e = (k + r) % NEST;
                    gi_detp_stats st;
                    memset(&st, 0, sizeof st);
                    gi_detp_accum_clear(&acc[e]);
                    double a = now(), b, c;
                    if (e == SC) {
                        uint32_t *order = gi_detp_query_order(&d, scp.order, 1, &err);
                        b = now();
                        if (!order || gi_detp_sphere_cache(&d, order, &segs, &scp, scene.bbox_min,
                                                           scene.bbox_max, &acc[e], &st, &err))
                            return fprintf(stderr, "detp_tree: %s\n", err.msg), 1;
                        c = now();
                        free(order);
                    } else if (e == OCT) {
                        gi_detp_octree *o;
                        if (gi_detp_octree_build(&d, &op, &o, &err))
                            return fprintf(stderr, "detp_tree: %s\n", err.msg), 1;
                        b = now();
                        gi_detp_octree_estimate(o, &segs, &acc[e], &st);
                        c = now();
                        gi_detp_octree_free(o);
                    } else {
                        gi_detp_embree_index *x;
                        if (gi_detp_embree_build(rt.device, &d, &x, &err))
                            return fprintf(stderr, "detp_tree: %s\n", err.msg), 1;
                        b = now();
                        gi_detp_embree_estimate(x, &segs, &acc[e], &st);
                        c = now();
                        gi_detp_embree_free(x);
                    }
                    build[e][r] = b - a;
                    est[e][r] = c - b;
                }
            for (int e = 1; e < NEST; e++)
                if (memcmp(acc[e].energy, acc[0].energy, (size_t)d.count * 3 * sizeof(double)) ||
                    memcmp(acc[e].hits, acc[0].hits, (size_t)d.count * sizeof(uint32_t))) {
                    fprintf(stderr, "detp_tree: %s and %s disagree\n", names[0], names[e]);
                    return 1;
                }
            double mb[NEST], me[NEST];
            for (int e = 0; e < NEST; e++) {
                mb[e] = median(build[e], rounds);
                me[e] = median(est[e], rounds);
                gi_detp_accum_free(&acc[e]);
            }
            printf("%-8llu %-8zu %-7.3f %-4.0f | %-8.4f %-8.4f | %-8.4f %-8.4f | %-8.4f %-8.4f | %.2f\n",
                   (unsigned long long)n, segs.count, trace, 100 * radii[ri], mb[SC], me[SC],
                   mb[OCT], me[OCT], mb[EMB], me[EMB], me[EMB] > 0 ? me[SC] / me[EMB] : 0.0);
            fflush(stdout);
            gi_detp_discs_free(&d);
        }
    }
    gi_detp_segments_free(&segs);
    gi_rt_free(&rt);
    gi_scene_free(&scene);
    return 0;
}
