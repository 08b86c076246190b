/* quad_integrate: adaptive cubature of a function on [0,1]^N in one
 * process (the loop of quad_refine.h over a single root region, with no
 * image): what the Genz tests and benchmarks run.
 *
 * Stops when the sum of the leaves' error estimates (eq. 4.4) is at most
 * max(abs_tol, rel_tol ||estimate||_1) - the usual global criterion of
 * adaptive cubature (Berntsen, Espelid, Genz 1991) - or when the next
 * bisection would exceed max_evals. */
#ifndef GI_QUAD_INTEGRATE_H
#define GI_QUAD_INTEGRATE_H

#include "quad_heap.h"
#include "quad_region.h"

typedef struct gi_quad_opts {
    gi_quad_rule_kind rule;
    gi_quad_axis_rule axis_rule;
    gi_qheap_kind heap;
    double rel_tol, abs_tol;
    uint64_t max_evals;
} gi_quad_opts;

typedef struct gi_quad_result {
    double est[GI_QUAD_MAX_CHANNELS];
    double err;       /* sum of the leaves' error estimates */
    uint64_t evals, splits, regions;
    int converged;    /* the tolerance was met */
} gi_quad_result;

int gi_quad_integrate(int dims, int channels, const gi_quad_integrand *fn,
                      const gi_quad_opts *opts, gi_quad_result *out, gi_error *err);

#endif
