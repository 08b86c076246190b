/* gi_frame_cache: encoded frames kept by a content hash, so that bytes sent
 * to many connections are read, checked and compressed once: gi-farmd's
 * ASSET_PUT of a job's scene and published data to every worker host (the
 * same frame for each: content-addressed bytes never change). The least
 * recently used frames go first once more than max_bytes are held; a frame
 * larger than a quarter of that is not kept. */
#ifndef GI_FRAME_CACHE_H
#define GI_FRAME_CACHE_H

#include <stddef.h>
#include <stdint.h>

#include "gi_assets.h"
#include "gi_buf.h"

typedef struct gi_frame_cache_entry {
    char hash[GI_HASH_HEX];
    gi_buf frame;
    uint64_t used; /* the cache's clock at its last use */
} gi_frame_cache_entry;

typedef struct gi_frame_cache {
    gi_frame_cache_entry *entries;
    size_t count, cap;
    size_t bytes, max_bytes;
    uint64_t clock;
} gi_frame_cache;

void gi_frame_cache_init(gi_frame_cache *c, size_t max_bytes);
void gi_frame_cache_free(gi_frame_cache *c);
/* The frame kept for hash, or NULL. */
const gi_buf *gi_frame_cache_get(gi_frame_cache *c, const char *hash);
/* Keeps frame for hash (taken over: frame is left empty), unless it is too
 * large; evicts the least recently used frames to make room. */
void gi_frame_cache_put(gi_frame_cache *c, const char *hash, gi_buf *frame);

#endif
