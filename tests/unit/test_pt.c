/* Unit tests: the path tracer's estimator against closed forms. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_jobrun.h"
#include "gi_rt.h"
#include "gi_test.h"
#include "pt/pt.h"
#include "test_drive.h"
#include "test_helpers.h"

GI_TEST(test_direct_irradiance_matches_lambert_polygon_formula)
{
    gi_error err;
    gi_scene s;
    /* A unit square emitter (radiance 2) facing down at height 1, over a
     * large diffuse floor (rho 0.5). */
    GI_REQUIRE_OK(gi_test_load_lambert_scene(&s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    gi_vec3 points[] = {{0, 0, 0}, {0.3f, 0, 0.2f}, {0.5f, 0, 0.5f}, {1.0f, 0, 0}, {2.0f, 0, -1.5f}};
    gi_pt_strategy strategies[] = {GI_PT_MIS, GI_PT_LIGHT, GI_PT_BSDF};
    for (int si = 0; si < 3; si++) {
        gi_pt_params p;
        gi_pt_params_default(&p);
        p.max_bounces = 1; /* direct light only */
        p.strategy = strategies[si];
        gi_pt_tracer tr = {&rt, &s, &p, NULL};
        /* BSDF sampling alone finds a small, far light too rarely for a 1%
         * check at a test's sample count: it covers the near points. */
        size_t npoints = si == 2 ? 3 : sizeof points / sizeof points[0];
        for (size_t i = 0; i < npoints; i++) {
            gi_vec3 x = points[i];
            double E = gi_test_polygon_irradiance(gi_test_lamp, 4, x, gi_v3(0, 1, 0), 2.0);
            double expect = 0.5 * E / GI_PI; /* L = rho E / pi */
            int n = si == 2 ? 400000 : 100000;
            double sum = 0;
            for (int k = 0; k < n; k++) {
                gi_rng rng;
                gi_rng_init(&rng, 11, i, (uint32_t)k);
                gi_vec3 L = gi_pt_radiance(&tr, gi_add(x, gi_v3(0, 0.01f, 0)), gi_v3(0, -1, 0), &rng);
                sum += L.y;
            }
            GI_CHECK_MSG(fabs(sum / n - expect) <= 0.01 * expect,
                         "strategy %d point %zu: %.6f vs Lambert %.6f (%.3f%%)", si, i, sum / n,
                         expect, 100.0 * (sum / n - expect) / expect);
        }
    }
    gi_rt_free(&rt);
    gi_scene_free(&s);
}

GI_TEST(test_rt_hits_report_distance_triangle_and_barycentrics)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    /* Straight down from the middle of the box onto the floor at y = 0. */
    gi_hit h;
    GI_REQUIRE(gi_rt_intersect(&rt, gi_v3(100, 500, 500), gi_v3(0, -1, 0), 0, 1e30f, &h));
    GI_CHECK_NEAR(h.t, 500.0, 1e-3);
    GI_CHECK(s.tri_object[h.tri] == (uint32_t)gi_scene_find_object(&s, "floor"));
    gi_vec3 a, b, c;
    gi_scene_triangle(&s, h.tri, &a, &b, &c);
    gi_vec3 p = gi_add(gi_add(gi_scale(a, 1 - h.u - h.v), gi_scale(b, h.u)), gi_scale(c, h.v));
    GI_CHECK_NEAR(p.x, 100.0, 1e-3);
    GI_CHECK_NEAR(p.z, 500.0, 1e-3);
    /* Up onto the light, and occlusion by the tall block. */
    GI_REQUIRE(gi_rt_intersect(&rt, gi_v3(278, 100, 280), gi_v3(0, 1, 0), 0, 1e30f, &h));
    GI_CHECK(s.tri_object[h.tri] == (uint32_t)gi_scene_find_object(&s, "light"));
    GI_CHECK_NEAR(h.t, 448.7, 1e-3);
    GI_CHECK(gi_rt_occluded(&rt, gi_v3(370, 100, 350), gi_v3(0, 1, 0), 0, 1000));
    GI_CHECK(!gi_rt_occluded(&rt, gi_v3(370, 400, 350), gi_v3(0, 1, 0), 0, 100));
    GI_CHECK(!gi_rt_intersect(&rt, gi_v3(278, 273, -10), gi_v3(0, 0, -1), 0, 1e30f, &h));
    GI_CHECK(rt.rays == 5);
    gi_rt_free(&rt);
    gi_scene_free(&s);
}

GI_TEST(test_paths_traced_together_match_one_at_a_time_bit_for_bit)
{
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_scene_file("scenes/cornell-box/scene.json", &s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    gi_pt_strategy strategies[] = {GI_PT_MIS, GI_PT_LIGHT, GI_PT_BSDF};
    for (int si = 0; si < 3; si++) {
        gi_pt_params p;
        gi_pt_params_default(&p);
        p.strategy = strategies[si];
        p.max_bounces = si == 1 ? 2 : -1;
        gi_pt_tracer tr = {&rt, &s, &p, NULL};
        enum { N = 3000 };
        static gi_pt_path paths[N];
        gi_vec3 single[N];
        gi_vec3 org = gi_v3(278, 273, -800);
        for (int i = 0; i < N; i++) {
            gi_rng rng;
            gi_rng_init(&rng, 9, (uint64_t)i, 0);
            gi_vec3 dir = gi_normalize(gi_v3(gi_rng_float(&rng) - 0.5f, gi_rng_float(&rng) - 0.5f, 1.5f));
            gi_pt_path_start(&paths[i], org, dir, &rng);
            single[i] = gi_pt_radiance(&tr, org, dir, &rng);
        }
        gi_pt_wavefront wf = {0};
        gi_pt_trace_paths(&tr, &wf, paths, N);
        gi_pt_wavefront_free(&wf);
        int differ = 0, nonzero = 0;
        for (int i = 0; i < N; i++) {
            differ += memcmp(&paths[i].L, &single[i], sizeof single[i]) != 0;
            nonzero += !gi_is_black(single[i]);
        }
        GI_CHECK_MSG(differ == 0, "strategy %d: %d of %d paths differ", si, differ, N);
        /* BSDF sampling alone rarely finds the small light. */
        GI_CHECK_MSG(nonzero > (si == 2 ? N / 200 : N / 2),
                     "strategy %d: only %d of %d paths carry light", si, nonzero, N);
    }
    gi_rt_free(&rt);
    gi_scene_free(&s);
}

GI_TEST(test_irradiance_matches_lambert_polygon_formula)
{
    /* gi_pt_irradiance (what per-vertex methods are checked against): the
     * direct irradiance from a square emitter at floor points, every
     * strategy, against Lambert's formula; with all bounces it is larger. */
    gi_error err;
    gi_scene s;
    GI_REQUIRE_OK(gi_test_load_lambert_scene(&s, &err));
    gi_rt rt;
    GI_REQUIRE_OK(gi_rt_create(&rt, &s, &err));
    gi_vec3 points[] = {{0, 0, 0}, {0.4f, 0, -0.3f}, {1.2f, 0, 0.5f}};
    gi_pt_strategy strategies[] = {GI_PT_MIS, GI_PT_LIGHT, GI_PT_BSDF};
    for (int si = 0; si < 3; si++)
        for (size_t i = 0; i < 3; i++) {
            gi_pt_params p;
            gi_pt_params_default(&p);
            p.max_bounces = 1;
            p.strategy = strategies[si];
            gi_pt_tracer tr = {&rt, &s, &p, NULL};
            double E = gi_test_polygon_irradiance(gi_test_lamp, 4, points[i], gi_v3(0, 1, 0), 2.0);
            int n = si == 2 ? 300000 : 60000;
            double sum = 0;
            for (int k = 0; k < n; k++) {
                gi_rng rng;
                gi_rng_init(&rng, 12, i, (uint32_t)k);
                sum += gi_pt_irradiance(&tr, points[i], gi_v3(0, 1, 0), &rng).y;
            }
            GI_CHECK_MSG(fabs(sum / n - E) <= 0.01 * E, "strategy %d point %zu: %.5f vs %.5f",
                         si, i, sum / n, E);
            if (si == 0) { /* light reflected by the floor cannot reach the floor */
                p.max_bounces = -1;
                double all = 0;
                for (int k = 0; k < n; k++) {
                    gi_rng rng;
                    gi_rng_init(&rng, 12, i, (uint32_t)k);
                    all += gi_pt_irradiance(&tr, points[i], gi_v3(0, 1, 0), &rng).y;
                }
                GI_CHECK(fabs(all - sum) <= 1e-9 * sum);
            }
        }
    gi_rt_free(&rt);
    gi_scene_free(&s);
}

/* Starts a 16 x 8 pt job of two 8 x 8 tiles (job file `name`). */
static int start_tiles_job(const char *name, gi_job *job, gi_jobrun *jr, gi_error *err)
{
    char text[1024], path[600];
    snprintf(text, sizeof text,
             "{\"scene\": \"%s/scenes/cornell-box/scene.json\", \"method\": \"pt\", \"seed\": 2,"
             " \"image\": {\"width\": 16, \"height\": 8}, \"pt\": {\"spp\": 2, \"tile\": 8}}",
             gi_test_srcdir());
    snprintf(path, sizeof path, "%s/%s", gi_test_tmpdir(), name);
    if (gi_write_file_atomic(path, text, strlen(text), err) || gi_job_load(path, job, err))
        return -1;
    if (gi_jobrun_start(jr, job, err)) {
        gi_job_free(job);
        return -1;
    }
    return 0;
}

/* A worker's result holding a NaN is refused as it arrives (the task then
 * fails and runs again) and names the pixel; a finite one passes. */
GI_TEST(test_pt_result_with_nan_is_refused)
{
    gi_error err;
    gi_job job;
    gi_jobrun jr;
    GI_REQUIRE_OK(start_tiles_job("nan.json", &job, &jr, &err));
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t != NULL);
    gi_buf res;
    gi_buf_init(&res);
    for (int i = 0; i < 8 * 8 * 4; i++)
        gi_buf_put_f64(&res, 0.25);
    GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &res, &err) == 0);
    double nan = NAN;
    memcpy(res.data + 8 * (4 * (3 * 8 + 5) + 1), &nan, 8); /* pixel (5, 3), green */
    GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &res, &err) != 0);
    GI_CHECK_MSG(strstr(err.msg, "task 0's result: pixel (5, 3) is not finite") != NULL, "%s",
                 err.msg);
    GI_CHECK(err.code == GI_EPROTO); /* a retry, not bad input */
    gi_buf_free(&res);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* A sum no task's samples of float radiance could give (which would
 * overflow the image's sums, or their mean as a float) is refused naming
 * the pixel and the sum; the largest possible passes. */
GI_TEST(test_pt_result_out_of_range_is_refused)
{
    gi_error err;
    gi_job job;
    gi_jobrun jr;
    GI_REQUIRE_OK(start_tiles_job("huge.json", &job, &jr, &err));
    const gi_task *t = gi_jobrun_lease(&jr); /* 2 samples a pixel */
    GI_REQUIRE(t != NULL);
    gi_buf res;
    gi_buf_init(&res);
    for (int i = 0; i < 8 * 8 * 4; i++)
        gi_buf_put_f64(&res, 0.25);
    double v = -2.0 * FLT_MAX, v2 = 2.0 * FLT_MAX * FLT_MAX; /* the most 2 samples give */
    memcpy(res.data + 8 * (4 * (3 * 8 + 5) + 2), &v, 8);     /* pixel (5, 3), blue */
    memcpy(res.data + 8 * (4 * (3 * 8 + 5) + 3), &v2, 8);
    GI_CHECK_MSG(gi_jobrun_check_result(&jr, t->id, t->attempt, &res, &err) == 0, "%s", err.msg);
    v = nextafter(v, -INFINITY);
    memcpy(res.data + 8 * (4 * (3 * 8 + 5) + 2), &v, 8);
    GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &res, &err) != 0);
    GI_CHECK_MSG(strstr(err.msg, "task 0's result: pixel (5, 3)'s blue sum is -6.80565e+38, "
                                 "out of range for 2 samples") != NULL, "%s", err.msg);
    v = 0.25;
    memcpy(res.data + 8 * (4 * (3 * 8 + 5) + 2), &v, 8);
    v2 = -1e-300; /* a sum of squares */
    memcpy(res.data + 8 * (4 * (3 * 8 + 5) + 3), &v2, 8);
    GI_CHECK(gi_jobrun_check_result(&jr, t->id, t->attempt, &res, &err) != 0);
    GI_CHECK_MSG(strstr(err.msg, "pixel (5, 3)'s sum of squared luminances is -1e-300") != NULL,
                 "%s", err.msg);
    GI_CHECK(err.code == GI_EPROTO);
    gi_buf_free(&res);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* A result of the wrong size (which pt_merge could not take) is refused as
 * it arrives, like a NaN: the task runs again and the job does not fail. */
GI_TEST(test_pt_result_of_the_wrong_size_is_retried)
{
    gi_error err;
    gi_job job;
    gi_jobrun jr;
    GI_REQUIRE_OK(start_tiles_job("size.json", &job, &jr, &err));
    size_t sizes[] = {8 * 8 * 4 * 8 - 8, 8 * 8 * 4 * 8 + 8, 0};
    for (size_t k = 0; k < GI_ARRAY_LEN(sizes); k++) {
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t != NULL);
        GI_CHECK(t->id == 0 && t->attempt == k); /* the same task, run again */
        gi_buf res;
        gi_buf_init(&res);
        for (size_t i = 0; i < sizes[k] / 8; i++)
            gi_buf_put_f64(&res, 0.25);
        GI_CHECK_OK(gi_test_refuse(&jr, t, &res, "task 0's result: result has", &err));
        gi_buf_free(&res);
    }
    GI_CHECK(jr.retries == GI_ARRAY_LEN(sizes) && !jr.failed);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}
