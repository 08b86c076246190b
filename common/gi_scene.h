/* gi_scene: the scene every method renders.
 *
 * All geometry is triangles in world space. Each object owns a contiguous
 * range of vertices and a contiguous range of triangles, so that an object
 * can become one Embree geometry and can later be moved on its own. Indices
 * are global (into the scene's vertex arrays).
 *
 * Conventions (docs/scene-format.md): right-handed, y up; units are those of
 * the scene file (the Cornell box is in millimetres). A triangle's front face
 * is the side its counter-clockwise winding faces; emitters emit from the
 * front face only unless the material says "two_sided". Reflection is
 * diffuse from both faces. */
#ifndef GI_SCENE_H
#define GI_SCENE_H

#include <stdint.h>

#include "gi_assets.h"
#include "gi_error.h"
#include "gi_math.h"
#include "gi_name_index.h"

/* Longest object or material name in a scene (bytes). A mesh's own
 * materials become "<object>/<material>" (each at most GI_MESH_NAME_MAX), and
 * output files that carry the names (a radiosity factorization) read them
 * back within a limit of their own, which this keeps them under. */
#define GI_SCENE_NAME_MAX 1000

typedef struct gi_material {
    char *name;
    gi_vec3 diffuse;  /* reflectance rho, each channel in [0, 1) */
    gi_vec3 emission; /* emitted radiance */
    int two_sided;    /* emits from both faces */
} gi_material;

/* An emissive triangle as light sampling sees it (one cache line, no
 * indirections): vertex a, edges to b and c, unit front normal, and the
 * density per unit area with which a light sample lands on it. */
typedef struct gi_light_tri {
    gi_vec3 a, e1, e2, n;
    float pdf_area;
    uint32_t tri;
} gi_light_tri;

typedef struct gi_camera {
    gi_vec3 position, look_at, up;
    float fov_y_deg; /* vertical field of view */
} gi_camera;

typedef struct gi_object {
    char *name;
    int mobile; /* may move between frames (animation) */
    uint32_t first_vertex, vertex_count;
    uint32_t first_triangle, triangle_count;
    gi_mat4 transform; /* object to world, as given */
} gi_object;

typedef struct gi_scene {
    char *name; /* the file it came from */
    gi_camera camera;
    int has_camera;

    uint32_t material_count;
    gi_material *materials;
    uint32_t object_count;
    gi_object *objects;

    /* Names to indices, filled as the scene is built, so that lookups by
     * name cost the same in a scene of 300,000 objects as in one of 10. A
     * scene whose arrays were assembled otherwise (the counts differ) is
     * scanned instead. */
    gi_name_index material_names, object_names;

    uint32_t vertex_count;
    gi_vec3 *positions; /* world space; one spare element for Embree's padded reads */
    gi_vec3 *normals;   /* unit shading normals, per vertex */
    uint32_t triangle_count;
    uint32_t *indices;      /* 3 per triangle */
    uint32_t *tri_material; /* per triangle */
    uint32_t *tri_object;   /* per triangle */

    /* Derived per triangle (gi_scene_update_derived): the unit front-face
     * normal, and whether shading normals vary over it (else the geometric
     * normal is the shading normal, and the tracer skips interpolation). */
    gi_vec3 *tri_normal;
    uint8_t *tri_smooth;

    gi_vec3 bbox_min, bbox_max;

    /* Emissive triangles, sampled in proportion to emitted power. */
    uint32_t light_count;
    struct gi_light_tri *light_geom; /* per light: what sampling it needs */
    uint32_t *light_tris;
    double *light_cdf;   /* light_count + 1 entries, cdf[0] = 0, cdf[n] = 1 */
    double *light_power; /* per light: pi * area * luminance(emission) * sides */
    double total_power;  /* sum of light_power (luminance watts, scene units) */
} gi_scene;

/* Loads a scene from `name` through src: a scene JSON file, or a bare OBJ
 * (with its MTL) / PLY / glTF taken as a whole scene. */
int gi_scene_load(const gi_asset_source *src, const char *name, gi_scene *out,
                  gi_error *err);
void gi_scene_free(gi_scene *s);

/* Geometry helpers. */
static inline void gi_scene_triangle(const gi_scene *s, uint32_t t, gi_vec3 *a, gi_vec3 *b,
                                     gi_vec3 *c)
{
    const uint32_t *ix = &s->indices[3 * t];
    *a = s->positions[ix[0]];
    *b = s->positions[ix[1]];
    *c = s->positions[ix[2]];
}
double gi_scene_triangle_area(const gi_scene *s, uint32_t t);
/* Unit front-face normal (valid after gi_scene_update_derived). */
static inline gi_vec3 gi_scene_triangle_normal(const gi_scene *s, uint32_t t)
{
    return s->tri_normal[t];
}
static inline const gi_material *gi_scene_tri_material(const gi_scene *s, uint32_t t)
{
    return &s->materials[s->tri_material[t]];
}

/* Shading normal at barycentrics (u, v) of triangle tri, on the side of
 * ng_facing (the geometric normal turned towards the side being shaded).
 * Flat triangles use ng_facing itself. */
static inline gi_vec3 gi_scene_shading_normal(const gi_scene *s, uint32_t tri, float u, float v,
                                              gi_vec3 ng_facing)
{
    if (!s->tri_smooth[tri])
        return ng_facing;
    const uint32_t *ix = &s->indices[3 * tri];
    gi_vec3 n = gi_add(gi_add(gi_scale(s->normals[ix[0]], 1.0f - u - v),
                              gi_scale(s->normals[ix[1]], u)),
                       gi_scale(s->normals[ix[2]], v));
    n = gi_normalize(n);
    /* Interpolated normals may point to the other side near silhouettes;
     * the geometric side decides which side we are on. */
    if (!(gi_dot(n, ng_facing) > 0.0f))
        n = gi_dot(n, ng_facing) < 0.0f ? gi_neg(n) : ng_facing;
    return n;
}

/* Recomputes bbox and the light distribution (after loading or moving). */
int gi_scene_update_derived(gi_scene *s, gi_error *err);
/* The parts of it that a moved non-emissive object needs: the scene bbox,
 * and the front normals and smooth flags of triangles [first, first+count). */
void gi_scene_update_bbox(gi_scene *s);
void gi_scene_update_triangles(gi_scene *s, uint32_t first, uint32_t count);

/* Poses (gi_scene_pose.c): sets object's vertices to m applied to its base
 * (as loaded / refined) positions, and its normals to the inverse transpose
 * of m applied to the base normals, renormalized; then recomputes its
 * triangles' normals and smooth flags and the scene bbox. The light
 * distribution is not touched, so the object must not be emissive. The
 * base arrays hold objects[object].vertex_count entries. Deterministic: the
 * same base and matrix give the same bits, and the identity restores the
 * base exactly. On error the scene is unchanged. */
int gi_scene_pose_object(gi_scene *s, uint32_t object, const gi_vec3 *base_positions,
                         const gi_vec3 *base_normals, const gi_mat4 *m, gi_error *err);
/* Copies an object's current positions and normals (its base pose, before
 * any gi_scene_pose_object) into new arrays the caller frees with free(). */
int gi_scene_object_copy_base(const gi_scene *s, uint32_t object, gi_vec3 **positions,
                              gi_vec3 **normals, gi_error *err);

/* Index of the object named `name`, or -1 (constant expected time). */
int gi_scene_find_object(const gi_scene *s, const char *name);
/* Index of the material named `name`, or -1 (constant expected time). */
int gi_scene_material_index(const gi_scene *s, const char *name);

#endif
