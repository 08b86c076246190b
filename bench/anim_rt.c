/* anim_rt: what moving one object costs (issue 7). On a scene with a
 * mobile object (e.g. gi_scenegen tree's torus): the Embree build, one
 * gi_rt_update_object after a small translation (median), closest-hit
 * throughput (random rays in the scene's box; a checksum of the hits shows
 * the layout does not change results), then N photons traced at frame 0
 * and one frame of gi_detp_anim_update against a full retrace.
 *   anim_rt SCENE.json [PHOTONS] [UPDATES]
 * Built with -DANIM_RT_ONLY it stops after the ray throughput (to compare
 * with an older gi_rt.c linked in its place). */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "detp/detp_anim.h"
#include "gi_rng.h"
#include "gi_rt.h"

static void move(gi_scene *s, uint32_t obj, gi_vec3 d)
{
    const gi_object *o = &s->objects[obj];
    for (uint32_t i = 0; i < o->vertex_count; i++)
        s->positions[o->first_vertex + i] = gi_add(s->positions[o->first_vertex + i], d);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: anim_rt SCENE.json [PHOTONS] [UPDATES]\n");
        return 2;
    }
    uint64_t photons = argc > 2 ? strtoull(argv[2], NULL, 10) : 100000;
    int updates = argc > 3 ? atoi(argv[3]) : 21;
    if (updates < 1 || updates > 10000)
        updates = 21;
    gi_error err;
    gi_scene s;
    if (gi_bench_load_scene(argv[1], &s, &err)) {
        fprintf(stderr, "anim_rt: %s\n", err.msg);
        return 1;
    }
    int mob = -1;
    for (uint32_t i = 0; i < s.object_count && mob < 0; i++)
        if (s.objects[i].mobile)
            mob = (int)i;
    if (mob < 0) {
        fprintf(stderr, "anim_rt: %s has no mobile object\n", argv[1]);
        return 1;
    }
    uint32_t m = (uint32_t)mob;
    double t0 = gi_bench_now();
    gi_rt rt;
    if (gi_rt_create(&rt, &s, &err)) {
        fprintf(stderr, "anim_rt: %s\n", err.msg);
        return 1;
    }
    double t_build = gi_bench_now() - t0;
    float size = (float)gi_detp_scene_size(&s);
    gi_vec3 step = gi_v3(1e-3f * size, 0, 0);
    double *t = malloc((size_t)updates * sizeof *t);
    for (int i = 0; i < updates; i++) {
        move(&s, m, i % 2 ? gi_neg(step) : step);
        t0 = gi_bench_now();
        if (gi_rt_update_object(&rt, m, &err)) {
            fprintf(stderr, "anim_rt: %s\n", err.msg);
            return 1;
        }
        t[i] = gi_bench_now() - t0;
    }
    if (updates % 2) {
        move(&s, m, gi_neg(step));
        gi_rt_update_object(&rt, m, &err);
    }
    double t_update = gi_bench_median(t, updates);
    /* Rays between random points of the box. */
    const int rays = 1000000;
    gi_rng r;
    gi_rng_init(&r, 1, 2, 3);
    gi_vec3 lo = s.bbox_min, ext = gi_sub(s.bbox_max, s.bbox_min);
    double sum = 0;
    uint64_t hits = 0, tri_sum = 0;
    t0 = gi_bench_now();
    for (int i = 0; i < rays; i++) {
        float u[6];
        for (int k = 0; k < 6; k++)
            u[k] = gi_rng_float(&r);
        gi_vec3 a = gi_add(lo, gi_mul(ext, gi_v3(u[0], u[1], u[2])));
        gi_vec3 b = gi_add(lo, gi_mul(ext, gi_v3(u[3], u[4], u[5])));
        gi_hit h;
        if (gi_rt_intersect(&rt, a, gi_normalize(gi_sub(b, a)), 0.0f, FLT_MAX, &h)) {
            hits++;
            tri_sum += h.tri;
            sum += h.t;
        }
    }
    double t_rays = gi_bench_now() - t0;
    printf("# %s: %u triangles, mobile \"%s\" %u triangles\n", argv[1], s.triangle_count,
           s.objects[m].name, s.objects[m].triangle_count);
    printf("build %.3f s; update_object median of %d: %.3f ms; %.2f Mrays/s closest hit "
           "(checksum %llu %llu %.6e)\n",
           t_build, updates, 1e3 * t_update, rays / t_rays / 1e6, (unsigned long long)hits,
           (unsigned long long)tri_sum, sum);

#ifndef ANIM_RT_ONLY /* the part above alone links against an older gi_rt.c */
    /* One frame of the incremental update against a full retrace. */
    gi_detp_tracer tr;
    gi_detp_tracer_init(&tr, &rt, &s, 5, photons, -1, 1);
    gi_detp_segments s0, full, next, o, n;
    gi_detp_segments_init(&s0);
    gi_detp_segments_init(&full);
    gi_detp_segments_init(&next);
    gi_detp_segments_init(&o);
    gi_detp_segments_init(&n);
    float eps = 1e-5f * size;
    t0 = gi_bench_now();
    for (uint64_t p = 0; p < photons; p++)
        gi_detp_trace_photon(&tr, p, &s0);
    gi_detp_set_extent(&s0, GI_DETP_AC_SECOND_HIT, eps);
    double t_trace = gi_bench_now() - t0;
    gi_detp_mobile_pose old_pose = gi_detp_object_sphere(&s, m);
    move(&s, m, gi_scale(step, 20.0f));
    t0 = gi_bench_now();
    gi_rt_update_object(&rt, m, &err);
    RTCScene alone = gi_rt_object_scene(&rt, m, &err);
    double t_move = gi_bench_now() - t0;
    tr.frame = 1;
    gi_detp_anim_update_in in = {s0.v, s0.count, &tr, s.objects[m].first_triangle,
                                 s.objects[m].triangle_count, old_pose,
                                 gi_detp_object_sphere(&s, m), alone, GI_DETP_AC_SECOND_HIT, eps,
                                 1, 0};
    gi_detp_update_stats st = {0};
    t0 = gi_bench_now();
    if (!alone || gi_detp_anim_update(&in, &next, &o, &n, &st, &err)) {
        fprintf(stderr, "anim_rt: %s\n", err.msg);
        return 1;
    }
    double t_inc = gi_bench_now() - t0;
    /* Again into the same buffers (a worker keeps them across frames):
     * fresh pages cost much in some VMs. */
    next.count = o.count = n.count = 0;
    gi_detp_update_stats st2 = {0};
    t0 = gi_bench_now();
    gi_detp_anim_update(&in, &next, &o, &n, &st2, &err);
    double t_warm = gi_bench_now() - t0;
    t0 = gi_bench_now();
    for (uint64_t p = 0; p < photons; p++)
        gi_detp_trace_photon(&tr, p, &full);
    double t_full = gi_bench_now() - t0;
    printf("%llu photons, %zu segments: trace %.3f s; move %.4f s; update %.3f s "
           "(tests %.3f, retrace %.3f): %llu of %llu paths retraced, %llu sphere passes, "
           "%llu t_second rays, old %zu new %zu; again in the same buffers %.3f s; "
           "full retrace %.3f s (%.1fx, %.1fx)\n",
           (unsigned long long)photons, s0.count, t_trace, t_move, t_inc, st.seconds_test,
           st.seconds_retrace, (unsigned long long)st.paths_retraced,
           (unsigned long long)st.paths, (unsigned long long)st.sphere_passes,
           (unsigned long long)st.second_tests, o.count, n.count, t_warm, t_full, t_full / t_inc,
           t_full / t_warm);
    gi_detp_segments_free(&s0);
    gi_detp_segments_free(&full);
    gi_detp_segments_free(&next);
    gi_detp_segments_free(&o);
    gi_detp_segments_free(&n);
#endif
    free(t);
    gi_rt_free(&rt);
    gi_scene_free(&s);
    return 0;
}
