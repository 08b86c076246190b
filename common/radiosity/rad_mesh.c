/* rad_mesh: the forest of quadtrees over the scene's triangles. */
#include "rad_mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int gi_rad_mesh_build(gi_rad_mesh *m, const gi_scene *s, double patch_area, uint32_t levels,
                      gi_error *err)
{
    memset(m, 0, sizeof *m);
    if (levels > GI_RAD_MAX_LEVELS)
        return gi_fail(err, GI_EINVAL, "radiosity mesh: %u levels (limit %d)", levels,
                       GI_RAD_MAX_LEVELS);
    m->levels = levels;
    m->tri_count = s->triangle_count;
    m->tri_first_root = gi_xcalloc((size_t)s->triangle_count + 1, sizeof *m->tri_first_root);
    m->tri_depth = gi_xcalloc(s->triangle_count ? s->triangle_count : 1, 1);
    /* Depths first, to size the arrays and check the limits before
     * allocating anything input-sized. */
    uint64_t roots = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        m->tri_first_root[t] = (uint32_t)roots;
        double a = gi_scene_triangle_area(s, t);
        if (!(a > 0.0) || !isfinite(a))
            continue; /* degenerate: no elements (rays never hit it) */
        uint32_t d = 0;
        /* The tolerance keeps triangles that are patch_area up to the
         * rounding of their single-precision vertices from being split
         * once more. */
        while (patch_area > 0.0 && a > patch_area * (1.0 + 1e-5)) {
            a *= 0.25;
            if (++d > GI_RAD_MAX_ROOT_DEPTH) {
                gi_rad_mesh_free(m);
                return gi_fail(err, GI_EINVAL,
                               "radiosity mesh: triangle %u needs more than %d splits to reach "
                               "the patch size (too many patches)",
                               t, GI_RAD_MAX_ROOT_DEPTH);
            }
        }
        m->tri_depth[t] = (uint8_t)d;
        roots += (uint64_t)1 << (2 * d);
        if ((roots << (2 * levels)) > GI_RAD_MAX_ELEMENTS) {
            gi_rad_mesh_free(m);
            return gi_fail(err, GI_EINVAL,
                           "radiosity mesh: more than %u elements (fewer patches or levels)",
                           GI_RAD_MAX_ELEMENTS);
        }
    }
    m->tri_first_root[s->triangle_count] = (uint32_t)roots;
    if (roots == 0) {
        gi_rad_mesh_free(m);
        return gi_fail(err, GI_EINVAL, "radiosity mesh: the scene has no surface");
    }
    m->root_count = (uint32_t)roots;
    m->element_count = (uint32_t)(roots << (2 * levels));
    m->root_tri = gi_xmalloc(roots * sizeof *m->root_tri);
    m->root_area = gi_xmalloc(roots * sizeof *m->root_area);
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        uint32_t r0 = m->tri_first_root[t], r1 = m->tri_first_root[t + 1];
        double a = r1 > r0 ? gi_scene_triangle_area(s, t) / (double)(r1 - r0) : 0.0;
        for (uint32_t r = r0; r < r1; r++) {
            m->root_tri[r] = t;
            m->root_area[r] = a;
        }
    }
    return 0;
}

void gi_rad_mesh_free(gi_rad_mesh *m)
{
    free(m->tri_first_root);
    free(m->tri_depth);
    free(m->root_tri);
    free(m->root_area);
    memset(m, 0, sizeof *m);
}

/* Lattice coordinates of a node's corners: integer barycentric triples
 * scaled by 2^depth, so midpoints stay integers and a point shared by two
 * nodes has the same triple in both. */
typedef struct lattice {
    uint32_t c[3][3];
} lattice;

static void lattice_child(lattice *l, unsigned digit)
{
    uint32_t mid[3][3]; /* m_ab, m_bc, m_ca */
    for (int k = 0; k < 3; k++) {
        mid[0][k] = (l->c[0][k] + l->c[1][k]) / 2;
        mid[1][k] = (l->c[1][k] + l->c[2][k]) / 2;
        mid[2][k] = (l->c[2][k] + l->c[0][k]) / 2;
    }
    lattice n;
    for (int k = 0; k < 3; k++) {
        switch (digit) {
        case 0:
            n.c[0][k] = l->c[0][k];
            n.c[1][k] = mid[0][k];
            n.c[2][k] = mid[2][k];
            break;
        case 1:
            n.c[0][k] = mid[0][k];
            n.c[1][k] = l->c[1][k];
            n.c[2][k] = mid[1][k];
            break;
        case 2:
            n.c[0][k] = mid[2][k];
            n.c[1][k] = mid[1][k];
            n.c[2][k] = l->c[2][k];
            break;
        default:
            n.c[0][k] = mid[1][k];
            n.c[1][k] = mid[2][k];
            n.c[2][k] = mid[0][k];
            break;
        }
    }
    *l = n;
}

void gi_rad_mesh_element_corners(const gi_rad_mesh *m, const gi_scene *s, uint32_t e,
                                 gi_vec3 out[3])
{
    uint32_t root = e >> (2 * m->levels), t = m->root_tri[root];
    uint32_t d = m->tri_depth[t], depth = d + m->levels;
    uint32_t N = 1u << depth;
    lattice l = {{{N, 0, 0}, {0, N, 0}, {0, 0, N}}};
    /* Root digits (its Morton index inside t), then the element's. */
    uint32_t morton = root - m->tri_first_root[t];
    for (uint32_t i = d; i-- > 0;)
        lattice_child(&l, (morton >> (2 * i)) & 3);
    for (uint32_t i = m->levels; i-- > 0;)
        lattice_child(&l, (e >> (2 * i)) & 3);
    gi_vec3 a, b, c;
    gi_scene_triangle(s, t, &a, &b, &c);
    /* (i a + j b) + k c in double, then / N (exact: a power of two). Two
     * triangles sharing an edge compute its lattice points from the same
     * two products (the third is zero), and addition commutes, so the
     * points agree bit for bit; + 0.0 turns a -0 into +0. */
    for (int v = 0; v < 3; v++) {
        double w0 = l.c[v][0], w1 = l.c[v][1], w2 = l.c[v][2];
        double x = (w0 * a.x + w1 * b.x) + w2 * c.x;
        double y = (w0 * a.y + w1 * b.y) + w2 * c.y;
        double z = (w0 * a.z + w1 * b.z) + w2 * c.z;
        out[v] = gi_v3((float)(x / N + 0.0), (float)(y / N + 0.0), (float)(z / N + 0.0));
    }
}

/* One step down: the child containing the point, and the point's
 * coordinates in it (the children's corners are those of lattice_child).
 * Inlined so that b stays in registers: as a call, b went through memory at
 * every level of every form-factor ray. */
static inline __attribute__((always_inline)) unsigned descend(double b[3])
{
    if (b[0] >= 0.5) {
        b[0] = 2.0 * b[0] - 1.0, b[1] *= 2.0, b[2] *= 2.0;
        return 0;
    }
    if (b[1] >= 0.5) {
        b[0] *= 2.0, b[1] = 2.0 * b[1] - 1.0, b[2] *= 2.0;
        return 1;
    }
    if (b[2] >= 0.5) {
        b[0] *= 2.0, b[1] *= 2.0, b[2] = 2.0 * b[2] - 1.0;
        return 2;
    }
    b[0] = 1.0 - 2.0 * b[0], b[1] = 1.0 - 2.0 * b[1], b[2] = 1.0 - 2.0 * b[2];
    return 3;
}

uint32_t gi_rad_mesh_locate(const gi_rad_mesh *m, uint32_t t, float u, float v, float bary[3])
{
    if (t >= m->tri_count || m->tri_first_root[t] == m->tri_first_root[t + 1])
        return UINT32_MAX;
    double b[3] = {1.0 - (double)u - (double)v, u, v};
    uint32_t morton = 0, path = 0;
    for (uint32_t i = 0; i < m->tri_depth[t]; i++)
        morton = (morton << 2) | descend(b);
    for (uint32_t i = 0; i < m->levels; i++)
        path = (path << 2) | descend(b);
    if (bary) {
        /* Rounding in (u, v) can leave a coordinate slightly outside. */
        double sum = 0.0;
        for (int k = 0; k < 3; k++) {
            b[k] = b[k] < 0.0 ? 0.0 : b[k] > 1.0 ? 1.0 : b[k];
            sum += b[k];
        }
        for (int k = 0; k < 3; k++)
            bary[k] = (float)(sum > 0.0 ? b[k] / sum : 1.0 / 3.0);
    }
    return ((m->tri_first_root[t] + morton) << (2 * m->levels)) | path;
}
