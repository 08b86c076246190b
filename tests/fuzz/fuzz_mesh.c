/* fuzz_mesh: libFuzzer target for mesh files (gi_mesh_import: the size
 * checks, then assimp, then the conversion). The first byte picks the
 * format the file is named as (OBJ, PLY, glTF, GLB); the rest is the file.
 * Any other file it names (an OBJ's .mtl, a glTF's buffers) is served the
 * same bytes. Any input must import or fail with a one-line message; a mesh
 * that imports must be sane. assimp and the conversion run in a forked
 * child, where libFuzzer sees no coverage and a bug in our code shows only
 * as an importer that died: our parts are fuzzed in-process by
 * fuzz_mesh_precheck, fuzz_mesh_convert and fuzz_mesh_wire. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_mesh.h"

typedef struct input {
    const uint8_t *data;
    size_t size;
} input;

static int serve(void *ctx, const char *name, gi_buf *out, gi_error *err)
{
    const input *in = ctx;
    (void)name;
    (void)err;
    gi_buf_reset(out);
    gi_buf_put(out, in->data, in->size);
    return 0;
}

static int finite3(gi_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const names[] = {"fuzz.obj", "fuzz.ply", "fuzz.gltf", "fuzz.glb"};
    if (size < 1)
        return 0;
    input in = {data + 1, size - 1};
    gi_asset_source src = {serve, &in};
    gi_mesh_data m;
    gi_error err;
    gi_error_clear(&err);
    if (gi_mesh_import(&src, names[data[0] % 4], &m, &err) != 0) {
        if (strchr(err.msg, '\n') || !err.msg[0])
            abort();
        return 0;
    }
    if (m.triangle_count == 0 || m.vertex_count == 0)
        abort();
    for (uint32_t i = 0; i < 3 * m.triangle_count; i++)
        if (m.indices[i] >= m.vertex_count)
            abort();
    for (uint32_t t = 0; t < m.triangle_count; t++)
        if (m.tri_material && m.material_count && m.tri_material[t] >= m.material_count)
            abort();
    for (uint32_t v = 0; v < m.vertex_count; v++)
        if (!finite3(m.positions[v]) || (m.normals && !finite3(m.normals[v])))
            abort();
    gi_mesh_data_free(&m);
    return 0;
}
