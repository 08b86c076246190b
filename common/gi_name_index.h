/* gi_name_index: which entry of a growing array bears a name, in constant
 * expected time. Scenes with hundreds of thousands of objects look names up
 * once per object while loading, where a scan of the array made loading
 * quadratic.
 *
 * The index keeps no copies: it points at names the caller owns, which must
 * stay in place (and unchanged) while the index is used; the arrays that
 * hold them may move, as only the names' own storage is referenced. */
#ifndef GI_NAME_INDEX_H
#define GI_NAME_INDEX_H

#include <stddef.h>
#include <stdint.h>

typedef struct gi_name_slot {
    const char *name; /* NULL: empty */
    uint32_t hash, index;
} gi_name_slot;

typedef struct gi_name_index {
    gi_name_slot *slots;
    size_t cap, count; /* cap: 0 or a power of two, at least twice count */
} gi_name_index;

void gi_name_index_init(gi_name_index *x);
void gi_name_index_free(gi_name_index *x);
/* The index stored with `name`, or -1. */
int64_t gi_name_index_find(const gi_name_index *x, const char *name);
/* Records that `name` (not in the index yet) is entry `index`. */
void gi_name_index_add(gi_name_index *x, const char *name, uint32_t index);
/* Forgets `name` (1 if it was there). */
int gi_name_index_remove(gi_name_index *x, const char *name);

#endif
