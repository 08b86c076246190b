/* gi_assets: content hashes, manifests, the in-memory asset store and the
 * two asset sources (local directory, manifest + store). */
#include "gi_assets.h"

#include <sodium.h>
#include <stdlib.h>
#include <string.h>

#include "gi_fs.h"

void gi_hash_hex(const void *data, size_t len, char out[GI_HASH_HEX])
{
    unsigned char h[32];
    crypto_generichash(h, sizeof h, data, len, NULL, 0);
    static const char hex[] = "0123456789abcdef";
    for (int i = 0; i < 32; i++) {
        out[2 * i] = hex[h[i] >> 4];
        out[2 * i + 1] = hex[h[i] & 15];
    }
    out[64] = '\0';
}

int gi_hash_is_valid(const char *hex)
{
    for (int i = 0; i < 64; i++) {
        char c = hex[i];
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f')))
            return 0;
    }
    return hex[64] == '\0';
}

void gi_manifest_init(gi_manifest *m)
{
    m->entries = NULL;
    m->count = m->cap = 0;
    gi_name_index_init(&m->by_name);
    gi_name_index_init(&m->by_hash);
}

void gi_manifest_free(gi_manifest *m)
{
    for (size_t i = 0; i < m->count; i++)
        free(m->entries[i].name);
    free(m->entries);
    gi_name_index_free(&m->by_name);
    gi_name_index_free(&m->by_hash);
    gi_manifest_init(m);
}

static void index_hash(gi_manifest *m, size_t i)
{
    if (gi_name_index_find(&m->by_hash, m->entries[i].hash) < 0)
        gi_name_index_add(&m->by_hash, m->entries[i].hash, (uint32_t)i);
}

/* The hash index points into the entries: made again when they move. */
static void reindex_hashes(gi_manifest *m)
{
    gi_name_index_free(&m->by_hash);
    for (size_t i = 0; i < m->count; i++)
        index_hash(m, i);
}

void gi_manifest_append(gi_manifest *m, const char *name, const char *hash, uint64_t size)
{
    if (m->count == m->cap) {
        m->cap = m->cap ? 2 * m->cap : 8;
        m->entries = gi_xrealloc(m->entries, m->cap * sizeof *m->entries);
        reindex_hashes(m);
    }
    size_t i = m->count++;
    gi_manifest_entry *e = &m->entries[i];
    e->name = gi_xstrdup(name);
    memcpy(e->hash, hash, GI_HASH_HEX);
    e->size = size;
    gi_name_index_add(&m->by_name, e->name, (uint32_t)i);
    index_hash(m, i);
}

void gi_manifest_put(gi_manifest *m, const char *name, const char *hash, uint64_t size)
{
    gi_manifest_entry *e = (gi_manifest_entry *)gi_manifest_find(m, name);
    if (!e) {
        gi_manifest_append(m, name, hash, size);
        return;
    }
    e->size = size;
    if (memcmp(e->hash, hash, GI_HASH_HEX) != 0) {
        memcpy(e->hash, hash, GI_HASH_HEX);
        reindex_hashes(m);
    }
}

const gi_manifest_entry *gi_manifest_find(const gi_manifest *m, const char *name)
{
    int64_t i = gi_name_index_find(&m->by_name, name);
    return i >= 0 ? &m->entries[i] : NULL;
}

int gi_manifest_has_hash(const gi_manifest *m, const char *hash)
{
    return gi_name_index_find(&m->by_hash, hash) >= 0;
}

void gi_manifest_encode(const gi_manifest *m, gi_buf *out)
{
    gi_buf_put_u32(out, (uint32_t)m->count);
    for (size_t i = 0; i < m->count; i++) {
        gi_buf_put_str(out, m->entries[i].name);
        gi_buf_put(out, m->entries[i].hash, 64);
        gi_buf_put_u64(out, m->entries[i].size);
    }
}

int gi_manifest_decode(gi_reader *r, gi_manifest *m, gi_error *err)
{
    uint32_t n = gi_get_u32(r);
    if (n > 100000)
        return gi_fail(err, GI_EPROTO, "%s: manifest has %u entries (limit 100000)",
                       r->what, n);
    for (uint32_t i = 0; i < n && !r->failed; i++) {
        char *name = gi_get_str(r, 4096);
        char hash[GI_HASH_HEX];
        gi_get(r, hash, 64);
        hash[64] = '\0';
        uint64_t size = gi_get_u64(r);
        if (!r->failed && (!gi_hash_is_valid(hash) || !name || !name[0])) {
            free(name);
            return gi_fail(err, GI_EPROTO, "%s: manifest entry %u is malformed", r->what, i);
        }
        if (!r->failed && gi_manifest_find(m, name)) {
            free(name);
            return gi_fail(err, GI_EPROTO, "%s: manifest entry %u repeats a name", r->what, i);
        }
        if (name && !r->failed)
            gi_manifest_put(m, name, hash, size);
        free(name);
    }
    if (r->failed)
        return gi_fail(err, GI_EPROTO, "%s: truncated manifest", r->what);
    return 0;
}

/* A flat array, indexed by hash (a scene may bring tens of thousands of
 * files). */
typedef struct store_entry {
    char hash[GI_HASH_HEX];
    gi_buf bytes;
} store_entry;

struct gi_asset_store {
    store_entry *entries;
    size_t count, cap, bytes;
    gi_name_index by_hash; /* points into entries: made again when they move */
};

static void store_reindex(gi_asset_store *s)
{
    gi_name_index_free(&s->by_hash);
    for (size_t i = 0; i < s->count; i++)
        gi_name_index_add(&s->by_hash, s->entries[i].hash, (uint32_t)i);
}

gi_asset_store *gi_asset_store_new(void) { return gi_xcalloc(1, sizeof(gi_asset_store)); }

void gi_asset_store_free(gi_asset_store *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->count; i++)
        gi_buf_free(&s->entries[i].bytes);
    free(s->entries);
    gi_name_index_free(&s->by_hash);
    free(s);
}

/* The entry of a hash (its first 64 characters), or -1. */
static int64_t store_find(const gi_asset_store *s, const char *hash)
{
    char key[GI_HASH_HEX];
    memcpy(key, hash, 64);
    key[64] = '\0';
    return gi_name_index_find(&s->by_hash, key);
}

const gi_buf *gi_asset_store_get(const gi_asset_store *s, const char *hash)
{
    int64_t i = store_find(s, hash);
    return i >= 0 ? &s->entries[i].bytes : NULL;
}

const gi_buf *gi_asset_store_put(gi_asset_store *s, const char *hash, const void *data,
                                 size_t len)
{
    const gi_buf *have = gi_asset_store_get(s, hash);
    if (have)
        return have;
    if (s->count == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 8;
        s->entries = gi_xrealloc(s->entries, s->cap * sizeof *s->entries);
        store_reindex(s);
    }
    size_t i = s->count++;
    store_entry *e = &s->entries[i];
    memcpy(e->hash, hash, 64);
    e->hash[64] = '\0';
    gi_buf_init(&e->bytes);
    gi_buf_put(&e->bytes, data, len);
    s->bytes += len;
    gi_name_index_add(&s->by_hash, e->hash, (uint32_t)i);
    return &e->bytes;
}

int gi_asset_store_remove(gi_asset_store *s, const char *hash)
{
    int64_t i = store_find(s, hash);
    if (i < 0)
        return 0;
    s->bytes -= s->entries[i].bytes.len;
    gi_buf_free(&s->entries[i].bytes);
    gi_name_index_remove(&s->by_hash, s->entries[i].hash);
    size_t last = --s->count;
    if ((size_t)i != last) { /* the last entry moves into i's place */
        gi_name_index_remove(&s->by_hash, s->entries[last].hash);
        s->entries[i] = s->entries[last];
        gi_name_index_add(&s->by_hash, s->entries[i].hash, (uint32_t)i);
    }
    return 1;
}

size_t gi_asset_store_bytes(const gi_asset_store *s) { return s->bytes; }

size_t gi_asset_store_count(const gi_asset_store *s) { return s->count; }

const gi_buf *gi_asset_store_at(const gi_asset_store *s, size_t i, char hash[GI_HASH_HEX])
{
    memcpy(hash, s->entries[i].hash, GI_HASH_HEX);
    return &s->entries[i].bytes;
}

void gi_dir_source_init(gi_dir_source *d, const char *root)
{
    d->root = gi_xstrdup(root);
    gi_manifest_init(&d->manifest);
    d->store = gi_asset_store_new();
}

void gi_dir_source_free(gi_dir_source *d)
{
    free(d->root);
    gi_manifest_free(&d->manifest);
    gi_asset_store_free(d->store);
    d->store = NULL;
}

static int dir_read(void *ctx, const char *name, gi_buf *out, gi_error *err)
{
    gi_dir_source *d = ctx;
    const gi_manifest_entry *known = gi_manifest_find(&d->manifest, name);
    if (known) {
        /* Read each name once per job: later readers see the same bytes
         * even if the file changes on disk meanwhile. */
        const gi_buf *b = gi_asset_store_get(d->store, known->hash);
        gi_buf_reset(out);
        gi_buf_put(out, b->data, b->len);
        return 0;
    }
    char *path = gi_path_join(d->root, name);
    int rc = gi_read_file(path, GI_ASSET_MAX_BYTES, out, err);
    free(path);
    if (rc)
        return -1;
    char hash[GI_HASH_HEX];
    gi_hash_hex(out->data, out->len, hash);
    gi_asset_store_put(d->store, hash, out->data, out->len);
    gi_manifest_put(&d->manifest, name, hash, out->len);
    return 0;
}

gi_asset_source gi_dir_source_as_source(gi_dir_source *d)
{
    gi_asset_source s = {dir_read, d};
    return s;
}

static int manifest_read(void *ctx, const char *name, gi_buf *out, gi_error *err)
{
    gi_manifest_source *m = ctx;
    const gi_manifest_entry *e = gi_manifest_find(m->manifest, name);
    if (!e)
        return gi_fail(err, GI_EINVAL, "%s: not among the job's assets", name);
    const gi_buf *b = gi_asset_store_get(m->store, e->hash);
    if (!b && m->fetch) {
        if (m->fetch(m->fetch_ctx, e->hash, err))
            return gi_error_prefix(err, "%s", name);
        b = gi_asset_store_get(m->store, e->hash);
    }
    if (!b)
        return gi_fail(err, GI_EIO, "%s: asset %.12s is not available", name, e->hash);
    gi_buf_reset(out);
    gi_buf_put(out, b->data, b->len);
    return 0;
}

gi_asset_source gi_manifest_source_as_source(gi_manifest_source *m)
{
    gi_asset_source s = {manifest_read, m};
    return s;
}
