/* quad_refine: the adaptive loop (see quad_refine.h). */
#include "quad_refine.h"

void gi_quad_refine_offer(gi_quad_engine *e, gi_qheap *heap, gi_quad_region *r, double threshold,
                          const gi_quad_refine_cb *cb)
{
    if (r->s.axis < 0 || r->s.err < threshold) {
        if (cb->on_close)
            cb->on_close(cb->user, r);
        gi_quad_region_release(e, r);
        return;
    }
    gi_qheap_push(heap, r->s.err, r->s.id, r->slot);
}

int gi_quad_refine(gi_quad_engine *e, gi_qheap *heap, double threshold, uint64_t max_splits,
                   const gi_quad_refine_cb *cb, uint64_t *splits, gi_error *err)
{
    *splits = 0;
    while (*splits < max_splits) {
        double key;
        uint64_t tie;
        uint32_t slot;
        if (!gi_qheap_peek(heap, &key, &tie, &slot) || key < threshold)
            break;
        if (cb->stop && cb->stop(cb->user))
            break;
        gi_qheap_pop(heap, &key, &tie, &slot);
        gi_quad_region *r = gi_quad_region_at(e, slot), *child[2];
        if (gi_quad_region_split(e, r, child, err)) {
            gi_qheap_push(heap, key, tie, slot);
            return -1;
        }
        (*splits)++;
        if (cb->on_split)
            cb->on_split(cb->user, r, child);
        gi_quad_region_release(e, r);
        for (int k = 0; k < 2; k++)
            gi_quad_refine_offer(e, heap, child[k], threshold, cb);
    }
    return 0;
}
