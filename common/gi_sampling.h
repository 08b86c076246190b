/* gi_sampling: warping uniform numbers to the distributions the methods
 * sample (cosine hemisphere, triangles, discrete CDFs). */
#ifndef GI_SAMPLING_H
#define GI_SAMPLING_H

#include <stdint.h>

#include "gi_math.h"

/* sin and cos of t for |t| <= pi/4 (Taylor to t^7 / t^8: error < 4e-7). */
static inline void gi_sincos_octant(float t, float *s, float *c)
{
    float t2 = t * t;
    *s = t * (1.0f + t2 * (-1.0f / 6.0f + t2 * (1.0f / 120.0f + t2 * (-1.0f / 5040.0f))));
    *c = 1.0f + t2 * (-0.5f + t2 * (1.0f / 24.0f + t2 * (-1.0f / 720.0f + t2 * (1.0f / 40320.0f))));
}

/* Uniform point in the unit disc, from the unit square by Shirley and
 * Chiu's concentric map (continuous, area preserving). */
static inline void gi_sample_disc(float u1, float u2, float *x, float *y)
{
    float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f, s, c;
    if (a == 0.0f && b == 0.0f) {
        *x = *y = 0.0f;
    } else if (a * a > b * b) {
        gi_sincos_octant((float)(GI_PI / 4) * (b / a), &s, &c); /* phi = pi/4 b/a */
        *x = a * c;
        *y = a * s;
    } else {
        gi_sincos_octant((float)(GI_PI / 4) * (a / b), &s, &c); /* phi = pi/2 - pi/4 a/b */
        *x = b * s;
        *y = b * c;
    }
}

/* Cosine-weighted direction around unit n; pdf = cos(theta) / pi
 * (Malley's method: a uniform disc point lifted to the hemisphere). */
static inline gi_vec3 gi_sample_cosine(gi_vec3 n, float u1, float u2)
{
    float x, y;
    gi_sample_disc(u1, u2, &x, &y);
    float z = sqrtf(gi_maxf(0.0f, 1.0f - x * x - y * y));
    gi_vec3 t, bt;
    gi_onb(n, &t, &bt);
    return gi_add(gi_add(gi_scale(t, x), gi_scale(bt, y)), gi_scale(n, z));
}

/* Uniform point on triangle (a, b, c) (Turk's square-root map). */
static inline gi_vec3 gi_sample_triangle(gi_vec3 a, gi_vec3 b, gi_vec3 c, float u1, float u2)
{
    float su = sqrtf(u1);
    float w0 = 1.0f - su, w1 = su * (1.0f - u2), w2 = su * u2;
    return gi_add(gi_add(gi_scale(a, w0), gi_scale(b, w1)), gi_scale(c, w2));
}

/* Index i with cdf[i] <= u < cdf[i+1] in a CDF of n+1 entries (cdf[0] = 0,
 * cdf[n] = 1), skipping zero-probability entries. */
static inline uint32_t gi_sample_cdf(const double *cdf, uint32_t n, double u)
{
    uint32_t lo = 0, hi = n; /* invariant: cdf[lo] <= u, answer in [lo, hi) */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

#endif
