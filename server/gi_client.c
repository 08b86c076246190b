/* gi_client: farm commands of `gi` (submit, status, wait, cancel, jobs,
 * workers, fetch) over the HTTP/JSON API. */
#include "gi_client.h"

#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "gi_args.h"
#include "gi_auth.h"
#include "gi_farm_submit.h"
#include "gi_fs.h"
#include "gi_http_client.h"
#include "gi_job.h"
#include "gi_log.h"
#include "gi_progress.h"

#define MAX_JSON_BODY ((uint64_t)64 << 20)
#define POLL_S 0.1     /* the longest wait between two looks at a job */
#define POLL_MIN_S 0.01 /* the shortest, once the job is about to end */
/* gi wait asks a farm that answered it and then went silent (a restart)
 * again this long. */
#define WAIT_UNANSWERED_S 300.0
/* A farm that refuses a connection, resets it or answers 503 (busy: its
 * connection limit, 1000 clients at once) is asked again this long (unless
 * --retry says otherwise), with a backoff from RETRY_FIRST_S doubling up to
 * RETRY_MAX_S, each pause jittered so that clients turned away together do
 * not return together. */
#define RETRY_S 60.0
#define RETRY_LIMIT_S 86400.0
#define RETRY_FIRST_S 0.1
#define RETRY_MAX_S 2.0

const char gi_client_usage[] =
    "       gi submit JOB.json [--priority N] [--wait] [--out DIR] [--progress MODE]\n"
    "       gi status ID [--json] | gi jobs [--json] | gi workers [--json]\n"
    "       gi wait ID [--out DIR] [--progress MODE] | gi cancel ID | gi fetch ID [--out DIR]\n"
    "       gi retry ID [--wait] [--out DIR] [--progress MODE]  (a failed or cancelled job)\n"
    "       gi purge ID  (an ended job: removes it, its checkpoint and its outputs)\n"
    "         (farm commands take --farm URL (default $GI_FARM or http://127.0.0.1:7070),\n"
    "          read the API token from --token-file FILE, $GI_FARM_TOKEN_FILE or $GI_FARM_TOKEN,\n"
    "          and ask a farm that cannot be reached or is busy again for --retry S seconds\n"
    "          (default 60; 0: fail at once; gi wait: 300 once the farm has answered it))\n";

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    interrupted = 1;
}

typedef struct client {
    gi_http_url url;
    const char *farm, *farm_from; /* the URL as given, and where it came from */
    double retry_s;               /* --retry */
    int retry_given;
    char token[GI_SECRET_MAX_BYTES + 1];
    /* Options. */
    const char *out_dir, *progress;
    gi_progress_mode mode; /* progress, parsed */
    int json, wait;
    int64_t priority;
    const char *arg; /* the command's operand (job file or id) */
    gi_job job;      /* submit: arg, loaded and checked before the farm is asked */
    /* The submission's Idempotency-Key while it is being sent (else NULL). */
    const char *idempotency_key;
    int said_retrying; /* stderr said once that the farm is asked again */
} client;

/* The options each command takes (--farm and --token-file: all). */
enum { OPT_OUT = 1, OPT_PROGRESS = 2, OPT_PRIORITY = 4, OPT_WAIT = 8, OPT_JSON = 16 };
static const char *const commands[] = {"submit", "status",  "wait",  "cancel", "retry",
                                       "jobs",   "workers", "fetch", "purge",  NULL};
static const unsigned command_options[] = {
    OPT_PRIORITY | OPT_WAIT | OPT_OUT | OPT_PROGRESS, OPT_JSON, OPT_OUT | OPT_PROGRESS, 0,
    OPT_WAIT | OPT_OUT | OPT_PROGRESS, OPT_JSON, OPT_JSON, OPT_OUT, 0};

int gi_client_is_command(const char *cmd)
{
    for (int i = 0; commands[i]; i++)
        if (strcmp(cmd, commands[i]) == 0)
            return 1;
    return 0;
}

static int fail_msg(int status, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static int fail_msg(int status, const char *fmt, ...)
{
    char line[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    gi_say("%s", line);
    return status;
}

/* ---- requests ------------------------------------------------------------ */

/* The message of an {"error": ...} body, or the body itself. */
static void error_text(const gi_buf *body, char *out, size_t n)
{
    cJSON *doc = cJSON_ParseWithLength((const char *)body->data, body->len);
    const cJSON *e = doc ? cJSON_GetObjectItemCaseSensitive(doc, "error") : NULL;
    if (cJSON_IsString(e))
        snprintf(out, n, "%s", e->valuestring);
    else
        snprintf(out, n, "%.*s", (int)(body->len < 300 ? body->len : 300), (const char *)body->data);
    cJSON_Delete(doc);
    out[strcspn(out, "\n")] = '\0';
}

/* Exit status for an HTTP failure: 2 for the caller's input, 1 otherwise. */
static int http_failure(const client *c, const char *what, int status, const gi_buf *body)
{
    char msg[1200];
    error_text(body, msg, sizeof msg);
    if (status == 401)
        return fail_msg(1, "%s: gi-farmd at %s (%s) refused the API token: %s (give the token "
                        "gi-farmd was started with: its --token-file)", what, c->farm,
                        c->farm_from, msg);
    /* A job id from another farm ($GI_FARM, --farm) or one purged. */
    if (status == 404 && strncmp(what, "/api/v1/jobs/", 13) == 0)
        return fail_msg(1, "%s: %s (HTTP 404 from the farm at %s; `gi jobs` lists its jobs)", what,
                        msg, c->url.hostport);
    return fail_msg(status == 400 ? 2 : 1, "%s: %s (HTTP %d)", what, msg, status);
}

/* One try. */
static int request_once(client *c, const char *method, const char *path, const void *body,
                        size_t len, const char *type, gi_buf *resp, const char *to_file,
                        gi_error *err)
{
    gi_http_request rq = {method, path, c->token, body, len, type, 60.0, c->idempotency_key};
    return gi_http_do(&c->url, &rq, resp, MAX_JSON_BODY, to_file, err);
}

/* The pause before the next try: *next (jittered into [next/2, next]),
 * then *next doubles up to max_s. */
static double backoff(double *next, double max_s)
{
    uint32_t r;
    gi_auth_random(&r, sizeof r);
    double s = *next * (0.5 + 0.5 * (double)r / 4294967295.0);
    *next = *next * 2 > max_s ? max_s : *next * 2;
    return s;
}

static void sleep_s(double s);

/* Whether a failed try may be made again: a request that did not reach the
 * farm whole, and a 503 (refused, nothing done), always; one that may have
 * been acted on (the connection broke after it went) only if a second one
 * changes nothing: GET, HEAD, PUT of an asset by its hash, and a
 * submission carrying its Idempotency-Key. Not DELETE or a retry's POST:
 * a second cancel of a job the first one cancelled would fail. */
static int may_retry(const client *c, const char *method, int status)
{
    if (status == GI_HTTP_UNSENT || status == 503)
        return 1;
    if (status != GI_HTTP_FAILED)
        return 0;
    return strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0 ||
           strcmp(method, "PUT") == 0 || (strcmp(method, "POST") == 0 && c->idempotency_key);
}

/* Says at once that the farm does not answer, and for how long it is
 * asked again: a newcomer's farm that is not running must not look like a
 * hang. what: "cannot be reached", "is busy", ... */
static void say_retrying(client *c, const char *what, const char *why, double for_s)
{
    if (for_s > 0)
        gi_say("gi-farmd at %s (%s) %s: %s; asking again for up to %g s, in case it is "
               "restarting (--retry S: how long)", c->farm, c->farm_from, what, why, for_s);
    c->said_retrying = 1;
}

/* The message of a farm given up on: err (a connection failure) is
 * rewritten to say what to do. */
static void gave_up(const client *c, double asked_s, gi_error *err)
{
    char why[sizeof err->msg], asked[64] = "";
    snprintf(why, sizeof why, "%s", err->msg);
    if (asked_s > 0)
        snprintf(asked, sizeof asked, ", asked again for %g s", asked_s);
    gi_fail(err, GI_EIO,
            "gi-farmd at %s (%s) cannot be reached (%s)%s: is it running? Start it (gi-farmd "
            "--state DIR ...; docs/farm.md, Quick start), or give its URL with --farm URL or "
            "$GI_FARM",
            c->farm, c->farm_from, why, asked);
}

/* A request, tried again for up to c->retry_s while may_retry says so. */
static int request(client *c, const char *method, const char *path, const void *body, size_t len,
                   const char *type, gi_buf *resp, const char *to_file, gi_error *err)
{
    double t0 = gi_now(), next = RETRY_FIRST_S;
    for (;;) {
        int st = request_once(c, method, path, body, len, type, resp, to_file, err);
        if (!may_retry(c, method, st) || interrupted)
            return st;
        double pause = backoff(&next, RETRY_MAX_S);
        if (gi_now() + pause - t0 > c->retry_s) {
            if (st == GI_HTTP_UNSENT)
                gave_up(c, c->retry_s, err);
            return st;
        }
        if (!c->said_retrying) {
            char why[1200];
            if (st == 503) {
                memcpy(why, "HTTP 503: ", 10);
                error_text(resp, why + 10, sizeof why - 10);
            }
            say_retrying(c,
                         st == 503              ? "is busy"
                         : st == GI_HTTP_UNSENT ? "cannot be reached"
                                                : "broke the connection",
                         st == 503 ? why : err->msg, c->retry_s);
        }
        sleep_s(pause);
    }
}

/* A request that must answer `want` (or also `want2` when non-zero): 0, or
 * the exit status with the message printed. The body is left in *resp. */
static int call(client *c, const char *method, const char *path, const void *body, size_t len,
                const char *type, int want, int want2, gi_buf *resp, const char *to_file)
{
    gi_error err;
    int st = request(c, method, path, body, len, type, resp, to_file, &err);
    if (st < 0)
        return fail_msg(1, "%s", err.msg);
    if (st != want && (!want2 || st != want2))
        return http_failure(c, path, st, resp);
    return 0;
}

/* GET path as JSON: 0 with *doc, else the exit status (message printed). */
static int get_json(client *c, const char *path, cJSON **doc)
{
    gi_buf b;
    gi_buf_init(&b);
    int rc = call(c, "GET", path, NULL, 0, NULL, 200, 0, &b, NULL);
    if (rc == 0 && !(*doc = cJSON_ParseWithLength((const char *)b.data, b.len)))
        rc = fail_msg(1, "%s: the farm's answer is not JSON", path);
    gi_buf_free(&b);
    return rc;
}

static int get_job(client *c, uint64_t id, cJSON **doc)
{
    char path[64];
    snprintf(path, sizeof path, "/api/v1/jobs/%llu", (unsigned long long)id);
    return get_json(c, path, doc);
}

/* gi wait's look at a job: 0 with *doc; -1 if the farm did not answer (it
 * may be restarting: no connection, a timeout, a 5xx), with why; else the
 * exit status, the message printed. */
static int look_at_job(client *c, uint64_t id, cJSON **doc, char *why, size_t n)
{
    char path[64];
    snprintf(path, sizeof path, "/api/v1/jobs/%llu", (unsigned long long)id);
    gi_buf b;
    gi_buf_init(&b);
    gi_error err;
    /* One try: wait_job asks a farm that does not answer again itself. */
    int st = request_once(c, "GET", path, NULL, 0, NULL, &b, NULL, &err), rc = 0;
    if (st < 0 || st >= 500) {
        if (st < 0)
            snprintf(why, n, "%s", err.msg);
        else
            snprintf(why, n, "HTTP %d", st);
        rc = -1;
    } else if (st != 200) {
        rc = http_failure(c, path, st, &b);
    } else if (!(*doc = cJSON_ParseWithLength((const char *)b.data, b.len))) {
        rc = fail_msg(1, "%s: the farm's answer is not JSON", path);
    }
    gi_buf_free(&b);
    return rc;
}

static double num(const cJSON *o, const char *k, double dflt)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsNumber(v) ? v->valuedouble : dflt;
}

/* A count from the farm's JSON, clamped into uint32_t. */
static uint32_t count(const cJSON *o, const char *k, uint32_t dflt)
{
    double v = num(o, k, dflt);
    return v >= 0 && v <= UINT32_MAX ? (uint32_t)v : dflt;
}

static const char *str(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsString(v) ? v->valuestring : "";
}

static int print_json(const cJSON *doc)
{
    char *s = cJSON_Print(doc);
    printf("%s\n", s ? s : "null");
    cJSON_free(s);
    return 0;
}

static int parse_id(const char *s, uint64_t *id)
{
    int64_t v;
    if (!s || gi_args_int(s, 1, INT64_MAX, &v))
        return -1;
    *id = (uint64_t)v;
    return 0;
}

/* ---- fetch ------------------------------------------------------------------ */

static int fetch_outputs(client *c, uint64_t id, const cJSON *job)
{
    gi_error err;
    if (gi_output_dir_ready(c->out_dir, &err))
        return fail_msg(1, "--out: %s", err.msg);
    gi_remove_stale_temps(c->out_dir); /* of a fetch killed while writing */
    const cJSON *outs = cJSON_GetObjectItemCaseSensitive(job, "outputs");
    int n = 0;
    for (const cJSON *o = outs ? outs->child : NULL; o; o = o->next) {
        const char *name = str(o, "name");
        /* The farm names outputs as the job does: plain file names. Refuse
         * anything else rather than write outside --out. */
        if (!name[0] || strchr(name, '/') || name[0] == '.')
            return fail_msg(1, "job %llu: refusing output name \"%s\"", (unsigned long long)id,
                            name);
        char path[512], *dest = gi_path_join(c->out_dir, name);
        snprintf(path, sizeof path, "/api/v1/jobs/%llu/outputs/%s", (unsigned long long)id, name);
        gi_buf b;
        gi_buf_init(&b);
        int rc = call(c, "GET", path, NULL, 0, NULL, 200, 0, &b, dest);
        const char *kind = str(o, "kind");
        if (rc == 0)
            printf("  %-4s %s\n", kind, dest);
        if (rc == 0 && c->mode == GI_PROGRESS_JSON)
            gi_progress_json_output(stderr, str(job, "name"), kind, dest);
        gi_buf_free(&b);
        free(dest);
        if (rc)
            return rc;
        n++;
    }
    if (n == 0)
        return fail_msg(1, "job %llu has no outputs to fetch", (unsigned long long)id);
    return 0;
}

/* ---- wait --------------------------------------------------------------------- */

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

/* The wait before the next look at a job: shorter as its end nears (the
 * client's latency adds to every job's wall time), never a busy loop. */
static double poll_wait(const cJSON *job, double last)
{
    const cJSON *eta = cJSON_GetObjectItemCaseSensitive(job, "eta_seconds");
    double next = cJSON_IsNumber(eta) ? 0.5 * eta->valuedouble : 2.0 * last;
    return next < POLL_MIN_S ? POLL_MIN_S : next > POLL_S ? POLL_S : next;
}

/* Exit status for a job that ended without success (the message says how
 * to run it again, unless its input was refused). */
static int job_failed(uint64_t id, const cJSON *job)
{
    const char *state = str(job, "state");
    const cJSON *e = cJSON_GetObjectItemCaseSensitive(job, "error");
    int status = (int)num(e, "exit_status", 1);
    /* A cancel's message says "cancelled: why": not "cancelled: cancelled: why". */
    const char *msg = str(e, "message");
    size_t n = strlen(state);
    if (n && strncmp(msg, state, n) == 0 && strncmp(msg + n, ": ", 2) == 0)
        msg += n + 2;
    if (status == 2)
        return fail_msg(2, "job %llu %s: %s", (unsigned long long)id, state, msg);
    const cJSON *ck = cJSON_GetObjectItemCaseSensitive(job, "checkpoint");
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(job, "tasks");
    double merged = num(ck, "merged", 0);
    char again[128];
    if (merged > 0)
        snprintf(again, sizeof again, "from its last checkpoint (%.0f of %.0f tasks merged)",
                 merged, num(t, "total", 0));
    else
        snprintf(again, sizeof again, "from the start");
    return fail_msg(1, "job %llu %s: %s; `gi retry %llu` runs it again %s",
                    (unsigned long long)id, state, msg, (unsigned long long)id,
                    again);
}

static int ended(const char *state)
{
    return strcmp(state, "done") == 0 || strcmp(state, "failed") == 0 ||
           strcmp(state, "cancelled") == 0;
}

/* before: the job had ended when the wait began (it says when). */
static void print_summary(uint64_t id, const cJSON *job, int before)
{
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(job, "tasks");
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(job, "stats");
    char a[32], b[32];
    printf("%s: job %llu (%s) done on the farm", str(job, "name"), (unsigned long long)id,
           str(job, "method"));
    if (before)
        printf(" already%s%s", str(job, "ended")[0] ? ", at " : "", str(job, "ended"));
    printf("\n");
    printf("  %s%s, ", gi_si(num(s, "samples", 0), a, sizeof a), str(job, "unit"));
    if (strcmp(str(job, "unit"), "rays") != 0) /* radiosity's unit is rays already */
        printf("%srays, ", gi_si(num(s, "rays", 0), b, sizeof b));
    printf("%.0f task%s", num(t, "total", 0), num(t, "total", 0) == 1 ? "" : "s");
    if (num(t, "retries", 0) > 0)
        printf(", %.0f retried", num(t, "retries", 0));
    printf("\n");
}

/* Polls the job until it ends (showing progress), then fetches its outputs. */
/* fresh: the job was just submitted or retried by this command (so it never
 * ended "already"). */
static int wait_job(client *c, uint64_t id, int fetch, int fresh)
{
    gi_progress prog;
    int started = 0;
    struct sigaction sa, old;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, &old);
    int rc;
    double wait = POLL_MIN_S, t_start = gi_now(), unanswered = -1, retry = 0.5;
    int answered = 0; /* the farm answered this wait once */
    int ended_before = 0; /* the job had ended when the farm first answered */
    int said_waiting = 0; /* that the job waits for a worker, since it last did not */
    char jname[256] = ""; /* the job's name, once the farm said it */
    for (;;) {
        cJSON *job = NULL;
        char why[1100];
        rc = look_at_job(c, id, &job, why, sizeof why);
        if (rc < 0 && !interrupted) {
            /* A coordinator restarting (or a network hiccup) is waited for:
             * the job goes on, and resumes with it. One never reached by
             * this wait may not run at all: it is asked as long as any
             * request is, and then said so. */
            double now = gi_now();
            double limit = answered && !c->retry_given ? WAIT_UNANSWERED_S : c->retry_s;
            int unreachable = !answered && strncmp(why, "HTTP ", 5) != 0;
            if (unanswered < 0) {
                unanswered = now;
                if (started)
                    gi_progress_end(&prog);
                /* Its requests need not say it again. */
                say_retrying(c, unreachable ? "cannot be reached" : "does not answer", why, limit);
            }
            if (now - unanswered < limit) {
                sleep_s(backoff(&retry, 5.0));
                continue;
            }
            if (unreachable) {
                gi_error e;
                gi_fail(&e, GI_EIO, "%s", why);
                gave_up(c, limit, &e);
                gi_say("%s", e.msg);
            } else {
                gi_say("the farm has not answered for %.0f s (%s); job %llu goes on there when "
                       "it is back (gi wait %llu)",
                       now - unanswered, why, (unsigned long long)id, (unsigned long long)id);
            }
            if (c->mode == GI_PROGRESS_JSON)
                gi_progress_json_end(stderr, jname, "unreachable", gi_now() - t_start, why);
            rc = 1;
            break;
        }
        if (rc < 0) {
            rc = 130;
            gi_say("interrupted; job %llu goes on on the farm (gi wait %llu)",
                   (unsigned long long)id, (unsigned long long)id);
            break;
        }
        if (rc)
            break;
        if (unanswered >= 0)
            gi_say("the farm answers again");
        unanswered = -1;
        ended_before = !fresh && !answered && ended(str(job, "state"));
        answered = 1;
        retry = 0.5;
        const char *state = str(job, "state");
        snprintf(jname, sizeof jname, "%s", str(job, "name"));
        const cJSON *work = cJSON_GetObjectItemCaseSensitive(job, "work");
        const cJSON *stats = cJSON_GetObjectItemCaseSensitive(job, "stats");
        int end = ended(state);
        /* A job that had ended before the wait gets no progress line: its
         * rate over no time would be a meaningless 0. */
        if (!started && !end && strcmp(state, "checking") != 0) {
            static char name[256], unit[64];
            snprintf(name, sizeof name, "%s", str(job, "name"));
            snprintf(unit, sizeof unit, "%s", str(job, "unit"));
            gi_progress_init(&prog, c->mode, stderr, name, unit);
            started = 1;
        }
        if (started) {
            const cJSON *eta = cJSON_GetObjectItemCaseSensitive(job, "eta_seconds");
            gi_progress_at at = {
                .fraction = num(job, "progress", 0),
                .eta_s = cJSON_IsNumber(eta) ? eta->valuedouble : -1,
                .done = num(work, "done", 0),
                .total = num(work, "total", 1),
                .samples = num(stats, "samples", 0),
                .rays = num(stats, "rays", 0),
                .frame = count(job, "frame", 0),
                .frames = count(job, "frames", 1),
            };
            gi_progress_update(&prog, &at, end);
        }
        if (end) {
            if (started)
                gi_progress_end(&prog);
            if (strcmp(state, "done") != 0) {
                rc = job_failed(id, job);
            } else {
                print_summary(id, job, ended_before);
                rc = fetch ? fetch_outputs(c, id, job) : 0;
            }
            if (c->mode == GI_PROGRESS_JSON) {
                /* A done job whose outputs could not be fetched ends failed here. */
                int done = strcmp(state, "done") == 0;
                const cJSON *e = cJSON_GetObjectItemCaseSensitive(job, "error");
                gi_progress_json_end(stderr, str(job, "name"), done && rc ? "failed" : state,
                                     gi_now() - t_start,
                                     !done ? str(e, "message")
                                     : rc  ? "the outputs could not be fetched"
                                           : NULL);
            }
            cJSON_Delete(job);
            break;
        }
        /* Else a farm without a worker (none started, all blocklisted)
         * shows a progress stuck at 0 and says nothing. */
        int waiting = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(job, "waiting_for_workers"));
        if (waiting && !said_waiting) {
            if (started)
                gi_progress_end(&prog);
            gi_say("job %llu waits: no connected worker may take its tasks now (none connected, "
                   "or excluded from it or blocklisted: gi workers, gi status %llu)",
                   (unsigned long long)id, (unsigned long long)id);
        }
        said_waiting = waiting;
        wait = poll_wait(job, wait);
        cJSON_Delete(job);
        if (interrupted) {
            if (started)
                gi_progress_end(&prog);
            gi_say("interrupted; job %llu goes on on the farm (gi wait %llu)",
                   (unsigned long long)id, (unsigned long long)id);
            rc = 130;
            break;
        }
        sleep_s(wait);
    }
    sigaction(SIGINT, &old, NULL);
    return rc;
}

/* ---- submit ------------------------------------------------------------------- */

static int upload_assets(client *c, const gi_job *job)
{
    for (size_t i = 0; i < job->manifest.count; i++) {
        const gi_manifest_entry *e = &job->manifest.entries[i];
        char path[128];
        snprintf(path, sizeof path, "/api/v1/assets/%s", e->hash);
        gi_buf b;
        gi_buf_init(&b);
        gi_error err;
        int st = request(c, "HEAD", path, NULL, 0, NULL, &b, NULL, &err);
        int rc = st < 0                    ? fail_msg(1, "%s", err.msg)
                 : st == 200 || st == 404 ? 0
                                          : http_failure(c, path, st, &b);
        if (rc == 0 && st == 404) {
            const gi_buf *bytes = job->assets ? gi_asset_store_get(job->assets, e->hash) : NULL;
            if (!bytes)
                rc = fail_msg(1, "%s: the bytes of %s are not loaded", job->file, e->name);
            else if ((rc = call(c, "PUT", path, bytes->data, bytes->len, "application/octet-stream",
                                201, 200, &b, NULL)) == 0)
                gi_say("uploaded %s (%zu bytes)", e->name, bytes->len);
        }
        gi_buf_free(&b);
        if (rc)
            return rc;
    }
    return 0;
}

/* The job file, checked as gi validate checks it (and with --wait, the
 * outputs against its inputs): all that needs no farm, so it comes before
 * the token and the connection, and a bad job never reaches the farm. */
static int submit_check(client *c)
{
    gi_error err;
    if (gi_job_load(c->arg, &c->job, &err) ||
        (c->wait && gi_job_outputs_spare_inputs(&c->job, c->arg, c->out_dir, &err)))
        return fail_msg(gi_error_exit_status(&err), "%s", err.msg);
    return 0;
}

static int cmd_submit(client *c)
{
    const gi_job *job = &c->job;
    int rc = upload_assets(c, job);
    uint64_t id = 0;
    if (rc == 0) {
        const char *base = strrchr(c->arg, '/');
        gi_buf body, resp;
        gi_buf_init(&body);
        gi_buf_init(&resp);
        gi_farm_submission_build(&body, base ? base + 1 : c->arg, job->text, &job->manifest,
                                 (uint32_t)c->priority);
        /* Sent again after a connection broken before its answer, the
         * submission makes no second job: the farm knows it by this key. */
        uint8_t raw[16];
        char key[2 * sizeof raw + 1];
        gi_auth_random(raw, sizeof raw);
        for (size_t i = 0; i < sizeof raw; i++)
            snprintf(key + 2 * i, 3, "%02x", raw[i]);
        c->idempotency_key = key;
        rc = call(c, "POST", "/api/v1/jobs", body.data, body.len, "application/json", 201, 200,
                  &resp, NULL);
        c->idempotency_key = NULL;
        if (rc == 0) {
            cJSON *doc = cJSON_ParseWithLength((const char *)resp.data, resp.len);
            id = (uint64_t)num(doc, "id", 0);
            cJSON_Delete(doc);
            if (!id)
                rc = fail_msg(1, "the farm's answer has no job id");
        }
        gi_buf_free(&body);
        gi_buf_free(&resp);
    }
    gi_job_free(&c->job); /* its scene and assets are not held while waiting */
    if (rc)
        return rc;
    gi_say("submitted %s as job %llu", c->arg, (unsigned long long)id);
    if (c->wait)
        return wait_job(c, id, 1, 1);
    /* Wait for the farm's own scene check, so a scene it refuses is an
     * error here rather than a surprise later. */
    for (;;) {
        cJSON *doc = NULL;
        if ((rc = get_job(c, id, &doc)) != 0)
            return rc;
        const char *state = str(doc, "state");
        if (strcmp(state, "checking") != 0) {
            if (strcmp(state, "failed") == 0)
                rc = job_failed(id, doc);
            cJSON_Delete(doc);
            break;
        }
        cJSON_Delete(doc);
        sleep_s(0.1);
    }
    if (rc == 0)
        printf("%llu\n", (unsigned long long)id);
    return rc;
}

/* ---- the other commands ---------------------------------------------------------- */

/* The workers excluded from a job for failing its tasks, and whether its
 * tasks wait for want of a worker: why a job makes no progress. */
static void print_exclusions(const cJSON *job)
{
    const cJSON *xs = cJSON_GetObjectItemCaseSensitive(job, "excluded_workers");
    int running = strcmp(str(job, "state"), "running") == 0;
    for (const cJSON *x = xs ? xs->child : NULL; x; x = x->next) {
        if (cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(x, "excluded")) && running)
            printf("  worker %s excluded from this job until %s (%.0f s more); last: %s\n",
                   str(x, "worker"), str(x, "until"), num(x, "seconds", 0), str(x, "last_error"));
        else
            printf("  worker %s was excluded from this job (until %s); last: %s\n",
                   str(x, "worker"), str(x, "until"), str(x, "last_error"));
    }
    if (cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(job, "waiting_for_workers")))
        printf("  waiting: no connected worker may take its tasks now (excluded from it, "
               "blocklisted, or none)\n");
}

/* A job's ETA, or -1: an ended job has none (the API's 0 for a done one
 * would read as "any moment now"). */
static double running_eta(const cJSON *job)
{
    return ended(str(job, "state")) ? -1 : num(job, "eta_seconds", -1);
}

static int cmd_status(client *c, uint64_t id)
{
    cJSON *job = NULL;
    int rc = get_job(c, id, &job);
    if (rc)
        return rc;
    if (c->json) {
        print_json(job);
        cJSON_Delete(job);
        return 0;
    }
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(job, "tasks");
    char eta[32];
    double e = running_eta(job);
    printf("job %llu: %s (%s), %s, priority %.0f\n", (unsigned long long)id, str(job, "name"),
           str(job, "method"), str(job, "state"), num(job, "priority", 0));
    printf("  progress %.1f%%%s%s\n", 100.0 * num(job, "progress", 0), e >= 0 ? ", ETA " : "",
           e >= 0 ? gi_duration(e, eta, sizeof eta) : "");
    printf("  tasks: %.0f total, %.0f merged, %.0f leased, %.0f pending, %.0f retries",
           num(t, "total", 0), num(t, "merged", 0), num(t, "leased", 0), num(t, "pending", 0),
           num(t, "retries", 0));
    if (num(t, "timeouts", 0) > 0)
        printf(" (%.0f run%s stopped for the task_timeout)", num(t, "timeouts", 0),
               num(t, "timeouts", 0) == 1 ? "" : "s");
    if (num(t, "losses", 0) > 0)
        printf(", %.0f lost with their host (requeued, not counted)", num(t, "losses", 0));
    if (num(t, "resumed_merged", 0) > 0)
        printf(", %.0f merged before a restart", num(t, "resumed_merged", 0));
    printf("\n");
    const cJSON *err = cJSON_GetObjectItemCaseSensitive(job, "error");
    if (cJSON_IsObject(err))
        printf("  error: %s\n", str(err, "message"));
    /* Retention purges the jobs fetched first (a farm before it has no "fetched"). */
    int done = strcmp(str(job, "state"), "done") == 0;
    int knows = cJSON_GetObjectItemCaseSensitive(job, "fetched") != NULL;
    if (done && str(job, "fetched")[0])
        printf("  outputs fetched at %s\n", str(job, "fetched"));
    else if (done && knows)
        printf("  outputs never fetched (gi fetch %llu)\n", (unsigned long long)id);
    if (str(job, "purge_at")[0])
        printf("  ended %s; purged at %s by the farm's retention%s\n", str(job, "ended"),
               str(job, "purge_at"),
               done && !str(job, "fetched")[0] ? " (fetch its outputs before)" : "");
    print_exclusions(job);
    const cJSON *te = cJSON_GetObjectItemCaseSensitive(job, "task_errors");
    int n = cJSON_GetArraySize(te);
    if (n > 0)
        printf("  task errors (last %d):\n", n > 5 ? 5 : n);
    for (int i = n > 5 ? n - 5 : 0; i < n; i++) {
        const cJSON *x = cJSON_GetArrayItem(te, i);
        printf("    task %.0f attempt %.0f on %s: %s\n", num(x, "task", 0), num(x, "attempt", 0),
               str(x, "worker"), str(x, "message"));
    }
    const cJSON *log = cJSON_GetObjectItemCaseSensitive(job, "log");
    n = cJSON_GetArraySize(log);
    if (n > 0)
        printf("  log (last %d):\n", n > 8 ? 8 : n);
    for (int i = n > 8 ? n - 8 : 0; i < n; i++) {
        const cJSON *x = cJSON_GetArrayItem(log, i);
        printf("    %s\n", cJSON_IsString(x) ? x->valuestring : "");
    }
    cJSON_Delete(job);
    return 0;
}

static int cmd_jobs(client *c)
{
    cJSON *doc = NULL;
    int rc = get_json(c, "/api/v1/jobs", &doc);
    if (rc)
        return rc;
    if (c->json)
        return print_json(doc), cJSON_Delete(doc), 0;
    printf("%-6s %-10s %5s %8s %9s %-12s %s\n", "ID", "STATE", "PRIO", "PROGRESS", "ETA", "METHOD",
           "NAME");
    const cJSON *jobs = cJSON_GetObjectItemCaseSensitive(doc, "jobs");
    for (const cJSON *j = jobs ? jobs->child : NULL; j; j = j->next) {
        char eta[32] = "";
        double e = running_eta(j);
        if (e >= 0)
            gi_duration(e, eta, sizeof eta);
        printf("%-6.0f %-10s %5.0f %7.1f%% %9s %-12s %s\n", num(j, "id", 0), str(j, "state"),
               num(j, "priority", 0), 100.0 * num(j, "progress", 0), eta, str(j, "method"),
               str(j, "name"));
    }
    cJSON_Delete(doc);
    return 0;
}

static int cmd_workers(client *c)
{
    cJSON *doc = NULL;
    int rc = get_json(c, "/api/v1/workers", &doc);
    if (rc)
        return rc;
    if (c->json)
        return print_json(doc), cJSON_Delete(doc), 0;
    /* OWNFAIL: the failures judged its host's own (they count towards its
     * blocklisting; the rest were its jobs'). */
    printf("%-20s %-22s %-12s %5s %5s %7s %6s %7s %6s %7s %5s %s\n", "NAME", "ADDRESS", "STATE",
           "PROCS", "CORES", "MEMORY", "LEASED", "DONE", "FAILED", "OWNFAIL", "LOST", "VERSION");
    const cJSON *ws = cJSON_GetObjectItemCaseSensitive(doc, "workers");
    for (const cJSON *w = ws ? ws->child : NULL; w; w = w->next) {
        printf("%-20s %-22s %-12s %5.0f %5.0f %5.1fG %6.0f %7.0f %6.0f %7.0f %5.0f %s\n",
               str(w, "name"), str(w, "address"), str(w, "state"), num(w, "processes", 0),
               num(w, "cores", 0), num(w, "memory_bytes", 0) / (1 << 30),
               num(w, "tasks_leased", 0), num(w, "tasks_done", 0), num(w, "tasks_failed", 0),
               num(w, "own_failures", 0), num(w, "losses", 0), str(w, "version"));
        /* Why a host gets no work, and for how long: what an operator asks first. */
        if (strcmp(str(w, "state"), "blocklisted") == 0)
            printf("    for %.0f s more; last: %s\n", num(w, "blocklisted_seconds", 0),
                   str(w, "last_error"));
    }
    cJSON_Delete(doc);
    return 0;
}

/* gi cancel (an unfinished job) and gi purge (an ended one). */
static int cmd_delete(client *c, uint64_t id, int purge)
{
    char path[64];
    snprintf(path, sizeof path, "/api/v1/jobs/%llu%s", (unsigned long long)id,
             purge ? "?purge=1" : "");
    gi_buf b;
    gi_buf_init(&b);
    int rc = call(c, "DELETE", path, NULL, 0, NULL, 200, 0, &b, NULL);
    if (rc == 0 && purge)
        printf("job %llu removed, with its checkpoint and outputs\n", (unsigned long long)id);
    else if (rc == 0) {
        /* A finishing job ends once its outputs are written (not served). */
        cJSON *doc = cJSON_ParseWithLength((const char *)b.data, b.len);
        int cancelling = doc && strcmp(str(doc, "state"), "cancelling") == 0;
        cJSON_Delete(doc);
        printf("job %llu cancelled%s\n", (unsigned long long)id,
               cancelling ? ": it ends once the outputs being written are (not served)" : "");
    }
    gi_buf_free(&b);
    return rc;
}

static int cmd_retry(client *c, uint64_t id)
{
    char path[64];
    snprintf(path, sizeof path, "/api/v1/jobs/%llu/retry", (unsigned long long)id);
    gi_buf b;
    gi_buf_init(&b);
    int rc = call(c, "POST", path, NULL, 0, NULL, 200, 0, &b, NULL);
    gi_buf_free(&b);
    if (rc)
        return rc;
    printf("job %llu runs again\n", (unsigned long long)id);
    fflush(stdout); /* before the progress on stderr, when stdout is a pipe */
    return c->wait ? wait_job(c, id, 1, 1) : 0;
}

static int cmd_fetch(client *c, uint64_t id)
{
    cJSON *job = NULL;
    int rc = get_job(c, id, &job);
    if (rc)
        return rc;
    const char *state = str(job, "state");
    unsigned long long n = (unsigned long long)id;
    /* What to do instead: an ended job has no outputs to wait for. */
    if (strcmp(state, "failed") == 0 || strcmp(state, "cancelled") == 0)
        rc = fail_msg(1, "job %llu is %s, not done: it has no outputs (`gi status %llu` says "
                         "why; `gi retry %llu --wait` runs it again and fetches them)",
                      n, state, n, n);
    else if (strcmp(state, "done") != 0)
        rc = fail_msg(1, "job %llu is %s, not done yet (`gi wait %llu` waits for it and fetches "
                         "its outputs)", n, state, n);
    else
        rc = fetch_outputs(c, id, job);
    cJSON_Delete(job);
    return rc;
}

/* After the checks that need no farm: the --out to fetch into, the farm's
 * URL and the token, then the command itself. */
static int client_run(client *c, const char *cmd, uint64_t id, const char *farm,
                      const char *token_file)
{
    gi_error err;
    /* Outputs are fetched at the end: an --out they cannot go to is said now,
     * not after the job has run. */
    int fetches = strcmp(cmd, "wait") == 0 || strcmp(cmd, "fetch") == 0 ||
                  ((strcmp(cmd, "submit") == 0 || strcmp(cmd, "retry") == 0) && c->wait);
    if (fetches && gi_output_dir_ready(c->out_dir, &err))
        return fail_msg(gi_error_exit_status(&err), "--out: %s", err.msg);
    if (gi_http_url_parse(farm, &c->url, &err))
        return fail_msg(2, "%s", err.msg);
    gi_buf tok;
    gi_buf_init(&tok);
    if (gi_secret_read(token_file, "GI_FARM_TOKEN_FILE", "GI_FARM_TOKEN", "API token",
                       "--token-file", &tok, &err)) {
        gi_http_url_free(&c->url);
        return fail_msg(2, "%s", err.msg);
    }
    memcpy(c->token, tok.data, tok.len);
    c->token[tok.len] = '\0';
    gi_secret_free(&tok);
    int rc;
    if (strcmp(cmd, "submit") == 0)
        rc = cmd_submit(c);
    else if (strcmp(cmd, "status") == 0)
        rc = cmd_status(c, id);
    else if (strcmp(cmd, "wait") == 0)
        rc = wait_job(c, id, 1, 0);
    else if (strcmp(cmd, "cancel") == 0)
        rc = cmd_delete(c, id, 0);
    else if (strcmp(cmd, "purge") == 0)
        rc = cmd_delete(c, id, 1);
    else if (strcmp(cmd, "retry") == 0)
        rc = cmd_retry(c, id);
    else if (strcmp(cmd, "jobs") == 0)
        rc = cmd_jobs(c);
    else if (strcmp(cmd, "workers") == 0)
        rc = cmd_workers(c);
    else
        rc = cmd_fetch(c, id);
    gi_http_url_free(&c->url);
    memset(c->token, 0, sizeof c->token);
    return rc;
}

int gi_client_main(int argc, char **argv)
{
    const char *cmd = argv[1];
    client c;
    memset(&c, 0, sizeof c);
    c.out_dir = "out";
    c.progress = "auto";
    c.priority = GI_FARM_PRIORITY_DEFAULT;
    const char *farm = getenv("GI_FARM"), *token_file = NULL, *prio = NULL, *retry = NULL;
    const char *env_farm = farm;
    if (!farm || !farm[0])
        farm = "http://127.0.0.1:7070";
    unsigned allowed = 0, given = 0;
    for (int i = 0; commands[i]; i++)
        if (strcmp(cmd, commands[i]) == 0)
            allowed = command_options[i];
    for (int i = 2; i < argc; i++) {
        const char *v;
        int rc;
        const char *names[] = {"--farm", "--token-file", "--out", "--progress", "--priority",
                               "--retry"};
        const char **dst[] = {&farm, &token_file, &c.out_dir, &c.progress, &prio, &retry};
        const unsigned opt[] = {0, 0, OPT_OUT, OPT_PROGRESS, OPT_PRIORITY, 0};
        size_t k;
        for (k = 0, rc = 0; k < GI_ARRAY_LEN(names); k++)
            if ((rc = gi_args_take(argc, argv, &i, names[k], &v)) != 0)
                break;
        if (rc < 0)
            return fail_msg(2, "%s needs a value", names[k]);
        if (rc > 0) {
            if (opt[k] && !(allowed & opt[k]))
                return fail_msg(2, "%s: %s is not one of its options", cmd, names[k]);
            *dst[k] = v;
            given |= opt[k];
            if (dst[k] == &farm)
                c.farm_from = "from --farm";
            continue;
        }
        unsigned flag = strcmp(argv[i], "--json") == 0   ? OPT_JSON
                        : strcmp(argv[i], "--wait") == 0 ? OPT_WAIT
                                                         : 0;
        if (flag && !(allowed & flag))
            return fail_msg(2, "%s: %s is not one of its options", cmd, argv[i]);
        if (flag) {
            c.json |= flag == OPT_JSON;
            c.wait |= flag == OPT_WAIT;
            given |= flag;
        } else if (strncmp(argv[i], "--token", 7) == 0)
            return fail_msg(2, "tokens are not taken from the command line (other users can read "
                               "it): use --token-file or GI_FARM_TOKEN");
        else if (argv[i][0] == '-' && argv[i][1])
            return fail_msg(2, "%s: unknown option %s (gi --help lists them)", cmd, argv[i]);
        else if (c.arg)
            return fail_msg(2, "%s: more than one operand (%s, %s)", cmd, c.arg, argv[i]);
        else
            c.arg = argv[i];
    }
    if ((allowed & OPT_WAIT) && !c.wait && (given & (OPT_OUT | OPT_PROGRESS)))
        return fail_msg(2, "%s: --out and --progress are for --wait", cmd);
    if (gi_progress_mode_parse(c.progress, &c.mode))
        return fail_msg(2, "--progress must be auto, bar, lines, json or none");
    gi_log_json(c.mode == GI_PROGRESS_JSON);
    c.retry_s = RETRY_S;
    c.retry_given = retry != NULL;
    if (retry && gi_args_number(retry, 0, RETRY_LIMIT_S, &c.retry_s))
        return fail_msg(2, "--retry must be seconds in [0, %.0f], got \"%s\"", RETRY_LIMIT_S,
                        retry);
    c.farm = farm;
    if (!c.farm_from)
        c.farm_from = env_farm && env_farm[0] ? "from $GI_FARM" : "the default";
    if (prio && gi_args_int(prio, 1, GI_FARM_PRIORITY_MAX, &c.priority))
        return fail_msg(2, "--priority must be an integer in [1, %d]", GI_FARM_PRIORITY_MAX);
    int needs_arg = strcmp(cmd, "jobs") != 0 && strcmp(cmd, "workers") != 0;
    if (needs_arg != (c.arg != NULL))
        return fail_msg(2, "%s: %s", cmd, needs_arg ? "missing operand" : "takes no operand");
    uint64_t id = 0;
    if (needs_arg && strcmp(cmd, "submit") != 0 && parse_id(c.arg, &id))
        return fail_msg(2, "%s: \"%s\" is not a job id", cmd, c.arg);
    int submit = strcmp(cmd, "submit") == 0;
    int rc = submit ? submit_check(&c) : 0;
    if (rc == 0)
        rc = client_run(&c, cmd, id, farm, token_file);
    if (submit)
        gi_job_free(&c.job);
    return rc;
}
