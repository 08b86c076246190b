/* rad_mesh: compatible meshes for low-rank radiosity (thesis 3.5, 4.1).
 *
 * Every input triangle of the scene is split 4-way (edge midpoints) until
 * its pieces are no larger than `patch_area`: those pieces are the level-0
 * nodes, the roots of a forest of quadtrees (thesis Fig. 3.10-3.11). Each
 * root is split `levels` more times; the leaves are the elements of the fine
 * mesh. All leaves of a tree have the same area (each split quarters it), so
 * any set of nodes that covers the trees without overlap is a coarse mesh
 * compatible with the elements (thesis 3.5: "compatible meshes").
 *
 * Only the topology is stored: node ids are dense per level,
 *   node (level l) = root * 4^l + (Morton path of l child digits),
 * so an element e = root * 4^L + path, its ancestor at level l is
 * e >> 2(L - l) (within the root's block), and the descendants of a node at
 * level l at level m >= l are a contiguous range. Positions come from the
 * scene at query time, so moving an object moves its elements.
 *
 * Child digits: 0, 1, 2 are the corner triangles at the parent's vertices a,
 * b, c; 3 is the middle one (m_bc, m_ca, m_ab). Every child keeps its
 * parent's orientation, so element triangles face where their input
 * triangle faces. */
#ifndef GI_RAD_MESH_H
#define GI_RAD_MESH_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_math.h"
#include "gi_scene.h"

#define GI_RAD_MAX_LEVELS 10     /* subdivision levels below the roots */
#define GI_RAD_MAX_ROOT_DEPTH 14 /* splits of an input triangle into roots */
#define GI_RAD_MAX_ELEMENTS (1u << 22)

typedef struct gi_rad_mesh {
    uint32_t levels;          /* L: from the roots (level 0) to the elements */
    uint32_t root_count;      /* level-0 nodes */
    uint32_t element_count;   /* n = root_count * 4^L */
    uint32_t tri_count;       /* input triangles (the scene's) */
    uint32_t *tri_first_root; /* tri_count + 1: roots of t are [first[t], first[t+1]) */
    uint8_t *tri_depth;       /* splits from input triangle t to its roots */
    uint32_t *root_tri;       /* input triangle of each root */
    double *root_area;        /* area of each root (its elements: / 4^L) */
} gi_rad_mesh;

/* Builds the forest over every triangle of `s` with positive area. A
 * non-positive patch_area keeps the input triangles as the roots. Fails
 * (GI_EINVAL) if the mesh would exceed the limits above. */
int gi_rad_mesh_build(gi_rad_mesh *m, const gi_scene *s, double patch_area, uint32_t levels,
                      gi_error *err);
void gi_rad_mesh_free(gi_rad_mesh *m);

/* Nodes at level l (0..L). */
static inline uint32_t gi_rad_mesh_nodes(const gi_rad_mesh *m, uint32_t level)
{
    return m->root_count << (2 * level);
}
/* Ancestor of element e at level l. */
static inline uint32_t gi_rad_mesh_ancestor(const gi_rad_mesh *m, uint32_t e, uint32_t level)
{
    return e >> (2 * (m->levels - level));
}
static inline double gi_rad_mesh_element_area(const gi_rad_mesh *m, uint32_t e)
{
    return m->root_area[e >> (2 * m->levels)] / (double)(1u << (2 * m->levels));
}
static inline uint32_t gi_rad_mesh_element_tri(const gi_rad_mesh *m, uint32_t e)
{
    return m->root_tri[e >> (2 * m->levels)];
}

/* The element's corners (in its input triangle's winding). */
void gi_rad_mesh_element_corners(const gi_rad_mesh *m, const gi_scene *s, uint32_t e,
                                 gi_vec3 out[3]);

/* The element containing the point with Embree barycentrics (u, v) on
 * input triangle t (p = (1-u-v) a + u b + v c), and the point's barycentric
 * coordinates in that element (may be NULL). Returns UINT32_MAX if t has no
 * elements (degenerate). */
uint32_t gi_rad_mesh_locate(const gi_rad_mesh *m, uint32_t t, float u, float v, float bary[3]);

#endif
