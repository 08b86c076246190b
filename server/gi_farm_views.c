/* gi_farm_views: what the API shows: jobs and workers as JSON, counters in
 * Prometheus' text format, and the dashboard page. Read-only over the
 * coordinator's state. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "gi_farm_impl.h"
#include "gi_progress.h"

static char *print(cJSON *doc)
{
    char *s = cJSON_PrintUnformatted(doc);
    cJSON_Delete(doc);
    if (!s)
        abort(); /* out of memory */
    return s;
}

static void add_time(cJSON *o, const char *key, double epoch)
{
    if (epoch <= 0) {
        cJSON_AddNullToObject(o, key);
        return;
    }
    char s[40];
    time_t t = (time_t)epoch;
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(s, sizeof s, "%Y-%m-%dT%H:%M:%SZ", &tm);
    cJSON_AddStringToObject(o, key, s);
}

static void add_progress(cJSON *o, const gi_progress_at *at)
{
    cJSON_AddNumberToObject(o, "progress", floor(at->fraction * 1e4) / 1e4);
    if (at->eta_s >= 0 && isfinite(at->eta_s))
        cJSON_AddNumberToObject(o, "eta_seconds", floor(at->eta_s * 10 + 0.5) / 10);
    else
        cJSON_AddNullToObject(o, "eta_seconds");
}

static cJSON *job_summary(const gi_farm_job *j)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", (double)j->id);
    cJSON_AddStringToObject(o, "name", j->name ? j->name : "?");
    cJSON_AddStringToObject(o, "method", j->method ? j->method : "?");
    cJSON_AddStringToObject(o, "state", gi_farm_job_state_name(j));
    cJSON_AddNumberToObject(o, "priority", j->priority);
    gi_progress_at at;
    gi_farm_job_progress(j, &at);
    add_progress(o, &at);
    add_time(o, "submitted", j->submitted);
    return o;
}

/* The workers excluded from the job (gi_farm_sched.c, Exclusions), now or
 * before, and whether its pending tasks wait for want of a worker. */
static void add_exclusions(const gi_farm *f, const gi_farm_job *j, cJSON *o)
{
    double now = gi_now(), wall = gi_farm_wallnow();
    cJSON *a = cJSON_AddArrayToObject(o, "excluded_workers");
    for (size_t i = 0; i < j->excl_count; i++) {
        const gi_fj_exclusion *x = &j->excl[i];
        if (!x->times)
            continue; /* a streak that has not excluded it (yet) */
        int on = x->until > now;
        cJSON *w = cJSON_CreateObject();
        cJSON_AddStringToObject(w, "worker", x->host->name);
        cJSON_AddBoolToObject(w, "excluded", on);
        cJSON_AddNumberToObject(w, "seconds", on ? x->until - now : 0);
        add_time(w, "until", wall + (x->until - now));
        cJSON_AddNumberToObject(w, "times", x->times);
        cJSON_AddNumberToObject(w, "consecutive_failures", x->streak);
        cJSON_AddStringToObject(w, "last_error", x->last_error);
        cJSON_AddItemToArray(a, w);
    }
    int waiting = j->state == GI_FJ_RUNNING && j->loaded && gi_jobrun_pending_count(&j->jr) > 0 &&
                  !gi_farm_job_has_host(f, j, now);
    cJSON_AddBoolToObject(o, "waiting_for_workers", waiting);
}

char *gi_farm_view_job(gi_farm *f, const gi_farm_job *j)
{
    cJSON *o = job_summary(j);
    cJSON_AddStringToObject(o, "file", j->file);
    add_time(o, "started", j->started);
    add_time(o, "ended", j->ended);
    add_time(o, "purge_at", gi_farm_job_purge_at(f, j)); /* --keep-ended */
    /* The first download of an output sent whole: retention purges fetched jobs first. */
    add_time(o, "fetched", j->fetched);

    uint64_t total = j->final_tasks, merged = j->final_merged, retries = j->final_retries;
    uint64_t losses = j->final_losses;
    uint64_t leased = 0, pending = 0, held = 0;
    gi_task_stats st = j->final_stats;
    if (j->loaded) {
        const gi_jobrun *jr = &j->jr;
        total = jr->task_count;
        merged = jr->merge_next;
        retries = jr->retries;
        losses = jr->losses;
        st = jr->stats;
        leased = jr->leased;
        held = jr->held;
        pending = gi_jobrun_pending_count(jr);
    }
    /* Work in the method's unit (samples, photons...), planned so far and
     * still to plan in this frame; the frame being computed, from 0. */
    gi_progress_at at;
    gi_farm_job_progress(j, &at);
    const gi_method *m = j->method ? gi_method_find(j->method) : NULL;
    cJSON_AddStringToObject(o, "unit", m ? m->unit : "");
    cJSON *work = cJSON_AddObjectToObject(o, "work");
    cJSON_AddNumberToObject(work, "done", at.done);
    cJSON_AddNumberToObject(work, "total", at.total);
    cJSON_AddNumberToObject(o, "frame", at.frame);
    cJSON_AddNumberToObject(o, "frames", at.frames);

    cJSON *t = cJSON_AddObjectToObject(o, "tasks");
    cJSON_AddNumberToObject(t, "total", (double)total);
    cJSON_AddNumberToObject(t, "merged", (double)merged);
    cJSON_AddNumberToObject(t, "held", (double)held);
    cJSON_AddNumberToObject(t, "leased", (double)leased);
    cJSON_AddNumberToObject(t, "pending", (double)pending);
    cJSON_AddNumberToObject(t, "retries", (double)retries);
    cJSON_AddNumberToObject(t, "losses", (double)losses);
    cJSON_AddNumberToObject(t, "resumed_merged", (double)j->resumed_merged);
    cJSON_AddNumberToObject(t, "results_this_run", (double)j->results_accepted);
    cJSON_AddNumberToObject(t, "late_results", (double)j->results_late);
    cJSON_AddNumberToObject(t, "lease_expiries", (double)j->lease_expiries);
    cJSON_AddNumberToObject(t, "host_disk_errors", (double)j->host_disk_errors);
    cJSON_AddNumberToObject(t, "timeouts", (double)j->task_timeouts);

    cJSON *s = cJSON_AddObjectToObject(o, "stats");
    cJSON_AddNumberToObject(s, "rays", (double)st.rays);
    cJSON_AddNumberToObject(s, "samples", (double)st.samples);
    cJSON_AddNumberToObject(s, "worker_seconds", st.seconds);
    cJSON_AddNumberToObject(s, "result_bytes", (double)j->result_bytes);
    cJSON_AddNumberToObject(s, "merged_bytes", (double)j->merged_bytes);
    cJSON_AddNumberToObject(s, "merge_seconds", j->merge_s);
    cJSON_AddNumberToObject(s, "finish_seconds", j->finish_s);

    cJSON *ck = cJSON_AddObjectToObject(o, "checkpoint");
    cJSON_AddNumberToObject(ck, "seq", (double)j->ckpt_seq);
    cJSON_AddNumberToObject(ck, "merged", (double)j->ckpt_merged);
    if (j->ckpt_error[0])
        cJSON_AddStringToObject(ck, "last_error", j->ckpt_error);
    else
        cJSON_AddNullToObject(ck, "last_error");

    if (j->state == GI_FJ_FAILED || j->state == GI_FJ_CANCELLED) {
        cJSON *e = cJSON_AddObjectToObject(o, "error");
        cJSON_AddStringToObject(e, "kind", gi_errcode_name(j->error.code));
        cJSON_AddNumberToObject(e, "exit_status", gi_error_exit_status(&j->error));
        cJSON_AddStringToObject(e, "message", j->error.msg);
    } else {
        cJSON_AddNullToObject(o, "error");
    }
    cJSON *outs = cJSON_AddArrayToObject(o, "outputs");
    if (j->state == GI_FJ_DONE)
        for (int i = 0; i < j->output_count; i++) {
            cJSON *x = cJSON_CreateObject();
            char url[400];
            snprintf(url, sizeof url, "/api/v1/jobs/%llu/outputs/%s", (unsigned long long)j->id,
                     j->outputs[i]);
            cJSON_AddStringToObject(x, "name", j->outputs[i]);
            /* As `gi render` names it; a file no spec explains, by its extension. */
            const char *kind = gi_job_output_kind(j->declared, j->declared_count, j->outputs[i]);
            const char *dot = strrchr(j->outputs[i], '.');
            cJSON_AddStringToObject(x, "kind", kind ? kind : dot ? dot + 1 : "");
            cJSON_AddStringToObject(x, "url", url);
            cJSON_AddItemToArray(outs, x);
        }
    cJSON *errs = cJSON_AddArrayToObject(o, "task_errors");
    for (int i = 0; i < j->err_count; i++) {
        const gi_fj_task_error *e = &j->errors[(j->err_start + i) % GI_FJ_ERRORS_KEEP];
        cJSON *x = cJSON_CreateObject();
        add_time(x, "time", e->when);
        cJSON_AddNumberToObject(x, "task", (double)e->task_id);
        cJSON_AddNumberToObject(x, "attempt", e->attempt);
        cJSON_AddStringToObject(x, "worker", e->worker);
        cJSON_AddStringToObject(x, "message", e->message);
        cJSON_AddItemToArray(errs, x);
    }
    add_exclusions(f, j, o);
    cJSON *log = cJSON_AddArrayToObject(o, "log");
    for (int i = 0; i < j->log_count; i++)
        cJSON_AddItemToArray(log, cJSON_CreateString(j->log[(j->log_start + i) % GI_FJ_LOG_KEEP]));
    return print(o);
}

char *gi_farm_view_jobs(gi_farm *f)
{
    cJSON *a = cJSON_CreateArray();
    for (size_t i = 0; i < f->job_count; i++)
        cJSON_AddItemToArray(a, job_summary(f->jobs[i]));
    cJSON *o = cJSON_CreateObject();
    cJSON_AddItemToObject(o, "jobs", a);
    return print(o);
}

/* A worker past its handshake: what GET /api/v1/workers and /metrics list. */
static int listed(const gi_farm_conn *c)
{
    return c->have_hello && c->state != GI_FC_HELLO && c->state != GI_FC_AUTH;
}

static const char *conn_state(const gi_farm *f, const gi_farm_conn *c, double now)
{
    if (gi_farm_host_blocked(c->host, now))
        return "blocklisted";
    switch (c->state) {
    case GI_FC_HELLO:
    case GI_FC_AUTH: return "handshake";
    case GI_FC_ACTIVE: return now - c->last_heard > 2 * f->cfg.heartbeat_s ? "silent" : "active";
    case GI_FC_DRAINING: return "draining";
    case GI_FC_CLOSING: return "closing";
    }
    return "?";
}

char *gi_farm_view_workers(gi_farm *f)
{
    double now = gi_now();
    cJSON *a = cJSON_CreateArray();
    for (size_t i = 0; i < f->conn_count; i++) {
        const gi_farm_conn *c = f->conns[i];
        if (!listed(c))
            continue;
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "id", (double)c->id);
        cJSON_AddStringToObject(o, "name", c->hello.name);
        cJSON_AddStringToObject(o, "address", c->peer);
        cJSON_AddStringToObject(o, "state", conn_state(f, c, now));
        cJSON_AddStringToObject(o, "version", c->hello.version);
        cJSON_AddNumberToObject(o, "processes", c->hello.procs);
        cJSON_AddNumberToObject(o, "slots", c->hello.slots);
        cJSON_AddNumberToObject(o, "cores", c->hello.cores);
        cJSON_AddNumberToObject(o, "memory_bytes", (double)c->hello.memory);
        cJSON_AddNumberToObject(o, "protocol", c->proto);
        cJSON_AddNumberToObject(o, "tasks_leased", (double)c->lease_count);
        size_t running = 0;
        for (size_t k = 0; k < c->lease_count; k++)
            running += c->leases[k].started > 0;
        cJSON_AddNumberToObject(o, "tasks_running", (double)running);
        cJSON_AddNumberToObject(o, "tasks_done", (double)c->tasks_done);
        cJSON_AddNumberToObject(o, "tasks_failed", (double)c->tasks_failed);
        cJSON_AddNumberToObject(o, "result_bytes", (double)c->result_bytes);
        cJSON_AddNumberToObject(o, "connected_seconds", floor(now - c->connected));
        cJSON_AddNumberToObject(o, "last_heard_seconds", floor((now - c->last_heard) * 10) / 10);
        /* Every field always (0 and "" for none), as docs/farm.md lists them. */
        const gi_farm_host *h = c->host;
        int blocked = h && gi_farm_host_blocked(h, now);
        cJSON_AddNumberToObject(o, "consecutive_failures", h ? h->consecutive_failures : 0);
        cJSON_AddNumberToObject(o, "own_failures", h ? (double)h->own_failures : 0);
        cJSON_AddNumberToObject(o, "losses", h ? (double)h->losses : 0);
        cJSON_AddNumberToObject(o, "consecutive_losses", h ? h->consecutive_losses : 0);
        cJSON_AddNumberToObject(o, "blocklisted_seconds",
                                blocked ? floor(h->blocked_until - now) : 0);
        if (h && h->last_error[0]) /* null when there is none, as in a job's view */
            cJSON_AddStringToObject(o, "last_error", h->last_error);
        else
            cJSON_AddNullToObject(o, "last_error");
        cJSON_AddItemToArray(a, o);
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddItemToObject(o, "workers", a);
    return print(o);
}

/* ---- metrics --------------------------------------------------------------- */

typedef struct mbuf {
    char *s;
    size_t len, cap;
} mbuf;

static void mprintf(mbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void mprintf(mbuf *b, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
        va_end(ap);
        if (n >= 0 && (size_t)n < b->cap - b->len) {
            b->len += (size_t)n;
            return;
        }
        b->cap = b->cap * 2 + (size_t)(n > 0 ? n : 256);
        b->s = gi_xrealloc(b->s, b->cap);
    }
}

static void counter(mbuf *b, const char *name, const char *help, double v)
{
    mprintf(b, "# HELP %s %s\n# TYPE %s counter\n%s %.17g\n", name, help, name, name, v);
}

static void gauge(mbuf *b, const char *name, const char *help, double v)
{
    mprintf(b, "# HELP %s %s\n# TYPE %s gauge\n%s %.17g\n", name, help, name, name, v);
}

char *gi_farm_view_metrics(gi_farm *f)
{
    mbuf b = {gi_xmalloc(4096), 0, 4096};
    b.s[0] = '\0';
    const gi_farm_metrics *m = &f->m;
    size_t by_state[5] = {0};
    for (size_t i = 0; i < f->job_count; i++)
        by_state[f->jobs[i]->state]++;
    mprintf(&b, "# HELP gi_farm_jobs Jobs by state.\n# TYPE gi_farm_jobs gauge\n");
    for (int s = 0; s < 5; s++)
        mprintf(&b, "gi_farm_jobs{state=\"%s\"} %zu\n", gi_fj_state_name((gi_fj_state)s), by_state[s]);
    /* The states of GET /api/v1/workers, for the workers it lists. */
    static const char *const wstates[] = {"active", "silent", "draining", "blocklisted"};
    size_t by_wstate[4] = {0}, leased = 0;
    double now = gi_now();
    for (size_t i = 0; i < f->conn_count; i++) {
        const gi_farm_conn *c = f->conns[i];
        leased += c->lease_count;
        if (!listed(c))
            continue;
        const char *st = conn_state(f, c, now);
        for (int k = 0; k < 4; k++)
            by_wstate[k] += strcmp(st, wstates[k]) == 0;
    }
    mprintf(&b, "# HELP gi_farm_workers Worker connections by state.\n# TYPE gi_farm_workers gauge\n");
    for (int k = 0; k < 4; k++)
        mprintf(&b, "gi_farm_workers{state=\"%s\"} %zu\n", wstates[k], by_wstate[k]);
    gauge(&b, "gi_farm_tasks_leased", "Tasks leased to workers now.", (double)leased);
    gauge(&b, "gi_farm_asset_store_bytes", "Bytes in the asset store.", (double)f->store_bytes);
    gauge(&b, "gi_farm_uptime_seconds", "Seconds since gi-farmd started.", gi_now() - f->started);
    size_t finishing = 0;
    for (size_t i = 0; i < f->job_count; i++)
        finishing += gi_farm_job_finishing(f->jobs[i]); /* "cancelling" ones too */
    gauge(&b, "gi_farm_jobs_finishing",
          "Running jobs whose finish (their outputs) runs on its thread now.", (double)finishing);
    gauge(&b, "gi_farm_loop_stall_seconds",
          "The coordinator loop's longest round (time out of poll: no merge, lease or answer "
          "meanwhile) in the last 60 s.",
          gi_farm_loop_stall(f, now));
    gauge(&b, "gi_farm_loop_stall_max_seconds",
          "The coordinator loop's longest round since gi-farmd started.", f->stall_max_ever);
    counter(&b, "gi_farm_jobs_submitted_total", "Jobs accepted.", (double)m->jobs_submitted);
    counter(&b, "gi_farm_jobs_done_total", "Jobs finished.", (double)m->jobs_done);
    counter(&b, "gi_farm_jobs_failed_total", "Jobs failed.", (double)m->jobs_failed);
    counter(&b, "gi_farm_jobs_cancelled_total", "Jobs cancelled.", (double)m->jobs_cancelled);
    counter(&b, "gi_farm_jobs_retried_total", "Failed or cancelled jobs run again (gi retry).",
            (double)m->jobs_retried);
    counter(&b, "gi_farm_task_leases_total", "Tasks handed to workers.", (double)m->tasks_leased);
    counter(&b, "gi_farm_task_results_total", "Task results accepted and merged in order.",
            (double)m->task_results);
    counter(&b, "gi_farm_task_failures_total", "Task failures reported (or results refused).",
            (double)m->task_failures);
    counter(&b, "gi_farm_tasks_lost_total",
            "Task runs lost with their host (connection lost, lease expired): requeued.",
            (double)m->tasks_lost);
    counter(&b, "gi_farm_host_losses_total",
            "Hosts lost with tasks held (connection lost, leases expired), once per loss "
            "however many tasks: they count towards blocklisting.",
            (double)m->host_losses);
    counter(&b, "gi_farm_job_exclusions_total",
            "Workers excluded from one job (not blocklisted) for failing its tasks in a row.",
            (double)m->job_exclusions);
    counter(&b, "gi_farm_task_failures_host_total",
            "Task failures judged the host's (they count towards blocklisting): the task then "
            "ran on another host, and its job fails on no other host that works; or its disk's.",
            (double)m->failures_host);
    counter(&b, "gi_farm_task_failures_job_total",
            "Task failures judged the job's: the task then ran on another host, but its job "
            "fails on other hosts that work too.",
            (double)m->failures_job);
    counter(&b, "gi_farm_late_results_total", "Results and failures discarded: lease no longer held.",
            (double)m->late_results);
    counter(&b, "gi_farm_lease_expiries_total", "Leases that expired.", (double)m->lease_expiries);
    counter(&b, "gi_farm_task_timeouts_total",
            "Task runs stopped for running longer than their task_timeout: failed.",
            (double)m->task_timeouts);
    counter(&b, "gi_farm_tasks_requeued_total", "Tasks handed back unrun.", (double)m->requeued);
    counter(&b, "gi_farm_result_bytes_total", "Bytes of result data accepted.", (double)m->result_bytes);
    counter(&b, "gi_farm_merged_bytes_total", "Bytes of result data merged.", (double)m->merged_bytes);
    counter(&b, "gi_farm_merge_seconds_total", "Coordinator time in the methods' merge.", m->merge_s);
    counter(&b, "gi_farm_finish_seconds_total",
            "Time in the methods' finish (outputs), on its thread.",
            m->finish_s);
    counter(&b, "gi_farm_checkpoints_total", "Checkpoints written.", (double)m->checkpoints);
    counter(&b, "gi_farm_checkpoint_failures_total", "Checkpoints that could not be written.",
            (double)m->checkpoint_failures);
    counter(&b, "gi_farm_checkpoint_bytes_total", "Bytes of checkpoints written.",
            (double)m->checkpoint_bytes);
    counter(&b, "gi_farm_workers_accepted_total", "Worker connections authenticated.",
            (double)m->workers_accepted);
    counter(&b, "gi_farm_workers_refused_total", "Worker connections refused.",
            (double)m->workers_refused);
    counter(&b, "gi_farm_worker_handshakes_displaced_total",
            "Unauthenticated worker connections closed to make room for newer ones.",
            (double)m->handshakes_displaced);
    counter(&b, "gi_farm_frames_refused_total", "Malformed or oversized frames refused.",
            (double)m->frames_refused);
    counter(&b, "gi_farm_api_requests_total", "HTTP API requests.", (double)m->api_requests);
    counter(&b, "gi_farm_api_refused_auth_total", "API requests refused: no or wrong token.",
            (double)m->api_refused_auth);
    counter(&b, "gi_farm_api_refused_input_total", "API requests refused: bad input or limits.",
            (double)m->api_refused_input);
    counter(&b, "gi_farm_api_slow_closed_total",
            "API connections closed for not sending a request head in time.",
            (double)m->api_slow_closed);
    counter(&b, "gi_farm_api_conns_shed_total",
            "API connections closed to keep a slot free: the longest idle, a request behind "
            "--api-min-rate, or a new one over the limit.",
            (double)m->api_conns_shed);
    counter(&b, "gi_farm_api_slow_requests_closed_total",
            "API connections closed for a request that fell --api-request-seconds behind "
            "--api-min-rate.",
            (double)m->api_slow_requests);
    counter(&b, "gi_farm_assets_uploaded_total", "Assets uploaded.", (double)m->assets_uploaded);
    counter(&b, "gi_farm_asset_bytes_uploaded_total", "Bytes of assets uploaded.",
            (double)m->asset_bytes_uploaded);
    counter(&b, "gi_farm_assets_served_total", "Assets sent to workers.", (double)m->assets_served);
    return b.s;
}

/* ---- dashboard ------------------------------------------------------------- */

/* Static: holds no data. Its script asks for the API token once (kept in
 * the tab's sessionStorage) and reads the same JSON API as everyone else. */
const char gi_farm_dashboard_html[] =
    "<!doctype html><html><head><meta charset=\"utf-8\"><title>gi-farm</title>\n"
    "<style>body{font:14px sans-serif;margin:2em}table{border-collapse:collapse;margin-bottom:2em}"
    "td,th{border-bottom:1px solid #ddd;padding:4px 10px;text-align:left}"
    ".bar{background:#eee;width:160px;height:10px}.bar div{background:#4a8;height:10px}</style>\n"
    "</head><body><h1>gi-farm</h1><h2>Jobs</h2><table id=\"jobs\"></table>"
    "<h2>Workers</h2><table id=\"workers\"></table><p id=\"msg\"></p>\n"
    "<script>\n"
    "function tok(){let t=sessionStorage.getItem('gi-token');"
    "if(!t){t=prompt('API token');sessionStorage.setItem('gi-token',t||'');}return t;}\n"
    "function esc(s){return String(s).replace(/[&<>\"]/g,c=>({'&':'&amp;','<':'&lt;','>':'&gt;','\"':'&quot;'}[c]));}\n"
    "async function get(u){const r=await fetch(u,{headers:{Authorization:'Bearer '+tok()}});"
    "if(r.status==401){sessionStorage.removeItem('gi-token');throw 'token refused';}return r.json();}\n"
    "function row(cells,h){return '<tr>'+cells.map(c=>(h?'<th>':'<td>')+c+(h?'</th>':'</td>')).join('')+'</tr>';}\n"
    "async function refresh(){try{\n"
    "const j=await get('/api/v1/jobs');let h=row(['id','name','method','state','priority','progress','ETA'],1);\n"
    "for(const x of j.jobs)h+=row([x.id,esc(x.name),esc(x.method),x.state,x.priority,"
    "'<div class=\"bar\"><div style=\"width:'+(100*x.progress).toFixed(1)+'%\"></div></div>',"
    "x.eta_seconds==null?'':x.eta_seconds.toFixed(0)+' s']);\n"
    "document.getElementById('jobs').innerHTML=h;\n"
    "const w=await get('/api/v1/workers');h=row(['name','address','state','processes','leased','done','failed'],1);\n"
    "for(const x of w.workers)h+=row([esc(x.name),esc(x.address),x.state,x.processes,x.tasks_leased,x.tasks_done,x.tasks_failed]);\n"
    "document.getElementById('workers').innerHTML=h;document.getElementById('msg').textContent='';\n"
    "}catch(e){document.getElementById('msg').textContent=String(e);}}\n"
    "refresh();setInterval(refresh,2000);\n"
    "</script></body></html>\n";
