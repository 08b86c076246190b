/* gi_asset_cache: a worker host's on-disk cache of assets by content hash
 * (scene files, meshes, data jobs publish), shared by its pool children
 * through the worker process and kept across jobs and restarts, so each
 * asset crosses the network once per host.
 *
 * <dir>/<first two hex digits>/<hash>, written atomically. Reads verify the
 * bytes against the name (a damaged file is deleted and fetched again).
 * When the total passes max_bytes, the least recently used files (by mtime,
 * refreshed on every read) are deleted down to 90%.
 *
 * One gi-worker per directory, enforced with a lock (<dir>/.lock): a second
 * one would delete the first's half-written files as leftovers, and their
 * batch directories (CACHE/batches by default) would mix. */
#ifndef GI_ASSET_CACHE_H
#define GI_ASSET_CACHE_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_buf.h"
#include "gi_error.h"

typedef struct gi_asset_cache {
    char *dir;
    int lock_fd; /* holds the directory's lock while open */
    uint64_t max_bytes, bytes;
    uint64_t hits, misses, evicted;
} gi_asset_cache;

/* Fails (GI_EINVAL, naming dir) when another process holds it open still
 * after a few seconds (a process may open it twice: the lock is per
 * process). */
int gi_asset_cache_open(gi_asset_cache *c, const char *dir, uint64_t max_bytes, gi_error *err);
void gi_asset_cache_close(gi_asset_cache *c);
/* 1 with the bytes in out, 0 if not cached, -1 on an I/O error. */
int gi_asset_cache_get(gi_asset_cache *c, const char *hash, gi_buf *out, gi_error *err);
/* Stores bytes already verified against hash. */
int gi_asset_cache_put(gi_asset_cache *c, const char *hash, const void *data, size_t len,
                       gi_error *err);

#endif
