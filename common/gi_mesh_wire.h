/* gi_mesh_wire: a gi_mesh_data as bytes, from the importer child to its
 * parent (gi_mesh_import: assimp runs in a forked child). */
#ifndef GI_MESH_WIRE_H
#define GI_MESH_WIRE_H

#include "gi_buf.h"
#include "gi_mesh.h"

/* Appends the mesh to b. The child is this program on this host: the
 * arrays go as their bytes. */
void gi_mesh_encode(gi_buf *b, const gi_mesh_data *m);

/* Reads a mesh that gi_mesh_encode wrote, into a freshly initialized m. The
 * child ran assimp over the file's bytes: its answer is checked like input
 * (counts against the bytes before any allocation, every index and
 * material in range, finite points and normals), so that a child that
 * went wrong cannot hand the parent a mesh that reads out of bounds.
 * Fails (GI_EINTERNAL, naming `name`) otherwise; m may then hold partial
 * arrays (gi_mesh_data_free them). */
int gi_mesh_decode(const void *data, size_t len, const char *name, gi_mesh_data *m,
                   gi_error *err);

#endif
