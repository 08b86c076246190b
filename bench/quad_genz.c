/* quad_genz: evaluations the adaptive cubature needs on Genz's six test
 * families (bench/genz.h) for relative errors 1e-3 and 1e-6, per family,
 * dimension and rule.
 *
 *   quad_genz [DMAX] [CAP]
 *
 * For each family, d = 2..DMAX (default 6), rule (Boole, Genz-Malik) and
 * tolerance, integrates the family's first function (seed 1; see
 * gi_genz_pick) with the global stopping rule sum of error estimates <=
 * tol |Q| and at most CAP evaluations (default 2e7), and prints the
 * evaluations used, the true relative error reached, and whether the
 * estimate claimed convergence. Deterministic: no timing. */
#include <stdio.h>
#include <stdlib.h>

#include "bench/genz.h"
#include "quadrature/quad_integrate.h"

static void genz_fn(void *user, size_t n, const double *pts, double *out)
{
    const gi_genz *g = user;
    for (size_t i = 0; i < n; i++)
        out[i] = gi_genz_eval(g, pts + i * g->d);
}

int main(int argc, char **argv)
{
    int dmax = argc > 1 ? atoi(argv[1]) : 6;
    double cap = argc > 2 ? atof(argv[2]) : 2e7;
    if (dmax < 2 || dmax > GI_QUAD_BOOLE_MAX_DIMS || !(cap >= 1e3)) {
        fprintf(stderr, "usage: quad_genz [DMAX in 2..%d] [CAP >= 1000]\n",
                GI_QUAD_BOOLE_MAX_DIMS);
        return 2;
    }
    static const char *const rules[] = {"Boole", "Genz-Malik"};
    static const double tols[] = {1e-3, 1e-6};
    printf("| family | d | rule | evaluations for 1e-3 | error reached | evaluations for 1e-6 "
           "| error reached |\n|---|---|---|---|---|---|---|\n");
    for (int fam = 0; fam < GI_GENZ_FAMILIES; fam++)
        for (int d = 2; d <= dmax; d++)
            for (int rule = 0; rule < 2; rule++) {
                gi_genz g;
                gi_genz_pick(&g, fam, d, 1);
                double exact = gi_genz_exact(&g);
                printf("| %s | %d | %s |", gi_genz_name(fam), d, rules[rule]);
                for (int k = 0; k < 2; k++) {
                    gi_quad_integrand fn = {genz_fn, &g};
                    gi_quad_opts o = {rule ? GI_QUAD_GM : GI_QUAD_BOOLE, GI_QUAD_AXIS_MARGINAL,
                                      GI_QHEAP_BUCKETED, tols[k], 0, (uint64_t)cap};
                    gi_quad_result r;
                    gi_error err;
                    if (gi_quad_integrate(d, 1, &fn, &o, &r, &err)) {
                        fprintf(stderr, "quad_genz: %s\n", err.msg);
                        return 1;
                    }
                    double rel = fabs(r.est[0] - exact) / fabs(exact);
                    if (r.converged)
                        printf(" %llu | %.1e%s |", (unsigned long long)r.evals, rel,
                               rel <= tols[k] ? "" : " (above)");
                    else
                        printf(" > %.0e (cap) | %.1e |", cap, rel);
                }
                printf("\n");
                fflush(stdout);
            }
    return 0;
}
