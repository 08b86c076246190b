/* quad_vs_pt: the quadrature renderer against the path tracer on the
 * Cornell box at equal wall time: relative RMSE against a converged
 * reference, for direct light (quadrature N = 4, pt max_bounces 1) and for
 * one bounce (N = 6, pt max_bounces 2).
 *
 *   quad_vs_pt SCENE OUTDIR [REF_SPP] [ROUNDS]
 *
 * The reference is the mean of two path tracer renders of REF_SPP samples
 * (default 16384; kept in OUTDIR and reused) with other seeds: it is
 * independent of both methods under test. Its own noise is known from the
 * difference of its two halves (noise^2 = rmse(a, b)^2 / 4), and since a
 * test image's error is independent of it, E rmse(x, ref)^2 = err(x)^2 +
 * noise^2: the table gives the raw figure and the one with the reference's
 * noise taken out.
 *
 * Per budget: the quadrature's wall time (median of ROUNDS runs, default 3,
 * each followed by a path tracer run at a calibration sample count, so the
 * two alternate on this shared machine); the path tracer's sample rate
 * from those calibration runs gives the samples per pixel that take the
 * same time, corrected once by a run at that count; then ROUNDS path tracer
 * runs at the corrected count (other seeds) give its median time and RMSE. Both use 2 pool workers (gi_render_local). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench/bench_util.h"
#include "gi_fs.h"
#include "gi_image.h"
#include "gi_job.h"
#include "gi_local.h"

static const char *scene_path, *out_dir;

/* Writes a job named `name` with the given method block, renders it with 2
 * workers; returns the wall time or exits. */
static double render(const char *name, int size, const char *method, const char *block)
{
    char path[1024], text[2048];
    snprintf(path, sizeof path, "%s/%s.json", out_dir, name);
    snprintf(text, sizeof text,
             "{\"name\": \"%s\", \"scene\": \"%s\", \"method\": \"%s\", %s, "
             "\"image\": {\"width\": %d, \"height\": %d}, \"outputs\": {\"exr\": \"%s.exr\"}}",
             name, scene_path, method, block, size, size, name);
    gi_error err;
    if (gi_write_file_atomic(path, text, strlen(text), &err)) {
        fprintf(stderr, "quad_vs_pt: %s\n", err.msg);
        exit(1);
    }
    gi_job job;
    if (gi_job_load(path, &job, &err)) {
        fprintf(stderr, "quad_vs_pt: %s\n", err.msg);
        exit(1);
    }
    job.out_dir = gi_xstrdup(out_dir);
    gi_local_opts opts = {2, GI_PROGRESS_NONE, -1.0, 0, 0.0}; /* no checkpoint files */
    gi_local_summary sum;
    double t0 = gi_bench_now();
    int rc = gi_render_local(&job, &opts, &sum, &err);
    double t = gi_bench_now() - t0;
    gi_job_free(&job);
    if (rc) {
        fprintf(stderr, "quad_vs_pt: %s: %s\n", name, err.msg);
        exit(1);
    }
    return t;
}

static void read_exr(const char *name, gi_image *img)
{
    char path[1024];
    gi_error err;
    snprintf(path, sizeof path, "%s/%s.exr", out_dir, name);
    if (gi_exr_read(path, img, &err)) {
        fprintf(stderr, "quad_vs_pt: %s\n", err.msg);
        exit(1);
    }
}

/* Relative RMSE of a against r (channels matched by name), as gi_imgtool. */
static double rel_rmse(const gi_image *a, const gi_image *r)
{
    static const char *const names[3] = {"R", "G", "B"};
    double se = 0, sum = 0;
    size_t n = (size_t)a->width * a->height;
    for (int c = 0; c < 3; c++) {
        int ka = gi_image_channel(a, names[c]), kr = gi_image_channel(r, names[c]);
        for (size_t i = 0; i < n; i++) {
            double d = a->pixels[i * a->channels + ka] - r->pixels[i * r->channels + kr];
            se += d * d;
            sum += r->pixels[i * r->channels + kr];
        }
    }
    return sqrt(se / (3.0 * n)) / (sum / (3.0 * n));
}

static int file_exists(const char *name)
{
    char path[1024];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s.exr", out_dir, name);
    return stat(path, &st) == 0;
}

typedef struct bench_case {
    const char *name;
    int size, dims, max_bounces;
    const char *rule;
    const long *budgets;
} bench_case;

static void run_case(const bench_case *bc, int ref_spp, int rounds)
{
    char name[128], block[512], name_a[128], name_b[128];
    snprintf(name_a, sizeof name_a, "ref-%d-b%d-%d-a", bc->size, bc->max_bounces, ref_spp);
    snprintf(name_b, sizeof name_b, "ref-%d-b%d-%d-b", bc->size, bc->max_bounces, ref_spp);
    for (int k = 0; k < 2; k++) {
        const char *n = k ? name_b : name_a;
        if (file_exists(n))
            continue;
        snprintf(block, sizeof block, "\"seed\": %d, \"pt\": {\"spp\": %d, \"max_bounces\": %d}",
                 9001 + k, ref_spp, bc->max_bounces);
        double t = render(n, bc->size, "pt", block);
        fprintf(stderr, "reference %s: %.1f s\n", n, t);
    }
    gi_image ra, rb, ref;
    gi_error err;
    read_exr(name_a, &ra);
    read_exr(name_b, &rb);
    if (gi_image_init(&ref, ra.width, ra.height, ra.channels, NULL, &err))
        exit(1);
    memcpy(ref.names, ra.names, sizeof ref.names);
    for (size_t i = 0; i < (size_t)ra.width * ra.height * ra.channels; i++)
        ref.pixels[i] = 0.5f * (ra.pixels[i] + rb.pixels[i]);
    double noise = rel_rmse(&ra, &rb) / 2.0;
    printf("\n%s: %dx%d, quadrature N = %d (%s) vs pt max_bounces %d; reference: 2 x %d spp, "
           "its own relative RMSE %.4f\n",
           bc->name, bc->size, bc->size, bc->dims, bc->rule, bc->max_bounces, ref_spp, noise);
    printf("| evaluations | quadrature time | its RMSE (noise out) | pt spp | pt time | pt RMSE "
           "(noise out) | ratio |\n|---|---|---|---|---|---|---|\n");
    fflush(stdout);
    for (const long *b = bc->budgets; *b; b++) {
        double tq[16], rate[16];
        const int calib_spp = 16;
        for (int r = 0; r < rounds; r++) {
            snprintf(name, sizeof name, "q-%s-%ld", bc->name, *b);
            snprintf(block, sizeof block,
                     "\"quadrature\": {\"dims\": %d, \"rule\": \"%s\", \"max_evals\": %ld}", bc->dims,
                     bc->rule, *b);
            tq[r] = render(name, bc->size, "quadrature", block);
            snprintf(block, sizeof block,
                     "\"seed\": %d, \"pt\": {\"spp\": %d, \"max_bounces\": %d}", 77 + r, calib_spp,
                     bc->max_bounces);
            double tc = render("calib", bc->size, "pt", block);
            rate[r] = (double)calib_spp * bc->size * bc->size / tc;
        }
        gi_image q;
        read_exr(name, &q);
        double eq = rel_rmse(&q, &ref);
        gi_image_free(&q);
        double t_quad = gi_bench_median(tq, rounds), pt_rate = gi_bench_median(rate, rounds);
        int spp = (int)floor(pt_rate * t_quad / ((double)bc->size * bc->size) + 0.5);
        if (spp < 1)
            spp = 1;
        /* A render's fixed costs (fork, scene, Embree build) weigh more at
         * the calibration's 16 spp: one run at the estimate corrects it. */
        snprintf(name, sizeof name, "p-%s-%ld", bc->name, *b);
        snprintf(block, sizeof block, "\"seed\": 500, \"pt\": {\"spp\": %d, \"max_bounces\": %d}",
                 spp, bc->max_bounces);
        double t1 = render(name, bc->size, "pt", block);
        double f = t_quad / t1;
        f = f < 0.25 ? 0.25 : f > 4.0 ? 4.0 : f;
        spp = (int)floor(spp * f + 0.5);
        if (spp < 1)
            spp = 1;
        double tp[16], ep[16];
        for (int r = 0; r < rounds; r++) {
            snprintf(name, sizeof name, "p-%s-%ld", bc->name, *b);
            snprintf(block, sizeof block,
                     "\"seed\": %d, \"pt\": {\"spp\": %d, \"max_bounces\": %d}", 1000 + r, spp,
                     bc->max_bounces);
            tp[r] = render(name, bc->size, "pt", block);
            gi_image p;
            read_exr(name, &p);
            ep[r] = rel_rmse(&p, &ref);
            gi_image_free(&p);
        }
        double e_pt = gi_bench_median(ep, rounds);
        double cq = sqrt(fmax(0.0, eq * eq - noise * noise));
        double cp = sqrt(fmax(0.0, e_pt * e_pt - noise * noise));
        printf("| %ld | %.2f s | %.4f (%.4f) | %d | %.2f s | %.4f (%.4f) | %.2f (%.2f) |\n", *b,
               t_quad, eq, cq, spp, gi_bench_median(tp, rounds), e_pt, cp, eq / e_pt,
               cp > 0 ? cq / cp : 0.0);
        fflush(stdout);
    }
    gi_image_free(&ra);
    gi_image_free(&rb);
    gi_image_free(&ref);
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: quad_vs_pt SCENE OUTDIR [REF_SPP] [ROUNDS]\n");
        return 2;
    }
    static char scene_abs[4096];
    if (!realpath(argv[1], scene_abs)) {
        fprintf(stderr, "quad_vs_pt: %s: no such scene\n", argv[1]);
        return 2;
    }
    scene_path = scene_abs;
    out_dir = argv[2];
    int ref_spp = argc > 3 ? atoi(argv[3]) : 16384;
    int rounds = argc > 4 ? atoi(argv[4]) : 3;
    gi_error err;
    if (ref_spp < 1 || rounds < 1 || rounds > 16 || gi_mkdirs(out_dir, &err)) {
        fprintf(stderr, "quad_vs_pt: bad arguments or output directory\n");
        return 2;
    }
    static const long direct[] = {250000, 500000, 1000000, 2000000, 4000000, 0};
    static const long bounce[] = {1000000, 4000000, 16000000, 0};
    bench_case cases[] = {
        {"direct", 64, 4, 1, "boole", direct},
        {"direct-gm", 64, 4, 1, "genz-malik", direct},
        {"bounce", 32, 6, 2, "genz-malik", bounce},
        {"bounce-boole", 32, 6, 2, "boole", bounce},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        run_case(&cases[i], ref_spp, rounds);
    return 0;
}
