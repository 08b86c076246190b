/* quad_heap_pairing: pairing heaps (see quad_heap.h): the node store shared
 * with the bucketed heap, and the single pairing heap. */
#include <stdlib.h>

#include "gi_error.h"
#include "quad_heap_impl.h"

void qp_store_free(qp_store *s)
{
    free(s->n);
    free(s->scratch);
}

uint32_t qp_new(qp_store *s, double key, uint64_t tie, uint32_t item)
{
    uint32_t i;
    if (s->free_head != QP_NIL) {
        i = s->free_head;
        s->free_head = s->n[i].sibling;
    } else {
        if (s->used == s->cap) {
            s->cap = s->cap ? 2 * s->cap : 64;
            s->n = gi_xrealloc(s->n, (size_t)s->cap * sizeof *s->n);
        }
        i = s->used++;
    }
    qp_node *x = &s->n[i];
    x->key = key;
    x->tie = tie;
    x->item = item;
    x->child = x->sibling = QP_NIL;
    return i;
}

void qp_release(qp_store *s, uint32_t i)
{
    s->n[i].sibling = s->free_head;
    s->free_head = i;
}

uint32_t qp_meld(qp_store *s, uint32_t a, uint32_t b)
{
    if (a == QP_NIL)
        return b;
    if (b == QP_NIL)
        return a;
    qp_node *na = &s->n[a], *nb = &s->n[b];
    if (gi_qheap_before(nb->key, nb->tie, na->key, na->tie)) {
        uint32_t t = a;
        a = b;
        b = t;
        na = &s->n[a];
        nb = &s->n[b];
    }
    /* b becomes a's first child. */
    nb->sibling = na->child;
    na->child = b;
    return a;
}

uint32_t qp_pop_root(qp_store *s, uint32_t r)
{
    /* Two-pass pairing of r's children: meld them in pairs left to right,
     * then meld the pairs right to left. */
    size_t k = 0;
    uint32_t c = s->n[r].child;
    while (c != QP_NIL) {
        uint32_t a = c, b = s->n[a].sibling;
        uint32_t next = b == QP_NIL ? QP_NIL : s->n[b].sibling;
        s->n[a].sibling = QP_NIL;
        if (b != QP_NIL)
            s->n[b].sibling = QP_NIL;
        if (k == s->scratch_cap) {
            s->scratch_cap = s->scratch_cap ? 2 * s->scratch_cap : 64;
            s->scratch = gi_xrealloc(s->scratch, s->scratch_cap * sizeof *s->scratch);
        }
        s->scratch[k++] = qp_meld(s, a, b);
        c = next;
    }
    uint32_t root = QP_NIL;
    while (k > 0)
        root = qp_meld(s, s->scratch[--k], root);
    s->n[r].child = QP_NIL;
    return root;
}

typedef struct pairing_heap {
    gi_qheap base;
    qp_store s;
    uint32_t root;
    size_t n;
} pairing_heap;

static void ph_free(gi_qheap *h)
{
    pairing_heap *p = (pairing_heap *)h;
    qp_store_free(&p->s);
    free(p);
}

static size_t ph_size(const gi_qheap *h) { return ((const pairing_heap *)h)->n; }

static void ph_push(gi_qheap *h, double key, uint64_t tie, uint32_t item)
{
    pairing_heap *p = (pairing_heap *)h;
    p->root = qp_meld(&p->s, p->root, qp_new(&p->s, key, tie, item));
    p->n++;
}

static int ph_peek(const gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    const pairing_heap *p = (const pairing_heap *)h;
    if (p->root == QP_NIL)
        return 0;
    const qp_node *x = &p->s.n[p->root];
    *key = x->key;
    *tie = x->tie;
    *item = x->item;
    return 1;
}

static int ph_pop(gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    pairing_heap *p = (pairing_heap *)h;
    if (!ph_peek(h, key, tie, item))
        return 0;
    uint32_t r = p->root;
    p->root = qp_pop_root(&p->s, r);
    qp_release(&p->s, r);
    p->n--;
    return 1;
}

static size_t ph_buckets(const gi_qheap *h) { return 1; }

static const gi_qheap_ops pairing_ops = {ph_free, ph_size, ph_push, ph_pop, ph_peek, ph_buckets};

gi_qheap *gi_qheap_pairing_create(void)
{
    pairing_heap *p = gi_xcalloc(1, sizeof *p);
    p->base.ops = &pairing_ops;
    p->s.free_head = QP_NIL;
    p->root = QP_NIL;
    return &p->base;
}
