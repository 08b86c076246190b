/* Tests for gi_mesh_wire: the importer child's mesh message round-trips,
 * and a message that breaks what the child's conversion guarantees is
 * refused by the parent. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_buf.h"
#include "gi_mesh_wire.h"
#include "gi_test.h"

static void two_triangles(gi_mesh_data *m)
{
    gi_mesh_data_init(m);
    gi_mesh_quad(m, 1.0, 1.0);
}

GI_TEST(mesh_wire_round_trip)
{
    gi_mesh_data m, d;
    two_triangles(&m);
    gi_buf b;
    gi_buf_init(&b);
    gi_mesh_encode(&b, &m);
    gi_error err;
    gi_mesh_data_init(&d);
    GI_REQUIRE_OK(gi_mesh_decode(b.data, b.len, "q.obj", &d, &err));
    GI_CHECK(d.vertex_count == m.vertex_count && d.triangle_count == m.triangle_count);
    GI_CHECK(d.material_count == m.material_count && (d.normals != NULL) == (m.normals != NULL));
    GI_CHECK(memcmp(d.positions, m.positions, m.vertex_count * sizeof *m.positions) == 0);
    GI_CHECK(memcmp(d.indices, m.indices, 3 * m.triangle_count * sizeof *m.indices) == 0);
    GI_CHECK(strcmp(d.materials[0].name, m.materials[0].name) == 0);
    gi_mesh_data_free(&d);
    gi_mesh_data_free(&m);
    gi_buf_free(&b);
}

/* Each case breaks one thing in a good mesh before it is encoded. */
GI_TEST(mesh_wire_refuses_what_the_conversion_never_sends)
{
    static const char *const expect[] = {"triangle 1 uses vertex 4 of 4",
                                         "triangle 0 uses material 1 of 1",
                                         "vertex 2 is not finite", "vertex 3 is not finite",
                                         "bad mesh"};
    for (int c = 0; c < (int)GI_ARRAY_LEN(expect); c++) {
        gi_mesh_data m, d;
        two_triangles(&m);
        GI_REQUIRE(m.vertex_count == 4 && m.triangle_count == 2 && m.material_count == 1 &&
                   m.normals);
        if (c == 0)
            m.indices[4] = 4;
        if (c == 1)
            m.tri_material[0] = 1;
        if (c == 2)
            m.positions[2].y = NAN;
        if (c == 3)
            m.normals[3].z = INFINITY;
        gi_buf b;
        gi_buf_init(&b);
        gi_mesh_encode(&b, &m);
        if (c == 4)
            b.data[12] = 2; /* the has-normals flag */
        gi_error err;
        gi_error_clear(&err);
        gi_mesh_data_init(&d);
        GI_CHECK_MSG(gi_mesh_decode(b.data, b.len, "q.obj", &d, &err) == -1 &&
                         strstr(err.msg, "q.obj") && strstr(err.msg, expect[c]),
                     "case %d: %s", c, err.msg);
        gi_mesh_data_free(&d);
        gi_mesh_data_free(&m);
        gi_buf_free(&b);
    }
}

/* The longest name the conversion makes (GI_MESH_NAME_MAX bytes, made
 * unique with the largest "#<index>") reaches the parent; a longer one
 * is not something the child sends. */
GI_TEST(mesh_wire_carries_the_longest_material_name)
{
    for (int extra = 0; extra < 2; extra++) {
        gi_mesh_data m, d;
        two_triangles(&m);
        size_t n = GI_MESH_NAME_MAX + strlen("#4294967295") + (size_t)extra;
        free(m.materials[0].name);
        m.materials[0].name = gi_xmalloc(n + 1);
        memset(m.materials[0].name, 'n', n);
        m.materials[0].name[n] = '\0';
        gi_buf b;
        gi_buf_init(&b);
        gi_mesh_encode(&b, &m);
        gi_error err;
        gi_error_clear(&err);
        gi_mesh_data_init(&d);
        int rc = gi_mesh_decode(b.data, b.len, "q.obj", &d, &err);
        if (extra == 0)
            GI_CHECK_MSG(rc == 0 && strcmp(d.materials[0].name, m.materials[0].name) == 0, "%s",
                         err.msg);
        else
            GI_CHECK_MSG(rc == -1 && strstr(err.msg, "q.obj"), "a %zu-byte name decoded", n);
        gi_mesh_data_free(&d);
        gi_mesh_data_free(&m);
        gi_buf_free(&b);
    }
}
