/* detp_grid: the paths of a stored batch by the cells they cross (see
 * detp_grid.h). */
#include "detp_grid.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi_checked_files.h"
#include "gi_crc32c.h"
#include "gi_fs.h"

#define GRID_MAGIC "GIDG"
#define GRID_VERSION 1u

typedef struct grid_header {
    char magic[4];
    uint32_t version;
    uint64_t p0, p1;
    uint64_t entries;
    float lo[3], cell;
    uint32_t n[3], frame;
    uint32_t base_crc; /* the records CRC of the base it indexes */
    uint32_t body_crc;
    uint32_t reserved;
    uint32_t header_crc; /* of the bytes before it */
} grid_header;

_Static_assert(sizeof(grid_header) == 80, "grid header is 80 bytes");

void detp_grid_spec_make(gi_vec3 lo, gi_vec3 hi, float cell, detp_grid_spec *out)
{
    float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    float emax = fmaxf(ext[0], fmaxf(ext[1], ext[2]));
    if (!(cell > 0.0f) || emax / cell > (float)DETP_GRID_MAX_AXIS)
        cell = emax / (float)DETP_GRID_MAX_AXIS;
    if (!(cell > 0.0f))
        cell = 1.0f;
    out->lo = lo;
    out->cell = cell;
    for (int a = 0; a < 3; a++) {
        float k = ceilf(ext[a] / cell);
        out->n[a] = k < 1.0f ? 1u : (k > DETP_GRID_MAX_AXIS ? DETP_GRID_MAX_AXIS : (uint32_t)k);
    }
}

static size_t cell_count(const detp_grid_spec *s)
{
    return (size_t)s->n[0] * s->n[1] * s->n[2];
}

static float axis(gi_vec3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

/* The cell range [c0, c1] on axis a that [x0, x1] overlaps, clamped. */
static void cell_range(const detp_grid_spec *s, int a, float x0, float x1, uint32_t *c0,
                       uint32_t *c1)
{
    float f0 = floorf((x0 - axis(s->lo, a)) / s->cell), f1 = floorf((x1 - axis(s->lo, a)) / s->cell);
    float top = (float)(s->n[a] - 1);
    *c0 = f0 < 0.0f ? 0u : (f0 > top ? s->n[a] - 1 : (uint32_t)f0);
    *c1 = f1 < 0.0f ? 0u : (f1 > top ? s->n[a] - 1 : (uint32_t)f1);
}

/* Adds a path to the cells one of its segments crosses, over the part of
 * the segment that can matter (up to its second hit, its disc extent or
 * its hit, and to the grid's edge if it escapes): a 3-D DDA (Amanatides and
 * Woo) over the part inside the grid's box. Rounding can only misplace a
 * crossing at a cell boundary, by far less than the margins the queries
 * add around the mobile (detp_anim_worker.c). */
typedef struct raster {
    uint32_t *count; /* pass 1: entries per cell */
    uint64_t *fill;  /* pass 2: next free slot per cell */
    uint32_t *entries;
    uint32_t *last; /* last path + 1 added to each cell */
} raster;

static void add_cell(raster *r, size_t c, uint32_t path)
{
    if (r->last[c] == path + 1)
        return;
    r->last[c] = path + 1;
    if (r->entries)
        r->entries[r->fill[c]++] = path;
    else
        r->count[c]++;
}

static void rasterize(const detp_grid_spec *s, const gi_detp_segment *g, uint32_t path, raster *r)
{
    float t1 = detp_grid_reach(g);
    float t0 = 0.0f;
    float o[3] = {g->org.x, g->org.y, g->org.z}, d[3] = {g->dir.x, g->dir.y, g->dir.z};
    float lo[3] = {s->lo.x, s->lo.y, s->lo.z};
    /* Clip to the grid's box (slabs). */
    for (int a = 0; a < 3; a++) {
        float hi = lo[a] + s->cell * (float)s->n[a];
        if (fabsf(d[a]) < 1e-30f) {
            if (o[a] < lo[a] || o[a] > hi)
                return;
            continue;
        }
        /* |d| >= 1e-30: ta and tb are numbers or infinities, never NaN. */
        float ta = (lo[a] - o[a]) / d[a], tb = (hi - o[a]) / d[a];
        t0 = gi_maxf(t0, gi_minf(ta, tb));
        t1 = gi_minf(t1, gi_maxf(ta, tb));
    }
    if (!(t1 >= t0))
        return;
    int32_t c[3], step[3], n[3];
    float tmax[3], tdelta[3];
    for (int a = 0; a < 3; a++) {
        n[a] = (int32_t)s->n[a];
        float x = (o[a] + d[a] * t0 - lo[a]) / s->cell;
        float f = floorf(x);
        c[a] = f < 0.0f ? 0 : (f >= (float)n[a] ? n[a] - 1 : (int32_t)f);
        if (d[a] > 0.0f) {
            step[a] = 1;
            tmax[a] = (lo[a] + s->cell * (float)(c[a] + 1) - o[a]) / d[a];
            tdelta[a] = s->cell / d[a];
        } else if (d[a] < 0.0f) {
            step[a] = -1;
            tmax[a] = (lo[a] + s->cell * (float)c[a] - o[a]) / d[a];
            tdelta[a] = -s->cell / d[a];
        } else {
            step[a] = 0;
            tmax[a] = INFINITY;
            tdelta[a] = INFINITY;
        }
    }
    for (;;) {
        add_cell(r, ((size_t)c[2] * s->n[1] + (size_t)c[1]) * s->n[0] + (size_t)c[0], path);
        int a = tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2);
        if (!(tmax[a] <= t1))
            return;
        c[a] += step[a];
        if (c[a] < 0 || c[a] >= n[a])
            return;
        tmax[a] += tdelta[a];
    }
}

/* Path starts take whole 8-byte words, so the u64 cell starts after them
 * are aligned in the mapping. */
static size_t path_bytes(uint64_t paths)
{
    return (size_t)((paths + 1) * 4 + 7) & ~(size_t)7;
}

static uint32_t header_crc(const grid_header *h)
{
    return gi_crc32c(0, h, offsetof(grid_header, header_crc));
}

int detp_grid_write(const char *path, const detp_grid_spec *spec, uint64_t p0, uint64_t p1,
                    uint32_t frame, const gi_detp_segments *base, uint32_t base_crc,
                    gi_error *err)
{
    uint32_t paths = (uint32_t)(p1 - p0);
    size_t cells = cell_count(spec);
    uint32_t *path_start = gi_xcalloc(path_bytes(paths) / 4, sizeof *path_start);
    uint64_t *cell_start = gi_xcalloc(cells + 1, sizeof *cell_start);
    raster r = {gi_xcalloc(cells, sizeof(uint32_t)), NULL, NULL,
                gi_xcalloc(cells, sizeof(uint32_t))};
    /* Pass 1: each path's first record and the list lengths. */
    size_t i = 0;
    for (uint32_t p = 0; p < paths; p++) {
        path_start[p] = (uint32_t)i;
        for (; i < base->count && base->v[i].photon == p0 + p; i++)
            rasterize(spec, &base->v[i], p, &r);
    }
    path_start[paths] = (uint32_t)i;
    int rc = 0;
    if (i != base->count)
        rc = gi_fail(err, GI_EINTERNAL, "%s: the base is not path-ordered over its batch", path);
    for (size_t c = 0; c < cells; c++)
        cell_start[c + 1] = cell_start[c] + r.count[c];
    uint64_t entries = cell_start[cells];
    uint32_t *list = rc ? NULL : gi_try_malloc((size_t)entries * 4 + 4, err, "detp grid");
    if (!list)
        rc = -1;
    if (rc == 0) {
        /* Pass 2: the lists, paths ascending. */
        r.fill = gi_xmalloc((cells + 1) * sizeof *r.fill);
        memcpy(r.fill, cell_start, (cells + 1) * sizeof *r.fill);
        r.entries = list;
        memset(r.last, 0, cells * sizeof *r.last);
        for (uint32_t p = 0; p < paths; p++)
            for (size_t k = path_start[p]; k < path_start[p + 1]; k++)
                rasterize(spec, &base->v[k], p, &r);
        grid_header h;
        memset(&h, 0, sizeof h);
        memcpy(h.magic, GRID_MAGIC, 4);
        h.version = GRID_VERSION;
        h.p0 = p0;
        h.p1 = p1;
        h.entries = entries;
        h.lo[0] = spec->lo.x;
        h.lo[1] = spec->lo.y;
        h.lo[2] = spec->lo.z;
        h.cell = spec->cell;
        memcpy(h.n, spec->n, sizeof h.n);
        h.frame = frame;
        h.base_crc = base_crc;
        uint32_t crc = gi_crc32c(0, path_start, path_bytes(paths));
        crc = gi_crc32c(crc, cell_start, (cells + 1) * sizeof *cell_start);
        h.body_crc = gi_crc32c(crc, list, (size_t)entries * sizeof *list);
        h.header_crc = header_crc(&h);
        gi_buf b;
        gi_buf_init(&b);
        gi_buf_put(&b, &h, sizeof h);
        gi_buf_put(&b, path_start, path_bytes(paths));
        gi_buf_put(&b, cell_start, (cells + 1) * sizeof *cell_start);
        gi_buf_put(&b, list, (size_t)entries * sizeof *list);
        /* A cache file: renamed into place, not fsync'ed (see detp_batch.h). */
        char *tmp = gi_temp_path(path);
        FILE *fp = fopen(tmp, "wb");
        if (!fp || fwrite(b.data, 1, b.len, fp) != b.len)
            rc = gi_fail(err, gi_disk_errcode(errno), "%s: %s", tmp, strerror(errno));
        if (fp && fclose(fp) != 0 && rc == 0)
            rc = gi_fail(err, gi_disk_errcode(errno), "%s: %s", tmp, strerror(errno));
        if (rc == 0 && rename(tmp, path) != 0)
            rc = gi_fail(err, gi_disk_errcode(errno), "%s: rename: %s", path, strerror(errno));
        if (rc)
            unlink(tmp);
        else
            gi_file_note_written(path, h.header_crc);
        free(tmp);
        gi_buf_free(&b);
    }
    free(list);
    free(r.fill);
    free(r.count);
    free(r.last);
    free(path_start);
    free(cell_start);
    return rc;
}

static int same_spec(const grid_header *h, const detp_grid_spec *s)
{
    return h->lo[0] == s->lo.x && h->lo[1] == s->lo.y && h->lo[2] == s->lo.z &&
           h->cell == s->cell && memcmp(h->n, s->n, sizeof h->n) == 0;
}

int detp_grid_map(const char *path, const detp_grid_spec *spec, uint64_t p0, uint64_t p1,
                  uint32_t frame, uint64_t records, uint32_t base_crc, detp_grid *g,
                  gi_error *err)
{
    memset(g, 0, sizeof *g);
    struct stat st;
    int fd = gi_open_regular(path, O_RDONLY, &st, err);
    if (fd < 0) {
        if (errno == EINVAL) { /* not a regular file: as a wrong one */
            gi_fail(err, GI_EPROTO, "%s: not a grid file", path);
            return 0;
        }
        if (errno != ENOENT)
            return gi_fail(err, GI_EIO, "%s: %s", path, strerror(errno));
        gi_fail(err, GI_EIO, "%s: missing", path);
        return 0;
    }
    if ((size_t)st.st_size < sizeof(grid_header)) {
        close(fd);
        gi_fail(err, GI_EPROTO, "%s: not a grid file", path);
        return 0;
    }
    size_t len = (size_t)st.st_size;
    void *map = mmap(NULL, len, PROT_READ, MAP_PRIVATE, fd, 0);
    int e = errno;
    close(fd);
    if (map == MAP_FAILED)
        return gi_fail(err, GI_EIO, "%s: mmap: %s", path, strerror(e));
    grid_header h;
    memcpy(&h, map, sizeof h);
    uint64_t paths = p1 - p0;
    size_t cells = cell_count(spec);
    size_t body = path_bytes(paths) + (cells + 1) * 8;
    const char *why = NULL;
    if (memcmp(h.magic, GRID_MAGIC, 4) != 0 || h.version != GRID_VERSION ||
        h.header_crc != header_crc(&h))
        why = "bad header";
    else if (h.p0 != p0 || h.p1 != p1 || h.frame != frame || h.base_crc != base_crc ||
             h.reserved != 0 || !same_spec(&h, spec))
        why = "another batch, base or grid";
    else if (h.entries > (len - sizeof h) / 4 || sizeof h + body + h.entries * 4 != len)
        why = "wrong size";
    if (!why) {
        const char *p = (const char *)map + sizeof h;
        g->path_start = (const uint32_t *)p;
        g->cell_start = (const uint64_t *)(p + path_bytes(paths));
        g->entries = (const uint32_t *)(p + body);
        if (!gi_file_was_checked(&st, h.header_crc)) {
            uint32_t crc = gi_crc32c(0, p, body);
            if (gi_crc32c(crc, g->entries, h.entries * 4) != h.body_crc)
                why = "bad CRC";
            /* Lists and path starts in range: what the lookups index. */
            for (uint64_t i = 0; !why && i < paths; i++)
                if (g->path_start[i] > g->path_start[i + 1])
                    why = "path starts out of order";
            if (!why && (g->path_start[0] != 0 || g->path_start[paths] != records))
                why = "not the grid of this base";
            for (size_t c = 0; !why && c < cells; c++)
                if (g->cell_start[c] > g->cell_start[c + 1])
                    why = "cell lists out of order";
            if (!why && g->cell_start[cells] != h.entries)
                why = "cell lists out of range";
            for (uint64_t i = 0; !why && i < h.entries; i++)
                if (g->entries[i] >= paths)
                    why = "a path out of range";
            if (!why)
                gi_file_note_checked(&st, h.header_crc);
        } else if (g->path_start[paths] != records) {
            why = "not the grid of this base";
        }
    }
    if (why) {
        munmap(map, len);
        memset(g, 0, sizeof *g);
        gi_fail(err, GI_EPROTO, "%s: %s", path, why);
        return 0;
    }
    g->spec = *spec;
    g->paths = (uint32_t)paths;
    g->map = map;
    g->len = len;
    return 1;
}

void detp_grid_unmap(detp_grid *g)
{
    if (g->map)
        munmap(g->map, g->len);
    memset(g, 0, sizeof *g);
}

/* Squared distance from x to the interval [a, a + w]. */
static float gap2(float x, float a, float w)
{
    float d = x < a ? a - x : (x > a + w ? x - (a + w) : 0.0f);
    return d * d;
}

void detp_grid_mark(const detp_grid *g, gi_vec3 c, float r, uint8_t *mark)
{
    const detp_grid_spec *s = &g->spec;
    uint32_t c0[3], c1[3];
    for (int k = 0; k < 3; k++)
        cell_range(s, k, axis(c, k) - r, axis(c, k) + r, &c0[k], &c1[k]);
    /* Cells of the sphere's box that the sphere misses (its corners) are
     * skipped; the radius is grown a little over the rounding of the
     * cells' corners. */
    float rr = r + 1e-4f * s->cell;
    rr *= rr;
    for (uint32_t z = c0[2]; z <= c1[2]; z++) {
        float dz = gap2(c.z, s->lo.z + (float)z * s->cell, s->cell);
        for (uint32_t y = c0[1]; y <= c1[1]; y++) {
            float dyz = dz + gap2(c.y, s->lo.y + (float)y * s->cell, s->cell);
            for (uint32_t x = c0[0]; x <= c1[0]; x++) {
                if (dyz + gap2(c.x, s->lo.x + (float)x * s->cell, s->cell) > rr)
                    continue;
                size_t k = ((size_t)z * s->n[1] + y) * s->n[0] + x;
                for (uint64_t i = g->cell_start[k]; i < g->cell_start[k + 1]; i++)
                    mark[g->entries[i]] = 1;
            }
        }
    }
}
