/* quad_light_map: a point on the scene's emitters from two numbers in [0,1),
 * continuous and with a polynomial Jacobian, for quadrature.
 *
 * The path tracer picks a point with pdf proportional to power and uniform
 * on the triangle (Turk's square-root map): fine for Monte Carlo, but the
 * square root puts a singular derivative into the integrand, which
 * polynomial rules cannot fit. Here instead:
 *   - t in [0,1) picks emitter triangle k through the power CDF
 *     (cdf[k] <= t < cdf[k+1]) and is rescaled to t' in [0,1) inside it;
 *   - the point is p = a + s (b - a) + s t' (c - b) (the square collapsed
 *     onto the triangle at vertex a), whose area element is dA = 2 A_k s
 *     ds dt', so with dt = P_k dt' the light integral is
 *       int h dA = int_0^1 int_0^1 h(p(s, t)) 2 A_k s / P_k ds dt.
 * For a fan-triangulated convex polygon of uniform emission (the Cornell
 * box's light is one quad, two triangles (a,b,c), (a,c,d)), triangle k's
 * t' = 1 edge (a, c) is triangle k+1's t' = 0 edge, and 2 A_k / P_k is the
 * same for every k: the map is continuous over the whole polygon (a kink
 * where the triangles meet). Between separate emitters it jumps, like any
 * geometry edge. */
#ifndef GI_QUAD_LIGHT_MAP_H
#define GI_QUAD_LIGHT_MAP_H

#include "gi_scene.h"
#include "gi_sampling.h"

typedef struct gi_quad_light_point {
    gi_vec3 p;     /* point on the emitter */
    gi_vec3 n;     /* unit front-face normal */
    uint32_t tri;  /* triangle index */
    double weight; /* dA / (ds dt): 2 A_k s / P_k */
} gi_quad_light_point;

/* tri_area[k]: area of emitter k (s->light_tris[k]). */
static inline void gi_quad_light_map(const gi_scene *sc, const double *tri_area, double s,
                                     double t, gi_quad_light_point *out)
{
    uint32_t k = gi_sample_cdf(sc->light_cdf, sc->light_count, t);
    double P = sc->light_cdf[k + 1] - sc->light_cdf[k];
    double tk = (t - sc->light_cdf[k]) / P;
    tk = tk < 0.0 ? 0.0 : tk > 1.0 ? 1.0 : tk;
    uint32_t tri = sc->light_tris[k];
    gi_vec3 a, b, c;
    gi_scene_triangle(sc, tri, &a, &b, &c);
    float fs = (float)s, ft = (float)(s * tk);
    out->p = gi_add(gi_add(a, gi_scale(gi_sub(b, a), fs)), gi_scale(gi_sub(c, b), ft));
    out->n = gi_scene_triangle_normal(sc, tri);
    out->tri = tri;
    out->weight = 2.0 * tri_area[k] * s / P;
}

#endif
