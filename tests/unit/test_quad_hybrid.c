/* Unit tests: the hybrid estimator (quadrature + Monte Carlo with the
 * region interpolant as control variate) is unbiased per pixel on a toy
 * problem with a closed-form image, and the causes of bias named in
 * quad_hybrid.h - dropping negative residuals (what Mitsuba's image block
 * does), a control variate whose integral and point values disagree, and
 * Monte Carlo on only some regions - each bias it measurably. */
#include <stdlib.h>
#include <string.h>

#include "gi_log.h"
#include "gi_rng.h"
#include "gi_test.h"
#include "quadrature/quad_hybrid.h"
#include "quadrature/quad_refine.h"
#include "quadrature/quad_splat.h"

#define W 8
#define H 8
#define DIMS 4
#define EDGE 0.37

/* The "cut" integrand: a jump at x = EDGE no dyadic region boundary meets,
 * smooth in y (curved enough that trapezoid and Boole differ) and in the
 * two path axes. */
static double toy_cut(const double *u)
{
    double step = u[0] > EDGE ? exp(3.0 * u[1]) : 0.0;
    return (1.0 + u[2]) * (0.5 + u[3]) * step + 0.2 * u[0];
}

static void toy_eval(void *user, size_t n, const double *pts, double *out)
{
    for (size_t i = 0; i < n; i++)
        out[i] = toy_cut(pts + i * DIMS);
}

/* The "full" integrand: the cut one plus what the coordinates beyond N add
 * (here 0.3 xi (1 + y), xi uniform: mean 0.15 (1 + y)). */
static void toy_mc(void *user, const double *u, gi_rng *rng, double *out)
{
    out[0] = toy_cut(u) + 0.3 * gi_rng_double(rng) * (1.0 + u[1]);
}

/* Exact pixel values of the full integrand: W H x its integral over the
 * pixel's slab. The path axes integrate (1+a)(0.5+b) to 1.5. */
static double exact_pixel(int i, int j)
{
    double x0 = (double)i / W, x1 = (double)(i + 1) / W, y0 = (double)j / H,
           y1 = (double)(j + 1) / H;
    double lit = x1 > EDGE ? x1 - (x0 > EDGE ? x0 : EDGE) : 0.0;
    double y_int = (exp(3.0 * y1) - exp(3.0 * y0)) / 3.0;
    double v = 1.5 * lit * y_int + 0.2 * 0.5 * (x1 * x1 - x0 * x0) * (y1 - y0) +
               0.15 * (x1 - x0) * ((y1 - y0) + 0.5 * (y1 * y1 - y0 * y0));
    return v * W * H;
}

typedef enum { HYBRID_OK, HYBRID_CLAMPED, HYBRID_MISMATCHED, HYBRID_PARTIAL } variant;

typedef struct toy {
    gi_quad_rule rule;
    gi_quad_engine e;
    gi_quad_region *leaf[64];
    gi_quad_interp raw[64]; /* the unscaled trapezoid grid, per leaf */
    int n;
    gi_quad_accum splat; /* the quadrature part, the same for every seed */
} toy;

static void collect(void *user, gi_quad_region *r) {}

static int toy_build(toy *t, gi_error *err)
{
    memset(t, 0, sizeof *t);
    if (gi_quad_rule_init(&t->rule, GI_QUAD_BOOLE, DIMS, 1, err))
        return -1;
    gi_quad_integrand fn = {toy_eval, NULL};
    gi_quad_image im = {W, H};
    if (gi_quad_engine_init(&t->e, &t->rule, GI_QUAD_AXIS_MARGINAL, &im, &fn, err) ||
        gi_quad_accum_init(&t->splat, W, H, 1, err))
        return -1;
    /* A deliberately coarse partition: 12 bisections. */
    double lo[DIMS] = {0}, hi[DIMS] = {1, 1, 1, 1};
    gi_qheap *heap = gi_qheap_create(GI_QHEAP_BINARY);
    gi_quad_refine_cb cb = {NULL, collect, NULL, NULL};
    gi_quad_region *root = gi_quad_region_new(&t->e, lo, hi, err);
    if (!root)
        return -1;
    gi_quad_refine_offer(&t->e, heap, root, 0.0, &cb);
    uint64_t splits;
    if (gi_quad_refine(&t->e, heap, 0.0, 12, &cb, &splits, err))
        return -1;
    double key;
    uint64_t tie;
    uint32_t slot;
    while (gi_qheap_pop(heap, &key, &tie, &slot)) {
        gi_quad_region *r = gi_quad_region_at(&t->e, slot);
        gi_quad_analysis a;
        gi_quad_rule_analyse(&t->rule, GI_QUAD_AXIS_MARGINAL, r->f, r->s.lo, r->s.hi, &a);
        t->raw[t->n].n = 5;
        t->raw[t->n].channels = 1;
        memcpy(t->raw[t->n].v, a.image, sizeof(double) * 25);
        t->leaf[t->n++] = r;
        gi_quad_splat(&r->s.interp, r->s.lo, r->s.hi, 1.0, &t->splat);
    }
    gi_qheap_free(heap);
    return 0;
}

static void toy_free(toy *t)
{
    gi_quad_accum_free(&t->splat);
    gi_quad_engine_free(&t->e);
    gi_quad_rule_free(&t->rule);
}

/* One run of a (possibly flawed) hybrid estimator: pixel values into img. */
static void run_variant(toy *t, variant v, uint64_t seed, int spp, gi_quad_accum *acc,
                        double *img)
{
    for (int k = 0; k < t->n; k++) {
        const gi_quad_summary *s = &t->leaf[k]->s;
        if (v == HYBRID_OK) {
            double total = 0;
            gi_quad_hybrid_region(toy_mc, NULL, seed, s, DIMS, spp, acc, &total);
            continue;
        }
        /* The flawed ones, written out like gi_quad_hybrid_region. */
        if (v == HYBRID_PARTIAL && s->err < t->leaf[t->n / 2]->s.err)
            continue; /* only the larger half of the errors get samples */
        uint64_t n = gi_quad_hybrid_samples(s, W, H, spp);
        double vol = 1, light = 1;
        for (int d = 0; d < DIMS; d++) {
            vol *= s->hi[d] - s->lo[d];
            light *= d >= 2 ? s->hi[d] - s->lo[d] : 1.0;
        }
        for (uint64_t j = 0; j < n; j++) {
            gi_rng rng;
            gi_rng_init(&rng, seed, s->id, (uint32_t)j);
            double u[DIMS], f, g;
            for (int d = 0; d < DIMS; d++)
                u[d] = s->lo[d] + (s->hi[d] - s->lo[d]) * gi_rng_double(&rng);
            toy_mc(NULL, u, &rng, &f);
            gi_quad_interp_eval(v == HYBRID_MISMATCHED ? &t->raw[k] : &s->interp, s->lo, s->hi,
                                u[0], u[1], &g);
            double r = f - g / light;
            if (v == HYBRID_CLAMPED && r < 0)
                continue; /* Mitsuba's ImageBlock refuses negative samples */
            int px = (int)(u[0] * W), py = (int)(u[1] * H);
            gi_quad_accum_add(acc, (uint32_t)(py * W + px), &r, vol * W * H / (double)n);
        }
    }
    for (int p = 0; p < W * H; p++) {
        img[p] = t->splat.px[p] + acc->px[p];
        acc->px[p] = 0;
        acc->mark[p] = 0;
    }
    acc->count = 0;
}

/* Sum over pixels of ((mean - exact) / standard error)^2 over `runs` seeds,
 * and the worst single pixel in standard errors. */
static double chi2(toy *t, variant v, int runs, double *worst)
{
    gi_error err;
    gi_quad_accum acc;
    if (gi_quad_accum_init(&acc, W, H, 1, &err))
        return -1;
    double s[W * H] = {0}, s2[W * H] = {0}, img[W * H];
    for (int r = 0; r < runs; r++) {
        run_variant(t, v, 1000 + (uint64_t)r, 4, &acc, img);
        for (int p = 0; p < W * H; p++) {
            s[p] += img[p];
            s2[p] += img[p] * img[p];
        }
    }
    double c = 0;
    *worst = 0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            int p = j * W + i;
            double mean = s[p] / runs, var = (s2[p] / runs - mean * mean) / (runs - 1);
            /* Pixels no sample reaches (a flawed variant) have no variance:
             * judge them on a 1e-6 relative scale. */
            double floor = 1e-6 * fabs(exact_pixel(i, j)) + 1e-12;
            double se = sqrt(var) > floor ? sqrt(var) : floor;
            double z = (mean - exact_pixel(i, j)) / se;
            c += z * z;
            *worst = fabs(z) > *worst ? fabs(z) : *worst;
        }
    gi_quad_accum_free(&acc);
    return c;
}

GI_TEST(test_quad_hybrid_is_unbiased_and_the_thesis_biases_are_real)
{
    gi_error err;
    toy t;
    GI_REQUIRE_OK(toy_build(&t, &err));
    GI_REQUIRE(t.n == 13);
    /* The quadrature alone is biased (cut coordinates, coarse regions). */
    double qerr = 0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++)
            qerr += fabs(t.splat.px[j * W + i] - exact_pixel(i, j));
    GI_CHECK_MSG(qerr / (W * H) > 0.05, "quadrature alone is too good to test: %g", qerr);

    int runs = 4000;
    double worst, c = chi2(&t, HYBRID_OK, runs, &worst);
    /* 64 pixels: chi^2 has mean 64, standard deviation ~11. */
    GI_CHECK_MSG(c < 64 + 5 * 11 && worst < 4.5, "hybrid: chi2 %.1f, worst pixel %.2f sigma", c,
                 worst);
    double c_clamp = chi2(&t, HYBRID_CLAMPED, runs, &worst);
    double c_mismatch = chi2(&t, HYBRID_MISMATCHED, runs, &worst);
    double c_partial = chi2(&t, HYBRID_PARTIAL, runs, &worst);
    /* Each flaw: chi^2 beyond 64 + 20 standard deviations. */
    GI_CHECK_MSG(c_clamp > 300, "dropping negative residuals: chi2 %.1f (no bias seen)", c_clamp);
    GI_CHECK_MSG(c_mismatch > 300, "mismatched control variate: chi2 %.1f", c_mismatch);
    GI_CHECK_MSG(c_partial > 300, "Monte Carlo on some regions only: chi2 %.1f", c_partial);
    gi_info("chi2 over 64 pixels, %d seeds: hybrid %.1f, clamped %.3g, mismatched %.3g, "
            "partial %.3g",
            runs, c, c_clamp, c_mismatch, c_partial);
    toy_free(&t);
}
