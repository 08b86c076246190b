/* detp_lanes: every (segment, disc) pair of a small disc set, several discs
 * at a time, for the mobile's own vertices (thesis 1.12.4): a few hundred
 * discs against the few thousand segments near them, where an index's
 * per-candidate cost (traversal, filter callback) is most of the work.
 * The discs go in groups of one vector each, in Hilbert order of their
 * centres (so a group is a patch of the mobile); a segment tests a group
 * only if some disc in it may face it and the segment passes near it.
 * Sixteen lanes (AVX-512) or eight (AVX2) where the CPU has them, else four
 * (SSE2), else one; all count exactly basic DETP's pairs
 * (detp_lanes_kernel.h), and the sums are the same whatever the order
 * (gi_detp_accum). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp.h"

#ifdef __x86_64__
#include <immintrin.h>

/* The discs as the kernels read them (structure of arrays, lane-padded). */
typedef struct lanes_set {
    float *cx, *cy, *cz, *nx, *ny, *nz; /* lanes: groups x width */
    uint32_t *idx;                      /* lane -> disc */
    /* Per group (padded to a multiple of the width with groups that are
     * always skipped): the normals' cone (axis, sine of the half-angle,
     * 2 when it cannot cull) and the centres' sphere grown by the disc
     * radius (squared; -1 for padding). */
    float *ax, *ay, *az, *sin_t, *gx, *gy, *gz, *reach2;
    size_t groups; /* padded */
    float r2;
} lanes_set;

#define LANES_FN lanes_sse
#define LANES_W 4
#define LANES_VF lanes_vf4
#define LANES_VI lanes_vi4
#define LANES_VL lanes_vl4
#define LANES_VU lanes_vu4
#define LANES_ATTR
#define LANES_MOVEMASK(m) _mm_movemask_ps((__m128)(m))
#include "detp_lanes_kernel.h"

#define LANES_FN lanes_avx2
#define LANES_W 8
#define LANES_VF lanes_vf8
#define LANES_VI lanes_vi8
#define LANES_VL lanes_vl8
#define LANES_VU lanes_vu8
#define LANES_ATTR __attribute__((target("avx2")))
#define LANES_MOVEMASK(m) _mm256_movemask_ps((__m256)(m))
#include "detp_lanes_kernel.h"

#define LANES_FN lanes_avx512
#define LANES_W 16
#define LANES_VF lanes_vf16
#define LANES_VI lanes_vi16
#define LANES_VL lanes_vl16
#define LANES_VU lanes_vu16
#define LANES_ATTR __attribute__((target("avx512f,avx512dq")))
#define LANES_MOVEMASK(m) _mm512_movepi32_mask((__m512i)(m))
#include "detp_lanes_kernel.h"

static void lanes_build(const gi_detp_discs *d, const uint32_t *given, size_t w, lanes_set *L)
{
    size_t groups = (d->count + w - 1) / w, gpad = (groups + w - 1) / w * w, n = gpad * w;
    float *f = gi_xcalloc(6 * n + 8 * gpad + 1, sizeof *f);
    L->cx = f, L->cy = L->cx + n, L->cz = L->cy + n;
    L->nx = L->cz + n, L->ny = L->nx + n, L->nz = L->ny + n;
    L->ax = L->nz + n, L->ay = L->ax + gpad, L->az = L->ay + gpad, L->sin_t = L->az + gpad;
    L->gx = L->sin_t + gpad, L->gy = L->gx + gpad, L->gz = L->gy + gpad;
    L->reach2 = L->gz + gpad;
    L->idx = gi_xcalloc(n + 1, sizeof *L->idx);
    L->groups = gpad;
    L->r2 = d->r2;
    /* The centres in Hilbert order (the Sphere Cache's query order), unless
     * given: consecutive discs, so a group, are a compact patch of the
     * mobile (a quarter fewer disc tests at the 2.5% sphere than Morton
     * order). Without memory for the order, mesh order (slower, the same
     * sums). */
    gi_error ignored;
    uint32_t *own = given ? NULL : gi_detp_query_order(d, GI_DETP_ORDER_HILBERT, 0, &ignored);
    const uint32_t *order = given ? given : own;
    for (size_t i = 0; i < d->count; i++) {
        uint32_t k = order ? order[i] : (uint32_t)i;
        const gi_detp_disc *D = &d->d[k];
        L->cx[i] = D->c.x, L->cy[i] = D->c.y, L->cz[i] = D->c.z;
        L->nx[i] = D->n.x, L->ny[i] = D->n.y, L->nz[i] = D->n.z;
        L->idx[i] = k;
    }
    free(own);
    for (size_t g = 0; g < gpad; g++) {
        size_t i0 = g * w, i1 = i0 + w < d->count ? i0 + w : d->count;
        L->sin_t[g] = 2.0f;
        L->reach2[g] = -1.0f;
        if (i0 >= i1)
            continue;
        /* The centres' sphere, grown by the disc radius: a crossing point
         * lies within it. Margins of 0.2% and 1e-4 rad dwarf rounding. */
        double lo3[3] = {INFINITY, INFINITY, INFINITY}, hi3[3] = {-INFINITY, -INFINITY, -INFINITY};
        double m[3] = {0, 0, 0};
        for (size_t i = i0; i < i1; i++) {
            double c[3] = {L->cx[i], L->cy[i], L->cz[i]};
            for (int a = 0; a < 3; a++) {
                lo3[a] = fmin(lo3[a], c[a]);
                hi3[a] = fmax(hi3[a], c[a]);
            }
            m[0] += L->nx[i], m[1] += L->ny[i], m[2] += L->nz[i];
        }
        double gc[3] = {0.5 * (lo3[0] + hi3[0]), 0.5 * (lo3[1] + hi3[1]), 0.5 * (lo3[2] + hi3[2])};
        double rho = 0.0;
        for (size_t i = i0; i < i1; i++) {
            double ex = L->cx[i] - gc[0], ey = L->cy[i] - gc[1], ez = L->cz[i] - gc[2];
            rho = fmax(rho, sqrt(ex * ex + ey * ey + ez * ez));
        }
        double reach = (rho + sqrt((double)d->r2)) * 1.002;
        L->gx[g] = (float)gc[0], L->gy[g] = (float)gc[1], L->gz[g] = (float)gc[2];
        L->reach2[g] = (float)(reach * reach);
        /* The normals' cone about their mean. */
        double len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (!(len > 1e-6))
            continue;
        double cos_min = 1.0;
        for (size_t i = i0; i < i1; i++) {
            double nl = sqrt((double)L->nx[i] * L->nx[i] + (double)L->ny[i] * L->ny[i] +
                             (double)L->nz[i] * L->nz[i]);
            if (!(nl > 0.0))
                continue; /* a zero normal crosses nothing */
            cos_min = fmin(cos_min, (L->nx[i] * m[0] + L->ny[i] * m[1] + L->nz[i] * m[2]) /
                                        (len * nl));
        }
        double theta = acos(fmax(-1.0, fmin(1.0, cos_min))) + 1e-4;
        if (theta < 0.5 * M_PI - 1e-3) {
            L->ax[g] = (float)(m[0] / len), L->ay[g] = (float)(m[1] / len);
            L->az[g] = (float)(m[2] / len);
            L->sin_t[g] = (float)(sin(theta) + 1e-4);
        }
    }
}

void gi_detp_lanes_estimate_width(const gi_detp_discs *d, const uint32_t *order,
                                  const gi_detp_segments *s, gi_detp_accum *acc,
                                  gi_detp_stats *st, unsigned lanes)
{
    int wider = lanes >= 16 && __builtin_cpu_supports("avx512f") &&
                __builtin_cpu_supports("avx512dq");
    int wide = lanes >= 8 && __builtin_cpu_supports("avx2");
    if (d->count == 0)
        return;
    lanes_set L;
    lanes_build(d, order, wider ? 16 : wide ? 8 : 4, &L);
    if (wider)
        lanes_avx512(&L, s, acc, st);
    else if (wide)
        lanes_avx2(&L, s, acc, st);
    else
        lanes_sse(&L, s, acc, st);
    free(L.cx);
    free(L.idx);
}
#else
void gi_detp_lanes_estimate_width(const gi_detp_discs *d, const uint32_t *order,
                                  const gi_detp_segments *s, gi_detp_accum *acc,
                                  gi_detp_stats *st, unsigned lanes)
{
    (void)order;
    (void)lanes;
    gi_detp_basic(d, s, acc, st);
}
#endif

void gi_detp_lanes_estimate(const gi_detp_discs *d, const uint32_t *order,
                            const gi_detp_segments *s, gi_detp_accum *acc, gi_detp_stats *st)
{
    gi_detp_lanes_estimate_width(d, order, s, acc, st, 16);
}
