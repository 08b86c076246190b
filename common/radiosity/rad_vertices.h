/* rad_vertices: the vertices elements share, for per-vertex outputs (PLY)
 * and Gouraud interpolation in camera images.
 *
 * Corners are welded when they are the same point (bit for bit: the mesh
 * computes lattice points so that shared edges agree exactly) on surfaces
 * with the same material and the same plane orientation. Creases (a wall
 * meeting the floor) and material boundaries keep separate vertices, so
 * radiosity does not bleed around corners. T-junctions where neighbouring
 * trees have different depths stay unwelded (a small shading seam). */
#ifndef GI_RAD_VERTICES_H
#define GI_RAD_VERTICES_H

#include <stdint.h>

#include "gi_error.h"
#include "gi_math.h"
#include "gi_scene.h"
#include "rad_mesh.h"

typedef struct gi_rad_vertices {
    uint32_t count;
    gi_vec3 *positions;
    uint32_t *corner; /* 3 per element: vertex ids, in the element's winding */
} gi_rad_vertices;

int gi_rad_vertices_build(gi_rad_vertices *v, const gi_rad_mesh *m, const gi_scene *s,
                          gi_error *err);
void gi_rad_vertices_free(gi_rad_vertices *v);

/* Per-vertex values from per-element values: the area-weighted mean of the
 * elements around each vertex. elem and out hold 3 floats per element /
 * vertex; area is per element. */
int gi_rad_vertex_values(const gi_rad_vertices *v, uint32_t n, const double *area,
                         const float *elem, float *out, gi_error *err);

#endif
