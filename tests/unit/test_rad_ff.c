/* Unit tests: ray-cast form factors (radiosity) against closed forms,
 * reciprocity and closure in a closed box, and the white furnace. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_rt.h"
#include "gi_test.h"
#include "radiosity/rad_factor.h"
#include "radiosity/rad_ff.h"
#include "radiosity/rad_mesh.h"
#include "radiosity/rad_model.h"
#include "radiosity/rad_patches.h"
#include "radiosity/rad_relight.h"
#include "test_helpers.h"

#define DEFAULT_RAYS 1024 /* the job default (docs/job-format.md) */

/* Counts at `level` for every element: n x nodes. */
typedef struct counts {
    uint32_t nodes;
    uint16_t *h;
    gi_rad_ff_stats st;
} counts;

static int cast_all(const gi_scene *s, const gi_rad_mesh *m, uint32_t rays, uint32_t level,
                    counts *c, gi_error *err)
{
    gi_rt rt;
    gi_rad_strata st;
    if (gi_rt_create(&rt, s, err))
        return -1;
    if (gi_rad_strata_init(&st, rays, err)) {
        gi_rt_free(&rt);
        return -1;
    }
    c->nodes = gi_rad_mesh_nodes(m, level);
    c->h = malloc((size_t)m->element_count * c->nodes * sizeof *c->h);
    gi_rad_ff_opts o = {7, level};
    int rc = gi_rad_ff_dense(&rt, s, m, &st, &o, c->h, c->nodes, &c->st, err);
    gi_rad_strata_free(&st);
    gi_rt_free(&rt);
    return rc;
}

/* Patch-to-patch form factor between two sets of level-0 roots (equal
 * element areas): F_PQ = mean over P's elements of F_e,Q. */
static double patch_ff(const gi_rad_mesh *m, const counts *c, uint32_t rays, uint32_t p0,
                       uint32_t p1, uint32_t q0, uint32_t q1)
{
    double sum = 0.0;
    uint32_t per = 1u << (2 * m->levels), ne = 0;
    for (uint32_t e = p0 * per; e < p1 * per; e++, ne++)
        for (uint32_t q = q0; q < q1; q++)
            sum += c->h[(size_t)e * c->nodes + q];
    return sum / ((double)rays * ne);
}

/* Aligned parallel rectangles a x b at distance d (Howell's catalogue,
 * C-11). */
static double ff_parallel(double a, double b, double d)
{
    double X = a / d, Y = b / d;
    return 2.0 / (M_PI * X * Y) *
           (log(sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y))) +
            X * sqrt(1 + Y * Y) * atan(X / sqrt(1 + Y * Y)) +
            Y * sqrt(1 + X * X) * atan(Y / sqrt(1 + X * X)) - X * atan(X) - Y * atan(Y));
}

/* Perpendicular rectangles with a common edge of length l: from the one of
 * width w to the one of height h (thesis Fig. 2.5, Lienhard; the power
 * factors inside the logarithm). */
static double ff_perpendicular(double w, double h, double l)
{
    double W = w / l, H = h / l, S = H * H + W * W;
    double t = log((1 + W * W) * (1 + H * H) / (1 + S)) +
               W * W * log(W * W * (1 + S) / ((1 + W * W) * S)) +
               H * H * log(H * H * (1 + S) / ((1 + H * H) * S));
    return (W * atan(1 / W) + H * atan(1 / H) - sqrt(S) * atan(1 / sqrt(S)) + 0.25 * t) /
           (M_PI * W);
}

static const char *two_quads =
    "{\"materials\": {\"m\": {\"diffuse\": [0.5, 0.5, 0.5]}, \"e\": {\"emission\": [1, 1, 1]}},"
    " \"objects\": ["
    "  {\"name\": \"a\", \"material\": \"e\", \"polygons\": {\"vertices\": %s, \"faces\": [[0, 1, "
    "2, 3]]}},"
    "  {\"name\": \"b\", \"material\": \"m\", \"polygons\": {\"vertices\": %s, \"faces\": [[0, 1, "
    "2, 3]]}}"
    "]}";

static double two_quad_ff(const char *name, const char *qa, const char *qb, double *err_est)
{
    char text[2048];
    snprintf(text, sizeof text, two_quads, qa, qb);
    gi_error err;
    gi_scene s;
    double f = -1.0;
    if (gi_test_load_scene_text(name, text, &s, &err)) {
        gi_test_failed(__FILE__, __LINE__, "scene: %s", err.msg);
        return f;
    }
    gi_rad_mesh m;
    counts c = {0};
    if (gi_rad_mesh_build(&m, &s, 0.0, 3, &err) == 0 && m.root_count == 4 &&
        cast_all(&s, &m, DEFAULT_RAYS, 0, &c, &err) == 0) {
        f = patch_ff(&m, &c, DEFAULT_RAYS, 0, 2, 2, 4); /* quad a (roots 0-1) to b (2-3) */
        *err_est = sqrt((double)c.st.d2 / (double)c.st.h2);
    } else {
        gi_test_failed(__FILE__, __LINE__, "form factors: %s", err.msg);
    }
    free(c.h);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
    return f;
}

GI_TEST(test_rad_ff_coaxial_parallel_squares)
{
    /* Unit squares at distance 1 and 0.5, facing each other. */
    double est;
    double f = two_quad_ff("par1.json", "[[0,0,0],[0,0,1],[1,0,1],[1,0,0]]",
                           "[[0,1,0],[1,1,0],[1,1,1],[0,1,1]]", &est);
    GI_CHECK_REL(f, ff_parallel(1, 1, 1), 0.01);
    GI_CHECK_NEAR(ff_parallel(1, 1, 1), 0.19982, 1e-5); /* the catalogue value */
    f = two_quad_ff("par2.json", "[[0,0,0],[0,0,1],[1,0,1],[1,0,0]]",
                    "[[0,0.5,0],[1,0.5,0],[1,0.5,1],[0,0.5,1]]", &est);
    GI_CHECK_REL(f, ff_parallel(1, 1, 0.5), 0.01);
}

GI_TEST(test_rad_ff_perpendicular_rectangles_with_a_common_edge)
{
    /* a in y = 0 (x in [0, w], z in [0, 1]) facing +y; b in x = 0 (y in
     * [0, h]) facing +x; common edge the z axis. */
    double est;
    double f = two_quad_ff("perp1.json", "[[0,0,0],[0,0,1],[1,0,1],[1,0,0]]",
                           "[[0,0,0],[0,1,0],[0,1,1],[0,0,1]]", &est);
    GI_CHECK_REL(f, ff_perpendicular(1, 1, 1), 0.01);
    GI_CHECK_NEAR(ff_perpendicular(1, 1, 1), 0.20004, 1e-5);
    f = two_quad_ff("perp2.json", "[[0,0,0],[0,0,1],[2,0,1],[2,0,0]]",
                    "[[0,0,0],[0,0.5,0],[0,0.5,1],[0,0,1]]", &est);
    GI_CHECK_REL(f, ff_perpendicular(2, 0.5, 1), 0.01);
    /* The estimate of the sampling error is a positive, small number. */
    GI_CHECK(est > 0.0 && est < 0.5);
}

static const char *closed_box =
    "{\"materials\": {\"w\": {\"diffuse\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},"
    " \"objects\": [{\"name\": \"box\", \"material\": \"w\","
    "   \"box\": {\"size\": [2, 1, 1.5], \"inward\": true}}]}";

GI_TEST(test_rad_ff_closed_box_rows_sum_to_one_and_reciprocity_holds)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_text("box.json", closed_box, &s, &err));
    gi_rad_mesh m;
    /* Patches of at most 1/40 of the area: the faces are split unevenly. */
    GI_REQUIRE_OK(gi_rad_mesh_build(&m, &s, 13.0 / 40.0, 2, &err));
    counts c = {0};
    uint32_t rays = 256;
    GI_REQUIRE_OK(cast_all(&s, &m, rays, 0, &c, &err));
    GI_CHECK(c.st.escaped == 0 && c.st.backface == 0); /* closed: every row sums to 1 */
    uint32_t k = m.root_count, per = 1u << (2 * m.levels);
    double *F = calloc((size_t)k * k, sizeof *F);
    for (uint32_t e = 0; e < m.element_count; e++) {
        uint64_t row = 0;
        for (uint32_t q = 0; q < k; q++) {
            row += c.h[(size_t)e * k + q];
            F[(size_t)(e / per) * k + q] += c.h[(size_t)e * k + q] / ((double)rays * per);
        }
        GI_CHECK(row == rays);
    }
    /* A_i F_ij = A_j F_ji within the sampling error: the binomial standard
     * error of each patch estimate bounds the stratified one. */
    int outside = 0, pairs = 0;
    double asym = 0.0, expect = 0.0;
    for (uint32_t i = 0; i < k; i++)
        for (uint32_t j = i + 1; j < k; j++) {
            double ai = m.root_area[i], aj = m.root_area[j];
            double fij = F[(size_t)i * k + j], fji = F[(size_t)j * k + i];
            double si = sqrt(fij * (1 - fij) / ((double)rays * per) + 1e-12);
            double sj = sqrt(fji * (1 - fji) / ((double)rays * per) + 1e-12);
            double d = ai * fij - aj * fji, sd = sqrt(ai * ai * si * si + aj * aj * sj * sj);
            outside += fabs(d) > 4.0 * sd;
            pairs++;
            asym += d * d;
            expect += sd * sd;
        }
    GI_CHECK_MSG(outside == 0, "%d of %d pairs differ by more than 4 sigma", outside, pairs);
    /* In sum: ||AF - (AF)^T||^2 no larger than its binomial expectation
     * (stratification makes it smaller; a wrong area weight, far larger). */
    GI_CHECK_MSG(asym <= 1.2 * expect, "||AF - (AF)^T||^2 = %g, expected about %g", asym, expect);
    free(F);
    free(c.h);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
}

GI_TEST(test_rad_white_furnace)
{
    /* Closed box, emission 1 and reflectance 0.5 everywhere: B = E / (1 -
     * rho) = 2 on every element, with SMW and with Neumann. */
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_text("furnace.json", closed_box, &s, &err));
    gi_rad_mesh m;
    GI_REQUIRE_OK(gi_rad_mesh_build(&m, &s, 13.0 / 40.0, 2, &err));
    counts c = {0};
    GI_REQUIRE_OK(cast_all(&s, &m, DEFAULT_RAYS, 0, &c, &err));
    uint32_t n = m.element_count, k = m.root_count;
    gi_rad_patches pt;
    gi_rad_2mf_patches(&m, 0, &pt);
    gi_rad_factor f;
    gi_rad_model md;
    GI_REQUIRE_OK(gi_rad_factor_from_counts(&f, &m, c.h, k, DEFAULT_RAYS, &pt, &err));
    GI_REQUIRE_OK(gi_rad_model_build(&md, &m, &s, &err));
    gi_rad_model_reflectance(&md, f.rho);
    GI_REQUIRE_OK(gi_rad_factor_prepare(&f, &err));
    gi_rad_emissions em;
    gi_rad_emissions_scene(&em);
    float *B = malloc(3 * (size_t)n * sizeof *B);
    gi_rad_solve_info info;
    for (int solver = 0; solver < 2; solver++) {
        gi_rad_solve_opts o;
        gi_rad_solve_opts_default(&o);
        o.solver = (gi_rad_solver)solver;
        o.tolerance = 1e-7;
        GI_REQUIRE_OK(gi_rad_solve_emissions(&f, &md, &em, &o, NULL, B, &info, &err));
        float lo = 1e9f, hi = -1e9f;
        for (size_t i = 0; i < 3 * (size_t)n; i++) {
            lo = B[i] < lo ? B[i] : lo;
            hi = B[i] > hi ? B[i] : hi;
        }
        GI_CHECK_MSG(fabsf(lo - 2.0f) <= 0.02f && fabsf(hi - 2.0f) <= 0.02f,
                     "solver %d: B in [%g, %g], expected 2 within 1%%", solver, lo, hi);
    }
    free(B);
    gi_rad_emissions_free(&em);
    gi_rad_model_free(&md);
    gi_rad_factor_free(&f);
    gi_rad_patches_free(&pt);
    free(c.h);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
}
