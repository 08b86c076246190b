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
#include "gi_rt.h"
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

static uint64_t splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}

static float uniform01(uint64_t *x)
{
    return (float)(splitmix(x) >> 40) * (1.0f / 16777216.0f);
}

typedef struct {
    float org[3], dir[3];
} bounce_ray;

static gi_vec3 corner(const gi_scene *s, uint32_t tri, int k)
{
    return s->positions[s->indices[3 * (size_t)tri + (size_t)k]];
}

/* n rays off the scene's triangles, area-weighted, cosine about the normal. */
static bounce_ray *bounce_rays(const gi_scene *s, size_t n)
{
    double *cdf = malloc(s->triangle_count * sizeof *cdf);
    double total = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        gi_vec3 a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
        gi_vec3 e1 = {b.x - a.x, b.y - a.y, b.z - a.z}, e2 = {c.x - a.x, c.y - a.y, c.z - a.z};
        double nx = (double)e1.y * e2.z - (double)e1.z * e2.y;
        double ny = (double)e1.z * e2.x - (double)e1.x * e2.z;
        double nz = (double)e1.x * e2.y - (double)e1.y * e2.x;
        total += 0.5 * sqrt(nx * nx + ny * ny + nz * nz);
        cdf[t] = total;
    }
    bounce_ray *r = malloc(n * sizeof *r);
    uint64_t seed = 12345;
    for (size_t i = 0; i < n; i++) {
        double u = (double)uniform01(&seed) * total;
        size_t lo = 0, hi = s->triangle_count - 1;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (cdf[mid] < u)
                lo = mid + 1;
            else
                hi = mid;
        }
        uint32_t t = (uint32_t)lo;
        gi_vec3 a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
        float su = sqrtf(uniform01(&seed)), v = uniform01(&seed);
        float wa = 1 - su, wb = su * (1 - v), wc = su * v;
        gi_vec3 e1 = {b.x - a.x, b.y - a.y, b.z - a.z}, e2 = {c.x - a.x, c.y - a.y, c.z - a.z};
        float nx = e1.y * e2.z - e1.z * e2.y, ny = e1.z * e2.x - e1.x * e2.z,
              nz = e1.x * e2.y - e1.y * e2.x;
        float len = sqrtf(nx * nx + ny * ny + nz * nz);
        if (len == 0) {
            nx = 0, ny = 0, nz = 1, len = 1;
        }
        nx /= len, ny /= len, nz /= len;
        /* Any two tangents; the cosine lobe is symmetric about the normal. */
        float tx, ty, tz;
        if (fabsf(nx) < 0.9f)
            tx = 0, ty = -nz, tz = ny;
        else
            tx = nz, ty = 0, tz = -nx;
        float tl = sqrtf(tx * tx + ty * ty + tz * tz);
        tx /= tl, ty /= tl, tz /= tl;
        float bx = ny * tz - nz * ty, by = nz * tx - nx * tz, bz = nx * ty - ny * tx;
        float r1 = uniform01(&seed), phi = 6.2831853f * uniform01(&seed);
        float sr = sqrtf(r1), x = sr * cosf(phi), y = sr * sinf(phi), z = sqrtf(1 - r1);
        bounce_ray *q = &r[i];
        q->org[0] = wa * a.x + wb * b.x + wc * c.x;
        q->org[1] = wa * a.y + wb * b.y + wc * c.y;
        q->org[2] = wa * a.z + wb * b.z + wc * c.z;
        q->dir[0] = x * tx + y * bx + z * nx;
        q->dir[1] = x * ty + y * by + z * ny;
        q->dir[2] = x * tz + y * bz + z * nz;
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
        rh.ray.org_x = r[i].org[0], rh.ray.org_y = r[i].org[1], rh.ray.org_z = r[i].org[2];
        rh.ray.dir_x = r[i].dir[0], rh.ray.dir_y = r[i].dir[1], rh.ray.dir_z = r[i].dir[2];
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
