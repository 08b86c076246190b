/* rad_scenes: procedural test scenes and emission vectors for the
 * low-rank radiosity benchmarks (thesis 4.3-4.4; nothing is downloaded).
 *
 * The room: a closed cube room of side 1 (metres), every wall a g x g grid
 * of quads (red wall at x = 0, green at x = 1, white others), a block of
 * g/2 x g/2 cells in the middle of the ceiling a separate "light" object,
 * and up to two cubes of side `cube` on the floor ("cube_a" axis-aligned,
 * "cube_b" turned 30 degrees about y, both marked mobile; cube_a can be
 * moved by an offset). With g = 4, two
 * cubes and cube = 0.25, every one of its 6 * 32 + 2 * 12 = 216 triangles
 * has area 1/32: 216 level-0 patches of equal size, 4^L elements each,
 * which gives the n and k of the thesis's Table 4.7 (n = 216 * 4^L,
 * k = 216 * 4^l). Camera inside, at the front wall.
 *
 * The moving projector (thesis 4.3.4): 70 emission vectors as if a
 * flashlight walked around the room. Frame f puts a pinhole projector on a
 * horizontal circle around the scene's centre at 3/4 of its height, aimed
 * across the room and down; each pixel's ray lights the element it lands on, and an element's
 * emission is its pixel count over its area (the thesis: proportional to
 * the count; the same when areas are equal), scaled so its mean over the
 * scene's area is 1. Monochrome (the same in R, G, B). */
#ifndef GI_RAD_SCENES_H
#define GI_RAD_SCENES_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_rt.h"
#include "rad_mesh.h"

typedef struct gi_rad_room_opts {
    int grid;        /* quads per wall side */
    int cubes;       /* 0, 1 or 2 */
    double cube;     /* cube side */
    double move[3];  /* added to cube_a's position (moving-object tests) */
    double emission; /* light radiance (grey) */
} gi_rad_room_opts;

/* The room as scene JSON (malloc'ed). */
char *gi_rad_room_scene(const gi_rad_room_opts *o);

/* The room loaded as a scene (from memory; named "room.json"). */
int gi_rad_room_load(const gi_rad_room_opts *o, gi_scene *out, gi_error *err);

/* frames x res^2 pixel rays; E is n x frames (element-major). */
int gi_rad_projector_emissions(gi_rt *rt, const gi_scene *s, const gi_rad_mesh *m, uint32_t frames,
                               uint32_t res, double fov_deg, double *E, gi_error *err);

#endif
