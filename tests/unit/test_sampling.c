/* Unit tests: sampling warps (disc, cosine hemisphere, triangle, CDF). */
#include "gi_rng.h"
#include "gi_sampling.h"
#include "gi_test.h"

GI_TEST(test_sincos_octant_accuracy)
{
    double worst = 0;
    for (int i = -1000; i <= 1000; i++) {
        float t = (float)(GI_PI / 4) * (float)i / 1000.0f, s, c;
        gi_sincos_octant(t, &s, &c);
        worst = fmax(worst, fmax(fabs(s - sin(t)), fabs(c - cos(t))));
    }
    GI_CHECK_MSG(worst < 5e-7, "worst error %g", worst);
}

GI_TEST(test_disc_and_cosine_sampling_moments)
{
    gi_rng rng;
    gi_rng_init(&rng, 1, 1, 1);
    int n = 400000;
    double sx = 0, sxx = 0, syy = 0, sxy = 0, sr = 0;
    double cz = 0, czz = 0, inner = 0;
    gi_vec3 nrm = gi_normalize(gi_v3(0.3f, -0.5f, 0.8f));
    int below = 0, outside = 0;
    for (int i = 0; i < n; i++) {
        float u1 = gi_rng_float(&rng), u2 = gi_rng_float(&rng), x, y;
        gi_sample_disc(u1, u2, &x, &y);
        outside += x * x + y * y > 1.0f + 1e-6f;
        sx += x;
        sxx += x * x;
        syy += y * y;
        sxy += x * y;
        sr += sqrt(x * x + y * y);
        inner += x * x + y * y < 0.25f;
        gi_vec3 w = gi_sample_cosine(nrm, u1, u2);
        double c = gi_dot(w, nrm);
        below += c < 0;
        GI_CHECK_NEAR(gi_length(w), 1.0, 1e-5);
        cz += c;
        czz += c * c;
    }
    GI_CHECK(outside == 0 && below == 0);
    /* Uniform disc: E[x] = 0, E[x^2] = E[y^2] = 1/4, E[xy] = 0, E[r] = 2/3,
     * P(r < 1/2) = 1/4. Cosine lobe: E[cos] = 2/3, E[cos^2] = 1/2. */
    GI_CHECK_NEAR(sx / n, 0.0, 0.003);
    GI_CHECK_NEAR(sxx / n, 0.25, 0.002);
    GI_CHECK_NEAR(syy / n, 0.25, 0.002);
    GI_CHECK_NEAR(sxy / n, 0.0, 0.002);
    GI_CHECK_NEAR(sr / n, 2.0 / 3.0, 0.002);
    GI_CHECK_NEAR(inner / n, 0.25, 0.003);
    GI_CHECK_NEAR(cz / n, 2.0 / 3.0, 0.002);
    GI_CHECK_NEAR(czz / n, 0.5, 0.002);
}

GI_TEST(test_triangle_and_cdf_sampling)
{
    gi_rng rng;
    gi_rng_init(&rng, 2, 2, 2);
    gi_vec3 a = gi_v3(0, 0, 0), b = gi_v3(2, 0, 0), c = gi_v3(0, 1, 0);
    double mx = 0, my = 0;
    int n = 200000;
    for (int i = 0; i < n; i++) {
        gi_vec3 p = gi_sample_triangle(a, b, c, gi_rng_float(&rng), gi_rng_float(&rng));
        GI_CHECK(p.x >= -1e-6f && p.y >= -1e-6f && p.x / 2 + p.y <= 1.0f + 1e-6f);
        mx += p.x;
        my += p.y;
    }
    /* Uniform: the mean is the centroid. */
    GI_CHECK_NEAR(mx / n, 2.0 / 3.0, 0.005);
    GI_CHECK_NEAR(my / n, 1.0 / 3.0, 0.003);
    double cdf[5] = {0.0, 0.1, 0.1, 0.6, 1.0}; /* entry 1 has probability 0 */
    int counts[4] = {0};
    for (int i = 0; i < n; i++)
        counts[gi_sample_cdf(cdf, 4, gi_rng_double(&rng))]++;
    GI_CHECK(counts[1] == 0);
    GI_CHECK_NEAR(counts[0] / (double)n, 0.1, 0.004);
    GI_CHECK_NEAR(counts[2] / (double)n, 0.5, 0.005);
    GI_CHECK_NEAR(counts[3] / (double)n, 0.4, 0.005);
    GI_CHECK(gi_sample_cdf(cdf, 4, 0.0) == 0 && gi_sample_cdf(cdf, 4, 0.9999999) == 3);
}

GI_TEST(test_sincos_turn_accuracy)
{
    double worst = 0;
    for (int i = 0; i < 100000; i++) {
        float u = (float)i / 100000.0f, s, c;
        gi_sincos_turn(u, &s, &c);
        double a = 2 * GI_PI * (double)u;
        worst = fmax(worst, fmax(fabs(s - sin(a)), fabs(c - cos(a))));
    }
    GI_CHECK_MSG(worst < 5e-7, "worst error %g", worst);
}
