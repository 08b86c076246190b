/* Unit tests: the three region heaps pop the same total order (largest key
 * first, ties by smaller tie value), under interleaved pushes and pops. */
#include <stdlib.h>
#include <string.h>

#include "gi_rng.h"
#include "gi_test.h"
#include "quadrature/quad_heap.h"

typedef struct item {
    double key;
    uint64_t tie;
    uint32_t id;
} item;

static int item_cmp(const void *pa, const void *pb)
{
    const item *a = pa, *b = pb;
    if (gi_qheap_before(a->key, a->tie, b->key, b->tie))
        return -1;
    return gi_qheap_before(b->key, b->tie, a->key, a->tie);
}

/* Reference: an unsorted array, scanned for the first element. */
static int ref_pop(item *v, size_t *n, item *out)
{
    if (*n == 0)
        return 0;
    size_t best = 0;
    for (size_t i = 1; i < *n; i++)
        if (item_cmp(&v[i], &v[best]) < 0)
            best = i;
    *out = v[best];
    v[best] = v[--*n];
    return 1;
}

static double random_key(gi_rng *rng)
{
    uint32_t k = gi_rng_below(rng, 100);
    if (k < 10)
        return (double)gi_rng_below(rng, 4); /* many equal keys */
    if (k == 10)
        return NAN;
    if (k == 11)
        return 0.0;
    /* Errors span many orders of magnitude. */
    return exp(-30.0 * gi_rng_double(rng));
}

GI_TEST(test_quad_heaps_pop_in_the_same_total_order)
{
    gi_qheap_kind kinds[3] = {GI_QHEAP_BINARY, GI_QHEAP_PAIRING, GI_QHEAP_BUCKETED};
    size_t cap = 20000;
    item *ref = malloc(cap * sizeof *ref);
    for (int k = 0; k < 3; k++) {
        gi_qheap *h = gi_qheap_create(kinds[k]);
        gi_rng rng;
        gi_rng_init(&rng, 5, 6, 7);
        size_t n = 0, max_buckets = 0;
        uint32_t next = 0;
        int bad = 0;
        for (int step = 0; step < 20000 && !bad; step++) {
            /* Grow for a while (past the bucket split threshold), then mostly
             * pop, like the refinement: one pop, two pushes. */
            int push = step < 10000 ? gi_rng_below(&rng, 3) != 0 : gi_rng_below(&rng, 3) == 0;
            if (push && n < cap) {
                /* Distinct ties: equal (key, tie) pairs have no defined order. */
                item it = {random_key(&rng), gi_mix64(next), next};
                next++;
                ref[n++] = it;
                gi_qheap_push(h, it.key, it.tie, it.id);
            } else {
                item want = {0, 0, 0};
                double key = 0;
                uint64_t tie = 0;
                uint32_t id = 0;
                int got = gi_qheap_pop(h, &key, &tie, &id);
                int exp = ref_pop(ref, &n, &want);
                if (got != exp || (got && (id != want.id || tie != want.tie))) {
                    GI_CHECK_MSG(0, "heap %d step %d: popped %u, expected %u", k, step, id,
                                 want.id);
                    bad = 1;
                }
            }
            GI_CHECK(gi_qheap_size(h) == n);
            if (gi_qheap_buckets(h) > max_buckets)
                max_buckets = gi_qheap_buckets(h);
        }
        /* The bucketed heap did split buckets (eq. 5.1) and merge them back. */
        if (kinds[k] == GI_QHEAP_BUCKETED)
            GI_CHECK_MSG(max_buckets >= 3, "only %zu buckets", max_buckets);
        gi_qheap_free(h);
    }
    free(ref);
}

GI_TEST(test_quad_heap_peek_and_empty)
{
    for (int k = 0; k < 3; k++) {
        gi_qheap *h = gi_qheap_create((gi_qheap_kind)k);
        double key;
        uint64_t tie;
        uint32_t id;
        GI_CHECK(!gi_qheap_peek(h, &key, &tie, &id) && !gi_qheap_pop(h, &key, &tie, &id));
        gi_qheap_push(h, 1.0, 9, 1);
        gi_qheap_push(h, 1.0, 3, 2);
        gi_qheap_push(h, 0.5, 0, 3);
        GI_CHECK(gi_qheap_peek(h, &key, &tie, &id) && id == 2 && key == 1.0);
        GI_CHECK(gi_qheap_pop(h, &key, &tie, &id) && id == 2);
        GI_CHECK(gi_qheap_pop(h, &key, &tie, &id) && id == 1);
        GI_CHECK(gi_qheap_pop(h, &key, &tie, &id) && id == 3);
        GI_CHECK(gi_qheap_size(h) == 0);
        gi_qheap_free(h);
    }
}
