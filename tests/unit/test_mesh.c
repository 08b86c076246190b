/* Tests for gi_mesh: import through assimp (OBJ+MTL, PLY ascii/binary, glTF
 * .gltf/.glb, malformed files), built-in shapes, normals, append. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_assets.h"
#include "gi_buf.h"
#include "gi_fs.h"
#include "gi_mesh.h"
#include "gi_test.h"

/* ---- helpers ---------------------------------------------------------- */

static double mesh_area(const gi_mesh_data *m)
{
    double a = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * t];
        gi_vec3 e1 = gi_sub(m->positions[ix[1]], m->positions[ix[0]]);
        gi_vec3 e2 = gi_sub(m->positions[ix[2]], m->positions[ix[0]]);
        a += 0.5 * gi_length(gi_cross(e1, e2));
    }
    return a;
}

/* Divergence theorem: V = 1/6 sum a . (b x c); positive when the surface is
 * closed and wound counter-clockwise seen from outside. */
static double mesh_volume(const gi_mesh_data *m)
{
    double v = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * t];
        gi_vec3 a = m->positions[ix[0]], b = m->positions[ix[1]], c = m->positions[ix[2]];
        v += (double)gi_dot(a, gi_cross(b, c)) / 6.0;
    }
    return v;
}

static gi_vec3 tri_normal(const gi_mesh_data *m, uint32_t t)
{
    const uint32_t *ix = &m->indices[3 * t];
    gi_vec3 e1 = gi_sub(m->positions[ix[1]], m->positions[ix[0]]);
    gi_vec3 e2 = gi_sub(m->positions[ix[2]], m->positions[ix[0]]);
    return gi_normalize(gi_cross(e1, e2));
}

static int near3(gi_vec3 a, gi_vec3 b, float tol)
{
    return fabsf(a.x - b.x) <= tol && fabsf(a.y - b.y) <= tol && fabsf(a.z - b.z) <= tol;
}

static int find_vertex(const gi_mesh_data *m, gi_vec3 p)
{
    for (uint32_t i = 0; i < m->vertex_count; i++)
        if (near3(m->positions[i], p, 1e-5f))
            return (int)i;
    return -1;
}

static int find_material(const gi_mesh_data *m, const char *name)
{
    for (uint32_t i = 0; i < m->material_count; i++)
        if (m->materials[i].name && strcmp(m->materials[i].name, name) == 0)
            return (int)i;
    return -1;
}

static int indices_valid(const gi_mesh_data *m)
{
    for (uint32_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->indices[i] >= m->vertex_count)
            return 0;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        if (m->tri_material[t] >= m->material_count)
            return 0;
    return 1;
}

static char *data_dir(void)
{
    return gi_path_join(gi_test_srcdir(), "tests/data/meshes");
}

/* Imports root/file through a directory source the caller frees. */
static int import_from(const char *root, const char *file, gi_dir_source *d, gi_mesh_data *m,
                       gi_error *err)
{
    gi_dir_source_init(d, root);
    gi_asset_source src = gi_dir_source_as_source(d);
    gi_error_clear(err);
    return gi_mesh_import(&src, file, m, err);
}

/* Imports tests/data/meshes/<file>. */
static int import_data(const char *file, gi_dir_source *d, gi_mesh_data *m, gi_error *err)
{
    char *dir = data_dir();
    int rc = import_from(dir, file, d, m, err);
    free(dir);
    return rc;
}

/* Writes bytes to <tmpdir>/<name>, creating directories. */
static void write_tmp(const char *name, const void *data, size_t len)
{
    char *path = gi_path_join(gi_test_tmpdir(), name);
    char *dir = gi_dirname(path);
    gi_error err;
    if (gi_mkdirs(dir, &err) || gi_write_file_atomic(path, data, len, &err))
        gi_test_failed(__FILE__, __LINE__, "writing %s: %s", path, err.msg);
    free(dir);
    free(path);
}

/* The buffer of tests/data/meshes/make_gltf.py: quad positions, normals,
 * uint16 indices (108 bytes). */
static void gltf_buffer(gi_buf *b)
{
    static const float pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    static const uint16_t ix[6] = {0, 1, 2, 0, 2, 3};
    for (int i = 0; i < 4; i++)
        gi_buf_put_f32s(b, pos[i], 3);
    for (int i = 0; i < 4; i++) {
        const float n[3] = {0, 0, 1};
        gi_buf_put_f32s(b, n, 3);
    }
    for (int i = 0; i < 6; i++)
        gi_buf_put_u16(b, ix[i]);
}

/* The document of make_gltf.py; `uri_member` is `"uri": "..." ,` or "". */
static char *gltf_json(const char *uri_member)
{
    static const char fmt[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],"
        "\"nodes\": [{\"translation\": [1, 2, 3], \"children\": [1]},"
        " {\"rotation\": [0.7071067811865476, 0, 0, 0.7071067811865476],"
        "  \"scale\": [2, 2, 2], \"mesh\": 0}],"
        "\"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1},"
        " \"indices\": 2, \"material\": 0, \"mode\": 4}]}],"
        "\"materials\": [{\"name\": \"glow\", \"pbrMetallicRoughness\":"
        " {\"baseColorFactor\": [0.2, 0.4, 0.6, 1.0]}, \"emissiveFactor\": [0.5, 0.25, 1.0]}],"
        "\"buffers\": [{%s\"byteLength\": 108}],"
        "\"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 96,"
        " \"byteStride\": 12, \"target\": 34962},"
        " {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 12, \"target\": 34963}],"
        "\"accessors\": [{\"bufferView\": 0, \"byteOffset\": 0, \"componentType\": 5126,"
        " \"count\": 4, \"type\": \"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},"
        " {\"bufferView\": 0, \"byteOffset\": 48, \"componentType\": 5126, \"count\": 4,"
        "  \"type\": \"VEC3\"},"
        " {\"bufferView\": 1, \"byteOffset\": 0, \"componentType\": 5123, \"count\": 6,"
        "  \"type\": \"SCALAR\"}]}";
    size_t n = sizeof fmt + strlen(uri_member);
    char *s = gi_xmalloc(n);
    snprintf(s, n, fmt, uri_member);
    return s;
}

/* GLB container (glTF 2.0 spec, "Binary glTF Layout"): 12-byte header,
 * JSON chunk padded with spaces, BIN chunk padded with zeros. */
static void make_glb(gi_buf *out)
{
    char *json = gltf_json("");
    gi_buf bin;
    gi_buf_init(&bin);
    gltf_buffer(&bin);
    size_t jl = strlen(json), jpad = (4 - jl % 4) % 4, bpad = (4 - bin.len % 4) % 4;
    gi_buf_put_u32(out, 0x46546C67u); /* "glTF" */
    gi_buf_put_u32(out, 2);
    gi_buf_put_u32(out, (uint32_t)(12 + 8 + jl + jpad + 8 + bin.len + bpad));
    gi_buf_put_u32(out, (uint32_t)(jl + jpad));
    gi_buf_put_u32(out, 0x4E4F534Au); /* "JSON" */
    gi_buf_put(out, json, jl);
    for (size_t i = 0; i < jpad; i++)
        gi_buf_put_u8(out, ' ');
    gi_buf_put_u32(out, (uint32_t)(bin.len + bpad));
    gi_buf_put_u32(out, 0x004E4942u); /* "BIN\0" */
    gi_buf_put(out, bin.data, bin.len);
    for (size_t i = 0; i < bpad; i++)
        gi_buf_put_u8(out, 0);
    gi_buf_free(&bin);
    free(json);
}

/* Checks the mesh of make_gltf.py after its node transforms: parent
 * translation (1,2,3) after child rotation +90 deg about x and scale 2, so
 * (x, y, 0) -> (1 + 2x, 2, 3 + 2y) and the normal +z -> -y. */
static void check_transformed_quad(const gi_mesh_data *m)
{
    GI_CHECK(m->vertex_count == 4);
    GI_CHECK(m->triangle_count == 2);
    GI_CHECK(indices_valid(m));
    static const float want[4][3] = {{1, 2, 3}, {3, 2, 3}, {3, 2, 5}, {1, 2, 5}};
    for (int i = 0; i < 4; i++)
        GI_CHECK_MSG(find_vertex(m, gi_v3(want[i][0], want[i][1], want[i][2])) >= 0,
                     "vertex (%g, %g, %g) missing", want[i][0], want[i][1], want[i][2]);
    GI_CHECK(m->normals != NULL);
    for (uint32_t i = 0; m->normals && i < m->vertex_count; i++)
        GI_CHECK(near3(m->normals[i], gi_v3(0, -1, 0), 1e-5f));
    for (uint32_t t = 0; t < m->triangle_count; t++)
        GI_CHECK(near3(tri_normal(m, t), gi_v3(0, -1, 0), 1e-5f));
    GI_CHECK_NEAR(mesh_area(m), 4.0, 1e-5);
    GI_REQUIRE(m->material_count == 1);
    GI_CHECK(strcmp(m->materials[0].name, "glow") == 0);
    GI_CHECK(near3(m->materials[0].diffuse, gi_v3(0.2f, 0.4f, 0.6f), 1e-6f));
    GI_CHECK(near3(m->materials[0].emission, gi_v3(0.5f, 0.25f, 1.0f), 1e-6f));
}

/* ---- import ----------------------------------------------------------- */

GI_TEST(mesh_import_obj_materials)
{
    gi_error err;
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_data("two_materials.obj", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        /* The quad became two triangles; identical vertices were joined. */
        GI_CHECK(m.vertex_count == 7);
        GI_CHECK(m.triangle_count == 3);
        GI_CHECK(indices_valid(&m));
        GI_CHECK(m.normals != NULL);
        GI_CHECK(m.material_count == 2);
        int white = find_material(&m, "white"), light = find_material(&m, "light");
        GI_REQUIRE(white >= 0 && light >= 0);
        GI_CHECK(near3(m.materials[white].diffuse, gi_v3(0.7f, 0.6f, 0.5f), 1e-6f));
        GI_CHECK(gi_is_black(m.materials[white].emission));
        GI_CHECK(near3(m.materials[light].diffuse, gi_v3(0, 0, 0), 1e-6f));
        GI_CHECK(near3(m.materials[light].emission, gi_v3(10, 9, 8), 1e-5f));
        uint32_t white_tris = 0;
        for (uint32_t t = 0; t < m.triangle_count; t++) {
            int is_white = m.tri_material[t] == (uint32_t)white;
            white_tris += (uint32_t)is_white;
            /* The floor faces +y, the light -y, as their normals say. */
            gi_vec3 want = is_white ? gi_v3(0, 1, 0) : gi_v3(0, -1, 0);
            GI_CHECK(near3(tri_normal(&m, t), want, 1e-6f));
            for (int k = 0; m.normals && k < 3; k++)
                GI_CHECK(near3(m.normals[m.indices[3 * t + k]], want, 1e-6f));
        }
        GI_CHECK(white_tris == 2);
        GI_CHECK_NEAR(mesh_area(&m), 4.0 + 0.125, 1e-6);
        GI_CHECK(find_vertex(&m, gi_v3(-1, 0, -1)) >= 0);
        GI_CHECK(find_vertex(&m, gi_v3(0, 1, 0.5f)) >= 0);
    }
    /* The .mtl came through the source: the manifest lists both files. */
    GI_CHECK(gi_manifest_find(&d.manifest, "two_materials.obj") != NULL);
    GI_CHECK(gi_manifest_find(&d.manifest, "two_materials.mtl") != NULL);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_obj_without_normals)
{
    gi_error err;
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_data("no_normals.obj", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        GI_CHECK(m.vertex_count == 7);
        GI_CHECK(m.triangle_count == 6);
        GI_CHECK(indices_valid(&m));
        GI_CHECK(m.normals == NULL);
        GI_REQUIRE(m.material_count == 1);
        GI_CHECK(strcmp(m.materials[0].name, "default") == 0);
        GI_CHECK(near3(m.materials[0].diffuse, gi_v3(0.8f, 0.8f, 0.8f), 1e-6f));
        GI_CHECK(gi_is_black(m.materials[0].emission));
        GI_CHECK_NEAR(mesh_area(&m), 3.0, 1e-6);
        /* What the scene does next: the three faces meet at 90 degrees, so
         * every vertex is split per face (the corner in three) and each
         * copy has its face's normal, not the diagonal mean. */
        gi_mesh_compute_normals(&m);
        GI_CHECK(m.vertex_count == 12 && m.triangle_count == 6);
        GI_CHECK(indices_valid(&m));
        for (uint32_t t = 0; t < m.triangle_count; t++)
            for (int k = 0; k < 3; k++)
                GI_CHECK(near3(m.normals[m.indices[3 * t + k]], tri_normal(&m, t), 1e-6f));
        GI_CHECK_NEAR(mesh_area(&m), 3.0, 1e-6);
    }
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_obj_missing_mtl_uses_default)
{
    /* assimp reports the missing library as a warning and imports the
     * geometry; the triangle gets the default material. */
    gi_error err;
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_data("missing_mtl.obj", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        GI_CHECK(m.triangle_count == 1);
        GI_REQUIRE(m.material_count == 1);
        GI_CHECK(near3(m.materials[0].diffuse, gi_v3(0.8f, 0.8f, 0.8f), 1e-6f));
        GI_CHECK(gi_is_black(m.materials[0].emission));
        GI_CHECK(m.tri_material[0] == 0);
    }
    GI_CHECK(gi_manifest_find(&d.manifest, "nowhere.mtl") == NULL);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_ply_ascii)
{
    gi_error err;
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_data("ascii.ply", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        GI_CHECK(m.vertex_count == 5);
        GI_CHECK(m.triangle_count == 6);
        GI_CHECK(indices_valid(&m));
        GI_CHECK(m.normals == NULL);
        GI_CHECK(m.material_count == 1);
        GI_CHECK(near3(m.materials[0].diffuse, gi_v3(0.8f, 0.8f, 0.8f), 1e-6f));
        GI_CHECK(find_vertex(&m, gi_v3(0, 2, 0)) >= 0);
        /* Square pyramid, base 2 x 2, height 2. */
        GI_CHECK_NEAR(mesh_area(&m), 4.0 + 4.0 * sqrt(5.0), 1e-5);
        GI_CHECK_NEAR(mesh_volume(&m), 8.0 / 3.0, 1e-5);
    }
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

/* A binary little-endian PLY quad with normals, written at runtime. */
static void binary_ply(gi_buf *b)
{
    static const char header[] = "ply\nformat binary_little_endian 1.0\n"
                                 "element vertex 4\nproperty float x\nproperty float y\n"
                                 "property float z\nproperty float nx\nproperty float ny\n"
                                 "property float nz\nelement face 1\n"
                                 "property list uchar int vertex_indices\nend_header\n";
    gi_buf_put(b, header, sizeof header - 1);
    static const float p[4][3] = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};
    for (int i = 0; i < 4; i++) {
        const float n[3] = {0, 1, 0};
        gi_buf_put_f32s(b, p[i], 3);
        gi_buf_put_f32s(b, n, 3);
    }
    gi_buf_put_u8(b, 4);
    for (uint32_t i = 0; i < 4; i++)
        gi_buf_put_u32(b, i);
}

GI_TEST(mesh_import_ply_binary)
{
    gi_error err;
    gi_buf b;
    gi_buf_init(&b);
    binary_ply(&b);
    write_tmp("binary.ply", b.data, b.len);
    gi_buf_free(&b);
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_from(gi_test_tmpdir(), "binary.ply", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        GI_CHECK(m.vertex_count == 4);
        GI_CHECK(m.triangle_count == 2);
        GI_CHECK(indices_valid(&m));
        GI_CHECK(m.normals != NULL);
        for (uint32_t i = 0; m.normals && i < m.vertex_count; i++)
            GI_CHECK(near3(m.normals[i], gi_v3(0, 1, 0), 1e-6f));
        for (uint32_t t = 0; t < m.triangle_count; t++)
            GI_CHECK(near3(tri_normal(&m, t), gi_v3(0, 1, 0), 1e-6f));
        GI_CHECK_NEAR(mesh_area(&m), 4.0, 1e-6);
    }
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_gltf_pretransform)
{
    gi_error err;
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_data("transformed.gltf", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0)
        check_transformed_quad(&m);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_glb)
{
    gi_error err;
    gi_buf glb;
    gi_buf_init(&glb);
    make_glb(&glb);
    write_tmp("quad.glb", glb.data, glb.len);
    gi_buf_free(&glb);
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_from(gi_test_tmpdir(), "quad.glb", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0)
        check_transformed_quad(&m);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_manifest_records_referenced_files)
{
    /* Files in a subdirectory, referenced as "./x": the names assimp asks
     * for ("sub/./x") reach the source normalized. */
    gi_error err;
    static const char obj[] = "mtllib ./m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
    static const char mtl[] = "newmtl red\nKd 0.5 0 0\n";
    write_tmp("sub/m.obj", obj, sizeof obj - 1);
    write_tmp("sub/m.mtl", mtl, sizeof mtl - 1);
    char *json = gltf_json("\"uri\": \"./ext.bin\", ");
    write_tmp("sub/ext.gltf", json, strlen(json));
    free(json);
    gi_buf bin;
    gi_buf_init(&bin);
    gltf_buffer(&bin);
    write_tmp("sub/ext.bin", bin.data, bin.len);
    gi_buf_free(&bin);

    gi_dir_source d;
    gi_dir_source_init(&d, gi_test_tmpdir());
    gi_asset_source src = gi_dir_source_as_source(&d);
    gi_mesh_data m;
    int rc = gi_mesh_import(&src, "sub/m.obj", &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        GI_REQUIRE(m.material_count == 1);
        GI_CHECK(strcmp(m.materials[0].name, "red") == 0);
        GI_CHECK(near3(m.materials[0].diffuse, gi_v3(0.5f, 0, 0), 1e-6f));
    }
    gi_mesh_data_free(&m);
    rc = gi_mesh_import(&src, "sub/ext.gltf", &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0)
        check_transformed_quad(&m);
    gi_mesh_data_free(&m);
    GI_CHECK(gi_manifest_find(&d.manifest, "sub/m.obj") != NULL);
    GI_CHECK(gi_manifest_find(&d.manifest, "sub/m.mtl") != NULL);
    GI_CHECK(gi_manifest_find(&d.manifest, "sub/ext.gltf") != NULL);
    const gi_manifest_entry *e = gi_manifest_find(&d.manifest, "sub/ext.bin");
    GI_CHECK(e != NULL && e->size == 108);
    for (size_t i = 0; i < d.manifest.count; i++)
        GI_CHECK_MSG(strstr(d.manifest.entries[i].name, "./") == NULL,
                     "unnormalized name %s in the manifest", d.manifest.entries[i].name);

    /* The same import from the manifest alone (as on a farm worker): every
     * file assimp needs is among the job's assets. */
    gi_manifest_source ms = {&d.manifest, d.store, NULL, NULL};
    gi_asset_source msrc = gi_manifest_source_as_source(&ms);
    rc = gi_mesh_import(&msrc, "sub/ext.gltf", &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0)
        check_transformed_quad(&m);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_drops_points_and_lines)
{
    gi_error err;
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nv 6 6 6\n"
                              "f 1 2 3\nl 4 5\np 4\n";
    write_tmp("mixed.obj", obj, sizeof obj - 1);
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_from(gi_test_tmpdir(), "mixed.obj", &d, &m, &err);
    GI_CHECK_OK(rc);
    if (rc == 0) {
        GI_CHECK(m.triangle_count == 1);
        GI_CHECK(m.vertex_count == 3);
        GI_CHECK(indices_valid(&m));
        GI_CHECK(find_vertex(&m, gi_v3(5, 5, 5)) < 0);
    }
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

/* Expects the import of `file` from `root` to fail with GI_EINVAL (or
 * `code`) and a message naming `file` and containing `also` (if given). */
static void expect_failure(const char *root, const char *file, gi_errcode code,
                           const char *also)
{
    gi_error err;
    gi_dir_source d;
    gi_mesh_data m;
    int rc = import_from(root, file, &d, &m, &err);
    GI_CHECK_MSG(rc == -1, "%s: import succeeded", file);
    if (rc == -1) {
        GI_CHECK_MSG(err.code == code, "%s: code %s, want %s (%s)", file,
                     gi_errcode_name(err.code), gi_errcode_name(code), err.msg);
        GI_CHECK_MSG(strstr(err.msg, file) != NULL, "message does not name %s: %s", file,
                     err.msg);
        GI_CHECK_MSG(!also || strstr(err.msg, also) != NULL, "message lacks \"%s\": %s",
                     also, err.msg);
        GI_CHECK_MSG(strchr(err.msg, '\n') == NULL, "multi-line message: %s", err.msg);
        /* Nothing is left allocated in the output on failure. */
        GI_CHECK(m.vertex_count == 0 && m.positions == NULL && m.materials == NULL);
    }
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

GI_TEST(mesh_import_malformed_files)
{
    char *dir = data_dir();
    expect_failure(dir, "empty.obj", GI_EINVAL, NULL);
    expect_failure(dir, "bad_index.obj", GI_EINVAL, NULL);
    /* assimp drops the face and keeps the rest; refused as the OBJ is. */
    expect_failure(dir, "bad_index.gltf", GI_EINVAL, "vertex index out of range");
    expect_failure(dir, "truncated.ply", GI_EINVAL, NULL);
    expect_failure(dir, "missing_bin.gltf", GI_EINVAL, "missing.bin");
    expect_failure(dir, "does_not_exist.obj", GI_EINVAL, NULL);
    /* Garbled PLYs on which assimp (5.2.5) fails an assertion and aborts,
     * or loops for ever (fuzz_mesh): its child process dies or is killed
     * after 5 s, and this one reports the file. */
    expect_failure(dir, "assimp_abort.ply", GI_EINVAL, NULL);
    expect_failure(dir, "assimp_hang.ply", GI_EINVAL, NULL);
    free(dir);

    /* Garbage bytes, under an unknown extension and under known ones. */
    unsigned char junk[512];
    uint32_t x = 12345;
    for (size_t i = 0; i < sizeof junk; i++) {
        x = x * 1664525u + 1013904223u; /* LCG (Numerical Recipes) */
        junk[i] = (unsigned char)(x >> 24);
    }
    write_tmp("garbage.dat", junk, sizeof junk);
    write_tmp("garbage.ply", junk, sizeof junk);
    write_tmp("garbage.glb", junk, sizeof junk);
    expect_failure(gi_test_tmpdir(), "garbage.dat", GI_EINVAL, NULL);
    expect_failure(gi_test_tmpdir(), "garbage.ply", GI_EINVAL, NULL);
    expect_failure(gi_test_tmpdir(), "garbage.glb", GI_EINVAL, NULL);

    /* A binary PLY cut in the middle of its face list. */
    gi_buf b;
    gi_buf_init(&b);
    binary_ply(&b);
    write_tmp("truncated_bin.ply", b.data, b.len - 6);
    gi_buf_free(&b);
    expect_failure(gi_test_tmpdir(), "truncated_bin.ply", GI_EINVAL, NULL);

    /* A GLB whose BIN chunk is cut short. */
    gi_buf_init(&b);
    make_glb(&b);
    write_tmp("truncated.glb", b.data, b.len - 40);
    gi_buf_free(&b);
    expect_failure(gi_test_tmpdir(), "truncated.glb", GI_EINVAL, NULL);

    /* Only lines and points: nothing to render. */
    static const char lines[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\np 1\n";
    write_tmp("lines.obj", lines, sizeof lines - 1);
    expect_failure(gi_test_tmpdir(), "lines.obj", GI_EINVAL, "no triangles");
}

/* ---- material names ---------------------------------------------------- */

/* n bytes of "abc...zabc...". */
static char *long_name(size_t n)
{
    char *s = gi_xmalloc(n + 1);
    for (size_t i = 0; i < n; i++)
        s[i] = (char)('a' + i % 26);
    s[n] = '\0';
    return s;
}

/* named.obj + named.mtl: one triangle of material `name` (Kd 0.5 0.25
 * 0.125); named.gltf + named.bin: make_gltf.py's quad, its material named
 * `name`. */
static void write_named_meshes(const char *name)
{
    gi_buf b;
    gi_buf_init(&b);
    static const char head[] = "mtllib named.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl ";
    gi_buf_put(&b, head, sizeof head - 1);
    gi_buf_put(&b, name, strlen(name));
    gi_buf_put(&b, "\nf 1 2 3\n", 9);
    write_tmp("named.obj", b.data, b.len);
    gi_buf_reset(&b);
    gi_buf_put(&b, "newmtl ", 7);
    gi_buf_put(&b, name, strlen(name));
    static const char kd[] = "\nKd 0.5 0.25 0.125\n";
    gi_buf_put(&b, kd, sizeof kd - 1);
    write_tmp("named.mtl", b.data, b.len);
    gi_buf_reset(&b);
    gltf_buffer(&b);
    write_tmp("named.bin", b.data, b.len);
    gi_buf_reset(&b);
    char *json = gltf_json("\"uri\": \"named.bin\", ");
    const char *glow = strstr(json, "\"glow\"");
    gi_buf_put(&b, json, (size_t)(glow - json) + 1);
    gi_buf_put(&b, name, strlen(name));
    gi_buf_put(&b, glow + 5, strlen(glow + 5));
    write_tmp("named.gltf", b.data, b.len);
    free(json);
    gi_buf_free(&b);
}

/* Names up to GI_MESH_NAME_MAX come through whole, with their colours;
 * longer ones are refused, naming the file, the material and the length.
 * assimp 5.2 drops an OBJ material named longer than 1023 bytes (its
 * aiString) with its colours, and cuts a glTF one there, both silently. */
GI_TEST(mesh_import_material_name_lengths)
{
    static const size_t lengths[] = {1, GI_MESH_NAME_MAX, GI_MESH_NAME_MAX + 1, 1022, 1023,
                                     1100, 5000};
    for (size_t i = 0; i < GI_ARRAY_LEN(lengths); i++) {
        size_t n = lengths[i];
        char *name = long_name(n);
        write_named_meshes(name);
        if (n <= GI_MESH_NAME_MAX) {
            static const char *const files[] = {"named.obj", "named.gltf"};
            for (int f = 0; f < 2; f++) {
                gi_dir_source d;
                gi_mesh_data m;
                gi_error err;
                int rc = import_from(gi_test_tmpdir(), files[f], &d, &m, &err);
                GI_CHECK_MSG(rc == 0, "%s, name of %zu bytes: %s", files[f], n, err.msg);
                if (rc == 0) {
                    GI_CHECK(m.material_count == 1 && strcmp(m.materials[0].name, name) == 0);
                    gi_vec3 kd = f == 0 ? gi_v3(0.5f, 0.25f, 0.125f) : gi_v3(0.2f, 0.4f, 0.6f);
                    GI_CHECK(near3(m.materials[0].diffuse, kd, 1e-6f));
                }
                gi_mesh_data_free(&m);
                gi_dir_source_free(&d);
            }
        } else {
            char want[256];
            snprintf(want, sizeof want,
                     "line 5: usemtl: the material's name (\"%.24s...\") is %zu bytes long, "
                     "over the limit of %d",
                     name, n, GI_MESH_NAME_MAX);
            expect_failure(gi_test_tmpdir(), "named.obj", GI_EINVAL, want);
            /* assimp keeps 1023 bytes of a glTF name: one that long may be cut. */
            snprintf(want, sizeof want,
                     "material 0: its name (\"%.24s...\") is %s%zu bytes long, over the limit "
                     "of %d",
                     name, n >= 1023 ? "at least " : "", n >= 1023 ? (size_t)1023 : n,
                     GI_MESH_NAME_MAX);
            expect_failure(gi_test_tmpdir(), "named.gltf", GI_EINVAL, want);
        }
        free(name);
    }
}

/* An OBJ of a triangle's three vertices and `body`: it must import (`also`
 * NULL) or fail with a message naming it and containing `also`. */
typedef struct obj_case {
    const char *body, *also;
} obj_case;

static void check_obj_cases(const char *file, const obj_case *cases, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        char text[256];
        snprintf(text, sizeof text, "v 0 0 0\nv 1 0 0\nv 0 1 0\n%s", cases[i].body);
        write_tmp(file, text, strlen(text));
        if (cases[i].also) {
            expect_failure(gi_test_tmpdir(), file, GI_EINVAL, cases[i].also);
            continue;
        }
        gi_dir_source d;
        gi_mesh_data m;
        gi_error err;
        GI_CHECK_MSG(import_from(gi_test_tmpdir(), file, &d, &m, &err) == 0, "case %zu: %s", i,
                     err.msg);
        gi_mesh_data_free(&m);
        gi_dir_source_free(&d);
    }
}

/* OBJ faces are checked against what the file defines before assimp sees
 * them (it refused these, but leaked the meshes it had built when the file
 * has more than one: fuzz_mesh; run under LSan). */
GI_TEST(mesh_import_obj_face_indices_in_range)
{
    static const obj_case cases[] = {
        {"f 1 2 3\nusemtl b\nf 1 2 4\n", "line 6: vertex index 4 is out of range (3 defined)"},
        {"usemtl a\nf 1 2 3\nusemtl b\nf -1 -2 -4\n",
         "line 7: vertex index -4 is out of range (3 defined before it)"},
        {"f 1 2 0\n", "vertex index 0"},
        {"vt 0 0\nf 1/1 2/2 3/1\n", "line 5: texture coordinate index 2"},
        {"vn 0 0 1\nf 1//1 2//1 3//2\r\n", "line 5: normal index 2"},
        {"l 1 5\nf 1 2 3\n", "line 4: vertex index 5"},
        {"f -3 -2 -1\r\n", NULL},           /* relative, CRLF */
        {"f 1 2 4\nv 1 1 0\n", NULL},       /* a vertex defined after the face */
        {"vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\n", NULL},
        {"f 1 2 3.0\n", "Invalid face index"}, /* not an integer: assimp's word */
        /* assimp skips indented lines: this vertex is not one, */
        {"  v 1 1 0\nf 1 2 4\n", "line 5: vertex index 4 is out of range (3 defined)"},
        {"\tv 1 1 0\nf 1 2 3\nf -4 -2 -1\n", "line 6: vertex index -4 is out of range"},
        /* and these faces and lines are none. */
        {"f 1 2 3\n  l 1 9\n\tf 7 8 9\n", NULL},
    };
    check_obj_cases("refs.obj", cases, GI_ARRAY_LEN(cases));
}

/* The OBJ checks read the lines assimp 5.2 reads, as it reads them (each
 * case was imported with assimp alone first): a case that imports here is
 * one assimp reads right, and one refused with a line is one it would
 * refuse or mis-read. */
GI_TEST(mesh_precheck_obj_reads_lines_as_assimp_does)
{
    static const obj_case cases[] = {
        /* A line's first byte says what it is: "fo", "lod" are a face and a line. */
        {"fo 1 2 3\n", NULL},
        {"f 1 2 3\nusemtl b\nfo 1 2 9\n", "line 6: vertex index 9 is out of range (3 defined)"},
        {"f 1 2 3\nlod 9\n", "line 5: vertex index 9 is out of range"},
        /* Lines from cstype to end are skipped. */
        {"f 1 2 3\ncstype bspline\nf 1 2 9\nend\n", NULL},
        {"cstype bspline\nend\nf 1 2 9\n", "line 6: vertex index 9"},
        /* A "v" line is a vertex with 3, 4 (homogeneous) or 6 numbers. */
        {"v 0 1\nf 1 2 4\n", "line 5: vertex index 4 is out of range (3 defined)"},
        {"v 1 1 0 1\nf 1 2 4\n", NULL},
        {"v 1 1 0 1 1 1\nf 1 2 4\n", NULL},
        {"v 1 1 0 nan\nf 1 2 4\n", "line 4: vertex coordinate \"nan\" is not a finite number"},
        {"vt0 0\nf 1/1 2/1 3/1\n", NULL},
        {"vn 0 0 1\nf 1/1 2/1 3/1\n", NULL}, /* v/vn, without texture coordinates */
        /* atoi over the bytes: "003" is 3, 3, 3; "3-1" is 3, -1. */
        {"f 1 2 003\n", NULL},
        {"f 1 2 3-1\n", NULL},
        {"f 1 2 3-4\n", "line 4: vertex index -4 is out of range (3 defined before it)"},
        {"vt 0 0\nvn 0 0 1\nf 1/1/1/1 2 3\n", "line 6: a corner has more than three indices"},
        {"f 1 2 3 # 9\n", "Invalid face index"}, /* no comment inside a face */
        /* Line continuations. */
        {"f 1 2 \\\n3\n", NULL},
        {"f 1 2 \\\r\n3\r\n", NULL},
        {"f 1 2 3\n# note \\\nf 1 2 9\n", NULL},
        {"# note \\\nv 5 5 5\nf 1 2 4\n", "line 6: vertex index 4 is out of range (3 defined)"},
        {"f 1 2 3 \\\n\nf 1 2 3\n",
         "line 4: the '\\' (a line continuation) at byte 32 joins an empty line"},
        {"f 1 2 \\\n\\\n3\n", "joins a line that starts with another '\\'"},
        {"f 1 2 3\nf 2 1 3 \\", NULL}, /* a '\' that ends the file ends the line */
    };
    check_obj_cases("lines.obj", cases, GI_ARRAY_LEN(cases));
    /* \r, \f and NUL end lines too; a lone \r counts as one in messages. */
    static const char cr[] = "v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\rusemtl b\rf 1 2 9\r";
    write_tmp("cr.obj", cr, sizeof cr - 1);
    expect_failure(gi_test_tmpdir(), "cr.obj", GI_EINVAL, "line 6: vertex index 9");
    static const char nul[] = "v 0 0 0\fv 1 0 0\fv 0 1 0\ff 1 2 3\0f 1 2 9\n";
    write_tmp("nul.obj", nul, sizeof nul - 1);
    expect_failure(gi_test_tmpdir(), "nul.obj", GI_EINVAL, "line 1: vertex index 9");
    write_tmp("nul.obj", nul, sizeof nul - 10);
    gi_dir_source d;
    gi_mesh_data m;
    gi_error err;
    GI_CHECK_MSG(import_from(gi_test_tmpdir(), "nul.obj", &d, &m, &err) == 0, "%s", err.msg);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

/* A file of more than one of assimp's 16 MiB read blocks: a continuation
 * that reaches over a block's end is refused (assimp reads past the
 * block), one inside a block is not; a last line without a line end is
 * not read (assimp drops it). Straight through the check: no assimp. */
GI_TEST(mesh_precheck_obj_16mib_blocks)
{
    const size_t block = (size_t)16 << 20;
    static const char tri[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\n", cont[] = "f 1 2 \\\n3\n";
    /* bs: where the continuation's '\' goes; tail: the file's last line. */
    static const struct {
        size_t bs_from_end; /* of the first block */
        const char *tail, *also;
    } cases[] = {
        {100, "f 1 2 3\n", NULL},
        {2, "f 1 2 3\n", "line 5: the '\\' (a line continuation) at byte 16777214 joins a line "
                         "that reaches over the end of the file or of a 16 MiB block"},
        {1, "f 1 2 3\n", "ends a 16 MiB block"},
        {100, "f 1 2 9", NULL},
        {100, "f 1 2 9\n", "vertex index 9 is out of range"},
    };
    for (size_t i = 0; i < GI_ARRAY_LEN(cases); i++) {
        gi_buf b;
        gi_buf_init(&b);
        gi_buf_put(&b, tri, sizeof tri - 1);
        /* One comment line up to the continuation, then comment lines. */
        size_t bs = block - cases[i].bs_from_end, fill = bs - 6 - b.len - 1;
        uint8_t *c = gi_buf_grow(&b, fill);
        memset(c, 'x', fill);
        c[0] = '#';
        gi_buf_put(&b, "\n", 1);
        gi_buf_put(&b, cont, sizeof cont - 1);
        GI_REQUIRE(b.data[bs] == '\\');
        while (b.len < block + 1000)
            gi_buf_put(&b, "# more\n", 7);
        gi_buf_put(&b, cases[i].tail, strlen(cases[i].tail));
        gi_error err;
        gi_error_clear(&err);
        int rc = gi_mesh_precheck("big.obj", b.data, b.len, &err);
        if (cases[i].also)
            GI_CHECK_MSG(rc == -1 && strstr(err.msg, "big.obj") &&
                             strstr(err.msg, cases[i].also),
                         "case %zu: %s", i, rc ? err.msg : "passed");
        else
            GI_CHECK_MSG(rc == 0, "case %zu: %s", i, err.msg);
        gi_buf_free(&b);
    }
}

/* assimp reads a PLY whose first line is "ply" with anything after it; the
 * size check must see those too (a 205-byte "ply \n" file declaring 2e9
 * vertices made the import take 2.2 GB). */
GI_TEST(mesh_precheck_ply_first_lines)
{
    static const char *const magic[] = {"ply\n", "ply \n", "ply\t\n", "ply \r\n", "PLY\r\n",
                                        "ply  \t \n"};
    for (size_t i = 0; i < GI_ARRAY_LEN(magic); i++) {
        char text[512];
        snprintf(text, sizeof text,
                 "%sformat binary_little_endian 1.0\nelement vertex 2000000000\n"
                 "property float x\nproperty float y\nproperty float z\nend_header\n"
                 "0 0 0\n0 1 0\n1 0 0\n",
                 magic[i]);
        gi_error err;
        gi_error_clear(&err);
        GI_CHECK_MSG(gi_mesh_precheck("big.ply", (const uint8_t *)text, strlen(text), &err) ==
                             -1 &&
                         strstr(err.msg, "big.ply") && strstr(err.msg, "declares"),
                     "first line %zu: %s", i, err.msg);
        /* Named otherwise, the bytes still go to assimp's PLY reader. */
        GI_CHECK(gi_mesh_precheck("big.mesh", (const uint8_t *)text, strlen(text), &err) == -1);
    }
    /* An ASCII header however spaced is counted as ASCII (the precheck does not
     * refuse it; assimp does, later, for its own reasons): this one fits. */
    static const char ok[] = "ply \r\nformat  ascii 1.0\r\nelement vertex 3\r\n"
                             "property float x\r\nproperty float y\r\nproperty float z\r\n"
                             "end_header\r\n0 0 0\n1 0 0\n0 1 0\n";
    gi_error err;
    GI_CHECK_MSG(gi_mesh_precheck("ok.ply", (const uint8_t *)ok, sizeof ok - 1, &err) == 0,
                 "%s", err.msg);
}

/* An element count must be a count: strtod also takes "nan", which no
 * comparison with the file's size refuses. */
GI_TEST(mesh_precheck_ply_counts_are_numbers)
{
    static const char *const counts[] = {"nan", "NAN", "-nan", "inf", "-1", "3x", "2147483648"};
    for (size_t i = 0; i < GI_ARRAY_LEN(counts); i++) {
        char text[256];
        snprintf(text, sizeof text,
                 "ply\nformat ascii 1.0\nelement vertex %s\nproperty float x\nend_header\n0\n",
                 counts[i]);
        gi_error err;
        gi_error_clear(&err);
        GI_CHECK_MSG(gi_mesh_precheck("c.ply", (const uint8_t *)text, strlen(text), &err) == -1 &&
                         strstr(err.msg, "c.ply") && strstr(err.msg, "bad count"),
                     "count %s: %s", counts[i], err.msg);
    }
    static const char one[] =
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n";
    gi_error err;
    GI_CHECK_MSG(gi_mesh_precheck("c.ply", (const uint8_t *)one, sizeof one - 1, &err) == 0,
                 "%s", err.msg);
}

/* A vertex that is not a finite point is refused, naming the file and the
 * vertex (the line, for an OBJ); normals that are not finite are dropped
 * (the scene computes its own). fuzz_mesh checks both. */
GI_TEST(mesh_import_refuses_non_finite_points)
{
    static const char nan_obj[] = "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n";
    static const char inf_obj[] = "v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n";
    write_tmp("nan.obj", nan_obj, sizeof nan_obj - 1);
    write_tmp("inf.obj", inf_obj, sizeof inf_obj - 1);
    /* The binary quad with its third vertex's y a NaN. */
    gi_buf b;
    gi_buf_init(&b);
    binary_ply(&b);
    const uint8_t *hdr_end = (const uint8_t *)strstr((const char *)b.data, "end_header\n");
    GI_REQUIRE(hdr_end != NULL);
    size_t at = (size_t)(hdr_end - b.data) + 11 + 2 * 24 + 4;
    const float qnan = NAN;
    memcpy(b.data + at, &qnan, sizeof qnan);
    write_tmp("nan.ply", b.data, b.len);
    gi_buf_free(&b);
    expect_failure(gi_test_tmpdir(), "nan.obj", GI_EINVAL, "line 2: vertex coordinate \"nan\"");
    expect_failure(gi_test_tmpdir(), "inf.obj", GI_EINVAL, "line 3: vertex coordinate \"1e999\"");
    expect_failure(gi_test_tmpdir(), "nan.ply", GI_EINVAL, "is not a finite point");
    char *dir = data_dir();
    expect_failure(dir, "nan_vertex.gltf", GI_EINVAL, "is not a finite point");
    free(dir);

    static const char nan_normals[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan 0 1\n"
                                      "f 1//1 2//1 3//1\n";
    write_tmp("nan_normals.obj", nan_normals, sizeof nan_normals - 1);
    gi_dir_source d;
    gi_mesh_data m;
    gi_error err;
    GI_CHECK_MSG(import_from(gi_test_tmpdir(), "nan_normals.obj", &d, &m, &err) == 0, "%s",
                 err.msg);
    GI_CHECK(m.normals == NULL);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&d);
}

/* One importer process serves a session's files while they import; a file
 * it fails on or dies on is named, and the next file gets a new process
 * that imports it exactly as a session of its own would. */
GI_TEST(mesh_importer_session_pins_failures_to_their_files)
{
    char *dir = data_dir();
    gi_dir_source d;
    gi_dir_source_init(&d, dir);
    gi_asset_source src = gi_dir_source_as_source(&d);
    static const struct {
        const char *file, *fails_with; /* NULL: imports */
        unsigned processes;            /* started by the session after it */
    } steps[] = {
        {"two_materials.obj", NULL, 1},
        {"transformed.gltf", NULL, 1},
        {"ascii.ply", NULL, 1},
        {"assimp_abort.ply", "assimp_abort.ply: cannot import: the importer (assimp) died", 1},
        {"two_materials.obj", NULL, 2},
        {"missing_bin.gltf", "missing_bin.gltf: cannot import", 2},
        {"bad_index.obj", "bad_index.obj", 2}, /* refused before any process */
        {"transformed.gltf", NULL, 3},
        {"cube_shared.obj", NULL, 3},
    };
    gi_mesh_importer *imp = gi_mesh_importer_new(&src);
    for (size_t i = 0; i < GI_ARRAY_LEN(steps); i++) {
        gi_error err;
        gi_error_clear(&err);
        gi_mesh_data m, alone;
        int rc = gi_mesh_importer_run(imp, steps[i].file, &m, &err);
        if (steps[i].fails_with) {
            GI_CHECK(rc == -1 && err.code == GI_EINVAL && strstr(err.msg, steps[i].fails_with));
        } else {
            GI_REQUIRE_OK(rc);
            GI_REQUIRE_OK(gi_mesh_import(&src, steps[i].file, &alone, &err));
            size_t tris = m.triangle_count;
            GI_CHECK(m.vertex_count == alone.vertex_count && tris == alone.triangle_count);
            GI_CHECK(memcmp(m.positions, alone.positions,
                            m.vertex_count * sizeof *m.positions) == 0);
            GI_CHECK(memcmp(m.indices, alone.indices, 3 * tris * sizeof *m.indices) == 0);
            gi_mesh_data_free(&alone);
        }
        gi_mesh_data_free(&m);
        if (gi_mesh_importer_processes(imp) != steps[i].processes)
            gi_test_failed(__FILE__, __LINE__, "after %s: %u importer processes, expected %u",
                           steps[i].file, gi_mesh_importer_processes(imp), steps[i].processes);
    }
    gi_mesh_importer_free(imp);
    gi_dir_source_free(&d);
    free(dir);
}

GI_TEST(mesh_import_repeated_does_not_leak)
{
    /* Run under LSan (ASAN_OPTIONS=detect_leaks=1): successes and failures
     * alike must release everything assimp and the reader allocated. */
    char *dir = data_dir();
    gi_dir_source d;
    gi_dir_source_init(&d, dir);
    gi_asset_source src = gi_dir_source_as_source(&d);
    static const char *const files[] = {"two_materials.obj", "transformed.gltf", "ascii.ply",
                                        "missing_bin.gltf", "bad_index.obj", "empty.obj"};
    int ok = 0;
    for (int round = 0; round < 20; round++)
        for (size_t i = 0; i < GI_ARRAY_LEN(files); i++) {
            gi_error err;
            gi_mesh_data m;
            ok += gi_mesh_import(&src, files[i], &m, &err) == 0;
            gi_mesh_data_free(&m);
        }
    GI_CHECK(ok == 20 * 3);
    gi_dir_source_free(&d);
    free(dir);
}

/* ---- shapes ----------------------------------------------------------- */

static void check_one_default_material(const gi_mesh_data *m)
{
    GI_CHECK(m->material_count == 1);
    GI_CHECK(m->material_count && strcmp(m->materials[0].name, "default") == 0);
    for (uint32_t t = 0; t < m->triangle_count; t++)
        GI_CHECK(m->tri_material[t] == 0);
}

GI_TEST(mesh_shape_quad)
{
    gi_mesh_data m;
    gi_mesh_quad(&m, 2.0, 3.0);
    GI_CHECK(m.vertex_count == 4 && m.triangle_count == 2);
    GI_CHECK(indices_valid(&m));
    check_one_default_material(&m);
    GI_CHECK_NEAR(mesh_area(&m), 6.0, 1e-6);
    for (uint32_t i = 0; i < 4; i++) {
        GI_CHECK(m.positions[i].y == 0.0f);
        GI_CHECK(fabsf(m.positions[i].x) == 1.0f && fabsf(m.positions[i].z) == 1.5f);
        GI_CHECK(near3(m.normals[i], gi_v3(0, 1, 0), 0));
    }
    for (uint32_t t = 0; t < 2; t++)
        GI_CHECK(near3(tri_normal(&m, t), gi_v3(0, 1, 0), 1e-6f));
    gi_mesh_data_free(&m);
}

GI_TEST(mesh_shape_box)
{
    for (int inward = 0; inward <= 1; inward++) {
        gi_mesh_data m;
        gi_mesh_box(&m, 1.0, 2.0, 3.0, inward);
        GI_CHECK(m.vertex_count == 24 && m.triangle_count == 12);
        GI_CHECK(indices_valid(&m));
        check_one_default_material(&m);
        GI_CHECK_NEAR(mesh_area(&m), 2.0 * (1 * 2 + 2 * 3 + 3 * 1), 1e-5);
        GI_CHECK_NEAR(mesh_volume(&m), inward ? -6.0 : 6.0, 1e-5);
        for (uint32_t t = 0; t < m.triangle_count; t++) {
            const uint32_t *ix = &m.indices[3 * t];
            gi_vec3 c = gi_scale(gi_add(gi_add(m.positions[ix[0]], m.positions[ix[1]]),
                                        m.positions[ix[2]]),
                                 1.0f / 3.0f);
            gi_vec3 n = tri_normal(&m, t);
            /* Flat faces: all three vertex normals equal the face normal,
             * which points away from the centre (toward it when inward). */
            for (int k = 0; k < 3; k++)
                GI_CHECK(near3(m.normals[ix[k]], n, 1e-6f));
            GI_CHECK(inward ? gi_dot(n, c) < 0 : gi_dot(n, c) > 0);
        }
        for (uint32_t i = 0; i < m.vertex_count; i++)
            GI_CHECK(fabsf(m.positions[i].x) == 0.5f && fabsf(m.positions[i].y) == 1.0f &&
                     fabsf(m.positions[i].z) == 1.5f);
        gi_mesh_data_free(&m);
    }
}

GI_TEST(mesh_shape_icosphere)
{
    const double r = 2.0, exact = 4.0 * GI_PI * r * r;
    double prev_area = 0;
    for (int level = 0; level <= 4; level++) {
        gi_mesh_data m;
        gi_mesh_sphere(&m, r, level);
        uint32_t p4 = 1u << (2 * level);
        GI_CHECK(m.triangle_count == 20 * p4);
        GI_CHECK(m.vertex_count == 10 * p4 + 2);
        GI_CHECK(indices_valid(&m));
        check_one_default_material(&m);
        double area = mesh_area(&m), vol = mesh_volume(&m);
        /* Inscribed polyhedra: area grows toward 4 pi r^2 from below. */
        GI_CHECK_MSG(area < exact && area > prev_area, "level %d: area %g", level, area);
        GI_CHECK(vol > 0 && vol < 4.0 / 3.0 * GI_PI * r * r * r);
        prev_area = area;
        for (uint32_t i = 0; i < m.vertex_count; i++) {
            GI_CHECK_NEAR(gi_length(m.positions[i]), r, 1e-5);
            GI_CHECK(near3(m.normals[i], gi_scale(m.positions[i], (float)(1.0 / r)), 1e-6f));
        }
        for (uint32_t t = 0; t < m.triangle_count; t++) {
            const uint32_t *ix = &m.indices[3 * t];
            gi_vec3 c = gi_add(gi_add(m.positions[ix[0]], m.positions[ix[1]]), m.positions[ix[2]]);
            GI_CHECK(gi_dot(tri_normal(&m, t), c) > 0);
        }
        /* Shared vertices: no two at the same place (O(n^2), small n). */
        int dup = 0;
        for (uint32_t i = 0; i < m.vertex_count && level <= 3; i++)
            for (uint32_t j = i + 1; j < m.vertex_count; j++)
                dup += near3(m.positions[i], m.positions[j], 1e-6f);
        GI_CHECK(dup == 0);
        gi_mesh_data_free(&m);
    }
    GI_CHECK_REL(prev_area, exact, 0.01);
}

/* ---- normals and append ----------------------------------------------- */

GI_TEST(mesh_compute_normals_cube_corner)
{
    /* Three faces at the corner (0,0,0) of the unit cube, wound outward
     * (-x, -y, -z), two triangles each, plus a degenerate triangle and an
     * unused vertex. */
    gi_mesh_data m;
    gi_mesh_data_init(&m);
    static const gi_vec3 p[] = {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0},
                                {0, 0, 1}, {0, 1, 1}, {1, 0, 1},
                                {5, 5, 5}, {6, 6, 6}, {7, 7, 7}, {9, 9, 9}};
    static const uint32_t ix[] = {
        0, 1, 2, 0, 2, 3, /* z = 0: two triangles of area 1/2 each */
        0, 4, 5, 0, 5, 1, /* x = 0 */
        0, 3, 6, 0, 6, 4, /* y = 0 */
        7, 8, 9,          /* degenerate (collinear) */
    };
    m.vertex_count = GI_ARRAY_LEN(p);
    m.triangle_count = GI_ARRAY_LEN(ix) / 3;
    m.positions = gi_xmalloc(sizeof p);
    memcpy(m.positions, p, sizeof p);
    m.indices = gi_xmalloc(sizeof ix);
    memcpy(m.indices, ix, sizeof ix);
    m.tri_material = gi_xcalloc(m.triangle_count, sizeof *m.tri_material);
    gi_mesh_compute_normals(&m);
    /* Hard edges (90 degrees) split the vertices: (0,0,0) in three, the
     * three on two faces in two (5 copies appended after the 11). Each
     * vertex's first group, in triangle order, keeps its index. */
    GI_REQUIRE(m.vertex_count == 16);
    for (uint32_t i = 0; i < 3 * m.triangle_count; i++)
        GI_REQUIRE(m.indices[i] < m.vertex_count);
    for (uint32_t t = 0; t < 6; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = m.indices[3 * t + k];
            GI_CHECK(near3(m.normals[v], tri_normal(&m, t), 1e-6f));
            GI_CHECK(near3(m.positions[v], p[ix[3 * t + k]], 0));
        }
    GI_CHECK(near3(m.normals[0], gi_v3(0, 0, -1), 1e-6f));
    GI_CHECK(m.indices[0] == 0 && m.indices[6] >= 11 && m.indices[12] >= 11);
    /* Only degenerate triangles, or none: +y by convention, not split. */
    for (int i = 7; i <= 9; i++) {
        GI_CHECK(near3(m.normals[i], gi_v3(0, 1, 0), 0));
        GI_CHECK(m.indices[18 + i - 7] == (uint32_t)i);
    }
    GI_CHECK(near3(m.normals[10], gi_v3(0, 1, 0), 0));
    for (uint32_t i = 0; i < m.vertex_count; i++)
        GI_CHECK_NEAR(gi_length(m.normals[i]), 1.0, 1e-6);

    /* Area weighting, not angle or count, within a smooth group: a big and
     * a small triangle sharing an edge at 45 degrees (under the crease
     * angle); the big one dominates in proportion to its area. */
    gi_mesh_data w;
    gi_mesh_data_init(&w);
    static const gi_vec3 q[] = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {-1, 0, 1}};
    static const uint32_t qi[] = {0, 1, 2, 0, 2, 3}; /* area 4.5 (+z), 2.12 (+x+z) */
    w.vertex_count = 4;
    w.triangle_count = 2;
    w.positions = gi_xmalloc(sizeof q);
    memcpy(w.positions, q, sizeof q);
    w.indices = gi_xmalloc(sizeof qi);
    memcpy(w.indices, qi, sizeof qi);
    w.tri_material = gi_xcalloc(2, sizeof *w.tri_material);
    gi_mesh_compute_normals(&w);
    GI_CHECK(w.vertex_count == 4); /* smooth: nothing split */
    gi_vec3 want = gi_normalize(gi_v3(3, 0, 12));
    GI_CHECK(near3(w.normals[0], want, 1e-6f));
    GI_CHECK(near3(w.normals[2], want, 1e-6f));
    GI_CHECK(near3(w.normals[1], gi_v3(0, 0, 1), 1e-6f));
    GI_CHECK(near3(w.normals[3], gi_normalize(gi_v3(1, 0, 1)), 1e-6f));
    gi_mesh_data_free(&w);
    gi_mesh_data_free(&m);
}

GI_TEST(mesh_append)
{
    gi_mesh_data a, b, q;
    gi_mesh_data_init(&a);
    gi_mesh_box(&b, 1, 1, 1, 0);
    gi_mesh_quad(&q, 2, 2);
    gi_mesh_data_append(&a, &b); /* into an empty mesh: a copy */
    GI_CHECK(a.vertex_count == 24 && a.triangle_count == 12 && a.material_count == 1);
    GI_CHECK(a.normals != NULL);
    gi_mesh_data_append(&a, &q);
    GI_CHECK(a.vertex_count == 28 && a.triangle_count == 14 && a.material_count == 2);
    GI_CHECK(indices_valid(&a));
    for (int k = 0; k < 6; k++)
        GI_CHECK(a.indices[36 + k] == q.indices[k] + 24);
    GI_CHECK(a.tri_material[11] == 0 && a.tri_material[12] == 1 && a.tri_material[13] == 1);
    GI_CHECK(near3(a.positions[24], q.positions[0], 0));
    GI_CHECK(near3(a.normals[27], gi_v3(0, 1, 0), 0));
    GI_CHECK(strcmp(a.materials[1].name, "default") == 0 && a.materials[1].name != q.materials[0].name);
    GI_CHECK_NEAR(mesh_area(&a), 6.0 + 4.0, 1e-5);

    /* A part without normals gets the ones the scene would compute. */
    gi_mesh_data n, c;
    gi_mesh_quad(&n, 1, 1);
    free(n.normals);
    n.normals = NULL;
    gi_mesh_data_init(&c);
    gi_mesh_data_append(&c, &n);
    GI_CHECK(c.normals == NULL);
    gi_mesh_data_append(&c, &q);
    GI_CHECK(c.normals != NULL);
    for (uint32_t i = 0; c.normals && i < c.vertex_count; i++)
        GI_CHECK(near3(c.normals[i], gi_v3(0, 1, 0), 1e-6f));

    /* A part without materials (its triangles mean "default") keeps
     * meaning that after the shift. */
    gi_mesh_data bare;
    gi_mesh_quad(&bare, 1, 1);
    for (uint32_t i = 0; i < bare.material_count; i++)
        free(bare.materials[i].name);
    free(bare.materials);
    bare.materials = NULL;
    bare.material_count = 0;
    gi_mesh_data_append(&c, &bare);
    GI_CHECK(c.material_count == 3);
    GI_CHECK(c.tri_material[c.triangle_count - 1] == 2);
    GI_CHECK(strcmp(c.materials[2].name, "default") == 0);
    GI_CHECK(near3(c.materials[2].diffuse, gi_v3(0.8f, 0.8f, 0.8f), 0));
    GI_CHECK(indices_valid(&c));
    gi_mesh_data_free(&bare);
    gi_mesh_data_free(&a);
    gi_mesh_data_free(&b);
    gi_mesh_data_free(&q);
    gi_mesh_data_free(&n);
    gi_mesh_data_free(&c);
}
