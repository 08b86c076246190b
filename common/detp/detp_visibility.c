/* detp_visibility: the visible part of each disc, for artifact control
 * rule 2 (thesis 1.5: "if part of the disc is not visible from the ray
 * origin, the contribution is divided by the area of the visible part").
 *
 * The thesis does not say how to compute that area. Per ray it would take
 * a visibility integral over the disc for every crossing. We compute, once
 * per disc, the fraction of the disc that can be reached from the disc's
 * centre along its tangent plane without crossing the scene: shadow rays
 * from just above the centre to points just above the disc (64 points of
 * equal area: 4 rings x 16 sectors). A part that is behind a wall meeting
 * the surface (a room's corner) or under an object standing on it is
 * reachable by no photon either, as long as segments stop at their first
 * hit (rule 2 is used with that extent, not with rule 1's extension through
 * the surface, which already sends photons through the wall into that
 * part: both together would count it twice). The origin is moved a little
 * into the vertex's own triangles, so that a vertex lying on the wall's
 * plane is on the room's side of it. */
#include <math.h>

#include "detp.h"

#define VIS_RINGS 4
#define VIS_SECTORS 16
_Static_assert(VIS_RINGS * VIS_SECTORS == GI_DETP_VIS_RAYS, "the rays detp.h counts");

void gi_detp_inward_dirs(const gi_scene *s, gi_vec3 *out)
{
    for (uint32_t i = 0; i < s->vertex_count; i++)
        out[i] = gi_v3(0, 0, 0);
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        gi_vec3 a, b, c;
        gi_scene_triangle(s, t, &a, &b, &c);
        gi_vec3 g = gi_scale(gi_add(gi_add(a, b), c), 1.0f / 3.0f);
        for (int k = 0; k < 3; k++) {
            uint32_t v = s->indices[3 * (size_t)t + k];
            out[v] = gi_add(out[v], gi_normalize(gi_sub(g, s->positions[v])));
        }
    }
    for (uint32_t i = 0; i < s->vertex_count; i++) {
        gi_vec3 n = gi_normalize(s->normals[i]);
        gi_vec3 w = gi_sub(out[i], gi_scale(n, gi_dot(out[i], n))); /* in the tangent plane */
        out[i] = gi_normalize(w);
    }
}

float gi_detp_visible_fraction(gi_rt *rt, const gi_detp_disc *D, float radius, gi_vec3 inward)
{
    gi_vec3 t, b;
    gi_onb(D->n, &t, &b);
    float m = gi_maxf(1.0f, gi_maxf(fabsf(D->c.x), gi_maxf(fabsf(D->c.y), fabsf(D->c.z))));
    float eps = gi_maxf(1e-3f * radius, 4e-5f * m);
    gi_vec3 org = gi_madd(gi_madd(D->c, D->n, eps), inward, eps);
    int open = 0;
    for (int r = 0; r < VIS_RINGS; r++) {
        float rad = radius * sqrtf(((float)r + 0.5f) / VIS_RINGS);
        for (int k = 0; k < VIS_SECTORS; k++) {
            float phi = (float)(2.0 * GI_PI) * ((float)k + 0.5f * (float)(r & 1)) / VIS_SECTORS;
            gi_vec3 q = gi_madd(gi_madd(D->c, t, rad * cosf(phi)), b, rad * sinf(phi));
            q = gi_madd(q, D->n, eps);
            gi_vec3 dir = gi_sub(q, org);
            float len = gi_length(dir);
            if (!(len > 0.0f) || !gi_rt_occluded(rt, org, gi_scale(dir, 1.0f / len), 0.0f, len))
                open++;
        }
    }
    return (float)open / (VIS_RINGS * VIS_SECTORS);
}
