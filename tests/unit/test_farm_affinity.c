/* Unit tests: task affinity. The rule the farm scheduler applies
 * (gi_affinity_may_take through gi_jobrun_lease_if, owners claimed on lease
 * and on result as gi_farm_sched.c does), with synthetic tasks and hosts;
 * affinity through checkpoints and the TASK message. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_affinity.h"
#include "gi_farm_impl.h"
#include "gi_fs.h"
#include "gi_jobrun.h"
#include "gi_msg.h"
#include "gi_test.h"

#define KEYS 4

/* Plan: one task per key (a batch's frame 0); each merge of a frame < 2
 * adds the same key's next frame (as an animation's update tasks do). */
typedef struct aff_state {
    int merged;
} aff_state;

static int aff_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    job->state = gi_xcalloc(1, sizeof(aff_state));
    for (uint64_t k = 1; k <= KEYS; k++) {
        gi_task *t = gi_task_queue_add(q, 0, 1.0);
        t->affinity = k;
    }
    return 0;
}

static int aff_merge(gi_job *job, const gi_task *t, const gi_buf *r, gi_task_queue *fq,
                     gi_error *err)
{
    aff_state *st = job->state;
    st->merged++;
    if (t->kind < 2) {
        gi_task *n = gi_task_queue_add(fq, t->kind + 1, 1.0);
        n->affinity = t->affinity;
    }
    return 0;
}

static int aff_finish(gi_job *job, gi_task_queue *fq, gi_error *err) { return 0; }

static void aff_release(gi_job *job)
{
    free(job->state);
    job->state = NULL;
}

static int aff_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    gi_buf_put_u32(out, (uint32_t)((const aff_state *)job->state)->merged);
    return 0;
}

static int aff_load(gi_job *job, gi_reader *in, gi_error *err)
{
    aff_state *st = gi_xcalloc(1, sizeof *st);
    job->state = st;
    st->merged = (int)gi_get_u32(in);
    return 0;
}

static const gi_method aff_method = {
    .name = "aff", .plan = aff_plan, .merge = aff_merge, .finish = aff_finish,
    .save = aff_save, .load = aff_load, .release = aff_release,
};

/* A worker host as the coordinator sees it. */
typedef struct host {
    const char *name;
    int present;
} host;

static int present(void *ctx, const void *owner)
{
    (void)ctx;
    return ((const host *)owner)->present;
}

typedef struct taker {
    const gi_affinity *map;
    const host *h;
} taker;

static int may_take(void *ctx, const gi_task *t)
{
    const taker *k = ctx;
    return gi_affinity_may_take(k->map, t->affinity, k->h, present, NULL);
}

/* What gi_farm_schedule does for one free slot of host h. */
static const gi_task *lease(gi_jobrun *jr, gi_affinity *map, host *h, uint64_t *refused)
{
    taker k = {map, h};
    const gi_task *t = gi_jobrun_lease_if(jr, may_take, &k, refused);
    if (t && t->affinity)
        gi_affinity_set(map, t->affinity, h);
    return t;
}

static void complete(gi_jobrun *jr, gi_affinity *map, host *h, const gi_task *t)
{
    uint64_t id = t->id, key = t->affinity;
    uint32_t at = t->attempt;
    gi_buf r;
    gi_buf_init(&r);
    gi_buf_put_u32(&r, 1);
    gi_task_stats s = {0, 1, 0.0};
    gi_affinity_set(map, key, h);
    gi_jobrun_complete(jr, id, at, &r, &s);
    gi_buf_free(&r);
}

GI_TEST(test_farm_affinity_map)
{
    gi_affinity m;
    gi_affinity_init(&m);
    host a = {"a", 1};
    GI_CHECK(gi_affinity_owner(&m, 7) == NULL);
    GI_CHECK(gi_affinity_set(&m, 0, &a) == NULL && gi_affinity_owner(&m, 0) == NULL);
    for (uint64_t k = 1; k <= 1000; k++)
        GI_CHECK(gi_affinity_set(&m, k * 0x100000001ull, k % 2 ? &a : NULL) == NULL);
    for (uint64_t k = 1; k <= 1000; k++)
        GI_CHECK(gi_affinity_owner(&m, k * 0x100000001ull) == (k % 2 ? &a : NULL));
    GI_CHECK(gi_affinity_set(&m, 0x100000001ull, NULL) == &a);
    GI_CHECK(gi_affinity_owner(&m, 0x100000001ull) == NULL);
    gi_affinity_free(&m);
}

GI_TEST(test_farm_affinity_tasks_follow_their_owner)
{
    gi_job job;
    memset(&job, 0, sizeof job);
    job.method = &aff_method;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
    gi_affinity map;
    gi_affinity_init(&map);
    host a = {"a", 1}, b = {"b", 1};
    uint64_t refused;

    /* Frame 0: nobody owns anything; hosts asking in turn share the keys. */
    const gi_task *t[2 * KEYS];
    for (int i = 0; i < KEYS; i++) {
        t[i] = lease(&jr, &map, i % 2 ? &b : &a, &refused);
        GI_REQUIRE(t[i] && t[i]->affinity == (uint64_t)i + 1 && refused == 0);
    }
    GI_CHECK(lease(&jr, &map, &a, &refused) == NULL && refused == 0);
    for (int i = KEYS - 1; i >= 0; i--) /* out of order: merging is by id anyway */
        complete(&jr, &map, i % 2 ? &b : &a, t[i]);
    GI_REQUIRE(jr.task_count == 2 * KEYS);

    /* Frame 1: a asks for everything first but only gets its keys 1 and 3;
     * b's tasks stay pending for b, in order. */
    const gi_task *a1 = lease(&jr, &map, &a, &refused);
    GI_REQUIRE(a1 && a1->affinity == 1 && a1->kind == 1);
    const gi_task *a3 = lease(&jr, &map, &a, &refused);
    GI_REQUIRE(a3 && a3->affinity == 3 && refused == 1);
    GI_CHECK(lease(&jr, &map, &a, &refused) == NULL && refused == 2);
    const gi_task *b2 = lease(&jr, &map, &b, &refused);
    GI_REQUIRE(b2 && b2->affinity == 2);
    const gi_task *b4 = lease(&jr, &map, &b, &refused);
    GI_REQUIRE(b4 && b4->affinity == 4);
    GI_CHECK(lease(&jr, &map, &b, &refused) == NULL && refused == 0);

    /* b's task for key 4 fails (b crashed): while b is present it gets the
     * retry; once b is gone, a takes it and becomes the owner. */
    gi_error crash;
    gi_fail(&crash, GI_ECRASH, "lost");
    gi_jobrun_fail(&jr, b4->id, b4->attempt, &crash);
    GI_CHECK(lease(&jr, &map, &a, &refused) == NULL && refused == 1);
    b.present = 0;
    const gi_task *a4 = lease(&jr, &map, &a, &refused);
    GI_REQUIRE(a4 && a4->affinity == 4 && a4->attempt == 1);
    GI_CHECK(gi_affinity_owner(&map, 4) == &a);
    GI_CHECK(gi_affinity_owner(&map, 2) == &b); /* leased to b, not moved */
    complete(&jr, &map, &a, a1);
    complete(&jr, &map, &a, a3);
    complete(&jr, &map, &a, a4);
    /* b's result for key 2 still arrives (it was slow, not dead). */
    complete(&jr, &map, &b, b2);

    /* Frame 2: b is back. Keys 1, 3, 4 are a's, key 2 is b's. */
    b.present = 1;
    const gi_task *got = lease(&jr, &map, &b, &refused);
    GI_REQUIRE(got && got->affinity == 2 && got->kind == 2);
    GI_CHECK(lease(&jr, &map, &b, &refused) == NULL && refused == 3);
    const gi_task *rest[3];
    for (int i = 0; i < 3; i++) {
        rest[i] = lease(&jr, &map, &a, &refused);
        GI_REQUIRE(rest[i] && rest[i]->affinity != 2);
    }
    /* Handed back unrun (a drains): the requeued task keeps its key and, a
     * being absent, goes to b. */
    gi_jobrun_requeue(&jr, rest[2]->id);
    a.present = 0;
    const gi_task *moved = lease(&jr, &map, &b, &refused);
    GI_REQUIRE(moved && moved->id == rest[2]->id && moved->affinity == rest[2]->affinity);
    GI_CHECK(gi_affinity_owner(&map, moved->affinity) == &b);
    complete(&jr, &map, &b, got);
    complete(&jr, &map, &a, rest[0]);
    complete(&jr, &map, &a, rest[1]);
    complete(&jr, &map, &b, moved);
    GI_CHECK(jr.finished && ((aff_state *)job.state)->merged == 3 * KEYS);
    gi_affinity_free(&map);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

GI_TEST(test_farm_affinity_survives_checkpoint_and_task_message)
{
    gi_job job;
    memset(&job, 0, sizeof job);
    job.method = &aff_method;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(gi_jobrun_start(&jr, &job, &err));
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->affinity == 1);
    gi_buf ck;
    gi_buf_init(&ck);
    GI_REQUIRE_OK(gi_jobrun_checkpoint(&jr, &ck, &err));
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    memset(&job, 0, sizeof job);
    job.method = &aff_method;
    GI_REQUIRE_OK(gi_jobrun_restore(&jr, &job, &ck, &err));
    GI_REQUIRE(jr.task_count == KEYS);
    for (uint64_t i = 0; i < KEYS; i++)
        GI_CHECK(gi_jobrun_task_at(&jr, i)->task.affinity == i + 1);
    gi_buf_free(&ck);

    /* TASK: the key travels; a task without one encodes as it always did. */
    gi_task *task = &gi_jobrun_task_at(&jr, 2)->task;
    gi_buf_put_u32(&task->payload, 0xabcdef);
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_task_encode(&b, 9, task);
    gi_msg_task m;
    GI_REQUIRE_OK(gi_msg_task_decode(&b, &m, &err));
    GI_CHECK(m.job_id == 9 && m.task.id == 2 && m.task.affinity == 3);
    GI_CHECK(m.task.payload.len == 4 && memcmp(m.task.payload.data, task->payload.data, 4) == 0);
    gi_task_free(&m.task);
    size_t with = b.len;
    task->affinity = 0;
    gi_buf_free(&b);
    gi_buf_init(&b);
    gi_msg_task_encode(&b, 9, task);
    GI_CHECK(b.len + 8 == with);
    GI_REQUIRE_OK(gi_msg_task_decode(&b, &m, &err));
    GI_CHECK(m.task.affinity == 0);
    gi_task_free(&m.task);
    gi_buf_put_u32(&b, 1); /* a short trailing field is refused */
    GI_CHECK(gi_msg_task_decode(&b, &m, &err) != 0);
    gi_buf_free(&b);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* The coordinator's owners, saved beside a checkpoint and restored by host
 * name into a fresh coordinator (whose hosts have not reconnected yet). */
GI_TEST(test_farm_affinity_owners_survive_a_restart)
{
    char path[512];
    snprintf(path, sizeof path, "%s/affinity", gi_test_tmpdir());
    gi_farm *f = gi_xcalloc(1, sizeof *f);
    gi_farm_job *j = gi_xcalloc(1, sizeof *j);
    j->id = 5;
    gi_farm_host *a = gi_farm_host_get(f, "render-a"), *b = gi_farm_host_get(f, "render-b");
    for (uint64_t k = 1; k <= 100; k++)
        gi_affinity_set(&j->affinity, k, k % 3 ? a : b);
    gi_affinity_set(&j->affinity, 50, NULL); /* forgotten: not saved */
    gi_farm_affinity_save(j, path);
    gi_affinity_free(&j->affinity);

    gi_farm *g = gi_xcalloc(1, sizeof *g);
    gi_farm_affinity_load(g, j, path);
    GI_REQUIRE(g->host_count == 2);
    for (uint64_t k = 1; k <= 100; k++) {
        const gi_farm_host *h = gi_affinity_owner(&j->affinity, k);
        if (k == 50)
            GI_CHECK(h == NULL);
        else
            GI_CHECK_MSG(h && strcmp(h->name, k % 3 ? "render-a" : "render-b") == 0,
                         "key %llu", (unsigned long long)k);
    }
    /* A file torn in its last entry gives the owners before it. */
    gi_buf whole;
    gi_buf_init(&whole);
    gi_error err;
    GI_REQUIRE_OK(gi_read_file(path, 1 << 20, &whole, &err));
    GI_REQUIRE_OK(gi_write_file_atomic(path, whole.data, whole.len - 5, &err));
    gi_buf_free(&whole);
    gi_farm_affinity_load(g, j, path);
    GI_CHECK_MSG(j->affinity.count == 98, "%zu owners from a torn file", j->affinity.count);
    /* Damaged or foreign files are ignored (a hint, never fatal). */
    FILE *fp = fopen(path, "wb");
    fputs("garbage", fp);
    fclose(fp);
    gi_farm_affinity_load(g, j, path);
    GI_CHECK(gi_affinity_owner(&j->affinity, 1) != NULL);
    gi_affinity_free(&j->affinity);
    gi_farm *farms[2] = {f, g};
    for (int k = 0; k < 2; k++) {
        for (size_t i = 0; i < farms[k]->host_count; i++)
            free(farms[k]->hosts[i]);
        free(farms[k]->hosts);
        free(farms[k]);
    }
    free(j);
}
