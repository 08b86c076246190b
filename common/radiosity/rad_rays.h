/* rad_rays: the rays an element casts to estimate its form factors.
 *
 * With cosine-distributed directions from uniform points on element e, a
 * ray lands on surface j with probability F_ej (thesis eq. 2.30: the
 * cos/(pi r^2) kernel is exactly the cosine density), so hits / rays is an
 * unbiased estimate of every F_ej at once, with no hemicube aliasing.
 *
 * Stratified: R = m^2 rays; ray j starts in point stratum j (the element
 * split into m^2 congruent sub-triangles, m per edge) and leaves through
 * direction stratum perm(j) (an m x m grid of the unit square, mapped by the
 * concentric disc and Malley's method), where perm is a random permutation
 * per element, so points and directions are both stratified and not
 * correlated with each other.
 *
 * Deterministic: ray j of element e uses gi_rng(seed, stream(e), j) and the
 * permutation gi_rng(seed, stream(e), GI_RAD_PERM_SAMPLE), so a ray is the
 * same on any worker, in any task, and in both states of a moving-object
 * update (what lets the change matrix be found by re-casting few rays). */
#ifndef GI_RAD_RAYS_H
#define GI_RAD_RAYS_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_math.h"
#include "gi_scene.h"
#include "rad_mesh.h"

#define GI_RAD_MAX_RAYS 65025u /* 255^2: hit counts fit 16 bits */
#define GI_RAD_PERM_SAMPLE 0xFFFFFFFFu

typedef struct gi_rad_strata {
    uint32_t m, rays; /* rays = m * m */
    float *sub;       /* rays x 6: (s, t) of each point stratum's corners, in [0, 1] */
    /* rays x 2: column and row (c % m, c / m) of direction stratum c, and
     * 1 / m: a table instead of two divisions per ray. */
    float *cell;
    float inv_m;
} gi_rad_strata;

/* rays must be a perfect square in [1, GI_RAD_MAX_RAYS]. */
int gi_rad_strata_init(gi_rad_strata *st, uint32_t rays, gi_error *err);
void gi_rad_strata_free(gi_rad_strata *st);
/* 1 if rays is a perfect square in range. */
int gi_rad_rays_valid(uint32_t rays);

typedef struct gi_rad_element_rays {
    const gi_rad_strata *st;
    gi_vec3 p0, e1, e2; /* corner a, b - a, c - a */
    gi_vec3 n, t, b;    /* unit front normal and a basis around it */
    uint64_t seed, stream;
    uint64_t stream_key; /* gi_rng_stream_key of the two: rays start from it */
    uint32_t *perm; /* rays entries, caller's storage */
} gi_rad_element_rays;

/* Prepares element e's rays (positions from the scene as it is now). */
void gi_rad_element_rays_init(gi_rad_element_rays *er, const gi_rad_strata *st,
                              const gi_rad_mesh *m, const gi_scene *s, uint64_t seed, uint32_t e,
                              uint32_t *perm);
/* Ray j: origin (already offset off the surface) and unit direction. */
void gi_rad_element_ray(const gi_rad_element_rays *er, uint32_t j, gi_vec3 *org, gi_vec3 *dir);

#endif
