/* quad_heap_bucketed: the thesis's bucketed heap (sec. 5.4; see
 * quad_heap.h for the rules this version settles).
 *
 * Bucket i holds the keys in [lower[i], lower[i+1]) (lower[0] = -inf, the
 * last bucket reaches +inf, NaN counts as +inf), as a pairing heap in the
 * shared node store. Buckets are sorted by range, so the maximum is the
 * root of the last bucket; only the last bucket ever loses elements, and it
 * is removed when it empties, so every bucket is non-empty (but a lone
 * empty one). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_error.h"
#include "quad_heap_impl.h"

#define SPLIT_FRACTION 0.4 /* eq. 5.1: c(i) >= 0.4 n */
#define SPLIT_MIN_TOTAL 1024
#define MAX_BUCKETS 64

typedef struct bucket {
    double lower;
    uint32_t root;
    size_t count;
    size_t retry_at; /* all keys were equal at this count: retry when doubled */
} bucket;

typedef struct bucketed_heap {
    gi_qheap base;
    qp_store s;
    bucket b[MAX_BUCKETS];
    int nb;
    size_t n;
    double *keys; /* split scratch */
    uint32_t *nodes;
    size_t scratch_cap;
} bucketed_heap;

static void bk_free(gi_qheap *h)
{
    bucketed_heap *q = (bucketed_heap *)h;
    qp_store_free(&q->s);
    free(q->keys);
    free(q->nodes);
    free(q);
}

static size_t bk_size(const gi_qheap *h) { return ((const bucketed_heap *)h)->n; }

static size_t bk_buckets(const gi_qheap *h) { return (size_t)((const bucketed_heap *)h)->nb; }

/* The bucket whose range holds key: the last with lower <= key. */
static int find_bucket(const bucketed_heap *q, double key)
{
    if (key != key)
        return q->nb - 1;
    int lo = 0, hi = q->nb - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (q->b[mid].lower <= key)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

static int cmp_double(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return a < b ? -1 : a > b;
}

/* Splits bucket i near the median of its keys (eq. 5.1 fired). */
static void split_bucket(bucketed_heap *q, int i)
{
    bucket *bk = &q->b[i];
    size_t c = bk->count;
    if (c > q->scratch_cap) {
        q->scratch_cap = c;
        q->keys = gi_xrealloc(q->keys, c * sizeof *q->keys);
        q->nodes = gi_xrealloc(q->nodes, c * sizeof *q->nodes);
    }
    /* Collect the bucket's nodes (depth-first over child / sibling links). */
    size_t k = 0, top = 0;
    q->nodes[top++] = bk->root;
    while (top > 0) {
        uint32_t x = q->nodes[--top];
        q->keys[k++] = q->s.n[x].key;
        for (uint32_t y = q->s.n[x].child; y != QP_NIL; y = q->s.n[y].sibling)
            q->nodes[top++] = y;
    }
    /* NaN keys count as +inf for the split point. */
    double kmin = INFINITY;
    for (size_t j = 0; j < c; j++) {
        if (q->keys[j] != q->keys[j])
            q->keys[j] = INFINITY;
        kmin = q->keys[j] < kmin ? q->keys[j] : kmin;
    }
    /* The median of an evenly spaced sample of at most 1024 keys: a key of
     * the bucket, so the upper bucket is not empty; the lower one is not
     * either once m > kmin (below). */
    size_t stride = c > 1024 ? c / 1024 : 1, ns = 0;
    for (size_t j = 0; j < c && ns < 1024; j += stride)
        q->keys[ns++] = q->keys[j];
    qsort(q->keys, ns, sizeof *q->keys, cmp_double);
    double m = q->keys[ns / 2];
    if (m == kmin) {
        /* The lower half of the sample is all the minimum: split at the
         * sample's next key, if any. */
        m = INFINITY;
        for (size_t j = 0; j < ns; j++)
            if (q->keys[j] > kmin) {
                m = q->keys[j];
                break;
            }
    }
    if (m == INFINITY) {
        bk->retry_at = 2 * c;
        return;
    }
    /* Gather the nodes again (the key scratch was sorted), unlink them and
     * deal them out to the two new buckets. */
    top = 0;
    uint32_t *all = q->nodes;
    all[top++] = bk->root;
    uint32_t lo_root = QP_NIL, hi_root = QP_NIL;
    size_t lo_count = 0;
    while (top > 0) {
        uint32_t x = all[--top];
        for (uint32_t y = q->s.n[x].child; y != QP_NIL; y = q->s.n[y].sibling)
            all[top++] = y;
        q->s.n[x].child = q->s.n[x].sibling = QP_NIL;
        double key = q->s.n[x].key;
        if (key == key && key < m) {
            lo_root = qp_meld(&q->s, lo_root, x);
            lo_count++;
        } else {
            hi_root = qp_meld(&q->s, hi_root, x);
        }
    }
    memmove(&q->b[i + 2], &q->b[i + 1], sizeof(bucket) * (size_t)(q->nb - i - 1));
    q->nb++;
    q->b[i].root = lo_root;
    q->b[i].count = lo_count;
    q->b[i].retry_at = 0;
    q->b[i + 1].lower = m;
    q->b[i + 1].root = hi_root;
    q->b[i + 1].count = c - lo_count;
    q->b[i + 1].retry_at = 0;
}

static void bk_push(gi_qheap *h, double key, uint64_t tie, uint32_t item)
{
    bucketed_heap *q = (bucketed_heap *)h;
    int i = find_bucket(q, key);
    bucket *bk = &q->b[i];
    bk->root = qp_meld(&q->s, bk->root, qp_new(&q->s, key, tie, item));
    bk->count++;
    q->n++;
    if (q->n >= SPLIT_MIN_TOTAL && q->nb < MAX_BUCKETS &&
        (double)bk->count >= SPLIT_FRACTION * (double)q->n && bk->count >= bk->retry_at)
        split_bucket(q, i);
}

static int bk_peek(const gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    const bucketed_heap *q = (const bucketed_heap *)h;
    if (q->n == 0)
        return 0;
    const qp_node *x = &q->s.n[q->b[q->nb - 1].root];
    *key = x->key;
    *tie = x->tie;
    *item = x->item;
    return 1;
}

static int bk_pop(gi_qheap *h, double *key, uint64_t *tie, uint32_t *item)
{
    bucketed_heap *q = (bucketed_heap *)h;
    if (!bk_peek(h, key, tie, item))
        return 0;
    bucket *bk = &q->b[q->nb - 1];
    uint32_t r = bk->root;
    bk->root = qp_pop_root(&q->s, r);
    qp_release(&q->s, r);
    bk->count--;
    q->n--;
    if (bk->count == 0 && q->nb > 1)
        q->nb--; /* its range joins the bucket below, which now reaches +inf */
    return 1;
}

static const gi_qheap_ops bucketed_ops = {bk_free, bk_size, bk_push, bk_pop, bk_peek, bk_buckets};

gi_qheap *gi_qheap_bucketed_create(void)
{
    bucketed_heap *q = gi_xcalloc(1, sizeof *q);
    q->base.ops = &bucketed_ops;
    q->s.free_head = QP_NIL;
    q->nb = 1;
    q->b[0].lower = -INFINITY;
    q->b[0].root = QP_NIL;
    return &q->base;
}
