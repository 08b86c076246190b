/* rad_kernel: y = U s for the 2MF/2MCE factor stored as 16-bit hit counts.
 *
 * U(e, p) = hits(e, p) / (rays c_p) (eq. 3.53 with F_ep = hits / rays): the
 * sampled factor is exactly an integer matrix times a diagonal, so it is
 * stored as uint16 (rays <= 65025) and the diagonal is folded into s. That
 * halves the bytes of a float U, and relighting (eq. 3.33) is bound by the
 * bytes of U it streams. OpenBLAS has no integer or half-precision GEMV, so
 * this one product is ours; it reads U once for all three colours.
 *
 * Bits do not depend on the CPU path or the thread count: each row is a
 * fixed set of 16 lane accumulators (column p goes to lane p mod 16, fused
 * multiply-add in increasing p), reduced in a fixed tree; the AVX2 path and
 * the portable path compute exactly that, and threads split rows. */
#ifndef GI_RAD_KERNEL_H
#define GI_RAD_KERNEL_H

#include <stdint.h>

#define GI_RAD_KPAD 16 /* rows of hits and s are padded with zeros to a multiple */

static inline uint32_t gi_rad_kpad(uint32_t k)
{
    return (k + GI_RAD_KPAD - 1) / GI_RAD_KPAD * GI_RAD_KPAD;
}

/* y[3e + c] = sum_p hits[e k_pad + p] * s[c k_pad + p] for rows [0, n),
 * using `threads` threads (>= 1). s holds 3 planar k_pad vectors. */
void gi_rad_apply3(const uint16_t *hits, uint32_t n, uint32_t k_pad, const float *s, float *y,
                   int threads);

/* The two implementations, for tests (rows [r0, r1)). */
void gi_rad_apply3_portable(const uint16_t *hits, uint32_t k_pad, const float *s, float *y,
                            uint32_t r0, uint32_t r1);
/* 0 if this CPU lacks AVX2 + FMA (then nothing is computed). */
int gi_rad_apply3_avx2(const uint16_t *hits, uint32_t k_pad, const float *s, float *y,
                       uint32_t r0, uint32_t r1);

#endif
