/* detp_disc_order: does the order of the discs in memory matter to Embree
 * Disc Indexing? The same segments estimated against the same discs in
 * three numberings: the mesh's (as every estimator uses them), along a 3-D
 * Hilbert curve, and shuffled. A segment's crossings land on discs that
 * are near each other in space; in a spatial numbering their records and
 * sums share cache lines. The three must give every disc the same energy
 * (the same segments in the same order, only renumbered); the run stops
 * if they do not.
 *
 *   detp_disc_order SCENE.json [SUBDIVIDE] [RADIUS] [PHOTONS] [ROUNDS]
 *
 * SUBDIVIDE: refine the mesh to edges of at most this many scene units
 * first (detp.subdivide; 0: not); RADIUS: the disc radius as a fraction of
 * the scene size (0, the default: the mean edge, detp's "auto");
 * PHOTONS: default 1000000; ROUNDS: default 5, the orders alternated. One
 * core; seconds of the estimate alone (the index built beforehand). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "detp/detp.h"
#include "gi_rt.h"

enum { MESH, HILBERT, SHUFFLED, ORDERS, MAX_ROUNDS = 99 };
static const char *const names[ORDERS] = {"mesh", "hilbert", "shuffled"};

static int fail(const gi_error *err)
{
    fprintf(stderr, "detp_disc_order: %s\n", err->msg);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: detp_disc_order SCENE.json [SUBDIVIDE] [RADIUS] [PHOTONS] "
                        "[ROUNDS]\n");
        return 2;
    }
    double subdivide = argc > 2 ? atof(argv[2]) : 0.0;
    double radius_frac = argc > 3 ? atof(argv[3]) : 0.0;
    uint64_t photons = argc > 4 ? strtoull(argv[4], NULL, 10) : 1000000;
    int rounds = argc > 5 ? atoi(argv[5]) : 5;
    if (rounds < 1 || rounds > MAX_ROUNDS)
        rounds = 5;
    gi_error err;
    gi_scene scene;
    if (gi_bench_load_scene(argv[1], &scene, &err))
        return fail(&err);
    double size = gi_detp_scene_size(&scene);
    if (subdivide > 0 && gi_detp_refine_scene(&scene, subdivide, &err))
        return fail(&err);
    gi_rt rt;
    if (gi_rt_create(&rt, &scene, &err))
        return fail(&err);
    double radius = radius_frac > 0 ? radius_frac * size : gi_detp_mean_edge(&scene);

    gi_detp_segments segs;
    gi_detp_segments_init(&segs);
    gi_detp_tracer tr;
    gi_detp_tracer_init(&tr, &rt, &scene, 1, photons, -1, 1);
    for (uint64_t p = 0; p < photons; p++)
        gi_detp_trace_photon(&tr, p, &segs);
    gi_detp_set_extent(&segs, GI_DETP_AC_SECOND_HIT, (float)(1e-5 * size));

    /* discs[k].d[i] is the mesh's disc perm[k][i] (the mesh's own: no perm). */
    gi_detp_discs discs[ORDERS];
    uint32_t *perm[ORDERS] = {NULL};
    if (gi_detp_discs_from_scene(&scene, (float)radius, &discs[MESH], &err))
        return fail(&err);
    uint32_t n = discs[MESH].count;
    perm[HILBERT] = gi_detp_query_order(&discs[MESH], GI_DETP_ORDER_HILBERT, 1, &err);
    perm[SHUFFLED] = gi_detp_query_order(&discs[MESH], GI_DETP_ORDER_SHUFFLED, 1, &err);
    if (!perm[HILBERT] || !perm[SHUFFLED])
        return fail(&err);
    for (int k = HILBERT; k < ORDERS; k++) {
        discs[k] = discs[MESH];
        discs[k].d = malloc((n ? n : 1) * sizeof(gi_detp_disc));
        for (uint32_t i = 0; i < n; i++)
            discs[k].d[i] = discs[MESH].d[perm[k][i]];
    }
    printf("# %s: %u discs of radius %.4g, %zu segments of %llu photons; median of %d "
           "rounds, one core\n",
           argv[1], n, radius, segs.count, (unsigned long long)photons, rounds);

    gi_detp_embree_index *index[ORDERS];
    gi_detp_accum acc[ORDERS];
    double secs[ORDERS][MAX_ROUNDS];
    for (int k = 0; k < ORDERS; k++)
        if (gi_detp_embree_build(rt.device, &discs[k], &index[k], &err) ||
            gi_detp_accum_init(&acc[k], n, &err))
            return fail(&err);
    for (int r = 0; r < rounds; r++)
        for (int j = 0; j < ORDERS; j++) {
            int k = (j + r) % ORDERS;
            gi_detp_stats st;
            memset(&st, 0, sizeof st);
            gi_detp_accum_clear(&acc[k]);
            double t0 = gi_bench_now();
            gi_detp_embree_estimate(index[k], &segs, &acc[k], &st);
            secs[k][r] = gi_bench_now() - t0;
        }
    for (int k = HILBERT; k < ORDERS; k++)
        for (uint32_t i = 0; i < n; i++) {
            uint32_t m = perm[k][i];
            if (memcmp(&acc[k].energy[3 * (size_t)i], &acc[MESH].energy[3 * (size_t)m],
                       3 * sizeof(double)) != 0 ||
                acc[k].hits[i] != acc[MESH].hits[m]) {
                fprintf(stderr, "detp_disc_order: %s order disagrees with the mesh's at disc %u\n",
                        names[k], m);
                return 1;
            }
        }
    for (int k = 0; k < ORDERS; k++) {
        double med = gi_bench_median(secs[k], rounds); /* sorts: [0] is the fastest */
        printf("%-9s estimate: fastest %.4f s, median %.4f s\n", names[k], secs[k][0], med);
        gi_detp_embree_free(index[k]);
        gi_detp_accum_free(&acc[k]);
        free(perm[k]);
        gi_detp_discs_free(&discs[k]);
    }
    gi_detp_segments_free(&segs);
    gi_rt_free(&rt);
    gi_scene_free(&scene);
    return 0;
}
