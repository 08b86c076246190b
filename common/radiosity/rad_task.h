/* rad_task: the radiosity method's task payloads, what its workers read
 * from a TASK message and its coordinator again as results arrive
 * (rad_method.c owns them; exposed for fuzz_task). */
#ifndef GI_RAD_TASK_H
#define GI_RAD_TASK_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_job.h"
#include "gi_task.h"
#include "gi_tiles.h"

/* u32 first element, u32 end element: a block of form-factor rows. */
#define RAD_TASK_FF 1
/* gi_tile, u32 emission set, str hash of the published corner radiosities;
 * with a camera path, u32 frame (its camera). */
#define RAD_TASK_TILE 2

typedef struct gi_rad_tile_task {
    gi_tile tile;
    uint32_t emission;
    char hash[GI_HASH_HEX];
    uint32_t frame; /* 0 without a camera path */
} gi_rad_tile_task;

/* The block [e0, e1) of an FF task, within the n elements. */
int gi_rad_task_block_decode(const gi_task *t, uint32_t n, uint32_t *e0, uint32_t *e1,
                             gi_error *err);
/* A TILE task: its tile within the job's image, emission below emissions
 * (a worker, which does not know them: UINT32_MAX), a valid hash and, with
 * a camera path, a frame of it. Bad bytes: GI_EPROTO naming the task. */
int gi_rad_task_tile_decode(const gi_job *job, const gi_task *t, uint32_t emissions,
                            gi_rad_tile_task *tt, gi_error *err);

/* The image data a TILE task's hash names: per element, its 3 corners' RGB
 * radiosities (9 floats), read and checked (gi_published.h): malloc'ed, or
 * NULL with GI_EPROTO naming the blob and what is wrong. */
float *gi_rad_corners_decode(const gi_buf *blob, const char *hash, uint32_t elements,
                             gi_error *err);

#endif
