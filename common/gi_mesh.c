/* gi_mesh: ownership of gi_mesh_data and concatenation (vertex normals for
 * meshes whose file gave none: gi_mesh_normals.c). */
#include "gi_mesh.h"

#include <stdlib.h>
#include <string.h>

void gi_mesh_data_init(gi_mesh_data *m) { memset(m, 0, sizeof *m); }

void gi_mesh_data_free(gi_mesh_data *m)
{
    free(m->positions);
    free(m->normals);
    free(m->indices);
    free(m->tri_material);
    for (uint32_t i = 0; i < m->material_count; i++)
        free(m->materials[i].name);
    free(m->materials);
    gi_mesh_data_init(m);
}

static void *dup_array(const void *p, size_t n, size_t size)
{
    if (!p)
        return NULL;
    void *q = gi_xmalloc((n + 1) * size); /* + 1: the padding the arrays carry */
    memcpy(q, p, n * size);
    return q;
}

void gi_mesh_data_copy(gi_mesh_data *dst, const gi_mesh_data *src)
{
    *dst = *src;
    dst->positions = dup_array(src->positions, src->vertex_count, sizeof(gi_vec3));
    dst->normals = dup_array(src->normals, src->vertex_count, sizeof(gi_vec3));
    dst->indices = dup_array(src->indices, 3 * (size_t)src->triangle_count, sizeof(uint32_t));
    dst->tri_material = dup_array(src->tri_material, src->triangle_count, sizeof(uint32_t));
    dst->materials = dup_array(src->materials, src->material_count, sizeof *src->materials);
    for (uint32_t i = 0; i < src->material_count; i++)
        if (src->materials[i].name)
            dst->materials[i].name = gi_xstrdup(src->materials[i].name);
}

static void add_default_material(gi_mesh_data *m)
{
    m->materials = gi_xrealloc(m->materials, (m->material_count + 1) * sizeof *m->materials);
    gi_mesh_material *d = &m->materials[m->material_count++];
    d->name = gi_xstrdup("default");
    d->diffuse = gi_v3(0.8f, 0.8f, 0.8f);
    d->emission = gi_v3(0.0f, 0.0f, 0.0f);
}

void gi_mesh_data_append(gi_mesh_data *dst, const gi_mesh_data *src)
{
    /* Normals survive if either part has them; a part without gets the
     * normals the scene would compute for it (the vertex sets are disjoint,
     * so computing them per part gives the same result as for the whole),
     * before the append: splitting at hard edges adds vertices. */
    if (src->normals && !dst->normals && dst->vertex_count > 0)
        gi_mesh_compute_normals(dst);
    if (dst->normals && !src->normals && src->vertex_count > 0) {
        gi_mesh_data copy;
        gi_mesh_data_init(&copy);
        gi_mesh_data_append(&copy, src);
        gi_mesh_compute_normals(&copy);
        gi_mesh_data_append(dst, &copy);
        gi_mesh_data_free(&copy);
        return;
    }
    /* A part with triangles but no materials means "the default material"
     * (index 0): make that explicit, or its triangles would point at the
     * other part's materials after the shift. */
    if (dst->material_count == 0 && dst->triangle_count > 0)
        add_default_material(dst);
    int src_default = src->material_count == 0 && src->triangle_count > 0;
    uint32_t v0 = dst->vertex_count, t0 = dst->triangle_count, m0 = dst->material_count;
    size_t nv = (size_t)v0 + src->vertex_count;
    size_t nt = (size_t)t0 + src->triangle_count;
    size_t nm = (size_t)m0 + src->material_count + (size_t)src_default;
    if (nv > UINT32_MAX || nt > UINT32_MAX / 3 || nm > UINT32_MAX) {
        /* Callers keep meshes far below this (the importer caps a file at
         * 2^31 vertices, the scene at 2^30): reaching it is a bug. */
        abort();
    }
    int keep_normals = dst->normals || src->normals;

    dst->positions = gi_xrealloc(dst->positions, (nv + 1) * sizeof *dst->positions);
    if (src->vertex_count)
        memcpy(dst->positions + v0, src->positions, src->vertex_count * sizeof *src->positions);
    if (keep_normals) {
        dst->normals = gi_xrealloc(dst->normals, (nv + 1) * sizeof *dst->normals);
        if (src->normals && src->vertex_count)
            memcpy(dst->normals + v0, src->normals, src->vertex_count * sizeof *src->normals);
    }

    dst->indices = gi_xrealloc(dst->indices, (3 * nt + 1) * sizeof *dst->indices);
    dst->tri_material = gi_xrealloc(dst->tri_material, (nt + 1) * sizeof *dst->tri_material);
    for (size_t i = 0; i < 3 * (size_t)src->triangle_count; i++)
        dst->indices[3 * (size_t)t0 + i] = src->indices[i] + v0;
    for (uint32_t t = 0; t < src->triangle_count; t++)
        dst->tri_material[t0 + t] = src->tri_material[t] + m0;

    dst->materials = gi_xrealloc(dst->materials, (nm + 1) * sizeof *dst->materials);
    for (uint32_t i = 0; i < src->material_count; i++) {
        gi_mesh_material *d = &dst->materials[m0 + i];
        *d = src->materials[i];
        d->name = src->materials[i].name ? gi_xstrdup(src->materials[i].name) : NULL;
    }
    if (src_default) {
        gi_mesh_material *d = &dst->materials[m0];
        d->name = gi_xstrdup("default");
        d->diffuse = gi_v3(0.8f, 0.8f, 0.8f);
        d->emission = gi_v3(0.0f, 0.0f, 0.0f);
    }

    dst->vertex_count = (uint32_t)nv;
    dst->triangle_count = (uint32_t)nt;
    dst->material_count = (uint32_t)nm;
}
