/* gi_limits: the process-wide input size limits. */
#include "gi_limits.h"

static gi_limits current = {
    .max_scene_triangles = 1u << 28, /* ~270 M: tens of GiB of scene */
    .max_scene_vertices = 1u << 28,
};

const gi_limits *gi_limits_get(void) { return &current; }

void gi_limits_set(const gi_limits *l) { current = *l; }
