/* Unit tests: adaptive cubature of Genz's six test families (bench/genz.h)
 * against their closed-form integrals. The benchmark (bench/quad_genz.c)
 * runs the same at 1e-3 and 1e-6 over more rules and reports evaluations. */
#include "bench/genz.h"
#include "gi_test.h"
#include "quadrature/quad_integrate.h"

static void genz_fn(void *user, size_t n, const double *pts, double *out)
{
    const gi_genz *g = user;
    for (size_t i = 0; i < n; i++)
        out[i] = gi_genz_eval(g, pts + i * g->d);
}

/* Integrates every family in d = lo..hi at tolerance tol; smooth families
 * must converge with an actual error below tol (relative). */
static void run_families(gi_quad_rule_kind rule, int dlo, int dhi, double tol,
                         uint64_t max_evals)
{
    gi_error err;
    for (int d = dlo; d <= dhi; d++)
        for (int fam = 0; fam < GI_GENZ_FAMILIES; fam++) {
            gi_genz g;
            gi_genz_pick(&g, fam, d, 1);
            double exact = gi_genz_exact(&g);
            gi_quad_integrand fn = {genz_fn, &g};
            gi_quad_opts o = {rule, GI_QUAD_AXIS_MARGINAL, GI_QHEAP_BUCKETED, tol, 0, max_evals};
            gi_quad_result res;
            GI_REQUIRE_OK(gi_quad_integrate(d, 1, &fn, &o, &res, &err));
            double rel = fabs(res.est[0] - exact) / fabs(exact);
            if (gi_genz_smooth(fam)) {
                GI_CHECK_MSG(res.converged && rel <= tol,
                             "%s d=%d rule %d: relative error %.3g (tolerance %g, estimate %.3g, "
                             "%llu evaluations, converged %d)",
                             gi_genz_name(fam), d, rule, rel, tol, res.err / fabs(exact),
                             (unsigned long long)res.evals, res.converged);
            } else {
                /* Kinks and jumps converge slowly: the estimate is still
                 * within 10% with the budget given. */
                GI_CHECK_MSG(rel <= 0.1, "%s d=%d: relative error %.3g", gi_genz_name(fam), d,
                             rel);
            }
        }
}

GI_TEST(test_quad_genz_families_genz_malik_d2_to_6)
{
    run_families(GI_QUAD_GM, 2, 6, 1e-3, 2000000);
}

GI_TEST(test_quad_genz_families_boole_d2_to_4)
{
    run_families(GI_QUAD_BOOLE, 2, 4, 1e-3, 2000000);
}

GI_TEST(test_quad_genz_tight_tolerance_d2)
{
    run_families(GI_QUAD_GM, 2, 2, 1e-6, 2000000);
    run_families(GI_QUAD_BOOLE, 2, 2, 1e-6, 2000000);
}

GI_TEST(test_quad_genz_exact_integrals_match_monte_carlo)
{
    /* The closed forms themselves, against plain Monte Carlo (1e6 points,
     * 5 standard errors): a wrong formula fails here, not in the tests
     * above. */
    for (int fam = 0; fam < GI_GENZ_FAMILIES; fam++) {
        gi_genz g;
        gi_genz_pick(&g, fam, 3, 7);
        gi_rng rng;
        gi_rng_init(&rng, 99, (uint64_t)fam, 0);
        double s = 0, s2 = 0, x[3];
        int n = 1000000;
        for (int i = 0; i < n; i++) {
            for (int k = 0; k < 3; k++)
                x[k] = gi_rng_double(&rng);
            double v = gi_genz_eval(&g, x);
            s += v;
            s2 += v * v;
        }
        double mean = s / n, se = sqrt((s2 / n - mean * mean) / n);
        GI_CHECK_MSG(fabs(mean - gi_genz_exact(&g)) <= 5 * se, "%s: MC %.6g +- %.2g vs %.6g",
                     gi_genz_name(fam), mean, se, gi_genz_exact(&g));
    }
}
