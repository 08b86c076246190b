/* rad_factorizations: the thesis's Table 4.2 (and 4.3) on our scenes -
 * mean relative radiosity error against the dense solve for 2MF, 2MCE,
 * truncated SVD, CUR and ACA, over 70 emission vectors from a moving
 * projector, at k = n/16 and n/4 (and k/2 + 2 for the dense-factor
 * methods, the thesis's equal-information ranks).
 *
 *   rad_factorizations SCENE [rays] [frames]
 *     SCENE: "room" (generated: a closed room, 2 x 2 quads per wall, one
 *            cube; rad_scenes.h) or a scene file (the Cornell box)
 *
 * Everything derives from one sampled element-to-element F (rays per
 * element, stratified, seed 1): 2MF and 2MCE aggregate its counts over
 * patches (the thesis's exact 2MF variant), SVD and CUR factor the dense
 * F, ACA reads only rows of F (columns by reciprocity, A_i F_ij = A_j F_ji;
 * "ACA*" reads the sampled columns instead),
 * and the reference is the dense LU solve of (I - R_c F) B = E per colour.
 * The error of one emission is ||B~ - B|| / ||B|| over all three colours
 * (eq. 4.3); the table gives the mean over the frames (eq. 4.4) and the
 * matrix distance ||F - U V^T||_F (Table 4.3). OpenBLAS threads: 2. */
#include <cblas.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_assets.h"
#include "gi_rt.h"
#include "rad_bench.h"
#include "radiosity/rad.h"
#include "radiosity/rad_2mce.h"
#include "radiosity/rad_ff.h"
#include "radiosity/rad_lowrank.h"
#include "radiosity/rad_patches.h"
#include "radiosity/rad_scenes.h"

static void die(const gi_error *err) { rad_bench_die("rad_factorizations", err); }

typedef struct bench {
    uint32_t n, frames;
    const gi_rad_mesh *m;
    const double *F, *area;
    const double *rho[3]; /* n per colour */
    const double *E;      /* n x frames (grey: the same in every colour) */
    double *ref[3];       /* n x frames per colour */
} bench;

/* Mean over frames of ||B~ - B|| / ||B|| (eqs. 4.3-4.4). */
static double radiosity_error(const bench *b, const gi_rad_lowrank *lr)
{
    gi_error err;
    size_t nm = (size_t)b->n * b->frames;
    double *B = malloc(nm * sizeof *B), *d2 = calloc(b->frames, sizeof *d2),
           *s2 = calloc(b->frames, sizeof *s2);
    for (int c = 0; c < 3; c++) {
        if (gi_rad_lowrank_smw(lr, b->rho[c], b->E, b->frames, B, &err))
            die(&err);
        for (size_t i = 0; i < nm; i++) {
            double d = B[i] - b->ref[c][i];
            d2[i % b->frames] += d * d;
            s2[i % b->frames] += b->ref[c][i] * b->ref[c][i];
        }
    }
    double mean = 0.0;
    for (uint32_t j = 0; j < b->frames; j++)
        mean += sqrt(d2[j] / s2[j]);
    free(B), free(d2), free(s2);
    return mean / b->frames;
}

static void row(const char *method, uint32_t k, const bench *b, const gi_rad_lowrank *lr,
                double seconds)
{
    printf("| %-5s | %5u | %8.4f | %9.4f | %7.2f |\n", method, k, radiosity_error(b, lr),
           gi_rad_lowrank_distance(lr, b->F), seconds);
    fflush(stdout);
}

/* The nodes of `level` as patches, counted at level T. */
static void level_patches(const gi_rad_mesh *m, uint32_t level, uint32_t T, gi_rad_patches *pt)
{
    memset(pt, 0, sizeof *pt);
    pt->tracked_level = T;
    for (uint32_t q = 0; q < gi_rad_mesh_nodes(m, level); q++)
        gi_rad_patches_add(pt, level, q);
}

static void two_mesh(const char *name, const bench *b, const uint16_t *counts, uint32_t rays,
                     const gi_rad_patches *pt, double seconds)
{
    gi_error err;
    gi_rad_factor f;
    gi_rad_lowrank lr;
    if (gi_rad_factor_from_counts(&f, b->m, counts, b->n, rays, pt, &err) ||
        gi_rad_lowrank_from_factor(&lr, &f, &err))
        die(&err);
    row(name, f.k, b, &lr, seconds);
    gi_rad_lowrank_free(&lr);
    gi_rad_factor_free(&f);
}

typedef struct rows_ctx {
    const double *F, *area;
    uint32_t n;
} rows_ctx;

static int get_row(void *user, uint32_t i, double *out, gi_error *err)
{
    const rows_ctx *c = user;
    memcpy(out, c->F + (size_t)i * c->n, c->n * sizeof *out);
    return 0;
}

/* Column j of F as sampled. */
static int get_true_col(void *user, uint32_t j, double *out, gi_error *err)
{
    const rows_ctx *c = user;
    for (uint32_t i = 0; i < c->n; i++)
        out[i] = c->F[(size_t)i * c->n + j];
    return 0;
}

/* Column j from row j: F_ij = A_j F_ji / A_i (reciprocity). */
static int get_col(void *user, uint32_t j, double *out, gi_error *err)
{
    const rows_ctx *c = user;
    for (uint32_t i = 0; i < c->n; i++)
        out[i] = c->area[j] * c->F[(size_t)j * c->n + i] / c->area[i];
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: rad_factorizations room|SCENE.json [rays] [frames]\n");
        return 2;
    }
    uint32_t rays = argc > 2 ? (uint32_t)atoi(argv[2]) : 1024;
    uint32_t frames = argc > 3 ? (uint32_t)atoi(argv[3]) : 70;
    openblas_set_num_threads(2);
    gi_error err;
    gi_scene s;
    uint32_t patches;
    if (strcmp(argv[1], "room") == 0) {
        gi_rad_room_opts o = {2, 1, 0.25, {0, 0, 0}, 10.0};
        if (gi_rad_room_load(&o, &s, &err))
            die(&err);
        patches = 48; /* wall cells (1/4 of a wall) stay whole: 60 level-0 patches */
    } else {
        char *dir = strdup(argv[1]), *slash = strrchr(dir, '/');
        const char *name = argv[1];
        if (slash) {
            *slash = 0;
            name = slash + 1;
        }
        gi_dir_source ds;
        gi_dir_source_init(&ds, slash ? dir : ".");
        gi_asset_source src = gi_dir_source_as_source(&ds);
        if (gi_scene_load(&src, name, &s, &err))
            die(&err);
        gi_dir_source_free(&ds);
        free(dir);
        patches = 40;
    }
    gi_rad_mesh m;
    uint32_t L = 3;
    if (gi_rad_mesh_build(&m, &s, gi_rad_patch_area(&s, patches), L, &err))
        die(&err);
    uint32_t n = m.element_count;
    printf("scene %s: n = %u elements, %u level-0 patches, %u levels; %u rays per element; %u "
           "projector frames\n",
           argv[1], n, m.root_count, L, rays, frames);
    gi_rt rt;
    gi_rad_strata st;
    if (gi_rt_create(&rt, &s, &err) || gi_rad_strata_init(&st, rays, &err))
        die(&err);
    double t0 = now();
    uint16_t *counts = malloc((size_t)n * n * sizeof *counts);
    gi_rad_ff_opts fo = {1, L};
    gi_rad_ff_stats fs;
    if (gi_rad_ff_dense(&rt, &s, &m, &st, &fo, counts, n, &fs, &err))
        die(&err);
    double t_ff = now() - t0;
    double *F = malloc((size_t)n * n * sizeof *F), *area = malloc(n * sizeof *area);
    for (size_t i = 0; i < (size_t)n * n; i++)
        F[i] = counts[i] / (double)rays;
    for (uint32_t e = 0; e < n; e++)
        area[e] = gi_rad_mesh_element_area(&m, e);
    double *E = malloc((size_t)n * frames * sizeof *E);
    if (gi_rad_projector_emissions(&rt, &s, &m, frames, 64, 40.0, E, &err))
        die(&err);
    bench b = {n, frames, &m, F, area, {0}, E, {0}};
    double *rho[3];
    t0 = now();
    for (int c = 0; c < 3; c++) {
        rho[c] = malloc(n * sizeof *rho[c]);
        for (uint32_t e = 0; e < n; e++)
            rho[c][e] =
                gi_v3_get(s.materials[s.tri_material[gi_rad_mesh_element_tri(&m, e)]].diffuse, c);
        b.rho[c] = rho[c];
        b.ref[c] = malloc((size_t)n * frames * sizeof *b.ref[c]);
        if (gi_rad_dense_solve(F, n, rho[c], E, frames, b.ref[c], &err))
            die(&err);
    }
    double t_dense = now() - t0;
    printf("form factors (element level, one thread) %.1f s, escaped %.4f, back faces %.4f; "
           "dense reference solves (3 colours, %u right-hand sides) %.1f s\n",
           t_ff, (double)fs.escaped / ((double)n * rays), (double)fs.backface / ((double)n * rays),
           frames, t_dense);
    t0 = now();
    gi_rad_svd svd;
    if (gi_rad_svd_compute(&svd, F, n, &err))
        die(&err);
    double t_svd = now() - t0;
    printf(
        "\n| method | rank | error (4.4) | \\|F - UV^T\\|_F | seconds |\n|---|---|---|---|---|\n");
    for (uint32_t level = 1; level <= 2; level++) {
        uint32_t k = gi_rad_mesh_nodes(&m, level), kh = k / 2 + 2;
        gi_rad_patches pt;
        t0 = now();
        level_patches(&m, level, L, &pt);
        two_mesh("2MF", &b, counts, rays, &pt, now() - t0);
        gi_rad_patches_free(&pt);
        /* 2MCE: patches anywhere from level 0 down to one level below
         * 2MF's (max_level), the threshold tuned to 2MF's k as in the
         * thesis. */
        t0 = now();
        gi_rad_2mce c;
        double th;
        uint32_t T = level + 1, nT = gi_rad_mesh_nodes(&m, T), span = 1u << (2 * (L - T));
        uint16_t *cT = calloc((size_t)n * nT, sizeof *cT);
        for (uint32_t e = 0; e < n; e++)
            for (uint32_t j = 0; j < n; j++)
                cT[(size_t)e * nT + j / span] += counts[(size_t)e * n + j];
        if (gi_rad_2mce_metrics(&c, &m, cT, nT, T, rays, &err) ||
            gi_rad_2mce_tune(&c, &m, k, &th, &pt, &err))
            die(&err);
        double t_2mce = now() - t0;
        uint32_t per_level[4] = {0};
        for (uint32_t i = 0; i < pt.k; i++)
            per_level[pt.p[i].level]++;
        gi_rad_patches ptL;
        memset(&ptL, 0, sizeof ptL);
        ptL.tracked_level = L;
        for (uint32_t i = 0; i < pt.k; i++)
            gi_rad_patches_add(&ptL, pt.p[i].level, pt.p[i].node);
        two_mesh("2MCE", &b, counts, rays, &ptL, t_2mce);
        printf("|  | | 2MCE patches per level 0/1/2/3: %u/%u/%u/%u, threshold %.3g | | |\n",
               per_level[0], per_level[1], per_level[2], per_level[3], th);
        gi_rad_patches_free(&pt);
        gi_rad_patches_free(&ptL);
        gi_rad_2mce_free(&c);
        free(cT);
        uint32_t ranks[2] = {k, kh};
        for (int r = 0; r < 2; r++) {
            gi_rad_lowrank lr;
            if (gi_rad_svd_truncate(&svd, ranks[r], &lr, &err))
                die(&err);
            row("SVD", ranks[r], &b, &lr, t_svd);
            gi_rad_lowrank_free(&lr);
            t0 = now();
            if (gi_rad_cur(F, n, ranks[r], 2, &lr, &err))
                die(&err);
            row("CUR", ranks[r], &b, &lr, now() - t0);
            gi_rad_lowrank_free(&lr);
            rows_ctx rc = {F, area, n};
            t0 = now();
            if (gi_rad_aca(get_row, get_col, &rc, n, ranks[r], 0.0, &lr, &err))
                die(&err);
            row("ACA", lr.k, &b, &lr, now() - t0);
            gi_rad_lowrank_free(&lr);
            t0 = now();
            if (gi_rad_aca(get_row, get_true_col, &rc, n, ranks[r], 0.0, &lr, &err))
                die(&err);
            row("ACA*", lr.k, &b, &lr, now() - t0);
            gi_rad_lowrank_free(&lr);
        }
    }
    gi_rad_svd_free(&svd);
    for (int c = 0; c < 3; c++) {
        free(rho[c]);
        free(b.ref[c]);
    }
    free(counts), free(F), free(area), free(E);
    gi_rad_strata_free(&st);
    gi_rt_free(&rt);
    gi_rad_mesh_free(&m);
    gi_scene_free(&s);
    return 0;
}
