/* gi_mesh: triangle meshes as read from files or generated from built-in
 * shapes, before they are placed in a scene (object coordinates). */
#ifndef GI_MESH_H
#define GI_MESH_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_error.h"
#include "gi_math.h"

/* The longest material name a mesh file may give, in bytes. assimp keeps at
 * most 1023 (its aiString): a longer OBJ material name is dropped with the
 * material's colours, a glTF one is cut, both silently. The limit is below
 * that, so that a name assimp cut is always over it and refused (a scene
 * and a relight's emissions file name the materials by it). */
#define GI_MESH_NAME_MAX 1000

/* A material as a mesh file describes it (OBJ .mtl Kd/Ke, glTF baseColor and
 * emissive, PLY has none). */
typedef struct gi_mesh_material {
    char *name; /* at most GI_MESH_NAME_MAX bytes, + "#<index>" when made unique */
    gi_vec3 diffuse;
    gi_vec3 emission;
} gi_mesh_material;

typedef struct gi_mesh_data {
    uint32_t vertex_count;
    gi_vec3 *positions;
    gi_vec3 *normals; /* NULL when the file has none: computed at scene build */
    uint32_t triangle_count;
    uint32_t *indices;      /* 3 per triangle, into positions */
    uint32_t *tri_material; /* per triangle, into materials (0 if none) */
    uint32_t material_count;
    gi_mesh_material *materials;
} gi_mesh_data;

void gi_mesh_data_init(gi_mesh_data *m);
void gi_mesh_data_free(gi_mesh_data *m);
/* dst (not initialized) becomes a copy of src, as it is. */
void gi_mesh_data_copy(gi_mesh_data *dst, const gi_mesh_data *src);
/* Appends src (indices shifted) to dst; src materials are appended too. */
void gi_mesh_data_append(gi_mesh_data *dst, const gi_mesh_data *src);

/* Loads OBJ (+ the .mtl files it names), PLY or glTF 2.0 (.gltf + .bin, or
 * .glb) through assimp. Every file is read through `src`, so the same call
 * works from disk, from a pool parent or from a farm coordinator. Errors name
 * the file: unreadable, unknown format, no triangles, bad indices, and an
 * importer that crashed or ran out of time (assimp runs in a forked child). */
int gi_mesh_import(const gi_asset_source *src, const char *name, gi_mesh_data *out,
                   gi_error *err);

/* A session of imports from one source (a scene's load): gi_mesh_import,
 * file after file, with one importer process for all of them while each
 * succeeds (a failure, a crash or a file over its deadline ends it; the next
 * file gets a new one). Not for use across fork(). */
typedef struct gi_mesh_importer gi_mesh_importer;
gi_mesh_importer *gi_mesh_importer_new(const gi_asset_source *src);
int gi_mesh_importer_run(gi_mesh_importer *imp, const char *name, gi_mesh_data *out,
                         gi_error *err);
void gi_mesh_importer_free(gi_mesh_importer *imp);
/* How many importer processes the session has started so far. */
unsigned gi_mesh_importer_processes(const gi_mesh_importer *imp);

/* Refuses files whose headers declare more data than they hold (assimp
 * would allocate what the header says): used by gi_mesh_import. */
int gi_mesh_precheck(const char *name, const uint8_t *data, size_t len, gi_error *err);

/* Built-in shapes, centred at the origin (see docs/scene-format.md). */
void gi_mesh_quad(gi_mesh_data *out, double size_x, double size_z); /* y = 0, normal +y */
void gi_mesh_box(gi_mesh_data *out, double sx, double sy, double sz, int inward);
void gi_mesh_sphere(gi_mesh_data *out, double radius, int subdivisions); /* icosphere */

/* Vertex normals for meshes without: a vertex is split (a copy at the same
 * position, triangles re-indexed) at hard edges, where faces meet at more
 * than GI_MESH_CREASE_DEG; each copy gets the area-weighted normal of its
 * smooth group. A mesh without hard edges keeps its vertices. */
#define GI_MESH_CREASE_DEG 60
void gi_mesh_compute_normals(gi_mesh_data *m);

#endif
