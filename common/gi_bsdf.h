/* gi_bsdf: surface scattering. Diffuse (Lambertian) for now: every method
 * of the three theses assumes it; the struct is where glossy lobes go.
 * Directions point away from the surface; n is the shading normal on the
 * side the light arrives from. */
#ifndef GI_BSDF_H
#define GI_BSDF_H

#include "gi_math.h"
#include "gi_sampling.h"
#include "gi_scene.h"

typedef struct gi_bsdf {
    gi_vec3 rho; /* diffuse reflectance */
    gi_vec3 n;   /* shading normal, facing the outgoing direction */
} gi_bsdf;

static inline gi_bsdf gi_bsdf_at(const gi_material *m, gi_vec3 n_facing)
{
    gi_bsdf b = {m->diffuse, n_facing};
    return b;
}

/* f(wo, wi): rho / pi for wi above the surface. */
static inline gi_vec3 gi_bsdf_eval(const gi_bsdf *b, gi_vec3 wi)
{
    if (gi_dot(b->n, wi) <= 0.0f)
        return gi_v3(0, 0, 0);
    return gi_scale(b->rho, (float)GI_INV_PI);
}

static inline float gi_bsdf_pdf(const gi_bsdf *b, gi_vec3 wi)
{
    float c = gi_dot(b->n, wi);
    return c > 0.0f ? c * (float)GI_INV_PI : 0.0f;
}

/* A BSDF sample's random numbers (u1, u2) mapped ahead of the sampling
 * (their square roots and polynomials), so that a batch of paths can do
 * that for all its vertices together. */
static inline gi_polar gi_bsdf_map(float u1, float u2) { return gi_polar_map(u1, u2); }

/* Samples wi from mapped numbers; returns the weight f * cos / pdf (= rho
 * for diffuse). */
static inline gi_vec3 gi_bsdf_sample_mapped(const gi_bsdf *b, gi_polar q, gi_vec3 *wi,
                                            float *pdf)
{
    gi_vec3 w = gi_cosine_dir(b->n, q); /* in registers, not read back through wi */
    float p = gi_bsdf_pdf(b, w);
    *wi = w;
    *pdf = p;
    return p > 0.0f ? b->rho : gi_v3(0, 0, 0);
}

/* Samples wi; returns the weight f * cos / pdf (= rho for diffuse). */
static inline gi_vec3 gi_bsdf_sample(const gi_bsdf *b, float u1, float u2, gi_vec3 *wi,
                                     float *pdf)
{
    return gi_bsdf_sample_mapped(b, gi_bsdf_map(u1, u2), wi, pdf);
}

#endif
