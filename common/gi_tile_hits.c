/* gi_tile_hits: the hits file of an animation's image tile (gi_tile_hits.h). */
#include "gi_tile_hits.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>

#include "gi_checked_files.h"
#include "gi_crc32c.h"
#include "gi_fs.h"

#define HITS_MAGIC "GTHT"
#define HITS_VERSION 1u
#define HITS_ENDIAN 0x01020304u

typedef struct hits_header {
    char magic[4];
    uint32_t version, endian, record_bytes;
    uint32_t x0, y0, x1, y1, spp;
    uint32_t records_crc;
    uint64_t count;
    uint32_t reserved;
    uint32_t header_crc; /* of everything before it */
} hits_header;

_Static_assert(sizeof(hits_header) == 56, "tile hits header is 56 bytes");
_Static_assert(sizeof(gi_tile_hit) == 16, "tile hit record is 16 bytes");

static uint32_t header_crc(const hits_header *h)
{
    return gi_crc32c(0, h, offsetof(hits_header, header_crc));
}

static char *file_name(const char *dir, const gi_tile *t, int spp)
{
    char name[96];
    snprintf(name, sizeof name, "tile.%u.%u.%u.%u.%d.hits", t->x0, t->y0, t->x1, t->y1, spp);
    return gi_path_join(dir, name);
}

static uint64_t hit_count(const gi_tile *t, int spp)
{
    return (uint64_t)(t->x1 - t->x0) * (t->y1 - t->y0) * (uint64_t)spp;
}

/* NULL if the header is this tile's, else why not. */
static const char *header_invalid(const hits_header *h, const gi_tile *t, int spp)
{
    if (memcmp(h->magic, HITS_MAGIC, 4) != 0)
        return "bad magic";
    if (h->header_crc != header_crc(h) || h->reserved != 0)
        return "bad header CRC";
    if (h->version != HITS_VERSION || h->endian != HITS_ENDIAN ||
        h->record_bytes != sizeof(gi_tile_hit))
        return "another version, byte order or record size";
    if (h->x0 != t->x0 || h->y0 != t->y0 || h->x1 != t->x1 || h->y1 != t->y1 ||
        h->spp != (uint32_t)spp || h->count != hit_count(t, spp))
        return "another tile's";
    return NULL;
}

/* NULL if every record is a miss or a hit on one of the scene's triangles
 * in front of the camera, else why not. */
static const char *records_invalid(const gi_tile_hit *v, uint64_t n, uint32_t tri_count)
{
    for (uint64_t i = 0; i < n; i++) {
        if (v[i].tri == GI_TILE_HIT_NONE)
            continue;
        if (v[i].tri >= tri_count)
            return "a hit names no triangle of the scene";
        if (!isfinite(v[i].u) || !isfinite(v[i].v) || !(v[i].t >= 0.0f) || !isfinite(v[i].t))
            return "a hit has non-finite values";
    }
    return NULL;
}

/* What a check of the file vouches for: its header, and the triangle
 * count its records were checked against. */
static uint32_t checked_key(const hits_header *h, uint32_t tri_count)
{
    return gi_crc32c(h->header_crc, &tri_count, sizeof tri_count);
}

int gi_tile_hits_read(const char *dir, const gi_tile *t, int spp, uint32_t tri_count,
                      gi_tile_hit *hits, gi_error *err)
{
    char *path = file_name(dir, t, spp);
    int fd = gi_open_regular(path, O_RDONLY, NULL, err);
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (!f) {
        int e = errno, rc = 0;
        if (fd >= 0)
            close(fd);
        if (e == ENOENT || e == ENOTDIR)
            gi_fail(err, GI_EIO, "%s: missing", path);
        else if (e == EINVAL) /* as an invalid file, below */
            gi_fail(err, GI_EPROTO, "%s: not a regular file", path);
        else
            rc = gi_fail(err, GI_EIO, "%s: %s", path, strerror(e));
        free(path);
        return rc;
    }
    hits_header h;
    uint64_t n = hit_count(t, spp);
    struct stat st;
    const char *why = NULL;
    if (fstat(fileno(f), &st) != 0)
        why = "cannot stat it";
    else if ((uint64_t)st.st_size != sizeof h + n * sizeof *hits)
        why = "truncated or wrong size";
    else if (fread(&h, sizeof h, 1, f) != 1)
        why = "cannot read the header";
    else if ((why = header_invalid(&h, t, spp)) != NULL)
        ;
    else if (fread(hits, sizeof *hits, (size_t)n, f) != (size_t)n)
        why = "cannot read the records";
    else if (!gi_file_was_checked(&st, checked_key(&h, tri_count))) {
        if (gi_crc32c(0, hits, (size_t)n * sizeof *hits) != h.records_crc)
            why = "bad record CRC";
        else if ((why = records_invalid(hits, n, tri_count)) == NULL)
            gi_file_note_checked(&st, checked_key(&h, tri_count));
    }
    int io = ferror(f);
    fclose(f);
    int rc = why ? 0 : 1;
    if (io)
        rc = gi_fail(err, GI_EIO, "%s: read error", path);
    else if (why)
        gi_fail(err, GI_EPROTO, "%s: %s", path, why);
    free(path);
    return rc;
}

int gi_tile_hits_write(const char *dir, const gi_tile *t, int spp, const gi_tile_hit *hits,
                       gi_error *err)
{
    uint64_t n = hit_count(t, spp);
    hits_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, HITS_MAGIC, 4);
    h.version = HITS_VERSION;
    h.endian = HITS_ENDIAN;
    h.record_bytes = sizeof *hits;
    h.x0 = t->x0;
    h.y0 = t->y0;
    h.x1 = t->x1;
    h.y1 = t->y1;
    h.spp = (uint32_t)spp;
    h.count = n;
    h.records_crc = gi_crc32c(0, hits, (size_t)n * sizeof *hits);
    h.header_crc = header_crc(&h);
    char *path = file_name(dir, t, spp);
    char *tmp = gi_temp_path(path);
    int rc = 0;
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        rc = gi_fail(err, GI_EIO, "%s: %s", tmp, strerror(errno));
    } else {
        int bad = fwrite(&h, sizeof h, 1, f) != 1 ||
                  fwrite(hits, sizeof *hits, (size_t)n, f) != (size_t)n;
        bad |= fclose(f) != 0;
        if (bad)
            rc = gi_fail(err, GI_EIO, "%s: write failed", tmp);
        else if (rename(tmp, path) != 0)
            rc = gi_fail(err, GI_EIO, "%s: rename: %s", path, strerror(errno));
        if (rc)
            unlink(tmp);
    }
    free(tmp);
    free(path);
    return rc;
}
