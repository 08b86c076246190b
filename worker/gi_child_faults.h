/* gi_child_faults: the fault injection hooks of a pool child, for tests
 * only. They are read from the environment once, when the child starts
 * (gi_child_faults_read), so a test sets them on the gi-worker (or
 * `gi render`) it starts and every child of it follows the same ones.
 *
 * Each hook names runs of tasks: "ID[:ATTEMPT][,ID[:ATTEMPT]...]" (ATTEMPT
 * 0 when left out); an entry "*" names every run. A run is named by its task
 * id and attempt, never by which child or host gets it, so a test knows
 * which run is hit however the tasks are spread. */
#ifndef GI_CHILD_FAULTS_H
#define GI_CHILD_FAULTS_H

#include <stddef.h>
#include <stdint.h>

/* GI_FAULT_CRASH_TASK makes a child kill itself with SIGKILL after
 * computing the run, before sending the result. */
#define GI_FAULT_CRASH_ENV "GI_FAULT_CRASH_TASK"
/* GI_FAULT_KILL_HOST_TASK makes the child that gets the run kill its parent
 * (the gi-worker, or `gi render`) with SIGKILL, then itself, before running
 * it: a task that takes its host down. */
#define GI_FAULT_KILL_HOST_ENV "GI_FAULT_KILL_HOST_TASK"
/* GI_FAULT_STOP_HOST_TASK makes it SIGSTOP its parent, then run the task: a
 * host gone silent (its leases expire) until SIGCONT. */
#define GI_FAULT_STOP_HOST_ENV "GI_FAULT_STOP_HOST_TASK"
/* GI_FAULT_HANG_TASK makes the child that gets the run hang (sleep until
 * killed) instead of running it: a task that never ends, for task time
 * limits (task_timeout). */
#define GI_FAULT_HANG_ENV "GI_FAULT_HANG_TASK"
/* GI_FAULT_SLOW_TASK makes the child sleep GI_FAULT_SLOW_S seconds
 * (default 1) before running the task: a task that takes long and ends, so
 * that others wait queued behind it. */
#define GI_FAULT_SLOW_ENV "GI_FAULT_SLOW_TASK"
#define GI_FAULT_SLOW_S_ENV "GI_FAULT_SLOW_S"
/* GI_FAULT_BAD_RESULT_TASK makes the child send the run's result one byte
 * short: it still travels as a well-formed RESULT message, but its payload
 * is cut, which every method's check_result refuses (a tile with a wrong
 * pixel count, a batch's or a row's last entry cut short), as it would a
 * result from a host with bad memory. The coordinator fails that run and
 * retries the task (tests/integration/farm_bad_results.sh). */
#define GI_FAULT_BAD_RESULT_ENV "GI_FAULT_BAD_RESULT_TASK"

typedef struct gi_fault_run {
    uint64_t task;
    uint32_t attempt;
} gi_fault_run;

/* One hook's runs. */
typedef struct gi_fault_spec {
    gi_fault_run *runs;
    size_t count;
    int every; /* "*": every run */
} gi_fault_spec;

typedef struct gi_child_faults {
    gi_fault_spec crash, kill_host, stop_host, hang, slow, bad_result;
    double slow_s;
} gi_child_faults;

/* Reads every hook from the environment (unset: names no run). A spec that
 * does not parse names the runs before the first bad entry, as before. */
void gi_child_faults_read(gi_child_faults *f);
void gi_child_faults_free(gi_child_faults *f);
/* 1 if spec names run `attempt` of task_id. */
int gi_fault_hits(const gi_fault_spec *spec, uint64_t task_id, uint32_t attempt);

#endif
