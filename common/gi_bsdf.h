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

/* The shading normal at barycentrics (u, v) of triangle tri, on the side of
 * ng_facing (the geometric normal facing the outgoing direction). */
static inline gi_vec3 gi_bsdf_shading_normal(const gi_scene *s, uint32_t tri, float u, float v,
                                             gi_vec3 ng_facing)
{
    if (!s->tri_smooth[tri])
        return ng_facing;
    const uint32_t *ix = &s->indices[3 * tri];
    gi_vec3 n = gi_add(gi_add(gi_scale(s->normals[ix[0]], 1.0f - u - v),
                              gi_scale(s->normals[ix[1]], u)),
                       gi_scale(s->normals[ix[2]], v));
    n = gi_normalize(n);
    /* Interpolated normals may point to the other side near silhouettes;
     * the geometric side decides which side we are on. */
    if (!(gi_dot(n, ng_facing) > 0.0f))
        n = gi_dot(n, ng_facing) < 0.0f ? gi_neg(n) : ng_facing;
    return n;
}

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

/* Samples wi; returns the weight f * cos / pdf (= rho for diffuse). */
static inline gi_vec3 gi_bsdf_sample(const gi_bsdf *b, float u1, float u2, gi_vec3 *wi,
                                     float *pdf)
{
    *wi = gi_sample_cosine(b->n, u1, u2);
    *pdf = gi_bsdf_pdf(b, *wi);
    return *pdf > 0.0f ? b->rho : gi_v3(0, 0, 0);
}

#endif
