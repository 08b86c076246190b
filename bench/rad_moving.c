/* rad_moving: a moving object (thesis 4.5) - the error of the updated
 * solution (Algorithm 6 + double SMW, eqs. 3.38-3.43) against a full
 * re-solve, for k_delta = 50, 100, 200.
 *
 *   rad_moving [rays] [frames]
 *
 * Scene: the generated room (4 x 4 quads per wall, one cube of side 0.2;
 * rad_scenes.h), 2 levels (n = 3264, the cube 192 of them), 2MF patches at
 * level 1 (k = n/4 = 816; the thesis: k = 860 ~ n/4 in a Cornell box with
 * "a small cube"). The cube moves by (0.3, 0, 0.25). The change
 * matrix dF = F_F - F_I comes from re-casting only the rays that can see
 * the cube at either position (rad_dynamic.h); F_F = F_I + dF exactly
 * (the same rays). Emission: 70 projector frames (in the final state).
 *
 * Algorithm 6 runs on two change matrices: the element-level dF (the
 * pseudocode's), and the change at 2MF resolution dU V^T (the thesis's
 * Figs. 4.10-4.11: two 2MF factorizations' difference). Errors (eq. 4.4
 * over the frames, all colours) of the updated B^_F from U_I V_I^T +
 * U_d V_d^T against:
 *   - the dense solve with F_F (the "exact" B_F of the thesis's Fig. 4.12a),
 *   - a new 2MF factorization of F_F (B~_F, Fig. 4.12b): the full re-solve.
 * The first line (k_delta = 0) is the old factorization used unchanged.
 * OpenBLAS threads: 2. */
#include <cblas.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_rt.h"
#include "rad_bench.h"
#include "radiosity/rad.h"
#include "radiosity/rad_dynamic.h"
#include "radiosity/rad_ff.h"
#include "radiosity/rad_lowrank.h"
#include "radiosity/rad_patches.h"
#include "radiosity/rad_scenes.h"

static void die(const gi_error *err) { rad_bench_die("rad_moving", err); }

/* Mean over the m columns of ||A - B|| / ||B|| with three colours stacked. */
static double mean_error(double *const A[3], double *const B[3], uint32_t n, uint32_t m)
{
    double *d2 = calloc(m, sizeof *d2), *s2 = calloc(m, sizeof *s2), mean = 0.0;
    for (int c = 0; c < 3; c++)
        for (size_t i = 0; i < (size_t)n * m; i++) {
            d2[i % m] += (A[c][i] - B[c][i]) * (A[c][i] - B[c][i]);
            s2[i % m] += B[c][i] * B[c][i];
        }
    for (uint32_t j = 0; j < m; j++)
        mean += sqrt(d2[j] / s2[j]);
    free(d2), free(s2);
    return mean / m;
}

static void factor_2mf(const gi_rad_mesh *m, const uint16_t *counts, uint32_t rays,
                       gi_rad_lowrank *lr, gi_rad_sparse *dF, gi_rad_sparse *coarse)
{
    gi_error err;
    gi_rad_patches pt;
    memset(&pt, 0, sizeof pt);
    pt.tracked_level = m->levels;
    for (uint32_t q = 0; q < gi_rad_mesh_nodes(m, 1); q++)
        gi_rad_patches_add(&pt, 1, q);
    gi_rad_factor f;
    if (gi_rad_factor_from_counts(&f, m, counts, m->element_count, rays, &pt, &err) ||
        gi_rad_lowrank_from_factor(lr, &f, &err))
        die(&err);
    if (dF && gi_rad_delta_coarse(dF, f.patch, f.patch_count, f.k, coarse, &err))
        die(&err);
    gi_rad_factor_free(&f);
    gi_rad_patches_free(&pt);
}

int main(int argc, char **argv)
{
    uint32_t rays = argc > 1 ? (uint32_t)atoi(argv[1]) : 1024;
    uint32_t frames = argc > 2 ? (uint32_t)atoi(argv[2]) : 70;
    openblas_set_num_threads(2);
    gi_error err;
    gi_scene si, sf;
    gi_rad_room_opts oi = {4, 1, 0.2, {0, 0, 0}, 10.0}, of = {4, 1, 0.2, {0.3, 0, 0.25}, 10.0};
    if (gi_rad_room_load(&oi, &si, &err) || gi_rad_room_load(&of, &sf, &err))
        die(&err);
    int cube = gi_scene_find_object(&si, "cube_a");
    gi_rad_mesh m;
    if (gi_rad_mesh_build(&m, &si, 1.0 / 32, 2, &err))
        die(&err);
    uint32_t n = m.element_count;
    gi_rt ri, rf;
    gi_rad_strata st;
    if (gi_rt_create(&ri, &si, &err) || gi_rt_create(&rf, &sf, &err) ||
        gi_rad_strata_init(&st, rays, &err))
        die(&err);
    uint16_t *ci = malloc((size_t)n * n * sizeof *ci), *cf = malloc((size_t)n * n * sizeof *cf);
    gi_rad_ff_opts fo = {1, m.levels};
    gi_rad_ff_stats fs;
    double t0 = now();
    if (gi_rad_ff_dense(&ri, &si, &m, &st, &fo, ci, n, &fs, &err))
        die(&err);
    double t_full = now() - t0;
    gi_rad_sparse dF;
    gi_rad_delta_stats ds;
    t0 = now();
    if (gi_rad_delta(&ri, &si, &rf, &sf, &m, &st, 1, (uint32_t)cube, &dF, &ds, &err))
        die(&err);
    double t_delta = now() - t0;
    /* F_F = F_I + dF, as counts. */
    memcpy(cf, ci, (size_t)n * n * sizeof *cf);
    for (uint32_t e = 0; e < n; e++)
        for (uint64_t q = dF.row_ptr[e]; q < dF.row_ptr[e + 1]; q++)
            cf[(size_t)e * n + dF.col[q]] =
                (uint16_t)(ci[(size_t)e * n + dF.col[q]] + lrint(dF.val[q] * rays));
    printf("room, cube (side 0.2) moved by (0.3, 0, 0.25): n = %u, k = %u, %u rays per element, %u "
           "frames\n",
           n, gi_rad_mesh_nodes(&m, 1), rays, frames);
    printf("change matrix: %llu of %llu cells (%.2f%%); rays re-cast %llu of %llu (%.1f%%), %llu "
           "changed; %.2f s (all rays of one state: %.2f s)\n",
           (unsigned long long)dF.nnz, (unsigned long long)n * n, 100.0 * dF.nnz / ((double)n * n),
           (unsigned long long)ds.recast, (unsigned long long)ds.rays, 100.0 * ds.recast / ds.rays,
           (unsigned long long)ds.changed, t_delta, t_full);
    double *F = malloc((size_t)n * n * sizeof *F);
    for (size_t i = 0; i < (size_t)n * n; i++)
        F[i] = cf[i] / (double)rays;
    double *E = malloc((size_t)n * frames * sizeof *E);
    if (gi_rad_projector_emissions(&rf, &sf, &m, frames, 64, 40.0, E, &err))
        die(&err);
    double *rho[3], *exact[3], *resolve[3], *B[3];
    gi_rad_lowrank li, lf;
    gi_rad_sparse dFc;
    factor_2mf(&m, ci, rays, &li, &dF, &dFc);
    factor_2mf(&m, cf, rays, &lf, NULL, NULL);
    for (int c = 0; c < 3; c++) {
        rho[c] = malloc(n * sizeof *rho[c]);
        for (uint32_t e = 0; e < n; e++)
            rho[c][e] =
                gi_v3_get(si.materials[si.tri_material[gi_rad_mesh_element_tri(&m, e)]].diffuse, c);
        exact[c] = malloc((size_t)n * frames * sizeof *exact[c]);
        resolve[c] = malloc((size_t)n * frames * sizeof *resolve[c]);
        B[c] = malloc((size_t)n * frames * sizeof *B[c]);
        if (gi_rad_dense_solve(F, n, rho[c], E, frames, exact[c], &err) ||
            gi_rad_lowrank_smw(&lf, rho[c], E, frames, resolve[c], &err))
            die(&err);
    }
    printf("\nfull re-solve (new 2MF factorization of F_F) vs dense: %.4f\n\n",
           mean_error(resolve, exact, n, frames));
    printf("coarse change dU V^T (2MF resolution): %llu cells (%.2f%%)\n\n",
           (unsigned long long)dFc.nnz, 100.0 * dFc.nnz / ((double)n * n));
    printf("| change matrix | k_delta | columns + rows | nonzeros captured | error vs dense F_F | "
           "error vs 2MF re-solve | update seconds |\n|---|---|---|---|---|---|---|\n");
    uint32_t kds[4] = {0, 50, 100, 200};
    const gi_rad_sparse *which[2] = {&dF, &dFc};
    static const char *const names[2] = {"element dF", "coarse dU V^T"};
    for (int w = 0; w < 2; w++)
        for (int i = w; i < 4; i++) {
            t0 = now();
            gi_rad_alg6_stats as = {0, 0};
            gi_rad_lowrank d;
            if (kds[i] && gi_rad_alg6(which[w], kds[i], &d, &as, &err))
                die(&err);
            for (int c = 0; c < 3; c++)
                if (kds[i] ? gi_rad_update_solve(&li, &d, rho[c], E, frames, B[c], &err)
                           : gi_rad_lowrank_smw(&li, rho[c], E, frames, B[c], &err))
                    die(&err);
            double secs = now() - t0;
            printf("| %s | %u | %u | %.1f%% | %.4f | %.4f | %.2f |\n", kds[i] ? names[w] : "none",
                   kds[i], 2 * kds[i], kds[i] ? 100.0 * as.captured / as.nnz : 0.0,
                   mean_error(B, exact, n, frames), mean_error(B, resolve, n, frames), secs);
            fflush(stdout);
            if (kds[i])
                gi_rad_lowrank_free(&d);
        }
    printf("(k_delta = 0: the initial factorization, not updated)\n");
    for (int c = 0; c < 3; c++)
        free(rho[c]), free(exact[c]), free(resolve[c]), free(B[c]);
    gi_rad_lowrank_free(&li);
    gi_rad_lowrank_free(&lf);
    gi_rad_sparse_free(&dF);
    gi_rad_sparse_free(&dFc);
    free(ci), free(cf), free(F), free(E);
    gi_rad_strata_free(&st);
    gi_rt_free(&ri);
    gi_rt_free(&rf);
    gi_rad_mesh_free(&m);
    gi_scene_free(&si);
    gi_scene_free(&sf);
    return 0;
}
