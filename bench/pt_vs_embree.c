/* pt_vs_embree: rays per second of the path tracer on the Cornell box,
 * against a bare rtcIntersect1 / rtcOccluded1 loop over the very same rays,
 * in the same run, on one core.
 *
 *   pt_vs_embree [SCENE] [WIDTH] [SPP] [ROUNDS]
 *
 * Renders WIDTH^2 pixels x SPP samples (as pt tasks do: the paths of a
 * tile advanced together) once with a ray log that records
 * every ray the tracer casts; then, ROUNDS times, renders again (timed) and
 * casts the recorded rays with nothing around them (timed). The ratio is
 * t_bare / t_pt = (rays / t_pt) / (rays / t_bare): the share of Embree's raw
 * rate our tracer keeps; the median over rounds is reported. */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "gi_blas_threads.h"
#include "gi_camera.h"
#include "gi_rt.h"
#include "pt/pt.h"

typedef struct rec_ray {
    float org[3], dir[3], tnear, tfar;
    int occlusion;
} rec_ray;

typedef struct ray_store {
    rec_ray *rays;
    size_t count, cap;
} ray_store;

static void record(void *user, gi_vec3 o, gi_vec3 d, float tnear, float tfar, int occ)
{
    ray_store *s = user;
    if (s->count == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 1 << 20;
        s->rays = realloc(s->rays, s->cap * sizeof *s->rays);
        if (!s->rays) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
    }
    rec_ray *r = &s->rays[s->count++];
    r->org[0] = o.x, r->org[1] = o.y, r->org[2] = o.z;
    r->dir[0] = d.x, r->dir[1] = d.y, r->dir[2] = d.z;
    r->tnear = tnear;
    r->tfar = tfar;
    r->occlusion = occ;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Renders like the pt method's tasks do: the paths of 64 x 64 pixel tiles
 * advanced together (gi_pt_trace_paths). */
static double render(const gi_pt_tracer *tr, const gi_camera_frame *cam, int w, int spp)
{
    double sum = 0;
    enum { TILE = 32 };
    gi_pt_path *paths = malloc((size_t)TILE * TILE * spp * sizeof *paths);
    gi_pt_wavefront wf = {0};
    for (int ty = 0; ty < w; ty += TILE)
        for (int tx = 0; tx < w; tx += TILE) {
            size_t n = 0;
            for (int y = ty; y < ty + TILE && y < w; y++)
                for (int x = tx; x < tx + TILE && x < w; x++)
                    for (int s = 0; s < spp; s++) {
                        gi_rng rng;
                        gi_rng_init(&rng, 1, (uint64_t)y * w + x, (uint32_t)s);
                        float jx = gi_rng_float(&rng), jy = gi_rng_float(&rng);
                        gi_vec3 d = gi_camera_dir(cam, (float)x + jx, (float)y + jy);
                        gi_pt_path_start(&paths[n++], cam->origin, d, &rng);
                    }
            gi_pt_trace_paths(tr, &wf, paths, n);
            for (size_t i = 0; i < n; i++)
                sum += paths[i].L.x + paths[i].L.y + paths[i].L.z;
        }
    free(paths);
    gi_pt_wavefront_free(&wf);
    return sum;
}

static double replay(RTCScene scene, const ray_store *st)
{
    double sum = 0;
    for (size_t i = 0; i < st->count; i++) {
        const rec_ray *r = &st->rays[i];
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        if (r->occlusion) {
            struct RTCRay ray = {r->org[0], r->org[1], r->org[2], r->tnear,
                                 r->dir[0], r->dir[1], r->dir[2], 0.0f,
                                 r->tfar,   0xFFFFFFFFu, 0, 0};
            rtcOccluded1(scene, &ctx, &ray);
            sum += ray.tfar < 0.0f;
        } else {
            struct RTCRayHit rh;
            rh.ray = (struct RTCRay){r->org[0], r->org[1], r->org[2], r->tnear,
                                     r->dir[0], r->dir[1], r->dir[2], 0.0f,
                                     r->tfar,   0xFFFFFFFFu, 0, 0};
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene, &ctx, &rh);
            sum += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? rh.ray.tfar : 0.0f;
        }
    }
    return sum;
}

int main(int argc, char **argv)
{
    const char *scene_path = argc > 1 ? argv[1] : "scenes/cornell-box/scene.json";
    int w = argc > 2 ? atoi(argv[2]) : 256, spp = argc > 3 ? atoi(argv[3]) : 8;
    int repeats = argc > 4 ? atoi(argv[4]) : 9;
    gi_blas_single_thread(); /* its idle threads would share the machine with both loops */
    gi_error err;
    gi_scene scene;
    if (gi_bench_load_scene(scene_path, &scene, &err)) {
        fprintf(stderr, "pt_vs_embree: %s\n", err.msg);
        return 2;
    }
    gi_rt rt;
    if (gi_rt_create(&rt, &scene, &err)) {
        fprintf(stderr, "pt_vs_embree: %s\n", err.msg);
        return 1;
    }
    gi_pt_params p;
    gi_pt_params_default(&p);
    if (getenv("PT_STRATEGY"))
        p.strategy = (gi_pt_strategy)atoi(getenv("PT_STRATEGY"));
    gi_camera_frame cam;
    gi_camera_frame_init(&cam, &scene.camera, w, w);
    gi_pt_tracer tr = {&rt, &scene, &p, NULL};

    /* Record the rays once, then alternate timed runs of the tracer and of
     * the bare loop, so both see the machine in the same state (this VM's
     * speed drifts by tens of percent between seconds). */
    ray_store st = {0};
    gi_pt_ray_log log = {record, &st};
    gi_pt_tracer logged = {&rt, &scene, &p, &log};
    double check = render(&logged, &cam, w, spp);
    uint64_t rays = st.count;
    double best_pt = 1e30, best_bare = 1e30, ratios[64];
    if (repeats > 64)
        repeats = 64;
    for (int r = 0; r < repeats; r++) {
        uint64_t r0 = rt.rays;
        double t0 = now();
        check += render(&tr, &cam, w, spp);
        double t_pt = now() - t0;
        if (rt.rays - r0 != rays) {
            fprintf(stderr, "pt_vs_embree: recorded %llu rays, traced %llu\n",
                    (unsigned long long)rays, (unsigned long long)(rt.rays - r0));
            return 1;
        }
        t0 = now();
        check += replay(rt.scene, &st);
        double t_bare = now() - t0;
        best_pt = t_pt < best_pt ? t_pt : best_pt;
        best_bare = t_bare < best_bare ? t_bare : best_bare;
        ratios[r] = t_bare / t_pt;
    }
    /* Median of the per-round ratios. */
    for (int i = 1; i < repeats; i++)
        for (int j = i; j > 0 && ratios[j - 1] > ratios[j]; j--) {
            double t = ratios[j];
            ratios[j] = ratios[j - 1];
            ratios[j - 1] = t;
        }
    double median = ratios[repeats / 2];
    size_t occl = 0;
    for (size_t i = 0; i < st.count; i++)
        occl += (size_t)st.rays[i].occlusion;
    double pt_rate = (double)rays / best_pt, bare_rate = (double)rays / best_bare;
    printf("scene %s, %dx%d, %d spp, %llu rays (%zu shadow), %d alternating rounds\n",
           scene_path, w, w, spp, (unsigned long long)rays, occl, repeats);
    printf("path tracer   %8.3f s  %6.2f Mrays/s (best round)\n", best_pt, pt_rate / 1e6);
    printf("bare Embree   %8.3f s  %6.2f Mrays/s (best round)\n", best_bare, bare_rate / 1e6);
    printf("ratio         %8.1f %%  median of rounds (best/best %.1f %%; target >= 70 %%)\n",
           100.0 * median, 100.0 * pt_rate / bare_rate);
    printf("(checksum %g)\n", check);
    free(st.rays);
    gi_rt_free(&rt);
    gi_scene_free(&scene);
    return 0;
}
