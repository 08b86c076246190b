/* fuzz_scene: libFuzzer target for the scene reader (JSON, materials,
 * objects, shapes, transforms, assembly checks). Mesh files named by the
 * input are not available: only the JSON path is exercised. Any input must
 * load or fail with a one-line message; a scene that loads must be sane
 * (its names found where they are, too). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_limits.h"
#include "gi_scene.h"
#include "gi_scene_build.h"

static int no_files(void *ctx, const char *name, gi_buf *out, gi_error *err)
{
    return gi_fail(err, GI_EINVAL, "%s: not available while fuzzing", name);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    /* Big spheres are legal but slow: keep each input cheap. */
    gi_limits l = {200000, 200000};
    gi_limits_set(&l);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    gi_asset_source src = {no_files, NULL};
    gi_scene s;
    gi_error err;
    gi_error_clear(&err);
    if (gi_scene_load_json(&src, "fuzz.json", (const char *)data, size, &s, &err) != 0) {
        if (strchr(err.msg, '\n') || !err.msg[0])
            abort();
        return 0;
    }
    /* Invariants of a loaded scene. */
    if (s.light_count == 0 || s.triangle_count == 0 || !(s.total_power > 0))
        abort();
    for (uint32_t i = 0; i < 3 * s.triangle_count; i++)
        if (s.indices[i] >= s.vertex_count)
            abort();
    for (uint32_t v = 0; v < s.vertex_count; v++)
        if (!isfinite(s.positions[v].x) || !isfinite(s.positions[v].y) || !isfinite(s.positions[v].z))
            abort();
    /* Names are found where they are (the name indices), objects own
     * their triangles, and the padding vertex Embree reads is there. */
    for (uint32_t i = 0; i < s.object_count; i++) {
        const gi_object *o = &s.objects[i];
        if (gi_scene_find_object(&s, o->name) != (int)i ||
            (uint64_t)o->first_triangle + o->triangle_count > s.triangle_count ||
            s.tri_object[o->first_triangle] != i)
            abort();
    }
    for (uint32_t i = 0; i < s.material_count; i++)
        if (gi_scene_material_index(&s, s.materials[i].name) != (int)i)
            abort();
    if (s.positions[s.vertex_count].x != 0 || s.positions[s.vertex_count].y != 0 ||
        s.positions[s.vertex_count].z != 0)
        abort();
    gi_scene_free(&s);
    return 0;
}
