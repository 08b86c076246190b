/* gi-farmd: the farm coordinator (docs/farm.md).
 *
 *   gi-farmd --state DIR [--listen-workers ADDR:PORT] [--listen-api ADDR:PORT]
 *            [--secret-file FILE] [--token-file FILE] [tuning options]
 *
 * The farm secret and the API token come from files (--secret-file,
 * --token-file, or GI_FARM_SECRET_FILE / GI_FARM_TOKEN_FILE) or from the
 * environment (GI_FARM_SECRET / GI_FARM_TOKEN), never from the command line.
 * Exit status: 0 after SIGTERM / SIGINT, 2 for bad arguments, 1 otherwise. */
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_args.h"
#include "gi_auth.h"
#include "gi_blas_threads.h"
#include "gi_farm.h"
#include "gi_job.h"
#include "gi_log.h"
#include "gi_version.h"

static gi_farm *the_farm;

static void on_signal(int sig)
{
    (void)sig;
    if (the_farm)
        gi_farm_stop(the_farm);
}

static void usage(FILE *out)
{
    fprintf(out,
            "usage: gi-farmd --state DIR [options]\n"
            "  --listen-workers ADDR:PORT  worker port (default 127.0.0.1:7071)\n"
            "  --listen-api ADDR:PORT      HTTP API (default 127.0.0.1:7070)\n"
            "  --secret-file FILE          farm secret (or GI_FARM_SECRET_FILE, GI_FARM_SECRET)\n"
            "  --token-file FILE           API token (or GI_FARM_TOKEN_FILE, GI_FARM_TOKEN)\n"
            "  --heartbeat S --lease S --dead S       worker timing (2, 30, 120)\n"
            "  --checkpoint S              checkpoint running jobs every S seconds (30)\n"
            "  --max-attempts N            failed runs of a task before its job fails (4)\n"
            "  --task-timeout S            stop a task running longer than S seconds (from the\n"
            "                              start of its run on the worker, not counting its wait\n"
            "                              in the worker's queue) and fail that run, for jobs\n"
            "                              that set no task_timeout of their own (0: no limit)\n"
            "  --max-task-losses N         runs of a task lost with their host (killed, cut\n"
            "                              off, lease expired) before its job fails (8);\n"
            "                              such runs are requeued, not counted as attempts\n"
            "  --blocklist-failures N --blocklist-seconds S   (5, 600) a host whose runs of one\n"
            "                              job's tasks fail N times in a row is excluded from\n"
            "                              that job for S seconds; one with N failures in a row\n"
            "                              judged its own (tasks of two jobs or more that then\n"
            "                              ran on other hosts, or its disk) is blocklisted;\n"
            "                              a job's failures on other hosts count against the\n"
            "                              job, not the host, for S seconds\n"
            "  --blocklist-losses N        a host lost with tasks held (connection lost, leases\n"
            "                              expired) N times in a row, no result in between, is\n"
            "                              blocklisted too (3; a drain loses nothing)\n"
            "  --max-asset-bytes B --max-store-bytes B --max-result-bytes B  (1G, 64G, 1G)\n"
            "  --max-pixels N --max-jobs N --max-workers N    (64M, 1000, 1024)\n"
            "  --max-jobs-memory B         what all jobs kept may hold, ended ones too (1G)\n"
            "  --check-timeout S --check-memory B             scene checker limits (300, 16G)\n"
            "  --api-head-seconds S        time an API client has to send a request's head (10)\n"
            "  --api-request-seconds S --api-min-rate B   an API request (its body in, its\n"
            "                              answer out) has S seconds in hand, spent as time\n"
            "                              goes, earned back at 1 s per B bytes moved, S at\n"
            "                              most; out of them, it is closed: one that stops is\n"
            "                              closed S s later, one at B bytes/s never\n"
            "                              (10, 16K; --api-min-rate 0: no such limit)\n"
            "  --keep-ended DURATION       purge ended jobs (done, failed, cancelled) this long\n"
            "                              after they ended, e.g. 14d (default: until purged)\n"
            "  --keep-ended-bytes B        and ended ones while their files hold more (outputs,\n"
            "                              checkpoints, logs; default: no limit). Both purge\n"
            "                              jobs fetched (or without outputs) before done jobs\n"
            "                              never fetched (warned about), oldest first in each\n"
            "  --refusal-log-window S      log an unauthenticated peer's refusals once per S\n"
            "                              seconds, then a count (10; 0: every one)\n"
            "Durations take s, m, h, d, w suffixes.\n"
            "Sizes take K, M, G, T suffixes. See docs/farm.md.\n");
}

static int bad(const char *opt, const char *v, const char *want)
{
    fprintf(stderr, "gi-farmd: %s: \"%s\" is not %s\n", opt, v, want);
    return 2;
}

/* Parses one option into cfg; returns 1 if consumed, 0 if unknown, 2 on error. */
static int option(int argc, char **argv, int *i, gi_farm_config *c, const char **secret_file,
                  const char **token_file)
{
    static const struct {
        const char *name;
        size_t off;
        double lo, hi;
    } secs[] = {
        {"--heartbeat", offsetof(gi_farm_config, heartbeat_s), 0.01, 3600},
        {"--lease", offsetof(gi_farm_config, lease_s), 0.05, 86400},
        {"--dead", offsetof(gi_farm_config, dead_s), 0.1, 86400 * 7},
        {"--checkpoint", offsetof(gi_farm_config, checkpoint_s), 0.05, 86400},
        {"--blocklist-seconds", offsetof(gi_farm_config, blocklist_s), 0, 86400 * 30},
        {"--check-timeout", offsetof(gi_farm_config, check_timeout_s), 1, 86400},
        {"--api-head-seconds", offsetof(gi_farm_config, api_head_s), 0.1, 3600},
        {"--api-request-seconds", offsetof(gi_farm_config, api_request_s), 0.1, 86400},
        {"--refusal-log-window", offsetof(gi_farm_config, refusal_window_s), 0, 3600},
        {"--task-timeout", offsetof(gi_farm_config, task_timeout_s), 0, GI_JOB_MAX_TASK_TIMEOUT},
    };
    static const struct {
        const char *name;
        size_t off;
    } sizes[] = {
        {"--max-asset-bytes", offsetof(gi_farm_config, max_asset_bytes)},
        {"--max-store-bytes", offsetof(gi_farm_config, max_store_bytes)},
        {"--max-jobs-memory", offsetof(gi_farm_config, max_jobs_memory)},
        {"--max-result-bytes", offsetof(gi_farm_config, max_result_bytes)},
        {"--max-pixels", offsetof(gi_farm_config, max_job_pixels)},
        {"--check-memory", offsetof(gi_farm_config, check_memory)},
        {"--keep-ended-bytes", offsetof(gi_farm_config, keep_ended_bytes)},
        {"--api-min-rate", offsetof(gi_farm_config, api_min_rate)},
    };
    static const struct {
        const char *name;
        size_t off;
        int64_t lo, hi;
    } counts[] = {
        {"--max-attempts", offsetof(gi_farm_config, max_attempts), 1, 100},
        {"--max-task-losses", offsetof(gi_farm_config, max_task_losses), 1, 1000},
        {"--blocklist-failures", offsetof(gi_farm_config, blocklist_failures), 1, 1000000},
        {"--blocklist-losses", offsetof(gi_farm_config, blocklist_losses), 1, 1000000},
        {"--max-jobs", offsetof(gi_farm_config, max_jobs), 1, 1000000},
        {"--max-workers", offsetof(gi_farm_config, max_workers), 1, 100000},
    };
    const char *v;
    int rc;
#define TAKE(name, dst)                                                                    \
    if ((rc = gi_args_take(argc, argv, i, name, &v)) != 0) {                               \
        if (rc < 0)                                                                        \
            return fprintf(stderr, "gi-farmd: %s needs a value\n", name), 2;               \
        *(dst) = v;                                                                        \
        return 1;                                                                          \
    }
    TAKE("--state", &c->state_dir)
    TAKE("--listen-workers", &c->listen_workers)
    TAKE("--listen-api", &c->listen_api)
    TAKE("--secret-file", secret_file)
    TAKE("--token-file", token_file)
#undef TAKE
    if ((rc = gi_args_take(argc, argv, i, "--keep-ended", &v)) != 0) {
        /* Up to 100 years: "forever" is leaving the option out. */
        if (rc < 0 || gi_args_duration(v, 1, 100 * 365.25 * 86400, &c->keep_ended_s))
            return bad("--keep-ended", rc < 0 ? "" : v,
                       "a duration of at least 1 s (e.g. 3600, 90m, 36h, 14d, 2w)");
        return 1;
    }
    for (size_t k = 0; k < GI_ARRAY_LEN(secs); k++)
        if ((rc = gi_args_take(argc, argv, i, secs[k].name, &v)) != 0) {
            if (rc < 0 || gi_args_number(v, secs[k].lo, secs[k].hi,
                                         (double *)((char *)c + secs[k].off))) {
                char want[96];
                snprintf(want, sizeof want, "a number of seconds in [%g, %g]", secs[k].lo,
                         secs[k].hi);
                return bad(secs[k].name, rc < 0 ? "" : v, want);
            }
            return 1;
        }
    for (size_t k = 0; k < GI_ARRAY_LEN(sizes); k++)
        if ((rc = gi_args_take(argc, argv, i, sizes[k].name, &v)) != 0) {
            if (rc < 0 || gi_args_bytes(v, (uint64_t *)((char *)c + sizes[k].off)))
                return bad(sizes[k].name, rc < 0 ? "" : v, "a size (e.g. 512M)");
            return 1;
        }
    for (size_t k = 0; k < GI_ARRAY_LEN(counts); k++)
        if ((rc = gi_args_take(argc, argv, i, counts[k].name, &v)) != 0) {
            int64_t n;
            if (rc < 0 || gi_args_int(v, counts[k].lo, counts[k].hi, &n)) {
                char want[96];
                snprintf(want, sizeof want, "an integer in [%lld, %lld]",
                         (long long)counts[k].lo, (long long)counts[k].hi);
                return bad(counts[k].name, rc < 0 ? "" : v, want);
            }
            *(uint32_t *)((char *)c + counts[k].off) = (uint32_t)n;
            return 1;
        }
    return 0;
}

int main(int argc, char **argv)
{
    gi_log_init("gi-farmd");
    gi_blas_single_thread();
    if (!getenv("GI_LOG"))
        gi_log_set_level(GI_LOG_INFO);
    gi_farm_config cfg;
    gi_farm_config_default(&cfg);
    const char *secret_file = NULL, *token_file = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        }
        if (strcmp(argv[i], "--version") == 0) {
            printf("gi-farmd %s\n", GI_VERSION);
            return 0;
        }
        if (strncmp(argv[i], "--secret", 8) == 0 && strncmp(argv[i], "--secret-file", 13) != 0) {
            fprintf(stderr, "gi-farmd: secrets are not taken from the command line (other users "
                            "can read it): use --secret-file or GI_FARM_SECRET\n");
            return 2;
        }
        if (strncmp(argv[i], "--token", 7) == 0 && strncmp(argv[i], "--token-file", 12) != 0) {
            fprintf(stderr, "gi-farmd: tokens are not taken from the command line: use "
                            "--token-file or GI_FARM_TOKEN\n");
            return 2;
        }
        int rc = option(argc, argv, &i, &cfg, &secret_file, &token_file);
        if (rc == 2)
            return 2;
        if (rc == 0) {
            fprintf(stderr, "gi-farmd: unknown argument %s\n", argv[i]);
            usage(stderr);
            return 2;
        }
    }
    if (!cfg.state_dir) {
        fprintf(stderr, "gi-farmd: --state DIR is required\n");
        usage(stderr);
        return 2;
    }
    if (cfg.lease_s < 2 * cfg.heartbeat_s || cfg.dead_s < cfg.lease_s) {
        fprintf(stderr, "gi-farmd: need --lease >= 2 x --heartbeat and --dead >= --lease\n");
        return 2;
    }
    if (cfg.task_timeout_s > 0 && cfg.task_timeout_s < GI_JOB_MIN_TASK_TIMEOUT) {
        fprintf(stderr, "gi-farmd: --task-timeout must be 0 (no limit) or seconds in [%g, %g]\n",
                GI_JOB_MIN_TASK_TIMEOUT, GI_JOB_MAX_TASK_TIMEOUT);
        return 2;
    }
    gi_error err;
    if (gi_secret_read(secret_file, "GI_FARM_SECRET_FILE", "GI_FARM_SECRET", "farm secret",
                       "--secret-file", &cfg.secret, &err) ||
        gi_secret_read(token_file, "GI_FARM_TOKEN_FILE", "GI_FARM_TOKEN", "API token",
                       "--token-file", &cfg.token, &err)) {
        fprintf(stderr, "gi-farmd: %s\n", err.msg);
        gi_secret_free(&cfg.secret);
        return 2;
    }
    gi_farm *f;
    int rc = gi_farm_open(&f, &cfg, &err);
    if (rc == 0) {
        the_farm = f;
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigaction(SIGINT, &sa, NULL);
        sigaction(SIGTERM, &sa, NULL);
        rc = gi_farm_run(f, &err);
    }
    if (rc)
        fprintf(stderr, "gi-farmd: %s\n", err.msg);
    gi_farm_close(f);
    return rc ? gi_error_exit_status(&err) : 0;
}
