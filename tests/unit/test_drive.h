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
/* The same the way gi-farmd and the local pool give results: each checked
 * (gi_jobrun_check_result: a method may keep what it decoded) before it
 * completes, up to `ahead` tasks leased at once and their results given
 * in reverse order, so that results wait for their turn to merge. A
 * refused result fails the drive. */
int gi_test_drive_checked(gi_jobrun *jr, gi_worker_ctx *ctx, unsigned ahead, gi_error *err);

/* Gives leased task t the worker's answer `bad` the way gi-farmd and the
 * local pool do (gi_jobrun_check_result, then gi_jobrun_fail when refused):
 * 0 if it was refused with GI_EPROTO and a message holding `want` and the
 * job did not fail, else -1 with err saying what went wrong. */
int gi_test_refuse(gi_jobrun *jr, const gi_task *t, const gi_buf *bad, const char *want,
                   gi_error *err);

#endif
