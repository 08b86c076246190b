/* rad_rays: stratified cosine-distributed rays from an element. */
#include "rad_rays.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_rng.h"
#include "gi_rt.h"
#include "gi_sampling.h"

/* Streams of the form-factor rays: a tag in the high bits keeps them apart
 * from other (seed, stream) users such as image pixels. */
#define RAD_STREAM_TAG ((uint64_t)0x5241 << 48)

int gi_rad_rays_valid(uint32_t rays)
{
    if (rays < 1 || rays > GI_RAD_MAX_RAYS)
        return 0;
    uint32_t m = (uint32_t)lrint(sqrt((double)rays));
    return m * m == rays;
}

int gi_rad_strata_init(gi_rad_strata *st, uint32_t rays, gi_error *err)
{
    memset(st, 0, sizeof *st);
    if (!gi_rad_rays_valid(rays))
        return gi_fail(err, GI_EINVAL,
                       "rays per element must be a perfect square in [1, %u], got %u",
                       GI_RAD_MAX_RAYS, rays);
    uint32_t m = (uint32_t)lrint(sqrt((double)rays));
    st->m = m;
    st->rays = rays;
    st->sub = gi_xmalloc((size_t)rays * 6 * sizeof *st->sub);
    st->cell = gi_xmalloc((size_t)rays * 2 * sizeof *st->cell);
    for (uint32_t c = 0; c < rays; c++) {
        st->cell[2 * c] = (float)(c % m);
        st->cell[2 * c + 1] = (float)(c / m);
    }
    st->inv_m = 1.0f / (float)m;
    /* Cell (i, j) of the (s, t) grid with i + j <= m - 1 holds a lower
     * triangle, and an upper one when i + j <= m - 2: m^2 in all. */
    float inv = 1.0f / (float)m;
    uint32_t k = 0;
    for (uint32_t i = 0; i < m; i++)
        for (uint32_t j = 0; i + j < m; j++) {
            float *q = &st->sub[6 * k++];
            q[0] = i * inv, q[1] = j * inv;
            q[2] = (i + 1) * inv, q[3] = j * inv;
            q[4] = i * inv, q[5] = (j + 1) * inv;
            if (i + j + 2 <= m) {
                q = &st->sub[6 * k++];
                q[0] = (i + 1) * inv, q[1] = j * inv;
                q[2] = (i + 1) * inv, q[3] = (j + 1) * inv;
                q[4] = i * inv, q[5] = (j + 1) * inv;
            }
        }
    return 0;
}

void gi_rad_strata_free(gi_rad_strata *st)
{
    free(st->sub);
    free(st->cell);
    memset(st, 0, sizeof *st);
}

void gi_rad_element_rays_init(gi_rad_element_rays *er, const gi_rad_strata *st,
                              const gi_rad_mesh *m, const gi_scene *s, uint64_t seed, uint32_t e,
                              uint32_t *perm)
{
    gi_vec3 c[3];
    gi_rad_mesh_element_corners(m, s, e, c);
    er->st = st;
    er->p0 = c[0];
    er->e1 = gi_sub(c[1], c[0]);
    er->e2 = gi_sub(c[2], c[0]);
    er->n = s->tri_normal[gi_rad_mesh_element_tri(m, e)];
    gi_onb(er->n, &er->t, &er->b);
    er->seed = seed;
    er->stream = RAD_STREAM_TAG | e;
    er->stream_key = gi_rng_stream_key(gi_rng_seed_key(seed), er->stream);
    er->perm = perm;
    for (uint32_t j = 0; j < st->rays; j++)
        perm[j] = j;
    gi_rng rng;
    gi_rng_init(&rng, seed, er->stream, GI_RAD_PERM_SAMPLE);
    for (uint32_t j = st->rays; j > 1; j--) { /* Fisher-Yates */
        uint32_t i = gi_rng_below(&rng, j);
        uint32_t tmp = perm[j - 1];
        perm[j - 1] = perm[i];
        perm[i] = tmp;
    }
}

void gi_rad_element_ray(const gi_rad_element_rays *er, uint32_t j, gi_vec3 *org, gi_vec3 *dir)
{
    const gi_rad_strata *st = er->st;
    gi_rng rng;
    gi_rng_init_stream(&rng, er->stream_key, j); /* = gi_rng_init(seed, stream, j) */
    float u1 = gi_rng_float(&rng), u2 = gi_rng_float(&rng);
    float u3 = gi_rng_float(&rng), u4 = gi_rng_float(&rng);
    /* A uniform point in point stratum j (square-root map), in (s, t). */
    const float *q = &st->sub[6 * (size_t)j];
    float su = sqrtf(u1), w0 = 1.0f - su, w1 = su * (1.0f - u2), w2 = su * u2;
    float s = w0 * q[0] + w1 * q[2] + w2 * q[4];
    float t = w0 * q[1] + w1 * q[3] + w2 * q[5];
    gi_vec3 p = gi_madd(gi_madd(er->p0, er->e1, s), er->e2, t);
    /* A cosine-distributed direction in direction stratum perm(j)
     * (Malley: a uniform disc point lifted to the hemisphere; unit length
     * by construction). */
    const float *cell = &st->cell[2 * (size_t)er->perm[j]];
    float inv = st->inv_m, x, y;
    gi_sample_disc((cell[0] + u3) * inv, (cell[1] + u4) * inv, &x, &y);
    float z = sqrtf(gi_maxf(0.0f, 1.0f - x * x - y * y));
    *dir = gi_add(gi_add(gi_scale(er->t, x), gi_scale(er->b, y)), gi_scale(er->n, z));
    *org = gi_rt_offset(p, er->n, *dir);
}
