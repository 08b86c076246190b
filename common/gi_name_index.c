/* gi_name_index: open addressing (linear probing) over FNV-1a hashes of
 * names, the table kept at most half full. */
#include "gi_name_index.h"

#include <stdlib.h>
#include <string.h>

#include "gi_error.h"

static uint32_t name_hash(const char *s)
{
    uint32_t h = 2166136261u;
    for (; *s; s++)
        h = (h ^ (uint8_t)*s) * 16777619u;
    return h;
}

void gi_name_index_init(gi_name_index *x)
{
    memset(x, 0, sizeof *x);
}

void gi_name_index_free(gi_name_index *x)
{
    free(x->slots);
    gi_name_index_init(x);
}

int64_t gi_name_index_find(const gi_name_index *x, const char *name)
{
    if (!x->cap)
        return -1;
    uint32_t h = name_hash(name);
    for (size_t i = h & (x->cap - 1);; i = (i + 1) & (x->cap - 1)) {
        const gi_name_slot *sl = &x->slots[i];
        if (!sl->name)
            return -1;
        if (sl->hash == h && strcmp(sl->name, name) == 0)
            return sl->index;
    }
}

static void put(gi_name_slot *slots, size_t cap, gi_name_slot s)
{
    size_t i = s.hash & (cap - 1);
    while (slots[i].name)
        i = (i + 1) & (cap - 1);
    slots[i] = s;
}

void gi_name_index_add(gi_name_index *x, const char *name, uint32_t index)
{
    if (2 * (x->count + 1) > x->cap) {
        size_t cap = x->cap ? 2 * x->cap : 16;
        gi_name_slot *slots = gi_xcalloc(cap, sizeof *slots);
        for (size_t i = 0; i < x->cap; i++)
            if (x->slots[i].name)
                put(slots, cap, x->slots[i]);
        free(x->slots);
        x->slots = slots;
        x->cap = cap;
    }
    put(x->slots, x->cap, (gi_name_slot){name, name_hash(name), index});
    x->count++;
}

int gi_name_index_remove(gi_name_index *x, const char *name)
{
    if (!x->cap)
        return 0;
    size_t mask = x->cap - 1, i = name_hash(name) & mask;
    for (;; i = (i + 1) & mask) {
        if (!x->slots[i].name)
            return 0;
        if (strcmp(x->slots[i].name, name) == 0)
            break;
    }
    /* Backward shift: the slots after the hole that probed past it move up,
     * so that no search stops early at the hole. */
    x->slots[i].name = NULL;
    x->count--;
    for (size_t j = (i + 1) & mask; x->slots[j].name; j = (j + 1) & mask) {
        size_t home = x->slots[j].hash & mask;
        int stays = i <= j ? i < home && home <= j : i < home || home <= j;
        if (stays)
            continue;
        x->slots[i] = x->slots[j];
        x->slots[j].name = NULL;
        i = j;
    }
    return 1;
}
