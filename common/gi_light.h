/* gi_light: sampling points on the scene's emitters (emissive triangles),
 * chosen in proportion to emitted power, uniform on each triangle. */
#ifndef GI_LIGHT_H
#define GI_LIGHT_H

#include "gi_scene.h"
#include "gi_sampling.h"

typedef struct gi_light_sample {
    gi_vec3 p;        /* point on the emitter */
    gi_vec3 n;        /* unit front-face normal of the emitter triangle */
    uint32_t tri;     /* global triangle index */
    float pdf_area;   /* probability density per unit area of choosing p */
} gi_light_sample;

/* Density per unit area with which gi_light_sample picks a point on
 * emissive triangle t: P(t) / A(t) = pi * lum(Le) * sides / total_power. */
static inline float gi_light_pdf_area(const gi_scene *s, const gi_material *m)
{
    return (float)(GI_PI * gi_luminance(m->emission) * (m->two_sided ? 2.0 : 1.0) /
                   s->total_power);
}

static inline void gi_light_sample_point(const gi_scene *s, double u_select, float u1,
                                         float u2, gi_light_sample *out)
{
    const gi_light_tri *L = &s->light_geom[gi_sample_cdf(s->light_cdf, s->light_count, u_select)];
    /* Turk's map: a + sqrt(u1) (1 - u2) e1 + sqrt(u1) u2 e2. */
    float su = sqrtf(u1);
    out->p = gi_add(L->a, gi_add(gi_scale(L->e1, su * (1.0f - u2)), gi_scale(L->e2, su * u2)));
    out->n = L->n;
    out->tri = L->tri;
    out->pdf_area = L->pdf_area;
}

/* Emitted radiance leaving emitter triangle t towards direction w (unit,
 * pointing away from the surface): its emission on an emitting face, else 0. */
static inline gi_vec3 gi_light_emitted(const gi_material *m, gi_vec3 n_front, gi_vec3 w)
{
    if (m->two_sided || gi_dot(n_front, w) > 0.0f)
        return m->emission;
    return gi_v3(0, 0, 0);
}

#endif
