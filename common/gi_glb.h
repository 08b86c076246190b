/* gi_glb: writing per-vertex results as a binary glTF 2.0 file (.glb), the
 * format real-time engines (Unreal, Godot, three.js; Unity with a package) and Blender
 * import directly: the baked mesh with its lighting as vertex colours. */
#ifndef GI_GLB_H
#define GI_GLB_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_math.h"

/* A mesh with per-vertex results. normals and irradiance_rgb may be NULL
 * (the attribute is left out). */
typedef struct gi_vertex_bake {
    uint32_t vertex_count;
    const gi_vec3 *positions;
    const gi_vec3 *normals;       /* unit */
    const float *radiance_rgb;    /* linear, reflected + emitted, 3 per vertex */
    const float *irradiance_rgb;  /* linear, 3 per vertex */
    uint32_t triangle_count;
    const uint32_t *indices;      /* 3 per triangle, counter-clockwise front */
    double exposure_stops;
} gi_vertex_bake;

/* One mesh, one node, one unlit material (KHR_materials_unlit, white), so a
 * viewer shows the bake as it is. Vertex attributes: POSITION, NORMAL,
 * COLOR_0 (linear radiance * 2^exposure clamped to [0, 1]: what the PNG
 * previews show, before their sRGB encoding, which the viewer applies), and
 * the unclamped float values as _RADIANCE and _IRRADIANCE (glTF's
 * application-specific attributes). Temp file + rename. */
int gi_glb_write(const char *path, const gi_vertex_bake *bake, gi_error *err);

/* 1 if a mesh of this size fits glTF's 32-bit lengths (some 50 million
 * vertices do not). A larger mesh's glb output is skipped with a warning
 * (gi_glb_write_or_skip) rather than failing a finished bake. */
int gi_glb_fits(uint32_t vertex_count, uint32_t triangle_count);
/* gi_glb_write, or a warning and 0 (nothing written) if the mesh does not
 * fit: returns 1 if written. -1 on a failed write. */
int gi_glb_write_or_skip(const char *path, const gi_vertex_bake *bake, gi_error *err);

#endif
