/* quad_heap_binary: an implicit binary max-heap (see quad_heap.h). */
#include <stdlib.h>

#include "gi_error.h"
#include "quad_heap_impl.h"

typedef struct entry {
    double key;
    uint64_t tie;
    uint32_t item;
} entry;

typedef struct binary_heap {
    gi_qheap base;
    entry *e;
    size_t n, cap;
} binary_heap;

static int before(const entry *a, const entry *b)
{
    return gi_qheap_before(a->key, a->tie, b->key, b->tie);
}

static void bh_free(gi_qheap *h)
{
    binary_heap *b = (binary_heap *)h;
    free(b->e);
    free(b);
}

static size_t bh_size(const gi_qheap *h) { return ((const binary_heap *)h)->n; }

static void bh_push(gi_qheap *h, double key, uint64_t tie, uint32_t item)
{
    binary_heap *b = (binary_heap *)h;
    if (b->n == b->cap) {
        b->cap = b->cap ? 2 * b->cap : 64;
        b->e = gi_xrealloc(b->e, b->cap * sizeof *b->e);
    }
    entry x = {key, tie, item};
    size_t i = b->n++;
    while (i > 0) {
        size_t p = (i - 1) / 2;
        if (!before(&x, &b->e[p]))
            break;
        b->e[i] = b->e[p];
        i = p;
    }
    b->e[i] = x;
}

static int bh_peek(const gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    const binary_heap *b = (const binary_heap *)h;
    if (b->n == 0)
        return 0;
    *key = b->e[0].key;
    *tie = b->e[0].tie;
    *item = b->e[0].item;
    return 1;
}

static int bh_pop(gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    binary_heap *b = (binary_heap *)h;
    if (!bh_peek(h, key, tie, item))
        return 0;
    entry x = b->e[--b->n];
    size_t i = 0, n = b->n;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && before(&b->e[c + 1], &b->e[c]))
            c++;
        if (!before(&b->e[c], &x))
            break;
        b->e[i] = b->e[c];
        i = c;
    }
    if (n > 0)
        b->e[i] = x;
    return 1;
}

static size_t bh_buckets(const gi_qheap *h) { return 1; }

static const gi_qheap_ops binary_ops = {bh_free, bh_size, bh_push, bh_pop, bh_peek, bh_buckets};

gi_qheap *gi_qheap_binary_create(void)
{
    binary_heap *b = gi_xcalloc(1, sizeof *b);
    b->base.ops = &binary_ops;
    return &b->base;
}
