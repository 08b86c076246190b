/* Unit tests: PLY and JSON outputs. */
#include <stdio.h>
#include <string.h>

#include "gi_fs.h"
#include "gi_image.h"
#include "gi_mesh.h"
#include "gi_ply.h"
#include "gi_test.h"

GI_TEST(test_ply_output_reads_back_through_assimp)
{
    gi_error err;
    gi_vec3 pos[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    float rad[12] = {0.5f, 0.25f, 0.0f, 1, 1, 1, 0, 0, 0, 2, 0.1f, 0.2f};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    char path[600];
    snprintf(path, sizeof path, "%s/out.ply", gi_test_tmpdir());
    GI_REQUIRE_OK(gi_ply_write(path, 4, pos, rad, 2, idx, 0.0, &err));
    gi_buf b;
    gi_buf_init(&b);
    GI_REQUIRE_OK(gi_read_file(path, 1 << 20, &b, &err));
    /* Header + 4 vertices of 27 bytes + 2 faces of 13 bytes. */
    const char *end = strstr((const char *)b.data, "end_header\n");
    GI_REQUIRE(end);
    size_t body = b.len - (size_t)(end + 11 - (const char *)b.data);
    GI_CHECK(body == 4 * 27 + 2 * 13);
    /* Vertex 0's colour: sRGB of 0.5, 0.25, 0. */
    const uint8_t *v0 = (const uint8_t *)end + 11;
    GI_CHECK(v0[12] == gi_srgb8_from_linear(0.5) && v0[13] == gi_srgb8_from_linear(0.25) &&
             v0[14] == 0);
    /* An independent reader (assimp) sees the same geometry. */
    gi_dir_source ds;
    gi_dir_source_init(&ds, gi_test_tmpdir());
    gi_asset_source src = gi_dir_source_as_source(&ds);
    gi_mesh_data m;
    GI_REQUIRE_OK(gi_mesh_import(&src, "out.ply", &m, &err));
    GI_CHECK(m.triangle_count == 2);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&ds);
    gi_buf_free(&b);
    uint32_t bad[3] = {0, 1, 9};
    GI_CHECK(gi_ply_write(path, 4, pos, rad, 1, bad, 0.0, &err) == -1);
}
