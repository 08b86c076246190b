/* rad_kernel: the factor's counts times three vectors. */
#include "rad_kernel.h"

#include <math.h>
#include <pthread.h>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

/* The fixed reduction of 16 lanes: l + l+8, then + l+4, + l+2, + l+1. */
static inline float reduce16(const float *a)
{
    float t8[8], t4[4], t2[2];
    for (int l = 0; l < 8; l++)
        t8[l] = a[l] + a[l + 8];
    for (int l = 0; l < 4; l++)
        t4[l] = t8[l] + t8[l + 4];
    for (int l = 0; l < 2; l++)
        t2[l] = t4[l] + t4[l + 2];
    return t2[0] + t2[1];
}

/* The excess of the 8-bit counts, after the dense part. */
static void add_excess(const gi_rad_counts *u, const float *s, float *y, uint32_t r0, uint32_t r1)
{
    if (!u->h8)
        return;
    for (uint32_t e = r0; e < r1; e++)
        for (uint32_t i = u->over_row[e]; i < u->over_row[e + 1]; i++) {
            float x = (float)u->over_val[i];
            for (int c = 0; c < 3; c++)
                y[3 * (size_t)e + c] =
                    fmaf(x, s[(size_t)c * u->k_pad + u->over_col[i]], y[3 * (size_t)e + c]);
        }
}

void gi_rad_apply3_portable(const gi_rad_counts *u, const float *s, float *y, uint32_t r0,
                            uint32_t r1)
{
    uint32_t kp = u->k_pad;
    for (uint32_t e = r0; e < r1; e++) {
        float acc[3][16] = {{0}};
        for (uint32_t p = 0; p < kp; p += 16)
            for (int l = 0; l < 16; l++) {
                size_t at = (size_t)e * kp + p + (uint32_t)l;
                float hv = u->h8 ? (float)u->h8[at] : (float)u->h16[at];
                for (int c = 0; c < 3; c++)
                    acc[c][l] = fmaf(hv, s[(size_t)c * kp + p + (uint32_t)l], acc[c][l]);
            }
        for (int c = 0; c < 3; c++)
            y[3 * (size_t)e + c] = reduce16(acc[c]);
    }
    add_excess(u, s, y, r0, r1);
}

#if defined(__x86_64__)
#define TARGET __attribute__((target("avx2,fma")))

TARGET static inline float reduce_avx2(__m256 lo, __m256 hi)
{
    __m256 v = _mm256_add_ps(lo, hi);                                               /* l + l+8 */
    __m128 v4 = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1)); /* + l+4 */
    __m128 v2 = _mm_add_ps(v4, _mm_movehl_ps(v4, v4));                              /* + l+2 */
    __m128 v1 = _mm_add_ss(v2, _mm_shuffle_ps(v2, v2, 1));                          /* + l+1 */
    return _mm_cvtss_f32(v1);
}

/* Three colours from columns p..p+15 (their counts in hl, hh). */
#define FMA3(hl, hh)                                                                               \
    do {                                                                                           \
        a0l = _mm256_fmadd_ps(hl, _mm256_loadu_ps(s0 + p), a0l);                                   \
        a0h = _mm256_fmadd_ps(hh, _mm256_loadu_ps(s0 + p + 8), a0h);                               \
        a1l = _mm256_fmadd_ps(hl, _mm256_loadu_ps(s1 + p), a1l);                                   \
        a1h = _mm256_fmadd_ps(hh, _mm256_loadu_ps(s1 + p + 8), a1h);                               \
        a2l = _mm256_fmadd_ps(hl, _mm256_loadu_ps(s2 + p), a2l);                                   \
        a2h = _mm256_fmadd_ps(hh, _mm256_loadu_ps(s2 + p + 8), a2h);                               \
    } while (0)

TARGET static void apply3_avx2(const gi_rad_counts *u, const float *s, float *y, uint32_t r0,
                               uint32_t r1)
{
    uint32_t kp = u->k_pad;
    const float *s0 = s, *s1 = s + kp, *s2 = s + 2 * (size_t)kp;
    for (uint32_t e = r0; e < r1; e++) {
        __m256 a0l = _mm256_setzero_ps(), a0h = _mm256_setzero_ps();
        __m256 a1l = _mm256_setzero_ps(), a1h = _mm256_setzero_ps();
        __m256 a2l = _mm256_setzero_ps(), a2h = _mm256_setzero_ps();
        /* The hardware prefetcher alone leaves these loops ~40% below
         * streaming speed (measured); asking 2 KiB ahead closes most of
         * it. A prefetch past the end of the array is harmless. */
        if (u->h8) {
            const uint8_t *h = u->h8 + (size_t)e * kp;
            for (uint32_t p = 0; p < kp; p += 16) {
                _mm_prefetch((const char *)(h + p) + 2048, _MM_HINT_T0);
                __m128i raw = _mm_loadu_si128((const __m128i *)(h + p));
                __m256 hl = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(raw));
                __m256 hh = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_srli_si128(raw, 8)));
                FMA3(hl, hh);
            }
        } else {
            const uint16_t *h = u->h16 + (size_t)e * kp;
            for (uint32_t p = 0; p < kp; p += 16) {
                _mm_prefetch((const char *)(h + p) + 2048, _MM_HINT_T0);
                __m256i raw = _mm256_loadu_si256((const __m256i *)(h + p));
                __m256 hl = _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_castsi256_si128(raw)));
                __m256 hh =
                    _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_extracti128_si256(raw, 1)));
                FMA3(hl, hh);
            }
        }
        y[3 * (size_t)e + 0] = reduce_avx2(a0l, a0h);
        y[3 * (size_t)e + 1] = reduce_avx2(a1l, a1h);
        y[3 * (size_t)e + 2] = reduce_avx2(a2l, a2h);
    }
    add_excess(u, s, y, r0, r1);
}
#endif

int gi_rad_apply3_avx2(const gi_rad_counts *u, const float *s, float *y, uint32_t r0, uint32_t r1)
{
#if defined(__x86_64__)
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
        apply3_avx2(u, s, y, r0, r1);
        return 1;
    }
#endif
    (void)u, (void)s, (void)y, (void)r0, (void)r1;
    return 0;
}

typedef struct apply_job {
    const gi_rad_counts *u;
    const float *s;
    float *y;
    uint32_t r0, r1;
} apply_job;

static void *apply_thread(void *arg)
{
    apply_job *j = arg;
    if (!gi_rad_apply3_avx2(j->u, j->s, j->y, j->r0, j->r1))
        gi_rad_apply3_portable(j->u, j->s, j->y, j->r0, j->r1);
    return NULL;
}

#define MAX_THREADS 64

void gi_rad_apply3(const gi_rad_counts *u, const float *s, float *y, int threads)
{
    if (threads > MAX_THREADS)
        threads = MAX_THREADS;
    /* Below a few MB of counts a thread costs more than it saves. */
    if (threads <= 1 || (uint64_t)u->n * u->k_pad < ((uint64_t)1 << 22)) {
        apply_job j = {u, s, y, 0, u->n};
        apply_thread(&j);
        return;
    }
    apply_job jobs[MAX_THREADS];
    pthread_t tid[MAX_THREADS];
    int started[MAX_THREADS] = {0};
    for (int t = 0; t < threads; t++) {
        jobs[t] = (apply_job){u, s, y, (uint32_t)((uint64_t)u->n * t / threads),
                              (uint32_t)((uint64_t)u->n * (t + 1) / threads)};
        if (t > 0)
            started[t] = pthread_create(&tid[t], NULL, apply_thread, &jobs[t]) == 0;
    }
    apply_thread(&jobs[0]);
    for (int t = 1; t < threads; t++) {
        if (started[t])
            pthread_join(tid[t], NULL);
        else
            apply_thread(&jobs[t]); /* no thread: do its rows here */
    }
}
