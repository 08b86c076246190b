/* gi_rt: Embree device and scene lifetime, error callback, the two-level
 * layout for scenes with mobile objects (gi_rt.h). */
#include "gi_rt.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void rt_error_callback(void *user, enum RTCError code, const char *str)
{
    gi_rt *rt = user;
    rt->failed = 1;
    snprintf(rt->error, sizeof rt->error, "Embree error %d: %s", (int)code,
             str ? str : "(no message)");
}

static int rt_check(gi_rt *rt, gi_error *err, const char *what)
{
    if (!rt->failed)
        return 0;
    return gi_fail(err, GI_EINTERNAL, "%s: %s", what, rt->error);
}

static RTCGeometry new_object_geometry(gi_rt *rt, const gi_scene *s, uint32_t obj)
{
    const gi_object *o = &s->objects[obj];
    RTCGeometry g = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    /* The whole vertex array, indexed by this object's slice of the global
     * index array: no copies, and hits map back to global triangles. */
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s->positions,
                               0, sizeof(gi_vec3), s->vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s->indices,
                               (size_t)o->first_triangle * 3 * sizeof(uint32_t),
                               3 * sizeof(uint32_t), o->triangle_count);
    if (o->mobile)
        rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
    rtcCommitGeometry(g);
    return g;
}

static void attach_object(gi_rt *rt, RTCScene scene, uint32_t obj)
{
    RTCGeometry g = new_object_geometry(rt, rt->src, obj);
    rtcAttachGeometryByID(scene, g, obj);
    rtcReleaseGeometry(g);
}

/* The object alone in a scene of its own (gi_rt_object_scene). A dynamic,
 * low-quality scene is the one in which Embree honours the geometry's
 * REFIT quality: a moved object's BVH keeps the topology built at load and
 * only its bounds are refit (0.27 -> 0.05 ms for a 1,280-triangle sphere),
 * so the BVH at a pose depends on that pose alone, on every host. */
static RTCScene alone_scene(gi_rt *rt, uint32_t obj)
{
    RTCScene sc = rtcNewScene(rt->device);
    rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_LOW);
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_DYNAMIC);
    attach_object(rt, sc, obj);
    rtcCommitScene(sc);
    return sc;
}

/* `lower` in the top scene as an identity instance: a ray enters it with
 * its own origin and direction bit for bit, so its hits there are those of
 * `lower` traced alone. */
static void attach_instance(gi_rt *rt, RTCScene lower, uint32_t id)
{
    RTCGeometry inst = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(inst, lower);
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
    rtcCommitGeometry(inst);
    rtcAttachGeometryByID(rt->scene, inst, id);
    rtcReleaseGeometry(inst);
}

/* Medium, not high, for the static triangles: high's spatial splits cost
 * 8-10 times the build (100,000 cubes: 3.6 against 0.49 s on one core)
 * and bought no faster GI bounce rays on any scene measured (cubes: 18%
 * slower; a tree, a Cornell box, long slivers: within 2%), `bench/rt_build`. */
#define GI_RT_STATIC_QUALITY RTC_BUILD_QUALITY_MEDIUM

int gi_rt_create(gi_rt *rt, const gi_scene *s, gi_error *err)
{
    memset(rt, 0, sizeof *rt);
    rt->src = s;
    rt->device = rtcNewDevice("threads=1,set_affinity=0,verbose=0");
    if (!rt->device)
        return gi_fail(err, GI_EINTERNAL, "Embree: cannot create a device (error %d)",
                       (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(rt->device, rt_error_callback, rt);
    int two_level = 0;
    for (uint32_t i = 0; i < s->object_count; i++)
        two_level |= s->objects[i].mobile;
    rt->scene = rtcNewScene(rt->device);
    if (!two_level) {
        rtcSetSceneBuildQuality(rt->scene, GI_RT_STATIC_QUALITY);
        for (uint32_t i = 0; i < s->object_count && !rt->failed; i++)
            attach_object(rt, rt->scene, i);
    } else {
        rt->statics = rtcNewScene(rt->device);
        rtcSetSceneBuildQuality(rt->statics, GI_RT_STATIC_QUALITY);
        rt->alone = gi_xcalloc(s->object_count, sizeof *rt->alone);
        rt->mobiles = gi_xmalloc(s->object_count * sizeof *rt->mobiles);
        for (uint32_t i = 0; i < s->object_count && !rt->failed; i++)
            if (s->objects[i].mobile) {
                rt->alone[i] = alone_scene(rt, i);
                rt->mobiles[rt->mobile_count++] = i;
            } else {
                attach_object(rt, rt->statics, i);
            }
        rtcCommitScene(rt->statics);
        /* The top level changes every frame: a quick build of a few entries. */
        rtcSetSceneBuildQuality(rt->scene, RTC_BUILD_QUALITY_LOW);
        attach_instance(rt, rt->statics, s->object_count); /* past every object's ID */
        for (uint32_t k = 0; k < rt->mobile_count && !rt->failed; k++)
            attach_instance(rt, rt->alone[rt->mobiles[k]], rt->mobiles[k]);
    }
    if (!rt->failed)
        rtcCommitScene(rt->scene);
    if (rt_check(rt, err, "building the ray tracing scene")) {
        gi_rt_free(rt);
        return -1;
    }
    return 0;
}

void gi_rt_free(gi_rt *rt)
{
    if (rt->alone) {
        for (uint32_t i = 0; i < rt->src->object_count; i++)
            if (rt->alone[i])
                rtcReleaseScene(rt->alone[i]);
        free(rt->alone);
    }
    free(rt->mobiles);
    rt->mobiles = NULL;
    rt->mobile_count = 0;
    if (rt->scene)
        rtcReleaseScene(rt->scene);
    if (rt->statics)
        rtcReleaseScene(rt->statics);
    if (rt->device)
        rtcReleaseDevice(rt->device);
    rt->alone = NULL;
    rt->scene = rt->statics = NULL;
    rt->device = NULL;
}

static void refit(RTCScene scene, uint32_t object)
{
    RTCGeometry g = rtcGetGeometry(scene, object);
    rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(g);
    rtcCommitScene(scene);
}

int gi_rt_update_object(gi_rt *rt, uint32_t object, gi_error *err)
{
    if (object >= rt->src->object_count)
        return gi_fail(err, GI_EINTERNAL, "gi_rt_update_object: no object %u", object);
    if (rt->statics) {
        /* Two levels: refit the object's lower scene, tell its instance,
         * rebuild the top level (a few entries). A static object that moved
         * after all refits the statics' scene, and any scene of its own. */
        int mobile = rt->src->objects[object].mobile;
        refit(mobile ? rt->alone[object] : rt->statics, object);
        if (!mobile && rt->alone[object])
            refit(rt->alone[object], object);
        RTCGeometry inst = rtcGetGeometry(rt->scene, mobile ? object : rt->src->object_count);
        rtcCommitGeometry(inst);
        rtcCommitScene(rt->scene);
    } else {
        refit(rt->scene, object);
        if (rt->alone && rt->alone[object])
            refit(rt->alone[object], object);
    }
    return rt_check(rt, err, "updating a moved object");
}

/* Point query callback: a primitive's bounds reach the query sphere. */
static bool found_one(struct RTCPointQueryFunctionArguments *args)
{
    *(int *)args->userPtr = 1;
    args->query->radius = 0.0f; /* the answer is known: shrink the rest away */
    return true;
}

/* Some primitive of `scene` has bounds within r of c. */
static int reaches(RTCScene scene, gi_vec3 c, float r)
{
    struct RTCPointQuery q = {.x = c.x, .y = c.y, .z = c.z, .time = 0.0f, .radius = r};
    struct RTCPointQueryContext qc;
    rtcInitPointQueryContext(&qc);
    int found = 0;
    rtcPointQuery(scene, &q, &qc, found_one, &found);
    return found;
}

int gi_rt_others_near(gi_rt *rt, uint32_t object, gi_vec3 c, float r)
{
    if (!rt->statics || reaches(rt->statics, c, r))
        return 1;
    /* Every other mobile object has a scene of its own. */
    for (uint32_t k = 0; k < rt->mobile_count; k++)
        if (rt->mobiles[k] != object && reaches(rt->alone[rt->mobiles[k]], c, r))
            return 1;
    return 0;
}

int gi_rt_intersect_except(gi_rt *rt, uint32_t object, gi_vec3 org, gi_vec3 dir, float tnear,
                           float tfar, gi_hit *hit)
{
    rt->rays++;
    int any = gi_rt_intersect_in(rt, rt->statics, org, dir, tnear, tfar, hit);
    for (uint32_t k = 0; k < rt->mobile_count; k++)
        if (rt->mobiles[k] != object &&
            gi_rt_intersect_in(rt, rt->alone[rt->mobiles[k]], org, dir, tnear,
                               any ? hit->t : tfar, hit))
            any = 1;
    return any;
}

RTCScene gi_rt_object_scene(gi_rt *rt, uint32_t object, gi_error *err)
{
    if (object >= rt->src->object_count) {
        gi_fail(err, GI_EINTERNAL, "gi_rt_object_scene: no object %u", object);
        return NULL;
    }
    if (!rt->alone)
        rt->alone = gi_xcalloc(rt->src->object_count, sizeof *rt->alone);
    if (!rt->alone[object]) {
        RTCScene sc = alone_scene(rt, object);
        if (rt_check(rt, err, "building an object's own scene")) {
            rtcReleaseScene(sc);
            return NULL;
        }
        rt->alone[object] = sc;
    }
    return rt->alone[object];
}
