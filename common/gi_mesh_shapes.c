/* gi_mesh_shapes: the built-in shapes of the scene format (quad, box,
 * icosphere), centred at the origin, with one default material. Front faces
 * wind counter-clockwise (gi_scene.h); sizes are assumed positive (the scene
 * parser checks them). */
#include "gi_mesh.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

/* Allocates the arrays (one spare position, as Embree reads 16 bytes per
 * vertex) and the single default material every shape gets. */
static void shape_alloc(gi_mesh_data *m, uint32_t nv, uint32_t nt)
{
    gi_mesh_data_init(m);
    m->vertex_count = nv;
    m->triangle_count = nt;
    m->positions = gi_xmalloc(((size_t)nv + 1) * sizeof *m->positions);
    m->normals = gi_xmalloc(((size_t)nv + 1) * sizeof *m->normals);
    m->indices = gi_xmalloc(3 * (size_t)nt * sizeof *m->indices);
    m->tri_material = gi_xcalloc(nt, sizeof *m->tri_material);
    m->material_count = 1;
    m->materials = gi_xcalloc(1, sizeof *m->materials);
    m->materials[0].name = gi_xstrdup("default");
    m->materials[0].diffuse = gi_v3(0.8f, 0.8f, 0.8f);
}

void gi_mesh_quad(gi_mesh_data *out, double size_x, double size_z)
{
    shape_alloc(out, 4, 2);
    float x = (float)(0.5 * size_x), z = (float)(0.5 * size_z);
    /* (-x,-z) -> (-x,+z) -> (+x,+z): (b-a) x (c-a) points to +y. */
    const gi_vec3 p[4] = {{-x, 0, -z}, {-x, 0, z}, {x, 0, z}, {x, 0, -z}};
    static const uint32_t ix[6] = {0, 1, 2, 0, 2, 3};
    for (int i = 0; i < 4; i++) {
        out->positions[i] = p[i];
        out->normals[i] = gi_v3(0, 1, 0);
    }
    memcpy(out->indices, ix, sizeof ix);
}

void gi_mesh_box(gi_mesh_data *out, double sx, double sy, double sz, int inward)
{
    shape_alloc(out, 24, 12);
    const float h[3] = {(float)(0.5 * sx), (float)(0.5 * sy), (float)(0.5 * sz)};
    /* Each face: outward normal axis and sign; u, v span it so that
     * u x v = outward normal, which makes (c, c+u, c+u+v, c+v) CCW from
     * outside. */
    static const struct {
        int axis, sign, u, v;
    } faces[6] = {
        {0, +1, 1, 2}, {0, -1, 2, 1}, /* +x: y x z = x;  -x: z x y = -x */
        {1, +1, 2, 0}, {1, -1, 0, 2}, /* +y: z x x = y;  -y: x x z = -y */
        {2, +1, 0, 1}, {2, -1, 1, 0}, /* +z: x x y = z;  -z: y x x = -z */
    };
    static const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int f = 0; f < 6; f++) {
        float n[3] = {0, 0, 0};
        n[faces[f].axis] = (float)faces[f].sign;
        float sign = inward ? -1.0f : 1.0f;
        for (int k = 0; k < 4; k++) {
            float p[3];
            p[faces[f].axis] = (float)faces[f].sign * h[faces[f].axis];
            p[faces[f].u] = corners[k][0] * h[faces[f].u];
            p[faces[f].v] = corners[k][1] * h[faces[f].v];
            out->positions[4 * f + k] = gi_v3(p[0], p[1], p[2]);
            out->normals[4 * f + k] = gi_v3(sign * n[0], sign * n[1], sign * n[2]);
        }
        uint32_t b = 4 * (uint32_t)f;
        uint32_t *t = &out->indices[6 * f];
        if (!inward) {
            const uint32_t q[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
            memcpy(t, q, sizeof q);
        } else {
            const uint32_t q[6] = {b, b + 2, b + 1, b, b + 3, b + 2};
            memcpy(t, q, sizeof q);
        }
    }
}

/* Edge -> midpoint vertex, so that neighbouring triangles share it (open
 * addressing on the sorted vertex pair). */
typedef struct edge_map {
    uint64_t *keys; /* (lo << 32 | hi) + 1; 0 = empty */
    uint32_t *vals;
    size_t mask;
} edge_map;

static uint32_t midpoint(edge_map *e, gi_mesh_data *m, uint32_t a, uint32_t b, float radius)
{
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    uint64_t key = (((uint64_t)lo << 32) | hi) + 1;
    size_t i = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 17) & e->mask;
    while (e->keys[i]) {
        if (e->keys[i] == key)
            return e->vals[i];
        i = (i + 1) & e->mask;
    }
    uint32_t v = m->vertex_count++;
    gi_vec3 n = gi_normalize(gi_add(m->positions[a], m->positions[b]));
    m->positions[v] = gi_scale(n, radius);
    m->normals[v] = n;
    e->keys[i] = key;
    e->vals[i] = v;
    return v;
}

/* Icosphere: an icosahedron whose triangles are split into four per level,
 * new vertices pushed onto the sphere. Level l has 20 * 4^l triangles,
 * 30 * 4^l edges and 10 * 4^l + 2 vertices (Euler: V - E + F = 2). */
void gi_mesh_sphere(gi_mesh_data *out, double radius, int subdivisions)
{
    assert(subdivisions >= 0 && subdivisions <= 12);
    uint64_t p4 = (uint64_t)1 << (2 * subdivisions);
    uint32_t nv = (uint32_t)(10 * p4 + 2), nt = (uint32_t)(20 * p4);
    shape_alloc(out, nv, nt);
    float r = (float)radius;

    /* The 12 vertices (0, +-1, +-phi) cyclically permuted, and 20 faces
     * wound counter-clockwise seen from outside. */
    const float t = (float)((1.0 + sqrt(5.0)) / 2.0);
    const gi_vec3 base[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                              {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                              {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    static const uint32_t faces[20][3] = {
        {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
        {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
        {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
        {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    out->vertex_count = 12;
    for (int i = 0; i < 12; i++) {
        gi_vec3 n = gi_normalize(base[i]);
        out->positions[i] = gi_scale(n, r);
        out->normals[i] = n;
    }
    memcpy(out->indices, faces, sizeof faces);
    uint32_t cur = 20;

    uint32_t *next = gi_xmalloc(3 * (size_t)nt * sizeof *next);
    for (int level = 0; level < subdivisions; level++) {
        edge_map e;
        size_t edges = (size_t)3 * cur / 2, cap = 1;
        while (cap < 2 * edges)
            cap <<= 1;
        e.keys = gi_xcalloc(cap, sizeof *e.keys);
        e.vals = gi_xmalloc(cap * sizeof *e.vals);
        e.mask = cap - 1;
        for (uint32_t f = 0; f < cur; f++) {
            const uint32_t *v = &out->indices[3 * (size_t)f];
            uint32_t a = midpoint(&e, out, v[0], v[1], r);
            uint32_t b = midpoint(&e, out, v[1], v[2], r);
            uint32_t c = midpoint(&e, out, v[2], v[0], r);
            /* Corner triangles keep the parent's orientation, as does the
             * centre one (a, b, c). */
            const uint32_t q[12] = {v[0], a, c, v[1], b, a, v[2], c, b, a, b, c};
            memcpy(&next[12 * (size_t)f], q, sizeof q);
        }
        free(e.keys);
        free(e.vals);
        cur *= 4;
        memcpy(out->indices, next, 3 * (size_t)cur * sizeof *next);
    }
    free(next);
    assert(out->vertex_count == nv && cur == nt);
}
