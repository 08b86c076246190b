/* rt_build: what building the ray tracing scene costs, against the same
 * triangles given to Embree other ways, for scenes of many objects.
 *
 *   rt_build SCENE [ROUNDS [RAYS]]
 *
 * Loads SCENE once (timed), then ROUNDS times, alternating: gi_rt_create
 * (one triangle geometry per object, medium build quality: what the methods
 * use), and bare Embree builds of the same buffers: one geometry per object
 * and one geometry for all triangles, each at HIGH and at MEDIUM quality.
 * Prints the median of each (one core: the device has threads=1, as in a
 * pool child). Tells per-object overhead (the two layouts) from the cost
 * of the build quality.
 *
 * Then what the quality buys: RAYS incoherent rays (default 1,000,000; 0
 * skips this) traced through the per-object scene built at HIGH and at
 * MEDIUM, alternating, ROUNDS times: each ray leaves a random point of a
 * random triangle (area-weighted) in a cosine-distributed direction about
 * its normal, like a GI bounce. Prints the median time per million rays of
 * each and how many rays the two BVHs give a different first hit (a tie
 * between two triangles at one distance goes either way). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <embree3/rtcore.h>

#include "bench_util.h"
#include "gi_assets.h"
#include "gi_rng.h"
#include "gi_rt.h"
#include "gi_sampling.h"
#include "gi_scene.h"

/* The scene's triangles in one Embree scene: one geometry per object (as
 * gi_rt does) or one for all of them. */
static RTCScene bare_scene(RTCDevice dev, const gi_scene *s, int one_geometry,
                           enum RTCBuildQuality q)
{
    RTCScene sc = rtcNewScene(dev);
    rtcSetSceneBuildQuality(sc, q);
    uint32_t n = one_geometry ? 1 : s->object_count;
    for (uint32_t i = 0; i < n; i++) {
        const gi_object *o = &s->objects[i];
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s->positions,
                                   0, sizeof(gi_vec3), s->vertex_count);
        size_t first = one_geometry ? 0 : o->first_triangle;
        size_t count = one_geometry ? s->triangle_count : o->triangle_count;
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s->indices,
                                   first * 3 * sizeof(uint32_t), 3 * sizeof(uint32_t), count);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(sc, g, i);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(sc);
    return sc;
}

static double bare_build(RTCDevice dev, const gi_scene *s, int one_geometry,
                         enum RTCBuildQuality q)
{
    double t0 = gi_bench_now();
    RTCScene sc = bare_scene(dev, s, one_geometry, q);
    double t = gi_bench_now() - t0;
    rtcReleaseScene(sc);
    return t;
}

typedef struct {
    gi_vec3 org, dir;
} bounce_ray;

/* n rays off the scene's triangles, area-weighted, cosine about the normal
 * (the samplers the methods use). */
static bounce_ray *bounce_rays(const gi_scene *s, size_t n)
{
    uint32_t tris = s->triangle_count;
    double *cdf = malloc((tris + 1) * sizeof *cdf);
    cdf[0] = 0;
    for (uint32_t t = 0; t < tris; t++)
        cdf[t + 1] = cdf[t] + gi_scene_triangle_area(s, t);
    for (uint32_t t = 1; t <= tris; t++)
        cdf[t] /= cdf[tris];
    bounce_ray *r = malloc(n * sizeof *r);
    gi_rng rng;
    gi_rng_init(&rng, 12345, 0, 0);
    for (size_t i = 0; i < n; i++) {
        uint32_t t = gi_sample_cdf(cdf, tris, gi_rng_double(&rng));
        const uint32_t *v = &s->indices[3 * (size_t)t];
        gi_vec3 a = s->positions[v[0]], b = s->positions[v[1]], c = s->positions[v[2]];
        gi_vec3 nrm = gi_triangle_normal(a, b, c);
        if (gi_dot(nrm, nrm) == 0)
            nrm = gi_v3(0, 0, 1);
        float u1 = gi_rng_float(&rng), u2 = gi_rng_float(&rng);
        r[i].org = gi_sample_triangle(a, b, c, u1, u2);
        u1 = gi_rng_float(&rng), u2 = gi_rng_float(&rng);
        r[i].dir = gi_sample_cosine(nrm, u1, u2);
    }
    free(cdf);
    return r;
}

/* Traces the rays; hits[i] = the first hit's geometry and primitive (or ~0).
 * Returns seconds. */
static double trace(RTCScene sc, const bounce_ray *r, size_t n, uint64_t *hits)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    double t0 = gi_bench_now();
    for (size_t i = 0; i < n; i++) {
        struct RTCRayHit rh;
        rh.ray.org_x = r[i].org.x, rh.ray.org_y = r[i].org.y, rh.ray.org_z = r[i].org.z;
        rh.ray.dir_x = r[i].dir.x, rh.ray.dir_y = r[i].dir.y, rh.ray.dir_z = r[i].dir.z;
        rh.ray.tnear = 1e-4f;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = ~0u;
        rh.ray.flags = 0;
        rh.ray.time = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(sc, &ctx, &rh);
        hits[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID
                      ? ~(uint64_t)0
                      : (uint64_t)rh.hit.geomID << 32 | rh.hit.primID;
    }
    return gi_bench_now() - t0;
}

static void ray_rounds(RTCDevice dev, const gi_scene *s, size_t n, int rounds)
{
    bounce_ray *r = bounce_rays(s, n);
    uint64_t *h[2] = {malloc(n * sizeof(uint64_t)), malloc(n * sizeof(uint64_t))};
    RTCScene sc[2] = {bare_scene(dev, s, 0, RTC_BUILD_QUALITY_HIGH),
                      bare_scene(dev, s, 0, RTC_BUILD_QUALITY_MEDIUM)};
    double *t[2] = {calloc((size_t)rounds, sizeof(double)), calloc((size_t)rounds, sizeof(double))};
    for (int k = 0; k < rounds; k++)
        for (int q = 0; q < 2; q++) {
            int which = (k % 2) ? 1 - q : q; /* alternate which goes first */
            t[which][k] = trace(sc[which], r, n, h[which]);
        }
    size_t differ = 0, missed = 0;
    for (size_t i = 0; i < n; i++) {
        differ += h[0][i] != h[1][i];
        missed += h[0][i] == ~(uint64_t)0;
    }
    double high = gi_bench_median(t[0], rounds), medium = gi_bench_median(t[1], rounds);
    printf("  %zu bounce rays (%zu escape): HIGH %.3f s, MEDIUM %.3f s per million "
           "(medians of %d; MEDIUM/HIGH %.3f); first hits differing: %zu\n",
           n, missed, high * 1e6 / (double)n, medium * 1e6 / (double)n, rounds, medium / high,
           differ);
    for (int q = 0; q < 2; q++) {
        rtcReleaseScene(sc[q]);
        free(h[q]);
        free(t[q]);
    }
    free(r);
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 4) {
        fprintf(stderr, "usage: rt_build SCENE [ROUNDS [RAYS]]\n");
        return 2;
    }
    int rounds = argc >= 3 ? atoi(argv[2]) : 3;
    if (rounds < 1 || rounds > 100) {
        fprintf(stderr, "rt_build: ROUNDS: 1 to 100\n");
        return 2;
    }
    long rays = argc == 4 ? atol(argv[3]) : 1000000;
    if (rays < 0 || rays > 100000000) {
        fprintf(stderr, "rt_build: RAYS: 0 to 100000000\n");
        return 2;
    }
    gi_dir_source d;
    gi_dir_source_init(&d, ".");
    gi_asset_source src = gi_dir_source_as_source(&d);
    gi_scene s;
    gi_error err;
    double t0 = gi_bench_now();
    if (gi_scene_load(&src, argv[1], &s, &err)) {
        fprintf(stderr, "rt_build: %s\n", err.msg);
        gi_dir_source_free(&d);
        return 1;
    }
    printf("%s: %u objects, %u triangles, %u vertices; loaded in %.3f s\n", argv[1],
           s.object_count, s.triangle_count, s.vertex_count, gi_bench_now() - t0);
    static const char *const what[5] = {
        "gi_rt_create (per object, MEDIUM)", "bare, per object, HIGH", "bare, one geometry, HIGH",
        "bare, per object, MEDIUM", "bare, one geometry, MEDIUM"};
    double *t[5];
    for (int k = 0; k < 5; k++)
        t[k] = calloc((size_t)rounds, sizeof *t[k]);
    RTCDevice dev = rtcNewDevice("threads=1,set_affinity=0,verbose=0");
    int rc = 0;
    for (int r = 0; r < rounds && rc == 0; r++) {
        gi_rt rt;
        double a = gi_bench_now();
        if (gi_rt_create(&rt, &s, &err)) {
            fprintf(stderr, "rt_build: %s\n", err.msg);
            rc = 1;
            break;
        }
        t[0][r] = gi_bench_now() - a;
        gi_rt_free(&rt);
        t[1][r] = bare_build(dev, &s, 0, RTC_BUILD_QUALITY_HIGH);
        t[2][r] = bare_build(dev, &s, 1, RTC_BUILD_QUALITY_HIGH);
        t[3][r] = bare_build(dev, &s, 0, RTC_BUILD_QUALITY_MEDIUM);
        t[4][r] = bare_build(dev, &s, 1, RTC_BUILD_QUALITY_MEDIUM);
    }
    for (int k = 0; k < 5 && rc == 0; k++)
        printf("  %-34s median %.3f s of %d\n", what[k], gi_bench_median(t[k], rounds), rounds);
    for (int k = 0; k < 5; k++)
        free(t[k]);
    if (rc == 0 && rays > 0 && s.triangle_count > 0)
        ray_rounds(dev, &s, (size_t)rays, rounds);
    rtcReleaseDevice(dev);
    gi_scene_free(&s);
    gi_dir_source_free(&d);
    return rc;
}
