/* Unit tests: the quadrature integrand (light map, next-event estimate,
 * cut and Monte Carlo forms) against closed forms. */
#include <float.h>
#include <string.h>

#include "gi_rt.h"
#include "gi_test.h"
#include "quadrature/quad_integrate.h"
#include "quadrature/quad_light_map.h"
#include "quadrature/quad_path.h"
#include "test_helpers.h"

typedef struct light_ctx {
    const gi_scene *s;
    const double *area;
} light_ctx;

static void light_weight_fn(void *user, size_t n, const double *pts, double *out)
{
    const light_ctx *c = user;
    for (size_t i = 0; i < n; i++) {
        gi_quad_light_point lp;
        gi_quad_light_map(c->s, c->area, pts[2 * i], pts[2 * i + 1], &lp);
        out[i] = lp.weight;
    }
}

GI_TEST(test_quad_light_map_covers_the_emitter_area)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &s, &err));
    double area[8];
    GI_REQUIRE(s.light_count == 2);
    for (uint32_t k = 0; k < s.light_count; k++)
        area[k] = gi_scene_triangle_area(&s, s.light_tris[k]);
    light_ctx c = {&s, area};
    gi_quad_integrand fn = {light_weight_fn, &c};
    gi_quad_opts o = {GI_QUAD_BOOLE, GI_QUAD_AXIS_MARGINAL, GI_QHEAP_BINARY, 1e-12, 0, 100000};
    gi_quad_result r;
    GI_REQUIRE_OK(gi_quad_integrate(2, 1, &fn, &o, &r, &err));
    /* The light is 130 x 105 mm. */
    GI_CHECK_NEAR(r.est[0], 130.0 * 105.0, 1e-6);
    /* Continuous across the two triangles (fan edge a-c). */
    gi_quad_light_point a, b;
    double t = s.light_cdf[1];
    gi_quad_light_map(&s, area, 0.7, t - 1e-12, &a);
    gi_quad_light_map(&s, area, 0.7, t, &b);
    GI_CHECK(gi_length(gi_sub(a.p, b.p)) < 1e-3f && fabs(a.weight - b.weight) < 1e-6 * a.weight);
    gi_scene_free(&s);
}

typedef struct pixel_ctx {
    gi_quad_path *p;
    double u0, u1;
} pixel_ctx;

/* The integrand at a fixed image point, over the light coordinates. */
static void fixed_pixel_fn(void *user, size_t n, const double *pts, double *out)
{
    pixel_ctx *c = user;
    for (size_t i = 0; i < n; i++) {
        double u[4] = {c->u0, c->u1, pts[2 * i], pts[2 * i + 1]};
        gi_quad_path_eval(c->p, 1, u, out + 3 * i);
    }
}

GI_TEST(test_quad_path_direct_light_matches_lambert_polygon_formula)
{
    gi_error err;
    gi_scene s;
    /* A unit square emitter (radiance 2) facing down at height 1 over a
     * large floor (rho 0.5); the camera looks at the floor from the side. */
    GI_REQUIRE_OK(gi_test_load_lambert_scene(&s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    gi_camera cam = {{6, 0.6f, 1}, {0.3f, 0, 0.2f}, {0, 1, 0}, 30.0f};
    gi_quad_path path;
    GI_REQUIRE_OK(gi_quad_path_init(&path, &rt, &s, &cam, 64, 64, 4, -1, 3, &err));
    double image_points[3][2] = {{0.5, 0.5}, {0.3, 0.6}, {0.71, 0.45}};
    for (int i = 0; i < 3; i++) {
        pixel_ctx c = {&path, image_points[i][0], image_points[i][1]};
        /* Where that image point's ray meets the floor. */
        gi_camera_frame f;
        gi_camera_frame_init(&f, &cam, 64, 64);
        gi_vec3 dir = gi_camera_dir(&f, (float)(c.u0 * 64), (float)(c.u1 * 64));
        gi_hit h;
        GI_REQUIRE(gi_rt_intersect(&rt, f.origin, dir, 0, FLT_MAX, &h));
        gi_vec3 x = gi_madd(f.origin, dir, h.t);
        double expect =
            0.5 / GI_PI * gi_test_polygon_irradiance(gi_test_lamp, 4, x, gi_v3(0, 1, 0), 2.0);
        gi_quad_integrand fn = {fixed_pixel_fn, &c};
        gi_quad_opts o = {GI_QUAD_GM, GI_QUAD_AXIS_MARGINAL, GI_QHEAP_BINARY, 1e-7, 0, 2000000};
        gi_quad_result r;
        GI_REQUIRE_OK(gi_quad_integrate(2, 3, &fn, &o, &r, &err));
        /* float geometry: 1e-5 relative */
        GI_CHECK_MSG(fabs(r.est[1] - expect) <= 1e-5 * expect, "point %d: %.9g vs Lambert %.9g", i,
                     r.est[1], expect);
    }
    /* The Monte Carlo form is the same function below N (direct light only:
     * one scattering event). */
    gi_quad_path mc;
    GI_REQUIRE_OK(gi_quad_path_init(&mc, &rt, &s, &cam, 64, 64, 4, 1, 3, &err));
    double u[4] = {0.5, 0.5, 0.3, 0.8}, a[3], b[3];
    gi_rng rng;
    gi_rng_init(&rng, 1, 2, 3);
    gi_quad_path_eval(&path, 1, u, a);
    gi_quad_path_eval_mc(&mc, u, &rng, b);
    GI_CHECK(a[0] == b[0] && a[1] == b[1] && a[2] == b[2] && a[0] > 0);
    gi_quad_path_free(&mc);
    gi_quad_path_free(&path);
    gi_rt_free(&rt);
    gi_scene_free(&s);
}
