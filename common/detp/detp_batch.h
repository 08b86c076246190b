/* detp_batch: a photon batch of an animation as the worker keeps it between
 * frames, in its batch directory.
 *
 * Rewriting every segment every frame would cost more than the update
 * itself (the update only reads them), so a batch is a BASE file holding
 * all its segments at some frame k plus one DELTA file per later frame,
 * holding the whole new path of every path that frame changed (both in the
 * batch store format, detp_store.c):
 *
 *   b12.f0.base  b12.f0.grid  b12.f1.delta  b12.f2.delta ...
 *
 * (a base's grid, detp_grid.h, lists its paths by the cells they cross).
 * The batch at frame f is the base with, for each path, its newest run in
 * the deltas up to f. When the deltas outgrow the base (or would number
 * more than DETP_BATCH_MAX_DELTAS), the frame is written as a new base.
 * Files a retry could still need (the frame before the newest) are kept;
 * older ones are removed. The files are a cache: they are not fsync'ed; a
 * torn or missing file is regenerated from the seed range
 * (detp_anim_worker.c). */
#ifndef GI_DETP_BATCH_H
#define GI_DETP_BATCH_H

#include <stdint.h>

#include "detp_anim.h"
#include "detp_grid.h"

/* The most deltas a base gets before it is rewritten (detp_batch.c says
 * why the rewrites wait). */
#define DETP_BATCH_MAX_DELTAS 64

/* One path: its segments, in bounce order. */
typedef struct detp_path {
    uint64_t photon;
    const gi_detp_segment *seg;
    uint32_t count;
} detp_path;

typedef struct detp_batch {
    uint32_t batch, frame, base_frame;
    uint64_t p0, p1;
    gi_detp_store_mapping base;
    detp_grid grid; /* the base's */
    gi_detp_store_mapping *deltas; /* frames base_frame+1 .. frame */
    uint32_t delta_count;
    uint64_t delta_segments;
    /* The newest run of every path the deltas changed, by photon. */
    detp_path *over;
    size_t over_count;
    /* The static discs each record of the newest file (detp_batch_newest)
     * crosses, as the process that wrote it found them
     * (detp_anim_worker.c): record i's are cross_ids[cross_off[i] ..
     * cross_off[i + 1]) where cross_known[i]. Memory only (a batch kept
     * open, detp_batch_shelf.h); NULL: none. */
    uint32_t *cross_off, *cross_ids;
    uint8_t *cross_known;
} detp_batch;

/* Opens batch `batch` (photons [p0, p1)) at `frame` from dir: 1 if found
 * whole, 0 if some file is missing or invalid (err says which; regenerate),
 * -1 on an I/O error. A base without its grid (spec) gets it rebuilt. */
int detp_batch_open(const char *dir, const detp_grid_spec *spec, uint32_t batch, uint64_t p0,
                    uint64_t p1, uint32_t frame, detp_batch *b, gi_error *err);
void detp_batch_close(detp_batch *b);
/* Lets go of the pages of the base and grid a frame read (they stay in the
 * page cache; the next read maps them again): a batch kept open between
 * frames then does not hold its whole base in the process's memory. */
void detp_batch_release_pages(const detp_batch *b);
/* The newest file: the newest delta, or the base if there is none. */
static inline const gi_detp_store_mapping *detp_batch_newest(const detp_batch *b)
{
    return b->delta_count ? &b->deltas[b->delta_count - 1] : &b->base;
}
/* Frees the crossing lists of the newest file. */
void detp_batch_forget_crossings(detp_batch *b);
/* The files of an open batch are still on disk (its base and newest
 * delta, by inode): a batch kept open must not outlive them. */
int detp_batch_files_present(const char *dir, const detp_batch *b);
/* Brings b, open at frame f-1, to frame f once detp_batch_write_frame has
 * written f (as_base: its return value): maps the new delta and merges its
 * runs into the overrides, without touching the rest; or reopens b on the
 * new base. Returns like detp_batch_open (b is closed unless 1). */
int detp_batch_advance(const char *dir, const detp_grid_spec *spec, detp_batch *b,
                       uint32_t frame, int as_base, gi_error *err);

/* Iterates the batch's paths in photon order. */
typedef struct detp_batch_iter {
    const detp_batch *b;
    size_t i; /* next base record */
    size_t o; /* next override */
} detp_batch_iter;

static inline void detp_batch_iter_init(detp_batch_iter *it, const detp_batch *b)
{
    it->b = b;
    it->i = 0;
    it->o = 0;
}
/* The next path, or 0 at the end. */
int detp_batch_next(detp_batch_iter *it, detp_path *run);

/* The paths that may come within either sphere: those the base's grid
 * lists in the cells the spheres overlap, and those a delta changed whose
 * newest run comes near one (over the same part of each segment as the
 * grid). Sets mark[i] to 1 for photon p0 + i if so, and to 0 for another
 * changed path (mark has p1 - p0 entries). */
void detp_batch_mark_near(const detp_batch *b, gi_detp_mobile_pose s0, gi_detp_mobile_pose s1,
                          uint8_t *mark);
/* The runs of the marked paths (mark[i]: photon p0 + i) as of the batch's
 * frame, in photon order, into *runs (grown as needed, *cap its room).
 * Returns how many. */
size_t detp_batch_marked(const detp_batch *b, const uint8_t *mark, detp_path **runs,
                         size_t *cap);
/* Segments in the batch at its frame. */
uint64_t detp_batch_count(const detp_batch *b);
/* The batch after `prev` with the whole new runs in `changed` (path-ordered)
 * replacing their paths' runs: every segment, path-ordered, into out. */
void detp_batch_materialize(const detp_batch *prev, const gi_detp_segments *changed,
                            gi_detp_segments *out);
/* Writes frame f of a batch: a delta (the whole new runs of the changed
 * paths, path-ordered, in `changed`) after `prev` (the batch at f-1, still
 * open), or a new base (with its grid) if the deltas would outgrow the
 * base. Then removes the files older than prev's base. Returns 0 (a delta
 * was written), 1 (a base) or -1. */
int detp_batch_write_frame(const char *dir, const detp_grid_spec *spec, const detp_batch *prev,
                           uint32_t frame, const gi_detp_segments *changed, gi_error *err);
/* Writes a whole batch as a base at `frame` (frame 0, or a regeneration),
 * with its grid. */
int detp_batch_write_base(const char *dir, const detp_grid_spec *spec, uint32_t batch,
                          uint64_t p0, uint64_t p1, uint32_t frame, const gi_detp_segments *s,
                          gi_error *err);
/* Removes every file of the batch (after its last frame). */
void detp_batch_remove(const char *dir, uint32_t batch);

#endif
