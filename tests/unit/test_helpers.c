/* Helpers shared by unit tests that need scenes. */
#include "test_helpers.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gi_assets.h"
#include "gi_fs.h"
#include "gi_test.h"

static int load_from(const char *root, const char *name, gi_scene *out, gi_error *err)
{
    gi_dir_source ds;
    gi_dir_source_init(&ds, root);
    gi_asset_source src = gi_dir_source_as_source(&ds);
    int rc = gi_scene_load(&src, name, out, err);
    gi_dir_source_free(&ds);
    return rc;
}

int gi_test_load_scene_text(const char *name, const char *text, gi_scene *out, gi_error *err)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", gi_test_tmpdir(), name);
    if (gi_write_file_atomic(path, text, strlen(text), err))
        return -1;
    return load_from(gi_test_tmpdir(), name, out, err);
}

int gi_test_load_scene_file(const char *path, gi_scene *out, gi_error *err)
{
    return load_from(gi_test_srcdir(), path, out, err);
}

const gi_vec3 gi_test_lamp[4] = {{-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}};

int gi_test_load_lambert_scene(gi_scene *out, gi_error *err)
{
    const char *text =
        "{\"materials\": {\"floor\": {\"diffuse\": [0.5, 0.5, 0.5]},"
        "                 \"lamp\": {\"diffuse\": [0, 0, 0], \"emission\": [2, 2, 2]}},"
        " \"objects\": ["
        "  {\"name\": \"lamp\", \"material\": \"lamp\", \"polygons\": {\"vertices\":"
        "   [[-0.5, 1, -0.5], [0.5, 1, -0.5], [0.5, 1, 0.5], [-0.5, 1, 0.5]], \"faces\": [[0, 1, 2, 3]]}},"
        "  {\"name\": \"floor\", \"material\": \"floor\", \"quad\": {\"size\": [40, 40]}}]}";
    return gi_test_load_scene_text("lambert.json", text, out, err);
}

double gi_test_polygon_irradiance(const gi_vec3 *poly, int k, gi_vec3 x, gi_vec3 n, double L)
{
    double sum = 0;
    for (int i = 0; i < k; i++) {
        gi_vec3 a = gi_normalize(gi_sub(poly[i], x));
        gi_vec3 b = gi_normalize(gi_sub(poly[(i + 1) % k], x));
        double theta = acos(fmax(-1.0, fmin(1.0, gi_dot(a, b))));
        gi_vec3 g = gi_normalize(gi_cross(a, b));
        sum += theta * gi_dot(n, g);
    }
    return 0.5 * L * fabs(sum);
}

gi_vec3 gi_test_random_dir(gi_rng *r)
{
    float a = gi_rng_float(r) * 6.2831853f, c = 2 * gi_rng_float(r) - 1;
    float sn = sqrtf(1 - c * c);
    return gi_v3(sn * cosf(a), sn * sinf(a), c);
}
