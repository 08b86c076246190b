/* quad_heap: max-priority queues of regions, keyed by error.
 *
 * Three implementations behind one interface, chosen per job ("heap"):
 *   - GI_QHEAP_BINARY: an implicit binary heap in an array, the baseline
 *     the thesis started from (sec. 5.4).
 *   - GI_QHEAP_PAIRING: a pairing heap (Fredman, Sedgewick, Sleator, Tarjan
 *     1986): O(1) insertion, O(log n) amortized deletion; in practice the
 *     fastest of the Fibonacci-heap family the thesis used via Boost.
 *   - GI_QHEAP_BUCKETED: the thesis's structure (sec. 5.4, Figs. 5.3-5.4):
 *     buckets over disjoint, ordered error ranges, each a pairing heap, so
 *     the maximum is the top of the highest non-empty bucket. A bucket that
 *     holds at least 0.4 n of the n elements (eq. 5.1; once n >= 1024) is
 *     split at the median of (a sample of up to 1024 of) its keys into two
 *     buckets, its elements moving to the one whose range holds them (so
 *     ranges stay disjoint and the maximum stays exact); a bucket emptied by deletions is removed (only
 *     the top bucket loses elements, so every bucket is non-empty).
 *
 * Order: larger key first; equal keys by smaller `tie` first (the region id):
 * a total order, so every implementation pops the same sequence, and a job's
 * result does not depend on the heap it used. NaN keys count as +infinity. */
#ifndef GI_QUAD_HEAP_H
#define GI_QUAD_HEAP_H

#include <stddef.h>
#include <stdint.h>

typedef enum { GI_QHEAP_BUCKETED, GI_QHEAP_BINARY, GI_QHEAP_PAIRING } gi_qheap_kind;

typedef struct gi_qheap gi_qheap;

gi_qheap *gi_qheap_create(gi_qheap_kind kind);
void gi_qheap_free(gi_qheap *h);
size_t gi_qheap_size(const gi_qheap *h);
void gi_qheap_push(gi_qheap *h, double key, uint64_t tie, uint32_t item);
/* Removes the first element; 0 if the heap was empty. */
int gi_qheap_pop(gi_qheap *h, double *key, uint64_t *tie, uint32_t *item);
/* The first element without removing it; 0 if the heap is empty. */
int gi_qheap_peek(const gi_qheap *h, double *key, uint64_t *tie, uint32_t *item);
/* Number of buckets (1 for the single heaps): for benchmarks. */
size_t gi_qheap_buckets(const gi_qheap *h);

/* a comes before b. */
static inline int gi_qheap_before(double ka, uint64_t ta, double kb, uint64_t tb)
{
    int na = ka != ka, nb = kb != kb;
    if (na || nb)
        return na && nb ? ta < tb : na;
    if (ka != kb)
        return ka > kb;
    return ta < tb;
}

#endif
