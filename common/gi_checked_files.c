/* gi_checked_files: the cache files this process has checked whole
 * (gi_checked_files.h).
 *
 * A hash table keyed by (device, inode), not a small ring: a frame opens a
 * base, a grid and up to 64 deltas per batch, and a worker holds many
 * batches; a ring smaller than that was emptied by every frame's own opens,
 * and each frame then read and checked every base whole (the very reads
 * the grids exist to avoid). A rewritten file is a new inode (temp +
 * rename) and a reused inode replaces its entry, so the table stays about
 * as large as the batch directory; it is emptied if it ever reaches
 * MAX_ENTRIES. */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "gi_checked_files.h"
#include "gi_error.h"

typedef struct checked_file {
    dev_t dev;
    ino_t ino;
    off_t size; /* 0: empty slot (checked files are never empty) */
    struct timespec mtime;
    uint32_t header_crc;
} checked_file;

#define MAX_ENTRIES (1u << 16) /* files: about 1,000 batches; 6 MiB of table */

static checked_file *table;
static size_t table_cap, table_used; /* cap: a power of two, or 0 */

static size_t slot_of(dev_t dev, ino_t ino, size_t cap)
{
    uint64_t h = ((uint64_t)ino * 0x9E3779B97F4A7C15ull) ^ ((uint64_t)dev * 0xC2B2AE3D27D4EB4Full);
    return (size_t)(h ^ (h >> 29)) & (cap - 1);
}

/* The slot holding (dev, ino), or the empty slot where it would go. */
static checked_file *find(dev_t dev, ino_t ino)
{
    for (size_t i = slot_of(dev, ino, table_cap);; i = (i + 1) & (table_cap - 1)) {
        checked_file *c = &table[i];
        if (c->size == 0 || (c->ino == ino && c->dev == dev))
            return c;
    }
}

void gi_file_forget_checked(void)
{
    free(table);
    table = NULL;
    table_cap = table_used = 0;
}

int gi_file_was_checked(const struct stat *st, uint32_t header_crc)
{
    if (!table_cap)
        return 0;
    const checked_file *c = find(st->st_dev, st->st_ino);
    return c->size > 0 && c->size == st->st_size && c->mtime.tv_sec == st->st_mtim.tv_sec &&
           c->mtime.tv_nsec == st->st_mtim.tv_nsec && c->header_crc == header_crc;
}

void gi_file_note_checked(const struct stat *st, uint32_t header_crc)
{
    if (st->st_size <= 0)
        return;
    if (table_used + 1 > MAX_ENTRIES)
        gi_file_forget_checked();
    if (2 * (table_used + 1) > table_cap) {
        /* Grow (load <= 1/2) and re-insert. */
        checked_file *old = table;
        size_t old_cap = table_cap;
        table_cap = old_cap ? 2 * old_cap : 256;
        table = gi_xcalloc(table_cap, sizeof *table);
        for (size_t i = 0; i < old_cap; i++)
            if (old[i].size > 0)
                *find(old[i].dev, old[i].ino) = old[i];
        free(old);
    }
    checked_file *c = find(st->st_dev, st->st_ino);
    table_used += c->size == 0;
    *c = (checked_file){st->st_dev, st->st_ino, st->st_size, st->st_mtim, header_crc};
}

void gi_file_note_written(const char *path, uint32_t header_crc)
{
    struct stat st;
    if (stat(path, &st) == 0)
        gi_file_note_checked(&st, header_crc);
}
