/* gi_task: task queues. */
#include "gi_task.h"

#include <stdlib.h>
#include <string.h>

void gi_task_queue_init(gi_task_queue *q, uint64_t first_id)
{
    memset(q, 0, sizeof *q);
    q->next_id = first_id;
}

void gi_task_free(gi_task *t) { gi_buf_free(&t->payload); }

void gi_task_queue_free(gi_task_queue *q)
{
    for (size_t i = 0; i < q->count; i++)
        gi_task_free(&q->tasks[i]);
    free(q->tasks);
    uint64_t next = q->next_id;
    gi_task_queue_init(q, next);
}

gi_task *gi_task_queue_add(gi_task_queue *q, uint32_t kind, double cost)
{
    if (q->count == q->cap) {
        q->cap = q->cap ? 2 * q->cap : 64;
        q->tasks = gi_xrealloc(q->tasks, q->cap * sizeof *q->tasks);
    }
    gi_task *t = &q->tasks[q->count++];
    memset(t, 0, sizeof *t);
    t->id = q->next_id++;
    t->kind = kind;
    t->cost = cost;
    gi_buf_init(&t->payload);
    return t;
}
