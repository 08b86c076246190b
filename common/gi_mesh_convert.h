/* gi_mesh_convert: assimp's imported scene -> gi_mesh_data, with the checks
 * that make a file's mesh safe to render (indices in range, finite points,
 * materials that exist). Split from gi_mesh_import so that it can be fuzzed
 * in-process over scenes built from fuzz bytes (fuzz_mesh_convert), without
 * running assimp. */
#ifndef GI_MESH_CONVERT_H
#define GI_MESH_CONVERT_H

#include <assimp/scene.h>
#include <stddef.h>

#include "gi_buf.h"
#include "gi_mesh.h"

/* Copies a flattened, triangulated scene (aiProcess_PreTransformVertices,
 * aiProcess_Triangulate) into out: only triangles; points and lines are
 * skipped. mtl_libs are the bytes of the material libraries an OBJ import
 * read (name ends in .obj): a material that usemtl names but none of them
 * defines gets the default colours. Fails, naming `name`, on a scene
 * without triangles, a face index past its mesh's vertices, a vertex that is
 * not finite, a material index past the scene's materials, a material name
 * longer than GI_MESH_NAME_MAX, or more than 2^31 vertices or triangles.
 * Normals that are not all finite are dropped (computed at scene build).
 * out must be freshly initialized; on failure it may hold partial arrays
 * (gi_mesh_data_free them). */
int gi_mesh_from_assimp(const struct aiScene *sc, const gi_buf *const *mtl_libs,
                        size_t mtl_count, const char *name, gi_mesh_data *out, gi_error *err);

#endif
