/* quad_heap: the interface over the three implementations (quad_heap.h). */
#include "quad_heap_impl.h"

gi_qheap *gi_qheap_create(gi_qheap_kind kind)
{
    switch (kind) {
    case GI_QHEAP_BINARY:
        return gi_qheap_binary_create();
    case GI_QHEAP_PAIRING:
        return gi_qheap_pairing_create();
    default:
        return gi_qheap_bucketed_create();
    }
}

void gi_qheap_free(gi_qheap *h)
{
    if (h)
        h->ops->free(h);
}

size_t gi_qheap_size(const gi_qheap *h) { return h->ops->size(h); }

void gi_qheap_push(gi_qheap *h, double key, uint64_t tie, uint32_t item)
{
    h->ops->push(h, key, tie, item);
}

int gi_qheap_pop(gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    return h->ops->pop(h, key, tie, item);
}

int gi_qheap_peek(const gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    return h->ops->peek(h, key, tie, item);
}

size_t gi_qheap_buckets(const gi_qheap *h) { return h->ops->buckets(h); }
