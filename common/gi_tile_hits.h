/* gi_tile_hits: a tile's primary hits of everything but an animation's
 * moving object (gi_tile_render_split), kept in the host's batch directory
 * (gi_batch_dir.h) from the first frame that renders the tile to the last:
 * later frames trace only the object.
 *
 *   <dir>/tile.<x0>.<y0>.<x1>.<y1>.<spp>.hits
 *
 * A header (magic, version, byte order, the tile, spp, count, CRC-32C of
 * the records and of the header) and count = pixels * spp gi_tile_hit
 * records in the host's byte order. The file is a cache: written to a
 * temporary name and renamed, not fsync'ed; one that is missing, torn or
 * not this tile's is traced again (any host or frame gives the same hits).
 * The batch directory belongs to one job, so the camera and the scene are
 * the job's. A file this process has checked once (against the
 * scene's triangle count) is not checked again (gi_checked_files.h): every
 * frame reads every tile's file. */
#ifndef GI_TILE_HITS_H
#define GI_TILE_HITS_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_tiles.h"

/* Reads the tile's hits into hits (pixels * spp entries): 1 if the file is
 * there and whole, with every triangle below tri_count; 0 if it is missing
 * or not valid (err says why: trace the hits again); -1 on an I/O error. */
int gi_tile_hits_read(const char *dir, const gi_tile *t, int spp, uint32_t tri_count,
                      gi_tile_hit *hits, gi_error *err);
/* Writes the tile's hits (pixels * spp entries). */
int gi_tile_hits_write(const char *dir, const gi_tile *t, int spp, const gi_tile_hit *hits,
                       gi_error *err);

#endif
