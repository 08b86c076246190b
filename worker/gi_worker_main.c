/* gi-worker: a render host of the farm (docs/farm.md).
 *
 *   gi-worker --connect HOST:PORT [--procs N] [--cache DIR] [--batch-dir DIR] [options]
 *
 * The farm secret comes from --secret-file FILE, GI_FARM_SECRET_FILE or
 * GI_FARM_SECRET, never from the command line. SIGTERM drains (queued tasks
 * handed back, running ones finished), a second SIGTERM stops at once.
 * Exit status: 0 after a drain, 2 for bad arguments, 1 otherwise. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_args.h"
#include "gi_auth.h"
#include "gi_blas_threads.h"
#include "gi_cores.h"
#include "gi_farm_worker.h"
#include "gi_log.h"
#include "gi_version.h"

static void on_signal(int sig)
{
    (void)sig;
    gi_farm_worker_signal();
}

static void usage(FILE *out)
{
    fprintf(out,
            "usage: gi-worker --connect HOST:PORT [options]\n"
            "  --procs N            pool processes (default: one per usable CPU: affinity\n"
            "                       mask and cgroup CPU limit)\n"
            "  --queue N            tasks queued beyond the running ones (default procs/2, >= 1)\n"
            "  --cache DIR          asset cache (default $XDG_CACHE_HOME/gi-worker or\n"
            "                       ~/.cache/gi-worker); one gi-worker per DIR (locked)\n"
            "  --cache-max BYTES    cache size bound (default 10G; K, M, G, T suffixes)\n"
            "  --batch-dir DIR      per-job batch directories (default CACHE/batches; not\n"
            "                       bounded by --cache-max)\n"
            "  --name NAME          name shown by `gi workers` (default: the host name)\n"
            "  --secret-file FILE   farm secret (or GI_FARM_SECRET_FILE, GI_FARM_SECRET)\n"
            "  --drain-seconds S    time to finish running tasks on SIGTERM (default 120)\n"
            "  --backoff-max S      longest wait between connection attempts (default 30)\n"
            "  --once               exit when the connection ends instead of reconnecting\n");
}

static char *default_cache(void)
{
    const char *x = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    char buf[4200];
    if (x && x[0])
        snprintf(buf, sizeof buf, "%s/gi-worker", x);
    else if (home && home[0])
        snprintf(buf, sizeof buf, "%s/.cache/gi-worker", home);
    else
        snprintf(buf, sizeof buf, "/tmp/gi-worker-cache-%ld", (long)getuid());
    return gi_xstrdup(buf);
}

int main(int argc, char **argv)
{
    gi_log_init("gi-worker");
    gi_blas_single_thread();
    if (!getenv("GI_LOG"))
        gi_log_set_level(GI_LOG_INFO);
    gi_worker_opts o;
    memset(&o, 0, sizeof o);
    o.procs = gi_cores_usable();
    o.queue = -1;
    o.cache_max = (uint64_t)10 << 30;
    o.drain_s = 120;
    o.backoff_max_s = 30;
    const char *secret_file = NULL, *v;
    char *cache = NULL;
    for (int i = 1; i < argc; i++) {
        int rc;
        int64_t n;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        }
        if (strcmp(argv[i], "--version") == 0) {
            printf("gi-worker %s\n", GI_VERSION);
            return 0;
        }
        if (strcmp(argv[i], "--once") == 0) {
            o.once = 1;
            continue;
        }
        if (strncmp(argv[i], "--secret", 8) == 0 && strncmp(argv[i], "--secret-file", 13) != 0) {
            fprintf(stderr, "gi-worker: secrets are not taken from the command line (other users "
                            "can read it): use --secret-file or GI_FARM_SECRET\n");
            return 2;
        }
        const char *names[] = {"--connect", "--procs", "--queue", "--cache", "--cache-max",
                               "--name", "--secret-file", "--drain-seconds", "--backoff-max",
                               "--batch-dir"};
        size_t k;
        for (k = 0; k < GI_ARRAY_LEN(names); k++)
            if ((rc = gi_args_take(argc, argv, &i, names[k], &v)) != 0)
                break;
        if (k == GI_ARRAY_LEN(names)) {
            fprintf(stderr, "gi-worker: unknown argument %s\n", argv[i]);
            usage(stderr);
            return 2;
        }
        if (rc < 0) {
            fprintf(stderr, "gi-worker: %s needs a value\n", names[k]);
            return 2;
        }
        int ok = 1;
        switch (k) {
        case 0: o.connect = v; break;
        case 1: ok = gi_args_int(v, 1, 1024, &n) == 0; o.procs = (int)n; break;
        case 2: ok = gi_args_int(v, 0, 4096, &n) == 0; o.queue = (int)n; break;
        case 3: free(cache); cache = gi_xstrdup(v); break;
        case 4: ok = gi_args_bytes(v, &o.cache_max) == 0; break;
        case 5: ok = v[0] && strlen(v) <= 255; o.name = v; break;
        case 6: secret_file = v; break;
        case 7: ok = gi_args_number(v, 0, 86400, &o.drain_s) == 0; break;
        case 8: ok = gi_args_number(v, 0.1, 3600, &o.backoff_max_s) == 0; break;
        case 9: ok = v[0] != 0; o.batch_dir = v; break;
        }
        if (!ok) {
            fprintf(stderr, "gi-worker: %s: \"%s\" is out of range\n", names[k], v);
            return 2;
        }
    }
    if (!o.connect) {
        fprintf(stderr, "gi-worker: --connect HOST:PORT is required\n");
        usage(stderr);
        return 2;
    }
    if (o.queue < 0)
        o.queue = o.procs / 2 > 1 ? o.procs / 2 : 1;
    if (o.queue > 3 * o.procs + 16)
        o.queue = 3 * o.procs + 16;
    o.cache_dir = cache ? cache : (cache = default_cache());
    gi_error err;
    gi_buf_init(&o.secret);
    if (gi_secret_read(secret_file, "GI_FARM_SECRET_FILE", "GI_FARM_SECRET", "farm secret",
                       "--secret-file", &o.secret, &err)) {
        fprintf(stderr, "gi-worker: %s\n", err.msg);
        free(cache);
        return 2;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: poll and sleeps wake up */
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    int rc = gi_farm_worker_run(&o, &err);
    if (rc)
        fprintf(stderr, "gi-worker: %s\n", err.msg);
    gi_secret_free(&o.secret);
    free(cache);
    return rc ? gi_error_exit_status(&err) : 0;
}
