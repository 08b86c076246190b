/* Unit tests: the glTF (.glb) per-vertex output, read back by a reader of the
 * GLB layout written here from the spec, and by assimp. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "gi_buf.h"
#include "gi_fs.h"
#include "gi_glb.h"
#include "gi_json.h"
#include "gi_mesh.h"
#include "gi_test.h"

typedef struct glb_file {
    gi_buf bytes;
    cJSON *json;
    const uint8_t *bin;
    size_t bin_len;
} glb_file;

/* Reads path and checks the container: header, a JSON chunk and a BIN chunk,
 * lengths that add up, 4-byte padding. */
static int glb_read(const char *path, glb_file *g)
{
    gi_error err;
    memset(g, 0, sizeof *g);
    gi_buf_init(&g->bytes);
    if (gi_read_file(path, 1 << 24, &g->bytes, &err))
        return -1;
    const uint8_t *p = g->bytes.data;
    size_t len = g->bytes.len;
    GI_CHECK(len >= 28 && len % 4 == 0);
    if (len < 28)
        return -1;
    GI_CHECK(gi_le_get_u32(p) == 0x46546C67u && gi_le_get_u32(p + 4) == 2);
    GI_CHECK(gi_le_get_u32(p + 8) == len);
    uint32_t json_len = gi_le_get_u32(p + 12);
    GI_CHECK(gi_le_get_u32(p + 16) == 0x4E4F534Au && json_len % 4 == 0);
    if (20 + (size_t)json_len + 8 > len)
        return -1;
    const uint8_t *bin_hdr = p + 20 + json_len;
    g->bin_len = gi_le_get_u32(bin_hdr);
    GI_CHECK(gi_le_get_u32(bin_hdr + 4) == 0x004E4942u);
    GI_CHECK(20 + (size_t)json_len + 8 + g->bin_len == len);
    g->bin = bin_hdr + 8;
    g->json = cJSON_ParseWithLength((const char *)p + 20, json_len);
    return g->json ? 0 : -1;
}

static void glb_free(glb_file *g)
{
    cJSON_Delete(g->json);
    gi_buf_free(&g->bytes);
}

static int num(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(v) ? v->valueint : -1;
}

/* The accessor of attribute `name` (or of the indices if name is NULL), its
 * data checked to lie in the BIN chunk, as 32-bit words; NULL if absent. */
static const uint8_t *accessor(const glb_file *g, const char *name, int *count,
                               const cJSON **acc_out)
{
    const cJSON *prim = cJSON_GetArrayItem(
        cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(g->json, "meshes"), 0),
                            "primitives"),
        0);
    int a = name ? num(cJSON_GetObjectItem(prim, "attributes"), name) : num(prim, "indices");
    if (a < 0)
        return NULL;
    const cJSON *acc = cJSON_GetArrayItem(cJSON_GetObjectItem(g->json, "accessors"), a);
    const cJSON *view =
        cJSON_GetArrayItem(cJSON_GetObjectItem(g->json, "bufferViews"), num(acc, "bufferView"));
    int off = num(view, "byteOffset"), len = num(view, "byteLength");
    *count = num(acc, "count");
    int comps = strcmp(cJSON_GetObjectItem(acc, "type")->valuestring, "VEC3") == 0 ? 3 : 1;
    GI_CHECK(off >= 0 && off % 4 == 0 && (size_t)off + (size_t)len <= g->bin_len);
    GI_CHECK(len == *count * comps * 4);
    if (acc_out)
        *acc_out = acc;
    return off >= 0 && (size_t)off + (size_t)len <= g->bin_len ? g->bin + off : NULL;
}

/* One black triangle, for the tests of what is left out, refused or skipped. */
static const gi_vec3 tri_pos[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
static const float tri_black[9] = {0};

static void tmp_path(char *out, size_t n, const char *name)
{
    snprintf(out, n, "%s/%s", gi_test_tmpdir(), name);
}

static float f32_at(const uint8_t *p, size_t i)
{
    uint32_t u = gi_le_get_u32(p + 4 * i);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

GI_TEST(test_glb_output_holds_the_mesh_and_its_light)
{
    gi_error err;
    gi_vec3 pos[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 2.5f, -1}};
    gi_vec3 nrm[4] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    float rad[12] = {0.5f, 0.25f, 0.0f, 1, 1, 1, 0, 0, 0, 2, 0.1f, 0.2f};
    float irr[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    gi_vertex_bake bake = {4, pos, nrm, rad, irr, 2, idx, 1.0}; /* one stop up */
    char path[600];
    tmp_path(path, sizeof path, "out.glb");
    GI_REQUIRE_OK(gi_glb_write(path, &bake, &err));

    glb_file g;
    GI_REQUIRE(glb_read(path, &g) == 0);
    const cJSON *asset = cJSON_GetObjectItem(g.json, "asset");
    GI_CHECK(strcmp(cJSON_GetObjectItem(asset, "version")->valuestring, "2.0") == 0);
    int n = 0;
    const cJSON *acc = NULL;
    const uint8_t *p = accessor(&g, "POSITION", &n, &acc);
    GI_REQUIRE(p && n == 4);
    for (int i = 0; i < 4; i++) {
        GI_CHECK(f32_at(p, 3 * (size_t)i) == pos[i].x && f32_at(p, 3 * (size_t)i + 1) == pos[i].y);
        GI_CHECK(f32_at(p, 3 * (size_t)i + 2) == pos[i].z);
    }
    /* POSITION needs its bounds (the spec); they are exact. */
    const cJSON *min = cJSON_GetObjectItem(acc, "min"), *max = cJSON_GetObjectItem(acc, "max");
    GI_REQUIRE(cJSON_GetArraySize(min) == 3 && cJSON_GetArraySize(max) == 3);
    GI_CHECK(cJSON_GetArrayItem(min, 2)->valuedouble == -1.0);
    GI_CHECK(cJSON_GetArrayItem(max, 1)->valuedouble == 2.5);
    p = accessor(&g, "NORMAL", &n, NULL);
    GI_CHECK(p && n == 4 && f32_at(p, 11) == 1.0f);
    /* COLOR_0: radiance * 2, clamped to [0, 1]; the float values unclamped. */
    p = accessor(&g, "COLOR_0", &n, NULL);
    GI_REQUIRE(p && n == 4);
    const float colour[12] = {1, 0.5f, 0, 1, 1, 1, 0, 0, 0, 1, 0.2f, 0.4f};
    for (int i = 0; i < 12; i++)
        GI_CHECK_MSG(f32_at(p, (size_t)i) == colour[i], "COLOR_0[%d] = %g", i,
                     (double)f32_at(p, (size_t)i));
    p = accessor(&g, "_RADIANCE", &n, NULL);
    GI_REQUIRE(p && n == 4);
    GI_CHECK(f32_at(p, 9) == 2.0f && f32_at(p, 0) == 0.5f);
    p = accessor(&g, "_IRRADIANCE", &n, NULL);
    GI_CHECK(p && n == 4 && f32_at(p, 11) == 12.0f);
    p = accessor(&g, NULL, &n, NULL);
    GI_REQUIRE(p && n == 6);
    for (int i = 0; i < 6; i++)
        GI_CHECK(gi_le_get_u32(p + 4 * i) == idx[i]);
    /* The unlit material it names. */
    const cJSON *mat = cJSON_GetArrayItem(cJSON_GetObjectItem(g.json, "materials"), 0);
    GI_CHECK(cJSON_GetObjectItem(cJSON_GetObjectItem(mat, "extensions"), "KHR_materials_unlit"));
    glb_free(&g);

    /* An independent reader (assimp) sees the same geometry. */
    gi_dir_source ds;
    gi_dir_source_init(&ds, gi_test_tmpdir());
    gi_asset_source src = gi_dir_source_as_source(&ds);
    gi_mesh_data m;
    GI_REQUIRE_OK(gi_mesh_import(&src, "out.glb", &m, &err));
    GI_CHECK(m.triangle_count == 2 && m.vertex_count == 4);
    gi_mesh_data_free(&m);
    gi_dir_source_free(&ds);
}

GI_TEST(test_glb_output_leaves_out_what_it_is_not_given)
{
    gi_error err;
    uint32_t idx[3] = {0, 1, 2};
    gi_vertex_bake bake = {3, tri_pos, NULL, tri_black, NULL, 1, idx, 0.0};
    char path[600];
    tmp_path(path, sizeof path, "bare.glb");
    GI_REQUIRE_OK(gi_glb_write(path, &bake, &err));
    glb_file g;
    GI_REQUIRE(glb_read(path, &g) == 0);
    int n = 0;
    GI_CHECK(accessor(&g, "NORMAL", &n, NULL) == NULL);
    GI_CHECK(accessor(&g, "_IRRADIANCE", &n, NULL) == NULL);
    GI_CHECK(accessor(&g, "_RADIANCE", &n, NULL) != NULL && n == 3);
    glb_free(&g);
}

/* A bad index or exposure fails naming the file, and writes nothing. */
GI_TEST(test_glb_output_refuses_bad_input_and_writes_nothing)
{
    gi_error err;
    uint32_t bad[3] = {0, 1, 3};
    char path[600];
    tmp_path(path, sizeof path, "bad.glb");
    gi_vertex_bake bake = {3, tri_pos, NULL, tri_black, NULL, 1, bad, 0.0};
    GI_CHECK(gi_glb_write(path, &bake, &err) == -1 && strstr(err.msg, "bad.glb"));
    uint32_t ok[3] = {0, 1, 2};
    bake.indices = ok;
    bake.exposure_stops = NAN;
    GI_CHECK(gi_glb_write(path, &bake, &err) == -1 && strstr(err.msg, "exposure"));
    struct stat st;
    GI_CHECK(stat(path, &st) != 0);
}

/* A mesh too large for glTF's 32-bit lengths is skipped (0, nothing
 * written) instead of failing a finished bake; one that fits is written. */
GI_TEST(test_glb_output_too_large_for_gltf_is_skipped)
{
    GI_CHECK(gi_glb_fits(52000000, 104000000) == 0);
    GI_CHECK(gi_glb_fits(40000000, 80000000) == 1);
    gi_error err;
    uint32_t idx[3] = {0, 1, 2};
    char path[600];
    tmp_path(path, sizeof path, "huge.glb");
    /* The counts are checked before any array is read. */
    gi_vertex_bake huge = {80000000, tri_pos, NULL, tri_black, NULL, 1, idx, 0.0};
    GI_CHECK(gi_glb_write_or_skip(path, &huge, &err) == 0);
    struct stat st;
    GI_CHECK(stat(path, &st) != 0);
    gi_vertex_bake small = {3, tri_pos, NULL, tri_black, NULL, 1, idx, 0.0};
    GI_CHECK(gi_glb_write_or_skip(path, &small, &err) == 1 && stat(path, &st) == 0);
}
