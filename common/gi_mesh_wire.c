/* gi_mesh_wire: the importer child's mesh message: u32 vertices, u32
 * triangles, u32 materials, u8 has normals, then the positions, normals,
 * indices and per-triangle materials as their bytes, then per material its
 * name (u32 length + bytes), diffuse and emission (3 f32 each). */
#include "gi_mesh_wire.h"

#include <math.h>

_Static_assert(sizeof(gi_vec3) == 3 * sizeof(float), "a gi_vec3 is 3 packed floats");

/* Longest material name: what gi_mesh_from_assimp lets through, and the
 * "#<index>" (at most 11 bytes) that makes it unique. */
#define MAX_NAME (GI_MESH_NAME_MAX + 11)

void gi_mesh_encode(gi_buf *b, const gi_mesh_data *m)
{
    size_t nv = m->vertex_count, nt = m->triangle_count;
    gi_buf_reserve(b, 16 + (m->normals ? 24 : 12) * nv + 16 * nt + 64 * m->material_count);
    gi_buf_put_u32(b, m->vertex_count);
    gi_buf_put_u32(b, m->triangle_count);
    gi_buf_put_u32(b, m->material_count);
    gi_buf_put_u8(b, m->normals != NULL);
    gi_buf_put(b, m->positions, nv * sizeof *m->positions);
    if (m->normals)
        gi_buf_put(b, m->normals, nv * sizeof *m->normals);
    gi_buf_put(b, m->indices, 3 * nt * sizeof *m->indices);
    gi_buf_put(b, m->tri_material, nt * sizeof *m->tri_material);
    for (uint32_t i = 0; i < m->material_count; i++) {
        gi_buf_put_str(b, m->materials[i].name);
        gi_buf_put_f32s(b, &m->materials[i].diffuse.x, 3);
        gi_buf_put_f32s(b, &m->materials[i].emission.x, 3);
    }
}

static int finite3(gi_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* What gi_mesh_from_assimp guarantees, checked again on this side. */
static int check_decoded(const gi_mesh_data *m, const char *name, gi_error *err)
{
    for (uint32_t v = 0; v < m->vertex_count; v++)
        if (!finite3(m->positions[v]) || (m->normals && !finite3(m->normals[v])))
            return gi_fail(err, GI_EINTERNAL,
                           "%s: the importer process sent a bad mesh: vertex %u is not finite",
                           name, v);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            if (m->indices[3 * (size_t)t + k] >= m->vertex_count)
                return gi_fail(err, GI_EINTERNAL,
                               "%s: the importer process sent a bad mesh: triangle %u uses "
                               "vertex %u of %u",
                               name, t, m->indices[3 * (size_t)t + k], m->vertex_count);
        if (m->tri_material[t] >= m->material_count)
            return gi_fail(err, GI_EINTERNAL,
                           "%s: the importer process sent a bad mesh: triangle %u uses "
                           "material %u of %u",
                           name, t, m->tri_material[t], m->material_count);
    }
    return 0;
}

int gi_mesh_decode(const void *data, size_t len, const char *name, gi_mesh_data *m,
                   gi_error *err)
{
    gi_reader r;
    gi_reader_init(&r, data, len, "imported mesh");
    uint32_t nv = gi_get_u32(&r), nt = gi_get_u32(&r), nm = gi_get_u32(&r);
    uint8_t normals = gi_get_u8(&r);
    /* Each vertex takes 12 bytes, a triangle 16, a material 28: counts the
     * payload cannot hold are refused before anything is allocated. */
    if (r.failed || nv == 0 || nt == 0 || nm == 0 || normals > 1 || r.left / 12 < nv ||
        r.left / 16 < nt || r.left / 28 < nm)
        return gi_fail(err, GI_EINTERNAL, "%s: the importer process sent a bad mesh", name);
    m->vertex_count = nv;
    m->triangle_count = nt;
    m->positions = gi_xmalloc(((size_t)nv + 1) * sizeof *m->positions);
    gi_get(&r, m->positions, (size_t)nv * sizeof *m->positions);
    if (normals) {
        m->normals = gi_xmalloc(((size_t)nv + 1) * sizeof *m->normals);
        gi_get(&r, m->normals, (size_t)nv * sizeof *m->normals);
    }
    m->indices = gi_xmalloc(3 * (size_t)nt * sizeof *m->indices);
    gi_get(&r, m->indices, 3 * (size_t)nt * sizeof *m->indices);
    m->tri_material = gi_xmalloc((size_t)nt * sizeof *m->tri_material);
    gi_get(&r, m->tri_material, (size_t)nt * sizeof *m->tri_material);
    m->materials = gi_xcalloc(nm, sizeof *m->materials);
    m->material_count = nm;
    for (uint32_t i = 0; i < nm && !r.failed; i++) {
        m->materials[i].name = gi_get_str(&r, MAX_NAME);
        gi_get_f32s(&r, &m->materials[i].diffuse.x, 3);
        gi_get_f32s(&r, &m->materials[i].emission.x, 3);
    }
    gi_error e;
    if (gi_reader_finish(&r, &e))
        return gi_fail(err, GI_EINTERNAL, "%s: the importer process sent a bad mesh: %s", name,
                       e.msg);
    return check_decoded(m, name, err);
}
