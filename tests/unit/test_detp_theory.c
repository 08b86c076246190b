/* Unit tests: the thesis's closed forms. eq. 3.46 (relative error of DETP
 * under uniformly distributed lines) and eqs. 3.15-3.21 (the photon map's
 * k-1 estimator is unbiased on a constant density, the k one is not). */
#include <string.h>

#include "detp/detp.h"
#include "gi_rng.h"
#include "gi_test.h"

/* Thesis Fig. 1.7: a uniform point on the unit sphere. */
static gi_vec3 point_on_sphere(gi_rng *r)
{
    double z = 2.0 * gi_rng_double(r) - 1.0, phi = 2.0 * GI_PI * gi_rng_double(r);
    double theta = asin(z);
    return gi_v3((float)(cos(theta) * cos(phi)), (float)(cos(theta) * sin(phi)), (float)z);
}

GI_TEST(test_detp_relative_error_matches_eq_3_46)
{
    /* Lines through two uniform points of the unit sphere are uniformly
     * distributed (Fig. 1.7); A_0 = 4 pi. One disc at the centre, total
     * power 1 shared by the n_R lines. */
    const int rays = 2000, seeds = 2000;
    const double d = 0.2, A0 = 4.0 * GI_PI, Ad = GI_PI * d * d;
    gi_detp_discs discs = {1, NULL, (float)d, (float)(d * d)};
    gi_detp_disc D = {{0, 0, 0}, {0.48f, -0.6f, 0.64f}};
    discs.d = &D;
    gi_detp_accum acc;
    gi_error err;
    GI_REQUIRE_OK(gi_detp_accum_init(&acc, 1, &err));
    gi_detp_segments s;
    gi_detp_segments_init(&s);
    double sum = 0, sum2 = 0;
    for (int k = 0; k < seeds; k++) {
        gi_rng r;
        gi_rng_init(&r, 346, (uint64_t)k, 0);
        s.count = 0;
        for (int i = 0; i < rays; i++) {
            gi_vec3 a = point_on_sphere(&r), b = point_on_sphere(&r);
            gi_detp_segment *g = gi_detp_segments_push(&s);
            gi_vec3 ab = gi_sub(b, a);
            g->org = a;
            g->dir = gi_normalize(ab);
            g->t_hit = g->t_end = gi_length(ab);
            g->t_second = INFINITY;
            g->energy = gi_v3(1.0f / rays, 0, 0);
        }
        gi_detp_accum_clear(&acc);
        gi_detp_stats st;
        memset(&st, 0, sizeof st);
        gi_detp_basic(&discs, &s, &acc, &st);
        double L = acc.energy[0] / Ad; /* Rad(X) = phi Ray(X) / A_d */
        sum += L;
        sum2 += L * L;
    }
    double mean = sum / seeds, sd = sqrt((sum2 - seeds * mean * mean) / (seeds - 1));
    double predicted = gi_detp_predicted_error(A0, Ad, rays);
    GI_CHECK_NEAR(predicted, sqrt((A0 - Ad) / (Ad * rays)), 1e-12);
    printf("eq. 3.46: measured relative error %.4f, predicted %.4f (mean %.5f, Phi/A_0 %.5f)\n",
           sd / mean, predicted, mean, 1.0 / A0);
    /* E(L) = Phi_T / A_0 (eq. 3.42); the relative error within 10% of
     * eq. 3.46 (the sample deviation of 2000 seeds is good to ~1.6%). */
    GI_CHECK_REL(mean, 1.0 / A0, 0.02);
    GI_CHECK_MSG(fabs(sd / mean / predicted - 1.0) < 0.10,
                 "measured relative error %.4f, eq. 3.46 predicts %.4f", sd / mean, predicted);
    /* Inverting eq. 3.46 gives back the ray count. */
    GI_CHECK(gi_detp_rays_for_error(A0, Ad, predicted) >= (uint64_t)rays - 1 &&
             gi_detp_rays_for_error(A0, Ad, predicted) <= (uint64_t)rays + 1);
    /* The thesis's own check (4.10.1): Tree Scene, d = 0.1, A_0 = 2.05507:
     * 8.02% at 10,000 photons, 25.38% at 1,000. */
    GI_CHECK_NEAR(gi_detp_predicted_error(2.05507, GI_PI * 0.01, 10000), 0.0802, 0.0001);
    GI_CHECK_NEAR(gi_detp_predicted_error(2.05507, GI_PI * 0.01, 1000), 0.2538, 0.0001);
    gi_detp_segments_free(&s);
    gi_detp_accum_free(&acc);
}

GI_TEST(test_detp_photon_map_k_minus_one_is_unbiased)
{
    /* n photons uniform in the unit disc (density v = 1 when each carries
     * phi = pi v / n), query at the centre: E[(k-1) phi / (pi R^2)] = v
     * (eqs. 3.15-3.21); summing k photons gives v k / (k-1). */
    const uint32_t n = 200;
    const uint32_t ks[2] = {5, 20};
    const int trials[2] = {6000, 3000};
    gi_detp_discs discs = {1, NULL, 1.0f, 1.0f};
    gi_detp_disc D = {{0, 0, 0}, {0, 0, 1}};
    discs.d = &D;
    gi_error err;
    gi_detp_accum acc;
    GI_REQUIRE_OK(gi_detp_accum_init(&acc, 1, &err));
    gi_detp_segments s;
    gi_detp_segments_init(&s);
    for (int c = 0; c < 2; c++) {
        uint32_t k = ks[c];
        double sum[2] = {0, 0}, sum2[2] = {0, 0};
        for (int t = 0; t < trials[c]; t++) {
            gi_rng r;
            gi_rng_init(&r, 320, (uint64_t)t, k);
            s.count = 0;
            for (uint32_t i = 0; i < n; i++) {
                float rad = sqrtf(gi_rng_float(&r)), phi = (float)(2 * GI_PI) * gi_rng_float(&r);
                gi_detp_segment *g = gi_detp_segments_push(&s);
                g->org = gi_v3(rad * cosf(phi), rad * sinf(phi), 1.0f);
                g->dir = gi_v3(0, 0, -1);
                g->t_hit = g->t_end = 1.0f;
                g->hit_tri = 0;
                g->energy = gi_v3((float)(GI_PI / n), 0, 0);
            }
            for (int km1 = 0; km1 < 2; km1++) {
                gi_detp_accum_clear(&acc);
                gi_detp_stats st;
                memset(&st, 0, sizeof st);
                GI_REQUIRE_OK(gi_detp_photon_map(&discs, &s, k, km1, &acc, &st, &err));
                sum[km1] += acc.energy[0];
                sum2[km1] += acc.energy[0] * acc.energy[0];
            }
        }
        for (int km1 = 0; km1 < 2; km1++) {
            double m = sum[km1] / trials[c];
            double se = sqrt((sum2[km1] / trials[c] - m * m) / trials[c]);
            double expect = km1 ? 1.0 : (double)k / (k - 1);
            printf("photon map k = %u, sum of %s: mean %.4f +- %.4f (expected %.4f)\n", k,
                   km1 ? "k-1" : "k", m, se, expect);
            GI_CHECK_MSG(fabs(m - expect) < 4.0 * se,
                         "k = %u, %s: mean %.4f, expected %.4f (standard error %.4f)", k,
                         km1 ? "k-1" : "k", m, expect, se);
            /* The bias k/(k-1) - 1 is far outside the noise. */
            GI_CHECK(fabs((double)k / (k - 1) - 1.0) > 6.0 * se);
        }
    }
    gi_detp_segments_free(&s);
    gi_detp_accum_free(&acc);
}
