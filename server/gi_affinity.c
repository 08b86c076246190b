/* gi_affinity: the key -> owner map and the rule for who takes a task. */
#include "gi_affinity.h"

#include <stdlib.h>
#include <string.h>

#include "gi_error.h"
#include "gi_msg_ctrl.h"

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

#define AFFINITY_MAGIC 0x46414947u /* "GIAF" */
#define AFFINITY_VERSION 1u

void gi_affinity_encode(const gi_affinity *m, const char *(*name)(const void *owner),
                        gi_buf *out)
{
    gi_buf_put_u32(out, AFFINITY_MAGIC);
    gi_buf_put_u32(out, AFFINITY_VERSION);
    uint64_t n = 0;
    for (size_t i = 0; i < m->cap; i++)
        n += m->slots[i].key && m->slots[i].owner;
    gi_buf_put_u64(out, n);
    for (size_t i = 0; i < m->cap; i++)
        if (m->slots[i].key && m->slots[i].owner) {
            gi_buf_put_u64(out, m->slots[i].key);
            gi_buf_put_str(out, name(m->slots[i].owner));
        }
}

int gi_affinity_decode(const void *data, size_t len, const char *what,
                       void (*each)(void *ctx, uint64_t key, const char *name), void *ctx,
                       gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, data, len, what);
    uint32_t magic = gi_get_u32(&r), version = gi_get_u32(&r);
    uint64_t n = gi_get_u64(&r);
    /* An entry takes 12 bytes at least: a count beyond that is damage. */
    if (r.failed || magic != AFFINITY_MAGIC || version != AFFINITY_VERSION || n > r.left / 12)
        return gi_fail(err, GI_EPROTO, "%s: not an affinity file", what);
    for (uint64_t i = 0; i < n && !r.failed; i++) {
        uint64_t key = gi_get_u64(&r);
        char *name = gi_get_str(&r, GI_MSG_MAX_NAME);
        if (name && key && name[0])
            each(ctx, key, name);
        free(name);
    }
    return gi_reader_finish(&r, err) ? 1 : 0;
}
