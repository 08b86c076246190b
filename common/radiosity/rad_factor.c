/* rad_factor: 2MF/2MCE factors, their SMW matrices, relighting. */
#include "rad_factor.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rad_kernel.h"

int gi_rad_factor_alloc(gi_rad_factor *f, uint32_t n, uint32_t k, uint32_t rays, gi_error *err)
{
    memset(f, 0, sizeof *f);
    if (n == 0 || k == 0 || k > n || k > GI_RAD_MAX_PATCHES || rays == 0 || rays > 65535)
        return gi_fail(err, GI_EINVAL,
                       "radiosity factor: bad sizes n = %u, k = %u (at most %u patches)", n, k,
                       GI_RAD_MAX_PATCHES);
    f->n = n;
    f->k = k;
    f->k_pad = gi_rad_kpad(k);
    f->rays = rays;
    f->hits = gi_try_calloc((size_t)n * f->k_pad, sizeof *f->hits, err, "radiosity factor U");
    f->w = gi_try_calloc(k, sizeof *f->w, err, "radiosity factor");
    f->patch = gi_try_calloc(n, sizeof *f->patch, err, "radiosity factor V");
    f->patch_count = gi_try_calloc(k, sizeof *f->patch_count, err, "radiosity factor");
    f->rho = gi_try_calloc((size_t)n * 3, sizeof *f->rho, err, "radiosity reflectances");
    if (!f->hits || !f->w || !f->patch || !f->patch_count || !f->rho) {
        gi_rad_factor_free(f);
        return -1;
    }
    return 0;
}

int gi_rad_factor_finish(gi_rad_factor *f, gi_error *err)
{
    memset(f->patch_count, 0, f->k * sizeof *f->patch_count);
    for (uint32_t e = 0; e < f->n; e++) {
        if (f->patch[e] >= f->k)
            return gi_fail(err, GI_EINVAL, "radiosity factor: element %u in patch %u of %u", e,
                           f->patch[e], f->k);
        f->patch_count[f->patch[e]]++;
    }
    for (uint32_t p = 0; p < f->k; p++) {
        if (f->patch_count[p] == 0)
            return gi_fail(err, GI_EINVAL, "radiosity factor: patch %u has no elements", p);
        f->w[p] = 1.0 / ((double)f->rays * f->patch_count[p]); /* eq. 3.53 */
    }
    return 0;
}

void gi_rad_factor_free(gi_rad_factor *f)
{
    free(f->hits);
    free(f->w);
    free(f->patch);
    free(f->patch_count);
    free(f->rho);
    free(f->M);
    free(f->hits8);
    free(f->over_row);
    free(f->over_col);
    free(f->over_val);
    memset(f, 0, sizeof *f);
}

static void unpack(gi_rad_factor *f)
{
    free(f->hits8);
    free(f->over_row);
    free(f->over_col);
    free(f->over_val);
    f->hits8 = NULL;
    f->over_row = f->over_col = NULL;
    f->over_val = NULL;
    f->over_count = 0;
}

int gi_rad_factor_pack(gi_rad_factor *f, gi_error *err)
{
    unpack(f);
    size_t cells = (size_t)f->n * f->k_pad, over = 0;
    for (size_t i = 0; i < cells; i++)
        over += f->hits[i] > 255;
    if (over > (size_t)f->n * f->k / 64)
        return 0; /* the lists would cost more than the 8 bits save */
    f->hits8 = gi_try_malloc(cells, err, "packed factor");
    f->over_row = gi_try_malloc(((size_t)f->n + 1) * sizeof *f->over_row, err, "packed factor");
    f->over_col = gi_try_malloc((over ? over : 1) * sizeof *f->over_col, err, "packed factor");
    f->over_val = gi_try_malloc((over ? over : 1) * sizeof *f->over_val, err, "packed factor");
    if (!f->hits8 || !f->over_row || !f->over_col || !f->over_val) {
        unpack(f);
        return -1;
    }
    uint32_t o = 0;
    for (uint32_t e = 0; e < f->n; e++) {
        f->over_row[e] = o;
        for (uint32_t p = 0; p < f->k_pad; p++) {
            uint16_t h = f->hits[(size_t)e * f->k_pad + p];
            f->hits8[(size_t)e * f->k_pad + p] = (uint8_t)(h > 255 ? 255 : h);
            if (h > 255) {
                f->over_col[o] = p;
                f->over_val[o++] = (uint16_t)(h - 255);
            }
        }
    }
    f->over_row[f->n] = o;
    f->over_count = o;
    return 0;
}

void gi_rad_factor_counts(const gi_rad_factor *f, gi_rad_counts *u)
{
    *u = (gi_rad_counts){f->n, f->k_pad, f->hits, f->hits8, f->over_row, f->over_col, f->over_val};
}

int gi_rad_factor_prepare(gi_rad_factor *f, gi_error *err)
{
    uint32_t k = f->k;
    size_t kk = (size_t)k * k;
    free(f->M);
    f->M = gi_try_malloc(3 * kk * sizeof *f->M, err, "radiosity SMW matrices");
    double *A = gi_try_malloc(kk * sizeof *A, err, "radiosity SMW matrices");
    lapack_int *ipiv = gi_try_malloc((size_t)k * sizeof *ipiv, err, "radiosity SMW matrices");
    if (!f->M || !A || !ipiv) {
        free(A);
        free(ipiv);
        return -1;
    }
    for (int c = 0; c < 3; c++) {
        /* G = V^T R_c U: row p sums rho_c(e) U(e, :) over the elements of
         * patch p (V^T as a per-patch sum). */
        memset(A, 0, kk * sizeof *A);
        for (uint32_t e = 0; e < f->n; e++) {
            double r = f->rho[3 * (size_t)e + c];
            if (r == 0.0)
                continue;
            double *row = A + (size_t)f->patch[e] * k;
            const uint16_t *h = f->hits + (size_t)e * f->k_pad;
            for (uint32_t q = 0; q < k; q++)
                row[q] += r * h[q];
        }
        /* A = I_k - G (the column weights of U applied once here). */
        for (uint32_t p = 0; p < k; p++) {
            double *row = A + (size_t)p * k;
            for (uint32_t q = 0; q < k; q++)
                row[q] = -row[q] * f->w[q];
            row[p] += 1.0;
        }
        lapack_int info =
            LAPACKE_dgetrf(LAPACK_ROW_MAJOR, (lapack_int)k, (lapack_int)k, A, (lapack_int)k, ipiv);
        if (info == 0)
            info = LAPACKE_dgetri(LAPACK_ROW_MAJOR, (lapack_int)k, A, (lapack_int)k, ipiv);
        if (info != 0) {
            free(A);
            free(ipiv);
            free(f->M);
            f->M = NULL;
            return gi_fail(err, info > 0 ? GI_EINVAL : GI_EINTERNAL,
                           "radiosity: I - V^T R U is singular in colour %d (LAPACK info %d): "
                           "is some reflectance 1?",
                           c, (int)info);
        }
        float *M = f->M + c * kk;
        for (size_t i = 0; i < kk; i++)
            M[i] = (float)A[i];
    }
    free(A);
    free(ipiv);
    return gi_rad_factor_pack(f, err);
}

void gi_rad_factor_vt(const gi_rad_factor *f, const float *x, double *t)
{
    memset(t, 0, 3 * (size_t)f->k_pad * sizeof *t);
    for (uint32_t e = 0; e < f->n; e++)
        for (int c = 0; c < 3; c++)
            t[(size_t)c * f->k_pad + f->patch[e]] += x[3 * (size_t)e + c];
}

int gi_rad_factor_relight(const gi_rad_factor *f, const float *E, float *B, uint32_t count,
                          int threads, gi_error *err)
{
    if (!f->M)
        return gi_fail(err, GI_EINTERNAL, "radiosity: relight before the SMW matrices exist");
    uint32_t k = f->k, kp = f->k_pad, n = f->n;
    size_t kk = (size_t)k * k;
    if (count == 1) {
        double *t = gi_try_malloc(3 * (size_t)kp * sizeof *t, err, "relight");
        float *tf = gi_try_calloc(3 * (size_t)kp, sizeof *tf, err, "relight");
        float *s = gi_try_calloc(3 * (size_t)kp, sizeof *s, err, "relight");
        if (!t || !tf || !s) {
            free(t), free(tf), free(s);
            return -1;
        }
        gi_rad_factor_vt(f, E, t); /* V^T E_c */
        for (size_t i = 0; i < 3 * (size_t)kp; i++)
            tf[i] = (float)t[i];
        for (int c = 0; c < 3; c++) { /* s_c = M_c (V^T E_c), then U's weights */
            cblas_sgemv(CblasRowMajor, CblasNoTrans, (int)k, (int)k, 1.0f, f->M + c * kk, (int)k,
                        tf + (size_t)c * kp, 1, 0.0f, s + (size_t)c * kp, 1);
            for (uint32_t p = 0; p < k; p++)
                s[(size_t)c * kp + p] = (float)(s[(size_t)c * kp + p] * f->w[p]);
        }
        gi_rad_counts u;
        gi_rad_factor_counts(f, &u);
        gi_rad_apply3(&u, s, B, threads); /* B = U s */
        for (size_t i = 0; i < 3 * (size_t)n; i++)
            B[i] = E[i] + f->rho[i] * B[i];
        free(t), free(tf), free(s);
        return 0;
    }
    /* Batched: T (k x 3count) = V^T E, S_c = M_c T_c, Y = U S, all as
     * matrix products. Column 3i + c is emission i, colour c. */
    size_t cols = 3 * (size_t)count;
    double *td = gi_try_calloc((size_t)k * cols, sizeof *td, err, "relight");
    float *T = gi_try_malloc((size_t)k * count * sizeof *T, err, "relight");
    float *Sc = gi_try_malloc((size_t)k * count * sizeof *Sc, err, "relight");
    float *S = gi_try_malloc((size_t)k * cols * sizeof *S, err, "relight");
    uint32_t block = 256;
    float *U = gi_try_malloc((size_t)block * kp * sizeof *U, err, "relight");
    float *Y = gi_try_malloc((size_t)block * cols * sizeof *Y, err, "relight");
    if (!td || !T || !Sc || !S || !U || !Y) {
        free(td), free(T), free(Sc), free(S), free(U), free(Y);
        return -1;
    }
    for (uint32_t i = 0; i < count; i++)
        for (uint32_t e = 0; e < n; e++)
            for (int c = 0; c < 3; c++)
                td[(size_t)f->patch[e] * cols + 3 * i + c] += E[((size_t)i * n + e) * 3 + c];
    for (int c = 0; c < 3; c++) {
        for (uint32_t p = 0; p < k; p++)
            for (uint32_t i = 0; i < count; i++)
                T[(size_t)p * count + i] = (float)td[(size_t)p * cols + 3 * i + c];
        cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)k, (int)count, (int)k, 1.0f,
                    f->M + c * kk, (int)k, T, (int)count, 0.0f, Sc, (int)count);
        for (uint32_t p = 0; p < k; p++)
            for (uint32_t i = 0; i < count; i++)
                S[(size_t)p * cols + 3 * i + c] = (float)(Sc[(size_t)p * count + i] * f->w[p]);
    }
    for (uint32_t r0 = 0; r0 < n; r0 += block) {
        uint32_t rows = n - r0 < block ? n - r0 : block;
        for (size_t i = 0; i < (size_t)rows * kp; i++)
            U[i] = f->hits[(size_t)r0 * kp + i];
        cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)rows, (int)cols, (int)k, 1.0f,
                    U, (int)kp, S, (int)cols, 0.0f, Y, (int)cols);
        for (uint32_t r = 0; r < rows; r++)
            for (uint32_t i = 0; i < count; i++)
                for (int c = 0; c < 3; c++) {
                    size_t at = ((size_t)i * n + r0 + r) * 3 + c;
                    B[at] =
                        E[at] + f->rho[3 * (size_t)(r0 + r) + c] * Y[(size_t)r * cols + 3 * i + c];
                }
    }
    (void)threads;
    free(td), free(T), free(Sc), free(S), free(U), free(Y);
    return 0;
}

int gi_rad_factor_neumann(const gi_rad_factor *f, const float *E, float *B, double tol,
                          int max_iter, int threads, int *iterations, double *residual,
                          gi_error *err)
{
    uint32_t n = f->n, kp = f->k_pad;
    double *t = gi_try_malloc(3 * (size_t)kp * sizeof *t, err, "Neumann iteration");
    float *s = gi_try_calloc(3 * (size_t)kp, sizeof *s, err, "Neumann iteration");
    float *y = gi_try_malloc(3 * (size_t)n * sizeof *y, err, "Neumann iteration");
    if (!t || !s || !y) {
        free(t), free(s), free(y);
        return -1;
    }
    memcpy(B, E, 3 * (size_t)n * sizeof *B); /* B_0 = E */
    double res = INFINITY;
    int it = 0;
    while (it < max_iter) {
        gi_rad_factor_vt(f, B, t);
        for (int c = 0; c < 3; c++)
            for (uint32_t p = 0; p < f->k; p++)
                s[(size_t)c * kp + p] = (float)(t[(size_t)c * kp + p] * f->w[p]);
        gi_rad_counts u;
        gi_rad_factor_counts(f, &u);
        gi_rad_apply3(&u, s, y, threads);
        double d2 = 0.0, b2 = 0.0;
        for (size_t i = 0; i < 3 * (size_t)n; i++) {
            float next = E[i] + f->rho[i] * y[i]; /* eq. 3.30 */
            double d = (double)next - B[i];
            d2 += d * d;
            b2 += (double)next * next;
            B[i] = next;
        }
        it++;
        res = b2 > 0.0 ? sqrt(d2 / b2) : 0.0;
        if (res <= tol)
            break;
    }
    free(t), free(s), free(y);
    if (iterations)
        *iterations = it;
    if (residual)
        *residual = res;
    if (res > tol)
        return gi_fail(err, GI_EINVAL,
                       "radiosity: Neumann iteration did not reach %.3g in %d iterations "
                       "(residual %.3g)",
                       tol, max_iter, res);
    return 0;
}
