/* Unit tests: the job state machine (ordered merge, retries, follow-ups) and
 * its progress clock. */
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "gi_crc32c.h"
#include "gi_jobrun.h"
#include "gi_log.h"
#include "gi_rng.h"
#include "gi_test.h"

#define HASH_A "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
#define HASH_B "bbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbb"

#define FAKE_TASKS 40

typedef struct fake_state {
    uint64_t order[256];
    int merged;
    int finish_calls;
    double sum; /* non-associative float sum: order matters */
} fake_state;

static int fake_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    job->state = gi_xcalloc(1, sizeof(fake_state));
    for (int i = 0; i < FAKE_TASKS; i++)
        gi_task_queue_add(q, 1, 1.0);
    return 0;
}

static int fake_merge(gi_job *job, const gi_task *t, const gi_buf *r, gi_task_queue *fq,
                      gi_error *err)
{
    fake_state *st = job->state;
    st->order[st->merged++] = t->id;
    double v;
    memcpy(&v, r->data, sizeof v);
    st->sum += v;
    /* Task 5 spawns two follow-ups (like a refinement). */
    if (t->id == 5) {
        gi_task_queue_add(fq, 2, 1.0);
        gi_task_queue_add(fq, 2, 1.0);
    }
    return 0;
}

static int fake_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    fake_state *st = job->state;
    /* The first finish adds a final pass of one task (like image tiles). */
    if (st->finish_calls++ == 0)
        gi_task_queue_add(fq, 3, 1.0);
    return 0;
}

static void fake_release(gi_job *job)
{
    free(job->state);
    job->state = NULL;
}

static int fake_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    const fake_state *st = job->state;
    gi_buf_put_u32(out, (uint32_t)st->merged);
    for (int i = 0; i < st->merged; i++)
        gi_buf_put_u64(out, st->order[i]);
    gi_buf_put_u32(out, (uint32_t)st->finish_calls);
    gi_buf_put_f64(out, st->sum);
    return 0;
}

static int fake_load(gi_job *job, gi_reader *in, gi_error *err)
{
    fake_state *st = gi_xcalloc(1, sizeof *st);
    job->state = st;
    st->merged = (int)gi_get_u32(in);
    if (st->merged > 256)
        return gi_fail(err, GI_EPROTO, "bad fake state");
    for (int i = 0; i < st->merged; i++)
        st->order[i] = gi_get_u64(in);
    st->finish_calls = (int)gi_get_u32(in);
    st->sum = gi_get_f64(in);
    return 0;
}

static const gi_method fake_method = {
    .name = "fake", .plan = fake_plan, .merge = fake_merge, .finish = fake_finish,
    .save = fake_save, .load = fake_load, .release = fake_release,
};

static double task_value(uint64_t id) { return 1.0 / (double)(id + 3) * 1e-3 + (id % 7) * 1e10; }

/* A fresh job of method m, planned into jr. */
static int start(const gi_method *m, gi_job *job, gi_jobrun *jr, gi_error *err)
{
    memset(job, 0, sizeof *job);
    job->method = m;
    return gi_jobrun_start(jr, job, err);
}

/* Takes one of the n leases held, at random: its task's id and attempt. */
static void take_lease(gi_rng *rng, uint64_t *leased, uint32_t *attempts, int *n, uint64_t *id,
                       uint32_t *at)
{
    int k = (int)gi_rng_below(rng, (uint32_t)*n);
    *id = leased[k];
    *at = attempts[k];
    leased[k] = leased[--*n];
    attempts[k] = attempts[*n];
}

/* The result of task id (attempt at): its value. */
static void complete(gi_jobrun *jr, uint64_t id, uint32_t at)
{
    gi_buf r;
    gi_buf_init(&r);
    double v = task_value(id);
    gi_buf_put(&r, &v, sizeof v);
    gi_task_stats s = {1, 1, 0.0};
    gi_jobrun_complete(jr, id, at, &r, &s);
    gi_buf_free(&r);
}

/* Runs the job completing leased tasks in a shuffled order, with some
 * failures and stale duplicates; returns the merge sum. */
static double run_shuffled(uint64_t seed, fake_state *out)
{
    gi_job job;
    memset(&job, 0, sizeof job);
    job.method = &fake_method;
    gi_jobrun jr;
    gi_error err;
    if (gi_jobrun_start(&jr, &job, &err))
        return -1;
    gi_rng rng;
    gi_rng_init(&rng, seed, 0, 0);
    uint64_t leased[512];
    uint32_t attempts[512];
    int nleased = 0;
    while (!gi_jobrun_done(&jr)) {
        const gi_task *t;
        while (nleased < 8 && (t = gi_jobrun_lease(&jr))) {
            leased[nleased] = t->id;
            attempts[nleased++] = t->attempt;
        }
        if (nleased == 0)
            break;
        uint64_t id;
        uint32_t at;
        take_lease(&rng, leased, attempts, &nleased, &id, &at);
        if (seed != 0 && at == 0 && gi_rng_below(&rng, 5) == 0) {
            gi_error e;
            gi_fail(&e, GI_ECRASH, "simulated crash");
            gi_jobrun_fail(&jr, id, at, &e);
            continue;
        }
        if (seed != 0 && at <= 2 && gi_rng_below(&rng, 5) == 0) {
            gi_error e;
            gi_fail(&e, GI_ECRASH, "simulated lost host");
            gi_jobrun_lost(&jr, id, at, "h", &e);
            /* What the lost run still sends is stale, even once the task
             * is leased again. */
            const gi_task *again = gi_jobrun_lease(&jr);
            if (again) {
                leased[nleased] = again->id;
                attempts[nleased++] = again->attempt;
            }
            complete(&jr, id, at);
            continue;
        }
        complete(&jr, id, at);
        /* A stale duplicate of the same result changes nothing. */
        complete(&jr, id, at);
    }
    fake_state *st = job.state;
    double sum = jr.finished ? st->sum : -1;
    if (out && st)
        *out = *st;
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    return sum;
}

GI_TEST(test_jobrun_merges_in_id_order_whatever_the_completion_order)
{
    fake_state ref, st;
    double a = run_shuffled(0, &ref);
    GI_REQUIRE(a >= 0);
    /* 40 planned + 2 follow-ups + 1 from finish. */
    GI_CHECK(ref.merged == FAKE_TASKS + 3);
    for (int i = 0; i < ref.merged; i++)
        GI_CHECK(ref.order[i] == (uint64_t)i);
    GI_CHECK(ref.finish_calls == 2);
    for (uint64_t seed = 1; seed < 20; seed++) {
        double b = run_shuffled(seed, &st);
        GI_CHECK_MSG(memcmp(&a, &b, sizeof a) == 0, "seed %llu: sum %.17g != %.17g",
                     (unsigned long long)seed, b, a);
        GI_CHECK(st.merged == ref.merged);
    }
}

/* The counts a job's view shows match the tasks' states. */
static int counts_match(const gi_jobrun *jr)
{
    uint64_t pending = 0, held = 0;
    for (uint64_t i = jr->merge_next; i < jr->task_count; i++) {
        pending += gi_jobrun_task_at(jr, i)->state == GI_TASK_PENDING;
        held += gi_jobrun_task_at(jr, i)->state == GI_TASK_DONE;
    }
    return pending == gi_jobrun_pending_count(jr) && held == jr->held;
}

GI_TEST(test_jobrun_counts_pending_and_held_tasks_as_they_change)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    gi_rng rng;
    gi_rng_init(&rng, 7, 0, 0);
    uint64_t leased[16];
    uint32_t attempts[16];
    int nleased = 0, steps = 0;
    gi_error crash;
    gi_fail(&crash, GI_ECRASH, "simulated crash");
    while (!gi_jobrun_done(&jr) && steps++ < 1000) {
        const gi_task *t;
        while (nleased < 12 && (t = gi_jobrun_lease(&jr))) {
            leased[nleased] = t->id;
            attempts[nleased++] = t->attempt;
            GI_REQUIRE(counts_match(&jr));
        }
        if (nleased == 0)
            break;
        uint64_t id;
        uint32_t at;
        take_lease(&rng, leased, attempts, &nleased, &id, &at);
        uint32_t what = gi_rng_below(&rng, 6);
        if (what == 0 && at == 0) {
            gi_jobrun_fail(&jr, id, at, &crash);
        } else if (what == 1) {
            gi_jobrun_requeue(&jr, id);
        } else {
            complete(&jr, id, at);
        }
        GI_REQUIRE(counts_match(&jr));
    }
    GI_CHECK(jr.finished && jr.held == 0 && gi_jobrun_pending_count(&jr) == 0);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

GI_TEST(test_jobrun_fails_after_max_attempts_and_on_bad_input)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    gi_error crash;
    gi_fail(&crash, GI_ECRASH, "boom");
    for (uint32_t attempt = 0; attempt < jr.max_attempts; attempt++) {
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t && t->id == 0 && t->attempt == attempt);
        gi_jobrun_fail(&jr, 0, attempt, &crash);
    }
    GI_CHECK(jr.failed);
    GI_CHECK_MSG(strstr(jr.error.msg, "task 0 failed 4 times; last error: boom") != NULL, "%s",
                 jr.error.msg);
    gi_jobrun_free(&jr);
    gi_job_free(&job);

    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    const gi_task *t = gi_jobrun_lease(&jr);
    gi_error bad;
    gi_fail(&bad, GI_EINVAL, "mesh.obj: garbage");
    gi_jobrun_fail(&jr, t->id, t->attempt, &bad);
    GI_CHECK(jr.failed && jr.error.code == GI_EINVAL);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* Completes leased tasks in id order until `stop_after` results were
 * given (or the job is done). */
static void drive(gi_jobrun *jr, int stop_after)
{
    int given = 0;
    const gi_task *t;
    while (!gi_jobrun_done(jr) && given < stop_after && (t = gi_jobrun_lease(jr))) {
        gi_buf r;
        gi_buf_init(&r);
        double v = task_value(t->id);
        gi_buf_put(&r, &v, sizeof v);
        gi_task_stats s = {1, 1, 0.0};
        gi_jobrun_complete(jr, t->id, t->attempt, &r, &s);
        gi_buf_free(&r);
        given++;
    }
}

/* Gives the run `results` results (drive), checkpoints it into ck
 * (initialised here), and frees the run and its job. */
static int checkpoint_then_free(gi_jobrun *jr, gi_job *job, int results, gi_buf *ck,
                                gi_error *err)
{
    drive(jr, results);
    gi_buf_init(ck);
    int rc = gi_jobrun_checkpoint(jr, ck, err);
    gi_jobrun_free(jr);
    gi_job_free(job);
    return rc;
}

/* A host lost with its task (gi_jobrun_lost) is not the task's failure:
 * losses are not retries and do not use up max_attempts; each advances the
 * attempt number, so the lost run's late result is refused and the task is
 * merged once, from the run that was leased. */
GI_TEST(test_jobrun_losses_are_not_attempts)
{
    fake_state ref;
    double want = run_shuffled(0, &ref);
    GI_REQUIRE(want >= 0);
    gi_job job;
    gi_jobrun jr;
    gi_error err, crash, lost;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    gi_fail(&crash, GI_ECRASH, "boom");
    gi_fail(&lost, GI_ECRASH, "worker h1 was lost");
    GI_REQUIRE(jr.max_attempts == 4 && jr.max_losses == 8);
    /* Task 0: lost 6 times (more than max_attempts), failed 3 times, in
     * turns; it is leased again first each time. */
    uint32_t at = 0;
    for (int k = 0; k < 9; k++) {
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t && t->id == 0 && t->attempt == at);
        if (k % 3 == 2)
            GI_CHECK(gi_jobrun_fail(&jr, 0, at, &crash) == 0);
        else
            GI_CHECK(gi_jobrun_lost(&jr, 0, at, k % 2 ? "h2" : "h1", &lost) == 0);
        at++;
        GI_REQUIRE(!jr.failed);
        /* The ended run's result is stale now, and so is a second report. */
        complete(&jr, 0, at - 1);
        GI_CHECK(gi_jobrun_lost(&jr, 0, at - 1, "h1", &lost) == 0);
        GI_CHECK(gi_jobrun_task_at(&jr, 0)->state == GI_TASK_PENDING);
    }
    const gi_jobrun_task *jt = gi_jobrun_task_at(&jr, 0);
    GI_CHECK(jt->failures == 3 && jt->losses == 6 && jr.retries == 3 && jr.losses == 6);
    GI_CHECK_MSG(jt->lost_on && strcmp(jt->lost_on, "h1, h2") == 0, "%s",
                 jt->lost_on ? jt->lost_on : "(none)");
    GI_CHECK(jr.merge_next == 0 && jr.held == 0 && jr.leased == 0);
    /* Leased again and lost, then its stale result arrives while the next
     * run holds it: refused; the run leased gives the one merged. */
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 0 && t->attempt == at);
    GI_CHECK(gi_jobrun_lost(&jr, 0, at, "h3", &lost) == 0);
    t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 0 && t->attempt == at + 1);
    complete(&jr, 0, at);
    GI_CHECK(jr.merge_next == 0 && gi_jobrun_task_at(&jr, 0)->state == GI_TASK_LEASED);
    complete(&jr, 0, at + 1);
    GI_CHECK(jr.merge_next == 1);
    drive(&jr, 1000);
    GI_REQUIRE(jr.finished);
    fake_state *st = job.state;
    GI_CHECK(memcmp(&st->sum, &want, sizeof want) == 0 && st->merged == ref.merged);
    for (int i = 0; i < st->merged; i++)
        GI_CHECK(st->order[i] == (uint64_t)i);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* A method whose check keeps what it decoded (gi_method.merge_decoded): the
 * value and a tag saying it came from the check; NaN is refused. */
static int decoded_merges, raw_merges;

static int dec_check(const gi_job *job, const gi_task *t, const gi_buf *r, gi_buf *decoded,
                     gi_error *err)
{
    double v;
    if (r->len != sizeof v)
        return gi_fail(err, GI_EPROTO, "%zu bytes", r->len);
    memcpy(&v, r->data, sizeof v);
    if (isnan(v))
        return gi_fail(err, GI_EPROTO, "not a number");
    gi_buf_put_u32(decoded, 0xDEC0DEDu);
    gi_buf_put_f64(decoded, v);
    return 0;
}

static int dec_merge(gi_job *job, const gi_task *t, const gi_buf *r, gi_task_queue *fq,
                     gi_error *err)
{
    raw_merges++;
    return fake_merge(job, t, r, fq, err);
}

static int dec_merge_decoded(gi_job *job, const gi_task *t, const gi_buf *d, gi_task_queue *fq,
                             gi_error *err)
{
    if (d->len != 12 || gi_le_get_u32(d->data) != 0xDEC0DEDu)
        return gi_fail(err, GI_EINTERNAL, "task %llu: not a decoded form",
                       (unsigned long long)t->id);
    decoded_merges++;
    gi_buf v;
    gi_buf_init(&v);
    gi_buf_put(&v, d->data + 4, 8);
    int rc = fake_merge(job, t, &v, fq, err);
    gi_buf_free(&v);
    return rc;
}

/* The value of task id as a worker's result, checked by jr for run `at`. */
static int check_value(gi_jobrun *jr, uint64_t id, uint32_t at, double v, gi_error *err)
{
    gi_buf r;
    gi_buf_init(&r);
    gi_buf_put(&r, &v, sizeof v);
    int rc = gi_jobrun_check_result(jr, id, at, &r, err);
    gi_buf_free(&r);
    return rc;
}

/* What a check decoded merges instead of the result, once, from the run it
 * was checked for: a run that ends otherwise (failed, lost, requeued), a
 * refusal, or a check of another run leaves nothing behind, and that run's
 * result (checked or not) merges as if there had been no check before. The
 * merged sum is bit-identical to the plain method's. */
GI_TEST(test_jobrun_merges_what_the_check_decoded)
{
    fake_state ref;
    double want = run_shuffled(0, &ref);
    gi_method m = fake_method;
    m.check_result = dec_check;
    m.merge = dec_merge;
    m.merge_decoded = dec_merge_decoded;
    decoded_merges = raw_merges = 0;
    gi_job job;
    gi_jobrun jr;
    gi_error err, crash;
    gi_fail(&crash, GI_ECRASH, "boom");
    GI_REQUIRE_OK(start(&m, &job, &jr, &err));
    const gi_task *t0 = gi_jobrun_lease(&jr), *t1 = gi_jobrun_lease(&jr);
    GI_REQUIRE(t0 && t1 && t0->id == 0 && t1->id == 1);
    /* Task 1 arrives first: checked, held in its decoded form. */
    GI_CHECK_OK(check_value(&jr, 1, 0, task_value(1), &err));
    const gi_jobrun_task *jt1 = gi_jobrun_task_at(&jr, 1);
    GI_CHECK(jt1->decoded && jt1->result.len == 12);
    complete(&jr, 1, 0);
    GI_CHECK(jr.held == 1 && jr.held_results_bytes == 12 && decoded_merges == 0);
    /* Task 0: a refusal keeps nothing; a check of a run not leased is not
     * made; a good check, then the run fails: dropped. */
    GI_CHECK(check_value(&jr, 0, 0, NAN, &err) == -1 && err.code == GI_EPROTO);
    GI_CHECK_MSG(strcmp(err.msg, "task 0's result: not a number") == 0, "%s", err.msg);
    GI_CHECK(!gi_jobrun_task_at(&jr, 0)->decoded && gi_jobrun_task_at(&jr, 0)->result.len == 0);
    GI_CHECK_OK(check_value(&jr, 0, 7, NAN, &err));
    GI_CHECK(!gi_jobrun_task_at(&jr, 0)->decoded);
    GI_CHECK_OK(check_value(&jr, 0, 0, 1e300, &err));
    GI_CHECK(gi_jobrun_task_at(&jr, 0)->decoded);
    GI_CHECK(gi_jobrun_fail(&jr, 0, 0, &crash) == 0);
    GI_CHECK(!gi_jobrun_task_at(&jr, 0)->decoded && gi_jobrun_task_at(&jr, 0)->result.len == 0);
    /* Leased again: checked, then requeued, then lost: each drops it. */
    GI_REQUIRE(gi_jobrun_lease(&jr)->attempt == 1);
    GI_CHECK_OK(check_value(&jr, 0, 1, 1e300, &err));
    gi_jobrun_requeue(&jr, 0);
    GI_CHECK(!gi_jobrun_task_at(&jr, 0)->decoded);
    GI_REQUIRE(gi_jobrun_lease(&jr)->attempt == 1);
    GI_CHECK_OK(check_value(&jr, 0, 1, 1e300, &err));
    GI_CHECK(gi_jobrun_lost(&jr, 0, 1, "h1", &crash) == 0);
    GI_CHECK(!gi_jobrun_task_at(&jr, 0)->decoded);
    /* The run leased now gives its result unchecked: the plain merge, then
     * task 1's decoded form. */
    GI_REQUIRE(gi_jobrun_lease(&jr)->attempt == 2);
    complete(&jr, 0, 2);
    GI_CHECK(jr.merge_next == 2 && raw_merges == 1 && decoded_merges == 1);
    GI_CHECK(jr.held == 0 && jr.held_results_bytes == 0);
    /* The rest, each checked first. */
    const gi_task *t;
    while (!gi_jobrun_done(&jr) && (t = gi_jobrun_lease(&jr))) {
        uint64_t id = t->id;
        uint32_t at = t->attempt;
        GI_CHECK_OK(check_value(&jr, id, at, task_value(id), &err));
        complete(&jr, id, at);
    }
    GI_CHECK_MSG(jr.finished, "%s", jr.error.msg);
    GI_REQUIRE(jr.finished);
    fake_state *st = job.state;
    GI_CHECK(memcmp(&st->sum, &want, sizeof want) == 0 && st->merged == ref.merged);
    GI_CHECK(raw_merges == 1 && decoded_merges == ref.merged - 1);
    GI_CHECK(jr.merged_bytes == (uint64_t)ref.merged * sizeof(double));
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* A task lost with its host max_losses times fails its job, naming it and
 * the hosts: it may be what takes them down. Losses of other tasks, and
 * its failures, do not add up to it. */
GI_TEST(test_jobrun_fails_a_task_lost_too_often_naming_its_hosts)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err, lost;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    jr.max_losses = 3;
    gi_fail(&lost, GI_ECRASH, "worker b (10.0.0.2:5000) was lost with 1 task: connection closed");
    /* Task 1 lost twice, task 0 once: nothing fails. */
    const gi_task *t0 = gi_jobrun_lease(&jr), *t1 = gi_jobrun_lease(&jr);
    GI_REQUIRE(t0 && t1 && t0->id == 0 && t1->id == 1);
    gi_jobrun_lost(&jr, 1, 0, "a", &lost);
    gi_jobrun_lost(&jr, 0, 0, "a", &lost);
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 0 && t->attempt == 1);
    t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 1 && t->attempt == 1);
    gi_jobrun_lost(&jr, 1, 1, "b", &lost);
    GI_CHECK(!jr.failed && jr.losses == 3);
    t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 1 && t->attempt == 2);
    GI_CHECK(gi_jobrun_lost(&jr, 1, 2, "a", &lost) == -1);
    GI_CHECK(jr.failed && jr.error.code == GI_ECRASH);
    GI_CHECK_MSG(strcmp(jr.error.msg, "task 1 was lost with its host 3 times (hosts a, b): it may "
                        "be taking its host down; last: worker b (10.0.0.2:5000) was lost with 1 "
                        "task: connection closed") == 0, "%s", jr.error.msg);
    GI_CHECK(gi_jobrun_lease(&jr) == NULL);
    gi_jobrun_free(&jr);
    gi_job_free(&job);

    /* A host list too long for the message is cut short. */
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    jr.max_losses = 100;
    char name[64];
    for (uint32_t k = 0; k < 40; k++) {
        t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t && t->id == 0 && t->attempt == k);
        snprintf(name, sizeof name, "a-rather-long-host-name-%02u", k);
        gi_jobrun_lost(&jr, 0, k, name, &lost);
    }
    const char *on = gi_jobrun_task_at(&jr, 0)->lost_on;
    GI_REQUIRE(on);
    GI_CHECK_MSG(strlen(on) < 260 && strncmp(on, "a-rather-long-host-name-00, ", 28) == 0 &&
                 strcmp(on + strlen(on) - 5, ", ...") == 0, "%s", on);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* A coordinator's restart: jr checkpointed, thrown away with its job, and
 * restored into a fresh job of method m. */
static int reload(gi_jobrun *jr, gi_job *job, const gi_method *m, gi_error *err)
{
    gi_buf ck;
    gi_buf_init(&ck);
    int rc = gi_jobrun_checkpoint(jr, &ck, err);
    gi_jobrun_free(jr);
    gi_job_free(job);
    memset(job, 0, sizeof *job);
    job->method = m;
    if (rc == 0)
        rc = gi_jobrun_restore(jr, job, &ck, err);
    gi_buf_free(&ck);
    return rc;
}

GI_TEST(test_jobrun_checkpoint_restore_resumes_without_redoing_work)
{
    fake_state ref;
    double a = run_shuffled(0, &ref);
    GI_REQUIRE(a >= 0);
    /* Stop at several points (before, at and after the follow-ups), save,
     * throw everything away, restore into a new job, and finish. */
    int stops[] = {0, 3, 6, 20, 42, 43};
    for (size_t k = 0; k < sizeof stops / sizeof stops[0]; k++) {
        gi_job job;
        gi_jobrun jr;
        gi_error err;
        GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
        drive(&jr, stops[k]);
        /* One task leased but not answered: it must run again after restore. */
        const gi_task *lost = gi_jobrun_lease(&jr);
        uint64_t merged_before = jr.merge_next;
        gi_progress_at before, after;
        gi_jobrun_progress(&jr, 0.0, &before);
        (void)lost;
        GI_REQUIRE_OK(reload(&jr, &job, &fake_method, &err));
        GI_CHECK(jr.merge_next == merged_before);
        /* It says as much done as before it stopped, not 0%. */
        gi_jobrun_progress(&jr, 0.0, &after);
        GI_CHECK_MSG(fabs(after.fraction - before.fraction) < 1e-12, "stop %d: %.6f then %.6f",
                     stops[k], before.fraction, after.fraction);
        drive(&jr, 1000);
        GI_CHECK_MSG(jr.finished, "stop %d: not finished", stops[k]);
        fake_state *st = job.state;
        GI_CHECK_MSG(memcmp(&st->sum, &a, sizeof a) == 0, "stop %d: sum differs", stops[k]);
        GI_CHECK(st->merged == ref.merged);
        for (int i = 0; i < st->merged; i++)
            GI_CHECK(st->order[i] == (uint64_t)i);
        gi_jobrun_free(&jr);
        gi_job_free(&job);
    }
    /* A damaged checkpoint is refused. */
    gi_job job;
    memset(&job, 0, sizeof job);
    job.method = &fake_method;
    gi_jobrun jr;
    gi_error err;
    gi_buf bad;
    gi_buf_init(&bad);
    gi_buf_put_u32(&bad, 12345);
    GI_CHECK(gi_jobrun_restore(&jr, &job, &bad, &err) == -1);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_buf_free(&bad);
    /* So is one whose bytes changed anywhere, though it still parses: the
     * method's sums would resume wrong. */
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    gi_buf ck;
    GI_REQUIRE_OK(checkpoint_then_free(&jr, &job, 20, &ck, &err));
    for (size_t at = 8; at < ck.len; at += ck.len / 7) {
        memset(&job, 0, sizeof job);
        job.method = &fake_method;
        ck.data[at] ^= 0x10;
        GI_CHECK_MSG(gi_jobrun_restore(&jr, &job, &ck, &err) == -1 && strstr(err.msg, "checksum"),
                     "a flipped bit at byte %zu of %zu: %s", at, ck.len, err.msg);
        ck.data[at] ^= 0x10;
        gi_jobrun_free(&jr);
        gi_job_free(&job);
    }
    memset(&job, 0, sizeof job);
    job.method = &fake_method;
    GI_CHECK_OK(gi_jobrun_restore(&jr, &job, &ck, &err));
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_buf_free(&ck);
}

/* A checkpoint as versions 4 and 5 wrote it (5: with the job's identity),
 * kept here as it was: a task's attempt was its failures, and losses were
 * not kept. */
static void old_checkpoint(const gi_jobrun *jr, uint32_t version, gi_buf *out)
{
    gi_buf_init(out);
    gi_buf_put_u32(out, 0x4B434947u);
    gi_buf_put_u32(out, version);
    gi_buf_put_str(out, jr->job->method->name);
    if (version >= 5) {
        char id[GI_HASH_HEX];
        gi_jobrun_identity(jr->job, id);
        gi_buf_put_str(out, id);
    }
    gi_buf_put_u64(out, jr->task_count);
    gi_buf_put_u64(out, jr->merge_next);
    gi_buf_put_u64(out, jr->retries);
    gi_buf_put_u64(out, jr->stats.rays);
    gi_buf_put_u64(out, jr->stats.samples);
    gi_buf_put_f64(out, jr->stats.seconds);
    gi_buf_put_f64(out, jr->cost_total);
    gi_buf_put_f64(out, jr->clock.frame_base);
    for (uint64_t i = jr->merge_next; i < jr->task_count; i++) {
        const gi_task *t = &gi_jobrun_task_at(jr, i)->task;
        gi_buf_put_u32(out, t->kind);
        gi_buf_put_u32(out, t->attempt);
        gi_buf_put_f64(out, t->cost);
        gi_buf_put_u64(out, t->affinity);
        gi_buf_put_blob(out, t->payload.data, t->payload.len);
    }
    gi_buf state;
    gi_buf_init(&state);
    gi_error err;
    fake_save(jr->job, &state, &err);
    gi_buf_put_blob(out, state.data, state.len);
    gi_buf_free(&state);
    gi_buf_put_u32(out, gi_crc32c(0, out->data, out->len));
}

/* A task's failures, losses and the hosts of those survive a restart
 * (version 6): its next loss still counts towards the same bound. A
 * version 5 checkpoint's attempt is its failures, with no losses. */
GI_TEST(test_jobrun_checkpoint_keeps_failures_and_losses)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err, crash, lost;
    gi_fail(&crash, GI_ECRASH, "boom");
    gi_fail(&lost, GI_ECRASH, "lost");
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    drive(&jr, 5);
    const gi_task *t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 5);
    gi_jobrun_fail(&jr, 5, 0, &crash);
    GI_REQUIRE(gi_jobrun_lease(&jr) == t);
    gi_jobrun_lost(&jr, 5, 1, "h1", &lost);
    GI_REQUIRE(gi_jobrun_lease(&jr) == t);
    gi_jobrun_lost(&jr, 5, 2, "h2", &lost);
    GI_REQUIRE(gi_jobrun_lease(&jr) == t && t->attempt == 3); /* leased when checkpointed */
    gi_buf v5;
    old_checkpoint(&jr, 5, &v5);
    GI_REQUIRE_OK(reload(&jr, &job, &fake_method, &err));
    const gi_jobrun_task *jt = gi_jobrun_task_at(&jr, 5);
    GI_REQUIRE(jt && jt->state == GI_TASK_PENDING);
    GI_CHECK(jt->task.attempt == 3 && jt->failures == 1 && jt->losses == 2);
    GI_CHECK(jt->lost_on && strcmp(jt->lost_on, "h1, h2") == 0);
    GI_CHECK(jr.retries == 1 && jr.losses == 2 && jr.merge_next == 5);
    jr.max_losses = 3;
    t = gi_jobrun_lease(&jr);
    GI_REQUIRE(t && t->id == 5 && t->attempt == 3);
    GI_CHECK(gi_jobrun_lost(&jr, 5, 3, "h3", &lost) == -1);
    GI_CHECK_MSG(strstr(jr.error.msg, "task 5 was lost with its host 3 times (hosts h1, h2, h3)"),
                 "%s", jr.error.msg);
    gi_jobrun_free(&jr);
    gi_job_free(&job);

    memset(&job, 0, sizeof job);
    job.method = &fake_method;
    GI_REQUIRE_OK(gi_jobrun_restore(&jr, &job, &v5, &err));
    jt = gi_jobrun_task_at(&jr, 5);
    GI_REQUIRE(jt);
    GI_CHECK(jt->task.attempt == 3 && jt->failures == 3 && jt->losses == 0 && !jt->lost_on);
    GI_CHECK(jr.retries == 1 && jr.losses == 0);
    drive(&jr, 1000);
    GI_CHECK(jr.finished);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_buf_free(&v5);
}

/* A checkpoint carries its job's identity (version 5): a job of other text
 * or other files does not resume it (a farm that lost its journal gave a
 * new job an old job's id, and its checkpoint); version 4, without the
 * identity, still restores. */
GI_TEST(test_jobrun_checkpoint_of_another_job_is_refused)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    job.text = gi_xstrdup("{\"seed\": 1}");
    gi_manifest_put(&job.manifest, "scene.json", HASH_A, 10);
    gi_buf ck;
    GI_REQUIRE_OK(checkpoint_then_free(&jr, &job, 20, &ck, &err));
    static const struct {
        const char *text, *hash;
        int ok;
    } cases[] = {{"{\"seed\": 1}", HASH_A, 1}, {"{\"seed\": 2}", HASH_A, 0},
                 {"{\"seed\": 1}", HASH_B, 0}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        memset(&job, 0, sizeof job);
        job.method = &fake_method;
        job.text = gi_xstrdup(cases[c].text);
        gi_manifest_put(&job.manifest, "scene.json", cases[c].hash, 10);
        int rc = gi_jobrun_restore(&jr, &job, &ck, &err);
        GI_CHECK_MSG(cases[c].ok ? rc == 0 : rc == -1 && strstr(err.msg, "another job"),
                     "case %zu: rc %d (%s)", c, rc, rc ? err.msg : "");
        if (rc == 0)
            GI_CHECK(jr.merge_next > 0);
        gi_jobrun_free(&jr);
        gi_job_free(&job);
    }
    gi_buf_free(&ck);
    /* The same as version 4, without the identity. */
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    job.text = gi_xstrdup("{\"seed\": 1}");
    drive(&jr, 20);
    old_checkpoint(&jr, 4, &ck);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    memset(&job, 0, sizeof job);
    job.method = &fake_method;
    job.text = gi_xstrdup("{\"seed\": 2}");
    GI_CHECK_OK(gi_jobrun_restore(&jr, &job, &ck, &err));
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    gi_buf_free(&ck);
}

/* The fake's follow-ups, told to the progress clock before they are planned:
 * task 5's two, then finish's one. */
static void fake_progress(const gi_job *job, gi_job_progress *out)
{
    const fake_state *st = job->state;
    int before_5 = st->merged <= 5;
    out->cost_unplanned = (before_5 ? 2.0 : 0.0) + (st->finish_calls == 0 ? 1.0 : 0.0);
}

GI_TEST(test_jobrun_progress_counts_follow_ups_before_they_are_planned)
{
    gi_method m = fake_method;
    m.progress = fake_progress;
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&m, &job, &jr, &err));
    gi_progress_at at;
    gi_jobrun_progress(&jr, gi_now(), &at);
    GI_CHECK(at.fraction == 0 && at.total == FAKE_TASKS + 3 && at.frames == 1);
    double last = 0;
    int steps = 0;
    while (!gi_jobrun_done(&jr)) {
        drive(&jr, 1);
        gi_jobrun_progress(&jr, gi_now(), &at);
        GI_CHECK_MSG(at.fraction >= last, "step %d: %.6f after %.6f", steps, at.fraction, last);
        GI_CHECK_MSG(fabs(at.fraction - (steps + 1.0) / (FAKE_TASKS + 3)) < 1e-12,
                     "step %d: %.6f", steps, at.fraction);
        last = at.fraction;
        steps++;
    }
    GI_CHECK(jr.finished && steps == FAKE_TASKS + 3 && at.fraction == 1 && at.eta_s == 0);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* A job that waited 100 s for a worker before its first task went out,
 * then did 10 of its 100 units in 10 s: 90 s left, not the 990 s that the
 * rate since the job started would say; a frame's wait is not counted
 * either, and once work is under way later leases do not move the clock. */
GI_TEST(test_progress_clock_rate_counts_from_the_first_task_out)
{
    gi_progress_clock c;
    memset(&c, 0, sizeof c);
    gi_progress_at at;
    gi_job_progress still = {.frames = 1};
    gi_progress_clock_note(&c, &still, 100, 0, 1000.0);
    gi_progress_clock_read(&c, 100, 0, 1100.0, &at);
    GI_CHECK(at.eta_s < 0); /* no rate yet */
    gi_progress_clock_working(&c, 0, 1100.0);
    gi_progress_clock_working(&c, 5, 1105.0); /* work under way: no change */
    gi_progress_clock_read(&c, 100, 10, 1110.0, &at);
    GI_CHECK_MSG(fabs(at.eta_s - 90.0) < 1e-9, "first ETA %.3f s after a 100 s wait", at.eta_s);
    /* Frame 1 of 2 waits 50 s for a worker too; its 100 units at 10/s. */
    gi_progress_clock_note(&c, &(gi_job_progress){.frames = 2}, 100, 0, 2000.0);
    gi_progress_clock_working(&c, 0, 2000.0);
    gi_progress_clock_note(&c, &(gi_job_progress){.frame = 1, .frames = 2}, 100, 100, 2010.0);
    gi_progress_clock_working(&c, 100, 2060.0);
    gi_progress_clock_read(&c, 200, 120, 2062.0, &at);
    GI_CHECK_MSG(fabs(at.eta_s - 8.0) < 1e-9, "frame 1's ETA %.3f s", at.eta_s);
}

/* The same through a run: a job left waiting (its clock set back as if it
 * had been planned 1000 s ago) whose first task then runs at once has a
 * first ETA of the order of that task's time, not of the wait. */
GI_TEST(test_jobrun_eta_leaves_out_the_wait_for_workers)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    jr.clock.t_frame -= 1000.0;
    drive(&jr, 4);
    gi_progress_at at;
    gi_jobrun_progress(&jr, gi_now(), &at);
    GI_CHECK_MSG(at.eta_s >= 0 && at.eta_s < 100.0, "first ETA %.1f s after a 1000 s wait",
                 at.eta_s);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* An animation as the clock sees it (times in seconds): frame 0 bakes for
 * 8 s then renders tiles for 2 s; frames 1.. take 1 s each, half update,
 * half tiles; 100 units of work each way. */
GI_TEST(test_progress_clock_times_an_animation_by_its_frames)
{
    gi_progress_clock c;
    memset(&c, 0, sizeof c);
    gi_progress_at at;
    gi_job_progress bake0 = {.frames = 4, .cost_unplanned = 100}, tiles0 = {.frames = 4};
    gi_progress_clock_note(&c, &bake0, 0, 0, 100.0);
    gi_progress_clock_read(&c, 100, 50, 104.0, &at);
    GI_CHECK(fabs(at.fraction - 0.25 / 4) < 1e-12);
    GI_CHECK(at.eta_s < 0); /* frame 0 says nothing of the frames after it */
    gi_progress_clock_note(&c, &tiles0, 100, 100, 108.0);
    gi_progress_clock_read(&c, 200, 150, 109.0, &at);
    GI_CHECK(fabs(at.fraction - 0.75 / 4) < 1e-12 && at.eta_s < 0 && at.frame == 0);

    gi_job_progress bake1 = {.frame = 1, .frames = 4, .cost_unplanned = 100},
                    tiles1 = {.frame = 1, .frames = 4},
                    bake2 = {.frame = 2, .frames = 4, .cost_unplanned = 100};
    gi_progress_clock_note(&c, &bake1, 200, 200, 110.0);
    gi_progress_clock_read(&c, 300, 250, 110.25, &at);
    /* Half of frame 1's bake at 200 units/s: 150 units left in it, and two
     * frames after it, projected at this frame's 1 s. */
    GI_CHECK(fabs(at.fraction - 1.25 / 4) < 1e-12 && at.frame == 1 && at.frames == 4);
    GI_CHECK_MSG(fabs(at.eta_s - (0.75 + 2 * 1.0)) < 1e-9, "eta %.9f", at.eta_s);
    gi_progress_clock_note(&c, &tiles1, 300, 300, 110.5);
    gi_progress_clock_note(&c, &bake2, 400, 400, 111.0);
    /* Frame 1 was seen whole: 1 s; frame 2 is faster so far (400 units/s). */
    gi_progress_clock_read(&c, 500, 500, 111.25, &at);
    GI_CHECK(fabs(at.fraction - 2.5 / 4) < 1e-12);
    GI_CHECK_MSG(fabs(at.eta_s - (0.25 + 1.0)) < 1e-9, "eta %.9f", at.eta_s);
    gi_progress_clock_read(&c, 500, 400, 111.0, &at);
    GI_CHECK_MSG(fabs(at.eta_s - 2.0) < 1e-9, "eta %.9f", at.eta_s); /* nothing done yet */

    /* A still restored with 300 of 400 units done: its rate counts from
     * the restart, its fraction from the start of the job. */
    gi_progress_clock r;
    memset(&r, 0, sizeof r);
    r.restored_base = -1; /* a checkpoint that did not keep it: frame 0 starts at 0 */
    gi_job_progress still = {.frames = 1};
    gi_progress_clock_note(&r, &still, 400, 300, 50.0);
    gi_progress_clock_read(&r, 400, 350, 52.0, &at);
    GI_CHECK(fabs(at.fraction - 0.875) < 1e-12 && fabs(at.eta_s - 2.0) < 1e-9);
    GI_CHECK(at.frames == 1 && at.done == 350 && at.total == 400);
    /* Frame 2 of 4 restored, its start (400) kept: a quarter of its 200. */
    memset(&r, 0, sizeof r);
    r.restored_base = 400;
    gi_job_progress f2 = {.frame = 2, .frames = 4};
    gi_progress_clock_note(&r, &f2, 600, 450, 50.0);
    gi_progress_clock_read(&r, 600, 450, 50.0, &at);
    GI_CHECK(fabs(at.fraction - 2.25 / 4) < 1e-12 && at.eta_s < 0);
}

/* Frame 0 of an animation whose method estimates its frames: 200 units of
 * work in frame 0, 20 (as frame 0 runs them) in each of the 3 after it. */
GI_TEST(test_progress_clock_weighs_frames_by_the_methods_estimate)
{
    gi_progress_clock c;
    memset(&c, 0, sizeof c);
    gi_progress_at at;
    gi_job_progress bake0 = {.frames = 4, .first_frame_cost = 200, .later_frame_cost = 20};
    gi_progress_clock_note(&c, &bake0, 200, 0, 100.0);
    gi_progress_clock_read(&c, 200, 100, 105.0, &at);
    GI_CHECK_MSG(fabs(at.fraction - 100.0 / 260) < 1e-12, "fraction %.9f", at.fraction);
    /* 5 s for the rest of frame 0 at its 20 units/s, then 3 frames of 1 s. */
    GI_CHECK_MSG(fabs(at.eta_s - 8.0) < 1e-9, "eta %.9f", at.eta_s);
    /* Frame 1 halfway (100 units a frame, as it is planned): frame 0 and
     * half a later frame done. */
    gi_job_progress bake1 = {.frame = 1, .frames = 4, .first_frame_cost = 200,
                             .later_frame_cost = 20};
    gi_progress_clock_note(&c, &bake1, 200, 200, 110.0);
    gi_progress_clock_read(&c, 300, 250, 110.5, &at);
    GI_CHECK_MSG(fabs(at.fraction - 210.0 / 260) < 1e-12, "fraction %.9f", at.fraction);
    /* Without estimates the frames count alike, and frame 0 has no ETA. */
    memset(&c, 0, sizeof c);
    gi_job_progress plain = {.frames = 4};
    gi_progress_clock_note(&c, &plain, 200, 0, 100.0);
    gi_progress_clock_read(&c, 200, 100, 105.0, &at);
    GI_CHECK(fabs(at.fraction - 0.5 / 4) < 1e-12 && at.eta_s < 0);
}

/* A job of many frames: each finish plans 300 more tasks, 40 times. */
static int frames_plan(gi_job *job, gi_task_queue *q, gi_error *err)
{
    (void)err;
    job->state = gi_xcalloc(1, sizeof(fake_state));
    for (int i = 0; i < 300; i++)
        gi_task_queue_add(q, 1, 1.0);
    return 0;
}

static int frames_merge(gi_job *job, const gi_task *t, const gi_buf *r, gi_task_queue *fq,
                        gi_error *err)
{
    (void)fq;
    (void)err;
    fake_state *st = job->state;
    double v;
    memcpy(&v, r->data, sizeof v);
    st->sum += v;
    st->order[st->merged++ % 256] = t->id;
    return 0;
}

static int frames_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    (void)err;
    fake_state *st = job->state;
    if (++st->finish_calls < 40)
        for (int i = 0; i < 300; i++)
            gi_task_queue_add(fq, 1, 1.0);
    return 0;
}

static int frames_save(const gi_job *job, gi_buf *out, gi_error *err);
static int frames_load(gi_job *job, gi_reader *in, gi_error *err);
static void frames_progress(const gi_job *job, gi_job_progress *out);

/* A job of 40 frames of 300 tasks each. */
static gi_method frames_method(void)
{
    gi_method m = fake_method;
    m.plan = frames_plan;
    m.merge = frames_merge;
    m.finish = frames_finish;
    m.save = frames_save;
    m.load = frames_load;
    m.progress = frames_progress;
    return m;
}

GI_TEST(test_jobrun_holds_only_the_tasks_not_yet_merged)
{
    gi_method m = frames_method();
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&m, &job, &jr, &err));
    uint64_t most_held = 0;
    /* Results out of order within a window of 8, a late duplicate of a
     * merged (and dropped) task ignored. */
    while (!gi_jobrun_done(&jr)) {
        const gi_task *t;
        uint64_t ids[8];
        uint32_t attempts[8];
        int n = 0;
        while (n < 8 && (t = gi_jobrun_lease(&jr))) {
            ids[n] = t->id;
            attempts[n++] = t->attempt;
        }
        GI_REQUIRE(n > 0);
        for (int k = n - 1; k >= 0; k--) {
            gi_buf r;
            gi_buf_init(&r);
            double v = task_value(ids[k]);
            gi_buf_put(&r, &v, sizeof v);
            gi_task_stats s = {1, 1, 0.0};
            GI_CHECK(gi_jobrun_complete(&jr, ids[k], attempts[k], &r, &s) == 0);
            gi_buf_free(&r);
        }
        gi_buf r;
        gi_buf_init(&r);
        double v = 1e300;
        gi_buf_put(&r, &v, sizeof v);
        gi_task_stats s = {1, 1, 0.0};
        GI_CHECK(gi_jobrun_complete(&jr, 0, 0, &r, &s) == 0); /* stale */
        gi_buf_free(&r);
        if (jr.task_count - jr.task_base > most_held)
            most_held = jr.task_count - jr.task_base;
    }
    fake_state *st = job.state;
    double sum = 0;
    for (uint64_t id = 0; id < 40 * 300; id++)
        sum += task_value(id);
    GI_CHECK(jr.finished && jr.task_count == 40 * 300 && st->merged == 40 * 300);
    GI_CHECK_MSG(memcmp(&st->sum, &sum, sizeof sum) == 0, "merged out of id order");
    GI_CHECK_MSG(most_held <= 2 * 300 + 256, "held %llu tasks at once of %llu",
                 (unsigned long long)most_held, (unsigned long long)jr.task_count);
    GI_CHECK(gi_jobrun_task_at(&jr, 5) == NULL && jr.task_base > 0);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

static int frames_save(const gi_job *job, gi_buf *out, gi_error *err)
{
    (void)err;
    const fake_state *st = job->state;
    gi_buf_put_u32(out, (uint32_t)st->merged);
    gi_buf_put_u32(out, (uint32_t)st->finish_calls);
    gi_buf_put_f64(out, st->sum);
    return 0;
}

static int frames_load(gi_job *job, gi_reader *in, gi_error *err)
{
    (void)err;
    fake_state *st = gi_xcalloc(1, sizeof *st);
    job->state = st;
    st->merged = (int)gi_get_u32(in);
    st->finish_calls = (int)gi_get_u32(in);
    st->sum = gi_get_f64(in);
    return 0;
}

static void frames_progress(const gi_job *job, gi_job_progress *out)
{
    const fake_state *st = job->state;
    out->frame = (uint32_t)st->finish_calls;
    out->frames = 40;
    out->cost_unplanned = 0;
}

GI_TEST(test_jobrun_restored_mid_frame_keeps_its_progress)
{
    gi_method m = frames_method();
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&m, &job, &jr, &err));
    drive(&jr, 7 * 300 + 120); /* 40% into frame 7 */
    gi_progress_at before, after;
    gi_jobrun_progress(&jr, 0.0, &before);
    GI_CHECK_MSG(fabs(before.fraction - 7.4 / 40) < 1e-12, "%.6f", before.fraction);
    GI_REQUIRE_OK(reload(&jr, &job, &m, &err));
    gi_jobrun_progress(&jr, 0.0, &after);
    GI_CHECK_MSG(fabs(after.fraction - before.fraction) < 1e-12 && after.frame == 7,
                 "%.6f then %.6f (frame %u)", before.fraction, after.fraction, after.frame);
    drive(&jr, 100000);
    GI_CHECK(jr.finished);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}

/* The interval after checkpoints that took these seconds (serialized, then
 * written), oldest first. */
static double interval_after(double every_s, const double *took, int n)
{
    gi_ckpt_pace p;
    memset(&p, 0, sizeof p);
    for (int i = 0; i < n; i++) {
        gi_ckpt_pace_begun(&p, 0.25 * took[i]);
        gi_ckpt_pace_written(&p, 0.75 * took[i]);
    }
    return gi_ckpt_pace_interval(&p, every_s);
}

GI_TEST(test_jobrun_checkpoints_are_spaced_on_slow_disks)
{
    /* Quick writes keep the asked interval, even a short one (the tests'). */
    GI_CHECK(interval_after(30.0, NULL, 0) == 30.0);
    GI_CHECK(interval_after(30.0, (double[]){0.0}, 1) == 30.0);
    GI_CHECK(interval_after(0.2, (double[]){0.2}, 1) == 0.2);
    /* A second to write: at least 20 s apart; a long interval stays. */
    GI_CHECK(interval_after(1.0, (double[]){1.0}, 1) == 20.0);
    GI_CHECK(interval_after(30.0, (double[]){1.0}, 1) == 30.0);
    GI_CHECK(interval_after(30.0, (double[]){5.0}, 1) == 100.0);
    /* One slowed by a hiccup after a quick one does not put the next off;
     * a disk slow twice in a row does, by the cheaper of the two. */
    GI_CHECK(interval_after(30.0, (double[]){0.1, 30.0}, 2) == 30.0);
    GI_CHECK(interval_after(30.0, (double[]){6.0, 30.0}, 2) == 120.0);
    GI_CHECK(interval_after(30.0, (double[]){30.0, 6.0}, 2) == 120.0);
    GI_CHECK(interval_after(30.0, (double[]){30.0, 30.0, 0.1}, 3) == 30.0);
}

/* ---- finish on a thread (gi_jobrun_opts.finish_threaded, gi-farmd's) ----- */

static atomic_int gate_open;        /* the threaded finish waits for it */
static pthread_t loop_thread;       /* the test's own: finish must not run there */
static atomic_int finish_on_loop;   /* a finish ran on the test's thread */
static atomic_int threaded_finishes;

/* Like fake_finish, on a thread: waits for the gate, warns, and fails its
 * second call as a full disk would (GI_EIO). */
static int gated_finish(gi_job *job, gi_task_queue *fq, gi_error *err)
{
    while (!atomic_load(&gate_open))
        usleep(1000);
    if (pthread_equal(pthread_self(), loop_thread))
        atomic_store(&finish_on_loop, 1);
    atomic_fetch_add(&threaded_finishes, 1);
    gi_warn("finish %d warns", atomic_load(&threaded_finishes));
    fake_state *st = job->state;
    if (st->finish_calls++ == 0) {
        gi_task_queue_add(fq, 3, 1.0);
        return 0;
    }
    return gi_fail(err, GI_EIO, "no room for the outputs");
}

static const gi_method gated_method = {
    .name = "fake", .plan = fake_plan, .merge = fake_merge, .finish = gated_finish,
    .save = fake_save, .load = fake_load, .release = fake_release,
};

static char hooked[4][128];
static int hooked_count;

static void hook_keep(void *ctx, gi_log_level level, const char *msg)
{
    (void)ctx;
    if (hooked_count < 4 && level == GI_LOG_WARN)
        snprintf(hooked[hooked_count++], sizeof hooked[0], "%s", msg);
}

/* Leases and completes every task pending now. */
static void complete_all_pending(gi_jobrun *jr)
{
    const gi_task *t;
    uint64_t ids[256];
    int n = 0;
    while (n < 256 && (t = gi_jobrun_lease(jr)))
        ids[n++] = t->id;
    for (int i = 0; i < n; i++)
        complete(jr, ids[i], 0);
}

/* Waits (up to 10 s) for the finish thread's wake-up on fd. */
static int woken(int fd)
{
    struct pollfd p = {.fd = fd, .events = POLLIN};
    if (poll(&p, 1, 10000) != 1)
        return 0;
    uint64_t count;
    return read(fd, &count, sizeof count) == (ssize_t)sizeof count && count >= 1;
}

GI_TEST(test_jobrun_finishes_on_a_thread_and_takes_its_end_in)
{
    loop_thread = pthread_self();
    int wake = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    GI_REQUIRE(wake >= 0);
    gi_job job;
    memset(&job, 0, sizeof job);
    job.method = &gated_method;
    gi_jobrun jr;
    gi_jobrun_opts opts = {.finish_threaded = 1, .finish_wake_fd = wake};
    gi_error err;
    GI_REQUIRE(gi_jobrun_start_opts(&jr, &job, &opts, &err) == 0);
    gi_log_hook_set(hook_keep, NULL);

    complete_all_pending(&jr);
    complete_all_pending(&jr); /* the merge's follow-ups */
    /* Everything merged: the finish runs on its thread, behind the gate. */
    GI_CHECK(jr.merge_next == jr.task_count);
    GI_CHECK(gi_jobrun_finishing(&jr) && !gi_jobrun_done(&jr));
    GI_CHECK(gi_jobrun_lease(&jr) == NULL);
    complete(&jr, 0, 0); /* a late duplicate: ignored */
    GI_CHECK(gi_jobrun_finishing(&jr) && !gi_jobrun_done(&jr));
    gi_buf cp;
    gi_buf_init(&cp);
    GI_CHECK(gi_jobrun_checkpoint(&jr, &cp, &err) == -1); /* its state is the thread's */
    gi_buf_free(&cp);
    GI_CHECK(gi_jobrun_finish_poll(&jr, 0) == 1);
    GI_CHECK(hooked_count == 0);

    atomic_store(&gate_open, 1);
    GI_CHECK(woken(wake));
    GI_CHECK(gi_jobrun_finish_poll(&jr, 0) == 0);
    GI_CHECK(!gi_jobrun_finishing(&jr) && !gi_jobrun_done(&jr));
    /* Its warning reached this thread's hook; its follow-up is pending. */
    GI_CHECK_MSG(hooked_count == 1 && strcmp(hooked[0], "finish 1 warns") == 0, "%d: %s",
                 hooked_count, hooked[0]);
    GI_CHECK(gi_jobrun_pending_count(&jr) == 1);

    /* The second finish fails writing: the run fails with its error, and
     * can be finished again (every task is merged). */
    complete_all_pending(&jr);
    GI_CHECK(gi_jobrun_finishing(&jr));
    GI_CHECK(gi_jobrun_finish_poll(&jr, 1) == 0);
    GI_CHECK(woken(wake)); /* written before the thread ended */
    GI_CHECK(jr.failed && jr.error.code == GI_EIO);
    GI_CHECK_MSG(strstr(jr.error.msg, "no room") != NULL, "%s", jr.error.msg);
    GI_CHECK(hooked_count == 2);
    GI_CHECK(jr.finish_seconds > 0);
    GI_CHECK(!atomic_load(&finish_on_loop) && atomic_load(&threaded_finishes) == 2);

    GI_CHECK(gi_jobrun_finish_poll(&jr, 1) == 0); /* nothing runs: nothing to take */
    gi_log_hook_set(NULL, NULL);

    /* Its checkpoint (every task merged: what gi-farmd keeps when outputs
     * fail) restored with the same options finishes on the thread again,
     * before the restore returns; restored in place, it finishes there. */
    gi_buf kept;
    gi_buf_init(&kept);
    GI_REQUIRE(gi_jobrun_checkpoint(&jr, &kept, &err) == 0);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
    for (int threaded = 1; threaded >= 0; threaded--) {
        memset(&job, 0, sizeof job);
        job.method = &gated_method;
        int rc = gi_jobrun_restore_opts(&jr, &job, &kept, threaded ? &opts : NULL, &err);
        GI_CHECK(rc == (threaded ? 0 : -1));
        GI_CHECK(gi_jobrun_finishing(&jr) == threaded);
        if (threaded) {
            GI_CHECK(woken(wake));
            GI_CHECK(gi_jobrun_finish_poll(&jr, 0) == 0);
        }
        GI_CHECK(jr.failed && jr.error.code == GI_EIO);
        gi_jobrun_free(&jr);
        gi_job_free(&job);
    }
    GI_CHECK(atomic_load(&finish_on_loop) == 1); /* the one restored in place */
    gi_buf_free(&kept);
    close(wake);
}

GI_TEST(test_jobrun_freed_while_it_finishes_waits_for_the_thread)
{
    loop_thread = pthread_self();
    gi_job job;
    memset(&job, 0, sizeof job);
    job.method = &gated_method;
    gi_jobrun jr;
    gi_jobrun_opts opts = {.finish_threaded = 1, .finish_wake_fd = -1};
    gi_error err;
    GI_REQUIRE(gi_jobrun_start_opts(&jr, &job, &opts, &err) == 0);
    complete_all_pending(&jr);
    complete_all_pending(&jr);
    GI_REQUIRE(gi_jobrun_finishing(&jr));
    atomic_store(&gate_open, 1); /* free joins the thread, which then ends */
    gi_jobrun_free(&jr);
    GI_CHECK(atomic_load(&threaded_finishes) == 1);
    GI_CHECK(!gi_jobrun_finishing(&jr));
    gi_job_free(&job);
}

/* Task time limits: the job's own task_timeout wins over the coordinator's
 * default; a run stopped for its limit is an attempt of the task (retried,
 * then the job fails saying why), never taken for bad input. */
GI_TEST(test_jobrun_timeouts_are_attempts)
{
    gi_job job;
    gi_jobrun jr;
    gi_error err;
    GI_REQUIRE_OK(start(&fake_method, &job, &jr, &err));
    GI_CHECK(gi_jobrun_task_timeout(&jr, 0) == 0);
    GI_CHECK(gi_jobrun_task_timeout(&jr, 30) == 30);
    job.task_timeout = 2;
    GI_CHECK(gi_jobrun_task_timeout(&jr, 30) == 2);
    GI_CHECK(gi_jobrun_task_timeout(&jr, 0) == 2);
    for (uint32_t attempt = 0; attempt < jr.max_attempts; attempt++) {
        const gi_task *t = gi_jobrun_lease(&jr);
        GI_REQUIRE(t && t->id == 0 && t->attempt == attempt);
        gi_error e;
        gi_jobrun_timeout_error(&e, t->id, 2, "worker w1");
        GI_CHECK(e.code != GI_EINVAL && e.code != GI_EHOST);
        gi_jobrun_fail(&jr, 0, attempt, &e);
        GI_CHECK(jr.failed == (attempt + 1 == jr.max_attempts));
    }
    GI_CHECK(jr.retries == jr.max_attempts - 1);
    GI_CHECK_MSG(strstr(jr.error.msg, "task 0 failed 4 times; last error: task 0 ran longer than "
                                      "its task_timeout of 2 s on worker w1: stopped") != NULL,
                 "%s", jr.error.msg);
    gi_jobrun_free(&jr);
    gi_job_free(&job);
}
