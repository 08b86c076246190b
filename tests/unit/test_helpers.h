/* Helpers shared by unit tests that need scenes. */
#ifndef GI_TEST_HELPERS_H
#define GI_TEST_HELPERS_H

#include "gi_error.h"
#include "gi_rng.h"
#include "gi_scene.h"

/* Writes `text` to <tmpdir>/<name> and loads it as a scene. */
int gi_test_load_scene_text(const char *name, const char *text, gi_scene *out, gi_error *err);
/* Loads a scene from the source tree (path relative to the repository). */
int gi_test_load_scene_file(const char *path, gi_scene *out, gi_error *err);

/* A unit square emitter of radiance 2 facing down at height 1 (corners
 * gi_test_lamp), over a 40 x 40 diffuse floor of reflectance 0.5 at y = 0. */
int gi_test_load_lambert_scene(gi_scene *out, gi_error *err);
extern const gi_vec3 gi_test_lamp[4];

/* Irradiance at x (normal n) from a Lambertian polygon of radiance L:
 * Lambert's formula E = L/2 sum_i theta_i (n . gamma_i) (e.g. Arvo 1995). */
double gi_test_polygon_irradiance(const gi_vec3 *poly, int k, gi_vec3 x, gi_vec3 n, double L);

/* A direction uniform on the unit sphere (two numbers of r: azimuth, then
 * height). */
gi_vec3 gi_test_random_dir(gi_rng *r);

#endif
