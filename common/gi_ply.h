/* gi_ply: writing per-vertex results as PLY (binary little-endian), the
 * format game engines and DCC tools read for baked vertex lighting. */
#ifndef GI_PLY_H
#define GI_PLY_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_math.h"

/* Writes vertices (x, y, z float; red, green, blue uchar as 8-bit sRGB of
 * radiance * 2^exposure, like the PNG previews; r, g, b float linear
 * radiance) and triangles (uchar count + int indices). Temp file + rename. */
int gi_ply_write(const char *path, uint32_t vertex_count, const gi_vec3 *positions,
                 const float *radiance_rgb, uint32_t triangle_count, const uint32_t *indices,
                 double exposure_stops, gi_error *err);

#endif
