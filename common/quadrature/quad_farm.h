/* quad_farm: what the coordinator (quad_coord.c) and the workers
 * (quad_task.c) exchange: task payloads and results, explicitly serialized.
 *
 * Refinement task (GI_QUAD_TASK_REFINE): u32 round, f64 threshold (absolute,
 * 0 in round 0), u64 bisection budget, u32 count, then per region u8 new
 * (1: round 0, not yet in the image) and its summary (quad_region.h).
 * Monte Carlo task (GI_QUAD_TASK_MC): u32 count and the summaries.
 *
 * Result: u64 evaluations, u64 of them re-evaluations of the task's
 * regions, u64 bisections, u64 regions closed, u64 Monte Carlo samples, u64
 * non-finite samples zeroed, f64 sum of the closed regions' errors, C f64
 * change of the sum of region estimates, C f64 integral of the Monte Carlo
 * residuals added, the image delta (quad_accum.h),
 * u32 count and the summaries of the regions left open. */
#ifndef GI_QUAD_FARM_H
#define GI_QUAD_FARM_H

#include <float.h>

#include "gi_method.h"
#include "gi_task.h"
#include "quad_region.h"
#include "quadrature.h"

#define GI_QUAD_TASK_REFINE 1u
#define GI_QUAD_TASK_MC 2u
#define GI_QUAD_CHANNELS 3

typedef struct gi_quad_task_in {
    uint32_t kind;
    uint32_t round;
    double threshold;
    uint64_t max_splits;
    uint32_t count;
    uint8_t *is_new;
    gi_quad_summary *regions;
    /* An animation's tasks end with their frame (the workers pose the
     * mobile); a still's carry none. */
    int animated;
    uint32_t frame;
} gi_quad_task_in;

typedef struct gi_quad_result {
    uint64_t evals, reevals, splits, closed, mc_samples, nonfinite;
    double closed_err;
    double dtotal[GI_QUAD_CHANNELS];
    double mc_total[GI_QUAD_CHANNELS];
    gi_reader delta; /* the image delta, not yet checked */
    uint32_t open_count; /* the open regions' summaries follow (decode_open) */
} gi_quad_result;

/* Task payloads. decode reads a frame below `frames` after the regions
 * when frames > 0 (an animation's task), none when 0. */
void gi_quad_task_encode(gi_buf *b, const gi_quad_task_in *t, const gi_quad_rule *rule);
int gi_quad_task_decode(const gi_task *t, const gi_quad_rule *rule, uint32_t frames,
                        gi_quad_task_in *out, gi_error *err);
void gi_quad_task_in_free(gi_quad_task_in *t);

/* The most a value of task `id`'s image delta may be in magnitude. The
 * coordinator's image is the sum of the deltas of every task merged (in
 * f64, never divided), and it is written as floats (EXR FLOAT, the PNG from
 * the same floats): a pixel beyond FLT_MAX would be written as Inf. Task
 * ids are unique within a job, so with FLT_MAX / (2 (i + 1) (i + 2)) for
 * task i the deltas of all tasks, however many rounds plan, add up to at
 * most FLT_MAX / 2 in magnitude (sum over i >= 0 of 1 / ((i + 1) (i + 2))
 * is 1), and the f64 rounding of fewer than 2^51 additions (70 years of
 * tasks at one a microsecond), each at most 2^-53 of a sum below FLT_MAX,
 * adds less than FLT_MAX / 4: no set of
 * results a check accepts can make a pixel non-finite. Early tasks (round
 * 0's, which put the image in) may carry up to 1.7e38; task 10,000 up to
 * 1.7e30, task 1,000,000 1.7e26: far above what a scene's radiance (its
 * emission at most 1e30) puts in a late task's corrections. */
static inline double gi_quad_pixel_delta_max(uint64_t id)
{
    return FLT_MAX / (2.0 * ((double)id + 1.0) * ((double)id + 2.0));
}

/* Results, in two steps, so that a caller puts the open summaries where it
 * likes: the fixed fields and counts (rest at the summaries; the delta is
 * left for gi_quad_accum_check), then count summaries into open and the
 * end checked. */
int gi_quad_result_decode_head(const gi_buf *b, const gi_quad_rule *rule, gi_quad_result *out,
                               gi_reader *rest, gi_error *err);
int gi_quad_result_decode_open(gi_reader *rest, const gi_quad_rule *rule, uint32_t count,
                               gi_quad_summary *open, gi_error *err);
int gi_quad_damage_result(const gi_job *job, const gi_task *task, gi_buf *result,
                          gi_damage how);

/* The coordinator side (quad_coord.c). */
int gi_quad_plan(gi_job *job, gi_task_queue *q, gi_error *err);
int gi_quad_check_result(const gi_job *job, const gi_task *task, const gi_buf *result,
                         gi_buf *decoded, gi_error *err);
int gi_quad_merge(gi_job *job, const gi_task *task, const gi_buf *result, gi_task_queue *fq,
                  gi_error *err);
int gi_quad_merge_decoded(gi_job *job, const gi_task *task, const gi_buf *decoded,
                          gi_task_queue *fq, gi_error *err);
int gi_quad_finish(gi_job *job, gi_task_queue *fq, gi_error *err);
int gi_quad_can_finish_again(const gi_job *job);
void gi_quad_progress(const gi_job *job, gi_job_progress *out);
int gi_quad_save(const gi_job *job, gi_buf *out, gi_error *err);
int gi_quad_load(gi_job *job, gi_reader *in, gi_error *err);
void gi_quad_release(gi_job *job);

/* The worker side of both task kinds. */
int gi_quad_run(gi_worker_ctx *ctx, const gi_task *task, gi_buf *result, gi_error *err);

/* The rule the job's parameters ask for, with RGB channels. */
int gi_quad_job_rule(const gi_quad_params *p, gi_quad_rule *rule, gi_error *err);

#endif
