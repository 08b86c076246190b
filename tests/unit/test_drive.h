/* Unit tests that run a whole job in this process: the coordinator's run
 * (gi_jobrun) and one worker (gi_worker_ctx) side by side, no pool. */
#ifndef GI_TEST_DRIVE_H
#define GI_TEST_DRIVE_H

#include "gi_jobrun.h"
#include "gi_worker_ctx.h"

/* Leases jr's tasks and runs them on ctx until the job is done or `stop`
 * tasks ran: 0, or -1 with err (a task's error, or the run's when it
 * failed). */
int gi_test_drive(gi_jobrun *jr, gi_worker_ctx *ctx, uint64_t stop, gi_error *err);

#endif
