/* quadrature: the adaptive cubature renderer as a farm method (thesis
 * "Renderizado adaptativo mediante tecnicas de cuadratura", Crespo 2018).
 *
 * The image is the integral of the path-space integrand (quad_path.h) over
 * [0,1]^N, computed by adaptive cubature over the joint image x path space:
 * regions are bisected where the estimated error is largest anywhere in the
 * image (quad_refine.h), and each region's image-plane interpolant is
 * splatted into the pixels it covers (quad_splat.h). Deterministic: no
 * noise, unless the hybrid Monte Carlo phase is on (quad_hybrid.h).
 *
 * Farm split (quad_coord.c, quad_task.c): the coordinator keeps the global
 * heap of open regions. Round 0 evaluates the initial regions; every later
 * round takes the regions with the largest errors, deals them out to a
 * fixed number of tasks (a set of regions and a budget of bisections each),
 * and a worker refines its set with a local heap, returning the change to
 * the image (its new regions' splats minus the splats of the regions they
 * replace) and the summaries of the regions it leaves open, which go back
 * into the global heap. Rounds go on until every region is below the
 * threshold, the global error estimate meets the tolerance, or the
 * evaluation budget is spent; then (hybrid) a Monte Carlo round over the
 * regions left open. The rounds and their tasks depend only on the job,
 * merges happen in task-id order, and everything a worker computes is a
 * function of the task: the output does not depend on the workers. */
#ifndef GI_QUADRATURE_H
#define GI_QUADRATURE_H

#include <stdint.h>

#include "gi_anim.h"
#include "gi_method.h"
#include "quad_heap.h"
#include "quad_rule.h"

typedef struct gi_quad_params {
    int dims;                     /* N: even, >= 4 */
    gi_quad_rule_kind rule;
    gi_quad_axis_rule axis_rule;
    gi_qheap_kind heap;
    double threshold;             /* per region, relative to the image integral */
    double tolerance;             /* global, relative */
    uint64_t max_evals;           /* evaluation budget */
    int initial[2];               /* initial splits of the image axes (powers of 2) */
    int initial_path;             /* initial splits of each path axis (power of 2) */
    int round_tasks;              /* tasks per round */
    int task_regions;             /* regions per task */
    int task_splits;              /* bisections per task */
    int hybrid;                   /* Monte Carlo phase */
    int mc_spp;                   /* its samples per pixel */
    int max_bounces;              /* scattering events; -1: unlimited */
    int rr_depth;                 /* Russian roulette start (hybrid) */
    gi_anim anim;                 /* quadrature.animation; anim.enabled = 0 without one */
} gi_quad_params;

void gi_quad_params_default(gi_quad_params *p);
/* Validates the "quadrature" block of a job whose image is width x height. */
int gi_quad_params_parse(gi_quad_params *p, const cJSON *params, int width, int height,
                         gi_jv *v);

extern const gi_method gi_method_quadrature;

#endif
