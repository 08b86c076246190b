/* gi_local: `gi render` - the embedded coordinator. Runs a job on this
 * machine with a fork-based pool, the same plan -> tasks -> workers -> merge
 * path as the farm. */
#ifndef GI_LOCAL_H
#define GI_LOCAL_H

#include "gi_job.h"
#include "gi_jobrun.h"
#include "gi_progress.h"

typedef struct gi_local_opts {
    int workers; /* pool children; <= 0: one per core */
    gi_progress_mode progress;
    /* Checkpoints (gi_local_checkpoint.h): written every checkpoint_s
     * seconds (0: only when interrupted) and removed when the job ends
     * well; resume restores from one instead of starting over. < 0: no
     * checkpoint file at all (not read, written or removed). */
    double checkpoint_s;
    int resume;
    /* Seconds a task may run in a pool child before the child is killed and
     * the run failed (an attempt), for a job that sets no task_timeout of
     * its own; 0: no limit. */
    double task_timeout_s;
} gi_local_opts;

typedef struct gi_local_summary {
    double seconds; /* this run's */
    uint64_t tasks, retries, crashes, timeouts; /* timeouts: runs stopped at their limit */
    gi_task_stats stats; /* the whole job's */
    int workers;
    /* A resumed render: what its checkpoint held (rates count this run's). */
    int resumed;
    double fraction_before;
    gi_task_stats stats_before;
} gi_local_summary;

/* Renders a loaded job (gi_job_load) into job->out_dir. */
int gi_render_local(gi_job *job, const gi_local_opts *opts, gi_local_summary *summary,
                    gi_error *err);

/* Set by a SIGINT/SIGTERM handler to stop the render: the outputs written so
 * far stay (an animation's finished frames), and a checkpoint is written. */
extern volatile int gi_local_interrupted;

#endif
