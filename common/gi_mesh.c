/* gi_mesh: ownership of gi_mesh_data, concatenation, and vertex normals for
 * meshes whose file gave none. */
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

/* Normals of vertices [first, first + count) from the triangles
 * [first_tri, first_tri + tri_count), written into m->normals. */
static void compute_normals_range(gi_mesh_data *m, uint32_t first, uint32_t count,
                                  uint32_t first_tri, uint32_t tri_count)
{
    /* Sums in double: a vertex shared by many triangles of very different
     * sizes would otherwise lose the small ones to rounding. */
    double *acc = gi_xcalloc((size_t)count * 3 + 1, sizeof *acc);
    for (uint32_t t = first_tri; t < first_tri + tri_count; t++) {
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        /* Indices are validated by the scene, not here: skip what is out of
         * range rather than write outside the accumulator. */
        if (ix[0] - first >= count || ix[1] - first >= count || ix[2] - first >= count)
            continue;
        gi_vec3 a = m->positions[ix[0]], b = m->positions[ix[1]], c = m->positions[ix[2]];
        double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
        double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
        /* The unnormalized cross product has length 2 * area: summing it
         * weights each face normal by its area. */
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++) {
            double *v = &acc[3 * (size_t)(ix[k] - first)];
            v[0] += n[0];
            v[1] += n[1];
            v[2] += n[2];
        }
    }
    for (uint32_t i = 0; i < count; i++) {
        const double *v = &acc[3 * (size_t)i];
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        gi_vec3 n = gi_v3(0.0f, 1.0f, 0.0f);
        if (len > 0.0 && isfinite(len))
            n = gi_v3((float)(v[0] / len), (float)(v[1] / len), (float)(v[2] / len));
        m->normals[first + i] = n;
    }
    free(acc);
}

/* A vertex with no defined direction (used by no triangle, or only by
 * degenerate ones, or by faces whose normals cancel) gets +y: any unit
 * vector is as good, and a fixed one keeps results deterministic. */
void gi_mesh_compute_normals(gi_mesh_data *m)
{
    free(m->normals);
    m->normals = gi_xmalloc(((size_t)m->vertex_count + 1) * sizeof *m->normals);
    compute_normals_range(m, 0, m->vertex_count, 0, m->triangle_count);
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
    /* Normals survive if either part has them; a part without gets the
     * normals the scene would compute for it (the vertex sets are disjoint,
     * so computing them per part gives the same result as for the whole). */
    int keep_normals = dst->normals || src->normals;
    int fill_dst = keep_normals && !dst->normals && v0 > 0;
    int fill_src = keep_normals && !src->normals && src->vertex_count > 0;

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
    if (fill_dst)
        compute_normals_range(dst, 0, v0, 0, t0);
    if (fill_src)
        compute_normals_range(dst, v0, src->vertex_count, t0, src->triangle_count);
}
