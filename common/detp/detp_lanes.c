/* detp_lanes: every (segment, disc) pair of a small disc set, several discs
 * at a time, for the mobile's own vertices (thesis 1.12.4): a few hundred
 * discs against the few thousand segments near them, where an index's
 * per-candidate cost (traversal, filter callback) is most of the work.
 * Sixteen lanes (AVX-512) or eight (AVX2) where the CPU has them, else four
 * (SSE2), else one; all count exactly basic DETP's pairs
 * (detp_lanes_kernel.h), and the sums are the same whatever the order
 * (gi_detp_accum). */
#include <stdlib.h>

#include "detp.h"

#ifdef __x86_64__
#include <immintrin.h>

#define LANES_FN lanes_sse
#define LANES_W 4
#define LANES_VF lanes_vf4
#define LANES_VI lanes_vi4
#define LANES_ATTR
#define LANES_MOVEMASK(m) _mm_movemask_ps((__m128)(m))
#include "detp_lanes_kernel.h"

#define LANES_FN lanes_avx2
#define LANES_W 8
#define LANES_VF lanes_vf8
#define LANES_VI lanes_vi8
#define LANES_ATTR __attribute__((target("avx2")))
#define LANES_MOVEMASK(m) _mm256_movemask_ps((__m256)(m))
#include "detp_lanes_kernel.h"

#define LANES_FN lanes_avx512
#define LANES_W 16
#define LANES_VF lanes_vf16
#define LANES_VI lanes_vi16
#define LANES_ATTR __attribute__((target("avx512f,avx512dq")))
#define LANES_MOVEMASK(m) _mm512_movepi32_mask((__m512i)(m))
#include "detp_lanes_kernel.h"

void gi_detp_lanes_estimate_width(const gi_detp_discs *d, const gi_detp_segments *s,
                                  gi_detp_accum *acc, gi_detp_stats *st, unsigned lanes)
{
    int wider = lanes >= 16 && __builtin_cpu_supports("avx512f") &&
                __builtin_cpu_supports("avx512dq");
    int wide = lanes >= 8 && __builtin_cpu_supports("avx2");
    size_t w = wider ? 16 : wide ? 8 : 4, n = ((size_t)d->count + w - 1) / w * w;
    /* Structure of arrays; padding lanes have n = 0, so denom = 0 rejects
     * them as gi_detp_crosses would. */
    float *soa = gi_xcalloc(6 * n + 1, sizeof *soa);
    float *cx = soa, *cy = cx + n, *cz = cy + n, *nx = cz + n, *ny = nx + n, *nz = ny + n;
    for (uint32_t i = 0; i < d->count; i++) {
        cx[i] = d->d[i].c.x, cy[i] = d->d[i].c.y, cz[i] = d->d[i].c.z;
        nx[i] = d->d[i].n.x, ny[i] = d->d[i].n.y, nz[i] = d->d[i].n.z;
    }
    if (wider)
        lanes_avx512(cx, cy, cz, nx, ny, nz, n, d->r2, s, acc, st);
    else if (wide)
        lanes_avx2(cx, cy, cz, nx, ny, nz, n, d->r2, s, acc, st);
    else
        lanes_sse(cx, cy, cz, nx, ny, nz, n, d->r2, s, acc, st);
    st->disc_tests += (uint64_t)d->count * s->count;
    free(soa);
}
#else
void gi_detp_lanes_estimate_width(const gi_detp_discs *d, const gi_detp_segments *s,
                                  gi_detp_accum *acc, gi_detp_stats *st, unsigned lanes)
{
    (void)lanes;
    gi_detp_basic(d, s, acc, st);
}
#endif

void gi_detp_lanes_estimate(const gi_detp_discs *d, const gi_detp_segments *s,
                            gi_detp_accum *acc, gi_detp_stats *st)
{
    gi_detp_lanes_estimate_width(d, s, acc, st, 16);
}
