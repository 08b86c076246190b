/* gi_method: the interface every rendering method implements.
 *
 * A method is one module with these entry points and nothing else in the
 * system knows its internals (DESIGN.md). The coordinator side (parse, plan,
 * merge, finish) never calls Embree; the worker side (run) does. merge is
 * called in task-id order; merge and finish may add follow-up tasks (e.g.
 * image tiles after a bake), and finish is called again whenever the tasks
 * it added have all been merged, until it adds none. */
#ifndef GI_METHOD_H
#define GI_METHOD_H

#include <math.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "gi_json.h"
#include "gi_task.h"

typedef struct gi_job gi_job;
typedef struct gi_worker_ctx gi_worker_ctx;

/* Where a job stands, for progress bars and ETAs (gi_jobrun_progress). */
typedef struct gi_job_progress {
    uint32_t frame;  /* the frame being computed, from 0 */
    uint32_t frames; /* how many the job has (a still: 1) */
    /* Work, in the method's unit, that this frame will still add as
     * follow-up tasks (image tiles after a bake), so that its fraction
     * does not jump back when they are planned. */
    double cost_unplanned;
    /* An animation whose frames differ in cost: the method's estimate of
     * frame 0's work and of each later frame's, in the unit as frame 0 runs
     * it (time-alike: a detp frame after 0 only updates). 0: frames count
     * alike. The job's fraction weighs its frames by them, and frame 0's
     * ETA counts the frames after it, until frames are timed. */
    double first_frame_cost, later_frame_cost;
} gi_job_progress;

/* A value a result adds into an f64 sum is at most this in magnitude, so
 * that no number of results (fewer than 2^64) can overflow the sum. Real
 * ones, sums of float radiance over fewer than 2^64 samples, stay below
 * 2^64 x FLT_MAX (6.3e57). A check_result refuses what goes beyond. A sum
 * that ends in a float (an image, published radiance) needs a tighter
 * bound of its method's own (gi_quad_pixel_delta_max, detp's
 * batch_energy_max). */
#define GI_RESULT_SUM_MAX 1e280
static inline int gi_result_summable(double v)
{
    return isfinite(v) && fabs(v) <= GI_RESULT_SUM_MAX;
}

/* How damage_result damages a result (tests only). */
typedef enum gi_damage {
    GI_DAMAGE_NAN = 1,  /* a NaN in place of a floating-point value */
    GI_DAMAGE_HUGE = 2, /* a value that would overflow the sums it goes into */
} gi_damage;

typedef struct gi_method {
    const char *name;
    const char *summary;              /* one line for `gi methods` */
    const char *unit;                 /* what task cost counts: "samples", "photons" */
    const char *const *output_kinds;  /* keys allowed in "outputs", NULL-terminated */
    const char *const *default_outputs; /* kinds written when "outputs" is absent */

    /* Validates the method's parameter block (params may be NULL when the
     * job has none) and stores the parsed parameters in job->params. */
    int (*parse)(gi_job *job, const cJSON *params, gi_jv *v);
    /* Checks that need the loaded scene, after parse. It runs wherever the
     * scene is loaded - on the coordinator and in every worker, before the
     * worker builds its ray tracing scene - so it may also prepare the
     * scene deterministically for the method (detp refines the mesh). */
    int (*check_scene)(gi_job *job, gi_error *err);
    int (*plan)(gi_job *job, gi_task_queue *tasks, gi_error *err);
    int (*run)(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err);
    /* Optional: refuses a result as it arrives (a non-finite value from a
     * worker with bad memory, say), before it waits for its turn to merge:
     * the task then fails and runs again, elsewhere on a farm, instead of
     * the value reaching the outputs or failing the job. decoded (NULL
     * unless the method has merge_decoded): where the check may leave what
     * it decoded, in a form of the method's own that merge_decoded adds
     * without reading the worker's bytes again (checking decodes them
     * anyway, on the coordinator's one loop); left empty, merge reads the
     * result. The form is in-process only: never sent, never checkpointed. */
    int (*check_result)(const gi_job *job, const gi_task *task, const gi_buf *result,
                        gi_buf *decoded, gi_error *err);
    int (*merge)(gi_job *job, const gi_task *task, const gi_buf *result,
                 gi_task_queue *followups, gi_error *err);
    /* Optional: merges what check_result left in decoded, exactly as merge
     * would the result it came from (same outputs, same refusals). */
    int (*merge_decoded)(gi_job *job, const gi_task *task, const gi_buf *decoded,
                         gi_task_queue *followups, gi_error *err);
    int (*finish)(gi_job *job, gi_task_queue *followups, gi_error *err);
    /* Checkpoints: save writes job->state as it stands after the merges so
     * far (everything merge and finish need later, explicitly serialized);
     * load rebuilds job->state from it in a freshly parsed and loaded job,
     * instead of plan. A restarted coordinator resumes from the last
     * checkpoint without redoing merged work (gi_jobrun_checkpoint). */
    int (*save)(const gi_job *job, gi_buf *out, gi_error *err);
    int (*load)(gi_job *job, gi_reader *in, gi_error *err);
    /* Optional: after finish failed writing the outputs (a full disk, a
     * path in the way), 1 if job->state still holds everything finish needs
     * to write the same outputs again, so that a checkpoint taken now
     * resumes into writing them instead of rendering again. NULL: never. */
    int (*can_finish_again)(const gi_job *job);
    /* Optional: fills *out after plan, load and each finish (NULL: a still
     * whose tasks are all planned up front). */
    void (*progress)(const gi_job *job, gi_job_progress *out);
    /* Frees job->params and job->state. */
    void (*release)(gi_job *job);
    /* Optional, for tests only (GI_FAULT_BAD_RESULT_KIND, worker/
     * gi_child_faults.h): damages the first value of a result that run()
     * made (in a worker: job->state is NULL) the way `how` says, as bad
     * memory could, for check_result to refuse. 1 if the result holds no
     * value such damage applies to (it is left as it is): a NaN needs a
     * floating-point value, a huge value one that is summed (a tile's
     * pixels are placed) or bounded by the method (quadrature's image
     * delta, a detp still's batch energies). */
    int (*damage_result)(const gi_job *job, const gi_task *task, gi_buf *result,
                         gi_damage how);
} gi_method;

/* The registry (gi_methods.c). */
const gi_method *gi_method_find(const char *name);
/* NULL-terminated list of all methods. */
const gi_method *const *gi_methods(void);

#endif
