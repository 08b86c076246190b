/* gi_assets: the files a job reads, by name and by content.
 *
 * A job names files (the scene, its meshes, the materials a mesh names);
 * every reader goes through a gi_asset_source, so the scene loader does not
 * care whether bytes come from the local disk (gi render), from the parent
 * over a socketpair (pool children) or from a coordinator (farm workers).
 *
 * The manifest records, for each name read, the content hash (BLAKE2b-256,
 * hex) and size. It travels with the job; receivers fetch bytes by hash and
 * cache them, so nothing needs a shared filesystem. */
#ifndef GI_ASSETS_H
#define GI_ASSETS_H

#include <stddef.h>
#include <stdint.h>

#include "gi_buf.h"
#include "gi_error.h"
#include "gi_name_index.h"

#define GI_HASH_HEX 65 /* 64 hex digits + NUL */
#define GI_ASSET_MAX_BYTES ((size_t)2 << 30) /* 2 GiB per file */

void gi_hash_hex(const void *data, size_t len, char out[GI_HASH_HEX]);
int gi_hash_is_valid(const char *hex);

typedef struct gi_asset_source {
    /* Reads the named file into out (replacing its contents). */
    int (*read)(void *ctx, const char *name, gi_buf *out, gi_error *err);
    void *ctx;
} gi_asset_source;

static inline int gi_asset_read(const gi_asset_source *src, const char *name, gi_buf *out,
                                gi_error *err)
{
    return src->read(src->ctx, name, out, err);
}

typedef struct gi_manifest_entry {
    char *name;
    char hash[GI_HASH_HEX];
    uint64_t size;
} gi_manifest_entry;

/* Looked up by name and by hash in constant expected time (a scene of tens
 * of thousands of mesh files made every scan per file quadratic). Change it
 * only through these functions; a struct copy moves it (one owner frees). */
typedef struct gi_manifest {
    gi_manifest_entry *entries;
    size_t count, cap;
    gi_name_index by_name; /* entries[i].name -> i */
    gi_name_index by_hash; /* entries[i].hash -> the first i with it (rebuilt when
                            * the entries move or a hash is replaced) */
} gi_manifest;

void gi_manifest_init(gi_manifest *m);
void gi_manifest_free(gi_manifest *m);
/* Adds or replaces name's entry. */
void gi_manifest_put(gi_manifest *m, const char *name, const char *hash, uint64_t size);
/* Adds an entry for a name the caller knows is not in m (no look-up: many
 * entries in a row without quadratic time). */
void gi_manifest_append(gi_manifest *m, const char *name, const char *hash, uint64_t size);
const gi_manifest_entry *gi_manifest_find(const gi_manifest *m, const char *name);
/* 1 if some file of the manifest has these bytes. */
int gi_manifest_has_hash(const gi_manifest *m, const char *hash);
void gi_manifest_encode(const gi_manifest *m, gi_buf *out);
int gi_manifest_decode(gi_reader *r, gi_manifest *m, gi_error *err);

/* Content-addressed bytes in memory (hash -> bytes). */
typedef struct gi_asset_store gi_asset_store;
gi_asset_store *gi_asset_store_new(void);
void gi_asset_store_free(gi_asset_store *s);
/* Stores a copy; returns the stored bytes. Idempotent for equal hashes. */
const gi_buf *gi_asset_store_put(gi_asset_store *s, const char *hash, const void *data,
                                 size_t len);
const gi_buf *gi_asset_store_get(const gi_asset_store *s, const char *hash);
/* Drops hash's bytes (pointers from get and put into the store are stale
 * after it); 1 if it was there. */
int gi_asset_store_remove(gi_asset_store *s, const char *hash);
size_t gi_asset_store_bytes(const gi_asset_store *s);
/* Iteration (insertion order): the i-th entry's bytes, its hash into hash. */
size_t gi_asset_store_count(const gi_asset_store *s);
const gi_buf *gi_asset_store_at(const gi_asset_store *s, size_t i, char hash[GI_HASH_HEX]);

/* A directory on the local disk. Names are paths relative to root (or
 * absolute). Every file read is hashed into `manifest` and its bytes kept in
 * `store`, so the same job can be handed to processes without the disk. */
typedef struct gi_dir_source {
    char *root;
    gi_manifest manifest;
    gi_asset_store *store;
} gi_dir_source;

void gi_dir_source_init(gi_dir_source *d, const char *root);
void gi_dir_source_free(gi_dir_source *d);
gi_asset_source gi_dir_source_as_source(gi_dir_source *d);

/* Names resolved through a manifest to hashes, bytes from a store, and
 * missing bytes from `fetch` (which must put them into the store). */
typedef struct gi_manifest_source {
    const gi_manifest *manifest;
    gi_asset_store *store;
    int (*fetch)(void *ctx, const char *hash, gi_error *err);
    void *fetch_ctx;
} gi_manifest_source;

gi_asset_source gi_manifest_source_as_source(gi_manifest_source *m);

#endif
