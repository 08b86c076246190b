/* rad_kernel: y = U s for the 2MF/2MCE factor stored as hit counts.
 *
 * U(e, p) = hits(e, p) / (rays c_p) (eq. 3.53 with F_ep = hits / rays): the
 * sampled factor is exactly an integer matrix times a diagonal, so it is
 * kept as integers and the diagonal is folded into s. Relighting (eq.
 * 3.33) is bound by the bytes of U it streams, so the counts are read as
 * 8 bits where they fit - most do: rays spread over k patches - with the
 * excess of the few larger ones in short per-row lists, else as 16 bits
 * (rays <= 65025). OpenBLAS has no integer or half-precision GEMV, so this
 * one product is ours; it reads U once for all three colours.
 *
 * Bits do not depend on the CPU path or the thread count: each row is a
 * fixed set of 16 lane accumulators (column p goes to lane p mod 16, fused
 * multiply-add in increasing p), reduced in a fixed tree, then the excess
 * list in increasing p; the AVX2 path and the portable path compute exactly
 * that, and threads split rows. */
#ifndef GI_RAD_KERNEL_H
#define GI_RAD_KERNEL_H

#include <stdint.h>

#define GI_RAD_KPAD 16 /* rows of counts and s are padded with zeros to a multiple */

static inline uint32_t gi_rad_kpad(uint32_t k)
{
    return (k + GI_RAD_KPAD - 1) / GI_RAD_KPAD * GI_RAD_KPAD;
}

/* The counts as the kernel reads them: h16, or h8 plus the excess lists
 * (row e's excess entries are [over_row[e], over_row[e + 1])). */
typedef struct gi_rad_counts {
    uint32_t n, k_pad;
    const uint16_t *h16;
    const uint8_t *h8;
    const uint32_t *over_row, *over_col;
    const uint16_t *over_val; /* count - 255 */
} gi_rad_counts;

/* y[3e + c] = sum_p count(e, p) * s[c k_pad + p] for every row, using
 * `threads` threads (>= 1). s holds 3 planar k_pad vectors. */
void gi_rad_apply3(const gi_rad_counts *u, const float *s, float *y, int threads);

/* The two implementations, for tests (rows [r0, r1)). */
void gi_rad_apply3_portable(const gi_rad_counts *u, const float *s, float *y, uint32_t r0,
                            uint32_t r1);
/* 0 if this CPU lacks AVX2 + FMA (then nothing is computed). */
int gi_rad_apply3_avx2(const gi_rad_counts *u, const float *s, float *y, uint32_t r0, uint32_t r1);

#endif
