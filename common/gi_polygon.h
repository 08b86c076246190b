/* gi_polygon: triangles of one planar polygon face (the scene format's
 * "polygons"), concave ones included. */
#ifndef GI_POLYGON_H
#define GI_POLYGON_H

#include <stdint.h>

#include "gi_math.h"

/* Faces of more vertices than this must be convex (ear clipping is
 * quadratic in them). */
#define GI_POLYGON_MAX_CONCAVE 4096

/* Writes n - 2 triangles (3 indices each, taken from ix) into tris, wound
 * like the polygon. A convex polygon is fanned from its first vertex; a
 * concave one is cut into ears (its plane: Newell's normal). Returns n - 2,
 * or -1 if the polygon is not simple (its edges cross) or is concave with
 * more than GI_POLYGON_MAX_CONCAVE vertices. One without area is fanned
 * (the scene's checks count its degenerate triangles). */
int gi_polygon_triangulate(const gi_vec3 *pos, const uint32_t *ix, int n, uint32_t *tris);

#endif
