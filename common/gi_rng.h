/* gi_rng: counter-based random numbers.
 *
 * A stream is fully determined by (seed, stream, sample): the same triple
 * gives the same numbers on any worker, in any order, after any retry.
 * Methods key streams by (job seed, what is being sampled, sample index),
 * e.g. (seed, pixel, sample) for the path tracer, so results do not depend
 * on how the work was split into tasks.
 *
 * Generator: the i-th 64-bit output of a stream is mix(start + i * gamma),
 * where start = hash(seed, stream, sample) and mix is the SplitMix64
 * finalizer (Steele, Lea, Flood 2014): a Weyl sequence through a strong
 * mixer, which passes BigCrush, costs a few cycles per output and is
 * counter-based by construction (output i needs only start and i). Distinct
 * triples start at unrelated points of the 2^64 sequence. */
#ifndef GI_RNG_H
#define GI_RNG_H

#include <stdint.h>

#define GI_RNG_GAMMA 0x9E3779B97F4A7C15ull

static inline uint64_t gi_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

typedef struct gi_rng {
    uint64_t state; /* start + i * gamma for the next output i */
    uint32_t spare; /* an unused half of the last 64-bit output */
    int has_spare;
} gi_rng;

/* gi_rng_init in steps, for loops over many streams and samples of one
 * seed: gi_rng_init_stream(r, gi_rng_stream_key(gi_rng_seed_key(seed),
 * stream), sample) gives the very state gi_rng_init does. */
static inline uint64_t gi_rng_seed_key(uint64_t seed) { return gi_mix64(seed + GI_RNG_GAMMA); }

static inline uint64_t gi_rng_stream_key(uint64_t seed_key, uint64_t stream)
{
    return gi_mix64(seed_key ^ (stream + 0xD1B54A32D192ED03ull));
}

static inline void gi_rng_init_stream(gi_rng *r, uint64_t stream_key, uint32_t sample)
{
    r->state = gi_mix64(stream_key ^ ((uint64_t)sample + 0x8CB92BA72F3D8DD7ull));
    r->has_spare = 0;
}

static inline void gi_rng_init(gi_rng *r, uint64_t seed, uint64_t stream, uint32_t sample)
{
    gi_rng_init_stream(r, gi_rng_stream_key(gi_rng_seed_key(seed), stream), sample);
}

static inline uint64_t gi_rng_u64(gi_rng *r)
{
    r->state += GI_RNG_GAMMA;
    return gi_mix64(r->state);
}

static inline uint32_t gi_rng_u32(gi_rng *r)
{
    if (r->has_spare) {
        r->has_spare = 0;
        return r->spare;
    }
    uint64_t v = gi_rng_u64(r);
    r->spare = (uint32_t)(v >> 32);
    r->has_spare = 1;
    return (uint32_t)v;
}

/* Uniform in [0, 1), 24 random bits (exactly representable). */
static inline float gi_rng_float(gi_rng *r)
{
    return (float)(gi_rng_u32(r) >> 8) * (1.0f / 16777216.0f);
}

/* Uniform in [0, 1), 53 random bits. */
static inline double gi_rng_double(gi_rng *r)
{
    return (double)(gi_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* Uniform integer in [0, n), n > 0 (Lemire's multiply-shift, bias < n 2^-32). */
static inline uint32_t gi_rng_below(gi_rng *r, uint32_t n)
{
    return (uint32_t)(((uint64_t)gi_rng_u32(r) * n) >> 32);
}

#endif
