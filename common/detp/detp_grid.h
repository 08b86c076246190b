/* detp_grid: which paths of a stored batch come near a region of space.
 *
 * An update only changes the paths that meet the mobile at its old or new
 * pose, and the mobile's own vertices only see the segments near it; both
 * are within the mobile's bounding spheres. Testing every segment of the
 * batch each frame (thesis Fig. 4.2) reads the whole batch, which costs
 * more than the update itself once the mobile is small. So next to each
 * base file (detp_batch.h) a grid is stored over the box the mobile can
 * ever reach: per cell, the paths with a segment through it (each segment
 * over all it can matter for: up to its second hit, or to the box's edge if
 * it escapes). A frame then looks only at the paths listed in the cells the
 * two spheres overlap, plus the paths the deltas changed. The lists are a
 * superset (cells are coarse and each segment is rasterized conservatively);
 * the exact tests decide.
 *
 * File: an 80-byte header (magic "GIDG", version, photon range, frame, the
 * grid's origin, cell size and dimensions, the base's records CRC, CRC32C
 * of the body and of the header), then per path the index of its first record in the base
 * (paths + 1 u32, padded to 8 bytes), per cell the start of its list (cells + 1 u64), and the
 * lists (u32 path indices, ascending within a cell). Native byte order:
 * like the store, it never leaves its host. */
#ifndef GI_DETP_GRID_H
#define GI_DETP_GRID_H

#include <stdint.h>

#include "detp_anim.h"

#define DETP_GRID_MAX_AXIS 48

typedef struct detp_grid_spec {
    gi_vec3 lo;     /* the box's low corner */
    float cell;     /* cell side */
    uint32_t n[3];  /* cells per axis, each in [1, DETP_GRID_MAX_AXIS] */
} detp_grid_spec;

/* A grid over [lo, hi] with cells of about `cell` (larger if the box would
 * need more than DETP_GRID_MAX_AXIS per axis). */
void detp_grid_spec_make(gi_vec3 lo, gi_vec3 hi, float cell, detp_grid_spec *out);

/* How far along a segment the grid lists it: every part the animation's
 * tests look at (its hit, the surface behind it, its extent), and without
 * end if it escapes or its extent does (rule 1 with nothing behind the
 * hit: the discs and the mobile may lie anywhere beyond). */
static inline float detp_grid_reach(const gi_detp_segment *g)
{
    if (!isfinite(g->t_hit) || !isfinite(g->t_end))
        return INFINITY;
    float t1 = gi_maxf(g->t_hit, g->t_end);
    if (isfinite(g->t_second))
        t1 = gi_maxf(t1, g->t_second);
    return t1 > 0.0f ? t1 : INFINITY;
}

typedef struct detp_grid {
    detp_grid_spec spec;
    uint32_t paths;             /* the batch's photons, p1 - p0 */
    const uint32_t *path_start; /* paths + 1: each path's first record in the base */
    const uint64_t *cell_start; /* cells + 1 */
    const uint32_t *entries;
    void *map;
    size_t len;
} detp_grid;

/* Builds the grid of a base (path-ordered segments of photons [p0, p1),
 * every photon with at least one segment; base_crc: its store file's
 * records CRC) and writes it (temp + rename). */
int detp_grid_write(const char *path, const detp_grid_spec *spec, uint64_t p0, uint64_t p1,
                    uint32_t frame, const gi_detp_segments *base, uint32_t base_crc,
                    gi_error *err);
/* Maps a grid file: 1 if valid and made with this spec for this batch,
 * frame and base (`records` segments, records CRC base_crc), 0 if missing
 * or invalid (err says why), -1 on an I/O error. */
int detp_grid_map(const char *path, const detp_grid_spec *spec, uint64_t p0, uint64_t p1,
                  uint32_t frame, uint64_t records, uint32_t base_crc, detp_grid *g,
                  gi_error *err);
void detp_grid_unmap(detp_grid *g);

/* Sets mark[i] = 1 for every path i listed in a cell the sphere (c, r)
 * overlaps (mark has g->paths entries). */
void detp_grid_mark(const detp_grid *g, gi_vec3 c, float r, uint8_t *mark);

#endif
