/* gi_scene_build: assembling a gi_scene from meshes (internal to the scene
 * loaders: gi_scene_json.c and the bare-mesh loader). */
#ifndef GI_SCENE_BUILD_H
#define GI_SCENE_BUILD_H

#include "gi_mesh.h"
#include "gi_scene.h"

typedef struct gi_scene_builder {
    gi_scene *scene;
    const char *file; /* for messages */
    /* Room in the scene's arrays: they grow geometrically while objects are
     * added (one exact realloc per object made loading quadratic in the
     * object count), and are cut to size by gi_scene_builder_finish. */
    size_t vertex_cap, triangle_cap, object_cap, material_cap;
} gi_scene_builder;

void gi_scene_builder_init(gi_scene_builder *b, gi_scene *scene, const char *file);
/* Adds a material; fails if the name exists already. Returns its index. */
int gi_scene_add_material(gi_scene_builder *b, const gi_material *m, gi_error *err);
/* The scene material for a mesh file's material: reflectance clamped to
 * [0, 1] and emission to >= 0 (with a warning), named `name`. */
gi_material gi_material_from_mesh(const gi_mesh_material *mm, const char *name,
                                  const char *file);
/* Adds an object from a mesh in object coordinates: transforms it, checks it
 * (finite, indices in range, some triangle with area, manifold unless
 * allowed), computes missing normals. tri_material values of the mesh are
 * mapped through material_map (mesh material i -> scene material). */
int gi_scene_add_object(gi_scene_builder *b, const char *name, int mobile,
                        int allow_non_manifold, const gi_mat4 *transform,
                        gi_mesh_data *mesh, const uint32_t *material_map, gi_error *err);
/* Final checks (some object, lights) and derived data; trims the arrays. */
int gi_scene_builder_finish(gi_scene_builder *b, gi_error *err);

/* Loads a scene JSON document (gi_scene_json.c). */
int gi_scene_load_json(const gi_asset_source *src, const char *name, const char *text,
                       size_t len, gi_scene *out, gi_error *err);

#endif
