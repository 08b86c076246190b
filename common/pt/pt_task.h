/* pt_task: the pt method's task payload, what its workers read from a TASK
 * message (and its coordinator again as results arrive): an image tile and
 * the sample indices [s0, s1) of its pixels, as gi_tiles_plan writes them
 * with the sample range as the extra bytes, and an animation's frame after
 * them. Exposed for fuzz_task. */
#ifndef GI_PT_TASK_H
#define GI_PT_TASK_H

#include <stdint.h>

#include "gi_anim.h"
#include "gi_job.h"
#include "gi_task.h"
#include "gi_tiles.h"
#include "pt.h"

#define PT_TASK_TILE 1

/* The job's "pt" block as parsed: job->params of a pt job. */
typedef struct gi_pt_job_params {
    gi_pt_params pt;
    gi_anim anim; /* pt.animation; anim.enabled = 0 without one */
} gi_pt_job_params;

typedef struct gi_pt_task {
    gi_tile tile;
    uint32_t s0, s1;
    uint32_t frame; /* an animation's frame; 0 in a still's (not sent) */
} gi_pt_task;

/* Reads t's payload, the tile within the job's image, s0 < s1 <= spp and,
 * in an animation, its frame; bad bytes: GI_EPROTO naming the task. */
int gi_pt_task_decode(const gi_job *job, const gi_task *t, gi_pt_task *out, gi_error *err);

#endif
