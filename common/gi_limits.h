/* gi_limits: process-wide size limits on input (what a job, a scene or a
 * peer can make this process allocate). Defaults suit a render host; a
 * coordinator or a fuzzer lowers them. Set once at start-up, read anywhere. */
#ifndef GI_LIMITS_H
#define GI_LIMITS_H

#include <stdint.h>

typedef struct gi_limits {
    uint32_t max_scene_triangles; /* whole scene */
    uint32_t max_scene_vertices;
} gi_limits;

const gi_limits *gi_limits_get(void);
void gi_limits_set(const gi_limits *l);

#endif
