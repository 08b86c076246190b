/* quad_refine: the adaptive loop (thesis Algorithm 1, sec. 4.3).
 *
 * Take the region with the largest error from the heap, bisect it along its
 * axis, and for each child: if its error is below the threshold (or it
 * cannot be split) it is final ("closed": its radiance is splatted and it
 * is never looked at again), else it goes back into the heap. One bisection
 * is one iteration. The loop ends when the split budget is spent, the heap
 * is empty, the largest error is below the threshold, or the caller's stop
 * test says so; what is left in the heap stays open. A popped parent is not
 * splatted: its children replace it (the callbacks see both). */
#ifndef GI_QUAD_REFINE_H
#define GI_QUAD_REFINE_H

#include "quad_heap.h"
#include "quad_region.h"

typedef struct gi_quad_refine_cb {
    /* parent was bisected into child[0], child[1] (both evaluated). */
    void (*on_split)(void *user, const gi_quad_region *parent, gi_quad_region *const child[2]);
    /* r is final; it is released after the call. */
    void (*on_close)(void *user, gi_quad_region *r);
    /* Polled before each split; nonzero ends the loop. May be NULL. */
    int (*stop)(void *user);
    void *user;
} gi_quad_refine_cb;

/* Puts a region in the heap (items are engine slots, keys its eq. 4.5
 * error), or closes it if it is final already. */
void gi_quad_refine_offer(gi_quad_engine *e, gi_qheap *heap, gi_quad_region *r, double threshold,
                          const gi_quad_refine_cb *cb);

/* Runs the loop for at most max_splits bisections; *splits counts them. */
int gi_quad_refine(gi_quad_engine *e, gi_qheap *heap, double threshold, uint64_t max_splits,
                   const gi_quad_refine_cb *cb, uint64_t *splits, gi_error *err);

#endif
