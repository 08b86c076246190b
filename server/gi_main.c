/* gi: the command line.
 *
 *   gi render JOB.json [--workers N] [--out DIR] [--progress MODE] [--checkpoint S]
 *             [--resume] [--task-timeout S]
 *   gi validate JOB.json | SCENE | [JOB.json] EMISSIONS.json
 *   gi relight JOB.json EMISSIONS.json [--out DIR] [--images] [--progress MODE] ...
 *   gi methods
 *
 * Exit status: 0 success, 2 invalid input (job, scene, mesh, arguments),
 * 1 any other failure, 130 interrupted. */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi_args.h"
#include "gi_blas_threads.h"
#include "gi_client.h"
#include "gi_fs.h"
#include "gi_job.h"
#include "gi_json.h"
#include "gi_local.h"
#include "gi_log.h"
#include "gi_progress.h"
#include "gi_relight.h"
#include "gi_version.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: gi render JOB.json [--workers N] [--out DIR] [--progress MODE]\n"
            "                          [--checkpoint S] [--resume] [--task-timeout S]\n"
            "       gi validate JOB.json | SCENE | [JOB.json] EMISSIONS.json\n"
            "       gi relight JOB.json EMISSIONS.json [--out DIR] [--images]\n"
            "                 [--workers N] [--threads N] [--progress MODE]\n"
            "       gi methods\n"
            "       gi --version\n"
            "%s"
            "\n"
            "render    renders a job on this machine with a pool of N worker processes\n"
            "          (default: one per usable CPU) and writes its outputs into DIR\n"
            "          (default: out)\n"
            "          MODE: auto (a bar on a terminal, lines otherwise), bar, lines, json, none\n"
            "          A checkpoint, DIR/.NAME.checkpoint, is written when the render is\n"
            "          stopped and every S seconds (30; 0: only then); --resume continues it\n"
            "          (an animation's photon batches are kept under $TMPDIR for it)\n"
            "          --task-timeout S: a task running longer than S seconds is stopped and\n"
            "          retried, as a crash is (default 0: none); a job's task_timeout wins\n"
            "validate  checks a job and its scene without rendering (or a scene alone: a scene\n"
            "          JSON, OBJ, PLY or glTF file; or an emissions file for gi relight: with\n"
            "          its radiosity job, its names are checked against the job's scene)\n"
            "relight   solves new emissions with a finished radiosity job's factorization\n"
            "          (in DIR, where gi render wrote it; default out): PLY and glTF per\n"
            "          emission set, and a report; --images renders the camera too\n"
            "methods   lists the rendering methods\n"
            "\n"
            "submit    uploads a job's files to a farm and queues it; --wait follows it and\n"
            "          downloads the outputs (docs/farm.md)\n"
            "retry     runs a failed or cancelled farm job again from its last checkpoint\n"
            "\n"
            "Job format: docs/job-format.md; scene format: docs/scene-format.md.\n",
            gi_client_usage);
}

static void on_signal(int sig)
{
    (void)sig;
    gi_local_interrupted = 1;
}

static int arg_value(int argc, char **argv, int *i, const char *name, const char **out)
{
    int rc = gi_args_take(argc, argv, i, name, out);
    if (rc < 0) {
        fprintf(stderr, "gi: %s needs a value\n", name);
        exit(2);
    }
    return rc;
}

static void print_summary(const gi_job *job, const gi_local_summary *s)
{
    char a[32], b[32], c[32], d[32], e[32];
    /* Rates are this run's: a resumed render's checkpoint brought the rest. */
    double secs = s->seconds > 0 ? s->seconds : 1e-9;
    double samples = (double)(s->stats.samples - s->stats_before.samples);
    double rays = (double)(s->stats.rays - s->stats_before.rays);
    double worker_secs = s->stats.seconds - s->stats_before.seconds;
    if (worker_secs <= 0)
        worker_secs = 1e-9;
    printf("%s: %s done in %s with %d worker%s", job->name, job->method->name,
           gi_duration(s->seconds, a, sizeof a), s->workers, s->workers == 1 ? "" : "s");
    if (s->resumed)
        printf(" (resumed at %.0f%%; the rates are this run's)", 100.0 * s->fraction_before);
    printf("\n");
    printf("  ");
    if (s->stats.samples != s->stats.rays || strcmp(job->method->unit, "rays") != 0)
        printf("%s%s (%s%s/s), ", gi_si((double)s->stats.samples, a, sizeof a), job->method->unit,
               gi_si(samples / secs, b, sizeof b), job->method->unit);
    printf("%srays (%srays/s, %srays per worker-second)\n", gi_si((double)s->stats.rays, c, sizeof c),
           gi_si(rays / secs, d, sizeof d), gi_si(rays / worker_secs, e, sizeof e));
    printf("  %llu task%s", (unsigned long long)s->tasks, s->tasks == 1 ? "" : "s");
    if (s->retries) {
        printf(", %llu retried (%llu worker crashes", (unsigned long long)s->retries,
               (unsigned long long)s->crashes);
        if (s->timeouts)
            printf(", %llu stopped at their time limit", (unsigned long long)s->timeouts);
        printf(")");
    }
    printf("\n");
    for (int i = 0; i + 1 < job->written_count; i += 2)
        printf("  %-4s %s\n", job->written[i], job->written[i + 1]);
    if (job->written_more)
        printf("  ... and %d more in %s\n", job->written_more, job->out_dir ? job->out_dir : ".");
}

static void json_output(void *ctx, const char *kind, const char *path)
{
    gi_progress_json_output(stderr, ((const gi_job *)ctx)->name, kind, path);
}

static int cmd_render(int argc, char **argv)
{
    const char *job_path = NULL, *out_dir = "out", *progress = "auto", *workers_s = NULL;
    const char *checkpoint_s = NULL, *timeout_s = NULL;
    int resume = 0;
    for (int i = 2; i < argc; i++) {
        const char *v;
        if (arg_value(argc, argv, &i, "--workers", &workers_s) ||
            arg_value(argc, argv, &i, "--out", &out_dir) ||
            arg_value(argc, argv, &i, "--progress", &progress) ||
            arg_value(argc, argv, &i, "--checkpoint", &checkpoint_s) ||
            arg_value(argc, argv, &i, "--task-timeout", &timeout_s))
            continue;
        if (strcmp(argv[i], "--resume") == 0) {
            resume = 1;
            continue;
        }
        if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "gi render: unknown option %s (gi --help lists them)\n", argv[i]);
            return 2;
        }
        if (job_path) {
            fprintf(stderr, "gi render: more than one job file (%s, %s)\n", job_path, argv[i]);
            return 2;
        }
        job_path = argv[i];
        (void)v;
    }
    if (!job_path) {
        usage(stderr);
        return 2;
    }
    gi_local_opts opts = {0, GI_PROGRESS_AUTO, 30.0, resume, 0.0};
    /* gi_args (fuzz_args): an empty value is no number, not 0. */
    if (checkpoint_s && gi_args_number(checkpoint_s, 0, 86400, &opts.checkpoint_s)) {
        fprintf(stderr, "gi render: --checkpoint must be seconds in [0, 86400], got \"%s\"\n",
                checkpoint_s);
        return 2;
    }
    double *limit = &opts.task_timeout_s;
    if (timeout_s && (gi_args_number(timeout_s, 0, GI_JOB_MAX_TASK_TIMEOUT, limit) ||
                      (*limit > 0 && *limit < GI_JOB_MIN_TASK_TIMEOUT))) {
        fprintf(stderr, "gi render: --task-timeout must be 0 (no limit) or seconds in [%g, %g], "
                "got \"%s\"\n", GI_JOB_MIN_TASK_TIMEOUT, GI_JOB_MAX_TASK_TIMEOUT, timeout_s);
        return 2;
    }
    if (workers_s) {
        int64_t n;
        if (gi_args_int(workers_s, 1, 1024, &n)) {
            fprintf(stderr, "gi render: --workers must be an integer in [1, 1024], got \"%s\"\n",
                    workers_s);
            return 2;
        }
        opts.workers = (int)n;
    }
    if (gi_progress_mode_parse(progress, &opts.progress)) {
        fprintf(stderr, "gi render: --progress must be auto, bar, lines, json or none\n");
        return 2;
    }
    int json = opts.progress == GI_PROGRESS_JSON;
    gi_log_json(json);
    gi_error err;
    gi_error_clear(&err);
    gi_job job;
    double t0 = gi_now();
    if (gi_job_load(job_path, &job, &err) == 0) {
        if (gi_output_dir_ready(out_dir, &err) != 0)
            gi_error_prefix(&err, "--out");
        else
            gi_job_outputs_spare_inputs(&job, job_path, out_dir, &err);
    }
    if (err.code != GI_OK) {
        if (json) /* the end event says why; there is no job name yet */
            gi_progress_json_end(stderr, job_path, "failed", gi_now() - t0, err.msg);
        else
            gi_say("%s", err.msg);
        gi_job_free(&job);
        return gi_error_exit_status(&err);
    }
    gi_remove_stale_temps(out_dir); /* of a render killed while writing */
    job.out_dir = gi_xstrdup(out_dir);
    /* Stopped, not killed: a checkpoint is written and the batches kept for
     * --resume. SIGHUP too: the terminal or ssh session went away. */
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGHUP, on_signal);
    if (json) {
        job.on_output = json_output;
        job.on_output_ctx = &job;
    }
    gi_local_summary summary;
    int rc = gi_render_local(&job, &opts, &summary, &err);
    int status = 0;
    if (rc) {
        if (!json) /* the end event carries it */
            gi_say("%s", err.msg);
        status = err.code == GI_ECANCEL ? 130 : gi_error_exit_status(&err);
    } else {
        print_summary(&job, &summary);
    }
    if (json)
        gi_progress_json_end(stderr, job.name,
                             rc == 0 ? "done" : err.code == GI_ECANCEL ? "interrupted" : "failed",
                             gi_now() - t0, rc ? err.msg : NULL);
    gi_job_free(&job);
    return status;
}

enum { FILE_JOB, FILE_SCENE, FILE_EMISSIONS };

/* What gi validate was given: a scene (a bare mesh file, or JSON with
 * "objects"), an emissions file for gi relight, or a job. Told by the
 * top-level keys alone (gi_json_top_keys, on the file read in pieces: a
 * map would fault if the file were truncated under it), not by parsing it:
 * each kind has its own size limit (a job's 16 MiB, a scene's 2 GiB), which
 * its loader applies to the file's size before it parses, so an oversized
 * job is refused at once, naming its size and the limit. */
static int file_kind(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strcmp(dot, ".json") != 0)
        return FILE_SCENE;
    int fd = gi_open_regular(path, O_RDONLY, NULL, NULL);
    if (fd < 0)
        return FILE_JOB; /* its loader says why */
    static const char *const keys[] = {"method", "objects", "emissions", NULL};
    gi_json_top_keys_scan scan;
    gi_json_top_keys_begin(&scan, keys);
    char buf[1 << 16];
    ssize_t n;
    /* Until the object closes, or names "method": a job, whatever follows. */
    while (!(scan.found & 1) && (n = read(fd, buf, sizeof buf)) != 0) {
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0 || gi_json_top_keys_feed(&scan, buf, (size_t)n) != 1)
            break;
    }
    close(fd);
    unsigned found;
    if (gi_json_top_keys_end(&scan, &found) != 0 || (found & 1))
        return FILE_JOB;
    return found & 2 ? FILE_SCENE : found & 4 ? FILE_EMISSIONS : FILE_JOB;
}

/* gi validate SCENE: the scene alone, as every method loads it. */
static int validate_scene(const char *path)
{
    char *dir = gi_dirname(path);
    gi_dir_source ds;
    gi_dir_source_init(&ds, dir);
    gi_asset_source src = gi_dir_source_as_source(&ds);
    const char *slash = strrchr(path, '/');
    gi_scene s;
    gi_error err;
    int rc = gi_scene_load(&src, slash ? slash + 1 : path, &s, &err);
    if (rc) {
        fprintf(stderr, "gi: %s\n", err.msg);
    } else {
        printf("%s: ok (scene: %u objects, %u triangles, %u emissive)\n", path, s.object_count,
               s.triangle_count, s.light_count);
        gi_scene_free(&s);
    }
    gi_dir_source_free(&ds);
    free(dir);
    return rc ? gi_error_exit_status(&err) : 0;
}

static int cmd_validate(int argc, char **argv)
{
    if (argc != 3 && argc != 4) {
        usage(stderr);
        return 2;
    }
    int kind = file_kind(argv[2]);
    /* JOB.json EMISSIONS.json, as gi relight takes them (or the other way). */
    if (argc == 4) {
        int k2 = file_kind(argv[3]);
        if (kind == FILE_JOB && k2 == FILE_EMISSIONS)
            return gi_relight_validate(argv[2], argv[3]);
        if (kind == FILE_EMISSIONS && k2 == FILE_JOB)
            return gi_relight_validate(argv[3], argv[2]);
        fprintf(stderr, "gi validate: two files must be a radiosity job and an emissions file "
                "(an object with \"emissions\"), as gi relight takes them: not %s and %s\n",
                argv[2], argv[3]);
        return 2;
    }
    if (kind == FILE_SCENE)
        return validate_scene(argv[2]);
    /* Alone: its own fields; its names are the scene's, which only the job knows. */
    if (kind == FILE_EMISSIONS)
        return gi_relight_validate(NULL, argv[2]);
    gi_error err;
    gi_job job;
    int rc = gi_job_load(argv[2], &job, &err);
    char frames[32] = ""; /* an animation's */
    if (rc == 0 && job.frame_count)
        snprintf(frames, sizeof frames, ", %u frame%s", job.frame_count,
                 job.frame_count == 1 ? "" : "s");
    if (rc)
        fprintf(stderr, "gi: %s\n", err.msg);
    else
        printf("%s: ok (%s%s, scene %s: %u objects, %u triangles, %u emissive)\n", argv[2],
               job.method->name, frames, job.scene_name, job.scene.object_count,
               job.scene.triangle_count, job.scene.light_count);
    gi_job_free(&job);
    return rc ? gi_error_exit_status(&err) : 0;
}

static int cmd_methods(void)
{
    for (const gi_method *const *m = gi_methods(); *m; m++)
        printf("%-12s %s\n", (*m)->name, (*m)->summary);
    return 0;
}

int main(int argc, char **argv)
{
    gi_log_init("gi");
    gi_blas_single_thread();
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    /* `gi render --help` and the like: the usage, not "unknown option". */
    for (int i = 2; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        }
    if (strcmp(cmd, "render") == 0)
        return cmd_render(argc, argv);
    if (strcmp(cmd, "validate") == 0)
        return cmd_validate(argc, argv);
    if (strcmp(cmd, "relight") == 0)
        return gi_relight_main(argc, argv);
    if (strcmp(cmd, "methods") == 0)
        return cmd_methods();
    if (gi_client_is_command(cmd))
        return gi_client_main(argc, argv);
    if (strcmp(cmd, "--version") == 0) {
        printf("gi %s\n", GI_VERSION);
        return 0;
    }
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        usage(stdout);
        return 0;
    }
    fprintf(stderr, "gi: unknown command \"%s\"\n", cmd);
    usage(stderr);
    return 2;
}
