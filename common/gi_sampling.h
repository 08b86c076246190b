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

/* sin and cos of 2 pi u for u in [0, 1), without branches or library
 * calls: h = pi (u - 1/2) in [-pi/2, pi/2), Taylor polynomials of sin h and
 * cos h (to h^11 / h^12), then the double angle: sin 2h = 2 sin h cos h,
 * cos 2h = cos^2 h - sin^2 h, and 2 pi u = 2h + pi flips both signs.
 * Error < 5e-7. */
static inline void gi_sincos_turn(float u, float *s, float *c)
{
    float h = (float)GI_PI * (u - 0.5f), h2 = h * h;
    float sh = h * (1.0f + h2 * (-1.0f / 6 + h2 * (1.0f / 120 + h2 * (-1.0f / 5040 +
                    h2 * (1.0f / 362880 + h2 * (-1.0f / 39916800))))));
    float ch = 1.0f + h2 * (-1.0f / 2 + h2 * (1.0f / 24 + h2 * (-1.0f / 720 +
                    h2 * (1.0f / 40320 + h2 * (-1.0f / 3628800 + h2 * (1.0f / 479001600))))));
    *s = -2.0f * sh * ch;
    *c = sh * sh - ch * ch;
}

/* Cosine-weighted direction around unit n; pdf = cos(theta) / pi.
 * Malley's method on the polar disc map (r = sqrt(u1), phi = 2 pi u2): the
 * three transcendentals are independent, so they overlap in the CPU (the
 * concentric map chains a division, a polynomial and a square root).
 * gi_polar_map is the transcendental half, gi_cosine_dir the rest: callers
 * with many samples map them all first. */
typedef struct gi_polar {
    float r, z; /* disc radius sqrt(u1); hemisphere height sqrt(1 - u1) */
    float s, c; /* sin and cos of phi */
} gi_polar;

static inline gi_polar gi_polar_map(float u1, float u2)
{
    gi_polar q = {sqrtf(u1), sqrtf(1.0f - u1), 0.0f, 0.0f};
    gi_sincos_turn(u2, &q.s, &q.c);
    return q;
}

static inline gi_vec3 gi_cosine_dir(gi_vec3 n, gi_polar q)
{
    gi_vec3 t, bt;
    gi_onb(n, &t, &bt);
    return gi_add(gi_add(gi_scale(t, q.r * q.c), gi_scale(bt, q.r * q.s)), gi_scale(n, q.z));
}

static inline gi_vec3 gi_sample_cosine(gi_vec3 n, float u1, float u2)
{
    return gi_cosine_dir(n, gi_polar_map(u1, u2));
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

/* Russian roulette keeps a path with probability min(1, its largest
 * throughput component), so its weight stays near 1 (a cap below 1 made the
 * weights grow as (albedo / cap)^bounces: infinite variance, and images
 * visibly too dark, for albedos above sqrt(cap)). Paths left to the
 * roulette are cut at GI_RR_MAX_PATH bounces, which only an albedo within a
 * few 1e-3 of 1 reaches (0.999^4096 = 1.7%). */
#define GI_RR_MAX_PATH 4096
static inline float gi_rr_survival(gi_vec3 beta)
{
    float m = gi_maxf(beta.x, gi_maxf(beta.y, beta.z));
    return m < 1.0f ? m : 1.0f;
}

#endif
