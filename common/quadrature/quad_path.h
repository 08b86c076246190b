/* quad_path: the integrand of the quadrature renderer - a documented map
 * from the unit hypercube [0,1]^N to a light path, and its RGB radiance.
 *
 * Coordinates (0-based):
 *   u0, u1            the image plane, the whole image: the camera ray goes
 *                     through pixel position (u0 W, u1 H) (pinhole, as pt);
 *   per path vertex k = 1, 2, ... (the k-th surface hit from the camera):
 *     u[2+4(k-1)], u[3+4(k-1)]   the point on the emitters for next-event
 *                                estimation at vertex k (quad_light_map.h);
 *     u[4+4(k-1)], u[5+4(k-1)]   the BSDF direction from vertex k
 *                                (cosine-weighted through the continuous
 *                                concentric disc map, gi_sample_cosine),
 *                                giving vertex k+1.
 * The path's radiance is the emission seen directly at vertex 1 plus, at
 * every vertex, the throughput times the next-event estimate
 *   f_r Le cos_s |cos_l| / d^2 V  x  dA/du  (light sampling only: emission
 * met at later vertices is not counted, so each coordinate pair has one
 * job). Its integral over the cube is the pixel-averaged image integral
 * (pixel value = W H x the integral over the pixel's slab).
 *
 * N = 4 is direct light; N = 6 adds one bounce. Coordinates at or beyond N:
 *   - cut (pure quadrature, gi_quad_path_eval): the path ends at the last
 *     vertex whose incoming direction lies below N, and a vertex whose own
 *     light coordinates lie beyond N uses the last light pair below N (so
 *     N = 6 has vertices 1 and 2, both lit through u2, u3). Each term's
 *     integral is still exactly its share of the rendering equation, so the
 *     only bias is the missing longer paths: vertices = 1 + floor((N-2)/4),
 *     and max_bounces may lower it.
 *   - filled by Monte Carlo (hybrid, gi_quad_path_eval_mc): coordinates
 *     beyond N come from a random stream, every vertex uses its own light
 *     pair, and the path continues (Russian roulette after rr_depth on the
 *     random part) up to max_bounces (-1: unlimited). Unbiased.
 * Scattering events are counted as pt's max_bounces: 1 = direct light. */
#ifndef GI_QUAD_PATH_H
#define GI_QUAD_PATH_H

#include <stdint.h>

#include "gi_bsdf.h"
#include "gi_camera.h"
#include "gi_rng.h"
#include "gi_rt.h"

typedef struct gi_quad_path {
    gi_rt *rt;
    const gi_scene *scene;
    gi_camera_frame cam;
    int width, height;
    int dims;
    int max_bounces;  /* -1: unlimited */
    int rr_depth;
    double *light_area; /* per emitter triangle */
    uint64_t nonfinite; /* samples set to 0 (not finite) */
    /* The last camera vertex (consecutive points share it). */
    int cache_valid;
    double cache_u0, cache_u1;
    int cache_hit;
    gi_hit cache_h;
    gi_vec3 cache_dir;
} gi_quad_path;

int gi_quad_path_init(gi_quad_path *p, gi_rt *rt, const gi_scene *s, const gi_camera *cam,
                      int width, int height, int dims, int max_bounces, int rr_depth,
                      gi_error *err);
void gi_quad_path_free(gi_quad_path *p);

/* The cut integrand, in the form gi_quad_integrand wants (3 channels). */
void gi_quad_path_eval(void *user, size_t n, const double *pts, double *out);

/* The full integrand at u (dims coordinates), coordinates beyond N from rng. */
void gi_quad_path_eval_mc(gi_quad_path *p, const double *u, gi_rng *rng, double *rgb);

#endif
