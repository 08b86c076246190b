/* detp_batch_shelf: the batches a worker process keeps open between frames
 * (see detp_batch_shelf.h). */
#include "detp_batch_shelf.h"

#include <stdlib.h>
#include <string.h>

static size_t mapped_bytes(const detp_batch *b)
{
    size_t n = b->base.len + b->grid.len;
    for (uint32_t d = 0; d < b->delta_count; d++)
        n += b->deltas[d].len;
    return n;
}

/* Removes entry i, closing it unless it is handed out. */
static void remove_at(detp_batch_shelf *s, size_t i, detp_batch *out)
{
    s->bytes -= mapped_bytes(&s->b[i]);
    if (out)
        *out = s->b[i];
    else
        detp_batch_close(&s->b[i]);
    memmove(&s->b[i], &s->b[i + 1], (s->count - i - 1) * sizeof *s->b);
    s->count--;
}

int detp_batch_shelf_take(detp_batch_shelf *s, const char *dir, uint32_t batch, uint64_t p0,
                          uint64_t p1, uint32_t frame, detp_batch *out)
{
    for (size_t i = 0; i < s->count; i++) {
        if (s->b[i].batch != batch)
            continue;
        int match = s->b[i].frame == frame && s->b[i].p0 == p0 && s->b[i].p1 == p1 &&
                    detp_batch_files_present(dir, &s->b[i]);
        remove_at(s, i, match ? out : NULL);
        return match;
    }
    return 0;
}

/* Entry i makes way for b: it is b's batch (stale), or it missed a frame
 * (the batch went elsewhere). */
static int gives_way(const detp_batch *kept, const detp_batch *b)
{
    return kept->batch == b->batch || kept->frame + 1 < b->frame;
}

int detp_batch_shelf_fits(const detp_batch_shelf *s, const detp_batch *b)
{
    size_t freed = 0;
    for (size_t i = 0; i < s->count; i++)
        if (gives_way(&s->b[i], b))
            freed += mapped_bytes(&s->b[i]);
    return s->bytes - freed + mapped_bytes(b) <= s->budget;
}

void detp_batch_shelf_put(detp_batch_shelf *s, detp_batch *b)
{
    if (!detp_batch_shelf_fits(s, b)) {
        /* Full of batches still in use: keep those. A process cycling
         * through more batches than fit then still finds the same ones
         * every frame (dropping the oldest would find none). */
        detp_batch_shelf_drop(s, b->batch);
        detp_batch_close(b);
        return;
    }
    detp_batch_shelf_drop(s, b->batch);
    size_t add = mapped_bytes(b);
    /* Batches that missed a frame went elsewhere: they go first. */
    for (size_t i = s->count; i-- > 0 && s->bytes + add > s->budget;)
        if (gives_way(&s->b[i], b))
            remove_at(s, i, NULL);
    if (s->count == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 8;
        s->b = gi_xrealloc(s->b, s->cap * sizeof *s->b);
    }
    detp_batch_release_pages(b);
    s->b[s->count++] = *b;
    s->bytes += add;
    memset(b, 0, sizeof *b);
}

void detp_batch_shelf_drop(detp_batch_shelf *s, uint32_t batch)
{
    for (size_t i = 0; i < s->count; i++)
        if (s->b[i].batch == batch) {
            remove_at(s, i, NULL);
            return;
        }
}

void detp_batch_shelf_free(detp_batch_shelf *s)
{
    while (s->count)
        remove_at(s, s->count - 1, NULL);
    free(s->b);
    memset(s, 0, sizeof *s);
}
