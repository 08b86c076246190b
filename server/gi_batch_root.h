/* gi_batch_root: `gi render`'s private batch roots, TMP/gi-render-XXXXXX,
 * where its pool children keep an animation's photon batches.
 *
 * A root holds an owner record, .owner: the render's process (pid and
 * start time, so that a reused pid is not taken for it) and the checkpoint
 * that may name the root. When the next `gi render` starts it removes the
 * roots nobody can use again: their render is gone and no checkpoint names
 * them (a render killed before its first checkpoint, or whose checkpoint
 * was removed or replaced). Roots a checkpoint names are kept for --resume
 * until nobody has touched them for GI_BATCH_DIR_MAX_AGE_S, and so are roots
 * without a record (made by an older gi). */
#ifndef GI_BATCH_ROOT_H
#define GI_BATCH_ROOT_H

#include <stddef.h>

#include "gi_buf.h"
#include "gi_error.h"

/* The owner record, ROOT/.owner: the line "gi-render-owner 1", then
 * "PID START" (decimal, PID > 0; START as /proc/PID/stat's 22nd field, 0
 * if unknown), then the absolute path of the checkpoint that may name the
 * root (an empty line if none), each line ended by a newline. */
typedef struct gi_batch_root_owner {
    long pid;
    unsigned long long start;
    char *ckpt; /* malloc'ed; "" if none */
} gi_batch_root_owner;

/* Records longer than this are not written (the root then waits for the
 * age rule) and not read. */
#define GI_BATCH_ROOT_OWNER_MAX (4096 + 128)

/* Appends o's record; -1 (nothing appended) if its checkpoint path cannot
 * be written in one (a newline in it, not absolute, too long). */
int gi_batch_root_owner_format(const gi_batch_root_owner *o, gi_buf *out);
/* Reads a record exactly as gi_batch_root_owner_format writes it; anything
 * else is GI_EINVAL naming path. */
int gi_batch_root_owner_parse(const char *text, size_t len, const char *path,
                              gi_batch_root_owner *o, gi_error *err);

/* A new root under tmp (an absolute path, malloc'ed), owned by this process
 * for the checkpoint at ckpt (NULL: the render keeps none). */
char *gi_batch_root_make(const char *tmp, const char *ckpt, gi_error *err);
/* Makes this process the owner of an existing root (a resumed render). */
void gi_batch_root_claim(const char *root, const char *ckpt);
/* Removes the roots under tmp that are of no use (see above) and those not
 * touched for max_age_s; returns how many were removed. */
int gi_batch_root_sweep(const char *tmp, double max_age_s);

#endif
