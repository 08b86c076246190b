/* fuzz_mesh_precheck: libFuzzer target for gi_mesh_precheck, the checks of
 * a mesh file's bytes that run in this process before assimp sees them (a
 * PLY header's element counts and property types against the bytes that
 * follow, binary or ASCII; an OBJ's vertices and the indices of its faces,
 * lines and points). The first byte picks the name the file goes by, as
 * in fuzz_mesh (OBJ, PLY, glTF, GLB: a PLY is known by its first line
 * whatever its name), so the two targets share inputs; the rest is the
 * file. Any input must pass or fail with a one-line message naming the
 * file. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const names[] = {"fuzz.obj", "fuzz.ply", "fuzz.gltf", "fuzz.glb"};
    if (size < 1)
        return 0;
    const char *name = names[data[0] % 4];
    /* A copy of exactly the file's bytes: a read past them is caught. */
    uint8_t *file = malloc(size - 1 ? size - 1 : 1);
    memcpy(file, data + 1, size - 1);
    gi_error err;
    gi_error_clear(&err);
    if (gi_mesh_precheck(name, file, size - 1, &err) != 0 &&
        (strchr(err.msg, '\n') || !strstr(err.msg, name)))
        abort();
    free(file);
    return 0;
}
