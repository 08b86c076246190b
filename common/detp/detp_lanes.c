/* detp_lanes: every (segment, disc) pair of a small disc set, the discs
 * four at a time (SSE), for the mobile's own vertices (thesis 1.12.4): a
 * few hundred discs against the few thousand segments near them, where
 * an index's per-candidate cost (traversal, filter callback) is most of
 * the work. Each lane does gi_detp_crosses' arithmetic, operation for
 * operation (packed IEEE operations round like scalar ones, and the build
 * contracts nothing), so the pairs are exactly basic DETP's; the sums are
 * the same whatever the order (gi_detp_accum). */
#include <stdlib.h>

#include "detp.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

void gi_detp_lanes_estimate(const gi_detp_discs *d, const gi_detp_segments *s,
                            gi_detp_accum *acc, gi_detp_stats *st)
{
#ifdef __SSE2__
    size_t n4 = ((size_t)d->count + 3) & ~(size_t)3;
    /* Structure of arrays; padding lanes have n = 0, so denom = 0 rejects
     * them as gi_detp_crosses would. */
    float *soa = gi_xcalloc(6 * n4 + 1, sizeof *soa);
    float *cx = soa, *cy = cx + n4, *cz = cy + n4, *nx = cz + n4, *ny = nx + n4, *nz = ny + n4;
    for (uint32_t i = 0; i < d->count; i++) {
        cx[i] = d->d[i].c.x, cy[i] = d->d[i].c.y, cz[i] = d->d[i].c.z;
        nx[i] = d->d[i].n.x, ny[i] = d->d[i].n.y, nz[i] = d->d[i].n.z;
    }
    const __m128 zero = _mm_setzero_ps(), r2 = _mm_set1_ps(d->r2);
    for (size_t j = 0; j < s->count; j++) {
        const gi_detp_segment *g = &s->v[j];
        const __m128 ox = _mm_set1_ps(g->org.x), oy = _mm_set1_ps(g->org.y),
                     oz = _mm_set1_ps(g->org.z), dx = _mm_set1_ps(g->dir.x),
                     dy = _mm_set1_ps(g->dir.y), dz = _mm_set1_ps(g->dir.z),
                     t_end = _mm_set1_ps(g->t_end);
        for (size_t i = 0; i < n4; i += 4) {
            __m128 vnx = _mm_loadu_ps(nx + i), vny = _mm_loadu_ps(ny + i),
                   vnz = _mm_loadu_ps(nz + i);
            /* denom = dir . n */
            __m128 denom = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, vnx), _mm_mul_ps(dy, vny)),
                                      _mm_mul_ps(dz, vnz));
            __m128 ok = _mm_cmplt_ps(denom, zero);
            if (!_mm_movemask_ps(ok))
                continue;
            __m128 vcx = _mm_loadu_ps(cx + i), vcy = _mm_loadu_ps(cy + i),
                   vcz = _mm_loadu_ps(cz + i);
            /* t = ((c - org) . n) / denom */
            __m128 num = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_sub_ps(vcx, ox), vnx),
                                               _mm_mul_ps(_mm_sub_ps(vcy, oy), vny)),
                                    _mm_mul_ps(_mm_sub_ps(vcz, oz), vnz));
            __m128 t = _mm_div_ps(num, denom);
            ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(t, zero), _mm_cmplt_ps(t, t_end)));
            if (!_mm_movemask_ps(ok))
                continue;
            /* p = (org + dir t) - c; |p|^2 <= r2 */
            __m128 px = _mm_sub_ps(_mm_add_ps(ox, _mm_mul_ps(dx, t)), vcx);
            __m128 py = _mm_sub_ps(_mm_add_ps(oy, _mm_mul_ps(dy, t)), vcy);
            __m128 pz = _mm_sub_ps(_mm_add_ps(oz, _mm_mul_ps(dz, t)), vcz);
            __m128 p2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(px, px), _mm_mul_ps(py, py)),
                                   _mm_mul_ps(pz, pz));
            int hit = _mm_movemask_ps(_mm_and_ps(ok, _mm_cmple_ps(p2, r2)));
            while (hit) {
                int k = __builtin_ctz((unsigned)hit);
                hit &= hit - 1;
                gi_detp_accum_add(acc, (uint32_t)(i + (size_t)k), g);
                st->crossings++;
            }
        }
        st->disc_tests += d->count;
    }
    free(soa);
#else
    gi_detp_basic(d, s, acc, st);
#endif
}
