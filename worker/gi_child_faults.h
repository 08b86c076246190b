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

#include "gi_job.h"

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
/* GI_FAULT_BAD_RESULT_TASK makes the child damage the run's result as a
 * host with bad memory could; it still travels as a well-formed RESULT
 * message, and the method's check_result refuses it. The coordinator fails
 * that run and retries the task (tests/integration/farm_bad_results.sh).
 * GI_FAULT_BAD_RESULT_KIND says how (gi_fault_damage):
 *   short (the default): the payload is cut one byte short (a tile with a
 *         wrong pixel count, a batch's or a row's last entry cut short);
 *   nan:  a NaN in place of the result's first floating-point value;
 *   huge: a value that would overflow the sums it goes into (pt's and
 *         quadrature's f64 sums, detp animations' exact sums, radiosity's
 *         squared-difference counts).
 * The method says where its values are (gi_method.h, damage_result); a
 * result without a value that kind of damage applies to is sent as it is
 * (the child says so). Any other kind damages nothing either: the child
 * says it is not one of these. */
#define GI_FAULT_BAD_RESULT_ENV "GI_FAULT_BAD_RESULT_TASK"
#define GI_FAULT_BAD_RESULT_KIND_ENV "GI_FAULT_BAD_RESULT_KIND"

/* GI_FAULT_BAD_RESULT_KIND's values; 0 is short. */
typedef enum gi_fault_damage_kind {
    GI_FAULT_SHORT = 0,
    GI_FAULT_NAN = 1,  /* GI_DAMAGE_NAN */
    GI_FAULT_HUGE = 2, /* GI_DAMAGE_HUGE */
    GI_FAULT_UNKNOWN = 3,
} gi_fault_damage_kind;

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
    gi_fault_damage_kind bad_kind;
    double slow_s;
} gi_child_faults;

/* Reads every hook from the environment (unset: names no run). A spec that
 * does not parse names the runs before the first bad entry, as before. */
void gi_child_faults_read(gi_child_faults *f);
void gi_child_faults_free(gi_child_faults *f);
/* 1 if spec names run `attempt` of task_id. */
int gi_fault_hits(const gi_fault_spec *spec, uint64_t task_id, uint32_t attempt);
/* Damages task's result (run by job's method) as f->bad_kind says, and
 * logs what it did (a warning naming the task). */
void gi_fault_damage(const gi_child_faults *f, const gi_job *job, const gi_task *task,
                     gi_buf *result);

#endif
