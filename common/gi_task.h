/* gi_task: units of work and the queues that hold them.
 *
 * Task ids are dense and assigned in creation order (plan first, then the
 * follow-ups each merge or finish creates). The engine merges results in id
 * order, so a method's merge sees the same sequence whatever the number of
 * workers, the order results arrive in, or the retries after faults: that is
 * what makes output bits independent of how the work was run. */
#ifndef GI_TASK_H
#define GI_TASK_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"

typedef struct gi_task {
    uint64_t id;
    uint32_t kind;    /* method-defined */
    uint32_t attempt; /* 0 on the first run, +1 per retry */
    double cost;      /* work units (progress and rates), e.g. samples */
    /* Scheduling hint, 0 = none. Tasks of one job with the same non-zero key
     * reuse state a worker host keeps on its disk (e.g. a photon batch), so
     * the farm sends them to the host that last returned a result for the
     * key while it is connected (docs/farm.md, "Affinity"). Set by methods
     * after gi_task_queue_add (which leaves it 0); kept through retries,
     * requeues, checkpoints and the TASK message. Never affects results. */
    uint64_t affinity;
    gi_buf payload;   /* method-defined, explicitly serialized */
} gi_task;

typedef struct gi_task_queue {
    gi_task *tasks;
    size_t count, cap;
    uint64_t next_id; /* id the next added task gets */
} gi_task_queue;

void gi_task_queue_init(gi_task_queue *q, uint64_t first_id);
void gi_task_queue_free(gi_task_queue *q);
/* Appends a task with the next id; fill its payload through the pointer
 * (valid until the next add). */
gi_task *gi_task_queue_add(gi_task_queue *q, uint32_t kind, double cost);

void gi_task_free(gi_task *t);

/* Statistics a worker reports with each result. */
typedef struct gi_task_stats {
    uint64_t rays;    /* rays traced */
    uint64_t samples; /* method's unit (path samples, photons, ...) */
    double seconds;   /* wall time of run() */
} gi_task_stats;

#endif
