/* fuzz_mesh_wire: libFuzzer target for gi_mesh_decode, the parent's reading
 * of the mesh its importer child sends (the child runs assimp over the
 * file: its answer is input). Any input must decode or fail with a
 * one-line message naming the file; a mesh that decodes must be in range
 * and finite, and encode back to the same bytes (nothing dropped or
 * defaulted). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_mesh_wire.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    gi_mesh_data m;
    gi_mesh_data_init(&m);
    gi_error err;
    gi_error_clear(&err);
    if (gi_mesh_decode(data, size, "fuzz.obj", &m, &err) != 0) {
        if (strchr(err.msg, '\n') || !strstr(err.msg, "fuzz.obj"))
            abort();
        gi_mesh_data_free(&m);
        return 0;
    }
    for (uint64_t i = 0; i < 3 * (uint64_t)m.triangle_count; i++)
        if (m.indices[i] >= m.vertex_count)
            abort();
    for (uint32_t t = 0; t < m.triangle_count; t++)
        if (m.tri_material[t] >= m.material_count)
            abort();
    for (uint32_t v = 0; v < m.vertex_count; v++)
        if (!isfinite(m.positions[v].x) || !isfinite(m.positions[v].y) ||
            !isfinite(m.positions[v].z))
            abort();
    gi_buf b;
    gi_buf_init(&b);
    gi_mesh_encode(&b, &m);
    if (b.len != size || memcmp(b.data, data, size) != 0)
        abort();
    gi_buf_free(&b);
    gi_mesh_data_free(&m);
    return 0;
}
