/* Unit tests: triangles of planar polygons (gi_polygon.h). */
#include <math.h>
#include <stdlib.h>

#include "gi_polygon.h"
#include "gi_rng.h"
#include "gi_test.h"

/* Random star-shaped polygons (simple by construction: vertices at
 * increasing angles around a centre, at random radii), convex or not, in
 * random planes: the triangles cover the polygon's area once, each wound
 * like the polygon. */
GI_TEST(test_polygon_ears_cover_star_shaped_polygons)
{
    gi_rng rng;
    gi_rng_init(&rng, 11, 0, 0);
    int concave_seen = 0;
    for (int trial = 0; trial < 400; trial++) {
        int n = 3 + trial % 40;
        gi_vec3 u = gi_normalize(gi_v3(gi_rng_float(&rng) - 0.5f, gi_rng_float(&rng) - 0.5f,
                                       gi_rng_float(&rng) - 0.5f));
        gi_vec3 a, b;
        gi_onb(u, &a, &b);
        gi_vec3 *pos = malloc((size_t)n * sizeof *pos);
        uint32_t *ix = malloc((size_t)n * sizeof *ix), *tris = malloc(3 * (size_t)n * sizeof *tris);
        double area = 0; /* in the (a, b) plane, counter-clockwise seen along u */
        double x[64], y[64];
        for (int i = 0; i < n; i++) {
            double t = 2 * GI_PI * (i + 0.8 * gi_rng_float(&rng)) / n;
            double r = trial % 3 ? 0.3 + gi_rng_float(&rng) : 1.0;
            x[i] = r * cos(t);
            y[i] = r * sin(t);
            pos[i] = gi_add(gi_v3(100, -50, 7),
                            gi_add(gi_scale(a, (float)x[i]), gi_scale(b, (float)y[i])));
            ix[i] = (uint32_t)i;
        }
        for (int i = 0; i < n; i++)
            area += 0.5 * (x[i] * y[(i + 1) % n] - x[(i + 1) % n] * y[i]);
        for (int i = 0; i < n && !concave_seen; i++) {
            int p = (i + n - 1) % n, q = (i + 1) % n;
            concave_seen = (x[i] - x[p]) * (y[q] - y[i]) - (y[i] - y[p]) * (x[q] - x[i]) < 0;
        }
        int made = gi_polygon_triangulate(pos, ix, n, tris);
        GI_REQUIRE(made == n - 2);
        double sum = 0;
        int backwards = 0;
        for (int t = 0; t < made; t++) {
            gi_vec3 e1 = gi_sub(pos[tris[3 * t + 1]], pos[tris[3 * t]]);
            gi_vec3 e2 = gi_sub(pos[tris[3 * t + 2]], pos[tris[3 * t]]);
            gi_vec3 c = gi_cross(e1, e2);
            double along = gi_dot(c, u);
            backwards += along < -1e-4;
            sum += 0.5 * fabs(along);
        }
        GI_CHECK_MSG(backwards == 0, "trial %d (%d vertices): %d triangles wound backwards",
                     trial, n, backwards);
        GI_CHECK_MSG(fabs(sum - area) < 1e-3 * area, "trial %d (%d vertices): area %g, "
                     "triangles %g", trial, n, area, sum);
        free(pos);
        free(ix);
        free(tris);
    }
    GI_CHECK(concave_seen);
}
