/* gi_glb: the baked mesh as binary glTF 2.0 (spec: registry.khronos.org/glTF,
 * "GLB File Format Specification"): a 12-byte header, a JSON chunk and a BIN
 * chunk, each padded to 4 bytes. Every attribute gets its own tightly packed
 * buffer view, so no view needs a stride. */
#include "gi_glb.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_buf.h"
#include "gi_json.h"
#include "gi_fs.h"
#include "gi_log.h"

#define GLB_MAGIC 0x46546C67u      /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au /* "JSON" */
#define GLB_CHUNK_BIN 0x004E4942u  /* "BIN\0" */
#define GL_FLOAT 5126
#define GL_UNSIGNED_INT 5125
#define GL_ARRAY_BUFFER 34962
#define GL_ELEMENT_ARRAY_BUFFER 34963

typedef struct glb_doc {
    cJSON *views, *accessors;
    gi_buf bin;
} glb_doc;

/* Ends the buffer view of the bytes appended to d->bin since `start` and
 * gives it an accessor of `count` elements; returns the accessor's index. */
static int end_view(glb_doc *d, size_t start, int target, int component, uint32_t count,
                    const char *type, const float *min, const float *max)
{
    cJSON *view = cJSON_CreateObject();
    cJSON_AddNumberToObject(view, "buffer", 0);
    cJSON_AddNumberToObject(view, "byteOffset", (double)start);
    cJSON_AddNumberToObject(view, "byteLength", (double)(d->bin.len - start));
    cJSON_AddNumberToObject(view, "target", target);
    cJSON_AddItemToArray(d->views, view);

    cJSON *acc = cJSON_CreateObject();
    cJSON_AddNumberToObject(acc, "bufferView", cJSON_GetArraySize(d->views) - 1);
    cJSON_AddNumberToObject(acc, "componentType", component);
    cJSON_AddNumberToObject(acc, "count", count);
    cJSON_AddStringToObject(acc, "type", type);
    if (min && max) {
        double lo[3] = {min[0], min[1], min[2]}, hi[3] = {max[0], max[1], max[2]};
        cJSON_AddItemToObject(acc, "min", cJSON_CreateDoubleArray(lo, 3));
        cJSON_AddItemToObject(acc, "max", cJSON_CreateDoubleArray(hi, 3));
    }
    cJSON_AddItemToArray(d->accessors, acc);
    return cJSON_GetArraySize(d->accessors) - 1;
}

static int add_rgb(glb_doc *d, const float *rgb, uint32_t count)
{
    size_t start = d->bin.len;
    gi_buf_put_f32s(&d->bin, rgb, 3 * (size_t)count);
    return end_view(d, start, GL_ARRAY_BUFFER, GL_FLOAT, count, "VEC3", NULL, NULL);
}

static int add_vec3s(glb_doc *d, const gi_vec3 *v, uint32_t count, int with_bounds)
{
    size_t start = d->bin.len;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < count; i++) {
        const float p[3] = {v[i].x, v[i].y, v[i].z};
        gi_buf_put_f32s(&d->bin, p, 3);
        for (int c = 0; c < 3; c++) {
            lo[c] = p[c] < lo[c] ? p[c] : lo[c];
            hi[c] = p[c] > hi[c] ? p[c] : hi[c];
        }
    }
    return end_view(d, start, GL_ARRAY_BUFFER, GL_FLOAT, count, "VEC3",
                    with_bounds ? lo : NULL, with_bounds ? hi : NULL);
}

static int add_colours(glb_doc *d, const gi_vertex_bake *b)
{
    size_t start = d->bin.len;
    float scale = (float)pow(2.0, b->exposure_stops);
    for (size_t i = 0; i < 3 * (size_t)b->vertex_count; i++) {
        float c = b->radiance_rgb[i] * scale;
        gi_buf_put_f32(&d->bin, c > 0.0f ? (c < 1.0f ? c : 1.0f) : 0.0f);
    }
    return end_view(d, start, GL_ARRAY_BUFFER, GL_FLOAT, b->vertex_count, "VEC3", NULL, NULL);
}

static int add_indices(glb_doc *d, const uint32_t *idx, uint32_t count)
{
    size_t start = d->bin.len;
    for (uint32_t i = 0; i < count; i++)
        gi_buf_put_u32(&d->bin, idx[i]);
    return end_view(d, start, GL_ELEMENT_ARRAY_BUFFER, GL_UNSIGNED_INT, count, "SCALAR", NULL,
                    NULL);
}

static cJSON *unlit_material(void)
{
    cJSON *m = cJSON_CreateObject();
    cJSON_AddStringToObject(m, "name", "gi-farm bake (unlit, vertex colours)");
    cJSON *pbr = cJSON_AddObjectToObject(m, "pbrMetallicRoughness");
    const double white[4] = {1, 1, 1, 1};
    cJSON_AddItemToObject(pbr, "baseColorFactor", cJSON_CreateDoubleArray(white, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0);
    cJSON_AddNumberToObject(pbr, "roughnessFactor", 1);
    cJSON *ext = cJSON_AddObjectToObject(m, "extensions");
    cJSON_AddObjectToObject(ext, "KHR_materials_unlit");
    return m;
}

/* The glTF document around the accessors (attributes: their indices). */
static cJSON *document(glb_doc *d, cJSON *attributes, int indices)
{
    cJSON *root = cJSON_CreateObject();
    cJSON *asset = cJSON_AddObjectToObject(root, "asset");
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddStringToObject(asset, "generator", "gi-farm");
    cJSON *used = cJSON_AddArrayToObject(root, "extensionsUsed");
    cJSON_AddItemToArray(used, cJSON_CreateString("KHR_materials_unlit"));
    cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scene = cJSON_CreateObject();
    cJSON_AddItemToObject(scene, "nodes", cJSON_CreateIntArray((const int[]){0}, 1));
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "scenes"), scene);
    cJSON *node = cJSON_CreateObject();
    cJSON_AddNumberToObject(node, "mesh", 0);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "nodes"), node);
    cJSON *prim = cJSON_CreateObject();
    cJSON_AddItemToObject(prim, "attributes", attributes);
    cJSON_AddNumberToObject(prim, "indices", indices);
    cJSON_AddNumberToObject(prim, "material", 0);
    cJSON_AddNumberToObject(prim, "mode", 4); /* triangles */
    cJSON *mesh = cJSON_CreateObject();
    cJSON_AddStringToObject(mesh, "name", "bake");
    cJSON_AddItemToArray(cJSON_AddArrayToObject(mesh, "primitives"), prim);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "meshes"), mesh);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "materials"), unlit_material());
    cJSON *buffer = cJSON_CreateObject();
    cJSON_AddNumberToObject(buffer, "byteLength", (double)d->bin.len);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "buffers"), buffer);
    cJSON_AddItemToObject(root, "bufferViews", d->views);
    cJSON_AddItemToObject(root, "accessors", d->accessors);
    return root;
}

static void put_chunk(gi_buf *out, uint32_t type, const void *data, size_t len, uint8_t pad)
{
    size_t padded = (len + 3) & ~(size_t)3;
    gi_buf_put_u32(out, (uint32_t)padded);
    gi_buf_put_u32(out, type);
    gi_buf_put(out, data, len);
    for (size_t i = len; i < padded; i++)
        gi_buf_put_u8(out, pad);
}

int gi_glb_fits(uint32_t vertex_count, uint32_t triangle_count)
{
    /* GLB lengths are 32-bit: 5 attributes of 12 bytes a vertex, 12 a
     * triangle, and the JSON (under 4 KiB). */
    return 60.0 * vertex_count + 12.0 * triangle_count + 65536.0 <= 4294967295.0;
}

int gi_glb_write_or_skip(const char *path, const gi_vertex_bake *b, gi_error *err)
{
    if (!gi_glb_fits(b->vertex_count, b->triangle_count)) {
        gi_warn("%s: not written: %u vertices and %u triangles pass glTF's 4 GiB file size (the "
                "ply and bin outputs hold the same values)",
                path, b->vertex_count, b->triangle_count);
        return 0;
    }
    return gi_glb_write(path, b, err) ? -1 : 1;
}

int gi_glb_write(const char *path, const gi_vertex_bake *b, gi_error *err)
{
    if (!isfinite(b->exposure_stops))
        return gi_fail(err, GI_EINVAL, "%s: exposure is not finite", path);
    if (b->vertex_count == 0 || b->triangle_count == 0)
        return gi_fail(err, GI_EINTERNAL, "%s: a glTF mesh needs vertices and triangles", path);
    for (size_t i = 0; i < 3 * (size_t)b->triangle_count; i++)
        if (b->indices[i] >= b->vertex_count)
            return gi_fail(err, GI_EINTERNAL, "%s: triangle index %u out of range", path,
                           b->indices[i]);
    if (!gi_glb_fits(b->vertex_count, b->triangle_count))
        return gi_fail(err, GI_EINTERNAL, "%s: %u vertices and %u triangles exceed glTF's 4 GiB",
                       path, b->vertex_count, b->triangle_count);

    glb_doc d = {cJSON_CreateArray(), cJSON_CreateArray(), {0}};
    gi_buf_init(&d.bin);
    cJSON *attrs = cJSON_CreateObject();
    cJSON_AddNumberToObject(attrs, "POSITION", add_vec3s(&d, b->positions, b->vertex_count, 1));
    if (b->normals)
        cJSON_AddNumberToObject(attrs, "NORMAL", add_vec3s(&d, b->normals, b->vertex_count, 0));
    cJSON_AddNumberToObject(attrs, "COLOR_0", add_colours(&d, b));
    cJSON_AddNumberToObject(attrs, "_RADIANCE", add_rgb(&d, b->radiance_rgb, b->vertex_count));
    if (b->irradiance_rgb)
        cJSON_AddNumberToObject(attrs, "_IRRADIANCE",
                                add_rgb(&d, b->irradiance_rgb, b->vertex_count));
    int indices = add_indices(&d, b->indices, 3 * b->triangle_count);
    cJSON *root = document(&d, attrs, indices);
    char *json = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!json) {
        gi_buf_free(&d.bin);
        return gi_fail(err, GI_ENOMEM, "%s: out of memory", path);
    }

    size_t json_len = strlen(json);
    gi_buf out;
    gi_buf_init(&out);
    gi_buf_put_u32(&out, GLB_MAGIC);
    gi_buf_put_u32(&out, 2);
    gi_buf_put_u32(&out, 0); /* total length, below */
    put_chunk(&out, GLB_CHUNK_JSON, json, json_len, ' ');
    put_chunk(&out, GLB_CHUNK_BIN, d.bin.data, d.bin.len, 0);
    gi_le_put_u32(out.data + 8, (uint32_t)out.len);
    free(json);
    gi_buf_free(&d.bin);
    int rc = gi_write_file_atomic(path, out.data, out.len, err);
    gi_buf_free(&out);
    return rc;
}
