/* gi_frame_cache: encoded frames by content hash, least recently used out. */
#include "gi_frame_cache.h"

#include <stdlib.h>
#include <string.h>

#include "gi_error.h"

void gi_frame_cache_init(gi_frame_cache *c, size_t max_bytes)
{
    memset(c, 0, sizeof *c);
    c->max_bytes = max_bytes;
}

void gi_frame_cache_free(gi_frame_cache *c)
{
    for (size_t i = 0; i < c->count; i++)
        gi_buf_free(&c->entries[i].frame);
    free(c->entries);
    memset(c, 0, sizeof *c);
}

const gi_buf *gi_frame_cache_get(gi_frame_cache *c, const char *hash)
{
    /* A job names a few assets: a scan is enough. */
    for (size_t i = 0; i < c->count; i++)
        if (strcmp(c->entries[i].hash, hash) == 0) {
            c->entries[i].used = ++c->clock;
            return &c->entries[i].frame;
        }
    return NULL;
}

static void evict_oldest(gi_frame_cache *c)
{
    size_t old = 0;
    for (size_t i = 1; i < c->count; i++)
        if (c->entries[i].used < c->entries[old].used)
            old = i;
    c->bytes -= c->entries[old].frame.len;
    gi_buf_free(&c->entries[old].frame);
    c->entries[old] = c->entries[--c->count];
}

void gi_frame_cache_put(gi_frame_cache *c, const char *hash, gi_buf *frame)
{
    if (frame->len > c->max_bytes / 4 || strlen(hash) >= GI_HASH_HEX ||
        gi_frame_cache_get(c, hash))
        return;
    while (c->count && c->bytes + frame->len > c->max_bytes)
        evict_oldest(c);
    if (c->count == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 8;
        c->entries = gi_xrealloc(c->entries, c->cap * sizeof *c->entries);
    }
    gi_frame_cache_entry *e = &c->entries[c->count++];
    memcpy(e->hash, hash, strlen(hash) + 1);
    gi_buf_init(&e->frame);
    gi_buf_move(&e->frame, frame);
    e->used = ++c->clock;
    c->bytes += e->frame.len;
}
