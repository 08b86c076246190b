/* quad_method: the quadrature renderer's entry points (see quadrature.h). */
#include "gi_job.h"
#include "quad_farm.h"

static int quad_parse(gi_job *job, const cJSON *params, gi_jv *v)
{
    gi_quad_params *p = gi_xcalloc(1, sizeof *p);
    job->params = p;
    return gi_quad_params_parse(p, params, job->width, job->height, v);
}

/* An animation's mobile, found in the scene wherever the scene is loaded
 * (coordinator and workers); its keys' warning is the coordinator's. */
static int quad_check_scene(gi_job *job, gi_error *err)
{
    gi_quad_params *p = job->params;
    return gi_anim_check_scene(&p->anim, job, err);
}

static const char *const quad_outputs[] = {"exr", "png", "report", NULL};

const gi_method gi_method_quadrature = {
    .name = "quadrature",
    .summary = "adaptive cubature over image x path space (deterministic; optional hybrid "
               "Monte Carlo)",
    .unit = "evaluations",
    .output_kinds = quad_outputs,
    .default_outputs = quad_outputs,
    .parse = quad_parse,
    .check_scene = quad_check_scene,
    .plan = gi_quad_plan,
    .run = gi_quad_run,
    .check_result = gi_quad_check_result,
    .damage_result = gi_quad_damage_result,
    .merge = gi_quad_merge,
    .merge_decoded = gi_quad_merge_decoded,
    .finish = gi_quad_finish,
    .save = gi_quad_save,
    .load = gi_quad_load,
    .progress = gi_quad_progress,
    .can_finish_again = gi_quad_can_finish_again,
    .release = gi_quad_release,
};
