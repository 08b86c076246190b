/* gi_rt: ray tracing through Embree 3.
 *
 * One Embree device and scene per process, created after fork() (never
 * inherited), single-threaded: a pool already runs one process per core.
 * Each scene object is its own triangle geometry whose geomID is the object
 * index, so objects can move on their own later; a hit reports the global
 * triangle index. Embree errors go through an error callback into gi_error.
 *
 * A scene with mobile objects is two-level: the static objects are one
 * scene, built once (medium quality, see gi_rt.c), and each mobile object
 * a scene of its own (gi_rt_object_scene), all placed in the top scene as identity
 * instances. Moving an object then refits its own scene and rebuilds a top
 * level of a few entries instead of the whole BVH, and a ray traced against
 * the mobile alone finds bit for bit the hits it finds there in the whole
 * scene. Hits inside an instance report the object's geomID all the same.
 * Scenes without mobile objects stay one level (their hits are bit for bit
 * what they were). */
#ifndef GI_RT_H
#define GI_RT_H

#include <stdint.h>

#include <embree3/rtcore.h>

#include "gi_error.h"
#include "gi_math.h"
#include "gi_scene.h"

typedef struct gi_rt {
    RTCDevice device;
    RTCScene scene;      /* what rays are traced against */
    RTCScene statics;    /* two-level only: the objects that never move, one instance in scene */
    RTCScene *alone;     /* per object: the object alone (gi_rt_object_scene), or NULL */
    /* Two-level only: the mobile objects' indices, ascending (the per-ray
     * loops over them would otherwise visit every object of the scene). */
    uint32_t *mobiles, mobile_count;
    const gi_scene *src; /* geometry buffers are shared with the gi_scene */
    uint64_t rays;       /* rays traced (closest hit + occlusion) */
    int failed;          /* set by the Embree error callback */
    char error[256];
} gi_rt;

typedef struct gi_hit {
    float t;      /* distance along the (unit) direction */
    uint32_t tri; /* global triangle index */
    float u, v;   /* barycentrics: p = (1-u-v) a + u b + v c */
    gi_vec3 ng;   /* geometric normal (unnormalized, front face side) */
} gi_hit;

/* Builds the acceleration structure over every object of `scene`. The scene
 * must outlive the gi_rt (its vertex and index arrays are shared). */
int gi_rt_create(gi_rt *rt, const gi_scene *scene, gi_error *err);
void gi_rt_free(gi_rt *rt);
/* Re-reads the object's vertices from the gi_scene (it moved) and rebuilds
 * (and its gi_rt_object_scene, if made). A mobile object's BVH is refit
 * instead: its topology is the one built at load, so its hits at a pose do
 * not depend on the poses before. */
int gi_rt_update_object(gi_rt *rt, uint32_t object, gi_error *err);
/* A scene holding the object alone, at its current pose (the animation
 * tests segments against the mobile only): made on first use, kept in step
 * by gi_rt_update_object, owned by rt. NULL on failure (err says why). */
RTCScene gi_rt_object_scene(gi_rt *rt, uint32_t object, gi_error *err);

/* 0 if no triangle of any object but `object` comes within r of c (their
 * BVH bounds, rounded outward, all lie farther); 1 if one may. Always 1 for
 * a scene without mobile objects (one BVH holds them all). */
int gi_rt_others_near(gi_rt *rt, uint32_t object, gi_vec3 c, float r);

/* The closest hit along org + t dir among every object but `object`: the
 * static scene, then every other mobile object's own scene (the closer
 * wins; on equal t the later). Its hits are the ones those objects give in
 * the whole scene, bit for bit. For a two-level rt and a mobile `object`
 * only (gi_rt_splits). Counted as one ray. */
int gi_rt_intersect_except(gi_rt *rt, uint32_t object, gi_vec3 org, gi_vec3 dir, float tnear,
                           float tfar, gi_hit *hit);
/* rt is two-level and `object` is one of its mobile objects. */
static inline int gi_rt_splits(const gi_rt *rt, uint32_t object)
{
    return rt->statics && object < rt->src->object_count && rt->src->objects[object].mobile &&
           rt->alone && rt->alone[object];
}

/* gi_rt_intersect against `scene` (rt's, or one of its gi_rt_object_scene),
 * not counted in rt->rays. */
static inline int gi_rt_intersect_in(const gi_rt *rt, RTCScene scene, gi_vec3 org, gi_vec3 dir,
                                     float tnear, float tfar, gi_hit *hit)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    rh.ray.org_x = org.x;
    rh.ray.org_y = org.y;
    rh.ray.org_z = org.z;
    rh.ray.tnear = tnear;
    rh.ray.dir_x = dir.x;
    rh.ray.dir_y = dir.y;
    rh.ray.dir_z = dir.z;
    rh.ray.time = 0.0f;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    hit->t = rh.ray.tfar;
    hit->tri = rt->src->objects[rh.hit.geomID].first_triangle + rh.hit.primID;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->ng = gi_v3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    return 1;
}

/* Closest hit along org + t dir, t in [tnear, tfar]; dir need not be unit
 * (t is then in units of |dir|). Returns 1 on a hit, 0 on a miss. */
static inline int gi_rt_intersect(gi_rt *rt, gi_vec3 org, gi_vec3 dir, float tnear,
                                  float tfar, gi_hit *hit)
{
    rt->rays++;
    return gi_rt_intersect_in(rt, rt->scene, org, dir, tnear, tfar, hit);
}

/* 1 if anything blocks the segment org + t dir, t in [tnear, tfar]. */
static inline int gi_rt_occluded(gi_rt *rt, gi_vec3 org, gi_vec3 dir, float tnear,
                                 float tfar)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    r.org_x = org.x;
    r.org_y = org.y;
    r.org_z = org.z;
    r.tnear = tnear;
    r.dir_x = dir.x;
    r.dir_y = dir.y;
    r.dir_z = dir.z;
    r.time = 0.0f;
    r.tfar = tfar;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(rt->scene, &ctx, &r);
    rt->rays++;
    return r.tfar < 0.0f;
}

/* A ray origin moved off the surface at p (geometric normal ng) towards the
 * side `dir` leaves through, by an amount relative to p's magnitude, so the
 * new ray does not hit the surface it starts on. */
static inline float gi_rt_offset_scale(gi_vec3 p)
{
    return 2e-5f * gi_maxf(1.0f, gi_maxf(fabsf(p.x), gi_maxf(fabsf(p.y), fabsf(p.z))));
}

static inline gi_vec3 gi_rt_offset(gi_vec3 p, gi_vec3 ng_unit, gi_vec3 dir)
{
    float eps = gi_rt_offset_scale(p);
    return gi_madd(p, ng_unit, gi_dot(ng_unit, dir) >= 0.0f ? eps : -eps);
}

/* A shadow segment from surface point p (facing geometric normal ng_f) to a
 * point on an emitter at distance dist along unit wi, whose normal makes
 * |cos| = 1 / inv_cos_l with wi. The origin is moved e off p's surface;
 * that brings the emitter's plane up to e / |cos_l| closer, so the segment
 * stops that much (plus a margin) short of the emitter point. Returns 0 if
 * nothing is left of it (the points nearly touch). */
static inline int gi_rt_shadow_segment(gi_vec3 p, gi_vec3 ng_f, gi_vec3 light_p, float dist,
                                       float inv_cos_l, gi_vec3 *org, float *tfar)
{
    float e = gi_rt_offset_scale(p);
    *org = gi_madd(p, ng_f, e);
    *tfar = dist - e * inv_cos_l - 2.0f * gi_rt_offset_scale(light_p);
    return *tfar > 0.0f;
}

#endif
