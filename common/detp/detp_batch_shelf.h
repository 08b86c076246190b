/* detp_batch_shelf: the batches a worker process keeps open between frames.
 *
 * A batch's next frame usually comes back to the same process (the farm
 * sends it to the host that holds its files, and one pool process often
 * runs every batch of a frame). Opening the batch from its files every
 * frame maps the base and every delta again, merges all the deltas'
 * runs, and faults the pages of the paths it reads in again; a batch kept
 * open only needs the delta its frame wrote (detp_batch_advance). The
 * shelf holds batches up to a budget of mapped bytes, and lets go of the
 * pages of their bases and grids (the next frame maps those it reads again,
 * from the page cache), so that a kept batch does not stay in the
 * process's resident memory; the files stay the truth: a batch not on the shelf at the frame asked for, or whose files
 * were removed or replaced meanwhile, is opened from them (or
 * regenerated). */
#ifndef GI_DETP_BATCH_SHELF_H
#define GI_DETP_BATCH_SHELF_H

#include "detp_batch.h"

typedef struct detp_batch_shelf {
    detp_batch *b;
    size_t count, cap;
    size_t bytes, budget; /* mapped bytes on the shelf, and the most kept */
} detp_batch_shelf;

/* Takes batch `batch` (photons [p0, p1)) at `frame` off the shelf into *out:
 * 1, or 0 if the shelf has it at no such frame or its files in dir are
 * gone or replaced (it is then closed). */
int detp_batch_shelf_take(detp_batch_shelf *s, const char *dir, uint32_t batch, uint64_t p0,
                          uint64_t p1, uint32_t frame, detp_batch *out);
/* Puts *b on the shelf (the shelf owns it; *b is cleared). If it does not
 * fit the budget, batches that missed a frame (kept at a frame before b's
 * previous one) are closed to make room; if it still does not fit, b is
 * closed instead. */
void detp_batch_shelf_put(detp_batch_shelf *s, detp_batch *b);
/* 1 if detp_batch_shelf_put would keep b (with the room it can make). */
int detp_batch_shelf_fits(const detp_batch_shelf *s, const detp_batch *b);
/* Closes batch `batch` if the shelf has it (its files are going). */
void detp_batch_shelf_drop(detp_batch_shelf *s, uint32_t batch);
/* Closes everything. */
void detp_batch_shelf_free(detp_batch_shelf *s);

#endif
