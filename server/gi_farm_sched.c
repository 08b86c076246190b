/* gi_farm_sched: who runs what.
 *
 * Leases. A task handed to a worker is leased to that connection until
 * `lease_s` after it was sent or last renewed (a worker's HEARTBEAT lists
 * the tasks it holds and renews exactly those). A lease ends with the
 * worker's RESULT or FAIL (a failure: retried up to max_attempts, then the
 * job fails with the task's error), when the worker drains and hands tasks
 * back unrun (requeued, not counted as attempts), or when its host is lost:
 * the connection is lost or closed for an error, or the lease expires.
 *
 * Losses. Hosts go away (spot instances, laptops, kill -9) with whatever
 * they hold, through no fault of their tasks: a lost task is requeued
 * without counting an attempt (gi_jobrun_lost), under a new attempt number.
 * Its losses are counted apart, up to max_losses, so that a task which takes
 * its host down every time (the whole gi-worker dies) fails its job, naming
 * the hosts, instead of going round the farm forever. Every loss counts,
 * however many tasks the host held: discounting a host lost with many tasks
 * would let such a task loop forever on big hosts (it always dies among
 * the 31 others of a 32-slot host), and a task only shares the bad luck of
 * one lost host at a time, so the bound (8 by default) leaves innocent tasks
 * a wide margin. A pool child's crash is a FAIL the worker reports: the
 * task's fault, counted as an attempt.
 *
 * Time limits. A task that runs longer than its time limit (the job's
 * task_timeout, else --task-timeout; none by default) ends too: the
 * coordinator CANCELs the task on its worker, which kills the pool child
 * running it, and fails the run (gi_jobrun_timeout_error): a task that
 * hangs on its input hangs anywhere, so this is the task's fault, an
 * attempt, not a loss. It is not counted against the host (host_failure):
 * a pathological task would otherwise blocklist every host it visits,
 * long after the fact; the run's next attempt goes to another host if one
 * can take it (leave_host), which is what a slow host needs. The limit
 * counts from the start of the run on the worker's pool, as gi render's
 * does (gi_local.c), not from the lease: a task queued on its worker
 * (--queue) waits off the clock however long. Workers speaking protocol
 * GI_PROTO_RUNS say in each HEARTBEAT which held tasks run and for how
 * long; the lease's `started` is dated back by that, so a run is stopped
 * at its limit, or at the first heartbeat after it when the limit is
 * shorter than a heartbeat (never more than a heartbeat late). A task not
 * yet reported running has no clock. For older workers (protocol 1) the
 * limit counts from the lease, as those builds did.
 *
 * A RESULT or FAIL for a task the connection no longer holds is late: it is
 * counted and discarded, never merged, so a task's result is merged exactly
 * once (gi_jobrun also refuses stale attempts, and a lost run's attempt
 * number is never leased again).
 *
 * Fair sharing. Jobs share workers in proportion to their priority by
 * stride scheduling in worker-seconds: each job has a pass; a lease adds
 * the job's mean task time divided by its priority, corrected by the time
 * the task really took when its result arrives; the job with the lowest
 * pass gets the next free slot. A job that becomes runnable starts at the
 * lowest pass of the others, so waiting earns no credit.
 *
 * Affinity. A task with a non-zero gi_task.affinity key goes to the host
 * that owns the key (the last to return a result for it, or to take its
 * task while the previous owner was gone) while that host is present:
 * connected, active, not blocklisted, heard from lately. Other hosts pass
 * such tasks over (they stay pending, in order, for the owner's next free
 * slot). An absent owner's keys go to the first host asking (gi_affinity.h).
 *
 * Blame. A task failure is the host's fault or the job's, and one host
 * cannot tell which: the evidence is what the other hosts do with the same
 * work. A failure of j's task t on host h (that counts: not bad input
 * (GI_EINVAL), not a timeout, not h's disk) is held as a suspect of j's
 * until t returns a result, and judged then (judge):
 *   - on h itself: passing trouble, judged nobody's (h's result ends its
 *     streak anyway);
 *   - on another host g: the task runs elsewhere, so the failure is h's,
 *     unless j's tasks also fail on another host that works (one that
 *     failed one of j's tasks and has returned a result, of any job,
 *     since; g counts): then j is flaky or broken, and the failure is j's.
 *     Such a failure counts if it came no more than `blocklist_s` before
 *     h's (or after): a job that failed once somewhere early in a long run
 *     does not excuse a bad host's failures of it for the rest of the run.
 * A task that never returns a result (a job whose tasks crash everywhere)
 * leaves its failures unjudged: they are dropped when its job ends. So two
 * broken jobs at once, which fail on every host, blocklist no host (before,
 * any host's failures of both in a row did), while a bad host, whose tasks
 * other hosts then run, is found; two bad hosts failing the same tasks are
 * both found, as long as some host works. Failures judged the host's make
 * its streak (consecutive_failures, since its last result: a failure
 * judged after a result of the host is counted, not streaked). The host's
 * disk errors (GI_EHOST) are its fault whatever the job, and join its
 * streak at once. What is judged is counted (failures_host, failures_job:
 * /metrics). A farm of one host has nothing to compare with: its task
 * failures are never judged its own, so it is excluded from failing jobs
 * (Exclusions) and never blocklisted for them; its disk errors and losses
 * still blocklist it.
 *
 * Blocklisting. A worker (by name, across reconnections) whose streak of
 * failures judged its own reaches `blocklist_failures` gets no tasks for
 * `blocklist_s`, provided the streak holds failures of at least two jobs,
 * or one of its disk: the tasks of several jobs that run elsewhere fail on
 * it. A streak of one job's failures is evidence against the pair, and
 * that job's exclusion (below) handles it. An exclusion ends the streak it
 * came from as far as the farm goes: the failures that excluded the host
 * from a job count globally only once the same tasks have run on other
 * hosts; a job's failures that stay unjudged (it fails everywhere) never
 * do, so a host excluded from a broken job whose next task, of another
 * job, fails is not blocklisted. The failures other hosts confirm stay
 * evidence: otherwise a bad host would escape, excluded job by job
 * (a job's exclusion comes as soon as its own streak does). Bad input
 * and timeouts do not count (above). So is a host blocklisted when lost
 * with tasks held `blocklist_losses` times (3 by default) with no result
 * accepted from it in between (host_lost), whatever the jobs: a machine
 * that keeps dying (bad memory, an OOM killer, a flapping link)
 * would otherwise take tasks again and again and lose them. A loss is one
 * event however many tasks it held: a connection lost or closed for an
 * error while holding leases, or leases of a connection expiring (those
 * expiring within a lease time of a counted loss of that connection are
 * the same loss). One network blip or one kill-and-restart is one loss,
 * and the host's next result wipes it; a worker that drains (SIGTERM)
 * hands back or finishes what it holds and loses nothing; a connection
 * ended by BYE requeues what it held without a loss. Why 3: two losses in
 * a row happen to a healthy host (a reboot during a network outage), a
 * third without one task finished between them rarely does. A task that
 * takes every host down can blocklist a host it meets three times before
 * that host finishes anything, but max_losses (8) fails its job soon.
 *
 * Exclusions. A worker whose runs of one job's tasks fail
 * `blocklist_failures` times with no result of that job from it in between
 * gets no more of that job's tasks for `blocklist_s`, and keeps serving the
 * other jobs: a job whose tasks crash the renderer everywhere would
 * otherwise blocklist the whole farm, host after host, stalling every other
 * job (render farms keep such "bad worker" evidence per job). Its tasks go
 * to the other hosts, so it reaches its max_attempts and fails soon; when
 * every host is excluded from it, it waits (its log says so, and its view
 * lists the exclusions and until when). What counts is what counts for
 * blocklisting (Blame), judged or not: the pair's streak needs no verdict,
 * for excluding a host from one job costs the farm little. The host's disk
 * errors count towards its blocklisting only. The blocklist, the hosts'
 * counts and streaks and the exclusions outlive a coordinator restart
 * (gi_farm_standing.c); failures not yet judged do not. A retried job
 * starts its exclusions afresh. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_batch_dir.h"
#include "gi_farm_impl.h"
#include "gi_fs.h"
#include "gi_progress.h"
#include "gi_log.h"
#include "gi_msg.h"

/* After a coordinator restart, the owners of restored affinity keys get
 * this long to reconnect before their keys go to whoever asks. */
#define AFFINITY_RESTART_GRACE_S 30.0

/* Output queue size above which no more work is queued on a connection. */
#define SCHED_OUT_HIGH ((size_t)64 << 20)

gi_farm_host *gi_farm_host_get(gi_farm *f, const char *name)
{
    for (size_t i = 0; i < f->host_count; i++)
        if (strcmp(f->hosts[i]->name, name) == 0)
            return f->hosts[i];
    if (f->host_count == f->host_cap) {
        f->host_cap = f->host_cap ? 2 * f->host_cap : 8;
        f->hosts = gi_xrealloc(f->hosts, f->host_cap * sizeof *f->hosts);
    }
    gi_farm_host *h = gi_xcalloc(1, sizeof *h);
    snprintf(h->name, sizeof h->name, "%s", name);
    f->hosts[f->host_count++] = h;
    return h;
}

int gi_farm_host_blocked(const gi_farm_host *h, double now)
{
    return h && h->blocked_until > now;
}

static gi_fj_exclusion *exclusion_find(const gi_farm_job *j, const gi_farm_host *h)
{
    for (size_t i = 0; i < j->excl_count; i++)
        if (j->excl[i].host == h)
            return &j->excl[i];
    return NULL;
}

gi_fj_exclusion *gi_farm_job_exclusion(gi_farm_job *j, gi_farm_host *h)
{
    gi_fj_exclusion *x = exclusion_find(j, h);
    if (x)
        return x;
    if (j->excl_count == j->excl_cap) {
        j->excl_cap = j->excl_cap ? 2 * j->excl_cap : 4;
        j->excl = gi_xrealloc(j->excl, j->excl_cap * sizeof *j->excl);
    }
    x = &j->excl[j->excl_count++];
    memset(x, 0, sizeof *x);
    x->host = h;
    x->results_at_failure = h->results;
    x->last_failed = -INFINITY;
    return x;
}

int gi_farm_job_excludes(const gi_farm_job *j, const gi_farm_host *h, double now)
{
    const gi_fj_exclusion *x = h ? exclusion_find(j, h) : NULL;
    return x && x->until > now;
}

static const char *conn_name(const gi_farm_conn *c)
{
    return c->have_hello ? c->hello.name : c->peer;
}

/* ---- lease bookkeeping -------------------------------------------------- */

static long lease_find(const gi_farm_conn *c, uint64_t job, uint64_t task, uint32_t attempt)
{
    for (size_t i = 0; i < c->lease_count; i++) {
        const gi_farm_lease *l = &c->leases[i];
        if (l->job_id == job && l->task_id == task && l->attempt == attempt)
            return (long)i;
    }
    return -1;
}

static gi_farm_lease lease_take(gi_farm_conn *c, size_t i)
{
    gi_farm_lease l = c->leases[i];
    c->leases[i] = c->leases[--c->lease_count];
    return l;
}

static void lease_add(gi_farm_conn *c, const gi_farm_lease *l)
{
    if (c->lease_count == c->lease_cap) {
        c->lease_cap = c->lease_cap ? 2 * c->lease_cap : 8;
        c->leases = gi_xrealloc(c->leases, c->lease_cap * sizeof *c->leases);
    }
    c->leases[c->lease_count++] = *l;
}

static gi_farm_job *running_job(gi_farm *f, uint64_t id)
{
    gi_farm_job *j = gi_farm_job_find(f, id);
    return j && j->state == GI_FJ_RUNNING && j->loaded ? j : NULL;
}

/* ---- fair sharing -------------------------------------------------------- */

void gi_farm_sched_join(gi_farm *f, gi_farm_job *j)
{
    double lowest = INFINITY;
    for (size_t i = 0; i < f->job_count; i++) {
        const gi_farm_job *o = f->jobs[i];
        if (o != j && o->state == GI_FJ_RUNNING && o->pass < lowest)
            lowest = o->pass;
    }
    if (isfinite(lowest) && lowest > j->pass)
        j->pass = lowest;
}

static void charge(gi_farm_job *j, double seconds)
{
    j->pass += seconds / (double)(j->priority ? j->priority : 1);
}

static int conn_takes_work(const gi_farm *f, const gi_farm_conn *c, double now)
{
    if (c->state != GI_FC_ACTIVE || c->fd < 0)
        return 0;
    if (c->lease_count >= c->hello.slots)
        return 0;
    if (gi_farm_host_blocked(c->host, now))
        return 0;
    /* A worker we have not heard from for two heartbeats may be cut off:
     * queue nothing more on it until it speaks again. */
    if (now - c->last_heard > 2.0 * f->cfg.heartbeat_s)
        return 0;
    return gi_outq_pending(&c->out) < SCHED_OUT_HIGH;
}

void gi_farm_conn_send_job(gi_farm_conn *c, const gi_farm_job *j)
{
    for (size_t i = 0; i < c->jobs_sent_count; i++)
        if (c->jobs_sent[i] == j->id)
            return;
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_job_encode(&b, j->id, j->file, j->text, &j->manifest);
    gi_farm_conn_send(c, GI_MSG_JOB, &b, 1);
    gi_buf_free(&b);
    if (c->jobs_sent_count == c->jobs_sent_cap) {
        c->jobs_sent_cap = c->jobs_sent_cap ? 2 * c->jobs_sent_cap : 8;
        c->jobs_sent = gi_xrealloc(c->jobs_sent, c->jobs_sent_cap * sizeof *c->jobs_sent);
    }
    c->jobs_sent[c->jobs_sent_count++] = j->id;
}

/* ---- affinity ------------------------------------------------------------ */

/* Marks the hosts that can take work, now or when a slot frees: an owner
 * that is not present loses its keys to whoever asks (no stalls). A host
 * not yet back since this coordinator started counts as present for a
 * short grace time, so keys restored from a checkpoint wait for it. */
static void mark_present(gi_farm *f, double now)
{
    int grace = now - f->started < AFFINITY_RESTART_GRACE_S;
    for (size_t i = 0; i < f->host_count; i++)
        f->hosts[i]->present = grace && !f->hosts[i]->seen;
    for (size_t ci = 0; ci < f->conn_count; ci++) {
        const gi_farm_conn *c = f->conns[ci];
        if (!c->host || c->state != GI_FC_ACTIVE || c->fd < 0)
            continue;
        c->host->seen = 1;
        if (c->hello.slots > 0 && !gi_farm_host_blocked(c->host, now) &&
            now - c->last_heard <= 2.0 * f->cfg.heartbeat_s)
            c->host->present = 1;
    }
}

typedef struct taker {
    const gi_farm *farm;
    const gi_farm_job *job;
    const gi_farm_host *host;
    double now;
} taker;

/* The host can take the job's work: an owner excluded from the job is as
 * good as absent for its keys. */
static int usable(const taker *k, const gi_farm_host *h)
{
    return h->present && !gi_farm_job_excludes(k->job, h, k->now);
}

static int host_present(void *ctx, const void *owner)
{
    return usable(ctx, owner);
}

/* Some host other than the taker's can take the job's work now. */
static int another_present(const taker *k)
{
    for (size_t i = 0; i < k->farm->host_count; i++)
        if (k->farm->hosts[i] != k->host && usable(k, k->farm->hosts[i]))
            return 1;
    return 0;
}

static int may_take(void *ctx, const gi_task *t)
{
    const taker *k = ctx;
    /* Not back to the host it just failed on, while another can take it. */
    if (gi_affinity_owner(&k->job->failed_on, t->id + 1) == k->host && another_present(k))
        return 0;
    return gi_affinity_may_take(&k->job->affinity, t->affinity, k->host, host_present, ctx);
}

int gi_farm_job_has_host(const gi_farm *f, const gi_farm_job *j, double now)
{
    for (size_t ci = 0; ci < f->conn_count; ci++) {
        const gi_farm_conn *c = f->conns[ci];
        if (c->host && c->state == GI_FC_ACTIVE && c->fd >= 0 && c->hello.slots > 0 &&
            !gi_farm_host_blocked(c->host, now) && !gi_farm_job_excludes(j, c->host, now))
            return 1;
    }
    return 0;
}

/* host now owns the key (it took or returned the key's task). */
static void affinity_own(gi_farm_job *j, uint64_t key, gi_farm_host *host, const char *how)
{
    if (!key || !host)
        return;
    const gi_farm_host *prev = gi_affinity_set(&j->affinity, key, host);
    if (prev == host)
        return;
    if (!prev) {
        gi_debug("job %llu: affinity key %llu goes to worker %s", (unsigned long long)j->id,
                 (unsigned long long)key, host->name);
        return;
    }
    j->affinity_moves++;
    gi_info("job %llu: affinity key %llu moves from worker %s to worker %s (%s)",
            (unsigned long long)j->id, (unsigned long long)key, prev->name, host->name, how);
}

static const char *host_name(const void *owner)
{
    return ((const gi_farm_host *)owner)->name;
}

void gi_farm_affinity_save(const gi_farm_job *j, const char *path)
{
    gi_buf b;
    gi_buf_init(&b);
    gi_affinity_encode(&j->affinity, host_name, &b);
    gi_error err;
    if (gi_write_file_atomic(path, b.data, b.len, &err))
        gi_warn("job %llu: saving affinity owners: %s", (unsigned long long)j->id, err.msg);
    gi_buf_free(&b);
}

typedef struct affinity_loader {
    gi_farm *farm;
    gi_affinity map;
} affinity_loader;

static void affinity_loaded(void *ctx, uint64_t key, const char *name)
{
    affinity_loader *l = ctx;
    gi_affinity_set(&l->map, key, gi_farm_host_get(l->farm, name));
}

void gi_farm_affinity_load(gi_farm *f, gi_farm_job *j, const char *path)
{
    if (access(path, F_OK) != 0)
        return;
    gi_buf b;
    gi_buf_init(&b);
    gi_error err;
    if (gi_read_file(path, (size_t)1 << 30, &b, &err)) {
        gi_warn("job %llu: affinity owners not restored: %s", (unsigned long long)j->id, err.msg);
        gi_buf_free(&b);
        return;
    }
    /* A file that is not one is ignored; a damaged one gives what it holds. */
    affinity_loader l = {f, {0}};
    gi_affinity_init(&l.map);
    int rc = gi_affinity_decode(b.data, b.len, path, affinity_loaded, &l, &err);
    if (rc < 0) {
        gi_warn("job %llu: affinity owners not restored: %s", (unsigned long long)j->id, err.msg);
        gi_affinity_free(&l.map);
    } else {
        if (rc > 0)
            gi_warn("job %llu: affinity owners partly restored: %s", (unsigned long long)j->id,
                    err.msg);
        gi_affinity_free(&j->affinity);
        j->affinity = l.map;
    }
    gi_debug("job %llu: %zu affinity owners restored", (unsigned long long)j->id,
             j->affinity.count);
    gi_buf_free(&b);
}

/* ---- leasing -------------------------------------------------------------- */

/* The jobs a scheduling round chooses from: the live ones. */
typedef struct candidates {
    gi_farm_job **jobs;
    size_t count;
    unsigned char *exhausted; /* [i]: job i has nothing pending for anyone */
    unsigned char *passed;    /* [i]: job i has nothing for this connection */
} candidates;

/* The running job with the lowest pass that may still have pending tasks
 * for this connection, as an index into cand->jobs, or -1. */
static long pick_job(const candidates *cand)
{
    long best = -1;
    for (size_t i = 0; i < cand->count; i++) {
        gi_farm_job *j = cand->jobs[i];
        if (cand->exhausted[i] || cand->passed[i] || j->state != GI_FJ_RUNNING || !j->loaded)
            continue;
        if (best < 0 || j->pass < cand->jobs[best]->pass)
            best = (long)i;
    }
    return best;
}

/* A task for connection c, from the job with the lowest pass that has one
 * it may take. */
static const gi_task *lease_for(gi_farm *f, gi_farm_conn *c, candidates *cand, gi_farm_job **job,
                               double now)
{
    memset(cand->passed, 0, cand->count);
    long i;
    while ((i = pick_job(cand)) >= 0) {
        gi_farm_job *j = cand->jobs[i];
        if (gi_farm_job_excludes(j, c->host, now)) {
            cand->passed[i] = 1;
            continue;
        }
        taker k = {f, j, c->host, now};
        uint64_t refused;
        const gi_task *t = gi_jobrun_lease_if(&j->jr, may_take, &k, &refused);
        if (t) {
            *job = j;
            return t;
        }
        if (refused)
            cand->passed[i] = 1; /* its pending tasks belong to other hosts */
        else
            cand->exhausted[i] = 1;
    }
    return NULL;
}

void gi_farm_schedule(gi_farm *f)
{
    candidates cand;
    cand.jobs = gi_farm_live_jobs(f, &cand.count);
    if (cand.count == 0 || f->conn_count == 0)
        return;
    double now = gi_now();
    mark_present(f, now);
    cand.exhausted = gi_xcalloc(cand.count, 1);
    cand.passed = gi_xcalloc(cand.count, 1);
    int any = 1;
    /* Round-robin over workers, one task at a time, so a burst of work is
     * spread rather than piled on the first worker. */
    while (any) {
        any = 0;
        for (size_t ci = 0; ci < f->conn_count; ci++) {
            gi_farm_conn *c = f->conns[ci];
            if (!conn_takes_work(f, c, now))
                continue;
            gi_farm_job *j = NULL;
            const gi_task *t = lease_for(f, c, &cand, &j, now);
            if (!t)
                continue;
            affinity_own(j, t->affinity, c->host, "its owner cannot take work");
            gi_farm_lease l = {j->id, t->id, t->attempt, now + f->cfg.lease_s, j->est_task_s,
                               now, 0};
            lease_add(c, &l);
            charge(j, j->est_task_s);
            j->leases++;
            f->m.tasks_leased++;
            gi_farm_conn_send_job(c, j);
            gi_buf b;
            gi_buf_init(&b);
            gi_msg_task_encode(&b, j->id, t);
            gi_farm_conn_send(c, GI_MSG_TASK, &b, 1);
            gi_buf_free(&b);
            any = 1;
        }
    }
    free(cand.exhausted);
    free(cand.passed);
}

/* ---- what workers report ------------------------------------------------- */

/* Blocklists h after `count` of `what` in a row (see the header), unless
 * it is already. */
static void host_block(gi_farm *f, gi_farm_host *h, uint32_t count, uint32_t bound,
                       const char *what, const char *last)
{
    double now = gi_now();
    if (count < bound || gi_farm_host_blocked(h, now))
        return;
    h->blocked_until = now + f->cfg.blocklist_s;
    gi_warn("worker %s blocklisted for %.0f s after %u %s in a row; last: %s", h->name,
            f->cfg.blocklist_s, count, what, last);
}

/* h failed one more of j's tasks: excluded from j after a streak of them
 * (see the header: Exclusions). */
static void job_exclude(gi_farm *f, gi_farm_job *j, gi_farm_host *h, const gi_error *e,
                        double now)
{
    gi_fj_exclusion *x = gi_farm_job_exclusion(j, h);
    f->standing_dirty = 1;
    x->streak++;
    x->last_failed = now;
    snprintf(x->last_error, sizeof x->last_error, "%.250s", e->msg);
    if (x->streak < f->cfg.blocklist_failures || x->until > now)
        return;
    x->until = now + f->cfg.blocklist_s;
    x->times++;
    f->m.job_exclusions++;
    /* One line, in the coordinator's log (a warning) and the job's. */
    gi_farm_job_warn(j, "worker %s excluded from it for %.0f s after %u of its task failures "
                     "in a row (it still serves other jobs); last: %s", h->name,
                     f->cfg.blocklist_s, x->streak, e->msg);
    if (!gi_farm_job_has_host(f, j, now))
        gi_farm_job_log(j, "no connected worker may take its tasks now (excluded or "
                        "blocklisted): they wait, %.0f s at most", f->cfg.blocklist_s);
}

/* One more failure of h judged its own (see the header: Blame), of job
 * `job`'s task, or of its disk (disk): blocklisted after a streak of them
 * that is not one job's alone. */
static void streak_add(gi_farm *f, gi_farm_host *h, uint64_t job, int disk, const char *last)
{
    if (h->consecutive_failures == 0) {
        h->streak_job = job;
        h->streak_wide = disk;
    } else if (disk || h->streak_job != job) {
        h->streak_wide = 1;
    }
    h->consecutive_failures++;
    f->standing_dirty = 1;
    if (h->streak_wide)
        host_block(f, h, h->consecutive_failures, f->cfg.blocklist_failures,
                   "task failures of its own (tasks of more than one job that other hosts "
                   "ran, or its disk's)", last);
}

/* Some host other than s's has failed one of j's tasks within `window`
 * seconds before s's failure, or since, and has returned a result (of any
 * job) since its first: j's tasks fail on hosts that work. */
static int job_fails_elsewhere(const gi_farm_job *j, const gi_fj_suspect *s, double window)
{
    for (size_t i = 0; i < j->excl_count; i++) {
        const gi_fj_exclusion *x = &j->excl[i];
        if (x->host != s->host && x->host->results > x->results_at_failure &&
            x->last_failed >= s->failed_at - window)
            return 1;
    }
    return 0;
}

/* Task task_id of j returned a result on host g: its failures on other
 * hosts get their verdict (see the header: Blame). */
static void judge(gi_farm *f, gi_farm_job *j, uint64_t task_id, const gi_farm_host *g)
{
    for (size_t i = 0; i < j->suspect_count;) {
        gi_fj_suspect s = j->suspects[i];
        if (s.task_id != task_id) {
            i++;
            continue;
        }
        j->suspects[i] = j->suspects[--j->suspect_count];
        if (s.host == g)
            continue; /* it failed there and then ran there: passing trouble */
        if (job_fails_elsewhere(j, &s, f->cfg.blocklist_s)) {
            f->m.failures_job++;
            continue;
        }
        f->m.failures_host++;
        s.host->own_failures++;
        gi_debug("job %llu: task %llu's failure on worker %s is that host's: it ran on %s",
                 (unsigned long long)j->id, (unsigned long long)task_id, s.host->name, g->name);
        if (s.host->results == s.results_at) /* else a result of it ended that streak */
            streak_add(f, s.host, j->id, 0, s.host->last_error);
    }
}

static void suspect_add(gi_farm_job *j, uint64_t task_id, gi_farm_host *h, double now)
{
    if (j->suspect_count == j->suspect_cap) {
        j->suspect_cap = j->suspect_cap ? 2 * j->suspect_cap : 8;
        j->suspects = gi_xrealloc(j->suspects, j->suspect_cap * sizeof *j->suspects);
    }
    j->suspects[j->suspect_count++] = (gi_fj_suspect){task_id, h, h->results, now};
}

/* c's host failed task l of j (see the header: Blame, Exclusions). */
static void host_failure(gi_farm *f, gi_farm_conn *c, gi_farm_job *j, const gi_farm_lease *l,
                         const gi_error *e)
{
    gi_farm_host *h = c->host;
    if (!h || e->code == GI_EINVAL)
        return;
    h->failures++;
    f->standing_dirty = 1;
    snprintf(h->last_error, sizeof h->last_error, "%.500s", e->msg);
    if (e->code == GI_EHOST) { /* its disk: the host's fault whatever the job */
        h->own_failures++;
        f->m.failures_host++;
        streak_add(f, h, j->id, 1, e->msg);
        return;
    }
    double now = gi_now();
    job_exclude(f, j, h, e, now);
    suspect_add(j, l->task_id, h, now);
}

/* c's host was lost with tasks held (see the header: Blocklisting). Leases
 * of one connection expiring within a lease time of a counted loss are the
 * same loss (they were sent at different times, so expire apart). */
static void host_lost(gi_farm *f, gi_farm_conn *c, double now, const char *why)
{
    gi_farm_host *h = c->host;
    if (!h || (c->lost_at > 0 && now - c->lost_at < f->cfg.lease_s))
        return;
    c->lost_at = now;
    f->standing_dirty = 1;
    h->losses++;
    h->consecutive_losses++;
    f->m.host_losses++;
    snprintf(h->last_error, sizeof h->last_error, "%.500s", why);
    host_block(f, h, h->consecutive_losses, f->cfg.blocklist_losses,
               "losses with tasks held (no result in between)", why);
}

static void late(gi_farm *f, gi_farm_conn *c, const char *what, uint64_t job, uint64_t task,
                 uint32_t attempt)
{
    f->m.late_results++;
    gi_farm_job *j = gi_farm_job_find(f, job);
    if (j)
        j->results_late++;
    gi_info("discarding a late %s for job %llu task %llu (attempt %u) from worker %s: it no "
            "longer holds that lease",
            what, (unsigned long long)job, (unsigned long long)task, attempt, conn_name(c));
}

/* The task's run on c's host ended without a result: its next run goes
 * elsewhere if it can (may_take), and so does its affinity key: the
 * host's files for it may be the trouble. */
static void leave_host(gi_farm_conn *c, gi_farm_job *j, const gi_farm_lease *l)
{
    if (!c->host)
        return;
    gi_affinity_set(&j->failed_on, l->task_id + 1, c->host);
    const gi_jobrun_task *jt = gi_jobrun_task_at(&j->jr, l->task_id);
    uint64_t key = jt ? jt->task.affinity : 0;
    if (key && gi_affinity_owner(&j->affinity, key) == c->host)
        gi_affinity_set(&j->affinity, key, NULL);
}

/* The task failed on a worker (reported, or a result refused). */
static void task_failed(gi_farm *f, gi_farm_conn *c, gi_farm_job *j, const gi_farm_lease *l,
                        const gi_error *e)
{
    f->m.task_failures++;
    c->tasks_failed++;
    gi_farm_job_task_error(j, l->task_id, l->attempt, conn_name(c), e->msg);
    /* A host's full or read-only disk is not the task's fault: the attempt
     * is not counted, the host's failures are (host_failure: it is
     * blocklisted after a few), and the task waits for a host that can
     * run it instead of failing the job. */
    int host_disk = e->code == GI_EHOST && c->host;
    gi_farm_job_log(j, "task %llu (attempt %u) failed on %s: %s%s", (unsigned long long)l->task_id,
                    l->attempt, conn_name(c), e->msg,
                    host_disk ? " (that host's disk: not counted as an attempt)" : "");
    leave_host(c, j, l);
    if (host_disk) {
        j->host_disk_errors++;
        gi_jobrun_requeue(&j->jr, l->task_id);
    } else {
        gi_jobrun_fail(&j->jr, l->task_id, l->attempt, e);
    }
    gi_farm_job_settle(f, j);
}

/* The task was lost with its host (the connection, or the lease expired). */
static void task_lost(gi_farm *f, gi_farm_conn *c, gi_farm_job *j, const gi_farm_lease *l,
                      const gi_error *e)
{
    f->m.tasks_lost++;
    gi_farm_job_task_error(j, l->task_id, l->attempt, conn_name(c), e->msg);
    const gi_jobrun_task *jt = gi_jobrun_task_at(&j->jr, l->task_id);
    uint32_t loss = jt ? jt->losses + 1 : 1;
    gi_farm_job_log(j, "task %llu (attempt %u) was lost with its host %s (loss %u of %u%s): %s",
                    (unsigned long long)l->task_id, l->attempt, conn_name(c), loss,
                    j->jr.max_losses,
                    loss < j->jr.max_losses ? "; requeued, not counted as an attempt" : "",
                    e->msg);
    leave_host(c, j, l);
    gi_jobrun_lost(&j->jr, l->task_id, l->attempt, conn_name(c), e);
    gi_farm_job_settle(f, j);
}

/* A worker's FAIL, or a result its method refused: the provisional charge
 * goes back, the host's failures count, the task fails. */
static void answer_failed(gi_farm *f, gi_farm_conn *c, gi_farm_job *j, const gi_farm_lease *l,
                          const gi_error *e)
{
    charge(j, -l->est_s);
    host_failure(f, c, j, l, e);
    task_failed(f, c, j, l, e);
}

/* The lease a RESULT or FAIL answers, taken from the connection, and its
 * running job (NULL if the job has ended). Returns 0, or -1 when the
 * connection does not hold that lease: the answer is late (counted). */
static int answered(gi_farm *f, gi_farm_conn *c, const char *what, uint64_t job, uint64_t task,
                    uint32_t attempt, gi_farm_lease *l, gi_farm_job **j)
{
    long i = lease_find(c, job, task, attempt);
    if (i < 0) {
        late(f, c, what, job, task, attempt);
        return -1;
    }
    *l = lease_take(c, (size_t)i);
    *j = running_job(f, l->job_id);
    return 0;
}

void gi_farm_sched_result(gi_farm *f, gi_farm_conn *c, const gi_buf *payload)
{
    gi_msg_result r;
    gi_error err;
    if (gi_msg_result_decode(payload, &r, &err)) {
        gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
        return;
    }
    gi_farm_lease l;
    gi_farm_job *j;
    if (answered(f, c, "result", r.job_id, r.task_id, r.attempt, &l, &j) || !j) {
        gi_buf_free(&r.data);
        return;
    }
    if (gi_jobrun_check_result(&j->jr, l.task_id, l.attempt, &r.data, &err)) {
        gi_buf_free(&r.data); /* a wrong answer: as if the worker had failed it */
        answer_failed(f, c, j, &l, &err);
        return;
    }
    if (c->host) {
        gi_fj_exclusion *x = exclusion_find(j, c->host);
        if (c->host->consecutive_failures || c->host->consecutive_losses || (x && x->streak))
            f->standing_dirty = 1;
        c->host->consecutive_failures = 0;
        c->host->consecutive_losses = 0;
        c->host->results++;
        if (x)
            x->streak = 0;
        judge(f, j, l.task_id, c->host);
    }
    const gi_jobrun_task *jt = gi_jobrun_task_at(&j->jr, l.task_id);
    if (jt)
        affinity_own(j, jt->task.affinity, c->host, "it returned a result");
    c->tasks_done++;
    c->result_bytes += r.data.len;
    /* Correct the provisional charge with what the task really cost. */
    double secs = isfinite(r.stats.seconds) && r.stats.seconds >= 0 ? r.stats.seconds : l.est_s;
    charge(j, secs - l.est_s);
    j->est_n++;
    j->est_task_s += (secs - j->est_task_s) / (double)(j->est_n < 64 ? j->est_n : 64);
    if (j->est_task_s < 1e-3)
        j->est_task_s = 1e-3;
    size_t bytes = r.data.len;
    double m0 = j->jr.merge_seconds, f0 = j->jr.finish_seconds;
    uint64_t b0 = j->jr.merged_bytes;
    gi_farm_job_logging(j); /* the merge's and finish's warnings */
    gi_jobrun_complete(&j->jr, l.task_id, l.attempt, &r.data, &r.stats);
    gi_farm_job_logging(NULL);
    gi_buf_free(&r.data);
    double dm = j->jr.merge_seconds - m0, df = j->jr.finish_seconds - f0;
    uint64_t db = j->jr.merged_bytes - b0;
    j->merge_s += dm;
    j->finish_s += df;
    j->merged_bytes += db;
    j->result_bytes += bytes;
    j->results_accepted++;
    f->m.merge_s += dm;
    f->m.finish_s += df;
    f->m.merged_bytes += db;
    f->m.result_bytes += bytes;
    f->m.task_results++;
    gi_farm_job_settle(f, j);
}

void gi_farm_sched_fail(gi_farm *f, gi_farm_conn *c, const gi_buf *payload)
{
    gi_msg_fail m;
    gi_error err;
    if (gi_msg_fail_decode(payload, &m, &err)) {
        gi_farm_conn_close(f, c, GI_EPROTO, "%s", err.msg);
        return;
    }
    gi_farm_lease l;
    gi_farm_job *j;
    if (answered(f, c, "failure", m.job_id, m.task_id, m.attempt, &l, &j) || !j)
        return;
    answer_failed(f, c, j, &l, &m.error);
}

void gi_farm_sched_heartbeat(gi_farm *f, gi_farm_conn *c, const gi_msg_tasklist *hb)
{
    double now = gi_now(), deadline = now + f->cfg.lease_s;
    for (uint32_t k = 0; k < hb->count; k++) {
        const gi_msg_taskref *r = &hb->refs[k];
        long i = lease_find(c, r->job_id, r->task_id, r->attempt);
        if (i < 0)
            continue;
        gi_farm_lease *l = &c->leases[i];
        l->deadline = deadline;
        /* The run's start, dated back by what the worker says it has run
         * (a duration: no clocks compared), never before the lease. */
        if (r->running && l->started == 0) {
            l->started = now - r->run_ms / 1000.0;
            if (l->started < l->leased)
                l->started = l->leased;
        }
    }
}

void gi_farm_sched_drain(gi_farm *f, gi_farm_conn *c, const gi_msg_tasklist *back)
{
    if (c->state == GI_FC_ACTIVE)
        gi_info("worker %s (%s) is draining: %u tasks handed back", conn_name(c), c->peer,
                back->count);
    c->state = GI_FC_DRAINING;
    for (uint32_t k = 0; k < back->count; k++) {
        long i = lease_find(c, back->refs[k].job_id, back->refs[k].task_id, back->refs[k].attempt);
        if (i < 0)
            continue;
        gi_farm_lease l = lease_take(c, (size_t)i);
        gi_farm_job *j = running_job(f, l.job_id);
        if (!j)
            continue;
        charge(j, -l.est_s);
        gi_jobrun_requeue(&j->jr, l.task_id);
        f->m.requeued++;
    }
}

void gi_farm_sched_release(gi_farm *f, gi_farm_conn *c, int crash, const char *why)
{
    size_t held = c->lease_count;
    if (crash && held) {
        char what[400];
        snprintf(what, sizeof what, "lost with %zu task%s: %.300s", held, held == 1 ? "" : "s",
                 why);
        host_lost(f, c, gi_now(), what);
    }
    while (c->lease_count) {
        gi_farm_lease l = lease_take(c, c->lease_count - 1);
        gi_farm_job *j = running_job(f, l.job_id);
        if (!j)
            continue;
        charge(j, -l.est_s);
        if (!crash) {
            gi_jobrun_requeue(&j->jr, l.task_id);
            f->m.requeued++;
            continue;
        }
        gi_error e;
        gi_fail(&e, GI_ECRASH, "worker %s (%s) was lost with %zu task%s: %s", conn_name(c),
                c->peer, held, held == 1 ? "" : "s", why);
        task_lost(f, c, j, &l, &e);
    }
}

static int worker_conn(const gi_farm_conn *c)
{
    return c->fd >= 0 && (c->state == GI_FC_ACTIVE || c->state == GI_FC_DRAINING);
}

/* Tells a worker to drop task `task_id` of job `id`, or every task of it
 * (GI_MSG_ALL_TASKS: the job is over, its batch directories go too;
 * GI_MSG_JOB_STOPPED: they stay). */
static void send_cancel(gi_farm_conn *c, uint64_t id, uint64_t task_id)
{
    gi_msg_cancel m = {id, task_id};
    gi_buf b;
    gi_buf_init(&b);
    gi_msg_cancel_encode(&b, &m);
    gi_farm_conn_send(c, GI_MSG_CANCEL, &b, 0);
    gi_buf_free(&b);
}

/* When lease l's task time limit started counting (see the header), or 0
 * while it does not: the run's start, which workers speaking protocol
 * GI_PROTO_RUNS report; the lease for older ones. */
static double limit_from(const gi_farm_conn *c, const gi_farm_lease *l)
{
    return c->proto >= GI_PROTO_RUNS ? l->started : l->leased;
}

/* Lease i of c has run past its task's time limit (see the header): the
 * worker stops the task, and its run fails. The job is charged the time
 * the worker spent on it. */
static void lease_overdue(gi_farm *f, gi_farm_conn *c, size_t i, gi_farm_job *j, double limit,
                          double now)
{
    gi_farm_lease l = lease_take(c, i);
    send_cancel(c, l.job_id, l.task_id);
    j->task_timeouts++;
    f->m.task_timeouts++;
    charge(j, (now - limit_from(c, &l)) - l.est_s);
    char where[GI_MSG_MAX_NAME + 16];
    snprintf(where, sizeof where, "worker %s", conn_name(c));
    gi_error e;
    gi_jobrun_timeout_error(&e, l.task_id, limit, where);
    task_failed(f, c, j, &l, &e);
}

/* The leases of c that ran past their task's time limit. */
static void stop_overdue(gi_farm *f, gi_farm_conn *c, double now)
{
    for (size_t i = 0; i < c->lease_count;) {
        const gi_farm_lease *l = &c->leases[i];
        gi_farm_job *j = running_job(f, l->job_id);
        double limit = j ? gi_jobrun_task_timeout(&j->jr, f->cfg.task_timeout_s) : 0;
        double from = limit_from(c, l);
        if (limit > 0 && from > 0 && now - from >= limit)
            lease_overdue(f, c, i, j, limit, now); /* takes lease i: the next is at i */
        else
            i++;
    }
}

void gi_farm_sched_expire(gi_farm *f, double now)
{
    for (size_t ci = 0; ci < f->conn_count; ci++) {
        gi_farm_conn *c = f->conns[ci];
        if (worker_conn(c))
            stop_overdue(f, c, now);
        for (size_t i = 0; i < c->lease_count;) {
            if (c->leases[i].deadline > now) {
                i++;
                continue;
            }
            gi_farm_lease l = lease_take(c, i);
            host_lost(f, c, now, "its leases expired: not renewed in time");
            gi_farm_job *j = running_job(f, l.job_id);
            if (!j)
                continue;
            j->lease_expiries++;
            f->m.lease_expiries++;
            charge(j, -l.est_s);
            gi_error e;
            gi_fail(&e, GI_ECRASH, "lease expired on worker %s (%s): not renewed for %.1f s",
                    conn_name(c), c->peer, f->cfg.lease_s);
            task_lost(f, c, j, &l, &e);
        }
    }
}

/* A failed job is likely to be retried once its cause is mended, and its
 * batches then save the hosts tracing them again: they are kept until it is
 * done, purged or retried no more (the hosts' 3-day sweep). */
static int batches_kept(const gi_farm_job *j)
{
    return j->keeps_batches && j->state == GI_FJ_FAILED;
}

void gi_farm_sched_welcome(gi_farm *f, gi_farm_conn *c)
{
    double since = gi_farm_wallnow() - GI_BATCH_DIR_MAX_AGE_S;
    for (size_t i = 0; i < f->job_count; i++) {
        const gi_farm_job *j = f->jobs[i];
        if (j->keeps_batches && j->ended >= since && !batches_kept(j))
            send_cancel(c, j->id, GI_MSG_ALL_TASKS);
    }
}

/* To every worker, not only those the job was sent to: one that restarted
 * since it held the job's batches hears of it too. */
static void broadcast_cancel(gi_farm *f, uint64_t id, uint64_t what)
{
    for (size_t ci = 0; ci < f->conn_count; ci++)
        if (worker_conn(f->conns[ci]))
            send_cancel(f->conns[ci], id, what);
}

void gi_farm_sched_job_over(gi_farm *f, uint64_t id) { broadcast_cancel(f, id, GI_MSG_ALL_TASKS); }

void gi_farm_sched_drop_job(gi_farm *f, gi_farm_job *j)
{
    j->suspect_count = 0; /* not judged now: their tasks run no more */
    for (size_t ci = 0; ci < f->conn_count; ci++) {
        gi_farm_conn *c = f->conns[ci];
        for (size_t i = 0; i < c->lease_count;) {
            if (c->leases[i].job_id == j->id)
                lease_take(c, i);
            else
                i++;
        }
        for (size_t i = 0; i < c->jobs_sent_count; i++)
            if (c->jobs_sent[i] == j->id) {
                c->jobs_sent[i] = c->jobs_sent[--c->jobs_sent_count];
                break;
            }
    }
    broadcast_cancel(f, j->id, batches_kept(j) ? GI_MSG_JOB_STOPPED : GI_MSG_ALL_TASKS);
}
