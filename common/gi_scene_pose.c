/* gi_scene_pose: moving one object of a loaded scene to a pose (quasi-static
 * animation, issue 7). Always from the object's base vertices, never from
 * the previous pose, so that frame f's geometry depends only on f's matrix
 * and rounding errors do not accumulate over frames. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_scene.h"

static int is_identity(const gi_mat4 *m)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (m->m[i][j] != (i == j ? 1.0 : 0.0))
                return 0;
    return 1;
}

static int in_range(gi_vec3 p)
{
    /* The loader's limit on world coordinates (gi_scene_add_object). */
    return isfinite(p.x) && isfinite(p.y) && isfinite(p.z) && fabsf(p.x) <= 1e18f &&
           fabsf(p.y) <= 1e18f && fabsf(p.z) <= 1e18f;
}

int gi_scene_pose_object(gi_scene *s, uint32_t object, const gi_vec3 *base_positions,
                         const gi_vec3 *base_normals, const gi_mat4 *m, gi_error *err)
{
    if (object >= s->object_count)
        return gi_fail(err, GI_EINVAL, "%s: no object %u to pose (%u objects)", s->name,
                       object, s->object_count);
    const gi_object *o = &s->objects[object];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(m->m[i][j]))
                return gi_fail(err, GI_EINVAL, "%s: object \"%s\": the pose is not finite",
                               s->name, o->name);
    gi_mat4 inv;
    if (gi_mat4_inverse(*m, &inv))
        return gi_fail(err, GI_EINVAL, "%s: object \"%s\": the pose is singular", s->name,
                       o->name);
    for (uint32_t t = o->first_triangle; t < o->first_triangle + o->triangle_count; t++)
        if (!gi_is_black(gi_scene_tri_material(s, t)->emission))
            return gi_fail(err, GI_EINVAL,
                           "%s: object \"%s\": an emissive object cannot be posed (the light "
                           "distribution would be stale)",
                           s->name, o->name);

    gi_vec3 *pos = s->positions + o->first_vertex, *nrm = s->normals + o->first_vertex;
    size_t n = o->vertex_count;
    if (is_identity(m)) {
        /* Bit-exact, including -0.0 and normals that renormalizing would
         * move by an ulp. */
        memcpy(pos, base_positions, n * sizeof *pos);
        memcpy(nrm, base_normals, n * sizeof *nrm);
    } else {
        /* Check first, so that a failure leaves the scene unchanged. */
        for (size_t i = 0; i < n; i++)
            if (!in_range(gi_mat4_point(m, base_positions[i])))
                return gi_fail(err, GI_EINVAL,
                               "%s: object \"%s\": vertex %zu is out of range in the pose",
                               s->name, o->name, i);
        for (size_t i = 0; i < n; i++) {
            pos[i] = gi_mat4_point(m, base_positions[i]);
            nrm[i] = gi_mat4_normal(&inv, base_normals[i]);
        }
    }
    gi_scene_update_triangles(s, o->first_triangle, o->triangle_count);
    gi_scene_update_bbox(s);
    return 0;
}

int gi_scene_object_copy_base(const gi_scene *s, uint32_t object, gi_vec3 **positions,
                              gi_vec3 **normals, gi_error *err)
{
    *positions = *normals = NULL;
    if (object >= s->object_count)
        return gi_fail(err, GI_EINVAL, "%s: no object %u (%u objects)", s->name, object,
                       s->object_count);
    const gi_object *o = &s->objects[object];
    size_t bytes = ((size_t)o->vertex_count + 1) * sizeof(gi_vec3);
    gi_vec3 *p = gi_try_malloc(bytes, err, "object base positions");
    gi_vec3 *nn = p ? gi_try_malloc(bytes, err, "object base normals") : NULL;
    if (!nn) {
        free(p);
        return -1;
    }
    memcpy(p, s->positions + o->first_vertex, o->vertex_count * sizeof *p);
    memcpy(nn, s->normals + o->first_vertex, o->vertex_count * sizeof *nn);
    p[o->vertex_count] = nn[o->vertex_count] = gi_v3(0, 0, 0);
    *positions = p;
    *normals = nn;
    return 0;
}
