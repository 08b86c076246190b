/* rt_build: what building the ray tracing scene costs, against the same
 * triangles given to Embree other ways, for scenes of many objects.
 *
 *   rt_build SCENE [ROUNDS]
 *
 * Loads SCENE once (timed), then ROUNDS times, alternating: gi_rt_create
 * (one triangle geometry per object, HIGH build quality: what the methods
 * use), and bare Embree builds of the same buffers: one geometry per object
 * and one geometry for all triangles, each at HIGH and at MEDIUM quality.
 * Prints the median of each (one core: the device has threads=1, as in a
 * pool child). Tells per-object overhead (the two layouts) from the cost
 * of the build quality. */
#include <stdio.h>
#include <stdlib.h>

#include <embree3/rtcore.h>

#include "bench_util.h"
#include "gi_assets.h"
#include "gi_rt.h"
#include "gi_scene.h"

static double bare_build(RTCDevice dev, const gi_scene *s, int one_geometry,
                         enum RTCBuildQuality q)
{
    double t0 = gi_bench_now();
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
    double t = gi_bench_now() - t0;
    rtcReleaseScene(sc);
    return t;
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: rt_build SCENE [ROUNDS]\n");
        return 2;
    }
    int rounds = argc == 3 ? atoi(argv[2]) : 3;
    if (rounds < 1 || rounds > 100) {
        fprintf(stderr, "rt_build: ROUNDS: 1 to 100\n");
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
        "gi_rt_create (per object, HIGH)", "bare, per object, HIGH", "bare, one geometry, HIGH",
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
    rtcReleaseDevice(dev);
    gi_scene_free(&s);
    gi_dir_source_free(&d);
    return rc;
}
