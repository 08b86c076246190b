/* detp_store: the batch store, one file per (batch, frame) of raw segment
 * records (detp_anim.h).
 *
 * Raw native records rather than gi_detp_segments_encode's portable form:
 * the file never leaves the host that wrote it (the scheduler's affinity
 * sends a batch's next frame back there), so it is mapped and used in
 * place with no decoding. The header's endianness and record size fields
 * make a file from another build or architecture read as invalid, which
 * means "regenerate", like a torn or corrupted one. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "detp_anim.h"
#include "gi_checked_files.h"
#include "gi_crc32c.h"
#include "gi_fs.h"

_Static_assert(sizeof(gi_detp_store_header) == 64, "store header is 64 bytes");
_Static_assert(sizeof(gi_detp_segment) == 64, "segment record is 64 bytes");

static uint32_t header_crc(const gi_detp_store_header *h)
{
    return gi_crc32c(0, h, offsetof(gi_detp_store_header, header_crc));
}

uint32_t gi_detp_store_records_crc(const gi_detp_segments *s)
{
    return gi_crc32c(0, s->v, s->count * sizeof *s->v);
}

static int write_all(int fd, const void *data, size_t len)
{
    const unsigned char *p = data;
    while (len) {
        ssize_t n = write(fd, p, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        p += n;
        len -= (size_t)n;
    }
    return 0;
}

static int finite3(gi_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* The records are what a tracer wrote: path-ordered photons of the batch,
 * usable geometry (a CRC only says the bytes are the ones written). NULL if
 * so, else why not. */
static const char *records_invalid(const gi_detp_store_header *h, const gi_detp_segment *v,
                                   size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const gi_detp_segment *g = &v[i];
        if (g->photon < h->p0 || g->photon >= h->p1)
            return "a record's photon is outside the batch";
        int first = i == 0 || v[i - 1].photon != g->photon;
        if (first ? (i > 0 && v[i - 1].photon > g->photon) || g->bounce != 0
                  : g->bounce != v[i - 1].bounce + 1)
            return "records not path-ordered";
        if (!finite3(g->org) || !finite3(g->dir) || !finite3(g->energy) ||
            isnan(g->t_hit) || isnan(g->t_second) || isnan(g->t_end))
            return "a record has non-finite values";
    }
    return NULL;
}

int gi_detp_store_write(const char *path, const gi_detp_store_header *h,
                        const gi_detp_segments *s, gi_error *err)
{
    gi_detp_store_header hd;
    memset(&hd, 0, sizeof hd);
    memcpy(hd.magic, GI_DETP_STORE_MAGIC, 4);
    hd.version = GI_DETP_STORE_VERSION;
    hd.endian = GI_DETP_STORE_ENDIAN;
    hd.record_bytes = sizeof(gi_detp_segment);
    hd.p0 = h->p0;
    hd.p1 = h->p1;
    hd.frame = h->frame;
    hd.kind = h->kind;
    hd.prev_base = h->prev_base;
    hd.count = s->count;
    hd.records_crc = gi_detp_store_records_crc(s);
    hd.header_crc = header_crc(&hd);
    char *tmp = gi_temp_path(path);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        gi_fail(err, gi_disk_errcode(errno), "%s: %s", tmp, strerror(errno));
        free(tmp);
        return -1;
    }
    int rc = 0;
    if (write_all(fd, &hd, sizeof hd) || write_all(fd, s->v, s->count * sizeof *s->v))
        rc = gi_fail(err, gi_disk_errcode(errno), "%s: write: %s", tmp, strerror(errno));
    if (close(fd) != 0 && rc == 0)
        rc = gi_fail(err, gi_disk_errcode(errno), "%s: close: %s", tmp, strerror(errno));
    if (rc == 0 && rename(tmp, path) != 0)
        rc = gi_fail(err, gi_disk_errcode(errno), "%s: rename: %s", path, strerror(errno));
    if (rc != 0)
        unlink(tmp);
    else if (!records_invalid(&hd, s->v, s->count))
        gi_file_note_written(path, hd.header_crc); /* what a map would check */
    free(tmp);
    return rc;
}

int gi_detp_store_map(const char *path, gi_detp_store_mapping *m, gi_error *err)
{
    memset(m, 0, sizeof *m);
    struct stat st;
    int fd = gi_open_regular(path, O_RDONLY, &st, err);
    if (fd < 0) {
        if (errno == ENOENT || errno == ENOTDIR) {
            gi_fail(err, GI_EIO, "%s: missing", path);
            return 0;
        }
        if (errno == EINVAL) { /* not a regular file: as a wrong one */
            gi_fail(err, GI_EPROTO, "%s: not a store file (not a regular file)", path);
            return 0;
        }
        return gi_fail(err, GI_EIO, "%s: %s", path, strerror(errno));
    }
    gi_detp_store_header h;
    size_t len = (size_t)st.st_size;
    if (len < sizeof h) {
        close(fd);
        gi_fail(err, GI_EPROTO, "%s: not a store file (%zu bytes)", path, len);
        return 0;
    }
    /* Not populated: a frame reads only the paths near the mobile
     * (detp_grid.h), and pages it does not touch stay on disk. */
    void *base = mmap(NULL, len, PROT_READ, MAP_PRIVATE, fd, 0);
    int e = errno;
    close(fd);
    if (base == MAP_FAILED)
        return gi_fail(err, GI_EIO, "%s: mmap: %s", path, strerror(e));
    memcpy(&h, base, sizeof h);
    const char *why = NULL;
    if (memcmp(h.magic, GI_DETP_STORE_MAGIC, 4) != 0)
        why = "bad magic";
    else if (h.header_crc != header_crc(&h) || h.reserved != 0 ||
             h.kind > GI_DETP_STORE_DELTA)
        why = "bad header CRC";
    else if (h.version != GI_DETP_STORE_VERSION || h.endian != GI_DETP_STORE_ENDIAN ||
             h.record_bytes != sizeof(gi_detp_segment))
        why = "another version, byte order or record size";
    else if (h.p0 > h.p1 || h.count > (len - sizeof h) / sizeof(gi_detp_segment) ||
             sizeof h + h.count * sizeof(gi_detp_segment) != len)
        why = "truncated or wrong size";
    if (!why) {
        const gi_detp_segment *seg = (const gi_detp_segment *)((const char *)base + sizeof h);
        if (!gi_file_was_checked(&st, h.header_crc)) {
            if (gi_crc32c(0, seg, h.count * sizeof *seg) != h.records_crc)
                why = "bad record CRC";
            else
                why = records_invalid(&h, seg, h.count);
            if (!why)
                gi_file_note_checked(&st, h.header_crc);
        }
        if (!why) {
            m->header = h;
            m->seg = seg;
            m->count = h.count;
            m->base = base;
            m->len = len;
            m->dev = (uint64_t)st.st_dev;
            m->ino = (uint64_t)st.st_ino;
            return 1;
        }
    }
    munmap(base, len);
    gi_fail(err, GI_EPROTO, "%s: %s", path, why);
    return 0;
}

void gi_detp_store_unmap(gi_detp_store_mapping *m)
{
    if (m->base)
        munmap(m->base, m->len);
    memset(m, 0, sizeof *m);
}
