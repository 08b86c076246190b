/* rad_form_factors: ray-cast form factors against closed forms, at several
 * ray counts: two unit squares (2 triangles, 3 levels: 128 elements each),
 * coaxial and parallel at distance 1, and perpendicular with a common edge.
 * F(square a -> square b) = mean over a's elements of hits on b / rays.
 * Prints the root mean square relative error over 10 seeds.
 *
 *   rad_form_factors */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_rt.h"
#include "rad_bench.h"
#include "radiosity/rad_ff.h"

static const char *scene_text =
    "{\"materials\": {\"m\": {\"diffuse\": [0.5, 0.5, 0.5]}, \"e\": {\"emission\": [1, 1, 1]}},"
    " \"objects\": ["
    "  {\"name\": \"a\", \"material\": \"e\", \"polygons\": {\"vertices\": "
    "[[0,0,0],[0,0,1],[1,0,1],[1,0,0]], \"faces\": [[0, 1, 2, 3]]}},"
    "  {\"name\": \"b\", \"material\": \"m\", \"polygons\": {\"vertices\": %s, "
    "\"faces\": [[0, 1, 2, 3]]}}]}";

static char text[2048];

static int read_text(void *ctx, const char *name, gi_buf *out, gi_error *err)
{
    gi_buf_reset(out);
    gi_buf_put(out, text, strlen(text));
    return 0;
}

static void die(const gi_error *err) { rad_bench_die("rad_form_factors", err); }

static double measure(const char *quad_b, uint32_t rays, uint64_t seed)
{
    snprintf(text, sizeof text, scene_text, quad_b);
    gi_asset_source src = {read_text, NULL};
    gi_error err;
    gi_scene s;
    gi_rad_mesh m;
    gi_rt rt;
    gi_rad_strata st;
    if (gi_scene_load(&src, "two-squares.json", &s, &err) ||
        gi_rad_mesh_build(&m, &s, 0.0, 3, &err) || gi_rt_create(&rt, &s, &err) ||
        gi_rad_strata_init(&st, rays, &err))
        die(&err);
    uint16_t *c = malloc((size_t)m.element_count * 4 * sizeof *c);
    gi_rad_ff_opts o = {seed, 0};
    gi_rad_ff_stats fs;
    if (gi_rad_ff_dense(&rt, &s, &m, &st, &o, c, 4, &fs, &err))
        die(&err);
    double sum = 0.0;
    for (uint32_t e = 0; e < m.element_count / 2; e++) /* square a: roots 0, 1 */
        sum += c[e * 4 + 2] + c[e * 4 + 3];            /* square b: roots 2, 3 */
    free(c);
    gi_rad_strata_free(&st);
    gi_rt_free(&rt);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
    return sum / ((double)rays * 128.0);
}

int main(void)
{
    /* Howell's catalogue C-11 (parallel) and Lienhard's (perpendicular). */
    double X = 1.0, par = 2.0 / (M_PI * X * X) *
                          (log((1 + X * X) / sqrt(1 + 2 * X * X)) +
                           2 * X * sqrt(1 + X * X) * atan(X / sqrt(1 + X * X)) - 2 * X * atan(X));
    double W = 1.0, H = 1.0, S = 2.0;
    double t = log((1 + W * W) * (1 + H * H) / (1 + S)) +
               W * W * log(W * W * (1 + S) / ((1 + W * W) * S)) +
               H * H * log(H * H * (1 + S) / ((1 + H * H) * S));
    double perp =
        (W * atan(1 / W) + H * atan(1 / H) - sqrt(S) * atan(1 / sqrt(S)) + 0.25 * t) / (M_PI * W);
    printf("| rays per element | coaxial parallel squares, d = 1 (F = %.5f) | perpendicular, "
           "common edge (F = %.5f) |\n|---|---|---|\n",
           par, perp);
    static const uint32_t rays[] = {256, 1024, 4096};
    for (int r = 0; r < 3; r++) {
        double e1 = 0.0, e2 = 0.0;
        for (uint64_t seed = 1; seed <= 10; seed++) {
            double a = measure("[[0,1,0],[1,1,0],[1,1,1],[0,1,1]]", rays[r], seed) / par - 1.0;
            double b = measure("[[0,0,0],[0,1,0],[0,1,1],[0,0,1]]", rays[r], seed) / perp - 1.0;
            e1 += a * a;
            e2 += b * b;
        }
        printf("| %u | %.2f%% | %.2f%% |\n", rays[r], 100 * sqrt(e1 / 10), 100 * sqrt(e2 / 10));
    }
    return 0;
}
