/* genz: Genz's six test families for multidimensional integration on
 * [0,1]^d, with their closed-form integrals (A. Genz, "Testing
 * multidimensional integration routines", in Tools, Methods and Languages
 * for Scientific and Engineering Computation, 1984; "A package for testing
 * multiple integration subroutines", 1987). Shared by the unit tests
 * (tests/unit/test_quad_genz.c) and the benchmark (bench/quad_genz.c).
 *
 *   oscillatory      cos(2 pi w1 + sum a_i x_i)
 *   product peak     prod (a_i^-2 + (x_i - w_i)^2)^-1
 *   corner peak      (1 + sum a_i x_i)^-(d+1)
 *   Gaussian         exp(-sum a_i^2 (x_i - w_i)^2)
 *   continuous       exp(-sum a_i |x_i - w_i|)          (C0: a kink at w)
 *   discontinuous    0 if x1 > w1 or x2 > w2, else exp(sum a_i x_i)
 *
 * Parameters: w_i uniform in [0,1); a_i uniform in (0,1], then scaled so
 * that sum a_i = h_f, the difficulty of family f from Genz 1987:
 * h = 9, 7.25, 1.85, 7.03, 20.4, 4.3. Random numbers come from gi_rng keyed
 * by (seed, family, d), so a (family, d, seed) triple is one fixed function. */
#ifndef GI_BENCH_GENZ_H
#define GI_BENCH_GENZ_H

#include <complex.h>
#include <math.h>

#include "gi_rng.h"

enum {
    GI_GENZ_OSCILLATORY,
    GI_GENZ_PRODUCT_PEAK,
    GI_GENZ_CORNER_PEAK,
    GI_GENZ_GAUSSIAN,
    GI_GENZ_CONTINUOUS,
    GI_GENZ_DISCONTINUOUS,
    GI_GENZ_FAMILIES
};

#define GI_GENZ_MAX_D 16

typedef struct gi_genz {
    int family, d;
    double a[GI_GENZ_MAX_D], w[GI_GENZ_MAX_D];
} gi_genz;

static inline const char *gi_genz_name(int family)
{
    static const char *const names[GI_GENZ_FAMILIES] = {
        "oscillatory", "product peak", "corner peak", "Gaussian", "continuous", "discontinuous"};
    return names[family];
}

/* The smooth families (the tolerance must be met for them). */
static inline int gi_genz_smooth(int family)
{
    return family <= GI_GENZ_GAUSSIAN;
}

static inline void gi_genz_init(gi_genz *g, int family, int d, uint64_t seed)
{
    static const double h[GI_GENZ_FAMILIES] = {9.0, 7.25, 1.85, 7.03, 20.4, 4.3};
    gi_rng rng;
    gi_rng_init(&rng, seed, (uint64_t)family, (uint32_t)d);
    double sum = 0;
    g->family = family;
    g->d = d;
    for (int i = 0; i < d; i++) {
        g->a[i] = 1.0 - gi_rng_double(&rng); /* (0, 1] */
        g->w[i] = gi_rng_double(&rng);
        sum += g->a[i];
    }
    for (int i = 0; i < d; i++)
        g->a[i] *= h[family] / sum;
}

static inline double gi_genz_eval(const gi_genz *g, const double *x)
{
    int d = g->d;
    double s = 0, p = 1;
    switch (g->family) {
    case GI_GENZ_OSCILLATORY:
        for (int i = 0; i < d; i++)
            s += g->a[i] * x[i];
        return cos(2.0 * M_PI * g->w[0] + s);
    case GI_GENZ_PRODUCT_PEAK:
        for (int i = 0; i < d; i++) {
            double t = x[i] - g->w[i];
            p /= 1.0 / (g->a[i] * g->a[i]) + t * t;
        }
        return p;
    case GI_GENZ_CORNER_PEAK:
        for (int i = 0; i < d; i++)
            s += g->a[i] * x[i];
        return pow(1.0 + s, -(d + 1));
    case GI_GENZ_GAUSSIAN:
        for (int i = 0; i < d; i++) {
            double t = x[i] - g->w[i];
            s += g->a[i] * g->a[i] * t * t;
        }
        return exp(-s);
    case GI_GENZ_CONTINUOUS:
        for (int i = 0; i < d; i++)
            s += g->a[i] * fabs(x[i] - g->w[i]);
        return exp(-s);
    default:
        if (x[0] > g->w[0] || (d > 1 && x[1] > g->w[1]))
            return 0.0;
        for (int i = 0; i < d; i++)
            s += g->a[i] * x[i];
        return exp(s);
    }
}

static inline double gi_genz_exact(const gi_genz *g)
{
    int d = g->d;
    double p = 1;
    switch (g->family) {
    case GI_GENZ_OSCILLATORY: {
        /* Re[e^(2 pi i w1) prod (e^(i a) - 1) / (i a)] */
        double complex z = cexp(2.0 * M_PI * I * g->w[0]);
        for (int i = 0; i < d; i++)
            z *= (cexp(I * g->a[i]) - 1.0) / (I * g->a[i]);
        return creal(z);
    }
    case GI_GENZ_PRODUCT_PEAK:
        for (int i = 0; i < d; i++)
            p *= g->a[i] * (atan(g->a[i] * (1.0 - g->w[i])) + atan(g->a[i] * g->w[i]));
        return p;
    case GI_GENZ_CORNER_PEAK: {
        /* (1 / (d! prod a)) sum over corners v of (-1)^|v| / (1 + a.v) */
        double sum = 0, fact = 1;
        for (int i = 2; i <= d; i++)
            fact *= i;
        for (unsigned v = 0; v < (1u << d); v++) {
            double s = 1.0;
            int bits = 0;
            for (int i = 0; i < d; i++)
                if (v >> i & 1) {
                    s += g->a[i];
                    bits++;
                }
            sum += (bits & 1 ? -1.0 : 1.0) / s;
        }
        for (int i = 0; i < d; i++)
            p *= g->a[i];
        return sum / (fact * p);
    }
    case GI_GENZ_GAUSSIAN:
        for (int i = 0; i < d; i++)
            p *= sqrt(M_PI) / (2.0 * g->a[i]) *
                 (erf(g->a[i] * (1.0 - g->w[i])) + erf(g->a[i] * g->w[i]));
        return p;
    case GI_GENZ_CONTINUOUS:
        for (int i = 0; i < d; i++)
            p *= (2.0 - exp(-g->a[i] * g->w[i]) - exp(-g->a[i] * (1.0 - g->w[i]))) / g->a[i];
        return p;
    default:
        for (int i = 0; i < d; i++) {
            double top = i < 2 ? g->w[i] : 1.0;
            p *= (exp(g->a[i] * top) - 1.0) / g->a[i];
        }
        return p;
    }
}

/* The oscillatory family can integrate to ~0 (a cosine over a box), where
 * relative errors mean nothing: from `seed` on, the first seed whose
 * integral is at least 0.05 in magnitude (|f| <= 1). The other families are
 * positive: their first seed is taken. */
static inline void gi_genz_pick(gi_genz *g, int family, int d, uint64_t seed)
{
    for (uint64_t s = seed;; s++) {
        gi_genz_init(g, family, d, s);
        if (family != GI_GENZ_OSCILLATORY || fabs(gi_genz_exact(g)) >= 0.05)
            return;
    }
}

#endif
