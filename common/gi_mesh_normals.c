/* gi_mesh_normals: vertex normals for meshes whose file gave none. As DCC
 * tools do, a vertex is split at hard edges: the triangles around it that
 * meet across edges of at most GI_MESH_CREASE_DEG form a smooth group, and
 * each group gets its own copy of the vertex with the area-weighted normal
 * of the group. A cube's corner thus has three normals, one per face, not
 * one pointing diagonally out (which tilts the per-vertex methods' discs and
 * the shading). */
#include "gi_mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* cos(GI_MESH_CREASE_DEG), with room for rounding: faces meeting at exactly
 * 60 degrees (a hexagonal prism) are smoothed whatever the last bit says. */
#define CREASE_COS (0.5 - 1e-9)
_Static_assert(GI_MESH_CREASE_DEG == 60, "CREASE_COS is cos(60 degrees)");

/* A run of triangles sharing one edge (non-manifold) is compared with this
 * many predecessors at most: bounded work on pathological fans. */
#define MAX_RUN_COMPARE 16

static uint32_t uf_find(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static void uf_union(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = uf_find(parent, a);
    b = uf_find(parent, b);
    /* The smaller corner is the root: groups are found in corner order. */
    if (a < b)
        parent[b] = a;
    else if (b < a)
        parent[a] = b;
}

/* A corner's edge at its vertex: the other end, and the corner. */
typedef struct edge_end {
    uint32_t other, corner;
} edge_end;

static int edge_end_cmp(const void *x, const void *y)
{
    const edge_end *p = x, *q = y;
    if (p->other != q->other)
        return p->other < q->other ? -1 : 1;
    return p->corner < q->corner ? -1 : p->corner > q->corner;
}

/* Unnormalized face normals (length 2 * area) in double, and whether each
 * triangle has a direction at all. */
static void face_normals(const gi_mesh_data *m, double *fn, uint8_t *valid)
{
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        double *n = &fn[3 * (size_t)t];
        n[0] = n[1] = n[2] = 0.0;
        valid[t] = 0;
        /* Indices are validated by the scene, not here: a triangle out of
         * range counts as degenerate rather than read outside positions. */
        if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
            continue;
        gi_vec3 a = m->positions[ix[0]], b = m->positions[ix[1]], c = m->positions[ix[2]];
        double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
        double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        valid[t] = len > 0.0 && isfinite(len);
    }
}

static int smooth_between(const double *fn, uint32_t s, uint32_t t)
{
    const double *a = &fn[3 * (size_t)s], *b = &fn[3 * (size_t)t];
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] >= CREASE_COS * la * lb;
}

/* Joins, around each vertex, the corners of triangles that share an edge
 * at it across which the faces are smooth. */
static void join_smooth_corners(const gi_mesh_data *m, const double *fn, const uint8_t *valid,
                                const uint32_t *start, const uint32_t *corners,
                                uint32_t *parent)
{
    uint32_t max_valence = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        if (start[v + 1] - start[v] > max_valence)
            max_valence = start[v + 1] - start[v];
    edge_end *ends = gi_xmalloc(((size_t)2 * max_valence + 1) * sizeof *ends);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        size_t n = 0;
        for (uint32_t i = start[v]; i < start[v + 1]; i++) {
            uint32_t c = corners[i], t = c / 3, k = c % 3;
            if (!valid[t])
                continue;
            ends[n++] = (edge_end){m->indices[3 * (size_t)t + (k + 1) % 3], c};
            ends[n++] = (edge_end){m->indices[3 * (size_t)t + (k + 2) % 3], c};
        }
        qsort(ends, n, sizeof *ends, edge_end_cmp);
        for (size_t i = 1; i < n; i++)
            for (size_t j = i; j-- > 0 && i - j <= MAX_RUN_COMPARE;) {
                if (ends[j].other != ends[i].other)
                    break;
                if (smooth_between(fn, ends[j].corner / 3, ends[i].corner / 3))
                    uf_union(parent, ends[j].corner, ends[i].corner);
            }
    }
    free(ends);
}

void gi_mesh_compute_normals(gi_mesh_data *m)
{
    uint32_t nv = m->vertex_count, nt = m->triangle_count;
    size_t nc = 3 * (size_t)nt;
    double *fn = gi_xmalloc((nc + 1) * sizeof *fn);
    uint8_t *valid = gi_xmalloc((size_t)nt + 1);
    face_normals(m, fn, valid);

    /* The corners at each vertex, in triangle order. */
    uint32_t *start = gi_xcalloc((size_t)nv + 2, sizeof *start);
    uint32_t *corners = gi_xmalloc((nc + 1) * sizeof *corners);
    for (size_t c = 0; c < nc; c++)
        if (m->indices[c] < nv)
            start[m->indices[c] + 1]++;
    for (uint32_t v = 0; v < nv; v++)
        start[v + 1] += start[v];
    uint32_t *fill = gi_xmalloc(((size_t)nv + 1) * sizeof *fill);
    memcpy(fill, start, (size_t)nv * sizeof *fill);
    for (size_t c = 0; c < nc; c++)
        if (m->indices[c] < nv)
            corners[fill[m->indices[c]]++] = (uint32_t)c;
    free(fill);

    uint32_t *parent = gi_xmalloc((nc + 1) * sizeof *parent);
    for (size_t c = 0; c < nc; c++)
        parent[c] = (uint32_t)c;
    join_smooth_corners(m, fn, valid, start, corners, parent);

    /* One vertex per group: the vertex's first group keeps its index (a
     * mesh without hard edges keeps its numbering), others are appended.
     * Corners of degenerate triangles, which have no direction, join the
     * vertex's first group. */
    uint32_t *vertex_of = gi_xmalloc((nc + 1) * sizeof *vertex_of);
    uint32_t *origin = NULL; /* the original of each appended vertex */
    size_t extra = 0, cap = 0;
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t first_root = UINT32_MAX;
        for (uint32_t i = start[v]; i < start[v + 1]; i++) {
            uint32_t c = corners[i];
            if (!valid[c / 3])
                continue;
            uint32_t r = uf_find(parent, c);
            if (first_root == UINT32_MAX)
                first_root = r;
            if (r == c) { /* the group's first corner: it names a vertex */
                if (r == first_root) {
                    vertex_of[c] = v;
                } else {
                    if ((uint64_t)nv + extra >= UINT32_MAX)
                        abort(); /* the scene's limits keep meshes far below */
                    if (extra == cap) {
                        cap = cap ? 2 * cap : 64;
                        origin = gi_xrealloc(origin, cap * sizeof *origin);
                    }
                    origin[extra] = v;
                    vertex_of[c] = nv + (uint32_t)extra++;
                }
            } else {
                vertex_of[c] = vertex_of[r];
            }
        }
        for (uint32_t i = start[v]; i < start[v + 1]; i++)
            if (!valid[corners[i] / 3])
                vertex_of[corners[i]] = v;
    }
    /* Out-of-range corners keep their index (the scene refuses them). */
    for (size_t c = 0; c < nc; c++)
        if (m->indices[c] >= nv)
            vertex_of[c] = m->indices[c];

    uint32_t total = nv + (uint32_t)extra;
    if (extra) {
        m->positions = gi_xrealloc(m->positions, ((size_t)total + 1) * sizeof *m->positions);
        for (size_t i = 0; i < extra; i++)
            m->positions[nv + i] = m->positions[origin[i]];
    }
    /* Sums in double: a vertex shared by many triangles of very different
     * sizes would otherwise lose the small ones to rounding. The
     * unnormalized cross product weights each face by its area. */
    double *acc = gi_xcalloc((size_t)total * 3 + 1, sizeof *acc);
    for (size_t c = 0; c < nc; c++) {
        if (!valid[c / 3])
            continue;
        const double *n = &fn[3 * (c / 3)];
        double *a = &acc[3 * (size_t)vertex_of[c]];
        a[0] += n[0];
        a[1] += n[1];
        a[2] += n[2];
    }
    free(m->normals);
    m->normals = gi_xmalloc(((size_t)total + 1) * sizeof *m->normals);
    for (uint32_t i = 0; i < total; i++) {
        const double *a = &acc[3 * (size_t)i];
        double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        /* A vertex with no direction (used by no triangle, or only by
         * degenerate ones, or by faces whose normals cancel) gets +y: any
         * unit vector would do, and a fixed one keeps results deterministic. */
        gi_vec3 n = gi_v3(0.0f, 1.0f, 0.0f);
        if (len > 0.0 && isfinite(len))
            n = gi_v3((float)(a[0] / len), (float)(a[1] / len), (float)(a[2] / len));
        m->normals[i] = n;
    }
    memcpy(m->indices, vertex_of, nc * sizeof *m->indices);
    m->vertex_count = total;

    free(acc);
    free(origin);
    free(vertex_of);
    free(parent);
    free(corners);
    free(start);
    free(valid);
    free(fn);
}
