/* gi_tiles: images made of tile tasks, for methods whose image is a view of
 * something computed elsewhere (per-vertex radiance from a bake, radiosity
 * per element): the coordinator plans tiles and adds their results; a
 * worker casts the primary rays of a tile and asks the method's shader for
 * the radiance leaving each visible point.
 *
 * Each pixel averages `spp` jittered primary rays (box filter), with random
 * numbers keyed by (job seed, pixel, sample): the image does not depend on
 * the tile size or on which worker ran which tile. */
#ifndef GI_TILES_H
#define GI_TILES_H

#include <stdint.h>

#include "gi_buf.h"
#include "gi_image.h"
#include "gi_job.h"
#include "gi_rt.h"
#include "gi_task.h"

typedef struct gi_tile {
    uint32_t x0, y0, x1, y1; /* pixels [x0, x1) x [y0, y1) */
} gi_tile;

/* Adds one task of `kind` per tile (side `tile` pixels) of a width x height
 * image; each payload is the tile followed by `extra` (may be NULL). The
 * task cost is pixels * spp. */
void gi_tiles_plan(gi_task_queue *q, uint32_t kind, int width, int height, int tile, int spp,
                   const gi_buf *extra);
/* The summed cost of the tasks gi_tiles_plan adds (for progress before
 * they are planned). */
static inline double gi_tiles_cost(int width, int height, int spp)
{
    return (double)width * height * spp;
}
/* How many tasks gi_tiles_plan adds. */
static inline double gi_tiles_count(int width, int height, int tile)
{
    return (double)((width + tile - 1) / tile) * (double)((height + tile - 1) / tile);
}
/* Reads a tile from the front of a task payload (checks it against the
 * image size); the reader is left after it, at the method's extra bytes. */
int gi_tile_read(gi_reader *r, int width, int height, gi_tile *out, gi_error *err);

/* Radiance leaving the surface point hit (p, unit direction wo towards the
 * camera) for the method. */
typedef gi_vec3 (*gi_surface_shader)(void *user, const gi_hit *hit, gi_vec3 p, gi_vec3 wo);

/* Renders a tile on a worker as seen from cam (the job's, or an animation
 * frame's): result = per-pixel RGB means as f32. Misses are black. */
int gi_tile_render(gi_rt *rt, const gi_job *job, const gi_camera *cam, const gi_tile *t, int spp,
                   gi_surface_shader shade, void *user, gi_buf *result, gi_error *err);
/* A primary ray's closest hit among all but the moving object
 * (gi_tile_render_split); tri GI_TILE_HIT_NONE: none. */
typedef struct gi_tile_hit {
    uint32_t tri;
    float u, v, t;
} gi_tile_hit;
#define GI_TILE_HIT_NONE UINT32_MAX

/* gi_tile_render for a frame of an animation in which only `object` (a
 * mobile object of a two-level rt, gi_rt.h) moves: each primary ray's hit
 * among the rest, rest[(pixel in the tile, row-major) * spp + sample], is
 * taken from `rest` if rest_known, else traced and stored there; the
 * object is traced alone, behind its bounding sphere (c, r), up to that
 * hit, and wins if it is as near. The rest's hits stay valid as long as
 * only the object moves (cam and all else stand still), and the
 * hit shaded is the one the whole scene gives, bit for bit (the top scene
 * holds identity instances of the same BVHs), except where the object and
 * something else lie at exactly the same distance. The shader gets hits of
 * the rest with a zero ng. */
int gi_tile_render_split(gi_rt *rt, const gi_job *job, const gi_camera *cam, const gi_tile *t,
                         int spp, uint32_t object, gi_vec3 c, float r, gi_tile_hit *rest,
                         int rest_known,
                         gi_surface_shader shade, void *user, gi_buf *result, gi_error *err);
/* Puts a tile result into img (RGB; coordinator side). */
int gi_tile_merge(gi_image *img, const gi_tile *t, const gi_buf *result, gi_error *err);
/* A tile result is what gi_tile_merge takes: the tile's size, and pixels
 * (RGB floats, row by row) that are finite; the error names the first pixel
 * that is not. */
int gi_tile_check_result(const gi_tile *t, const uint8_t *px, size_t len, gi_error *err);

#endif
