/* gi_relight: `gi relight JOB.json EMISSIONS.json` - new emissions for a
 * finished radiosity job, from its factorization file, without form
 * factors or the scene (common/radiosity/rad_relight.h does the work).
 * With --images the camera images are rendered too, which needs the scene
 * and a local pool (image tiles run on workers). */
#include "gi_relight.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cblas.h>

#include "gi_args.h"
#include "gi_cores.h"
#include "gi_fs.h"
#include "gi_job.h"
#include "gi_local.h"
#include "gi_progress.h"
#include "radiosity/rad.h"

static void relight_usage(FILE *out)
{
    fprintf(out, "usage: gi relight JOB.json EMISSIONS.json [--out DIR] [--images] [--workers N] "
                 "[--threads N] [--progress MODE]\n");
}

/* Emissions files are small: names and colours. */
#define EMISSIONS_MAX_BYTES (64u << 20)

typedef struct relight_args {
    const char *job, *emissions, *out;
    gi_progress_mode progress;
    int images, workers, threads;
} relight_args;

/* An emissions file read and parsed (its own fields; names not checked). */
static int read_emissions(const char *path, gi_rad_emissions *em, gi_error *err)
{
    gi_buf text;
    gi_buf_init(&text);
    int rc = gi_read_file(path, EMISSIONS_MAX_BYTES, &text, err);
    if (rc == 0)
        rc = gi_rad_emissions_parse((const char *)text.data, text.len, path, em, err);
    gi_buf_free(&text);
    return rc;
}

static int parse_int(const char *opt, const char *s, int lo, int hi, int *out)
{
    int64_t v;
    if (gi_args_int(s, lo, hi, &v)) {
        fprintf(stderr, "gi relight: %s must be an integer in [%d, %d], got \"%s\"\n", opt, lo, hi,
                s);
        return -1;
    }
    *out = (int)v;
    return 0;
}

static int parse_args(int argc, char **argv, relight_args *a)
{
    memset(a, 0, sizeof *a);
    a->out = "out";
    a->progress = GI_PROGRESS_NONE;
    a->threads = gi_cores_usable();
    for (int i = 2; i < argc; i++) {
        const char *arg = argv[i];
        if (strcmp(arg, "--images") == 0) {
            a->images = 1;
        } else if (strcmp(arg, "--out") == 0 || strcmp(arg, "--workers") == 0 ||
                   strcmp(arg, "--threads") == 0 || strcmp(arg, "--progress") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "gi relight: %s needs a value\n", arg);
                return -1;
            }
            const char *v = argv[++i];
            if (strcmp(arg, "--out") == 0)
                a->out = v;
            else if (strcmp(arg, "--progress") == 0) {
                if (gi_progress_mode_parse(v, &a->progress)) {
                    fprintf(stderr,
                            "gi relight: --progress must be auto, bar, lines, json or none\n");
                    return -1;
                }
            } else if (parse_int(arg, v, 1, 1024,
                                 strcmp(arg, "--workers") == 0 ? &a->workers : &a->threads))
                return -1;
        } else if (arg[0] == '-' && arg[1]) {
            fprintf(stderr, "gi relight: unknown option %s (gi --help lists them)\n", arg);
            return -1;
        } else if (!a->job) {
            a->job = arg;
        } else if (!a->emissions) {
            a->emissions = arg;
        } else {
            fprintf(stderr, "gi relight: unexpected argument %s\n", arg);
            return -1;
        }
    }
    if (!a->job || !a->emissions) {
        relight_usage(stderr);
        return -1;
    }
    return 0;
}

static double now_ms(void)
{
    return gi_now() * 1e3;
}

static void print_written(void *user, const char *kind, const char *path)
{
    printf("  %-4s %s\n", kind, path);
}

/* The files relight writes in a->out: each kind's file per emission set,
 * the report as NAME-relight (rad_relight.h); exr and png with --images.
 * Returns how many paths (malloc'ed) it put in `paths`, kinds beside. */
static int relight_outputs(const relight_args *a, const gi_job *job, const gi_rad_emissions *em,
                           char ***paths, const char ***kinds)
{
    static const char *const per_set[] = {"ply", "glb", "exr", "png"};
    int n = 0, cap = (int)(4 * em->count + 1);
    *paths = gi_xcalloc((size_t)cap, sizeof **paths);
    *kinds = gi_xcalloc((size_t)cap, sizeof **kinds);
    for (int k = 0; k < (a->images ? 4 : 2); k++) {
        const char *file = gi_job_output(job, per_set[k]);
        for (uint32_t i = 0; file && i < em->count; i++, n++) {
            char *name = gi_rad_output_name(file, em->items[i].name);
            (*paths)[n] = gi_path_join(a->out, name);
            (*kinds)[n] = per_set[k];
            free(name);
        }
    }
    const char *rep = gi_job_output(job, "report");
    if (rep) {
        char *name = gi_rad_output_name(rep, "relight");
        (*paths)[n] = gi_path_join(a->out, name);
        (*kinds)[n++] = "report";
        free(name);
    }
    return n;
}

/* Refuses, before anything is written, outputs that would replace what the
 * relight reads: the job file, its scene's files, the factorization and
 * the emissions file. Without --images the scene is not loaded; it is read
 * here only if an output exists already (else nothing can be replaced), to
 * learn the files it names: a scene that does not load names those read
 * before it failed, which is all an output could replace. */
static int outputs_spare_inputs(const relight_args *a, gi_job *job, const char *fpath,
                                const gi_rad_emissions *em, gi_error *err)
{
    char **paths;
    const char **kinds;
    int n = relight_outputs(a, job, em, &paths, &kinds), exists = 0;
    for (int i = 0; i < n && !exists; i++)
        exists = access(paths[i], F_OK) == 0;
    int rc = 0;
    if (exists) {
        if (!job->scene_loaded && job->manifest.count == 0) {
            char *dir = gi_dirname(a->job);
            gi_dir_source ds;
            gi_dir_source_init(&ds, dir);
            free(dir);
            gi_asset_source src = gi_dir_source_as_source(&ds);
            gi_scene scene;
            gi_error ignored;
            if (gi_scene_load(&src, job->scene_name, &scene, &ignored) == 0)
                gi_scene_free(&scene);
            job->manifest = ds.manifest;
            gi_manifest_init(&ds.manifest);
            gi_dir_source_free(&ds);
        }
        gi_job_inputs in;
        gi_job_inputs_init(&in, job, a->job);
        gi_job_inputs_add(&in, fpath, "the factorization it relights");
        gi_job_inputs_add(&in, a->emissions, "the emissions file");
        for (int i = 0; i < n && rc == 0; i++)
            rc = gi_job_inputs_spare(&in, paths[i], a->job, kinds[i], err);
        gi_job_inputs_free(&in);
    }
    for (int i = 0; i < n; i++)
        free(paths[i]);
    free(paths);
    free(kinds);
    return rc;
}

static int relight(const relight_args *a, gi_error *err)
{
    gi_job job;
    int images = a->images;
    /* Without images the scene is not needed: the job is only parsed. */
    if (images ? gi_job_load(a->job, &job, err) : gi_job_read(a->job, &job, err)) {
        gi_job_free(&job);
        return -1;
    }
    int rc = -1;
    gi_rad_file_info info;
    gi_rad_model md;
    gi_rad_factor f;
    gi_rad_emissions em;
    memset(&md, 0, sizeof md);
    memset(&f, 0, sizeof f);
    memset(&em, 0, sizeof em);
    float *E = NULL, *B = NULL;
    gi_rad_solve_info *si = NULL;
    char *fpath = NULL;
    if (strcmp(job.method->name, "radiosity") != 0) {
        gi_fail(err, GI_EINVAL, "%s: relight needs a radiosity job, not %s", a->job,
                job.method->name);
        goto done;
    }
    const char *ffile = gi_job_output(&job, "factorization");
    if (!ffile) {
        gi_fail(err, GI_EINVAL, "%s: the job writes no \"factorization\" output to relight",
                a->job);
        goto done;
    }
    fpath = gi_path_join(a->out, ffile);
    /* The usual slip: the job was rendered into another --out, or not yet. */
    if (access(fpath, F_OK) != 0 && errno == ENOENT) {
        gi_fail(err, GI_EINVAL,
                "%s: no such file: relight reads the factorization the job wrote; render it "
                "first (gi render %s --out DIR, or gi fetch ID --out DIR from a farm) and give "
                "relight the same --out DIR",
                fpath, a->job);
        goto done;
    }
    double t0 = now_ms();
    if (gi_rad_file_read(fpath, &info, &md, &f, err))
        goto done;
    double t_load = now_ms() - t0;
    if ((rc = read_emissions(a->emissions, &em, err)) ||
        (rc = gi_rad_emissions_check(&em, &md, a->emissions, err)))
        goto done;
    rc = -1;
    if (outputs_spare_inputs(a, &job, fpath, &em, err) || gi_output_dir_ready(a->out, err))
        goto done;
    if (images) {
        /* The method renders the tiles (and writes every output) in relight
         * mode: it solves, publishes, and plans only image tiles. */
        gi_rad_params *p = job.params;
        p->relight_info = &info;
        p->relight_model = &md;
        p->relight_factor = &f;
        p->relight_emissions = &em;
        /* No checkpoint: relighting is fast, and its state lives in memory. */
        gi_local_opts opts = {a->workers, a->progress, -1.0, 0, 0.0};
        job.out_dir = gi_xstrdup(a->out);
        gi_local_summary sum;
        double t1 = now_ms();
        if (gi_render_local(&job, &opts, &sum, err))
            goto done;
        printf("%s: relit %u emission set%s with images in %.1f ms (factorization loaded in "
               "%.1f ms)\n",
               job.name, em.count, em.count == 1 ? "" : "s", now_ms() - t1, t_load);
        for (int i = 0; i + 1 < job.written_count; i += 2)
            printf("  %-4s %s\n", job.written[i], job.written[i + 1]);
        rc = 0;
        goto done;
    }
    size_t n3 = 3 * (size_t)f.n;
    E = gi_try_malloc(em.count * n3 * sizeof *E, err, "relight");
    B = gi_try_malloc(em.count * n3 * sizeof *B, err, "relight");
    si = gi_xcalloc(em.count, sizeof *si);
    if (!E || !B)
        goto done;
    gi_rad_solve_opts so;
    gi_rad_solve_opts_default(&so);
    so.threads = a->threads;
    openblas_set_num_threads(1); /* k x k products: one thread is enough */
    if (gi_rad_solve_emissions(&f, &md, &em, &so, E, B, si, err))
        goto done;
    double total = 0.0, worst = 0.0;
    for (uint32_t i = 0; i < em.count; i++) {
        total += si[i].seconds * 1e3;
        worst = si[i].seconds * 1e3 > worst ? si[i].seconds * 1e3 : worst;
    }
    printf("%s: relit %u emission set%s (n = %u elements, k = %u patches) in %.2f ms, %.2f ms "
           "per set (slowest %.2f ms, %d thread%s); factorization loaded in %.1f ms\n",
           job.name, em.count, em.count == 1 ? "" : "s", f.n, f.k, total, total / em.count, worst,
           a->threads, a->threads == 1 ? "" : "s", t_load);
    rc = gi_rad_relight_write(a->out, gi_job_output(&job, "ply"), gi_job_output(&job, "glb"),
                              gi_job_output(&job, "report"), job.name, job.exposure, &info, &md, &f, &em, E, B, si, print_written,
                              NULL, err);
done:
    free(fpath);
    free(E);
    free(B);
    free(si);
    gi_rad_emissions_free(&em);
    gi_rad_model_free(&md);
    gi_rad_factor_free(&f);
    gi_job_free(&job);
    return rc;
}

static const char *set_name(const void *em, uint32_t i)
{
    return ((const gi_rad_emissions *)em)->items[i].name;
}

int gi_relight_validate(const char *job_path, const char *emissions_path)
{
    gi_error err;
    gi_error_clear(&err);
    gi_job job;
    int job_loaded = 0;
    gi_rad_emissions em;
    memset(&em, 0, sizeof em);
    if (job_path) {
        job_loaded = 1;
        if (gi_job_load(job_path, &job, &err) == 0 &&
            strcmp(job.method->name, "radiosity") != 0)
            gi_fail(&err, GI_EINVAL, "%s: an emissions file is for a radiosity job (gi relight), "
                    "not %s", job_path, job.method->name);
    }
    if (err.code == GI_OK && read_emissions(emissions_path, &em, &err) == 0 && job_path)
        gi_rad_emissions_check_scene(&em, &job.scene, emissions_path, "emissions", &err);
    if (err.code != GI_OK) {
        fprintf(stderr, "gi: %s\n", err.msg);
    } else {
        char names[400];
        printf("%s: ok (%u emission set%s: %s", emissions_path, em.count,
               em.count == 1 ? "" : "s", gi_rad_name_list(names, sizeof names, em.count,
                                                          set_name, &em));
        if (job_path)
            printf("; names found in %s's scene %s)\n", job_path, job.scene_name);
        else
            printf("; its material and object names are not checked without the job: gi "
                   "validate JOB.json %s)\n", emissions_path);
    }
    gi_rad_emissions_free(&em);
    if (job_loaded)
        gi_job_free(&job);
    return err.code != GI_OK ? gi_error_exit_status(&err) : 0;
}

int gi_relight_main(int argc, char **argv)
{
    relight_args a;
    if (parse_args(argc, argv, &a))
        return 2;
    gi_error err;
    gi_error_clear(&err);
    if (relight(&a, &err)) {
        fprintf(stderr, "gi: %s\n", err.msg);
        return gi_error_exit_status(&err);
    }
    return 0;
}
