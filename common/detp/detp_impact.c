/* detp_impact: the impact count estimator [Arvo 86, Heckbert 90, Pattanaik
 * 92] (thesis 1.2, eqs. 3.6-3.8). A hit gives its energy to the triangle it
 * lands on; a triangle's irradiance is its energy over its area (eq. 3.6),
 * a vertex's the plain mean over its triangles (eq. 3.7), and the renderer
 * interpolates barycentrically inside triangles (eq. 3.8). The per-vertex
 * values are linear in the hits, so batches add. */
#include <stdlib.h>

#include "detp.h"

int gi_detp_impact_count(const gi_scene *scene, const gi_detp_segments *s, gi_detp_accum *acc,
                         gi_detp_stats *st, gi_error *err)
{
    uint32_t nt = scene->triangle_count;
    double *tri = gi_try_calloc((size_t)nt * 3 + 1, sizeof *tri, err, "impact counts");
    uint32_t *hits = gi_try_calloc((size_t)nt + 1, sizeof *hits, err, "impact counts");
    uint32_t *around = gi_try_calloc((size_t)scene->vertex_count + 1, sizeof *around, err,
                                     "impact counts");
    if (!tri || !hits || !around) {
        free(tri);
        free(hits);
        free(around);
        return -1;
    }
    for (size_t j = 0; j < s->count; j++) {
        const gi_detp_segment *g = &s->v[j];
        if (g->hit_tri >= nt)
            continue;
        const uint32_t *ix = &scene->indices[3 * (size_t)g->hit_tri];
        /* The side the triangle's vertex normals face is its front. */
        gi_vec3 nv = gi_add(gi_add(scene->normals[ix[0]], scene->normals[ix[1]]),
                            scene->normals[ix[2]]);
        if (!(gi_dot(g->dir, nv) < 0.0f))
            continue;
        double *e = &tri[3 * (size_t)g->hit_tri];
        e[0] += g->energy.x;
        e[1] += g->energy.y;
        e[2] += g->energy.z;
        hits[g->hit_tri]++;
        st->crossings++;
    }
    for (uint32_t t = 0; t < nt; t++) {
        double area = gi_scene_triangle_area(scene, t);
        if (!(area > 0.0))
            continue;
        for (int k = 0; k < 3; k++)
            around[scene->indices[3 * (size_t)t + k]]++;
    }
    for (uint32_t t = 0; t < nt; t++) {
        double area = gi_scene_triangle_area(scene, t);
        if (!(area > 0.0) || hits[t] == 0)
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t v = scene->indices[3 * (size_t)t + k];
            double w = 1.0 / (area * around[v]); /* eq. 3.6 then eq. 3.7 */
            for (int c = 0; c < 3; c++)
                acc->energy[3 * (size_t)v + c] += tri[3 * (size_t)t + c] * w;
            acc->hits[v] += hits[t];
        }
    }
    free(tri);
    free(hits);
    free(around);
    return 0;
}
