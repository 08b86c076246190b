/* gi_rt: Embree device and scene lifetime, error callback. */
#include "gi_rt.h"

#include <stdio.h>
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

int gi_rt_create(gi_rt *rt, const gi_scene *s, gi_error *err)
{
    memset(rt, 0, sizeof *rt);
    rt->src = s;
    rt->device = rtcNewDevice("threads=1,set_affinity=0,verbose=0");
    if (!rt->device)
        return gi_fail(err, GI_EINTERNAL, "Embree: cannot create a device (error %d)",
                       (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(rt->device, rt_error_callback, rt);
    rt->scene = rtcNewScene(rt->device);
    rtcSetSceneBuildQuality(rt->scene, RTC_BUILD_QUALITY_HIGH);
    for (uint32_t i = 0; i < s->object_count && !rt->failed; i++) {
        RTCGeometry g = new_object_geometry(rt, s, i);
        rtcAttachGeometryByID(rt->scene, g, i);
        rtcReleaseGeometry(g);
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
    if (rt->scene)
        rtcReleaseScene(rt->scene);
    if (rt->device)
        rtcReleaseDevice(rt->device);
    rt->scene = NULL;
    rt->device = NULL;
}

int gi_rt_update_object(gi_rt *rt, uint32_t object, gi_error *err)
{
    if (object >= rt->src->object_count)
        return gi_fail(err, GI_EINTERNAL, "gi_rt_update_object: no object %u", object);
    RTCGeometry g = rtcGetGeometry(rt->scene, object);
    rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(g);
    rtcCommitScene(rt->scene);
    return rt_check(rt, err, "updating a moved object");
}
