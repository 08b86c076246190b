/* gi_affinity: the key -> owner map and the rule for who takes a task. */
#include "gi_affinity.h"

#include <stdlib.h>
#include <string.h>

#include "gi_error.h"

void gi_affinity_init(gi_affinity *m) { memset(m, 0, sizeof *m); }

void gi_affinity_free(gi_affinity *m)
{
    free(m->slots);
    gi_affinity_init(m);
}

static size_t slot_of(uint64_t key, size_t cap)
{
    /* splitmix64's finalizer: keys are small consecutive integers. */
    uint64_t z = key + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (size_t)(z ^ (z >> 31)) & (cap - 1);
}

static gi_affinity_slot *find(const gi_affinity *m, uint64_t key)
{
    if (!m->cap)
        return NULL;
    for (size_t i = slot_of(key, m->cap);; i = (i + 1) & (m->cap - 1)) {
        gi_affinity_slot *s = &m->slots[i];
        if (s->key == key || s->key == 0)
            return s;
    }
}

static void grow(gi_affinity *m)
{
    gi_affinity old = *m;
    m->cap = old.cap ? 2 * old.cap : 64;
    m->slots = gi_xcalloc(m->cap, sizeof *m->slots);
    m->count = 0;
    for (size_t i = 0; i < old.cap; i++)
        if (old.slots[i].key) {
            *find(m, old.slots[i].key) = old.slots[i];
            m->count++;
        }
    free(old.slots);
}

const void *gi_affinity_owner(const gi_affinity *m, uint64_t key)
{
    const gi_affinity_slot *s = key ? find(m, key) : NULL;
    return s && s->key ? s->owner : NULL;
}

const void *gi_affinity_set(gi_affinity *m, uint64_t key, const void *owner)
{
    if (!key)
        return NULL;
    /* A forgotten key keeps its slot with a NULL owner (no tombstones needed). */
    if (2 * (m->count + 1) > m->cap)
        grow(m);
    gi_affinity_slot *s = find(m, key);
    const void *prev = s->key ? s->owner : NULL;
    if (!s->key) {
        s->key = key;
        m->count++;
    }
    s->owner = owner;
    return prev;
}

int gi_affinity_may_take(const gi_affinity *m, uint64_t key, const void *host,
                         gi_affinity_present_fn present, void *ctx)
{
    const void *owner = key ? gi_affinity_owner(m, key) : NULL;
    return !owner || owner == host || !present(ctx, owner);
}
