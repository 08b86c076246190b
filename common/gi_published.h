/* gi_published: a worker's checked read of the floats a coordinator
 * published for its tasks (gi_job_publish: detp's per-vertex radiance,
 * radiosity's per-corner radiosities). The bytes cross the wire and a
 * host's memory like any result, so they are checked as one: their size,
 * and every value finite and within what the renderer that reads them can
 * take without overflowing. A bad blob fails the task with an error that
 * names it, instead of crashing or rendering NaN light. */
#ifndef GI_PUBLISHED_H
#define GI_PUBLISHED_H

#include <float.h>
#include <stddef.h>

#include "gi_assets.h"
#include "gi_buf.h"
#include "gi_error.h"

/* The largest magnitude of a published value: a shader interpolates them
 * with barycentric weights (in [0, 1], summing to 1, rounded) and adds an
 * emission of at most 1e30 (gi_scene.h) in floats, which stays finite for
 * values up to this. */
#define GI_PUBLISHED_VALUE_MAX (FLT_MAX / 4)

/* A blob's layout: `count` entries (named `entry`, `entries`: "vertex",
 * "vertices") of `per` floats each, named in errors as `what` (e.g. "detp:
 * published radiance"). */
typedef struct gi_published_layout {
    const char *what;
    const char *entry, *entries;
    size_t count;
    unsigned per;
} gi_published_layout;

/* Reads the blob named hash: its count x per floats, malloc'ed. NULL with
 * GI_EPROTO naming the blob (its hash's first 12 digits) and what is wrong:
 * its size, or the first value that is not finite or is beyond
 * GI_PUBLISHED_VALUE_MAX (its entry and channel). */
float *gi_published_floats(const gi_buf *blob, const char *hash, const gi_published_layout *l,
                           gi_error *err);

#endif
