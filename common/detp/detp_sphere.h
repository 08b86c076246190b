/* detp_sphere: the sphere geometry both Sphere Caches share (internal). */
#ifndef GI_DETP_SPHERE_H
#define GI_DETP_SPHERE_H

#include "detp.h"

/* S_0: the sphere around the box [lo, hi], grown by the disc radius so that
 * it holds every disc centred in the box. */
static inline void gi_detp_sphere_root(gi_vec3 lo, gi_vec3 hi, float radius, gi_vec3 *c,
                                       float *r)
{
    *c = gi_scale(gi_add(lo, hi), 0.5f);
    *r = 0.5f * gi_length(gi_sub(hi, lo)) * 1.0001f + radius;
}

/* Margin added to sphere radii in segment tests, so that rounding never
 * drops a segment that crosses a disc inside the sphere: 1e-5 of S_0,
 * far above float error at the scene's scale. */
static inline float gi_detp_sphere_slack(float r0) { return 1e-5f * r0; }

/* The whole disc (centre p, radius d) lies inside sphere (c, r). */
static inline int gi_detp_sphere_holds(gi_vec3 c, float r, gi_vec3 p, float d)
{
    return gi_length(gi_sub(p, c)) + d <= r;
}

/* The part of the segment that can feed a disc, [0, t_end], comes within
 * sqrt(rr) of c. */
static inline int gi_detp_segment_meets_sphere(const gi_detp_segment *g, gi_vec3 c, float rr)
{
    gi_vec3 oc = gi_sub(c, g->org);
    float t = gi_dot(oc, g->dir);
    t = t < 0.0f ? 0.0f : (t > g->t_end ? g->t_end : t);
    gi_vec3 q = gi_sub(oc, gi_scale(g->dir, t));
    return gi_dot(q, q) <= rr;
}

#endif
