/* rad_relight: time per RGB relight (eq. 3.33) for the nine (n, k) cases of
 * the thesis's Table 4.7, beside its CPU and GPU columns.
 *
 *   rad_relight [rounds] [cases]      (cases: e.g. "1-9" or "8")
 *
 * Scene: the generated room with 4 x 4 quads per wall and two cubes (216
 * equal level-0 patches, rad_scenes.h), L levels below them (n = 216 4^L)
 * and 2MF patches at level l (k = 216 4^l). Form factors from 64 rays per
 * element: the time of a relight does not depend on the values, only on
 * whether the counts pack into 8 bits (with 64 rays they always do, with
 * the default 1024 almost always), and 64 keeps the set-up short. One
 * relight = V^T E (per-patch sums), the three k x k products M_c t_c
 * (cblas_sgemv), one pass over the factor's counts for the three colours
 * (rad_kernel.h), and B = E + R Y: everything between an emission vector
 * and its radiosity. Emission vectors: moving-projector frames, a
 * different one each time.
 *
 * Each round times every (case, kernel threads) pair once, in turn, so
 * the machine's drift spreads over all of them; the table gives medians
 * over the rounds. OpenBLAS threads: 1 for the relight (its k x k products
 * are small), 2 while building the SMW matrices (not timed). "batched" is
 * the per-emission time of 64 emissions relit as one matrix product. */
#include <cblas.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_rt.h"
#include "rad_bench.h"
#include "radiosity/rad.h"
#include "radiosity/rad_ff.h"
#include "radiosity/rad_patches.h"
#include "radiosity/rad_scenes.h"

#define BATCH 64
#define FRAMES 16

static const struct {
    uint32_t n, k;
    double cpu_ms, gpu_ms; /* thesis Table 4.7: (a) CPU, (b + c) GPU total */
} cases[9] = {
    {3456, 216, 1.27, 0.73},     {3456, 864, 4.64, 1.10},    {13824, 216, 5.23, 2.62},
    {3456, 3456, 14.53, 3.65},   {13824, 864, 20.14, 3.72},  {55296, 216, 22.70, 10.11},
    {13824, 3456, 72.77, 13.40}, {55296, 864, 88.37, 14.62}, {221184, 216, 86.99, 42.84},
};

static void die(const gi_error *err) { rad_bench_die("rad_relight", err); }

static uint32_t log4(uint32_t x)
{
    uint32_t l = 0;
    while (x > 1) {
        x /= 4;
        l++;
    }
    return l;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

typedef struct prepared {
    gi_rad_factor f;
    float *E, *B; /* FRAMES emissions; BATCH for the batched run */
    double setup_s;
} prepared;

static void prepare(int c, const gi_scene *s, prepared *p)
{
    gi_error err;
    double t0 = now();
    uint32_t L = log4(cases[c].n / 216), l = log4(cases[c].k / 216);
    gi_rad_mesh m;
    if (gi_rad_mesh_build(&m, s, gi_rad_patch_area(s, 216), L, &err))
        die(&err);
    if (m.element_count != cases[c].n || gi_rad_mesh_nodes(&m, l) != cases[c].k) {
        fprintf(stderr, "rad_relight: case %d: mesh has n = %u, k = %u\n", c + 1, m.element_count,
                gi_rad_mesh_nodes(&m, l));
        exit(1);
    }
    gi_rt rt;
    gi_rad_strata st;
    if (gi_rt_create(&rt, s, &err) || gi_rad_strata_init(&st, 64, &err))
        die(&err);
    uint32_t n = m.element_count, k = cases[c].k;
    uint16_t *counts = malloc((size_t)n * k * sizeof *counts);
    gi_rad_ff_opts o = {1, l};
    gi_rad_ff_stats fs;
    gi_rad_patches pt;
    gi_rad_2mf_patches(&m, l, &pt);
    if (gi_rad_ff_dense(&rt, s, &m, &st, &o, counts, k, &fs, &err) ||
        gi_rad_factor_from_counts(&p->f, &m, counts, k, 64, &pt, &err))
        die(&err);
    for (uint32_t e = 0; e < n; e++)
        for (int ch = 0; ch < 3; ch++)
            p->f.rho[3 * e + ch] = gi_v3_get(
                s->materials[s->tri_material[gi_rad_mesh_element_tri(&m, e)]].diffuse, ch);
    openblas_set_num_threads(2);
    if (gi_rad_factor_prepare(&p->f, &err))
        die(&err);
    openblas_set_num_threads(1);
    /* Emission vectors: projector frames, coloured differently per channel. */
    double *E = malloc((size_t)n * FRAMES * sizeof *E);
    if (gi_rad_projector_emissions(&rt, s, &m, FRAMES, 32, 40.0, E, &err))
        die(&err);
    p->E = malloc((size_t)BATCH * n * 3 * sizeof *p->E);
    p->B = malloc((size_t)BATCH * n * 3 * sizeof *p->B);
    for (uint32_t i = 0; i < BATCH; i++)
        for (uint32_t e = 0; e < n; e++)
            for (int ch = 0; ch < 3; ch++)
                p->E[((size_t)i * n + e) * 3 + ch] =
                    (float)(E[(size_t)e * FRAMES + i % FRAMES] * (1.0 + 0.25 * ch));
    free(E);
    free(counts);
    gi_rad_patches_free(&pt);
    gi_rad_strata_free(&st);
    gi_rt_free(&rt);
    gi_rad_mesh_free(&m);
    p->setup_s = now() - t0;
}

int main(int argc, char **argv)
{
    int rounds = argc > 1 ? atoi(argv[1]) : 15, first = 1, last = 9;
    if (argc > 2 && sscanf(argv[2], "%d-%d", &first, &last) == 1)
        last = first;
    if (rounds < 1 || first < 1 || last > 9 || first > last) {
        fprintf(stderr, "usage: rad_relight [rounds] [cases, e.g. 1-9]\n");
        return 2;
    }
    gi_error err;
    gi_scene s;
    gi_rad_room_opts ro = {4, 2, 0.25, {0, 0, 0}, 10.0};
    if (gi_rad_room_load(&ro, &s, &err))
        die(&err);
    int nc = last - first + 1;
    prepared *p = calloc((size_t)nc, sizeof *p);
    for (int c = 0; c < nc; c++) {
        prepare(first - 1 + c, &s, &p[c]);
        fprintf(stderr, "case %d ready (%.1f s, counts %s)\n", first + c, p[c].setup_s,
                p[c].f.hits8 ? "8-bit" : "16-bit");
    }
    openblas_set_num_threads(1);
    double *t1 = malloc((size_t)nc * rounds * sizeof *t1),
           *t2 = malloc((size_t)nc * rounds * sizeof *t2);
    double *tb = malloc((size_t)nc * rounds * sizeof *tb);
    for (int r = 0; r < rounds; r++)
        for (int c = 0; c < nc; c++) {
            size_t n3 = 3 * (size_t)p[c].f.n, at = (size_t)(r % FRAMES) * n3;
            for (int th = 1; th <= 2; th++) {
                double t0 = now();
                if (gi_rad_factor_relight(&p[c].f, p[c].E + at, p[c].B + at, 1, th, &err))
                    die(&err);
                (th == 1 ? t1 : t2)[c * rounds + r] = (now() - t0) * 1e3;
            }
            if (r < 3 || r % 3 == 0) { /* the batched run is long: fewer samples */
                double t0 = now();
                if (gi_rad_factor_relight(&p[c].f, p[c].E, p[c].B, BATCH, 1, &err))
                    die(&err);
                tb[c * rounds + r] = (now() - t0) * 1e3 / BATCH;
            } else {
                tb[c * rounds + r] = -1;
            }
        }
    printf(
        "| case | n | k | thesis CPU (1 channel) | thesis GPU (1 channel) | ours, 1 thread (RGB) | "
        "ours, 2 threads (RGB) | batched, per RGB relight |\n|---|---|---|---|---|---|---|---|\n");
    for (int c = 0; c < nc; c++) {
        int ci = first - 1 + c, nb = 0;
        double *b = malloc((size_t)rounds * sizeof *b);
        for (int r = 0; r < rounds; r++)
            if (tb[c * rounds + r] >= 0)
                b[nb++] = tb[c * rounds + r];
        printf("| %d | %u | %u | %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.2f ms |\n", ci + 1,
               cases[ci].n, cases[ci].k, cases[ci].cpu_ms, cases[ci].gpu_ms,
               median(t1 + c * rounds, rounds), median(t2 + c * rounds, rounds), median(b, nb));
        free(b);
        gi_rad_factor_free(&p[c].f);
        free(p[c].E);
        free(p[c].B);
    }
    printf("(medians of %d rounds; OpenBLAS threads 1; U read as 8-bit counts where they fit, "
           "see rad_kernel.h)\n",
           rounds);
    free(p), free(t1), free(t2), free(tb);
    gi_scene_free(&s);
    return 0;
}
