/* Unit tests: radiosity solvers - the 16-bit kernel, Neumann vs SMW, the
 * validation factorizations (SVD, CUR, maxvol, ACA), Algorithm 6 with the
 * double SMW update, and the change matrix of a moving object. */
#include <cblas.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <lapacke.h>

#include "gi_rng.h"
#include "gi_rt.h"
#include "gi_test.h"
#include "radiosity/rad.h"
#include "radiosity/rad_dynamic.h"
#include "radiosity/rad_ff.h"
#include "radiosity/rad_kernel.h"
#include "radiosity/rad_lowrank.h"
#include "radiosity/rad_patches.h"
#include "test_helpers.h"

GI_TEST(test_rad_kernel_paths_agree_bit_for_bit_and_with_double)
{
    gi_error err;
    uint32_t n = 90000, k = 37; /* n x k_pad above the kernel's threading threshold */
    gi_rad_factor f;
    GI_REQUIRE_OK(gi_rad_factor_alloc(&f, n, k, 4096, &err));
    uint32_t kp = f.k_pad;
    float *s = calloc(3 * (size_t)kp, sizeof *s);
    float *y[6];
    for (int i = 0; i < 6; i++)
        y[i] = malloc(3 * (size_t)n * sizeof *y[i]);
    gi_rng r;
    gi_rng_init(&r, 1, 2, 3);
    for (uint32_t e = 0; e < n; e++)
        for (uint32_t p = 0; p < k; p++) /* mostly small counts, a few large */
            f.hits[(size_t)e * kp + p] =
                (uint16_t)(gi_rng_below(&r, 100) == 0 ? 256 + gi_rng_below(&r, 3000)
                                                      : gi_rng_below(&r, 40));
    for (int c = 0; c < 3; c++)
        for (uint32_t p = 0; p < k; p++)
            s[(size_t)c * kp + p] = gi_rng_float(&r) * 1e-3f;
    gi_rad_counts u16, u8;
    gi_rad_factor_counts(&f, &u16);
    GI_REQUIRE_OK(gi_rad_factor_pack(&f, &err));
    GI_REQUIRE(f.hits8 != NULL && f.over_count > 0);
    gi_rad_factor_counts(&f, &u8);
    u16.h8 = NULL;
    const gi_rad_counts *us[2] = {&u16, &u8};
    for (int w = 0; w < 2; w++) {
        float **yy = y + 3 * w;
        gi_rad_apply3(us[w], s, yy[0], 3); /* threads split rows */
        int have_avx2 = gi_rad_apply3_avx2(us[w], s, yy[1], 0, n);
        if (have_avx2)
            GI_CHECK_MSG(memcmp(yy[0], yy[1], 3 * (size_t)n * sizeof(float)) == 0,
                         "%s: threads change bits", w ? "8-bit" : "16-bit");
        /* The portable path (slow: fmaf calls) on two row ranges. */
        uint32_t r0[2] = {0, n / 2};
        for (int q = 0; q < 2; q++) {
            gi_rad_apply3_portable(us[w], s, yy[2], r0[q], r0[q] + 2000);
            GI_CHECK_MSG(memcmp(yy[0] + 3 * (size_t)r0[q], yy[2] + 3 * (size_t)r0[q],
                                3 * 2000 * sizeof(float)) == 0,
                         "%s: portable path differs", w ? "8-bit" : "16-bit");
        }
        /* Against a double-precision product. */
        double worst = 0.0;
        for (uint32_t e = 0; e < n; e += 7)
            for (int c = 0; c < 3; c++) {
                double ref = 0.0;
                for (uint32_t p = 0; p < k; p++)
                    ref += (double)f.hits[(size_t)e * kp + p] * s[(size_t)c * kp + p];
                double d = fabs(ref - yy[0][3 * (size_t)e + c]) / (fabs(ref) + 1e-30);
                worst = d > worst ? d : worst;
            }
        GI_CHECK_MSG(worst < 1e-5, "relative error %g", worst);
    }
    /* Too many large counts: packing is declined. */
    for (size_t i = 0; i < (size_t)n * kp; i += 7)
        f.hits[i] = 1000;
    GI_REQUIRE_OK(gi_rad_factor_pack(&f, &err));
    GI_CHECK(f.hits8 == NULL);
    for (int i = 0; i < 6; i++)
        free(y[i]);
    free(s);
    gi_rad_factor_free(&f);
}

/* The Cornell box job's factorization, built in process. */
typedef struct built {
    gi_scene s;
    gi_rad_mesh m;
    gi_rad_factor f;
    gi_rad_model md;
} built;

static int build_cornell(built *b, uint32_t patches, uint32_t levels, uint32_t rays, gi_error *err)
{
    memset(b, 0, sizeof *b);
    if (gi_test_load_scene_file("scenes/cornell-box/scene.json", &b->s, err) ||
        gi_rad_mesh_build(&b->m, &b->s, gi_rad_patch_area(&b->s, patches), levels, err))
        return -1;
    gi_rt rt;
    gi_rad_strata st;
    if (gi_rt_create(&rt, &b->s, err) || gi_rad_strata_init(&st, rays, err))
        return -1;
    uint32_t n = b->m.element_count, k = b->m.root_count;
    uint16_t *h = malloc((size_t)n * k * sizeof *h);
    gi_rad_ff_opts o = {1, 0};
    gi_rad_ff_stats fs;
    int rc = gi_rad_ff_dense(&rt, &b->s, &b->m, &st, &o, h, k, &fs, err);
    gi_rad_patches pt;
    gi_rad_2mf_patches(&b->m, 0, &pt);
    if (rc == 0)
        rc = gi_rad_factor_from_counts(&b->f, &b->m, h, k, rays, &pt, err);
    if (rc == 0)
        rc = gi_rad_model_build(&b->md, &b->m, &b->s, err);
    if (rc == 0) {
        gi_rad_model_reflectance(&b->md, b->f.rho);
        rc = gi_rad_factor_prepare(&b->f, err);
    }
    gi_rad_patches_free(&pt);
    free(h);
    gi_rad_strata_free(&st);
    gi_rt_free(&rt);
    return rc;
}

static void built_free(built *b)
{
    gi_rad_model_free(&b->md);
    gi_rad_factor_free(&b->f);
    gi_rad_mesh_free(&b->m);
    gi_scene_free(&b->s);
}

static double rel_diff(const float *a, const float *b, size_t n)
{
    double d = 0.0, s = 0.0;
    for (size_t i = 0; i < n; i++) {
        d += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        s += (double)b[i] * b[i];
    }
    return sqrt(d / s);
}

GI_TEST(test_rad_neumann_and_smw_agree)
{
    gi_error err;
    built b;
    GI_REQUIRE_OK(build_cornell(&b, 60, 2, 256, &err));
    uint32_t n = b.f.n;
    gi_rad_emissions em;
    gi_rad_emissions_scene(&em);
    float *E = malloc(3 * (size_t)n * sizeof *E), *B1 = malloc(3 * (size_t)n * sizeof *B1);
    float *B2 = malloc(3 * (size_t)n * sizeof *B2);
    gi_rad_emission_vector(&em, 0, &b.md, E);
    /* Single precision, as relighting runs (eq. 3.33 vs eq. 3.30). */
    int it = 0;
    double res;
    GI_REQUIRE_OK(gi_rad_factor_relight(&b.f, E, B1, 1, 1, &err));
    GI_REQUIRE_OK(gi_rad_factor_neumann(&b.f, E, B2, 1e-7, 1000, 2, &it, &res, &err));
    GI_CHECK_MSG(rel_diff(B2, B1, 3 * (size_t)n) < 1e-5, "float: %g after %d iterations",
                 rel_diff(B2, B1, 3 * (size_t)n), it);
    GI_CHECK(it > 3 && res <= 1e-7);
    /* The lamp dominates ||B||: the reflected part C = B - E must agree
     * too (eq. 3.44's C, where the solvers actually differ). */
    float *C1 = malloc(3 * (size_t)n * sizeof *C1), *C2 = malloc(3 * (size_t)n * sizeof *C2);
    for (size_t i = 0; i < 3 * (size_t)n; i++) {
        C1[i] = B1[i] - E[i];
        C2[i] = B2[i] - E[i];
    }
    GI_CHECK_MSG(rel_diff(C2, C1, 3 * (size_t)n) < 1e-4, "reflected part: %g",
                 rel_diff(C2, C1, 3 * (size_t)n));
    free(C1), free(C2);
    /* Double precision, per colour (eq. 3.32 vs eq. 3.30). */
    gi_rad_lowrank lr;
    GI_REQUIRE_OK(gi_rad_lowrank_from_factor(&lr, &b.f, &err));
    double *rho = malloc(n * sizeof *rho), *e = malloc(n * sizeof *e);
    double *d1 = malloc(n * sizeof *d1), *d2 = malloc(n * sizeof *d2);
    for (int c = 0; c < 3; c++) {
        for (uint32_t i = 0; i < n; i++) {
            rho[i] = b.f.rho[3 * i + c];
            e[i] = E[3 * i + c];
        }
        GI_REQUIRE_OK(gi_rad_lowrank_smw(&lr, rho, e, 1, d1, &err));
        GI_REQUIRE_OK(gi_rad_lowrank_neumann(&lr, rho, e, 1, 1e-10, 10000, d2, &it, &err));
        double dd = 0, ss = 0, df = 0;
        for (uint32_t i = 0; i < n; i++) {
            dd += (d1[i] - d2[i]) * (d1[i] - d2[i]);
            ss += d1[i] * d1[i];
            df += (d1[i] - B1[3 * i + c]) * (d1[i] - B1[3 * i + c]);
        }
        GI_CHECK_MSG(sqrt(dd / ss) < 1e-5, "colour %d: %g", c, sqrt(dd / ss));
        GI_CHECK_MSG(sqrt(df / ss) < 1e-5, "colour %d: float vs double %g", c, sqrt(df / ss));
    }
    /* Batched relighting (one matrix product) gives the same solutions. */
    float *E3 = malloc(3 * 3 * (size_t)n * sizeof *E3),
          *B3 = malloc(3 * 3 * (size_t)n * sizeof *B3);
    for (int i = 0; i < 3; i++)
        for (size_t j = 0; j < 3 * (size_t)n; j++)
            E3[i * 3 * (size_t)n + j] = E[j] * (float)(i + 1);
    GI_REQUIRE_OK(gi_rad_factor_relight(&b.f, E3, B3, 3, 1, &err));
    for (int i = 0; i < 3; i++) {
        for (size_t j = 0; j < 3 * (size_t)n; j++)
            B2[j] = B1[j] * (float)(i + 1);
        GI_CHECK(rel_diff(B3 + i * 3 * (size_t)n, B2, 3 * (size_t)n) < 1e-5);
    }
    free(E), free(B1), free(B2), free(E3), free(B3), free(rho), free(e), free(d1), free(d2);
    gi_rad_lowrank_free(&lr);
    gi_rad_emissions_free(&em);
    built_free(&b);
}

/* A random n x n matrix of rank r (U V^T with entries in [0, 1)). */
static double *low_rank_matrix(uint32_t n, uint32_t r, uint64_t seed)
{
    double *U = malloc((size_t)n * r * sizeof *U), *V = malloc((size_t)n * r * sizeof *V);
    double *F = malloc((size_t)n * n * sizeof *F);
    gi_rng g;
    gi_rng_init(&g, seed, 0, 0);
    for (size_t i = 0; i < (size_t)n * r; i++) {
        U[i] = gi_rng_double(&g);
        V[i] = gi_rng_double(&g);
    }
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)n, (int)n, (int)r, 1.0, U, (int)r, V,
                (int)r, 0.0, F, (int)n);
    free(U);
    free(V);
    return F;
}

static int row_of(void *user, uint32_t i, double *out, gi_error *err)
{
    const double *F = ((const double **)user)[0];
    uint32_t n = (uint32_t)(uintptr_t)((void **)user)[1];
    memcpy(out, F + (size_t)i * n, n * sizeof *out);
    return 0;
}

static int col_of(void *user, uint32_t j, double *out, gi_error *err)
{
    const double *F = ((const double **)user)[0];
    uint32_t n = (uint32_t)(uintptr_t)((void **)user)[1];
    for (uint32_t i = 0; i < n; i++)
        out[i] = F[(size_t)i * n + j];
    return 0;
}

GI_TEST(test_rad_validation_factorizations_recover_a_low_rank_matrix)
{
    gi_error err;
    uint32_t n = 60, r = 5;
    double *F = low_rank_matrix(n, r, 9);
    double fn = cblas_dnrm2((int)(n * n), F, 1);
    gi_rad_svd svd;
    gi_rad_lowrank lr;
    GI_REQUIRE_OK(gi_rad_svd_compute(&svd, F, n, &err));
    GI_REQUIRE_OK(gi_rad_svd_truncate(&svd, r, &lr, &err));
    GI_CHECK(gi_rad_lowrank_distance(&lr, F) < 1e-10 * fn);
    gi_rad_lowrank_free(&lr);
    /* Rank 2: the Eckart-Young error is sqrt(sum of the rest squared). */
    GI_REQUIRE_OK(gi_rad_svd_truncate(&svd, 2, &lr, &err));
    double rest = 0.0;
    for (uint32_t i = 2; i < n; i++)
        rest += svd.S[i] * svd.S[i];
    GI_CHECK_REL(gi_rad_lowrank_distance(&lr, F), sqrt(rest), 1e-8);
    gi_rad_lowrank_free(&lr);
    gi_rad_svd_free(&svd);

    GI_REQUIRE_OK(gi_rad_cur(F, n, r, 2, &lr, &err));
    GI_CHECK_MSG(gi_rad_lowrank_distance(&lr, F) < 1e-8 * fn, "CUR distance %g",
                 gi_rad_lowrank_distance(&lr, F));
    gi_rad_lowrank_free(&lr);

    void *ctx[2] = {F, (void *)(uintptr_t)n};
    GI_REQUIRE_OK(gi_rad_aca(row_of, col_of, ctx, n, 20, 1e-12, &lr, &err));
    GI_CHECK(lr.k <= r + 1);
    GI_CHECK_MSG(gi_rad_lowrank_distance(&lr, F) < 1e-8 * fn, "ACA distance %g",
                 gi_rad_lowrank_distance(&lr, F));
    gi_rad_lowrank_free(&lr);
    free(F);
}

GI_TEST(test_rad_maxvol_finds_a_dominant_submatrix)
{
    gi_error err;
    uint32_t n = 200, k = 6;
    double *A = malloc((size_t)n * k * sizeof *A);
    gi_rng g;
    gi_rng_init(&g, 4, 0, 0);
    for (size_t i = 0; i < (size_t)n * k; i++)
        A[i] = gi_rng_double(&g) - 0.5;
    uint32_t rows[6];
    GI_REQUIRE_OK(gi_rad_maxvol(A, n, k, 1e-3, 1000, rows, &err));
    /* Every row of A is a combination of the chosen rows with coefficients
     * at most 1 + tol: check it directly. */
    double W[36], X[36];
    for (uint32_t i = 0; i < k; i++)
        memcpy(W + i * k, A + (size_t)rows[i] * k, k * sizeof *W);
    int dominated = 1;
    for (uint32_t e = 0; e < n; e++) {
        /* coefficients c with c W = A(e,:): solve W^T c^T = A(e,:)^T */
        memcpy(X, W, sizeof W);
        double c[6];
        memcpy(c, A + (size_t)e * k, k * sizeof *c);
        int ipiv[6];
        GI_REQUIRE(LAPACKE_dgesv(LAPACK_COL_MAJOR, (int)k, 1, X, (int)k, ipiv, c, (int)k) == 0);
        for (uint32_t i = 0; i < k; i++)
            dominated &= fabs(c[i]) <= 1.0 + 1e-3 + 1e-9;
    }
    GI_CHECK(dominated);
    free(A);
}

GI_TEST(test_rad_algorithm6_and_double_smw_update_are_exact_when_nothing_is_dropped)
{
    gi_error err;
    uint32_t n = 80, k = 7;
    gi_rng g;
    gi_rng_init(&g, 11, 0, 0);
    /* State init: a 2MF-like factor (V a selector), rows of F_I summing to < 1. */
    gi_rad_lowrank init;
    GI_REQUIRE_OK(gi_rad_lowrank_alloc(&init, n, k, 0, &err));
    for (uint32_t e = 0; e < n; e++) {
        init.patch[e] = e % k;
        for (uint32_t p = 0; p < k; p++)
            init.U[e * k + p] = 0.9 * gi_rng_double(&g) / n;
    }
    /* dF: nonzero in 3 columns and, elsewhere, in 2 rows. */
    gi_rad_sparse dF = {n, 0, calloc(n + 1, sizeof(uint64_t)), malloc(4 * n * sizeof(uint32_t)),
                        malloc(4 * n * sizeof(double))};
    uint32_t cols[3] = {5, 17, 60}, rows[2] = {3, 40};
    double *D = calloc((size_t)n * n, sizeof *D);
    for (uint32_t e = 0; e < n; e++) {
        for (uint32_t j = 0; j < n; j++) {
            int in = j == cols[0] || j == cols[1] || j == cols[2] || (e == rows[0] && j % 3 == 0) ||
                     (e == rows[1] && j % 5 == 1);
            if (!in)
                continue;
            double v = (gi_rng_double(&g) - 0.5) * 0.01;
            D[(size_t)e * n + j] = v;
            dF.col[dF.nnz] = j;
            dF.val[dF.nnz++] = v;
        }
        dF.row_ptr[e + 1] = dF.nnz;
    }
    gi_rad_lowrank delta;
    gi_rad_alg6_stats st;
    GI_REQUIRE_OK(gi_rad_alg6(&dF, 3, &delta, &st, &err));
    GI_CHECK(st.captured == st.nnz);
    /* The factors reproduce dF exactly. */
    double *P = malloc((size_t)n * n * sizeof *P);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)n, (int)n, (int)delta.k, 1.0, delta.U,
                (int)delta.k, delta.V, (int)delta.k, 0.0, P, (int)n);
    double maxd = 0.0;
    for (size_t i = 0; i < (size_t)n * n; i++)
        maxd = fabs(P[i] - D[i]) > maxd ? fabs(P[i] - D[i]) : maxd;
    GI_CHECK(maxd == 0.0);
    /* The update equals the dense solve of (init - R (F_I + dF)) B = E. */
    double *F = malloc((size_t)n * n * sizeof *F), *rho = malloc(n * sizeof *rho);
    double *E = malloc((size_t)n * 2 * sizeof *E), *B1 = malloc((size_t)n * 2 * sizeof *B1);
    double *B2 = malloc((size_t)n * 2 * sizeof *B2);
    for (uint32_t e = 0; e < n; e++) {
        rho[e] = 0.3 + 0.6 * gi_rng_double(&g);
        E[2 * e] = gi_rng_double(&g);
        E[2 * e + 1] = e < 10 ? 1.0 : 0.0;
        for (uint32_t j = 0; j < n; j++)
            F[(size_t)e * n + j] = init.U[e * k + init.patch[j]] + D[(size_t)e * n + j];
    }
    GI_REQUIRE_OK(gi_rad_update_solve(&init, &delta, rho, E, 2, B1, &err));
    GI_REQUIRE_OK(gi_rad_dense_solve(F, n, rho, E, 2, B2, &err));
    double dd = 0, ss = 0;
    for (uint32_t i = 0; i < 2 * n; i++) {
        dd += (B1[i] - B2[i]) * (B1[i] - B2[i]);
        ss += B2[i] * B2[i];
    }
    GI_CHECK_MSG(sqrt(dd / ss) < 1e-12, "update vs dense: %g", sqrt(dd / ss));
    /* With k_delta = 1 something is dropped, and the result differs. */
    gi_rad_lowrank small;
    GI_REQUIRE_OK(gi_rad_alg6(&dF, 1, &small, &st, &err));
    GI_CHECK(st.captured < st.nnz);
    GI_REQUIRE_OK(gi_rad_update_solve(&init, &small, rho, E, 2, B1, &err));
    dd = 0;
    for (uint32_t i = 0; i < 2 * n; i++)
        dd += (B1[i] - B2[i]) * (B1[i] - B2[i]);
    GI_CHECK(sqrt(dd / ss) > 1e-6);
    gi_rad_lowrank_free(&small);
    gi_rad_lowrank_free(&delta);
    gi_rad_lowrank_free(&init);
    gi_rad_sparse_free(&dF);
    free(D), free(P), free(F), free(rho), free(E), free(B1), free(B2);
}

static const char *room_with_panel =
    "{\"materials\": {\"w\": {\"diffuse\": [0.6, 0.6, 0.6], \"emission\": [1, 1, 1]},"
    "                 \"p\": {\"diffuse\": [0.5, 0.5, 0.5]}},"
    " \"objects\": [{\"name\": \"room\", \"material\": \"w\", \"box\": {\"size\": [2, 2, 2], "
    "\"inward\": true}},"
    "  {\"name\": \"panel\", \"material\": \"p\", \"mobile\": true,"
    "   \"box\": {\"size\": [0.4, 0.4, 0.4]}, \"transform\": [{\"translate\": [%g, -0.6, 0.1]}]}]}";

GI_TEST(test_rad_delta_recasts_few_rays_and_is_exact)
{
    gi_error err;
    gi_scene si, sf;
    char text[1024];
    snprintf(text, sizeof text, room_with_panel, -0.4);
    GI_REQUIRE_OK(gi_test_load_scene_text("state-i.json", text, &si, &err));
    snprintf(text, sizeof text, room_with_panel, 0.5);
    GI_REQUIRE_OK(gi_test_load_scene_text("state-f.json", text, &sf, &err));
    gi_rad_mesh m;
    GI_REQUIRE_OK(gi_rad_mesh_build(&m, &si, 24.96 / 60.0, 1, &err));
    gi_rt ri, rf;
    gi_rad_strata st;
    uint32_t rays = 64, n = m.element_count;
    GI_REQUIRE_OK(gi_rt_create(&ri, &si, &err));
    GI_REQUIRE_OK(gi_rt_create(&rf, &sf, &err));
    GI_REQUIRE_OK(gi_rad_strata_init(&st, rays, &err));
    gi_rad_sparse dF;
    gi_rad_delta_stats ds;
    GI_REQUIRE_OK(gi_rad_delta(&ri, &si, &rf, &sf, &m, &st, 5, 1, &dF, &ds, &err));
    GI_CHECK(ds.recast < ds.rays / 2 && ds.changed > 0 && dF.nnz > 0);
    /* Full element-level F in both states: F_F - F_I must equal dF. */
    uint16_t *h[2];
    gi_rt *rt[2] = {&ri, &rf};
    gi_scene *sc[2] = {&si, &sf};
    for (int s = 0; s < 2; s++) {
        h[s] = malloc((size_t)n * n * sizeof *h[s]);
        gi_rad_ff_opts o = {5, m.levels};
        gi_rad_ff_stats fs;
        GI_REQUIRE_OK(gi_rad_ff_dense(rt[s], sc[s], &m, &st, &o, h[s], n, &fs, &err));
    }
    int same = 1;
    for (uint32_t e = 0; e < n; e++) {
        uint64_t q = dF.row_ptr[e];
        for (uint32_t j = 0; j < n; j++) {
            int32_t d = (int32_t)h[1][(size_t)e * n + j] - h[0][(size_t)e * n + j];
            double v = 0.0;
            if (q < dF.row_ptr[e + 1] && dF.col[q] == j)
                v = dF.val[q++];
            same &= fabs(v - (double)d / rays) < 1e-15;
        }
    }
    GI_CHECK(same);
    /* At 2MF resolution: U_I V^T + coarse change = U_F V^T, entry by entry. */
    gi_rad_patches pt;
    gi_rad_2mf_patches(&m, 0, &pt);
    gi_rad_factor f[2];
    for (int s = 0; s < 2; s++) {
        uint16_t *c0 = calloc((size_t)n * pt.k, sizeof *c0);
        for (uint32_t e = 0; e < n; e++)
            for (uint32_t j = 0; j < n; j++)
                c0[(size_t)e * pt.k + j / 4] += h[s][(size_t)e * n + j];
        GI_REQUIRE_OK(gi_rad_factor_from_counts(&f[s], &m, c0, pt.k, rays, &pt, &err));
        free(c0);
    }
    gi_rad_sparse dc;
    GI_REQUIRE_OK(gi_rad_delta_coarse(&dF, f[0].patch, f[0].patch_count, f[0].k, &dc, &err));
    double worst = 0.0;
    for (uint32_t e = 0; e < n; e++) {
        uint64_t q = dc.row_ptr[e];
        for (uint32_t j = 0; j < n; j++) {
            uint32_t p = f[0].patch[j];
            double ui = f[0].hits[(size_t)e * f[0].k_pad + p] * f[0].w[p];
            double uf = f[1].hits[(size_t)e * f[1].k_pad + p] * f[1].w[p];
            double v = 0.0;
            if (q < dc.row_ptr[e + 1] && dc.col[q] == j)
                v = dc.val[q++];
            worst = fabs(ui + v - uf) > worst ? fabs(ui + v - uf) : worst;
        }
    }
    GI_CHECK_MSG(worst < 1e-12, "coarse change off by %g", worst);
    gi_rad_sparse_free(&dc);
    gi_rad_factor_free(&f[0]);
    gi_rad_factor_free(&f[1]);
    gi_rad_patches_free(&pt);
    free(h[0]);
    free(h[1]);
    gi_rad_sparse_free(&dF);
    gi_rad_strata_free(&st);
    gi_rt_free(&ri);
    gi_rt_free(&rf);
    gi_rad_mesh_free(&m);
    gi_scene_free(&si);
    gi_scene_free(&sf);
}
