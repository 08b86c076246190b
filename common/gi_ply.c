/* gi_ply: binary PLY output with vertex colours and linear radiance. */
#include "gi_ply.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gi_buf.h"
#include "gi_fs.h"
#include "gi_image.h"

int gi_ply_write(const char *path, uint32_t vertex_count, const gi_vec3 *positions,
                 const float *radiance_rgb, uint32_t triangle_count, const uint32_t *indices,
                 double exposure_stops, gi_error *err)
{
    if (!isfinite(exposure_stops))
        return gi_fail(err, GI_EINVAL, "%s: exposure is not finite", path);
    for (uint32_t i = 0; i < 3 * triangle_count; i++)
        if (indices[i] >= vertex_count)
            return gi_fail(err, GI_EINTERNAL, "%s: triangle index %u out of range", path,
                           indices[i]);
    gi_buf b;
    gi_buf_init(&b);
    char header[512];
    int n = snprintf(header, sizeof header,
                     "ply\nformat binary_little_endian 1.0\ncomment gi-farm per-vertex radiance\n"
                     "element vertex %u\nproperty float x\nproperty float y\nproperty float z\n"
                     "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                     "property float r\nproperty float g\nproperty float b\n"
                     "element face %u\nproperty list uchar int vertex_indices\nend_header\n",
                     vertex_count, triangle_count);
    gi_buf_put(&b, header, (size_t)n);
    double scale = pow(2.0, exposure_stops);
    for (uint32_t v = 0; v < vertex_count; v++) {
        gi_buf_put_f32(&b, positions[v].x);
        gi_buf_put_f32(&b, positions[v].y);
        gi_buf_put_f32(&b, positions[v].z);
        for (int c = 0; c < 3; c++)
            gi_buf_put_u8(&b, gi_srgb8_from_linear(radiance_rgb[3 * v + c] * scale));
        gi_buf_put_f32s(&b, &radiance_rgb[3 * v], 3);
    }
    for (uint32_t t = 0; t < triangle_count; t++) {
        gi_buf_put_u8(&b, 3);
        for (int k = 0; k < 3; k++)
            gi_buf_put_u32(&b, indices[3 * t + k]);
    }
    int rc = gi_write_file_atomic(path, b.data, b.len, err);
    gi_buf_free(&b);
    return rc;
}
