/* rad_vertices: welding element corners into shared vertices. */
#include "rad_vertices.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct corner_key {
    uint32_t group[4]; /* material, quantized normal */
    uint32_t pos[3];   /* float bits */
    uint32_t index;    /* corner index: a total order, so sorting is deterministic */
} corner_key;

static int key_cmp(const void *pa, const void *pb)
{
    const corner_key *a = pa, *b = pb;
    int c = memcmp(a->group, b->group, sizeof a->group);
    if (c == 0)
        c = memcmp(a->pos, b->pos, sizeof a->pos);
    if (c)
        return c;
    return a->index < b->index ? -1 : a->index > b->index;
}

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

int gi_rad_vertices_build(gi_rad_vertices *v, const gi_rad_mesh *m, const gi_scene *s,
                          gi_error *err)
{
    memset(v, 0, sizeof *v);
    size_t corners = (size_t)m->element_count * 3;
    corner_key *keys = gi_try_malloc(corners * sizeof *keys, err, "radiosity vertices");
    gi_vec3 *pos = gi_try_malloc(corners * sizeof *pos, err, "radiosity vertices");
    v->corner = gi_try_malloc(corners * sizeof *v->corner, err, "radiosity vertices");
    if (!keys || !pos || !v->corner) {
        free(keys);
        free(pos);
        gi_rad_vertices_free(v);
        return -1;
    }
    for (uint32_t e = 0; e < m->element_count; e++) {
        uint32_t t = gi_rad_mesh_element_tri(m, e);
        gi_vec3 n = s->tri_normal[t];
        /* Normals agreeing to ~1e-3 are one plane orientation. */
        uint32_t group[4] = {s->tri_material[t], (uint32_t)(int32_t)lrintf(n.x * 1000.0f),
                             (uint32_t)(int32_t)lrintf(n.y * 1000.0f),
                             (uint32_t)(int32_t)lrintf(n.z * 1000.0f)};
        gi_rad_mesh_element_corners(m, s, e, &pos[3 * (size_t)e]);
        for (int k = 0; k < 3; k++) {
            corner_key *ck = &keys[3 * (size_t)e + k];
            memcpy(ck->group, group, sizeof group);
            gi_vec3 p = pos[3 * (size_t)e + k];
            ck->pos[0] = float_bits(p.x);
            ck->pos[1] = float_bits(p.y);
            ck->pos[2] = float_bits(p.z);
            ck->index = (uint32_t)(3 * (size_t)e + k);
        }
    }
    qsort(keys, corners, sizeof *keys, key_cmp);
    uint32_t count = 0;
    for (size_t i = 0; i < corners; i++) {
        if (i == 0 || memcmp(keys[i].group, keys[i - 1].group, sizeof keys[i].group) ||
            memcmp(keys[i].pos, keys[i - 1].pos, sizeof keys[i].pos))
            count++;
        v->corner[keys[i].index] = count - 1;
    }
    v->count = count;
    v->positions = gi_try_malloc((size_t)count * sizeof *v->positions, err, "radiosity vertices");
    if (!v->positions) {
        free(keys);
        free(pos);
        gi_rad_vertices_free(v);
        return -1;
    }
    for (size_t i = 0; i < corners; i++)
        v->positions[v->corner[i]] = pos[i];
    free(keys);
    free(pos);
    return 0;
}

void gi_rad_vertices_free(gi_rad_vertices *v)
{
    free(v->positions);
    free(v->corner);
    memset(v, 0, sizeof *v);
}

int gi_rad_vertex_values(const gi_rad_vertices *v, uint32_t n, const double *area,
                         const float *elem, float *out, gi_error *err)
{
    double *acc = gi_try_calloc((size_t)v->count * 4, sizeof *acc, err, "vertex values");
    if (!acc)
        return -1;
    for (uint32_t e = 0; e < n; e++)
        for (int k = 0; k < 3; k++) {
            double *a = &acc[4 * (size_t)v->corner[3 * (size_t)e + k]];
            for (int c = 0; c < 3; c++)
                a[c] += area[e] * elem[3 * (size_t)e + c];
            a[3] += area[e];
        }
    for (uint32_t i = 0; i < v->count; i++)
        for (int c = 0; c < 3; c++)
            out[3 * (size_t)i + c] = acc[4 * (size_t)i + 3] > 0.0
                                         ? (float)(acc[4 * (size_t)i + c] / acc[4 * (size_t)i + 3])
                                         : 0.0f;
    free(acc);
    return 0;
}
