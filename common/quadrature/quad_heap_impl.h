/* quad_heap_impl: what the heap implementations share (internal).
 *
 * Pairing-heap nodes live in one growable store (indices, not pointers, so
 * it may move), which the bucketed heap shares among its buckets. */
#ifndef GI_QUAD_HEAP_IMPL_H
#define GI_QUAD_HEAP_IMPL_H

#include "quad_heap.h"

#define QP_NIL UINT32_MAX

typedef struct qp_node {
    double key;
    uint64_t tie;
    uint32_t item;
    uint32_t child, sibling;
} qp_node;

typedef struct qp_store {
    qp_node *n;
    uint32_t cap, used, free_head;
    uint32_t *scratch; /* pairing passes */
    size_t scratch_cap;
} qp_store;

void qp_store_free(qp_store *s);
uint32_t qp_new(qp_store *s, double key, uint64_t tie, uint32_t item);
void qp_release(qp_store *s, uint32_t i);
/* Root of the meld of two heaps (either may be QP_NIL). */
uint32_t qp_meld(qp_store *s, uint32_t a, uint32_t b);
/* Root of the heap left after removing root r (r's node is not released). */
uint32_t qp_pop_root(qp_store *s, uint32_t r);

typedef struct gi_qheap_ops {
    void (*free)(gi_qheap *h);
    size_t (*size)(const gi_qheap *h);
    void (*push)(gi_qheap *h, double key, uint64_t tie, uint32_t item);
    int (*pop)(gi_qheap *h, double *key, uint64_t *tie, uint32_t *item);
    int (*peek)(const gi_qheap *h, double *key, uint64_t *tie, uint32_t *item);
    size_t (*buckets)(const gi_qheap *h);
} gi_qheap_ops;

struct gi_qheap {
    const gi_qheap_ops *ops;
};

gi_qheap *gi_qheap_binary_create(void);
gi_qheap *gi_qheap_pairing_create(void);
gi_qheap *gi_qheap_bucketed_create(void);

#endif
