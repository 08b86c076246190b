/* detp_points: the irradiance samples - mesh vertices with their normals,
 * one disc each (thesis 1.5) - and the optional refinement that splits
 * large triangles so the samples are evenly spaced (the Cornell box's walls
 * are single quads: four samples per wall would say little). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "detp.h"
#include "gi_limits.h"
#include "gi_rng.h"

/* ---- An edge -> vertex map (open addressing; keys are vertex pairs) ---- */

typedef struct edge_map {
    uint64_t *keys; /* (min << 32 | max) + 1; 0 = empty */
    uint32_t *vals;
    size_t cap, count;
} edge_map;

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    return (((uint64_t)lo << 32) | hi) + 1;
}

static void map_init(edge_map *m, size_t expect)
{
    m->cap = 64;
    while (m->cap < 2 * expect)
        m->cap *= 2;
    m->keys = gi_xcalloc(m->cap, sizeof *m->keys);
    m->vals = gi_xcalloc(m->cap, sizeof *m->vals);
    m->count = 0;
}

static void map_free(edge_map *m)
{
    free(m->keys);
    free(m->vals);
    memset(m, 0, sizeof *m);
}

/* Slot of key: where it is, or the empty slot where it goes. */
static size_t map_slot(const edge_map *m, uint64_t key)
{
    size_t i = (size_t)gi_mix64(key) & (m->cap - 1);
    while (m->keys[i] && m->keys[i] != key)
        i = (i + 1) & (m->cap - 1);
    return i;
}

static void map_put(edge_map *m, uint64_t key, uint32_t val)
{
    if (2 * (m->count + 1) > m->cap) {
        edge_map bigger;
        map_init(&bigger, m->cap);
        for (size_t i = 0; i < m->cap; i++)
            if (m->keys[i])
                map_put(&bigger, m->keys[i], m->vals[i]);
        map_free(m);
        *m = bigger;
    }
    size_t i = map_slot(m, key);
    if (!m->keys[i])
        m->count++;
    m->keys[i] = key;
    m->vals[i] = val;
}

/* ---- Refinement of one object's mesh ------------------------------------ */

typedef struct mesh {
    gi_vec3 *pos, *nrm;
    uint32_t nv, cap_v;
    uint32_t *tri; /* 3 per triangle, local vertex ids */
    uint32_t *mat; /* per triangle */
    uint32_t nt, cap_t;
} mesh;

static uint32_t mesh_add_vertex(mesh *m, gi_vec3 p, gi_vec3 n)
{
    if (m->nv == m->cap_v) {
        m->cap_v = m->cap_v ? 2 * m->cap_v : 64;
        m->pos = gi_xrealloc(m->pos, m->cap_v * sizeof *m->pos);
        m->nrm = gi_xrealloc(m->nrm, m->cap_v * sizeof *m->nrm);
    }
    m->pos[m->nv] = p;
    m->nrm[m->nv] = n;
    return m->nv++;
}

static void mesh_add_tri(mesh *m, uint32_t a, uint32_t b, uint32_t c, uint32_t mat)
{
    if (m->nt == m->cap_t) {
        m->cap_t = m->cap_t ? 2 * m->cap_t : 64;
        m->tri = gi_xrealloc(m->tri, (size_t)m->cap_t * 3 * sizeof *m->tri);
        m->mat = gi_xrealloc(m->mat, m->cap_t * sizeof *m->mat);
    }
    m->tri[3 * m->nt] = a;
    m->tri[3 * m->nt + 1] = b;
    m->tri[3 * m->nt + 2] = c;
    m->mat[m->nt++] = mat;
}

static float dist2(gi_vec3 a, gi_vec3 b)
{
    gi_vec3 d = gi_sub(a, b);
    return gi_dot(d, d);
}

/* The midpoint vertex of edge (a, b), created once per edge: computed from
 * the lower vertex id to the higher, so it does not depend on which
 * triangle asks first. */
static uint32_t midpoint(mesh *m, edge_map *map, uint32_t a, uint32_t b, gi_vec3 fallback_n)
{
    uint64_t key = edge_key(a, b);
    size_t i = map_slot(map, key);
    if (map->keys[i])
        return map->vals[i];
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    gi_vec3 p = gi_scale(gi_add(m->pos[lo], m->pos[hi]), 0.5f);
    gi_vec3 n = gi_add(m->nrm[lo], m->nrm[hi]);
    n = gi_length(n) > 1e-6f ? gi_normalize(n) : fallback_n;
    uint32_t v = mesh_add_vertex(m, p, n);
    map_put(map, key, v);
    return v;
}

/* One pass: every edge longer than max_edge is split (red-green
 * refinement: a triangle with 1, 2 or 3 split edges becomes 2, 3 or 4,
 * keeping its orientation). Returns the number of split triangles. */
static uint32_t refine_pass(mesh *m, float max2, edge_map *map)
{
    uint32_t nt = m->nt, split = 0;
    uint32_t *tri = m->tri, *mat = m->mat;
    m->tri = NULL;
    m->mat = NULL;
    m->nt = m->cap_t = 0;
    for (uint32_t t = 0; t < nt; t++) {
        uint32_t v[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
        uint32_t mt = mat[t];
        int mask = 0;
        for (int k = 0; k < 3; k++)
            if (dist2(m->pos[v[k]], m->pos[v[(k + 1) % 3]]) > max2)
                mask |= 1 << k;
        if (!mask) {
            mesh_add_tri(m, v[0], v[1], v[2], mt);
            continue;
        }
        split++;
        gi_vec3 fn = gi_triangle_normal(m->pos[v[0]], m->pos[v[1]], m->pos[v[2]]);
        uint32_t mid[3];
        for (int k = 0; k < 3; k++)
            mid[k] = (mask >> k & 1) ? midpoint(m, map, v[k], v[(k + 1) % 3], fn) : 0;
        int marked = (mask & 1) + (mask >> 1 & 1) + (mask >> 2 & 1);
        if (marked == 3) {
            mesh_add_tri(m, v[0], mid[0], mid[2], mt);
            mesh_add_tri(m, mid[0], v[1], mid[1], mt);
            mesh_add_tri(m, mid[2], mid[1], v[2], mt);
            mesh_add_tri(m, mid[0], mid[1], mid[2], mt);
            continue;
        }
        /* Rotate so that edge 0 is split (one split edge) or edge 2 is the
         * unsplit one (two split edges). */
        int r = 0;
        if (marked == 1)
            r = (mask & 1) ? 0 : (mask & 2) ? 1 : 2;
        else
            r = !(mask & 4) ? 0 : !(mask & 1) ? 1 : 2;
        uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3];
        uint32_t m0 = mid[r], m1 = mid[(r + 1) % 3];
        if (marked == 1) {
            mesh_add_tri(m, a, m0, c, mt);
            mesh_add_tri(m, m0, b, c, mt);
        } else {
            mesh_add_tri(m, m0, b, m1, mt);
            /* The quad (a, m0, m1, c) along its shorter diagonal. */
            if (dist2(m->pos[a], m->pos[m1]) <= dist2(m->pos[m0], m->pos[c])) {
                mesh_add_tri(m, a, m0, m1, mt);
                mesh_add_tri(m, a, m1, c, mt);
            } else {
                mesh_add_tri(m, a, m0, c, mt);
                mesh_add_tri(m, m0, m1, c, mt);
            }
        }
    }
    free(tri);
    free(mat);
    return split;
}

static void mesh_free(mesh *m)
{
    free(m->pos);
    free(m->nrm);
    free(m->tri);
    free(m->mat);
    memset(m, 0, sizeof *m);
}

int gi_detp_refine_scene(gi_scene *s, double max_edge, gi_error *err)
{
    if (!(max_edge > 0.0) || !isfinite(max_edge))
        return gi_fail(err, GI_EINVAL, "%s: subdivision edge length must be positive",
                       s->name);
    const gi_limits *lim = gi_limits_get();
    float max2 = (float)(max_edge * max_edge);
    uint32_t nobj = s->object_count;
    mesh *meshes = gi_xcalloc(nobj ? nobj : 1, sizeof *meshes);
    uint64_t total_v = 0, total_t = 0;
    int rc = 0;
    for (uint32_t o = 0; o < nobj && rc == 0; o++) {
        const gi_object *ob = &s->objects[o];
        mesh *m = &meshes[o];
        for (uint32_t i = 0; i < ob->vertex_count; i++)
            mesh_add_vertex(m, s->positions[ob->first_vertex + i],
                            s->normals[ob->first_vertex + i]);
        for (uint32_t t = 0; t < ob->triangle_count; t++) {
            const uint32_t *ix = &s->indices[3 * (size_t)(ob->first_triangle + t)];
            mesh_add_tri(m, ix[0] - ob->first_vertex, ix[1] - ob->first_vertex,
                         ix[2] - ob->first_vertex, s->tri_material[ob->first_triangle + t]);
        }
        /* Each pass at least halves the split edges; 64 passes would take a
         * 2^64-times longer edge than max_edge. */
        for (int pass = 0; pass < 64; pass++) {
            edge_map map;
            map_init(&map, m->nt);
            uint32_t split = refine_pass(m, max2, &map);
            map_free(&map);
            if (total_v + m->nv > lim->max_scene_vertices ||
                total_t + m->nt > lim->max_scene_triangles) {
                rc = gi_fail(err, GI_EINVAL,
                             "%s: subdividing to edges of %g makes more than %u vertices or %u "
                             "triangles (the scene limits); use a larger subdivision length",
                             s->name, max_edge, lim->max_scene_vertices,
                             lim->max_scene_triangles);
                break;
            }
            if (!split)
                break;
        }
        total_v += m->nv;
        total_t += m->nt;
    }
    if (rc == 0) {
        gi_vec3 *pos = gi_xmalloc((size_t)(total_v + 1) * sizeof *pos);
        gi_vec3 *nrm = gi_xmalloc((size_t)(total_v + 1) * sizeof *nrm);
        uint32_t *idx = gi_xmalloc((size_t)(total_t * 3 + 1) * sizeof *idx);
        uint32_t *tmat = gi_xmalloc((size_t)(total_t + 1) * sizeof *tmat);
        uint32_t *tobj = gi_xmalloc((size_t)(total_t + 1) * sizeof *tobj);
        uint32_t v0 = 0, t0 = 0;
        for (uint32_t o = 0; o < nobj; o++) {
            mesh *m = &meshes[o];
            memcpy(pos + v0, m->pos, m->nv * sizeof *pos);
            memcpy(nrm + v0, m->nrm, m->nv * sizeof *nrm);
            for (uint32_t t = 0; t < m->nt; t++) {
                for (int k = 0; k < 3; k++)
                    idx[3 * (size_t)(t0 + t) + k] = v0 + m->tri[3 * (size_t)t + k];
                tmat[t0 + t] = m->mat[t];
                tobj[t0 + t] = o;
            }
            s->objects[o].first_vertex = v0;
            s->objects[o].vertex_count = m->nv;
            s->objects[o].first_triangle = t0;
            s->objects[o].triangle_count = m->nt;
            v0 += m->nv;
            t0 += m->nt;
        }
        pos[total_v] = nrm[total_v] = gi_v3(0, 0, 0); /* Embree's padded read */
        free(s->positions);
        free(s->normals);
        free(s->indices);
        free(s->tri_material);
        free(s->tri_object);
        s->positions = pos;
        s->normals = nrm;
        s->indices = idx;
        s->tri_material = tmat;
        s->tri_object = tobj;
        s->vertex_count = (uint32_t)total_v;
        s->triangle_count = (uint32_t)total_t;
    }
    for (uint32_t o = 0; o < nobj; o++)
        mesh_free(&meshes[o]);
    free(meshes);
    return rc ? rc : gi_scene_update_derived(s, err);
}

double gi_detp_mean_edge(const gi_scene *s)
{
    edge_map seen;
    map_init(&seen, (size_t)s->triangle_count * 2);
    double sum = 0.0;
    uint64_t n = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const uint32_t *ix = &s->indices[3 * (size_t)t];
        for (int k = 0; k < 3; k++) {
            uint32_t a = ix[k], b = ix[(k + 1) % 3];
            uint64_t key = edge_key(a, b);
            if (seen.keys[map_slot(&seen, key)])
                continue;
            map_put(&seen, key, 1);
            sum += sqrt((double)dist2(s->positions[a], s->positions[b]));
            n++;
        }
    }
    map_free(&seen);
    return n ? sum / (double)n : 0.0;
}

int gi_detp_discs_from_scene(const gi_scene *s, float radius, gi_detp_discs *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    out->d = gi_try_calloc((size_t)s->vertex_count + 1, sizeof *out->d, err, "discs");
    if (!out->d)
        return -1;
    out->count = s->vertex_count;
    out->radius = radius;
    out->r2 = radius * radius;
    for (uint32_t i = 0; i < s->vertex_count; i++) {
        out->d[i].c = s->positions[i];
        out->d[i].n = gi_normalize(s->normals[i]);
    }
    return 0;
}

void gi_detp_vertex_materials(const gi_scene *s, float *rho, float *emission)
{
    double *acc = gi_xcalloc((size_t)s->vertex_count * 7 + 1, sizeof *acc);
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const gi_material *m = gi_scene_tri_material(s, t);
        double a = gi_scene_triangle_area(s, t);
        for (int k = 0; k < 3; k++) {
            double *v = &acc[7 * (size_t)s->indices[3 * (size_t)t + k]];
            v[0] += a * m->diffuse.x;
            v[1] += a * m->diffuse.y;
            v[2] += a * m->diffuse.z;
            v[3] += a * m->emission.x;
            v[4] += a * m->emission.y;
            v[5] += a * m->emission.z;
            v[6] += a;
        }
    }
    for (uint32_t i = 0; i < s->vertex_count; i++) {
        const double *v = &acc[7 * (size_t)i];
        double w = v[6] > 0.0 ? 1.0 / v[6] : 0.0;
        for (int c = 0; c < 3; c++) {
            rho[3 * (size_t)i + c] = (float)(v[c] * w);
            emission[3 * (size_t)i + c] = (float)(v[3 + c] * w);
        }
    }
    free(acc);
}
