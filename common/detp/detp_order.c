/* detp_order: the order in which the Sphere Cache visits the discs (thesis
 * 1.7). The cache only pays off when consecutive queries are close: sorting
 * the samples along a space-filling curve gives that coherence.
 *
 * Coordinates are mapped to 16-bit integers per axis, the discs' bounding
 * box spanning 0..65535 on each axis (thesis 1.7), and sorted by a 48-bit
 * key: Lebesgue (Morton) interleaves the bits MSB first in the order x, y,
 * z; Hilbert uses Skilling's transpose algorithm ("Programming the Hilbert
 * curve", AIP Conf. Proc. 707, 2004), whose consecutive cells always share
 * a face. Ties keep mesh order (the sort is stable on the index). */
#include <stdlib.h>

#include "detp.h"
#include "gi_rng.h"

#define ORDER_BITS 16

uint64_t gi_detp_morton_key(uint32_t x, uint32_t y, uint32_t z)
{
    uint64_t key = 0;
    for (int b = ORDER_BITS - 1; b >= 0; b--)
        key = (key << 3) | ((uint64_t)(x >> b & 1) << 2) | ((uint64_t)(y >> b & 1) << 1) |
              (uint64_t)(z >> b & 1);
    return key;
}

uint64_t gi_detp_hilbert_key(uint32_t x, uint32_t y, uint32_t z)
{
    uint32_t X[3] = {x, y, z};
    const uint32_t M = 1u << (ORDER_BITS - 1);
    /* Inverse undo excess work. */
    for (uint32_t Q = M; Q > 1; Q >>= 1) {
        uint32_t P = Q - 1;
        for (int i = 0; i < 3; i++) {
            if (X[i] & Q) {
                X[0] ^= P;
            } else {
                uint32_t t = (X[0] ^ X[i]) & P;
                X[0] ^= t;
                X[i] ^= t;
            }
        }
    }
    /* Gray encode. */
    for (int i = 1; i < 3; i++)
        X[i] ^= X[i - 1];
    uint32_t t = 0;
    for (uint32_t Q = M; Q > 1; Q >>= 1)
        if (X[2] & Q)
            t ^= Q - 1;
    for (int i = 0; i < 3; i++)
        X[i] ^= t;
    /* The transposed form, interleaved MSB first, is the curve index. */
    return gi_detp_morton_key(X[0], X[1], X[2]);
}

typedef struct keyed {
    uint64_t key;
    uint32_t index;
} keyed;

static int keyed_cmp(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

static uint32_t quantize(float v, float lo, float scale)
{
    float q = (v - lo) * scale;
    if (!(q > 0.0f))
        return 0;
    return q >= 65535.0f ? 65535u : (uint32_t)q;
}

uint32_t *gi_detp_query_order(const gi_detp_discs *d, gi_detp_order order, uint64_t seed,
                              gi_error *err)
{
    uint32_t n = d->count;
    uint32_t *perm = gi_try_malloc(((size_t)n + 1) * sizeof *perm, err, "query order");
    if (!perm)
        return NULL;
    for (uint32_t i = 0; i < n; i++)
        perm[i] = i;
    if (order == GI_DETP_ORDER_NONE || n < 2)
        return perm;
    if (order == GI_DETP_ORDER_SHUFFLED) {
        /* Fisher-Yates with numbers keyed by the job's seed. */
        gi_rng r;
        gi_rng_init(&r, seed, GI_DETP_STREAM_PHOTON - 2, 0);
        for (uint32_t i = n - 1; i > 0; i--) {
            uint32_t j = gi_rng_below(&r, i + 1);
            uint32_t t = perm[i];
            perm[i] = perm[j];
            perm[j] = t;
        }
        return perm;
    }
    keyed *k = gi_try_malloc((size_t)n * sizeof *k, err, "query order keys");
    if (!k) {
        free(perm);
        return NULL;
    }
    gi_vec3 lo = d->d[0].c, hi = lo;
    for (uint32_t i = 1; i < n; i++) {
        lo = gi_min_v3(lo, d->d[i].c);
        hi = gi_max_v3(hi, d->d[i].c);
    }
    float s[3];
    for (int a = 0; a < 3; a++) {
        float ext = gi_v3_get(hi, a) - gi_v3_get(lo, a);
        s[a] = ext > 0.0f ? 65535.0f / ext : 0.0f;
    }
    for (uint32_t i = 0; i < n; i++) {
        gi_vec3 c = d->d[i].c;
        uint32_t x = quantize(c.x, lo.x, s[0]), y = quantize(c.y, lo.y, s[1]),
                 z = quantize(c.z, lo.z, s[2]);
        k[i].key = order == GI_DETP_ORDER_HILBERT ? gi_detp_hilbert_key(x, y, z)
                                                  : gi_detp_morton_key(x, y, z);
        k[i].index = i;
    }
    qsort(k, n, sizeof *k, keyed_cmp);
    for (uint32_t i = 0; i < n; i++)
        perm[i] = k[i].index;
    free(k);
    return perm;
}
