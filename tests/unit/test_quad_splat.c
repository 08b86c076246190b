/* Unit tests: region interpolants and their splatting into pixels:
 * conservation (pixel values times pixel area add up to the region
 * estimates), exact pixel means of functions the interpolant reproduces. */
#include <stdlib.h>
#include <string.h>

#include "gi_rng.h"
#include "gi_test.h"
#include "quadrature/quad_region.h"
#include "quadrature/quad_splat.h"

typedef struct fn_ctx {
    int dims, kind; /* kind 0: positive, peaked; 1: signed; 2: linear in x, y */
} fn_ctx;

static void test_fn(void *user, size_t n, const double *pts, double *out)
{
    const fn_ctx *c = user;
    for (size_t i = 0; i < n; i++) {
        const double *x = pts + i * c->dims;
        double w = 1.0;
        for (int d = 2; d < c->dims; d++)
            w *= 1.0 + x[d];
        double v;
        if (c->kind == 0)
            v = w / (0.01 + (x[0] - 0.3) * (x[0] - 0.3) + (x[1] - 0.6) * (x[1] - 0.6));
        else if (c->kind == 1)
            v = w * sin(20 * x[0] + 7 * x[1]);
        else
            v = w * (1.0 + 2.0 * x[0] - 3.0 * x[1]);
        out[3 * i] = v;
        out[3 * i + 1] = 0.5 * v;
        out[3 * i + 2] = c->kind == 1 ? -v : v * x[0];
    }
}

/* Partitions [0,1]^dims by random bisections into `leaves` regions and
 * splats them all; checks the pixel sum against the estimates. */
static void check_partition(gi_quad_rule_kind kind, int dims, int fkind, int W, int H)
{
    gi_error err;
    gi_quad_rule r;
    GI_REQUIRE_OK(gi_quad_rule_init(&r, kind, dims, 3, &err));
    fn_ctx ctx = {dims, fkind};
    gi_quad_integrand fn = {test_fn, &ctx};
    gi_quad_image im = {W, H};
    gi_quad_engine e;
    GI_REQUIRE_OK(gi_quad_engine_init(&e, &r, GI_QUAD_AXIS_MARGINAL, &im, &fn, &err));
    gi_quad_accum acc;
    GI_REQUIRE_OK(gi_quad_accum_init(&acc, W, H, 3, &err));
    double lo[GI_QUAD_MAX_DIMS] = {0}, hi[GI_QUAD_MAX_DIMS];
    for (int d = 0; d < dims; d++)
        hi[d] = 1.0;
    gi_quad_region *leaves[400];
    int n = 0;
    leaves[n++] = gi_quad_region_new(&e, lo, hi, &err);
    gi_rng rng;
    gi_rng_init(&rng, 3, (uint64_t)kind, (uint32_t)fkind);
    while (n < 200) {
        int k = (int)gi_rng_below(&rng, (uint32_t)n);
        gi_quad_region *p = leaves[k], *c[2];
        p->s.axis = (int)gi_rng_below(&rng, (uint32_t)dims);
        GI_REQUIRE_OK(gi_quad_region_split(&e, p, c, &err));
        gi_quad_region_release(&e, p);
        leaves[k] = c[0];
        leaves[n++] = c[1];
    }
    double est[3] = {0, 0, 0}, integ[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        gi_quad_summary *s = &leaves[i]->s;
        double g[3];
        gi_quad_interp_integral(&s->interp, s->lo, s->hi, g);
        for (int c = 0; c < 3; c++) {
            /* The interpolant integrates to the region's estimate. */
            GI_CHECK_MSG(fabs(g[c] - s->est[c]) <= 1e-12 * (fabs(s->est[c]) + 1e-300) ||
                             fabs(g[c] - s->est[c]) <= 1e-15,
                         "rule %d: interpolant %.17g vs estimate %.17g", kind, g[c], s->est[c]);
            est[c] += s->est[c];
            integ[c] += g[c];
        }
        gi_quad_splat(&s->interp, s->lo, s->hi, 1.0, &acc);
    }
    double sum[3] = {0, 0, 0};
    int negative = 0;
    for (size_t p = 0; p < (size_t)W * H; p++)
        for (int c = 0; c < 3; c++) {
            sum[c] += acc.px[3 * p + c];
            negative += acc.px[3 * p + c] < 0.0;
        }
    /* A positive function gives no negative pixel (Boole: scaled grid;
     * Genz-Malik: the slope limiter). */
    if (fkind == 0)
        GI_CHECK_MSG(negative == 0, "rule %d: %d negative pixel values", kind, negative);
    double area = 1.0 / ((double)W * H), scale = 0;
    for (int i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            scale += fabs(leaves[i]->s.est[c]);
    for (int c = 0; c < 3; c++)
        GI_CHECK_MSG(fabs(sum[c] * area - est[c]) <= 1e-9 * scale,
                     "rule %d f %d %dx%d channel %d: pixels %.17g vs regions %.17g (rel %.3g)", kind,
                     fkind, W, H, c, sum[c] * area, est[c], fabs(sum[c] * area - est[c]) / scale);
    for (int i = 0; i < n; i++)
        gi_quad_region_release(&e, leaves[i]);
    gi_quad_accum_free(&acc);
    gi_quad_engine_free(&e);
    gi_quad_rule_free(&r);
}

GI_TEST(test_quad_splat_conserves_region_estimates)
{
    for (int kind = 0; kind < 2; kind++)
        for (int f = 0; f < 3; f++) {
            check_partition(kind ? GI_QUAD_GM : GI_QUAD_BOOLE, 4, f, 37, 23);
            check_partition(kind ? GI_QUAD_GM : GI_QUAD_BOOLE, 2, f, 64, 64);
            check_partition(kind ? GI_QUAD_GM : GI_QUAD_BOOLE, 3, f, 5, 7);
        }
}

GI_TEST(test_quad_splat_pixel_means_of_linear_functions_are_exact)
{
    /* Linear in x, y (times a weight over the light axes): both
     * interpolants reproduce it, so every pixel gets its exact mean. */
    gi_error err;
    int W = 13, H = 11;
    for (int kind = 0; kind < 2; kind++) {
        gi_quad_rule r;
        GI_REQUIRE_OK(gi_quad_rule_init(&r, kind ? GI_QUAD_GM : GI_QUAD_BOOLE, 4, 3, &err));
        fn_ctx ctx = {4, 2};
        gi_quad_integrand fn = {test_fn, &ctx};
        gi_quad_image im = {W, H};
        gi_quad_engine e;
        GI_REQUIRE_OK(gi_quad_engine_init(&e, &r, GI_QUAD_AXIS_MARGINAL, &im, &fn, &err));
        gi_quad_accum acc;
        GI_REQUIRE_OK(gi_quad_accum_init(&acc, W, H, 3, &err));
        double lo[4] = {0, 0, 0, 0}, hi[4] = {1, 1, 1, 1};
        gi_quad_region *g = gi_quad_region_new(&e, lo, hi, &err);
        GI_REQUIRE(g != NULL);
        gi_quad_splat(&g->s.interp, g->s.lo, g->s.hi, 1.0, &acc);
        /* int over the light axes of (1+x2)(1+x3) = 2.25 */
        for (int j = 0; j < H; j++)
            for (int i = 0; i < W; i++) {
                double cx = (i + 0.5) / W, cy = (j + 0.5) / H;
                double want = 2.25 * (1.0 + 2.0 * cx - 3.0 * cy);
                GI_CHECK_NEAR(acc.px[3 * (j * W + i)], want, 1e-12);
                GI_CHECK_NEAR(acc.px[3 * (j * W + i) + 1], 0.5 * want, 1e-12);
            }
        /* The pointwise interpolant (the hybrid's control variate) is the
         * same function: G(x, y) / light volume = the linear function. */
        double v[3];
        gi_quad_interp_eval(&g->s.interp, g->s.lo, g->s.hi, 0.3, 0.7, v);
        GI_CHECK_NEAR(v[0], 2.25 * (1.0 + 0.6 - 2.1), 1e-12);
        gi_quad_region_release(&e, g);
        gi_quad_accum_free(&acc);
        gi_quad_engine_free(&e);
        gi_quad_rule_free(&r);
    }
}

GI_TEST(test_quad_accum_serializes_touched_pixels_in_order)
{
    gi_error err;
    gi_quad_accum acc;
    GI_REQUIRE_OK(gi_quad_accum_init(&acc, 8, 4, 3, &err));
    double v[3] = {1, 2, 3};
    gi_quad_accum_add(&acc, 17, v, 1.0);
    gi_quad_accum_add(&acc, 3, v, 2.0);
    gi_quad_accum_add(&acc, 17, v, -1.0);
    gi_buf b;
    gi_buf_init(&b);
    gi_quad_accum_emit(&acc, &b);
    GI_CHECK(acc.count == 0 && acc.px[17 * 3] == 0.0);
    double img[8 * 4 * 3] = {0};
    gi_reader r;
    gi_reader_init(&r, b.data, b.len, "delta");
    GI_REQUIRE_OK(gi_quad_accum_apply(&r, 8, 4, 3, 6.0, img, &err));
    GI_CHECK(r.left == 0);
    GI_CHECK(img[3 * 3] == 2.0 && img[3 * 3 + 2] == 6.0 && img[17 * 3] == 0.0);
    /* A value beyond the bound (6 is at it) is refused and changes nothing. */
    gi_reader_init(&r, b.data, b.len, "delta");
    GI_CHECK(gi_quad_accum_apply(&r, 8, 4, 3, 5.5, img, &err) == -1 && err.code == GI_EPROTO);
    GI_CHECK_MSG(strstr(err.msg, "pixel 3's value is 6, not within +-5.5") != NULL, "%s",
                 err.msg);
    GI_CHECK(img[3 * 3] == 2.0 && img[3 * 3 + 2] == 6.0);
    /* Out-of-range or unordered indices are refused and change nothing. */
    gi_buf_reset(&b);
    gi_buf_put_u32(&b, 2);
    gi_buf_put_u32(&b, 5);
    gi_buf_put_f64s(&b, v, 3);
    gi_buf_put_u32(&b, 4);
    gi_buf_put_f64s(&b, v, 3);
    gi_reader_init(&r, b.data, b.len, "delta");
    GI_CHECK(gi_quad_accum_apply(&r, 8, 4, 3, 1e30, img, &err) == -1 && err.code == GI_EPROTO);
    GI_CHECK(img[5 * 3] == 0.0);
    gi_buf_free(&b);
    gi_quad_accum_free(&acc);
}
